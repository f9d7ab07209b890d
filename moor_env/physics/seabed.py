"""Flat seabed at z = -depth: vertical spring-damper contact and regularised Coulomb friction for line nodes.

Vertical pressure (MoorDyn's ``kBot``/``cBot`` model) acts on the node's contact area (diameter times the
half-lengths of its segments); friction opposes horizontal sliding with magnitude ``mu * F_z``, ramped
linearly below ``friction_velocity_m_s`` so that a resting line feels no friction (and statics on the
seabed match the frictionless catenary theory of seeds 000 and 004).
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit
from moor_env.physics.layout import EF_CBOT, EF_DEPTH, EF_FRIC_V, EF_KBOT, EF_MU, EF_SEABED_SMOOTHING


@jit
def seabed_force(z, vx, vy, vz, contact_area, env_f):
    """Contact force on a node [N]; zero above the seabed.

    Parameters
    ----------
    z : float
        Node height [m].
    vx, vy, vz : float
        Node velocity [m/s].
    contact_area : float
        Diameter times half-lengths of the node's segments [m^2].
    env_f : ndarray
        Environment slots (see ``layout``).
    """
    penetration = -env_f[EF_DEPTH] - z
    smoothing = env_f[EF_SEABED_SMOOTHING]
    if smoothing > 0.0:  # the static solver's smoothed contact (velocities are zero there)
        penetration = 0.5 * (penetration + math.sqrt(penetration * penetration + smoothing * smoothing))
    if penetration <= 0.0 or contact_area <= 0.0:
        return 0.0, 0.0, 0.0
    fz = (env_f[EF_KBOT] * penetration - env_f[EF_CBOT] * vz) * contact_area
    if fz <= 0.0:
        return 0.0, 0.0, 0.0
    vh = math.sqrt(vx * vx + vy * vy)
    if vh == 0.0:
        return 0.0, 0.0, fz
    friction = env_f[EF_MU] * fz * min(vh / env_f[EF_FRIC_V], 1.0) / vh
    return -friction * vx, -friction * vy, fz

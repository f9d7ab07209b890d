"""Flat seabed at z = -depth: vertical spring-damper contact and regularised Coulomb friction for line nodes.

Vertical pressure (MoorDyn's ``kBot``/``cBot`` model) acts on the node's contact area (its segments' seabed width
``MF_SEABED_D``, their diameter as compiled, times their half-lengths); friction opposes horizontal sliding with
magnitude ``mu * F_z``, ramped linearly below ``friction_velocity_m_s`` so that a resting line feels no friction
(and statics on the seabed match the frictionless catenary theory of seeds 000 and 004).

With penetration p = -depth - z, contact area A, vertical force f_z = (k_bot p - c_bot v_z) A (> 0, else no
contact) and horizontal velocity v_h::

    f_h = -mu f_z min(|v_h| / v_f, 1) v_h / |v_h|

Derivatives beside it (:func:`add_seabed_dv`, the implicit step's block M + h C + h^2 K and right-hand side
h F - h^2 K v): K_zz = k_bot A, C_zz = c_bot A; the friction's velocity Jacobian at fixed f_z is
C_h = mu f_z / v_f I below the friction velocity v_f and mu f_z / |v_h| (I - e e^T), e = v_h / |v_h|, above it.
The static solver takes K_zz on the nodes its active set holds on the seabed.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit, jit_step
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


@jit
def seabed_stiffness_n_m(contact_area, env_f):
    """Normal stiffness [N/m] of the seabed under a node of contact area ``contact_area`` [m^2] pressed into it:
    the slope of :func:`seabed_force`'s unsmoothed normal force."""
    return env_f[EF_KBOT] * contact_area


@jit_step
def add_seabed_dv(node_mm, node_acc, e, h, z, vx, vy, vz, contact_area, env_f):
    """Add the seabed law's linearisation at a node of height ``z`` [m], velocity (vx, vy, vz) [m/s] and contact area
    [m^2] to the implicit step's block ``node_mm[e]`` (h C + h^2 K, xx yy zz xy xz yz) and right-hand side
    ``node_acc[e]`` (-h^2 K v) of the unknown e that carries the node; nothing where the node is not pressed into
    the seabed (see the module docstring)."""
    penetration = -env_f[EF_DEPTH] - z
    if not (penetration > 0.0 and contact_area > 0.0):
        return
    kbot = env_f[EF_KBOT]
    cbot = env_f[EF_CBOT]
    fz = (kbot * penetration - cbot * vz) * contact_area
    if not fz > 0.0:
        return
    node_mm[e, 2] += h * cbot * contact_area + h * h * kbot * contact_area
    node_acc[e, 2] -= h * h * kbot * contact_area * vz
    fric_v = env_f[EF_FRIC_V]
    vh = math.sqrt(vx * vx + vy * vy)
    if vh < fric_v:
        cf = h * env_f[EF_MU] * fz / fric_v
        node_mm[e, 0] += cf
        node_mm[e, 1] += cf
    else:
        cf = h * env_f[EF_MU] * fz / vh
        ex = vx / vh
        ey = vy / vh
        node_mm[e, 0] += cf * (1.0 - ex * ex)
        node_mm[e, 1] += cf * (1.0 - ey * ey)
        node_mm[e, 3] -= cf * ex * ey

"""Point loads on a line node: a lumped body at the node (the release unit on the wire's end) of mass m, displaced
volume V, added-mass coefficient Ca and isotropic drag area Cd A (``layout.NF_POINT_*``).

Its loads on the node::

    f = -(m - rho V) g e_z + 1/2 rho CdA |v_r| v_r,        v_r = u(z) - v,

with u the current at the node's depth, its mass m and its added mass rho V Ca I in the node's 3x3 mass matrix.

Derivative beside it (:func:`add_point_loads_dv`, the implicit step's damping): the drag's velocity Jacobian
-df/dv = df/dv_r = 1/2 rho CdA (|v_r| I + v_r v_r^T / |v_r|), symmetric. The weight does not depend on the
state, so the law adds no stiffness.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit, jit_step
from moor_env.physics.environment import current_velocity
from moor_env.physics.layout import (
    EF_G,
    EF_RHO,
    NF_POINT_CA,
    NF_POINT_CDA,
    NF_POINT_MASS,
    NF_POINT_VOLUME,
)
from moor_env.physics.tree import add_sym


@jit
def has_point_load(node_f, n):
    """Whether node n carries a lumped body (a mass or a displaced volume)."""
    return node_f[n, NF_POINT_MASS] > 0.0 or node_f[n, NF_POINT_VOLUME] > 0.0


@jit
def point_added_mass(node_f, n, rho):
    """Added mass of node n's lumped body [kg], isotropic: rho V Ca (``rho`` the water density [kg/m^3])."""
    return rho * node_f[n, NF_POINT_VOLUME] * node_f[n, NF_POINT_CA]


@jit
def point_relative_velocity(n, node_pos, node_vel, env_f, current_profile):
    """Velocity of the current relative to node n, u(z) - v [m/s]."""
    ux, uy, uz = current_velocity(node_pos[n, 2], env_f, current_profile)
    return ux - node_vel[n, 0], uy - node_vel[n, 1], uz - node_vel[n, 2]


@jit
def _add_isotropic(node_mm, n, mass):
    """Add ``mass`` I to the symmetric 3x3 block ``node_mm[n]``."""
    node_mm[n, 0] += mass
    node_mm[n, 1] += mass
    node_mm[n, 2] += mass


@jit
def add_point_loads(n, node_f, node_pos, node_vel, env_f, current_profile, node_force, node_mm, node_mass):
    """Add the loads of node n's lumped body, if it has one: its mass to ``node_mass`` [kg], its added mass to the
    3x3 mass ``node_mm`` (xx, yy, zz, xy, xz, yz) [kg], its weight less buoyancy and its drag to ``node_force``
    [N]."""
    if not has_point_load(node_f, n):
        return
    rho = env_f[EF_RHO]
    pm = node_f[n, NF_POINT_MASS]
    vol = node_f[n, NF_POINT_VOLUME]
    node_mass[n] += pm
    node_force[n, 2] -= (pm - rho * vol) * env_f[EF_G]
    _add_isotropic(node_mm, n, point_added_mass(node_f, n, rho))
    cda = node_f[n, NF_POINT_CDA]
    if cda > 0.0:
        rx, ry, rz = point_relative_velocity(n, node_pos, node_vel, env_f, current_profile)
        k = 0.5 * rho * cda * math.sqrt(rx * rx + ry * ry + rz * rz)
        node_force[n, 0] += k * rx
        node_force[n, 1] += k * ry
        node_force[n, 2] += k * rz


@jit_step
def add_point_loads_dv(node_mm, e, n, h, node_f, node_pos, node_vel, env_f, current_profile):
    """Add h times the velocity Jacobian of node n's point drag (-df/dv, see the module docstring) to the 3x3 block
    ``node_mm[e]`` of the unknown that carries node n (itself, or its parent if welded)."""
    if not has_point_load(node_f, n):
        return
    rho = env_f[EF_RHO]
    cda = node_f[n, NF_POINT_CDA]
    if cda > 0.0:
        rx, ry, rz = point_relative_velocity(n, node_pos, node_vel, env_f, current_profile)
        vr = math.sqrt(rx * rx + ry * ry + rz * rz)
        if vr > 0.0:
            k = h * 0.5 * rho * cda
            kv = k / vr
            add_sym(node_mm, e, k * vr + kv * rx * rx, k * vr + kv * ry * ry, k * vr + kv * rz * rz,
                    kv * rx * ry, kv * rx * rz, kv * ry * rz)

"""Current field: a piecewise-linear speed profile over depth with one horizontal direction.

The profile array holds (depth below surface [m], speed [m/s]) rows, depths increasing, and ends with the
seabed point (water depth, 0) appended by the compiler, so the speed falls linearly to zero at the seabed
below the deepest user point (the profile of seed 003: Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*,
section 6.4).
"""

from __future__ import annotations

from moor_env.physics._jit import jit
from moor_env.physics.layout import EF_CUR_DX, EF_CUR_DY, EF_CUR_SCALE


@jit
def current_speed(z, env_f, current_profile):
    """Current speed at height ``z`` (negative below the surface) [m/s], already scaled."""
    scale = env_f[EF_CUR_SCALE]
    if scale == 0.0:
        return 0.0
    depth = -z
    n = current_profile.shape[0]
    if depth <= current_profile[0, 0]:
        return scale * current_profile[0, 1]
    for i in range(1, n):
        d1 = current_profile[i, 0]
        if depth <= d1:
            d0 = current_profile[i - 1, 0]
            w = (depth - d0) / (d1 - d0)
            return scale * ((1.0 - w) * current_profile[i - 1, 1] + w * current_profile[i, 1])
    return scale * current_profile[n - 1, 1]


@jit
def current_velocity(z, env_f, current_profile):
    """Current velocity vector (ux, uy, 0) at height ``z`` [m/s]."""
    u = current_speed(z, env_f, current_profile)
    return u * env_f[EF_CUR_DX], u * env_f[EF_CUR_DY], 0.0


@jit
def current_velocity_along(n, last_node, last_u, z, env_f, current_profile):
    """Current velocity (ux, uy, uz) at node ``n`` of height ``z`` [m/s]: ``last_u`` where n is ``last_node``.

    Why: a line's segments run on (the end b of one is the end a of the next), so a pass over the segments that
    keeps the last end's velocity looks the profile up once per node instead of once per segment end."""
    if n == last_node:
        return last_u
    return current_velocity(z, env_f, current_profile)

"""Morison loads shared by line segments and the anchor: drag on the relative velocity and added mass.

Drag per unit length on a slender element with unit tangent q and relative velocity v_r = u_fluid - v
(seed 003: Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, eq. 5-11; MoorDyn ``Line::getStateDeriv``)::

    f = 1/2 rho Cd_n D |v_rn| v_rn  +  1/2 rho Cd_t (pi D) |v_rt| v_rt

with v_rt = (v_r . q) q and v_rn = v_r - v_rt. Added mass per unit length is
rho (pi D^2 / 4) [Ca_n (I - q q^T) + Ca_t q q^T].

Derivatives of the drag, beside it (with c_n = 1/2 rho Cd_n D len, c_t = 1/2 rho Cd_t pi D len, v_t = v_r . q):

- with respect to the structure's velocity (:func:`add_slender_drag_dv`, the implicit step's damping):
  -df/dv = df/dv_r = c_n (|v_rn| (I - q q^T) + v_rn v_rn^T / |v_rn|) + 2 c_t |v_t| q q^T, symmetric;
- with respect to the unit tangent at fixed relative velocity, projected on the tangent's turns
  (:func:`slender_drag_turn`, the static solver's drag stiffness on a line that turns).
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit, jit_step
from moor_env.physics.tree import add_sym


@jit
def slender_drag(vrx, vry, vrz, qx, qy, qz, half_rho_cdn_d_len, half_rho_cdt_pid_len):
    """Drag force on a slender piece of given length [N].

    Parameters
    ----------
    vrx, vry, vrz : float
        Relative velocity fluid minus structure [m/s].
    qx, qy, qz : float
        Unit tangent of the piece.
    half_rho_cdn_d_len : float
        1/2 rho Cd_n D length [kg/m].
    half_rho_cdt_pid_len : float
        1/2 rho Cd_t pi D length [kg/m].
    """
    vt = vrx * qx + vry * qy + vrz * qz
    vnx = vrx - vt * qx
    vny = vry - vt * qy
    vnz = vrz - vt * qz
    vn = math.sqrt(vnx * vnx + vny * vny + vnz * vnz)
    fn = half_rho_cdn_d_len * vn
    ft = half_rho_cdt_pid_len * abs(vt) * vt
    return fn * vnx + ft * qx, fn * vny + ft * qy, fn * vnz + ft * qz


@jit
def add_slender_added_mass(mm, node, qx, qy, qz, normal_mass, tangential_mass):
    """Add ``normal_mass (I - q q^T) + tangential_mass q q^T`` to the 3x3 mass of ``node``.

    ``mm[node]`` holds the symmetric matrix as (xx, yy, zz, xy, xz, yz) [kg].
    """
    d = tangential_mass - normal_mass
    mm[node, 0] += normal_mass + d * qx * qx
    mm[node, 1] += normal_mass + d * qy * qy
    mm[node, 2] += normal_mass + d * qz * qz
    mm[node, 3] += d * qx * qy
    mm[node, 4] += d * qx * qz
    mm[node, 5] += d * qy * qz


@jit
def slender_drag_turn(vrx, vry, vrz, qx, qy, qz, half_rho_cdn_d_len, half_rho_cdt_pid_len, out):
    """The change of :func:`slender_drag` as its unit tangent q turns, at fixed relative velocity:
    ``out = (d f / d q) P`` with P = I - q q^T the turn's projection [N] (the static solver's Jacobian of current
    drag on a line that turns: a segment's end moved by dx turns q by P dx / length).

    With v_t = v_r . q and n = v_r - v_t q (so that n . q = 0 and v_r^T P = n^T):
    d f / d q = -c_n (|n| I + n n^T / |n|)(q v_r^T + v_t I) + c_t |v_t| (2 q v_r^T + v_t I), hence
    (d f / d q) P = (2 c_t |v_t| - c_n |n|) q n^T + (c_t |v_t| - c_n |n|) v_t P - c_n v_t n n^T / |n|.
    """
    vt = vrx * qx + vry * qy + vrz * qz
    n = (vrx - vt * qx, vry - vt * qy, vrz - vt * qz)
    vn = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    q = (qx, qy, qz)
    tangential = half_rho_cdt_pid_len * abs(vt)
    along_q = 2.0 * tangential - half_rho_cdn_d_len * vn
    iso = (tangential - half_rho_cdn_d_len * vn) * vt
    across = -half_rho_cdn_d_len * vt / vn if vn > 0.0 else 0.0
    for i in range(3):
        for j in range(3):
            out[i, j] = (along_q * q[i] * n[j] + iso * ((1.0 if i == j else 0.0) - q[i] * q[j])
                         + across * n[i] * n[j])


@jit_step
def add_slender_drag_dv(mm, n, h, vrx, vry, vrz, qx, qy, qz, cn, ct):
    """Add h * (-d drag / d v) of :func:`slender_drag` (cn = 1/2 rho Cd_n D len, ct = 1/2 rho Cd_t pi D len) to
    the symmetric 3x3 block ``mm[n]`` (xx, yy, zz, xy, xz, yz)."""
    vt = vrx * qx + vry * qy + vrz * qz
    nx = vrx - vt * qx
    ny = vry - vt * qy
    nz = vrz - vt * qz
    vn = math.sqrt(nx * nx + ny * ny + nz * nz)
    # cn (|vn| (I - q q^T) + vn vn^T / |vn|) + 2 ct |vt| q q^T
    iso = h * cn * vn
    qq = h * 2.0 * ct * abs(vt) - iso
    nn = h * cn / vn if vn > 0.0 else 0.0
    add_sym(mm, n, iso + qq * qx * qx + nn * nx * nx, iso + qq * qy * qy + nn * ny * ny,
            iso + qq * qz * qz + nn * nz * nz, qq * qx * qy + nn * nx * ny, qq * qx * qz + nn * nx * nz,
            qq * qy * qz + nn * ny * nz)

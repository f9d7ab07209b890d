"""Rigid dart anchor: an axisymmetric body with distributed Morison loads, free in translation and in the
direction of its axis (pitch and yaw; roll about the axis does not change any load and is not tracked).

Body state (12 floats): COG position r_G, velocity v_G, unit axis e (from back tip to tip; a vertical,
tip-down anchor has e = (0, 0, -1)) and angular velocity omega (kept perpendicular to e). A point at axial
coordinate s (from the COG, + towards the tip) is at r_G + s e and moves at v_G + omega x (s e).

Loads (seed 003: Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, sections 2.5 and 5.2):
- gravity on structure + flooded water at the COG; buoyancy of the outer volume at the centre of buoyancy;
- normal drag 1/2 rho Cd_n D |v_rn| v_rn and skin friction 1/2 rho Cd_t pi D |v_rt| v_rt per metre, by
  section (fins aft have a much larger Cd_n), integrated with midpoint quadrature;
- pressure drag on the tip and back faces, 1/2 rho Cd A |v_ra| v_ra along the axis;
- line loads at attachment points (the chain at the back tip), passed in as forces and moments about the COG.

Equations of motion with Morison added mass m_a(s) on the normal acceleration of each section: axially
M_ax a_ax = F . e; in the normal plane, with P = I - e e^T and b = alpha x e,

    [[M + A0, A1], [A1, I_G + A2]] [P a_G, b] = [P F, M_G x e],

where A_k = integral of m_a(s) s^k ds (point masses at attachments enter A0, A1, A2 too). The Munk moment
and centripetal terms of off-COG masses are not modelled (as in the RIFLEX and MoorDyn references).
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics._jit import jit
from moor_env.physics.environment import current_velocity
from moor_env.physics.hydro import slender_drag
from moor_env.physics.layout import (
    BF_BACK_CDA,
    BF_BUOYANCY,
    BF_M11,
    BF_M12,
    BF_M22,
    BF_MASS_AXIAL,
    BF_S_BACK,
    BF_S_BUOY,
    BF_S_TIP,
    BF_TIP_CDA,
    BF_WEIGHT,
    BQ_CDN_D,
    BQ_CDT_PID,
    BQ_DS,
    BQ_S,
    BS_AXIS,
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    EF_RHO,
)


@jit
def tilt_deg(ez):
    """Angle of the anchor axis from vertical, tip down [deg], from the axis' vertical component ``ez``
    (acos(-e_z); 0 for e = (0, 0, -1))."""
    return math.degrees(math.acos(min(1.0, max(-1.0, -ez))))


@jit
def tilt_deg_array(ez):
    """:func:`tilt_deg` of every entry of the 1-D array ``ez``."""
    out = np.empty(ez.shape[0])
    for i in range(ez.shape[0]):
        out[i] = tilt_deg(ez[i])
    return out


@jit
def body_point(body_state, s):
    """Position and velocity of the body point at axial coordinate ``s`` [m, m/s]."""
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    wx = body_state[BS_OMEGA]
    wy = body_state[BS_OMEGA + 1]
    wz = body_state[BS_OMEGA + 2]
    px = body_state[BS_POS] + s * ex
    py = body_state[BS_POS + 1] + s * ey
    pz = body_state[BS_POS + 2] + s * ez
    vx = body_state[BS_VEL] + s * (wy * ez - wz * ey)
    vy = body_state[BS_VEL + 1] + s * (wz * ex - wx * ez)
    vz = body_state[BS_VEL + 2] + s * (wx * ey - wy * ex)
    return px, py, pz, vx, vy, vz


@jit
def body_loads(body_state, body_f, body_q, env_f, current_profile, load):
    """Add the anchor's own loads (gravity, buoyancy, drag) to ``load`` = (F [N], M about COG [N m])."""
    rho = env_f[EF_RHO]
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    load[2] += body_f[BF_BUOYANCY] - body_f[BF_WEIGHT]
    sb = body_f[BF_S_BUOY] * body_f[BF_BUOYANCY]
    load[3] += sb * ey
    load[4] -= sb * ex
    for q in range(body_q.shape[0]):
        s = body_q[q, BQ_S]
        px, py, pz, vx, vy, vz = body_point(body_state, s)
        ux, uy, uz = current_velocity(pz, env_f, current_profile)
        ds = body_q[q, BQ_DS]
        fx, fy, fz = slender_drag(ux - vx, uy - vy, uz - vz, ex, ey, ez,
                                  0.5 * rho * body_q[q, BQ_CDN_D] * ds, 0.5 * rho * body_q[q, BQ_CDT_PID] * ds)
        _add_load_at(load, s, ex, ey, ez, fx, fy, fz)
    for end in range(2):
        s = body_f[BF_S_TIP] if end == 0 else body_f[BF_S_BACK]
        cda = body_f[BF_TIP_CDA] if end == 0 else body_f[BF_BACK_CDA]
        px, py, pz, vx, vy, vz = body_point(body_state, s)
        ux, uy, uz = current_velocity(pz, env_f, current_profile)
        va = (ux - vx) * ex + (uy - vy) * ey + (uz - vz) * ez
        f = 0.5 * rho * cda * abs(va) * va
        _add_load_at(load, s, ex, ey, ez, f * ex, f * ey, f * ez)


@jit
def _add_load_at(load, s, ex, ey, ez, fx, fy, fz):
    load[0] += fx
    load[1] += fy
    load[2] += fz
    load[3] += s * (ey * fz - ez * fy)
    load[4] += s * (ez * fx - ex * fz)
    load[5] += s * (ex * fy - ey * fx)


@jit
def add_point_load(load, body_state, s, fx, fy, fz):
    """Add a force applied at axial coordinate ``s`` (e.g. chain tension at the back tip) to ``load``."""
    _add_load_at(load, s, body_state[BS_AXIS], body_state[BS_AXIS + 1], body_state[BS_AXIS + 2], fx, fy, fz)


@jit
def body_acceleration(body_state, body_f, load, acc):
    """Solve the rigid-body equations for ``acc`` = (a_G [m/s^2], alpha [rad/s^2]) from ``load``."""
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    fa = load[0] * ex + load[1] * ey + load[2] * ez
    pfx = load[0] - fa * ex
    pfy = load[1] - fa * ey
    pfz = load[2] - fa * ez
    # M_G x e
    mex = load[4] * ez - load[5] * ey
    mey = load[5] * ex - load[3] * ez
    mez = load[3] * ey - load[4] * ex
    m11 = body_f[BF_M11]
    m12 = body_f[BF_M12]
    m22 = body_f[BF_M22]
    inv_det = 1.0 / (m11 * m22 - m12 * m12)
    a_ax = fa / body_f[BF_MASS_AXIAL]
    pax = (m22 * pfx - m12 * mex) * inv_det
    pay = (m22 * pfy - m12 * mey) * inv_det
    paz = (m22 * pfz - m12 * mez) * inv_det
    bx = (m11 * mex - m12 * pfx) * inv_det
    by = (m11 * mey - m12 * pfy) * inv_det
    bz = (m11 * mez - m12 * pfz) * inv_det
    acc[0] = pax + a_ax * ex
    acc[1] = pay + a_ax * ey
    acc[2] = paz + a_ax * ez
    # alpha = e x b
    acc[3] = ey * bz - ez * by
    acc[4] = ez * bx - ex * bz
    acc[5] = ex * by - ey * bx


@jit
def rotate_axis(body_state, src, wx, wy, wz, dt):
    """Set the axis to ``src`` (3 floats) rotated by omega*dt (Rodrigues), renormalised; drop omega's roll."""
    sx = src[0]
    sy = src[1]
    sz = src[2]
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    angle = w * dt
    if angle > 0.0:
        kx = wx / w
        ky = wy / w
        kz = wz / w
        c = math.cos(angle)
        sn = math.sin(angle)
        kd = kx * sx + ky * sy + kz * sz
        cx = ky * sz - kz * sy
        cy = kz * sx - kx * sz
        cz = kx * sy - ky * sx
        sx, sy, sz = (sx * c + cx * sn + kx * kd * (1.0 - c), sy * c + cy * sn + ky * kd * (1.0 - c),
                      sz * c + cz * sn + kz * kd * (1.0 - c))
    norm = math.sqrt(sx * sx + sy * sy + sz * sz)
    body_state[BS_AXIS] = sx / norm
    body_state[BS_AXIS + 1] = sy / norm
    body_state[BS_AXIS + 2] = sz / norm
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    roll = body_state[BS_OMEGA] * ex + body_state[BS_OMEGA + 1] * ey + body_state[BS_OMEGA + 2] * ez
    body_state[BS_OMEGA] -= roll * ex
    body_state[BS_OMEGA + 1] -= roll * ey
    body_state[BS_OMEGA + 2] -= roll * ez

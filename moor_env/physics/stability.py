"""Stable explicit time step of a compiled model.

The fastest mode of a lumped-mass line is bounded with Gershgorin's theorem on M^-1 K: for node i,
omega_max^2 <= 2 * sum(EA_s / l0_s over its segments) / m_i, which is exact (2 sqrt(EA/w) / l) for a uniform
line. Payout lines are bounded at their shortest allowed top segment. The step is
``safety * h_max(zeta) / omega_max`` where h_max is the integrator's stability limit for a mode with
damping ratio zeta (symplectic Euler: 2 (sqrt(1 + zeta^2) - zeta); RK2: from its amplification factor,
which needs zeta > 0 at all). Seabed contact, seabed friction and line drag at ``reference_speed_m_s``
give further limits; the smallest wins.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics.layout import (
    EF_CBOT,
    EF_FRIC_V,
    EF_G,
    EF_KBOT,
    EF_MU,
    EF_RHO,
    LF_L_MIN_TOP,
    LI_NSEG,
    LI_PAYOUT,
    LI_SEG_START,
    MF_CDN,
    MF_D,
    MF_EA,
    MF_MASS,
    MF_SUBMERGED,
    MF_ZETA,
    NF_POINT_MASS,
    NI_KIND,
    NI_REF,
    NODE_FREE,
    NODE_WELDED,
    SF_L0,
    SI_A,
    SI_ACTIVE,
    SI_B,
    SI_MAT,
)

REFERENCE_SPEED_M_S = 40.0


def stability_limit(integrator: str, zeta: float) -> float:
    """Largest omega*dt for which the integrator is stable on x'' + 2 zeta w x' + w^2 x = 0."""
    if integrator == "symplectic_euler":
        return 2.0 * (math.sqrt(1.0 + zeta * zeta) - zeta)

    def radius(h: float) -> float:
        a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]]) * h
        return float(max(abs(np.linalg.eigvals(np.eye(2) + a + a @ a / 2.0))))

    if radius(1e-3) > 1.0 + 1e-12:
        return 0.0
    lo, hi = 1e-3, 4.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if radius(mid) <= 1.0 + 1e-12:
            lo = mid
        else:
            hi = mid
    return lo


def stable_time_step(model_arrays: dict, integrator: str) -> tuple[float, str]:
    """Stability limit of the explicit step for the current topology [s] and what sets it.

    Parameters
    ----------
    model_arrays : dict
        ``node_i``, ``node_f``, ``seg_i``, ``seg_f``, ``mat_f``, ``line_i``, ``line_f``, ``env_f``.
    integrator : str
        ``symplectic_euler`` or ``rk2``.

    Returns
    -------
    dt_limit_s : float
        Largest stable step (no safety factor) [s].
    governed_by : str
        Short description of the limiting mechanism.
    """
    node_i, node_f = model_arrays["node_i"], model_arrays["node_f"]
    seg_i, seg_f, mat_f = model_arrays["seg_i"], model_arrays["seg_f"], model_arrays["mat_f"]
    line_i, line_f, env_f = model_arrays["line_i"], model_arrays["line_f"], model_arrays["env_f"]
    nn = node_i.shape[0]
    owner = np.arange(nn)
    welded = node_i[:, NI_KIND] == NODE_WELDED
    owner[welded] = node_i[welded, NI_REF]
    mass = node_f[:, NF_POINT_MASS].copy()
    stiff = np.zeros(nn)
    weight = np.zeros(nn)
    contact = np.zeros(nn)
    drag = np.zeros(nn)
    zeta_max = 0.0
    active = np.nonzero(seg_i[:, SI_ACTIVE])[0]
    rho, g = env_f[EF_RHO], env_f[EF_G]
    for s in active:
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        zeta_max = max(zeta_max, mat_f[m, MF_ZETA])
        for n in (seg_i[s, SI_A], seg_i[s, SI_B]):
            o = owner[n]
            mass[o] += 0.5 * l0 * mat_f[m, MF_MASS]
            stiff[o] += mat_f[m, MF_EA] / l0
            weight[o] += 0.5 * l0 * max(mat_f[m, MF_SUBMERGED], 0.0) * g
            contact[o] += 0.5 * l0 * mat_f[m, MF_D]
            drag[o] += rho * mat_f[m, MF_CDN] * mat_f[m, MF_D] * 0.5 * l0 * REFERENCE_SPEED_M_S
    for n in np.nonzero(welded)[0]:
        mass[owner[n]] += mass[n]
        mass[n] = 0.0
    free = (node_i[:, NI_KIND] == NODE_FREE) & (mass > 0)
    limits: list[tuple[float, str]] = []
    h_axial = stability_limit(integrator, zeta_max)
    if h_axial <= 0.0:
        raise ValueError(f"integrator {integrator} is unstable without axial damping (axial_damping_ratio = 0)")
    if np.any(free):
        omega2 = 2.0 * stiff[free] / mass[free]
        limits.append((h_axial / math.sqrt(omega2.max()), "axial segment mode"))
    for line in range(line_i.shape[0]):
        if line_i[line, LI_PAYOUT] and line_i[line, LI_NSEG] >= 2:
            k = line_i[line, LI_SEG_START] + line_i[line, LI_NSEG] - 1
            m = seg_i[k, SI_MAT]
            l_below = seg_f[k - 1, SF_L0]
            l_top = line_f[line, LF_L_MIN_TOP]
            omega2 = 2.0 * (mat_f[m, MF_EA] / l_below + mat_f[m, MF_EA] / l_top) / (
                0.5 * mat_f[m, MF_MASS] * (l_below + l_top))
            limits.append((h_axial / math.sqrt(omega2), "shortest payout segment"))
    if np.any(free):
        kbot, cbot = env_f[EF_KBOT], env_f[EF_CBOT]
        omega_c = np.sqrt(kbot * contact[free] / mass[free])
        zeta_c = cbot * contact[free] / (2.0 * mass[free] * np.maximum(omega_c, 1e-12))
        worst = int(np.argmax(omega_c))
        h_c = stability_limit(integrator, max(float(zeta_c[worst]), 1e-3))
        limits.append((h_c / float(omega_c[worst]), "seabed contact"))
        friction_rate = env_f[EF_MU] * weight[free] / env_f[EF_FRIC_V] / mass[free]
        if friction_rate.max() > 0:
            limits.append((2.0 / float(friction_rate.max()), "seabed friction"))
        drag_rate = drag[free] / mass[free]
        if drag_rate.max() > 0:
            limits.append((2.0 / float(drag_rate.max()), f"line drag at {REFERENCE_SPEED_M_S:.0f} m/s"))
    if not limits:
        return math.inf, "no line"
    return min(limits)

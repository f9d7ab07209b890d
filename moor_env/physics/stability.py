"""Stable explicit time step of a compiled model.

The fastest mode of a lumped-mass line is bounded with Gershgorin's theorem on M^-1 K: for node i,
omega_max^2 <= 2 * sum(EA_s / l0_s over its segments) / m_i, which is exact (2 sqrt(EA/w) / l) for a uniform
line. Payout lines are bounded at their shortest allowed top segment. The step is
``safety * h_max(zeta) / omega_max`` where h_max is the integrator's stability limit for a mode with
damping ratio zeta (symplectic Euler: 2 (sqrt(1 + zeta^2) - zeta); RK2: from its amplification factor,
which needs zeta > 0 at all). Seabed contact, seabed friction and line drag at ``reference_speed_m_s``
give further limits; the smallest wins. ``implicit_euler`` has none of these limits; its step is capped by
the accuracy of its linearisation (:func:`implicit_time_step`).
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
    MF_SEABED_D,
    MF_SUBMERGED,
    MF_ZETA,
    NF_POINT_MASS,
    NI_KIND,
    NI_REF,
    NODE_BODY,
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
    if integrator == "implicit_euler":
        return math.inf  # linearly implicit backward Euler: A-stable on the linearised modes

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
        ``symplectic_euler``, ``rk2`` or ``implicit_euler`` (see :func:`implicit_time_step`).

    Returns
    -------
    dt_limit_s : float
        Largest stable step (no safety factor) [s].
    governed_by : str
        Short description of the limiting mechanism.
    """
    if integrator == "implicit_euler":
        return implicit_time_step(model_arrays)
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
    active = np.nonzero(seg_i[:, SI_ACTIVE])[0]
    rho, g = env_f[EF_RHO], env_f[EF_G]
    m = seg_i[active, SI_MAT]
    l0 = seg_f[active, SF_L0]
    zeta_max = max(float(mat_f[m, MF_ZETA].max()), 0.0) if active.size else 0.0
    # each segment's share to both its ends, end A before end B, segment by segment (np.add.at sums in that order)
    ends = owner[np.stack([seg_i[active, SI_A], seg_i[active, SI_B]], axis=1).ravel()]
    np.add.at(mass, ends, np.repeat(0.5 * l0 * mat_f[m, MF_MASS], 2))
    np.add.at(stiff, ends, np.repeat(mat_f[m, MF_EA] / l0, 2))
    np.add.at(weight, ends, np.repeat(0.5 * l0 * np.maximum(mat_f[m, MF_SUBMERGED], 0.0) * g, 2))
    np.add.at(contact, ends, np.repeat(0.5 * l0 * mat_f[m, MF_SEABED_D], 2))
    np.add.at(drag, ends, np.repeat(rho * mat_f[m, MF_CDN] * mat_f[m, MF_D] * 0.5 * l0 * REFERENCE_SPEED_M_S, 2))
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


IMPLICIT_SEGMENT_CROSSING = 0.5


def implicit_time_step(model_arrays: dict) -> tuple[float, str]:
    """Largest step of ``implicit_euler`` [s] (the default is ``dt_safety`` times it) and what sets it.

    The linearly implicit step has no axial, drag, seabed or friction limit (all linearised), so what is left
    is the accuracy of the linearisation itself: the Jacobians are taken at the start of the step, and the
    segment directions they contain must not turn much within it. The step is capped so that a node moving at
    ``REFERENCE_SPEED_M_S`` crosses at most ``IMPLICIT_SEGMENT_CROSSING`` of the shortest segment (payout lines
    at their shortest allowed top segment). Measured against symplectic Euler at its limit (1 m chain, cap
    12.5 ms, default 11.25 ms): touchdown speed within 0.1 % on gjoa-500 and the vertical chain, 0.3 % and
    0.1 deg on spacing 170 m with a 10 m vertical chain; at 3x the cap still stable (1.8 %, 0.3 deg on that
    case), at 8x (a node crossing two segments per step) the strain limit is hit. Where the chain loop snaps
    taut just before touchdown (spacing 170 m, 50 m vertical chain) the speed is 2-4 % low at any step from
    0.5 to 20 ms: backward Euler makes the snap inelastic and instantaneous, and only steps that resolve the
    axial waves (about 0.2 ms) recover the explicit result.
    """
    seg_i, seg_f = model_arrays["seg_i"], model_arrays["seg_f"]
    line_i, line_f = model_arrays["line_i"], model_arrays["line_f"]
    active = np.nonzero(seg_i[:, SI_ACTIVE])[0]
    if active.size == 0:
        return math.inf, "no line"
    _check_tree(model_arrays["node_i"], seg_i[active])
    shortest = float(seg_f[active, SF_L0].min())
    for line in range(line_i.shape[0]):
        if line_i[line, LI_PAYOUT]:
            shortest = min(shortest, float(line_f[line, LF_L_MIN_TOP]))
    limit = IMPLICIT_SEGMENT_CROSSING * shortest / REFERENCE_SPEED_M_S
    return limit, (f"segment rotation per step (a node at {REFERENCE_SPEED_M_S:.0f} m/s crosses "
                   f"{IMPLICIT_SEGMENT_CROSSING:g} of the shortest segment, {shortest:.3g} m)")


def _check_tree(node_i: np.ndarray, segs: np.ndarray) -> None:
    """Raise ValueError unless the free nodes (welded ones merged into their parent, the anchor's nodes into
    one vertex) and the segments between them form a forest with at most one line attachment on the anchor:
    what ``implicit_euler``'s O(N) solver and its anchor coupling need."""
    kind = node_i[:, NI_KIND]
    vertex = np.where((kind == NODE_FREE) | (kind == NODE_BODY), np.arange(kind.size), -1)
    body = np.nonzero(kind == NODE_BODY)[0]
    if body.size:
        vertex[body] = body[0]
    welded = np.nonzero(kind == NODE_WELDED)[0]
    vertex[welded] = vertex[node_i[welded, NI_REF]]
    parent = np.arange(kind.size)

    def root(v: int) -> int:
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    attached = set()
    for a, b in zip(vertex[segs[:, SI_A]], vertex[segs[:, SI_B]], strict=True):
        if a < 0 or b < 0 or a == b:
            continue
        for end, other in ((a, b), (b, a)):
            if kind[end] == NODE_BODY:
                attached.add(int(other))
        ra, rb = root(int(a)), root(int(b))
        if ra == rb:
            raise ValueError("implicit_euler needs the lines between free nodes and the anchor to form a tree "
                             "(a closed loop was found)")
        parent[ra] = rb
    if len(attached) > 1:
        raise ValueError("implicit_euler couples the anchor through a single line attachment "
                         f"({len(attached)} found)")

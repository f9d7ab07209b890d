"""Lumped-mass lines: axial elasticity (tension only), internal damping, Morison loads, weight, payout.

Each segment is an axial spring-damper between two nodes (MoorDyn ``Line::getStateDeriv``; seed 003, Landhaug 2015,
*Dynamic Simulation of Dart Anchor Installation*, section 2.3, uses beams, a chain has EI ~ 0). Tension is EA *
strain + BA * strain rate with BA = zeta * l0 * sqrt(EA * w) (zeta is the damping ratio of one segment's axial
mode), and is never negative: a slack segment (stretched length <= l0) carries nothing, and a straightening slack
segment is not damped. (The static solver's first phase replaces the kink at zero strain by the smooth EA (strain +
sqrt(strain^2 + s^2)) / 2, then polishes with the exact law.) Half of each segment's mass, net weight, drag and
added mass go to each end node; the drag of each half uses that end node's velocity and the segment's tangent, which
damps odd-even node modes too.

Payout: the top segment's unstretched length changes at the winch rate; above ``L_MAX_TOP`` it splits
(a new node at ``L_NOM`` from the node below), below ``L_MIN_TOP`` it merges with the segment below. Mass
per metre times unstretched length is therefore conserved exactly, and segment lengths stay within
[L_MIN_TOP, L_MAX_TOP], which the time-step limit accounts for.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit
from moor_env.physics.environment import current_velocity_along
from moor_env.physics.hydro import add_slender_added_mass, slender_drag
from moor_env.physics.layout import (
    EF_G,
    EF_RHO,
    EF_SLACK_SMOOTHING,
    LF_L_MAX_TOP,
    LF_L_MIN_TOP,
    LF_L_NOM,
    LF_MAX_TENSION,
    LF_RATE,
    LI_CLAMPED,
    LI_NODE_CAP,
    LI_NODE_START,
    LI_NSEG,
    LI_PAYOUT,
    LI_SEG_CAP,
    LI_SEG_START,
    MF_CAN,
    MF_CAT,
    MF_CDN,
    MF_CDT,
    MF_D,
    MF_EA,
    MF_MASS,
    MF_SEABED_D,
    MF_SUBMERGED,
    MF_ZETA,
    NI_KIND,
    NI_LINE,
    NODE_FREE,
    NODE_INACTIVE,
    NODE_VESSEL,
    SF_L0,
    SI_A,
    SI_ACTIVE,
    SI_B,
    SI_LINE,
    SI_MAT,
)


@jit
def segment_axis(node_pos, a, b):
    """Stretched length [m] and unit tangent (from node a to node b) of a segment; +z for a zero-length one."""
    dx = node_pos[b, 0] - node_pos[a, 0]
    dy = node_pos[b, 1] - node_pos[a, 1]
    dz = node_pos[b, 2] - node_pos[a, 2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length > 0.0:
        return length, dx / length, dy / length, dz / length
    return length, 0.0, 0.0, 1.0


@jit
def segment_damping_n_s(mat_f, m, l0):
    """BA = zeta l0 sqrt(EA w) [N s]: a segment's tension per unit strain rate (material m, unstretched length
    ``l0`` [m])."""
    return mat_f[m, MF_ZETA] * l0 * math.sqrt(mat_f[m, MF_EA] * mat_f[m, MF_MASS])


@jit
def segment_damping_n_s_m(mat_f, m):
    """BA / l0 = zeta sqrt(EA w) [N s/m]: a segment's tension per unit rate of stretch (material m)."""
    return mat_f[m, MF_ZETA] * math.sqrt(mat_f[m, MF_EA] * mat_f[m, MF_MASS])


@jit
def axial_tension_n(mat_f, m, l0, strain, strain_rate_1_s):
    """The axial law of a segment (material m, unstretched length ``l0`` [m]): the linear spring-damper
    EA strain + BA strain rate [N], unclipped. A line carries no compression: the loads take it where the segment is
    stretched and clip it at 0; the implicit step linearises it on its active set with the derivatives of
    :func:`axial_derivatives`."""
    return mat_f[m, MF_EA] * strain + segment_damping_n_s(mat_f, m, l0) * strain_rate_1_s


@jit
def axial_derivatives(mat_f, m, l0):
    """Derivatives of :func:`axial_tension_n` with respect to the segment's length, EA / l0 [N/m], and to the rate
    of its length, BA / l0 [N s/m]."""
    return mat_f[m, MF_EA] / l0, segment_damping_n_s_m(mat_f, m)


@jit
def smoothed_tension_n(ea, strain, smoothing):
    """The static solver's tension-only law with its kink rounded over the strain scale ``smoothing``:
    EA (strain + sqrt(strain^2 + smoothing^2)) / 2 [N] (no damping: the statics have no velocities)."""
    return 0.5 * ea * (strain + math.sqrt(strain * strain + smoothing * smoothing))


@jit
def smoothed_tension_slope_n(ea, strain, smoothing):
    """Derivative of :func:`smoothed_tension_n` with respect to the strain [N]."""
    return 0.5 * ea * (1.0 + strain / math.sqrt(strain * strain + smoothing * smoothing))


@jit
def half_segment_morison(mat_f, m, l0, rho):
    """Morison coefficients of the half of a segment (material m, unstretched length ``l0`` [m]) that each end
    node carries, in water of density ``rho`` [kg/m^3]: normal and tangential drag factors ``0.5 rho C_D A``
    [kg/m] (the arguments of :func:`moor_env.physics.hydro.slender_drag`) and normal and tangential added mass
    [kg]."""
    half = 0.5 * l0
    d = mat_f[m, MF_D]
    drag_n = 0.5 * rho * mat_f[m, MF_CDN] * d * half
    drag_t = 0.5 * rho * mat_f[m, MF_CDT] * math.pi * d * half
    volume = 0.25 * math.pi * d * d * half
    return drag_n, drag_t, rho * volume * mat_f[m, MF_CAN], rho * volume * mat_f[m, MF_CAT]


@jit
def segment_loads(node_pos, node_vel, seg_i, seg_f, mat_f, line_f, env_f, current_profile,
                  node_force, node_mm, node_mass, node_contact, seg_tension):
    """Accumulate every active segment's loads on its end nodes.

    Writes ``seg_tension`` [N] and adds into ``node_force`` [N], ``node_mm`` (added mass, 6 entries)
    [kg], ``node_mass`` [kg] and ``node_contact`` (seabed contact area) [m^2]. Updates the running
    maximum tension per line in ``line_f``.

    Returns
    -------
    max_strain : float
        Largest strain of any segment (NaN propagates).
    worst_segment : int
        Segment index of ``max_strain``.
    """
    rho = env_f[EF_RHO]
    g = env_f[EF_G]
    smoothing = env_f[EF_SLACK_SMOOTHING]
    max_strain = 0.0
    worst = -1
    last_node = -1  # the end b of the last segment, and the current velocity there
    last_u = (0.0, 0.0, 0.0)
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        strain = (length - l0) / l0
        if strain > max_strain:
            max_strain = strain
            worst = s
        elif strain != strain and max_strain == max_strain:
            max_strain = strain
            worst = s
        tension = 0.0
        if smoothing > 0.0:
            tension = smoothed_tension_n(mat_f[m, MF_EA], strain, smoothing)
        elif strain > 0.0:
            rate = ((node_vel[b, 0] - node_vel[a, 0]) * qx + (node_vel[b, 1] - node_vel[a, 1]) * qy
                    + (node_vel[b, 2] - node_vel[a, 2]) * qz) / l0
            tension = axial_tension_n(mat_f, m, l0, strain, rate)
            if tension < 0.0:
                tension = 0.0
        seg_tension[s] = tension
        line = seg_i[s, SI_LINE]
        if tension > line_f[line, LF_MAX_TENSION]:
            line_f[line, LF_MAX_TENSION] = tension
        half = 0.5 * l0
        bearing = mat_f[m, MF_SEABED_D] * half  # seabed contact area the segment gives each end
        drag_n, drag_t, ma_n, ma_t = half_segment_morison(mat_f, m, l0, rho)
        half_mass = mat_f[m, MF_MASS] * half
        half_weight = mat_f[m, MF_SUBMERGED] * half * g
        for end in range(2):
            n = a if end == 0 else b
            sign = 1.0 if end == 0 else -1.0
            ux, uy, uz = current_velocity_along(n, last_node, last_u, node_pos[n, 2], env_f, current_profile)
            if end == 1:
                last_node, last_u = n, (ux, uy, uz)
            fx, fy, fz = slender_drag(ux - node_vel[n, 0], uy - node_vel[n, 1], uz - node_vel[n, 2],
                                      qx, qy, qz, drag_n, drag_t)
            node_force[n, 0] += fx + sign * tension * qx
            node_force[n, 1] += fy + sign * tension * qy
            node_force[n, 2] += fz + sign * tension * qz - half_weight
            add_slender_added_mass(node_mm, n, qx, qy, qz, ma_n, ma_t)
            node_mass[n] += half_mass
            node_contact[n] += bearing
    return max_strain, worst


@jit
def apply_payout(dt, node_pos, node_vel, node_i, seg_i, seg_f, line_i, line_f):
    """Advance every paying-out line's top segment by ``rate * dt``; split or merge at the limits."""
    for line in range(line_i.shape[0]):
        rate = line_f[line, LF_RATE]
        if line_i[line, LI_PAYOUT] == 0 or rate == 0.0:
            continue
        nseg = line_i[line, LI_NSEG]
        k = line_i[line, LI_SEG_START] + nseg - 1
        new_l0 = seg_f[k, SF_L0] + rate * dt
        if rate > 0.0 and new_l0 > line_f[line, LF_L_MAX_TOP]:
            if nseg >= line_i[line, LI_SEG_CAP] or nseg > line_i[line, LI_NODE_CAP]:
                line_i[line, LI_CLAMPED] = 1
                continue
            _split_top(line, k, new_l0, node_pos, node_vel, node_i, seg_i, seg_f, line_i, line_f)
        elif rate < 0.0 and new_l0 < line_f[line, LF_L_MIN_TOP]:
            if nseg < 2 or seg_i[k - 1, SI_MAT] != seg_i[k, SI_MAT]:
                seg_f[k, SF_L0] = line_f[line, LF_L_MIN_TOP]
                line_i[line, LI_CLAMPED] = 1
                continue
            _merge_top(line, k, new_l0, node_i, seg_i, seg_f, line_i)
        else:
            seg_f[k, SF_L0] = new_l0


@jit
def _split_top(line, k, new_l0, node_pos, node_vel, node_i, seg_i, seg_f, line_i, line_f):
    nseg = line_i[line, LI_NSEG]
    lower = seg_i[k, SI_A]
    top = seg_i[k, SI_B]
    new = line_i[line, LI_NODE_START] + nseg - 1
    l_nom = line_f[line, LF_L_NOM]
    frac = l_nom / new_l0
    for c in range(3):
        node_pos[new, c] = node_pos[lower, c] + frac * (node_pos[top, c] - node_pos[lower, c])
        node_vel[new, c] = node_vel[lower, c] + frac * (node_vel[top, c] - node_vel[lower, c])
    node_i[new, NI_KIND] = NODE_FREE
    node_i[new, NI_LINE] = line
    seg_i[k, SI_B] = new
    seg_f[k, SF_L0] = l_nom
    seg_i[k + 1, SI_A] = new
    seg_i[k + 1, SI_B] = top
    seg_i[k + 1, SI_MAT] = seg_i[k, SI_MAT]
    seg_i[k + 1, SI_LINE] = line
    seg_i[k + 1, SI_ACTIVE] = 1
    seg_f[k + 1, SF_L0] = new_l0 - l_nom
    line_i[line, LI_NSEG] = nseg + 1


@jit
def _merge_top(line, k, new_l0, node_i, seg_i, seg_f, line_i):
    removed = seg_i[k, SI_A]
    seg_i[k - 1, SI_B] = seg_i[k, SI_B]
    seg_f[k - 1, SF_L0] += new_l0
    seg_i[k, SI_ACTIVE] = 0
    node_i[removed, NI_KIND] = NODE_INACTIVE
    line_i[line, LI_NSEG] -= 1


@jit
def top_tensions(line_i, seg_i, node_i, node_force, seg_tension, out):
    """Load of each line on its vessel [N] into ``out[line]``, from loads already evaluated at the state: the
    resultant force on the top node (top segment's tension plus the top half-segment's weight and drag) where
    the line ends at a vessel, else its top segment's tension; 0 for a dropped line."""
    for line in range(line_i.shape[0]):
        k = line_i[line, LI_SEG_START] + line_i[line, LI_NSEG] - 1
        top = seg_i[k, SI_B]
        if seg_i[k, SI_ACTIVE] == 0:
            out[line] = 0.0
        elif node_i[top, NI_KIND] == NODE_VESSEL:
            out[line] = math.sqrt(node_force[top, 0] ** 2 + node_force[top, 1] ** 2 + node_force[top, 2] ** 2)
        else:
            out[line] = seg_tension[k]

"""Linearly implicit (Rosenbrock-type) backward Euler step for the line nodes, coupled to the explicit anchor.

Why: the explicit integrators are limited by the axial mode of one chain segment, omega = 2 sqrt(EA/w)/l
(about 4000 rad/s for 1 m of 142 mm chain, dt ~ 0.34 ms). Here the stiff parts are linearised and solved
for, so the step is limited by accuracy only (see ``stability.implicit_time_step``).

One step of length h from (x, v), loads F(x, v) evaluated by ``compute_accelerations`` (added mass in the
node mass matrix M). With K = -dF/dx and C = -dF/dv of the linearised parts (both symmetric, >= 0)::

    (M + h C + h^2 K) dv = h F - h^2 K v,        v1 = v + dv,        x1 = x + h v1

i.e. one Newton iteration of backward Euler on the momentum equations, with the stiff terms evaluated at
(x1, v1). Backward Euler is L-stable: unresolved modes (the axial waves) are damped out, never amplified, and a
segment snapping taut within a step is an inelastic event. Linearised (implicit) parts:

- axial spring-damper of every segment in the step's active (taut) set: K_s = EA/l0 q q^T + (T/len)(I - q q^T),
  C_s = BA/l0 q q^T (the geometric term keeps the transverse string and pendulum modes implicit too). Segments
  outside the set carry no tension (the tension-only law). The set is predicted to the *end* of the step: start
  from the segments taut now, solve, predict every segment's strain and tension at the end of the step from the
  solution (both > 0: taut), and solve again while segments change set (each may change once per step, at most
  ``MAX_ACTIVE_SET_SOLVES`` solves; typically 1-2; segments enter before any leaves, see
  ``_update_active_set``). A segment entering the set brings its linear law
  (unclipped, so the solve sees where it goes taut), one leaving it no tension. Without this, a segment going
  taut inside a step was stretched explicitly and sprang back elastically in the next one, and on a slack
  chain these snaps ran along it one segment per step and grew until the strain limit;
- line drag per half segment (the exact 3x3 Jacobian of the Morison drag, ``hydro.add_slender_drag_dv``,
  skipped where h times its damping rate is below ``DRAG_SKIP`` of the node mass, i.e. where explicit drag is
  far from any limit); point-mass drag;
- seabed contact (vertical spring-damper) and regularised Coulomb friction (its damping slope below the
  friction velocity, its transverse slope above it);
- the anchor through the node at its back tip: the anchor's own loads stay explicit (it is heavy and its
  drag is not stiff), but the line's reaction on it is solved with the lines. After the line tree hanging
  from the body node p is eliminated it is a 3x3 impedance S_p and impulse rho_p at p; with the anchor's
  point mobility W = J M_b^-1 J^T (axial 1/M_ax, normal (m22 - 2 s m12 + s^2 m11)/det) and the explicit body
  velocity increment u0 at p, the line impulse on the anchor f solves (I + S_p W) f = rho_p - S_p u0. Only the
  first body node is coupled so (compile time refuses a second attachment); others count as prescribed.

Weight, buoyancy and everything else are explicit. The anchor is then advanced like symplectic Euler with its
corrected acceleration; nodes set from the anchor, vessels and welded parents are placed by the caller.

Solver: the block tree elimination of ``physics/tree.py`` (O(N), no fill-in), with the body node as the root of
its component. Its ordering depends on the topology alone, so it is kept from one step to the next and rebuilt
only where the caller cannot vouch for the topology (``reuse_order`` false): at the first step of every
``advance`` call (release, a dropped line, a restored state happen between calls) and after a step whose payout
split or merged a segment. A kept order is the one a rebuild would give, so results are the same bit for bit
(tested). A closed loop of lines is refused at compile time (``stability.implicit_time_step``).

Scratch memory (no new workspace arrays, no allocation per step, ``advance``'s signature unchanged): the step
reuses the simulator's workspace. ``node_mm`` holds the diagonal blocks and, after elimination, their
inverses; ``node_acc`` the right-hand sides and finally dv/h (the effective acceleration of the step);
``pos0``/``vel0`` (the RK2 midpoint's scratch, otherwise unused) are viewed as int64 for the tree ordering and
the active set, and keep the ordering between steps. ``node_force``, ``node_mass``, ``node_contact`` and
``seg_tension`` keep the loads at the start of the step, as after an explicit step (the step evaluates them
with ``compute_loads``: the explicit node accelerations would only be overwritten); ``node_mm`` does not hold
the added mass afterwards: call ``compute_accelerations`` (the simulator's ``evaluate_loads``) for loads, as
every output already does.

Cost (``benchmarks/bench_implicit_step.py``, ~110 active segments): about 15 us per step with one solve, in
roughly equal parts loads, assembly and elimination with back substitution. The kernels use ``jit_step``
(numpy's error model): without a zero test before every division they are ~30 % faster.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics._jit import jit_step
from moor_env.physics.anchor import rotate_axis
from moor_env.physics.environment import current_velocity
from moor_env.physics.hydro import add_slender_added_mass, add_slender_drag_dv
from moor_env.physics.layout import (
    BF_M11,
    BF_M12,
    BF_M22,
    BF_MASS_AXIAL,
    BS_AXIS,
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    EF_CBOT,
    EF_DEPTH,
    EF_FRIC_V,
    EF_KBOT,
    EF_MU,
    EF_RHO,
    MF_CAN,
    MF_CAT,
    MF_CDN,
    MF_CDT,
    MF_D,
    MF_EA,
    MF_MASS,
    MF_ZETA,
    NF_BODY_S,
    NF_POINT_CA,
    NF_POINT_CDA,
    NF_POINT_VOLUME,
    NI_KIND,
    NODE_BODY,
    NODE_FREE,
    SF_L0,
    SI_A,
    SI_ACTIVE,
    SI_B,
    SI_MAT,
)
from moor_env.physics.line import segment_axis
from moor_env.physics.tree import (
    OR_EFF,
    OR_FLAGS,
    OR_ORDER,
    TR_DEG,
    TR_NB,
    TR_SEG,
    add_sym,
    back_from_parent,
    build_tree,
    count_unknowns,
    invert_block,
    order,
    schur_into_parent,
)

# int64 views of pos0 (tree) and vel0 (orow); bits 2 (s & 31) and 2 (s & 31) + 1 of word s >> 5 of
# orow[:, OR_FLAGS]: segment s is taut / has changed set
MAX_ACTIVE_SET_SOLVES = 8
SET_TOLERANCE = 1e-6  # strain by which a segment must miss its predicted set before the step is solved again
DRAG_SKIP = 0.02  # drag of a half segment is linearised only where h * (its damping rate) exceeds this


@jit_step
def _is_active(orow, s):
    """Bit 2s of the flag words: segment s is in the active (taut) set (the words hold 32 segments per node;
    a segment beyond that, which no compiled model has, is never active and so stays explicit)."""
    if (s >> 5) >= orow.shape[0]:
        return 0
    return (orow[s >> 5, OR_FLAGS] >> (2 * (s & 31))) & 1


@jit_step
def _is_frozen(orow, s):
    """Bit 2s + 1: segment s has already changed set once in this step."""
    return (orow[s >> 5, OR_FLAGS] >> (2 * (s & 31) + 1)) & 1


@jit_step
def _flip(orow, s):
    """Toggle the active bit of segment s and freeze it for the rest of the step."""
    orow[s >> 5, OR_FLAGS] ^= np.int64(1) << (2 * (s & 31))
    orow[s >> 5, OR_FLAGS] |= np.int64(1) << (2 * (s & 31) + 1)


@jit_step
def _segment_gain(s, h, orow, node_pos, seg_i, seg_f, mat_f, seg_tension):
    """G_s = h C_s + h^2 K_s = alpha q q^T + beta I of an active segment, with its unit tangent.

    Returns (alpha, beta, qx, qy, qz, kq, kt), with K_s = kq q q^T + kt (I - q q^T) [N/m]; zeros for a
    segment outside the active set.
    """
    if _is_active(orow, s) == 0:
        return 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0
    a = seg_i[s, SI_A]
    b = seg_i[s, SI_B]
    m = seg_i[s, SI_MAT]
    l0 = seg_f[s, SF_L0]
    length, qx, qy, qz = segment_axis(node_pos, a, b)
    ea = mat_f[m, MF_EA]
    kq = ea / l0
    cq = mat_f[m, MF_ZETA] * math.sqrt(ea * mat_f[m, MF_MASS])  # BA / l0
    kt = seg_tension[s] / length
    alpha = h * cq + h * h * (kq - kt)
    beta = h * h * kt
    return alpha, beta, qx, qy, qz, kq, kt


@jit_step
def _init_active_set(seg_i, seg_tension, orow):
    """Initial active set: the coupling segments taut at the start of the step."""
    nn = orow.shape[0]
    for w in range(min(nn, ((seg_i.shape[0] - 1) >> 5) + 1)):
        orow[w, OR_FLAGS] = 0
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0 or not (seg_tension[s] > 0.0) or (s >> 5) >= nn:
            continue
        if orow[seg_i[s, SI_A], OR_EFF] != orow[seg_i[s, SI_B], OR_EFF]:
            orow[s >> 5, OR_FLAGS] |= np.int64(1) << (2 * (s & 31))


@jit_step
def _setup(body_node, node_i, seg_i, seg_tension, tree, orow):
    """Effective unknown of every node, tree degrees and neighbour/segment sums, initial active set."""
    build_tree(body_node, node_i, seg_i, tree, orow)
    _init_active_set(seg_i, seg_tension, orow)


@jit_step
def _prepare(reuse_order, body_node, node_i, seg_i, seg_tension, tree, orow):
    """Elimination order (rebuilt unless ``reuse_order``: the topology is that of the previous implicit step
    and its order is still in the scratch) and the initial active set; returns the number of unknowns ordered.
    """
    if not reuse_order:
        _setup(body_node, node_i, seg_i, seg_tension, tree, orow)
        return order(body_node, node_i, seg_i, tree, orow)
    _init_active_set(seg_i, seg_tension, orow)
    return count_unknowns(body_node, orow)


@jit_step
def _assemble(h, first, body_node, node_pos, node_vel, node_i, node_f, seg_i, seg_f, mat_f, env_f,
              current_profile, node_force, node_mm, node_mass, node_contact, node_acc, seg_tension, orow):
    """Diagonal blocks (node_mm) and right-hand sides (node_acc) for the current active set.

    On the first call node_mm still holds the added mass from the load evaluation; later calls rebuild it.
    """
    nn = node_i.shape[0]
    rho = env_f[EF_RHO]
    depth = env_f[EF_DEPTH]
    for n in range(nn):
        if orow[n, OR_EFF] != n:
            continue
        if n == body_node:
            for c in range(6):
                node_mm[n, c] = 0.0
            for c in range(3):
                node_acc[n, c] = 0.0
            continue
        if not first:
            for c in range(6):
                node_mm[n, c] = 0.0
        node_mm[n, 0] += node_mass[n]
        node_mm[n, 1] += node_mass[n]
        node_mm[n, 2] += node_mass[n]
        for c in range(3):
            node_acc[n, c] = h * node_force[n, c]
    # point loads: added mass, point-mass drag, seabed contact and friction
    kbot = env_f[EF_KBOT]
    cbot = env_f[EF_CBOT]
    mu = env_f[EF_MU]
    fric_v = env_f[EF_FRIC_V]
    for n in range(nn):
        e = orow[n, OR_EFF]
        if e < 0 or e == body_node:
            continue
        if not first:
            ma = rho * node_f[n, NF_POINT_VOLUME] * node_f[n, NF_POINT_CA]
            node_mm[e, 0] += ma
            node_mm[e, 1] += ma
            node_mm[e, 2] += ma
        cda = node_f[n, NF_POINT_CDA]
        if cda > 0.0:
            ux, uy, uz = current_velocity(node_pos[n, 2], env_f, current_profile)
            rx = ux - node_vel[n, 0]
            ry = uy - node_vel[n, 1]
            rz = uz - node_vel[n, 2]
            vr = math.sqrt(rx * rx + ry * ry + rz * rz)
            if vr > 0.0:
                k = h * 0.5 * rho * cda
                kv = k / vr
                add_sym(node_mm, e, k * vr + kv * rx * rx, k * vr + kv * ry * ry, k * vr + kv * rz * rz,
                         kv * rx * ry, kv * rx * rz, kv * ry * rz)
        area = node_contact[n]
        penetration = -depth - node_pos[n, 2]
        if penetration > 0.0 and area > 0.0:
            vx = node_vel[n, 0]
            vy = node_vel[n, 1]
            vz = node_vel[n, 2]
            fz = (kbot * penetration - cbot * vz) * area
            if fz > 0.0:
                node_mm[e, 2] += h * cbot * area + h * h * kbot * area
                node_acc[e, 2] -= h * h * kbot * area * vz
                vh = math.sqrt(vx * vx + vy * vy)
                if vh < fric_v:
                    cf = h * mu * fz / fric_v
                    node_mm[e, 0] += cf
                    node_mm[e, 1] += cf
                else:
                    cf = h * mu * fz / vh
                    ex = vx / vh
                    ey = vy / vh
                    node_mm[e, 0] += cf * (1.0 - ex * ex)
                    node_mm[e, 1] += cf * (1.0 - ey * ey)
                    node_mm[e, 3] -= cf * ex * ey
    # segments: added mass (rebuild), drag Jacobians, axial spring-damper of the active set
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        ea = orow[a, OR_EFF]
        eb = orow[b, OR_EFF]
        if ea < 0 and eb < 0:
            continue
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        half = 0.5 * l0
        d = mat_f[m, MF_D]
        cn = 0.5 * rho * mat_f[m, MF_CDN] * d * half
        ct = 0.5 * rho * mat_f[m, MF_CDT] * math.pi * d * half
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        volume = 0.25 * math.pi * d * d * half
        for end in range(2):
            n = a if end == 0 else b
            e = ea if end == 0 else eb
            if e < 0 or e == body_node:
                continue
            if not first:
                add_slender_added_mass(node_mm, e, qx, qy, qz, rho * volume * mat_f[m, MF_CAN],
                                       rho * volume * mat_f[m, MF_CAT])
            if cn > 0.0 or ct > 0.0:
                ux, uy, uz = current_velocity(node_pos[n, 2], env_f, current_profile)
                rx = ux - node_vel[n, 0]
                ry = uy - node_vel[n, 1]
                rz = uz - node_vel[n, 2]
                # linearise only where the drag is stiff on this step's scale (h * rate > DRAG_SKIP)
                c = h * (cn + 2.0 * ct)
                if c * c * (rx * rx + ry * ry + rz * rz) > (DRAG_SKIP * node_mass[e]) ** 2:
                    add_slender_drag_dv(node_mm, e, h, rx, ry, rz, qx, qy, qz, cn, ct)
        if ea == eb:
            continue
        tension = seg_tension[s]
        rx = node_vel[b, 0] - node_vel[a, 0]
        ry = node_vel[b, 1] - node_vel[a, 1]
        rz = node_vel[b, 2] - node_vel[a, 2]
        rq = rx * qx + ry * qy + rz * qz
        if _is_active(orow, s) == 0:
            if tension == 0.0:
                continue
            # leaves the active set during the step: no tension at its end
            fx = -h * tension * qx
            fy = -h * tension * qy
            fz = -h * tension * qz
        else:
            ea_ = mat_f[m, MF_EA]
            cq = mat_f[m, MF_ZETA] * math.sqrt(ea_ * mat_f[m, MF_MASS])
            kq = ea_ / l0
            kt = tension / length
            # unclipped tension of the linear law minus the (clipped) tension already in the loads
            t_lin = ea_ * (length - l0) / l0 + cq * rq
            alpha = h * cq + h * h * (kq - kt)
            beta = h * h * kt
            w = h * (t_lin - tension) + h * h * (kq - kt) * rq
            # h (t_lin - T) q + h^2 K_s (v_b - v_a), acting on node a (minus on b)
            fx = w * qx + h * h * kt * rx
            fy = w * qy + h * h * kt * ry
            fz = w * qz + h * h * kt * rz
            gxx = alpha * qx * qx + beta
            gyy = alpha * qy * qy + beta
            gzz = alpha * qz * qz + beta
            gxy = alpha * qx * qy
            gxz = alpha * qx * qz
            gyz = alpha * qy * qz
            if ea >= 0:
                add_sym(node_mm, ea, gxx, gyy, gzz, gxy, gxz, gyz)
            if eb >= 0:
                add_sym(node_mm, eb, gxx, gyy, gzz, gxy, gxz, gyz)
        if ea >= 0:
            node_acc[ea, 0] += fx
            node_acc[ea, 1] += fy
            node_acc[ea, 2] += fz
        if eb >= 0:
            node_acc[eb, 0] -= fx
            node_acc[eb, 1] -= fy
            node_acc[eb, 2] -= fz


@jit_step
def _eliminate(h, nq, node_pos, seg_i, seg_f, mat_f, seg_tension, node_mm, node_acc, tree, orow):
    """Forward elimination, leaves first: node_mm <- D^-1, node_acc <- y = D^-1 r; Schur terms into parents."""
    for k in range(nq):
        c = orow[k, OR_ORDER]
        invert_block(node_mm, node_acc, c)
        if tree[c, TR_DEG] != -1:
            continue
        alpha, beta, qx, qy, qz, kq, kt = _segment_gain(tree[c, TR_SEG], h, orow, node_pos, seg_i, seg_f, mat_f,
                                                        seg_tension)
        if alpha == 0.0 and beta == 0.0:
            continue
        schur_into_parent(node_mm, node_acc, c, tree[c, TR_NB], alpha, beta, qx, qy, qz)


@jit_step
def _back_substitute(h, nq, node_pos, seg_i, seg_f, mat_f, seg_tension, node_mm, node_acc, tree, orow):
    """Root first: dv_c = y_c + D_c^-1 G dv_parent (node_acc <- dv)."""
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        if tree[c, TR_DEG] != -1:
            continue
        alpha, beta, qx, qy, qz, kq, kt = _segment_gain(tree[c, TR_SEG], h, orow, node_pos, seg_i, seg_f, mat_f,
                                                        seg_tension)
        if alpha == 0.0 and beta == 0.0:
            continue
        back_from_parent(node_mm, node_acc, c, tree[c, TR_NB], alpha, beta, qx, qy, qz)


@jit_step
def _update_active_set(h, node_pos, node_vel, seg_i, seg_f, mat_f, node_acc, orow):
    """Predict every segment's strain and tension at the end of the step from the solved dv; a segment is
    active (taut) iff both are positive. Returns the number of segments that changed.

    Entries first: while some slack segment is predicted taut, no taut one leaves the set in the same pass
    (they are judged again on the next solve, with the entering segments carrying load). A solve that misses a
    taut segment misplaces the nodes it would have held, and the segments beside them can then look
    compressed; as a segment changes set at most once per step, letting them leave on that evidence froze a
    wrong set. Measured: a hanging chain loop at a 0.5 s step dropped five consecutive loop segments from the
    set while a fibre segment went taut, and the next step stretched them 105 % (blow-up).
    """
    entries, exits = _pass_active_set(h, node_pos, node_vel, seg_i, seg_f, mat_f, node_acc, orow, False)
    if entries > 0 or exits == 0:
        return entries
    return _pass_active_set(h, node_pos, node_vel, seg_i, seg_f, mat_f, node_acc, orow, True)[1]


@jit_step
def _pass_active_set(h, node_pos, node_vel, seg_i, seg_f, mat_f, node_acc, orow, flip_exits):
    """One pass of :func:`_update_active_set`: flip the slack segments predicted taut (and, with ``flip_exits``,
    the taut ones predicted slack); returns (entries, exits), the exits counted whether flipped or not."""
    entries = 0
    exits = 0
    nn = orow.shape[0]
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0 or (s >> 5) >= nn or _is_frozen(orow, s) == 1:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        ea = orow[a, OR_EFF]
        eb = orow[b, OR_EFF]
        if ea == eb:
            continue
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        rate0 = ((node_vel[b, 0] - node_vel[a, 0]) * qx + (node_vel[b, 1] - node_vel[a, 1]) * qy
                 + (node_vel[b, 2] - node_vel[a, 2]) * qz) / l0
        ddx = 0.0
        ddy = 0.0
        ddz = 0.0
        if eb >= 0:
            ddx += node_acc[eb, 0]
            ddy += node_acc[eb, 1]
            ddz += node_acc[eb, 2]
        if ea >= 0:
            ddx -= node_acc[ea, 0]
            ddy -= node_acc[ea, 1]
            ddz -= node_acc[ea, 2]
        drate = (ddx * qx + ddy * qy + ddz * qz) / l0
        rate1 = rate0 + drate  # strain rate at the end of the step
        strain1 = (length - l0) / l0 + h * rate1
        ea_ = mat_f[m, MF_EA]
        t1 = ea_ * strain1 + mat_f[m, MF_ZETA] * l0 * math.sqrt(ea_ * mat_f[m, MF_MASS]) * rate1
        if _is_active(orow, s) == 1:
            if strain1 < -SET_TOLERANCE or t1 < -SET_TOLERANCE * ea_:
                exits += 1
                if flip_exits:
                    _flip(orow, s)
        elif strain1 > SET_TOLERANCE and t1 > SET_TOLERANCE * ea_:
            entries += 1
            _flip(orow, s)
    return entries, exits


@jit_step
def _couple_body(h, p, body_state, node_f, body_f, body_acc, node_mm, node_acc):
    """Solve the line impulse on the anchor at node p implicitly; node_acc[p] <- dv_p.

    node_mm[p] holds S (the eliminated lines' impedance at p), node_acc[p] holds rho; ``body_acc`` is the
    explicit acceleration (not changed). Returns the correction of the anchor's acceleration (6 values).
    """
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    s = node_f[p, NF_BODY_S]
    m_ax = body_f[BF_MASS_AXIAL]
    m11 = body_f[BF_M11]
    m12 = body_f[BF_M12]
    m22 = body_f[BF_M22]
    det = m11 * m22 - m12 * m12
    w_ax = 1.0 / m_ax
    w_n = (m22 - 2.0 * s * m12 + s * s * m11) / det
    # explicit velocity increment of the body point: h (a_G + s alpha x e)
    ax = body_acc[3]
    ay = body_acc[4]
    az = body_acc[5]
    u0x = h * (body_acc[0] + s * (ay * ez - az * ey))
    u0y = h * (body_acc[1] + s * (az * ex - ax * ez))
    u0z = h * (body_acc[2] + s * (ax * ey - ay * ex))
    s11 = node_mm[p, 0]
    s22 = node_mm[p, 1]
    s33 = node_mm[p, 2]
    s12 = node_mm[p, 3]
    s13 = node_mm[p, 4]
    s23 = node_mm[p, 5]
    # W = w_n I + (w_ax - w_n) e e^T
    dw = w_ax - w_n
    w11 = w_n + dw * ex * ex
    w22 = w_n + dw * ey * ey
    w33 = w_n + dw * ez * ez
    w12 = dw * ex * ey
    w13 = dw * ex * ez
    w23 = dw * ey * ez
    # (I + S W) f = rho - S u0
    a11 = 1.0 + s11 * w11 + s12 * w12 + s13 * w13
    a12 = s11 * w12 + s12 * w22 + s13 * w23
    a13 = s11 * w13 + s12 * w23 + s13 * w33
    a21 = s12 * w11 + s22 * w12 + s23 * w13
    a22 = 1.0 + s12 * w12 + s22 * w22 + s23 * w23
    a23 = s12 * w13 + s22 * w23 + s23 * w33
    a31 = s13 * w11 + s23 * w12 + s33 * w13
    a32 = s13 * w12 + s23 * w22 + s33 * w23
    a33 = 1.0 + s13 * w13 + s23 * w23 + s33 * w33
    bx = node_acc[p, 0] - (s11 * u0x + s12 * u0y + s13 * u0z)
    by = node_acc[p, 1] - (s12 * u0x + s22 * u0y + s23 * u0z)
    bz = node_acc[p, 2] - (s13 * u0x + s23 * u0y + s33 * u0z)
    c11 = a22 * a33 - a23 * a32
    c12 = a13 * a32 - a12 * a33
    c13 = a12 * a23 - a13 * a22
    c21 = a23 * a31 - a21 * a33
    c22 = a11 * a33 - a13 * a31
    c23 = a13 * a21 - a11 * a23
    c31 = a21 * a32 - a22 * a31
    c32 = a12 * a31 - a11 * a32
    c33 = a11 * a22 - a12 * a21
    inv = 1.0 / (a11 * c11 + a12 * c21 + a13 * c31)
    fx = (c11 * bx + c12 * by + c13 * bz) * inv
    fy = (c21 * bx + c22 * by + c23 * bz) * inv
    fz = (c31 * bx + c32 * by + c33 * bz) * inv
    # dv_p = u0 + W f
    node_acc[p, 0] = u0x + w11 * fx + w12 * fy + w13 * fz
    node_acc[p, 1] = u0y + w12 * fx + w22 * fy + w23 * fz
    node_acc[p, 2] = u0z + w13 * fx + w23 * fy + w33 * fz
    # M_b^-1 J^T f / h: the line impulse f applied at s (axial, normal translation, alpha = e x b)
    fa = fx * ex + fy * ey + fz * ez
    pfx = fx - fa * ex
    pfy = fy - fa * ey
    pfz = fz - fa * ez
    ca = fa / (m_ax * h)
    cp = (m22 - s * m12) / (det * h)
    cb = (m11 * s - m12) / (det * h)
    return (ca * ex + cp * pfx, ca * ey + cp * pfy, ca * ez + cp * pfz, cb * (ey * pfz - ez * pfy),
            cb * (ez * pfx - ex * pfz), cb * (ex * pfy - ey * pfx))


@jit_step
def implicit_euler_update(h, body_active, node_pos, node_vel, body_state, node_i, node_f, seg_i, seg_f, mat_f,
                          body_f, env_f, current_profile, node_force, node_mm, node_mass, node_contact, node_acc,
                          seg_tension, body_acc, pos0, vel0, body0, reuse_order):
    """Advance free nodes and the anchor by one linearly implicit step (loads already evaluated at the start).

    Expects the workspace as left by ``compute_loads`` at (x, v) and ``body0`` = anchor state at the start.
    Writes positions/velocities of free nodes, the anchor state and ``body_acc`` (corrected). ``reuse_order``:
    the caller guarantees that the topology (node kinds, segments) is that of the previous implicit step on the
    same workspace, whose elimination order is then kept.

    Returns
    -------
    vmax2 : float
        Largest squared speed of a free node (NaN if any is non-finite).
    worst_node : int
    body_v2 : float
        Squared speed of the anchor's COG.
    """
    nn = node_i.shape[0]
    tree = pos0.view(np.int64)
    orow = vel0.view(np.int64)
    body_node = -1
    if body_active:
        for n in range(nn):
            if node_i[n, NI_KIND] == NODE_BODY:
                body_node = n
                break
    nq = _prepare(reuse_order, body_node, node_i, seg_i, seg_tension, tree, orow)
    c0 = c1 = c2 = c3 = c4 = c5 = 0.0
    for it in range(MAX_ACTIVE_SET_SOLVES):
        _assemble(h, it == 0, body_node, node_pos, node_vel, node_i, node_f, seg_i, seg_f, mat_f, env_f,
                  current_profile, node_force, node_mm, node_mass, node_contact, node_acc, seg_tension, orow)
        _eliminate(h, nq, node_pos, seg_i, seg_f, mat_f, seg_tension, node_mm, node_acc, tree, orow)
        if body_node >= 0:
            c0, c1, c2, c3, c4, c5 = _couple_body(h, body_node, body_state, node_f, body_f, body_acc, node_mm,
                                                  node_acc)
        _back_substitute(h, nq, node_pos, seg_i, seg_f, mat_f, seg_tension, node_mm, node_acc, tree, orow)
        if _update_active_set(h, node_pos, node_vel, seg_i, seg_f, mat_f, node_acc, orow) == 0:
            break
    body_v2 = 0.0
    if body_active:
        body_acc[0] += c0
        body_acc[1] += c1
        body_acc[2] += c2
        body_acc[3] += c3
        body_acc[4] += c4
        body_acc[5] += c5
        wx = body0[BS_OMEGA] + h * body_acc[3]
        wy = body0[BS_OMEGA + 1] + h * body_acc[4]
        wz = body0[BS_OMEGA + 2] + h * body_acc[5]
        for c in range(3):
            body_state[BS_VEL + c] = body0[BS_VEL + c] + h * body_acc[c]
            body_state[BS_OMEGA + c] = body0[BS_OMEGA + c] + h * body_acc[3 + c]
            body_state[BS_POS + c] = body0[BS_POS + c] + h * body_state[BS_VEL + c]
            body_v2 += body_state[BS_VEL + c] ** 2
        rotate_axis(body_state, body0[BS_AXIS:BS_AXIS + 3], wx, wy, wz, h)
    # v += dv, x += h v; node_acc <- dv / h (the step's effective acceleration)
    vmax2 = 0.0
    worst = -1
    inv_h = 1.0 / h
    for n in range(nn):
        if node_i[n, NI_KIND] != NODE_FREE:
            continue
        v2 = 0.0
        for c in range(3):
            dv = node_acc[n, c]
            v = node_vel[n, c] + dv
            node_vel[n, c] = v
            node_pos[n, c] += h * v
            node_acc[n, c] = dv * inv_h
            v2 += v * v
        if not (v2 <= vmax2):
            vmax2 = v2
            worst = n
            if v2 != v2:
                return v2, n, body_v2
    return vmax2, worst, body_v2

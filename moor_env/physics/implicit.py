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
  ``MAX_ACTIVE_SET_SOLVES`` solves; typically 1-3; segments enter before any leaves, see
  ``implicit_active_set.update_active_set``). A segment entering the set brings its linear law
  (unclipped, so the solve sees where it goes taut), one leaving it no tension. An active segment that the
  solve turns so far that its end chord |d0 + h (v1_b - v1_a)| passes the linear prediction by
  ``TURN_TOLERANCE`` (strain) is linearised again at that chord and the step solved again, one more Newton
  iteration on its spring: the turn would otherwise stretch it by about (h v_perp)^2 / (2 l0), which the next
  load evaluation reads as tension (24 MN on a 1 m chain segment turning at 15 m/s over 11.25 ms). A segment
  entering the set is linearised along the direction the solve gave its end chord
  (``implicit_active_set._enter_along_end_chord``), which saves the turn check's solve. A taut segment is not
  linearised along a chord predicted from its start velocities: where a chain piles up on the falling anchor the
  step reverses those velocities, and fall steps linearised so end at about three times the chain's MBL in most
  crew episodes (``benchmarks/mbl_exceedance.py``). Without the
  end-of-step set, a segment going taut inside a step would be stretched explicitly and spring back elastically in
  the next one, and on a slack chain these snaps would run along it one segment per step and grow until the strain
  limit;
- line drag per half segment (the exact 3x3 Jacobian of the Morison drag, ``hydro.add_slender_drag_dv``,
  skipped where h times its damping rate is below ``DRAG_SKIP`` of the node mass, i.e. where explicit drag is
  far from any limit); point-mass drag (``point_loads.add_point_loads_dv``);
- seabed contact (vertical spring-damper) and regularised Coulomb friction (its damping slope below the
  friction velocity, its transverse slope above it; ``seabed.add_seabed_dv``);
- the anchor through the node at its back tip: the anchor's own loads stay explicit (it is heavy and its
  drag is not stiff), but the line's reaction on it is solved with the lines. After the line tree hanging
  from the body node p is eliminated it is a 3x3 impedance S_p and impulse rho_p at p; with the anchor's
  point mobility W = J M_b^-1 J^T (axial 1/M_ax, normal (m22 - 2 s m12 + s^2 m11)/det) and the explicit body
  velocity increment u0 at p, the line impulse on the anchor f solves (I + S_p W) f = rho_p - S_p u0. Only the
  first body node is coupled so (compile time refuses a second attachment); others count as prescribed.

Weight, buoyancy and everything else are explicit. The anchor is then advanced like symplectic Euler with its
corrected acceleration; nodes set from the anchor, vessels and welded parents are placed by the caller.

The assembly of the block system is in ``physics/implicit_assembly.py``, the active set in
``physics/implicit_active_set.py``, the line-anchor contact in ``physics/implicit_contact.py`` and its set in
``physics/implicit_contact_set.py``. Solver: the block tree elimination of ``physics/tree.py`` (O(N), no fill-in),
with the body node as the root of its component. Its ordering depends on the topology alone, so it is kept from
one step to the next and rebuilt only where the caller cannot vouch for the topology (``reuse_order`` false): at
the first step of every ``advance`` call (release, a dropped line, a restored state happen between calls) and
after a step whose payout split or merged a segment. A kept order is the one a rebuild would give, so results are
the same bit for bit (tested). A closed loop of lines is refused at compile time (``stability.implicit_time_step``).

Scratch memory (no allocation per step): the step reuses the state record's work arrays. ``node_mm`` holds the
diagonal blocks and, after elimination, their inverses; ``node_acc`` the right-hand sides and finally dv/h (the
effective acceleration of the step); ``node_base`` the part of the blocks and right-hand sides that the active set
leaves unchanged (all but the springs and the line-anchor contact), which a step's later solves start from
(``implicit_assembly.assemble``); ``seg_gain`` each segment's block G_s of the present solve, for the elimination
and the back substitution; ``pos0``/``vel0`` (the RK2 midpoint's scratch, otherwise unused) are viewed as int64 for
the tree ordering and the active set, and keep the ordering between steps. ``node_force``, ``node_mass``,
``node_contact`` and ``seg_tension`` keep the loads at the start of the step, as after an explicit step (the step
evaluates them with ``compute_loads``: the explicit node accelerations would only be overwritten); ``node_mm`` does
not hold the added mass afterwards: call ``compute_accelerations`` (the simulator's ``evaluate_loads``) for loads,
as every output already does.

Cost: ``benchmarks/bench_implicit_step.py`` times each piece of a step (``docs/implicit-step.md``). The kernels use
``jit_step`` (numpy's error model): without a zero test before every division they are ~30 % faster.
"""

from __future__ import annotations

import numpy as np

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor import body_acceleration, rotate_axis
from moor_env.physics.contact import record_contact_force
from moor_env.physics.implicit_active_set import init_active_set, update_active_set
from moor_env.physics.implicit_assembly import assemble
from moor_env.physics.implicit_contact import any_law, assemble_contact, contact_reaction
from moor_env.physics.implicit_contact_set import init_contact_set, update_contact_set
from moor_env.physics.layout import (
    BF_ACTIVE,
    BF_M11,
    BF_M12,
    BF_M22,
    BF_MASS_AXIAL,
    BS_AXIS,
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    CF_ON,
    NF_BODY_S,
    NI_KIND,
    NODE_BODY,
    NODE_FREE,
)
from moor_env.physics.tree import (
    OR_ORDER,
    TR_DEG,
    TR_NB,
    TR_SEG,
    back_from_parent,
    build_tree,
    count_unknowns,
    invert_block,
    order,
    schur_into_parent,
)

MAX_ACTIVE_SET_SOLVES = 8


@jit_no_refcount
def prepare(reuse_order, body_node, state, tree, orow):
    """Elimination order (rebuilt unless ``reuse_order``: the topology is that of the previous implicit step
    and its order is still in the scratch) and the initial active set; returns the number of unknowns ordered.
    """
    node_i = state.node_i
    seg_i = state.seg_i
    if not reuse_order:
        build_tree(body_node, node_i, seg_i, tree, orow)
        init_active_set(seg_i, state.seg_tension, state.seg_chord, orow)
        return order(body_node, node_i, seg_i, tree, orow)
    init_active_set(seg_i, state.seg_tension, state.seg_chord, orow)
    return count_unknowns(body_node, orow)


@jit_no_refcount
def eliminate(nq, state, tree, orow):
    """Forward elimination, leaves first: node_mm <- D^-1, node_acc <- y = D^-1 r; Schur terms into parents, each
    segment's block G_s as the assembly kept it (``state.seg_gain``)."""
    node_mm, node_acc, seg_gain = state.node_mm, state.node_acc, state.seg_gain
    for k in range(nq):
        c = orow[k, OR_ORDER]
        invert_block(node_mm, node_acc, c)
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        alpha, beta = seg_gain[s, 0], seg_gain[s, 1]
        if alpha == 0.0 and beta == 0.0:
            continue
        schur_into_parent(node_mm, node_acc, c, tree[c, TR_NB], alpha, beta, seg_gain[s, 2], seg_gain[s, 3],
                          seg_gain[s, 4])


@jit_no_refcount
def back_substitute(nq, state, tree, orow):
    """Root first: dv_c = y_c + D_c^-1 G dv_parent (node_acc <- dv)."""
    node_mm, node_acc, seg_gain = state.node_mm, state.node_acc, state.seg_gain
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        alpha, beta = seg_gain[s, 0], seg_gain[s, 1]
        if alpha == 0.0 and beta == 0.0:
            continue
        back_from_parent(node_mm, node_acc, c, tree[c, TR_NB], alpha, beta, seg_gain[s, 2], seg_gain[s, 3],
                         seg_gain[s, 4])


@jit_step
def couple_body(h, p, model, state):
    """Solve the line impulse on the anchor at node p implicitly; node_acc[p] <- dv_p.

    node_mm[p] holds S (the eliminated lines' impedance at p), node_acc[p] holds rho; ``body_acc`` is the
    explicit acceleration (not changed). Returns the correction of the anchor's acceleration (6 values).
    """
    body_f, body_state, body_acc = model.body_f, state.body_state, state.body_acc
    node_mm, node_acc = state.node_mm, state.node_acc
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    s = state.node_f[p, NF_BODY_S]
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


@jit_no_refcount
def implicit_euler_update(model, state, h, reuse_order):
    """Advance free nodes and the anchor by one linearly implicit step of ``h`` [s] (loads already evaluated at
    the start).

    Expects the work arrays as left by ``compute_loads`` at (x, v) and ``body0`` = anchor state at the start.
    Writes positions/velocities of free nodes, the anchor state and ``body_acc`` (corrected). ``reuse_order``:
    the caller guarantees that the topology (node kinds, segments) is that of the previous implicit step on the
    same state, whose elimination order is then kept.

    Returns
    -------
    vmax2 : float
        Largest squared speed of a free node (NaN if any is non-finite).
    worst_node : int
    body_v2 : float
        Squared speed of the anchor's COG.
    closing2 : float
        Largest squared speed of a free node relative to the COG (the line-anchor contact's neighbour list,
        ``contact_broadphase.note_moved``; 0 without the contact).
    """
    node_pos, node_vel, body_state = state.node_pos, state.node_vel, state.body_state
    node_i, node_acc, body_acc = state.node_i, state.node_acc, state.body_acc
    body0 = state.body0
    body_active = model.body_f[BF_ACTIVE] != 0.0
    nn = node_i.shape[0]
    tree = state.pos0.view(np.int64)
    orow = state.vel0.view(np.int64)
    body_node = -1
    if body_active:
        for n in range(nn):
            if node_i[n, NI_KIND] == NODE_BODY:
                body_node = n
                break
    nq = prepare(reuse_order, body_node, state, tree, orow)
    contact = body_active and model.contact_f[CF_ON] != 0.0
    if contact:
        init_contact_set(h, model, state)
    c0 = c1 = c2 = c3 = c4 = c5 = 0.0
    for it in range(MAX_ACTIVE_SET_SOLVES):
        assemble(h, it == 0, body_node, model, state, orow)
        if contact and any_law(state.contact_set, state.segment_set):
            assemble_contact(h, model, state)
        eliminate(nq, state, tree, orow)
        if body_node >= 0:
            c0, c1, c2, c3, c4, c5 = couple_body(h, body_node, model, state)
        back_substitute(nq, state, tree, orow)
        changed = update_active_set(h, model, state, orow)
        if contact:
            changed += update_contact_set(h, model, state)
        if changed == 0:
            break
    body_v2 = 0.0
    if contact and not any_law(state.contact_set, state.segment_set):
        record_contact_force(state.contact_out, 0.0, 0.0, 0.0)
    elif contact and contact_reaction(h, model, state):
        # the anchor takes the opposite of the contact impulses the solve gave the nodes
        body_acceleration(body_state, model.body_f, state.body_load, body_acc)
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
    closing2 = 0.0
    worst = -1
    inv_h = 1.0 / h
    gvx = body_state[BS_VEL] if contact else 0.0
    gvy = body_state[BS_VEL + 1] if contact else 0.0
    gvz = body_state[BS_VEL + 2] if contact else 0.0
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
        if contact:
            closing2 = max(closing2, (node_vel[n, 0] - gvx) ** 2 + (node_vel[n, 1] - gvy) ** 2
                           + (node_vel[n, 2] - gvz) ** 2)
        if not (v2 <= vmax2):
            vmax2 = v2
            worst = n
            if v2 != v2:
                return v2, n, body_v2, closing2
    return vmax2, worst, body_v2, closing2

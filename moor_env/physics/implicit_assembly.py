"""Assembly of the implicit step's block system (``physics/implicit.py``): the diagonal blocks M + h C + h^2 K of
every unknown and the right-hand sides h F - h^2 K v, for the step's active set.

Linearised here: the axial spring-damper of every active segment (with its geometric stiffness), the line drag
per half segment (its exact 3x3 velocity Jacobian, skipped where the drag is far from stiff on the step's scale),
the point masses' drag and the seabed contact with its regularised friction (the derivatives beside their laws:
``hydro.add_slender_drag_dv``, ``point_loads.add_point_loads_dv``, ``seabed.add_seabed_dv``). A segment leaving
the active set contributes the removal of its start-of-step tension.
"""

from __future__ import annotations

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.environment import current_velocity
from moor_env.physics.hydro import add_slender_drag_dv
from moor_env.physics.implicit_active_set import chord_point, is_active
from moor_env.physics.layout import (
    EF_RHO,
    SF_L0,
    SI_A,
    SI_ACTIVE,
    SI_B,
    SI_MAT,
)
from moor_env.physics.line import axial_derivatives, axial_tension_n, half_segment_morison, segment_axis
from moor_env.physics.point_loads import add_point_loads_dv
from moor_env.physics.seabed import add_seabed_dv
from moor_env.physics.tree import OR_EFF, add_sym

DRAG_SKIP = 0.02  # drag of a half segment is linearised only where h * (its damping rate) exceeds this


@jit_no_refcount
def assemble(h, first, body_node, model, state, orow):
    """Diagonal blocks (``state.node_mm``) and right-hand sides (``state.node_acc``) for the current active set.

    The first call of a step (``first``; node_mm still holds the added mass from the load evaluation) assembles
    what the active set leaves unchanged, keeps it in ``state.node_base`` and adds the segments' springs; a later
    call of the step (the set changed, the state did not) starts from the kept part and adds the springs only.
    Why: the fall's steps solve 2-3 times on average, and the drag Jacobians are most of an assembly.
    """
    node_mm, node_acc, node_base = state.node_mm, state.node_acc, state.node_base
    if first:
        _assemble_fixed(h, body_node, model, state, orow)
    for n in range(node_mm.shape[0]):
        if orow[n, OR_EFF] != n:
            continue
        for c in range(6):
            if first:
                node_base[n, c] = node_mm[n, c]
            else:
                node_mm[n, c] = node_base[n, c]
        for c in range(3):
            if first:
                node_base[n, 6 + c] = node_acc[n, c]
            else:
                node_acc[n, c] = node_base[n, 6 + c]
    _add_springs(h, model, state, orow)


@jit_step(inline="always")
def _segment_unknowns(seg_i, orow, s):
    """Segment s's end nodes and the unknowns that carry them (both -1 where the segment is not active)."""
    a = seg_i[s, SI_A]
    b = seg_i[s, SI_B]
    if seg_i[s, SI_ACTIVE] == 0:
        return a, b, -1, -1
    return a, b, orow[a, OR_EFF], orow[b, OR_EFF]


@jit_no_refcount
def _assemble_fixed(h, body_node, model, state, orow):
    """The blocks and right-hand sides without the segments' springs: masses, loads, point loads and seabed, and
    the segments' drag Jacobians, on the added mass of the load evaluation."""
    mat_f, env_f, current_profile = model.mat_f, model.env_f, model.current_profile
    node_pos, node_vel, node_i = state.node_pos, state.node_vel, state.node_i
    node_f, seg_i, seg_f = state.node_f, state.seg_i, state.seg_f
    node_force, node_mm, node_mass = state.node_force, state.node_mm, state.node_mass
    node_contact, node_acc = state.node_contact, state.node_acc
    nn = node_i.shape[0]
    rho = env_f[EF_RHO]
    for n in range(nn):
        if orow[n, OR_EFF] != n:
            continue
        if n == body_node:
            for c in range(6):
                node_mm[n, c] = 0.0
            for c in range(3):
                node_acc[n, c] = 0.0
            continue
        node_mm[n, 0] += node_mass[n]
        node_mm[n, 1] += node_mass[n]
        node_mm[n, 2] += node_mass[n]
        for c in range(3):
            node_acc[n, c] = h * node_force[n, c]
    # point loads (drag) and the seabed, linearised by their laws' own derivatives
    for n in range(nn):
        e = orow[n, OR_EFF]
        if e < 0 or e == body_node:
            continue
        add_point_loads_dv(node_mm, e, n, h, node_f, node_pos, node_vel, env_f, current_profile)
        add_seabed_dv(node_mm, node_acc, e, h, node_pos[n, 2], node_vel[n, 0], node_vel[n, 1], node_vel[n, 2],
                      node_contact[n], env_f)
    for s in range(seg_i.shape[0]):
        a, b, ea, eb = _segment_unknowns(seg_i, orow, s)
        if ea < 0 and eb < 0:
            continue
        cn, ct, _, _ = half_segment_morison(mat_f, seg_i[s, SI_MAT], seg_f[s, SF_L0], rho)
        if cn <= 0.0 and ct <= 0.0:
            continue
        _, qx, qy, qz = segment_axis(node_pos, a, b)
        for end in range(2):
            n = a if end == 0 else b
            e = ea if end == 0 else eb
            if e < 0 or e == body_node:
                continue
            ux, uy, uz = current_velocity(node_pos[n, 2], env_f, current_profile)
            rx = ux - node_vel[n, 0]
            ry = uy - node_vel[n, 1]
            rz = uz - node_vel[n, 2]
            # linearise only where the drag is stiff on this step's scale (h * rate > DRAG_SKIP)
            c = h * (cn + 2.0 * ct)
            if c * c * (rx * rx + ry * ry + rz * rz) > (DRAG_SKIP * node_mass[e]) ** 2:
                add_slender_drag_dv(node_mm, e, h, rx, ry, rz, qx, qy, qz, cn, ct)


@jit_no_refcount
def _add_springs(h, model, state, orow):
    """The axial spring-damper of every segment of the active set (a segment leaving it: the removal of its
    start-of-step tension), each one's block also kept in ``state.seg_gain`` (:func:`_add_axial_block`)."""
    mat_f = model.mat_f
    node_pos, node_vel, seg_i, seg_f = state.node_pos, state.node_vel, state.seg_i, state.seg_f
    node_mm, node_acc, seg_tension = state.node_mm, state.node_acc, state.seg_tension
    seg_chord, seg_gain = state.seg_chord, state.seg_gain
    for s in range(seg_i.shape[0]):
        a, b, ea, eb = _segment_unknowns(seg_i, orow, s)
        if ea == eb:  # not active, both prescribed, or a welded node and its parent
            continue
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        tension = seg_tension[s]
        seg_gain[s, 0] = 0.0  # outside the active set: no block (the elimination skips it)
        seg_gain[s, 1] = 0.0
        rx = node_vel[b, 0] - node_vel[a, 0]
        ry = node_vel[b, 1] - node_vel[a, 1]
        rz = node_vel[b, 2] - node_vel[a, 2]
        rq = rx * qx + ry * qy + rz * qz
        if is_active(orow, s) == 0:
            if tension == 0.0:
                continue
            # leaves the active set during the step: no tension at its end
            fx = -h * tension * qx
            fy = -h * tension * qy
            fz = -h * tension * qz
        elif seg_chord[s, 3] != 0.0:
            fx, fy, fz = _add_chord_spring(s, h, tension, qx, qy, qz, rx, ry, rz, node_pos, a, b, ea, eb, l0, mat_f,
                                           m, seg_chord, node_mm, seg_gain)
        else:
            kq, cq = axial_derivatives(mat_f, m, l0)
            kt = tension / length
            # unclipped tension of the linear law minus the (clipped) tension already in the loads
            t_lin = axial_tension_n(mat_f, m, l0, (length - l0) / l0, rq / l0)
            alpha = h * cq + h * h * (kq - kt)
            beta = h * h * kt
            w = h * (t_lin - tension) + h * h * (kq - kt) * rq
            # h (t_lin - T) q + h^2 K_s (v_b - v_a), acting on node a (minus on b)
            fx = w * qx + h * h * kt * rx
            fy = w * qy + h * h * kt * ry
            fz = w * qz + h * h * kt * rz
            _add_axial_block(node_mm, ea, eb, alpha, beta, qx, qy, qz, seg_gain, s)
        if ea >= 0:
            node_acc[ea, 0] += fx
            node_acc[ea, 1] += fy
            node_acc[ea, 2] += fz
        if eb >= 0:
            node_acc[eb, 0] -= fx
            node_acc[eb, 1] -= fy
            node_acc[eb, 2] -= fz


@jit_step
def _add_chord_spring(s, h, tension, q0x, q0y, q0z, rx, ry, rz, node_pos, a, b, ea, eb, l0, mat_f, m, seg_chord,
                      node_mm, seg_gain):
    """The axial spring-damper of active segment s linearised at the chord p of ``seg_chord`` (an end chord a solve
    predicted, or a predicted direction at a chosen length, ``implicit_active_set``): adds
    its block h C + h^2 K at p to both ends' blocks and returns its right-hand side on node a (minus on b).

    With d1 = d0 + h (v_b - v_a + dv_b - dv_a) the end chord, the spring's force on a is linearised about p as
    f(p) + K(p) (d1 - p), K(p) = EA/l0 q q^T + T_e/|p| (I - q q^T) (q = p / |p|, T_e = EA (|p| / l0 - 1)), and
    its damping as BA/l0 q q^T (v_b - v_a + dv_b - dv_a); the loads already hold the start tension T along the
    start tangent q0, so the right-hand side is h (f(p) + BA/l0 (r . q) q - T q0) - h K(p) (p - d0 - h r), r the
    relative velocity at the start.
    """
    kq, cq = axial_derivatives(mat_f, m, l0)
    length, qx, qy, qz, kt = chord_point(s, seg_chord, kq, l0)
    t_lin = axial_tension_n(mat_f, m, l0, (length - l0) / l0, (rx * qx + ry * qy + rz * qz) / l0)
    ex = seg_chord[s, 0] - (node_pos[b, 0] - node_pos[a, 0]) - h * rx
    ey = seg_chord[s, 1] - (node_pos[b, 1] - node_pos[a, 1]) - h * ry
    ez = seg_chord[s, 2] - (node_pos[b, 2] - node_pos[a, 2]) - h * rz
    w = h * (kq - kt) * (ex * qx + ey * qy + ez * qz)
    fx = h * (t_lin * qx - tension * q0x) - w * qx - h * kt * ex
    fy = h * (t_lin * qy - tension * q0y) - w * qy - h * kt * ey
    fz = h * (t_lin * qz - tension * q0z) - w * qz - h * kt * ez
    alpha = h * cq + h * h * (kq - kt)
    beta = h * h * kt
    _add_axial_block(node_mm, ea, eb, alpha, beta, qx, qy, qz, seg_gain, s)
    return fx, fy, fz


@jit_step
def _add_axial_block(node_mm, ea, eb, alpha, beta, qx, qy, qz, seg_gain, s):
    """Add segment s's block alpha q q^T + beta I (its damping and stiffness along and across the axis q) to the
    blocks of both end nodes (a negative index: the end is not a free node) and keep it in ``seg_gain[s]``, which
    the elimination and the back substitution of this solve read (``implicit.eliminate``)."""
    seg_gain[s, 0] = alpha
    seg_gain[s, 1] = beta
    seg_gain[s, 2] = qx
    seg_gain[s, 3] = qy
    seg_gain[s, 4] = qz
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

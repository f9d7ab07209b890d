"""Assembly of one static step's linear system (``physics/statics_system.py``): the lines' part of K, kept from one
solve to the next at the same state, and the diagonal and right-hand side of each solve.

A step is solved several times at one state: again while the contacts it predicts change, and again at a grown or
cut pseudo time step (``physics/statics_newton.py``). Those solves differ only in the mass term D / tau^2, the
seabed's terms and the line-anchor contact's, so the segments' stiffness and current-drag terms, the most costly
part of the assembly, are computed once per state and set of taut segments (:func:`assemble_lines`) and each
solve adds its own diagonal to them (:func:`assemble_diagonal`). The line-anchor contact adds its segment terms to
the couplings themselves: the couplings of the segments it touches are copied before it and put back after the
elimination (:func:`hold_contact_couplings`, :func:`release_contact_couplings`).
"""

from __future__ import annotations

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.environment import current_velocity_along
from moor_env.physics.hydro import slender_drag_turn
from moor_env.physics.line import half_segment_morison, segment_axis, smoothed_tension_slope_n
from moor_env.physics.seabed import seabed_stiffness_n_m
from moor_env.physics.tree import OR_EFF

SLACK_STIFFNESS = 1e-6  # least stiffness of a segment in K, as a fraction of EA / l0 (keeps K regular)
# a node's place in a step's seabed set (``node_down``): held on the seabed at and above SEABED_DOWN
SEABED_UP = 0
SEABED_DOWN = 1
SEABED_BACK = 2  # held again after leaving in this step: it stays
SEABED_LEFT = -1  # left in this step

# the arrays of new_lines_k, in this order
LK_DIAGONAL = 0  # (n_nodes, 3, 3): the lines' diagonal blocks of K
LK_TAUT = 1  # (n_segs,): the segments held taut when they were assembled
LK_HELD = 2  # (n_segs, 2, 3, 3): couplings of segments in contact, as assembled, while contact terms are added
LK_HELD_ROWS = 3  # (n_segs,): which segments those are
LK_VALID = 4  # (1,): 1 once assembled


@jit_step
def new_lines_k(n_nodes, n_segs):
    """The arrays that keep the lines' part of K between solves (``LK_*``), empty: the first solve assembles."""
    return (np.zeros((n_nodes, 3, 3)), np.zeros(n_segs, np.int64), np.zeros((n_segs, 2, 3, 3)),
            np.zeros(n_segs, np.int64), np.zeros(1, np.int64))


@jit_no_refcount
def assemble_lines(moved, model, state, taut, coupling, orow, kmat, lines_k):
    """The lines' part of K at the present state: ``coupling`` and the diagonal blocks in ``lines_k``, computed
    where the nodes have ``moved`` since the last call or the taut set differs from its, else kept.
    ``kmat``: a 3x3 scratch block."""
    diagonal, taut_then, _, _, valid = lines_k
    if not moved and valid[0] == 1 and _same_taut(taut, taut_then):
        return
    _segment_terms(model, state, taut, diagonal, coupling, orow, kmat)
    for s in range(taut.shape[0]):
        taut_then[s] = taut[s]
    valid[0] = 1


@jit_no_refcount
def _same_taut(taut, taut_then):
    for s in range(taut.shape[0]):
        if taut[s] != taut_then[s]:
            return False
    return True


@jit_no_refcount
def hold_contact_couplings(nodes, cand, cin, coupling, lines_k):
    """Copy the couplings of the segments the line-anchor contact is about to add terms to (candidate rows past the
    ``nodes`` node rows that are inside after the step: ``statics_contact.add_contact_blocks``); returns how many."""
    held, rows = lines_k[LK_HELD], lines_k[LK_HELD_ROWS]
    count = 0
    for r in range(nodes, cand.shape[0]):
        if cand[r] != 0 and cin[r] != 0:
            s = r - nodes
            rows[count] = s
            _copy_coupling(held, count, coupling, s)
            count += 1
    return count


@jit_no_refcount
def release_contact_couplings(coupling, lines_k, count):
    """Put back the ``count`` couplings :func:`hold_contact_couplings` copied (the lines' part of K again)."""
    held, rows = lines_k[LK_HELD], lines_k[LK_HELD_ROWS]
    for k in range(count):
        _copy_coupling(coupling, rows[k], held, k)


@jit_no_refcount(inline="always")
def _copy_coupling(dst, i, src, j):
    """dst[i] = src[j] for (2, 3, 3) coupling blocks (written out: a slice copy would allocate)."""
    for e in range(2):
        for a in range(3):
            for b in range(3):
                dst[i, e, a, b] = src[j, e, a, b]


@jit_no_refcount
def assemble_diagonal(inv_tau2, body_node, model, state, node_down, dmat, orow, lines_k):
    """Diagonal blocks D / tau^2 + K (``dmat``) from the lines' part (``assemble_lines``) and the right-hand side F + G
    (``state.node_acc``); ``node_down``: nodes on the seabed at the end of the step (``SEABED_DOWN`` and up)."""
    node_pos = state.node_pos
    node_force = state.node_force
    node_contact = state.node_contact
    rhs = state.node_acc
    env_f = model.env_f
    diagonal = lines_k[LK_DIAGONAL]
    nn = node_pos.shape[0]
    for n in range(nn):
        for i in range(3):
            for j in range(3):
                dmat[n, i, j] = diagonal[n, i, j]
        if orow[n, OR_EFF] == n and n != body_node:
            m = max(state.node_mass[n], 1e-6) * inv_tau2
            for c in range(3):
                dmat[n, c, c] += m
                rhs[n, c] = node_force[n, c]
    if body_node >= 0:
        for c in range(3):
            rhs[body_node, c] = 0.0  # the anchor's own residual enters at the root
    seabed = -env_f[L.EF_DEPTH]
    for n in range(nn):
        e = orow[n, OR_EFF]
        if e < 0 or e == body_node or node_contact[n] <= 0.0:
            continue
        k = seabed_stiffness_n_m(node_contact[n], env_f)
        penetration = seabed - node_pos[n, 2]
        if node_down[n] >= SEABED_DOWN:
            dmat[e, 2, 2] += k
            if penetration < 0.0:
                rhs[e, 2] += k * penetration  # the gap to close before the seabed holds the node
        elif penetration > 0.0:
            rhs[e, 2] -= k * penetration  # lifts off: the seabed lets go


@jit_no_refcount(inline="always")
def _add_block(dmat, n, sign, m):
    """dmat[n] += sign * m (3x3)."""
    for i in range(3):
        for j in range(3):
            dmat[n, i, j] += sign * m[i, j]


@jit_no_refcount
def _segment_terms(model, state, taut, diagonal, coupling, orow, kmat):
    """Every segment's stiffness (elastic and geometric) and current-drag turning: its two ends' diagonal blocks
    into ``diagonal`` (cleared first), the couplings of its two ends (``coupling[s, 0]`` = K_ab, ``coupling[s, 1]``
    = K_ba); ``taut``: segments that K holds taut."""
    node_pos = state.node_pos
    seg_i = state.seg_i
    seg_f = state.seg_f
    seg_tension = state.seg_tension
    mat_f = model.mat_f
    env_f = model.env_f
    diagonal[:, :, :] = 0.0
    smoothing = env_f[L.EF_SLACK_SMOOTHING]
    rho = env_f[L.EF_RHO]
    current = env_f[L.EF_CUR_SCALE] != 0.0
    profile = model.current_profile
    last_node = -1  # the end b of the last segment whose drag turned, and the current velocity there
    last_u = (0.0, 0.0, 0.0)
    for s in range(seg_i.shape[0]):
        a = seg_i[s, L.SI_A]
        b = seg_i[s, L.SI_B]
        ea = orow[a, OR_EFF]
        eb = orow[b, OR_EFF]
        if seg_i[s, L.SI_ACTIVE] == 0 or ea == eb:
            coupling[s, :, :, :] = 0.0
            continue
        mat = seg_i[s, L.SI_MAT]
        ea_n = mat_f[mat, L.MF_EA]
        l0 = seg_f[s, L.SF_L0]
        length, qx, qy, qz = segment_axis(node_pos, a, b)
        q = (qx, qy, qz)
        strain = (length - l0) / l0
        floor = SLACK_STIFFNESS * ea_n / l0
        kt = seg_tension[s] / length if length > 0.0 else 0.0
        if strain <= 0.0 and taut[s] == 1:
            kq = ea_n / l0  # slack for a step or two only: K keeps it taut
        else:  # the smoothed tension-only law's slope
            kq = max(smoothed_tension_slope_n(ea_n, strain, smoothing) / l0, floor)
            if taut[s] == 0:
                kt = max(kt, floor)
        for i in range(3):
            for j in range(3):
                k = (kq - kt) * q[i] * q[j] + (kt if i == j else 0.0)
                if ea >= 0:
                    diagonal[ea, i, j] += k
                if eb >= 0:
                    diagonal[eb, i, j] += k
                coupling[s, 0, i, j] = -k
                coupling[s, 1, i, j] = -k
        # current drag turns with the segment: d f_end / d x_b = D_end P / length, d / d x_a = -D_end P / length
        if not current or length <= 0.0:
            continue
        cn, ct, _, _ = half_segment_morison(mat_f, mat, l0, rho)
        for end in range(2):
            node = a if end == 0 else b
            ux, uy, uz = current_velocity_along(node, last_node, last_u, node_pos[node, 2], env_f, profile)
            if end == 1:
                last_node, last_u = node, (ux, uy, uz)
            slender_drag_turn(ux, uy, uz, qx, qy, qz, cn / length, ct / length, kmat)
            # K = -dF/dx: this end's row gets +D P / l from x_a and -D P / l from x_b
            if end == 0:
                if ea >= 0:
                    _add_block(diagonal, ea, 1.0, kmat)
                _add_block(coupling[s], 0, -1.0, kmat)
            else:
                if eb >= 0:
                    _add_block(diagonal, eb, -1.0, kmat)
                _add_block(coupling[s], 1, 1.0, kmat)

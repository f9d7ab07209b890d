"""The linear system of one step of the static solver (``physics/statics_newton.py``) and its O(N) solution.

At a state x the residual F(x) is the net load on every free node and on the anchor from the dynamics' own load
kernel (``loads.compute_loads``) with every velocity zero, so that current drag acts as a static load and the
equilibrium is an exact rest state of the dynamic model. A step solves::

    (D / tau^2 + K) dx = F(x) + G,

D the node masses and the anchor's inertia (the pseudo-transient term), K = -dF/dx analytic: per segment
dT/dl q q^T + (T / l)(I - q q^T) (elastic and geometric stiffness), the seabed's vertical stiffness, for the anchor
J^T S J plus the geometric stiffness of its arms (a force f at axial coordinate s resists a tilt by s (e . f)),
and the current drag's change with each segment's direction (``hydro.slender_drag_turn``); the drag's change with
depth and the anchor's own drag are left out. The system is solved in O(N) by block elimination over the tree of
lines (``physics/statics_elimination.py``, ``physics/tree.py``), leaves first, the anchor's five unknowns
(position, two tilt angles) at the root. The lines' contact with the anchor's body adds its own terms and
couplings (``physics/statics_contact.py``).

The seabed contact is one-sided: K carries its stiffness for the nodes that are on the seabed at the end of the
step, and G the gap a node must close before the seabed holds it (or the support it loses when it lifts off). The
step is solved again while that prediction changes (``ACTIVE_SET_ROUNDS``): a line that lands on the seabed stops
there, where the free line's stiffness would carry it metres into the seabed and the contact throw it back. A node
joins the set where a solve puts it on or below the seabed, and leaves it where a solve lifts it: in the first
solve always, in the later ones where the caller asks (``release_later``, ``physics/statics_newton.py``), each node
leaving once per step (one that comes back stays, so that the solves cannot cycle).

A segment carries tension only when taut. A segment that has been slack for ``SLACK_PATIENCE`` iterations (and
one slack in the first guess: excess line laid on the seabed) keeps only a small floor stiffness
(``SLACK_STIFFNESS`` EA / l0, along and across it), so that folds and grounded slack move freely; one slack for a
step or two, as a large step leaves many, keeps its EA in K, so that K stays far from singular.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.environment import current_velocity_along
from moor_env.physics.hydro import slender_drag_turn
from moor_env.physics.line import half_segment_morison, segment_axis, smoothed_tension_slope_n
from moor_env.physics.loads import compute_loads, set_constrained_nodes
from moor_env.physics.seabed import seabed_stiffness_n_m
from moor_env.physics.statics_contact import (
    N_GEO,
    add_contact_blocks,
    contact_geometry,
    predict_contact,
    release_pulling,
)
from moor_env.physics.statics_elimination import eliminate
from moor_env.physics.tree import OR_EFF

SLACK_STIFFNESS = 1e-6  # least stiffness of a segment in K, as a fraction of EA / l0 (keeps K regular)
SLACK_PATIENCE = 3  # iterations a segment is slack before K lets it go
# a node's place in a step's seabed set (``node_down``): held on the seabed at and above SEABED_DOWN
SEABED_UP = 0
SEABED_DOWN = 1
SEABED_BACK = 2  # held again after leaving in this step: it stays
SEABED_LEFT = -1  # left in this step
ACTIVE_SET_ROUNDS = 8  # solves per step at most while the predicted seabed and line-anchor contacts change


@jit_no_refcount
def _basis(body_state, basis):
    """Two unit vectors perpendicular to the anchor axis (the tilt unknowns rotate about them)."""
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    tx, ty, tz = (1.0, 0.0, 0.0) if abs(ex) < 0.9 else (0.0, 1.0, 0.0)
    ux = ey * tz - ez * ty
    uy = ez * tx - ex * tz
    uz = ex * ty - ey * tx
    norm = math.sqrt(ux * ux + uy * uy + uz * uz)
    basis[0, 0] = ux / norm
    basis[0, 1] = uy / norm
    basis[0, 2] = uz / norm
    basis[1, 0] = ey * basis[0, 2] - ez * basis[0, 1]
    basis[1, 1] = ez * basis[0, 0] - ex * basis[0, 2]
    basis[1, 2] = ex * basis[0, 1] - ey * basis[0, 0]


@jit_no_refcount
def residual(model, state, body_node, basis, res_body):
    """Loads at the current state (velocities zero); returns (sum of squared scaled residuals, largest one) and
    the anchor's five generalised residuals in ``res_body``.

    A node's residual is scaled by its weight, the anchor's force by its weight and its moments by its weight
    times its length.
    """
    set_constrained_nodes(model, state, 0.0)
    compute_loads(model, state)
    node_i = state.node_i
    node_force = state.node_force
    node_mass = state.node_mass
    body_f = model.body_f
    body_load = state.body_load
    g = model.env_f[L.EF_G]
    norm2 = 0.0
    worst = 0.0
    for n in range(node_i.shape[0]):
        if node_i[n, L.NI_KIND] != L.NODE_FREE:
            continue
        scale = max(node_mass[n], 1e-6) * g
        for c in range(3):
            r = abs(node_force[n, c]) / scale
            norm2 += r * r
            if not (r <= worst):
                worst = r
    if body_node >= 0:
        _basis(state.body_state, basis)
        weight = body_f[L.BF_WEIGHT]
        for c in range(3):
            res_body[c] = body_load[c]
        for k in range(2):
            res_body[3 + k] = (body_load[3] * basis[k, 0] + body_load[4] * basis[k, 1]
                               + body_load[5] * basis[k, 2])
        for c in range(5):
            r = abs(res_body[c]) / (weight if c < 3 else weight * body_f[L.BF_LENGTH])
            norm2 += r * r
            if not (r <= worst):
                worst = r
    return norm2, worst


@jit_no_refcount(inline="always")
def _add_block(dmat, n, sign, m):
    """dmat[n] += sign * m (3x3)."""
    for i in range(3):
        for j in range(3):
            dmat[n, i, j] += sign * m[i, j]


@jit_no_refcount
def _assemble(inv_tau2, body_node, model, state, taut, node_down, dmat, coupling, orow, kmat):
    """Diagonal blocks D / tau^2 + K (``dmat``), the couplings of every segment's two ends (``coupling[s, 0]`` =
    K_ab, ``coupling[s, 1]`` = K_ba) and the right-hand side F + G (``state.node_acc``); ``taut``: segments that K
    holds taut, ``node_down``: nodes on the seabed at the end of the step (``SEABED_DOWN`` and up), ``kmat``: a
    3x3 scratch block."""
    node_pos = state.node_pos
    seg_i = state.seg_i
    seg_f = state.seg_f
    node_force = state.node_force
    node_contact = state.node_contact
    seg_tension = state.seg_tension
    rhs = state.node_acc
    mat_f = model.mat_f
    env_f = model.env_f
    nn = node_pos.shape[0]
    dmat[:, :, :] = 0.0
    for n in range(nn):
        if orow[n, OR_EFF] == n and n != body_node:
            m = max(state.node_mass[n], 1e-6) * inv_tau2
            for c in range(3):
                dmat[n, c, c] = m
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
                    dmat[ea, i, j] += k
                if eb >= 0:
                    dmat[eb, i, j] += k
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
                    _add_block(dmat, ea, 1.0, kmat)
                _add_block(coupling[s], 0, -1.0, kmat)
            else:
                if eb >= 0:
                    _add_block(dmat, eb, -1.0, kmat)
                _add_block(coupling[s], 1, 1.0, kmat)


@jit_no_refcount
def _predict_seabed(body_node, state, seabed, node_down, orow, release):
    """Update the nodes predicted on the seabed after the step in ``state.node_acc`` (``node_down``, ``SEABED_*``
    values); returns how many changed. With ``release`` a node on the seabed that the step lifts leaves the set
    (once per step: one that comes back stays), otherwise the set only grows."""
    node_pos = state.node_pos
    node_contact = state.node_contact
    node_acc = state.node_acc
    changed = 0
    for n in range(node_pos.shape[0]):
        e = orow[n, OR_EFF]
        if e < 0 or e == body_node or node_contact[n] <= 0.0:
            continue
        z = node_pos[n, 2] + node_acc[e, 2]
        if node_down[n] >= SEABED_DOWN:
            if not (release and z > seabed and node_down[n] == SEABED_DOWN):
                continue
            node_down[n] = SEABED_LEFT
        elif z <= seabed:
            node_down[n] = SEABED_BACK if node_down[n] == SEABED_LEFT else SEABED_DOWN
        else:
            continue
        changed += 1
    return changed


@jit_no_refcount
def _start_sets(model, state, seg_age, taut, node_down):
    """The segments K holds taut and the nodes on the seabed at the present state."""
    node_pos = state.node_pos
    seg_i = state.seg_i
    seg_f = state.seg_f
    seabed = -model.env_f[L.EF_DEPTH]
    for s in range(seg_i.shape[0]):
        length = segment_axis(node_pos, seg_i[s, L.SI_A], seg_i[s, L.SI_B])[0]
        taut[s] = 1 if length > seg_f[s, L.SF_L0] or seg_age[s] < SLACK_PATIENCE else 0
    for n in range(node_pos.shape[0]):
        node_down[n] = SEABED_DOWN if node_pos[n, 2] <= seabed else SEABED_UP


@jit_step
def solve_step(inv_tau2, nq, body_node, basis, res_body, dq, model, state, scratch, tree, orow, seg_age,
               release_later):
    """The step at the present state (its loads evaluated) into ``state.node_acc`` (free nodes) and ``dq`` (the
    anchor), solved again while the contacts it predicts change (``release_later``: a node the seabed set took in
    may leave it again after the first solve, module docstring), and once more where, with the contacts settled,
    line-anchor contacts that would pull leave the set (``statics_contact.release_pulling``); at most
    ``ACTIVE_SET_ROUNDS`` solves, their number returned. ``scratch``: the arrays of :func:`new_scratch`."""
    dmat, coupling, taut, node_down, geo, cand, cin, bmat, cmat, coupled, body_a, body_r, blocks = scratch
    seabed = -model.env_f[L.EF_DEPTH]
    _start_sets(model, state, seg_age, taut, node_down)
    contact = (body_node >= 0 and model.contact_f[L.CF_ON] != 0.0
               and contact_geometry(basis, model, state, geo, cand, cin) > 0)
    solves = 0
    released = False
    while True:
        _assemble(inv_tau2, body_node, model, state, taut, node_down, dmat, coupling, orow, blocks[0])
        if contact:
            add_contact_blocks(model, state, geo, cand, cin, dmat, coupling, bmat, cmat, coupled, body_a, body_r)
        eliminate(inv_tau2, nq, body_node, basis, res_body, dq, model, state, dmat, coupling, tree, orow, contact,
                  bmat, cmat, coupled, body_a, body_r, blocks)
        solves += 1
        if solves >= ACTIVE_SET_ROUNDS:
            return solves
        changed = _predict_seabed(body_node, state, seabed, node_down, orow, solves == 1 or release_later)
        if contact:
            changed += predict_contact(state, dq, geo, cand, cin, solves == 1)
            if changed == 0 and not released:  # once per step: the set settled, none of it may pull
                released = True
                changed = release_pulling(state, dq, geo, cand, cin)
        if changed == 0:
            return solves


@jit_no_refcount
def step_size(body_node, model, state, dq):
    """Largest node move of a step [m] (the anchor's rotation counted at its length): the free nodes' in
    ``state.node_acc``, the anchor's in ``dq``."""
    node_i = state.node_i
    node_acc = state.node_acc
    biggest = 0.0
    for n in range(node_i.shape[0]):
        if node_i[n, L.NI_KIND] == L.NODE_FREE:
            move = math.sqrt(node_acc[n, 0] ** 2 + node_acc[n, 1] ** 2 + node_acc[n, 2] ** 2)
            if not (move <= biggest):
                biggest = move
    if body_node >= 0:
        move = max(math.sqrt(dq[0] ** 2 + dq[1] ** 2 + dq[2] ** 2),
                   math.sqrt(dq[3] ** 2 + dq[4] ** 2) * model.body_f[L.BF_LENGTH])
        if not (move <= biggest):
            biggest = move
    return biggest


@jit_no_refcount
def count_slack(state, seg_age):
    """Count the iterations each segment has been slack (0 while taut)."""
    node_pos = state.node_pos
    seg_i = state.seg_i
    seg_f = state.seg_f
    for s in range(seg_i.shape[0]):
        if seg_i[s, L.SI_ACTIVE] == 0:
            continue
        length = segment_axis(node_pos, seg_i[s, L.SI_A], seg_i[s, L.SI_B])[0]
        seg_age[s] = seg_age[s] + 1.0 if length < seg_f[s, L.SF_L0] else 0.0


@jit_step
def new_scratch(n_nodes, n_segs):
    """Scratch arrays of :func:`solve_step`: diagonal blocks, segment couplings, segments K holds taut, nodes on the
    seabed after the step; the line-anchor contact's (``physics/statics_contact.py``): candidates' geometry,
    candidates, candidates inside after the step (a row per node, then one per segment), node-anchor and
    anchor-node couplings, coupled nodes, the anchor's block and right-hand side; small blocks (4, 3, 3): the
    assembly's 3x3 block, the elimination's inverse and product, and its two 3-vectors in the last."""
    return (np.zeros((n_nodes, 3, 3)), np.zeros((n_segs, 2, 3, 3)), np.zeros(n_segs, np.int64),
            np.zeros(n_nodes, np.int64), np.zeros((n_nodes + n_segs, N_GEO)), np.zeros(n_nodes + n_segs, np.int64),
            np.zeros(n_nodes + n_segs, np.int64), np.zeros((n_nodes, 3, 5)), np.zeros((n_nodes, 5, 3)),
            np.zeros(n_nodes, np.int64), np.zeros((5, 5)), np.zeros(5), np.zeros((4, 3, 3)))

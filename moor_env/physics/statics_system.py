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
(``statics_assembly.SLACK_STIFFNESS`` EA / l0, along and across it), so that folds and grounded slack move freely;
one slack for a step or two, as a large step leaves many, keeps its EA in K, so that K stays far from singular.
K's part from the lines is assembled in ``physics/statics_assembly.py``, once per state.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.line import segment_axis
from moor_env.physics.loads import compute_loads, set_constrained_nodes
from moor_env.physics.statics_assembly import (
    SEABED_BACK,
    SEABED_DOWN,
    SEABED_LEFT,
    SEABED_UP,
    assemble_diagonal,
    assemble_lines,
    hold_contact_couplings,
    new_lines_k,
    release_contact_couplings,
)
from moor_env.physics.statics_contact import (
    N_GEO,
    add_contact_blocks,
    contact_geometry,
    predict_contact,
    release_pulling,
)
from moor_env.physics.statics_elimination import eliminate
from moor_env.physics.tree import OR_EFF

SLACK_PATIENCE = 3  # iterations a segment is slack before K lets it go
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
               release_later, moved):
    """The step at the present state (its loads evaluated) into ``state.node_acc`` (free nodes) and ``dq`` (the
    anchor), solved again while the contacts it predicts change (``release_later``: a node the seabed set took in
    may leave it again after the first solve, module docstring), and once more where, with the contacts settled,
    line-anchor contacts that would pull leave the set (``statics_contact.release_pulling``); at most
    ``ACTIVE_SET_ROUNDS`` solves, their number returned. ``scratch``: the arrays of :func:`new_scratch`.

    ``moved``: the nodes moved since the last call with this scratch. The lines' part of K is assembled once per
    state and set of taut segments (``statics_assembly``): the solves of one step, and a step solved again at
    another pseudo time step, differ only in the diagonal and the contacts."""
    dmat, coupling, taut, node_down, geo, cand, cin, bmat, cmat, coupled, body_a, body_r, blocks = scratch[:13]
    lines_k = scratch[13:]
    seabed = -model.env_f[L.EF_DEPTH]
    _start_sets(model, state, seg_age, taut, node_down)
    contact = (body_node >= 0 and model.contact_f[L.CF_ON] != 0.0
               and contact_geometry(basis, model, state, geo, cand, cin) > 0)
    assemble_lines(moved, model, state, taut, coupling, orow, blocks[0], lines_k)
    solves = 0
    released = False
    while True:
        assemble_diagonal(inv_tau2, body_node, model, state, node_down, dmat, orow, lines_k)
        held = 0
        if contact:
            held = hold_contact_couplings(state.node_pos.shape[0], cand, cin, coupling, lines_k)
            add_contact_blocks(model, state, geo, cand, cin, dmat, coupling, bmat, cmat, coupled, body_a, body_r)
        eliminate(inv_tau2, nq, body_node, basis, res_body, dq, model, state, dmat, coupling, tree, orow, contact,
                  bmat, cmat, coupled, body_a, body_r, blocks)
        release_contact_couplings(coupling, lines_k, held)
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
    assembly's 3x3 block, the elimination's inverse and product, and its two 3-vectors in the last; then the
    lines' part of K kept for the next solve at the same state (``statics_assembly.new_lines_k``)."""
    return (np.zeros((n_nodes, 3, 3)), np.zeros((n_segs, 2, 3, 3)), np.zeros(n_segs, np.int64),
            np.zeros(n_nodes, np.int64), np.zeros((n_nodes + n_segs, N_GEO)), np.zeros(n_nodes + n_segs, np.int64),
            np.zeros(n_nodes + n_segs, np.int64), np.zeros((n_nodes, 3, 5)), np.zeros((n_nodes, 5, 3)),
            np.zeros(n_nodes, np.int64), np.zeros((5, 5)), np.zeros(5), np.zeros((4, 3, 3))) + new_lines_k(n_nodes,
                                                                                                            n_segs)

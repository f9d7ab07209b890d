"""Newton kernel of the static solver (seed 003: Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*,
section 8.2, Model 1): one numba call runs many iterations.

Each iteration solves the linear system of ``physics/statics_system.py``, (D / tau^2 + K) dx = F + G, and moves
the state along the step: the anchor by its five unknowns, every free node along the tree of lines from the anchor,
each at its segment's new direction and linearly predicted length (:func:`_apply`).

Globalisation (pseudo-transient continuation): a step is kept when the step computed at its end is shorter than
it by a share of its length (the natural monotonicity test of Deuflhard's affine-invariant Newton methods), or
when the residual fell as much and the next step is at most ``GROWTH`` times longer (a swing the placement closes
in one stiff segment makes a large, harmless residual there). Otherwise the state goes back and the same step is
taken shorter; after ``LINE_SEARCH_CUTS`` cuts the pseudo time step tau is cut tenfold instead. A full step that
is kept grows tau fourfold (switched evolution relaxation), so that the iteration becomes Newton's method near the
solution; while tau <= ``TAU_NEWTON_S`` the step is solved again at the grown tau. A step carried past it was solved
at tau >= 640 s (from the start's 10 s), where D / tau^2 is below 2.5e-3 N/m per tonne of a node's mass and about
0.3 N/m on the anchor, a hundredth or less of the least stiffness K keeps on a slack segment
(``statics_assembly.SLACK_STIFFNESS`` EA / l0: 20-75 N/m on the polyester), so that the step hardly changes with
tau. A step longer than ``OVERSIZE`` step limits cuts tau at once (K nearly singular: a part of the model held by
slack segments alone). A step that raises the largest residual more than ``RESIDUAL_JUMP`` times is taken back
whatever the step at its end: a step along a nearly free mode (a stretch of line between slack segments) can stretch
segments so far that K at its end is stiffer and its step short, which the step test alone would keep, and the solve
then spends hundreds of iterations undoing it (on a coarse equilibrium mapped onto finer lines: a residual of 95
node weights raised to 8e6). Why 1e4: the first guess's steps raise the residual a thousandfold where a swing closes
in one stiff segment, harmlessly, and on the statics benchmark's slowest scenes a bound of 3e3 left a solve
unconverged; a bound of 1e5 let the slowest solves wander (the residual swinging between 1e-2 and 1e5 node weights
over hundreds of iterations, a third of the steps taken back) and left one unconverged. Converged when the residual
is within tolerance and the step at the state is below the step tolerance.

The step's seabed set (``statics_system.solve_step``): a node on the seabed (at the state, or put there by one of
the step's solves) leaves the set where a later solve lifts it (once per step), unless ``C_SEABED_RELEASE`` is 0,
where the set only grows after the step's first solve. Why: where the set only grows, whether a node near a
touchdown is held turns on an intermediate solve, so that the step jumps between nearby states; in strong current,
as a mooring line's touchdown swings over the seabed, the step test then takes back almost every step, however
short (in the slowest such scenes of the statics benchmark, half to nine tenths of the steps taken back, nearly all
of those shorter than a twentieth of their step, have a set other than the state's step). With the releases the
sets of nearby states mostly agree.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor import rotate_axis
from moor_env.physics.statics_contact import N_GEO, slide_on_surface, slide_plan
from moor_env.physics.statics_system import count_slack, new_scratch, residual, solve_step, step_size
from moor_env.physics.tree import OR_ORDER, TR_DEG, TR_NB, build_tree, order

SMOOTHING_FINAL = 1e-8  # strain scale of the tension-only law's rounded kink: EA 1e-8 / 2 (9 N on 142 mm chain)
MAX_ROTATION_RAD = 0.2  # largest anchor tilt change per step
TAU_START_S = 10.0
TAU_NEWTON_S = 1e3  # above this the node masses no longer change the step (module docstring)
TAU_MAX_S = 1e12
OVERSIZE = 10.0  # a step this many step limits long means K is nearly singular: tau is cut
SHRINK = 0.25  # a kept step shortens the next by this share of its own length at least (or the residual as much)
GROWTH = 2.0  # a step kept for a smaller residual may make the next this much longer, no more
RESIDUAL_JUMP = 1e4  # a step that raises the largest residual more than this many times is taken back
LINE_SEARCH_CUTS = 3  # shorter tries of a step that made no progress before tau is cut
STEP_TOLERANCE_M = 1e-4  # converged once the residual is within tolerance and the step below this

# ctl slots: the kernel's controls and the state it hands back between calls
C_TAU = 0
C_TOL = 1  # residual tolerance, relative to the weight scales
C_MAX_STEP = 2  # longest node move of a step [m]
C_ITERATIONS = 3  # total iterations so far
C_STATUS = 4
C_RESIDUAL = 5  # largest |residual| / weight scale of the last evaluation
C_LAST_STEP = 6  # largest node move of the step at the state [m]
C_SOLVES = 7  # linear solves so far
C_REJECTED = 8  # steps taken back
C_CAP = 9  # longest move allowed for the next step [m] (0: the step limit)
C_CUTS = 10  # cuts of the present step so far
C_STEP_TOL = 11  # converged once the residual is within tolerance and the step below this [m]
C_TAU_MAX = 12  # longest pseudo time step [s] (0: TAU_MAX_S)
C_SEABED_RELEASE = 13  # 1: a step's seabed set may lose nodes in every solve; 0: in its first only (module docstring)
N_CTL = 14

STATUS_RUNNING = 0
STATUS_CONVERGED = 1
STATUS_NONFINITE = 2


@jit_no_refcount
def _apply(scale, nq, body_node, basis, dq, model, state, axis0, saved, tree, orow, plan, planned):
    """x += scale * dx for the anchor, and for every free node along the tree from its root: each node is placed
    from its (already moved) parent along the segment's new direction at its linearly predicted length; a node
    predicted inside the anchor (``plan``, ``planned`` of them: ``statics_contact.slide_plan``) is then put at its
    linearly predicted depth (``statics_contact.slide_on_surface``).

    Why: a segment that turns by an angle t under x += dx lengthens by l t^2 / 2, which its axial stiffness turns
    into a spurious tension EA t^2 / 2; on a slack loop that has to swing (current) this confines plain Newton to
    steps of a tenth of a degree. Placing nodes by direction and length keeps the linear model's axial
    prediction; the mismatch gathers in the segments to prescribed ends, where Newton corrects it as a linear,
    axial error.
    """
    node_pos = state.node_pos
    node_acc = state.node_acc
    body_state = state.body_state
    if body_node >= 0:
        for c in range(3):
            body_state[L.BS_POS + c] += scale * dq[c]
            axis0[c] = body_state[L.BS_AXIS + c]
        phx = scale * (dq[3] * basis[0, 0] + dq[4] * basis[1, 0])
        phy = scale * (dq[3] * basis[0, 1] + dq[4] * basis[1, 1])
        phz = scale * (dq[3] * basis[0, 2] + dq[4] * basis[1, 2])
        rotate_axis(body_state, axis0, phx, phy, phz, 1.0)
        sp = state.node_f[body_node, L.NF_BODY_S]
        for c in range(3):
            node_pos[body_node, c] = body_state[L.BS_POS + c] + sp * body_state[L.BS_AXIS + c]
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        linear = tree[c, TR_DEG] != -1
        if not linear:
            p = tree[c, TR_NB]
            old_len = math.sqrt((saved[c, 0] - saved[p, 0]) ** 2 + (saved[c, 1] - saved[p, 1]) ** 2
                                + (saved[c, 2] - saved[p, 2]) ** 2)
            # predicted relative vector and length of the segment (linear in the step, parent's linear motion)
            vx = saved[c, 0] - saved[p, 0] + scale * (node_acc[c, 0] - node_acc[p, 0])
            vy = saved[c, 1] - saved[p, 1] + scale * (node_acc[c, 1] - node_acc[p, 1])
            vz = saved[c, 2] - saved[p, 2] + scale * (node_acc[c, 2] - node_acc[p, 2])
            new_len = math.sqrt(vx * vx + vy * vy + vz * vz)
            target = old_len
            if old_len > 0.0:
                target += scale * ((saved[c, 0] - saved[p, 0]) * (node_acc[c, 0] - node_acc[p, 0])
                                   + (saved[c, 1] - saved[p, 1]) * (node_acc[c, 1] - node_acc[p, 1])
                                   + (saved[c, 2] - saved[p, 2]) * (node_acc[c, 2] - node_acc[p, 2])) / old_len
            if new_len <= 0.0 or target <= 0.0:
                linear = True
            else:
                f = target / new_len
                node_pos[c, 0] = node_pos[p, 0] + vx * f
                node_pos[c, 1] = node_pos[p, 1] + vy * f
                node_pos[c, 2] = node_pos[p, 2] + vz * f
        if linear:
            for i in range(3):
                node_pos[c, i] += scale * node_acc[c, i]
        if planned > 0 and plan[c, 0] == plan[c, 0]:
            slide_on_surface(node_pos, c, body_state, model.contact_shape, plan[c, 0] + scale * plan[c, 1])


@jit_step
def _bounded_step(tau, ctl, nq, body_node, basis, res_body, dq, model, state, scratch, tree, orow, seg_age, moved):
    """The step at the present state with pseudo time step tau, cut tenfold while the step is longer than
    ``OVERSIZE`` step limits; returns (tau, step size). ``moved``: the nodes moved since the last solve."""
    size = math.inf
    for k in range(8):
        ctl[C_SOLVES] += solve_step(1.0 / (tau * tau), nq, body_node, basis, res_body, dq, model, state, scratch,
                                    tree, orow, seg_age, ctl[C_SEABED_RELEASE] != 0.0, moved and k == 0)
        size = step_size(body_node, model, state, dq)
        if size <= OVERSIZE * ctl[C_MAX_STEP]:
            break
        tau *= 0.1
    return tau, size


@jit_step
def newton_statics(ctl, max_iter, body_node, model, state, seg_age):
    """Up to ``max_iter`` iterations of the static problem from the state of the records ``model``, ``state``
    (``physics/records.py``), in place.

    ``ctl`` (``C_*`` slots) carries the pseudo time step, the tolerances and the step limit in, and the iteration
    count, status and residual out, so that a long solve can be run in chunks. ``body_node``: the node attaching
    the lines to the anchor (the anchor is then solved for), or -1. ``seg_age``: each segment's count of slack
    iterations, kept between calls.
    """
    node_i = state.node_i
    seg_i = state.seg_i
    node_pos = state.node_pos
    node_acc = state.node_acc
    body_state = state.body_state
    nn = node_i.shape[0]
    tree = state.pos0.view(np.int64)
    orow = state.vel0.view(np.int64)
    for n in range(nn):
        if node_i[n, L.NI_KIND] == L.NODE_FREE:
            for c in range(3):
                state.node_vel[n, c] = 0.0
    for c in range(3):
        body_state[L.BS_VEL + c] = 0.0
        body_state[L.BS_OMEGA + c] = 0.0
    build_tree(body_node, node_i, seg_i, tree, orow)
    nq = order(body_node, node_i, seg_i, tree, orow)
    scratch = new_scratch(nn, seg_i.shape[0])
    saved = np.empty((nn, 3))
    saved_body = np.empty(L.N_BODY_STATE)
    saved_step = np.empty((nn, 3))
    saved_dq = np.zeros(5)
    basis = np.zeros((2, 3))
    saved_basis = np.zeros((2, 3))
    res_body = np.zeros(5)
    dq = np.zeros(5)
    axis0 = np.zeros(3)
    contact = body_node >= 0 and model.contact_f[L.CF_ON] != 0.0
    plan = np.empty((nn, 2))
    plan_geo = np.zeros((nn, N_GEO))  # node rows only: the slide plan is the nodes' (no segment rows computed)
    plan_cand = np.zeros(nn, np.int64)
    plan_cin = np.zeros(nn, np.int64)
    tau = ctl[C_TAU]
    tol = ctl[C_TOL]
    tau_max = ctl[C_TAU_MAX] if ctl[C_TAU_MAX] > 0.0 else TAU_MAX_S
    status = STATUS_RUNNING
    norm2, worst = residual(model, state, body_node, basis, res_body)
    tau, size = _bounded_step(tau, ctl, nq, body_node, basis, res_body, dq, model, state, scratch, tree, orow, seg_age,
                              True)
    step_contact = contact and scratch[6].any()  # the step's solve predicted a node inside the anchor
    saved_contact = step_contact
    cap = ctl[C_CAP] if ctl[C_CAP] > 0.0 else ctl[C_MAX_STEP]
    cuts = int(ctl[C_CUTS])
    for it in range(max_iter):
        if not (worst == worst) or not (size == size):
            status = STATUS_NONFINITE
            break
        ctl[C_LAST_STEP] = size
        if worst < tol and size < ctl[C_STEP_TOL]:
            status = STATUS_CONVERGED
            break
        ctl[C_ITERATIONS] += 1.0
        scale = 1.0
        if body_node >= 0:
            rot = math.sqrt(dq[3] * dq[3] + dq[4] * dq[4])
            if rot > MAX_ROTATION_RAD:
                scale = MAX_ROTATION_RAD / rot
        if size * scale > cap:
            scale = cap / size
        saved[:, :] = node_pos
        saved_body[:] = body_state
        saved_basis[:, :] = basis
        saved_step[:, :] = node_acc
        saved_dq[:] = dq
        # no node predicted inside the anchor by the step's solve: nothing to slide, no planning cost
        planned = slide_plan(basis, model, state, dq, plan_geo, plan_cand, plan_cin, plan) if step_contact else 0
        saved_contact = step_contact
        _apply(scale, nq, body_node, basis, dq, model, state, axis0, saved, tree, orow, plan, planned)
        new2, new_worst = residual(model, state, body_node, basis, res_body)
        new_size = math.inf
        new_tau = tau
        if new2 == new2:
            new_tau, new_size = _bounded_step(tau, ctl, nq, body_node, basis, res_body, dq, model, state, scratch,
                                              tree, orow, seg_age, True)
        shrink = 1.0 - SHRINK * scale
        if (new_worst <= RESIDUAL_JUMP * max(worst, tol)
                and (new_size <= shrink * size or (new2 <= shrink * shrink * norm2 and new_size <= GROWTH * size)
                     or new_size < ctl[C_STEP_TOL])):
            count_slack(state, seg_age)
            step_contact = contact and scratch[6].any()
            cap = min(2.0 * max(cap, scale * size), ctl[C_MAX_STEP])
            norm2 = new2
            worst = new_worst
            size = new_size
            cuts = 0
            if scale == 1.0 and new_tau == tau and tau < tau_max:  # a full step: towards Newton's method
                tau = min(tau * 4.0, tau_max)
                if tau <= TAU_NEWTON_S:  # the step changes with tau: the next test compares steps of one tau
                    tau, size = _bounded_step(tau, ctl, nq, body_node, basis, res_body, dq, model, state, scratch,
                                              tree, orow, seg_age, False)
                    step_contact = contact and scratch[6].any()
            else:
                tau = new_tau
            continue
        # no progress: back, and the same step shorter (or, after a few cuts, with a shorter pseudo time step)
        ctl[C_REJECTED] += 1.0
        node_pos[:, :] = saved
        body_state[:] = saved_body
        cuts += 1
        if cuts > LINE_SEARCH_CUTS or it == max_iter - 1:  # the solve at a cut tau, or the caller, reads the loads
            norm2, worst = residual(model, state, body_node, basis, res_body)
        else:  # norm2 and worst are still the state's; a shorter try of the step evaluates its own loads
            basis[:, :] = saved_basis
        if cuts <= LINE_SEARCH_CUTS:
            node_acc[:, :] = saved_step
            dq[:] = saved_dq
            step_contact = saved_contact
            cap = 0.3 * scale * size
        else:
            cuts = 0
            cap = ctl[C_MAX_STEP]
            tau, size = _bounded_step(0.1 * tau, ctl, nq, body_node, basis, res_body, dq, model, state, scratch,
                                              tree, orow, seg_age, True)
            step_contact = contact and scratch[6].any()
    ctl[C_TAU] = tau
    ctl[C_CAP] = cap
    ctl[C_CUTS] = cuts
    ctl[C_STATUS] = status
    ctl[C_RESIDUAL] = worst
    return status

"""Time integration: step the state (the loads from ``physics/loads.py``), detect touchdown and blow-ups.

``advance`` is the one entry point called from Python: it steps from ``t`` to ``t_end`` (or to touchdown, or
to a blow-up) with no Python work per step. Every kernel takes the model and state records of
``physics/records.py`` first. Integrators:

- ``symplectic_euler`` (default, one load evaluation per step): v += dt a(x, v); x += dt v. For an axial
  segment mode with damping ratio zeta it is stable for omega_n dt <= 2 (sqrt(1 + zeta^2) - zeta), and it
  conserves energy without drift when nothing dissipates.
- ``rk2`` (explicit midpoint, MoorDyn's default, two evaluations per step): stable for omega_n dt <= 2 only
  with damping; undamped it amplifies every mode slightly at each step.
- ``implicit_euler`` (``physics/implicit.py``): linearly implicit backward Euler for the line nodes (axial
  spring-dampers, drag, seabed linearised; O(N) block elimination over the tree of lines), anchor explicit. No
  axial step limit: its step is capped for accuracy (segment rotation per step), typically 30x the explicit one.
  ``advance`` tells it when the topology is that of its previous step (no payout split or merge, not the first
  step of the call), so that it keeps its elimination order.

A blow-up is caught every step: any node faster than the speed limit, any segment strained beyond the strain
limit, or a non-finite value (NaN fails every comparison) ends the call with a status and the failing
component, never with NaN returned as a result. A step checks the loads at its start, so the state the last step
of a call leaves is checked by :func:`end_state_status` once its loads are evaluated (the env's batch kernel does
this after every advance).
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor import body_point, rotate_axis
from moor_env.physics.contact_broadphase import note_moved, prepare_near
from moor_env.physics.implicit import implicit_euler_update
from moor_env.physics.layout import (
    BF_ACTIVE,
    BF_S_TIP,
    BS_AXIS,
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    CF_ON,
    EF_DEPTH,
    EF_SPEED_LIMIT,
    EF_STRAIN_LIMIT,
    LF_MAX_TENSION,
    LI_NSEG,
    MF_MBL,
    N_BODY_STATE,
    NI_KIND,
    NODE_FREE,
    NODE_INACTIVE,
    SI_ACTIVE,
    SI_LINE,
    SI_MAT,
    STATUS_BREAKING_LOAD,
    STATUS_NONFINITE,
    STATUS_RUNNING,
    STATUS_SPEED_LIMIT,
    STATUS_STRAIN_LIMIT,
    STATUS_TIME_LIMIT,
    STATUS_TOUCHDOWN,
    TD_AXIS,
    TD_TIME,
    TD_TIP,
    TD_VEL,
)
from moor_env.physics.line import apply_payout
from moor_env.physics.loads import compute_accelerations, compute_loads, set_constrained_nodes
from moor_env.physics.stability import REFERENCE_SPEED_M_S

INTEGRATOR_SYMPLECTIC_EULER = 0
INTEGRATOR_RK2 = 1
INTEGRATOR_IMPLICIT_EULER = 2  # linearly implicit backward Euler for the lines (physics/implicit.py)

FAIL_NONE = 0
FAIL_NODE = 1
FAIL_SEGMENT = 2
FAIL_BODY = 3


@jit_step
def _kick_drift_nodes(node_i, node_pos, node_vel, node_acc, pos0, vel0, dt_v, dt_x):
    """vel = vel0 + dt_v * acc; pos = pos0 + dt_x * vel for free nodes. Returns (max speed^2, node)."""
    vmax2 = 0.0
    worst = -1
    for n in range(node_i.shape[0]):
        if node_i[n, NI_KIND] != NODE_FREE:
            continue
        v2 = 0.0
        for c in range(3):
            v = vel0[n, c] + dt_v * node_acc[n, c]
            node_vel[n, c] = v
            node_pos[n, c] = pos0[n, c] + dt_x * v
            v2 += v * v
        if not (v2 <= vmax2):
            vmax2 = v2
            worst = n
            if v2 != v2:
                return v2, n
    return vmax2, worst


@jit_step
def _kick_drift_body(body_state, body_acc, body0, dt_v, dt_x, wx, wy, wz, dt_rot):
    """Translational/rotational velocity update, then position and axis update of the anchor."""
    for c in range(3):
        body_state[BS_VEL + c] = body0[BS_VEL + c] + dt_v * body_acc[c]
        body_state[BS_OMEGA + c] = body0[BS_OMEGA + c] + dt_v * body_acc[3 + c]
        body_state[BS_POS + c] = body0[BS_POS + c] + dt_x * body_state[BS_VEL + c]
    rotate_axis(body_state, body0[BS_AXIS:BS_AXIS + 3], wx, wy, wz, dt_rot)
    v2 = 0.0
    for c in range(3):
        v2 += body_state[BS_VEL + c] ** 2
    return v2


@jit_no_refcount
def step(model, state, t, dt, integrator, same_topology):
    """One time step of length ``dt`` [s] from time ``t`` [s].

    ``same_topology``: the nodes and segments are those of the previous step on this state (the implicit step
    then keeps its elimination order).

    Returns
    -------
    status : int
        STATUS_RUNNING, or a blow-up status.
    fail_kind, fail_index : int
        Component of a blow-up (FAIL_NODE / FAIL_SEGMENT / FAIL_BODY and its index).
    """
    env_f, node_pos, node_vel = model.env_f, state.node_pos, state.node_vel
    body_state, node_i, node_acc = state.body_state, state.node_i, state.node_acc
    body_acc, pos0, vel0 = state.body_acc, state.pos0, state.vel0
    body0 = state.body0
    body_active = model.body_f[BF_ACTIVE] != 0.0
    near = body_active and model.contact_f[CF_ON] != 0.0 and integrator != INTEGRATOR_RK2
    if near:
        prepare_near(model, state, same_topology, dt)
    if integrator == INTEGRATOR_IMPLICIT_EULER:
        args_strain = compute_loads(model, state)
    else:
        args_strain = compute_accelerations(model, state)
    max_strain = args_strain[0]
    worst_seg = args_strain[1]
    for c in range(N_BODY_STATE):
        body0[c] = body_state[c]
    closing2 = 0.0
    if integrator == INTEGRATOR_SYMPLECTIC_EULER:
        vmax2, worst_node = _kick_drift_nodes(node_i, node_pos, node_vel, node_acc, node_pos, node_vel, dt, dt)
        body_v2 = 0.0
        if body_active:
            wx = body0[BS_OMEGA] + dt * body_acc[3]
            wy = body0[BS_OMEGA + 1] + dt * body_acc[4]
            wz = body0[BS_OMEGA + 2] + dt * body_acc[5]
            body_v2 = _kick_drift_body(body_state, body_acc, body0, dt, dt, wx, wy, wz, dt)
    elif integrator == INTEGRATOR_IMPLICIT_EULER:
        vmax2, worst_node, body_v2, closing2 = implicit_euler_update(model, state, dt, same_topology)
    else:
        for n in range(node_i.shape[0]):
            for c in range(3):
                pos0[n, c] = node_pos[n, c]
                vel0[n, c] = node_vel[n, c]
        # midpoint: positions advance with the start velocity, velocities with the start acceleration
        for n in range(node_i.shape[0]):
            if node_i[n, NI_KIND] == NODE_FREE:
                for c in range(3):
                    node_pos[n, c] = pos0[n, c] + 0.5 * dt * vel0[n, c]
                    node_vel[n, c] = vel0[n, c] + 0.5 * dt * node_acc[n, c]
        if body_active:
            for c in range(3):
                body_state[BS_POS + c] = body0[BS_POS + c] + 0.5 * dt * body0[BS_VEL + c]
                body_state[BS_VEL + c] = body0[BS_VEL + c] + 0.5 * dt * body_acc[c]
                body_state[BS_OMEGA + c] = body0[BS_OMEGA + c] + 0.5 * dt * body_acc[3 + c]
            rotate_axis(body_state, body0[BS_AXIS:BS_AXIS + 3], body0[BS_OMEGA], body0[BS_OMEGA + 1],
                        body0[BS_OMEGA + 2], 0.5 * dt)
        set_constrained_nodes(model, state, t + 0.5 * dt)
        mid = compute_accelerations(model, state)
        if not (mid[0] <= max_strain):
            max_strain = mid[0]
            worst_seg = mid[1]
        # full step: x1 = x0 + dt v_mid, v1 = v0 + dt a_mid (node_vel holds v_mid)
        for n in range(node_i.shape[0]):
            if node_i[n, NI_KIND] == NODE_FREE:
                for c in range(3):
                    node_pos[n, c] = pos0[n, c] + dt * node_vel[n, c]
        vmax2, worst_node = _kick_drift_nodes(node_i, node_pos, node_vel, node_acc, node_pos, vel0, dt, 0.0)
        body_v2 = 0.0
        if body_active:
            wx = body_state[BS_OMEGA]
            wy = body_state[BS_OMEGA + 1]
            wz = body_state[BS_OMEGA + 2]
            vmx = body_state[BS_VEL]
            vmy = body_state[BS_VEL + 1]
            vmz = body_state[BS_VEL + 2]
            body_state[BS_POS] = body0[BS_POS] + dt * vmx
            body_state[BS_POS + 1] = body0[BS_POS + 1] + dt * vmy
            body_state[BS_POS + 2] = body0[BS_POS + 2] + dt * vmz
            for c in range(3):
                body_state[BS_VEL + c] = body0[BS_VEL + c] + dt * body_acc[c]
                body_state[BS_OMEGA + c] = body0[BS_OMEGA + c] + dt * body_acc[3 + c]
            rotate_axis(body_state, body0[BS_AXIS:BS_AXIS + 3], wx, wy, wz, dt)
            for c in range(3):
                body_v2 += body_state[BS_VEL + c] ** 2
    if near:
        closing = closing2 ** 0.5 if integrator == INTEGRATOR_IMPLICIT_EULER else vmax2 ** 0.5 + body_v2 ** 0.5
        note_moved(state, dt, closing)
    set_constrained_nodes(model, state, t + dt)
    apply_payout(dt, node_pos, node_vel, node_i, state.seg_i, state.seg_f, state.line_i, state.line_f)
    if max_strain != max_strain:
        return STATUS_NONFINITE, FAIL_SEGMENT, worst_seg
    if vmax2 != vmax2:
        return STATUS_NONFINITE, FAIL_NODE, worst_node
    if body_v2 != body_v2:
        return STATUS_NONFINITE, FAIL_BODY, 0
    if max_strain > env_f[EF_STRAIN_LIMIT]:
        return STATUS_STRAIN_LIMIT, FAIL_SEGMENT, worst_seg
    limit2 = env_f[EF_SPEED_LIMIT] ** 2
    if vmax2 > limit2:
        return STATUS_SPEED_LIMIT, FAIL_NODE, worst_node
    if body_v2 > limit2:
        return STATUS_SPEED_LIMIT, FAIL_BODY, 0
    return STATUS_RUNNING, FAIL_NONE, -1


@jit_step
def end_state_status(model, state, max_strain, worst_seg, max_tension_before):
    """Blow-up status of the state reached by an advance, its loads just evaluated (``max_strain`` and
    ``worst_seg`` as :func:`~moor_env.physics.loads.compute_accelerations` returns them): STATUS_RUNNING if sound.

    The step's own checks read the loads at its start, so without this the last step's result would only be
    caught at the start of the next advance, after the caller has kept it. ``max_tension_before`` (each line's
    running maximum tension before the advance [N]; empty: no such check) also fails an advance that raised a
    line's running maximum above the line's breaking load (the least of its materials' MBL;
    ``STATUS_BREAKING_LOAD``, at the line's segment most loaded against its MBL now): the check of an advance at a
    step coarser than the scene's (the env's pre-release phase), where such a peak comes from a segment turned
    through several lengths in one step (a swinging chain loop) rather than from a load, and the advance is
    repeated at the scene's step. A line already above its breaking load (taken there at the scene's step) is
    checked too, at every raise: a coarse step's spike on top of such a peak is no load either (unchecked, a coarse
    step raised a mooring line's maximum from 1.2 to 25 times its MBL in a calm episode of
    ``benchmarks/robustness.py``).

    Returns
    -------
    status, fail_kind, fail_index : int
    """
    if max_strain != max_strain:
        return STATUS_NONFINITE, FAIL_SEGMENT, worst_seg
    if max_strain > model.env_f[EF_STRAIN_LIMIT]:
        return STATUS_STRAIN_LIMIT, FAIL_SEGMENT, worst_seg
    seg_i, seg_tension, mat_f, line_f = state.seg_i, state.seg_tension, model.mat_f, state.line_f
    for line in range(max_tension_before.shape[0]):
        if not line_f[line, LF_MAX_TENSION] > max_tension_before[line]:
            continue  # the advance did not raise this line's maximum
        breaking, worst, ratio = math.inf, -1, -1.0
        for s in range(seg_i.shape[0]):
            if seg_i[s, SI_ACTIVE] != 0 and seg_i[s, SI_LINE] == line:
                mbl = mat_f[seg_i[s, SI_MAT], MF_MBL]
                breaking = min(breaking, mbl)
                if seg_tension[s] / mbl > ratio:
                    worst, ratio = s, seg_tension[s] / mbl
        if line_f[line, LF_MAX_TENSION] > breaking:
            return STATUS_BREAKING_LOAD, FAIL_SEGMENT, worst
    return STATUS_RUNNING, FAIL_NONE, -1


@jit_no_refcount
def _record(model, state, t):
    """Append the tip state at time ``t`` [s] to the history (``hist``, ``hist_count[0]`` rows used)."""
    hist = state.hist
    hist_count = state.hist_count
    body_state = state.body_state
    k = hist_count[0]
    if k >= hist.shape[0]:
        return
    px, py, pz, vx, vy, vz = body_point(body_state, model.body_f[BF_S_TIP])
    hist[k, 0] = t
    hist[k, 1] = px
    hist[k, 2] = py
    hist[k, 3] = pz
    hist[k, 4] = vx
    hist[k, 5] = vy
    hist[k, 6] = vz
    for c in range(3):
        hist[k, 7 + c] = body_state[BS_AXIS + c]
        hist[k, 10 + c] = body_state[BS_OMEGA + c]
    hist_count[0] = k + 1


@jit_step
def _keep_segment_counts(line_i, nseg):
    """Whether every line still has ``nseg`` segments (no payout split or merge); ``nseg`` <- the counts."""
    same = True
    for line in range(line_i.shape[0]):
        if line_i[line, LI_NSEG] != nseg[line]:
            nseg[line] = line_i[line, LI_NSEG]
            same = False
    return same


@jit_no_refcount(inline="always")
def speed_step_factor(node_i, node_vel, growth_max):
    """How many times the implicit step may be lengthened at these velocities of the active nodes [m/s]: its accuracy
    cap lets a node at ``REFERENCE_SPEED_M_S`` cross half the shortest segment (``stability.implicit_time_step``);
    where the fastest node is slower, it crosses as little in a longer step. Between 1 and ``growth_max``; 1 where
    a speed is not finite."""
    v2max = 0.0
    for n in range(node_vel.shape[0]):
        if node_i[n, NI_KIND] == NODE_INACTIVE:
            continue
        v2 = node_vel[n, 0] ** 2 + node_vel[n, 1] ** 2 + node_vel[n, 2] ** 2
        if v2 != v2:
            return 1.0
        v2max = max(v2max, v2)
    if not (v2max * growth_max * growth_max > REFERENCE_SPEED_M_S * REFERENCE_SPEED_M_S):
        return growth_max
    return max(1.0, REFERENCE_SPEED_M_S / math.sqrt(v2max))


@jit_step
def advance(model, state, t, t_end, dt, integrator, detect_touchdown, hist_every, step_growth_max):
    """Step from ``t`` until ``t_end`` [s] (the first step that ends at or past ``t_end`` - dt / 2), touchdown of
    the anchor tip, or a blow-up.

    Only whole steps of ``dt`` are taken, so the time reached is within dt/2 of ``t_end`` and a run split into
    several calls is bit-identical to one call. With ``step_growth_max`` > 1 (``implicit_euler`` only) each step
    is ``dt`` times :func:`speed_step_factor` of the state it starts from, and the last step may end past
    ``t_end``; a step's length depends on its start state alone, so a split run is still bit-identical.

    Touchdown (``detect_touchdown``) is interpolated linearly inside the step in which the tip crosses
    z = -depth: its time, tip position, tip velocity and axis are written to ``state.touchdown``. Every
    ``hist_every`` steps (0: never) the tip state is appended to ``state.hist``.

    Returns
    -------
    status : int
        STATUS_TIME_LIMIT (reached t_end), STATUS_TOUCHDOWN or a blow-up status.
    t : float
        Time reached [s].
    n_steps : int
    fail_kind, fail_index : int
    """
    body_state = state.body_state
    line_i = state.line_i
    touchdown = state.touchdown
    body_active = model.body_f[BF_ACTIVE] != 0.0
    depth = model.env_f[EF_DEPTH]
    s_tip = model.body_f[BF_S_TIP]
    n_steps = 0
    p0x = p0y = p0z = v0x = v0y = v0z = e0x = e0y = e0z = 0.0
    set_constrained_nodes(model, state, t)
    # whole steps only, each as long as the state it starts from sets, so that splitting a run into calls never
    # changes the step sequence (determinism)
    h = dt
    grow = step_growth_max > 1.0 and integrator == INTEGRATOR_IMPLICIT_EULER
    # the topology is trusted only from the second step of a call on: between calls the caller may release,
    # drop a line or restore a state; within a call only a payout split or merge changes it (segment count)
    nseg = line_i[:, LI_NSEG].copy()
    same_topology = False
    while t < t_end - 0.5 * dt:
        if detect_touchdown:
            p0x, p0y, p0z, v0x, v0y, v0z = body_point(body_state, s_tip)
            e0x = body_state[BS_AXIS]
            e0y = body_state[BS_AXIS + 1]
            e0z = body_state[BS_AXIS + 2]
        if grow:
            h = dt * speed_step_factor(state.node_i, state.node_vel, step_growth_max)
        status, fail_kind, fail_index = step(model, state, t, h, integrator, same_topology)
        same_topology = _keep_segment_counts(line_i, nseg)
        n_steps += 1
        if status != STATUS_RUNNING:
            return status, t, n_steps, fail_kind, fail_index
        t_prev = t
        t = t + h
        if hist_every > 0 and n_steps % hist_every == 0 and body_active:
            _record(model, state, t)
        if detect_touchdown:
            p1x, p1y, p1z, v1x, v1y, v1z = body_point(body_state, s_tip)
            if p1z <= -depth:
                w = (p0z + depth) / (p0z - p1z)
                touchdown[TD_TIME] = t_prev + w * h
                touchdown[TD_TIP] = p0x + w * (p1x - p0x)
                touchdown[TD_TIP + 1] = p0y + w * (p1y - p0y)
                touchdown[TD_TIP + 2] = -depth
                touchdown[TD_VEL] = v0x + w * (v1x - v0x)
                touchdown[TD_VEL + 1] = v0y + w * (v1y - v0y)
                touchdown[TD_VEL + 2] = v0z + w * (v1z - v0z)
                ex = e0x + w * (body_state[BS_AXIS] - e0x)
                ey = e0y + w * (body_state[BS_AXIS + 1] - e0y)
                ez = e0z + w * (body_state[BS_AXIS + 2] - e0z)
                norm = math.sqrt(ex * ex + ey * ey + ez * ez)
                touchdown[TD_AXIS] = ex / norm
                touchdown[TD_AXIS + 1] = ey / norm
                touchdown[TD_AXIS + 2] = ez / norm
                return STATUS_TOUCHDOWN, t, n_steps, 0, -1
    return STATUS_TIME_LIMIT, t, n_steps, 0, -1

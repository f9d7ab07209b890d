"""Time integration: assemble accelerations, step (symplectic Euler or RK2 midpoint), detect events.

``advance`` is the one entry point called from Python: it steps from ``t`` to ``t_end`` (or to touchdown, or
to a blow-up) with no Python work per step. Integrators:

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
component, never with NaN returned as a result.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_step
from moor_env.physics.anchor import add_point_load, body_acceleration, body_loads, body_point, rotate_axis
from moor_env.physics.environment import current_velocity
from moor_env.physics.implicit import implicit_euler_update
from moor_env.physics.layout import (
    BF_S_TIP,
    BS_AXIS,
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    EF_DEPTH,
    EF_G,
    EF_RHO,
    EF_SEABED_SMOOTHING,
    EF_SPEED_LIMIT,
    EF_STRAIN_LIMIT,
    LI_NSEG,
    N_BODY_STATE,
    NF_BODY_S,
    NF_POINT_CA,
    NF_POINT_CDA,
    NF_POINT_MASS,
    NF_POINT_VOLUME,
    NI_KIND,
    NI_REF,
    NODE_BODY,
    NODE_FREE,
    NODE_VESSEL,
    NODE_WELDED,
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
from moor_env.physics.linalg3 import solve_sym3
from moor_env.physics.line import apply_payout, segment_loads
from moor_env.physics.seabed import seabed_force
from moor_env.physics.vessels import track_state

INTEGRATOR_SYMPLECTIC_EULER = 0
INTEGRATOR_RK2 = 1
INTEGRATOR_IMPLICIT_EULER = 2  # linearly implicit backward Euler for the lines (physics/implicit.py)

FAIL_NONE = 0
FAIL_NODE = 1
FAIL_SEGMENT = 2
FAIL_BODY = 3


@jit_step
def set_constrained_nodes(t, node_pos, node_vel, body_state, node_i, node_f, tracks, env_f):
    """Place vessel, body-attached and welded nodes from their vessel track, the anchor or their parent."""
    nn = node_i.shape[0]
    for n in range(nn):
        kind = node_i[n, NI_KIND]
        if kind == NODE_VESSEL:
            x, y, z, vx, vy, vz = track_state(tracks, node_i[n, NI_REF], t, env_f)
        elif kind == NODE_BODY:
            x, y, z, vx, vy, vz = body_point(body_state, node_f[n, NF_BODY_S])
        else:
            continue
        node_pos[n, 0] = x
        node_pos[n, 1] = y
        node_pos[n, 2] = z
        node_vel[n, 0] = vx
        node_vel[n, 1] = vy
        node_vel[n, 2] = vz
    for n in range(nn):
        if node_i[n, NI_KIND] == NODE_WELDED:
            p = node_i[n, NI_REF]
            for c in range(3):
                node_pos[n, c] = node_pos[p, c]
                node_vel[n, c] = node_vel[p, c]


@jit_step
def compute_accelerations(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i, seg_f, mat_f,
                          line_f, body_f, body_q, env_f, current_profile, node_force, node_mm, node_mass,
                          node_contact, node_acc, seg_tension, body_load, body_acc):
    """Loads and accelerations of every free node and the anchor at the current state.

    Returns
    -------
    max_strain : float
        Largest segment strain (NaN if any load is non-finite).
    worst_segment : int
    """
    max_strain, worst = compute_loads(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i, seg_f,
                                      mat_f, line_f, body_f, body_q, env_f, current_profile, node_force, node_mm,
                                      node_mass, node_contact, seg_tension, body_load, body_acc)
    for n in range(node_i.shape[0]):
        if node_i[n, NI_KIND] == NODE_FREE:
            ax, ay, az = solve_sym3(node_mass[n], node_mm[n, 0], node_mm[n, 1], node_mm[n, 2], node_mm[n, 3],
                                    node_mm[n, 4], node_mm[n, 5], node_force[n, 0], node_force[n, 1],
                                    node_force[n, 2])
            node_acc[n, 0] = ax
            node_acc[n, 1] = ay
            node_acc[n, 2] = az
    return max_strain, worst


@jit_step
def compute_loads(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i, seg_f, mat_f, line_f, body_f,
                  body_q, env_f, current_profile, node_force, node_mm, node_mass, node_contact, seg_tension,
                  body_load, body_acc):
    """Loads (forces, masses, added masses, contact areas, tensions) of every node and the anchor's acceleration.

    The free nodes' accelerations are left to the caller: the implicit step solves for them with the lines'
    stiffness, so it skips ``compute_accelerations``' explicit solve.
    """
    rho = env_f[EF_RHO]
    g = env_f[EF_G]
    nn = node_i.shape[0]
    for n in range(nn):
        for c in range(3):
            node_force[n, c] = 0.0
        for c in range(6):
            node_mm[n, c] = 0.0
        node_mass[n] = 0.0
        node_contact[n] = 0.0
    max_strain, worst = segment_loads(node_pos, node_vel, seg_i, seg_f, mat_f, line_f, env_f, current_profile,
                                      node_force, node_mm, node_mass, node_contact, seg_tension)
    for n in range(nn):
        kind = node_i[n, NI_KIND]
        if kind != NODE_FREE and kind != NODE_WELDED:
            continue
        pm = node_f[n, NF_POINT_MASS]
        vol = node_f[n, NF_POINT_VOLUME]
        if pm > 0.0 or vol > 0.0:
            node_mass[n] += pm
            node_force[n, 2] -= (pm - rho * vol) * g
            ma = rho * vol * node_f[n, NF_POINT_CA]
            node_mm[n, 0] += ma
            node_mm[n, 1] += ma
            node_mm[n, 2] += ma
            cda = node_f[n, NF_POINT_CDA]
            if cda > 0.0:
                ux, uy, uz = current_velocity(node_pos[n, 2], env_f, current_profile)
                rx = ux - node_vel[n, 0]
                ry = uy - node_vel[n, 1]
                rz = uz - node_vel[n, 2]
                k = 0.5 * rho * cda * math.sqrt(rx * rx + ry * ry + rz * rz)
                node_force[n, 0] += k * rx
                node_force[n, 1] += k * ry
                node_force[n, 2] += k * rz
        if node_pos[n, 2] < -env_f[EF_DEPTH] or env_f[EF_SEABED_SMOOTHING] > 0.0:
            fx, fy, fz = seabed_force(node_pos[n, 2], node_vel[n, 0], node_vel[n, 1], node_vel[n, 2],
                                      node_contact[n], env_f)
            node_force[n, 0] += fx
            node_force[n, 1] += fy
            node_force[n, 2] += fz
    for n in range(nn):
        if node_i[n, NI_KIND] == NODE_WELDED:
            p = node_i[n, NI_REF]
            for c in range(3):
                node_force[p, c] += node_force[n, c]
            for c in range(6):
                node_mm[p, c] += node_mm[n, c]
            node_mass[p] += node_mass[n]
    if body_active:
        for c in range(6):
            body_load[c] = 0.0
        body_loads(body_state, body_f, body_q, env_f, current_profile, body_load)
        for n in range(nn):
            if node_i[n, NI_KIND] == NODE_BODY:
                add_point_load(body_load, body_state, node_f[n, NF_BODY_S], node_force[n, 0], node_force[n, 1],
                               node_force[n, 2])
        body_acceleration(body_state, body_f, body_load, body_acc)
    return max_strain, worst


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


@jit_step
def step(t, dt, integrator, body_active, node_pos, node_vel, body_state, node_i, node_f, seg_i, seg_f, mat_f,
         line_i, line_f, body_f, body_q, env_f, current_profile, tracks, node_force, node_mm, node_mass,
         node_contact, node_acc, seg_tension, body_load, body_acc, pos0, vel0, body0, same_topology):
    """One time step of length ``dt`` from time ``t``.

    ``same_topology``: the nodes and segments are those of the previous step on this workspace (the implicit
    step then keeps its elimination order).

    Returns
    -------
    status : int
        STATUS_RUNNING, or a blow-up status.
    fail_kind, fail_index : int
        Component of a blow-up (FAIL_NODE / FAIL_SEGMENT / FAIL_BODY and its index).
    """
    if integrator == INTEGRATOR_IMPLICIT_EULER:
        args_strain = compute_loads(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i, seg_f,
                                    mat_f, line_f, body_f, body_q, env_f, current_profile, node_force, node_mm,
                                    node_mass, node_contact, seg_tension, body_load, body_acc)
    else:
        args_strain = compute_accelerations(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i,
                                            seg_f, mat_f, line_f, body_f, body_q, env_f, current_profile,
                                            node_force, node_mm, node_mass, node_contact, node_acc, seg_tension,
                                            body_load, body_acc)
    max_strain = args_strain[0]
    worst_seg = args_strain[1]
    for c in range(N_BODY_STATE):
        body0[c] = body_state[c]
    if integrator == INTEGRATOR_SYMPLECTIC_EULER:
        vmax2, worst_node = _kick_drift_nodes(node_i, node_pos, node_vel, node_acc, node_pos, node_vel, dt, dt)
        body_v2 = 0.0
        if body_active:
            wx = body0[BS_OMEGA] + dt * body_acc[3]
            wy = body0[BS_OMEGA + 1] + dt * body_acc[4]
            wz = body0[BS_OMEGA + 2] + dt * body_acc[5]
            body_v2 = _kick_drift_body(body_state, body_acc, body0, dt, dt, wx, wy, wz, dt)
    elif integrator == INTEGRATOR_IMPLICIT_EULER:
        vmax2, worst_node, body_v2 = implicit_euler_update(dt, body_active, node_pos, node_vel, body_state, node_i,
                                                           node_f, seg_i, seg_f, mat_f, body_f, env_f,
                                                           current_profile, node_force, node_mm, node_mass,
                                                           node_contact, node_acc, seg_tension, body_acc, pos0,
                                                           vel0, body0, same_topology)
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
        set_constrained_nodes(t + 0.5 * dt, node_pos, node_vel, body_state, node_i, node_f, tracks, env_f)
        mid = compute_accelerations(node_pos, node_vel, body_state, body_active, node_i, node_f, seg_i, seg_f,
                                    mat_f, line_f, body_f, body_q, env_f, current_profile, node_force, node_mm,
                                    node_mass, node_contact, node_acc, seg_tension, body_load, body_acc)
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
    set_constrained_nodes(t + dt, node_pos, node_vel, body_state, node_i, node_f, tracks, env_f)
    apply_payout(dt, node_pos, node_vel, node_i, seg_i, seg_f, line_i, line_f)
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
def _record(hist, hist_count, t, body_state, body_f):
    k = hist_count[0]
    if k >= hist.shape[0]:
        return
    px, py, pz, vx, vy, vz = body_point(body_state, body_f[BF_S_TIP])
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


@jit_step
def advance(t, t_end, dt, integrator, body_active, detect_touchdown, node_pos, node_vel, body_state, node_i,
            node_f, seg_i, seg_f, mat_f, line_i, line_f, body_f, body_q, env_f, current_profile, tracks,
            node_force, node_mm, node_mass, node_contact, node_acc, seg_tension, body_load, body_acc, pos0, vel0,
            body0, touchdown, hist, hist_count, hist_every):
    """Step from ``t`` until the step nearest ``t_end``, touchdown of the anchor tip, or a blow-up.

    Only whole steps of ``dt`` are taken, so the time reached is within dt/2 of ``t_end`` and a run split into
    several calls is bit-identical to one call.

    Touchdown is interpolated linearly inside the step in which the tip crosses z = -depth: its time, tip
    position, tip velocity and axis are written to ``touchdown``. Every ``hist_every`` steps the tip state is
    appended to ``hist`` (``hist_count[0]`` rows used).

    Returns
    -------
    status : int
        STATUS_TIME_LIMIT (reached t_end), STATUS_TOUCHDOWN or a blow-up status.
    t : float
        Time reached [s].
    n_steps : int
    fail_kind, fail_index : int
    """
    depth = env_f[EF_DEPTH]
    s_tip = body_f[BF_S_TIP]
    n_steps = 0
    p0x = p0y = p0z = v0x = v0y = v0z = e0x = e0y = e0z = 0.0
    set_constrained_nodes(t, node_pos, node_vel, body_state, node_i, node_f, tracks, env_f)
    # whole steps only, so that splitting a run into calls never changes the step sequence (determinism)
    h = dt
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
        status, fail_kind, fail_index = step(t, h, integrator, body_active, node_pos, node_vel, body_state,
                                             node_i, node_f, seg_i, seg_f, mat_f, line_i, line_f, body_f, body_q,
                                             env_f, current_profile, tracks, node_force, node_mm, node_mass,
                                             node_contact, node_acc, seg_tension, body_load, body_acc, pos0,
                                             vel0, body0, same_topology)
        same_topology = _keep_segment_counts(line_i, nseg)
        n_steps += 1
        if status != STATUS_RUNNING:
            return status, t, n_steps, fail_kind, fail_index
        t_prev = t
        t = t + h
        if hist_every > 0 and n_steps % hist_every == 0 and body_active:
            _record(hist, hist_count, t, body_state, body_f)
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

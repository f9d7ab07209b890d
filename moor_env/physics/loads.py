"""The loads of a state: every force on the line nodes and the anchor, and the nodes the state prescribes.

:func:`compute_loads` calls each force law once (line segments ``line.segment_loads``, point masses
``point_loads.add_point_loads``, seabed ``seabed.seabed_force``, the anchor ``anchor.body_loads``, the lines'
contact with the anchor, of its nodes ``contact.add_contact_loads`` and of its segments
``segment_contact.add_segment_contact_loads``) for every integrator and the statics; a new force is a
law in its own module, called here, with its parameters in the model record and any state it carries in the state
record (``physics/records.py``). :func:`set_constrained_nodes` places the nodes held by a vessel, the anchor or a
parent node; :func:`compute_accelerations` adds the explicit integrators' solve for the free nodes.
"""

from __future__ import annotations

from moor_env.physics._jit import jit_no_refcount
from moor_env.physics.anchor import add_point_load, body_acceleration, body_loads, body_point
from moor_env.physics.contact import add_contact_loads, record_contact_force
from moor_env.physics.layout import (
    BF_ACTIVE,
    CF_ON,
    EF_DEPTH,
    EF_SEABED_SMOOTHING,
    NEAR_ON,
    NF_BODY_S,
    NI_KIND,
    NI_REF,
    NODE_BODY,
    NODE_FREE,
    NODE_VESSEL,
    NODE_WELDED,
)
from moor_env.physics.linalg3 import solve_sym3
from moor_env.physics.line import segment_loads
from moor_env.physics.point_loads import add_point_loads
from moor_env.physics.seabed import seabed_force
from moor_env.physics.segment_contact import add_segment_contact_loads
from moor_env.physics.vessels import track_state


@jit_no_refcount
def set_constrained_nodes(model, state, t):
    """Place vessel, body-attached and welded nodes at time ``t`` [s] from their vessel track, the anchor or their
    parent."""
    tracks, env_f, node_pos = model.tracks, model.env_f, state.node_pos
    node_vel, body_state, node_i = state.node_vel, state.body_state, state.node_i
    node_f = state.node_f
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


@jit_no_refcount
def compute_accelerations(model, state):
    """Loads and accelerations of every free node and the anchor at the current state.

    Returns
    -------
    max_strain : float
        Largest segment strain (NaN if any load is non-finite).
    worst_segment : int
    """
    max_strain, worst = compute_loads(model, state)
    node_i, node_mm, node_mass = state.node_i, state.node_mm, state.node_mass
    node_force, node_acc = state.node_force, state.node_acc
    for n in range(node_i.shape[0]):
        if node_i[n, NI_KIND] == NODE_FREE:
            ax, ay, az = solve_sym3(node_mass[n], node_mm[n, 0], node_mm[n, 1], node_mm[n, 2], node_mm[n, 3],
                                    node_mm[n, 4], node_mm[n, 5], node_force[n, 0], node_force[n, 1],
                                    node_force[n, 2])
            node_acc[n, 0] = ax
            node_acc[n, 1] = ay
            node_acc[n, 2] = az
    return max_strain, worst


@jit_no_refcount
def compute_loads(model, state):
    """Loads (forces, masses, added masses, contact areas, tensions) of every node and the anchor's acceleration.

    The free nodes' accelerations are left to the caller: the implicit step solves for them with the lines'
    stiffness, so it skips ``compute_accelerations``' explicit solve. Each force law is called here once, for
    every integrator and the statics.

    Returns
    -------
    max_strain : float
        Largest segment strain (NaN if any load is non-finite).
    worst_segment : int
    """
    mat_f, body_f, body_q = model.mat_f, model.body_f, model.body_q
    env_f, current_profile, node_pos = model.env_f, model.current_profile, state.node_pos
    node_vel, body_state, node_i = state.node_vel, state.body_state, state.node_i
    node_f, node_force, node_mm = state.node_f, state.node_force, state.node_mm
    node_mass, node_contact, body_load = state.node_mass, state.node_contact, state.body_load
    nn = node_i.shape[0]
    for n in range(nn):
        for c in range(3):
            node_force[n, c] = 0.0
        for c in range(6):
            node_mm[n, c] = 0.0
        node_mass[n] = 0.0
        node_contact[n] = 0.0
    max_strain, worst = segment_loads(node_pos, node_vel, state.seg_i, state.seg_f, mat_f, state.line_f, env_f,
                                      current_profile, node_force, node_mm, node_mass, node_contact,
                                      state.seg_tension)
    for n in range(nn):
        kind = node_i[n, NI_KIND]
        if kind != NODE_FREE and kind != NODE_WELDED:
            continue
        add_point_loads(n, node_f, node_pos, node_vel, env_f, current_profile, node_force, node_mm, node_mass)
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
    if body_f[BF_ACTIVE] != 0.0:
        for c in range(6):
            body_load[c] = 0.0
        body_loads(body_state, body_f, body_q, env_f, current_profile, body_load)
        if model.contact_f[CF_ON] != 0.0:
            listed_on = state.near_skin[NEAR_ON] != 0.0
            reaction = add_contact_loads(node_pos, node_vel, node_i, node_mass, node_force, body_state,
                                         model.contact_shape, model.contact_f, state.contact_out, -env_f[EF_DEPTH],
                                         state.near_nodes, listed_on)
            segments = add_segment_contact_loads(node_pos, node_vel, node_i, node_mass, state.seg_i, node_force,
                                                 body_state, model.contact_shape, model.contact_f, -env_f[EF_DEPTH],
                                                 state.contact_out, state.near_segs, listed_on)
            for c in range(6):
                body_load[c] += reaction[c] + segments[c]
            record_contact_force(state.contact_out, reaction[0] + segments[0], reaction[1] + segments[1],
                                 reaction[2] + segments[2])
        for n in range(nn):
            if node_i[n, NI_KIND] == NODE_BODY:
                add_point_load(body_load, body_state, node_f[n, NF_BODY_S], node_force[n, 0], node_force[n, 1],
                               node_force[n, 2])
        body_acceleration(body_state, body_f, body_load, state.body_acc)
    return max_strain, worst

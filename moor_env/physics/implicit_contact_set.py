"""The contact set of the implicit step (``physics/implicit.py``): which line nodes carry the line-anchor contact's
linearised law (``physics/implicit_contact.py``) during the step.

- The set holds the nodes inside at the start of the step and those predicted to land within it; after each
  solve, a node outside predicted inside at the end of the step enters with the unclipped linear law
  k d - c (w . n) (d < 0: the gap), so that the solve sees where it lands, and a node inside predicted outside
  leaves (its start-of-step force removed); each node changes at most once per step (as the segments,
  ``implicit_active_set``), a coming node that misses at most twice (it may still enter). A node predicted to
  land that the contact's damping pushes back out within the step keeps its law where an estimate says that
  without it, it would end inside (:func:`_caught`).
- Broad phase: once per step, one distance per node to the anchor's COG keeps the candidates, the nodes that can
  reach the anchor within the step; the solves test only them. Storage: ``state.contact_set`` holds the
  candidates in node order, each as node << ``SET_BITS`` | its ``SET_*`` state, the list ended by -1 where it
  is shorter than the nodes.
- The segments in contact during the step (``physics/segment_contact.py``) are listed once per step with their law,
  in ``state.segment_set`` (:func:`init_segment_set`): the step's assembly and reaction visit only them.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount
from moor_env.physics.anchor_surface import bounding_radius_m, within_reach
from moor_env.physics.contact import relative_velocity
from moor_env.physics.contact_broadphase import covers_step, listed
from moor_env.physics.implicit_contact import (
    SET_BITS,
    SET_COMING,
    SET_ENTERED,
    SET_IN,
    SET_LEFT,
    SET_MISSED,
    SET_OUT,
    candidate,
    contact_force_change,
    predicted_depth,
    segment_mode,
    start_state,
)
from moor_env.physics.layout import (
    BS_POS,
    CC_READY,
    CF_SEGMENTS,
    EF_DEPTH,
    EF_SPEED_LIMIT,
    NI_KIND,
    NODE_FREE,
    SI_A,
    SI_B,
)
from moor_env.physics.segment_contact import may_cut, near_sphere, segment_contact

DEPTH_TOLERANCE_M = 1e-6  # a node must miss its predicted set by this much before the step is solved again
# a node this close to the anchor counts as resting on it, its explicit load counted in its landing (h^2 a off a
# surface accelerating at a: 0.7 mm at 5.7 m/s^2 and 11.25 ms; 2 mm covers 15 m/s^2)
RESTING_GAP_M = 2e-3


@jit_no_refcount(inline="always")
def init_contact_set(h, model, state):
    """Start of a step: the step's candidates, in node order, into ``state.contact_set`` (each as
    node << ``SET_BITS`` | its state, the list ended by -1 where shorter than the nodes): the free nodes above the
    seabed (below it the anchor is in the soil, ``contact.add_contact_loads``) that can reach the anchor in the
    step (the broad phase: one distance per node and step; the solves test the candidates only). Every candidate
    inside the anchor is in the contact set (``SET_IN``), and every one that reaches it within the step joins it
    (``SET_COMING``), so that a node landing on the anchor needs no second solve: reaches it at its present
    velocity, relative to the anchor's point at its present velocity as the solve's law takes it, changed where it
    lies within ``RESTING_GAP_M`` of the anchor by its explicit load over the step, h F / m (its loads at the
    start of the step, without a contact force: it is outside; its added mass left out). Why: a chain
    resting on the back end of the accelerating anchor starts each step a fraction of a millimetre off it (the law
    holds the anchor's point at its start velocity) and falls back on it within the step. Why only that close: a
    joining node carries the linear law from its gap, which pulls it in, so a prediction that reaches farther would
    pull in nodes that do not land."""
    contact_set = state.contact_set
    node_i = state.node_i
    p = state.node_pos
    v = state.node_vel
    body_state = state.body_state
    # the broad phase: in a step the integrator accepts neither the node nor the COG moves faster than the speed
    # limit (beyond it the step fails), so a node farther than 2 h v_limit outside the sphere cannot reach it
    body_m = bounding_radius_m(model.contact_shape)
    body2 = body_m * body_m
    far = body_m + 2.0 * h * model.env_f[EF_SPEED_LIMIT]
    far2 = far * far
    gx = body_state[BS_POS]
    gy = body_state[BS_POS + 1]
    gz = body_state[BS_POS + 2]
    seabed_z = -model.env_f[EF_DEPTH]
    k = 0
    for n in range(node_i.shape[0]):
        dz = p[n, 2] - gz
        if dz * dz > far2:
            continue
        dx = p[n, 0] - gx
        dy = p[n, 1] - gy
        r2 = dx * dx + dy * dy + dz * dz
        if r2 > far2 or node_i[n, NI_KIND] != NODE_FREE or p[n, 2] < seabed_z:
            continue
        # the start-of-step state, where computed here, is cached for the step (``start_state``)
        state.contact_cache[k, CC_READY] = 0.0
        mode = SET_OUT
        if r2 <= body2 and within_reach(p[n, 0], p[n, 1], p[n, 2], body_state, model.contact_shape):
            if start_state(model, state, k, n)[0] > 0.0:
                mode = SET_IN
        if mode == SET_OUT:
            wx, wy, wz = relative_velocity(p[n, 0], p[n, 1], p[n, 2], v[n, 0], v[n, 1], v[n, 2], body_state)
            # its velocity changed by its explicit load over the step (outside, no contact force in it), counted
            # only where it rests (below)
            inv_m = h / max(state.node_mass[n], 1e-12)
            dx = inv_m * state.node_force[n, 0]
            dy = inv_m * state.node_force[n, 1]
            dz = inv_m * state.node_force[n, 2]
            reach = h * math.sqrt((wx + dx) ** 2 + (wy + dy) ** 2 + (wz + dz) ** 2)
            if within_reach(p[n, 0], p[n, 1], p[n, 2], body_state, model.contact_shape, reach):
                depth, nx, ny, nz = start_state(model, state, k, n)[:4]
                if -depth > RESTING_GAP_M:  # not resting: its present velocity alone
                    dx = dy = dz = 0.0
                if predicted_depth(h, depth, nx, ny, nz, wx, wy, wz, dx, dy, dz) > DEPTH_TOLERANCE_M:
                    mode = SET_COMING
        contact_set[k] = (n << SET_BITS) | mode
        k += 1
    if k < contact_set.shape[0]:
        contact_set[k] = -1
    init_segment_set(h, model, state)


# inlined into init_contact_set, its one caller: a call that takes the records passes their every array (~0.1 us)
@jit_no_refcount(inline="always")
def init_segment_set(h, model, state):
    """Start of a step: the segments in contact during it, each with its law (``implicit_contact.segment_mode``),
    into ``state.segment_set`` (segment << ``SET_BITS`` | its state, ended by -1 where shorter than the segments);
    the step's passes over the segment contacts (``implicit_contact._segment_pass``) visit only these. Broad
    phase: the segments listed near the anchor where the list holds all that can reach it in the step
    (``contact_broadphase.covers_step``), else all; of them, those within the anchor's bounding sphere grown by the
    farthest a segment and the anchor close in within an accepted step (2 h v_limit,
    ``segment_contact.near_sphere``), then ``segment_contact.may_cut`` grown by the farthest this segment's nodes
    move against the anchor's points at their present velocities (h max |w|: the deepest point moves at the nodes'
    relative velocities interpolated, no faster)."""
    segment_set = state.segment_set
    seg_i = state.seg_i
    p = state.node_pos
    v = state.node_vel
    body_state = state.body_state
    shape = model.contact_shape
    seabed_z = -model.env_f[EF_DEPTH]
    radius = bounding_radius_m(shape)
    far = 2.0 * h * model.env_f[EF_SPEED_LIMIT]
    listed_on = covers_step(model, state, h)
    near = state.near_segs
    k = 0
    for j in range(seg_i.shape[0] if model.contact_f[CF_SEGMENTS] != 0.0 else 0):
        s = listed(near, listed_on, j)
        if s < 0:
            break
        if not near_sphere(p, seg_i, s, body_state, radius + far):
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        speed2 = 0.0
        for n in (a, b):
            wx, wy, wz = relative_velocity(p[n, 0], p[n, 1], p[n, 2], v[n, 0], v[n, 1], v[n, 2], body_state)
            speed2 = max(speed2, wx * wx + wy * wy + wz * wz)
        if not may_cut(p, state.node_i, seg_i, s, body_state, shape, seabed_z, radius, h * math.sqrt(speed2)):
            continue
        e, _, _, _, _, _, _, nx, ny, nz, wx, wy, wz, _, _, wa, wb, node_inside = segment_contact(
            p, v, state.node_i, state.node_mass, a, b, body_state, shape, model.contact_f)
        mode = segment_mode(h, e, nx, ny, nz, wx, wy, wz, node_inside)
        if wa + wb <= 0.0 or mode == SET_OUT:
            continue
        segment_set[k] = (s << SET_BITS) | mode
        k += 1
    if k < segment_set.shape[0]:
        segment_set[k] = -1


@jit_no_refcount
def _caught(h, model, state, n, depth, end, nx, ny, nz, wx, wy, wz):
    """Whether a coming node (start depth ``depth`` [m]) that the solve ends ``end`` [m] outside the anchor
    (negative) was stopped by the contact: the force its law applied in the step
    (``implicit_contact.contact_force_change``: k d - c (w + dv) . n at the end) pushes it out, and without that
    push it would end inside, estimated as h^2 F / m deeper (its structural mass alone: no added mass, no pull of
    its line). Such a node keeps its law. Why: solved without it, such a node mostly ends inside, enters with the
    same law again and the step ends near the first solve's answer after two more solves; on the vertical chain's
    implicit fall that was every one of these nodes (32 solves in 399 steps). It is an estimate, so it changes a
    result where it is wrong: on gjoa-500's implicit fall, once in 201 cases (a node kept with its law 0.15 mm off
    the anchor that, solved without it, ends 0.71 mm off with no contact force)."""
    dv = state.node_acc
    mass = state.node_mass[n]
    fx, fy, fz = contact_force_change(h, SET_ENTERED, depth, nx, ny, nz, wx, wy, wz, mass, model.contact_f,
                                      dv[n, 0], dv[n, 1], dv[n, 2], 0.0, 0.0, 0.0)
    normal = fx * nx + fy * ny + fz * nz
    return normal > 0.0 and end + h * h * normal / max(mass, 1e-12) > DEPTH_TOLERANCE_M


@jit_no_refcount(inline="always")
def update_contact_set(h, model, state):
    """After a solve (``node_acc`` = dv): candidates outside predicted inside at the end of the step enter the set,
    nodes inside predicted outside leave it, each once per step. Returns how many changed."""
    contact_set = state.contact_set
    p = state.node_pos
    v = state.node_vel
    dv = state.node_acc
    changed = 0
    for k in range(contact_set.shape[0]):
        n, mode = candidate(contact_set, k)
        if n < 0:
            break
        if mode == SET_ENTERED or mode == SET_LEFT:
            continue
        wx, wy, wz = relative_velocity(p[n, 0], p[n, 1], p[n, 2], v[n, 0], v[n, 1], v[n, 2], state.body_state)
        # reach: how far the node can move against the anchor in the step
        reach = h * (math.sqrt(wx * wx + wy * wy + wz * wz)
                     + math.sqrt(dv[n, 0] * dv[n, 0] + dv[n, 1] * dv[n, 1] + dv[n, 2] * dv[n, 2]))
        if not within_reach(p[n, 0], p[n, 1], p[n, 2], state.body_state, model.contact_shape, reach):
            continue
        depth, nx, ny, nz, wx, wy, wz = start_state(model, state, k, n)[:7]
        end = predicted_depth(h, depth, nx, ny, nz, wx, wy, wz, dv[n, 0], dv[n, 1], dv[n, 2])
        if (mode == SET_OUT or mode == SET_MISSED) and end > DEPTH_TOLERANCE_M:
            mode = SET_ENTERED
        elif mode == SET_IN and end < -DEPTH_TOLERANCE_M:
            mode = SET_LEFT
        elif mode == SET_COMING and end < -DEPTH_TOLERANCE_M and not _caught(h, model, state, n, depth, end, nx, ny,
                                                                            nz, wx, wy, wz):
            mode = SET_MISSED
        else:
            continue
        contact_set[k] = (n << SET_BITS) | mode
        changed += 1
    return changed

"""The line-anchor contact's broad phase across time steps: the nodes and segments near the anchor, listed once and
reused while nothing else can have come near (a neighbour list with a skin, as in molecular dynamics).

Why: in a fall most of a line lies tens to hundreds of metres from the anchor, and testing every node and every
segment against the anchor's bounding sphere at every step costs several per cent of an explicit step. The list
holds the free nodes within R + ``SKIN_M`` of the anchor's COG and the segments whose nearest point lies within it
(R: ``anchor_surface.bounding_radius_m``, the sphere about the COG that holds the anchor whatever its orientation),
and every segment with a node that is not free (a vessel's or the anchor's node moves with its holder, not at the
free nodes' speeds). The contact's load passes (``contact.add_contact_loads``,
``segment_contact.add_segment_contact_loads``) visit only the listed ones while the nodes and the COG cannot have
closed the skin: the sum over the steps since the list was built of dt times a bound on the free nodes' speeds
relative to the COG, each taken after the step (the explicit and implicit Euler steps move every point by dt times
its new velocity), stays below ``SKIN_M``. The implicit step gives the fastest node's relative speed itself, from
the loop that updates the nodes; the explicit step gives the fastest node's speed plus the COG's
(``benchmarks/contact_cost.py`` counts the lists each fall builds). Every node or
segment left out then lies outside the sphere, where the contact's force is zero, so the forces, their order of
summation and every result are bit for bit those of a pass over all.

Only ``integrate.step`` uses the list, within its own step (symplectic and implicit Euler; the midpoint step
moves its points at its midpoint velocities, which it does not bound): ``near_skin[NEAR_ON]`` is set for that
step only, so that the statics and a load evaluation from Python pass over all. The list is
rebuilt at the first step of every ``integrate.advance`` call and after a payout changed the segments.

The implicit step's segment contacts (``implicit_contact_set.init_segment_set``) visit the listed segments too
where the list holds every segment that the step's prediction can bring to the anchor (:func:`covers_step`). That
prediction (``implicit_contact.segment_mode``) moves a segment by h w (w: its points' velocities relative to the
anchor at the start of the step, at most the bound the last step ended with, ``NEAR_SPEED_M_S``, plus the
anchor's rotation times the distance); a segment whose nearest point lies farther than h |w| outside the sphere
gets no law in the step. Where that reach fits in what is left of the skin, every other segment is listed, and
the step's segment set is that of a pass over all. The speeds are known from the second
step of an ``advance`` call on; the lists are rebuilt a step early where the next step's reach would not fit.

The skin: 2 m is about 100 explicit steps of a node falling at 25 m/s onto the anchor (0.34 ms steps) and two
implicit steps (11 ms); a chain that falls with the anchor keeps a list for many more (``benchmarks/contact_cost.py``
counts them). It adds to the list only the chain within 2 m of the sphere.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor_surface import bounding_radius_m
from moor_env.physics.layout import (
    BS_OMEGA,
    BS_POS,
    NEAR_BUILDS,
    NEAR_LONGEST_M,
    NEAR_MOVED_M,
    NEAR_ON,
    NEAR_SPEED_M_S,
    NI_KIND,
    NODE_FREE,
    SI_A,
    SI_ACTIVE,
    SI_B,
)

SKIN_M = 2.0  # how far beyond the anchor's bounding sphere the list reaches [m]
ROUNDING_M = 1e-6  # the lists are rebuilt this much before the skin closes (positions are rounded at every step)


@jit_no_refcount(inline="always")
def prepare_near(model, state, same_topology, dt):
    """Before a step of ``dt`` [s], its load evaluation: rebuild the lists where needed (not ``same_topology``, i.e.
    the first step of a call or after a payout; the skin closed, or would not hold the step's reach,
    :func:`step_reach_m`) and let the contact's passes use them (``NEAR_ON``)."""
    skin = state.near_skin
    if not same_topology:  # the last step's speeds are another call's, or the segments changed since
        skin[NEAR_SPEED_M_S] = math.inf
    if not same_topology or not skin[NEAR_MOVED_M] + step_reach_m(model, state, dt) < SKIN_M - ROUNDING_M:
        _build(model, state)
        skin[NEAR_MOVED_M] = 0.0
        skin[NEAR_BUILDS] += 1.0
    skin[NEAR_ON] = 1.0


@jit_no_refcount(inline="always")
def note_moved(state, dt, closing_m_s):
    """After a step of ``dt`` [s] in which no free node moved faster than ``closing_m_s`` [m/s] relative to the
    COG (their new velocities; the fastest node's speed plus the COG's bounds it): add how far they can have
    closed on each other, keep that speed for the next step, and end the lists' use by anything but the next
    step."""
    skin = state.near_skin
    skin[NEAR_MOVED_M] += dt * closing_m_s
    skin[NEAR_SPEED_M_S] = closing_m_s
    skin[NEAR_ON] = 0.0


@jit_no_refcount
def step_reach_m(model, state, h):
    """The farthest a point of a segment that can reach the anchor moves against the anchor's point beside it in a
    step of ``h`` [s], at the speeds the last step ended with (inf where not known) [m]:
    h (closing speed bound of :func:`note_moved` + |omega| r), r = R + ``SKIN_M`` + the longest segment,
    stretched by as much as its nodes can have moved apart since the build.

    Why that r: a segment that reaches the sphere of radius R within the step lies within R + reach of the COG,
    so its nodes within R + reach + its length; while the reach fits in the skin (:func:`covers_step`), that is
    less than r."""
    skin = state.near_skin
    body = state.body_state
    omega = math.sqrt(body[BS_OMEGA] ** 2 + body[BS_OMEGA + 1] ** 2 + body[BS_OMEGA + 2] ** 2)
    r = bounding_radius_m(model.contact_shape) + SKIN_M + skin[NEAR_LONGEST_M] + 2.0 * skin[NEAR_MOVED_M]
    # a relative margin for the rounding of the bound itself
    return h * (skin[NEAR_SPEED_M_S] + omega * r) * (1.0 + 1e-9)


@jit_no_refcount
def covers_step(model, state, h):
    """Whether the segment list holds every segment that the prediction of a step of ``h`` [s] can bring to the
    anchor's bounding sphere (``implicit_contact_set.init_segment_set``): the lists are in use and the step's reach
    at the present velocities fits in what is left of the skin. Any segment left out then lies farther from the
    sphere than its predicted move against the anchor, and gets no law in the step."""
    skin = state.near_skin
    return skin[NEAR_ON] != 0.0 and step_reach_m(model, state, h) < SKIN_M - ROUNDING_M - skin[NEAR_MOVED_M]


@jit_no_refcount
def _build(model, state):
    """The free nodes and the segments within ``SKIN_M`` of the bounding sphere, and every segment with a node that
    is not free, in index order, into ``state.near_nodes`` and ``state.near_segs`` (each ended by -1 where
    shorter); the longest active segment into ``near_skin``."""
    p = state.node_pos
    node_i = state.node_i
    seg_i = state.seg_i
    body_state = state.body_state
    gx = body_state[BS_POS]
    gy = body_state[BS_POS + 1]
    gz = body_state[BS_POS + 2]
    reach = bounding_radius_m(model.contact_shape) + SKIN_M
    reach2 = reach * reach
    nodes = state.near_nodes
    k = 0
    for n in range(node_i.shape[0]):
        r2 = (p[n, 0] - gx) ** 2 + (p[n, 1] - gy) ** 2 + (p[n, 2] - gz) ** 2
        if node_i[n, NI_KIND] == NODE_FREE and r2 <= reach2:
            nodes[k] = n
            k += 1
    if k < nodes.shape[0]:
        nodes[k] = -1
    segs = state.near_segs
    k = 0
    longest2 = 0.0
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        ax = p[a, 0] - gx
        ay = p[a, 1] - gy
        az = p[a, 2] - gz
        bx = p[b, 0] - gx
        by = p[b, 1] - gy
        bz = p[b, 2] - gz
        length2 = (bx - ax) ** 2 + (by - ay) ** 2 + (bz - az) ** 2
        longest2 = max(longest2, length2)
        # the exact distance only where the midpoint lies within reach + l / 2 (|m|^2 <= 2 (reach^2 + l^2 / 4)):
        # most segments lie far from the anchor
        near = ((ax + bx) ** 2 + (ay + by) ** 2 + (az + bz) ** 2 <= 8.0 * reach2 + 2.0 * length2
                and _segment_distance2(ax, ay, az, bx, by, bz) <= reach2)
        if near or node_i[a, NI_KIND] != NODE_FREE or node_i[b, NI_KIND] != NODE_FREE:
            segs[k] = s
            k += 1
    if k < segs.shape[0]:
        segs[k] = -1
    state.near_skin[NEAR_LONGEST_M] = math.sqrt(longest2)


@jit_step
def _segment_distance2(ax, ay, az, bx, by, bz):
    """Squared distance from the origin to the segment from a to b [m^2]."""
    dx = bx - ax
    dy = by - ay
    dz = bz - az
    d2 = dx * dx + dy * dy + dz * dz
    t = min(max(-(ax * dx + ay * dy + az * dz) / d2, 0.0), 1.0) if d2 > 0.0 else 0.0
    return (ax + t * dx) ** 2 + (ay + t * dy) ** 2 + (az + t * dz) ** 2


@jit_step(inline="always")
def listed(near, listed_on, k):
    """The index at position k of a pass: ``near[k]`` (-1 past the list's end) where the list is used
    (``listed_on``), else k."""
    return near[k] if listed_on else k

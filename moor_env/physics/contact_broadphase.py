"""The line-anchor contact's broad phase across time steps: the nodes and segments near the anchor, listed once and
reused while nothing else can have come near (a neighbour list with a skin, as in molecular dynamics).

Why: in a fall most of a line lies tens to hundreds of metres from the anchor, and testing every node and every
segment against the anchor's bounding sphere at every step costs several per cent of an explicit step. The list
holds the free nodes within R + ``SKIN_M`` of the anchor's COG and the segments whose nearest point lies within it
(R: ``anchor_surface.bounding_radius_m``, the sphere about the COG that holds the anchor whatever its
orientation), and every segment with a node that is not free (a vessel's or the anchor's node moves with its
holder, not at the free nodes' speeds). The contact's load passes (``contact.add_contact_loads``,
``segment_contact.add_segment_contact_loads``) visit only the listed ones while the nodes and the COG cannot have
closed the skin: the sum over the steps since the list was built of dt (fastest free node + COG speed), each taken
after the step (the explicit and implicit Euler steps move every point by dt times its new velocity), stays below
``SKIN_M``. Every node or segment left out then lies outside the sphere, where the contact's force is zero, so
the forces, their order of summation and every result are bit for bit those of a pass over all.

Only ``integrate.step`` uses the list, for the load evaluation of its own step (symplectic and implicit Euler;
the midpoint step moves its points at its midpoint velocities, which it does not bound): ``near_skin[NEAR_ON]``
is set for that evaluation only, so that the statics and a load evaluation from Python pass over all. The list is
rebuilt at the first step of every ``integrate.advance`` call and after a payout changed the segments.

The skin: 2 m is about 100 explicit steps of a fall at 25 m/s (0.34 ms steps) and a few implicit steps (11 ms),
and it adds to the list only the chain within 2 m of the sphere.
"""

from __future__ import annotations

from moor_env.physics._jit import jit, jit_no_refcount
from moor_env.physics.anchor_surface import bounding_radius_m
from moor_env.physics.layout import BS_POS, NEAR_MOVED_M, NEAR_ON, NI_KIND, NODE_FREE, SI_A, SI_ACTIVE, SI_B

SKIN_M = 2.0  # how far beyond the anchor's bounding sphere the list reaches [m]
ROUNDING_M = 1e-6  # the lists are rebuilt this much before the skin closes (positions are rounded at every step)


@jit_no_refcount
def prepare_near(model, state, same_topology):
    """Before a step's load evaluation: rebuild the lists where needed (not ``same_topology``, i.e. the first step
    of a call or after a payout; the skin closed) and let the contact's passes use them (``NEAR_ON``)."""
    skin = state.near_skin
    if not same_topology or not skin[NEAR_MOVED_M] < SKIN_M - ROUNDING_M:
        _build(model, state)
        skin[NEAR_MOVED_M] = 0.0
    skin[NEAR_ON] = 1.0


@jit_no_refcount
def note_moved(state, dt, vmax2, body_v2):
    """After a step of ``dt`` [s] whose fastest free node moved at sqrt(``vmax2``) and the COG at sqrt(``body_v2``)
    [m/s] (their new velocities): add how far they can have closed on each other, and end the lists' use by
    anything but the next step."""
    skin = state.near_skin
    skin[NEAR_MOVED_M] += dt * (vmax2 ** 0.5 + body_v2 ** 0.5)
    skin[NEAR_ON] = 0.0


@jit_no_refcount
def _build(model, state):
    """The free nodes and the segments within ``SKIN_M`` of the bounding sphere, and every segment with a node that
    is not free, in index order, into ``state.near_nodes`` and ``state.near_segs`` (each ended by -1 where
    shorter)."""
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
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        held = node_i[a, NI_KIND] != NODE_FREE or node_i[b, NI_KIND] != NODE_FREE
        if held or _segment_distance2(p[a, 0] - gx, p[a, 1] - gy, p[a, 2] - gz, p[b, 0] - gx, p[b, 1] - gy,
                                      p[b, 2] - gz) <= reach2:
            segs[k] = s
            k += 1
    if k < segs.shape[0]:
        segs[k] = -1


@jit
def _segment_distance2(ax, ay, az, bx, by, bz):
    """Squared distance from the origin to the segment from a to b [m^2]."""
    dx = bx - ax
    dy = by - ay
    dz = bz - az
    d2 = dx * dx + dy * dy + dz * dz
    t = min(max(-(ax * dx + ay * dy + az * dz) / d2, 0.0), 1.0) if d2 > 0.0 else 0.0
    return (ax + t * dx) ** 2 + (ay + t * dy) ** 2 + (az + t * dz) ** 2


@jit(inline="always")
def listed(near, listed_on, k):
    """The index at position k of a pass: ``near[k]`` (-1 past the list's end) where the list is used
    (``listed_on``), else k."""
    return near[k] if listed_on else k

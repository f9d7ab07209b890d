"""The line-anchor contact in the static solver's linear system (``physics/statics_system.py``).

At rest the contact law of ``physics/contact.py`` is its spring alone, F = k d n on a node d inside the anchor's
surface (the damping and the friction act on velocities, all zero in a static state), and the anchor takes -F at
the node. The step's system gets its linearisation in the depth, d' = d - n . (dx - J dq), J the motion of the
anchor's material point at the node per unknown (translation, then rotation about the two tilt axes):

    node block        k n n^T
    node-anchor       -k n (J^T n)^T      (and its transpose, anchor-node)
    anchor block      k (J^T n) (J^T n)^T

Left out: the turning of the normal (f_n H) and the moment arm's change, both smaller than k n n^T by the depth
over the anchor's radius (millimetres over metres at rest); Newton's method keeps the exact residual, so they only
slow its last iterations, never move its answer. Why not f_n H: far from the solution, with a node centimetres
inside the convex shaft, it makes the node's block indefinite; on the low-spacing scenes of the statics benchmark
it leaves more of them unsolved than it solves.

Except for a segment contact in a stage that creeps (``CF_TURNING`` set by ``statics_stages.Stage``): there the
system takes the turning of its normal round the anchor's axis, -k e (n . u) / rho t t^T on the motion of p*
relative to the anchor (u the radial unit vector at p*, rho its distance from the axis, t = e x u less its part
along the segment: ``_turning``). Why: a chain over a rim is free to slide round the axis, where k n n^T has no
stiffness and the turning (a softening: the force turns with the normal) is the contact's whole stiffness. Without
it the system is too stiff in that direction, each step removes a small share of the residual there, the
monotonicity test refuses it, and the solve creeps (on the statics benchmark, stages of 400-1900 iterations at
residuals of a few 1e-4 node weights). Why only after a while: with the residual gate at 1e-2, switched on from the
first iteration of a solve's last stage it left four of the benchmark's 1000 scenes unsolved that converge or are
refused without it, after 50 iterations one, after 100 none. Why a solve's last stage only, near its solution: see
``statics_stages.Stage.run``. On the statics benchmark, of the seven stages that creep for 444-1891 iterations
without it (five scenes), three stop creeping with it, three take 134-575 iterations (921-1485 without), and one
takes 444 either way (at residuals of a hundred node weights, far from its solution).

A node couples to the anchor outside its attachment, which closes a loop in the tree of lines. The block
elimination carries it exactly: every eliminated node passes its coupling to the anchor on to its parent (a 3x5
block each way, nodes on the path from a contact to the anchor only) and its share to the anchor's 5x5 block,
which is solved last at the root.

As the seabed, the contact is an active set predicted to the end of the step: a node predicted inside gets the
spring and, where it is still outside, the gap it must close before it touches (the linear law k d n from its
present depth d < 0); a node inside now and predicted outside lets go. After the first prediction the set only
grows (no cycling); once it has settled, a contact outside now and still outside at the step's end leaves it
(:func:`release_pulling`: its gap term would pull the line onto the anchor).

A segment that cuts into the anchor deeper than its nodes (``physics/segment_contact.py``: a chain over a rim)
has a row of its own after the nodes' rows: its excess e at its deepest point p* = x_a + t (x_b - x_a), normal n
and J^T n there. Its terms are k |g|^2 g g^T with g = ((1 - t) n, t n, -J^T n) (node blocks, the two nodes'
coupling in the segment's own block of the tree, node-anchor couplings, the anchor's block), and the change of its
shares as p* moves along the segment (node a takes (1 - t) F: K_aj += F (dt/dx_j)^T, K_bj -= F (dt/dx_j)^T). Why
the whole coupling: with two separate node contacts of stiffness (1 - t) k and t k instead (stiffer by
k t (1 - t) across), Newton's method converges linearly where p* lies near one node; on gjoa-500 at spacing 0
(the chain over the back end's rim at t = 0.01) the residual fell by 0.05 % per iteration and the solve stopped
unconverged after 2000. A segment with both nodes outside enters the set as a node does (its gap, e < 0);
one with a node inside does only once it cuts in deeper than that node.

A step moves a node resting on the shaft round it; the Newton kernel then puts the node on the surface at its
linearly predicted depth (:func:`slide_plan`, :func:`slide_on_surface`) instead of along the tangent, which the
penalty would punish as a lost contact force k s^2 / (2 rho).
"""

from __future__ import annotations

import math

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount
from moor_env.physics.anchor_surface import FEATURE_SHAFT, bounding_radius_m, from_cog, radial_part, surface_distance
from moor_env.physics.contact import may_touch
from moor_env.physics.segment_contact import free_shares, may_cut, segment_geometry

SLIDE_DEPTH_M = 0.01  # lines no deeper than this inside the anchor rest on it: a step slides them along it
REACH_M = 2.0  # nodes this close to the anchor's bounding cylinder may enter the contact in one step
SEGMENT_REACH_M = 0.1  # segments this close to it (and with a gap below REACH_M) may; farther ones wait a step
# contact geometry of a candidate: depth (negative: gap) [m], normal, J^T n (5), and for a segment contact
# (``physics/segment_contact.py``) the node a's share (1 - t); rows 0 .. nodes - 1 are the nodes, the rows after
# them the segments (their depth the excess e, candidates only while e > 0)
G_DEPTH = 0
G_NORMAL = 1
G_JN = 4
G_SHARE = 9
G_SCALE = 10  # a segment contact's stiffness factor |g|^2 (physics/segment_contact.py: 1 off a rim's kink)
G_DT = 11  # and how its deepest point moves along it, dt/dx_a (3), dt/dx_b (3) [1/m]
G_TURN = 17  # a segment contact's direction round the anchor's axis at its deepest point, across the segment (3)
G_JT = 20  # J^T of it (5)
G_CURVATURE = 25  # how fast the normal turns towards t per metre moved along it, (n . u) / rho [1/m]
N_GEO = 26


@jit_no_refcount
def _jn(basis, rx, ry, rz, nx, ny, nz, geo, n, column=G_JN):
    """J^T n of a material point at r from the COG into ``geo[n, column:column + 5]``: the vector's translation
    part, then basis[k] . (r x n)."""
    geo[n, column] = nx
    geo[n, column + 1] = ny
    geo[n, column + 2] = nz
    cx = ry * nz - rz * ny
    cy = rz * nx - rx * nz
    cz = rx * ny - ry * nx
    for k in range(2):
        geo[n, column + 3 + k] = basis[k, 0] * cx + basis[k, 1] * cy + basis[k, 2] * cz


@jit_no_refcount
def contact_geometry(basis, model, state, geo, cand, cin):
    """Depth, normal and J^T n of every free node near the anchor (``cand`` 1) at the present state; ``cin`` 1
    where it is inside now: the nodes the contact acts on (``contact.may_touch``); then the segment contacts' rows
    (:func:`_segment_geometry`). Returns the number of candidates."""
    node_pos = state.node_pos
    node_i = state.node_i
    body_state = state.body_state
    shape = model.contact_shape
    seabed = -model.env_f[L.EF_DEPTH]
    count = 0
    for n in range(node_pos.shape[0]):
        cand[n] = 0
        cin[n] = 0
        if not may_touch(node_pos, node_i, n, body_state, shape, seabed, REACH_M):
            continue
        px = node_pos[n, 0]
        py = node_pos[n, 1]
        pz = node_pos[n, 2]
        sd, nx, ny, nz, _, _, _, _, _, _, _ = surface_distance(px, py, pz, body_state, shape)
        rx, ry, rz, _ = from_cog(px, py, pz, body_state)
        geo[n, G_DEPTH] = -sd
        geo[n, G_NORMAL] = nx
        geo[n, G_NORMAL + 1] = ny
        geo[n, G_NORMAL + 2] = nz
        _jn(basis, rx, ry, rz, nx, ny, nz, geo, n)
        cand[n] = 1
        cin[n] = 1 if sd < 0.0 else 0
        count += 1
    return count + _segment_geometry(basis, model, state, geo, cand, cin)


@jit_no_refcount
def _segment_geometry(basis, model, state, geo, cand, cin):
    """The rows of the segment contacts (after the nodes' rows, where ``geo`` has them): excess, normal and J^T n
    at the deepest point, node a's share; candidates where the excess is positive (inside), or where both nodes
    are outside and its gap below ``REACH_M`` (a segment with a node inside is that node's contact until it cuts
    in deeper). Returns their number."""
    node_pos = state.node_pos
    seg_i = state.seg_i
    body_state = state.body_state
    first = node_pos.shape[0]
    if geo.shape[0] < first + seg_i.shape[0]:
        return 0
    if model.contact_f[L.CF_SEGMENTS] == 0.0:
        cand[first:first + seg_i.shape[0]] = 0
        cin[first:first + seg_i.shape[0]] = 0
        return 0
    seabed = -model.env_f[L.EF_DEPTH]
    radius = bounding_radius_m(model.contact_shape)
    turning = model.contact_f[L.CF_TURNING] != 0.0  # the turning's columns are read only then
    count = 0
    for s in range(seg_i.shape[0]):
        r = first + s
        cand[r] = 0
        cin[r] = 0
        if not may_cut(node_pos, state.node_i, seg_i, s, body_state, model.contact_shape, seabed, radius,
                       SEGMENT_REACH_M):
            continue
        a = seg_i[s, L.SI_A]
        b = seg_i[s, L.SI_B]
        e, t, px, py, pz, nx, ny, nz, scale, node_inside, uax, uay, uaz, ubx, uby, ubz = segment_geometry(
            node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], node_pos[b, 0], node_pos[b, 1], node_pos[b, 2],
            body_state, model.contact_shape)
        wa, wb = free_shares(state.node_i, a, b, t)
        if e <= (0.0 if node_inside else -REACH_M) or wa + wb <= 0.0:
            continue
        rx, ry, rz, _ = from_cog(px, py, pz, body_state)
        geo[r, G_DEPTH] = e
        geo[r, G_NORMAL] = nx
        geo[r, G_NORMAL + 1] = ny
        geo[r, G_NORMAL + 2] = nz
        _jn(basis, rx, ry, rz, nx, ny, nz, geo, r)
        geo[r, G_SHARE] = 1.0 - t
        geo[r, G_SCALE] = scale
        for i, u in enumerate((uax, uay, uaz, ubx, uby, ubz)):
            geo[r, G_DT + i] = u
        if turning:
            _turning(basis, body_state, px, py, pz, rx, ry, rz, nx, ny, nz, node_pos[b, 0] - node_pos[a, 0],
                     node_pos[b, 1] - node_pos[a, 1], node_pos[b, 2] - node_pos[a, 2], geo, r)
        cand[r] = 1
        cin[r] = 1 if e > 0.0 else 0
        count += 1
    return count


@jit_no_refcount
def _turning(basis, body_state, px, py, pz, rx, ry, rz, nx, ny, nz, dx, dy, dz, geo, r):
    """Segment contact row r's turning of the normal round the anchor's axis: t = e x u at its deepest point p (u
    the radial unit vector there) less its part along the segment (d: node a to node b), t - (t . s) s, J^T of
    that, and (n . u) / rho, the rate at which n turns towards t per metre p moves along t relative to the anchor
    (zero on the axis). Why less the part along the segment: a segment moved along itself keeps its deepest point
    where it is (a chord across the shaft, running round the axis), and its normal does not turn; a chain over a
    rim runs across t, and keeps all of it."""
    _, qx, qy, qz = radial_part(px, py, pz, body_state)
    rho = math.sqrt(qx * qx + qy * qy + qz * qz)
    geo[r, G_CURVATURE] = 0.0
    if rho <= 0.0:
        return
    ux = qx / rho
    uy = qy / rho
    uz = qz / rho
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    tx = ey * uz - ez * uy
    ty = ez * ux - ex * uz
    tz = ex * uy - ey * ux
    length2 = dx * dx + dy * dy + dz * dz
    if length2 > 0.0:
        along = (tx * dx + ty * dy + tz * dz) / length2
        tx -= along * dx
        ty -= along * dy
        tz -= along * dz
    geo[r, G_TURN] = tx
    geo[r, G_TURN + 1] = ty
    geo[r, G_TURN + 2] = tz
    _jn(basis, rx, ry, rz, tx, ty, tz, geo, r, G_JT)
    geo[r, G_CURVATURE] = (nx * ux + ny * uy + nz * uz) / rho


@jit_no_refcount
def _add_normal_force(force_n, geo, n, rhs, body_r):
    """A force ``force_n`` [N] along candidate n's normal into its right-hand side, its reaction into the
    anchor's (-force J^T n)."""
    for i in range(3):
        rhs[n, i] += force_n * geo[n, G_NORMAL + i]
    for i in range(5):
        body_r[i] -= force_n * geo[n, G_JN + i]


@jit_no_refcount
def add_contact_blocks(model, state, geo, cand, cin, dmat, coupling, bmat, cmat, coupled, body_a, body_r):
    """The contact's terms of the step (module docstring): node blocks into ``dmat``, a segment contact's coupling
    of its two nodes into the segment's ``coupling``, the couplings into ``bmat`` (node-anchor, 3x5) and ``cmat``
    (anchor-node, 5x3), the anchor's block into ``body_a`` and the
    right-hand sides' changes into ``state.node_acc`` and ``body_r``. Clears the couplings of the last step."""
    rhs = state.node_acc
    k = model.contact_f[L.CF_STIFFNESS]
    for n in range(coupled.shape[0]):
        if coupled[n] != 0:
            bmat[n, :, :] = 0.0
            cmat[n, :, :] = 0.0
            coupled[n] = 0
    body_a[:, :] = 0.0
    body_r[:] = 0.0
    nodes = state.node_pos.shape[0]
    for n in range(nodes):
        if cand[n] == 0:
            continue
        depth = geo[n, G_DEPTH]
        inside_now = depth > 0.0
        if cin[n] == 0:
            if inside_now:  # lets go during the step: its present force goes
                _add_normal_force(-k * depth, geo, n, rhs, body_r)
            continue
        if not inside_now:  # the gap to close before the anchor holds the node
            _add_normal_force(k * depth, geo, n, rhs, body_r)
        for i in range(3):
            for j in range(3):
                dmat[n, i, j] += k * geo[n, G_NORMAL + i] * geo[n, G_NORMAL + j]
            for j in range(5):
                bmat[n, i, j] -= k * geo[n, G_NORMAL + i] * geo[n, G_JN + j]
                cmat[n, j, i] -= k * geo[n, G_JN + j] * geo[n, G_NORMAL + i]
        for i in range(5):
            for j in range(5):
                body_a[i, j] += k * geo[n, G_JN + i] * geo[n, G_JN + j]
        coupled[n] = 1
    turning = model.contact_f[L.CF_TURNING] != 0.0
    for r in range(nodes, geo.shape[0]):
        if cand[r] != 0:
            _add_segment_blocks(k, turning, state, geo, cin, r, dmat, coupling, bmat, cmat, coupled, body_a, body_r)


@jit_no_refcount
def _add_segment_blocks(k, turning, state, geo, cin, r, dmat, coupling, bmat, cmat, coupled, body_a, body_r):
    """Segment contact row r's terms (``physics/segment_contact.py``: k g g^T, g = ((1 - t) n, t n, -J^T n),
    and with ``turning`` the turning of its normal round the anchor's axis, module docstring): its free nodes'
    blocks, their coupling in the segment's block, their couplings to the anchor, the anchor's block, and where it
    is outside now, the gap to close (the linear law k e n, e < 0); where it lets go during the step, its present
    force leaves the right-hand sides instead."""
    s = r - state.node_pos.shape[0]
    a, b, wa, wb = _segment_nodes(state, geo, r)
    excess = geo[r, G_DEPTH]
    if cin[r] == 0:
        if excess > 0.0:  # lets go during the step: its present force goes
            _add_segment_force(-k * excess, geo, r, state.node_acc, a, wa, b, wb, body_r)
        return
    if excess <= 0.0:  # the gap to close before it cuts in
        _add_segment_force(k * excess, geo, r, state.node_acc, a, wa, b, wb, body_r)
    _add_share_transfer(k * excess, geo, r, s, a, wa, b, wb, dmat, coupling)
    _add_pair(k * geo[r, G_SCALE], geo, r, G_NORMAL, G_JN, s, a, wa, b, wb, dmat, coupling, bmat, cmat, coupled,
              body_a)
    if turning and excess > 0.0 and geo[r, G_CURVATURE] != 0.0:
        _add_pair(-k * excess * geo[r, G_CURVATURE], geo, r, G_TURN, G_JT, s, a, wa, b, wb, dmat, coupling, bmat,
                  cmat, coupled, body_a)


@jit_no_refcount
def _add_pair(k, geo, r, vector, jv, s, a, wa, b, wb, dmat, coupling, bmat, cmat, coupled, body_a):
    """k G G^T of segment contact row r, G = ((1 - t) v, t v, -J^T v) over its free nodes and the anchor, v the
    vector in ``geo[r, vector:vector + 3]`` (the unit normal, or the turning's direction) and J^T v in
    ``geo[r, jv:jv + 5]``."""
    for i in range(3):
        for j in range(3):
            nn = k * geo[r, vector + i] * geo[r, vector + j]
            if wa > 0.0:
                dmat[a, i, j] += wa * wa * nn
            if wb > 0.0:
                dmat[b, i, j] += wb * wb * nn
            if wa > 0.0 and wb > 0.0:  # coupling[s, 0] = K_ab, coupling[s, 1] = K_ba
                coupling[s, 0, i, j] += wa * wb * nn
                coupling[s, 1, i, j] += wa * wb * nn
    for n, w in ((a, wa), (b, wb)):
        if w <= 0.0:
            continue
        for i in range(3):
            for j in range(5):
                bmat[n, i, j] -= w * k * geo[r, vector + i] * geo[r, jv + j]
                cmat[n, j, i] -= w * k * geo[r, jv + j] * geo[r, vector + i]
        coupled[n] = 1
    for i in range(5):
        for j in range(5):
            body_a[i, j] += k * geo[r, jv + i] * geo[r, jv + j]


@jit_no_refcount
def _add_share_transfer(force_n, geo, r, s, a, wa, b, wb, dmat, coupling):
    """The change of segment contact row r's shares as its deepest point moves along it: node a takes (1 - t) F,
    node b t F (F = ``force_n`` n), so K_aj += F (dt/dx_j)^T and K_bj -= F (dt/dx_j)^T (K = -dF/dx; j = a, b,
    free nodes only)."""
    for i in range(3):
        f = force_n * geo[r, G_NORMAL + i]
        for j in range(3):
            ua = f * geo[r, G_DT + j]
            ub = f * geo[r, G_DT + 3 + j]
            if wa > 0.0:
                dmat[a, i, j] += ua
            if wb > 0.0:
                dmat[b, i, j] -= ub
            if wa > 0.0 and wb > 0.0:  # coupling[s, 0] = K_ab, coupling[s, 1] = K_ba
                coupling[s, 0, i, j] += ub
                coupling[s, 1, i, j] -= ua


@jit_no_refcount
def _add_segment_force(force_n, geo, r, rhs, a, wa, b, wb, body_r):
    """A force ``force_n`` [N] along segment contact row r's normal at its deepest point: its free nodes' shares
    into their right-hand sides, its reaction into the anchor's (-force J^T n)."""
    for i in range(3):
        rhs[a, i] += wa * force_n * geo[r, G_NORMAL + i]
        rhs[b, i] += wb * force_n * geo[r, G_NORMAL + i]
    for i in range(5):
        body_r[i] -= force_n * geo[r, G_JN + i]


@jit_no_refcount
def _segment_nodes(state, geo, r):
    """The nodes of segment contact row r and their shares of its force (zero where not free)."""
    s = r - state.node_pos.shape[0]
    a = state.seg_i[s, L.SI_A]
    b = state.seg_i[s, L.SI_B]
    wa, wb = free_shares(state.node_i, a, b, 1.0 - geo[r, G_SHARE])
    return a, b, wa, wb


@jit_no_refcount
def pass_on_eliminated(c, inv, state, bmat, cmat, body_a, body_r):
    """Node c just eliminated (``inv`` = D_c^-1, ``state.node_acc[c]`` = D_c^-1 r_c): the anchor's rows take
    -C_c D_c^-1 (B_c, r_c); ``bmat[c]`` becomes D_c^-1 B_c (for the back substitution) and ``cmat[c]`` C_c D_c^-1
    (for the parent, :func:`pass_on_parent`)."""
    x = state.node_acc
    for i in range(5):
        body_r[i] -= cmat[c, i, 0] * x[c, 0] + cmat[c, i, 1] * x[c, 1] + cmat[c, i, 2] * x[c, 2]
    for j in range(5):
        b0 = inv[0, 0] * bmat[c, 0, j] + inv[0, 1] * bmat[c, 1, j] + inv[0, 2] * bmat[c, 2, j]
        b1 = inv[1, 0] * bmat[c, 0, j] + inv[1, 1] * bmat[c, 1, j] + inv[1, 2] * bmat[c, 2, j]
        b2 = inv[2, 0] * bmat[c, 0, j] + inv[2, 1] * bmat[c, 1, j] + inv[2, 2] * bmat[c, 2, j]
        bmat[c, 0, j] = b0
        bmat[c, 1, j] = b1
        bmat[c, 2, j] = b2
    for i in range(5):
        for j in range(5):
            body_a[i, j] -= (cmat[c, i, 0] * bmat[c, 0, j] + cmat[c, i, 1] * bmat[c, 1, j]
                             + cmat[c, i, 2] * bmat[c, 2, j])
    for i in range(5):
        c0 = cmat[c, i, 0] * inv[0, 0] + cmat[c, i, 1] * inv[1, 0] + cmat[c, i, 2] * inv[2, 0]
        c1 = cmat[c, i, 0] * inv[0, 1] + cmat[c, i, 1] * inv[1, 1] + cmat[c, i, 2] * inv[2, 1]
        c2 = cmat[c, i, 0] * inv[0, 2] + cmat[c, i, 1] * inv[1, 2] + cmat[c, i, 2] * inv[2, 2]
        cmat[c, i, 0] = c0
        cmat[c, i, 1] = c1
        cmat[c, i, 2] = c2


@jit_no_refcount
def pass_on_parent(c, p, k_pc, k_cp, bmat, cmat, coupled):
    """The parent p of an eliminated, coupled node c takes its coupling: B_p -= K_pc D_c^-1 B_c, C_p -= C_c D_c^-1
    K_cp (``bmat[c]``, ``cmat[c]`` as :func:`pass_on_eliminated` left them)."""
    for i in range(3):
        for j in range(5):
            bmat[p, i, j] -= k_pc[i, 0] * bmat[c, 0, j] + k_pc[i, 1] * bmat[c, 1, j] + k_pc[i, 2] * bmat[c, 2, j]
    for i in range(5):
        for j in range(3):
            cmat[p, i, j] -= cmat[c, i, 0] * k_cp[0, j] + cmat[c, i, 1] * k_cp[1, j] + cmat[c, i, 2] * k_cp[2, j]
    coupled[p] = 1


@jit_no_refcount
def predict_contact(state, dq, geo, cand, cin, release):
    """Update the nodes predicted inside the anchor after the step (nodes in ``state.node_acc``, the anchor in
    ``dq``); returns how many changed. With ``release`` False a node in contact stays in (no cycling)."""
    changed = 0
    for n in range(geo.shape[0]):
        if cand[n] == 0:
            continue
        inside = 1 if geo[n, G_DEPTH] - _normal_move(state, dq, geo, n) > 0.0 else 0
        if inside != cin[n] and (release or inside == 1):
            cin[n] = inside
            changed += 1
    return changed


@jit_no_refcount
def release_pulling(state, dq, geo, cand, cin):
    """Let go of the contacts in the set that are outside the anchor now and still outside at the step's end
    (nodes in ``state.node_acc``, the anchor in ``dq``); returns how many.

    Why: such a contact's linearised force at the step's end, k (d - move) n with d - move <= 0, pulls the line
    onto the anchor. Kept in the set by the rule that lets no contact go after the first prediction (no cycling),
    two of them can balance a third that pushes a chain off a rim, and the step comes out zero while the residual
    stays (a chain loop resting over the back end's rim in strong current: a residual of 20 node weights that no
    step reduces). A contact inside now stays: its spring holds a real load, and the step's prediction only
    says where the linear model would carry it."""
    changed = 0
    for n in range(geo.shape[0]):
        if cand[n] == 0 or cin[n] == 0 or geo[n, G_DEPTH] >= 0.0:
            continue
        if geo[n, G_DEPTH] - _normal_move(state, dq, geo, n) <= 0.0:
            cin[n] = 0
            changed += 1
    return changed


@jit_no_refcount(inline="always")
def _normal_move(state, dq, geo, n):
    """The step's motion of candidate row ``n`` (a node, or a segment's deepest point) relative to the anchor's
    point there, along the contact normal [m]."""
    node_acc = state.node_acc
    move = 0.0
    if n < state.node_pos.shape[0]:
        for i in range(3):
            move += geo[n, G_NORMAL + i] * node_acc[n, i]
    else:
        a, b, _, _ = _segment_nodes(state, geo, n)
        wa = geo[n, G_SHARE]
        for i in range(3):
            move += geo[n, G_NORMAL + i] * (wa * node_acc[a, i] + (1.0 - wa) * node_acc[b, i])
    for i in range(5):
        move -= geo[n, G_JN + i] * dq[i]
    return move


@jit_no_refcount
def slide_plan(basis, model, state, dq, geo, cand, cin, plan):
    """Where the lines rest on the anchor (no node deeper than ``SLIDE_DEPTH_M`` inside it), for every node on the
    shaft that the step (``state.node_acc``, ``dq``) predicts inside: its depth now and its predicted change of
    depth per unit step, ``plan[n]`` = (depth [m], -move [m]); NaN for the others. Returns how many nodes were
    planned. ``geo``, ``cand``, ``cin``: scratch of :func:`contact_geometry`.

    Why the shaft only: the end faces are flat (a step along them keeps its depth) and a rim has no tangent
    plane. Why resting lines only: a line that still passes through the anchor (the contact's stiffness ramp)
    is pushed out along its nearest faces, and a node slid along the shaft there would steer it."""
    plan[:, 0] = math.nan
    if contact_geometry(basis, model, state, geo, cand, cin) == 0:
        return 0
    node_pos = state.node_pos
    for n in range(node_pos.shape[0]):
        if cand[n] != 0 and geo[n, G_DEPTH] > SLIDE_DEPTH_M:
            return 0
    node_acc = state.node_acc
    count = 0
    for n in range(node_pos.shape[0]):
        if cand[n] == 0 or geo[n, G_DEPTH] <= 0.0:
            continue
        move = 0.0
        for i in range(3):
            move += geo[n, G_NORMAL + i] * node_acc[n, i]
        for i in range(5):
            move -= geo[n, G_JN + i] * dq[i]
        if geo[n, G_DEPTH] - move <= 0.0:
            continue
        feature = surface_distance(node_pos[n, 0], node_pos[n, 1], node_pos[n, 2], state.body_state,
                                   model.contact_shape)[10]
        if feature == FEATURE_SHAFT:
            plan[n, 0] = geo[n, G_DEPTH]
            plan[n, 1] = -move
            count += 1
    return count


@jit_no_refcount
def slide_on_surface(node_pos, n, body_state, shape, depth_m):
    """Move node n along the anchor's normal to the depth ``depth_m`` [m] (the anchor at its new place), where it
    still lies nearest the shaft.

    Why: a step slides a resting node along the surface, but its linear model moves it along the tangent, which
    leaves a curved surface by s^2 / (2 rho) over a slide s; at the contact's stiffness that is a force of k s^2 /
    (2 rho), 130 N for a 0.8 mm slide on a 0.6 m shaft at k = 2.5e8 N/m (the fast preset's chain), which can be as
    large as the residual the step removes, so the step would be refused and the solve crawl. Placed at its
    linearly predicted depth, the node keeps the linear model's normal force; a segment to it, near the tangent
    plane, changes length only by the square of the correction."""
    sd, nx, ny, nz, _, _, _, _, _, _, feature = surface_distance(node_pos[n, 0], node_pos[n, 1], node_pos[n, 2],
                                                                 body_state, shape)
    if feature != FEATURE_SHAFT:  # moved past an end of the shaft: the face or rim there is no slide's surface
        return
    shift = sd + depth_m
    node_pos[n, 0] -= shift * nx
    node_pos[n, 1] -= shift * ny
    node_pos[n, 2] -= shift * nz

"""The line-anchor contact in the implicit step (``physics/implicit.py``): its linearisation and its reaction on
the anchor; the step's contact set is in ``physics/implicit_contact_set.py``.

Why: the contact is stiff on the implicit step's scale (omega = 552 rad/s for the chain against steps of ~11 ms,
k h^2 / m ~ 40), and a node that meets the anchor inside a step would fly a whole step into it (16 cm at 15 m/s).
So, as the segments' axial law, the contact is solved for:

- a node in the step's contact set gets h C + h^2 K on its diagonal block and h F - h^2 K w on its right-hand
  side, with K = k n n^T, C = c n n^T + the friction's damping at fixed normal force (viscous g (I - n n^T), or
  sliding mu N / |w_t| (I - n n^T - t t^T), t the slip direction), w the velocity relative to the body point:
  one Newton iteration of backward Euler on the contact, with the anchor moving as the explicit step moves it;
- left out of K and C (the solver's blocks are symmetric): the turning of the normal (f_n H, below d / rho of k
  n n^T), the anchor's rotation, and the friction's dependence on the normal force (symmetrised, it would be an
  indefinite term of size mu k that can make the block singular);
- the anchor receives the opposite of the impulse the solve gives each node (its change from the start-of-step
  force, already in the anchor's explicit load), through its rigid-body equations: momentum is conserved;
- a segment that cuts into the anchor deeper than its nodes at the start of the step, or is predicted to at its
  end (``physics/segment_contact.py``), is solved as two node contacts at its deepest point, one per free node
  with its share of the stiffness and damping (:func:`_segment_pass`).
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor_surface import surface_distance
from moor_env.physics.contact import add_contact_reaction, law_at, record_contact_force, relative_velocity
from moor_env.physics.layout import (
    CC_DEPTH,
    CC_FORCE,
    CC_NORMAL,
    CC_READY,
    CC_VEL,
    CF_MU,
    CF_STICK_SPEED,
    CF_STIFFNESS,
    CF_ZETA,
    SI_A,
    SI_B,
)
from moor_env.physics.segment_contact import segment_contact
from moor_env.physics.tree import add_sym

# contact set of a node during one implicit step
SET_OUT = 0  # outside, no contact this step
SET_IN = 1  # inside at the start of the step
SET_ENTERED = 2  # outside at the start, predicted inside at its end (linear law from the start)
SET_LEFT = 3  # inside at the start, predicted outside at its end (no force)
SET_COMING = 4  # outside at the start, inside at its end at its start velocity: in the first solve as SET_ENTERED
SET_MISSED = 5  # SET_COMING whose solve ends it outside: out, and it may still enter once
SEGMENT_ENTRY_M = 1e-6  # a segment predicted this far into the anchor at the end of the step enters it in the step
SET_BITS = 3  # an entry of the candidate list (``state.contact_set``) is node << SET_BITS | its SET_* state
SET_MASK = (1 << SET_BITS) - 1


@jit_step
def contact_state(px, py, pz, vx, vy, vz, body_state, shape):
    """Depth d (negative: gap) [m], outward normal, and the velocity w relative to the body point at the node
    [m/s] of a node (anywhere: the signed distance is defined everywhere)."""
    sd, nx, ny, nz, _, _, _, _, _, _, _ = surface_distance(px, py, pz, body_state, shape)
    wx, wy, wz = relative_velocity(px, py, pz, vx, vy, vz, body_state)
    return -sd, nx, ny, nz, wx, wy, wz


@jit_step(inline="always")
def start_state(model, state, k, n):
    """:func:`contact_state` of candidate k (node n) at the start of the step and its contact force there [N]
    (the load law's, ``contact.law_at``; zero outside), computed at its first use in the step and kept in
    ``state.contact_cache`` (``CC_*``): the step's solves and its reaction read it again."""
    cache = state.contact_cache
    if cache[k, CC_READY] == 0.0:
        p = state.node_pos
        v = state.node_vel
        depth, nx, ny, nz, wx, wy, wz = contact_state(p[n, 0], p[n, 1], p[n, 2], v[n, 0], v[n, 1], v[n, 2],
                                                      state.body_state, model.contact_shape)
        fx = fy = fz = 0.0
        if depth > 0.0:
            fx, fy, fz = law_at(depth, nx, ny, nz, wx, wy, wz, state.node_mass[n], model.contact_f)[:3]
        cache[k, CC_READY] = 1.0
        cache[k, CC_DEPTH] = depth
        cache[k, CC_NORMAL] = nx
        cache[k, CC_NORMAL + 1] = ny
        cache[k, CC_NORMAL + 2] = nz
        cache[k, CC_VEL] = wx
        cache[k, CC_VEL + 1] = wy
        cache[k, CC_VEL + 2] = wz
        cache[k, CC_FORCE] = fx
        cache[k, CC_FORCE + 1] = fy
        cache[k, CC_FORCE + 2] = fz
    return (cache[k, CC_DEPTH], cache[k, CC_NORMAL], cache[k, CC_NORMAL + 1], cache[k, CC_NORMAL + 2],
            cache[k, CC_VEL], cache[k, CC_VEL + 1], cache[k, CC_VEL + 2], cache[k, CC_FORCE],
            cache[k, CC_FORCE + 1], cache[k, CC_FORCE + 2])


@jit_step
def _friction_damping(depth, wn, tx, ty, tz, k, c, contact_f):
    """The friction's damping at fixed normal force on the tangent plane, g (I - n n^T) - g_s t t^T [N s/m]:
    viscous (g = the slope, g_s = 0) or sliding (g = mu N / |w_t|, g_s = g / |w_t|^2: sliding friction does not
    grow with the slip speed). Returns (g, g_s)."""
    normal = k * depth - c * wn
    mu = contact_f[CF_MU]
    if not (normal > 0.0 and mu > 0.0):
        return 0.0, 0.0
    st = math.sqrt(tx * tx + ty * ty + tz * tz)
    slope = min(mu * normal / contact_f[CF_STICK_SPEED], c)
    if slope * st <= mu * normal:
        return slope, 0.0
    g = mu * normal / st
    return g, g / (st * st)


@jit_step
def contact_terms(h, mode, depth, nx, ny, nz, wx, wy, wz, mass_kg, contact_f, f0x, f0y, f0z):
    """The node's terms of the implicit step in contact set ``mode``: h C + h^2 K (xx, yy, zz, xy, xz, yz) and
    the right-hand side's addition (3) beyond the start-of-step contact force ``f0`` [N] already in it."""
    if mode == SET_OUT:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if mode == SET_LEFT:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -h * f0x, -h * f0y, -h * f0z
    k = contact_f[CF_STIFFNESS]
    c = 2.0 * contact_f[CF_ZETA] * math.sqrt(k * mass_kg)
    wn = wx * nx + wy * ny + wz * nz
    # h C_n + h^2 K = (h c + h^2 k) n n^T; -h^2 K w; an entering node's linear law at the start, h (k d - c w.n) n
    a = h * c + h * h * k
    f = -h * h * k * wn
    if mode == SET_ENTERED:
        f += h * (k * depth - c * wn)
    bxx = a * nx * nx
    byy = a * ny * ny
    bzz = a * nz * nz
    bxy = a * nx * ny
    bxz = a * nx * nz
    byz = a * ny * nz
    if mode == SET_IN:
        tx = wx - wn * nx
        ty = wy - wn * ny
        tz = wz - wn * nz
        g, gs = _friction_damping(depth, wn, tx, ty, tz, k, c, contact_f)
        g *= h
        gs *= h
        bxx += g * (1.0 - nx * nx) - gs * tx * tx
        byy += g * (1.0 - ny * ny) - gs * ty * ty
        bzz += g * (1.0 - nz * nz) - gs * tz * tz
        bxy -= g * nx * ny + gs * tx * ty
        bxz -= g * nx * nz + gs * tx * tz
        byz -= g * ny * nz + gs * ty * tz
    return bxx, byy, bzz, bxy, bxz, byz, f * nx, f * ny, f * nz


@jit_step
def predicted_depth(h, depth, nx, ny, nz, wx, wy, wz, dvx, dvy, dvz):
    """Depth at the end of the step [m] from the solved velocity change dv (the anchor moving as explicitly
    predicted, its point at the node keeping its velocity)."""
    return depth - h * ((wx + dvx) * nx + (wy + dvy) * ny + (wz + dvz) * nz)


@jit_step
def contact_force_change(h, mode, depth, nx, ny, nz, wx, wy, wz, mass_kg, contact_f, dvx, dvy, dvz, f0x, f0y,
                         f0z):
    """The node's contact force over the step as the solve applied it, less the start-of-step force ``f0``
    whose reaction the anchor's explicit load already holds [N] (the anchor takes the opposite):
    F_step - f0 = -C dv - h K (w + dv), plus for an entering node its linear law at the start."""
    if mode == SET_OUT:
        return 0.0, 0.0, 0.0
    if mode == SET_LEFT:
        return -f0x, -f0y, -f0z
    k = contact_f[CF_STIFFNESS]
    c = 2.0 * contact_f[CF_ZETA] * math.sqrt(k * mass_kg)
    dvn = dvx * nx + dvy * ny + dvz * nz
    wn = wx * nx + wy * ny + wz * nz
    fn = -c * dvn - h * k * (wn + dvn)
    if mode == SET_ENTERED:
        fn += k * depth - c * wn
    fx = fn * nx
    fy = fn * ny
    fz = fn * nz
    if mode == SET_IN:
        tx = wx - wn * nx
        ty = wy - wn * ny
        tz = wz - wn * nz
        g, gs = _friction_damping(depth, wn, tx, ty, tz, k, c, contact_f)
        # -(g (I - n n^T) - g_s t t^T) dv
        dtx = dvx - dvn * nx
        dty = dvy - dvn * ny
        dtz = dvz - dvn * nz
        dvt = dvx * tx + dvy * ty + dvz * tz
        fx -= g * dtx - gs * tx * dvt
        fy -= g * dty - gs * ty * dvt
        fz -= g * dtz - gs * tz * dvt
    return fx, fy, fz


@jit_step
def candidate(contact_set, k):
    """Node (segment) and ``SET_*`` state of entry k of the step's candidate list ``state.contact_set``
    (``state.segment_set``; the lists built by ``implicit_contact_set.init_contact_set``); -1 past its end."""
    entry = contact_set[k]
    if entry < 0:
        return -1, SET_OUT
    return entry >> SET_BITS, entry & SET_MASK


@jit_step
def _law_mode(mode):
    """The law a contact-set state applies: a coming node's that of an entering one, a missed node's none."""
    if mode == SET_COMING:
        return SET_ENTERED
    if mode == SET_MISSED:
        return SET_OUT
    return mode


@jit_step(inline="always")
def any_law(contact_set, segment_set):
    """Whether the step's contact set (``state.contact_set``, ``state.segment_set``) gives any node or segment a
    law. Without one the step's contact terms and reaction are zero, and the integrator skips
    :func:`assemble_contact` and :func:`contact_reaction`: each scans the candidates and calls the segments' pass,
    a call that takes the records and so passes their every array (about 0.1 us), and until a chain lands on the
    anchor no line touches it (about half the steps of the implicit falls of the vertical-chain and gjoa-500
    scenes)."""
    if segment_set.shape[0] > 0 and segment_set[0] >= 0:
        return True
    for k in range(contact_set.shape[0]):
        n, mode = candidate(contact_set, k)
        if n < 0:
            break
        if _law_mode(mode) != SET_OUT:
            return True
    return False


@jit_no_refcount(inline="always")
def assemble_contact(h, model, state):
    """Add every candidate's contact terms (:func:`contact_terms`) to its block (``node_mm``) and right-hand side
    (``node_acc``), after the lines' assembly."""
    contact_set = state.contact_set
    node_mm = state.node_mm
    node_acc = state.node_acc
    for k in range(contact_set.shape[0]):
        n, mode = candidate(contact_set, k)
        if n < 0:
            break
        mode = _law_mode(mode)
        if mode == SET_OUT:
            continue
        depth, nx, ny, nz, wx, wy, wz, f0x, f0y, f0z = start_state(model, state, k, n)
        if mode != SET_LEFT:
            f0x = f0y = f0z = 0.0
        bxx, byy, bzz, bxy, bxz, byz, rx, ry, rz = contact_terms(h, mode, depth, nx, ny, nz, wx, wy, wz,
                                                                 state.node_mass[n], model.contact_f, f0x, f0y,
                                                                 f0z)
        add_sym(node_mm, n, bxx, byy, bzz, bxy, bxz, byz)
        node_acc[n, 0] += rx
        node_acc[n, 1] += ry
        node_acc[n, 2] += rz
    _segment_pass(h, model, state, False)


@jit_no_refcount(inline="always")
def contact_reaction(h, model, state):
    """Add to the anchor's load (``body_load``) the opposite of each node's contact force as the solve applied
    it beyond its start-of-step force (:func:`contact_force_change`), and record the step's net contact force
    (``contact_out``); returns whether any node was in contact."""
    contact_set = state.contact_set
    p = state.node_pos
    dv = state.node_acc
    load = state.body_load
    any_contact = False
    tx = ty = tz = 0.0
    for k in range(contact_set.shape[0]):
        n, mode = candidate(contact_set, k)
        if n < 0:
            break
        mode = _law_mode(mode)
        if mode == SET_OUT:
            continue
        any_contact = True
        depth, nx, ny, nz, wx, wy, wz, f0x, f0y, f0z = start_state(model, state, k, n)
        if mode != SET_IN and mode != SET_LEFT:
            f0x = f0y = f0z = 0.0
        fx, fy, fz = contact_force_change(h, mode, depth, nx, ny, nz, wx, wy, wz, state.node_mass[n],
                                          model.contact_f, dv[n, 0], dv[n, 1], dv[n, 2], f0x, f0y, f0z)
        add_contact_reaction(load, state.body_state, p[n, 0], p[n, 1], p[n, 2], fx, fy, fz)
        tx += f0x + fx
        ty += f0y + fy
        tz += f0z + fz
    sx, sy, sz = _segment_pass(h, model, state, True)
    if sx != 0.0 or sy != 0.0 or sz != 0.0:
        any_contact = True
    record_contact_force(state.contact_out, tx + sx, ty + sy, tz + sz)
    return any_contact


@jit_step
def segment_mode(h, e, nx, ny, nz, wx, wy, wz, node_inside):
    """The step's law for a segment contact of excess e [m] (``segment_contact.segment_contact``), normal n and
    velocity w [m/s] of its deepest point: ``SET_IN`` where it cuts in at the start of the step, ``SET_ENTERED``
    where both nodes are outside and it reaches the anchor within the step at its present velocity (the linear law
    from its gap), else ``SET_OUT``."""
    if e > 0.0:
        return SET_IN
    if not node_inside and e - h * (wx * nx + wy * ny + wz * nz) > SEGMENT_ENTRY_M:
        return SET_ENTERED
    return SET_OUT


@jit_no_refcount
def _segment_pass(h, model, state, react):
    """The segment contacts of the step (``physics/segment_contact.py``; the list ``state.segment_set``, built with
    their laws by ``implicit_contact_set.init_contact_set``), each linearised as two node contacts at its deepest
    point, one per free node with its share of the stiffness and damping (that module's docstring). With ``react``
    False: their terms into the nodes' blocks and right-hand sides (:func:`assemble_contact`); with ``react`` True:
    the anchor's reaction to the force the solve applied to the free nodes beyond the start-of-step force
    (:func:`contact_reaction`). Returns the net force of the segments over the step [N] (zero without
    ``react``)."""
    seg_i = state.seg_i
    segment_set = state.segment_set
    p = state.node_pos
    v = state.node_vel
    dv = state.node_acc
    net_x = net_y = net_z = 0.0
    for k in range(segment_set.shape[0]):
        s, mode = candidate(segment_set, k)
        if s < 0:
            break
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        e, fx, fy, fz, px, py, pz, nx, ny, nz, wx, wy, wz, mass, _, wa, wb, _ = segment_contact(
            p, v, state.node_i, state.node_mass, a, b, state.body_state, model.contact_shape, model.contact_f)
        if not react:
            terms = contact_terms(h, mode, e, nx, ny, nz, wx, wy, wz, mass, model.contact_f, 0.0, 0.0, 0.0)
            for n, w in ((a, wa), (b, wb)):
                if w > 0.0:
                    add_sym(state.node_mm, n, w * terms[0], w * terms[1], w * terms[2], w * terms[3],
                            w * terms[4], w * terms[5])
                    dv[n, 0] += w * terms[6]
                    dv[n, 1] += w * terms[7]
                    dv[n, 2] += w * terms[8]
            continue
        cx = cy = cz = 0.0
        for n, w in ((a, wa), (b, wb)):
            if w > 0.0:
                gx, gy, gz = contact_force_change(h, mode, e, nx, ny, nz, wx, wy, wz, mass, model.contact_f,
                                                  dv[n, 0], dv[n, 1], dv[n, 2], 0.0, 0.0, 0.0)
                cx += w * gx
                cy += w * gy
                cz += w * gz
        add_contact_reaction(state.body_load, state.body_state, px, py, pz, cx, cy, cz)
        net_x += fx + cx
        net_y += fy + cy
        net_z += fz + cz
    return net_x, net_y, net_z

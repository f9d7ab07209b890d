"""Contact between line nodes and the anchor's surface: the penalty law with friction, its Jacobians, the loads.

Why: lengthwise a chain with the seed's tangential drag falls faster than the anchor (seed 003, Landhaug 2015,
*Dynamic Simulation of Dart Anchor Installation*, chapter 8: C_D,T = 0.0069), so the vertical chain catches up
with the anchor's back end during the fall. Without contact it would pass into the body; with it, it lands on
the back end, rests there or slides off along the shaft, and its momentum goes into the anchor.

Surface (``physics/anchor_surface.py``): the union of the coaxial cylinders of the anchor's sections, its signed
distance sd (negative inside), outward normal n and n's derivative H.

Law. A free node of mass m inside the surface (depth d = -sd > 0), with velocity w = v - v_b relative to the body
point at the node (v_b = v_G + omega x (x - r_G)), feels

    f_n = k d - c (w . n),   c = 2 zeta sqrt(k m),   F = f_n n + F_t,

    F_t = -min(mu N |w_t| / v_s', mu N) w_t / |w_t|,   N = max(f_n, 0),   v_s' = max(v_s, mu N / c),

with w_t = w - (w . n) n. The body feels -F at the node, i.e. the moment (x - r_G) x (-F) about its COG (the
point whose velocity enters w, so the contact's power is -F . w: the spring stores, the dampers dissipate).

- Normal: a linear spring-dashpot (Kelvin-Voigt, as the Hooke model of penalty contact in rigid-body codes, e.g.
  Project Chrono's SMC contact). While the node is inside the law stays linear (it is not cut at f_n = 0), so
  the restitution is exactly e = exp(-zeta pi / sqrt(1 - zeta^2)), i.e. zeta = -ln e / sqrt(pi^2 + ln^2 e),
  and e = 0 gives zeta = 1: the node comes to rest on the surface without rebound. (Cut at zero, a critically
  damped contact would let go while still inside and leave at 13.5 % of its impact speed.) The price is a pull
  of at most c |w . n| while inside and moving out, for at most d / |w . n|: an impulse below c d, i.e. below
  the node's momentum at 2 zeta omega d, a few mm/s for a resting node.
- Friction: Coulomb, regularised as the seabed's (``seabed.py``): viscous below the stick speed v_s, so that a
  resting node feels none and there is no stick state to carry. The viscous slope mu N / v_s' never exceeds
  the normal damping c, so the friction is no stiffer for the explicit step than the normal law (under an impact
  N is large and the stick zone widens to mu N / c).

Jacobians (:func:`node_contact`): dF/dx and dF/dv, exact (including the turning of the normal, the body's rotation
and the friction's dependence on the normal force; checked against central differences), the body's state held
fixed. The implicit step (``implicit_contact.py``) takes their symmetric, positive part: k n n^T and the damping.
The static solver takes k n n^T and its coupling to the anchor (``statics_contact.py``).

The numbers (stiffness, restitution, friction) and the shape are chosen in ``physics/contact_setup.py``; the
contact of segments that cut into the anchor deeper than their nodes is ``physics/segment_contact.py``, with this
law (:func:`law_at`).
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor_surface import bounding_radius_m, from_cog, surface_distance, within_reach
from moor_env.physics.contact_broadphase import listed
from moor_env.physics.layout import (
    BS_OMEGA,
    BS_POS,
    BS_VEL,
    CF_MU,
    CF_STICK_SPEED,
    CF_STIFFNESS,
    CF_ZETA,
    CO_DEPTH,
    CO_FORCE,
    CO_NODES,
    CO_PEAK_DEPTH,
    CO_PEAK_FORCE,
    NI_KIND,
    NODE_FREE,
)


@jit_step(inline="always")
def may_touch(node_pos, node_i, n, body_state, shape, seabed_z, margin_m=0.0):
    """Whether node n is one the contact acts on and lies within ``margin_m`` [m] of the anchor's bounding
    cylinder: a free node above the seabed (``seabed_z`` [m]; below it the anchor is in the soil, which strips a
    line off it)."""
    if node_i[n, NI_KIND] != NODE_FREE or node_pos[n, 2] < seabed_z:
        return False
    return within_reach(node_pos[n, 0], node_pos[n, 1], node_pos[n, 2], body_state, shape, margin_m)


# features of the surface nearest to a point
@jit_step(inline="always")
def relative_velocity(px, py, pz, vx, vy, vz, body_state):
    """Velocity of a point at p moving at v relative to the anchor's material point there,
    w = v - v_G - omega x (p - r_G) [m/s]."""
    ox = body_state[BS_OMEGA]
    oy = body_state[BS_OMEGA + 1]
    oz = body_state[BS_OMEGA + 2]
    rx, ry, rz, _ = from_cog(px, py, pz, body_state)
    return (vx - body_state[BS_VEL] - (oy * rz - oz * ry), vy - body_state[BS_VEL + 1] - (oz * rx - ox * rz),
            vz - body_state[BS_VEL + 2] - (ox * ry - oy * rx))


@jit_step
def _law(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f):
    """The law of :func:`node_contact`: (depth, force, and what its Jacobian needs); depth 0 outside."""
    sd = 1.0
    nx = ny = nz = hxx = hyy = hzz = hxy = hxz = hyz = 0.0
    if within_reach(px, py, pz, body_state, shape):
        sd, nx, ny, nz, hxx, hyy, hzz, hxy, hxz, hyz, _ = surface_distance(px, py, pz, body_state, shape)
    depth = -sd if sd < 0.0 else 0.0
    wx, wy, wz = relative_velocity(px, py, pz, vx, vy, vz, body_state)
    fx, fy, fz, wn, fn, k, c, mu, tx, ty, tz, st, normal, g, sliding, viscous_from_n = law_at(
        depth, nx, ny, nz, wx, wy, wz, mass_kg, contact_f)
    return (depth, fx, fy, fz, nx, ny, nz, hxx, hyy, hzz, hxy, hxz, hyz, wx, wy, wz, wn, fn, k, c, mu, tx, ty, tz,
            st, normal, g, sliding, viscous_from_n)


@jit_step(inline="always")
def law_at(depth, nx, ny, nz, wx, wy, wz, mass_kg, contact_f):
    """The contact law at a point ``depth`` [m] inside the surface (0: outside) with outward normal n and velocity
    w relative to the body's point there [m/s], for a mass ``mass_kg`` [kg] (module docstring): the force
    (fx, fy, fz) [N], then what its Jacobian needs (w.n, f_n, k, c, mu, w_t, |w_t|, N, the friction's factor g,
    sliding, whether the viscous slope follows N)."""
    k = contact_f[CF_STIFFNESS]
    c = 2.0 * contact_f[CF_ZETA] * math.sqrt(k * mass_kg)
    mu = contact_f[CF_MU]
    wn = wx * nx + wy * ny + wz * nz
    fn = k * depth - c * wn if depth > 0.0 else 0.0
    tx = wx - wn * nx
    ty = wy - wn * ny
    tz = wz - wn * nz
    st = math.sqrt(tx * tx + ty * ty + tz * tz)
    normal = fn if fn > 0.0 else 0.0
    slope = 0.0  # friction as -slope * w_t (viscous) or -mu N w_t / |w_t| (sliding)
    sliding = False
    viscous_from_n = False
    if normal > 0.0 and mu > 0.0:
        slope = mu * normal / contact_f[CF_STICK_SPEED]
        viscous_from_n = True
        if slope > c:
            slope = c
            viscous_from_n = False
        if slope * st > mu * normal:
            sliding = True
    g = mu * normal / st if sliding else slope
    return (fn * nx - g * tx, fn * ny - g * ty, fn * nz - g * tz, wn, fn, k, c, mu, tx, ty, tz, st, normal, g,
            sliding, viscous_from_n)


@jit_step
def contact_force(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f):
    """Contact force on a node of mass ``mass_kg`` at (p, v) from the anchor (module docstring).

    Returns
    -------
    depth : float
        Penetration [m] (0 outside).
    fx, fy, fz : float
        Force on the node [N]; the body takes the opposite force at the node (:func:`add_contact_reaction`).
    """
    if not within_reach(px, py, pz, body_state, shape):
        return 0.0, 0.0, 0.0, 0.0
    return force_within_reach(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f)


@jit_step(inline="always")
def force_within_reach(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f):
    """:func:`contact_force` of a node already found within the anchor's bounding cylinder
    (``anchor_surface.within_reach``): nothing but the surface distance computed for a node outside the surface."""
    sd, nx, ny, nz = surface_distance(px, py, pz, body_state, shape)[:4]
    if sd >= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    wx, wy, wz = relative_velocity(px, py, pz, vx, vy, vz, body_state)
    fx, fy, fz = law_at(-sd, nx, ny, nz, wx, wy, wz, mass_kg, contact_f)[:3]
    return -sd, fx, fy, fz


@jit_step
def node_contact(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f, jac):
    """:func:`contact_force` and its Jacobians: ``jac`` (shape (2, 3, 3)) receives dF/dx [N/m] and dF/dv [N s/m]
    (zeros out of contact)."""
    (depth, fx, fy, fz, nx, ny, nz, hxx, hyy, hzz, hxy, hxz, hyz, wx, wy, wz, wn, fn, k, c, mu, tx, ty, tz, st,
     normal, g, sliding, viscous_from_n) = _law(px, py, pz, vx, vy, vz, mass_kg, body_state, shape, contact_f)
    for i in range(3):
        for j in range(3):
            jac[0, i, j] = 0.0
            jac[1, i, j] = 0.0
    if depth > 0.0:
        _contact_jacobian(jac, nx, ny, nz, hxx, hyy, hzz, hxy, hxz, hyz, body_state[BS_OMEGA],
                          body_state[BS_OMEGA + 1], body_state[BS_OMEGA + 2], wx, wy, wz, wn, fn, k, c, mu,
                          contact_f[CF_STICK_SPEED], tx, ty, tz, st, normal, g, sliding, viscous_from_n)
    return depth, fx, fy, fz


@jit_step
def _contact_jacobian(jac, nx, ny, nz, hxx, hyy, hzz, hxy, hxz, hyz, ox, oy, oz, wx, wy, wz, wn, fn, k, c, mu,
                      stick, tx, ty, tz, st, normal, g, sliding, viscous_from_n):
    """dF/dx and dF/dv of :func:`node_contact` into ``jac`` (body state fixed)."""
    n = (nx, ny, nz)
    t = (tx, ty, tz)
    h = ((hxx, hxy, hxz), (hxy, hyy, hyz), (hxz, hyz, hzz))
    # dw/dx = -[omega]x (the body point's velocity follows the node), dw/dv = I
    om = ((0.0, oz, -oy), (-oz, 0.0, ox), (oy, -ox, 0.0))  # -[omega]x
    # d(w.n)/dx = n^T dw/dx + (H w)^T ; d(w.n)/dv = n^T
    hw = (h[0][0] * wx + h[0][1] * wy + h[0][2] * wz, h[1][0] * wx + h[1][1] * wy + h[1][2] * wz,
          h[2][0] * wx + h[2][1] * wy + h[2][2] * wz)
    dwn_dx = (n[0] * om[0][0] + n[1] * om[1][0] + n[2] * om[2][0] + hw[0],
              n[0] * om[0][1] + n[1] * om[1][1] + n[2] * om[2][1] + hw[1],
              n[0] * om[0][2] + n[1] * om[1][2] + n[2] * om[2][2] + hw[2])
    # f_n = k d - c w.n: df_n/dx = -k n^T - c dwn/dx, df_n/dv = -c n^T
    dfn_dx = (-k * n[0] - c * dwn_dx[0], -k * n[1] - c * dwn_dx[1], -k * n[2] - c * dwn_dx[2])
    dfn_dv = (-c * n[0], -c * n[1], -c * n[2])
    dn_x = dfn_dx if normal > 0.0 else (0.0, 0.0, 0.0)
    dn_v = dfn_dv if normal > 0.0 else (0.0, 0.0, 0.0)
    # dg: the friction's factor on w_t
    if sliding:
        gx = (mu * dn_x[0] / st, mu * dn_x[1] / st, mu * dn_x[2] / st)
        gv = (mu * dn_v[0] / st, mu * dn_v[1] / st, mu * dn_v[2] / st)
    elif viscous_from_n:
        gx = (mu * dn_x[0] / stick, mu * dn_x[1] / stick, mu * dn_x[2] / stick)
        gv = (mu * dn_v[0] / stick, mu * dn_v[1] / stick, mu * dn_v[2] / stick)
    else:
        gx = (0.0, 0.0, 0.0)
        gv = (0.0, 0.0, 0.0)
    for i in range(3):
        for j in range(3):
            eye = 1.0 if i == j else 0.0
            # w_t = w - (w.n) n: dw_t/dx = dw/dx - n dwn/dx - (w.n) H, dw_t/dv = I - n n^T
            dwt_x = om[i][j] - n[i] * dwn_dx[j] - wn * h[i][j]
            dwt_v = eye - n[i] * n[j]
            ax = n[i] * dfn_dx[j] + fn * h[i][j]
            av = n[i] * dfn_dv[j]
            if sliding:
                # g = mu N / |w_t|: d(g w_t) = w_t dg + g (I - t t^T / |t|^2) dw_t
                px_ = 0.0
                pv_ = 0.0
                for m in range(3):
                    proj = (1.0 if i == m else 0.0) - t[i] * t[m] / (st * st)
                    dwt_xm = om[m][j] - n[m] * dwn_dx[j] - wn * h[m][j]
                    dwt_vm = (1.0 if m == j else 0.0) - n[m] * n[j]
                    px_ += proj * dwt_xm
                    pv_ += proj * dwt_vm
                ax -= t[i] * gx[j] + g * px_
                av -= t[i] * gv[j] + g * pv_
            else:
                ax -= t[i] * gx[j] + g * dwt_x
                av -= t[i] * gv[j] + g * dwt_v
            jac[0, i, j] = ax
            jac[1, i, j] = av


@jit_step(inline="always")
def _reaction_moment(body_state, px, py, pz, fx, fy, fz):
    """Moment about the COG of the reaction -F at the node: (x - r_G) x (-F)."""
    rx, ry, rz, _ = from_cog(px, py, pz, body_state)
    return rz * fy - ry * fz, rx * fz - rz * fx, ry * fx - rx * fy


@jit_step
def add_contact_reaction(load, body_state, px, py, pz, fx, fy, fz):
    """Add the reaction of a contact force (fx, fy, fz) on a node at p to the body's ``load`` (F [N], M about
    the COG [N m]): -F at the node."""
    mx, my, mz = _reaction_moment(body_state, px, py, pz, fx, fy, fz)
    load[0] -= fx
    load[1] -= fy
    load[2] -= fz
    load[3] += mx
    load[4] += my
    load[5] += mz


@jit_no_refcount(inline="always")
def add_contact_loads(node_pos, node_vel, node_i, node_mass, node_force, body_state, shape, contact_f, contact_out,
                      seabed_z, near_nodes, listed_on):
    """Add the contact force of every free node inside the anchor to ``node_force`` and record the nodes inside in
    ``contact_out`` (``CO_NODES``, ``CO_DEPTH``, ``CO_PEAK_DEPTH``; the force: :func:`record_contact_force`);
    returns the reaction on the anchor (F [N], M about the COG [N m]) as six floats.

    The node's mass in the damping is its structural mass (``node_mass``, welded parts included); its added mass
    (a few % for chain) only makes the contact slightly softer and less damped than chosen. Nodes below the seabed
    (``seabed_z`` [m]) are left to the seabed (:func:`may_touch`). Broad phase: one distance to the anchor's COG
    per node against the sphere that holds the anchor (most of a line lies far from it), over the nodes listed
    near the anchor in ``near_nodes`` where ``listed_on`` (``contact_broadphase``), else over all.
    """
    lx = ly = lz = mx = my = mz = 0.0
    count = 0
    deepest = 0.0
    reach2 = bounding_radius_m(shape) ** 2
    gx = body_state[BS_POS]
    gy = body_state[BS_POS + 1]
    gz = body_state[BS_POS + 2]
    for k in range(node_i.shape[0]):
        n = listed(near_nodes, listed_on, k)
        if n < 0:
            break
        dx = node_pos[n, 0] - gx
        dy = node_pos[n, 1] - gy
        dz = node_pos[n, 2] - gz
        if dx * dx + dy * dy + dz * dz > reach2 or not may_touch(node_pos, node_i, n, body_state, shape, seabed_z):
            continue
        px = node_pos[n, 0]
        py = node_pos[n, 1]
        pz = node_pos[n, 2]
        depth, fx, fy, fz = force_within_reach(px, py, pz, node_vel[n, 0], node_vel[n, 1], node_vel[n, 2],
                                               node_mass[n], body_state, shape, contact_f)
        if depth == 0.0:
            continue
        count += 1
        deepest = max(deepest, depth)
        node_force[n, 0] += fx
        node_force[n, 1] += fy
        node_force[n, 2] += fz
        lx -= fx
        ly -= fy
        lz -= fz
        ax, ay, az = _reaction_moment(body_state, px, py, pz, fx, fy, fz)
        mx += ax
        my += ay
        mz += az
    contact_out[CO_NODES] = count
    contact_out[CO_DEPTH] = deepest
    contact_out[CO_PEAK_DEPTH] = max(contact_out[CO_PEAK_DEPTH], deepest)
    return lx, ly, lz, mx, my, mz


@jit_no_refcount
def record_contact_force(contact_out, fx, fy, fz):
    """Record the net contact force on the anchor (F [N]) and its running peak in ``contact_out``."""
    force = math.sqrt(fx * fx + fy * fy + fz * fz)
    contact_out[CO_FORCE] = force
    contact_out[CO_PEAK_FORCE] = max(contact_out[CO_PEAK_FORCE], force)

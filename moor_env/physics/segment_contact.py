"""Contact between line segments and the anchor's surface, where a straight segment cuts into the anchor deeper
than its nodes do: a chain draped over the back end's rim, or a chord across the shaft.

Why: the node contact (``physics/contact.py``) holds the nodes out of the anchor, but a segment between two nodes
resting on either side of a rim cuts the corner (at rest over the back rim, by up to 9 cm with 0.5-2 m chain
segments), and a segment crossing the shaft with both nodes outside passes through it unhindered.

Geometry. The segment's deepest point inside the surface, p* = x_a + t (x_b - x_a) at depth d*
(``anchor_surface.segment_depth``), is measured against what the node contact already holds there: the excess

    e = d* - ((1 - t) max(d_a, 0) + t max(d_b, 0)),

with d_a, d_b the nodes' depths. It is zero where the depth is linear along the segment (a segment lying on a
face, or along the shaft at one depth), d* where both nodes are outside, and it goes to zero as p* moves to an
end, so the segment's force sets in and fades out continuously. Moving the segment across itself by dx changes
e by -g . dx: where p* lies inside one face or on the shaft, g is the surface normal there (perpendicular to the
segment: the depth is stationary along it); where it lies on the kink between an end face and the shaft (a
segment over a rim), g is the combination l n- + (1 - l) n+ of the two faces' normals that is perpendicular to
the segment (the depth's subgradient that does not slide the segment along itself), |g| < 1. The contact acts
along n = g / |g| on the depth e |g|: its force k e g is the gradient of the energy k e^2 / 2, and its stiffness
along n is k |g|^2.

Law. The node law of ``contact.py`` (:func:`moor_env.physics.contact.law_at`: spring-dashpot, regularised
Coulomb friction) at depth e, normal n, the velocity of p* relative to the anchor's point there (the nodes'
velocities interpolated) and the inertia of p* (:func:`point_mass`). The force is shared
(1 - t, t) between the segment's nodes and the anchor takes its opposite at p* (a node held by a vessel takes
its share out of the model; segments from the anchor's own node are left out, :func:`may_cut`).

Linearisation. The segment's stiffness is k |g|^2 G G^T, G = ((1 - t) n, t n, -J^T n) over node a, node b and
the anchor (t and n held), plus the shift of the shares as p* moves along the segment (:func:`contact_frame`).
The static solver takes it whole (``physics/statics_contact.py``): node blocks (1 - t)^2 and t^2 times
k n n^T, their coupling t (1 - t) k n n^T in the segment's own block, the anchor's terms as a node contact's.
The implicit step, whose segment blocks have no room for the coupling, takes two node contacts at p* instead,
one per node with stiffness (1 - t) k and t k: the same anchor terms, and node blocks (1 - t) and t times
k n n^T. That is stiffer by the positive semidefinite form k (1 - t) t (n . (dx_a - dx_b))^2, so the step is at
least as stable as with the exact coupling. (The static solver cannot take it: Newton's method with it converges
linearly where t is near 0 or 1; on gjoa-500 at spacing 0, with the chain over the back end's rim at t = 0.01,
the residual fell by 0.05 % per iteration and the solve stopped unconverged after 2000.)
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.anchor_surface import (
    FEATURE_SHAFT,
    bounding_radius_m,
    from_cog,
    radial_part,
    segment_depth,
    surface_distance,
)
from moor_env.physics.contact import law_at, relative_velocity
from moor_env.physics.contact_broadphase import listed
from moor_env.physics.layout import (
    BS_POS,
    CF_SEGMENTS,
    CO_SEGMENTS,
    CS_BACK,
    CS_FRONT,
    CS_RADIUS,
    NI_KIND,
    NODE_BODY,
    NODE_FREE,
    SI_A,
    SI_ACTIVE,
    SI_B,
)

KINK_PROBE_M = 1e-6  # how far to either side of the deepest point the normals are compared for a kink [m]


@jit_step(inline="always")  # called once per segment per load evaluation: inlined, its array arguments stay in place
def near_sphere(node_pos, seg_i, s, body_state, reach_m):
    """Whether active segment s may reach into the sphere of radius ``reach_m`` [m] about the anchor's COG: its
    midpoint within half its length of it, tested as |m - r_G|^2 <= 2 (R^2 + (l / 2)^2) (>= (R + l / 2)^2: no
    square root; most segments lie far from the anchor)."""
    if seg_i[s, SI_ACTIVE] == 0:
        return False
    a = seg_i[s, SI_A]
    b = seg_i[s, SI_B]
    dx = node_pos[b, 0] - node_pos[a, 0]
    dy = node_pos[b, 1] - node_pos[a, 1]
    dz = node_pos[b, 2] - node_pos[a, 2]
    gx = node_pos[a, 0] + 0.5 * dx - body_state[BS_POS]
    gy = node_pos[a, 1] + 0.5 * dy - body_state[BS_POS + 1]
    gz = node_pos[a, 2] + 0.5 * dz - body_state[BS_POS + 2]
    return gx * gx + gy * gy + gz * gz <= 2.0 * (reach_m * reach_m + 0.25 * (dx * dx + dy * dy + dz * dz))


@jit_step(inline="always")  # called once per segment per load evaluation: inlined, its array arguments stay in place
def may_cut(node_pos, node_i, seg_i, s, body_state, shape, seabed_z, body_radius_m, margin_m):
    """Whether active segment s can cut into the anchor (cheap tests before :func:`segment_geometry`): its
    midpoint within half its length of the sphere that holds the anchor (``body_radius_m`` [m] about its COG,
    ``anchor_surface.bounding_radius_m``), one of its nodes free and neither the anchor's own, both above the
    seabed (``seabed_z`` [m]: below it the anchor is in the soil), its nodes not both behind the back end or both
    ahead of the tip, and its closest approach to the axis within the widest radius, each grown by ``margin_m``
    [m] (0: cutting in now; more: able to within a step); and not both nodes where the back face is the nearest
    surface (:func:`_on_the_back_face`).

    Why not a segment from the anchor's own node (the padeye at the back end's centre): hinged there, it cannot
    lie along the back face and over the rim as the chain does, and once turned past the rim it cuts the corner by
    most of its length. On gjoa-500 at 170 m spacing (fast preset, 1 m vertical chain segments) that pushed the
    anchor with 1.3 MN and tilted it 1.0 deg at touchdown, against no tilt with 0.5 m segments, where the chain's
    nodes carry the contact (0.49 MN)."""
    if not near_sphere(node_pos, seg_i, s, body_state, body_radius_m + margin_m):
        return False
    a = seg_i[s, SI_A]
    b = seg_i[s, SI_B]
    if node_i[a, NI_KIND] != NODE_FREE and node_i[b, NI_KIND] != NODE_FREE:
        return False
    if node_i[a, NI_KIND] == NODE_BODY or node_i[b, NI_KIND] == NODE_BODY:
        return False
    if node_pos[a, 2] < seabed_z or node_pos[b, 2] < seabed_z:
        return False
    aa, qax, qay, qaz = radial_part(node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], body_state)
    ab, qbx, qby, qbz = radial_part(node_pos[b, 0], node_pos[b, 1], node_pos[b, 2], body_state)
    back = shape[shape.shape[0] - 1, CS_BACK] - margin_m
    front = shape[0, CS_FRONT] + margin_m
    if (aa <= back and ab <= back) or (aa >= front and ab >= front):
        return False
    if _on_the_back_face(aa, qax, qay, qaz, ab, qbx, qby, qbz, shape):  # the chain piled on the back end: cheap
        return False
    # the segment's closest approach to the axis, min |q_a + t (q_b - q_a)| over [0, 1], against the widest radius
    q1x = qbx - qax
    q1y = qby - qay
    q1z = qbz - qaz
    q11 = q1x * q1x + q1y * q1y + q1z * q1z
    t = min(max(-(qax * q1x + qay * q1y + qaz * q1z) / q11, 0.0), 1.0) if q11 > 0.0 else 0.0
    widest = 0.0
    for i in range(shape.shape[0]):
        widest = max(widest, shape[i, CS_RADIUS])
    reach = widest + margin_m
    return (qax + t * q1x) ** 2 + (qay + t * q1y) ** 2 + (qaz + t * q1z) ** 2 <= reach * reach


@jit_step(inline="always")
def _on_the_back_face(aa, qax, qay, qaz, ab, qbx, qby, qbz, shape):
    """Whether a segment of a one-cylinder anchor has both nodes (axial coordinates aa, ab; radial vectors q)
    where the back face is the nearest surface: within the radius and nearer the back face than the shaft and the
    tip. Why: along such a segment the depth is the back face's, linear, so it cannot cut in deeper than its
    nodes; a chain piled on the back end in the fall is all such segments, and the test is far cheaper than
    :func:`segment_geometry`."""
    if shape.shape[0] != 1:
        return False
    back = shape[0, CS_BACK]
    front = shape[0, CS_FRONT]
    radius = shape[0, CS_RADIUS]
    for a, qx, qy, qz in ((aa, qax, qay, qaz), (ab, qbx, qby, qbz)):
        rho2 = qx * qx + qy * qy + qz * qz
        gap = a - back
        # rho > radius, or gap > radius - rho (nearer the shaft), without the square root
        if rho2 > radius * radius or gap > radius or rho2 > (radius - gap) ** 2 or gap > front - a:
            return False
    return True


@jit_step
def segment_geometry(ax, ay, az, bx, by, bz, body_state, shape):
    """The segment contact's geometry (module docstring) of the segment from a to b: the excess e [m] along the
    contact's normal (negative: the gap the segment must close before it cuts in deeper than its nodes), t (p* =
    a + t (b - a)), p* [m], the unit normal n, the stiffness factor |g|^2 of the excess's gradient (1 off a kink),
    whether a node of it lies inside the anchor (its excess is then measured from that node's depth, not a gap),
    and dt/dx_a, dt/dx_b (:func:`contact_frame`)."""
    deepest, t = segment_depth(ax, ay, az, bx, by, bz, body_state, shape)
    da = -surface_distance(ax, ay, az, body_state, shape)[0]
    db = -surface_distance(bx, by, bz, body_state, shape)[0]
    excess = deepest - ((1.0 - t) * max(da, 0.0) + t * max(db, 0.0))
    px = ax + t * (bx - ax)
    py = ay + t * (by - ay)
    pz = az + t * (bz - az)
    gx, gy, gz, uax, uay, uaz, ubx, uby, ubz = contact_frame(ax, ay, az, bx, by, bz, t, body_state, shape)
    size = math.sqrt(gx * gx + gy * gy + gz * gz)
    return (excess * size, t, px, py, pz, gx / size, gy / size, gz / size, size * size, da > 0.0 or db > 0.0,
            uax, uay, uaz, ubx, uby, ubz)


@jit_step
def _normal_along(ax, ay, az, bx, by, bz, t, body_state, shape):
    """The surface normal (the signed distance's gradient) at the point a + t (b - a)."""
    return surface_distance(ax + t * (bx - ax), ay + t * (by - ay), az + t * (bz - az), body_state, shape)[1:4]


@jit_step
def contact_frame(ax, ay, az, bx, by, bz, t, body_state, shape):
    """g, the gradient of the segment's depth at its deepest point p* (t) with respect to a move of the segment
    across itself (|g| <= 1), and how p* moves along the segment as either node moves, dt/dx_a and dt/dx_b [1/m]
    (module docstring): (gx, gy, gz, dt/dx_a (3), dt/dx_b (3)).

    Off a kink g is the surface normal at p*; where p* lies on the shaft, t is the segment's closest approach to
    the axis, t = -(q0 . q1) / |q1|^2 (q0, q1: node a's and the segment's radial parts), and moves as they do. On
    the kink between two faces (normals n- and n+ found ``KINK_PROBE_M`` to either side), g is the combination
    l n- + (1 - l) n+ perpendicular to the segment, and t the crossing of the two faces' depths,
    (n- - n+) . (x_a + t (x_b - x_a)) fixed."""
    dx = bx - ax
    dy = by - ay
    dz = bz - az
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    sd, nx, ny, nz, _, _, _, _, _, _, feature = surface_distance(ax + t * dx, ay + t * dy, az + t * dz, body_state,
                                                                 shape)
    if length <= 0.0:
        return nx, ny, nz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    sx = dx / length
    sy = dy / length
    sz = dz / length
    probe = KINK_PROBE_M / length
    mx, my, mz = _normal_along(ax, ay, az, bx, by, bz, max(t - probe, 0.0), body_state, shape)
    qx, qy, qz = _normal_along(ax, ay, az, bx, by, bz, min(t + probe, 1.0), body_state, shape)
    if mx * qx + my * qy + mz * qz < 1.0 - 1e-9:
        sm = mx * sx + my * sy + mz * sz
        sq = qx * sx + qy * sy + qz * sz
        jx = mx - qx
        jy = my - qy
        jz = mz - qz
        across = jx * dx + jy * dy + jz * dz
        if sq != sm and across != 0.0:
            share = sq / (sq - sm)
            if 0.0 <= share <= 1.0:
                fa = -(1.0 - t) / across
                fb = -t / across
                return (share * mx + (1.0 - share) * qx, share * my + (1.0 - share) * qy,
                        share * mz + (1.0 - share) * qz, fa * jx, fa * jy, fa * jz, fb * jx, fb * jy, fb * jz)
    along = nx * sx + ny * sy + nz * sz  # zero where the depth is stationary along the segment
    gx = nx - along * sx
    gy = ny - along * sy
    gz = nz - along * sz
    size = math.sqrt(gx * gx + gy * gy + gz * gz)
    if size < 1e-9:  # the segment lies along the normal
        return nx, ny, nz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if feature != FEATURE_SHAFT or not 0.0 < t < 1.0:
        return gx / size, gy / size, gz / size, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return (gx / size, gy / size, gz / size) + _closest_approach_motion(ax, ay, az, bx, by, bz, t, body_state)


@jit_step
def _closest_approach_motion(ax, ay, az, bx, by, bz, t, body_state):
    """dt/dx_a and dt/dx_b of the segment's closest approach to the anchor's axis, t = -(q0 . q1) / |q1|^2:
    dt/dx_a = -((1 - 2 t) q1 - q0) / |q1|^2, dt/dx_b = -(q0 + 2 t q1) / |q1|^2."""
    _, q0x, q0y, q0z = radial_part(ax, ay, az, body_state)
    _, qbx, qby, qbz = radial_part(bx, by, bz, body_state)
    q1x = qbx - q0x
    q1y = qby - q0y
    q1z = qbz - q0z
    q11 = q1x * q1x + q1y * q1y + q1z * q1z
    if q11 <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return (-((1.0 - 2.0 * t) * q1x - q0x) / q11, -((1.0 - 2.0 * t) * q1y - q0y) / q11,
            -((1.0 - 2.0 * t) * q1z - q0z) / q11, -(q0x + 2.0 * t * q1x) / q11, -(q0y + 2.0 * t * q1y) / q11,
            -(q0z + 2.0 * t * q1z) / q11)


@jit_step
def free_shares(node_i, a, b, t):
    """The shares (1 - t, t) of the segment's force that its nodes a and b take: zero for a node that is not free
    (held by a vessel, its share leaves the model with it; welded, or the anchor's own, left out by
    :func:`may_cut`). :func:`point_mass` counts the inertia of the free ones."""
    wa = 1.0 - t if node_i[a, NI_KIND] == NODE_FREE else 0.0
    wb = t if node_i[b, NI_KIND] == NODE_FREE else 0.0
    return wa, wb


@jit_step
def point_velocity(node_vel, a, b, t, px, py, pz, body_state):
    """Velocity of p* (the nodes' velocities interpolated at t) relative to the anchor's point there [m/s]."""
    return relative_velocity(px, py, pz, (1.0 - t) * node_vel[a, 0] + t * node_vel[b, 0],
                             (1.0 - t) * node_vel[a, 1] + t * node_vel[b, 1],
                             (1.0 - t) * node_vel[a, 2] + t * node_vel[b, 2], body_state)


@jit_step
def point_mass(node_mass, wa, wb, a, b):
    """The mass the law's damping takes at p* [kg]: the inertia p* has where the force is shared (wa, wb) between
    its free nodes, 1 / (wa^2 / m_a + wb^2 / m_b) (a node that is not free, zero share, counts as held). Why: with
    it every node in the contact is damped at the law's ratio (node b, of its share t, feels the stiffness t^2 k and
    the damping t^2 c = 2 zeta sqrt(t^2 k m_b))."""
    inverse = 0.0
    if wa > 0.0:
        inverse += wa * wa / node_mass[a]
    if wb > 0.0:
        inverse += wb * wb / node_mass[b]
    return 1.0 / inverse


@jit_step
def segment_contact(node_pos, node_vel, node_i, node_mass, a, b, body_state, shape, contact_f):
    """The contact of the segment from node a to node b: (excess e [m], force at p* [N] (3), p* [m] (3), normal
    (3), relative velocity of p* [m/s] (3), its mass [kg], t, the free nodes' shares wa, wb, whether a node lies
    inside the anchor); no force where e <= 0 (then the gap, where both nodes are outside) or neither node is
    free (then e <= 0 too)."""
    e, t, px, py, pz, nx, ny, nz, _, node_inside = segment_geometry(
        node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], node_pos[b, 0], node_pos[b, 1], node_pos[b, 2], body_state,
        shape)[:10]
    wa, wb = free_shares(node_i, a, b, t)
    if wa + wb <= 0.0:
        return min(e, 0.0), 0.0, 0.0, 0.0, px, py, pz, nx, ny, nz, 0.0, 0.0, 0.0, 0.0, t, 0.0, 0.0, node_inside
    wx, wy, wz = point_velocity(node_vel, a, b, t, px, py, pz, body_state)
    mass = point_mass(node_mass, wa, wb, a, b)
    if e <= 0.0:
        return e, 0.0, 0.0, 0.0, px, py, pz, nx, ny, nz, wx, wy, wz, mass, t, wa, wb, node_inside
    fx, fy, fz = law_at(e, nx, ny, nz, wx, wy, wz, mass, contact_f)[:3]
    return e, fx, fy, fz, px, py, pz, nx, ny, nz, wx, wy, wz, mass, t, wa, wb, node_inside


@jit_no_refcount(inline="always")
def add_segment_contact_loads(node_pos, node_vel, node_i, node_mass, seg_i, node_force, body_state, shape,
                              contact_f, seabed_z, contact_out, near_segs, listed_on):
    """Add every segment contact's force (module docstring) to its nodes' ``node_force`` (shares 1 - t and t, to
    the free ones: :func:`free_shares`) and count the segments in ``contact_out`` (``CO_SEGMENTS``),
    where ``contact_f`` has the segments' contact on (``CF_SEGMENTS``), over the segments listed near the anchor in
    ``near_segs`` where ``listed_on`` (``contact_broadphase``), else over all;
    returns the reaction on the anchor, the opposite of the force at p* (F [N], M about the COG [N m], six
    floats), and the deepest excess [m]."""
    lx = ly = lz = mx = my = mz = 0.0
    deepest = 0.0
    count = 0
    radius = bounding_radius_m(shape)
    for k in range(seg_i.shape[0] if contact_f[CF_SEGMENTS] != 0.0 else 0):
        s = listed(near_segs, listed_on, k)
        if s < 0:
            break
        if not may_cut(node_pos, node_i, seg_i, s, body_state, shape, seabed_z, radius, 0.0):
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        e, fx, fy, fz, px, py, pz, _, _, _, _, _, _, _, _, wa, wb, _ = segment_contact(
            node_pos, node_vel, node_i, node_mass, a, b, body_state, shape, contact_f)
        if e <= 0.0:
            continue
        count += 1
        deepest = max(deepest, e)
        node_force[a, 0] += wa * fx
        node_force[a, 1] += wa * fy
        node_force[a, 2] += wa * fz
        node_force[b, 0] += wb * fx
        node_force[b, 1] += wb * fy
        node_force[b, 2] += wb * fz
        rx, ry, rz, _ = from_cog(px, py, pz, body_state)
        lx -= fx
        ly -= fy
        lz -= fz
        mx -= ry * fz - rz * fy
        my -= rz * fx - rx * fz
        mz -= rx * fy - ry * fx
    contact_out[CO_SEGMENTS] = count
    return lx, ly, lz, mx, my, mz, deepest

"""The anchor's surface for the line-anchor contact (``physics/contact.py``): signed distance, normal, curvature.

The anchor model is axisymmetric: each section is a cylinder of its outer diameter (the fins' envelope is the
outer diameter of the fin sections, as the drag and added mass use it). The surface is the union of these coaxial
cylinders (``contact_setup.anchor_shape`` merges neighbours of equal radius), closed by the tip face, the back end
face and the annular steps between sections of different radius. In the anchor's frame a point has the axial
coordinate a = (x - r_G) . e (+ towards the tip, as ``anchor.py``) and the radius rho from the axis, with the
radial unit vector u. :func:`surface_distance` gives the signed distance sd (negative inside), its gradient, the
outward normal n, and its Hessian H = dn/dx (zero on the faces, (I - e e^T - u u^T) / rho on the shaft, that plus
the rim's own curvature outside a rim). The closest surface point is x - sd n. Inside, the depth is the distance
to the nearest shaft, face or face edge of the cylinder that contains the point: a step's face is the annulus
outside the narrower neighbour's radius (``contact_setup.anchor_shape`` records its inner radius), and inside that
radius its nearest point is the annulus' inner rim.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit_step
from moor_env.physics.layout import (
    BS_AXIS,
    BS_POS,
    CS_BACK,
    CS_BACK_INNER,
    CS_FRONT,
    CS_FRONT_INNER,
    CS_RADIUS,
    SF_L0,
    SI_A,
    SI_ACTIVE,
    SI_B,
)
from moor_env.physics.line import segment_axis

FEATURE_SHAFT = 0
FEATURE_FRONT = 1
FEATURE_BACK = 2
FEATURE_RIM = 3

@jit_step(inline="always")
def from_cog(px, py, pz, body_state):
    """The point relative to the anchor's COG, r = x - r_G [m], and its axial coordinate a = r . e [m]."""
    rx = px - body_state[BS_POS]
    ry = py - body_state[BS_POS + 1]
    rz = pz - body_state[BS_POS + 2]
    return rx, ry, rz, rx * body_state[BS_AXIS] + ry * body_state[BS_AXIS + 1] + rz * body_state[BS_AXIS + 2]


@jit_step(inline="always")
def radial_part(px, py, pz, body_state):
    """A point's axial coordinate a [m] and its radial vector from the anchor's axis, q = r - a e [m]."""
    rx, ry, rz, a = from_cog(px, py, pz, body_state)
    return a, rx - a * body_state[BS_AXIS], ry - a * body_state[BS_AXIS + 1], rz - a * body_state[BS_AXIS + 2]


@jit_step(inline="always")
def _anchor_frame(px, py, pz, body_state):
    """Axial coordinate a, radius rho, radial unit vector u and axis e of a point in the anchor's frame."""
    ex = body_state[BS_AXIS]
    ey = body_state[BS_AXIS + 1]
    ez = body_state[BS_AXIS + 2]
    a, qx, qy, qz = radial_part(px, py, pz, body_state)
    rho = math.sqrt(qx * qx + qy * qy + qz * qz)
    if rho > 0.0:
        return a, rho, qx / rho, qy / rho, qz / rho, ex, ey, ez
    # on the axis: any radial direction (the shaft's normal is then undefined, its depth the full radius)
    if abs(ex) < 0.9:
        qx, qy, qz = 0.0, -ez, ey
    else:
        qx, qy, qz = ez, 0.0, -ex
    norm = math.sqrt(qx * qx + qy * qy + qz * qz)
    return a, 0.0, qx / norm, qy / norm, qz / norm, ex, ey, ez


@jit_step(inline="always")
def _end_depth(gap, inner, rho):
    """Depth below an end face ``gap`` [m] inside it (annulus from radius ``inner`` out); inside the annulus'
    inner radius the nearest point of the face is its inner rim. Returns (depth, e-part, u-part of the normal
    direction from the point to the face, or to the rim)."""
    if rho >= inner:
        return gap, 1.0, 0.0
    dr = inner - rho
    depth = math.sqrt(gap * gap + dr * dr)
    return depth, gap / depth, dr / depth


@jit_step(inline="always")
def surface_distance(px, py, pz, body_state, shape):
    """Signed distance of a point to the anchor's surface and its derivatives.

    Returns
    -------
    sd : float
        Signed distance [m], negative inside.
    nx, ny, nz : float
        Outward normal (the gradient of sd); the closest surface point is x - sd n.
    hxx, hyy, hzz, hxy, hxz, hyz : float
        The Hessian of sd (dn/dx, symmetric) [1/m].
    feature : int
        ``FEATURE_SHAFT``, ``FEATURE_FRONT``, ``FEATURE_BACK`` (end faces and steps) or ``FEATURE_RIM`` (an edge
        of a face: outside a convex rim, or inside near the inner rim of a step).
    """
    a, rho, ux, uy, uz, ex, ey, ez = _anchor_frame(px, py, pz, body_state)
    depth = -math.inf
    feature = FEATURE_SHAFT
    ca = 0.0  # the normal's components along e and u, and the distance to a rim
    cr = 1.0
    dist = 0.0
    out = math.inf
    for i in range(shape.shape[0]):
        front = shape[i, CS_FRONT]
        back = shape[i, CS_BACK]
        radius = shape[i, CS_RADIUS]
        if back <= a <= front and rho <= radius:
            d = radius - rho
            f = FEATURE_SHAFT
            fa = 0.0
            fr = 1.0
            df, pa, pr = _end_depth(front - a, shape[i, CS_FRONT_INNER], rho)
            if df < d:
                d = df
                f = FEATURE_FRONT if pr == 0.0 else FEATURE_RIM
                fa = pa
                fr = pr
            db, pa, pr = _end_depth(a - back, shape[i, CS_BACK_INNER], rho)
            if db < d:
                d = db
                f = FEATURE_BACK if pr == 0.0 else FEATURE_RIM
                fa = -pa
                fr = pr
            if d > depth:
                depth = d
                feature = f
                ca = fa
                cr = fr
                dist = d
        elif depth == -math.inf:
            da = a - back if a < back else (a - front if a > front else 0.0)
            dr = rho - radius if rho > radius else 0.0
            d = math.sqrt(da * da + dr * dr)
            if d < out:
                out = d
                if dr > 0.0 and da != 0.0:
                    feature = FEATURE_RIM
                elif dr > 0.0:
                    feature = FEATURE_SHAFT
                else:
                    feature = FEATURE_FRONT if da > 0.0 else FEATURE_BACK
                ca = da / d
                cr = dr / d
                dist = d
    sd = out if depth == -math.inf else -depth
    nx = ca * ex + cr * ux
    ny = ca * ey + cr * uy
    nz = ca * ez + cr * uz
    if feature == FEATURE_FRONT or feature == FEATURE_BACK:
        return sd, nx, ny, nz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, feature
    # the turning of the radial direction, n_u (I - e e^T - u u^T) / rho with I - e e^T - u u^T = t t^T,
    # t = e x u; at a rim also the turning in the (e, u) plane, sign(sd) (e e^T + u u^T - n n^T) / dist
    kt = cr / rho if rho > 0.0 else 0.0
    tx = ey * uz - ez * uy
    ty = ez * ux - ex * uz
    tz = ex * uy - ey * ux
    kp = 0.0
    if feature == FEATURE_RIM:
        kp = 1.0 / dist if sd > 0.0 else -1.0 / dist
    return (sd, nx, ny, nz,
            kp * (ex * ex + ux * ux - nx * nx) + kt * tx * tx,
            kp * (ey * ey + uy * uy - ny * ny) + kt * ty * ty,
            kp * (ez * ez + uz * uz - nz * nz) + kt * tz * tz,
            kp * (ex * ey + ux * uy - nx * ny) + kt * tx * ty,
            kp * (ex * ez + ux * uz - nx * nz) + kt * tx * tz,
            kp * (ey * ez + uy * uz - ny * nz) + kt * ty * tz,
            feature)


@jit_step(inline="always")
def bounding_radius_m(shape):
    """Radius of the sphere about the anchor's COG that holds every section's cylinder (the whole surface) [m]."""
    r2 = 0.0
    for i in range(shape.shape[0]):
        r2 = max(r2, max(shape[i, CS_FRONT] ** 2, shape[i, CS_BACK] ** 2) + shape[i, CS_RADIUS] ** 2)
    return math.sqrt(r2)


@jit_step(inline="always")
def within_reach(px, py, pz, body_state, shape, margin_m=0.0):
    """Whether a point lies inside the cylinder that bounds the anchor, grown by ``margin_m`` [m] on every side
    (cheap test before the contact law)."""
    rx, ry, rz, a = from_cog(px, py, pz, body_state)
    if a > shape[0, CS_FRONT] + margin_m or a < shape[shape.shape[0] - 1, CS_BACK] - margin_m:
        return False
    rho2 = rx * rx + ry * ry + rz * rz - a * a
    for i in range(shape.shape[0]):
        if rho2 <= (shape[i, CS_RADIUS] + margin_m) ** 2:
            return True
    return False


@jit_step
def length_on_surface(node_pos, seg_i, seg_f, first_seg, n_segs, body_state, shape, tolerance_m):
    """Unstretched length of the segments ``first_seg`` .. ``first_seg + n_segs - 1`` with both ends within
    ``tolerance_m`` of the anchor's surface or inside it [m] (a line resting on the anchor)."""
    total = 0.0
    for s in range(first_seg, first_seg + n_segs):
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        da = surface_distance(node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], body_state, shape)[0]
        db = surface_distance(node_pos[b, 0], node_pos[b, 1], node_pos[b, 2], body_state, shape)[0]
        if da <= tolerance_m and db <= tolerance_m:
            total += seg_f[s, SF_L0]
    return total


SEGMENT_SAMPLES = 16  # points of a segment sampled for its deepest one inside the anchor
GOLDEN_STEPS = 24  # golden-section steps that refine it (the bracket shrinks to 1e-5 of its initial width)
INSIDE_TOLERANCE_M = 1e-9  # deeper than this counts as inside (a line's end on the surface rounds either way)


@jit_step
def _depth_along(ax, ay, az, bx, by, bz, t, body_state, shape):
    """Depth [m] of the point a + t (b - a) inside the anchor's surface (negative: outside)."""
    return -surface_distance(ax + t * (bx - ax), ay + t * (by - ay), az + t * (bz - az), body_state, shape)[0]


@jit_step
def segment_depth(ax, ay, az, bx, by, bz, body_state, shape):
    """The deepest point of the straight segment from a to b inside the anchor's surface: (depth [m], t), the point
    at a + t (b - a); the depth is negative where the whole segment stays outside.

    The points where the deepest lies in closed form are tried (:func:`_kink_candidates`): the ends, the closest
    approach to the axis and the crossings of a shaft's depth with an end face's, where the depth along the
    segment has its kink. On a one-cylinder anchor these hold the deepest point wherever the segment cuts in (the
    depth there is the least of the shaft's, concave, and the faces', linear). On a stepped one, the segment is
    also sampled at ``SEGMENT_SAMPLES`` + 1 points and the deepest refined by golden-section search between its
    neighbours (exact within one cylinder, the deepest of the sampled ones elsewhere); the search alone finds a
    kink to about 1e-6 of the segment's length, which at a contact's stiffness is a force of a hundred newtons.
    """
    if shape.shape[0] == 1:
        best, best_t = _try(ax, ay, az, bx, by, bz, 0.0, body_state, shape, -math.inf, 0.0)
        best, best_t = _try(ax, ay, az, bx, by, bz, 1.0, body_state, shape, best, best_t)
        return _kink_candidates(ax, ay, az, bx, by, bz, body_state, shape, best, best_t)
    best_t = 0.0
    best = -math.inf
    for i in range(SEGMENT_SAMPLES + 1):
        t = i / SEGMENT_SAMPLES
        d = _depth_along(ax, ay, az, bx, by, bz, t, body_state, shape)
        if d > best:
            best = d
            best_t = t
    lo = max(0.0, best_t - 1.0 / SEGMENT_SAMPLES)
    hi = min(1.0, best_t + 1.0 / SEGMENT_SAMPLES)
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    t1 = hi - ratio * (hi - lo)
    t2 = lo + ratio * (hi - lo)
    d1 = _depth_along(ax, ay, az, bx, by, bz, t1, body_state, shape)
    d2 = _depth_along(ax, ay, az, bx, by, bz, t2, body_state, shape)
    for _ in range(GOLDEN_STEPS):
        if d1 >= d2:
            hi = t2
            t2 = t1
            d2 = d1
            t1 = hi - ratio * (hi - lo)
            d1 = _depth_along(ax, ay, az, bx, by, bz, t1, body_state, shape)
        else:
            lo = t1
            t1 = t2
            d1 = d2
            t2 = lo + ratio * (hi - lo)
            d2 = _depth_along(ax, ay, az, bx, by, bz, t2, body_state, shape)
    if d1 > best:
        best = d1
        best_t = t1
    if d2 > best:
        best = d2
        best_t = t2
    return _kink_candidates(ax, ay, az, bx, by, bz, body_state, shape, best, best_t)


@jit_step
def _try(ax, ay, az, bx, by, bz, t, body_state, shape, best, best_t):
    """The deeper of (best, best_t) and the point at t, where t lies on the segment."""
    if 0.0 <= t <= 1.0:
        d = _depth_along(ax, ay, az, bx, by, bz, t, body_state, shape)
        if d >= best:
            return d, t
    return best, best_t


@jit_step
def _kink_candidates(ax, ay, az, bx, by, bz, body_state, shape, best, best_t):
    """:func:`segment_depth`'s closed-form candidates, per section: the segment's closest approach to the axis
    (where the shaft's depth peaks) and the points where the shaft's depth R - rho(t) equals an end face's, with
    a(t) and the radial vector q(t) linear in t: (|q1|^2 - d^2) t^2 + 2 (q0.q1 - c d) t + |q0|^2 - c^2 = 0 for
    rho = c + d t. Returns the deepest of them and (best, best_t)."""
    a0, q0x, q0y, q0z = radial_part(ax, ay, az, body_state)
    ab, qbx, qby, qbz = radial_part(bx, by, bz, body_state)
    a1 = ab - a0
    q1x = qbx - q0x
    q1y = qby - q0y
    q1z = qbz - q0z
    q00 = q0x * q0x + q0y * q0y + q0z * q0z
    q01 = q0x * q1x + q0y * q1y + q0z * q1z
    q11 = q1x * q1x + q1y * q1y + q1z * q1z
    if q11 > 0.0:
        best, best_t = _try(ax, ay, az, bx, by, bz, -q01 / q11, body_state, shape, best, best_t)
    for i in range(shape.shape[0]):
        radius = shape[i, CS_RADIUS]
        for face, sign in ((shape[i, CS_BACK], 1.0), (shape[i, CS_FRONT], -1.0)):
            # R - rho = sign (a(t) - face): rho = c + d t
            c = radius - sign * (a0 - face)
            d = -sign * a1
            qa = q11 - d * d
            qb = 2.0 * (q01 - c * d)
            qc = q00 - c * c
            if abs(qa) > 1e-14 * (q11 + d * d):
                disc = qb * qb - 4.0 * qa * qc
                if disc >= 0.0:
                    root = math.sqrt(disc)
                    for t in ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)):
                        if c + d * t >= 0.0:
                            best, best_t = _try(ax, ay, az, bx, by, bz, t, body_state, shape, best, best_t)
            elif qb != 0.0:
                t = -qc / qb
                if c + d * t >= 0.0:
                    best, best_t = _try(ax, ay, az, bx, by, bz, t, body_state, shape, best, best_t)
    return best, best_t


@jit_step
def deepest_segment_point(node_pos, seg_i, body_state, shape):
    """How deep the deepest point of any active segment, its interior included, lies inside the anchor's surface
    [m] (0 where none lies more than ``INSIDE_TOLERANCE_M`` inside), and that segment's index (-1 where none)."""
    deepest = 0.0
    which = -1
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        reach = segment_axis(node_pos, a, b)[0]  # a segment that meets the anchor has both ends this close
        if not within_reach(node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], body_state, shape, reach):
            continue
        d, _ = segment_depth(node_pos[a, 0], node_pos[a, 1], node_pos[a, 2], node_pos[b, 0], node_pos[b, 1],
                             node_pos[b, 2], body_state, shape)
        if d > deepest and d > INSIDE_TOLERANCE_M:
            deepest = d
            which = s
    return deepest, which

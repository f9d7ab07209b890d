"""Statics of the lumped-mass line in a vertical plane without current: the discrete model's own equilibrium.

The static solver's first guess places a line's nodes where the discrete model (point weights at the nodes,
straight elastic segments) is in equilibrium, not on the continuous catenary: near a touchdown with a small
horizontal force the catenary bends within one segment, where chords and arcs differ most. Every segment carries
the horizontal force H; walking along the line the vertical force grows by each node's weight, and a segment of
unstretched length l0 under tension T spans l0 (1 + T / EA) along its direction.

:func:`discrete_hang` hangs a line fully suspended between two points; :func:`discrete_grounded` lays a line
across a flat, frictionless seabed: each suspended part rises from a touchdown node that the seabed holds (the
segment leaving it carries a vertical force between zero and the node's weight, so the touchdown slides along
the line continuously; where both parts rise from one node, their two forces together), both parts carry the
same H, and the grounded segments between them lie straight,
stretched by H. A line longer than the span needs even hanging straight down (H -> 0) lays the rest on the seabed
without tension: evenly shortened segments, or a fold where the room is less than half the grounded length. The
horizontal force is found by a bracketed Newton iteration with the exact derivative of the span, from the
continuous catenary's value.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit

SPAN_ITERATIONS = 60
SPAN_TOLERANCE = 1e-10  # relative to the line's length
VERTICAL_ITERATIONS = 40
FOLD_BELOW = 0.5  # excess grounded line is folded where the room between the touchdowns is below this share of it


@jit
def discrete_walk(h, va, node_w, seg_l0, seg_ea, out):
    """Node positions of the lumped-mass line in equilibrium under (H, V_A) at its end A, relative to A.

    The exact statics of the discrete model without current or seabed: every segment carries the horizontal force
    h, segment k the vertical force V_k = V_A + (weights of nodes 1..k), and is stretched by its tension. Writes
    the (horizontal, vertical) offsets of nodes 1..n into ``out`` (``node_w[k]``: weight of node k [N]) and
    returns those of the last node.
    """
    x = 0.0
    z = 0.0
    v = va
    for k in range(seg_l0.shape[0]):
        if k > 0:
            v += node_w[k]
        t = math.sqrt(h * h + v * v)
        stretched = seg_l0[k] * (1.0 + t / seg_ea[k])
        if t > 0.0:
            x += stretched * h / t
            z += stretched * v / t
        out[k, 0] = x
        out[k, 1] = z
    return x, z


@jit
def _end_force(h, dz, va, node_w, seg_l0, seg_ea):
    """Vertical force at end A (+ up) for which the suspended line under horizontal force h rises dz by its last
    node (the rise grows with it: bracketed Newton); returns (V_A, span x, dx/dH along the solution)."""
    lo = -math.inf
    hi = math.inf
    weight = 0.0
    for k in range(node_w.shape[0]):
        weight += node_w[k]
    x, z, xv, zv, xh, zh = _side_walk(h, va, 0, False, node_w, seg_l0, seg_ea)
    for _ in range(SPAN_ITERATIONS):
        f = z - dz
        if abs(f) <= 1e-12 * (1.0 + abs(dz)) or hi - lo <= 1e-14 * (1.0 + abs(va)):
            break
        if f < 0.0:
            lo = va
        else:
            hi = va
        step = va - f / zv if zv > 0.0 else math.nan
        if not (lo < step < hi):
            if lo > -math.inf and hi < math.inf:
                step = 0.5 * (lo + hi)
            elif lo > -math.inf:
                step = lo + max(lo - va, 0.0) + weight + h
            else:
                step = hi - weight - h
        va = step
        x, z, xv, zv, xh, zh = _side_walk(h, va, 0, False, node_w, seg_l0, seg_ea)
    return va, x, xh - xv * zh / zv if zv > 0.0 else xh


@jit
def discrete_hang(dx, dz, h0, va0, node_w, seg_l0, seg_ea, out):
    """(H, V_A) of the suspended lumped-mass line whose last node reaches (dx, dz) from end A, from a guess (the
    continuous catenary's); writes the node offsets into ``out`` and returns (H, V_A, converged). The span grows
    with H once V_A keeps the rise: bracketed Newton on H, each step solving for V_A."""
    total = 0.0
    weight = 0.0
    for k in range(seg_l0.shape[0]):
        total += seg_l0[k]
        weight += node_w[k]
    h_min = 1e-9 * weight + 1e-6
    h = max(h0, h_min)
    va = va0
    lo = 0.0
    hi = math.inf
    found = False
    for _ in range(SPAN_ITERATIONS):
        va, x, slope = _end_force(h, dz, va, node_w, seg_l0, seg_ea)
        g = x - dx
        if abs(g) <= SPAN_TOLERANCE * total:
            found = True
            break
        if g > 0.0:
            hi = h
        else:
            lo = h
        step = h - g / slope if slope > 0.0 else -1.0
        if not (lo < step < hi):
            step = 0.5 * (lo + hi) if hi < math.inf else 2.0 * h
        if step <= h_min and g > 0.0 and h <= h_min:
            break  # shorter than the span needs even with no horizontal force: not a suspended line
        h = max(step, h_min)
    discrete_walk(h, va, node_w, seg_l0, seg_ea, out)
    return h, va, found


@jit
def _side_segment(i, t, toward_a, v, node_w):
    """Step i of a walk from touchdown node t toward end A or end B: the segment's index and the vertical force
    it carries, ``v`` being the force the step before carried (the first segment's force for i = 0)."""
    k = t - 1 - i if toward_a else t + i
    if i > 0:
        v += node_w[k + 1] if toward_a else node_w[k]
    return k, v


@jit
def _side_walk(h, v1, t, toward_a, node_w, seg_l0, seg_ea):
    """Walk from touchdown node t toward end A (node 0) or end B (node n), the segment leaving t carrying the
    vertical force v1: returns the span (x, z) and its derivatives (dx/dv1, dz/dv1, dx/dH, dz/dH)."""
    n = seg_l0.shape[0]
    x = 0.0
    z = 0.0
    xv = 0.0
    zv = 0.0
    xh = 0.0
    zh = 0.0
    v = v1
    count = t if toward_a else n - t
    for i in range(count):
        k, v = _side_segment(i, t, toward_a, v, node_w)
        tension = math.sqrt(h * h + v * v)
        l0 = seg_l0[k]
        inv_ea = 1.0 / seg_ea[k]
        t3 = tension * tension * tension
        x += l0 * (h / tension + h * inv_ea)
        z += l0 * (v / tension + v * inv_ea)
        xv -= l0 * h * v / t3
        zv += l0 * (h * h / t3 + inv_ea)
        xh += l0 * (v * v / t3 + inv_ea)
        zh -= l0 * h * v / t3
    return x, z, xv, zv, xh, zh


@jit
def _touchdown(h, rise, t, toward_a, node_w, seg_l0, seg_ea):
    """Touchdown node (searched from t) and vertical force v1 of the segment leaving it for which the suspended
    part toward one end rises ``rise``; returns (found, t, v1, span x, dx/dH along the solution)."""
    n = seg_l0.shape[0]
    more = 1 if toward_a else -1  # the direction of t that suspends more of the line
    z0 = z1 = 0.0
    found = False
    for _ in range(n + 2):
        if t < 1 or t > n - 1:
            break
        z0 = _side_walk(h, 0.0, t, toward_a, node_w, seg_l0, seg_ea)[1]
        if rise < z0:
            t -= more
            continue
        z1 = _side_walk(h, node_w[t], t, toward_a, node_w, seg_l0, seg_ea)[1]
        if rise > z1:
            t += more
            continue
        found = True
        break
    if not found:
        return False, t, 0.0, 0.0, 0.0
    lo = 0.0
    hi = node_w[t]
    v = lo + (hi - lo) * (rise - z0) / (z1 - z0) if z1 > z0 else lo
    x, z, xv, zv, xh, zh = _side_walk(h, v, t, toward_a, node_w, seg_l0, seg_ea)
    for _ in range(VERTICAL_ITERATIONS):
        f = z - rise
        if abs(f) <= 1e-12 * (1.0 + rise):
            break
        if f < 0.0:
            lo = v
        else:
            hi = v
        step = v - f / zv if zv > 0.0 else -1.0
        v = step if lo < step < hi else 0.5 * (lo + hi)
        x, z, xv, zv, xh, zh = _side_walk(h, v, t, toward_a, node_w, seg_l0, seg_ea)
        if hi - lo <= 1e-14 * (1.0 + hi):
            break
    dv_dh = -zh / zv if zv > 0.0 else 0.0
    return True, t, v, x, xh + xv * dv_dh


@jit
def discrete_grounded(dx, dz, seabed_dz, h0, t_a, t_b, node_w, seg_l0, seg_ea, out):
    """Lumped-mass line from end A to end B (at horizontal distance dx and height dz from A) across the seabed
    ``seabed_dz`` below A, touching down near interior nodes ``t_a`` (toward A) and ``t_b`` (toward B).

    ``node_w[k]``: weight of local node k [N]; ``h0``: a guess of H (the continuous catenary's). Writes the
    (horizontal, vertical) offsets from A of nodes 1..n-1 into ``out`` and returns (H [N], mode, found): mode 1
    two touchdowns with the grounded segments stretched by H, 2 more line than the span needs (H = 0, the
    grounded segments evenly shortened, without tension); not found where the line lifts off the seabed.
    """
    n = seg_l0.shape[0]
    total = 0.0
    weight = 0.0
    for k in range(n):
        total += seg_l0[k]
        weight += node_w[k]
    h_min = 1e-9 * weight + 1e-6
    rise_a = -seabed_dz
    rise_b = dz - seabed_dz
    h = max(h0, h_min)
    lo = 0.0
    hi = math.inf
    mode = 0
    v_a = v_b = x_a = x_b = 0.0
    for _ in range(SPAN_ITERATIONS):
        ok_a, t_a, v_a, x_a, dxa = _touchdown(h, rise_a, t_a, True, node_w, seg_l0, seg_ea)
        ok_b, t_b, v_b, x_b, dxb = _touchdown(h, rise_b, t_b, False, node_w, seg_l0, seg_ea)
        if not ok_a or not ok_b or t_a > t_b or (t_a == t_b and v_a + v_b > node_w[t_a]):
            # the suspended parts need more than the whole line (or lift their one shared node): H too large
            t_a = min(max(t_a, 1), n - 1)
            t_b = min(max(t_b, t_a), n - 1)
            hi = h
            h = 0.5 * (max(lo, h_min) + hi)
            mode = 0
            continue
        ground = 0.0
        dground = 0.0
        for k in range(t_a, t_b):
            ground += seg_l0[k] * (1.0 + h / seg_ea[k])
            dground += seg_l0[k] / seg_ea[k]
        g = x_a + x_b + ground - dx
        mode = 1
        if abs(g) <= SPAN_TOLERANCE * total:
            break
        if g > 0.0 and h <= h_min:
            mode = 2
            break
        if g > 0.0:
            hi = h
        else:
            lo = h
        slope = dxa + dxb + dground
        step = h - g / slope if slope > 0.0 else -1.0
        if not (lo < step < hi):
            step = 0.5 * (lo + hi) if hi < math.inf else 2.0 * h
        h = max(step, h_min)
    if mode == 0:
        return h, 0, False
    _place_side(h, v_a, t_a, True, x_a, seabed_dz, node_w, seg_l0, seg_ea, out)
    _place_side(h, v_b, t_b, False, dx - x_b, seabed_dz, node_w, seg_l0, seg_ea, out)
    room = dx - x_b - x_a  # horizontal room between the touchdowns
    grounded = 0.0
    for k in range(t_a, t_b):
        grounded += seg_l0[k]
    fold = 0.5 * (grounded - room) if room < FOLD_BELOW * grounded else 0.0
    x = x_a
    arc = 0.0
    for k in range(t_a, t_b + 1):
        if mode == 1:
            out[k - 1, 0] = x
        elif fold > 0.0:  # a fold at the natural length: back under end A, then on toward B
            out[k - 1, 0] = x_a - arc if arc <= fold else x_a - 2.0 * fold + arc
        else:  # the excess spread evenly: every grounded segment a little short, without tension
            out[k - 1, 0] = x_a + room * arc / grounded
        out[k - 1, 1] = seabed_dz
        if k < t_b:
            x += seg_l0[k] * (1.0 + h / seg_ea[k])
            arc += seg_l0[k]
    return h, mode, True


@jit
def _place_side(h, v1, t, toward_a, x_td, z_td, node_w, seg_l0, seg_ea, out):
    """Offsets of the suspended nodes rising from touchdown node t (at x_td, z_td) toward one end into ``out``."""
    n = seg_l0.shape[0]
    x = 0.0
    z = 0.0
    v = v1
    count = t if toward_a else n - t
    for i in range(count):
        k, v = _side_segment(i, t, toward_a, v, node_w)
        tension = math.sqrt(h * h + v * v)
        stretched = seg_l0[k] * (1.0 + tension / seg_ea[k])
        x += stretched * h / tension
        z += stretched * v / tension
        node = k if toward_a else k + 1  # the node this segment reaches
        if 1 <= node <= n - 1:
            out[node - 1, 0] = x_td - x if toward_a else x_td + x
            out[node - 1, 1] = z_td + z

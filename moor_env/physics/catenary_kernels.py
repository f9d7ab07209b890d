"""Numba kernels of the analytic elastic catenary (``physics/catenary.py`` gives the equations and references):
the static solver's first guess in microseconds.

The kernels take a line as arrays (weight per metre, EA, unstretched length per section, from end A to end B).
:func:`hang_line` places a line's nodes between two points, fully suspended or with a grounded middle (touchdown on
both sides of a flat, frictionless seabed), and lays any length that cannot hang as a zero-tension fold on the
seabed. ``physics/discrete_catenary.py`` turns that shape into the lumped-mass model's own equilibrium.
"""

from __future__ import annotations

import math

from moor_env.physics._jit import jit

ROOT_ITERATIONS = 200
NEWTON_ITERATIONS = 50


@jit
def _piece(h, v0, w, ea, ds):
    """(dx, dz) over an unstretched length ds of one section, vertical force v0 at its start (+ up) [m]."""
    v1 = v0 + w * ds
    stretch = (v1 * v1 - v0 * v0) / (2.0 * w * ea) if w > 0.0 else 0.0
    if h <= 0.0:
        return 0.0, math.copysign(ds, v0 + v1) + stretch
    if w <= 0.0:
        t = math.sqrt(h * h + v0 * v0)
        return ds * (h / t) * (1.0 + t / ea), ds * (v0 / t) * (1.0 + t / ea)
    dx = h / w * (math.asinh(v1 / h) - math.asinh(v0 / h)) + h * ds / ea
    dz = h / w * (math.sqrt(1.0 + (v1 / h) ** 2) - math.sqrt(1.0 + (v0 / h) ** 2)) + stretch
    return dx, dz


@jit
def walk(h, v0, sec_w, sec_ea, sec_len, a0, a1):
    """(dx, dz) from unstretched arc a0 to a1 >= a0 with vertical force v0 at a0, and the force at a1."""
    x = 0.0
    z = 0.0
    v = v0
    start = 0.0
    for k in range(sec_len.shape[0]):
        end = start + sec_len[k]
        lo = max(a0, start)
        hi = min(a1, end)
        if hi > lo:
            dx, dz = _piece(h, v, sec_w[k], sec_ea[k], hi - lo)
            x += dx
            z += dz
            v += sec_w[k] * (hi - lo)
        start = end
    return x, z, v


@jit
def walk_arcs(h, v0, sec_w, sec_ea, sec_len, arcs, out):
    """(dx, dz) from arc 0 (vertical force v0 there) to each of the ascending unstretched ``arcs`` into ``out``."""
    x = 0.0
    z = 0.0
    v = v0
    a = 0.0
    for i in range(arcs.shape[0]):
        dx, dz, v = walk(h, v, sec_w, sec_ea, sec_len, a, arcs[i])
        x += dx
        z += dz
        a = arcs[i]
        out[i, 0] = x
        out[i, 1] = z


@jit
def _illinois(f_lo, f_hi, lo, hi, target, kind, h, p0, sec_w, sec_ea, sec_len, total):
    """Root of g(u) = target on [lo, hi] (g increasing, g(lo) - target = f_lo < 0 < f_hi) by the Illinois method.

    ``kind`` 0: u = V_A of a suspended line with H = h, g = z at its end B; 1: u = suspended length rising
    from a touchdown at arc ``total - u`` (toward end B), g = its rise; 2: the same toward end A (arc ``u``).
    """
    side = 0
    u = lo
    for _ in range(ROOT_ITERATIONS):
        u = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        g = _evaluate(kind, u, h, p0, sec_w, sec_ea, sec_len, total) - target
        if abs(g) < 1e-9 * (1.0 + abs(target)) or hi - lo < 1e-12 * (1.0 + abs(u)):
            return u
        if g < 0.0:
            lo, f_lo = u, g
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = u, g
            if side == 1:
                f_lo *= 0.5
            side = 1
    return u


@jit
def _evaluate(kind, u, h, p0, sec_w, sec_ea, sec_len, total):
    if kind == 0:
        return walk(h, u, sec_w, sec_ea, sec_len, 0.0, total)[1]
    if kind == 1:
        return walk(h, 0.0, sec_w, sec_ea, sec_len, total - u, total)[1]
    return _walk_back(h, sec_w, sec_ea, sec_len, u, 0.0)[1]


@jit
def _walk_back(h, sec_w, sec_ea, sec_len, a_touchdown, a_stop):
    """(dx, dz, V) walking from a touchdown at arc ``a_touchdown`` (V = 0 there) back toward end A to arc
    ``a_stop`` (<= a_touchdown): :func:`walk` along the line turned end for end."""
    total = 0.0
    for k in range(sec_len.shape[0]):
        total += sec_len[k]
    return walk(h, 0.0, sec_w[::-1], sec_ea[::-1], sec_len[::-1], total - a_touchdown, total - a_stop)


@jit
def suspended_va(h, dz, sec_w, sec_ea, sec_len, total, weight):
    """Vertical force at end A (+ up) of a suspended line with horizontal force h whose end B is dz above A."""
    big = 10.0 * (weight + h) + 1.0
    lo = -big
    hi = big
    f_lo = walk(h, lo, sec_w, sec_ea, sec_len, 0.0, total)[1] - dz
    f_hi = walk(h, hi, sec_w, sec_ea, sec_len, 0.0, total)[1] - dz
    for _ in range(60):
        if f_lo < 0.0:
            break
        lo *= 4.0
        f_lo = walk(h, lo, sec_w, sec_ea, sec_len, 0.0, total)[1] - dz
    for _ in range(60):
        if f_hi > 0.0:
            break
        hi *= 4.0
        f_hi = walk(h, hi, sec_w, sec_ea, sec_len, 0.0, total)[1] - dz
    return _illinois(f_lo, f_hi, lo, hi, dz, 0, h, 0.0, sec_w, sec_ea, sec_len, total)


@jit
def _rise_length(h, rise, toward_b, sec_w, sec_ea, sec_len, total):
    """Suspended length that rises ``rise`` from a touchdown (V = 0), walking toward end B or end A."""
    if rise <= 0.0:
        return 0.0
    kind = 1 if toward_b else 2
    f_lo = -rise
    f_hi = _evaluate(kind, total, h, 0.0, sec_w, sec_ea, sec_len, total) - rise
    if f_hi <= 0.0:
        return total + 1.0  # the whole line cannot rise that far
    return _illinois(f_lo, f_hi, 0.0, total, rise, kind, h, 0.0, sec_w, sec_ea, sec_len, total)


@jit
def _grounded_span(h, rise_a, rise_b, sec_w, sec_ea, sec_len, total, ea_ground):
    """Horizontal span of a line touching down on both sides for horizontal force h: (span, s_a, s_b);
    span = -1 where the two suspended parts need more than the whole line."""
    s_b = _rise_length(h, rise_b, True, sec_w, sec_ea, sec_len, total)
    s_a = _rise_length(h, rise_a, False, sec_w, sec_ea, sec_len, total)
    grounded = total - s_a - s_b
    if grounded < 0.0:
        return -1.0, s_a, s_b
    x_b = walk(h, 0.0, sec_w, sec_ea, sec_len, total - s_b, total)[0]
    x_a = _walk_back(h, sec_w, sec_ea, sec_len, s_a, 0.0)[0]
    return x_a + x_b + grounded * (1.0 + h / ea_ground), s_a, s_b


@jit
def hang_line(dx, dz, seabed_dz, sec_w, sec_ea, sec_len, arcs, out):
    """Static shape of a line from end A to end B (B at horizontal distance dx >= 0 and height dz from A).

    ``seabed_dz`` is the seabed's height relative to A (<= 0). Writes (horizontal, vertical) offsets from A of
    the points at unstretched arcs ``arcs`` into ``out`` and returns (H [N], V_A [N], mode): mode 0 suspended,
    1 grounded between two touchdowns, 2 grounded with a zero-tension fold (more line than the span needs).
    """
    n_sec = sec_len.shape[0]
    total = 0.0
    weight = 0.0
    for k in range(n_sec):
        total += sec_len[k]
        weight += sec_w[k] * sec_len[k]
    # suspended: Newton's method on (H, V_A); where it does not converge, nested bracketing (H from the
    # horizontal span, increasing in H)
    h, va, converged = _suspended_newton(dx, dz, sec_w, sec_ea, sec_len, total, weight)
    if not converged:
        h = _suspended_h(dx, dz, sec_w, sec_ea, sec_len, total, weight, 1e-9 * weight + 1e-6, 10.0 * weight + 1.0)
        va = suspended_va(h, dz, sec_w, sec_ea, sec_len, total, weight)
    low = 0.0
    if va < 0.0 < va + weight:
        cum = 0.0
        s_low = total
        for k in range(n_sec):
            if cum + sec_w[k] * sec_len[k] >= -va:
                s_low = _arc_at(sec_len, k) + (-va - cum) / sec_w[k]
                break
            cum += sec_w[k] * sec_len[k]
        low = walk(h, va, sec_w, sec_ea, sec_len, 0.0, s_low)[1]
    elif va + weight <= 0.0:
        low = dz
    if low >= seabed_dz:
        for i in range(arcs.shape[0]):
            x, z, _ = walk(h, va, sec_w, sec_ea, sec_len, 0.0, arcs[i])
            out[i, 0] = x
            out[i, 1] = z
        return h, va, 0
    return _hang_grounded(dx, dz, seabed_dz, sec_w, sec_ea, sec_len, total, weight, arcs, out)


@jit
def _arc_at(sec_len, k):
    a = 0.0
    for j in range(k):
        a += sec_len[j]
    return a


@jit
def _walk_jacobian(h, v0, sec_w, sec_ea, sec_len):
    """(x, z) of the whole line from end A (H = h > 0, vertical force v0 there, every section heavy) and their
    partial derivatives (dx/dH, dx/dV0, dz/dH, dz/dV0): the sums of :func:`_piece`'s closed-form derivatives."""
    x = z = x_h = x_v = z_h = z_v = 0.0
    v = v0
    for k in range(sec_len.shape[0]):
        w, ea, ds = sec_w[k], sec_ea[k], sec_len[k]
        r0, r1 = v / h, (v + w * ds) / h
        s0, t1 = math.sqrt(1.0 + r0 * r0), math.sqrt(1.0 + r1 * r1)
        x += h / w * (math.asinh(r1) - math.asinh(r0)) + h * ds / ea
        z += h / w * (t1 - s0) + ((v + w * ds) ** 2 - v * v) / (2.0 * w * ea)
        x_h += (math.asinh(r1) - math.asinh(r0) - r1 / t1 + r0 / s0) / w + ds / ea
        x_v += (1.0 / t1 - 1.0 / s0) / w
        z_h += (1.0 / t1 - 1.0 / s0) / w
        z_v += (r1 / t1 - r0 / s0) / w + ds / ea
        v += w * ds
    return x, z, x_h, x_v, z_h, z_v


@jit
def _suspended_newton(dx, dz, sec_w, sec_ea, sec_len, total, weight):
    """(H, V_A, converged) of the suspended line spanning (dx, dz) by Newton's method on both, from the
    parabola's estimate (V_A = H dz / dx - W / 2, H from its sag); H is kept within a factor ten per step.

    Why: the nested bracketing it stands in for takes some hundred passes over the line; this takes a few. It
    is not tried on a vertical or nearly vertical span, nor on a line with a section that does not sink (the
    closed form needs w > 0), and reports failure after ``NEWTON_ITERATIONS``."""
    if dx <= 1e-3 * total:
        return 0.0, 0.0, False
    for k in range(sec_len.shape[0]):
        if sec_w[k] <= 0.0:
            return 0.0, 0.0, False
    chord = math.sqrt(dx * dx + dz * dz)
    # a parabola of length total over the chord sags by sqrt(3 chord (total - chord) / 8); H = W dx / (8 sag)
    sag = math.sqrt(max(3.0 * chord * (total - chord) / 8.0, 1e-6 * total * total))
    h = weight * dx / (8.0 * sag)
    va = h * dz / dx - 0.5 * weight
    tol = 1e-10 * (total + chord)
    for _ in range(NEWTON_ITERATIONS):
        x, z, x_h, x_v, z_h, z_v = _walk_jacobian(h, va, sec_w, sec_ea, sec_len)
        fx, fz = x - dx, z - dz
        if abs(fx) < tol and abs(fz) < tol:
            return h, va, True
        det = x_h * z_v - x_v * z_h
        if not (det != 0.0 and det == det):
            return h, va, False
        step_h = -(z_v * fx - x_v * fz) / det
        step_v = -(x_h * fz - z_h * fx) / det
        if h + step_h < 0.1 * h or h + step_h > 10.0 * h:
            f = (-0.9 * h if h + step_h < 0.1 * h else 9.0 * h) / step_h
            step_h *= f
            step_v *= f
        h += step_h
        va += step_v
    return h, va, False


@jit
def _suspended_h(dx, dz, sec_w, sec_ea, sec_len, total, weight, h_lo, h_hi):
    """H of the suspended line spanning dx (bisection on log H)."""
    lo = math.log(h_lo)
    hi = math.log(h_hi)
    for _ in range(60):
        h = math.exp(hi)
        if walk(h, suspended_va(h, dz, sec_w, sec_ea, sec_len, total, weight), sec_w, sec_ea, sec_len, 0.0,
                total)[0] >= dx:
            break
        hi += 2.0
    for _ in range(ROOT_ITERATIONS):
        mid = 0.5 * (lo + hi)
        h = math.exp(mid)
        x = walk(h, suspended_va(h, dz, sec_w, sec_ea, sec_len, total, weight), sec_w, sec_ea, sec_len, 0.0,
                 total)[0]
        if x < dx:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-10:
            break
    return math.exp(0.5 * (lo + hi))


@jit
def _hang_grounded(dx, dz, seabed_dz, sec_w, sec_ea, sec_len, total, weight, arcs, out):
    rise_a = -seabed_dz
    rise_b = dz - seabed_dz
    ea_ground = sec_ea[0]
    lo = math.log(1e-9 * weight + 1e-6)
    span_lo, s_a, s_b = _grounded_span(math.exp(lo), rise_a, rise_b, sec_w, sec_ea, sec_len, total, ea_ground)
    mode = 1
    h = math.exp(lo)
    if span_lo >= dx:
        mode = 2  # even hanging straight down the line is longer than the span: fold the rest on the seabed
    else:
        hi = math.log(10.0 * weight + 1.0)
        for _ in range(ROOT_ITERATIONS):
            mid = 0.5 * (lo + hi)
            span, _, _ = _grounded_span(math.exp(mid), rise_a, rise_b, sec_w, sec_ea, sec_len, total, ea_ground)
            if 0.0 <= span < dx:
                lo = mid
            else:
                hi = mid
            if hi - lo < 1e-10:
                break
        h = math.exp(0.5 * (lo + hi))
        span_lo, s_a, s_b = _grounded_span(h, rise_a, rise_b, sec_w, sec_ea, sec_len, total, ea_ground)
    x_td, _, v_top_a = _walk_back(h, sec_w, sec_ea, sec_len, s_a, 0.0)
    grounded = total - s_a - s_b
    stretch = 1.0 + h / ea_ground
    fold = 0.0
    if mode == 2:
        fold = 0.5 * max(grounded * stretch - (dx - x_td - walk(h, 0.0, sec_w, sec_ea, sec_len, total - s_b,
                                                                   total)[0]), 0.0)
    for i in range(arcs.shape[0]):
        a = arcs[i]
        if a <= s_a:
            px, pz, _ = _walk_back(h, sec_w, sec_ea, sec_len, s_a, a)
            out[i, 0] = x_td - px
            out[i, 1] = seabed_dz + pz
        elif a < total - s_b:
            along = (a - s_a) * stretch
            along = -along if along <= fold else along - 2.0 * fold  # a fold: back under end A, then on
            out[i, 0] = x_td + along
            out[i, 1] = seabed_dz
        else:
            x_b, z_b, _ = walk(h, 0.0, sec_w, sec_ea, sec_len, total - s_b, a)
            out[i, 0] = x_td + grounded * stretch - 2.0 * fold + x_b
            out[i, 1] = seabed_dz + z_b
    return h, -v_top_a, mode  # end A holds its suspended part: the line pulls it down

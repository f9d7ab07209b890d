"""Lines as nodes and segments: the mesh of a scene's lines, built by :func:`moor_env.compile.compile_scene`.

A line of sections (material, length, segment length) becomes a block of segment slots and a block of interior-node
slots, with spare slots for payout at a winch (``physics/layout.py`` describes the slots); its initial shape is a
polyline sampled at the segments' arc lengths (a first guess the statics replaces).
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics import layout as L

PAYOUT_EXTRA_FRACTION = 1.0  # capacity for paying out as much again as the initial line length
PAYOUT_EXTRA_SEGMENTS = 40


class MeshBuilder:
    """Accumulates nodes, segments and lines; turns them into arrays."""

    def __init__(self) -> None:
        self.node_kind: list[int] = []
        self.node_ref: list[int] = []
        self.node_line: list[int] = []
        self.node_f: list[list[float]] = []
        self.node_pos: list[np.ndarray] = []
        self.segs: list[tuple[int, int, int, int, int, float]] = []
        self.lines: list[list] = []

    def add_node(self, kind: int, pos, ref: int = -1, line: int = -1, mass=0.0, volume=0.0, cda=0.0, ca=0.0,
                 body_s=0.0) -> int:
        self.node_kind.append(kind)
        self.node_ref.append(ref)
        self.node_line.append(line)
        self.node_f.append([mass, volume, cda, ca, body_s])
        self.node_pos.append(np.asarray(pos, dtype=float))
        return len(self.node_kind) - 1

    def add_line(self, bottom: int, top: int, sections: list[tuple[int, float, float]], points: np.ndarray,
                 payout: bool, l_nom_top: float) -> int:
        """Add a line of ``sections`` = (material, length, segment length) from bottom to top.

        ``points`` is a (k, 3) polyline from the bottom node to the top node used as the initial shape.
        """
        line = len(self.lines)
        lengths: list[float] = []
        mats: list[int] = []
        for mat, length, seg_len in sections:
            n = max(1, int(math.ceil(length / seg_len - 1e-9)))
            lengths += [length / n] * n
            mats += [mat] * n
        nseg = len(lengths)
        extra = 0
        if payout:
            extra = max(PAYOUT_EXTRA_SEGMENTS, int(PAYOUT_EXTRA_FRACTION * sum(lengths) / l_nom_top))
        seg_cap = nseg + extra
        node_cap = seg_cap - 1
        positions = _points_at_arclength(points, np.cumsum(lengths)[:-1] / sum(lengths))
        node_start = len(self.node_kind)
        for k in range(node_cap):
            if k < nseg - 1:
                self.add_node(L.NODE_FREE, positions[k], line=line)
            else:
                self.add_node(L.NODE_INACTIVE, positions[-1] if nseg > 1 else points[-1], line=line)
        seg_start = len(self.segs)
        for k in range(seg_cap):
            if k < nseg:
                a = bottom if k == 0 else node_start + k - 1
                b = top if k == nseg - 1 else node_start + k
                self.segs.append((a, b, mats[k], line, 1, lengths[k]))
            else:
                self.segs.append((top, top, mats[-1], line, 0, l_nom_top))
        self.lines.append([seg_start, seg_cap, nseg, node_start, node_cap, bottom, top, int(payout), 0, l_nom_top])
        return line


def _points_at_arclength(points: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Points at the given fractions (0..1) of the arc length of a polyline."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    u = fractions * cum[-1]
    return np.stack([np.interp(u, cum, points[:, c]) for c in range(3)], axis=1).reshape(-1, 3)


def hanging_curve(start, end, length: float, seabed_z: float, n: int = 400) -> np.ndarray:
    """A first-guess hanging shape of given length between two points: the chord plus a parabolic sag,
    sized so that its arc length is ``length`` (within ``SAG_TOLERANCE`` of it), clipped at the seabed.

    The sag is found by the Illinois variant of regula falsi on a bracket: the arc length grows monotonically with
    the sag, and the search takes about nine evaluations (23 at most over 2000 random depths of 100-1500 m, spans
    up to 600 m and lengths up to twice the chord), a fraction of what bisection to the same tolerance takes.
    """
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    u = np.linspace(0.0, 1.0, n)
    chord = start[None, :] + u[:, None] * (end - start)[None, :]
    bulge = 4.0 * u * (1.0 - u)

    def curve(sag: float) -> np.ndarray:
        pts = chord.copy()
        pts[:, 2] = np.maximum(chord[:, 2] - sag * bulge, seabed_z)
        return pts

    def excess(sag: float) -> float:
        steps = np.diff(curve(sag), axis=0)
        return float(np.sum(np.sqrt(np.einsum("ij,ij->i", steps, steps)))) - length

    f_lo = excess(0.0)
    if f_lo >= 0.0:
        return curve(0.0)
    lo, hi = 0.0, max(length, 1.0)
    f_hi = excess(hi)
    while f_hi < 0.0 and hi < 1e7:
        lo, f_lo, hi = hi, f_hi, 2.0 * hi
        f_hi = excess(hi)
    if f_hi < 0.0:  # the seabed holds the middle: no sag reaches the length, the deepest shape is the guess
        return curve(hi)
    return curve(_illinois(excess, lo, f_lo, hi, f_hi, SAG_TOLERANCE * max(length, 1.0)))


SAG_TOLERANCE = 1e-12  # of the line length: the arc length's error where the sag search stops


def _illinois(f, lo: float, f_lo: float, hi: float, f_hi: float, tol: float, max_evaluations: int = 200) -> float:
    """A root of the increasing function ``f`` within the bracket [lo, hi] (f_lo < 0 <= f_hi) by the Illinois
    method: regula falsi whose end that stays put has its weight halved. Stops where |f| <= ``tol`` or the bracket
    has closed to rounding, and returns the end with the smaller |f| (the ends' own values, not their weights)."""
    w_lo, w_hi = f_lo, f_hi  # the interpolation weights; f_lo and f_hi stay the function's values
    side = 0
    for _ in range(max_evaluations):
        if hi - lo <= 1e-15 * hi:
            break
        x = hi - w_hi * (hi - lo) / (w_hi - w_lo)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        fx = f(x)
        if abs(fx) <= tol:
            return x
        if fx < 0.0:
            lo, f_lo, w_lo = x, fx, fx
            if side == -1:
                w_hi *= 0.5
            side = -1
        else:
            hi, f_hi, w_hi = x, fx, fx
            if side == 1:
                w_lo *= 0.5
            side = 1
    return hi if f_hi <= -f_lo else lo

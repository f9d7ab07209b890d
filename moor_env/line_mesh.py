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
    sized by bisection so that its arc length is ``length``, clipped at the seabed.
    """
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    u = np.linspace(0.0, 1.0, n)
    chord = start[None, :] + u[:, None] * (end - start)[None, :]

    def curve(sag: float) -> np.ndarray:
        pts = chord.copy()
        pts[:, 2] -= sag * 4.0 * u * (1.0 - u)
        pts[:, 2] = np.maximum(pts[:, 2], seabed_z)
        return pts

    def arclength(sag: float) -> float:
        return float(np.sum(np.linalg.norm(np.diff(curve(sag), axis=0), axis=1)))

    if arclength(0.0) >= length:
        return curve(0.0)
    lo, hi = 0.0, max(length, 1.0)
    while arclength(hi) < length and hi < 1e7:
        hi *= 2.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if arclength(mid) < length:
            lo = mid
        else:
            hi = mid
    return curve(0.5 * (lo + hi))

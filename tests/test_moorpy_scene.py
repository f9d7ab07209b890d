"""The MoorPy model of the hanging installation scene (``benchmarks/_moorpy_scene.py``) against our statics.

Measured on gjoa-500: release point within 1e-5 m, wire and mooring-line top tensions within 2e-6 relative;
the vertical chain's tension 0.22 % above ours (876.29 kN against 874.40 kN): ours is the top segment's
tension, at the middle of the chain's top 1 m segment, MoorPy's the tension at R, half a segment's submerged
weight (1.9 kN) higher. Tolerances: release point 0.5 m, top tensions 2 %. MoorPy is a test dependency.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from _moorpy_scene import moorpy_statics  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402


def test_gjoa_500_agrees_with_ours():
    ours = solve_statics(load_scene("gjoa-500"), progress=False)
    theirs = moorpy_statics({})
    assert theirs["failed"] is None, theirs["failed"]
    for a, b in zip(theirs["release_point_m"], ours.release_point_m, strict=True):
        assert abs(a - b) < 0.5
    for name, tension in ours.top_tensions_n.items():
        assert theirs["top_tensions_n"][name] == pytest.approx(tension, rel=0.02), name

"""The first-guess hanging shape of a line (``moor_env/line_mesh.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env.line_mesh import SAG_TOLERANCE, hanging_curve


def _arc_length_m(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


@pytest.mark.parametrize(("start", "end", "length_m", "seabed_z_m"), [
    ((0.0, 0.0, -400.0), (50.0, 0.0, 0.0), 420.0, -500.0),  # nearly taut
    ((0.0, 0.0, -400.0), (50.0, 0.0, 0.0), 600.0, -500.0),  # slack, clipped at the seabed
    ((0.0, 0.0, -100.0), (10.0, 0.0, 0.0), 100.5, -500.0),  # within centimetres of the chord
    ((0.0, 0.0, -480.0), (300.0, 40.0, 0.0), 600.0, -500.0),  # across the seabed, the horizontal out of a plane
])
def test_the_curve_has_the_line_length(start, end, length_m, seabed_z_m):
    """Reference: the requested length. The sag found makes the polyline's arc length the line's within
    ``SAG_TOLERANCE`` of it; the ends are the given points and no point lies below the seabed."""
    points = hanging_curve(start, end, length_m, seabed_z_m)
    assert abs(_arc_length_m(points) - length_m) <= 2 * SAG_TOLERANCE * length_m
    np.testing.assert_allclose(points[0], start, atol=1e-9)
    np.testing.assert_allclose(points[-1], end, atol=1e-9)
    assert points[:, 2].min() >= seabed_z_m


def test_a_line_no_longer_than_the_chord_is_the_chord():
    """Reference: the straight line between the ends. A line shorter than the span has no sag to take."""
    points = hanging_curve((0.0, 0.0, -100.0), (60.0, 0.0, 0.0), 100.0, -500.0)
    np.testing.assert_allclose(points[:, 2], np.linspace(-100.0, 0.0, points.shape[0]), atol=1e-12)


def test_a_line_the_seabed_cannot_take_lies_as_deep_as_it_can():
    """A line far longer than the clipped parabola can be (the seabed holds its middle) gets the deepest shape:
    its arc length short of the line's, the curve along the seabed from near one end to near the other."""
    points = hanging_curve((0.0, 0.0, -400.0), (50.0, 0.0, 0.0), 3000.0, -500.0)
    assert _arc_length_m(points) < 3000.0
    on_seabed = points[:, 2] == -500.0
    assert on_seabed[1:-1].all()

"""The peak-tension helpers of ``benchmarks/mbl_exceedance.py`` (``benchmarks/_peak_tension.py``): the strain a
segment's turn leaves beyond a step's linearisation, and where a line's peak is placed."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from _peak_tension import FALL, PRE_RELEASE, turn_strain, update_peaks  # noqa: E402

from moor_env import load_scene  # noqa: E402
from moor_env.compile import compile_scene  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402
from moor_env.simulation import Simulator  # noqa: E402


def test_turn_strain_of_a_pure_turn():
    """Reference: a segment of length l0 along x whose far node moves across it at v for a step h ends at
    sqrt(l0^2 + (h v)^2) while its length along x stays l0, a strain of sqrt(1 + (h v / l0)^2) - 1, which is
    (h v)^2 / (2 l0^2) to second order. Exact value to 1e-12 relative, the second-order form to 1 %."""
    l0, h, v = 1.0, 0.01125, 12.0
    got = turn_strain(np.array([l0, 0.0, 0.0]), np.array([0.0, v, 0.0]), h, l0)
    assert got == pytest.approx(math.sqrt(1.0 + (h * v / l0) ** 2) - 1.0, rel=1e-12)
    assert got == pytest.approx((h * v) ** 2 / (2.0 * l0 * l0), rel=0.01)


def test_turn_strain_of_a_stretch_along_the_segment_is_zero():
    """Reference: a stretch along the segment is what the linearisation predicts exactly, so no strain is left
    beyond it (a 0.5 m segment along (0.6, 0.8, 0) pulled apart at 5 m/s along itself; zero to 1e-14)."""
    direction = np.array([0.6, 0.8, 0.0])
    assert abs(turn_strain(0.5 * direction, 5.0 * direction, 0.01, 0.5)) < 1e-14


@pytest.fixture(scope="module")
def sim():
    """gjoa-500 on the fast preset at its compiled start shape (no statics: only the line layout is read)."""
    return Simulator(compile_scene(load_scene("gjoa-500", {"fidelity": "fast"})))


def test_update_peaks_places_the_largest_segment(sim):
    """With the segment tensions set by hand, a line's peak is its largest segment, placed at that segment's
    mid-point from the line's bottom end, with the phase and time given; a smaller tension later does not
    replace it, a larger one does."""
    st = sim.state
    line = sim.model.lines["vertical_chain"].index
    first = st.line_i[line, L.LI_SEG_START]
    l0 = st.seg_f[first, L.SF_L0]
    sim.work.seg_tension[:] = 0.0
    sim.work.seg_tension[first + 7] = 5.0e6
    peaks: dict = {}
    assert update_peaks(sim, {"vertical_chain": line}, peaks, FALL, 1.5) == ["vertical_chain"]
    peak = peaks["vertical_chain|fall"]
    assert (peak["segment"], peak["tension_n"], peak["t_s"]) == (7, 5.0e6, 1.5)
    assert peak["position_m"] == pytest.approx(7.5 * l0)
    sim.work.seg_tension[first + 2] = 4.0e6
    assert update_peaks(sim, {"vertical_chain": line}, peaks, FALL, 2.0) == []
    sim.work.seg_tension[first + 2] = 6.0e6
    assert update_peaks(sim, {"vertical_chain": line}, peaks, FALL, 2.5) == ["vertical_chain"]
    assert peaks["vertical_chain|fall"]["segment"] == 2
    assert update_peaks(sim, {"vertical_chain": line}, peaks, PRE_RELEASE, 3.0) == ["vertical_chain"]
    assert set(peaks) == {"vertical_chain|fall", "vertical_chain|pre-release"}

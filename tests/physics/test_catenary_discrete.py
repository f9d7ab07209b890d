"""The lumped-mass line's own equilibrium (``physics/discrete_catenary.py``), the static solver's first guess.

Seed 004 is Melozzi 2021, *Hydrodynamics of floating systems, Project 2, Task 1: Analysis of a mooring cable*.
"""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics.catenary import Section, solve_grounded, solve_suspended
from moor_env.physics.discrete_catenary import discrete_grounded, discrete_hang, discrete_walk

W_N_M = 1875.0  # seed 004's 100 mm chain: submerged weight [N/m], EA [N]
EA_N = 9e8


def _line(length_m: float, segment_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = int(round(length_m / segment_m))
    seg_l0 = np.full(n, length_m / n)
    node_w = np.zeros(n)
    node_w[1:] = W_N_M * seg_l0[1:]  # half of each neighbouring segment
    return node_w, seg_l0, np.full(n, EA_N)


def test_grounded_line_matches_the_elastic_catenary():
    """Reference: seed 004 section 5.4, 1750 m of chain from an anchor on the seabed to a fairlead 500 m up and
    1412.00 m away carries H = 200 kN (the analytic grounded catenary, ``catenary.solve_grounded``, to 0.01 %).
    The lumped-mass line of 5 m segments carries H within 0.2 %, its grounded segments flat and stretched by H,
    its last segment ending at the fairlead stretched by no more than the top tension."""
    node_w, seg_l0, seg_ea = _line(1750.0, 5.0)
    out = np.zeros((seg_l0.size - 1, 2))
    h_ref, _ = solve_grounded(1412.0, 500.0, [Section(W_N_M, EA_N, 1750.0)])
    h, mode, found = discrete_grounded(1412.0, 500.0, 0.0, 0.9 * h_ref, 1, 100, node_w, seg_l0, seg_ea, out)
    assert found and mode == 1
    assert h == pytest.approx(h_ref, rel=2e-3)
    flat = np.nonzero(out[:, 1] == 0.0)[0]
    assert flat.size > 50
    steps = np.diff(out[flat, 0])
    assert np.allclose(steps, 5.0 * (1.0 + h / EA_N), rtol=1e-9)
    top_chord = float(np.hypot(1412.0 - out[-1, 0], 500.0 - out[-1, 1]))  # the last segment reaches the fairlead
    assert 5.0 < top_chord < 5.0 * (1.0 + 1.2e6 / EA_N)  # stretched by at most its 1.14 MN top tension


def test_excess_line_lies_on_the_seabed_without_tension():
    """A line far longer than hanging straight down from both ends needs (2000 m between points 50 m apart, 500 m
    above the seabed) hangs with H -> 0 and lays the rest on the seabed, folded where the room between the two
    touchdowns is less than half of it."""
    node_w, seg_l0, seg_ea = _line(2000.0, 5.0)
    out = np.zeros((seg_l0.size - 1, 2))
    h, mode, found = discrete_grounded(50.0, 0.0, -500.0, 1e3, 150, 250, node_w, seg_l0, seg_ea, out)
    assert found and mode == 2
    assert h < 1e-3 * W_N_M
    grounded = out[:, 1] == -500.0
    assert grounded.sum() > 150
    assert out[:, 0].min() < 0.0  # the fold goes back under end A


def test_suspended_line_matches_the_elastic_catenary():
    """Reference: the continuous elastic catenary (``catenary.solve_suspended``) of 600 m of chain between points
    400 m apart and 300 m up. The lumped-mass line of 1 m segments carries its H within 0.05 % and ends exactly at
    end B."""
    node_w, seg_l0, seg_ea = _line(600.0, 1.0)
    out = np.zeros((seg_l0.size, 2))
    h_ref, va_ref = solve_suspended(400.0, 300.0, [Section(W_N_M, EA_N, 600.0)])
    h, va, found = discrete_hang(400.0, 300.0, 0.8 * h_ref, va_ref, node_w, seg_l0, seg_ea, out)
    assert found
    assert h == pytest.approx(h_ref, rel=5e-4)
    assert np.allclose(discrete_walk(h, va, node_w, seg_l0, seg_ea, out), (400.0, 300.0), atol=1e-6)


@pytest.mark.parametrize("name", ["seed004-chain-500", "seed000-chain-fibre"])
def test_grounded_guess_is_the_equilibrium(name):
    """The first guess of a grounded line is the discrete model's equilibrium, its nodes on the seabed up to their
    own penetration: Newton's method needs at most three iterations from it."""
    assert solve_statics(load_scene(name), progress=False, method="newton").iterations <= 3

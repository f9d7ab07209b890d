"""The two-vessel drop at 500 m of seed 003 (Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*; gjoa-500)
against the thesis's RIFLEX results (chapters 8, 10)."""

from __future__ import annotations

import pytest

from moor_env import simulate_drop


def test_default_touchdown_speed_and_tilt():
    """Reference: seed 003 Table 8-5, 26 m/s with chain tangential Cd 0.0069, tilt 0. Tolerance 6 %, tilt < 1.5 deg."""
    result = simulate_drop("gjoa-500")
    assert result.status == "touchdown"
    assert result.touchdown_speed_m_s == pytest.approx(26.0, rel=0.06)
    assert result.tilt_deg < 1.5


def test_dnv_chain_drag_slows_the_fall():
    """Reference: seed 003 Tables 8-2/8-3, 9.8-10.6 m/s with the DNV tangential Cd 0.4456. Tolerance 12 % on 10.2."""
    result = simulate_drop("gjoa-500", {"chain_cd_tangential": 0.4456})
    assert result.touchdown_speed_m_s == pytest.approx(10.2, rel=0.12)


def test_wider_vessel_spacing_lowers_speed():
    """Reference: seed 003 Table 10-5, spacing 50 -> 170 m lowers the speed 26.4 -> 24.9 m/s (trend must hold)."""
    narrow = simulate_drop("gjoa-500", {"vessel_spacing_m": 50.0})
    wide = simulate_drop("gjoa-500", {"vessel_spacing_m": 170.0})
    assert wide.touchdown_speed_m_s < narrow.touchdown_speed_m_s - 0.5
    assert wide.touchdown_speed_m_s == pytest.approx(24.9, rel=0.06)


def test_wide_loop_with_short_vertical_chain_tilts_the_anchor():
    """Reference: seed 003 Table 11-3, spacing 170 m with a 10 m vertical chain tilts the anchor about 3 deg
    (the issue quotes 3-4 deg). Tolerance: 2 to 5 deg, i.e. clearly tilted but inside the 5 deg criterion."""
    result = simulate_drop("gjoa-500", {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0})
    assert 2.0 < result.tilt_deg < 5.0

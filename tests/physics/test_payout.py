"""Winch payout and haul-in: mass conservation and stability down to a very short line."""

from __future__ import annotations

import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L


def test_mooring_line_payout_conserves_mass():
    """Reference: mass = mass per metre x unstretched length, with the length grown by rate x time exactly.
    Tolerance 1e-9 relative, checked after every step for 4 s of payout at 0.8 m/s (polyester top)."""
    sim = solve_statics(load_scene("gjoa-500")).simulator
    length0 = sim.line_length_m("mooring_line")
    mass0 = sim.line_mass_kg("mooring_line")
    sim.set_payout_rate("mooring_line", 0.8)
    n0 = sim.state.line_i[sim.model.lines["mooring_line"].index, L.LI_NSEG]
    steps = int(4.0 / sim.dt)
    for k in range(1, steps + 1):
        sim.advance_to(sim.state.t + sim.dt)
        paid = 0.8 * sim.dt * k
        assert sim.line_length_m("mooring_line") == pytest.approx(length0 + paid, rel=1e-9)
        assert sim.line_mass_kg("mooring_line") == pytest.approx(mass0 + 42.5 * paid, rel=1e-9)
    assert sim.state.line_i[sim.model.lines["mooring_line"].index, L.LI_NSEG] > n0


def test_wire_haul_in_to_a_very_short_line_and_out_again():
    """A 19 m wire hauled in at 2 m/s until the winch stops at half a segment, then paid out: no blow-up,
    mass = mass per metre x length throughout, segment lengths stay within the stable range."""
    scene = load_scene("gjoa-500", {"water_depth_m": 150.0, "installation.components.mooring_line": False})
    sim = solve_statics(scene).simulator
    wire = sim.model.lines["wire"].index
    sim.set_payout_rate("wire", -2.0)
    sim.advance_to(sim.state.t + 12.0)
    assert sim.state.line_i[wire, L.LI_CLAMPED] == 1
    assert sim.state.line_i[wire, L.LI_NSEG] == 1
    assert sim.line_length_m("wire") == pytest.approx(sim.state.line_f[wire, L.LF_L_MIN_TOP], rel=1e-9)
    sim.set_payout_rate("wire", 2.0)
    t0 = sim.state.t
    sim.advance_to(t0 + 10.0)
    paid = 2.0 * (sim.state.t - t0)
    assert sim.line_length_m("wire") == pytest.approx(sim.state.line_f[wire, L.LF_L_MIN_TOP] + paid, rel=1e-9)
    assert sim.line_mass_kg("wire") == pytest.approx(24.7 * sim.line_length_m("wire"), rel=1e-12)
    on_wire = sim.state.seg_i[:, L.SI_LINE] == wire
    lengths = sim.state.seg_f[on_wire][sim.state.seg_i[on_wire, L.SI_ACTIVE] == 1, L.SF_L0]
    assert lengths.min() >= sim.state.line_f[wire, L.LF_L_MIN_TOP] - 1e-9
    assert lengths.max() <= sim.state.line_f[wire, L.LF_L_MAX_TOP] + 1e-9

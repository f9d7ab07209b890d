"""Hard cases: numerically stressful scenes must stay finite with bounded energy and either agree
with a finer-resolution reference within the stated tolerance or end with a clear typed error."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import ConfigError, compile_scene, load_scene, simulate_drop, solve_statics
from moor_env.physics import layout as L
from moor_env.simulation import run_drop

from ._helpers import assert_finite_state, max_node_speed, run_checked

FINE = {"discretization.vertical_chain_segment_m": 0.5, "discretization.loop_chain_segment_m": 0.5}

NO_CONTACT = {"discretization.line_anchor_contact": "off"}


def test_loop_snapping_taut_under_fast_haul_in():
    """Wide spacing (170 m), short vertical chain (10 m) and the mooring winch hauling in at 1 m/s for 15 s
    before release: the loop is pulled from slack to taut. Reference: the same run with 0.5 m chain elements.
    Tolerance: touchdown speed 3 %, tilt 0.5 deg; speeds stay bounded throughout."""
    overrides = {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0, "release_time_s": 15.0,
                 "installation.payout_rate_m_s": -1.0}
    coarse = simulate_drop("gjoa-500", overrides)
    fine = simulate_drop("gjoa-500", dict(overrides, **FINE))
    assert coarse.status == fine.status == "touchdown"
    assert coarse.touchdown_speed_m_s == pytest.approx(fine.touchdown_speed_m_s, rel=0.03)
    assert coarse.tilt_deg == pytest.approx(fine.tilt_deg, abs=0.5)
    assert np.isfinite(coarse.max_tension_n["mooring_line"])


def test_very_short_chain_elements_at_the_default_step():
    """0.25 m chain elements (4x finer, 16x stiffer segments) with the derived default step: stable, and the
    touchdown speed agrees with the 1 m default within 1 % (reference: the default resolution)."""
    fine = simulate_drop("vertical-chain", {"discretization.vertical_chain_segment_m": 0.25})
    default = simulate_drop("vertical-chain")
    assert fine.dt_s < default.dt_s / 3.5
    assert fine.touchdown_speed_m_s == pytest.approx(default.touchdown_speed_m_s, rel=0.01)


def test_3000_m_depth_with_a_3000_m_wire():
    """3000 m depth (a 2867 m wire, 3200 m mooring line, spacing 300 m): statics converge with the tip at the
    drop height and the fall matches the 500 m scene within 2 % (the anchor and its 150 m of bottom chain
    dominate; the wire is cut at release). Both without the line-anchor contact: with it the 500 m scene's vertical
    chain snaps taut before touchdown and its speed depends on the snaps' timing (docs/model.md), which is not
    what this compares."""
    overrides = {"water_depth_m": 3000.0, "vessel_spacing_m": 300.0, "mooring_line_length_m": 3200.0, **NO_CONTACT}
    static = solve_statics(load_scene("gjoa-500", overrides))
    assert static.tip_height_above_seabed_m == pytest.approx(68.5, abs=1e-3)
    assert static.wire_length_m == pytest.approx(2867.0, rel=0.01)
    result = run_drop(static.simulator)
    shallow = simulate_drop("gjoa-500", {"vessel_spacing_m": 300.0 * 500 / 3000, **NO_CONTACT})
    assert result.touchdown_speed_m_s == pytest.approx(shallow.touchdown_speed_m_s, rel=0.02)


def test_strong_current_across_the_lines():
    """2 m/s surface current (seed profile x 2.5) flowing across the plane of the lines: statics converge (the
    release point moves sideways, along the current), the fall stays finite and drifts with the current."""
    static = solve_statics(load_scene("gjoa-500", {"current_scale": 2.5, "current_direction_deg": 90.0}))
    x, y, _ = static.release_point_m
    assert y > 5.0
    sim = static.simulator
    sim.release()
    status = run_checked(sim, 15.0, detect_touchdown=True)
    assert status == L.STATUS_TOUCHDOWN
    tip = sim.work.touchdown[L.TD_TIP:L.TD_TIP + 3]
    assert tip[1] > y - 1.0


def test_release_at_the_worst_phase_of_resonant_heave():
    """Sea with its peak period near the heave period of the anchor on the wire (about 2.4 s; vessel transfer
    tuned to follow it): the anchor heaves; it is released while moving upward at its fastest. The run stays
    finite and lands, slower than from rest (it starts upward)."""
    scene = load_scene("gjoa-500", {"sea_state_hs_m": 4.0, "sea_state_tp_s": 3.0,
                                    "environment.sea_state.vessel_natural_period_s": 2.5})
    sim = solve_statics(scene).simulator
    sim.set_vessel_motion(0.0, 60.0, np.zeros(2))
    best_up = 0.0
    released_up = None
    while sim.state.t < 40.0:
        sim.advance_to(sim.state.t + 0.02)
        assert_finite_state(sim)
        vz = sim.tip_state()[1][2]
        if sim.state.t < 20.0:
            best_up = max(best_up, vz)
        elif vz > 0.9 * best_up:
            released_up = vz
            break
    assert best_up > 0.05
    assert released_up is not None and released_up > 0.0
    sim.release()
    status = run_checked(sim, sim.state.t + 15.0, detect_touchdown=True)
    assert status == L.STATUS_TOUCHDOWN
    calm = simulate_drop("gjoa-500")
    assert np.linalg.norm(sim.work.touchdown[L.TD_VEL:L.TD_VEL + 3]) < calm.touchdown_speed_m_s + 0.5


def test_vertical_chain_slack_during_the_fall():
    """With the seed's low chain drag the vertical chain falls faster than the anchor and carries no tension
    for most of the fall: zero-tension segments must not destabilise anything."""
    sim = solve_statics(load_scene("gjoa-500")).simulator
    sim.release()
    line = sim.model.lines["vertical_chain"].index
    seg_start = sim.state.line_i[line, L.LI_SEG_START]
    segs = slice(seg_start, seg_start + sim.state.line_i[line, L.LI_NSEG])
    slack_seen = 0
    for k in range(1, 17):
        sim.advance_to(0.25 * k)
        sim.evaluate_loads()
        slack_seen += int(np.sum(sim.work.seg_tension[segs] == 0.0))
        assert_finite_state(sim)
    assert slack_seen > 100


def test_chain_hitting_the_seabed_at_speed():
    """After touchdown the run goes on (the anchor has no soil model and passes the seabed): the vertical chain
    and loop hit the seabed at 20+ m/s. Contact must stop them without blow-up: finite state, bounded speeds,
    shallow penetration, chain lying on the seabed. Without the line-anchor contact: the anchor has no soil to
    stop it, and the contact would carry the chain on its back end down with it."""
    sim = solve_statics(load_scene("gjoa-500", NO_CONTACT)).simulator
    sim.release()
    run_checked(sim, 6.0, detect_touchdown=True)
    speed_at_impact = max_node_speed(sim)
    assert speed_at_impact > 20.0
    run_checked(sim, sim.state.t + 2.0)
    active = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
    depth = sim.model.env_f[L.EF_DEPTH]
    assert np.min(sim.state.node_pos[active, 2]) > -depth - 1.0
    assert sim.line_length_on_seabed_m() > 10.0


@pytest.mark.parametrize(("overrides", "key"), [
    ({"dt_s": 0.002}, "discretization.dt_s"),
    ({"materials.chain_142.ea_n": -1.0}, "materials.chain_142.ea_n"),
    ({"water_depth_m": 0.0}, "environment.water_depth_m"),
    ({"anchor_mass_scale": 1.5, "materials.wire_76.mbl_n": 6.0e5}, "materials.wire_76.mbl_n"),
])
def test_impossible_requests_are_typed_errors(overrides, key):
    """A step beyond the stable limit, negative EA, zero depth, an anchor heavier than the wire's MBL: refused
    before any simulation with a ConfigError naming the field."""
    with pytest.raises(ConfigError) as info:
        compile_scene(load_scene("gjoa-500", overrides))
    assert info.value.key == key

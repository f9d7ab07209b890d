"""Determinism, blow-up reporting and the command line of the drop simulation."""

from __future__ import annotations

import json
import subprocess
import sys
import threading

import numpy as np
import pytest

from moor_env import SimulationDiverged, load_scene, simulate_drop, solve_statics
from moor_env.physics import layout as L


def test_same_scene_gives_bit_identical_results():
    a = simulate_drop("gjoa-500", {"vessel_spacing_m": 120.0})
    b = simulate_drop("gjoa-500", {"vessel_spacing_m": 120.0})
    da, db = a.to_dict(), b.to_dict()
    for key in ("wall_static_s", "wall_dynamic_s"):
        da.pop(key), db.pop(key)
    assert da == db
    assert np.array_equal(a.history, b.history)


def test_waves_with_the_same_seed_are_identical_and_other_seeds_differ():
    overrides = {"sea_state_hs_m": 2.5, "release_time_s": 6.0, "sea_state_seed": 3}
    a = simulate_drop("gjoa-500", overrides)
    b = simulate_drop("gjoa-500", overrides)
    c = simulate_drop("gjoa-500", dict(overrides, sea_state_seed=4))
    assert a.touchdown_speed_m_s == b.touchdown_speed_m_s
    assert a.release_point_m == b.release_point_m
    assert a.release_point_m != c.release_point_m


def test_blow_up_is_a_typed_error_naming_time_and_component():
    sim = solve_statics(load_scene("vertical-chain")).simulator
    sim.release()
    sim.dt = 4.0 * sim.model.dt_limit_s
    with pytest.raises(SimulationDiverged) as info:
        sim.advance_to(2.0)
    assert 0.0 < info.value.time_s < 2.0
    assert "vertical_chain" in info.value.component or info.value.component == "anchor"
    assert np.all(np.isfinite(sim.state.body_state))


def test_cli_drop_json_has_the_interface_keys(tmp_path):
    plot = tmp_path / "fall.png"
    proc = subprocess.run([sys.executable, "-m", "moor_env.cli", "drop", "vertical-chain", "--json", "--no-progress",
                           "--plot", str(plot)], capture_output=True, text=True, check=True)
    data = json.loads(proc.stdout)
    for key in ("touchdown_time_s", "touchdown_speed_m_s", "touchdown_vertical_speed_m_s", "tilt_deg", "drift_m",
                "release_point_m", "chain_on_seabed_m", "chain_past_back_end_m", "max_tension_n", "n_nodes",
                "n_steps", "dt_s", "wall_static_s", "wall_dynamic_s"):
        assert key in data
    assert plot.stat().st_size > 10_000


def test_cli_static_json():
    proc = subprocess.run([sys.executable, "-m", "moor_env.cli", "static", "gjoa-500", "--json"], capture_output=True,
                          text=True, check=True)
    data = json.loads(proc.stdout)
    assert data["release_point_m"][2] == pytest.approx(-368.5, abs=1.5)
    assert set(data["top_tensions_n"]) == {"vertical_chain", "mooring_line", "wire"}


def test_kept_wire_recoils_after_release():
    """With keep_wire_after_release the cut wire springs back: its end rises by about its static stretch
    (1.5 m at 500 m, seed 003: Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, Table 14-7) while the
    anchor falls."""
    from moor_env.simulation import run_drop

    scene = load_scene("gjoa-500", {"installation.components.keep_wire_after_release": True})
    sim = solve_statics(scene).simulator
    wire_end = sim.model.wire_end_node
    z0 = sim.state.node_pos[wire_end, 2]
    result = run_drop(sim)
    assert result.status == "touchdown"
    assert sim.state.node_pos[wire_end, 2] > z0 + 0.5


def test_second_vessel_moves_before_release():
    """A spacing rate moves the second vessel at that speed; the release point follows it (pulled by the line)."""
    from moor_env.physics import layout as L
    from moor_env.simulation import run_drop

    scene = load_scene("gjoa-500", {"release_time_s": 20.0, "installation.spacing_rate_m_s": 1.0})
    static = solve_statics(scene)
    x0 = static.release_point_m[0]
    sim = static.simulator
    result = run_drop(sim)
    top = sim.state.line_i[sim.model.lines["mooring_line"].index, L.LI_TOP]
    assert sim.state.node_pos[top, 0] > 50.0 + 20.0
    assert result.release_point_m[0] > x0


def test_vessel_tracks_follow_the_wave_components():
    """Sampled tracks (the kernel advances each component's phase by rotation from sample to sample) against the
    closed-form sum eta = sum a |H| cos(w t - k x + phase + arg H) and its surge and velocities, over 95 s of
    0.05 s samples at two vessel positions; reference: the direct formula, tolerance 1e-9 m and 1e-9 m/s."""
    from moor_env.physics.vessels import jonswap_components, motion_transfer, sample_tracks

    amp, omega, phase = jonswap_components(3.0, 7.0, 3.3, 64, 11)
    sea = {"amplitude": amp, "omega": omega, "phase": phase, "natural_period_s": 9.0, "damping_ratio": 0.2}
    base = np.array([[0.0, 0.0, -5.0], [50.0, 0.0, -5.0]])
    speeds = np.array([0.0, 0.4])
    tracks = sample_tracks(base, speeds, 20.0, 95.0, 0.05, sea, 9.81)
    times = 20.0 + 0.05 * np.arange(tracks.shape[1])
    transfer = motion_transfer(omega, 9.0, 0.2)
    a = amp * np.abs(transfer)
    for v in range(2):
        arg = omega * times[:, None] - omega**2 / 9.81 * base[v, 0] + phase + np.angle(transfer)
        expected = {0: base[v, 0] + speeds[v] * (times - 20.0) + np.sum(a * np.sin(arg), axis=1),
                    2: base[v, 2] + np.sum(a * np.cos(arg), axis=1),
                    3: speeds[v] + np.sum(a * omega * np.cos(arg), axis=1),
                    5: -np.sum(a * omega * np.sin(arg), axis=1)}
        for column, values in expected.items():
            assert np.max(np.abs(tracks[v, :, column] - values)) < 1e-9, (v, column)


def test_line_past_back_end_measures_along_and_off_the_anchor_axis():
    """Geometry of ``Simulator.line_past_back_end_m`` (reference: a node placed by hand, exact to 1e-9 m)."""
    sim = solve_statics(load_scene("vertical-chain")).simulator
    st, m = sim.state, sim.model
    along, off = sim.line_past_back_end_m("vertical_chain")
    seg_m = sim.model.scene.discretization.vertical_chain_segment_m
    assert along == pytest.approx(-seg_m, abs=0.02) and off < 0.02  # hanging straight above the back end
    axis = st.body_state[L.BS_AXIS:L.BS_AXIS + 3].copy()
    normal = np.cross(axis, [1.0, 0.0, 0.0])
    normal /= np.linalg.norm(normal)
    back = sim.tip_state()[0] - m.body_f[L.BF_LENGTH] * axis
    chain = m.lines["vertical_chain"].index
    node = st.seg_i[st.line_i[chain, L.LI_SEG_START] + 2, L.SI_B]  # third node up the chain
    st.node_pos[node] = back + 0.4 * axis + 0.3 * normal
    assert sim.line_past_back_end_m("vertical_chain") == pytest.approx((0.4, 0.3), abs=1e-9)


def test_a_fall_cut_short_ends_where_the_kernel_stops():
    """A fall whose time limit is no whole number of steps (0.5 s at the fast preset's 22.5 ms: the kernel stops at
    0.495 s, the first step that ends within half a step of the limit) ends there with the time-limit status,
    rather than asking the kernel again for a step it never takes."""
    out = []
    run = threading.Thread(target=lambda: out.append(simulate_drop(
        "gjoa-500", {"fidelity": "fast", "simulation.max_fall_time_s": 0.5}, history=False)), daemon=True)
    run.start()
    run.join(120.0)
    assert out, "the drop did not end"
    result = out[0]
    assert result.status == "no touchdown within max_fall_time_s"
    assert result.dt_s == pytest.approx(0.0225)
    assert result.n_steps == 22


def test_fall_integrator_takes_over_at_the_release():
    """An implicit scene with ``fall_integrator: symplectic_euler`` falls like the explicit scene: same step and
    step count, touchdown speed within 1e-4 (reference: symplectic Euler throughout; the two equilibria are
    solved at the two integrators' steps, measured 3.7e-5 apart), while the implicit fall is 1e-3 off."""
    explicit = simulate_drop("gjoa-500", {"integrator": "symplectic_euler"}, history=False)
    mixed = simulate_drop("gjoa-500", {"integrator": "implicit_euler", "fall_integrator": "symplectic_euler"},
                          history=False)
    implicit = simulate_drop("gjoa-500", {"integrator": "implicit_euler"}, history=False)
    assert mixed.dt_s == explicit.dt_s and mixed.n_steps == explicit.n_steps
    assert mixed.touchdown_speed_m_s == pytest.approx(explicit.touchdown_speed_m_s, rel=1e-4)
    assert abs(implicit.touchdown_speed_m_s / explicit.touchdown_speed_m_s - 1.0) > 5e-4

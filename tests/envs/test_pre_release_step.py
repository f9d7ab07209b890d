"""The coarse pre-release step (control.pre_release_dt_s): the grid it keeps, its fallback, and what it changes.

The tiny config runs the explicit integrator; here it is switched to implicit_euler, the only integrator that takes
the coarse step.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.envs.core import InstallationCore, run_advance
from moor_env.envs.measures import line_summary
from moor_env.envs.resolution import even_step_s
from moor_env.errors import SimulationDiverged
from moor_env.physics import layout as L

IMPLICIT = {"fidelity.discretization.integrator": "implicit_euler"}
HOLD = np.array([0.0, 0.0, -1.0], np.float32)


def _tiny(tiny, **control):
    overrides = {**tiny, **IMPLICIT, **{f"control.{k}": v for k, v in control.items()}}
    return gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=overrides)


def test_coarse_steps_end_on_the_control_grid(tiny):
    env = _tiny(tiny, pre_release_dt_s=0.13, interval_s=0.25)
    env.reset(seed=3, options={"sea_state_hs_m": 1.0})
    core = env.unwrapped.core
    scene_dt = core.sim.dt
    for k in range(1, 5):
        adv = core.begin_step(np.array([0.5, 0.5, -1.0]))
        assert scene_dt < adv.dt_s <= 0.13
        assert adv.dt_s == 0.125  # 2 equal steps: the fewest of at most 0.13 s
        core.finish_step(*run_advance(core, adv))
        assert core.time_s == pytest.approx(0.25 * k, abs=1e-12)
    # the fall is integrated at the scene's step
    assert core.begin_step(np.array([0.0, 0.0, 1.0])).dt_s == scene_dt


def test_a_sea_without_waves_takes_the_calm_step(tiny):
    env = _tiny(tiny, pre_release_dt_s=0.05, pre_release_dt_calm_s=0.125, interval_s=0.25)
    core = env.unwrapped.core
    env.reset(seed=3, options={"sea_state_hs_m": 0.0})
    assert core.begin_step(HOLD).dt_s == 0.125
    env.reset(seed=3, options={"sea_state_hs_m": 0.5})
    assert core.begin_step(HOLD).dt_s == 0.05
    unset = _tiny(tiny, pre_release_dt_s=0.05, interval_s=0.25)  # no calm step: the one step everywhere
    unset.reset(seed=3, options={"sea_state_hs_m": 0.0})
    assert unset.unwrapped.core.begin_step(HOLD).dt_s == 0.05


def test_explicit_integrator_keeps_the_scene_step(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "control.pre_release_dt_s": 0.13})
    env.reset(seed=3)
    core = env.unwrapped.core
    assert core.begin_step(HOLD).dt_s <= core.sim.dt


def test_fallback_repeats_the_advance_at_the_scene_step(tiny):
    """A diverged coarse advance goes again from the saved state at the scene's step: the result is bit for bit
    the step of an env configured with the scene's step."""
    coarse = _tiny(tiny, pre_release_dt_s=0.13)
    fine = _tiny(tiny, pre_release_dt_s=None)
    coarse.reset(seed=5)
    fine.reset(seed=5)
    core: InstallationCore = coarse.unwrapped.core
    t0 = core.sim.state.t
    action = np.array([0.3, -0.4, -1.0], np.float32)
    adv = core.begin_step(action)
    assert adv.dt_s > core.sim.dt and adv.backup
    run_advance(core, adv)
    assert core.sim.state.t > t0
    retry = core.fallback(adv, SimulationDiverged(core.sim.state.t, "test", "strain above limit"))
    assert retry is not None and retry.dt_s <= core.sim.dt and core.sim.state.t == t0 and core.fallbacks == 1
    assert core.fallback(retry, SimulationDiverged(t0, "test", "strain above limit")) is None  # only once
    out_c = core.finish_step(*run_advance(core, retry))
    out_f = fine.step(action)
    assert np.array_equal(out_c[0], out_f[0]) and out_c[1] == out_f[1]
    for name in ("node_pos", "node_vel", "body_state"):
        assert np.array_equal(getattr(core.sim.state, name), getattr(fine.unwrapped.core.sim.state, name)), name


def test_a_coarse_advance_raising_a_tension_above_the_breaking_load_is_repeated_at_the_scene_step(tiny):
    """With the breaking loads lowered below the hanging tensions and the running maxima cleared, the coarse
    advance raises them above it, fails its end check and is repeated at the scene's step, which is not checked
    against them: bit for bit the scene-step env's step."""
    coarse = _tiny(tiny, pre_release_dt_s=0.13)
    fine = _tiny(tiny, pre_release_dt_s=None)
    coarse.reset(seed=5)
    fine.reset(seed=5)
    for env in (coarse, fine):
        env.unwrapped.core.sim.model.mat_f[:, L.MF_MBL] = 1.0  # [N]
        env.unwrapped.core.sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0
    action = np.array([0.3, -0.4, -1.0], np.float32)
    out_c = coarse.step(action)
    out_f = fine.step(action)
    core = coarse.unwrapped.core
    assert core.fallbacks == 1 and out_c[4]["sim_status"] == "running"
    assert np.array_equal(out_c[0], out_f[0])
    for name in ("node_pos", "node_vel", "body_state"):
        assert np.array_equal(getattr(core.sim.state, name), getattr(fine.unwrapped.core.sim.state, name)), name


def test_a_fast_moving_line_shortens_the_coarse_step(tiny):
    """A node at 30 m/s may travel half the shortest segment (5 m) per step (``pre_release_travel_segments``):
    the advance takes the fewest equal steps within that (3 of 0.083 s), never below the scene's step (at
    300 m/s); at rest, or without the limit, the configured coarse step."""
    limited = _tiny(tiny, pre_release_dt_s=0.13, interval_s=0.25, pre_release_travel_segments=0.5)
    free = _tiny(tiny, pre_release_dt_s=0.13, interval_s=0.25, pre_release_travel_segments=None)
    for env in (limited, free):
        env.reset(seed=3, options={"sea_state_hs_m": 0.0})
    assert limited.unwrapped.core.begin_step(HOLD).dt_s == 0.125  # at rest
    for speed_m_s in (30.0, 300.0):
        for env in (limited, free):
            env.reset(seed=3, options={"sea_state_hs_m": 0.0})
            st = env.unwrapped.core.sim.state
            node = int(np.nonzero(st.node_i[:, L.NI_KIND] == L.NODE_FREE)[0][0])
            st.node_vel[node] = (0.0, 0.0, -speed_m_s)
        core = limited.unwrapped.core
        st = core.sim.state
        shortest = st.seg_f[st.seg_i[:, L.SI_ACTIVE] != 0, L.SF_L0].min()
        travel = 0.5 * shortest / speed_m_s
        assert (travel > core.sim.dt) == (speed_m_s == 30.0)
        assert core.begin_step(HOLD).dt_s == even_step_s(0.25, max(travel, core.sim.dt))
        assert free.unwrapped.core.begin_step(HOLD).dt_s == 0.125


def test_calm_loop_moved_by_the_crew_stays_within_its_loads(default_overrides):
    """The default config in calm water, vessel and winch moved at random (the seeded controls of
    ``benchmarks/pre_release_step.py``, seed 1009: a 0.5 m chain loop that swings at a few m/s). The coarse steps
    must neither blow up nor load a segment beyond half its breaking load at a step's end, nor raise a line's
    running maximum tension (what the limit check reads) beyond it (reference: the lines hang at a quarter of it at
    most; with neither the travel limit nor the end check this episode ends in a blow-up at t = 4 s)."""
    env = gym.make("moor_env/AnchorRelease-v0", overrides={**default_overrides, "scenario.sea_state_hs_m": 0.0})
    core = env.unwrapped.core
    rng = np.random.default_rng(1009)
    rng.integers(25, 56)  # the benchmark draws its release step and a first pair of rates before the episode
    rng.uniform(-1.0, 1.0, 2)
    env.reset(seed=1009)
    largest = 0.0
    for k in range(20):
        if k % 10 == 0:
            rates = rng.uniform(-1.0, 1.0, 2)
        _, _, terminated, truncated, info = env.step(np.array([rates[0], rates[1], -1.0], np.float32))
        assert info["sim_status"] == "running" and not (terminated or truncated)
        st = core.sim.state
        active = st.seg_i[:, L.SI_ACTIVE] != 0
        mbl = core.sim.model.mat_f[st.seg_i[active, L.SI_MAT], L.MF_MBL]
        largest = max(largest, float(np.max(core.sim.work.seg_tension[active] / mbl)))
    assert largest < 0.5
    running = {name: core.sim.state.line_f[info.index, L.LF_MAX_TENSION] / core.mbl[name]
               for name, info in core.sim.model.lines.items()}
    assert max(running.values()) < 0.5, running


def test_coarse_episode_is_deterministic_and_close_to_the_scene_step(tiny):
    """Same seed and actions: identical with the coarse step; against the scene's step the anchor state after 3 s
    of 1 m waves and winch/spacing moves differs little (reference: the scene-step run of the same episode;
    tolerance 1 cm and 5 mm/s, measured 2.6 mm and 0.5 mm/s at 2.2x the scene's step)."""
    def episode(dt):
        env = _tiny(tiny, pre_release_dt_s=dt)
        env.reset(seed=8, options={"sea_state_hs_m": 1.0, "current_scale": 0.0})
        for _ in range(12):
            env.step(np.array([0.5, -0.5, -1.0], np.float32))
        return env.unwrapped.core.sim.state.body_state.copy()

    a, b, ref = episode(0.13), episode(0.13), episode(None)
    assert np.array_equal(a, b)
    assert np.max(np.abs(a[L.BS_POS:L.BS_POS + 3] - ref[L.BS_POS:L.BS_POS + 3])) < 0.01
    assert np.max(np.abs(a[L.BS_VEL:L.BS_VEL + 3] - ref[L.BS_VEL:L.BS_VEL + 3])) < 0.005


def test_line_summary_matches_the_segment_table(tiny):
    """The observation's one-pass line summary against numpy masks over the segment table, after payout."""
    env = _tiny(tiny)
    env.reset(seed=1)
    core = env.unwrapped.core
    for _ in range(6):
        env.step(np.array([0.0, 1.0, -1.0], np.float32))  # pay out: segments split at the top
    st = core.sim.state
    line = core.lines["mooring_line"]
    segs = (st.seg_i[:, L.SI_LINE] == line) & (st.seg_i[:, L.SI_ACTIVE] == 1)
    nodes = np.unique(st.seg_i[segs][:, [L.SI_A, L.SI_B]])
    fibre = segs & (st.seg_i[:, L.SI_MAT] == core.fibre_mat)
    fibre_nodes = np.unique(st.seg_i[fibre][:, [L.SI_A, L.SI_B]])
    z_all, z_fibre, length = line_summary(st.node_pos, st.seg_i, st.seg_f, st.line_i, line, core.fibre_mat)
    assert z_all == st.node_pos[nodes, 2].min()
    assert z_fibre == st.node_pos[fibre_nodes, 2].min()
    assert length == pytest.approx(np.sum(st.seg_f[segs, L.SF_L0]), rel=1e-12)

"""AnchorRelease-v1: the levers' rates and ranges, the release decision, determinism, a refused move, and the crew
driving to its plan and installing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from agents.baselines import make_baseline
from agents.policy import EpisodeContext
from moor_env.envs import AnchorReleaseV1Env, load_env_config
from moor_env.envs.anchor_release_v1 import OBS_NAMES_V1
from moor_env.envs.levers import drop_height_max_m
from moor_env.envs.positioning import LEVER_STATE, move_levers, release_decision, steps_to_reach
from moor_env.errors import ConfigError

ENV_ID = "moor_env/AnchorRelease-v1"
CALM_500 = {"water_depth_m": 500.0, "current_scale": 0.0, "current_direction_deg": 0.0, "sea_state_hs_m": 0.0}
START = {"vessel_spacing_m": 40.0, "mooring_line_length_m": 540.0, "vertical_chain_length_m": 10.0,
         "drop_height_m": 70.0}
ANCHOR_LENGTH_M, FAIRLEAD_DEPTH_M = 13.0, 0.0


@pytest.fixture(scope="module")
def cfg():
    return load_env_config("anchor-plan")


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID)
    yield e
    e.close()


def test_full_commands_move_each_lever_by_its_rate(cfg):
    """A full command moves each lever by rate x step (config ``positioning``); paying chain with the wire held
    lowers the anchor by the chain paid."""
    pos = cfg.positioning
    moved = move_levers(START, [1.0, 1.0, 1.0, 0.0, 0.0], 500.0, cfg.levers, pos, ANCHOR_LENGTH_M, FAIRLEAD_DEPTH_M)
    assert moved["vessel_spacing_m"] == pytest.approx(40.0 + pos.vessel_speed_max_m_s * pos.step_s)
    assert moved["mooring_line_length_m"] == pytest.approx(540.0 + pos.winch_rate_max_m_s * pos.step_s)
    chain_paid = pos.chain_rate_max_m_s * pos.step_s
    assert moved["vertical_chain_length_m"] == pytest.approx(10.0 + chain_paid)
    assert moved["drop_height_m"] == pytest.approx(70.0 - chain_paid)
    hauled = move_levers(START, [0.0, 0.0, 0.0, 1.0, 0.0], 500.0, cfg.levers, pos, ANCHOR_LENGTH_M,
                         FAIRLEAD_DEPTH_M)
    assert hauled["drop_height_m"] == pytest.approx(70.0 + pos.wire_rate_max_m_s * pos.step_s)


def test_levers_stay_in_their_ranges(cfg):
    """Commands beyond a range end stop at it (the drop height at its clearance limit); NaN holds."""
    pos = cfg.positioning
    state = dict(START)
    for _ in range(30):
        state = move_levers(state, [-1.0, 1.0, 1.0, 1.0, 0.0], 500.0, cfg.levers, pos, ANCHOR_LENGTH_M,
                            FAIRLEAD_DEPTH_M)
    assert state["vessel_spacing_m"] == cfg.levers.vessel_spacing_over_depth[0] * 500.0
    assert state["mooring_line_length_m"] == cfg.levers.mooring_line_length_over_depth[1] * 500.0
    assert state["vertical_chain_length_m"] == cfg.levers.vertical_chain_length_m[1]
    top = drop_height_max_m(cfg.levers, 500.0, state["vertical_chain_length_m"], ANCHOR_LENGTH_M, FAIRLEAD_DEPTH_M)
    assert state["drop_height_m"] == top
    assert move_levers(START, [np.nan] * 5, 500.0, cfg.levers, pos, ANCHOR_LENGTH_M, FAIRLEAD_DEPTH_M) == START


def test_any_target_reachable_before_the_forced_release(cfg):
    """At the deepest site of the default distribution every lever crosses its range with the confirmation steps
    to spare."""
    deepest = cfg.site.water_depth_m.uniform[1]
    steps = steps_to_reach(cfg.levers, cfg.positioning, deepest)
    assert steps == 11
    assert steps + cfg.positioning.release_confirm_steps <= cfg.positioning.max_steps


def test_release_needs_confirmed_commands(cfg):
    """A command above the threshold on consecutive steps releases; a lower one disarms; the phase maps the excess
    over the threshold onto the release window. Uniform random commands release within the first two steps with
    probability 1/16 (binomial, 4000 draws: within 4 standard deviations)."""
    pos, window = cfg.positioning, cfg.levers.release_window_periods
    assert release_decision(0.9, 0, pos, window)[:2] == (1, False)
    assert release_decision(0.2, 1, pos, window) == (0, False, 0.0)
    armed, fire, phase = release_decision(1.0, 1, pos, window)
    assert (armed, fire, phase) == (2, True, window)
    assert release_decision(np.nan, 1, pos, window)[:2] == (0, False)
    rng = np.random.default_rng(0)
    commands = rng.uniform(-1.0, 1.0, (4000, 2))
    fired = [release_decision(c2, release_decision(c1, 0, pos, window)[0], pos, window)[1] for c1, c2 in commands]
    p = 1.0 / 16.0
    assert abs(np.mean(fired) - p) < 4.0 * np.sqrt(p * (1.0 - p) / len(fired))


def test_spaces_and_determinism(env):
    """Same seed, same episode, bit for bit (observations over positioning steps)."""
    assert isinstance(env.unwrapped, AnchorReleaseV1Env)
    assert env.observation_space.shape == (len(OBS_NAMES_V1),) and env.action_space.shape == (5,)
    runs = []
    for _ in range(2):
        obs, info = env.reset(seed=11, options={"sea_state_hs_m": 0.0})
        assert info["start_draws"] >= 1 and env.observation_space.contains(obs)
        seq = [obs.tobytes()]
        rng = np.random.default_rng(5)
        for _ in range(3):
            action = np.append(rng.uniform(-1.0, 1.0, 4), -1.0).astype(np.float32)
            obs, reward, terminated, truncated, info = env.step(action)
            assert reward == 0.0 and not terminated and not truncated
            seq.append(obs.tobytes())
        runs.append(seq)
    assert runs[0] == runs[1]


def test_move_without_equilibrium_is_refused(env, refuse_spacing_below_20_m):
    """Mechanism: a move to a geometry without an equilibrium (here any spacing below 20 m, ``tests/conftest.py``)
    is not carried out: the levers stay where they were and the observation flags the refusal."""
    obs, info = env.reset(seed=0, options={**CALM_500, "levers": START})
    assert info["start_draws"] == 0 and info["levers"] == START
    obs, _, terminated, _, info = env.step(np.array([-1.0, 0.0, 0.0, 0.0, -1.0], np.float32))
    assert not terminated
    assert "vessel_spacing_m" in info["move_refused"] and info["levers"] == START
    assert obs[OBS_NAMES_V1.index("move_refused")] == 1.0


def test_fixed_start_outside_its_range_is_refused(env):
    with pytest.raises(ConfigError, match="options.levers.vertical_chain_length_m"):
        env.reset(seed=0, options={**CALM_500, "levers": {**START, "vertical_chain_length_m": 90.0}})


def test_crew_drives_to_its_plan_and_installs(env, cfg):
    """The crew's plan (spacing 0.1 h, line 1.08 h, 50 m chain, drop height for the required speed, crest) is
    reached within the rates, then released on two confirmed commands; the installation reports its outcome."""
    crew = make_baseline("crew", ENV_ID, cfg)
    obs, info = env.reset(seed=2, options={**CALM_500, "levers": START})
    crew.begin_episode(EpisodeContext(ENV_ID, cfg, {}, 2, obs, info))
    for _ in range(cfg.positioning.max_steps):
        obs, reward, terminated, truncated, info = env.step(crew.act(obs, info))
        if terminated:
            break
    assert terminated and not truncated and not info["forced_release"]
    assert info["step"] <= steps_to_reach(cfg.levers, cfg.positioning, 500.0) + cfg.positioning.release_confirm_steps
    assert info["levers"]["vessel_spacing_m"] == pytest.approx(50.0, abs=0.05)
    assert info["levers"]["vertical_chain_length_m"] == pytest.approx(50.0, abs=0.05)
    assert info["targets"]["release_phase"] == pytest.approx(0.25, abs=1e-5)
    assert info["touchdown"] is not None and info["failure"] is None
    assert 0.0 < reward <= 1.0 and info["success"] == (info["touchdown"]["speed_m_s"] >= info["site"][
        "required_speed_m_s"] and info["touchdown"]["tilt_deg"] < 2.0 and not info["limits_exceeded"]
        and info["touchdown"]["offset_m"] <= 2.0)
    assert set(info["levers"]) == set(LEVER_STATE)

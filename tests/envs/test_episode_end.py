"""Episode ends: touchdown, truncation with its penalty, numerical failure, no touchdown; the default scene."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

HOLD = np.array([0.0, 0.0, -1.0], np.float32)
RELEASE = np.array([0.0, 0.0, 1.0], np.float32)


def test_truncation_penalty(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    env.reset(seed=0, options={"sea_state_hs_m": 0.0})
    cfg = env.unwrapped.cfg
    n = int(round(cfg.control.max_pre_release_s / cfg.control.interval_s))
    for k in range(n):
        obs, reward, terminated, truncated, info = env.step(HOLD)
        assert not terminated
        assert truncated == (k == n - 1)
    assert info["reward_terms"]["truncation"] == -cfg.reward.truncation_penalty
    assert info["sim_status"] == "time limit"
    with pytest.raises(gym.error.ResetNeeded):
        env.unwrapped.step(HOLD)


def test_time_limit_wrapper_follows_the_config(tiny, default_overrides):
    assert gym.make("moor_env/AnchorRelease-v0", overrides=default_overrides).spec.max_episode_steps == 60
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "control.max_pre_release_s": 1.0})
    assert env.spec.max_episode_steps == 4
    env.reset(seed=0)
    for k in range(4):
        obs, reward, terminated, truncated, info = env.step(HOLD)
        assert truncated == (k == 3)
    assert info["reward_terms"]["truncation"] < 0


@pytest.mark.parametrize("hs", [0.0, 2.0])
def test_numerical_failure_ends_cleanly(tiny, hs):
    # a strain limit below the hanging chain's static strain (5e-4) makes the kernel report a blow-up at once
    overrides = {**tiny, "scene_overrides.simulation.strain_limit": 1e-4, "control.warmup_s": 1.0}
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=overrides)
    obs, info = env.reset(seed=0, options={"sea_state_hs_m": hs, "current_scale": 0.0})
    assert np.all(np.isfinite(obs))
    obs, reward, terminated, truncated, info = env.step(HOLD)
    assert terminated and not truncated
    assert info["sim_status"].startswith("diverged")
    assert "strain above limit" in info["sim_status"]
    assert np.all(np.isfinite(obs))
    assert reward == info["reward_terms"]["failure"] == -env.unwrapped.cfg.reward.failure_penalty


def test_no_touchdown_penalty(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny",
                   overrides={**tiny, "scene_overrides.simulation.max_fall_time_s": 0.3})
    env.reset(seed=0, options={"sea_state_hs_m": 0.0})
    obs, reward, terminated, truncated, info = env.step(RELEASE)
    assert terminated
    assert info["sim_status"].startswith("no touchdown")
    assert info["reward_terms"]["no_touchdown"] == -3.0
    assert np.all(np.isfinite(obs))


def test_default_scene_episode(default_overrides):
    """The default config on the gjoa-500 geometry: calm, 0.1 h spacing, released after 3 s."""
    env = gym.make("moor_env/AnchorRelease-v0", overrides=default_overrides)
    obs, info = env.reset(seed=0, options={"water_depth_m": 500.0, "vessel_spacing_over_depth": 0.1,
                                           "mooring_line_length_over_depth": 1.08, "current_scale": 0.0,
                                           "sea_state_hs_m": 0.0, "chain_cd_tangential": 0.0069,
                                           "anchor_mass_scale": 1.0})
    assert abs(obs[21]) < 1e-3  # tip 68.5 m above the seabed
    for _ in range(3):
        obs, reward, terminated, truncated, info = env.step(HOLD)
        assert reward == pytest.approx(-0.002)
    obs, reward, terminated, truncated, info = env.step(RELEASE)
    assert terminated and info["sim_status"] == "touchdown"
    td = info["touchdown"]
    # seed 003 (Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*) Table 8-5: 26 m/s; README: 26.34
    assert td["speed_m_s"] == pytest.approx(26.34, abs=0.1)
    assert td["tilt_deg"] < 0.1 and td["offset_m"] < 0.1
    assert reward == pytest.approx(2.25, abs=0.02)  # speed 1 + tilt ~1 + offset ~0.25

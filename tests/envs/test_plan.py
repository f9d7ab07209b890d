"""AnchorPlan-v0: one step to touchdown, same reward terms, deterministic."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from moor_env.envs import REWARD_TERMS


def test_one_step_plan(tiny):
    env = gym.make("moor_env/AnchorPlan-v0", config="tiny", overrides=tiny)
    results = []
    for _ in range(2):
        obs, info = env.reset(seed=3, options={"sea_state_hs_m": 2.0})
        obs, reward, terminated, truncated, info = env.step(np.array([-0.5, 0.5, 0.2], np.float32))
        results.append((obs, reward))
        assert terminated and not truncated
        assert info["sim_status"] == "touchdown"
        assert tuple(info["reward_terms"]) == REWARD_TERMS
        assert reward == sum(info["reward_terms"].values())
        plan = info["plan"]
        assert plan["release_s"] >= plan["wave_reference_s"] >= env.unwrapped.cfg.plan.positioning_s - 0.01
        assert abs(plan["release_s"] - plan["wave_reference_s"] - plan["release_delay_s"]) < 0.01
    assert np.array_equal(results[0][0], results[1][0]) and results[0][1] == results[1][1]


def test_calm_plan_delay(tiny):
    env = gym.make("moor_env/AnchorPlan-v0", config="tiny", overrides=tiny)
    env.reset(seed=0, options={"sea_state_hs_m": 0.0})
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 1.0], np.float32))
    assert info["plan"]["release_delay_s"] == env.unwrapped.cfg.plan.calm_release_window_s

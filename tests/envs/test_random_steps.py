"""10,000 random-action steps: no exception, no non-finite value, reward = sum of its terms, obs in space."""

from __future__ import annotations

import math
import os

import gymnasium as gym
import numpy as np

from moor_env.envs import OBS_NAMES, REWARD_TERMS


def test_ten_thousand_random_steps(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    env.action_space.seed(123)
    obs, info = env.reset(seed=123)
    episodes, statuses = 0, {}
    # some actions outside [-1, 1] and NaN: the env clips them (NaN holds position, never releases)
    extreme = [np.array([5.0, -5.0, -3.0], np.float32), np.array([np.nan, np.nan, np.nan], np.float32)]
    for k in range(int(os.environ.get("FUZZ_STEPS", 10_000))):
        action = extreme[k % 2] if k % 997 == 0 else env.action_space.sample()
        obs, reward, terminated, truncated, info = env.step(action)
        assert obs.shape == (len(OBS_NAMES),) and obs.dtype == np.float32
        assert np.all(np.isfinite(obs)) and env.observation_space.contains(obs)
        assert math.isfinite(reward)
        terms = info["reward_terms"]
        assert tuple(terms) == REWARD_TERMS
        assert all(math.isfinite(v) for v in terms.values())
        assert reward == sum(terms.values())
        if terminated or truncated:
            episodes += 1
            statuses[info["sim_status"].split(":")[0]] = statuses.get(info["sim_status"].split(":")[0], 0) + 1
            if info["sim_status"] == "touchdown":
                assert all(math.isfinite(v) for v in info["touchdown"].values())
            obs, info = env.reset()
            assert np.all(np.isfinite(obs))
    assert episodes > int(os.environ.get("FUZZ_STEPS", 10_000)) // 10
    assert statuses.get("touchdown", 0) > 0.9 * episodes, statuses

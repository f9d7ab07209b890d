"""Gymnasium's and stable-baselines3's env checkers pass for both envs."""

from __future__ import annotations

import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

# The only warning allowed: check_env makes the env once per declared render mode; "human" cannot draw without a
# display (CI runs matplotlib's Agg backend), and the env says so once instead of failing silently.
JUSTIFIED = ("render_mode='human' needs a display",)


def _unexpected(records) -> list[str]:
    return [str(r.message) for r in records if not any(j in str(r.message) for j in JUSTIFIED)]


@pytest.mark.parametrize("env_id", ["moor_env/AnchorRelease-v0", "moor_env/AnchorPlan-v0"])
def test_gymnasium_checker(env_id, tiny):
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always")
        env = gym.make(env_id, config="tiny", overrides=tiny, render_mode="rgb_array")
        check_env(env.unwrapped)  # render modes and close are checked through env.spec
        env.close()
    assert _unexpected(records) == []


@pytest.mark.parametrize("env_id", ["moor_env/AnchorRelease-v0", "moor_env/AnchorPlan-v0"])
def test_sb3_checker(env_id, tiny):
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always")
        env = gym.make(env_id, config="tiny", overrides=tiny)
        sb3_check_env(env.unwrapped, warn=True)
        env.close()
    assert _unexpected(records) == []

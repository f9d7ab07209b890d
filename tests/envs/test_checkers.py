"""Gymnasium's and stable-baselines3's env checkers pass for every env."""

from __future__ import annotations

import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

# The warnings allowed: check_env makes the env once per declared render mode; "human" cannot draw without a
# display (CI runs matplotlib's Agg backend), and the env says so once instead of failing silently. Gymnasium
# calls AnchorPlan-v0 and AnchorRelease-v0 out of date beside their v1, which they are; they are kept on purpose
# (README).
JUSTIFIED = ("render_mode='human' needs a display", "moor_env/AnchorPlan-v0 is out of date",
             "moor_env/AnchorRelease-v0 is out of date")
# the env config each env is checked with: the miniature where it fits, AnchorPlan-v1's own (its site is deep water)
# for AnchorPlan-v1 and AnchorRelease-v1
CONFIGS = {"moor_env/AnchorRelease-v0": "tiny", "moor_env/AnchorPlan-v0": "tiny", "moor_env/AnchorPlan-v1": None,
           "moor_env/AnchorRelease-v1": None}


def _unexpected(records) -> list[str]:
    return [str(r.message) for r in records if not any(j in str(r.message) for j in JUSTIFIED)]


def _make(env_id, tiny, **kwargs):
    config = CONFIGS[env_id]
    return gym.make(env_id, **kwargs) if config is None else gym.make(env_id, config=config, overrides=tiny, **kwargs)


@pytest.mark.parametrize("env_id", list(CONFIGS))
def test_gymnasium_checker(env_id, tiny):
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always")
        env = _make(env_id, tiny, render_mode="rgb_array")
        check_env(env.unwrapped)  # render modes and close are checked through env.spec
        env.close()
    assert _unexpected(records) == []


@pytest.mark.parametrize("env_id", list(CONFIGS))
def test_sb3_checker(env_id, tiny):
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always")
        env = _make(env_id, tiny)
        sb3_check_env(env.unwrapped, warn=True)
        env.close()
    assert _unexpected(records) == []

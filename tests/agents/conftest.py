"""Fixtures of the agents tests: the ``tiny`` env config (millisecond episodes), a tiny scenario set for it, and
a tiny-budget training config."""

from __future__ import annotations

import pytest

import moor_env  # noqa: F401 - registers the envs
from moor_env.envs import load_env_config


@pytest.fixture(scope="session")
def tiny_cfg():
    """The ``tiny`` env config."""
    return load_env_config("tiny")


@pytest.fixture(scope="session")
def tiny_scenarios():
    """Three scenarios of the tiny config (calm, waves, waves with current)."""
    return [{"id": "calm", "seed": 1, "options": {"sea_state_hs_m": 0.0, "current_scale": 0.0}},
            {"id": "waves", "seed": 2, "options": {"sea_state_hs_m": 2.0, "sea_state_tp_s": 8.0}},
            {"id": "current", "seed": 3, "options": {"current_scale": 1.0, "vessel_spacing_over_depth": 0.3}}]


def tiny_train_config(out_dir, *_, **changes) -> dict:
    """A training config dict on the tiny env with a budget of tens of steps (in-process env); further positional
    arguments are ignored."""
    cfg = {
        "name": "t", "algo": "sac", "total_timesteps": 24, "seeds": [0], "n_envs": 1, "vec_env": "dummy",
        "env": {"id": "moor_env/AnchorPlan-v0", "config": "tiny", "overrides": {}},
        "policy": {"net_arch": [16], "activation": "tanh"},
        "hyperparams": {"learning_starts": 8, "batch_size": 8, "buffer_size": 1000},
        "eval": {"freq_steps": 12, "episodes": 1}, "checkpoint": {"freq_steps": 12, "keep": 2},
        "tensorboard": True, "progress_bar": False, "out_dir": str(out_dir),
    }
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(cfg.get(key), dict):
            cfg[key] = {**cfg[key], **value}
        else:
            cfg[key] = value
    return cfg

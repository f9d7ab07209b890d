"""Registration: ids, spec limits and the vector entry point."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from moor_env.envs import AnchorPlanEnv, AnchorPlanV1Env, AnchorReleaseEnv, AnchorReleaseVectorEnv


def test_ids_resolve(tiny):
    for env_id in ("moor_env/AnchorRelease-v0", "moor_env:AnchorRelease-v0", "AnchorRelease-v0"):
        env = gym.make(env_id, config="tiny", overrides=tiny)
        assert isinstance(env.unwrapped, AnchorReleaseEnv)
        assert env.spec.max_episode_steps == 20  # tiny: 5 s of 0.25 s steps
        env.close()
    for env_id in ("moor_env/AnchorPlan-v0", "moor_env:AnchorPlan-v0"):
        env = gym.make(env_id, config="tiny", overrides=tiny)
        assert isinstance(env.unwrapped, AnchorPlanEnv)
        env.close()
    for env_id in ("moor_env/AnchorPlan-v1", "moor_env:AnchorPlan-v1", "AnchorPlan-v1"):
        env = gym.make(env_id)
        assert isinstance(env.unwrapped, AnchorPlanV1Env) and env.unwrapped.cfg.name == "anchor-plan"
        env.close()
    spec = gym.spec("moor_env/AnchorRelease-v0")
    assert spec.vector_entry_point == "moor_env.envs.vector:make_vector_env"  # AnchorReleaseVectorEnv or sharded


def test_spaces(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (3,), np.float32)
    assert env.observation_space.shape == (27,)
    assert env.observation_space.dtype == np.float32
    vec = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=2, config="tiny", overrides=tiny)
    assert isinstance(vec, AnchorReleaseVectorEnv)
    assert vec.observation_space.shape == (2, 27)
    vec.close()

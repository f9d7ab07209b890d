"""Vector envs: make_vec sync/async, and the batched env's rows equal single envs bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.compile import compile_scene
from moor_env.envs import AnchorReleaseVectorEnv
from moor_env.envs.core import InstallationCore, draw_scenario


def _actions(n_envs, n_steps, seed=0):
    rng = np.random.default_rng(seed)
    acts = rng.uniform(-1, 1, (n_steps, n_envs, 3)).astype(np.float32)
    acts[..., 2] = np.where(rng.uniform(size=(n_steps, n_envs)) < 0.25, 1.0, -1.0)  # release now and then
    return acts


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_modes(tiny, mode):
    env = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=2, vectorization_mode=mode, config="tiny",
                       overrides=tiny)
    obs, info = env.reset(seed=0)
    assert obs.shape == (2, 27)
    for act in _actions(2, 6):
        obs, reward, terminated, truncated, info = env.step(act)
        assert np.all(np.isfinite(obs)) and np.all(np.isfinite(reward))
    env.close()


@pytest.mark.parametrize(("n", "threads"), [(3, 1), (3, 2), (10, 2)])  # 10 > BATCH_WIDTH: several kernel calls
def test_batched_rows_equal_single_envs(tiny, n, threads):
    steps = 40
    batched = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, vectorization_mode="vector_entry_point",
                           config="tiny", overrides=tiny, num_threads=threads)
    assert isinstance(batched, AnchorReleaseVectorEnv)
    sync = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, vectorization_mode="sync", config="tiny",
                        overrides=tiny)
    obs_b, info_b = batched.reset(seed=21)
    obs_s, info_s = sync.reset(seed=21)
    assert np.array_equal(obs_b, obs_s)
    ended = 0
    for act in _actions(n, steps, seed=4):
        out_b = batched.step(act)
        out_s = sync.step(act)
        for k in range(4):
            assert np.array_equal(out_b[k], out_s[k]), (k, out_b[k], out_s[k])
        assert np.array_equal(out_b[4]["_reward_terms"], out_s[4]["_reward_terms"])
        for term, values in out_s[4]["reward_terms"].items():
            batched_values = out_b[4]["reward_terms"][term]
            assert np.array_equal(batched_values, values), (term, batched_values - values)
        ended += int(np.sum(out_b[2] | out_b[3]))
    assert ended >= n  # autoresets happened on the way
    batched.close()
    sync.close()


def test_batched_reset_mask_and_options(tiny):
    env = AnchorReleaseVectorEnv(num_envs=2, config="tiny", overrides=tiny)
    obs, info = env.reset(seed=0, options={"sea_state_hs_m": 0.0})
    assert np.all(info["scenario"]["sea_state_hs_m"] == 0.0)
    obs2, info2 = env.reset(options={"reset_mask": np.array([False, True])})
    assert np.array_equal(obs2[0], obs[0]) and list(info2["_scenario"]) == [False, True]
    frames = AnchorReleaseVectorEnv(num_envs=1, config="tiny", overrides=tiny, render_mode="rgb_array")
    frames.reset(seed=0)
    (frame,) = frames.render()
    assert frame.ndim == 3


def test_derived_model_equals_compiled(tiny):
    """An episode's model is the cached statics model with its sea state and Cd_t: check it against a compile."""
    core = InstallationCore(gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny).unwrapped.cfg)
    rng = np.random.default_rng(0)
    for _ in range(3):
        scenario = draw_scenario(core.cfg, rng, {"sea_state_hs_m": float(rng.uniform(0.5, 3))})
        core.start(scenario)
        derived = core.sim.model
        fresh = compile_scene(core.factory.scene(scenario))
        assert derived.scene == fresh.scene
        assert derived.dt_s == fresh.dt_s
        for name, arr in fresh.arrays().items():
            assert np.array_equal(getattr(derived, name), arr), name
        for name in ("body_f", "body_q", "current_profile", "node_pos0", "body_state0", "vessel_base_m"):
            assert np.array_equal(getattr(derived, name), getattr(fresh, name)), name

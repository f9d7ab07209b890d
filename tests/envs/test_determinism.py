"""Same seed and actions give identical episodes (also from a cached equilibrium and across env instances)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.envs import equilibria, load_env_config
from moor_env.envs.scenario import representative_scenario
from moor_env.envs.scene import SceneFactory
from moor_env.errors import StaticsNotConverged


def _episode(env, seed, n_steps=12, action_seed=7):
    rng = np.random.default_rng(action_seed)
    obs, info = env.reset(seed=seed)
    out = [obs.copy()]
    rewards = []
    for _ in range(n_steps):
        action = rng.uniform(-1, 1, 3).astype(np.float32)
        action[2] = -1.0 if len(rewards) < n_steps - 1 else 1.0  # hold, then release on the last step
        obs, reward, terminated, truncated, info = env.step(action)
        out.append(obs.copy())
        rewards.append(reward)
        if terminated or truncated:
            break
    return np.array(out), np.array(rewards), info


def test_same_seed_same_episode(tiny):
    a = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    b = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    for seed in (0, 3):
        obs_a, rew_a, info_a = _episode(a, seed)
        obs_b, rew_b, info_b = _episode(b, seed)
        assert np.array_equal(obs_a, obs_b)
        assert np.array_equal(rew_a, rew_b)
        assert info_a["touchdown"] == info_b["touchdown"]
    obs_c, _, _ = _episode(a, 1)
    assert not np.array_equal(obs_c, _episode(a, 0)[0])


def test_fixed_option_keeps_other_draws(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    _, free = env.reset(seed=5)
    _, fixed = env.reset(seed=5, options={"sea_state_hs_m": 0.0})
    assert fixed["scenario"]["sea_state_hs_m"] == 0.0
    for key, value in free["scenario"].items():
        if key != "sea_state_hs_m":
            assert fixed["scenario"][key] == value


def test_cached_equilibrium_gives_identical_episode(tmp_path):
    overrides = {"statics.dir": str(tmp_path)}
    equilibria._SHARED_MEMORY.clear()
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=overrides)
    obs_solved, rew_solved, _ = _episode(env, 11)
    assert env.unwrapped.core.statics_origin in ("memory", "solved")
    equilibria._SHARED_MEMORY.clear()  # next start reads the .npz written by the first
    env2 = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=overrides)
    obs_disk, rew_disk, _ = _episode(env2, 11)
    assert env2.unwrapped.core.statics_origin == "disk"
    assert np.array_equal(obs_solved, obs_disk) and np.array_equal(rew_solved, rew_disk)


def test_a_failed_equilibrium_is_remembered_not_solved_again(tmp_path, monkeypatch):
    """A geometry whose statics do not converge fails once per cache: later draws raise at once (in this process
    from memory, in another from the ``.failed`` marker on disk) instead of repeating a solve of up to minutes."""
    calls = []

    def failing_solve(scene):
        calls.append(scene.name)
        raise StaticsNotConverged("static equilibrium not reached (test)")

    monkeypatch.setattr(equilibria, "solve_statics", failing_solve)
    monkeypatch.setattr(equilibria, "_SHARED_FAILURES", {})
    cfg = load_env_config("tiny", {"statics.dir": str(tmp_path)})
    factory = SceneFactory(cfg)
    data = factory.statics_data(representative_scenario(cfg))
    equilibria._SHARED_MEMORY.clear()
    for _ in range(2):
        with pytest.raises(StaticsNotConverged, match="not reached"):
            equilibria.EquilibriumCache(cfg.statics).state(data)
    assert len(calls) == 1
    monkeypatch.setattr(equilibria, "_SHARED_FAILURES", {})  # another process: only the disk marker
    with pytest.raises(StaticsNotConverged, match="cached failure"):
        equilibria.EquilibriumCache(cfg.statics).state(data)
    assert len(calls) == 1

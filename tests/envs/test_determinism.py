"""Same seed and actions give identical episodes (also from a kept equilibrium and across env instances); a drawn
geometry without an equilibrium is drawn again."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.config import scene_from_dict
from moor_env.envs import equilibria, load_env_config
from moor_env.envs.scenario import MAX_SCENARIO_DRAWS, draw_scenario
from moor_env.envs.scene import SceneFactory
from moor_env.errors import ConfigError, NoEquilibrium
from moor_env.simulation import solve_statics


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


def test_kept_equilibrium_gives_identical_episode(tiny):
    """A geometry drawn again starts from the equilibrium kept in memory: the same episode as a fresh solve."""
    equilibria._SHARED_MEMORY.clear()
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    obs_solved, rew_solved, _ = _episode(env, 11)
    assert env.unwrapped.core.statics_origin == "solved"
    obs_kept, rew_kept, _ = _episode(env, 11)
    assert env.unwrapped.core.statics_origin == "memory"
    fresh = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "statics.memory_entries": 0})
    obs_fresh, rew_fresh, _ = _episode(fresh, 11)
    assert fresh.unwrapped.core.statics_origin == "solved"
    for obs, rew in ((obs_kept, rew_kept), (obs_fresh, rew_fresh)):
        assert np.array_equal(obs_solved, obs) and np.array_equal(rew_solved, rew)


def _refuse_first(monkeypatch, times):
    """Make the env's solver refuse its first ``times`` calls with NoEquilibrium; the list of calls."""
    calls = []

    def solve(model, **kwargs):
        calls.append(model.scene.environment.water_depth_m)
        if len(calls) <= times:
            raise NoEquilibrium("installation.mooring_line_length_m", 1.0, "> 2 m", "the line is too short (test)")
        return solve_statics(model, **kwargs)

    monkeypatch.setattr(equilibria, "solve_statics", solve)
    return calls


def test_a_geometry_without_equilibrium_is_drawn_again(tiny, monkeypatch):
    equilibria._SHARED_MEMORY.clear()
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    _, plain = env.reset(seed=21)
    equilibria._SHARED_MEMORY.clear()
    _refuse_first(monkeypatch, 1)
    obs, info = env.reset(seed=21)
    assert info["scenario_redraws"] == 1 and info["statics"] == "solved"
    assert info["scenario"] != plain["scenario"]  # the second draw of the same generator
    assert np.all(np.isfinite(obs))
    _, again = env.reset(seed=22)
    assert again["scenario_redraws"] == 0


def test_redraws_are_bounded_and_name_the_config_keys(tiny, monkeypatch):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "statics.memory_entries": 0})
    calls = _refuse_first(monkeypatch, 10**6)
    with pytest.raises(ConfigError, match="scenario.vessel_spacing_over_depth") as info:
        env.reset(seed=0)
    assert len(calls) == MAX_SCENARIO_DRAWS
    assert "static equilibrium" in str(info.value) and "line is too short (test)" in str(info.value)
    with pytest.raises(NoEquilibrium):  # a scenario fixed by options is not drawn again
        env.reset(seed=0, options={"vessel_spacing_over_depth": 0.2})
    assert len(calls) == MAX_SCENARIO_DRAWS + 1


def test_statics_scene_from_template_equals_full_validation():
    """A new geometry's statics scene is a template's with the geometry sections validated on their own: equal to
    validating the whole mapping."""
    cfg = load_env_config("anchor-release")
    factory = SceneFactory(cfg)
    rng = np.random.default_rng(4)
    for hs in (0.0, 2.0, 0.0, 2.0, 0.0):
        scenario = draw_scenario(cfg, rng, {"sea_state_hs_m": hs, "current_scale": float(rng.choice([0.0, 1.0]))})
        data = factory.statics_data(scenario)
        assert factory.statics_scene(data) == scene_from_dict(data)
    assert len(factory.templates) == 2  # calm and in-waves pre-release resolutions

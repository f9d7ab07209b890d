"""Env configs: bundled files validate; errors name the key, its value and the allowed range."""

from __future__ import annotations

import gymnasium as gym
import pytest

from moor_env.envs import SCENARIO_FIELDS, load_env_config
from moor_env.envs.config import env_config_names
from moor_env.errors import ConfigError


def test_bundled_configs_validate():
    assert {"anchor-release", "tiny"} <= set(env_config_names())
    for name in env_config_names():
        cfg = load_env_config(name)
        assert cfg.name == name


@pytest.mark.parametrize(("overrides", "key", "allowed"), [
    ({"control.interval_s": -1.0}, "control.interval_s", "> 0"),
    ({"control.spacing_rate_max_m_s": 5.0}, "control.spacing_rate_max_m_s", "<= 2"),
    ({"control.bogus": 1.0}, "control.bogus", "a known key"),
    ({"reward.speed_weight": "high"}, "reward.speed_weight", "number"),
    ({"scenario.water_depth_m": 50.0}, "scenario.water_depth_m", "100.0 .. 3000.0"),
    ({"scenario.sea_state_hs_m": {"uniform": [3.0, 1.0]}}, "scenario.sea_state_hs_m", "uniform"),
    ({"scenario.sea_state_hs_m": {"uniform": [0.0, 9.0]}}, "scenario.sea_state_hs_m.uniform[1]", "0.0 .. 8.0"),
    ({"scenario.current_scale": {"choice": [0.0, 7.0]}}, "scenario.current_scale.choice[1]", "0.0 .. 3.0"),
    ({"scenario.current_scale": {"normal": [0.0, 1.0]}}, "scenario.current_scale", "{choice"),
    ({"control.line_length_max_over_depth": 0.5}, "control.line_length_max_over_depth", "> line_length_min"),
])
def test_errors_name_the_key(overrides, key, allowed):
    with pytest.raises(ConfigError) as exc:
        load_env_config("anchor-release", overrides)
    assert exc.value.key == key
    assert allowed in str(exc.value)


def test_unknown_config_and_scene_keys(tiny):
    with pytest.raises(ConfigError, match="config='nope'"):
        load_env_config("nope")
    with pytest.raises(ConfigError) as exc:
        gym.make("moor_env/AnchorRelease-v0", config="tiny",
                 overrides={**tiny, "fidelity.discretization.wire_segment_m": -3.0})
    assert exc.value.key == "discretization.wire_segment_m"
    with pytest.raises(ConfigError) as exc:
        gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "fidelity.discretization.nope": 1})
    assert "discretization.nope" in exc.value.key


def test_reset_options_fix_fields_and_reject_unknown(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    fixed = {"vessel_spacing_over_depth": 0.3, "sea_state_hs_m": 1.25, "sea_state_tp_s": 8.0, "sea_state_seed": 42,
             "chain_cd_tangential": 0.0069, "current_scale": 1.0}
    _, info = env.reset(seed=0, options=fixed)
    for key, value in fixed.items():
        assert info["scenario"][key] == value
    assert set(info["scenario"]) == set(SCENARIO_FIELDS)
    with pytest.raises(ConfigError, match="options.wind_speed"):
        env.reset(options={"wind_speed": 3.0})
    with pytest.raises(ConfigError, match="options.sea_state_hs_m"):
        env.reset(options={"sea_state_hs_m": 30.0})


def test_geometry_is_drawn_from_ranges():
    """The default config draws depth, spacing, line length and anchor mass from continuous ranges that span the
    values the env was validated on; every draw lies in its range and the seeds give distinct geometries."""
    import numpy as np

    from moor_env.envs.scenario import draw_scenario

    cfg = load_env_config("anchor-release")
    ranges = {"water_depth_m": (400.0, 600.0), "vessel_spacing_over_depth": (0.1, 0.3),
              "mooring_line_length_over_depth": (1.04, 1.08), "anchor_mass_scale": (0.98, 1.02)}
    for name, bounds in ranges.items():
        assert getattr(cfg.scenario, name).uniform == bounds, name
    draws = [draw_scenario(cfg, np.random.default_rng(seed)) for seed in range(40)]
    for name, (lo, hi) in ranges.items():
        values = [d[name] for d in draws]
        assert all(lo <= v <= hi for v in values), name
        assert len(set(values)) == len(values), name  # continuous: no value drawn twice
    assert draw_scenario(cfg, np.random.default_rng(3)) == draws[3]  # seeded


def test_distinct_geometries_over_reset_seeds(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    spacings, keys = set(), set()
    for seed in range(6):
        _, info = env.reset(seed=1000 + seed)
        assert info["statics"] == "solved" and info["scenario_redraws"] == 0
        spacings.add(info["scenario"]["vessel_spacing_over_depth"])
        keys.add(env.unwrapped.core.statics_key)
    assert len(spacings) == len(keys) == 6 and all(0.15 <= s <= 0.3 for s in spacings)


def test_statics_section_keeps_only_the_memory_lru():
    with pytest.raises(ConfigError, match="statics.dir"):
        load_env_config("tiny", {"statics.dir": "/tmp"})
    with pytest.raises(ConfigError, match="statics.memory_entries"):
        load_env_config("tiny", {"statics.memory_entries": -1})

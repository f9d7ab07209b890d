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


def test_precompute_grid():
    from moor_env.envs.equilibria import discrete_grid

    assert len(discrete_grid(load_env_config("tiny"))) == 4
    # 3 depths x 3 spacings x 2 line lengths x 3 masses x (no current + 2 scales x 2 directions)
    assert len(discrete_grid(load_env_config("anchor-release"))) == 270
    with pytest.raises(ValueError, match="water_depth_m is continuous"):
        discrete_grid(load_env_config("anchor-release", {"scenario.water_depth_m": {"uniform": [400.0, 600.0]}}))

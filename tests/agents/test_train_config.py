"""Training configs: bundled presets validate; every invalid value is refused naming its dotted key."""

from __future__ import annotations

import pytest

from agents.config import AGENT_CONFIG_DIR, load_train_config, parse_set
from moor_env.errors import ConfigError


@pytest.mark.parametrize("name", sorted(p.stem for p in AGENT_CONFIG_DIR.glob("*.yaml")
                                         if not p.stem.startswith("rllib")))  # RLlib configs: test_rllib.py
def test_bundled_presets_validate(name):
    cfg = load_train_config(name)
    assert cfg.name and cfg.total_timesteps > 0
    cfg.algo_params()


@pytest.mark.parametrize(("overrides", "key"), [
    ({"hyperparams.n_step": 64}, "hyperparams.n_step"),                 # unknown key (typo of n_steps)
    ({"hyperparams.learning_rate": -1.0}, "hyperparams.learning_rate"),
    ({"hyperparams.ent_coef": "sometimes"}, "hyperparams.ent_coef"),
    ({"algo": "a2c"}, "algo"),
    ({"total_timesteps": 0}, "total_timesteps"),
    ({"policy.net_arch": [64, 0]}, "policy.net_arch[1]"),
    ({"policy.activation": "sigmoid"}, "policy.activation"),
    ({"vec_env": "batched"}, "vec_env"),                                # the plan env has no batched env
    ({"seeds": [1, 1]}, "seeds"),
    ({"eval.freq_steps": 0}, "eval.freq_steps"),
    ({"colour": "red"}, "colour"),
])
def test_errors_name_the_key(overrides, key):
    with pytest.raises(ConfigError) as err:
        load_train_config("quick", overrides)
    assert err.value.key == key


def test_ppo_key_refused_for_sac():
    with pytest.raises(ConfigError) as err:
        load_train_config("quick", {"hyperparams.n_epochs": 5})
    assert err.value.key == "hyperparams.n_epochs"


def test_set_values_are_yaml_data_not_code():
    values = parse_set(["hyperparams.learning_rate=1e-3", "seeds=[0, 1]", "name=__import__('os')",
                        "env.overrides.control.interval_s=0.5"])
    assert values["hyperparams.learning_rate"] == 1e-3
    assert values["seeds"] == [0, 1]
    assert values["name"] == "__import__('os')"  # a string, never executed
    cfg = load_train_config("quick", {k: v for k, v in values.items() if k != "name"})
    assert cfg.env.overrides["control.interval_s"] == 0.5
    with pytest.raises(ConfigError) as err:
        parse_set(["novalue"])
    assert err.value.key == "--set"

"""Held-out scenario set: fixed, seeded, partly outside the training distribution; scenario files."""

from __future__ import annotations

import pytest

from agents.scenarios import (
    HELD_OUT_VALUES,
    WAVE_SEED_RANGE,
    held_out_scenarios,
    load_scenarios,
    save_scenarios,
    validate_scenarios,
)
from moor_env.envs import load_env_config
from moor_env.errors import ConfigError


def test_fixed_and_seeded():
    assert held_out_scenarios(10) == held_out_scenarios(10)
    assert held_out_scenarios(10, seed=1) != held_out_scenarios(10)
    assert len({s["id"] for s in held_out_scenarios(24)}) == 24


def test_values_not_used_in_training():
    """Currents differ from every training choice; depths and spacings reach beyond the training ranges."""
    train = load_env_config("anchor-release").scenario
    assert not set(HELD_OUT_VALUES["current_scale"]) & set(train.current_scale.choice)
    for name in ("water_depth_m", "vessel_spacing_over_depth"):
        assert max(HELD_OUT_VALUES[name]) > getattr(train, name).uniform[1], name
    scenarios = held_out_scenarios(24)
    assert any(s["options"]["sea_state_hs_m"] > train.sea_state_hs_m.uniform[1] for s in scenarios)
    assert any(s["options"]["sea_state_tp_s"] > train.sea_state_tp_s.uniform[1] for s in scenarios)
    assert all(s["options"]["sea_state_seed"] >= WAVE_SEED_RANGE[0] for s in scenarios)
    for name, values in HELD_OUT_VALUES.items():  # balanced design: every value appears
        assert {s["options"][name] for s in scenarios} == set(values)


def test_file_round_trip(tmp_path):
    scenarios = held_out_scenarios(3)
    save_scenarios(scenarios, tmp_path / "s.json")
    assert load_scenarios(tmp_path / "s.json") == scenarios


@pytest.mark.parametrize(("data", "key"), [
    ([{"id": "a", "seed": -1}], "scenarios[0].seed"),
    ([{"id": "a", "options": {"depth": 1}}], "scenarios[0].options.depth"),
    ([{"id": "a", "colour": 1}], "scenarios[0].colour"),
    ([], "scenarios"),
])
def test_validation_names_the_key(data, key):
    with pytest.raises(ConfigError) as err:
        validate_scenarios(data)
    assert err.value.key == key


def test_held_out_sites_are_fixed_and_never_drawn_in_training():
    """Same distribution as training, a generator of their own, wave seeds above every training draw."""
    from agents.scenarios import held_out_sites  # noqa: PLC0415
    from moor_env.envs.plan_config import SITE_FIELDS, TRAINING_SEED_HIGH  # noqa: PLC0415

    sites = held_out_sites(40)
    assert sites == held_out_sites(40) and held_out_sites(10) == sites[:10]
    assert len({s["id"] for s in sites}) == 40 and held_out_sites(5, seed=1) != sites[:5]
    assert all(set(s["options"]) == set(SITE_FIELDS) for s in sites)
    assert all(s["options"]["sea_state_seed"] > TRAINING_SEED_HIGH for s in sites)
    site = load_env_config("anchor-plan").site
    for name in ("water_depth_m", "sea_state_hs_m", "penetration_ratio"):
        lo, hi = getattr(site, name).uniform
        values = [s["options"][name] for s in sites]
        assert lo <= min(values) and max(values) <= hi and max(values) - min(values) > 0.5 * (hi - lo), name
    assert validate_scenarios(sites) == sites  # site fields are valid options

"""AnchorPlan-v1: spaces, levers, site and soil, the outcome and its reward, determinism, a plan without an
equilibrium, and AnchorPlan-v0 still registered beside it."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from moor_env.envs import AnchorPlanEnv, AnchorPlanV1Env, load_env_config, soil
from moor_env.envs.levers import LEVER_NAMES, TARGET_NAMES, drop_height_max_m, lever_action, lever_targets
from moor_env.envs.plan_config import SITE_FIELDS, TRAINING_SEED_HIGH
from moor_env.envs.plan_outcome import (
    MARGIN_NAMES,
    InstallationRecord,
    is_success,
    margins,
    outcome,
    smooth_success,
    soft_minimum,
)
from moor_env.envs.site import SITE_OBS_NAMES, draw_site, site_from_observation, site_measures
from moor_env.errors import ConfigError, StaticsNotConverged

ENV_ID = "moor_env/AnchorPlan-v1"
CALM = {"sea_state_hs_m": 0.0, "current_scale": 0.0, "water_depth_m": 500.0}
GOOD = {"vessel_spacing_over_depth": 0.1, "mooring_line_length_over_depth": 1.08, "vertical_chain_length_m": 50.0,
        "drop_height_m": 70.0, "release_phase": 0.25}


@pytest.fixture(scope="module")
def cfg():
    return load_env_config("anchor-plan")


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID)
    yield e
    e.close()


def _action(targets, depth_m, cfg):
    return lever_action(targets, depth_m, cfg.levers, 13.0, 0.0)


def test_spaces_and_ids(env):
    assert isinstance(env.unwrapped, AnchorPlanV1Env)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (5,), np.float32)
    assert env.observation_space == gym.spaces.Box(-5.0, 5.0, (len(SITE_OBS_NAMES),), np.float32)
    obs, info = env.reset(seed=0)
    assert obs.shape == (9,) and obs.dtype == np.float32 and env.observation_space.contains(obs)
    assert set(SITE_FIELDS) <= set(info["site"])
    v0 = gym.make("moor_env/AnchorPlan-v0", config="tiny")  # the old id keeps working
    assert isinstance(v0.unwrapped, AnchorPlanEnv) and v0.action_space.shape == (3,)


def test_levers_map_onto_their_ranges_and_back(cfg):
    lo = lever_targets(-np.ones(5), 500.0, cfg.levers, 13.0, 0.0)
    hi = lever_targets(np.ones(5), 500.0, cfg.levers, 13.0, 0.0)
    assert (lo["vessel_spacing_over_depth"], hi["vessel_spacing_over_depth"]) == (0.0, 0.5)
    assert (lo["mooring_line_length_over_depth"], hi["mooring_line_length_over_depth"]) == pytest.approx((0.95, 1.25))
    assert (lo["vertical_chain_length_m"], hi["vertical_chain_length_m"]) == (5.0, 60.0)
    assert (lo["drop_height_m"], hi["drop_height_m"]) == (30.0, 120.0)
    assert (lo["release_phase"], hi["release_phase"]) == (0.0, 1.0)
    a = np.random.default_rng(0).uniform(-1, 1, 5)
    back = lever_action(lever_targets(a, 450.0, cfg.levers, 13.0, 0.0), 450.0, cfg.levers, 13.0, 0.0)
    assert back == pytest.approx(a.astype(np.float32), abs=1e-6)
    assert np.array_equal(lever_targets([np.nan] * 5, 500.0, cfg.levers, 13.0, 0.0)["drop_height_m"], 75.0)
    assert len(LEVER_NAMES) == len(TARGET_NAMES) == 5


def test_drop_height_cut_by_the_wire_clearance(cfg):
    """At 200 m depth with a 60 m vertical chain the release node must stay 50 m below the fairlead: the tip
    hangs at most 200 - 50 - 13 - 60 = 77 m above the seabed."""
    assert drop_height_max_m(cfg.levers, 200.0, 60.0, 13.0, 0.0) == pytest.approx(77.0)
    assert drop_height_max_m(cfg.levers, 500.0, 60.0, 13.0, 0.0) == 120.0
    t = lever_targets(np.ones(5), 200.0, cfg.levers, 13.0, 0.0)
    assert t["drop_height_m"] == pytest.approx(77.0) and t["drop_height_max_m"] == pytest.approx(77.0)


def test_site_draws_options_and_soil(cfg):
    a = draw_site(cfg, np.random.default_rng(1))
    b = draw_site(cfg, np.random.default_rng(1), {"sea_state_hs_m": 0.0})
    others = [k for k in a if k != "sea_state_hs_m"]
    assert [a[k] for k in others] == [b[k] for k in others]
    assert b["sea_state_hs_m"] == 0.0 and 0 <= a["sea_state_seed"] <= TRAINING_SEED_HIGH
    for bad in ({"depth": 1.0}, {"soil_fraction": 9.0}, {"sea_state_seed": -1}):
        with pytest.raises(ConfigError):
            draw_site(cfg, np.random.default_rng(1), bad)


def test_soil_sets_the_required_speed():
    """Penetration ratio 1 with the nominal anchor asks the Gjoa design speed (25 m/s) in any soil; a deeper
    penetration or a lighter anchor asks more; the mapping is moor_env.envs.soil's, inverted exactly."""
    mass = 79_406.97
    for fraction in (0.0, 0.4, 1.0):
        site = {"soil_fraction": fraction, "penetration_ratio": 1.0, "anchor_mass_scale": 1.0}
        assert site_measures(site, mass)["required_speed_m_s"] == pytest.approx(25.0, rel=1e-9)
    base = {"soil_fraction": 0.3, "penetration_ratio": 0.97, "anchor_mass_scale": 1.0}
    m = site_measures(base, mass)
    assert site_measures({**base, "penetration_ratio": 1.02}, mass)["required_speed_m_s"] > m["required_speed_m_s"]
    assert site_measures({**base, "anchor_mass_scale": 0.97}, mass)["required_speed_m_s"] > m["required_speed_m_s"]
    z = soil.tip_penetration_m(m["required_speed_m_s"], m["soil_resistance_j_m3"], mass)
    assert z == pytest.approx(m["required_penetration_m"], rel=1e-9)
    gjoa1 = site_measures({"soil_fraction": 0.0, "penetration_ratio": 1.0, "anchor_mass_scale": 1.0}, mass)
    assert gjoa1["required_penetration_m"] == pytest.approx(20.5, rel=2e-3)  # calibrated to the Gjoa prediction


def _record(**kw):
    td = {"speed_m_s": 26.0, "tilt_deg": 0.5, "offset_m": 0.3, "chain_on_seabed_m": 0.0}
    td.update(kw.pop("td", {}))
    return InstallationRecord(td, 25.0, **{"tension_ratio": 0.5, "wire_load_ratio": 0.3, "fibre_clearance_m": 50.0,
                                           **kw})


@pytest.mark.parametrize(("record", "ok"), [
    (_record(), True),
    (_record(td={"speed_m_s": 25.0}), True),      # at the required speed
    (_record(td={"speed_m_s": 24.99}), False),
    (_record(td={"tilt_deg": 2.0}), False),       # 2 deg is not under 2 deg
    (_record(td={"offset_m": 2.01}), False),
    (_record(td={"chain_on_seabed_m": 5.5}), False),
    (_record(exceeded={"tension": True}, tension_ratio=1.2), False),
    (InstallationRecord(None, 25.0, failure="no equilibrium"), False),
])
def test_success_criterion(cfg, record, ok):
    assert is_success(record, cfg) is ok
    m = margins(record, cfg)
    assert tuple(m) == MARGIN_NAMES
    if record.touchdown is not None and not record.exceeded:
        assert (min(m.values()) >= 0.0) == ok or record.touchdown["tilt_deg"] == 2.0


def test_reward_is_a_smooth_surrogate_of_success(cfg):
    good, tight, bad = (outcome(_record(td=td), cfg) for td in ({}, {"speed_m_s": 25.05}, {"speed_m_s": 23.0}))
    assert good["success"] and tight["success"] and not bad["success"]
    assert 1.0 > good["reward"] > tight["reward"] > 0.3 > bad["reward"] > 0.0
    assert outcome(InstallationRecord(None, 25.0, failure="x"), cfg)["reward"] == 0.0
    assert soft_minimum([1.0, 5.0], 0.25) == pytest.approx(1.0 - 0.25 * math.log(1 + math.exp(-16.0)))
    assert soft_minimum([0.0, 0.0], 0.25) == pytest.approx(-0.25 * math.log(2.0))
    assert smooth_success({"a": 0.0, "b": None}, 0.25) == 0.0


def test_episode_is_deterministic_and_succeeds(env, cfg):
    runs = []
    for _ in range(2):
        obs, info = env.reset(seed=5, options={**CALM, "penetration_ratio": 0.95})
        assert site_from_observation(obs, "water_depth_m") == pytest.approx(500.0)
        runs.append((obs, *env.step(_action(GOOD, 500.0, cfg))))
    (o1, o1s, r1, term, trunc, i1), (o2, o2s, r2, *_, i2) = runs
    assert term and not trunc
    assert np.array_equal(o1, o2) and np.array_equal(o1s, o1) and r1 == r2 and i1["touchdown"] == i2["touchdown"]
    td = i1["touchdown"]
    assert i1["sim_status"] == "touchdown" and 20.0 < td["speed_m_s"] < 32.0 and i1["failure"] is None
    assert i1["targets"]["drop_height_m"] == pytest.approx(70.0)
    assert r1 == i1["reward_terms"]["success_surrogate"] and 0.0 < r1 < 1.0
    assert i1["success"] == (td["speed_m_s"] >= i1["site"]["required_speed_m_s"] and td["tilt_deg"] < 2.0
                             and td["offset_m"] <= 2.0 and not i1["limits_exceeded"])
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(5, np.float32))


def test_waves_release_at_the_chosen_phase(env, cfg):
    env.reset(seed=2, options={"sea_state_hs_m": 1.5, "sea_state_tp_s": 9.0, "water_depth_m": 450.0})
    _, _, _, _, info = env.step(_action({**GOOD, "release_phase": 0.5}, 450.0, cfg))
    plan = info["plan"]
    assert plan["release_delay_s"] == pytest.approx(4.5)
    assert plan["release_s"] == pytest.approx(plan["wave_reference_s"] + 4.5, abs=0.11)  # on the 0.1 s grid


def test_plan_without_equilibrium_fails_cleanly(env, cfg):
    """The widest spacing with the shortest line cannot span the loop: the episode ends at once as a failure."""
    env.reset(seed=0, options=CALM)
    obs, reward, terminated, truncated, info = env.step(np.array([1.0, -1.0, 0.0, 0.0, 0.0], np.float32))
    assert terminated and not truncated and reward == 0.0 and not info["success"]
    assert info["failure"].startswith("no equilibrium") and info["touchdown"] is None
    assert info["margins"]["speed"] is None and info["margins"]["tension"] is None


def test_unconverged_statics_is_not_called_no_equilibrium(env, monkeypatch):
    """A static solve that stops short of its tolerance is the solver's failure, not a geometry shown to have no
    equilibrium: the episode ends at once as a failure whose ``failure`` says so."""
    env.reset(seed=0, options=CALM)

    def stalls(*args, **kwargs):
        raise StaticsNotConverged("static equilibrium not reached after 2000 iterations", 4.9)

    monkeypatch.setattr(env.unwrapped.core, "start", stalls)
    obs, reward, terminated, truncated, info = env.step(np.zeros(5, np.float32))
    assert terminated and not truncated and reward == 0.0 and not info["success"]
    assert info["failure"].startswith("statics not converged: static equilibrium not reached")
    assert info["sim_status"] == info["failure"] and info["touchdown"] is None

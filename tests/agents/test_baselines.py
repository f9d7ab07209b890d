"""Baselines act validly on both envs; the crew rule's kinematics; the optimiser bounds the crew."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from agents.baselines import (
    CREW_MIN_VERTICAL_CHAIN_M,
    CREW_SPACING_OVER_DEPTH,
    PLAN_ENV,
    PLAN_V1_ENV,
    RELEASE_ENV,
    crew_drop_height_m,
    make_baseline,
    plan_speed_m_s,
    spacing_speed_m_s,
)
from agents.evaluate import evaluate_policy, run_episode
from moor_env.errors import ConfigError


@pytest.mark.parametrize("env_id", [PLAN_ENV, RELEASE_ENV])
@pytest.mark.parametrize("name", ["random", "crew"])
def test_actions_valid_and_episode_ends_with_touchdown(env_id, name, tiny_cfg, tiny_scenarios):
    policy = make_baseline(name, env_id, tiny_cfg)
    env = gym.make(env_id, config=tiny_cfg)
    actions = []
    act = policy.act
    policy.act = lambda obs, info: actions.append(act(obs, info)) or actions[-1]
    for sc in tiny_scenarios:
        rec = run_episode(env, policy, sc, env_id, tiny_cfg)
        assert rec["touchdown"], rec["sim_status"]  # random releases early; the crew before the time limit
    a = np.array(actions)
    assert a.shape[1] == 3 and np.isfinite(a).all() and (np.abs(a) <= 1.0).all()


def test_crew_moves_towards_tenth_of_depth(tiny_cfg):
    """Tiny config: depth 150 m, spacing 0.3 x depth = 45 m > 0.1 x depth -> the crew closes in (action < 0)."""
    policy = make_baseline("crew", RELEASE_ENV, tiny_cfg)
    env = gym.make(RELEASE_ENV, config=tiny_cfg)
    obs, info = env.reset(seed=0, options={"vessel_spacing_over_depth": 0.3})
    spacing0 = info["spacing_m"] if "spacing_m" in info else None
    from agents.policy import EpisodeContext

    policy.begin_episode(EpisodeContext(RELEASE_ENV, tiny_cfg, {}, 0, obs, info))
    assert policy.act(obs, info)[0] < 0.0
    assert spacing0 is None or spacing0 == pytest.approx(45.0, rel=1e-6)


def test_spacing_kinematics():
    """Braking speed sqrt(2 a d) capped at the DP limit; the plan speed covers the distance with its ramp."""
    assert spacing_speed_m_s(-100.0, 0.5, 0.05) == -0.5
    assert spacing_speed_m_s(1.0, 0.5, 0.05) == pytest.approx(math.sqrt(0.1))
    v = plan_speed_m_s(-10.0, 40.0, 0.5, 0.05)
    assert v < 0 and abs(v) * 40.0 - v * v / (2 * 0.05) == pytest.approx(10.0)
    assert plan_speed_m_s(-1000.0, 40.0, 0.5, 0.05) == -0.5  # out of reach: full speed


def test_optimiser_never_worse_than_crew_on_its_objective(tiny_cfg, tiny_scenarios):
    sc = tiny_scenarios[1:2]
    crew = evaluate_policy(make_baseline("crew", PLAN_ENV, tiny_cfg), sc, PLAN_ENV, tiny_cfg, progress=False)
    opt = make_baseline("optimiser", PLAN_ENV, tiny_cfg, population=3, iterations=1, elite=2)
    res = evaluate_policy(opt, sc, PLAN_ENV, tiny_cfg, progress=False)
    assert opt.evaluations == 4  # the crew's plan + one population
    score = [10 * r["episodes"][0]["success"] + r["episodes"][0]["reward"] for r in (crew, res)]
    assert score[1] >= score[0] - 1e-12


def test_unknown_and_misplaced_baselines(tiny_cfg):
    with pytest.raises(ConfigError) as err:
        make_baseline("optimiser", RELEASE_ENV, tiny_cfg)
    assert err.value.key == "baseline"
    with pytest.raises(ConfigError):
        make_baseline("oracle", PLAN_ENV, tiny_cfg)


# --- AnchorPlan-v1 -------------------------------------------------------------------------------------------------
V1_SITES = [{"id": "calm", "seed": 4, "options": {"sea_state_hs_m": 0.0, "current_scale": 0.0, "water_depth_m": 500.0,
                                                 "penetration_ratio": 0.95}},
            {"id": "waves", "seed": 7, "options": {"sea_state_hs_m": 2.0, "sea_state_tp_s": 10.0}}]


@pytest.fixture(scope="module")
def plan_cfg():
    from moor_env.envs import load_env_config  # noqa: PLC0415

    return load_env_config("anchor-plan")


def test_crew_rule_on_the_five_levers(plan_cfg):
    """Seed 003's rule (Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*) as absolute targets: 0.1 h,
    1.08 h, L_VERT 50 m, the Gjoa drop line + 2 m/s, the crest."""
    from moor_env.envs.levers import lever_targets  # noqa: PLC0415

    assert crew_drop_height_m(24.5, 0.0) == 50.0 and crew_drop_height_m(27.0, 0.0) == 75.0
    assert crew_drop_height_m(24.5) == pytest.approx(70.0)  # the median site: the thesis' working drop height
    env = gym.make(PLAN_V1_ENV)
    crew = make_baseline("crew", PLAN_V1_ENV, plan_cfg)
    obs, info = env.reset(seed=3, options={"water_depth_m": 420.0})
    a = crew.act(obs, info)
    assert a.shape == (5,) and a.dtype == np.float32 and (np.abs(a) <= 1.0).all()
    t = lever_targets(a, 420.0, plan_cfg.levers, 13.0, 0.0)
    assert t["vessel_spacing_over_depth"] == pytest.approx(CREW_SPACING_OVER_DEPTH, abs=1e-6)
    assert t["mooring_line_length_over_depth"] == pytest.approx(1.08, abs=1e-6)
    assert t["vertical_chain_length_m"] == pytest.approx(50.0, abs=1e-4)
    assert t["vertical_chain_length_m"] >= CREW_MIN_VERTICAL_CHAIN_M
    assert t["drop_height_m"] == pytest.approx(crew_drop_height_m(info["site"]["required_speed_m_s"]), abs=1e-4)
    assert t["release_phase"] == pytest.approx(0.25, abs=1e-6)


def test_v1_baselines_act_on_five_levers(plan_cfg):
    rnd = make_baseline("random", PLAN_V1_ENV, plan_cfg)
    env = gym.make(PLAN_V1_ENV, config=plan_cfg)
    rec = run_episode(env, rnd, V1_SITES[0], PLAN_V1_ENV, plan_cfg)
    assert rec["required_speed_m_s"] == pytest.approx(25.0 * 0.95 ** 2.1, rel=0.02)  # site, not reward config
    assert set(rec["targets"]) >= {"drop_height_m", "release_phase"} and rec["steps"] == 1
    assert rnd.act(np.zeros(9), {}).shape == (5,)


def test_v1_optimiser_never_worse_than_crew(plan_cfg):
    crew = evaluate_policy(make_baseline("crew", PLAN_V1_ENV, plan_cfg), V1_SITES, PLAN_V1_ENV, plan_cfg,
                           progress=False)
    opt = make_baseline("optimiser", PLAN_V1_ENV, plan_cfg, population=2, iterations=1, elite=1)
    res = evaluate_policy(opt, V1_SITES, PLAN_V1_ENV, plan_cfg, progress=False)
    assert opt.evaluations == 2 * 3 and opt.best_action.shape == (5,)
    for c, o in zip(crew["episodes"], res["episodes"], strict=True):
        assert 10 * o["success"] + o["reward"] >= 10 * c["success"] + c["reward"] - 1e-12

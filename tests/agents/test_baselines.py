"""Baselines act validly on both envs; the crew rule's kinematics; the optimiser bounds the crew."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from agents.baselines import PLAN_ENV, RELEASE_ENV, make_baseline, plan_speed_m_s, spacing_speed_m_s
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

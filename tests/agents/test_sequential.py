"""A plan policy on AnchorRelease-v1: the bundled AnchorPlan-v1 policy loaded and followed to its targets
(:class:`agents.sequential.LeverFollower`), and the episode record's positioning counts (forced release, refused
moves)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from agents.baselines import RELEASE_V1_ENV, plan_geometry
from agents.bundle import resolve_target
from agents.episodes import run_episode
from agents.policy import Policy
from agents.sequential import LeverFollower, physical_targets
from agents.train_rllib import load_run_policies
from moor_env.envs.levers import lever_targets
from moor_env.envs.site import SITE_OBS_NAMES

CALM_500 = {"water_depth_m": 500.0, "current_scale": 0.0, "current_direction_deg": 0.0, "sea_state_hs_m": 0.0}
START = {"vessel_spacing_m": 40.0, "mooring_line_length_m": 540.0, "vertical_chain_length_m": 10.0,
         "drop_height_m": 70.0}


@pytest.fixture(scope="module")
def env():
    """One AnchorRelease-v1 env for the module, on its default config (``env.unwrapped.cfg``)."""
    with gym.make(RELEASE_V1_ENV) as e:
        yield e


class _Script(Policy):
    """Plays a fixed list of actions."""

    def __init__(self, actions: list[list[float]]) -> None:
        self.actions = [np.asarray(a, np.float32) for a in actions]
        self.k = 0

    def act(self, obs, info):
        self.k += 1
        return self.actions[self.k - 1]


def test_follower_of_the_bundled_plan_policy_reaches_its_targets(env):
    """The loaded ``plan-v1-sac`` sets its targets from the 9 site values of AnchorRelease-v1's observation; the
    follower reaches them (each lever within its 0.05 m tolerance) and releases on two confirmed commands, never
    forced, with no move refused; the installation runs from the targets reached."""
    cfg = env.unwrapped.cfg
    (plan,) = load_run_policies(resolve_target("plan-v1-sac"))
    follower = LeverFollower(plan, cfg, *plan_geometry(cfg))
    scenario = {"id": "calm-500", "seed": 3, "options": {**CALM_500, "levers": START}}
    record = run_episode(env, follower, scenario, RELEASE_V1_ENV, cfg)
    obs, _ = env.reset(seed=3, options={**CALM_500, "levers": START})
    site_obs = obs[:len(SITE_OBS_NAMES)]
    goal = lever_targets(plan.act(site_obs, {}), 500.0, cfg.levers, *plan_geometry(cfg))
    reached = physical_targets(record["targets"], 500.0)
    for name, value in physical_targets(goal, 500.0).items():
        assert reached[name] == pytest.approx(value, abs=0.05), name
    assert record["targets"]["release_phase"] == pytest.approx(goal["release_phase"], abs=1e-5)
    assert record["forced_release"] is False and record["moves_refused"] == 0
    assert record["steps"] < cfg.positioning.max_steps
    assert record["failure"] is None and record["touchdown"]


def test_episode_record_counts_refused_moves(env, refuse_spacing_below_20_m):
    """Closing the spacing to 10 m has no equilibrium (made so by the fixture: refused); the release then fires on
    the second of two commands: 3 steps, 1 move refused, not forced."""
    policy = _Script([[-1.0, 0.0, 0.0, 0.0, -1.0], [0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0, 1.0]])
    scenario = {"id": "refused", "seed": 0, "options": {**CALM_500, "levers": START}}
    record = run_episode(env, policy, scenario, RELEASE_V1_ENV, env.unwrapped.cfg)
    assert record["steps"] == 3
    assert record["moves_refused"] == 1 and record["forced_release"] is False

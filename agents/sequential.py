"""A plan executed under the actuators' rate limits: any AnchorPlan-v1 policy as an ``AnchorRelease-v1`` policy.

:class:`LeverFollower` asks a plan policy (the crew's rule of thumb, a trained plan policy) for its targets on the
site it observes (the first 9 entries of AnchorRelease-v1's observation are AnchorPlan-v1's), then drives every
lever towards its target at full rate, the wire winch allowing for the chain the stopper pays in the same step
(:mod:`moor_env.envs.positioning`), and commands the release at the plan's phase once every lever is within
``tolerance_m`` of its target, or when only the confirmation steps are left before the forced release. The crew
of ``AnchorRelease-v1`` is this follower of :class:`agents.baselines.CrewPlanV1Policy`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.policy import EpisodeContext, Policy
from moor_env.envs.config import EnvConfig
from moor_env.envs.levers import lever_targets
from moor_env.envs.positioning import LEVER_STATE, POSITIONING_ACTIONS
from moor_env.envs.site import SITE_OBS_NAMES, site_from_observation

TOLERANCE_M = 0.05


class LeverFollower(Policy):
    """Drive AnchorRelease-v1's levers to a plan policy's targets, then release at the plan's phase.

    Parameters
    ----------
    plan : Policy
        A policy of ``AnchorPlan-v1`` (its ``act`` takes the site observation).
    env_config : EnvConfig
        The sequential env's config (its ``positioning`` rates and ``levers`` ranges).
    anchor_length_m, fairlead_depth_m : float
        The scene's anchor length and fairlead depth (the drop height's clearance limit).
    """

    def __init__(self, plan: Policy, env_config: EnvConfig, anchor_length_m: float, fairlead_depth_m: float,
                 tolerance_m: float = TOLERANCE_M) -> None:
        self.plan = plan
        self.name = getattr(plan, "name", "plan")
        self.cfg = env_config
        self.anchor_length_m, self.fairlead_depth_m = anchor_length_m, fairlead_depth_m
        self.tolerance_m = tolerance_m
        self.targets: dict[str, float] | None = None

    def begin_episode(self, ctx: EpisodeContext) -> None:
        """Forget the last episode's targets (the plan sees the site on the first action)."""
        self.targets = None
        self.plan.begin_episode(ctx)

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """Rate commands towards the plan's targets, or the release command (module docstring)."""
        site_obs = np.asarray(obs[:len(SITE_OBS_NAMES)])
        depth = site_from_observation(site_obs, "water_depth_m")
        if self.targets is None:
            self.targets = lever_targets(self.plan.act(site_obs, info), depth, self.cfg.levers, self.anchor_length_m,
                                         self.fairlead_depth_m)
        goal = physical_targets(self.targets, depth)
        levers = info["levers"]
        pos = self.cfg.positioning
        rates = (pos.vessel_speed_max_m_s, pos.winch_rate_max_m_s, pos.chain_rate_max_m_s)
        errors = [goal[name] - levers[name] for name in LEVER_STATE]
        action = np.zeros(len(POSITIONING_ACTIONS))
        for i, rate in enumerate(rates):
            action[i] = np.clip(errors[i] / (rate * pos.step_s), -1.0, 1.0)
        chain_step = action[2] * pos.chain_rate_max_m_s * pos.step_s
        action[3] = np.clip((errors[3] + chain_step) / (pos.wire_rate_max_m_s * pos.step_s), -1.0, 1.0)
        steps_left = pos.max_steps - int(info.get("step", 0))
        reached = max(abs(e) for e in errors) <= self.tolerance_m
        if reached or steps_left <= pos.release_confirm_steps or int(info.get("release_armed", 0)) > 0:
            action[:4] = 0.0
            action[4] = release_command(self.targets["release_phase"], self.cfg)
        else:
            action[4] = -1.0
        return action.astype(np.float32)


def physical_targets(targets: dict[str, float], depth_m: float) -> dict[str, float]:
    """AnchorPlan-v1's targets as AnchorRelease-v1's physical lever state (:data:`LEVER_STATE`)."""
    return {"vessel_spacing_m": targets["vessel_spacing_over_depth"] * depth_m,
            "mooring_line_length_m": targets["mooring_line_length_over_depth"] * depth_m,
            "vertical_chain_length_m": targets["vertical_chain_length_m"],
            "drop_height_m": targets["drop_height_m"]}


def release_command(phase: float, cfg: EnvConfig) -> float:
    """The release command that releases at ``phase`` [heave periods] (the inverse of the env's mapping)."""
    threshold = cfg.positioning.release_threshold
    fraction = min(1.0, max(0.0, phase / cfg.levers.release_window_periods))
    # just above the threshold for phase 0, so that the command counts as a release
    return float(min(1.0, threshold + max(fraction, 1e-6) * (1.0 - threshold)))

"""Baseline policies: random, the rule-of-thumb crew policy of seed 003, and a per-scenario optimiser.

``make_baseline(name, env_id)`` builds one; :data:`BASELINES` lists the names.

**Crew rule of thumb** (:class:`CrewPolicy`), from seed 003 (Landhaug 2015, "Dynamic Simulation of Dart Anchor
Installation"; sections as cited):

* spacing about 0.1 x depth: "Default vessel spacing X_DIST = 0.1 h" (section 1.4), "use as low as possible
  X_DIST" and tilt risk beyond 0.3 h (sections 4.4, 5, 6 item 7). The crew moves the second vessel towards
  0.1 x depth at the DP limits (``control``) and holds the mooring-line length (payout 0: the seed gives
  1.02-1.08 h and no rule for changing it during the operation, section 1.4).
* vertical chain at least 30 m: "keep X_DIST <~ 0.3h and L_VERT >= ~20-30 m" (section 5) and "tilt ~0 deg for
  L_VERT >= 30 m" (section 7 summary of chapter 11). The vertical chain is a scenario property in the envs (50 m
  in training, 40/50 m held out), not an action; the crew policy refuses nothing but reports it in
  ``vertical_chain_ok``.
* release when the anchor's heave velocity is near zero on a downswing: seed 003 has no waves but says "the
  release instant is not arbitrary in waves" (section 6 item 5); releasing at zero velocity at the crest is the
  crew's rule of thumb. In ``AnchorRelease-v0`` the crew watches the release node's vertical velocity
  (observation ``release_node_vz_m_s``, the anchor hangs from it) and releases on the first step where it has
  turned from upwards to downwards, once positioned (at 0.1 h within 5 m, or after ``plan.positioning_s``),
  and at the latest 3 s before the time limit. In ``AnchorPlan-v0`` the wave reference is the installation
  vessel's heave up-crossing, so the crest follows a quarter period later: delay Tp/4 (0 in calm water).

**Crew on AnchorPlan-v1** (:class:`CrewPlanV1Policy`): the same rules set as absolute targets of the five levers:

* spacing 0.1 x depth (as above);
* mooring-line length 1.08 x depth: the thesis' case study (540 m at 500 m, Ch. 8) and the upper end of its
  1.02-1.08 h (Ch. 6);
* vertical chain 50 m: the thesis' case study value (Ch. 8-10), above the 30 m from which it found no tilt
  (Ch. 11);
* drop height from the Gjoa practice: drops from about 50 m and 75 m gave 24.5 and 27 m/s (Landhaug 2015, section
  3.3, after Lieng et al. 2010), read as a line (0.1 m/s per metre) for the required speed plus a margin of
  ``CREW_SPEED_MARGIN_M_S`` (2 m/s). The margin pads the prediction as the Gjoa design did (28.5 m/s computed
  from about 70 m, 24.5-27 m/s measured), and it puts the median site (24.5 m/s required) at the thesis' working
  drop height of about 70 m (App. D; DPA 50-70 m, Ch. 2);
* release at the heave crest: a quarter period after the up-crossing (phase 0.25).

**Crew on AnchorRelease-v1**: the same targets, driven to at the actuators' rates and released at the crest once
reached (:class:`agents.sequential.LeverFollower`).

**Optimiser** (:class:`OptimiserPolicy`, the plan envs ``AnchorPlan-v0`` and ``-v1``): for each scenario a
cross-entropy search over the plan's actions, each candidate scored by replaying the very scenario (same seed and
options, so the score is exact): score = 10 x success + reward. It starts from the crew's plan and also tries it,
so it is never worse than the crew on its own objective. It sees the scenario and the future, so it bounds what a
policy can reach (at ``1 + population x iterations`` episodes per scenario).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from agents.policy import EpisodeContext, Policy
from agents.sequential import LeverFollower
from agents.success import episode_success
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.levers import LEVER_NAMES, lever_action
from moor_env.envs.observation import OBS_NAMES, OBS_OFFSET, OBS_SCALE
from moor_env.envs.scene import SceneFactory
from moor_env.envs.site import site_from_observation
from moor_env.errors import ConfigError

PLAN_ENV = "moor_env/AnchorPlan-v0"
PLAN_V1_ENV = "moor_env/AnchorPlan-v1"
RELEASE_ENV = "moor_env/AnchorRelease-v0"
RELEASE_V1_ENV = "moor_env/AnchorRelease-v1"
BASELINES = ("random", "crew", "optimiser")
CREW_SPACING_OVER_DEPTH = 0.1
CREW_MIN_VERTICAL_CHAIN_M = 30.0
CREW_LINE_LENGTH_OVER_DEPTH = 1.08
CREW_VERTICAL_CHAIN_M = 50.0
GJOA_DROPS = ((50.0, 24.5), (75.0, 27.0))  # (drop height [m], touchdown speed [m/s]) at Gjoa
CREW_SPEED_MARGIN_M_S = 2.0
CREW_RELEASE_PHASE = 0.25  # the heave crest, a quarter period after the up-crossing
CREW_POSITION_TOLERANCE_M = 5.0
CREW_DEADLINE_MARGIN_S = 3.0

_IDX = {name: i for i, name in enumerate(OBS_NAMES)}


def physical(obs: np.ndarray, name: str) -> float:
    """One observation entry in physical units (exact unless the entry was clipped at +-5)."""
    i = _IDX[name]
    return float(obs[i]) * OBS_SCALE[i] + OBS_OFFSET[i]


def is_plan_env(env_id: str) -> bool:
    """Whether ``env_id`` is a one-step plan env (``AnchorPlan-v0`` or ``-v1``)."""
    return env_id.split("/")[-1] in (PLAN_ENV.split("/")[-1], PLAN_V1_ENV.split("/")[-1])


def is_plan_v1(env_id: str) -> bool:
    """Whether ``env_id`` is ``AnchorPlan-v1`` (five levers on an observed site)."""
    return env_id.split("/")[-1] == PLAN_V1_ENV.split("/")[-1]


def is_release_v1(env_id: str) -> bool:
    """Whether ``env_id`` names AnchorRelease-v1 (the levers moved step by step, AnchorPlan-v1's site)."""
    return env_id.split("/")[-1] == RELEASE_V1_ENV.split("/")[-1]


def action_size(env_id: str) -> int:
    """Number of actions of an env: 5 on ``AnchorPlan-v1`` and ``AnchorRelease-v1``, else 3."""
    return len(LEVER_NAMES) if is_plan_v1(env_id) or is_release_v1(env_id) else 3


class RandomPolicy(Policy):
    """Uniform actions in [-1, 1]^k (k = ``size``) from its own seeded generator (reseeded per episode from the
    scenario seed)."""

    name = "random"

    def __init__(self, seed: int = 0, size: int = 3) -> None:
        self.seed = seed
        self.size = size
        self.rng = np.random.default_rng(seed)

    def begin_episode(self, ctx: EpisodeContext) -> None:
        """Reseed so that an episode's actions depend only on (policy seed, scenario seed)."""
        self.rng = np.random.default_rng([self.seed, ctx.seed])

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """A uniform random action."""
        return self.rng.uniform(-1.0, 1.0, self.size).astype(np.float32)


def spacing_speed_m_s(error_m: float, speed_max_m_s: float, accel_max_m_s2: float) -> float:
    """Signed speed that closes a spacing error without overshoot under the DP acceleration limit."""
    return math.copysign(min(speed_max_m_s, math.sqrt(2.0 * accel_max_m_s2 * abs(error_m))), error_m)


def plan_speed_m_s(error_m: float, duration_s: float, speed_max_m_s: float, accel_max_m_s2: float) -> float:
    """Constant commanded speed whose ramped move over ``duration_s`` covers ``error_m`` (as far as possible).

    The DP ramps the speed up at ``accel_max``: a move at speed v covers v * T - v^2 / (2 a); solved for v.
    """
    a, big_t = accel_max_m_s2, duration_s
    disc = big_t * big_t - 2.0 * abs(error_m) / a
    v = a * (big_t - math.sqrt(disc)) if disc >= 0.0 else a * big_t
    return math.copysign(min(v, speed_max_m_s), error_m)


class CrewPolicy(Policy):
    """The rule-of-thumb crew (see the module docstring for the rules and their sources)."""

    name = "crew"

    def __init__(self, env_id: str, env_config: EnvConfig) -> None:
        self.plan = is_plan_env(env_id)
        self.cfg = env_config
        self.prev_vz = None
        self.vertical_chain_ok = True

    def begin_episode(self, ctx: EpisodeContext) -> None:
        """Forget the last episode's heave history."""
        self.prev_vz = None
        self.vertical_chain_ok = physical(ctx.obs, "vertical_chain_length_m") >= CREW_MIN_VERTICAL_CHAIN_M

    def target_error_m(self, obs: np.ndarray) -> float:
        """Spacing target (0.1 x depth, within the DP limits) minus the current spacing [m]."""
        c = self.cfg.control
        depth = physical(obs, "water_depth_m")
        target = min(max(CREW_SPACING_OVER_DEPTH * depth, c.spacing_min_m), c.spacing_max_over_depth * depth)
        return target - physical(obs, "vessel_spacing_m")

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """Spacing towards 0.1 h, payout 0, release at the heave crest once positioned."""
        c = self.cfg.control
        error = self.target_error_m(obs)
        if self.plan:
            v = plan_speed_m_s(error, self.cfg.plan.positioning_s, c.spacing_rate_max_m_s, c.spacing_accel_max_m_s2)
            calm = physical(obs, "sea_state_hs_m") <= 0.0
            return np.array([v / c.spacing_rate_max_m_s, 0.0, -1.0 if calm else -0.5], dtype=np.float32)
        v = spacing_speed_m_s(error, c.spacing_rate_max_m_s, c.spacing_accel_max_m_s2)
        t_s = physical(obs, "time_fraction") * c.max_pre_release_s
        vz = physical(obs, "release_node_vz_m_s")
        positioned = abs(error) <= CREW_POSITION_TOLERANCE_M or t_s >= self.cfg.plan.positioning_s
        crest = physical(obs, "sea_state_hs_m") <= 0.0 or (self.prev_vz is not None and self.prev_vz > 0.0 >= vz)
        deadline = t_s >= c.max_pre_release_s - CREW_DEADLINE_MARGIN_S
        self.prev_vz = vz
        release = 1.0 if (positioned and crest) or deadline else -1.0
        return np.array([v / c.spacing_rate_max_m_s, 0.0, release], dtype=np.float32)


def crew_drop_height_m(required_speed_m_s: float, margin_m_s: float = CREW_SPEED_MARGIN_M_S) -> float:
    """The crew's drop height for a required speed [m]: the line through the Gjoa drops (:data:`GJOA_DROPS`) at
    the required speed plus ``margin_m_s``."""
    (h0, v0), (h1, v1) = GJOA_DROPS
    return h0 + (required_speed_m_s + margin_m_s - v0) * (h1 - h0) / (v1 - v0)


def plan_geometry(cfg: EnvConfig) -> tuple[float, float]:
    """The anchor length and fairlead depth [m] of an env config's scene (what the drop height's clearance needs)."""
    factory = SceneFactory(cfg)
    return factory.anchor_length_m, factory.fairlead_depth_m


class CrewPlanV1Policy(Policy):
    """The rule-of-thumb crew on ``AnchorPlan-v1``: absolute targets from the site it observes (module docstring)."""

    name = "crew"

    def __init__(self, env_config: EnvConfig) -> None:
        self.cfg = env_config
        self.anchor_length_m, self.fairlead_depth_m = plan_geometry(env_config)

    def targets(self, obs: np.ndarray) -> dict[str, float]:
        """The crew's targets of the levers for a site observation."""
        return {"vessel_spacing_over_depth": CREW_SPACING_OVER_DEPTH,
                "mooring_line_length_over_depth": CREW_LINE_LENGTH_OVER_DEPTH,
                "vertical_chain_length_m": CREW_VERTICAL_CHAIN_M,
                "drop_height_m": crew_drop_height_m(site_from_observation(obs, "required_speed_m_s")),
                "release_phase": CREW_RELEASE_PHASE}

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The action of :meth:`targets`."""
        return lever_action(self.targets(obs), site_from_observation(obs, "water_depth_m"), self.cfg.levers,
                            self.anchor_length_m, self.fairlead_depth_m)


class OptimiserPolicy(Policy):
    """Per-scenario cross-entropy search on a plan env (an upper bound; see the module docstring)."""

    name = "optimiser"

    def __init__(self, env_config: EnvConfig, population: int = 8, iterations: int = 3, elite: int = 3,
                 seed: int = 0, env_id: str = PLAN_ENV) -> None:
        if population < 2 or iterations < 1 or not 1 <= elite <= population:
            raise ConfigError("optimiser", (population, iterations, elite),
                              "population >= 2, iterations >= 1, 1 <= elite <= population")
        self.cfg = env_config
        self.env_id = env_id
        self.population, self.iterations, self.elite, self.seed = population, iterations, elite, seed
        self.crew = make_baseline("crew", env_id, env_config)
        self.size = action_size(env_id)
        self._env = None
        self.best_action = np.zeros(self.size, dtype=np.float32)
        self.best_score = -math.inf
        self.evaluations = 0

    def score(self, ctx: EpisodeContext, action: np.ndarray) -> float:
        """10 x success + reward of ``action`` replayed on the episode's scenario."""
        if self._env is None:
            self._env = gym.make(self.env_id, config=self.cfg)
        self._env.reset(seed=ctx.seed, options=ctx.scenario)
        _, reward, _, _, info = self._env.step(action)
        self.evaluations += 1
        return 10.0 * float(episode_success(info, self.cfg)) + float(reward)

    def begin_episode(self, ctx: EpisodeContext) -> None:
        """Search the plan for this scenario."""
        rng = np.random.default_rng([self.seed, ctx.seed])
        self.crew.begin_episode(ctx)
        mean = self.crew.act(ctx.obs, ctx.info).astype(np.float64)
        std = np.full(self.size, 0.5)
        self.best_action, self.best_score = mean.astype(np.float32), self.score(ctx, mean)
        for _ in range(self.iterations):
            cands = np.clip(mean + std * rng.standard_normal((self.population, self.size)), -1.0, 1.0)
            scores = np.array([self.score(ctx, a) for a in cands])
            order = np.argsort(-scores)
            if scores[order[0]] > self.best_score:
                self.best_score, self.best_action = float(scores[order[0]]), cands[order[0]].astype(np.float32)
            elites = cands[order[: self.elite]]
            mean, std = elites.mean(axis=0), np.maximum(elites.std(axis=0), 0.05)

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The best plan found for this scenario."""
        return self.best_action


def make_baseline(name: str, env_id: str = PLAN_ENV, env_config: str | dict | EnvConfig = "anchor-release",
                  **kwargs: Any) -> Policy:
    """Build a baseline by name (``random``, ``crew``, ``optimiser``) for ``env_id`` and its env config.

    ``kwargs`` go to the policy (``seed`` for random; ``population``, ``iterations``, ``elite``, ``seed`` for the
    optimiser). The optimiser exists for the plan envs only.
    """
    cfg = env_config if isinstance(env_config, EnvConfig) else load_env_config(env_config)
    if name == "random":
        return RandomPolicy(size=action_size(env_id), **kwargs)
    if name == "crew" and is_release_v1(env_id):
        return LeverFollower(CrewPlanV1Policy(cfg), cfg, *plan_geometry(cfg), **kwargs)
    if name == "crew":
        return CrewPlanV1Policy(cfg, **kwargs) if is_plan_v1(env_id) else CrewPolicy(env_id, cfg, **kwargs)
    if name == "optimiser":
        if not is_plan_env(env_id):
            raise ConfigError("baseline", name, f"the optimiser baseline runs on {PLAN_ENV} and {PLAN_V1_ENV} only")
        return OptimiserPolicy(cfg, env_id=env_id, **kwargs)
    raise ConfigError("baseline", name, "one of " + ", ".join(BASELINES))

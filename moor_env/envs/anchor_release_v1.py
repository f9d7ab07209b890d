"""``moor_env/AnchorRelease-v1``: the crew's five levers commanded step by step under their actuators' rate limits."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from moor_env.envs import measures
from moor_env.envs.anchor_plan_v1 import PLAN_V1_CONFIG, AnchorPlanV1Env
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.levers import episode_scenario
from moor_env.envs.positioning import (
    LEVER_STATE,
    POSITIONING_ACTIONS,
    lever_fractions,
    lever_ranges,
    move_levers,
    plan_targets,
    release_decision,
)
from moor_env.envs.render import snapshot
from moor_env.envs.site import SITE_OBS_NAMES
from moor_env.errors import ConfigError, NoEquilibrium, StaticsNotConverged

# (name, unit, offset, scale) of the entries after the site's: observation = (raw - offset) / scale, clipped
STATE_OBS_SPEC: tuple[tuple[str, str, float, float], ...] = (
    ("vessel_spacing", "-", 0.0, 1.0),
    ("mooring_line_payout", "-", 0.0, 1.0),
    ("vertical_chain", "-", 0.0, 1.0),
    ("drop_height", "-", 0.0, 1.0),
    ("mooring_line_tension_ratio", "-", 0.3, 0.3),
    ("wire_load_ratio", "-", 0.5, 0.5),
    ("fibre_clearance_m", "m", 50.0, 50.0),
    ("tilt_deg", "deg", 0.0, 2.0),
    ("steps_left_fraction", "-", 0.5, 0.5),
    ("release_armed_fraction", "-", 0.5, 0.5),
    ("move_refused", "-", 0.5, 0.5),
)
OBS_NAMES_V1: tuple[str, ...] = (*SITE_OBS_NAMES, *(row[0] for row in STATE_OBS_SPEC))
OBS_CLIP_V1 = 5.0
_STATE_OFFSET = np.array([row[2] for row in STATE_OBS_SPEC])
_STATE_SCALE = np.array([row[3] for row in STATE_OBS_SPEC])


class AnchorReleaseV1Env(gym.Env):
    r"""Position a dart-anchor installation step by step and decide when to release it, on an observed site.

    ## Description

    The sequential counterpart of ``moor_env/AnchorPlan-v1``, with the same site (depth, current, sea state, anchor
    mass, soil and its required touchdown speed; chain drag and wave train hidden), the same five levers, the same
    installation and the same success and reward. Here the crew does not set the levers at will: each step of
    ``positioning.step_s`` (60 s) moves them at most as far as their actuators' rates allow
    (:mod:`moor_env.envs.positioning`): the second vessel's DP (0.5 m/s), its mooring-line winch (0.3 m/s), the
    release unit's chain stopper (0.2 m/s) and the installation vessel's wire winch (0.5 m/s). Every step ends at
    the hanging equilibrium of the geometry reached, solved fresh (:func:`moor_env.solve_statics`): the vessels move
    slowly against the lines' swing periods, so the positioning is quasi-static and the waves act only in the
    installation. What that leaves out (the lag of the release point behind the equilibrium after a full-rate move,
    the dynamic tension peaks) is measured against the dynamic simulation of the same moves by
    ``benchmarks/positioning_quasi_static.py`` (``docs/positioning.md``). A move into a geometry without an
    equilibrium (the fibre rope on the seabed, a line too short, a loop resting on the anchor that the static solver
    does not settle) is not carried out: the levers stay, ``info["move_refused"]`` says why.

    A release command above ``positioning.release_threshold`` (0.5) on ``positioning.release_confirm_steps`` (2)
    consecutive steps releases the anchor: the installation then runs as AnchorPlan-v1's from the levers reached
    (warm-up in waves, release at the commanded phase after the installation vessel's heave up-crossing, fall to
    touchdown). A uniformly random command confirms with probability 1/16 per pair of steps, so random exploration
    does not release at once. At ``positioning.max_steps`` (16) the release is forced at phase 0. The episode
    starts from a geometry drawn uniformly over the levers' ranges (drawn again until it has an equilibrium):
    the default rates take every lever across its whole range in 11 steps at the deepest site (650 m,
    :func:`moor_env.envs.positioning.steps_to_reach`), so any target is reachable with steps to spare.

    ## Action Space

    ``Box(-1, 1, (5,), float32)`` (NaN counts as 0):

    | index | name | physical command for a in [-1, 1] |
    |---|---|---|
    | 0 | vessel_dp | spacing change a * 0.5 m/s * 60 s |
    | 1 | mooring_line_winch | payout (+) or haul-in (-) a * 0.3 m/s * 60 s |
    | 2 | chain_stopper | chain from the loop into the vertical chain a * 0.2 m/s * 60 s |
    | 3 | wire_winch | wire hauled in (+) a * 0.5 m/s * 60 s; the drop height changes by it minus the chain paid |
    | 4 | release | > 0.5 on 2 consecutive steps releases; phase (a - 0.5) / 0.5 x 1 heave period |

    Each lever stays within AnchorPlan-v1's ranges (config ``levers``): spacing 0-0.5 h, mooring line 0.95-1.25 h,
    vertical chain 5-60 m, drop height 30 m to the clearance limit.

    ## Observation Space

    ``Box(-5, 5, (20,), float32)``: (raw - offset) / scale, clipped. Entries 0-8 are AnchorPlan-v1's site
    observation; then:

    | index | name | unit | offset | scale | meaning |
    |---|---|---|---|---|---|
    | 9 | vessel_spacing | - | 0 | 1 | spacing's place in its range, -1 .. +1 (as the plan's action) |
    | 10 | mooring_line_payout | - | 0 | 1 | mooring-line length's place in its range |
    | 11 | vertical_chain | - | 0 | 1 | vertical chain's place in its range |
    | 12 | drop_height | - | 0 | 1 | drop height's place in its range (its upper end follows the chain) |
    | 13 | mooring_line_tension_ratio | - | 0.3 | 0.3 | static top tension of the mooring line / its MBL |
    | 14 | wire_load_ratio | - | 0.5 | 0.5 | static wire load on the installation vessel / release unit rating |
    | 15 | fibre_clearance_m | m | 50 | 50 | lowest fibre-rope node above the seabed |
    | 16 | tilt_deg | deg | 0 | 2 | anchor tilt in the equilibrium |
    | 17 | steps_left_fraction | - | 0.5 | 0.5 | steps left before the forced release / max_steps |
    | 18 | release_armed_fraction | - | 0.5 | 0.5 | consecutive release commands / release_confirm_steps |
    | 19 | move_refused | - | 0.5 | 0.5 | 1 where the last move was not carried out |

    ## Rewards

    0 on every positioning step; on the release step AnchorPlan-v1's reward (a smooth surrogate of success in
    [0, 1]) of the installation, so the return orders policies as AnchorPlan-v1's reward does.

    ## Starting State

    The site is drawn from the config's ``site`` section (``reset(options=...)`` fixes its fields by name,
    ``moor_env.envs.plan_config.SITE_FIELDS``); the levers' start is drawn uniformly over their ranges with the
    env's generator until its equilibrium exists (``positioning.max_start_draws``; ``info["start_draws"]``), or
    set by ``options["levers"]`` (every name of :data:`~moor_env.envs.positioning.LEVER_STATE`, physical values;
    a start without an equilibrium raises :class:`~moor_env.errors.NoEquilibrium`).

    ## Episode End

    Terminated on the release step (commanded or forced at ``positioning.max_steps``): the installation's outcome
    is in ``info`` as AnchorPlan-v1's (``success``, ``margins``, ``limits_exceeded``, ``touchdown``, ``failure``).
    Never truncated.

    ## Arguments

    ```python
    gym.make("moor_env/AnchorRelease-v1", config="anchor-plan", overrides=None, render_mode=None)
    ```

    ``config``, ``overrides`` as AnchorPlan-v1's (the ``positioning`` section holds this env's keys);
    ``render_mode="rgb_array"``: ``render()`` draws the equilibrium reached (the installation after the release),
    ``fall_frames()`` the fall. ``info`` on a positioning step: ``levers`` (physical, :data:`LEVER_STATE`),
    ``statics`` (the measures observed), ``move_refused``, ``release_armed``, ``step``.

    ## Version History

    * v1: the five levers of AnchorPlan-v1 as rate commands over quasi-static 60 s steps, the site and the
      equilibrium as the observation (20 values), a confirmed release, AnchorPlan-v1's installation and reward.
    * v0 (``moor_env/AnchorRelease-v0``, kept): spacing and payout rates in 1 s dynamic steps and a release on
      the first positive command, on AnchorRelease-v0's scenarios.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, config: str | Path | dict | EnvConfig = PLAN_V1_CONFIG,
                 overrides: dict[str, Any] | None = None, render_mode: str | None = None) -> None:
        self.cfg = load_env_config(config, overrides)
        self.plan = AnchorPlanV1Env(self.cfg, render_mode=render_mode)
        self.render_mode = render_mode
        self.action_space = spaces.Box(-1.0, 1.0, (len(POSITIONING_ACTIONS),), np.float32)
        self.observation_space = spaces.Box(-OBS_CLIP_V1, OBS_CLIP_V1, (len(OBS_NAMES_V1),), np.float32)
        self.levers: dict[str, float] = {}
        self.statics: dict[str, float] = {}
        self.steps = 0
        self.armed = 0
        self._site_obs = np.zeros(len(SITE_OBS_NAMES), np.float32)
        self._refused = False
        self._done = True
        self._installed = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a site and a start geometry with an equilibrium; the first observation."""
        super().reset(seed=seed)
        options = dict(options or {})
        start = options.pop("levers", None)
        site_obs, info = self.plan.reset(seed=int(self.np_random.integers(2**31 - 1)), options=options)
        self._site_obs = site_obs
        self.steps, self.armed, self._refused, self._done, self._installed = 0, 0, False, False, False
        draws = self._draw_start() if start is None else self._fixed_start(start)
        info.update(levers=dict(self.levers), statics=dict(self.statics), start_draws=draws)
        return self._observe(), info

    def step(self, action):
        """One positioning step, or the release and the installation (class docstring)."""
        if self._done:
            raise gym.error.ResetNeeded("call reset() before step()")
        a = np.asarray(action, dtype=np.float64).reshape(len(POSITIONING_ACTIONS))
        self.steps += 1
        pos = self.cfg.positioning
        self.armed, fire, phase = release_decision(a[4], self.armed, pos, self.cfg.levers.release_window_periods)
        if fire or self.steps >= pos.max_steps:
            return self._release(phase if fire else 0.0, forced=not fire)
        new = move_levers(self.levers, a, self._depth_m, self.cfg.levers, pos, *self._vessel_geometry())
        refused = None
        if new != self.levers:
            try:
                self._settle(new)
            except (ConfigError, StaticsNotConverged) as exc:
                refused = str(exc)
        self._refused = refused is not None
        info = {"levers": dict(self.levers), "statics": dict(self.statics), "move_refused": refused,
                "release_armed": self.armed, "step": self.steps, "reward_terms": {"success_surrogate": 0.0}}
        return self._observe(), 0.0, False, False, info

    def render(self):
        """``render_mode="rgb_array"``: the equilibrium reached, or the installation after the release."""
        if self.render_mode != "rgb_array" or self.plan.core.sim is None:
            return None
        if self._installed:
            return self.plan.render()
        return self.plan._draw(snapshot(self.plan.core))

    def fall_frames(self, which: list[int] | None = None) -> list[np.ndarray]:
        """Frames of the fall after the release (AnchorPlan-v1's)."""
        return self.plan.fall_frames(which)

    def close(self):
        """Drop the figure."""
        self.plan.close()

    @property
    def obs_names(self) -> tuple[str, ...]:
        """Names of the observation entries."""
        return OBS_NAMES_V1

    # --- helpers -----------------------------------------------------------------------------------------------
    @property
    def _depth_m(self) -> float:
        return float(self.plan.site["water_depth_m"])

    def _vessel_geometry(self) -> tuple[float, float]:
        factory = self.plan.core.factory
        return factory.anchor_length_m, factory.fairlead_depth_m

    def _draw_start(self) -> int:
        """Draw start levers until their equilibrium exists; the number of draws."""
        levers = self.cfg.levers
        last = None
        for draw in range(1, self.cfg.positioning.max_start_draws + 1):
            u = self.np_random.uniform(-1.0, 1.0, len(LEVER_STATE))
            chain_lo, chain_hi = levers.vertical_chain_length_m
            chain = chain_lo + 0.5 * (u[2] + 1.0) * (chain_hi - chain_lo)
            ranges = lever_ranges(levers, self._depth_m, chain, *self._vessel_geometry())
            start = {name: float(lo + 0.5 * (x + 1.0) * (hi - lo))
                     for name, x, (lo, hi) in zip(LEVER_STATE, u, ranges, strict=True)}
            try:
                self._settle(start)
                return draw
            except (ConfigError, StaticsNotConverged) as exc:
                last = exc
        raise NoEquilibrium("positioning.max_start_draws", self.cfg.positioning.max_start_draws,
                            "more draws", f"no start geometry with an equilibrium was drawn ({last})")

    def _fixed_start(self, start: dict[str, float]) -> int:
        """Start from the levers ``start`` (every name of :data:`LEVER_STATE`, within its range); 0 draws."""
        if not isinstance(start, dict) or sorted(start) != sorted(LEVER_STATE):
            raise ConfigError("options.levers", start, "a mapping of " + ", ".join(LEVER_STATE))
        chain = float(start["vertical_chain_length_m"])
        ranges = lever_ranges(self.cfg.levers, self._depth_m, chain, *self._vessel_geometry())
        for name, (lo, hi) in zip(LEVER_STATE, ranges, strict=True):
            if not lo - 1e-9 <= float(start[name]) <= hi + 1e-9:
                raise ConfigError(f"options.levers.{name}", start[name], f"{lo:.6g} .. {hi:.6g} at this site")
        self._settle({name: float(start[name]) for name in LEVER_STATE})
        return 0

    def _settle(self, levers: dict[str, float]) -> None:
        """Solve the equilibrium of ``levers`` on the site and take it as the state (raises where there is none)."""
        core = self.plan.core
        targets = plan_targets(levers, self._depth_m, 0.0, self.cfg.levers, *self._vessel_geometry())
        core.start(episode_scenario(self.plan.site, targets))
        sim = core.sim
        tops = sim.top_tensions_n()
        lowest, lowest_fibre, _ = measures.mooring_line(sim, core.buffers, core.lines["mooring_line"], core.fibre_mat)
        self.statics = {"mooring_line_tension_ratio": tops["mooring_line"] / core.mbl["mooring_line"],
                        "wire_load_ratio": tops["wire"] / core.release_unit_limit_n,
                        "fibre_clearance_m": lowest_fibre + core.depth, "loop_bottom_m": lowest + core.depth,
                        "tilt_deg": sim.tilt_deg()}
        self.levers = dict(levers)

    def _release(self, phase: float, forced: bool):
        targets = plan_targets(self.levers, self._depth_m, phase, self.cfg.levers, *self._vessel_geometry())
        reward, info = self.plan.install(targets)
        self._done, self._installed = True, True
        info.update(levers=dict(self.levers), statics=dict(self.statics), move_refused=None,
                    release_armed=self.armed, step=self.steps, forced_release=forced)
        return self._observe(), reward, True, False, info

    def _observe(self) -> np.ndarray:
        pos = self.cfg.positioning
        fractions = lever_fractions(self.levers, self._depth_m, self.cfg.levers, *self._vessel_geometry())
        st = self.statics
        raw = np.array([*fractions, st["mooring_line_tension_ratio"], st["wire_load_ratio"], st["fibre_clearance_m"],
                        st["tilt_deg"], 1.0 - self.steps / pos.max_steps, self.armed / pos.release_confirm_steps,
                        float(self._refused)])
        state = np.clip((raw - _STATE_OFFSET) / _STATE_SCALE, -OBS_CLIP_V1, OBS_CLIP_V1).astype(np.float32)
        return np.concatenate([self._site_obs, state])

"""``moor_env/AnchorPlan-v1``: the crew's installation plan as one decision on an observed site (contextual bandit)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from moor_env.envs.anchor_plan import next_upcrossing_s
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.core import InstallationCore, run_advance
from moor_env.envs.levers import LEVER_NAMES, episode_scenario, lever_targets
from moor_env.envs.plan_outcome import InstallationRecord, outcome
from moor_env.envs.render import PlanFrames, snapshot
from moor_env.envs.site import SITE_OBS_CLIP, SITE_OBS_NAMES, draw_site, site_measures, site_observation
from moor_env.errors import ConfigError, StaticsNotConverged

PLAN_V1_CONFIG = "anchor-plan"


class AnchorPlanV1Env(PlanFrames, gym.Env):
    r"""Plan a dart-anchor installation on an observed site: one action sets the crew's five levers.

    ## Description

    A contextual bandit. The reset draws a **site** the crew cannot choose (``site`` section of the config): water
    depth, current strength and direction, sea state, the anchor's mass as weighed, and the **soil**, given as the
    tip penetration the anchor must reach, which sets the touchdown speed required
    (:mod:`moor_env.envs.soil`: total impact energy against the soil's embedment resistance, calibrated to the
    Gjoa predictions). The chain's tangential drag (+-25 %) and the wave train stay hidden. The one action sets
    **absolute targets** of the crew's levers: vessel spacing, mooring-line payout, vertical chain, drop height and
    the release phase. The installation then runs in the numba model: the hanging equilibrium of the chosen
    geometry is solved fresh (:func:`moor_env.solve_statics`), the waves are ramped in over ``control.warmup_s``,
    the vessels hold station until the chosen phase after the next up-crossing of the installation vessel's heave,
    the anchor is released and falls to touchdown. The geometry is set directly (the DP, winches and wire winch
    are not simulated moving there). A geometry without an equilibrium (a line too short, fibre on the seabed),
    or one whose static solve does not converge, ends the episode as a failure, with the solver's reason in
    ``info["failure"]``.

    The lever ranges and their sources (Landhaug 2015, "Dynamic Simulation of Dart Anchor Installation", seed 003,
    by chapter; the Gjoa field figures after Lieng et al. 2010, its section 3.3):

    * **vessel spacing 0-0.5 h**: 0.1 h is the thesis' default (§6.2), 0.34 h the widest it tested (Ch. 10-11),
      with tilt beyond 0.3 h; 0.5 h is AnchorRelease-v0's DP limit; 0 puts the second vessel over the anchor.
    * **mooring-line length 0.95-1.25 h** (the payout, vertical chain included): the thesis' 1.02-1.08 h
      (Ch. 6), with its warning that the length should follow depth and spacing (too long piles chain on the
      seabed, too short pulls the line taut before touchdown, §6 item 7); 1.25 h leaves slack over the straight
      span at 0.5 h (1.12 h).
    * **vertical chain 5-60 m**: the thesis studied 10-50 m (Ch. 11): about 3 deg tilt at 10 m with the widest
      spacing, about 0 from 30 m.
    * **drop height 30-120 m**: Petrobras drops large anchors from about 30 m and small ones from over 100 m,
      DPAs 50-70 m (Ch. 2); at Gjoa about 50 m and 75 m gave 24.5 and 27 m/s. The upper end is cut so that the
      release node stays ``levers.wire_clearance_m`` (50 m) below the fairlead.
    * **release phase 0-1 heave period** after the installation vessel's heave up-crossing: the release instant
      "is not arbitrary" in waves (§6 item 5); the heave crest is at a quarter period.

    ## Action Space

    ``Box(-1, 1, (5,), float32)``; each entry maps linearly onto its range (config ``levers``):

    | index | name | target | range (-1 .. +1) |
    |---|---|---|---|
    | 0 | vessel_spacing | vessel spacing over depth | 0 .. 0.5 |
    | 1 | mooring_line_payout | mooring-line length (vertical chain included) over depth | 0.95 .. 1.25 |
    | 2 | vertical_chain | vertical chain length [m] | 5 .. 60 |
    | 3 | drop_height | anchor tip height above the seabed at the release [m] | 30 .. min(120, clearance) |
    | 4 | release_phase | release after the heave up-crossing [heave periods Tp] | 0 .. 1 |

    ``moor_env.envs.levers.lever_targets`` gives the targets of an action, ``lever_action`` the action of targets.

    ## Observation Space

    ``Box(-5, 5, (9,), float32)``, the site (``moor_env.envs.site.SITE_OBS_SPEC``), normalised as
    (raw - offset) / scale and clipped:

    | index | name | unit | offset | scale |
    |---|---|---|---|---|
    | 0 | water_depth_m | m | 500.0 | 150.0 |
    | 1 | current_x | - | 0.0 | 1.0 |
    | 2 | current_y | - | 0.0 | 1.0 |
    | 3 | sea_state_hs_m | m | 1.75 | 1.75 |
    | 4 | sea_state_tp_s | s | 10.5 | 3.5 |
    | 5 | anchor_mass_scale | - | 1.0 | 0.03 |
    | 6 | soil_resistance_kj_m3 | kJ/m^3 | 3.3 | 1.0 |
    | 7 | required_penetration_m | m | 23.0 | 3.0 |
    | 8 | required_speed_m_s | m/s | 24.5 | 3.0 |

    The current is its scale times the seed 003 profile (0.8 m/s at the surface), resolved towards the second
    vessel (x) and across (y). The step returns the same observation.

    ## Rewards

    A smooth surrogate of success with margin (:mod:`moor_env.envs.plan_outcome`): the logistic function of the
    soft minimum of seven normalised margins (speed over the required speed, tilt under 2 deg, offset within 2 m,
    each line under its MBL, the release unit under its rating, fibre clear of the seabed, no chain pile-up), in
    [0, 1]; 0 without touchdown. ``info["reward_terms"]`` holds it as its one term ``success_surrogate``.

    **Success** (``info["success"]``): speed >= the site's required speed, tilt < 2 deg, offset <= 2 m and no
    limit exceeded (``info["limits_exceeded"]``: ``tension``, ``release_unit``, ``fibre_seabed``, ``chain_pile``).

    ## Starting State

    The reset draws the site only (``reset(options=...)`` fixes its fields by name:
    ``moor_env.envs.plan_config.SITE_FIELDS``); nothing is simulated before the action.

    ## Episode End

    Every step terminates: at touchdown, after ``simulation.max_fall_time_s`` without touchdown, on a numerical
    failure, or at once when the chosen geometry has no equilibrium or the static solver does not reach it
    (``info["failure"]`` starts with ``no equilibrium`` or ``statics not converged``). Never truncated.

    ## Arguments

    ```python
    gym.make("moor_env/AnchorPlan-v1", config="anchor-plan", overrides=None, render_mode=None)
    ```

    ``config``: bundled env config name, YAML path, mapping or ``EnvConfig``; ``overrides``: dotted keys
    (``{"site.sea_state_hs_m": 0.0}``). ``render_mode="rgb_array"``: ``render()`` draws the site after the reset
    and the state after the step, ``fall_frames()`` the fall. ``info`` after the step: ``site`` (drawn fields and
    the soil's measures), ``targets`` (physical targets), ``plan`` (wave reference, release delay and time [s]),
    ``touchdown``, ``margins``, ``limits_exceeded``, ``success``, ``failure``, ``max_tension_n``, ``sim_status``.

    ## Version History

    * v1: the crew's five levers as absolute targets (5 actions), the site as the observation (9 values), the
      soil's required speed, a smooth surrogate of success as the reward.
    * v0 (``moor_env/AnchorPlan-v0``, kept): spacing and payout rates for 40 s and a release delay.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, config: str | Path | dict | EnvConfig = PLAN_V1_CONFIG,
                 overrides: dict[str, Any] | None = None, render_mode: str | None = None) -> None:
        self.cfg = load_env_config(config, overrides)
        if render_mode not in (None, "rgb_array"):
            raise ConfigError("render_mode", render_mode, "None or 'rgb_array'")
        self.render_mode = render_mode
        self.core = InstallationCore(self.cfg)
        self.core.max_steps = 2**62  # the plan never truncates
        self.action_space = spaces.Box(-1.0, 1.0, (len(LEVER_NAMES),), np.float32)
        self.observation_space = spaces.Box(-SITE_OBS_CLIP, SITE_OBS_CLIP, (len(SITE_OBS_NAMES),), np.float32)
        self.site: dict[str, Any] = {}
        self.measures: dict[str, float] = {}
        self._obs = np.zeros(len(SITE_OBS_NAMES), np.float32)
        self._renderer = None
        self._fall_snapshots: list[dict] = []
        self._started = False
        self._stepped = False
        self._simulated = False  # the core holds this episode's installation

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a site and return its observation."""
        super().reset(seed=seed)
        self.site = draw_site(self.cfg, self.np_random, options)
        self.measures = site_measures(self.site, self.core.factory.anchor_mass_kg)
        self._obs = site_observation(self.site, self.measures)
        self._fall_snapshots = []
        self._started, self._stepped, self._simulated = True, False, False
        return self._obs.copy(), {"site": {**self.site, **self.measures}}

    def step(self, action):
        """Install with the action's targets: equilibrium, warm-up, wait for the phase, release, fall."""
        if not self._started or self._stepped:
            raise gym.error.ResetNeeded("call reset() before step()")
        self._stepped = True
        factory = self.core.factory
        targets = lever_targets(action, self.site["water_depth_m"], self.cfg.levers, factory.anchor_length_m,
                                factory.fairlead_depth_m)
        reward, info = self.install(targets)
        return self._obs.copy(), reward, True, False, info

    def install(self, targets: dict[str, float]) -> tuple[float, dict[str, Any]]:
        """Install on the reset's site with absolute targets (:data:`~moor_env.envs.levers.TARGET_NAMES` and
        ``drop_height_max_m``, as :func:`~moor_env.envs.levers.lever_targets` gives them): the reward and the
        info of the step (class docstring)."""
        info: dict[str, Any] = {"site": {**self.site, **self.measures}, "targets": targets, "plan": None,
                                "touchdown": None, "max_tension_n": {}, "failure": None}
        record = InstallationRecord(None, self.measures["required_speed_m_s"])
        try:
            self._install(targets, info, record)
        except ConfigError as exc:
            record.failure = f"no equilibrium: {exc}"
            info["sim_status"] = record.failure
        except StaticsNotConverged as exc:  # the solver's failure, not a geometry shown to have no equilibrium
            record.failure = f"statics not converged: {exc}"
            info["sim_status"] = record.failure
        info["failure"] = record.failure
        result = outcome(record, self.cfg)
        info.update(margins=result["margins"], limits_exceeded=result["limits_exceeded"], success=result["success"],
                    reward_terms={"success_surrogate": result["reward"]})
        return float(result["reward"]), info

    def _install(self, targets: dict[str, float], info: dict[str, Any], record: InstallationRecord) -> None:
        """Run the installation of ``targets`` on the core, filling ``info`` and ``record``.

        Raises
        ------
        ConfigError, StaticsNotConverged
            Where the geometry has no equilibrium, or the static solver does not reach it (from
            :meth:`InstallationCore.start`).
        """
        core = self.core
        adv = core.start(episode_scenario(self.site, targets))
        self._simulated = True
        error = run_advance(core, adv)[1] if adv is not None else None
        core.finish_start(error)
        if error is not None:
            record.failure = info["sim_status"] = core.status
            return
        t_pos = core.sim.state.t
        t_ref, delay = t_pos, 0.0
        if core.hs > 0.0:
            t_ref = next_upcrossing_s(core, t_pos, 3.0 * core.tp)
            delay = targets["release_phase"] * core.tp
        clearance = math.inf
        result = None
        if t_ref + delay > t_pos + 0.5 * core.sim.dt:
            result = core.finish_step(*run_advance(core, core.begin_hold(t_ref + delay)))
            clearance = core._mooring_line()[1] + core.depth
        if result is None or not result[2]:
            adv = core.begin_step(np.array([0.0, 0.0, 1.0]))
            if self.render_mode is not None:
                self._fall_snapshots = []
                run = run_advance(core, adv, self.cfg.render.fall_frame_interval_s,
                                  lambda: self._fall_snapshots.append(snapshot(core)))
            else:
                run = run_advance(core, adv)
            result = core.finish_step(*run)
            clearance = min(clearance, core._mooring_line()[1] + core.depth)
        step_info = result[4]
        maxima = step_info["max_tension_n"]
        info.update(sim_status=core.status, max_tension_n=maxima, fall_resolution=step_info.get("fall_resolution"),
                    plan={"wave_reference_s": float(t_ref - core.t0), "release_delay_s": float(delay),
                          "release_s": float(core.sim.release_time_s - core.t0) if core.released else None})
        record.tension_ratio = max(maxima[name] / core.mbl[name] for name in maxima if name in core.mbl)
        record.wire_load_ratio = maxima.get("wire", 0.0) / core.release_unit_limit_n
        record.fibre_clearance_m = clearance
        record.exceeded = dict(core.flags)
        if core.touchdown is None:
            record.failure = core.status
        else:
            record.touchdown = info["touchdown"] = dict(core.touchdown)

    def render(self):
        """``render_mode="rgb_array"``: the state after the step; before it (or where the plan had no
        equilibrium) the site."""
        if self.render_mode != "rgb_array" or not self._started:
            return None
        if self._simulated:
            return self._draw(snapshot(self.core))
        site, m = self.site, self.measures
        lines = [f"depth          {site['water_depth_m']:7.1f} m",
                 f"current        {site['current_scale']:7.2f} x, to {site['current_direction_deg']:.0f} deg",
                 f"Hs, Tp         {site['sea_state_hs_m']:7.2f} m, {site['sea_state_tp_s']:.1f} s",
                 f"anchor mass    {site['anchor_mass_scale']:7.3f} x nominal",
                 f"soil R         {m['soil_resistance_j_m3'] / 1e3:7.2f} kJ/m^3",
                 f"penetration    {m['required_penetration_m']:7.1f} m required",
                 f"speed          {m['required_speed_m_s']:7.2f} m/s required"]
        return self._frames().draw_site(site["water_depth_m"], lines)

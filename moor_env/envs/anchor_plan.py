"""``moor_env/AnchorPlan-v0``: the whole release plan in one action (bandit / optimisation studies)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.core import InstallationCore, run_advance
from moor_env.envs.observation import OBS_CLIP, OBS_NAMES
from moor_env.envs.render import PlanFrames, snapshot
from moor_env.envs.reward import REWARD_TERMS
from moor_env.envs.scenario import start_episode
from moor_env.physics.vessels import track_state

PLAN_ACTION_NAMES: tuple[str, ...] = ("spacing_rate", "payout_rate", "release_delay")


def next_upcrossing_s(core: InstallationCore, t0_s: float, window_s: float) -> float:
    """First zero up-crossing of the installation vessel's heave at or after ``t0_s`` (``t0_s`` if none)."""
    sim = core.sim
    sim.set_vessel_motion(t0_s, window_s, np.zeros(2), ramp_s=core.ramp_s)
    mean_z = -sim.model.scene.installation.fairlead_depth_m
    n = int(math.ceil(window_s / 0.05)) + 1
    times = t0_s + 0.05 * np.arange(n)
    z = np.array([track_state(sim.tracks, 0, t, sim.env_f)[2] for t in times]) - mean_z
    for k in range(1, n):
        if z[k - 1] < 0.0 <= z[k]:
            return float(times[k - 1] + 0.05 * (-z[k - 1]) / (z[k] - z[k - 1]))
    return float(t0_s)


class AnchorPlanEnv(PlanFrames, gym.Env):
    r"""One-shot dart-anchor release: a single action sets spacing, payout and the release delay.

    ## Description

    The scene, scenario distribution, equilibria and reward are those of ``moor_env/AnchorRelease-v0``. The one
    action is a plan: for ``plan.positioning_s`` (40 s) the second vessel moves and the winch runs at the
    commanded rates (with the same DP and winch limits as AnchorRelease-v0, stepped every
    ``control.interval_s``); the second vessel then stops and, after the next zero up-crossing of the installation
    vessel's heave (the wave phase reference), the anchor is released after the commanded delay and falls to
    touchdown. One step ends the episode. Meant for bandit and black-box optimisation studies.

    ## Action Space

    ``Box(-1, 1, (3,), float32)``:

    | index | name | unit | physical command for a in [-1, 1] |
    |---|---|---|---|
    | 0 | spacing_rate | m/s | second vessel's commanded speed while positioning: a * 0.5 (DP-limited) |
    | 1 | payout_rate | m/s | winch rate while positioning: a * 0.3 (pays out for a > 0) |
    | 2 | release_delay | s | (a + 1) / 2 * Tp after the heave up-crossing; calm: (a + 1) / 2 * 10 s |

    The rates and limits are AnchorRelease-v0's (config ``control``); the delay range is
    ``plan.release_window_periods`` (1) peak periods, or ``plan.calm_release_window_s`` (10 s) without waves.

    ## Observation Space

    ``Box(-5, 5, (27,), float32)``, the same vector as AnchorRelease-v0 (``moor_env.envs.OBS_NAMES``): the
    reset observation describes the scenario and the hanging state; the step returns the state at touchdown.

    ## Rewards

    The sum of AnchorRelease-v0's terms over the plan (``info["reward_terms"]`` holds each term summed; their sum
    is the reward): speed, tilt, offset, chain_pile at touchdown; tension, release_unit, fibre_seabed
    penalties; time cost for the positioning and waiting time; failure and no_touchdown penalties. truncation is
    always 0.

    ## Starting State

    As AnchorRelease-v0: a scenario drawn from the config (``reset(options=...)`` fixes fields), its hanging
    equilibrium solved at the reset and, with waves, the ``control.warmup_s`` warm-up.

    ## Episode End

    Every step terminates: at touchdown, after ``simulation.max_fall_time_s`` without touchdown, or on a
    numerical failure (``info["sim_status"]``, last finite observation, failure penalty).

    ## Arguments

    ```python
    gym.make("moor_env/AnchorPlan-v0", config="anchor-release", overrides=None, render_mode=None)
    ```

    As AnchorRelease-v0; ``render_mode="rgb_array"`` renders the current state and ``fall_frames()`` the fall.
    ``info["plan"]`` holds the applied spacing and payout rates, the wave reference time, the delay and the
    release time [s, from the first observation].

    ## Version History

    * v0: 3 actions (spacing rate, payout rate, release delay), 27 observations, AnchorRelease-v0's 11 reward
      terms summed over the plan.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, config: str | Path | dict | EnvConfig = "anchor-release",
                 overrides: dict[str, Any] | None = None, render_mode: str | None = None) -> None:
        self.cfg = load_env_config(config, overrides)
        if render_mode not in (None, "rgb_array"):
            raise gym.error.Error(f"render_mode={render_mode!r}: allowed None or 'rgb_array'")
        self.render_mode = render_mode
        self.core = InstallationCore(self.cfg)
        self.core.max_steps = 2**62  # the plan never truncates
        self.action_space = spaces.Box(-1.0, 1.0, (len(PLAN_ACTION_NAMES),), np.float32)
        self.observation_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (len(OBS_NAMES),), np.float32)
        self._renderer = None
        self._fall_snapshots: list[dict] = []
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a scenario and return the observation of the hanging anchor."""
        super().reset(seed=seed)
        adv = start_episode(self.core, self.np_random, options)
        error = run_advance(self.core, adv)[1] if adv is not None else None
        obs, info = self.core.finish_start(error)
        self._fall_snapshots = []
        self._started = True
        return obs, info

    def step(self, action):
        """Execute the plan to touchdown."""
        if not self._started or self.core.done:
            raise gym.error.ResetNeeded("call reset() before step()")
        core, cfg = self.core, self.cfg
        a = np.clip(np.nan_to_num(np.asarray(action, dtype=np.float64).reshape(3)), -1.0, 1.0)
        total = dict.fromkeys(REWARD_TERMS, 0.0)

        def accumulate(result):
            for k, v in result[4]["reward_terms"].items():
                total[k] += v
            return result

        n_positioning = int(round(cfg.plan.positioning_s / cfg.control.interval_s))
        result = None
        for _ in range(n_positioning):
            adv = core.begin_step(np.array([a[0], a[1], -1.0]))
            result = accumulate(core.finish_step(*run_advance(core, adv) if adv is not None else (None, None)))
            if result[2]:
                return self._final(result, total, a, None, None)
        t_pos = core.sim.state.t
        if core.failed_at_start is None and core.hs > 0.0:
            t_ref = next_upcrossing_s(core, t_pos, 3.0 * core.tp)
            delay = 0.5 * (a[2] + 1.0) * cfg.plan.release_window_periods * core.tp
        else:
            t_ref = t_pos
            delay = 0.5 * (a[2] + 1.0) * cfg.plan.calm_release_window_s
        t_release = t_ref + delay
        if t_release > t_pos + 0.5 * (core.sim.dt if core.sim is not None else 0.0):
            adv = core.begin_hold(t_release)
            result = accumulate(core.finish_step(*run_advance(core, adv) if adv is not None else (None, None)))
            if result[2]:
                return self._final(result, total, a, t_ref, delay)
        adv = core.begin_step(np.array([0.0, 0.0, 1.0]))
        if adv is not None and self.render_mode is not None:
            self._fall_snapshots = []
            run = run_advance(core, adv, cfg.render.fall_frame_interval_s,
                              lambda: self._fall_snapshots.append(snapshot(core)))
        else:
            run = run_advance(core, adv) if adv is not None else (None, None)
        result = accumulate(core.finish_step(*run))
        return self._final(result, total, a, t_ref, delay)

    def _final(self, result, total, a, t_ref, delay):
        obs, _, _, _, info = result
        core = self.core
        info = dict(info)
        info["reward_terms"] = total
        info["plan"] = {"spacing_rate_cmd_m_s": float(a[0] * self.cfg.control.spacing_rate_max_m_s),
                        "payout_rate_cmd_m_s": float(a[1] * (self.cfg.control.payout_rate_max_m_s if a[1] > 0
                                                             else self.cfg.control.haul_rate_max_m_s)),
                        "wave_reference_s": None if t_ref is None else float(t_ref - core.t0),
                        "release_delay_s": None if delay is None else float(delay),
                        "release_s": float(core.sim.release_time_s - core.t0) if core.released else None}
        core.done = True
        return obs, float(sum(total.values())), True, False, info

    def render(self):
        """The current state (``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array" or not self._started:
            return None
        return self._draw(snapshot(self.core))

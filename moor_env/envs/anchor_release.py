"""``moor_env/AnchorRelease-v0``: sequential control of a two-vessel dart-anchor release."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from moor_env.envs.actuators import ACTION_NAMES
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.core import InstallationCore, run_advance
from moor_env.envs.observation import OBS_CLIP, OBS_NAMES
from moor_env.envs.render import FrameRenderer, snapshot
from moor_env.envs.reward import PHASE_FALL, REWARD_TERMS
from moor_env.envs.scenario import start_episode
from moor_env.errors import ConfigError


def step_limit(cfg: EnvConfig, max_episode_steps: int | None) -> int:
    """Steps before truncation: control.max_pre_release_s / control.interval_s, or the TimeLimit if sooner."""
    limit = max(1, int(np.ceil(cfg.control.max_pre_release_s / cfg.control.interval_s - 1e-9)))
    if max_episode_steps is not None:
        limit = min(limit, int(max_episode_steps))
    return limit


def make_anchor_release(**kwargs: Any) -> gym.Env:
    """Entry point of ``moor_env/AnchorRelease-v0``: the env in a ``TimeLimit`` of its configured step limit."""
    env = AnchorReleaseEnv(**kwargs)
    return gym.wrappers.TimeLimit(env, max_episode_steps=step_limit(env.cfg, None))


class AnchorReleaseEnv(gym.Env):
    r"""Release a dart anchor hanging from an installation vessel beside its chain loop and mooring line.

    ## Description

    An 80 t dart anchor (the DPA of seed 003, Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*,
    chapter 8) hangs on the installation vessel's wire about 70 m above the seabed. Its mooring line runs from the
    anchor's back tip up a vertical chain to the release node (where the wire's release unit holds it), then down in
    a chain loop and up as fibre rope to a second vessel. Before the release the crew sets the **spacing of the two
    vessels** and the **mooring-line payout** (together they shape the chain loop, whose width/depth ratio governs
    the anchor's tilt) and chooses the **release time** (in waves the anchor heaves on the long elastic wire). After
    the release the anchor falls freely and must hit the seabed fast (to penetrate) and vertical (at most 5 deg
    tilt). Each step is ``control.interval_s`` of simulated time (default 1 s) of the numba lumped-mass model
    (:class:`moor_env.Simulator`) with waves, current, the wire and both lines. A step whose release action is
    positive releases the anchor and simulates the fall to touchdown. Before the release the implicit integrator
    steps ``control.pre_release_dt_s`` (0.2 s; waves of 7-13 s and slow vessel moves; without waves
    ``control.pre_release_dt_calm_s``, 0.5 s), the fall at the scene's own step; the accuracy of that trade is
    measured by ``benchmarks/pre_release_step.py`` (``--calm``). A calm scenario with a slack loop runs on the
    fidelity preset's own resolution (``fast``: 2 m chain) and, at the release, moves onto its ``tight_line``
    resolution if the loop, at the spacing and line length of that moment, will be tight at touchdown
    (``moor_env.remesh``); in waves, or with a loop tight from the start, ``tight_line`` runs throughout
    (``benchmarks/remesh_at_release.py``), in waves with its ``in_waves`` keys (a 1 m loop chain,
    ``benchmarks/fall_reference.py``).

    ## Action Space

    ``Box(-1, 1, (3,), float32)``; values are clipped to [-1, 1] (NaN counts as 0) and scaled to physical
    commands:

    | index | name | unit | physical command for a in [-1, 1] |
    |---|---|---|---|
    | 0 | spacing_rate | m/s | second vessel's speed away from the installation vessel: a * 0.5 |
    | 1 | payout_rate | m/s | mooring-line winch: a * 0.3 (pays out for a > 0, hauls in for a < 0) |
    | 2 | release | - | release the anchor at the start of this step when a > 0 |

    Limits (config ``control``): speed ``spacing_rate_max_m_s`` (0.5 m/s, a DP slow move), its change
    ``spacing_accel_max_m_s2`` (0.05 m/s^2), spacing ``spacing_min_m`` (20 m) to ``spacing_max_over_depth``
    (0.5) x depth; winch ``payout_rate_max_m_s`` / ``haul_rate_max_m_s`` (0.3 m/s), line length
    ``line_length_min_over_depth`` (0.9) to ``line_length_max_over_depth`` (1.3) x depth. Commands beyond a
    limit are cut to it (the observation reports the rates applied).

    ## Observation Space

    ``Box(-5, 5, (27,), float32)``: each entry is (raw - offset) / scale, clipped to [-5, 5] (the names are
    ``moor_env.envs.OBS_NAMES``). Heights are above the seabed; x points from the installation vessel towards the
    second vessel, z up.

    | index | name | unit | offset | scale | meaning |
    |---|---|---|---|---|---|
    | 0 | time_fraction | - | 0.5 | 0.5 | time since the first observation / control.max_pre_release_s |
    | 1 | released | - | 0.5 | 0.5 | 1 after the release, else 0 |
    | 2 | vessel_spacing_m | m | 125 | 100 | distance between the two vessels' mean positions |
    | 3 | spacing_rate_m_s | m/s | 0 | 0.5 | second vessel's speed (after the DP limits) |
    | 4 | line_length_over_depth | - | 1.06 | 0.1 | mooring line (vertical chain + loop chain + fibre) / depth |
    | 5 | payout_rate_m_s | m/s | 0 | 0.3 | winch rate (after the limits), + pays out |
    | 6 | release_node_dx_m | m | 0 | 5 | release node x minus its x at the start |
    | 7 | release_node_dy_m | m | 0 | 5 | release node y minus its y at the start |
    | 8 | release_node_dz_m | m | 0 | 5 | release node z minus its z at the start |
    | 9 | release_node_vx_m_s | m/s | 0 | 1 | release node velocity, x |
    | 10 | release_node_vy_m_s | m/s | 0 | 1 | release node velocity, y |
    | 11 | release_node_vz_m_s | m/s | 0 | 1 | release node velocity, z |
    | 12 | tilt_deg | deg | 0 | 5 | anchor axis angle from vertical |
    | 13 | tilt_rate_deg_s | deg/s | 0 | 5 | angular speed of the anchor axis |
    | 14 | wire_tension_mn | MN | 1.25 | 1.25 | wire load on the installation vessel (0 after release) |
    | 15 | mooring_line_tension_mn | MN | 0.5 | 0.5 | mooring-line load on the second vessel |
    | 16 | vessel_heave_m | m | 0 | 2 | installation vessel heave |
    | 17 | vessel_heave_rate_m_s | m/s | 0 | 1 | installation vessel heave velocity |
    | 18 | current_surface_x_m_s | m/s | 0 | 1 | surface current, x |
    | 19 | current_surface_y_m_s | m/s | 0 | 1 | surface current, y |
    | 20 | water_depth_m | m | 500 | 200 | water depth |
    | 21 | tip_height_m | m | 68.5 | 20 | anchor tip height above the seabed |
    | 22 | loop_bottom_height_m | m | 80 | 60 | lowest mooring-line node above the seabed |
    | 23 | fibre_clearance_m | m | 100 | 100 | lowest fibre-rope node above the seabed |
    | 24 | sea_state_hs_m | m | 1.5 | 1.5 | significant wave height (forecast) |
    | 25 | sea_state_tp_s | s | 10 | 3 | spectral peak period (forecast) |
    | 26 | vertical_chain_length_m | m | 50 | 25 | chain between the anchor and the release node |

    The chain drag coefficient and the anchor mass tolerance are drawn but not observed (a crew does not know them).

    ## Rewards

    ``info["reward_terms"]`` holds every term at every step (0 when it does not apply); the reward is their sum.
    Weights and thresholds are in the config's ``reward`` section (defaults in brackets).

    | term | when | value (defaults) |
    |---|---|---|
    | speed | touchdown | 1 * clip(1 - max(0, 24 - v) / 8, 0, 1); v = tip speed [m/s] |
    | tilt | touchdown | 1 * (1 - tilt / 5), and -2 more when tilt > 5 deg |
    | offset | touchdown | 0.25 * (1 - min(d / 2, 2)); d = tip's horizontal distance from its start [m] |
    | tension | once | -1 when any line's tension has exceeded its MBL |
    | release_unit | once | -1 when the wire's maximum tension has exceeded the release unit's 273 t |
    | fibre_seabed | once | -1 when a fibre node comes within 0.5 m of the seabed |
    | chain_pile | touchdown | -1 * min(1, max(0, L - 5) / 20); L = chain on the seabed [m] |
    | time | each step before release | -0.002 * control.interval_s |
    | truncation | time limit | -3 |
    | failure | numerical failure | -3 |
    | no_touchdown | after the fall time | -3 without touchdown within simulation.max_fall_time_s (30 s) |

    Config keys (``reward``), in order: ``speed_weight``, ``required_speed_m_s``, ``speed_falloff_m_s``;
    ``tilt_weight``, ``tilt_criterion_deg``, ``tilt_excess_penalty``; ``offset_weight``, ``offset_tolerance_m``;
    ``tension_penalty``; ``release_unit_penalty`` (the limit is the scene's ``release_unit.max_release_load_n``;
    it is compared with the wire's running maximum tension over all its segments, which exceeds the load at the
    unit by the wire's own weight, inertia and drag: conservative by 0.067 MN in statics at 500 m);
    ``fibre_seabed_penalty``, ``fibre_clearance_m`` (checked after every step and at touchdown);
    ``chain_pile_penalty``, ``chain_pile_allowance_m``, ``chain_pile_scale_m``; ``time_cost_per_s``;
    ``truncation_penalty``; ``failure_penalty``; ``no_touchdown_penalty``. "once" terms count at the step where
    the condition first holds.

    ## Starting State

    ``reset`` draws a scenario from the config's ``scenario`` section with the env's seeded generator: water
    depth (400-600 m), vessel spacing (0.1-0.3 x depth) and mooring-line length (1.04-1.08 x depth, including
    150 m of bottom chain), each uniform, current scale (0/0.5/1 x the seed 003 profile 0.8/0.6/0.2 m/s at
    0/300/400 m) and direction (0/180 deg), sea state Hs (0-3 m) and Tp (7-13 s) with a drawn phase seed, chain
    tangential drag coefficient (0.0052-0.0086) and anchor mass scale (0.98-1.02). ``reset(options={...})``
    fixes any of these fields by name (``moor_env.envs.SCENARIO_FIELDS``). The anchor starts at the hanging
    equilibrium of that scene, solved at the reset (wire length solved so that the tip hangs ``drop_height_m`` =
    68.5 m above the seabed; see ``moor_env.envs.equilibria``); a drawn scenario without one is drawn again
    (``info["scenario_redraws"]`` counts them). With waves, ``control.warmup_s`` (20 s) of simulated time, over
    which the waves are ramped in, passes before the first observation.

    ## Episode End

    * Terminated after the release step: the fall is simulated to touchdown (actions no longer change it);
      without touchdown within the scene's ``simulation.max_fall_time_s`` the no_touchdown penalty applies.
    * Terminated when the simulation diverges (a blow-up in the kernel): ``info["sim_status"]`` names the time
      and component, the observation is the last finite one, the failure penalty applies.
    * Truncated when ``control.max_pre_release_s`` (60 s, 60 steps) pass without release, with the truncation
      penalty. ``gym.make`` wraps the env in Gymnasium's ``TimeLimit`` with this same step limit (computed from
      the config, so ``env.spec.max_episode_steps`` is 60 by default); change the limit through the config. A
      smaller ``max_episode_steps`` given to ``gym.make`` truncates earlier without the penalty.

    ## Arguments

    ```python
    gym.make("moor_env/AnchorRelease-v0", config="anchor-release", overrides=None, render_mode=None)
    ```

    * ``config``: bundled env config name (``configs/envs/*.yaml``), YAML path, mapping or ``EnvConfig``.
    * ``overrides``: ``{dotted key: value}`` into the config, e.g. ``{"control.interval_s": 0.5,
      "scenario.sea_state_hs_m": 0.0}``; invalid keys or values raise ``ConfigError`` naming the key.
    * ``render_mode``: ``"rgb_array"`` (the current frame; ``env.unwrapped.fall_frames()`` gives the last fall
      every ``render.fall_frame_interval_s`` = 0.25 s), ``"rgb_array_list"`` (all frames since the last call,
      the fall included) or ``"human"`` (a matplotlib window where a display exists).
      ``python -m moor_env.envs.video --out episode.gif`` writes an episode as a GIF.

    ``gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n)`` returns the batched vector env
    (``moor_env.envs.AnchorReleaseVectorEnv``, one kernel call per thread group per step; ``num_workers=k``
    splits it over k processes, this one included, ``moor_env.envs.sharded.ShardedVectorEnv``: on this project's
    2-core machine ``num_workers=2`` is the fastest, see the README's "Speed of the envs");
    ``vectorization_mode="sync"`` or ``"async"`` give Gymnasium's vector envs of this env.

    ``info`` holds ``reward_terms``, ``sim_status`` (running, touchdown, time limit, diverged: ..., no touchdown
    ...), ``t_s`` (time since the first observation [s]), ``released``, ``spacing_m``, ``max_tension_n`` per line,
    after the release ``fall_resolution`` (``preset``, ``tight_line``, or why the switch was refused) and at
    touchdown ``touchdown`` (speed_m_s, vertical_speed_m_s, tilt_deg, offset_m, fall_time_s, chain_on_seabed_m,
    chain_past_back_end_m: how far the vertical chain has fallen past the anchor's back end, about 0 where it has
    landed on it (the line-anchor contact), positive where it has passed into the body (contact off);
    ``reset`` returns the ``scenario``, the draws refused before it (``scenario_redraws``: scenarios without an
    equilibrium) and where its equilibrium came from (``statics``: ``solved``, or ``memory`` for a geometry
    drawn again).

    ## Version History

    * v0: 3 actions, 27 observations, 11 reward terms; the fall's resolution is fitted at the release;
      ``info["touchdown"]`` holds ``chain_past_back_end_m``; in waves the scenes run the ``fast`` preset's
      tight_line resolution with its ``in_waves`` keys (1 m loop chain at 11.25 ms).
    """

    metadata = {"render_modes": ["human", "rgb_array", "rgb_array_list"], "render_fps": 4}

    def __init__(self, config: str | Path | dict | EnvConfig = "anchor-release",
                 overrides: dict[str, Any] | None = None, render_mode: str | None = None) -> None:
        self.cfg = load_env_config(config, overrides)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ConfigError("render_mode", render_mode, "one of " + ", ".join(self.metadata["render_modes"]))
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": self.cfg.render.render_fps}
        self.core = InstallationCore(self.cfg)
        self.action_space = spaces.Box(-1.0, 1.0, (len(ACTION_NAMES),), np.float32)
        self.observation_space = spaces.Box(-OBS_CLIP, OBS_CLIP, (len(OBS_NAMES),), np.float32)
        self._renderer = None
        self._frames: list[np.ndarray] = []
        self._fall_snapshots: list[dict] = []
        self._window = None
        self._started = False

    # --- API ---------------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw a scenario (``options`` fix scenario fields by name) and return the first observation."""
        super().reset(seed=seed)
        core = self.core
        core.max_steps = step_limit(self.cfg, None)
        adv = start_episode(core, self.np_random, options)
        error = None
        if adv is not None:
            _, error = run_advance(core, adv)
        obs, info = core.finish_start(error)
        self._started = True
        self._frames = []
        self._fall_snapshots = []
        self._record_frame()
        return obs, info

    def step(self, action):
        """Apply one action for ``control.interval_s`` (or release and simulate the fall)."""
        core = self.core
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        if core.done:
            raise gym.error.ResetNeeded("the episode has ended: call reset()")
        adv = core.begin_step(action)
        status, error = None, None
        if adv is not None:
            if adv.phase == PHASE_FALL and self.render_mode is not None:
                self._fall_snapshots = []
                status, error = run_advance(core, adv, self.cfg.render.fall_frame_interval_s, self._on_fall_chunk)
            else:
                status, error = run_advance(core, adv)
        obs, reward, terminated, truncated, info = core.finish_step(status, error)
        self._record_frame()
        return obs, reward, terminated, truncated, info

    def fall_frames(self, which: list[int] | None = None) -> list[np.ndarray]:
        """Frames of the last fall, one every ``render.fall_frame_interval_s`` (any render mode but None;
        ``which``: only those of these indices, negative from the end)."""
        snaps = self._fall_snapshots if which is None else [self._fall_snapshots[i] for i in which]
        return [self._renderer_draw(snap) for snap in snaps]

    def fall_frame_count(self) -> int:
        """Frames :meth:`fall_frames` holds."""
        return len(self._fall_snapshots)

    def render(self):
        """``rgb_array``: the current frame; ``rgb_array_list``: frames since the last call; ``human``: draw."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to make()")
            return None
        if self.render_mode == "rgb_array":
            return self._draw() if self._started else None
        if self.render_mode == "rgb_array_list":
            frames, self._frames = self._frames, []
            return frames
        return None  # human: frames are shown as they are recorded

    def close(self):
        """Release the figure (and the window in human mode)."""
        if self._window is not None:
            import matplotlib.pyplot as plt  # noqa: PLC0415 - matplotlib: only the human render mode opens a window

            plt.close(self._window[0])
            self._window = None
        self._renderer = None

    # --- helpers -----------------------------------------------------------------------------------------------
    @property
    def obs_names(self) -> tuple[str, ...]:
        """Names of the observation entries."""
        return OBS_NAMES

    @property
    def reward_terms(self) -> tuple[str, ...]:
        """Names of the reward terms."""
        return REWARD_TERMS

    def _draw(self) -> np.ndarray:
        return self._renderer_draw(snapshot(self.core))

    def _record_frame(self) -> None:
        if self.render_mode == "rgb_array_list":
            self._frames.append(self._draw())
        elif self.render_mode == "human":
            self._show(self._draw())

    def _on_fall_chunk(self) -> None:
        snap = snapshot(self.core)
        self._fall_snapshots.append(snap)
        if self.render_mode == "rgb_array_list":
            self._frames.append(self._renderer_draw(snap))
        elif self.render_mode == "human":
            self._show(self._renderer_draw(snap))

    def _renderer_draw(self, snap: dict) -> np.ndarray:
        if self._renderer is None:
            self._renderer = FrameRenderer(self.cfg.render.width_px, self.cfg.render.height_px)
        return self._renderer.draw(snap)

    def _show(self, frame: np.ndarray) -> None:
        # matplotlib's pyplot (a GUI backend where there is a display) loads only in the human render mode
        import matplotlib  # noqa: PLC0415
        import matplotlib.pyplot as plt  # noqa: PLC0415

        if not _interactive_backend(matplotlib.get_backend()):
            if not getattr(AnchorReleaseEnv, "_warned_headless", False):
                AnchorReleaseEnv._warned_headless = True
                gym.logger.warn("render_mode='human' needs a display (matplotlib backend "
                                f"'{matplotlib.get_backend()}' is not interactive); use 'rgb_array'")
            return
        if self._window is None:
            fig, ax = plt.subplots(figsize=(frame.shape[1] / 100, frame.shape[0] / 100), dpi=100)
            ax.axis("off")
            image = ax.imshow(frame)
            fig.tight_layout(pad=0)
            self._window = (fig, image)
            plt.show(block=False)
        else:
            self._window[1].set_data(frame)
        self._window[0].canvas.draw_idle()
        plt.pause(1.0 / self.metadata["render_fps"])


def _interactive_backend(name: str) -> bool:
    return name.lower() not in ("agg", "pdf", "ps", "svg", "cairo", "template", "module://matplotlib_inline.backend_inline")

"""One episode slot: a simulator started from its scenario's hanging equilibrium and the RL bookkeeping around it.

The physics stays in :mod:`moor_env.physics` / :class:`moor_env.Simulator`; a slot only drives a simulator through
its public methods, with the pieces of the RL problem kept apart: the scenario (:mod:`~moor_env.envs.scenario`),
its scene and model (:mod:`~moor_env.envs.scene`), the mesh it runs on (:mod:`~moor_env.envs.resolution`), the
actuators (:mod:`~moor_env.envs.actuators`), the observation (:mod:`~moor_env.envs.observation`) and the reward
and episode end (:mod:`~moor_env.envs.reward`).

An env step is split into ``begin_step`` (apply the action, return an :class:`Advance` request: integrate to
``t_end``), the integration itself (:func:`run_advance` for one simulator, :mod:`moor_env.envs.batch` for many in
one numba call) and ``finish_step`` (observation, reward, episode end). The single env and the batched vector env
therefore share every line of RL logic, and row i of the batched env equals the single env bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from moor_env.envs import actuators, measures
from moor_env.envs.batch import BACKED_UP, TAKE_BACKUP, BatchAdvancer
from moor_env.envs.config import EnvConfig
from moor_env.envs.equilibria import Equilibria
from moor_env.envs.measures import SlotBuffers
from moor_env.envs.observation import OBS_NAMES, normalise_observations, raw_observation
from moor_env.envs.resolution import even_step_s, has_resolution, line_speed_m_s, pre_release_step_s, remesh_for_fall
from moor_env.envs.reward import (
    LIMITS,
    PHASE_CONTROL,
    PHASE_FALL,
    PHASE_HOLD,
    PHASE_WARMUP,
    StepRecord,
    step_outcome,
)
from moor_env.envs.scene import SceneFactory
from moor_env.errors import SimulationDiverged
from moor_env.physics import layout as L
from moor_env.simulation import Simulator


@dataclass
class Advance:
    """Integrate the core's simulator to ``t_end_s`` (to touchdown when ``detect_touchdown``) in steps of
    ``dt_s``; with ``backup`` the kernel first saves the state into the core's slot buffers (see
    ``InstallationCore.fallback``)."""

    t_end_s: float
    detect_touchdown: bool
    phase: str
    dt_s: float
    backup: bool = False

    def job(self, core: InstallationCore) -> tuple:
        """This advance as a :class:`~moor_env.envs.batch.BatchAdvancer` job of ``core``'s simulator."""
        return core.sim, self.t_end_s, self.detect_touchdown, self.dt_s, core.buffers, self.backup


class InstallationCore:
    """One episode slot: a simulator started from its scenario's hanging equilibrium and the RL bookkeeping
    around it.

    Parameters
    ----------
    cfg : EnvConfig
    equilibria : Equilibria, optional
        Shared between the slots of a vector env.
    factory : SceneFactory, optional
        Shared between the slots of a vector env (with its compiled models).
    """

    def __init__(self, cfg: EnvConfig, equilibria: Equilibria | None = None,
                 factory: SceneFactory | None = None) -> None:
        self.cfg = cfg
        self.factory = factory or SceneFactory(cfg)
        self.equilibria = equilibria or Equilibria(cfg.statics)
        self.sim: Simulator | None = None
        self.max_steps = max(1, int(math.ceil(cfg.control.max_pre_release_s / cfg.control.interval_s - 1e-9)))
        self.scenario: dict[str, Any] = {}
        self.last_obs = np.zeros(len(OBS_NAMES), dtype=np.float32)
        self.pending: Advance | None = None
        self.done = True
        self.buffers: SlotBuffers | None = None  # the kernel's measures and state backup for this slot
        self.fallbacks = 0
        self.advancer = None  # the BatchAdvancer of run_advance, made on first use
        self.redraws = 0  # scenarios drawn again at the last reset (set by scenario.start_episode)

    # --- episode start -----------------------------------------------------------------------------------------
    def start(self, scenario: dict[str, Any]) -> Advance | None:
        """Build the simulator of a scenario at its hanging equilibrium; the warm-up to run, if any.

        Raises
        ------
        ConfigError, StaticsNotConverged
            If the scenario gives no valid scene or no equilibrium (:class:`~moor_env.errors.NoEquilibrium`, a
            ConfigError).
        """
        cfg = self.cfg
        scene, _, statics, key = self.factory.episode_scene(scenario)
        model, statics_model = self.factory.model(key, statics, scene)
        state, origin = self.equilibria.state(key, statics_model)
        self.statics_key = key
        self.statics_scene = statics
        sim = Simulator(model)
        sim.state = state
        self.sim = sim
        self.lines = {name: info.index for name, info in model.lines.items()}
        self.fibre_mat = model.material_names.index(scene.installation.fibre_material)
        self.buffers = self._slot_buffers(sim, backup=True)
        self.scenario = dict(scenario)
        self.statics_origin = origin
        self.depth = scene.environment.water_depth_m
        self.hs = scene.environment.sea_state.hs_m
        self.tp = scene.environment.sea_state.tp_s
        self.ramp_s = cfg.control.warmup_s if cfg.control.warmup_s > 0 else 2.0 * self.tp
        self.vertical_chain_m = scene.installation.vertical_chain_length_m
        self.fairlead_depth_m = scene.installation.fairlead_depth_m
        self.chain_material = scene.installation.chain_material
        self.mbl = {name: min(scene.materials[m].mbl_n for m in info.materials) for name, info in model.lines.items()}
        self.release_unit_limit_n = scene.release_unit.max_release_load_n
        self.max_fall_s = scene.simulation.max_fall_time_s
        self.spacing_rate = 0.0
        self.payout_rate = 0.0
        self.steps = 0
        self.fallbacks = 0  # pre-release advances repeated at the scene's step (see fallback)
        self.released = False
        self.fall_resolution: str | None = None
        self.done = False
        self.status = "running"
        self.flags = dict.fromkeys(LIMITS, False)  # the limits exceeded so far
        self.failed_at_start: str | None = None
        self.release_ref = sim.state.node_pos[model.release_node].copy()
        tip, _ = sim.tip_state()
        self.target_xy = tip[:2].copy()
        self.touchdown: dict[str, float] | None = None
        self.t0 = 0.0
        if self.hs > 0.0 and cfg.control.warmup_s > 0.0:
            actuators.hold(sim, sim.state.t, cfg.control.warmup_s, self.ramp_s)
            self.pending = self._pre_release(sim.state.t + cfg.control.warmup_s, PHASE_WARMUP)
        else:
            self.pending = None
        return self.pending

    def _slot_buffers(self, sim: Simulator, backup: bool) -> SlotBuffers:
        """The kernel's buffers for ``sim`` (:func:`~moor_env.envs.measures.slot_buffers`)."""
        return measures.slot_buffers(sim, self.lines, self.fibre_mat, backup)

    def finish_start(self, error: SimulationDiverged | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """After the warm-up (if any): the first observation and the reset info."""
        raw, info = self.finish_start_raw(error)
        return self.observe_raw(raw), info

    def finish_start_raw(self, error: SimulationDiverged | None = None
                         ) -> tuple[list[float] | None, dict[str, Any]]:
        """:meth:`finish_start` with the observation in physical units (None: keep the last observation), for
        :meth:`observe_raw` or the vector env's normalisation of every slot at once."""
        sim = self.sim
        if error is not None:
            # keep the episode well defined: the first step ends it with the failure penalty
            self.failed_at_start = f"diverged during warm-up: {error}"
            self.status = self.failed_at_start
        self.t0 = sim.state.t
        self.pending = None
        sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0  # tension maxima count from the first observation
        raw = self.raw_observation() if error is None else None
        info = {"scenario": dict(self.scenario), "scenario_redraws": self.redraws, "sim_status": self.status,
                "statics": self.statics_origin, "t_s": 0.0}
        return raw, info

    # --- integration steps ---------------------------------------------------------------------------------------
    def _pre_release(self, t_end_s: float, phase: str) -> Advance:
        """Advance to ``t_end_s`` before the release in n equal steps, n the smallest whole number that keeps them
        at or below :func:`~moor_env.envs.resolution.pre_release_step_s`, so the advance ends exactly at
        ``t_end_s`` and the release falls on the control grid. Before a step coarser than the scene's the kernel
        saves the state for :meth:`fallback` (``Advance.backup``)."""
        sim = self.sim
        target = pre_release_step_s(sim, self.hs, self.cfg.control)
        adv = Advance(t_end_s, False, phase, even_step_s(t_end_s - sim.state.t, target))
        if adv.dt_s > sim.dt:
            adv.backup = True
            backup = self.buffers.backup
            backup.t = sim.state.t  # the kernel copies the arrays
            backup.released = sim.state.released
        return adv

    def fallback(self, adv: Advance, error: SimulationDiverged | None) -> Advance | None:
        """The advance to repeat at the scene's step, from the state the kernel saved before ``adv``, if ``adv``
        diverged with a coarser pre-release step; else None.

        A coarse pre-release step is an accuracy trade (``control.pre_release_dt_s``); it must never end an
        episode that the scene's own step would have carried through, so a blow-up with it is retried once.
        """
        if error is None or not adv.backup or adv.dt_s <= self.sim.dt:
            return None
        # the saved state becomes the state; the diverged one's arrays are the next backup's buffers
        self.sim.state, self.buffers.backup = self.buffers.backup, self.sim.state
        self.fallbacks += 1
        self.pending = Advance(adv.t_end_s, adv.detect_touchdown, adv.phase,
                               even_step_s(adv.t_end_s - self.sim.state.t, self.sim.dt))
        return self.pending

    # --- steps -------------------------------------------------------------------------------------------------
    def begin_step(self, action: np.ndarray | list[float]) -> Advance | None:
        """Apply an action (3 numbers, or a list of 3 Python floats as the vector env passes its rows); the
        integration it needs (None when the episode ends without one)."""
        cfg = self.cfg.control
        sim = self.sim
        a = actuators.clip_action(action)
        if self.failed_at_start is not None:
            self.pending = None
            return None
        t = sim.state.t
        if a[2] > 0.0:
            actuators.stop_winch(sim)
            self.payout_rate = 0.0
            self.spacing_rate = 0.0
            self._fit_fall_resolution()
            sim = self.sim
            actuators.release(sim, t, self.max_fall_s, self.ramp_s)
            self.released = True
            self.pending = Advance(t + self.max_fall_s, True, PHASE_FALL, sim.dt * self.cfg.control.fall_dt_scale)
            return self.pending
        v = actuators.dp_speed_m_s(a[0], self.spacing_rate, self.spacing_m(), self.depth, cfg)
        rate = actuators.winch_rate_m_s(a[1], self.line_length_total_m(), self.depth, cfg)
        self.spacing_rate = v
        self.payout_rate = rate
        actuators.drive(sim, t, cfg.interval_s, v, rate, self.ramp_s)
        self.pending = self._pre_release(t + cfg.interval_s, PHASE_CONTROL)
        return self.pending

    def begin_hold(self, t_end_s: float) -> Advance | None:
        """Hold the vessels (second vessel stopped) and the winch until ``t_end_s`` (AnchorPlan-v0's wait)."""
        if self.failed_at_start is not None:
            self.pending = None
            return None
        sim = self.sim
        t = sim.state.t
        actuators.stop_winch(sim)
        self.payout_rate = 0.0
        self.spacing_rate = 0.0
        actuators.hold(sim, t, max(t_end_s - t, sim.dt), self.ramp_s)
        self.hold_start_s = t
        self.pending = self._pre_release(t_end_s, PHASE_HOLD)
        return self.pending

    def _fit_fall_resolution(self) -> None:
        """Move the simulation onto the resolution the fall needs (:meth:`SceneFactory.fall_resolution`)."""
        old = self.sim
        lines = [self.lines["vertical_chain"], self.lines["mooring_line"]]
        keys = self.factory.fall_resolution(old.model.scene, self.spacing_m(), self.line_length_total_m(),
                                            line_speed_m_s(old, lines))
        self.fall_resolution = "preset" if keys is None else "tight_line"
        if has_resolution(old, keys):
            return
        model = self.factory.fall_model(self.statics_key, self.statics_scene, old.model.scene, keys)
        sim, refusal = remesh_for_fall(old, model)
        if sim is None:  # keep the preset's resolution
            self.fall_resolution = f"preset (remesh refused: {refusal})"
            return
        self.sim = sim
        self.buffers = self._slot_buffers(sim, backup=False)  # the fall takes no backup

    def finish_step(self, status: int | None, error: SimulationDiverged | None
                    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Observation, reward, terminated, truncated and info after the integration of ``begin_step``."""
        raw, *rest = self.finish_step_raw(status, error)
        return self.observe_raw(raw), *rest

    def finish_step_raw(self, status: int | None, error: SimulationDiverged | None
                        ) -> tuple[list[float] | None, float, bool, bool, dict[str, Any]]:
        """:meth:`finish_step` with the observation in physical units (None: keep the last observation)."""
        phase = self.pending.phase if self.pending is not None else None
        self.pending = None
        maxima = self._max_tensions_n()
        record = self._step_record(phase, status, error, maxima)
        outcome = step_outcome(record, self.cfg.reward)
        self.flags = outcome.exceeded
        if outcome.status is not None:
            self.status = outcome.status
        raw = None if record.failed else self.raw_observation()
        self.done = outcome.terminated or outcome.truncated
        info = self.info(outcome.terms, maxima)
        return raw, outcome.reward, outcome.terminated, outcome.truncated, info

    def _step_record(self, phase: str | None, status: int | None, error: SimulationDiverged | None,
                     maxima: dict[str, float]) -> StepRecord:
        """What the step of ``phase`` did (:class:`~moor_env.envs.reward.StepRecord`), read from the simulator."""
        if self.failed_at_start is not None or error is not None:
            return StepRecord(phase, failed=True, error=None if error is None else str(error), exceeded=self.flags)
        elapsed_s = 0.0
        if phase == PHASE_CONTROL:
            self.steps += 1
            elapsed_s = self.cfg.control.interval_s
        elif phase == PHASE_HOLD:
            elapsed_s = self.sim.state.t - self.hold_start_s
        elif status == L.STATUS_TOUCHDOWN:
            self.touchdown = measures.touchdown(self.sim, self.target_xy, self.chain_material)
        return StepRecord(phase, steps=self.steps, max_steps=self.max_steps, elapsed_s=elapsed_s,
                          max_tension_n=maxima, mbl_n=self.mbl, release_unit_limit_n=self.release_unit_limit_n,
                          fibre_clearance_m=self._mooring_line()[1] + self.depth, touchdown=self.touchdown,
                          exceeded=self.flags)

    def info(self, terms: dict[str, float], max_tension_n: dict[str, float] | None = None) -> dict[str, Any]:
        """Step info (see the env docstring); ``max_tension_n``: :meth:`_max_tensions_n` if already read."""
        info: dict[str, Any] = {
            "reward_terms": terms,
            "sim_status": self.status,
            "t_s": float(self.time_s) if self.failed_at_start is None else 0.0,
            "released": self.released,
            "spacing_m": self.spacing_m(),
            "max_tension_n": self._max_tensions_n() if max_tension_n is None else max_tension_n,
        }
        if self.released:
            info["fall_resolution"] = self.fall_resolution
        if self.touchdown is not None:
            info["touchdown"] = dict(self.touchdown)
        return info

    # --- state -------------------------------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        """Time since the first observation [s]."""
        return self.sim.state.t - self.t0

    def spacing_m(self) -> float:
        """Distance between the two vessels' mean positions [m]."""
        return measures.spacing_m(self.sim)

    def _mooring_line(self) -> tuple[float, float, float]:
        """Lowest node z, lowest fibre node z and unstretched length of the mooring line [m]."""
        return measures.mooring_line(self.sim, self.buffers, self.lines["mooring_line"], self.fibre_mat)

    def line_length_total_m(self) -> float:
        """Mooring line including the vertical chain [m] (unstretched)."""
        return self._mooring_line()[2] + self.vertical_chain_m

    def _max_tensions_n(self) -> dict[str, float]:
        """Running maximum tension of each line by name [N]."""
        return measures.max_tensions_n(self.sim, self.lines)

    # --- observation -------------------------------------------------------------------------------------------
    def raw_observation(self) -> list[float]:
        """Observation in physical units (:func:`~moor_env.envs.observation.raw_observation`)."""
        m = measures.kernel_measures(self.sim, self.buffers)
        return raw_observation(m, time_fraction=self.time_s / self.cfg.control.max_pre_release_s,
                               released=self.released, spacing_m=self.spacing_m(),
                               spacing_rate_m_s=self.spacing_rate, payout_rate_m_s=self.payout_rate,
                               depth_m=self.depth, vertical_chain_m=self.vertical_chain_m,
                               fairlead_depth_m=self.fairlead_depth_m, release_ref=self.release_ref, hs_m=self.hs,
                               tp_s=self.tp)

    def observe(self) -> np.ndarray:
        """Normalised float32 observation, clipped to +-OBS_CLIP; the last finite one if the state is not."""
        return self.observe_raw(self.raw_observation())

    def observe_raw(self, raw: list[float] | None) -> np.ndarray:
        """The normalised observation of a :meth:`raw_observation` (None: the last observation); it becomes the
        last observation where it is finite."""
        if raw is not None:
            obs, finite = normalise_observations(np.array([raw]))
            if finite[0]:
                self.last_obs = obs[0]
        return self.last_obs.copy()


def run_advance(core: InstallationCore, adv: Advance, chunk_s: float | None = None,
                on_chunk=None) -> tuple[int | None, SimulationDiverged | None]:
    """Integrate one core's simulator as ``adv`` asks (optionally in chunks with a callback, e.g. frames).

    The integration goes through :func:`moor_env.envs.batch.advance_many` with one scene, the kernel the batched
    vector env uses, so that both give bit-identical episodes. Chunking never changes the result: the kernel
    takes whole steps from the same start time, each as long as the state it starts from sets.
    """
    if core.advancer is None:
        core.advancer = BatchAdvancer()
    sim = core.sim
    chunk_s = None if chunk_s is None or on_chunk is None else max(chunk_s, adv.dt_s)
    status = L.STATUS_TIME_LIMIT
    backup = TAKE_BACKUP if adv.backup else 0  # the state before the first chunk is the one a fallback goes back to
    while sim.state.t < adv.t_end_s - 0.5 * adv.dt_s:
        t_stop = adv.t_end_s if chunk_s is None else min(sim.state.t + chunk_s, adv.t_end_s)
        job = (sim, t_stop, adv.detect_touchdown, adv.dt_s, core.buffers, backup)
        status, error = core.advancer.run({0: job})[0]
        backup = BACKED_UP if adv.backup else 0
        retry = core.fallback(adv, error)
        if retry is not None:
            return run_advance(core, retry, chunk_s, on_chunk)
        if error is not None:
            return None, error
        if chunk_s is not None:
            on_chunk()
        if status == L.STATUS_TOUCHDOWN:
            break
    return status, None

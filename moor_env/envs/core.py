"""RL logic shared by every env class: scenario draw, episode start, controls, observation, reward.

The physics stays in :mod:`moor_env.physics` / :class:`moor_env.Simulator`; this module only drives a
simulator through its public methods. One :class:`InstallationCore` is one episode slot. An env step is split
into ``begin_step`` (apply the action, return an :class:`Advance` request: integrate to ``t_end``),
the integration itself (:func:`run_advance` for one simulator, :mod:`moor_env.envs.batch` for many in one numba
call) and ``finish_step`` (observation, reward, episode end). The single env and the batched vector env
therefore share every line of RL logic, and row i of the batched env equals the single env bit for bit.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import ValidationError

from moor_env.compile import VESSEL_INSTALLATION, VESSEL_SECOND, Model, compile_scene
from moor_env.config import (
    SET_SHORTCUTS,
    DiscretizationConfig,
    EnvironmentConfig,
    InstallationConfig,
    MaterialConfig,
    SceneConfig,
    check_scene_consistency,
    line_slack_geometry,
    scene_dict,
    scene_from_dict,
    tight_line_keys,
    tight_line_needed,
    tight_line_rule,
)
from moor_env.envs import batch as B
from moor_env.envs.batch import BatchAdvancer, SlotBuffers, line_summary, measure_scene
from moor_env.envs.config import SCENARIO_FIELDS, SCENARIO_RANGES, SEED_FIELD, SEED_HIGH, Choice, EnvConfig, Uniform
from moor_env.envs.equilibria import EquilibriumCache, plain_copy, scene_key, scene_text, statics_scene_dict
from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.environment import current_velocity
from moor_env.physics.integrate import INTEGRATOR_IMPLICIT_EULER
from moor_env.physics.vessels import track_state
from moor_env.remesh import remesh_state
from moor_env.simulation import Simulator

# --- observation: (name, unit, offset, scale, meaning); normalised value = (raw - offset) / scale ----------------
OBS_SPEC: tuple[tuple[str, str, float, float, str], ...] = (
    ("time_fraction", "-", 0.5, 0.5, "time since the first observation / control.max_pre_release_s"),
    ("released", "-", 0.5, 0.5, "1 after the release, else 0"),
    ("vessel_spacing_m", "m", 125.0, 100.0, "horizontal distance between the two vessels' mean positions"),
    ("spacing_rate_m_s", "m/s", 0.0, 0.5, "second vessel's speed away from the installation vessel"),
    ("line_length_over_depth", "-", 1.06, 0.1, "mooring line length (vertical chain + loop chain + fibre) / depth"),
    ("payout_rate_m_s", "m/s", 0.0, 0.3, "mooring-line winch rate, + pays out"),
    ("release_node_dx_m", "m", 0.0, 5.0, "release node x minus its x at the start of the episode"),
    ("release_node_dy_m", "m", 0.0, 5.0, "release node y minus its y at the start"),
    ("release_node_dz_m", "m", 0.0, 5.0, "release node z minus its z at the start"),
    ("release_node_vx_m_s", "m/s", 0.0, 1.0, "release node velocity x"),
    ("release_node_vy_m_s", "m/s", 0.0, 1.0, "release node velocity y"),
    ("release_node_vz_m_s", "m/s", 0.0, 1.0, "release node velocity z (up +)"),
    ("tilt_deg", "deg", 0.0, 5.0, "anchor axis angle from vertical"),
    ("tilt_rate_deg_s", "deg/s", 0.0, 5.0, "angular speed of the anchor axis"),
    ("wire_tension_mn", "MN", 1.25, 1.25, "installation wire load on its vessel (0 after release)"),
    ("mooring_line_tension_mn", "MN", 0.5, 0.5, "mooring line load on the second vessel"),
    ("vessel_heave_m", "m", 0.0, 2.0, "installation vessel heave"),
    ("vessel_heave_rate_m_s", "m/s", 0.0, 1.0, "installation vessel heave velocity"),
    ("current_surface_x_m_s", "m/s", 0.0, 1.0, "surface current, x (towards the second vessel)"),
    ("current_surface_y_m_s", "m/s", 0.0, 1.0, "surface current, y"),
    ("water_depth_m", "m", 500.0, 200.0, "water depth"),
    ("tip_height_m", "m", 68.5, 20.0, "anchor tip height above the seabed"),
    ("loop_bottom_height_m", "m", 80.0, 60.0, "lowest mooring-line node above the seabed"),
    ("fibre_clearance_m", "m", 100.0, 100.0, "lowest fibre-rope node above the seabed"),
    ("sea_state_hs_m", "m", 1.5, 1.5, "significant wave height (forecast)"),
    ("sea_state_tp_s", "s", 10.0, 3.0, "peak period (forecast)"),
    ("vertical_chain_length_m", "m", 50.0, 25.0, "chain hanging between the anchor and the release node"),
)
OBS_NAMES: tuple[str, ...] = tuple(row[0] for row in OBS_SPEC)
OBS_UNITS: tuple[str, ...] = tuple(row[1] for row in OBS_SPEC)
OBS_OFFSET = np.array([row[2] for row in OBS_SPEC])
OBS_SCALE = np.array([row[3] for row in OBS_SPEC])
OBS_CLIP = 5.0


def normalise_observations(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of raw observations (physical units, float64[n, len(OBS_NAMES)]) normalised, clipped to +-OBS_CLIP and
    as float32, with a mask of the rows that were finite (a row that is not must be replaced by its slot's last
    observation). Row by row the same numbers whatever the number of rows, so that the batched env's rows equal
    the single env's observations."""
    obs = (raw - OBS_OFFSET) / OBS_SCALE
    finite = np.isfinite(obs).all(axis=1)
    np.clip(obs, -OBS_CLIP, OBS_CLIP, out=obs)
    return obs.astype(np.float32), finite


# --- action ----------------------------------------------------------------------------------------------------
ACTION_NAMES: tuple[str, ...] = ("spacing_rate", "payout_rate", "release")

# --- reward terms (every key in info["reward_terms"] at every step; their sum is the reward) ------------------
REWARD_TERMS: tuple[str, ...] = ("speed", "tilt", "offset", "tension", "release_unit", "fibre_seabed",
                                 "chain_pile", "time", "truncation", "failure", "no_touchdown")

PHASE_WARMUP = "warmup"
PHASE_CONTROL = "control"
PHASE_FALL = "fall"
PHASE_HOLD = "hold"


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


def apply_scene_overrides(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Copy of a scene mapping with ``--set`` style overrides (shortcuts of :data:`SET_SHORTCUTS`) applied."""
    data = plain_copy(base)
    chain = data.get("installation", {}).get("chain_material", "chain_142")
    for key, value in overrides.items():
        path = SET_SHORTCUTS.get(key, key).replace("{chain}", str(chain)).split(".")
        node = data
        for part in path[:-1]:
            node = node.setdefault(part, {})
        node[path[-1]] = value
    return data


class SceneFactory:
    """Scenario -> scene mapping -> validated :class:`SceneConfig` (the base scene is read from YAML once).

    Raises
    ------
    ConfigError
        At construction, if the scene, ``fidelity`` or ``scene_overrides`` are invalid (checked with the
        config's representative scenario: the first value of every scenario distribution).
    """

    STATICS_SCENE_ENTRIES = 256

    def __init__(self, cfg: EnvConfig) -> None:
        self.cfg = cfg
        self.models: OrderedDict[str, Model] = OrderedDict()  # compiled statics scenes by equilibrium key
        self.statics_scenes: OrderedDict[str, SceneConfig] = OrderedDict()  # validated, by statics mapping
        raw = scene_dict(cfg.scene)
        if raw.get("kind", "dart_installation") != "dart_installation" or "installation" not in raw:
            raise ConfigError("scene", cfg.scene, "a dart_installation scene")
        self.base = apply_scene_overrides(raw, {**cfg.fidelity, **cfg.scene_overrides})
        self.tight_line_rule = tight_line_rule(self.base.get("fidelity", "default"))
        explicit = self.base.get("discretization", {})
        # the rule's keys in calm water and in waves (its in_waves entry), less those the config sets explicitly
        tight_line = None if self.tight_line_rule is None else tuple(
            {k: v for k, v in tight_line_keys(self.tight_line_rule, hs_m).items() if k not in explicit} or None
            for hs_m in (0.0, math.inf))
        self.tight_line = None  # the representative scene below supplies the geometry the rule needs
        scene = self.scene(representative_scenario(cfg))
        self.anchor_length_m = scene.anchor.length_m
        self.fairlead_depth_m = scene.installation.fairlead_depth_m
        self.tight_line = tight_line
        self.chain_material = scene.installation.chain_material
        self.nominal_cd_t = float(self.base["materials"][self.chain_material]["cd_tangential"])
        comp = scene.installation.components
        if not (comp.wire and comp.vertical_chain and comp.mooring_line):
            raise ConfigError("scene", cfg.scene, "a scene with wire, vertical chain and mooring line")

    def scene_overrides(self, scenario: dict[str, Any]) -> dict[str, Any]:
        """Scene ``--set`` overrides of a scenario, at its pre-release resolution (:meth:`pre_release_resolution`)."""
        depth = float(scenario["water_depth_m"])
        return {
            "discretization.fit_to_geometry": False,  # the fall's resolution is fitted at the release
            **{f"discretization.{k}": v for k, v in self.pre_release_resolution(scenario).items()},
            "water_depth_m": depth,
            "vessel_spacing_m": float(scenario["vessel_spacing_over_depth"]) * depth,
            "mooring_line_length_m": float(scenario["mooring_line_length_over_depth"]) * depth,
            "vertical_chain_length_m": float(scenario["vertical_chain_length_m"]),
            "drop_height_m": float(scenario["drop_height_m"]),
            "current_scale": float(scenario["current_scale"]),
            "current_direction_deg": float(scenario["current_direction_deg"]),
            "sea_state_hs_m": float(scenario["sea_state_hs_m"]),
            "sea_state_tp_s": float(scenario["sea_state_tp_s"]),
            "sea_state_seed": int(scenario["sea_state_seed"]),
            "chain_cd_tangential": float(scenario["chain_cd_tangential"]),
            "anchor_mass_scale": float(scenario["anchor_mass_scale"]),
        }

    def _tight_line_needed(self, depth_m: float, vertical_chain_m: float, spacing_m: float, line_length_m: float,
                           hs_m: float, line_speed_m_s: float) -> bool:
        geometry = line_slack_geometry(water_depth_m=depth_m, tip_height_m=0.0, anchor_length_m=self.anchor_length_m,
                                       vertical_chain_m=vertical_chain_m, fairlead_depth_m=self.fairlead_depth_m,
                                       spacing_m=spacing_m, line_length_m=line_length_m)
        return tight_line_needed(self.tight_line_rule, *geometry, hs_m, line_speed_m_s)

    def _tight_line_keys(self, hs_m: float) -> dict[str, Any] | None:
        """The preset's ``tight_line`` keys for a sea of significant wave height ``hs_m`` [m] (its ``in_waves``
        keys in waves), None where there are none to set."""
        waves = hs_m > self.tight_line_rule["waves_above_hs_m"]
        keys = self.tight_line[1 if waves else 0]
        return None if keys is None else dict(keys)

    def pre_release_resolution(self, scenario: dict[str, Any]) -> dict[str, Any]:
        """Discretization keys of a scenario before its release: the preset's ``tight_line`` keys (in waves with
        its ``in_waves`` keys) where its starting geometry or its waves need them
        (:func:`moor_env.config.tight_line_needed`), else none (the preset's own resolution).

        Why: a calm, slack loop held until the release falls on the coarse resolution within 0.03 m/s of the
        fine one, at about 30 % of the cost; the coarse pre-release phase of a loop that is tight from the start,
        or that waves move, changed touchdown speed by 0.25-0.31 m/s median (benchmarks/remesh_at_release.py)
        for 15-18 % of the episode's cost, the fall there needing the fine resolution anyway.
        """
        if self.tight_line is None:
            return {}
        depth = float(scenario["water_depth_m"])
        hs_m = float(scenario["sea_state_hs_m"])
        tight = self._tight_line_needed(depth, float(scenario["vertical_chain_length_m"]),
                                        float(scenario["vessel_spacing_over_depth"]) * depth,
                                        float(scenario["mooring_line_length_over_depth"]) * depth,
                                        hs_m, 0.0)  # the equilibrium is at rest
        return (self._tight_line_keys(hs_m) or {}) if tight else {}

    def fall_resolution(self, scene: SceneConfig, spacing_m: float, line_length_m: float,
                        line_speed_m_s: float) -> dict[str, Any] | None:
        """Discretization keys the fall needs, or None for the preset's own resolution.

        At the release, a preset with a ``tight_line`` entry (``configs/fidelity.yaml``) uses it where the
        mooring line, at the spacing and line length (vertical chain included) [m] of that moment, will be tight
        when the anchor touches down, where there are waves, or where its fastest node moves faster than the
        rule's ``moving_above_m_s`` [m/s] (:func:`moor_env.config.tight_line_needed`). Keys the scene or the
        config's overrides set explicitly win.
        """
        if self.tight_line is None:
            return None
        inst = scene.installation
        hs_m = scene.environment.sea_state.hs_m
        tight = self._tight_line_needed(scene.environment.water_depth_m, inst.vertical_chain_length_m, spacing_m,
                                        line_length_m, hs_m, line_speed_m_s)
        return self._tight_line_keys(hs_m) if tight else None

    def scene_data(self, scenario: dict[str, Any]) -> dict[str, Any]:
        """Scene mapping of a scenario."""
        return apply_scene_overrides(self.base, self.scene_overrides(scenario))

    def statics_data(self, scenario: dict[str, Any], scene_data: dict[str, Any] | None = None) -> dict[str, Any]:
        """Scene mapping whose equilibrium starts the episode (see :mod:`moor_env.envs.equilibria`), from the
        scenario's :meth:`scene_data` (made here when not given)."""
        if scene_data is None:
            scene_data = self.scene_data(scenario)
        data = statics_scene_dict(scene_data, self.chain_material, self.nominal_cd_t)
        if data["environment"]["current"]["scale"] == 0.0:
            data["environment"]["current"]["direction_deg"] = 0.0
        return data

    def episode_scene(self, scenario: dict[str, Any]) -> tuple[SceneConfig, dict[str, Any], SceneConfig, str]:
        """The scenario's validated scene, its statics mapping, that mapping's validated scene and its
        :func:`~moor_env.envs.equilibria.scene_text` (the cache keys' text).

        The statics scene is validated once per equilibrium (cached); the episode scene is it with the
        scenario's ``environment``, ``installation``, chain material and fall integrator validated on their own,
        which is what
        :meth:`scene` gives at a fraction of the cost (a full validation re-reads the fidelity presets; tested
        equal). Any validation error is reported by :meth:`scene`.

        Raises
        ------
        ConfigError
            Naming the scene key the scenario makes invalid.
        """
        data = self.scene_data(scenario)
        statics_data = self.statics_data(scenario, data)
        text = scene_text(statics_data)
        key = scene_key(statics_data, "", text)
        statics = self.statics_scenes.get(key)
        try:
            if statics is None:
                statics = scene_from_dict(statics_data)
            chain = self.chain_material
            update = {
                "environment": EnvironmentConfig.model_validate(data["environment"]),
                "installation": InstallationConfig.model_validate(data["installation"]),
                "materials": {**statics.materials, chain: MaterialConfig.model_validate(data["materials"][chain])},
            }
            fall = data.get("discretization", {}).get("fall_integrator")
            if fall is not None:  # left out of the statics scene (it does not change the equilibrium)
                update["discretization"] = DiscretizationConfig.model_validate(
                    {**statics.discretization.model_dump(), "fall_integrator": fall})
            scene = statics.model_copy(update=update)
            check_scene_consistency(scene)
        except (ConfigError, ValidationError):
            return self.scene(scenario), statics_data, statics, text  # raises the keyed error
        self.statics_scenes[key] = statics
        self.statics_scenes.move_to_end(key)
        while len(self.statics_scenes) > self.STATICS_SCENE_ENTRIES:
            self.statics_scenes.popitem(last=False)
        return scene, statics_data, statics, text

    def scene(self, scenario: dict[str, Any]):
        """Validated scene of a scenario.

        Raises
        ------
        ConfigError
            Naming the scene key the scenario makes invalid.
        """
        try:
            return scene_from_dict(self.scene_data(scenario))
        except ConfigError as exc:
            raise ConfigError(exc.key, exc.value, exc.allowed,
                              (exc.reason + "; " if exc.reason else "") + f"scene of scenario {scenario}") from None


def derive_model(base: Model, scene) -> Model:
    """``base`` (compiled from the statics scene) turned into the model of ``scene``, which differs from it only in
    the sea state, the chain's tangential drag coefficient and the fall's integrator
    (:mod:`moor_env.envs.equilibria`; the Simulator reads the last from ``model.scene`` at the release).

    Neither enters the compiled arrays except the material table's ``MF_CDT`` column (the sea state is read from
    ``model.scene`` by the Simulator; the time-step bound uses normal drag only). The test suite checks that the
    result equals ``compile_scene(scene)`` array for array.
    """
    mat_f = base.mat_f.copy()
    for i, name in enumerate(base.material_names):
        mat_f[i, L.MF_CDT] = scene.materials[name].cd_tangential
    return dataclasses.replace(base, scene=scene, mat_f=mat_f)


def representative_scenario(cfg: EnvConfig) -> dict[str, Any]:
    """First value of every scenario distribution (constant, first choice, lower uniform bound); seed 0."""
    out: dict[str, Any] = {}
    for name in SCENARIO_FIELDS:
        dist = getattr(cfg.scenario, name)
        if name == SEED_FIELD:
            out[name] = 0 if dist == "draw" else int(dist)
        elif isinstance(dist, Choice):
            out[name] = float(dist.choice[0])
        elif isinstance(dist, Uniform):
            out[name] = float(dist.uniform[0])
        else:
            out[name] = float(dist)
    return out


def _draw(dist, rng: np.random.Generator) -> float:
    if isinstance(dist, Choice):
        return float(dist.choice[int(rng.integers(len(dist.choice)))])
    if isinstance(dist, Uniform):
        lo, hi = dist.uniform
        return float(rng.uniform(lo, hi))
    return float(dist)


def draw_scenario(cfg: EnvConfig, rng: np.random.Generator, options: dict[str, Any] | None = None) -> dict[str, Any]:
    """Draw a scenario from the config's distribution; ``options`` fixes fields.

    Every field is drawn (in the fixed order of :data:`SCENARIO_FIELDS`) even when ``options`` fixes it, so that
    fixing one field leaves the draws of the others unchanged for a given seed.

    Raises
    ------
    ConfigError
        For an unknown option key or a value outside the field's range.
    """
    scenario: dict[str, Any] = {}
    for name in SCENARIO_FIELDS:
        if name == SEED_FIELD:
            dist = cfg.scenario.sea_state_seed
            scenario[name] = int(rng.integers(0, SEED_HIGH + 1)) if dist == "draw" else int(dist)
        else:
            scenario[name] = _draw(getattr(cfg.scenario, name), rng)
    for key, value in (options or {}).items():
        if key not in SCENARIO_FIELDS:
            raise ConfigError(f"options.{key}", value, "a scenario field: " + ", ".join(SCENARIO_FIELDS))
        if key == SEED_FIELD:
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= SEED_HIGH:
                raise ConfigError(f"options.{key}", value, f"an integer 0 .. {SEED_HIGH}")
            scenario[key] = int(value)
            continue
        lo, hi = SCENARIO_RANGES[key]
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ConfigError(f"options.{key}", value, "a number") from None
        if not (lo <= v <= hi):
            raise ConfigError(f"options.{key}", value, f"{lo} .. {hi}")
        scenario[key] = v
    return scenario


class InstallationCore:
    """One episode slot: a simulator started from a cached equilibrium and the RL bookkeeping around it.

    Parameters
    ----------
    cfg : EnvConfig
    cache : EquilibriumCache, optional
        Shared between the slots of a vector env.
    factory : SceneFactory, optional
    """

    MODEL_CACHE_ENTRIES = 1024  # pre-release and fall models of the 270 cached equilibria of the default grid

    def __init__(self, cfg: EnvConfig, cache: EquilibriumCache | None = None,
                 factory: SceneFactory | None = None) -> None:
        self.cfg = cfg
        self.factory = factory or SceneFactory(cfg)
        self.cache = cache or EquilibriumCache(cfg.statics)
        self._models = self.factory.models  # shared by the cores of a vector env
        self.sim: Simulator | None = None
        self.max_steps = max(1, int(math.ceil(cfg.control.max_pre_release_s / cfg.control.interval_s - 1e-9)))
        self.scenario: dict[str, Any] = {}
        self.last_obs = np.zeros(len(OBS_NAMES), dtype=np.float32)
        self.pending: Advance | None = None
        self.done = True
        self.buffers: SlotBuffers | None = None  # the kernel's measures and state backup for this slot
        self.fallbacks = 0
        self.advancer = None  # the BatchAdvancer of run_advance, made on first use

    # --- episode start -----------------------------------------------------------------------------------------
    def _compiled(self, key: str, scene: SceneConfig) -> Model:
        """``compile_scene(scene)`` cached under ``key`` (shared by the cores of a vector env)."""
        base = self._models.get(key)
        if base is None:
            base = compile_scene(scene)
            self._models[key] = base
            while len(self._models) > self.MODEL_CACHE_ENTRIES:
                self._models.popitem(last=False)
        else:
            self._models.move_to_end(key)
        return base

    def _model(self, scene: SceneConfig, statics_data: dict[str, Any], statics: SceneConfig, text: str) -> Model:
        """Compiled model of ``scene``: the model of the statics scene ``statics`` (mapping ``statics_data``, of
        :func:`~moor_env.envs.equilibria.scene_text` ``text``; cached) with the episode's sea state and chain Cd_t
        (:func:`derive_model`), so that a new sea state costs no compile."""
        self.statics_key = scene_key(statics_data, self.cache.source_hash, text)
        return derive_model(self._compiled(self.statics_key, statics), scene)

    def _fall_model(self, keys: dict[str, Any]) -> Model:
        """The episode's model at the pre-release resolution changed by the discretization ``keys``."""
        statics = self.statics_scene
        disc = DiscretizationConfig.model_validate({**statics.discretization.model_dump(), **keys})
        base = self._compiled(self.statics_key + json.dumps(keys, sort_keys=True),
                              statics.model_copy(update={"discretization": disc}))
        episode = self.sim.model.scene
        disc = disc.model_copy(update={"fall_integrator": episode.discretization.fall_integrator})
        return derive_model(base, episode.model_copy(update={"discretization": disc}))

    def _line_speed_m_s(self) -> float:
        """Speed of the fastest free node of the vertical chain and the mooring line [m/s]."""
        st = self.sim.state
        lines = [self.lines["vertical_chain"], self.lines["mooring_line"]]
        free = (st.node_i[:, L.NI_KIND] == L.NODE_FREE) & np.isin(st.node_i[:, L.NI_LINE], lines)
        return float(np.sqrt(np.max(np.sum(st.node_vel[free] ** 2, axis=1), initial=0.0)))

    def _fit_fall_resolution(self) -> None:
        """Move the simulation onto the resolution the fall needs (:meth:`SceneFactory.fall_resolution`)."""
        old = self.sim
        keys = self.factory.fall_resolution(old.model.scene, self.spacing_m(), self.line_length_total_m(),
                                            self._line_speed_m_s())
        self.fall_resolution = "preset" if keys is None else "tight_line"
        current = old.model.scene.discretization
        if keys is None or all(getattr(current, k) == v for k, v in keys.items()):
            return
        model = self._fall_model(keys)
        sim = Simulator(model)
        try:
            sim.state = remesh_state(old.state, old.model, model)
        except ValueError as exc:  # e.g. paid out beyond the fine model's segment slots: keep the preset's
            self.fall_resolution = f"preset (remesh refused: {exc})"
            return
        sim.env_f[:] = old.env_f
        sim.vessel_mean_m[:] = old.vessel_mean_m
        sim.tracks = old.tracks.copy()
        self.sim = sim
        self.buffers = self._slot_buffers(sim, backup=False)  # the fall takes no backup

    def start(self, scenario: dict[str, Any]) -> Advance | None:
        """Build the simulator of a scenario at its hanging equilibrium; the warm-up to run, if any.

        Raises
        ------
        ConfigError, StaticsNotConverged
            If the scenario gives no valid scene or no equilibrium.
        """
        cfg = self.cfg
        scene, statics_data, statics, text = self.factory.episode_scene(scenario)
        model = self._model(scene, statics_data, statics, text)
        self.statics_scene = statics
        state, origin = self.cache.state(statics_data, text)
        if state.node_pos.shape != model.node_pos0.shape or state.seg_i.shape != model.seg_i.shape:
            raise StaticsNotConverged("cached equilibrium does not match the compiled scene's topology")
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
        self.flags = {"tension": False, "release_unit": False, "fibre_seabed": False}
        self.failed_at_start: str | None = None
        self.release_ref = sim.state.node_pos[model.release_node].copy()
        tip, _ = sim.tip_state()
        self.target_xy = tip[:2].copy()
        self.touchdown: dict[str, float] | None = None
        self.t0 = 0.0
        if self.hs > 0.0 and cfg.control.warmup_s > 0.0:
            sim.set_vessel_motion(sim.state.t, cfg.control.warmup_s, np.zeros(2), ramp_s=self.ramp_s)
            self.pending = self._pre_release(sim.state.t + cfg.control.warmup_s, PHASE_WARMUP)
        else:
            self.pending = None
        return self.pending

    def _slot_buffers(self, sim: Simulator, backup: bool) -> SlotBuffers:
        """The kernel's buffers for ``sim``: measure what the observation reads (the mooring line summarised with
        the fibre as the material), and a backup of the state where pre-release advances may take one."""
        spec = [0] * B.N_SPEC
        spec[B.SPEC_RELEASE_NODE] = sim.model.release_node
        spec[B.SPEC_LINE] = self.lines["mooring_line"]
        spec[B.SPEC_MATERIAL] = self.fibre_mat
        spec[B.SPEC_WIRE] = self.lines.get("wire", -1)
        spec[B.SPEC_VESSEL] = VESSEL_INSTALLATION
        return SlotBuffers(spec, sim.state if backup else None)

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
        info = {"scenario": dict(self.scenario), "sim_status": self.status, "statics": self.statics_origin,
                "t_s": 0.0}
        return raw, info

    # --- steps -------------------------------------------------------------------------------------------------
    def _pre_release(self, t_end_s: float, phase: str) -> Advance:
        """Advance to ``t_end_s`` before the release, in steps of about ``control.pre_release_dt_s`` (in a sea
        without waves ``control.pre_release_dt_calm_s``, where set).

        The span is split into n equal steps, n the smallest whole number that keeps them at or below the
        configured step (never below the scene's step), so the advance ends exactly at ``t_end_s`` and the
        release falls on the control grid. Only the implicit integrator takes the coarser step: the explicit
        ones are bound by the lines' axial stability limit whether or not the anchor falls. Before a step
        coarser than the scene's the kernel saves the state for :meth:`fallback` (``Advance.backup``).
        """
        sim = self.sim
        cfg = self.cfg.control
        step = cfg.pre_release_dt_s
        if self.hs == 0.0 and cfg.pre_release_dt_calm_s is not None:
            step = cfg.pre_release_dt_calm_s
        target = sim.dt
        if sim.integrator_code == INTEGRATOR_IMPLICIT_EULER and step is not None:
            target = max(step, sim.dt)
        adv = Advance(t_end_s, False, phase, _even_step(t_end_s - sim.state.t, target))
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
                               _even_step(adv.t_end_s - self.sim.state.t, self.sim.dt))
        return self.pending

    @property
    def time_s(self) -> float:
        """Time since the first observation [s]."""
        return self.sim.state.t - self.t0

    def spacing_m(self) -> float:
        """Distance between the two vessels' mean positions [m]."""
        v = self.sim.vessel_mean_m
        return float(v[VESSEL_SECOND, 0] - v[VESSEL_INSTALLATION, 0])

    def _mooring_line(self) -> tuple[float, float, float]:
        """:func:`line_summary` of the mooring line with the fibre as the material: the kernel's measure where it
        is current (every step after its advance), else evaluated here (after a reset without a warm-up or an
        in-place change such as the release)."""
        m = self.buffers.current_measures(self.sim)
        if m is not None:
            return m[B.M_LOOP_Z_M], m[B.M_FIBRE_Z_M], m[B.M_LINE_L0_M]
        st = self.sim.state
        return line_summary(st.node_pos, st.seg_i, st.seg_f, st.line_i, self.lines["mooring_line"], self.fibre_mat)

    def line_length_total_m(self) -> float:
        """Mooring line including the vertical chain [m] (unstretched)."""
        return self._mooring_line()[2] + self.vertical_chain_m

    def begin_step(self, action: np.ndarray | list[float]) -> Advance | None:
        """Apply an action (3 numbers, or a list of 3 Python floats as the vector env passes its rows); the
        integration it needs (None when the episode ends without one)."""
        cfg = self.cfg.control
        sim = self.sim
        values = action if type(action) is list else np.asarray(action, dtype=np.float64).reshape(3).tolist()
        # clipped to [-1, 1]; NaN holds position and does not release
        a = [0.0 if x != x else min(1.0, max(-1.0, x)) for x in values]
        if self.failed_at_start is not None:
            self.pending = None
            return None
        t = sim.state.t
        if a[2] > 0.0:
            sim.set_payout_rate("mooring_line", 0.0)
            self.payout_rate = 0.0
            self.spacing_rate = 0.0
            self._fit_fall_resolution()
            sim = self.sim
            sim.release()
            self.released = True
            sim.set_vessel_motion(t, self.max_fall_s + 1.0, np.zeros(2), ramp_s=self.ramp_s)
            self.pending = Advance(t + self.max_fall_s, True, PHASE_FALL, sim.dt)
            return self.pending
        dt = cfg.interval_s
        # DP vessel: commanded speed, acceleration-limited, kept inside the spacing limits
        cmd = a[0] * cfg.spacing_rate_max_m_s
        dv = cfg.spacing_accel_max_m_s2 * dt
        v = min(max(cmd, self.spacing_rate - dv), self.spacing_rate + dv)
        s = self.spacing_m()
        s_max = cfg.spacing_max_over_depth * self.depth
        v = min(max(v, (cfg.spacing_min_m - s) / dt), (s_max - s) / dt)
        # winch: pay out (+) or haul in (-), kept inside the line-length limits
        rate = a[1] * (cfg.payout_rate_max_m_s if a[1] > 0.0 else cfg.haul_rate_max_m_s)
        length = self.line_length_total_m()
        lo = cfg.line_length_min_over_depth * self.depth
        hi = cfg.line_length_max_over_depth * self.depth
        rate = min(max(rate, (lo - length) / dt), (hi - length) / dt)
        self.spacing_rate = float(v)
        self.payout_rate = float(rate)
        sim.set_vessel_motion(t, dt, np.array([0.0, v]), ramp_s=self.ramp_s)
        sim.set_payout_rate("mooring_line", float(rate))
        self.pending = self._pre_release(t + dt, PHASE_CONTROL)
        return self.pending

    def begin_hold(self, t_end_s: float) -> Advance | None:
        """Hold the vessels (second vessel stopped) and the winch until ``t_end_s`` (AnchorPlan-v0's wait)."""
        if self.failed_at_start is not None:
            self.pending = None
            return None
        sim = self.sim
        t = sim.state.t
        sim.set_payout_rate("mooring_line", 0.0)
        self.payout_rate = 0.0
        self.spacing_rate = 0.0
        sim.set_vessel_motion(t, max(t_end_s - t, sim.dt), np.zeros(2), ramp_s=self.ramp_s)
        self.hold_start_s = t
        self.pending = self._pre_release(t_end_s, PHASE_HOLD)
        return self.pending

    def finish_step(self, status: int | None, error: SimulationDiverged | None
                    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Observation, reward, terminated, truncated and info after the integration of ``begin_step``."""
        raw, *rest = self.finish_step_raw(status, error)
        return self.observe_raw(raw), *rest

    def finish_step_raw(self, status: int | None, error: SimulationDiverged | None
                        ) -> tuple[list[float] | None, float, bool, bool, dict[str, Any]]:
        """:meth:`finish_step` with the observation in physical units (None: keep the last observation)."""
        rcfg = self.cfg.reward
        terms = dict.fromkeys(REWARD_TERMS, 0.0)
        phase = self.pending.phase if self.pending is not None else None
        self.pending = None
        terminated = truncated = False
        maxima = self._max_tensions_n()
        if self.failed_at_start is not None or error is not None:
            if error is not None:
                self.status = f"diverged: {error}"
            terms["failure"] = -rcfg.failure_penalty
            terminated = True
            raw = None
        else:
            if phase == PHASE_CONTROL:
                self.steps += 1
                terms["time"] = -rcfg.time_cost_per_s * self.cfg.control.interval_s
                self._check_limits(terms, maxima)
                if self.steps >= self.max_steps:
                    truncated = True
                    terms["truncation"] = -rcfg.truncation_penalty
                    self.status = "time limit"
            elif phase == PHASE_HOLD:
                terms["time"] = -rcfg.time_cost_per_s * (self.sim.state.t - self.hold_start_s)
                self._check_limits(terms, maxima)
            else:  # the fall
                terminated = True
                self._check_limits(terms, maxima)
                if status == L.STATUS_TOUCHDOWN:
                    self.status = "touchdown"
                    self._touchdown_terms(terms)
                else:
                    self.status = "no touchdown within max_fall_time_s"
                    terms["no_touchdown"] = -rcfg.no_touchdown_penalty
            raw = self.raw_observation()
        reward = float(sum(terms.values()))
        self.done = terminated or truncated
        info = self.info(terms, maxima)
        return raw, reward, terminated, truncated, info

    def _max_tensions_n(self) -> dict[str, float]:
        """Running maximum tension of each line by name [N]."""
        maxima = self.sim.state.line_f[:, L.LF_MAX_TENSION].tolist()
        return {name: maxima[i] for name, i in self.lines.items()}

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

    def _check_limits(self, terms: dict[str, float], maxima: dict[str, float]) -> None:
        """Penalties of the limits first exceeded in this step; ``maxima``: :meth:`_max_tensions_n`."""
        rcfg = self.cfg.reward
        if not self.flags["tension"]:
            if any(maxima[name] > self.mbl[name] for name in self.lines):
                self.flags["tension"] = True
                terms["tension"] = -rcfg.tension_penalty
        if not self.flags["release_unit"] and "wire" in self.lines:
            # running maximum over the wire's segments: exceeds the load at the unit by at most the wire's weight
            if maxima["wire"] > self.release_unit_limit_n:
                self.flags["release_unit"] = True
                terms["release_unit"] = -rcfg.release_unit_penalty
        if not self.flags["fibre_seabed"]:
            if self._fibre_clearance_m() < rcfg.fibre_clearance_m:
                self.flags["fibre_seabed"] = True
                terms["fibre_seabed"] = -rcfg.fibre_seabed_penalty

    def _touchdown_terms(self, terms: dict[str, float]) -> None:
        rcfg = self.cfg.reward
        sim = self.sim
        td = sim.work.touchdown
        vel = td[L.TD_VEL:L.TD_VEL + 3]
        speed = float(np.linalg.norm(vel))
        tilt = float(math.degrees(math.acos(min(1.0, max(-1.0, -td[L.TD_AXIS + 2])))))
        offset = float(np.hypot(td[L.TD_TIP] - self.target_xy[0], td[L.TD_TIP + 1] - self.target_xy[1]))
        pile = float(sim.line_length_on_seabed_m({self.chain_material}))
        terms["speed"] = rcfg.speed_weight * min(1.0, max(0.0, 1.0 - max(0.0, rcfg.required_speed_m_s - speed)
                                                          / rcfg.speed_falloff_m_s))
        terms["tilt"] = rcfg.tilt_weight * (1.0 - tilt / rcfg.tilt_criterion_deg)
        if tilt > rcfg.tilt_criterion_deg:
            terms["tilt"] -= rcfg.tilt_excess_penalty
        terms["offset"] = rcfg.offset_weight * (1.0 - min(offset / rcfg.offset_tolerance_m, 2.0))
        excess = max(0.0, pile - rcfg.chain_pile_allowance_m)
        if excess > 0.0:
            terms["chain_pile"] = -rcfg.chain_pile_penalty * min(1.0, excess / rcfg.chain_pile_scale_m)
        self.touchdown = {"speed_m_s": speed, "vertical_speed_m_s": float(-vel[2]), "tilt_deg": tilt,
                          "offset_m": offset, "fall_time_s": float(td[L.TD_TIME] - sim.release_time_s),
                          "chain_on_seabed_m": pile,
                          "chain_past_back_end_m": sim.line_past_back_end_m("vertical_chain")[0]}

    # --- observation -------------------------------------------------------------------------------------------
    def _fibre_clearance_m(self) -> float:
        return self._mooring_line()[1] + self.depth

    def _measures(self) -> list[float]:
        """The kernel's ``M_*`` measures of the current state (:func:`moor_env.envs.batch.measure_scene`), measured
        here where the state is not the one the kernel left (a reset without a warm-up)."""
        sim = self.sim
        buffers = self.buffers
        measured = buffers.current_measures(sim)
        if measured is None:
            st = sim.state
            sim.top_tensions_n()  # the loads, where they are not current
            measure_scene(st.t, st.node_pos, st.node_vel, st.body_state, st.seg_i, st.seg_f, st.line_i,
                          sim.model.body_f, sim.env_f, sim.model.current_profile, sim.tracks, sim.work.top_tension,
                          buffers.spec, buffers.measures)
            measured = buffers.measures.tolist()
        return measured

    def raw_observation(self) -> list[float]:
        """Observation in physical units (see :data:`OBS_SPEC`), from the kernel's measures and the slot's own
        state (Python floats: it runs every step, where small numpy operations cost more than the arithmetic)."""
        m = self._measures()
        ref = self.release_ref
        fibre = m[B.M_FIBRE_Z_M] + self.depth
        loop_bottom = m[B.M_LOOP_Z_M] + self.depth
        return [
            self.time_s / self.cfg.control.max_pre_release_s,
            1.0 if self.released else 0.0,
            self.spacing_m(),
            self.spacing_rate,
            (m[B.M_LINE_L0_M] + self.vertical_chain_m) / self.depth,
            self.payout_rate,
            m[B.M_RELEASE_POS] - ref[0],
            m[B.M_RELEASE_POS + 1] - ref[1],
            m[B.M_RELEASE_POS + 2] - ref[2],
            m[B.M_RELEASE_VEL],
            m[B.M_RELEASE_VEL + 1],
            m[B.M_RELEASE_VEL + 2],
            m[B.M_TILT_DEG],
            m[B.M_AXIS_RATE_DEG_S],
            m[B.M_WIRE_TENSION_N] / 1e6,
            m[B.M_LINE_TENSION_N] / 1e6,
            m[B.M_HEAVE_M] + self.fairlead_depth_m,
            m[B.M_HEAVE_RATE_M_S],
            m[B.M_CURRENT_X_M_S],
            m[B.M_CURRENT_Y_M_S],
            self.depth,
            m[B.M_TIP_Z_M] + self.depth,
            loop_bottom if math.isfinite(loop_bottom) else 0.0,
            fibre if math.isfinite(fibre) else 1000.0,
            self.hs,
            self.tp,
            self.vertical_chain_m,
        ]

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

    # --- drawing -----------------------------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        """Geometry for a frame (copies): line polylines with materials, anchor, vessels, current."""
        sim = self.sim
        st = sim.state
        m = sim.model
        lines = {}
        for name, idx in self.lines.items():
            li = st.line_i[idx]
            if not st.seg_i[li[L.LI_SEG_START], L.SI_ACTIVE]:
                continue
            segs = np.arange(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])
            nodes = np.concatenate([[st.seg_i[segs[0], L.SI_A]], st.seg_i[segs, L.SI_B]])
            mats = [m.material_names[k] for k in st.seg_i[segs, L.SI_MAT]]
            lines[name] = (st.node_pos[nodes].copy(), mats)
        tip, vel = sim.tip_state()
        vessels = []
        for v in range(sim.vessel_mean_m.shape[0]):
            x, y, z, *_ = track_state(sim.tracks, v, st.t, sim.env_f)
            vessels.append((x, z))
        profile = m.current_profile
        depths = np.linspace(0.0, self.depth * 0.95, 6)
        current = [(-d, *current_velocity(-d, sim.env_f, profile)[:2]) for d in depths]
        return {"t_s": self.time_s, "depth_m": self.depth, "lines": lines, "tip": tip.copy(),
                "back": sim.back_end_m(), "tip_speed_m_s": float(np.linalg.norm(vel)),
                "tilt_deg": sim.tilt_deg(), "vessels": vessels, "current": current, "released": self.released,
                "status": self.status, "chain_material": self.chain_material,
                "fibre_material": m.material_names[self.fibre_mat], "hs_m": self.hs, "target_xy": self.target_xy}


def _even_step(span_s: float, max_step_s: float) -> float:
    """``span_s`` / n for the smallest whole n that keeps the step at or below ``max_step_s``."""
    return span_s / max(1, math.ceil(span_s / max_step_s - 1e-9))


def run_advance(core: InstallationCore, adv: Advance, chunk_s: float | None = None,
                on_chunk=None) -> tuple[int | None, SimulationDiverged | None]:
    """Integrate one core's simulator as ``adv`` asks (optionally in chunks with a callback, e.g. frames).

    The integration goes through :func:`moor_env.envs.batch.advance_many` with one scene, the kernel the batched
    vector env uses, so that both give bit-identical episodes. Chunking never changes the result: the kernel
    takes whole steps of dt from the same start time.
    """
    if core.advancer is None:
        core.advancer = BatchAdvancer()
    sim = core.sim
    chunk_s = None if chunk_s is None or on_chunk is None else max(chunk_s, adv.dt_s)
    status = L.STATUS_TIME_LIMIT
    backup = adv.backup  # the state before the first chunk is the one a fallback goes back to
    while sim.state.t < adv.t_end_s - 0.5 * adv.dt_s:
        t_stop = adv.t_end_s if chunk_s is None else min(sim.state.t + chunk_s, adv.t_end_s)
        job = (sim, t_stop, adv.detect_touchdown, adv.dt_s, core.buffers, backup)
        status, error = core.advancer.run({0: job})[0]
        backup = False
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

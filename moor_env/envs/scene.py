"""Scenario -> scene -> compiled model: what an episode simulates.

:class:`SceneFactory` reads the config's base scene once, applies the fidelity preset and the config's scene
overrides, and turns each scenario into a scene mapping, its validated :class:`~moor_env.scene_schema.SceneConfig`,
the statics mapping whose equilibrium starts the episode (:mod:`moor_env.envs.equilibria`) and the compiled
model (one compile per geometry: a new sea state or chain drag costs none, :func:`derive_model`). A new
geometry's statics scene is validated section by section against a template of the same resolution
(:meth:`SceneFactory.statics_scene`): a full validation re-reads the fidelity presets and costs more than the
static solve. The mesh a scenario starts on and the one its fall needs come from the preset's
:class:`~moor_env.envs.resolution.TightLineRule`.
"""

from __future__ import annotations

import dataclasses
import json
from collections import OrderedDict
from typing import Any

from pydantic import ValidationError

from moor_env.compile import Model, compile_scene
from moor_env.config import (
    SET_SHORTCUTS,
    SceneConfig,
    check_scene_consistency,
    scene_dict,
    scene_from_dict,
    tight_line_rule,
)
from moor_env.envs.config import EnvConfig
from moor_env.envs.equilibria import FALL_KEYS, plain_copy, scene_key, scene_text, statics_scene_dict
from moor_env.envs.resolution import TightLineRule, tight_line_keys_by_sea
from moor_env.envs.scenario import representative_scenario
from moor_env.errors import ConfigError
from moor_env.physics import layout as L
from moor_env.scene_schema import (
    AnchorConfig,
    DiscretizationConfig,
    EnvironmentConfig,
    InstallationConfig,
    MaterialConfig,
)


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


_GEOMETRY_SECTIONS = ("environment", "installation", "anchor")  # the sections a scenario's geometry sets


def _keep(entries: OrderedDict, key: str, value: Any, size: int) -> None:
    """Put ``value`` under ``key`` as the newest entry of the LRU ``entries``, which keeps ``size``."""
    entries[key] = value
    entries.move_to_end(key)
    while len(entries) > size:
        entries.popitem(last=False)


class SceneFactory:
    """Scenario -> scene mapping -> validated :class:`SceneConfig` -> compiled model (the base scene is read from
    YAML once; the statics scenes and compiled models of the last ``statics.memory_entries`` geometries are kept,
    shared by the slots of a vector env, with the equilibria of :mod:`moor_env.envs.equilibria`).

    Raises
    ------
    ConfigError
        At construction, if the scene, ``fidelity`` or ``scene_overrides`` are invalid (checked with the
        config's representative scenario: the first value of every scenario distribution).
    """

    TEMPLATE_ENTRIES = 8  # statics scenes by everything but the geometry: one per pre-release resolution

    def __init__(self, cfg: EnvConfig) -> None:
        self.cfg = cfg
        # the last geometries' statics scenes and compiled models (pre-release and fall) by equilibrium key
        self.statics_entries = cfg.statics.memory_entries
        self.models: OrderedDict[str, Model] = OrderedDict()
        self.statics_scenes: OrderedDict[str, SceneConfig] = OrderedDict()
        self.templates: OrderedDict[str, SceneConfig] = OrderedDict()
        raw = scene_dict(cfg.scene)
        if raw.get("kind", "dart_installation") != "dart_installation" or "installation" not in raw:
            raise ConfigError("scene", cfg.scene, "a dart_installation scene")
        self.base = apply_scene_overrides(raw, {**cfg.fidelity, **cfg.scene_overrides})
        rule = tight_line_rule(self.base.get("fidelity", "default"))
        keys_by_sea = None if rule is None else tight_line_keys_by_sea(rule, self.base.get("discretization", {}))
        self.tight_line: TightLineRule | None = None  # the representative scene below supplies its geometry
        scene = self.scene(representative_scenario(cfg))
        if rule is not None:
            self.tight_line = TightLineRule(rule, keys_by_sea, scene.anchor.length_m,
                                            scene.installation.fairlead_depth_m)
        self.chain_material = scene.installation.chain_material
        # what AnchorPlan-v1's levers and soil need of the scene (the same in every scenario of a config)
        self.anchor_length_m = scene.anchor.length_m
        self.anchor_mass_kg = sum(s.length_m * s.mass_per_length_kg_m for s in scene.anchor.sections)
        self.fairlead_depth_m = scene.installation.fairlead_depth_m
        self.nominal_cd_t = float(self.base["materials"][self.chain_material]["cd_tangential"])
        comp = scene.installation.components
        if not (comp.wire and comp.vertical_chain and comp.mooring_line):
            raise ConfigError("scene", cfg.scene, "a scene with wire, vertical chain and mooring line")

    # --- resolution ------------------------------------------------------------------------------------------------
    def pre_release_resolution(self, scenario: dict[str, Any]) -> dict[str, Any]:
        """Discretization keys of a scenario before its release (:meth:`TightLineRule.pre_release`; none without
        a ``tight_line`` rule)."""
        return {} if self.tight_line is None else self.tight_line.pre_release(scenario)

    def fall_resolution(self, scene: SceneConfig, spacing_m: float, line_length_m: float,
                        line_speed_m_s: float) -> dict[str, Any] | None:
        """Discretization keys the fall needs, or None for the preset's own resolution
        (:meth:`TightLineRule.fall`). Keys the scene or the config's overrides set explicitly win."""
        return None if self.tight_line is None else self.tight_line.fall(scene, spacing_m, line_length_m,
                                                                         line_speed_m_s)

    # --- scene mappings --------------------------------------------------------------------------------------------
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

    # --- validated scenes ------------------------------------------------------------------------------------------
    def episode_scene(self, scenario: dict[str, Any]) -> tuple[SceneConfig, dict[str, Any], SceneConfig, str]:
        """The scenario's validated scene, its statics mapping, that mapping's validated scene
        (:meth:`statics_scene`) and its :func:`~moor_env.envs.equilibria.scene_key` (the equilibrium key).

        The episode scene is the statics scene with the scenario's ``environment``, ``installation``, chain
        material and fall integrator validated on their own, which is what :meth:`scene` gives at a fraction of
        the cost (tested equal). Any validation error is reported by :meth:`scene`.

        Raises
        ------
        ConfigError
            Naming the scene key the scenario makes invalid.
        """
        data = self.scene_data(scenario)
        statics_data = self.statics_data(scenario, data)
        text = scene_text(statics_data)
        key = scene_key(statics_data, text)
        statics = self.statics_scenes.get(key)
        try:
            if statics is None:
                statics = self.statics_scene(statics_data)
            chain = self.chain_material
            update = {
                "environment": EnvironmentConfig.model_validate(data["environment"]),
                "installation": InstallationConfig.model_validate(data["installation"]),
                "materials": {**statics.materials, chain: MaterialConfig.model_validate(data["materials"][chain])},
            }
            disc_data = data.get("discretization", {})
            fall = {k: disc_data[k] for k in FALL_KEYS if disc_data.get(k) is not None}
            if fall:  # left out of the statics scene (they do not change the equilibrium)
                update["discretization"] = DiscretizationConfig.model_validate(
                    {**statics.discretization.model_dump(), **fall})
            scene = statics.model_copy(update=update)
            check_scene_consistency(scene)
        except (ConfigError, ValidationError):
            return self.scene(scenario), statics_data, statics, key  # raises the keyed error
        _keep(self.statics_scenes, key, statics, self.statics_entries)
        return scene, statics_data, statics, key

    def statics_scene(self, statics_data: dict[str, Any]) -> SceneConfig:
        """Validated scene of a statics mapping (:meth:`statics_data`).

        Mappings that differ only in the geometry's sections (``environment``, ``installation``, ``anchor``)
        share a template: the first of them is validated in full (:func:`scene_from_dict`, with the fidelity
        preset applied); the others are the template with those sections validated on their own and the scene's
        consistency checked (tested equal to a full validation). The envs never fit the resolution to the
        geometry in the scene (``discretization.fit_to_geometry`` false), so the preset fills the same keys for all.

        Raises
        ------
        ConfigError, ValidationError
        """
        rest = scene_text({k: v for k, v in statics_data.items() if k not in _GEOMETRY_SECTIONS})
        template = self.templates.get(rest)
        if template is None or template.discretization.fit_to_geometry:
            scene = scene_from_dict(statics_data)
            _keep(self.templates, rest, scene, self.TEMPLATE_ENTRIES)
            return scene
        self.templates.move_to_end(rest)
        scene = template.model_copy(update={
            "environment": EnvironmentConfig.model_validate(statics_data["environment"]),
            "installation": InstallationConfig.model_validate(statics_data["installation"]),
            "anchor": AnchorConfig.model_validate(statics_data["anchor"]),
        })
        check_scene_consistency(scene)
        return scene

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

    # --- compiled models -------------------------------------------------------------------------------------------
    def compiled(self, key: str, scene: SceneConfig) -> Model:
        """``compile_scene(scene)``, kept under ``key`` for the last geometries (pre-release and fall model of
        each of ``statics.memory_entries``)."""
        base = self.models.get(key)
        if base is None:
            base = compile_scene(scene)
            _keep(self.models, key, base, 2 * self.statics_entries)
        else:
            self.models.move_to_end(key)
        return base

    def model(self, statics_key: str, statics: SceneConfig, scene: SceneConfig) -> tuple[Model, Model]:
        """Compiled model of ``scene`` and that of its statics scene ``statics`` (kept under the equilibrium key
        ``statics_key``): the first is the second with the episode's sea state and chain Cd_t
        (:func:`derive_model`), so that a new sea state costs no compile."""
        base = self.compiled(statics_key, statics)
        return derive_model(base, scene), base

    def fall_model(self, statics_key: str, statics: SceneConfig, episode: SceneConfig, keys: dict[str, Any]) -> Model:
        """The model of the episode scene ``episode`` (statics scene ``statics``, equilibrium key ``statics_key``)
        at its pre-release resolution changed by the discretization ``keys``."""
        disc = DiscretizationConfig.model_validate({**statics.discretization.model_dump(), **keys})
        base = self.compiled(statics_key + json.dumps(keys, sort_keys=True),
                             statics.model_copy(update={"discretization": disc}))
        disc = disc.model_copy(update={k: getattr(episode.discretization, k) for k in FALL_KEYS})
        return derive_model(base, episode.model_copy(update={"discretization": disc}))

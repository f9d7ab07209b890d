"""Scene configuration: YAML -> validated, frozen config objects.

This is the first stage of the one-way pipeline
``configs/scenes/*.yaml -> SceneConfig (here) -> Model (compile.py) -> numba kernels -> results``.

The config objects (:class:`SceneConfig` and its sections, SI units with the unit in the key's name) are
defined in :mod:`moor_env.scene_schema`. This module reads a bundled scene or a YAML file, expands its library
entries (``configs/library.yaml``), applies ``--set`` overrides and validates; :func:`load_scene` turns
pydantic's errors into one-line :class:`~moor_env.errors.ConfigError` messages that name the key, its value and
the allowed range (:mod:`moor_env.config_text`, with the nearest known key for an unknown one). Quantities
derived from a validated scene and the cross-field checks live in :mod:`moor_env.scene_geometry`; the
discretization presets and their fit to the geometry in :mod:`moor_env.fidelity`.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from moor_env.config_text import key_help_lines, unknown_key_error, validation_error, yaml_error_text
from moor_env.errors import ConfigError, did_you_mean

# the names imported "as" themselves are re-exported: the envs and the benchmarks import them from here
from moor_env.fidelity import FIDELITY_PATH, apply_fidelity, fit_fidelity
from moor_env.fidelity import TIGHT_LINE as TIGHT_LINE
from moor_env.fidelity import fidelity_presets as fidelity_presets
from moor_env.fidelity import tight_line_keys as tight_line_keys
from moor_env.fidelity import tight_line_needed as tight_line_needed
from moor_env.fidelity import tight_line_rule as tight_line_rule
from moor_env.scene_geometry import DROP_HEIGHT_KEY, WATER_DEPTH_KEY, check_scene_consistency, drop_fit_bound_error
from moor_env.scene_geometry import line_slack_geometry as line_slack_geometry
from moor_env.scene_geometry import mooring_line_slack as mooring_line_slack
from moor_env.scene_schema import SceneConfig

CONFIG_DIR = FIDELITY_PATH.parent
SCENE_DIR = CONFIG_DIR / "scenes"
LIBRARY_PATH = CONFIG_DIR / "library.yaml"


# --- --set shortcuts: interface names (stable) -> dotted paths in the scene --------------------------------
SET_SHORTCUTS: dict[str, str] = {
    "water_depth_m": "environment.water_depth_m",
    "vessel_spacing_m": "installation.vessel_spacing_m",
    "vertical_chain_length_m": "installation.vertical_chain_length_m",
    "mooring_line_length_m": "installation.mooring_line_length_m",
    "bottom_chain_length_m": "installation.bottom_chain_length_m",
    "drop_height_m": "installation.drop_height_m",
    "chain_cd_tangential": "materials.{chain}.cd_tangential",
    "current_scale": "environment.current.scale",
    "current_direction_deg": "environment.current.direction_deg",
    "sea_state_hs_m": "environment.sea_state.hs_m",
    "sea_state_tp_s": "environment.sea_state.tp_s",
    "sea_state_seed": "environment.sea_state.seed",
    "release_time_s": "installation.release_time_s",
    "anchor_mass_scale": "anchor.mass_scale",
    "dt_s": "discretization.dt_s",
    "integrator": "discretization.integrator",
    "fall_integrator": "discretization.fall_integrator",
    "fidelity": "fidelity",
}


def bundled_scene_names() -> list[str]:
    """Names of the scenes shipped in ``configs/scenes`` (without ``.yaml``)."""
    return sorted(p.stem for p in _scene_dir().glob("*.yaml"))


def _scene_dir() -> Path:
    return SCENE_DIR


def _load_library() -> dict[str, Any]:
    with open(LIBRARY_PATH, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _resolve_library(data: dict[str, Any]) -> dict[str, Any]:
    """Expand ``{library: NAME, ...overrides}`` entries of ``materials`` and ``anchor`` from library.yaml.

    A scene without ``materials`` gets every library material.
    """
    library = _load_library()

    def expand(entry: Any, section: str, key: str) -> Any:
        if isinstance(entry, dict) and "library" in entry:
            name = entry["library"]
            if name not in library[section]:
                raise ConfigError(f"{key}.library", name, "one of " + ", ".join(library[section]),
                                  did_you_mean(str(name), library[section]))
            merged = copy.deepcopy(library[section][name])
            merged.update({k: v for k, v in entry.items() if k != "library"})
            return merged
        return entry

    if "materials" not in data:
        data["materials"] = copy.deepcopy(library["materials"])
    elif isinstance(data["materials"], dict):
        data["materials"] = {k: expand(v, "materials", f"materials.{k}") for k, v in data["materials"].items()}
    if "anchor" in data:
        data["anchor"] = expand(data["anchor"], "anchors", "anchor")
    return data


def _resolve_scene_path(scene: str | Path) -> Path:
    path = Path(scene)
    if path.is_dir():
        raise ConfigError("scene", str(scene), "a bundled scene name or a YAML file", "this is a directory")
    if path.is_file():
        return path
    if path.suffix in (".yaml", ".yml"):
        raise ConfigError("scene", str(scene), "an existing YAML file", "file not found")
    candidate = _scene_dir() / f"{scene}.yaml"
    if not candidate.is_file():
        names = bundled_scene_names()
        raise ConfigError("scene", str(scene), "one of " + ", ".join(names) + " or a YAML path",
                          did_you_mean(str(scene), names))
    return candidate


def parse_set_value(text: str) -> Any:
    """Parse the VALUE of a ``--set KEY=VALUE`` with YAML rules (numbers, booleans, lists, strings)."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def _apply_override(data: dict[str, Any], key: str, value: Any) -> None:
    chain = data.get("installation", {}).get("chain_material", "chain_142")
    path = SET_SHORTCUTS.get(key, key).replace("{chain}", str(chain))
    parts = path.split(".")
    unknown = unknown_key_error(SceneConfig, key, parts, value, data, list(SET_SHORTCUTS))
    if unknown is not None:
        raise unknown
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        if isinstance(node, list):  # an entry of a list section by its index: anchor.sections.0.length_m
            if not (part.isdigit() and int(part) < len(node)):
                raise ConfigError(key, value, f"an index 0 .. {len(node) - 1} of {'.'.join(parts[:i])}")
            node = node[int(part)]
            continue
        if not isinstance(node, dict):
            raise ConfigError(key, value, "a dotted path into the scene", f"'{'.'.join(parts[:i])}' is not a section")
        if part not in node:
            if part not in _OPTIONAL_SECTIONS:
                raise ConfigError(key, value, "a key of a section this scene has", f"it has no '{part}' section")
            node[part] = {}
        node = node[part]
    if not isinstance(node, dict):
        raise ConfigError(key, value, "a dotted path into the scene", f"'{'.'.join(parts[:-1])}' is not a section")
    node[parts[-1]] = value


_OPTIONAL_SECTIONS = {
    "current", "seabed", "sea_state", "discretization", "simulation", "components", "release_unit", "environment",
}


def set_key_help() -> list[str]:
    """One line per ``--set`` shortcut: its name, unit or type, allowed range and the dotted path it sets."""
    return key_help_lines(SceneConfig, SET_SHORTCUTS)


def scene_from_dict(data: dict[str, Any], depth_key: str = DROP_HEIGHT_KEY) -> SceneConfig:
    """Validate a plain dict (as read from YAML) into a :class:`SceneConfig`, filling the discretization
    keys it does not set from its ``fidelity`` preset.

    Parameters
    ----------
    data : dict
    depth_key : str
        The key a drop height that does not fit the water depth is reported on (see
        :func:`moor_env.scene_geometry.check_scene_consistency`).

    Raises
    ------
    ConfigError
        On the first invalid key, naming it with its value and allowed range.
    """
    try:
        scene = SceneConfig.model_validate(apply_fidelity(copy.deepcopy(data)))
        fitted = fit_fidelity(scene, data)
        if fitted is not None:
            scene = SceneConfig.model_validate(fitted)
    except ValidationError as exc:
        raise drop_fit_bound_error(SceneConfig, exc, data) or validation_error(SceneConfig, exc, data) from None
    check_scene_consistency(scene, depth_key)
    return scene


def scene_dict(scene: str | Path) -> dict[str, Any]:
    """The raw mapping of a bundled scene or YAML file with library entries expanded (for editing)."""
    path = _resolve_scene_path(scene)
    try:
        with open(path, encoding="utf-8") as fh:
            data = yaml.safe_load(fh)
    except yaml.YAMLError as exc:
        raise ConfigError("scene", str(path), "a YAML file without syntax errors", yaml_error_text(exc)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError("scene", str(path), "a readable UTF-8 YAML file", str(exc)) from None
    if not isinstance(data, dict):
        raise ConfigError("scene", str(path), "a YAML mapping", f"the file holds a {type(data).__name__}")
    return _resolve_library(copy.deepcopy(data))


def load_scene(scene: str | Path, overrides: dict[str, Any] | None = None) -> SceneConfig:
    """Load a bundled scene by name (``gjoa-500``) or a YAML path, apply overrides and validate.

    Parameters
    ----------
    scene : str or Path
        Bundled scene name or path to a YAML file.
    overrides : dict, optional
        ``{key: value}`` where key is a shortcut from :data:`SET_SHORTCUTS` (``water_depth_m``...) or a
        dotted path into the scene (``environment.seabed.friction_coefficient``). A drop height that does not
        fit the water depth is reported on the water depth when the overrides set it and not the drop height.

    Returns
    -------
    SceneConfig
        The validated, frozen scene.
    """
    data = scene_dict(scene)
    overrides = overrides or {}
    for key, value in overrides.items():
        _apply_override(data, key, value)
    paths = {SET_SHORTCUTS.get(k, k) for k in overrides}
    depth_key = WATER_DEPTH_KEY if WATER_DEPTH_KEY in paths and DROP_HEIGHT_KEY not in paths else DROP_HEIGHT_KEY
    return scene_from_dict(data, depth_key)

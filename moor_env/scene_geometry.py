"""Quantities derived from a validated scene: hanging lengths, the drop height and water depth the scene allows,
the mooring line's slack, submerged line weights, and the cross-field checks that use them.

:mod:`moor_env.config` validates each key on its own range; this module answers whether the keys fit together
(:func:`check_scene_consistency`, called by :func:`moor_env.config.scene_from_dict`).
"""

from __future__ import annotations

import copy
import math
import typing
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from moor_env.config_text import BOUND_ERRORS
from moor_env.errors import ConfigError

if TYPE_CHECKING:
    from moor_env.scene_schema import MaterialConfig, SceneConfig

DROP_HEIGHT_KEY = "installation.drop_height_m"
WATER_DEPTH_KEY = "environment.water_depth_m"
CLEARANCE_M = 1.0  # least distance between the top of the hanging vertical chain and the fairlead depth [m]


def field_bound(model: object, name: str, bound: str) -> float:
    """The ``bound`` (``gt``, ``ge``, ``lt`` or ``le``) of field ``name`` of a config model or object."""
    cls = model if isinstance(model, type) else type(model)
    for item in cls.model_fields[name].metadata:
        if hasattr(item, bound):
            return float(getattr(item, bound))
    raise KeyError(f"{cls.__name__}.{name} has no {bound} bound")


def hanging_length_m(scene: SceneConfig) -> float:
    """Length hanging below the release point before the release: anchor plus vertical chain (if simulated) [m]."""
    inst, anchor = scene.installation, scene.anchor
    assert inst is not None and anchor is not None
    return anchor.length_m + (inst.vertical_chain_length_m if inst.components.vertical_chain else 0.0)


def max_drop_height_m(scene: SceneConfig) -> float:
    """Largest drop height that leaves the anchor, the vertical chain and ``CLEARANCE_M`` below the fairleads [m]."""
    inst = scene.installation
    assert inst is not None
    return scene.environment.water_depth_m - inst.fairlead_depth_m - hanging_length_m(scene) - CLEARANCE_M


def min_water_depth_m(scene: SceneConfig) -> float:
    """Smallest water depth that fits the scene's drop height, anchor, vertical chain and ``CLEARANCE_M`` [m]."""
    inst = scene.installation
    assert inst is not None
    return inst.drop_height_m + inst.fairlead_depth_m + hanging_length_m(scene) + CLEARANCE_M


def drop_fit_error(scene: SceneConfig, key: str = DROP_HEIGHT_KEY) -> ConfigError:
    """The error for a drop height that does not fit the water depth, naming ``key`` (the drop height or the water
    depth) with its value and the range the rest of the scene allows."""
    inst, anchor = scene.installation, scene.anchor
    assert inst is not None and anchor is not None
    parts = f"anchor {anchor.length_m:g} m"
    if inst.components.vertical_chain:
        parts += f", vertical chain {inst.vertical_chain_length_m:g} m"
    if inst.fairlead_depth_m:
        parts += f", fairlead depth {inst.fairlead_depth_m:g} m"
    if key == WATER_DEPTH_KEY:
        low = min_water_depth_m(scene)
        high = field_bound(scene.environment, "water_depth_m", "le")
        return ConfigError(key, scene.environment.water_depth_m, f">= {low:.1f} and <= {high:g} m",
                           f"drop height {inst.drop_height_m:g} m, {parts} and {CLEARANCE_M:g} m clearance "
                           "must fit in the water depth")
    high = min(max_drop_height_m(scene), field_bound(inst, "drop_height_m", "le"))
    low = field_bound(inst, "drop_height_m", "gt")
    allowed = (f"> {low:g} and <= {high:.1f} m" if high > low
               else "none: the water is too shallow for any drop")
    return ConfigError(key, inst.drop_height_m, allowed,
                       f"water depth {scene.environment.water_depth_m:g} m minus {parts} "
                       f"and {CLEARANCE_M:g} m clearance")


def drop_fit_bound_error(root: type[SceneConfig], exc: ValidationError, data: dict[str, Any]) -> ConfigError | None:
    """A drop height or water depth outside its own range (the first error of ``exc``, unless there is an unknown
    key), reported with the range the rest of the scene allows: the scene is validated with a placeholder in its
    place. None for other errors, or when the rest of the scene is invalid too."""
    errors = exc.errors()
    err = errors[0]
    key = ".".join(str(p) for p in err["loc"])
    if (key not in (DROP_HEIGHT_KEY, WATER_DEPTH_KEY) or err["type"] not in BOUND_ERRORS
            or any(e["type"] == "extra_forbidden" for e in errors)):
        return None
    section, name = key.split(".")
    placeholder = copy.deepcopy(data)
    model = root.model_fields[section].annotation
    model = next(a for a in typing.get_args(model) if a is not type(None)) if typing.get_args(model) else model
    # a value inside the field's own range: the drop height just above its minimum, the water depth at its maximum
    placeholder[section][name] = (field_bound(model, name, "gt") + 1.0 if key == DROP_HEIGHT_KEY
                                  else field_bound(model, name, "le"))
    try:
        scene = root.model_validate(placeholder)
        if scene.installation is None or scene.anchor is None:
            return None
        part = getattr(scene, section).model_copy(update={name: float(err["input"])})
    except (ValidationError, ConfigError, TypeError, ValueError):
        return None
    return drop_fit_error(scene.model_copy(update={section: part}), key)


def mooring_line_slack(scene: SceneConfig, tip_height_m: float) -> tuple[float, float] | None:
    """Slack of the mooring line (free length from the release point to the second vessel minus its chord) [m]
    and the chord's angle from the vertical [deg], with the anchor tip ``tip_height_m`` above the seabed, the
    vertical chain hanging straight above the anchor and the spacing and line length as at the release (after
    ``release_time_s`` of spacing move and payout); None without a mooring line.
    """
    inst = scene.installation
    if inst is None or scene.anchor is None or not inst.components.mooring_line:
        return None
    return line_slack_geometry(
        water_depth_m=scene.environment.water_depth_m, tip_height_m=tip_height_m,
        anchor_length_m=scene.anchor.length_m, vertical_chain_m=inst.vertical_chain_length_m,
        fairlead_depth_m=inst.fairlead_depth_m,
        spacing_m=inst.vessel_spacing_m + inst.spacing_rate_m_s * inst.release_time_s,
        line_length_m=inst.mooring_line_length_m + inst.payout_rate_m_s * inst.release_time_s)


def line_slack_geometry(water_depth_m: float, tip_height_m: float, anchor_length_m: float, vertical_chain_m: float,
                        fairlead_depth_m: float, spacing_m: float, line_length_m: float) -> tuple[float, float]:
    """:func:`mooring_line_slack` from plain numbers: ``line_length_m`` includes the vertical chain, ``spacing_m``
    is the horizontal distance from the release point to the second vessel's fairlead [m]."""
    z_release = -(water_depth_m - tip_height_m - anchor_length_m - vertical_chain_m)
    rise = -(z_release + fairlead_depth_m)
    slack = line_length_m - vertical_chain_m - math.hypot(spacing_m, rise)
    return slack, math.degrees(math.atan2(spacing_m, rise))


def submerged_mass_per_length(scene: SceneConfig, material: str) -> float:
    """Submerged mass per metre of a material [kg/m] (given, or from its diameter)."""
    return _submerged(scene, scene.materials[material])


def _submerged(scene: SceneConfig, mat: MaterialConfig) -> float:
    if mat.submerged_mass_per_length_kg_m is not None:
        return mat.submerged_mass_per_length_kg_m
    return mat.mass_per_length_kg_m - scene.environment.water_density_kg_m3 * math.pi / 4.0 * mat.diameter_m**2


def check_scene_consistency(scene: SceneConfig, depth_key: str = DROP_HEIGHT_KEY) -> None:
    """Cross-field physical checks that single-field ranges cannot express.

    Parameters
    ----------
    scene : SceneConfig
    depth_key : str
        The key a drop height that does not fit the water depth is reported on: ``installation.drop_height_m``
        or ``environment.water_depth_m`` (the one the user changed).

    Raises
    ------
    ConfigError
        Naming the key whose value makes the scene impossible.
    """
    depth = scene.environment.water_depth_m
    for name, mat in scene.materials.items():
        if mat.submerged_mass_per_length_kg_m is None:
            displaced = scene.environment.water_density_kg_m3 * math.pi / 4.0 * mat.diameter_m**2
            if displaced >= mat.mass_per_length_kg_m:
                raise ConfigError(f"materials.{name}.diameter_m", mat.diameter_m,
                                  "a value that leaves the line heavier than water",
                                  "give submerged_mass_per_length_kg_m for buoyant lines")
    if scene.kind == "catenary_line":
        line = scene.catenary_line
        assert line is not None
        for i, (mat, length) in enumerate(line.segments):
            if mat not in scene.materials:
                raise ConfigError(f"catenary_line.segments[{i}]", mat, "one of " + ", ".join(scene.materials))
            if length <= 0:
                raise ConfigError(f"catenary_line.segments[{i}]", length, "> 0 m")
        if line.fairlead_depth_m >= depth:
            raise ConfigError("catenary_line.fairlead_depth_m", line.fairlead_depth_m, f"< water_depth_m = {depth}")
        return
    inst = scene.installation
    anchor = scene.anchor
    assert inst is not None and anchor is not None
    comp = inst.components
    for key in ("wire_material", "chain_material", "fibre_material"):
        name = getattr(inst, key)
        needed = {"wire_material": comp.wire, "chain_material": comp.vertical_chain or comp.mooring_line,
                  "fibre_material": comp.mooring_line}[key]
        if needed and name not in scene.materials:
            raise ConfigError(f"installation.{key}", name, "one of " + ", ".join(scene.materials))
    if comp.mooring_line and not comp.vertical_chain:
        raise ConfigError("installation.components.mooring_line", True, "false when vertical_chain is false",
                          "the mooring line hangs from the release point at the top of the vertical chain")
    if comp.wire and not comp.vertical_chain:
        raise ConfigError("installation.components.wire", True, "false when vertical_chain is false")
    if inst.drop_height_m > max_drop_height_m(scene):
        raise drop_fit_error(scene, depth_key)
    hang = hanging_length_m(scene)
    if comp.mooring_line:
        if inst.bottom_chain_length_m < inst.vertical_chain_length_m:
            raise ConfigError("installation.vertical_chain_length_m", inst.vertical_chain_length_m,
                              f"<= bottom_chain_length_m = {inst.bottom_chain_length_m} m")
        if inst.mooring_line_length_m < inst.bottom_chain_length_m:
            raise ConfigError("installation.mooring_line_length_m", inst.mooring_line_length_m,
                              f">= bottom_chain_length_m = {inst.bottom_chain_length_m} m")
        z_release = -(depth - inst.drop_height_m - hang)
        chord = math.hypot(inst.vessel_spacing_m, z_release + inst.fairlead_depth_m)
        free_length = inst.mooring_line_length_m - inst.vertical_chain_length_m
        if free_length < chord * 1.001:
            raise ConfigError("installation.mooring_line_length_m", inst.mooring_line_length_m,
                              f">= {chord + inst.vertical_chain_length_m:.1f} m",
                              "the line from the release point must reach the second vessel")
    if comp.wire:
        wire = scene.materials[inst.wire_material]
        wsub = _submerged(scene, wire)
        g = scene.environment.gravity_m_s2
        anchor_mass = anchor.mass_scale * sum(s.mass_per_length_kg_m * s.length_m for s in anchor.sections)
        hang_load = anchor_mass * g + (depth - inst.drop_height_m) * wsub * g
        if hang_load >= wire.mbl_n:
            raise ConfigError(f"materials.{inst.wire_material}.mbl_n", wire.mbl_n, f"> {hang_load:.3g} N",
                              "the wire cannot carry the anchor and its own weight")

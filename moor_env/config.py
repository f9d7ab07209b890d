"""Scene configuration: YAML -> validated, frozen config objects.

This is the first stage of the one-way pipeline
``configs/scenes/*.yaml -> SceneConfig (here) -> Model (compile.py) -> numba kernels -> results``.

All values are SI. A key whose unit is not obvious carries it as a suffix (``_m``, ``_s``, ``_kg``,
``_n``, ``_deg``, ``_kg_m`` for kg per metre, ``_pa_m`` for Pa per metre). Dimensionless coefficients have
no suffix. Validation is done by pydantic (chosen over hand-written checks because it gives strict
unknown-key rejection, type coercion rules and range constraints with a machine-readable error location);
:func:`load_scene` turns its errors into one-line :class:`~moor_env.errors.ConfigError` messages that
name the key, its value and the allowed range (:mod:`moor_env.config_text`, with the nearest known key for an
unknown one). Quantities derived from a validated scene and the cross-field checks live in
:mod:`moor_env.scene_geometry`; the discretization presets and their fit to the geometry in :mod:`moor_env.fidelity`.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

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

CONFIG_DIR = FIDELITY_PATH.parent
SCENE_DIR = CONFIG_DIR / "scenes"
LIBRARY_PATH = CONFIG_DIR / "library.yaml"


class _Strict(BaseModel):
    """Base: unknown keys are errors, objects are immutable, no silent float->int coercion."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=False)


class CurrentConfig(_Strict):
    """Steady current: piecewise-linear speed over depth, one horizontal direction.

    Below the deepest profile point the speed falls linearly to 0 at the seabed.
    """

    profile: tuple[tuple[float, float], ...] = Field(
        default=((0.0, 0.8), (300.0, 0.6), (400.0, 0.2)),
        description="(depth below surface [m], speed [m/s]) pairs, depths increasing",
    )
    direction_deg: float = Field(0.0, ge=-360.0, le=360.0,
                                 description="direction the current flows towards, from +x towards +y [deg]")
    scale: float = Field(1.0, ge=0.0, le=5.0, description="multiplies every profile speed; 0 switches current off")

    @model_validator(mode="after")
    def _check_profile(self) -> CurrentConfig:
        depths = [p[0] for p in self.profile]
        if any(d < 0 for d in depths) or any(b <= a for a, b in zip(depths, depths[1:], strict=False)):
            raise ValueError("profile depths must be >= 0 and strictly increasing")
        if any(abs(p[1]) > 5.0 for p in self.profile):
            raise ValueError("profile speeds must be within -5 .. 5 m/s")
        return self


class SeabedConfig(_Strict):
    """Flat seabed at ``-water_depth_m``: vertical spring-damper contact and Coulomb friction for line nodes."""

    stiffness_pa_m: float = Field(3.0e6, gt=0.0, le=1.0e9,
                                  description="contact pressure per metre of penetration [Pa/m]")
    damping_pa_s_m: float = Field(3.0e5, ge=0.0, le=1.0e8,
                                  description="contact pressure per m/s of penetration rate [Pa s/m]")
    friction_coefficient: float = Field(0.5, ge=0.0, le=2.0)
    friction_velocity_m_s: float = Field(0.05, gt=0.0, le=1.0,
                                         description="sliding speed below which friction is ramped linearly [m/s]")


class SeaStateConfig(_Strict):
    """Irregular sea (JONSWAP) driving the vessel tops through a simple motion transfer (see physics.vessels)."""

    hs_m: float = Field(0.0, ge=0.0, le=16.0, description="significant wave height [m]; 0 is calm")
    tp_s: float = Field(10.0, ge=3.0, le=25.0, description="spectral peak period [s]")
    gamma: float = Field(3.3, ge=1.0, le=10.0, description="JONSWAP peak enhancement")
    n_components: int = Field(64, ge=8, le=1024)
    seed: int = Field(0, ge=0, description="seed of the random component phases")
    vessel_natural_period_s: float = Field(9.0, ge=2.0, le=40.0,
                                           description="heave/surge natural period of the vessels [s]")
    vessel_damping_ratio: float = Field(0.3, gt=0.0, le=2.0)


class EnvironmentConfig(_Strict):
    """Water, seabed, current and sea state."""

    water_depth_m: float = Field(..., gt=10.0, le=6000.0)
    gravity_m_s2: float = Field(9.81, gt=0.0, le=20.0)
    water_density_kg_m3: float = Field(1025.0, ge=900.0, le=1100.0)
    current: CurrentConfig = CurrentConfig(scale=0.0)
    seabed: SeabedConfig = SeabedConfig()
    sea_state: SeaStateConfig = SeaStateConfig()


class MaterialConfig(_Strict):
    """A line material (chain, wire, fibre rope).

    Reference areas: normal drag on ``diameter_m`` per metre; tangential drag on the wetted perimeter
    ``pi * diameter_m`` per metre (RIFLEX and MoorDyn convention; the seed's chain value 0.0069 uses it);
    added mass on ``pi/4 * diameter_m**2`` per metre.
    """

    diameter_m: float = Field(..., gt=0.0, le=2.0,
                              description="hydrodynamic diameter (drag and added-mass reference) [m]")
    mass_per_length_kg_m: float = Field(..., gt=0.0, le=5000.0, description="mass in air per unstretched metre [kg/m]")
    submerged_mass_per_length_kg_m: float | None = Field(
        None, description="mass in air minus displaced water per metre [kg/m]; default: from diameter_m"
    )
    ea_n: float = Field(..., gt=0.0, le=1.0e12, description="axial stiffness [N]")
    axial_damping_ratio: float = Field(
        0.3, ge=0.0, le=2.0, description="internal axial damping as a ratio of critical for one segment's axial mode")
    cd_normal: float = Field(..., ge=0.0, le=20.0)
    cd_tangential: float = Field(..., ge=0.0, le=5.0, description="tangential drag, wetted-perimeter (pi*D) reference")
    ca_normal: float = Field(1.0, ge=0.0, le=5.0)
    ca_tangential: float = Field(0.0, ge=0.0, le=5.0)
    mbl_n: float = Field(..., gt=0.0, le=1.0e9, description="minimum breaking load [N]")

    @model_validator(mode="after")
    def _check_submerged(self) -> MaterialConfig:
        if self.submerged_mass_per_length_kg_m is not None and not (
            -self.mass_per_length_kg_m < self.submerged_mass_per_length_kg_m <= self.mass_per_length_kg_m
        ):
            raise ValueError("submerged_mass_per_length_kg_m must lie in (-mass_per_length_kg_m, mass_per_length_kg_m]")
        return self


class AnchorSectionConfig(_Strict):
    """One axial section of the anchor, listed from the tip backwards."""

    length_m: float = Field(..., gt=0.0, le=50.0)
    outer_diameter_m: float = Field(..., gt=0.0, le=10.0,
                                    description="outer diameter: buoyancy, drag and added-mass reference [m]")
    flooded_diameter_m: float = Field(0.0, ge=0.0, le=10.0, description="diameter of the open, water-filled bore [m]")
    mass_per_length_kg_m: float = Field(..., gt=0.0, le=1.0e5, description="structural mass per metre [kg/m]")
    cd_normal: float = Field(..., ge=0.0, le=50.0, description="normal drag on outer_diameter_m (fins: much larger)")
    ca_normal: float = Field(1.0, ge=0.0, le=10.0)
    cd_tangential: float = Field(0.0, ge=0.0, le=10.0,
                                 description="skin friction on the wetted perimeter pi*outer_diameter_m")

    @model_validator(mode="after")
    def _check_bore(self) -> AnchorSectionConfig:
        if self.flooded_diameter_m >= self.outer_diameter_m:
            raise ValueError("flooded_diameter_m must be smaller than outer_diameter_m")
        return self


class AnchorConfig(_Strict):
    """Rigid dart anchor: sections from tip to back tip, end pressure drag on the end faces."""

    sections: tuple[AnchorSectionConfig, ...] = Field(..., min_length=1)
    tip_drag_coefficient: float = Field(0.387, ge=0.0, le=5.0,
                                        description="pressure drag on the tip face, reference pi/4*D^2")
    back_drag_coefficient: float = Field(0.043, ge=0.0, le=5.0,
                                         description="pressure drag on the back face, reference pi/4*D^2")
    mass_scale: float = Field(1.0, ge=0.5, le=1.5,
                              description="multiplies the structural mass (fabrication tolerance studies)")
    quadrature_points: int = Field(26, ge=4, le=400,
                                   description="points along the body for distributed drag and added mass")

    @property
    def length_m(self) -> float:
        """Total length of the anchor [m]."""
        return sum(s.length_m for s in self.sections)


class ReleaseUnitConfig(_Strict):
    """Release unit at the wire's lower end (stays on the wire after release)."""

    mass_kg: float = Field(1780.0, ge=0.0, le=1.0e5)
    volume_m3: float = Field(0.672, ge=0.0, le=100.0)
    drag_area_m2: float = Field(0.98, ge=0.0, le=100.0,
                                description="Cd times projected area, applied isotropically [m^2]")
    added_mass_coefficient: float = Field(1.0, ge=0.0, le=5.0, description="added mass as a multiple of rho*volume_m3")
    max_release_load_n: float = Field(273.0e3 * 9.81, gt=0.0, description="rated release load [N] (273 t)")


class ComponentsConfig(_Strict):
    """Which parts of the installation the scene simulates."""

    wire: bool = True
    vertical_chain: bool = True
    mooring_line: bool = True
    keep_wire_after_release: bool = False


class InstallationConfig(_Strict):
    """Geometry of a two-vessel dart-anchor installation (seed 003, Model 1/2), all in the x-z plane.

    The installation vessel (wire top) is at x = 0, the second vessel (mooring-line top) at
    x = ``vessel_spacing_m``. The bottom chain (``bottom_chain_length_m``) starts at the anchor's back tip:
    its first ``vertical_chain_length_m`` hang vertically to the release point, the rest forms the loop, then
    fibre up to the second vessel; ``mooring_line_length_m`` counts all of it. The wire length is solved so
    that the anchor tip hangs ``drop_height_m`` above the seabed at equilibrium.
    """

    vessel_spacing_m: float = Field(50.0, ge=0.0, le=3000.0)
    drop_height_m: float = Field(68.5, gt=1.0, le=500.0, description="anchor tip above the seabed at release [m]")
    vertical_chain_length_m: float = Field(50.0, ge=2.0, le=500.0)
    bottom_chain_length_m: float = Field(150.0, ge=2.0, le=2000.0)
    mooring_line_length_m: float = Field(540.0, gt=0.0, le=10000.0)
    wire_material: str = "wire_76"
    chain_material: str = "chain_142"
    fibre_material: str = "polyester_254"
    fairlead_depth_m: float = Field(0.0, ge=0.0, le=50.0, description="depth of both vessel hang-off points [m]")
    components: ComponentsConfig = ComponentsConfig()
    release_time_s: float = Field(0.0, ge=0.0, le=3600.0,
                                  description="pre-release simulated time before the release [s]")
    spacing_rate_m_s: float = Field(0.0, ge=-2.0, le=2.0,
                                    description="second vessel's horizontal speed before release [m/s]")
    payout_rate_m_s: float = Field(0.0, ge=-1.0, le=1.0,
                                   description="mooring-line winch payout rate before release [m/s]")


class CatenaryLineConfig(_Strict):
    """A single mooring line from a seabed anchor point to a fairlead (statics validation scenes)."""

    segments: tuple[tuple[str, float], ...] = Field(..., min_length=1,
                                                    description="(material, length [m]) from the anchor up")
    anchor_x_m: float = 0.0
    fairlead_x_m: float = Field(..., description="horizontal position of the fairlead [m]")
    fairlead_depth_m: float = Field(0.0, ge=0.0)


class DiscretizationConfig(_Strict):
    """Resolution and time stepping (the fidelity knobs)."""

    vertical_chain_segment_m: float = Field(1.0, ge=0.05, le=50.0)
    loop_chain_segment_m: float = Field(1.0, ge=0.05, le=50.0)
    fibre_segment_m: float = Field(5.0, ge=0.1, le=200.0)
    wire_segment_m: float = Field(10.0, ge=0.1, le=500.0)
    catenary_segment_m: float = Field(2.0, ge=0.1, le=200.0)
    integrator: Literal["symplectic_euler", "rk2", "implicit_euler"] = "symplectic_euler"
    dt_s: float | None = Field(None, gt=0.0, le=1.0,
                               description="time step [s]; None derives it from the stability limit")
    dt_safety: float = Field(0.9, gt=0.0, le=1.0,
                             description="fraction of the stability limit used when dt_s is derived")
    fall_integrator: Literal["symplectic_euler", "rk2", "implicit_euler"] | None = Field(
        None, description="integrator of the fall after the release, at dt_safety times its own limit on the mesh "
        "of the fall (e.g. symplectic_euler after an implicit pre-release phase: the explicit reference fall); "
        "None: integrator")
    fit_to_geometry: bool = Field(
        True, description="fit a preset's tight_line resolution to the scene's release geometry when it is loaded; "
        "the envs set false and choose it themselves, at the reset and again for the fall at the release")
    line_anchor_contact: Literal["auto", "on", "off"] = Field(
        "auto", description="contact between the lines and the anchor's body; auto: where the chain can catch up "
        "with the falling anchor (moor_env.contact_model)")
    contact_stiffness_scale: float = Field(
        1.0, gt=0.0, le=10.0, description="multiplies the line-anchor contact stiffness (convergence studies)")


class SimulationConfig(_Strict):
    """Run control."""

    max_fall_time_s: float = Field(30.0, gt=0.0, le=600.0,
                                   description="fall time after which a run without touchdown stops [s]")
    record_interval_s: float = Field(0.02, gt=0.0, le=10.0)
    snapshot_interval_s: float = Field(0.5, gt=0.0, le=60.0)
    speed_limit_m_s: float = Field(300.0, gt=0.0, description="any node faster than this is treated as a blow-up [m/s]")
    strain_limit: float = Field(0.5, gt=0.0, description="any segment strained more than this is treated as a blow-up")


class SceneConfig(_Strict):
    """A complete scene: environment, materials, anchor and what to simulate."""

    name: str
    description: str = ""
    kind: Literal["dart_installation", "catenary_line"] = "dart_installation"
    fidelity: Literal["fast", "default", "accurate", "custom"] = Field(
        "default", description="discretization preset from configs/fidelity.yaml; explicit discretization keys win")
    environment: EnvironmentConfig
    materials: dict[str, MaterialConfig]
    anchor: AnchorConfig | None = None
    release_unit: ReleaseUnitConfig = ReleaseUnitConfig()
    installation: InstallationConfig | None = None
    catenary_line: CatenaryLineConfig | None = None
    discretization: DiscretizationConfig = DiscretizationConfig()
    simulation: SimulationConfig = SimulationConfig()

    @model_validator(mode="after")
    def _check_kind(self) -> SceneConfig:
        if self.kind == "dart_installation" and (self.anchor is None or self.installation is None):
            raise ValueError("a dart_installation scene needs 'anchor' and 'installation'")
        if self.kind == "catenary_line" and self.catenary_line is None:
            raise ValueError("a catenary_line scene needs 'catenary_line'")
        return self


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

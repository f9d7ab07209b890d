"""Environment settings: ``configs/envs/*.yaml`` -> validated, frozen :class:`EnvConfig`.

An env config names the scene it builds on (``scene: gjoa-500``), the fidelity overrides applied to every
episode (a mapping of scene overrides, which a fidelity preset can stand in for), the control
limits, the scenario distribution drawn at every reset, the reward weights, the one-shot plan settings
(AnchorPlan-v0's ``plan``; AnchorPlan-v1's ``site``, ``levers`` and ``success``, and AnchorRelease-v1's
``positioning`` besides them, :mod:`moor_env.envs.plan_config`),
the equilibria kept in memory and rendering. Every value is SI with the unit in the key name (``_m``, ``_s``, ``_m_s``,
``_n``, ``_deg``); ``_over_depth`` values are fractions of the water depth.

Validation is pydantic (as :mod:`moor_env.config`); an invalid value raises
:class:`~moor_env.errors.ConfigError` naming the dotted key, the value and the allowed range, e.g.
``control.interval_s=-1.0: allowed > 0.0``.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import Field, ValidationError, model_validator

from moor_env.config import CONFIG_DIR
from moor_env.envs.distributions import (
    SCENARIO_RANGES,
    SEED_FIELD,
    SEED_HIGH,
    Choice,
    Distribution,
    Uniform,
    _KeyedError,
    _Strict,
    check_ranges,
)
from moor_env.envs.plan_config import LeverConfig, PositioningConfig, SiteConfig, SuccessConfig
from moor_env.errors import ConfigError

ENV_CONFIG_DIR = CONFIG_DIR / "envs"
DEFAULT_ENV_CONFIG = "anchor-release"

# The fields that shape the hanging geometry (ranges or constants in the bundled configs); a drawn scenario
# without an equilibrium is drawn again.
GEOMETRY_FIELDS: tuple[str, ...] = ("water_depth_m", "vessel_spacing_over_depth", "mooring_line_length_over_depth",
                                    "vertical_chain_length_m", "drop_height_m")
SCENARIO_FIELDS: tuple[str, ...] = (*SCENARIO_RANGES, SEED_FIELD)


class ScenarioConfig(_Strict):
    """Distribution of the scenario drawn at each reset (a number is a constant; ``{uniform: [low, high]}``;
    ``{choice: [...]}``). ``sea_state_seed: draw`` draws the wave phases' seed from the env's generator.

    The geometry (:data:`GEOMETRY_FIELDS`) is drawn from continuous ranges: every reset solves its own hanging
    equilibrium (:mod:`moor_env.envs.equilibria`), and a drawn geometry without one is drawn again
    (:func:`moor_env.envs.scenario.start_episode`).
    """

    water_depth_m: Distribution = Uniform(uniform=(400.0, 600.0))
    vessel_spacing_over_depth: Distribution = Uniform(uniform=(0.1, 0.3))
    mooring_line_length_over_depth: Distribution = Uniform(uniform=(1.04, 1.08))
    vertical_chain_length_m: Distribution = 50.0
    drop_height_m: Distribution = 68.5
    current_scale: Distribution = Choice(choice=(0.0, 0.5, 1.0))
    current_direction_deg: Distribution = Choice(choice=(0.0, 180.0))
    sea_state_hs_m: Distribution = Uniform(uniform=(0.0, 3.0))
    sea_state_tp_s: Distribution = Uniform(uniform=(7.0, 13.0))
    sea_state_seed: Literal["draw"] | int = "draw"
    chain_cd_tangential: Distribution = Uniform(uniform=(0.0052, 0.0086))
    anchor_mass_scale: Distribution = Uniform(uniform=(0.98, 1.02))

    @model_validator(mode="after")
    def _ranges(self) -> ScenarioConfig:
        check_ranges(self, SCENARIO_RANGES, "scenario")
        if isinstance(self.sea_state_seed, int) and not 0 <= self.sea_state_seed <= SEED_HIGH:
            raise _KeyedError("scenario.sea_state_seed", self.sea_state_seed, f"'draw' or 0 .. {SEED_HIGH}")
        return self


class ControlConfig(_Strict):
    """Control interval, time limit and the physical limits the normalised actions are scaled to."""

    interval_s: float = Field(1.0, gt=0.0, le=10.0, description="simulated time per env step before release [s]")
    max_pre_release_s: float = Field(60.0, gt=0.0, le=3600.0,
                                     description="pre-release time after which the episode is truncated [s]")
    warmup_s: float = Field(20.0, ge=0.0, le=600.0,
                            description="waves ramped in and simulated before the first observation when Hs > 0 [s]")
    pre_release_dt_s: float | None = Field(
        None, gt=0.0, le=0.5,
        description="integration step before the release (warm-up, control, hold) with the implicit integrator "
                    "[s]; each advance takes the whole number of equal steps nearest below it, never finer than "
                    "the scene's step; null: the scene's step. The fall uses the scene's step (or that of "
                    "discretization.fall_integrator, where set)")
    pre_release_dt_calm_s: float | None = Field(
        None, gt=0.0, le=0.5,
        description="pre_release_dt_s for a sea without waves (Hs 0), where the loop moves only with the "
                    "vessels and the winch [s]; null: pre_release_dt_s")
    pre_release_travel_segments: float | None = Field(
        0.5, gt=0.0, le=10.0,
        description="a pre-release step coarser than the scene's is shortened (never below the scene's step) so "
                    "that the fastest free line node, at its speed at the start of the advance, travels at most "
                    "this many lengths of the shortest segment in one step: a loop swinging through several "
                    "segment lengths per step turns its segments beyond what the linearised implicit step follows "
                    "(docs/pre-release-step.md); null: no such limit")
    fall_dt_scale: float = Field(
        1.0, gt=0.0, le=1.0,
        description="the fall's integration step as a fraction of the scene's (or fall integrator's) step; a "
                    "segment that goes from slack to taut while it turns within one implicit step can end it "
                    "stretched, and a smaller step lowers that peak in the tension limits (docs/mbl-exceedance.md)")
    spacing_rate_max_m_s: float = Field(0.5, gt=0.0, le=2.0,
                                        description="second vessel's largest horizontal speed (DP slow move) [m/s]")
    spacing_accel_max_m_s2: float = Field(0.05, gt=0.0, le=1.0,
                                          description="largest change of that speed per second [m/s^2]")
    spacing_min_m: float = Field(20.0, ge=0.0, le=3000.0, description="vessels never closer than this [m]")
    spacing_max_over_depth: float = Field(0.5, gt=0.0, le=2.0,
                                          description="vessels never farther apart than this times the depth")
    payout_rate_max_m_s: float = Field(0.3, gt=0.0, le=1.0, description="winch pay-out speed at action +1 [m/s]")
    haul_rate_max_m_s: float = Field(0.3, gt=0.0, le=1.0, description="winch haul-in speed at action -1 [m/s]")
    line_length_min_over_depth: float = Field(0.9, gt=0.0, le=5.0,
                                              description="mooring line (total) never shorter than this x depth")
    line_length_max_over_depth: float = Field(1.3, gt=0.0, le=5.0,
                                              description="mooring line never paid out beyond this times the depth")

    @model_validator(mode="after")
    def _limits(self) -> ControlConfig:
        if self.line_length_max_over_depth <= self.line_length_min_over_depth:
            raise _KeyedError("control.line_length_max_over_depth", self.line_length_max_over_depth,
                              f"> line_length_min_over_depth = {self.line_length_min_over_depth}")
        return self


class RewardConfig(_Strict):
    """Weights and thresholds of the reward terms (see the env docstring's Rewards section)."""

    required_speed_m_s: float = Field(24.0, gt=0.0, le=100.0,
                                      description="full speed score at or above this touchdown speed [m/s]")
    speed_falloff_m_s: float = Field(8.0, gt=0.0, le=100.0,
                                     description="speed score falls linearly to 0 this far below it [m/s]")
    speed_weight: float = Field(1.0, ge=0.0)
    tilt_criterion_deg: float = Field(5.0, gt=0.0, le=90.0,
                                      description="tilt score is 0 here (DPA criterion 5 deg) [deg]")
    tilt_weight: float = Field(1.0, ge=0.0)
    tilt_excess_penalty: float = Field(2.0, ge=0.0, description="subtracted when the tilt exceeds the criterion")
    offset_weight: float = Field(0.25, ge=0.0, description="landing-offset term weight (0 switches it off)")
    offset_tolerance_m: float = Field(2.0, gt=0.0,
                                      description="offset at which the offset term is 0 (Gjoa: 2 m radius) [m]")
    tension_penalty: float = Field(1.0, ge=0.0, description="once per episode when any line's tension exceeds its MBL")
    release_unit_penalty: float = Field(1.0, ge=0.0,
                                        description="once when the wire load exceeds the release unit's rating")
    fibre_seabed_penalty: float = Field(1.0, ge=0.0, description="once per episode when fibre rope touches the seabed")
    fibre_clearance_m: float = Field(0.5, ge=0.0,
                                     description="a fibre node lower than this above the seabed touches it [m]")
    chain_pile_penalty: float = Field(1.0, ge=0.0,
                                      description="at touchdown, times min(1, (chain on seabed - allowance) / scale)")
    chain_pile_allowance_m: float = Field(5.0, ge=0.0,
                                          description="chain on the seabed at touchdown not penalised [m]")
    chain_pile_scale_m: float = Field(20.0, gt=0.0,
                                      description="excess chain on the seabed giving the full penalty [m]")
    time_cost_per_s: float = Field(0.002, ge=0.0, description="cost per simulated second before release [1/s]")
    truncation_penalty: float = Field(3.0, ge=0.0,
                                      description="when the pre-release time limit is reached without release")
    failure_penalty: float = Field(3.0, ge=0.0, description="when the simulation diverges")
    no_touchdown_penalty: float = Field(3.0, ge=0.0,
                                        description="no touchdown within the scene's max_fall_time_s")


class PlanConfig(_Strict):
    """AnchorPlan-v0: hold the commanded rates for ``positioning_s``, then release at a delay after the next
    up-crossing of the installation vessel's heave."""

    positioning_s: float = Field(40.0, ge=0.0, le=3600.0, description="duration of the spacing/payout change [s]")
    release_window_periods: float = Field(1.0, gt=0.0, le=10.0,
                                          description="release delay range after the heave up-crossing [Tp]")
    calm_release_window_s: float = Field(10.0, ge=0.0, le=600.0,
                                         description="release delay range in calm water (no wave phase) [s]")


class StaticsConfig(_Strict):
    """Hanging equilibria, solved at every reset (see :mod:`moor_env.envs.equilibria`)."""

    memory_entries: int = Field(64, ge=0, le=100000,
                                description="equilibria (with their compiled models) kept in memory for a geometry "
                                            "drawn again; 0 keeps none")
    method: Literal["auto", "newton"] = Field(
        "newton", description="solve_statics' method: newton refuses a geometry Newton's method does not solve at "
                              "once (StaticsNotConverged, the reset draws again); auto falls back to the slow "
                              "relaxation solver there (seconds)")


class RenderConfig(_Strict):
    """Frames of ``render_mode='rgb_array'``."""

    width_px: int = Field(720, ge=160, le=4000)
    height_px: int = Field(480, ge=120, le=4000)
    fall_frame_interval_s: float = Field(0.25, gt=0.0, le=10.0, description="frames recorded during the fall [s]")
    render_fps: int = Field(4, ge=1, le=120)


class EnvConfig(_Strict):
    """Everything an env needs besides the seed."""

    name: str = "anchor-release"
    description: str = ""
    scene: str = Field("gjoa-500", description="bundled scene name or YAML path the scenarios modify")
    fidelity: dict[str, Any] = Field(default_factory=dict, description="scene overrides for resolution/time step")
    scene_overrides: dict[str, Any] = Field(default_factory=dict, description="further fixed scene overrides")
    control: ControlConfig = ControlConfig()
    scenario: ScenarioConfig = ScenarioConfig()
    reward: RewardConfig = RewardConfig()
    plan: PlanConfig = PlanConfig()
    site: SiteConfig = SiteConfig()
    levers: LeverConfig = LeverConfig()
    success: SuccessConfig = SuccessConfig()
    positioning: PositioningConfig = PositioningConfig()
    statics: StaticsConfig = StaticsConfig()
    render: RenderConfig = RenderConfig()


def _to_config_error(exc: ValidationError) -> ConfigError:
    err = exc.errors()[0]
    original = (err.get("ctx") or {}).get("error")
    if isinstance(original, _KeyedError):
        return ConfigError(original.key, original.value, original.allowed)
    loc = ".".join(str(p) for p in err["loc"])
    # a union (number | choice | uniform) reports one error per member; name the field and the forms
    for tag in (".float", ".Choice", ".Uniform"):
        if tag in loc:
            loc = loc.split(tag)[0]
            return ConfigError(loc, err.get("input"), "a number, {choice: [v, ...]} or {uniform: [low, high]}")
    ctx = err.get("ctx") or {}
    bounds = [f"{sym} {ctx[k]}" for k, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")) if k in ctx]
    if bounds:
        allowed = " and ".join(bounds)
    elif err["type"] == "extra_forbidden":
        allowed = "a known key (this one does not exist)"
    elif err["type"] == "missing":
        allowed = "a value (required)"
    elif "expected" in ctx:
        allowed = f"one of {ctx['expected']}"
    else:
        allowed = err.get("msg", "a valid value")
    value = err.get("input")
    if isinstance(value, dict):
        value = "{...}"
    return ConfigError(loc or "env config", value, allowed)


def env_config_names() -> list[str]:
    """Bundled env configs (``configs/envs/*.yaml`` without the suffix)."""
    return sorted(p.stem for p in ENV_CONFIG_DIR.glob("*.yaml"))


def _read(config: str | Path) -> dict[str, Any]:
    path = Path(config)
    if path.suffix not in (".yaml", ".yml"):
        path = ENV_CONFIG_DIR / f"{config}.yaml"
        if not path.is_file():
            raise ConfigError("config", str(config), "one of " + ", ".join(env_config_names()) + " or a YAML path")
    elif not path.is_file():
        raise ConfigError("config", str(config), "an existing YAML file", "file not found")
    with open(path, encoding="utf-8") as fh:
        data = yaml.safe_load(fh) or {}
    if not isinstance(data, dict):
        raise ConfigError("config", str(path), "a YAML mapping")
    return data


def _set_dotted(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``a.b.c`` in a nested dict; ``fidelity.X`` / ``scene_overrides.X`` take the rest as one scene key."""
    parts = key.split(".")
    if parts[0] in ("fidelity", "scene_overrides") and len(parts) > 1:
        data.setdefault(parts[0], {})
        data[parts[0]] = {**(data[parts[0]] or {}), ".".join(parts[1:]): value}
        return
    node = data
    for part in parts[:-1]:
        nxt = node.get(part)
        if nxt is None:
            nxt = node[part] = {}
        if not isinstance(nxt, dict):
            raise ConfigError(key, value, "a key inside a section", f"'{part}' is not a section")
        node = nxt
    node[parts[-1]] = value


def load_env_config(config: str | Path | dict[str, Any] | EnvConfig = DEFAULT_ENV_CONFIG,
                    overrides: dict[str, Any] | None = None) -> EnvConfig:
    """Load and validate an env config.

    Parameters
    ----------
    config : str, Path, dict or EnvConfig
        Bundled name (``anchor-release``), YAML path, a mapping as read from YAML, or a config.
    overrides : dict, optional
        ``{dotted key: value}``, e.g. ``{"control.interval_s": 0.5, "scenario.sea_state_hs_m": 0.0,
        "fidelity": {...}}``. A ``fidelity`` or ``scene_overrides`` value replaces the whole mapping;
        ``fidelity.<scene key>`` sets one entry.

    Raises
    ------
    ConfigError
        Naming the first invalid key, its value and the allowed range.
    """
    if isinstance(config, EnvConfig):
        data = config.model_dump()
    elif isinstance(config, dict):
        data = copy.deepcopy(config)
    else:
        data = _read(config)
    for key, value in (overrides or {}).items():
        _set_dotted(data, key, value)
    try:
        cfg = EnvConfig.model_validate(data)
    except ValidationError as exc:
        raise _to_config_error(exc) from None
    except _KeyedError as exc:  # pragma: no cover - pydantic wraps it, kept for safety
        raise ConfigError(exc.key, exc.value, exc.allowed) from None
    return cfg

"""AnchorPlan-v1's sections of the env config: the site drawn at every reset (``site``), the ranges of the crew's
levers (``levers``) and the success criterion with the margins of its smooth surrogate (``success``); and
AnchorRelease-v1's rates and steps of moving those levers (``positioning``).

The values and their sources are argued in the docstring of :class:`moor_env.envs.AnchorPlanV1Env`; the bundled
``configs/envs/anchor-plan.yaml`` states them with a comment each. Validation as in :mod:`moor_env.envs.config`:
a bad value raises a :class:`~moor_env.errors.ConfigError` naming the dotted key, e.g.
``levers.drop_height_m=[30.0, 250.0]: allowed within 2.0 .. 200.0``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from moor_env.envs.distributions import (
    SCENARIO_RANGES,
    SEED_FIELD,
    SEED_HIGH,
    Distribution,
    Uniform,
    _KeyedError,
    _Strict,
    check_ranges,
)

# the site's fields shared with AnchorRelease-v0's scenario keep its ranges; the soil's are AnchorPlan-v1's own
SITE_RANGES: dict[str, tuple[float, float]] = {
    **{name: SCENARIO_RANGES[name] for name in ("water_depth_m", "current_scale", "current_direction_deg",
                                                "sea_state_hs_m", "sea_state_tp_s", "chain_cd_tangential",
                                                "anchor_mass_scale")},
    "soil_fraction": (-0.5, 1.5),
    "penetration_ratio": (0.5, 1.5),
}
SITE_FIELDS: tuple[str, ...] = (*SITE_RANGES, SEED_FIELD)
# wave seeds a training draw takes; held-out sets take theirs from above it (agents.scenarios)
TRAINING_SEED_HIGH = 2**30 - 1


class SiteConfig(_Strict):
    """Distribution of the site drawn at each AnchorPlan-v1 reset (a number is a constant; ``{uniform: [low,
    high]}``; ``{choice: [...]}``); ``sea_state_seed: draw`` draws the wave seed in ``0 .. 2**30 - 1``.

    ``soil_fraction`` places the seabed between the two Gjoa sites (0: ``gjoa-1``, 1: ``gjoa-2``, geometrically in
    the embedment resistance, :func:`moor_env.envs.soil.between`); ``penetration_ratio`` is the required tip
    penetration over the penetration that soil gives at 25 m/s (the Gjoa design speed).
    """

    water_depth_m: Distribution = Uniform(uniform=(350.0, 650.0))
    current_scale: Distribution = Uniform(uniform=(0.0, 1.2))
    current_direction_deg: Distribution = Uniform(uniform=(-180.0, 180.0))
    sea_state_hs_m: Distribution = Uniform(uniform=(0.0, 3.5))
    sea_state_tp_s: Distribution = Uniform(uniform=(7.0, 14.0))
    chain_cd_tangential: Distribution = Uniform(uniform=(0.0052, 0.0086))
    anchor_mass_scale: Distribution = Uniform(uniform=(0.97, 1.03))
    soil_fraction: Distribution = Uniform(uniform=(0.0, 1.0))
    penetration_ratio: Distribution = Uniform(uniform=(0.92, 1.06))
    sea_state_seed: Literal["draw"] | int = "draw"

    @model_validator(mode="after")
    def _ranges(self) -> SiteConfig:
        check_ranges(self, SITE_RANGES, "site")
        if isinstance(self.sea_state_seed, int) and not 0 <= self.sea_state_seed <= SEED_HIGH:
            raise _KeyedError("site.sea_state_seed", self.sea_state_seed, f"'draw' or 0 .. {SEED_HIGH}")
        return self


LEVER_RANGE_FIELDS = ("vessel_spacing_over_depth", "mooring_line_length_over_depth", "vertical_chain_length_m",
                      "drop_height_m")


class LeverConfig(_Strict):
    """Ranges ``[low, high]`` the normalised action maps onto (action -1: low, +1: high)."""

    vessel_spacing_over_depth: tuple[float, float] = (0.0, 0.5)
    mooring_line_length_over_depth: tuple[float, float] = (0.95, 1.25)
    vertical_chain_length_m: tuple[float, float] = (5.0, 60.0)
    drop_height_m: tuple[float, float] = (30.0, 120.0)
    release_window_periods: float = Field(1.0, gt=0.0, le=10.0,
                                          description="release phase range after the heave up-crossing [Tp]")
    wire_clearance_m: float = Field(50.0, ge=0.0, le=1000.0,
                                    description="the release node at least this far below the installation "
                                                "vessel's fairlead; the drop height's upper end is cut to keep it [m]")

    @model_validator(mode="after")
    def _ranges(self) -> LeverConfig:
        for name in LEVER_RANGE_FIELDS:
            lo, hi = getattr(self, name)
            a, b = SCENARIO_RANGES[name]
            if not (a <= lo < hi <= b):
                raise _KeyedError(f"levers.{name}", [lo, hi], f"[low, high] with {a} <= low < high <= {b}")
        return self


class SuccessConfig(_Strict):
    """Success of an AnchorPlan-v1 installation and the scales of its normalised margins (the reward)."""

    tilt_max_deg: float = Field(2.0, gt=0.0, le=90.0, description="success below this tilt (Gjoa: < 2 deg) [deg]")
    offset_max_m: float = Field(2.0, gt=0.0, le=100.0,
                                description="success within this horizontal offset (Gjoa: 2 m radius) [m]")
    chain_pile_allowance_m: float = Field(5.0, ge=0.0, description="chain on the seabed at touchdown allowed [m]")
    speed_scale_m_s: float = Field(1.0, gt=0.0, description="speed margin of one unit [m/s]")
    tilt_scale_deg: float = Field(0.5, gt=0.0, description="tilt margin of one unit [deg]")
    offset_scale_m: float = Field(0.5, gt=0.0, description="offset margin of one unit [m]")
    load_scale: float = Field(0.1, gt=0.0, description="line and release-unit margin of one unit [fraction of the "
                                                        "limit]")
    fibre_scale_m: float = Field(2.0, gt=0.0, description="fibre clearance margin of one unit [m]")
    chain_pile_scale_m: float = Field(5.0, gt=0.0, description="chain-pile margin of one unit [m]")
    softmin_temperature: float = Field(0.25, gt=0.0, le=10.0,
                                       description="temperature of the soft minimum over the margins [margin units]")


class PositioningConfig(_Strict):
    """AnchorRelease-v1's positioning: the length of one step and the crew's actuator rates (each lever moves at
    most its rate times the step per step), the step limit and the release decision (a release command above
    ``release_threshold`` on ``release_confirm_steps`` consecutive steps)."""

    step_s: float = Field(60.0, ge=1.0, le=600.0, description="crew time of one positioning step [s]")
    vessel_speed_max_m_s: float = Field(0.5, gt=0.0, le=5.0, description="second vessel's DP speed [m/s]")
    winch_rate_max_m_s: float = Field(0.3, gt=0.0, le=5.0, description="mooring-line winch, out or in [m/s]")
    chain_rate_max_m_s: float = Field(0.2, gt=0.0, le=5.0,
                                      description="chain paid through the release unit, out or in [m/s]")
    wire_rate_max_m_s: float = Field(0.5, gt=0.0, le=5.0, description="installation vessel's wire winch [m/s]")
    max_steps: int = Field(16, ge=2, le=1000, description="steps before the release is forced")
    release_threshold: float = Field(0.5, ge=0.0, lt=1.0, description="release command that counts as 'release'")
    release_confirm_steps: int = Field(2, ge=1, le=10, description="consecutive steps the command must hold")
    max_start_draws: int = Field(50, ge=1, le=10000, description="start geometries drawn before the reset fails")

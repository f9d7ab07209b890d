"""The building blocks of the env configs: strict frozen sections, keyed validation errors, the scenario
distributions (a constant, ``{uniform: [low, high]}`` or ``{choice: [...]}``) and the allowed range of every
scenario field (:data:`SCENARIO_RANGES`) with their check.

Shared by :mod:`moor_env.envs.config` (the config as a whole, AnchorRelease-v0's scenario) and
:mod:`moor_env.envs.plan_config` (AnchorPlan-v1's site, levers and success criterion).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from moor_env.errors import ConfigError

# Allowed range of every scenario field (inclusive): checked for constants, every choice and both uniform bounds.
SCENARIO_RANGES: dict[str, tuple[float, float]] = {
    "water_depth_m": (100.0, 3000.0),
    "vessel_spacing_over_depth": (0.0, 1.0),
    "mooring_line_length_over_depth": (0.5, 3.0),
    "vertical_chain_length_m": (2.0, 150.0),
    "drop_height_m": (2.0, 200.0),
    "current_scale": (0.0, 3.0),
    "current_direction_deg": (-360.0, 360.0),
    "sea_state_hs_m": (0.0, 8.0),
    "sea_state_tp_s": (3.0, 25.0),
    "chain_cd_tangential": (0.0, 5.0),
    "anchor_mass_scale": (0.5, 1.5),
}
SEED_HIGH = 2**31 - 1  # wave seeds lie in 0 .. SEED_HIGH
SEED_FIELD = "sea_state_seed"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class _KeyedError(ValueError):
    """Raised inside validators to carry a full dotted key to the ConfigError."""

    def __init__(self, key: str, value: object, allowed: str) -> None:
        super().__init__(f"{key}={value!r}: allowed {allowed}")
        self.key, self.value, self.allowed = key, value, allowed


class Choice(_Strict):
    """Draw one of the listed values with equal probability."""

    choice: tuple[float, ...] = Field(..., min_length=1)


class Uniform(_Strict):
    """Draw uniformly between the two bounds (``[low, high]``)."""

    uniform: tuple[float, float]

    @model_validator(mode="after")
    def _ordered(self) -> Uniform:
        if not self.uniform[0] <= self.uniform[1]:
            raise ValueError("uniform bounds must be [low, high] with low <= high")
        return self


Distribution = float | Choice | Uniform


def _values(dist: Distribution) -> tuple[float, ...]:
    if isinstance(dist, Choice):
        return dist.choice
    if isinstance(dist, Uniform):
        return dist.uniform
    return (float(dist),)


def check_ranges(section: BaseModel, ranges: dict[str, tuple[float, float]], prefix: str) -> None:
    """Every value of every distribution field of ``section`` named in ``ranges`` within its inclusive range
    (constants, each choice and both uniform bounds), else a :class:`_KeyedError` naming ``prefix.field``."""
    for name, (lo, hi) in ranges.items():
        dist = getattr(section, name)
        for i, v in enumerate(_values(dist)):
            if not (lo <= v <= hi) or not math.isfinite(v):
                where = name + ({Choice: f".choice[{i}]", Uniform: f".uniform[{i}]"}.get(type(dist), ""))
                raise _KeyedError(f"{prefix}.{where}", v, f"{lo} .. {hi}")


def draw_value(dist: Distribution, rng: np.random.Generator) -> float:
    """One draw of a distribution (a constant costs no draw)."""
    if isinstance(dist, Choice):
        return float(dist.choice[int(rng.integers(len(dist.choice)))])
    if isinstance(dist, Uniform):
        lo, hi = dist.uniform
        return float(rng.uniform(lo, hi))
    return float(dist)


def draw_fields(section: BaseModel, ranges: dict[str, tuple[float, float]], rng: np.random.Generator,
                options: dict[str, Any] | None, seed_high: int, kind: str) -> dict[str, Any]:
    """Draw every field of ``ranges`` from ``section`` in order, then :data:`SEED_FIELD` (``draw``: in
    ``0 .. seed_high``); ``options`` fixes fields by name.

    Every field is drawn even when ``options`` fixes it, so that fixing one field leaves the draws of the others
    unchanged for a given generator state.

    Raises
    ------
    ConfigError
        For an unknown option key (naming the ``kind`` of field) or a value outside the field's range (a seed:
        ``0 .. SEED_HIGH``).
    """
    fields = (*ranges, SEED_FIELD)
    out: dict[str, Any] = {name: draw_value(getattr(section, name), rng) for name in ranges}
    seed = getattr(section, SEED_FIELD)
    out[SEED_FIELD] = int(rng.integers(0, seed_high + 1)) if seed == "draw" else int(seed)
    for key, value in (options or {}).items():
        if key not in fields:
            raise ConfigError(f"options.{key}", value, f"a {kind} field: " + ", ".join(fields))
        if key == SEED_FIELD:
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= SEED_HIGH:
                raise ConfigError(f"options.{key}", value, f"an integer 0 .. {SEED_HIGH}")
            out[key] = int(value)
            continue
        lo, hi = ranges[key]
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ConfigError(f"options.{key}", value, "a number") from None
        if not (lo <= v <= hi):
            raise ConfigError(f"options.{key}", value, f"{lo} .. {hi}")
        out[key] = v
    return out

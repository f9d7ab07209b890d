"""AnchorPlan-v1's site: the conditions the crew finds and cannot choose, drawn at every reset, and what the agent
sees of them.

A site is a mapping of every field of :data:`~moor_env.envs.plan_config.SITE_FIELDS` (depth, current scale and
direction, sea state and its seed, chain drag, anchor mass scale, soil and required penetration), drawn from the
config's ``site`` section (:func:`draw_site`; ``reset(options=...)`` fixes fields by name). :func:`site_measures`
adds what follows from it: the soil's embedment resistance, the required tip penetration and the touchdown speed
that reaches it (:mod:`moor_env.envs.soil`). :func:`site_observation` is the agent's view (:data:`SITE_OBS_SPEC`):
everything but the wave seed and the chain's tangential drag, which stay hidden (seed 003, Landhaug 2015,
*Dynamic Simulation of Dart Anchor Installation*, chapter 8, names that drag the dominant uncertainty of the fall).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from moor_env.envs import soil
from moor_env.envs.config import EnvConfig
from moor_env.envs.distributions import draw_fields
from moor_env.envs.plan_config import SITE_RANGES, TRAINING_SEED_HIGH

# --- observation: (name, unit, offset, scale, meaning); normalised value = (raw - offset) / scale ----------------
SITE_OBS_SPEC: tuple[tuple[str, str, float, float, str], ...] = (
    ("water_depth_m", "m", 500.0, 150.0, "water depth"),
    ("current_x", "-", 0.0, 1.0, "current scale x cos(direction): the seed 003 profile's multiple (1: 0.8 m/s at "
                                 "the surface) towards the second vessel"),
    ("current_y", "-", 0.0, 1.0, "current scale x sin(direction), across the line of the vessels"),
    ("sea_state_hs_m", "m", 1.75, 1.75, "significant wave height (forecast)"),
    ("sea_state_tp_s", "s", 10.5, 3.5, "peak period (forecast)"),
    ("anchor_mass_scale", "-", 1.0, 0.03, "anchor mass over the nominal mass (the anchor as weighed)"),
    ("soil_resistance_kj_m3", "kJ/m^3", 3.3, 1.0, "the soil's embedment resistance R (moor_env.envs.soil)"),
    ("required_penetration_m", "m", 23.0, 3.0, "required tip penetration"),
    ("required_speed_m_s", "m/s", 24.5, 3.0, "touchdown speed that reaches it (moor_env.envs.soil)"),
)
SITE_OBS_NAMES: tuple[str, ...] = tuple(row[0] for row in SITE_OBS_SPEC)
SITE_OBS_OFFSET = np.array([row[2] for row in SITE_OBS_SPEC])
SITE_OBS_SCALE = np.array([row[3] for row in SITE_OBS_SPEC])
SITE_OBS_CLIP = 5.0
DESIGN_SPEED_M_S = soil.GJOA_PREDICTION_SPEED_M_S


def draw_site(cfg: EnvConfig, rng: np.random.Generator, options: dict[str, Any] | None = None) -> dict[str, Any]:
    """Draw a site from the config's ``site`` section; ``options`` fixes fields.

    Every field is drawn in the fixed order of :data:`SITE_FIELDS` even when ``options`` fixes it, so that fixing
    one field leaves the others' draws unchanged for a given seed (:func:`~moor_env.envs.distributions.draw_fields`).
    A drawn wave seed lies in ``0 .. TRAINING_SEED_HIGH``; ``options`` may set any seed up to ``2**31 - 1``
    (held-out sets use the upper half).

    Raises
    ------
    ConfigError
        For an unknown option key or a value outside the field's range.
    """
    return draw_fields(cfg.site, SITE_RANGES, rng, options, TRAINING_SEED_HIGH, "site")


def soil_resistance_j_m3(soil_fraction: float) -> float:
    """Embedment resistance [J/m^3] ``soil_fraction`` of the way from the ``gjoa-1`` to the ``gjoa-2`` site."""
    return float(soil.between(soil.SOILS["gjoa-1"], soil.SOILS["gjoa-2"], soil_fraction))


def site_measures(site: dict[str, Any], anchor_mass_kg: float) -> dict[str, float]:
    """What follows from a site for an anchor of nominal structural mass ``anchor_mass_kg``: the soil's
    embedment resistance, the required tip penetration (``penetration_ratio`` times the penetration the nominal
    anchor reaches at 25 m/s in that soil) and the touchdown speed at which the site's anchor (``anchor_mass_scale``
    times the nominal mass) reaches it [SI units]."""
    r = soil_resistance_j_m3(site["soil_fraction"])
    design = soil.tip_penetration_m(DESIGN_SPEED_M_S, r, anchor_mass_kg)
    depth_m = float(site["penetration_ratio"]) * design
    mass = float(site["anchor_mass_scale"]) * anchor_mass_kg
    return {"soil_resistance_j_m3": r, "required_penetration_m": depth_m,
            "required_speed_m_s": float(soil.required_speed_m_s(depth_m, r, mass))}


def raw_site_observation(site: dict[str, Any], measures: dict[str, float]) -> list[float]:
    """The site's observation in physical units (:data:`SITE_OBS_SPEC`)."""
    direction = math.radians(site["current_direction_deg"])
    return [site["water_depth_m"], site["current_scale"] * math.cos(direction),
            site["current_scale"] * math.sin(direction), site["sea_state_hs_m"], site["sea_state_tp_s"],
            site["anchor_mass_scale"], measures["soil_resistance_j_m3"] / 1e3, measures["required_penetration_m"],
            measures["required_speed_m_s"]]


def site_observation(site: dict[str, Any], measures: dict[str, float]) -> np.ndarray:
    """The normalised float32 observation of a site, clipped to +-SITE_OBS_CLIP."""
    raw = np.array(raw_site_observation(site, measures))
    return np.clip((raw - SITE_OBS_OFFSET) / SITE_OBS_SCALE, -SITE_OBS_CLIP, SITE_OBS_CLIP).astype(np.float32)


def site_from_observation(obs: np.ndarray, name: str) -> float:
    """One entry of a site observation in physical units (exact unless it was clipped)."""
    i = SITE_OBS_NAMES.index(name)
    return float(obs[i]) * SITE_OBS_SCALE[i] + SITE_OBS_OFFSET[i]

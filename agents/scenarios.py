"""Held-out evaluation scenarios: fixed, seeded, and outside the values the training distribution uses.

Training draws scenarios from the env config (``configs/envs/anchor-release.yaml``): depth 400/500/600 m,
spacing 0.1/0.2/0.3 x depth, line length 1.04/1.08 x depth, vertical chain 50 m, current scale 0/0.5/1,
Hs uniform 0-3 m, Tp uniform 7-13 s, anchor mass scale 0.98/1/1.02. The held-out set (:data:`HELD_OUT_VALUES`)
uses depths, spacings, line lengths, vertical chains, currents and mass scales **between or beyond** those
choices (e.g. 450/550/650 m, spacing 0.15/0.25/0.35), sea states partly outside the training range (Hs 3.5 m,
Tp 14 s) and wave seeds from ``[2**30, 2**31)``: training draws its wave seeds from ``[0, 2**31)``, so a
held-out wave train repeats a training one with probability about (training episodes) / 2**30. The chain
tangential drag stays a nuisance drawn from the training range (the crew does not know it).

A scenario is a mapping ``{"id": str, "seed": int, "options": {field: value}}``; ``options`` fixes every
field of ``moor_env.envs.SCENARIO_FIELDS`` through ``env.reset(seed=seed, options=options)``.

**AnchorPlan-v1** (:func:`held_out_sites`): sites drawn from the env config's own continuous ``site``
distribution with a generator training never uses (seeded by :data:`HELD_OUT_SITE_SEED`), each with a wave seed
from ``[2**30, 2**31)``, where training draws its wave seeds from ``[0, 2**30)``
(:data:`moor_env.envs.plan_config.TRAINING_SEED_HIGH`): the same distribution, never the same draw. ``options``
fixes every field of ``moor_env.envs.plan_config.SITE_FIELDS``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from agents.io import write_text_atomic
from moor_env.envs import SCENARIO_FIELDS, load_env_config
from moor_env.envs.plan_config import SITE_FIELDS, TRAINING_SEED_HIGH
from moor_env.envs.site import draw_site
from moor_env.errors import ConfigError

HELD_OUT_SEED = 20250605
HELD_OUT_SITE_SEED = 17_2026_0917
# a second held-out set, drawn the same way: it confirms a result after design choices were made looking at the first
CONFIRMATION_SITE_SEED = HELD_OUT_SITE_SEED + 1
DEFAULT_COUNT = 24
DEFAULT_SITE_COUNT = 500
PLAN_V1_CONFIG = "anchor-plan"
HELD_OUT_VALUES: dict[str, tuple[float, ...]] = {
    "water_depth_m": (450.0, 550.0, 650.0),
    "vessel_spacing_over_depth": (0.15, 0.25, 0.35),
    "mooring_line_length_over_depth": (1.06,),
    "vertical_chain_length_m": (40.0, 50.0),
    "drop_height_m": (68.5,),
    "current_scale": (0.25, 0.75),
    "current_direction_deg": (0.0, 180.0),
    "sea_state_hs_m": (0.5, 1.5, 2.5, 3.5),
    "sea_state_tp_s": (8.0, 11.0, 14.0),
    "anchor_mass_scale": (0.99, 1.01),
}
GEOMETRY_FIELDS = ("water_depth_m", "vessel_spacing_over_depth", "mooring_line_length_over_depth",
                   "vertical_chain_length_m", "drop_height_m", "current_scale", "current_direction_deg",
                   "anchor_mass_scale")
SEA_STATES_PER_GEOMETRY = 3
CHAIN_CD_RANGE = (0.0052, 0.0086)
WAVE_SEED_RANGE = (2**30, 2**31 - 1)


def _balanced(rng: np.random.Generator, values: tuple[float, ...], n: int) -> np.ndarray:
    """``n`` entries cycling through ``values`` in a seeded random order (each value about n / len times)."""
    return rng.permutation(np.tile(np.asarray(values), -(-n // len(values)))[:n])


def held_out_scenarios(n: int = DEFAULT_COUNT, seed: int = HELD_OUT_SEED) -> list[dict[str, Any]]:
    """The fixed held-out set: ``n`` scenarios drawn with ``seed`` from :data:`HELD_OUT_VALUES`.

    Scenarios come in groups of :data:`SEA_STATES_PER_GEOMETRY` sharing one geometry (depth, spacing, line, vertical
    chain, current, anchor mass: one hanging equilibrium, a static solve of seconds to minutes) with different sea
    states and wave seeds (free). Each field cycles through its values in a seeded random order (a
    Latin-hypercube-like design), so every value appears about equally often even in small sets. The same
    ``(n, seed)`` always gives the same list; sets of different sizes are different designs.
    """
    if n < 1:
        raise ConfigError("n", n, ">= 1")
    rng = np.random.default_rng(seed)
    n_geom = -(-n // SEA_STATES_PER_GEOMETRY)
    geometry = {name: _balanced(rng, HELD_OUT_VALUES[name], n_geom) for name in GEOMETRY_FIELDS}
    sea = {name: _balanced(rng, HELD_OUT_VALUES[name], n) for name in HELD_OUT_VALUES if name not in GEOMETRY_FIELDS}
    chain_cd = rng.uniform(*CHAIN_CD_RANGE, size=n)
    wave_seeds = rng.integers(WAVE_SEED_RANGE[0], WAVE_SEED_RANGE[1] + 1, size=n)
    reset_seeds = rng.integers(0, 2**31 - 1, size=n)
    scenarios = []
    for i in range(n):
        options = {name: float(geometry[name][i // SEA_STATES_PER_GEOMETRY]) for name in GEOMETRY_FIELDS}
        options.update({name: float(column[i]) for name, column in sea.items()})
        options["chain_cd_tangential"] = round(float(chain_cd[i]), 6)
        options["sea_state_seed"] = int(wave_seeds[i])
        scenarios.append({"id": scenario_id(i, options), "seed": int(reset_seeds[i]), "options": options})
    return scenarios


def held_out_sites(n: int = DEFAULT_SITE_COUNT, seed: int = HELD_OUT_SITE_SEED,
                   env_config: str = PLAN_V1_CONFIG) -> list[dict[str, Any]]:
    """The held-out AnchorPlan-v1 set: ``n`` sites drawn from ``env_config``'s ``site`` distribution with a
    generator seeded by ``seed``, wave seeds from the upper half of the seed range (module docstring).

    Site ``i`` depends on ``(seed, i)`` only, so a smaller set is the start of a larger one.
    """
    if n < 1:
        raise ConfigError("n", n, ">= 1")
    cfg = load_env_config(env_config)
    scenarios = []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        options = draw_site(cfg, rng)
        options["sea_state_seed"] = int(rng.integers(TRAINING_SEED_HIGH + 1, 2**31))
        scenarios.append({"id": site_id(i, options), "seed": int(rng.integers(0, 2**31 - 1)), "options": options})
    return scenarios


def site_id(index: int, options: dict[str, Any]) -> str:
    """A short readable name of a site: index, depth, current scale, Hs and required penetration ratio."""
    return (f"{index:04d}-h{options['water_depth_m']:.0f}-c{options['current_scale']:.2f}"
            f"-hs{options['sea_state_hs_m']:.1f}-p{options['penetration_ratio']:.3f}")


def scenario_id(index: int, options: dict[str, Any]) -> str:
    """A short readable name: index, depth, spacing/depth, current scale and Hs."""
    return (f"{index:03d}-h{options['water_depth_m']:.0f}-s{options['vessel_spacing_over_depth']:.2f}"
            f"-c{options['current_scale']:.2f}-hs{options['sea_state_hs_m']:.1f}")


def validate_scenarios(scenarios: Any, source: str = "scenarios") -> list[dict[str, Any]]:
    """Check a list of scenario mappings; raises ``ConfigError`` naming the entry and key."""
    if not isinstance(scenarios, list) or not scenarios:
        raise ConfigError(source, type(scenarios).__name__, "a non-empty list of {id, seed, options}")
    out = []
    for i, sc in enumerate(scenarios):
        where = f"{source}[{i}]"
        if not isinstance(sc, dict):
            raise ConfigError(where, sc, "a mapping with keys id, seed, options")
        extra = set(sc) - {"id", "seed", "options"}
        if extra:
            raise ConfigError(f"{where}.{sorted(extra)[0]}", sc[sorted(extra)[0]], "one of id, seed, options")
        seed = sc.get("seed", i)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(f"{where}.seed", seed, "an integer >= 0")
        options = sc.get("options", {})
        if not isinstance(options, dict):
            raise ConfigError(f"{where}.options", options, "a mapping of scenario fields")
        for key in options:
            if key not in SCENARIO_FIELDS and key not in SITE_FIELDS:
                fields = ", ".join(dict.fromkeys(SCENARIO_FIELDS + SITE_FIELDS))
                raise ConfigError(f"{where}.options.{key}", options[key], f"a scenario or site field: {fields}")
        out.append({"id": str(sc.get("id", f"{i:03d}")), "seed": seed, "options": dict(options)})
    return out


def load_scenarios(path: str | Path) -> list[dict[str, Any]]:
    """Read a scenario list from JSON or YAML (``[{id, seed, options}, ...]`` or ``{scenarios: [...]}``)."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError("scenarios", str(path), "an existing JSON or YAML file")
    with open(path, encoding="utf-8") as fh:
        data = json.load(fh) if path.suffix == ".json" else yaml.safe_load(fh)
    if isinstance(data, dict) and "scenarios" in data:
        data = data["scenarios"]
    return validate_scenarios(data, str(path))


def save_scenarios(scenarios: list[dict[str, Any]], path: str | Path) -> None:
    """Write a scenario list as JSON (atomically)."""
    write_text_atomic(path, json.dumps({"scenarios": scenarios}, indent=1))

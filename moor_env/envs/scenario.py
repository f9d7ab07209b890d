"""The scenario distribution: what varies from one episode to the next, and how a scenario is drawn.

A scenario is a mapping of every field of :data:`~moor_env.envs.config.SCENARIO_FIELDS` to a value (depth,
spacing, line length, current, sea state and its seed, chain drag, anchor mass scale). The config's ``scenario``
section gives each field a constant, a uniform range or a choice; the bundled configs draw the geometry from
ranges, every draw a new geometry whose equilibrium the reset solves. ``reset(options=...)`` fixes fields by
name.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from moor_env.envs.config import GEOMETRY_FIELDS, SCENARIO_FIELDS, SCENARIO_RANGES, SEED_FIELD, SEED_HIGH, EnvConfig
from moor_env.envs.distributions import Choice, Uniform, _values, draw_fields
from moor_env.errors import ConfigError, StaticsNotConverged

MAX_SCENARIO_DRAWS = 10


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


def draw_scenario(cfg: EnvConfig, rng: np.random.Generator, options: dict[str, Any] | None = None) -> dict[str, Any]:
    """Draw a scenario from the config's distribution; ``options`` fixes fields.

    Every field is drawn (in the fixed order of :data:`SCENARIO_FIELDS`) even when ``options`` fixes it, so that
    fixing one field leaves the draws of the others unchanged for a given seed
    (:func:`~moor_env.envs.distributions.draw_fields`).

    Raises
    ------
    ConfigError
        For an unknown option key or a value outside the field's range.
    """
    return draw_fields(cfg.scenario, SCENARIO_RANGES, rng, options, SEED_HIGH, "scenario")


def start_episode(core, rng: np.random.Generator, options: dict[str, Any] | None):
    """Draw a scenario (``options`` fix fields) and start the episode slot ``core``
    (:class:`~moor_env.envs.core.InstallationCore`) on it; the warm-up advance to integrate, if any.

    A drawn scenario whose scene is invalid or has no equilibrium (:class:`~moor_env.errors.ConfigError`, e.g.
    :class:`~moor_env.errors.NoEquilibrium`, or :class:`~moor_env.errors.StaticsNotConverged`) is drawn again,
    up to ``MAX_SCENARIO_DRAWS`` draws in all; ``core.redraws`` counts the draws refused (the reset info's
    ``scenario_redraws``). With ``options`` given the error is raised at once.

    Raises
    ------
    ConfigError
        Naming the config's scenario keys when no draw gave an equilibrium, with the last refusal as the reason;
        the solver's or scene's own error when ``options`` are given.
    """
    refusals: list[str] = []
    for attempt in range(MAX_SCENARIO_DRAWS):
        scenario = draw_scenario(core.cfg, rng, options)
        try:
            core.redraws = attempt
            return core.start(scenario)
        except (ConfigError, StaticsNotConverged) as exc:
            if options:
                raise
            refusals.append(str(exc))
    drawn = {name: getattr(core.cfg.scenario, name) for name in GEOMETRY_FIELDS}
    drawn = {name: list(_values(dist)) for name, dist in drawn.items() if isinstance(dist, (Choice, Uniform))}
    raise ConfigError(", ".join(f"scenario.{name}" for name in drawn) or "scenario", drawn,
                      "ranges in which the scene has a static equilibrium",
                      f"{MAX_SCENARIO_DRAWS} draws in a row refused; the last: {refusals[-1]}")

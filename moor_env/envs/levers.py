"""AnchorPlan-v1's levers: the normalised action, the absolute targets it sets, and the scenario they make.

An action is five numbers in [-1, 1] (:data:`LEVER_NAMES`); each maps linearly onto its range in the config's
``levers`` section (-1: the lower end, +1: the upper end): vessel spacing over depth, mooring-line length over
depth (the payout), vertical chain length, drop height and the release phase in heave periods after the
installation vessel's heave up-crossing. The drop height's upper end is cut where the release node would come
closer than ``levers.wire_clearance_m`` to the installation vessel's fairlead (:func:`drop_height_max_m`).
:func:`lever_targets` and :func:`lever_action` are inverse to each other within the ranges.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from moor_env.envs.config import SCENARIO_FIELDS
from moor_env.envs.plan_config import LeverConfig

LEVER_NAMES: tuple[str, ...] = ("vessel_spacing", "mooring_line_payout", "vertical_chain", "drop_height",
                                "release_phase")
# the targets of the levers, in the order of LEVER_NAMES, by their scenario (or plan) name
TARGET_NAMES: tuple[str, ...] = ("vessel_spacing_over_depth", "mooring_line_length_over_depth",
                                 "vertical_chain_length_m", "drop_height_m", "release_phase")


def drop_height_max_m(levers: LeverConfig, depth_m: float, vertical_chain_m: float, anchor_length_m: float,
                      fairlead_depth_m: float) -> float:
    """Highest drop height the scene allows [m]: the range's upper end, cut so that the release node (the
    anchor's length and the vertical chain above the tip) stays ``levers.wire_clearance_m`` below the fairlead; never
    below the range's lower end."""
    lo, hi = levers.drop_height_m
    room = depth_m - fairlead_depth_m - levers.wire_clearance_m - anchor_length_m - vertical_chain_m
    return float(max(lo, min(hi, room)))


def _ranges(levers: LeverConfig, drop_max_m: float) -> list[tuple[float, float]]:
    return [levers.vessel_spacing_over_depth, levers.mooring_line_length_over_depth, levers.vertical_chain_length_m,
            (levers.drop_height_m[0], drop_max_m), (0.0, levers.release_window_periods)]


def lever_targets(action: np.ndarray, depth_m: float, levers: LeverConfig, anchor_length_m: float,
                  fairlead_depth_m: float) -> dict[str, float]:
    """The absolute targets of an action (clipped to [-1, 1]; NaN counts as 0) at a site of depth ``depth_m``:
    :data:`TARGET_NAMES` with ``drop_height_max_m`` beside them."""
    a = np.clip(np.nan_to_num(np.asarray(action, dtype=np.float64).reshape(len(LEVER_NAMES))), -1.0, 1.0)
    chain_lo, chain_hi = levers.vertical_chain_length_m
    chain = chain_lo + 0.5 * (a[2] + 1.0) * (chain_hi - chain_lo)
    drop_max = drop_height_max_m(levers, depth_m, chain, anchor_length_m, fairlead_depth_m)
    targets = {name: float(lo + 0.5 * (x + 1.0) * (hi - lo))
               for name, x, (lo, hi) in zip(TARGET_NAMES, a, _ranges(levers, drop_max), strict=True)}
    targets["drop_height_max_m"] = drop_max
    return targets


def lever_action(targets: dict[str, float], depth_m: float, levers: LeverConfig, anchor_length_m: float,
                 fairlead_depth_m: float) -> np.ndarray:
    """The action (float32, within [-1, 1]) whose targets are the :data:`TARGET_NAMES` of ``targets``, each cut to
    its range."""
    drop_max = drop_height_max_m(levers, depth_m, float(np.clip(targets["vertical_chain_length_m"],
                                                                *levers.vertical_chain_length_m)),
                                 anchor_length_m, fairlead_depth_m)
    out = []
    for name, (lo, hi) in zip(TARGET_NAMES, _ranges(levers, drop_max), strict=True):
        out.append(0.0 if hi <= lo else 2.0 * (float(targets[name]) - lo) / (hi - lo) - 1.0)
    return np.clip(np.array(out), -1.0, 1.0).astype(np.float32)


def episode_scenario(site: dict[str, Any], targets: dict[str, float]) -> dict[str, Any]:
    """The AnchorRelease-v0 scenario (every field of :data:`SCENARIO_FIELDS`) of a site with the levers' targets:
    the geometry the episode's equilibrium is solved for."""
    geometry = {name: float(targets[name]) for name in TARGET_NAMES if name in SCENARIO_FIELDS}
    scenario = {name: site[name] for name in SCENARIO_FIELDS if name in site}
    scenario.update(geometry)
    missing = [name for name in SCENARIO_FIELDS if name not in scenario]
    if missing:
        raise KeyError(f"site and targets lack the scenario fields {missing}")
    return scenario

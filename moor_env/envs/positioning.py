"""AnchorRelease-v1's positioning: the crew's four geometry levers moved at their actuators' rates, one step at a
time, and the release decision.

The levers' state is physical (:data:`LEVER_STATE`): vessel spacing, mooring-line length (vertical chain
included), vertical chain and drop height. One step of ``positioning.step_s`` moves them by the action's first four
numbers in [-1, 1], each scaled by its actuator's rate limit (config ``positioning``):

* the second vessel's **DP** changes the spacing by at most ``vessel_speed_max_m_s`` x step;
* the second vessel's **winch** pays the mooring line out (+) or hauls it in (-) by at most
  ``winch_rate_max_m_s`` x step;
* the **release unit's chain stopper** pays chain from the loop into the vertical chain (+) or takes it back
  (-), at most ``chain_rate_max_m_s`` x step; the mooring line's total length does not change;
* the installation vessel's **wire winch** hauls the wire in (+) or pays it out (-) by at most
  ``wire_rate_max_m_s`` x step. The anchor hangs below the release node by the vertical chain, so its drop height
  changes by the wire hauled in minus the chain paid out (the wire lengthens, the anchor sinks).

Each lever is then kept within its range of the ``levers`` section at the site's depth (the drop height's upper
end follows the vertical chain, :func:`moor_env.envs.levers.drop_height_max_m`). The DP's acceleration limit is
left out: at its 0.05 m/s^2 (AnchorRelease-v0) the vessel reaches full speed in 10 s, 2.5 m short of the move of
a 60 s step at most.

:func:`steps_to_reach` says how many steps take every lever across its whole range; the default config reaches
any target from any start within its step limit with steps to spare for the release decision
(``tests/envs/test_release_v1.py``).
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.envs.levers import TARGET_NAMES, drop_height_max_m
from moor_env.envs.plan_config import LeverConfig, PositioningConfig

LEVER_STATE: tuple[str, ...] = ("vessel_spacing_m", "mooring_line_length_m", "vertical_chain_length_m",
                                "drop_height_m")
POSITIONING_ACTIONS: tuple[str, ...] = ("vessel_dp", "mooring_line_winch", "chain_stopper", "wire_winch",
                                        "release")


def lever_ranges(levers: LeverConfig, depth_m: float, vertical_chain_m: float, anchor_length_m: float,
                 fairlead_depth_m: float) -> list[tuple[float, float]]:
    """Range [m] of each lever of :data:`LEVER_STATE` at depth ``depth_m``; the drop height's with the vertical
    chain ``vertical_chain_m``."""
    drop_max = drop_height_max_m(levers, depth_m, vertical_chain_m, anchor_length_m, fairlead_depth_m)
    return [(levers.vessel_spacing_over_depth[0] * depth_m, levers.vessel_spacing_over_depth[1] * depth_m),
            (levers.mooring_line_length_over_depth[0] * depth_m, levers.mooring_line_length_over_depth[1] * depth_m),
            tuple(levers.vertical_chain_length_m), (levers.drop_height_m[0], drop_max)]


def move_levers(state: dict[str, float], action: np.ndarray | list[float], depth_m: float, levers: LeverConfig,
                positioning: PositioningConfig, anchor_length_m: float, fairlead_depth_m: float) -> dict[str, float]:
    """The levers after one step of the action's first four numbers (clipped to [-1, 1], NaN as 0) from
    ``state`` (module docstring)."""
    a = [0.0 if x != x else min(1.0, max(-1.0, float(x))) for x in list(action)[:4]]
    step = positioning.step_s
    chain_lo, chain_hi = levers.vertical_chain_length_m
    chain = min(chain_hi, max(chain_lo, state["vertical_chain_length_m"] + a[2] * positioning.chain_rate_max_m_s
                              * step))
    ranges = lever_ranges(levers, depth_m, chain, anchor_length_m, fairlead_depth_m)
    spacing = state["vessel_spacing_m"] + a[0] * positioning.vessel_speed_max_m_s * step
    line = state["mooring_line_length_m"] + a[1] * positioning.winch_rate_max_m_s * step
    drop = state["drop_height_m"] + a[3] * positioning.wire_rate_max_m_s * step - (chain - state[
        "vertical_chain_length_m"])
    values = (spacing, line, chain, drop)
    return {name: float(min(hi, max(lo, x))) for name, x, (lo, hi) in zip(LEVER_STATE, values, ranges, strict=True)}


def steps_to_reach(levers: LeverConfig, positioning: PositioningConfig, depth_m: float) -> int:
    """Steps that take every lever across its whole range at depth ``depth_m`` (the drop height across its
    widest range, with the chain moving against it)."""
    rates = (positioning.vessel_speed_max_m_s, positioning.winch_rate_max_m_s, positioning.chain_rate_max_m_s)
    widths = (np.diff(levers.vessel_spacing_over_depth)[0] * depth_m,
              np.diff(levers.mooring_line_length_over_depth)[0] * depth_m, np.diff(levers.vertical_chain_length_m)[0])
    steps = [math.ceil(w / (r * positioning.step_s) - 1e-9) for w, r in zip(widths, rates, strict=True)]
    drop_width = np.diff(levers.drop_height_m)[0] + np.diff(levers.vertical_chain_length_m)[0]
    steps.append(math.ceil(drop_width / (positioning.wire_rate_max_m_s * positioning.step_s) - 1e-9))
    return int(max(steps))


def lever_fractions(state: dict[str, float], depth_m: float, levers: LeverConfig, anchor_length_m: float,
                    fairlead_depth_m: float) -> list[float]:
    """Where each lever stands in its range, -1 (low end) .. +1 (high end), as AnchorPlan-v1's actions map."""
    ranges = lever_ranges(levers, depth_m, state["vertical_chain_length_m"], anchor_length_m, fairlead_depth_m)
    return [0.0 if hi <= lo else 2.0 * (state[name] - lo) / (hi - lo) - 1.0
            for name, (lo, hi) in zip(LEVER_STATE, ranges, strict=True)]


def plan_targets(state: dict[str, float], depth_m: float, release_phase: float, levers: LeverConfig,
                 anchor_length_m: float, fairlead_depth_m: float) -> dict[str, float]:
    """AnchorPlan-v1's targets (:data:`~moor_env.envs.levers.TARGET_NAMES` and ``drop_height_max_m``) of the
    levers' state and a release phase [heave periods]."""
    drop_max = drop_height_max_m(levers, depth_m, state["vertical_chain_length_m"], anchor_length_m,
                                 fairlead_depth_m)
    values = (state["vessel_spacing_m"] / depth_m, state["mooring_line_length_m"] / depth_m,
              state["vertical_chain_length_m"], state["drop_height_m"], release_phase)
    return {**dict(zip(TARGET_NAMES, map(float, values), strict=True)), "drop_height_max_m": drop_max}


def release_decision(command: float, armed_steps: int, positioning: PositioningConfig,
                     window_periods: float) -> tuple[int, bool, float]:
    """The release command of one step (NaN as 0) after ``armed_steps`` consecutive steps above the threshold:
    (steps armed now, whether the anchor is released, the release phase [heave periods]). The phase maps the
    command's excess over the threshold linearly onto 0 .. ``window_periods``."""
    c = 0.0 if command != command else min(1.0, max(-1.0, float(command)))
    threshold = positioning.release_threshold
    if c <= threshold:
        return 0, False, 0.0
    armed = armed_steps + 1
    phase = (c - threshold) / (1.0 - threshold) * window_periods
    return armed, armed >= positioning.release_confirm_steps, float(phase)

"""The crew's actuators: the second vessel's dynamic positioning, the mooring-line winch and the release.

An action is three numbers in [-1, 1] (:data:`ACTION_NAMES`). The first two are scaled to physical commands and
cut to the limits of the config's ``control`` section (:func:`dp_speed_m_s`, :func:`winch_rate_m_s`, pure
functions); :func:`drive`, :func:`hold` and :func:`release` hand the result to a simulator.
"""

from __future__ import annotations

import numpy as np

from moor_env.envs.config import ControlConfig
from moor_env.simulation import Simulator

ACTION_NAMES: tuple[str, ...] = ("spacing_rate", "payout_rate", "release")
WINCH_LINE = "mooring_line"


def clip_action(action: np.ndarray | list[float]) -> list[float]:
    """An action (3 numbers, or a list of 3 Python floats as the vector env passes its rows) as Python floats
    clipped to [-1, 1]; NaN becomes 0 (holds position and does not release)."""
    values = action if type(action) is list else np.asarray(action, dtype=np.float64).reshape(3).tolist()
    return [0.0 if x != x else min(1.0, max(-1.0, x)) for x in values]


def dp_speed_m_s(a: float, speed_m_s: float, spacing_m: float, depth_m: float, cfg: ControlConfig) -> float:
    """The second vessel's speed away from the installation vessel over the next control interval [m/s]: the
    command ``a`` * ``spacing_rate_max_m_s``, changed from the present ``speed_m_s`` by at most
    ``spacing_accel_max_m_s2`` per second, and kept so that the spacing stays within ``spacing_min_m`` ..
    ``spacing_max_over_depth`` x depth at the end of the interval."""
    dt = cfg.interval_s
    cmd = a * cfg.spacing_rate_max_m_s
    dv = cfg.spacing_accel_max_m_s2 * dt
    v = min(max(cmd, speed_m_s - dv), speed_m_s + dv)
    s_max = cfg.spacing_max_over_depth * depth_m
    v = min(max(v, (cfg.spacing_min_m - spacing_m) / dt), (s_max - spacing_m) / dt)
    return float(v)


def winch_rate_m_s(a: float, line_length_m: float, depth_m: float, cfg: ControlConfig) -> float:
    """The mooring-line winch rate over the next control interval [m/s], + pays out: ``a`` times
    ``payout_rate_max_m_s`` (a > 0) or ``haul_rate_max_m_s``, kept so that the line (vertical chain included,
    ``line_length_m`` now) stays within ``line_length_min_over_depth`` .. ``line_length_max_over_depth`` x
    depth at the end of the interval."""
    dt = cfg.interval_s
    rate = a * (cfg.payout_rate_max_m_s if a > 0.0 else cfg.haul_rate_max_m_s)
    lo = cfg.line_length_min_over_depth * depth_m
    hi = cfg.line_length_max_over_depth * depth_m
    rate = min(max(rate, (lo - line_length_m) / dt), (hi - line_length_m) / dt)
    return float(rate)


def drive(sim: Simulator, t_s: float, duration_s: float, speed_m_s: float, rate_m_s: float, ramp_s: float) -> None:
    """Move the second vessel at ``speed_m_s`` and run the winch at ``rate_m_s`` from ``t_s`` for
    ``duration_s``."""
    sim.set_vessel_motion(t_s, duration_s, np.array([0.0, speed_m_s]), ramp_s=ramp_s)
    sim.set_payout_rate(WINCH_LINE, rate_m_s)


def stop_winch(sim: Simulator) -> None:
    """Stop paying out or hauling in."""
    sim.set_payout_rate(WINCH_LINE, 0.0)


def hold(sim: Simulator, t_s: float, duration_s: float, ramp_s: float) -> None:
    """Keep both vessels on station (wave motion only) from ``t_s`` for ``duration_s``."""
    sim.set_vessel_motion(t_s, duration_s, np.zeros(2), ramp_s=ramp_s)


def release(sim: Simulator, t_s: float, max_fall_s: float, ramp_s: float) -> None:
    """Open the release unit at ``t_s``; the vessels hold station over the fall."""
    sim.release()
    hold(sim, t_s, max_fall_s + 1.0, ramp_s)

"""Shared checks of the hard-case suite: finiteness and bounded energy along a run."""

from __future__ import annotations

import numpy as np

from moor_env import Simulator
from moor_env.physics import layout as L


def assert_finite_state(sim: Simulator) -> None:
    """Every active node and the anchor have finite positions and velocities."""
    active = sim.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE
    assert np.all(np.isfinite(sim.state.node_pos[active]))
    assert np.all(np.isfinite(sim.state.node_vel[active]))
    assert np.all(np.isfinite(sim.state.body_state))


def max_node_speed(sim: Simulator) -> float:
    """Fastest free node [m/s]."""
    free = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
    if not np.any(free):
        return 0.0
    return float(np.sqrt(np.max(np.sum(sim.state.node_vel[free] ** 2, axis=1))))


def run_checked(sim: Simulator, t_end: float, chunk_s: float = 0.25, speed_bound_m_s: float = 80.0,
                detect_touchdown: bool = False) -> int:
    """Advance in chunks, asserting a finite state, bounded node speeds (bounded kinetic energy) and, with the
    line-anchor contact, no node more than 5 cm inside the anchor throughout."""
    status = L.STATUS_TIME_LIMIT
    while sim.state.t < t_end - 0.5 * sim.dt:
        status, _ = sim.advance_to(min(sim.state.t + chunk_s, t_end), detect_touchdown=detect_touchdown)
        assert_finite_state(sim)
        assert max_node_speed(sim) < speed_bound_m_s
        assert sim.contact_report()["peak_depth_m"] < 0.05
        if status == L.STATUS_TOUCHDOWN:
            break
    return status

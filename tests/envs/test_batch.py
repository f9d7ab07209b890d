"""The batch kernel's call layer (moor_env.envs.batch): address tables and the loads it leaves behind."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.envs.batch import BatchAdvancer


@pytest.fixture()
def hanging_sim():
    """A hanging vertical chain (the cheapest scene with a line and a vessel)."""
    return solve_statics(load_scene("vertical-chain")).simulator


def _advance(sim, span_s: float = 0.2) -> None:
    status, error = BatchAdvancer(1).run({0: (sim, sim.state.t + span_s, False, sim.dt)})[0]
    assert error is None, error


def test_kernel_leaves_the_loads_of_the_state_reached(hanging_sim):
    """Reference: ``evaluate_loads`` at the same state; tolerance 1e-12 relative (the kernel may contract
    floating-point operations differently from the stand-alone compiled function)."""
    sim = hanging_sim
    _advance(sim)
    from_kernel = sim.top_tensions_n()  # no evaluation of its own: the kernel's record is current
    assert sim._loads_current()
    sim.evaluate_loads()  # drops the record ...
    assert not sim._loads_current()
    fresh = sim.top_tensions_n()  # ... so this evaluates again
    assert from_kernel.keys() == fresh.keys()
    for name, value in fresh.items():
        assert from_kernel[name] == pytest.approx(value, rel=1e-12, abs=1e-9)


def test_the_loads_record_goes_with_any_change_of_the_state(hanging_sim):
    sim = hanging_sim
    _advance(sim)
    sim.release()
    assert not sim._loads_current()
    _advance(sim)
    sim.state = sim.state.copy()  # a new state object never matches the record
    assert not sim._loads_current()
    _advance(sim)
    sim.state.t += 1.0
    assert not sim._loads_current()


def test_address_table_names_an_array_of_the_wrong_layout(hanging_sim):
    sim = hanging_sim
    sim.work.node_force = np.zeros((sim.work.node_force.shape[0], 6))[:, :3]  # a strided view
    with pytest.raises(TypeError, match="node_force"):
        _advance(sim)


def test_new_tracks_are_read_on_every_call(hanging_sim):
    """The vessel tracks may be replaced between calls (``set_vessel_motion`` with a new window length); the
    cached table must follow. Reference: the same advance through ``Simulator.advance_to``."""
    sim = hanging_sim
    twin = solve_statics(load_scene("vertical-chain")).simulator
    advancer = BatchAdvancer(1)
    for s in (sim, twin):
        s.set_vessel_motion(s.state.t, 0.5, np.full(s.vessel_mean_m.shape[0], 0.2))
    advancer.run({0: (sim, sim.state.t + 0.5, False, sim.dt)})
    twin.advance_to(twin.state.t + 0.5)
    for s in (sim, twin):
        s.set_vessel_motion(s.state.t, 2.0, np.full(s.vessel_mean_m.shape[0], -0.3))
    advancer.run({0: (sim, sim.state.t + 2.0, False, sim.dt)})
    twin.advance_to(twin.state.t + 2.0)
    np.testing.assert_allclose(sim.state.node_pos, twin.state.node_pos, rtol=0, atol=1e-9)

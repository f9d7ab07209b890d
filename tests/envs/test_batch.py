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
    """Reference: ``evaluate_loads`` at the same state; tolerance 1e-12 relative (the kernel may round
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
    sim.work = sim.work._replace(node_force=np.zeros((sim.work.node_force.shape[0], 6))[:, :3])  # a strided view
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


def test_backup_holds_the_state_before_the_advance(hanging_sim):
    """With ``take_backup`` the kernel copies the state before advancing (reference: a copy taken in Python,
    equal bit for bit); the state itself moves on."""
    from moor_env.envs.measures import SlotBuffers
    from moor_env.simulation import STATE_ARRAY_FIELDS

    sim = hanging_sim
    sim.set_vessel_motion(sim.state.t, 0.5, np.full(sim.vessel_mean_m.shape[0], 0.3))
    before = sim.state.copy()
    buffers = SlotBuffers([-1] * 5, sim.state)
    buffers.backup.node_pos[:] = 0.0  # stale contents must be overwritten
    status, error = BatchAdvancer(1).run({0: (sim, sim.state.t + 0.5, False, sim.dt, buffers, True)})[0]
    assert error is None
    for name in STATE_ARRAY_FIELDS:
        assert np.array_equal(getattr(buffers.backup, name), getattr(before, name)), name
    assert not np.array_equal(sim.state.node_pos, before.node_pos)


def test_coarse_advances_and_their_later_chunks_are_checked_against_breaking_loads(hanging_sim):
    """With the breaking loads lowered below the hanging tension and the running maxima cleared, an advance
    taking a backup (``TAKE_BACKUP``) and a later chunk of one (``BACKED_UP``, no backup taken) both fail with
    ``tension above breaking load``; the backup is written only by the first; an advance at the scene's step
    (0) is not checked."""
    from moor_env.envs.batch import BACKED_UP, TAKE_BACKUP
    from moor_env.envs.measures import SlotBuffers
    from moor_env.physics import layout as L

    sim = hanging_sim
    sim.model.mat_f[:, L.MF_MBL] = 1.0  # [N]
    buffers = SlotBuffers([-1] * 5, sim.state)
    start = sim.state.copy()
    for mode, fails in ((TAKE_BACKUP, True), (BACKED_UP, True), (0, False)):
        buffers.backup.node_pos[:] = 0.0
        sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0
        status, error = BatchAdvancer(1).run({0: (sim, sim.state.t + 0.1, False, sim.dt, buffers, mode)})[0]
        assert (error is not None and error.reason == "tension above breaking load") == fails, (mode, error)
        assert np.array_equal(buffers.backup.node_pos, start.node_pos) == (mode == TAKE_BACKUP), mode
        start = sim.state.copy()


def test_backup_needs_buffers_with_a_backup_state(hanging_sim):
    from moor_env.envs.measures import SlotBuffers

    sim = hanging_sim
    for buffers in (None, SlotBuffers([-1] * 5)):
        with pytest.raises(ValueError, match="backup"):
            BatchAdvancer(1).run({0: (sim, sim.state.t + 0.1, False, sim.dt, buffers, True)})


def test_kernel_measures_equal_the_simulator_quantities(tiny):
    """The observation's measures from the kernel (``moor_env.envs.measures.measure_scene`` after an advance)
    against the same quantities from the Simulator's own methods and the physics functions, after a step in
    waves with spacing and winch moves. Reference: those functions; tolerance 1e-9 relative (the kernel may
    round floating-point operations differently)."""
    import gymnasium as gym

    from moor_env.envs import measures as M
    from moor_env.envs.measures import line_summary
    from moor_env.physics.environment import current_velocity
    from moor_env.physics.vessels import track_state

    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    env.reset(seed=4, options={"sea_state_hs_m": 1.5, "current_scale": 1.0})
    for _ in range(4):
        env.step(np.array([0.6, 0.8, -1.0], np.float32))
    core = env.unwrapped.core
    sim, st = core.sim, core.sim.state
    measured = core.buffers.current_measures(sim)
    assert measured is not None  # the kernel's, of this state
    tensions = sim.top_tensions_n()
    loop_z, fibre_z, length = line_summary(st.node_pos, st.seg_i, st.seg_f, st.line_i, core.lines["mooring_line"],
                                           core.fibre_mat)
    _, _, hz, _, _, hvz = track_state(sim.tracks, 0, st.t, sim.env_f)
    cx, cy, _ = current_velocity(0.0, sim.env_f, sim.model.current_profile)
    e = st.body_state[6:9]
    w = st.body_state[9:12]
    expected = {
        M.M_TILT_DEG: sim.tilt_deg(), M.M_AXIS_RATE_DEG_S: np.degrees(np.linalg.norm(w - (w @ e) * e)),
        M.M_HEAVE_M: hz, M.M_HEAVE_RATE_M_S: hvz, M.M_CURRENT_X_M_S: cx, M.M_CURRENT_Y_M_S: cy,
        M.M_TIP_Z_M: sim.tip_state()[0][2], M.M_LOOP_Z_M: loop_z, M.M_FIBRE_Z_M: fibre_z, M.M_LINE_L0_M: length,
        M.M_WIRE_TENSION_N: tensions["wire"], M.M_LINE_TENSION_N: tensions["mooring_line"],
        **{M.M_RELEASE_POS + c: st.node_pos[sim.model.release_node, c] for c in range(3)},
        **{M.M_RELEASE_VEL + c: st.node_vel[sim.model.release_node, c] for c in range(3)},
    }
    assert sorted(expected) == list(range(M.N_MEASURES))
    assert abs(cx) > 0.01 and abs(hz + core.fairlead_depth_m) > 1e-5  # current and waves (small here) are exercised
    for index, value in expected.items():
        assert measured[index] == pytest.approx(value, rel=1e-9, abs=1e-9), index
    sim.set_payout_rate("mooring_line", 0.0)  # any change in place: the measures are no longer current
    assert core.buffers.current_measures(sim) is None

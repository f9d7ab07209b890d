"""The check of the state an advance leaves (``integrate.end_state_status``) and the growing implicit step
(``integrate.speed_step_factor``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L
from moor_env.physics.integrate import FAIL_NONE, FAIL_SEGMENT, end_state_status, speed_step_factor
from moor_env.physics.stability import REFERENCE_SPEED_M_S


def _hanging():
    """gjoa-500 at rest, its loads evaluated: records, largest strain and its segment."""
    sim = solve_statics(load_scene("gjoa-500")).simulator
    max_strain, worst = sim.evaluate_loads()
    model, state = sim.records()
    return model, state, max_strain, worst


NO_CHECK = np.zeros(0)  # no breaking-load check


def test_a_sound_state_passes_with_and_without_the_breaking_load_check():
    model, state, max_strain, worst = _hanging()
    before = np.zeros(state.line_i.shape[0])
    for max_tension_before in (NO_CHECK, before):
        assert end_state_status(model, state, max_strain, worst, max_tension_before) == (
            L.STATUS_RUNNING, FAIL_NONE, -1)


def test_strain_and_non_finite_loads_fail_whatever_the_advance():
    model, state, _, _ = _hanging()
    limit = model.env_f[L.EF_STRAIN_LIMIT]
    assert end_state_status(model, state, 1.01 * limit, 7, NO_CHECK) == (L.STATUS_STRAIN_LIMIT, FAIL_SEGMENT, 7)
    assert end_state_status(model, state, math.nan, 3, NO_CHECK) == (L.STATUS_NONFINITE, FAIL_SEGMENT, 3)


def test_a_running_maximum_raised_above_the_breaking_load_fails_only_where_asked():
    """With every material's breaking load lowered below the hanging tensions, an advance that raised a line's
    running maximum tension above it fails the coarse check, at that line's most loaded segment, also where the
    line was above it before (a line taken over it at the scene's step is checked on at every raise: a coarse
    step's spike on top of it is no load either); one that left every maximum where it was does not, nor an
    advance checked without it."""
    model, state, max_strain, worst = _hanging()
    model.mat_f[:, L.MF_MBL] = 1.0  # [N]
    n_lines = state.line_i.shape[0]
    assert end_state_status(model, state, max_strain, worst, NO_CHECK)[0] == L.STATUS_RUNNING
    status, kind, index = end_state_status(model, state, max_strain, worst, np.zeros(n_lines))
    assert (status, kind) == (L.STATUS_BREAKING_LOAD, FAIL_SEGMENT)
    line = state.seg_i[index, L.SI_LINE]
    assert line == 0 and state.line_f[line, L.LF_MAX_TENSION] > 1.0
    in_line = (state.seg_i[:, L.SI_LINE] == line) & (state.seg_i[:, L.SI_ACTIVE] != 0)
    assert state.seg_tension[index] == state.seg_tension[in_line].max()
    raised_further = 0.5 * state.line_f[:, L.LF_MAX_TENSION]  # above the breaking load before, and raised
    assert raised_further.min() > 1.0
    assert end_state_status(model, state, max_strain, worst, raised_further)[0] == L.STATUS_BREAKING_LOAD
    unchanged = state.line_f[:, L.LF_MAX_TENSION].copy()
    assert end_state_status(model, state, max_strain, worst, unchanged)[0] == L.STATUS_RUNNING


def _velocities(*speeds_m_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Free nodes moving along x at ``speeds_m_s``: their kinds and velocities."""
    node_i = np.zeros((len(speeds_m_s), L.N_NODE_I), np.int64)
    node_vel = np.zeros((len(speeds_m_s), 3))
    node_vel[:, 0] = speeds_m_s
    return node_i, node_vel


def test_the_step_grows_as_far_as_the_fastest_node_allows():
    """Reference: the implicit step's cap lets a node at ``REFERENCE_SPEED_M_S`` (40 m/s) cross half the shortest
    segment; a node at v crosses as little in 40 / v times that step, up to the growth asked for."""
    assert REFERENCE_SPEED_M_S == 40.0
    assert speed_step_factor(*_velocities(0.0, 0.0), 3.0) == 3.0
    assert speed_step_factor(*_velocities(1.0, -10.0), 3.0) == 3.0
    assert speed_step_factor(*_velocities(5.0, 20.0), 3.0) == pytest.approx(2.0, rel=1e-15)
    assert speed_step_factor(*_velocities(5.0, 80.0), 3.0) == 1.0
    node_i, node_vel = _velocities(5.0, 80.0)
    node_i[1, L.NI_KIND] = L.NODE_INACTIVE  # a dropped line's nodes do not count
    assert speed_step_factor(node_i, node_vel, 3.0) == 3.0
    assert speed_step_factor(*_velocities(5.0, math.nan), 3.0) == 1.0


def test_a_growing_fall_is_bit_identical_whether_split_or_not():
    """The fall's steps grow with the state they start from (``discretization.fall_step_growth_max``) and never
    with the call's end time: a fall run in calls of 0.3 s lands exactly as one call, in fewer steps than at the
    fixed step."""
    scene = load_scene("gjoa-500", {"fidelity": "fast", "discretization.fall_step_growth_max": 3.0})
    sim = solve_statics(scene).simulator
    assert sim.step_growth_max == 1.0  # the hanging phase keeps its step
    sim.release()
    start = sim.state.copy()
    assert sim.step_growth_max == 3.0
    _, steps_one_call = sim.advance_to(30.0, detect_touchdown=True)
    one_call = sim.work.touchdown.copy(), sim.state.body_state.copy(), sim.state.node_pos.copy()
    sim.state = start.copy()
    steps = 0
    status = L.STATUS_TIME_LIMIT
    while status != L.STATUS_TOUCHDOWN and sim.state.t < 30.0:
        status, n = sim.advance_to(sim.state.t + 0.3, detect_touchdown=True)
        steps += n
    assert status == L.STATUS_TOUCHDOWN
    assert steps == steps_one_call
    for a, b in zip(one_call, (sim.work.touchdown, sim.state.body_state, sim.state.node_pos), strict=True):
        assert np.array_equal(a, b)
    sim.state = start.copy()
    sim.step_growth_max = 1.0
    _, steps_fixed = sim.advance_to(30.0, detect_touchdown=True)
    assert steps_one_call < 0.7 * steps_fixed

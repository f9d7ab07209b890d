"""The check of the state an advance leaves (``integrate.end_state_status``)."""

from __future__ import annotations

import math

import numpy as np

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L
from moor_env.physics.integrate import FAIL_NONE, FAIL_SEGMENT, end_state_status


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
    running maximum tension above it fails the coarse check, at that line's most loaded segment; one whose lines
    were above it before does not, nor an advance checked without it."""
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
    above_before = state.line_f[:, L.LF_MAX_TENSION].copy()
    assert end_state_status(model, state, max_strain, worst, above_before)[0] == L.STATUS_RUNNING

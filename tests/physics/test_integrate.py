"""The check of the state an advance leaves (``integrate.end_state_status``)."""

from __future__ import annotations

import math

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L
from moor_env.physics.integrate import FAIL_NONE, FAIL_SEGMENT, end_state_status


def _hanging():
    """gjoa-500 at rest, its loads evaluated: records, largest strain and its segment."""
    sim = solve_statics(load_scene("gjoa-500")).simulator
    max_strain, worst = sim.evaluate_loads()
    model, state = sim.records()
    return model, state, max_strain, worst


def test_a_sound_state_passes_with_and_without_the_breaking_load_check():
    model, state, max_strain, worst = _hanging()
    for breaking_load in (False, True):
        assert end_state_status(model, state, max_strain, worst, breaking_load) == (L.STATUS_RUNNING, FAIL_NONE, -1)


def test_strain_and_non_finite_loads_fail_whatever_the_advance():
    model, state, _, _ = _hanging()
    limit = model.env_f[L.EF_STRAIN_LIMIT]
    assert end_state_status(model, state, 1.01 * limit, 7, False) == (L.STATUS_STRAIN_LIMIT, FAIL_SEGMENT, 7)
    assert end_state_status(model, state, math.nan, 3, False) == (L.STATUS_NONFINITE, FAIL_SEGMENT, 3)


def test_a_tension_above_the_breaking_load_fails_only_where_asked():
    """With every material's breaking load lowered below the hanging tensions, the first taut segment fails
    the coarse check (``breaking_load``) and nothing else does."""
    model, state, max_strain, worst = _hanging()
    model.mat_f[:, L.MF_MBL] = 1.0  # [N]
    assert end_state_status(model, state, max_strain, worst, False)[0] == L.STATUS_RUNNING
    status, kind, index = end_state_status(model, state, max_strain, worst, True)
    assert (status, kind) == (L.STATUS_BREAKING_LOAD, FAIL_SEGMENT)
    taut = [s for s in range(state.seg_i.shape[0]) if state.seg_i[s, L.SI_ACTIVE] and state.seg_tension[s] > 1.0]
    assert index == taut[0]

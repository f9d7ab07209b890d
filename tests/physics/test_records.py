"""The kernels' model and state records (moor_env.physics.records) and their address table
(moor_env.physics.record_table)."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.compile import compile_scene
from moor_env.physics import layout as L
from moor_env.physics.record_table import N_TABLE_COLUMNS, copy_rows, record_from_table, table_row, table_rows
from moor_env.physics.records import (
    MODEL_FIELDS,
    STATE_FIELDS,
    STATE_NAMES,
    WORK_FIELDS,
    ModelRecord,
    SimState,
    StateRecord,
    Workspace,
)
from moor_env.simulator import Simulator


@pytest.fixture(scope="module")
def sim():
    """A hanging vertical chain at its equilibrium."""
    return solve_statics(load_scene("vertical-chain"), progress=False).simulator


def test_field_lists_make_the_records():
    assert ModelRecord._fields == tuple(f.name for f in MODEL_FIELDS)
    assert StateRecord._fields == tuple(f.name for f in STATE_FIELDS + WORK_FIELDS)
    assert Workspace._fields == tuple(f.name for f in WORK_FIELDS)
    names = [f.name for f in MODEL_FIELDS + STATE_FIELDS + WORK_FIELDS]
    assert len(names) == len(set(names))


@pytest.mark.parametrize("scene", ["gjoa-500", "anchor-only", "seed004-chain-500"])
def test_a_compiled_scene_gives_every_array_as_declared(scene):
    """Every array of both records has its field's dtype and rank and is C-contiguous (what the batch kernel's
    table requires), for an installation, an anchor alone and a catenary line."""
    model, state = Simulator(compile_scene(load_scene(scene))).records()
    for record in (model, state):
        for field, array in zip(record.FIELDS, record, strict=True):
            assert array.dtype == field.dtype and array.ndim == field.ndim, field.name
            assert array.flags.c_contiguous, field.name
    n_nodes, n_segs, n_lines = state.node_pos.shape[0], state.seg_i.shape[0], state.line_i.shape[0]
    assert state.node_force.shape == (n_nodes, 3) and state.seg_tension.shape == (n_segs,)
    assert state.top_tension.shape == (n_lines,) and state.touchdown.shape == (L.N_TD,)


def test_sim_state_takes_exactly_the_state_arrays(sim):
    arrays = {name: getattr(sim.state, name) for name in STATE_NAMES}
    with pytest.raises(TypeError, match="missing \\['node_vel'\\]"):
        SimState(**{k: v for k, v in arrays.items() if k != "node_vel"})
    with pytest.raises(TypeError, match="unknown \\['extra'\\]"):
        SimState(extra=np.zeros(1), **arrays)
    copy = sim.state.copy()
    for name in STATE_NAMES:
        assert np.array_equal(getattr(copy, name), getattr(sim.state, name))
        assert not np.shares_memory(getattr(copy, name), getattr(sim.state, name))
    assert (copy.t, copy.released) == (sim.state.t, sim.state.released)


def test_records_follow_a_replaced_state_workspace_or_tracks(sim):
    """The simulator's records are kept while nothing is replaced and rebuilt when the state, the work arrays,
    the environment array or the vessel tracks are (the kernels must never see a stale array)."""
    model, state = sim.records()
    assert sim.records()[0] is model and sim.records()[1] is state
    assert state.node_pos is sim.state.node_pos and state.node_force is sim.work.node_force
    assert model.tracks is sim.tracks and model.env_f is sim.env_f and model.mat_f is sim.model.mat_f
    sim.state = sim.state.copy()
    assert sim.records()[1].node_pos is sim.state.node_pos
    sim.work = sim.work._replace(node_force=sim.work.node_force.copy())
    assert sim.records()[1].node_force is sim.work.node_force
    sim.set_vessel_motion(sim.state.t, 3.0, np.zeros(sim.vessel_mean_m.shape[0]))  # a new window length
    assert sim.records()[0].tracks is sim.tracks
    sim.env_f = sim.env_f.copy()
    assert sim.records()[0].env_f is sim.env_f


@numba.njit
def _node_sum_and_write(table):
    """Rebuild the state record from its table rows, write into it and read from it."""
    state = record_from_table(StateRecord, table, 0)
    state.hist_count[0] = 7
    return state.node_pos.sum() + state.seg_i.sum() + state.node_force.shape[1]


def test_table_rows_give_views_of_the_record_arrays(sim):
    """Reference: the same sums in numpy, and the write seen in the simulator's own array."""
    _, state = sim.records()
    table = table_rows(state)
    assert table.shape == (len(StateRecord.FIELDS), N_TABLE_COLUMNS)
    expected = state.node_pos.sum() + state.seg_i.sum() + 3
    assert _node_sum_and_write(table) == pytest.approx(expected, rel=1e-12)
    assert sim.work.hist_count[0] == 7
    sim.work.hist_count[0] = 0


def test_copy_rows_copies_every_state_array_bit_for_bit(sim):
    st = sim.state
    target = st.copy()
    for name in STATE_NAMES:
        getattr(target, name)[...] = 0
    st.node_vel[0, 0] = np.nan  # NaN bits too
    fields = STATE_FIELDS
    table = np.concatenate([table_rows([getattr(st, n) for n in STATE_NAMES], fields),
                            table_rows([getattr(target, n) for n in STATE_NAMES], fields)])
    copy_rows(table, 0, len(fields), len(fields))
    for name in STATE_NAMES:
        assert getattr(st, name).tobytes() == getattr(target, name).tobytes(), name
    st.node_vel[0, 0] = 0.0


def test_a_table_row_refuses_an_array_the_kernel_would_misread():
    with pytest.raises(TypeError, match="'seg_tension' is float32"):
        table_row("seg_tension", np.zeros(3, np.float32), np.float64, 1)
    with pytest.raises(TypeError, match="'node_pos' is float64\\[2d\\], expected C-contiguous"):
        table_row("node_pos", np.zeros((4, 6))[:, :3], np.float64, 2)
    assert table_row("x", np.zeros((2, 3)), np.float64, 2)[1:] == [2, 3, 0, 6]

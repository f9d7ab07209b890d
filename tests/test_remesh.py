"""Remeshing a state onto another resolution of the same scene (moor_env.remesh)."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene
from moor_env.compile import compile_scene
from moor_env.physics import layout as L
from moor_env.remesh import remesh_state
from moor_env.simulation import Simulator, run_drop, solve_statics

# gjoa-500 at 120 m spacing: the loop tightens in the fall, so `fast` fits its tight_line resolution there
# (the speed-vs-error study measured the coarse one 4-9 % slow at 85-120 m, the fine one within 0.05 %)
# The line-anchor contact is off: with it, this fall's vertical chain lands on the anchor and snaps taut at a
# moment that a 0.06 mm change of the static state moves (touchdown 25.3 or 26.3 m/s), which says nothing of the
# state transfer this file checks.
TIGHT_SCENE = {"fidelity": "fast", "vessel_spacing_m": 120.0, "discretization.line_anchor_contact": "off"}
COARSE = {**TIGHT_SCENE, "discretization.fit_to_geometry": False}


@pytest.fixture(scope="module")
def coarse_static():
    return solve_statics(load_scene("gjoa-500", COARSE))


@pytest.fixture(scope="module")
def fine_model():
    return compile_scene(load_scene("gjoa-500", TIGHT_SCENE))


def _active_segments(state, line):
    li = state.line_i[line]
    return np.arange(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])


def _material_lengths(state, model):
    out = {}
    for name, info in model.lines.items():
        segs = _active_segments(state, info.index)
        for mat in np.unique(state.seg_i[segs, L.SI_MAT]):
            out[name, int(mat)] = float(np.sum(state.seg_f[segs[state.seg_i[segs, L.SI_MAT] == mat], L.SF_L0]))
    return out


def test_fitted_scene_is_the_fine_one(coarse_static, fine_model):
    coarse = coarse_static.simulator.model
    assert coarse.scene.discretization.loop_chain_segment_m == 2.0
    assert fine_model.scene.discretization.loop_chain_segment_m == 0.5


def test_remesh_onto_the_same_resolution_is_the_identity(coarse_static):
    sim = coarse_static.simulator
    out = remesh_state(sim.state, sim.model, sim.model)
    for name in ("node_i", "seg_i", "line_i"):
        assert np.array_equal(getattr(out, name), getattr(sim.state, name)), name
    np.testing.assert_allclose(out.seg_f, sim.state.seg_f, rtol=1e-14)
    active = sim.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE
    np.testing.assert_allclose(out.node_pos[active], sim.state.node_pos[active], rtol=0, atol=1e-9)
    assert np.array_equal(out.body_state, sim.state.body_state)


def test_coarse_to_fine_conserves_every_material_length_and_keeps_the_shape(coarse_static, fine_model):
    """Exact: unstretched length (hence mass) per line and material. Shape: every new node lies on the old
    polyline, and a straight hanging chain keeps its strain (the vertical chain: new segments at the old ones'
    strain to 1e-9)."""
    sim = coarse_static.simulator
    out = remesh_state(sim.state, sim.model, fine_model)
    before, after = _material_lengths(sim.state, sim.model), _material_lengths(out, fine_model)
    assert before.keys() == after.keys()
    for key, length in before.items():
        assert after[key] == pytest.approx(length, rel=1e-12), key
    vc = fine_model.lines["vertical_chain"].index
    segs = _active_segments(out, vc)
    assert out.seg_f[segs[0], L.SF_L0] == pytest.approx(1.0, abs=1e-9)  # tight_line: 1 m vertical chain
    strain = [np.linalg.norm(out.node_pos[out.seg_i[s, L.SI_B]] - out.node_pos[out.seg_i[s, L.SI_A]])
              / out.seg_f[s, L.SF_L0] - 1.0 for s in segs]
    old = _active_segments(sim.state, vc)
    old_strain = [np.linalg.norm(sim.state.node_pos[sim.state.seg_i[s, L.SI_B]]
                                 - sim.state.node_pos[sim.state.seg_i[s, L.SI_A]]) / sim.state.seg_f[s, L.SF_L0] - 1.0
                  for s in old]
    np.testing.assert_allclose(strain, np.repeat(old_strain, 2), rtol=0, atol=1e-9)
    free = out.node_i[:, L.NI_KIND] == L.NODE_FREE
    assert int(np.sum(free)) > int(np.sum(sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE))
    # the remeshed hanging state is near its equilibrium: the load on the second vessel within 1 %
    fine_sim = Simulator(fine_model)
    fine_sim.state = out
    assert fine_sim.top_tensions_n()["mooring_line"] == pytest.approx(
        coarse_static.top_tensions_n["mooring_line"], rel=0.01)


def test_fall_from_a_remeshed_state_matches_the_fine_run(coarse_static, fine_model):
    """Reference: the same scene solved and dropped on the fine resolution throughout. The remeshed run (coarse
    equilibrium, fine fall) is within 0.1 % in touchdown speed (measured 0.002 %: 26.3203 against 26.3197 m/s)
    and 0.1 deg in tilt (both 0.00 deg); the coarse run throughout misses by more than 2 % (what the fit at the
    release is for)."""
    reference = run_drop(solve_statics(fine_model).simulator, history=False)
    sim = Simulator(fine_model)
    sim.state = remesh_state(coarse_static.simulator.state, coarse_static.simulator.model, fine_model)
    remeshed = run_drop(sim, history=False)
    coarse = run_drop(solve_statics(coarse_static.simulator.model).simulator, history=False)
    assert remeshed.status == reference.status == "touchdown"
    assert remeshed.touchdown_speed_m_s == pytest.approx(reference.touchdown_speed_m_s, rel=0.001)
    assert remeshed.tilt_deg == pytest.approx(reference.tilt_deg, abs=0.1)
    assert abs(coarse.touchdown_speed_m_s / reference.touchdown_speed_m_s - 1.0) > 0.02


def test_errors_name_the_mismatch(coarse_static, fine_model):
    sim = coarse_static.simulator
    other = compile_scene(load_scene("vertical-chain"))
    with pytest.raises(ValueError, match="lines or materials differ"):
        remesh_state(sim.state, sim.model, other)
    longer = sim.state.copy()  # a vertical chain longer than the fine model has segment slots for
    segs = _active_segments(longer, sim.model.lines["vertical_chain"].index)
    longer.seg_f[segs, L.SF_L0] *= 1.1
    with pytest.raises(ValueError, match="line 'vertical_chain' needs 55 segments"):
        remesh_state(longer, sim.model, fine_model)

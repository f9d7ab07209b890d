"""The lines' part of the static step's K kept between solves at one state (``physics/statics_assembly.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene
from moor_env.physics import layout as L
from moor_env.physics.statics_stages import body_root
from moor_env.physics.statics_system import new_scratch, residual, solve_step
from moor_env.physics.tree import build_tree, order
from moor_env.simulation import solve_statics

# drawn by the statics benchmark: 8 m apart in 418 m of water, in current; at rest the loop's chain hangs over the
# anchor's back end, held there by segment contacts (the contact terms that go into the segments' couplings)
OVER_THE_RIM = {"water_depth_m": 418.343, "vessel_spacing_m": 8.185, "mooring_line_length_m": 519.5,
                "vertical_chain_length_m": 29.053, "drop_height_m": 79.56, "current_scale": 0.409,
                "current_direction_deg": 155.957, "anchor_mass_scale": 0.927, "fidelity": "fast"}


@pytest.fixture(scope="module")
def resting():
    """The records of the equilibrium with the loop over the rim, the tree's order and the step's arrays."""
    sim = solve_statics(load_scene("gjoa-500", OVER_THE_RIM), progress=False).simulator
    model, state = sim.records()
    body = body_root(sim)
    nn = state.node_pos.shape[0]
    tree, orow = np.zeros((nn, 3), np.int64), np.zeros((nn, 3), np.int64)
    build_tree(body, state.node_i, state.seg_i, tree, orow)
    nq = order(body, state.node_i, state.seg_i, tree, orow)
    return {"model": model, "state": state, "body": body, "tree": tree, "orow": orow, "nq": nq}


def _step(r, scratch, moved, seg_age=None, tau_s=30.0):
    """The step at the state (loads evaluated first) with ``scratch``; the step, the anchor's step, the couplings
    and the scratch's candidate rows inside after the step."""
    state = r["state"]
    seg_age = np.zeros(state.seg_i.shape[0]) if seg_age is None else seg_age
    basis, res_body, dq = np.zeros((2, 3)), np.zeros(5), np.zeros(5)
    residual(r["model"], state, r["body"], basis, res_body)
    solve_step(1.0 / tau_s**2, r["nq"], r["body"], basis, res_body, dq, r["model"], state, scratch, r["tree"],
               r["orow"], seg_age, True, moved)
    return state.node_acc.copy(), dq.copy(), scratch[1].copy(), scratch[6].copy()


def test_a_solve_at_the_same_state_keeps_the_lines_part_exactly(resting):
    """Reference: the same step assembled afresh. A solve at the state already assembled (at another pseudo time
    step, as a grown tau asks) gives the fresh assembly's step bit for bit, and the couplings it leaves are the
    lines' own: the segment contacts' terms (present here) were taken out again after the elimination."""
    nn = resting["state"].node_pos.shape[0]
    scratch = new_scratch(nn, resting["state"].seg_i.shape[0])
    first = _step(resting, scratch, True, tau_s=10.0)
    assert first[3][nn:].any(), "no segment contact in the step: the test would not exercise the held couplings"
    kept = _step(resting, scratch, False)
    fresh = _step(resting, new_scratch(nn, resting["state"].seg_i.shape[0]), True)
    for a, b in zip(kept[:3], fresh[:3], strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(first[2], fresh[2])


def test_a_changed_taut_set_is_assembled_afresh(resting):
    """Reference: a fresh assembly. A segment slack in the state counts as taut for its first ``SLACK_PATIENCE``
    slack iterations and keeps only its floor stiffness after them; a solve at the same state after that change
    assembles again rather than keep the taut segment's stiffness."""
    state = resting["state"]
    seg = int(np.nonzero(state.seg_i[:, L.SI_ACTIVE])[0][10])
    l0 = state.seg_f[seg, L.SF_L0]
    state.seg_f[seg, L.SF_L0] = 1.01 * l0  # slack at the state
    try:
        nn, ns = state.node_pos.shape[0], state.seg_i.shape[0]
        scratch = new_scratch(nn, ns)
        taut = _step(resting, scratch, True)
        long_slack = np.full(ns, 10.0)
        kept = _step(resting, scratch, False, long_slack)
        fresh = _step(resting, new_scratch(nn, ns), True, long_slack)
    finally:
        state.seg_f[seg, L.SF_L0] = l0
    assert not np.array_equal(taut[0], fresh[0])
    for a, b in zip(kept[:3], fresh[:3], strict=True):
        np.testing.assert_array_equal(a, b)

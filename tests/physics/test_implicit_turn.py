"""The implicit step on a taut segment that turns within the step (``implicit_active_set._pass_active_set``).

The step moves every node by h v1, so a segment that turns at v_perp across itself ends |d0 + h dv1| long, about
(h v_perp)^2 / (2 l0) longer than its spring linearised at the start direction holds it; the next load evaluation
would read EA times that stretch (a 1 m segment of 142 mm chain turned at 10 m/s over 11.25 ms: 0.63 % strain,
11 MN). Where that excess passes ``TURN_TOLERANCE`` the segment's spring is linearised again at its predicted end
chord and the step solved again.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import implicit_active_set as S
from moor_env.physics import layout as L

IMPLICIT = {"integrator": "implicit_euler"}
REFERENCE_SUBSTEPS = 64  # 0.18 ms: below the explicit limit of the 1 m chain's axial mode (0.34 ms)


@functools.cache
def _hanging_chain():
    """vertical-chain before the release (the DPA hanging from 50 m of 1 m chain, 0.78 MN in the chain) at its
    equilibrium: the simulator, its state, the middle node of the chain and its two segments."""
    sim = solve_statics(load_scene("vertical-chain", IMPLICIT)).simulator
    st = sim.state
    line = sim.model.lines["vertical_chain"].index
    first, count = st.line_i[line, L.LI_SEG_START], st.line_i[line, L.LI_NSEG]
    upper = first + count // 2
    return sim, st.copy(), int(st.seg_i[upper, L.SI_B]), (upper, upper + 1)


def _kicked_step(v_perp_m_s: float, substeps: int) -> tuple[np.ndarray, object]:
    """Tensions [N] of the two segments beside the chain's middle node after one model step taken in
    ``substeps`` steps, the node started at ``v_perp_m_s`` across the chain (x); and the simulator."""
    sim, start, node, segs = _hanging_chain()
    sim.state = start.copy()
    h = sim.model.dt_s
    sim.dt = h / substeps
    sim.state.node_vel[node] = (v_perp_m_s, 0.0, 0.0)
    sim.advance_to(sim.state.t + h)
    sim.evaluate_loads()
    return sim.work.seg_tension[list(segs)].copy(), sim


@pytest.mark.parametrize("v_perp_m_s", [5.0, 10.0, 15.0])
def test_turning_segment_keeps_the_substepped_tension(v_perp_m_s):
    """Reference: the same interval in 64 implicit sub-steps (0.18 ms; 32 and 128 sub-steps agree within 0.5 %).
    A node of the hanging 142 mm chain (1 m segments, EA 1.74 GN, 0.78 MN) kicked across the chain at v_perp:
    after one step of 11.25 ms both its segments carry the reference tension within 25 % (measured 9 %, 19 %,
    16 % at 5, 10, 15 m/s: 0.84, 0.99, 1.25 MN against 0.92, 1.22, 1.49 MN); the spring linearised at the start
    direction alone left 1.8, 5.0 and 10.0 MN (2, 4 and 6.7 times the reference)."""
    reference, _ = _kicked_step(v_perp_m_s, REFERENCE_SUBSTEPS)
    one_step, sim = _kicked_step(v_perp_m_s, 1)
    assert sim.dt == sim.model.dt_s > 0.011
    assert reference.min() > 0.85e6
    np.testing.assert_allclose(one_step, reference, rtol=0.25)


def test_only_a_turning_segment_is_linearised_again():
    """The extra solve is paid only where a segment turns: at 0.5 m/s the turn strain over a step is
    (h v)^2 / (2 l0^2) = 1.6e-5, below ``TURN_TOLERANCE`` (1e-4), and no segment is linearised again; at 10 m/s
    (6.3e-3) both segments beside the kicked node are, and no other."""
    _, sim = _kicked_step(0.5, 1)
    assert not np.any(sim.work.seg_chord[:, 3])
    _, sim = _kicked_step(10.0, 1)
    segs = _hanging_chain()[3]
    assert set(np.nonzero(sim.work.seg_chord[:, 3])[0]) == set(segs)
    assert S.TURN_TOLERANCE == 1e-4

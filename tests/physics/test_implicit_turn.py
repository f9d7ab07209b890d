"""The implicit step on a taut segment that turns within the step (``implicit_active_set._pass_active_set``).

The step moves every node by h v1, so a segment that turns at v_perp across itself ends |d0 + h dv1| long, about
(h v_perp)^2 / (2 l0) longer than its spring linearised at the start direction holds it; the next load evaluation
would read EA times that stretch (a 1 m segment of 142 mm chain turned at 10 m/s over 11.25 ms: 0.63 % strain,
11 MN). Where that excess passes ``TURN_TOLERANCE`` the segment's spring is linearised again at its predicted end
chord and the step solved again. A chord predicted from the start velocities is not used (see the crew episode
test below).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import implicit_active_set as S
from moor_env.physics import layout as L
from moor_env.physics import tree as T
from moor_env.physics.records import ModelRecord, StateRecord
from tests.physics.test_implicit import _record

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
    after one step of 11.25 ms both its segments carry the reference tension within 25 % (measured 9 %, 20 %,
    21 % at 5, 10, 15 m/s: 0.84, 0.98, 1.18 MN against 0.92, 1.22, 1.49 MN); the spring linearised at the start
    direction alone left 1.8, 5.0 and 10.0 MN (2, 4 and 6.7 times the reference)."""
    reference, _ = _kicked_step(v_perp_m_s, REFERENCE_SUBSTEPS)
    one_step, sim = _kicked_step(v_perp_m_s, 1)
    assert sim.dt == sim.model.dt_s > 0.011
    assert reference.min() > 0.85e6
    np.testing.assert_allclose(one_step, reference, rtol=0.25)


def test_only_a_turning_segment_is_linearised_again():
    """Only a segment that turns is linearised again: at 0.5 m/s the turn strain over a step is
    (h v)^2 / (2 l0^2) = 1.6e-5, below ``TURN_TOLERANCE`` (1e-4), and no segment is; at 10 m/s (6.3e-3) both
    segments beside the kicked node are, and no other."""
    _, sim = _kicked_step(0.5, 1)
    assert not np.any(sim.work.seg_chord[:, 3])
    _, sim = _kicked_step(10.0, 1)
    segs = _hanging_chain()[3]
    assert set(np.nonzero(sim.work.seg_chord[:, 3])[0]) == set(segs)
    assert S.TURN_TOLERANCE == 1e-4


L0_M = 2.0  # the hanging pendulum segment of the two tests below


def _pendulum(lower_z_m: float, vel_x_m_s: float, dv_m_s: tuple, taut: bool) -> tuple:
    """A segment of ``L0_M`` hanging from a held node, its lower node at ``lower_z_m`` moving sideways at
    ``vel_x_m_s`` and given the solved velocity change ``dv_m_s``; in the active set where ``taut``. Returns the
    records and the ordering scratch ``update_active_set`` reads."""
    node_pos = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, lower_z_m]])
    node_vel = np.array([[0.0, 0.0, 0.0], [vel_x_m_s, 0.0, 0.0]])
    seg_i = np.zeros((1, L.N_SEG_I), np.int64)
    seg_i[0, [L.SI_A, L.SI_B, L.SI_ACTIVE]] = 0, 1, 1
    seg_f = np.zeros((1, L.N_SEG_F))
    seg_f[0, L.SF_L0] = L0_M
    mat_f = np.zeros((1, L.N_MAT_F))
    mat_f[0, L.MF_EA], mat_f[0, L.MF_MASS], mat_f[0, L.MF_ZETA] = 1e9, 400.0, 0.3
    node_acc = np.array([[0.0, 0.0, 0.0], dv_m_s])
    orow = np.zeros((2, 3), np.int64)
    orow[:, T.OR_EFF] = -1, 1
    orow[0, T.OR_FLAGS] = int(taut)
    model = _record(ModelRecord, mat_f=mat_f)
    state = _record(StateRecord, node_pos=node_pos, node_vel=node_vel, seg_i=seg_i, seg_f=seg_f, node_acc=node_acc,
                    seg_chord=np.zeros((1, 4)))
    return model, state, orow


def test_an_entering_segment_is_linearised_along_its_solved_direction():
    """A slack segment that the solve carries taut and turns (its end chord beyond its linear prediction by more
    than ``TURN_TOLERANCE``) enters the set linearised at its unstretched length along that chord, not at the
    chord itself (which the solve, without its spring, overstretched)."""
    h = 0.1
    # the lower node swings sideways at 2 m/s; the solve moves it down 0.1 m/s more
    model, state, orow = _pendulum(-0.999 * L0_M, 2.0, (0.0, 0.0, -0.1), taut=False)
    assert S.update_active_set(h, model, state, orow) == 1
    assert S.is_active(orow, 0) == 1
    end_chord = state.node_pos[1] - state.node_pos[0] + h * (state.node_vel[1] + state.node_acc[1])
    assert state.seg_chord[0, 3] == 1.0
    np.testing.assert_allclose(state.seg_chord[0, :3], L0_M * end_chord / np.linalg.norm(end_chord), rtol=0,
                               atol=1e-15)


def test_a_turn_that_only_the_solve_shows_is_linearised_again():
    """A taut segment at rest that the solve swings sideways at 2 m/s over 0.1 s (turn strain (h v)^2 / (2 l0^2) =
    5e-3) is linearised again at the end chord the solve predicts and solved again."""
    h = 0.1
    model, state, orow = _pendulum(-1.0001 * L0_M, 0.0, (2.0, 0.0, 0.0), taut=True)
    assert S.update_active_set(h, model, state, orow) == 1
    end_chord = state.node_pos[1] - state.node_pos[0] + h * (state.node_vel[1] + state.node_acc[1])
    assert state.seg_chord[0, 3] == 1.0
    np.testing.assert_allclose(state.seg_chord[0, :3], end_chord, rtol=0, atol=1e-15)


def test_a_crew_fall_keeps_every_line_below_its_breaking_load():
    """Reference: the explicit fall of the same crew episodes peaks at about two thirds of the chain's MBL
    (docs/mbl-exceedance.md). The crew's AnchorPlan-v0 episode with seed 5000, whose vertical chain catches up with
    the anchor and piles onto its back end late in the fall, touches down with every line's running maximum tension
    below its MBL; linearising taut segments along chords predicted from their start velocities took the vertical
    chain to 3.2 times it there."""
    import gymnasium as gym

    from agents.baselines import PLAN_ENV, make_baseline
    from agents.policy import EpisodeContext

    env = gym.make(PLAN_ENV)
    policy = make_baseline("crew", PLAN_ENV)
    obs, info = env.reset(seed=5000)
    policy.begin_episode(EpisodeContext(PLAN_ENV, None, info["scenario"], 5000, obs, info))
    info = env.step(policy.act(obs, info))[4]
    mbl = env.unwrapped.core.mbl
    assert info["sim_status"] == "touchdown"
    ratios = {name: tension / mbl[name] for name, tension in info["max_tension_n"].items()}
    assert max(ratios.values()) < 1.0, ratios
    env.close()

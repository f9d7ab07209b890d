"""The line-anchor contact in the static problem (moor_env.physics.statics_contact and its use by the statics).

Reference scenes: gjoa-500 with the mooring line's loop hanging beside the vertical chain (vessels 0 m apart; a very
slack line 30 m apart; scenes drawn by the statics benchmark; an AnchorPlan-v1 held-out site's random plan with the
env's segment lengths): the loop rests against the anchor's shaft or over its back end's rim. The
residual is the dynamic model's own loads at rest, contact included (1e-4 of every node's weight, the solver's
tolerance).
"""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.compile import compile_scene
from moor_env.errors import NoEquilibrium, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.statics_checks import ANCHOR_CLEARANCE_M, anchor_intrusion
from tests.physics.test_statics import _residual_ratio

RESTING = [
    {"vessel_spacing_m": 0.0, "fidelity": "fast"},
    {"vessel_spacing_m": 0.0, "fidelity": "default"},
    # drawn by the statics benchmark: 31 m apart in 339 m, a 5.8 m vertical chain, in current
    {"water_depth_m": 339.087, "vessel_spacing_m": 30.575, "mooring_line_length_m": 413.87,
     "vertical_chain_length_m": 5.848, "drop_height_m": 80.772, "current_scale": 0.287,
     "current_direction_deg": 275.998, "anchor_mass_scale": 0.996, "fidelity": "fast"},
    {"mooring_line_length_m": 640.0, "vessel_spacing_m": 30.0, "fidelity": "default"},
    # drawn by the statics benchmark: 22 m apart in 1440 m, a 6.5 m vertical chain, in current
    {"water_depth_m": 1440.162, "vessel_spacing_m": 21.986, "mooring_line_length_m": 1401.477,
     "vertical_chain_length_m": 6.53, "drop_height_m": 89.935, "current_scale": 0.33,
     "current_direction_deg": 207.511, "anchor_mass_scale": 1.059, "fidelity": "default"},
    # an AnchorPlan-v1 held-out site's random plan: 119 m apart in 580 m, a 7.7 m vertical chain, strong current,
    # the env's segment lengths; the chain loop rests over the back end's rim (release_pulling)
    {"water_depth_m": 580.034, "vessel_spacing_m": 119.044, "mooring_line_length_m": 703.649,
     "vertical_chain_length_m": 7.684, "drop_height_m": 35.921, "current_scale": 1.117,
     "current_direction_deg": 64.99, "anchor_mass_scale": 1.018, "fidelity": "fast",
     "discretization.fit_to_geometry": False, "discretization.loop_chain_segment_m": 1.0,
     "discretization.vertical_chain_segment_m": 1.0, "discretization.fibre_segment_m": 50.0,
     "discretization.wire_segment_m": 100.0},
]


@pytest.mark.parametrize("overrides", RESTING)
def test_loop_rests_on_the_anchor(overrides):
    """Newton's method reaches the equilibrium with the loop against the anchor: residual below 1e-4 of every
    node's weight with the contact's forces in it, the loop held by the anchor (at a node or a segment over a rim),
    no node and no point of a segment deeper than a millimetre inside it (the contact's penalty at rest; the
    acceptance limit is 5 cm), the tip at its drop height."""
    static = solve_statics(load_scene("gjoa-500", overrides), progress=False, method="newton")
    sim = static.simulator
    assert _residual_ratio(static) < 1e-4
    out = sim.work.contact_out
    assert out[L.CO_NODES] + out[L.CO_SEGMENTS] >= 1 and out[L.CO_FORCE] > 0.0
    assert anchor_intrusion(sim)[0] < 1e-3 < ANCHOR_CLEARANCE_M
    assert 0.0 < sim.deepest_segment_inside_m() < 1e-3
    assert static.tip_height_above_seabed_m == pytest.approx(load_scene("gjoa-500", overrides)
                                                             .installation.drop_height_m, abs=1e-3)


def test_resting_equilibrium_is_deterministic():
    """Same scene, same equilibrium, bit for bit."""
    scene = load_scene("gjoa-500", RESTING[0])
    a, b = (solve_statics(scene, progress=False).simulator.state for _ in range(2))
    assert np.array_equal(a.node_pos, b.node_pos) and np.array_equal(a.body_state, b.body_state)


def test_clear_of_the_anchor_the_contact_changes_nothing():
    """Where no line comes near the anchor (gjoa-500 as bundled), the equilibrium with the contact modelled is the
    one without it, bit for bit: the lines are solved without it first and that equilibrium is kept."""
    on = solve_statics(load_scene("gjoa-500", {"discretization.line_anchor_contact": "on"}), progress=False)
    off = solve_statics(load_scene("gjoa-500", {"discretization.line_anchor_contact": "off"}), progress=False)
    assert anchor_intrusion(on.simulator)[0] == 0.0
    assert np.array_equal(on.simulator.state.node_pos, off.simulator.state.node_pos)
    assert on.iterations == off.iterations


def _resting(segments: bool):
    """The resting equilibrium of ``RESTING[0]`` with the segments' contact on or off (off: nodes rest on the
    shaft; on: the chain is held over the back end's rim by a segment)."""
    model = compile_scene(load_scene("gjoa-500", RESTING[0]))
    model.contact_f[L.CF_SEGMENTS] = 1.0 if segments else 0.0
    return solve_statics(model, progress=False, method="newton").simulator


def _contact_point(sim, segments: bool):
    """The deepest contact of a resting equilibrium: its point, its row in the static solver's contact geometry
    (a node's, or a segment's after the nodes')."""
    from moor_env.physics.anchor_surface import deepest_segment_point, segment_depth

    st, shape = sim.state, sim.model.contact_shape
    if not segments:
        node = int(np.argmax([anchor_intrusion_depth(sim, n) for n in range(st.node_pos.shape[0])]))
        return st.node_pos[node], node
    s = deepest_segment_point(st.node_pos, st.seg_i, st.body_state, shape)[1]
    a, b = st.node_pos[st.seg_i[s, L.SI_A]], st.node_pos[st.seg_i[s, L.SI_B]]
    t = segment_depth(*a, *b, st.body_state, shape)[1]
    return a + t * (b - a), st.node_pos.shape[0] + s


@pytest.mark.parametrize(("segments", "turning"), [(False, False), (True, False), (True, True)])
def test_newton_step_predicts_the_residual_change(segments, turning):
    """The linear system of a step, with the contact's terms and their coupling to the anchor carried through the
    tree elimination, is the residual's derivative: from a state with the anchor pushed 2 mm into the resting
    loop (at a node resting on the shaft, or at the segment over the back end's rim), a step of eps = 1e-3 along
    the Newton direction (pseudo time step 1e12 s, the contact and seabed sets as they are) changes every line
    node's residual as predicted, F(x + eps dx) = (1 - eps) F(x), within 2 % of the change at a node (the turning
    of the normal and the moment arm's change, left out of the system, are below that) and 3 % at a segment (there
    also the turning of its direction g with the segment, k e dg/dx, and the shift of its shares as the anchor
    moves, at e of 2 mm); with the turning of the segment's normal round the axis in the system (``CF_TURNING``,
    as a creeping stage takes it) within the same bound."""
    from moor_env.physics import statics_system as system
    from moor_env.physics.statics_assembly import assemble_diagonal, assemble_lines
    from moor_env.physics.statics_contact import add_contact_blocks, contact_geometry, slide_plan
    from moor_env.physics.statics_newton import _apply
    from moor_env.physics.statics_stages import body_root, slack_counts
    from moor_env.physics.tree import build_tree, order

    sim = _resting(segments)
    model, state = sim.records()
    body = body_root(sim)
    point, row = _contact_point(sim, segments)
    axis = sim.state.body_state[L.BS_AXIS:L.BS_AXIS + 3]
    push = point - sim.state.body_state[L.BS_POS:L.BS_POS + 3]
    push -= (push @ axis) * axis
    shift = 2e-3 * push / np.linalg.norm(push)
    sim.state.body_state[L.BS_POS:L.BS_POS + 3] += shift
    sim.state.node_pos[body] += shift
    sim.env_f[L.EF_SLACK_SMOOTHING] = 1e-8

    nn, ns = sim.state.node_pos.shape[0], sim.state.seg_i.shape[0]
    tree, orow = state.pos0.view(np.int64), state.vel0.view(np.int64)
    build_tree(body, state.node_i, state.seg_i, tree, orow)
    nq = order(body, state.node_i, state.seg_i, tree, orow)
    basis, res_body, dq = np.zeros((2, 3)), np.zeros(5), np.zeros(5)
    free = state.node_i[:, L.NI_KIND] == L.NODE_FREE

    def line_loads():
        system.residual(model, state, body, basis, res_body)
        return state.node_force[free].copy()

    f0 = line_loads()
    scratch = system.new_scratch(nn, ns)
    dmat, coupling, taut, node_down, geo, cand, cin, bmat, cmat, coupled, body_a, body_r, blocks = scratch[:13]
    seg = sim.state.seg_i
    length = np.linalg.norm(sim.state.node_pos[seg[:, L.SI_B]] - sim.state.node_pos[seg[:, L.SI_A]], axis=1)
    taut[:] = (length > sim.state.seg_f[:, L.SF_L0]) | (slack_counts(sim.state, False) < system.SLACK_PATIENCE)
    node_down[:] = sim.state.node_pos[:, 2] <= -sim.env_f[L.EF_DEPTH]
    assert contact_geometry(basis, model, state, geo, cand, cin) > 0 and cin[row] == 1
    model.contact_f[L.CF_TURNING] = 1.0 if turning else 0.0
    assemble_lines(True, model, state, taut, coupling, orow, blocks[0], scratch[13:])
    assemble_diagonal(1e-24, body, model, state, node_down, dmat, orow, scratch[13:])
    add_contact_blocks(model, state, geo, cand, cin, dmat, coupling, bmat, cmat, coupled, body_a, body_r)
    system.eliminate(1e-24, nq, body, basis, res_body, dq, model, state, dmat, coupling, tree, orow, True, bmat,
                     cmat, coupled, body_a, body_r, blocks)
    assert np.abs(f0).max() > 1e5  # the push loads the line
    eps = 1e-3
    plan = np.zeros((nn, 2))
    planned = slide_plan(basis, model, state, dq, *system.new_scratch(nn, ns)[4:7], plan)
    _apply(eps, nq, body, basis, dq, model, state, np.zeros(3), state.node_pos.copy(), tree, orow, plan, planned)
    change = line_loads() - f0
    assert np.linalg.norm(change + eps * f0) < (0.03 if segments else 0.02) * eps * np.linalg.norm(f0)


@pytest.mark.parametrize("slide", [True, False])
def test_a_step_slides_a_resting_node_along_the_shaft(slide):
    """A Newton step that moves the resting node 5 mm round the shaft (radius rho 0.6 m) keeps it at its depth
    (the linear model's prediction: no change along the normal) within 1e-9 m when it is placed on the surface
    (``statics_contact.slide_on_surface``); moved along the tangent instead it would leave the surface by
    s^2 / (2 rho) = 21 um, more than its resting depth, and lose its contact force. (The segments' contact off,
    so that the loop rests on the shaft at a node.)"""
    from moor_env.physics.anchor_surface import surface_distance
    from moor_env.physics.statics_contact import N_GEO, slide_plan
    from moor_env.physics.statics_newton import _apply
    from moor_env.physics.statics_stages import body_root
    from moor_env.physics.tree import build_tree, order

    sim = _resting(segments=False)
    model, state = sim.records()
    body = body_root(sim)
    nn = state.node_pos.shape[0]
    node = int(np.argmax([anchor_intrusion_depth(sim, n) for n in range(nn)]))
    depth0 = anchor_intrusion_depth(sim, node)
    bs = state.body_state
    normal = np.array(surface_distance(*state.node_pos[node], bs, model.contact_shape)[1:4])
    tangent = np.cross(bs[L.BS_AXIS:L.BS_AXIS + 3], normal)
    tree, orow = state.pos0.view(np.int64), state.vel0.view(np.int64)
    build_tree(body, state.node_i, state.seg_i, tree, orow)
    nq = order(body, state.node_i, state.seg_i, tree, orow)
    basis, dq = np.zeros((2, 3)), np.zeros(5)
    state.node_acc[:] = 0.0
    state.node_acc[node] = 5e-3 * tangent / np.linalg.norm(tangent)
    plan = np.zeros((nn, 2))
    planned = slide_plan(basis, model, state, dq, np.zeros((nn, N_GEO)), np.zeros(nn, np.int64),
                         np.zeros(nn, np.int64), plan)
    assert planned >= 1 and plan[node, 0] == depth0 and abs(plan[node, 1]) < 1e-12
    _apply(1.0, nq, body, basis, dq, model, state, np.zeros(3), state.node_pos.copy(), tree, orow, plan,
           planned if slide else 0)
    depth = -surface_distance(*state.node_pos[node], bs, model.contact_shape)[0]
    if slide:
        assert depth == pytest.approx(depth0, abs=1e-9)
    else:
        assert depth < depth0 - 1.5e-5 and depth < 0.0


def anchor_intrusion_depth(sim, node: int) -> float:
    """How deep free node ``node`` lies inside the anchor [m] (0 outside or not free)."""
    from moor_env.physics.anchor_surface import surface_distance

    if sim.state.node_i[node, L.NI_KIND] != L.NODE_FREE:
        return 0.0
    p = sim.state.node_pos[node]
    return max(0.0, -surface_distance(p[0], p[1], p[2], sim.state.body_state, sim.model.contact_shape)[0])


def test_unsolved_with_a_line_on_the_anchor_names_the_spacing(monkeypatch):
    """Mechanism: where Newton's method does not converge with a line resting on the anchor (the current stage
    replaced here by one that gives up), the solve stops with StaticsNotConverged naming the vessel spacing, and
    the relaxation fallback is not run."""
    import moor_env.physics.statics as statics
    from moor_env.physics import statics_relaxation
    from moor_env.physics.statics_newton import C_STATUS, STATUS_RUNNING

    def give_up(stage, *args):
        stage.ctl[C_STATUS] = STATUS_RUNNING
        return False

    monkeypatch.setattr(statics, "apply_current", give_up)
    monkeypatch.setattr(statics_relaxation, "solve_equilibrium", lambda *a, **k: pytest.fail("the fallback ran"))
    with pytest.raises(StaticsNotConverged, match="installation.vessel_spacing_m"):
        solve_statics(load_scene("gjoa-500", RESTING[2]), progress=False)


def test_contact_too_soft_to_hold_the_loop_is_refused():
    """A contact 1e5 times softer than chosen lets the resting loop press 12 cm into the anchor, more than the
    5 cm accepted: the equilibrium is refused with the stiffness scale named."""
    with pytest.raises(NoEquilibrium) as info:
        solve_statics(load_scene("gjoa-500", {**RESTING[0], "discretization.contact_stiffness_scale": 1e-5}),
                      progress=False)
    assert info.value.key == "discretization.contact_stiffness_scale"
    assert "into the anchor" in info.value.cause


def test_clearance_check_after_each_solver():
    """The lines' equilibrium without the contact hangs the loop 0.4 m through the anchor (vessels 0 m apart): from
    the relaxation solver, which leaves the contact out, that is a StaticsNotConverged naming the spacing; from
    Newton's method, which solves the contact, it would mean a contact too soft (NoEquilibrium naming its
    stiffness scale)."""
    from moor_env import Simulator
    from moor_env.compile import compile_scene
    from moor_env.physics.statics import solve_newton
    from moor_env.physics.statics_checks import check_anchor_clearance

    sim = Simulator(compile_scene(load_scene("gjoa-500", RESTING[0])))
    solve_newton(sim, progress=False, contact=False)
    assert anchor_intrusion(sim)[0] > ANCHOR_CLEARANCE_M
    with pytest.raises(StaticsNotConverged, match="installation.vessel_spacing_m") as info:
        check_anchor_clearance(sim, "relaxation")
    assert info.value.line_on_anchor
    with pytest.raises(NoEquilibrium) as refused:
        check_anchor_clearance(sim, "newton")
    assert refused.value.key == "discretization.contact_stiffness_scale"


@pytest.mark.parametrize("inside", [False, True])
def test_failed_solve_is_repeated_with_the_contact_only_where_a_line_met_the_anchor(monkeypatch, inside):
    """Where the solve without the contact does not converge, the contact problem is solved from the start only
    where a line lay inside the anchor at that solve's start or end (``StaticsNotConverged.inside_anchor``);
    otherwise the failure is raised as it is (with the contact the solve would take the same steps)."""
    from moor_env import Simulator, compile_scene
    from moor_env.physics import statics

    calls = []

    def newton(sim, contact=True, **kwargs):
        calls.append(contact)
        if not contact:
            raise StaticsNotConverged("stalled", 1.0, inside_anchor=inside)
        return statics.StaticsReport(1, 0.0, 0.0, 1, "newton")

    monkeypatch.setattr(statics, "solve_newton", newton)
    sim = Simulator(compile_scene(load_scene("gjoa-500", {"vessel_spacing_m": 0.0, "fidelity": "fast"})))
    if inside:
        assert statics.solve_equilibrium(sim, method="newton", progress=False).iterations == 1
        assert calls == [False, True]
    else:
        with pytest.raises(StaticsNotConverged, match="stalled"):
            statics.solve_equilibrium(sim, method="newton", progress=False)
        assert calls == [False]


def test_a_contact_that_would_pull_leaves_the_set():
    """Once the predicted set has settled, a contact outside the anchor now and still outside at the step's end
    leaves it (its linearised force there would pull the line onto the anchor); one inside now (even where the step
    carries it out), one the step carries inside and one not in the set are left as they are; a segment's row
    (its deepest point moved by its nodes' shares) is judged alike."""
    from moor_env.physics.statics_contact import G_DEPTH, G_NORMAL, G_SHARE, release_pulling
    from moor_env.physics.statics_system import new_scratch
    from moor_env.simulator import Simulator

    _, state = Simulator(compile_scene(load_scene("gjoa-500", {"fidelity": "fast"}))).records()
    nn, ns = state.node_pos.shape[0], state.seg_i.shape[0]
    geo, cand, cin = new_scratch(nn, ns)[4:7]
    state.node_acc[:] = 0.0
    seg = int(np.nonzero(state.seg_i[:, L.SI_ACTIVE])[0][0])
    a, b = state.seg_i[seg, L.SI_A], state.seg_i[seg, L.SI_B]
    rows = np.array([a, b, 2, 3, nn + seg])
    rows[2:4] = [n for n in range(nn) if n not in (a, b)][:2]
    cand[rows] = 1
    cin[rows] = (1, 1, 1, 0, 1)
    geo[rows, G_DEPTH] = (-1e-3, 1e-3, -1e-3, -1e-3, -1e-3)  # outside, inside, outside, outside, outside [m]
    geo[rows, G_NORMAL] = 1.0
    geo[nn + seg, G_NORMAL] = -1.0  # the segment's normal opposes its node b's move
    geo[nn + seg, G_SHARE] = 0.25  # node a's share of its deepest point
    state.node_acc[b, 0] = 2e-3  # carries row b (inside now) 1 mm outside, the segment's point 1.5 mm inside
    state.node_acc[rows[2], 0] = -2e-3  # carries row 2 1 mm inside
    assert release_pulling(state, np.zeros(5), geo, cand, cin) == 1
    assert list(cin[rows]) == [0, 1, 1, 0, 1]


# drawn by the statics benchmark: 8 m apart in 418 m, a 29 m vertical chain, in current; the loop's chain hangs over
# the back end's rim and down the shaft, a few millimetres clear of it, free to slide round the anchor's axis
OVER_THE_RIM = {"water_depth_m": 418.343, "vessel_spacing_m": 8.185, "mooring_line_length_m": 519.5,
                "vertical_chain_length_m": 29.053, "drop_height_m": 79.56, "current_scale": 0.409,
                "current_direction_deg": 155.957, "anchor_mass_scale": 0.927, "fidelity": "fast"}


def test_a_creeping_stage_takes_the_turning_of_the_normal(monkeypatch):
    """A solve's last stage that still runs after ``TURNING_AFTER`` iterations, its residual below ``TURNING_BELOW``,
    takes the turning of the segment contacts' normals round the anchor's axis: the loop over the back end's rim
    (``OVER_THE_RIM``) then converges in a few hundred iterations in all, where without it the solve creeps for over
    a thousand; both end within the solver's tolerance (1e-4 of a node's weight) at nearly the same state: release
    point within 1 mm, anchor within 5 mm (the creeping solve stops where its residual is within tolerance, short of
    the rest state in the direction round the axis, which the residual barely resists); the switch is off again after
    every stage."""
    from moor_env.physics import statics_stages

    scene = load_scene("gjoa-500", OVER_THE_RIM)
    turning = solve_statics(scene, progress=False, method="newton")
    monkeypatch.setattr(statics_stages, "TURNING_AFTER", 10**9)
    creeping = solve_statics(scene, progress=False, method="newton")
    assert turning.iterations < 400 < 1000 < creeping.iterations and 3 * turning.iterations < creeping.iterations
    assert _residual_ratio(turning) < 1e-4 and _residual_ratio(creeping) < 1e-4
    assert np.linalg.norm(np.subtract(turning.release_point_m, creeping.release_point_m)) < 1e-3
    body_a, body_b = (s.simulator.state.body_state[L.BS_POS:L.BS_POS + 3] for s in (turning, creeping))
    assert np.linalg.norm(body_a - body_b) < 5e-3
    assert turning.simulator.model.contact_f[L.CF_TURNING] == 0.0
    assert turning.simulator.work.contact_out[L.CO_SEGMENTS] >= 1

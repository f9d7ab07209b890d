"""The linearly implicit integrator ``implicit_euler``: agreement with the explicit reference, stability far
beyond the explicit limit, its O(N) tree solver against a dense solve, energy, payout and blow-up detection.

References are computed here with the explicit symplectic Euler at its default (stability-limited) step, so the
tolerances below bound the implicit scheme's own error, not the model's.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from moor_env import SimulationDiverged, load_scene, simulate_drop, solve_statics
from moor_env.compile import compile_scene
from moor_env.config import scene_dict, scene_from_dict
from moor_env.physics import implicit as I
from moor_env.physics import implicit_active_set as S
from moor_env.physics import layout as L
from moor_env.physics import tree as T
from moor_env.physics.implicit_assembly import assemble
from moor_env.physics.integrate import compute_loads
from moor_env.physics.line import segment_damping_n_s_m
from moor_env.physics.records import ModelRecord, StateRecord
from moor_env.simulation import run_drop

IMPLICIT = {"integrator": "implicit_euler"}
WIDE = {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0}


@functools.cache
def _explicit(scene: str, items: tuple) -> object:
    return simulate_drop(scene, dict(items), history=False)


@pytest.mark.parametrize(
    ("scene", "overrides", "speed_rel", "tilt_deg"),
    [
        ("gjoa-500", {}, 0.01, 0.5),
        ("gjoa-500", WIDE, 0.015, 0.5),
        ("vertical-chain", {"chain_cd_tangential": 0.4456}, 0.01, 0.5),
    ],
    ids=["gjoa-500", "spacing-170-vertical-10", "vertical-chain-dnv-drag"],
)
def test_touchdown_agrees_with_explicit_reference(scene, overrides, speed_rel, tilt_deg):
    """Reference: symplectic Euler at its stability limit (~0.34 ms). implicit_euler at its default step
    (11.25 ms for 1 m chain, 33x larger): speed within 1 % (1.5 % for the wide loop, whose tilt builds up from
    the loop's snap), tilt within 0.5 deg (measured: 0.09 %, 0.27 % / 0.09 deg, 0.00 %)."""
    ref = _explicit(scene, tuple(sorted(overrides.items())))
    result = simulate_drop(scene, dict(overrides, **IMPLICIT), history=False)
    assert result.status == "touchdown"
    assert result.dt_s > 25 * ref.dt_s
    assert result.touchdown_speed_m_s == pytest.approx(ref.touchdown_speed_m_s, rel=speed_rel)
    assert abs(result.tilt_deg - ref.tilt_deg) < tilt_deg


def test_anchor_only_is_the_explicit_step():
    """With no line the implicit step reduces to symplectic Euler on the anchor: identical results."""
    ref = simulate_drop("anchor-only", history=False)
    result = simulate_drop("anchor-only", IMPLICIT, history=False)
    assert result.touchdown_speed_m_s == ref.touchdown_speed_m_s
    assert result.touchdown_time_s == ref.touchdown_time_s


@pytest.mark.parametrize("scene", ["gjoa-500", "vertical-chain"])
def test_stable_at_100_times_the_explicit_limit(scene):
    """The axial mode no longer limits the step: at 100x the explicit stability limit (~37 ms, 3x the
    implicit default cap, set directly on the simulator) the fall completes, nothing is non-finite and the
    touchdown speed is within 2 % of the explicit reference (measured: 0.1 %, 0.0 %)."""
    explicit_limit = compile_scene(load_scene(scene)).dt_limit_s
    sim = solve_statics(load_scene(scene, IMPLICIT)).simulator
    sim.dt = 100.0 * explicit_limit
    result = run_drop(sim, history=False)
    assert result.status == "touchdown"
    assert np.all(np.isfinite(sim.state.node_pos)) and np.all(np.isfinite(sim.state.body_state))
    assert result.touchdown_speed_m_s == pytest.approx(_explicit(scene, ()).touchdown_speed_m_s, rel=0.02)


def test_default_step_and_what_governs_it():
    """The default step is set by the segment rotation per step (0.5 of the shortest segment at 40 m/s, an
    accuracy cap, times dt_safety), not by the axial mode; requests are accepted up to 3x the cap (measured
    stable there) and refused beyond, like the explicit integrators' limits."""
    model = compile_scene(load_scene("gjoa-500", IMPLICIT))
    cap = 0.5 * 1.0 / 40.0
    assert model.dt_s == pytest.approx(0.9 * cap)
    assert model.dt_limit_s == pytest.approx(3.0 * cap)
    assert "segment rotation" in model.dt_governed_by
    coarse = compile_scene(load_scene("gjoa-500", dict(IMPLICIT, **{"discretization.vertical_chain_segment_m": 2.0,
                                                                    "discretization.loop_chain_segment_m": 4.0})))
    assert coarse.dt_s == pytest.approx(0.9 * 0.5 * 2.0 / 40.0)
    assert compile_scene(load_scene("gjoa-500", dict(IMPLICIT, dt_s=0.03))).dt_s == 0.03
    with pytest.raises(ValueError, match="dt_s"):
        compile_scene(load_scene("gjoa-500", dict(IMPLICIT, dt_s=0.04)))


def test_a_closed_loop_of_lines_is_refused():
    """The O(N) solver needs a tree: a segment closing a loop between two mooring-line nodes is refused when the
    step is derived, with a message saying why."""
    from moor_env.physics.stability import stable_time_step

    model = compile_scene(load_scene("gjoa-500", IMPLICIT))
    arrays = {k: v.copy() for k, v in model.arrays().items()}
    li = arrays["line_i"][model.lines["mooring_line"].index]
    spare = li[L.LI_SEG_START] + li[L.LI_SEG_CAP] - 1
    first = li[L.LI_NODE_START]
    arrays["seg_i"][spare] = [first, first + 2, 0, 1, 1]
    with pytest.raises(ValueError, match="tree"):
        stable_time_step(arrays, "implicit_euler")


def _segment_block(s, h, st, m, w):
    """G_s = h C_s + h^2 K_s of segment s of the step's first active set, from its definition (``physics/implicit.py``):
    K_s = EA/l0 q q^T + T/len (I - q q^T), C_s = BA/l0 q q^T at the segment's present axis; zero where it is slack."""
    if w.seg_tension[s] <= 0.0:
        return np.zeros((3, 3))
    a, b, mat = st.seg_i[s, L.SI_A], st.seg_i[s, L.SI_B], st.seg_i[s, L.SI_MAT]
    chord = st.node_pos[b] - st.node_pos[a]
    length = np.linalg.norm(chord)
    q = chord / length
    kq = m.mat_f[mat, L.MF_EA] / st.seg_f[s, L.SF_L0]
    kt = w.seg_tension[s] / length
    cq = segment_damping_n_s_m(m.mat_f, mat)
    return (h * cq + h * h * (kq - kt)) * np.outer(q, q) + h * h * kt * np.eye(3)


def test_tree_solver_matches_a_dense_solve():
    """One linear solve of the step on gjoa-500 before release (three lines at the release point, the release unit
    welded to it, the anchor as root) in a disturbed state: the leaves-first block elimination with the anchor
    coupled through its back-tip node gives the dense solution of the same block system to 1e-9."""
    sim = solve_statics(load_scene("gjoa-500", IMPLICIT)).simulator
    st, m, w = sim.state, sim.model, sim.work
    rng = np.random.default_rng(7)
    free = st.node_i[:, L.NI_KIND] == L.NODE_FREE
    st.node_vel[free] += rng.normal(0.0, 0.3, (int(free.sum()), 3))
    st.body_state[L.BS_OMEGA:L.BS_OMEGA + 2] = [0.02, -0.01]
    sim.advance_to(3 * sim.dt)
    h = sim.dt
    sim.evaluate_loads()
    body_node = int(np.nonzero(st.node_i[:, L.NI_KIND] == L.NODE_BODY)[0][0])
    tree = w.pos0.view(np.int64)
    orow = w.vel0.view(np.int64)
    model, state = sim.records()
    nq = I.prepare(False, body_node, state, tree, orow)
    assemble(h, True, body_node, model, state, orow)
    diag, rhs = w.node_mm.copy(), w.node_acc.copy()
    eff = orow[:, T.OR_EFF].copy()
    unknowns = [n for n in range(st.node_i.shape[0]) if eff[n] == n and n != body_node]
    assert nq == len(unknowns)
    edges = []
    for s in np.nonzero(st.seg_i[:, L.SI_ACTIVE])[0]:
        a, b = eff[st.seg_i[s, L.SI_A]], eff[st.seg_i[s, L.SI_B]]
        if a >= 0 and b >= 0 and a != b:
            gain = _segment_block(s, h, st, m, w)
            g = w.seg_gain[s]  # the block the assembly kept for the elimination
            np.testing.assert_allclose(g[0] * np.outer(g[2:], g[2:]) + g[1] * np.eye(3), gain, rtol=1e-12,
                                       atol=1e-12 * max(np.abs(gain).max(), 1.0))
            edges.append((a, b, gain))
    I.eliminate(nq, state, tree, orow)
    corr = np.array(I.couple_body(h, body_node, model, state))
    I.back_substitute(nq, state, tree, orow)

    def sym(v):
        return np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])

    # dense system: 3 dofs per free node, then the anchor's (v_G, b = omega x e)
    index = {n: 3 * k for k, n in enumerate(unknowns)}
    nb = 3 * len(unknowns)
    e = st.body_state[L.BS_AXIS:L.BS_AXIS + 3]
    proj = np.eye(3) - np.outer(e, e)
    bf = m.body_f
    mass_b = np.block([[bf[L.BF_MASS_AXIAL] * np.outer(e, e) + bf[L.BF_M11] * proj, bf[L.BF_M12] * proj],
                       [bf[L.BF_M12] * proj, bf[L.BF_M22] * np.eye(3)]])
    jac = np.hstack([np.eye(3), st.node_f[body_node, L.NF_BODY_S] * proj])
    a_mat = np.zeros((nb + 6, nb + 6))
    b_vec = np.zeros(nb + 6)
    for n in unknowns:
        a_mat[index[n]:index[n] + 3, index[n]:index[n] + 3] = sym(diag[n])
        b_vec[index[n]:index[n] + 3] = rhs[n]
    a_mat[nb:, nb:] = mass_b + jac.T @ sym(diag[body_node]) @ jac
    u_explicit = np.concatenate([w.body_acc[:3], np.cross(w.body_acc[3:], e)])
    b_vec[nb:] = h * mass_b @ u_explicit + jac.T @ rhs[body_node]
    for a, b, g in edges:
        for x, y in ((a, b), (b, a)):
            if x == body_node:
                continue
            if y == body_node:
                a_mat[index[x]:index[x] + 3, nb:] -= g @ jac
                a_mat[nb:, index[x]:index[x] + 3] -= jac.T @ g
            else:
                a_mat[index[x]:index[x] + 3, index[y]:index[y] + 3] -= g
    dense = np.linalg.solve(a_mat, b_vec)
    solved = np.concatenate([w.node_acc[n] for n in unknowns])
    scale = np.abs(dense[:nb]).max()
    assert np.abs(solved - dense[:nb]).max() < 1e-9 * scale
    du = np.concatenate([h * (w.body_acc[:3] + corr[:3]), np.cross(h * (w.body_acc[3:] + corr[3:]), e)])
    assert np.abs(du - dense[nb:]).max() < 1e-9 * np.abs(dense[nb:]).max()
    assert np.abs(w.node_acc[body_node] - jac @ dense[nb:]).max() < 1e-9 * np.abs(dense[nb:]).max()


def test_a_later_solve_assembles_what_a_first_solve_would():
    """A step's later solve starts from the blocks its first solve kept and adds the springs of the changed active
    set: on gjoa-500 mid-fall, with a taut segment of the loop taken out of the set, its blocks and right-hand sides
    equal those of a first solve of the same set from the loads, to 1e-12 of the largest entry (round-off: the
    terms are summed in another order); the elimination reads each segment's block as that assembly left it."""
    sim = solve_statics(load_scene("gjoa-500", IMPLICIT)).simulator
    sim.release()
    sim.advance_to(sim.state.t + 1.0)
    model, state = sim.records()
    st, w, h = sim.state, sim.work, sim.dt
    body_node = int(np.nonzero(st.node_i[:, L.NI_KIND] == L.NODE_BODY)[0][0])
    tree, orow = w.pos0.view(np.int64), w.vel0.view(np.int64)
    compute_loads(model, state)
    I.prepare(False, body_node, state, tree, orow)
    assemble(h, True, body_node, model, state, orow)
    taut = [s for s in range(st.seg_i.shape[0]) if S.is_active(orow, s) and w.seg_gain[s, 1] > 0.0]
    s_out = taut[len(taut) // 2]
    S._flip(orow, s_out)
    assemble(h, False, body_node, model, state, orow)
    later = w.node_mm.copy(), w.node_acc.copy(), w.seg_gain.copy()
    compute_loads(model, state)
    assemble(h, True, body_node, model, state, orow)
    first = w.node_mm, w.node_acc, w.seg_gain
    unknowns = orow[:, T.OR_EFF] == np.arange(st.node_i.shape[0])
    for a, b in zip(later[:2], first[:2], strict=True):
        np.testing.assert_allclose(a[unknowns], b[unknowns], rtol=0.0, atol=1e-12 * np.abs(b[unknowns]).max())
    assert later[2][s_out, 0] == later[2][s_out, 1] == 0.0  # out of the set: no block in the elimination
    np.testing.assert_array_equal(later[2][:, :2], first[2][:, :2])


def test_energy_never_grows_without_dissipation():
    """Reference: exact conservation (no drag, no added mass, no internal damping; as test_energy). Backward Euler
    may only lose energy: every 0.5 s sample is below the previous one, and the loss over the 5 s fall stays under
    1 % of the energy released (measured 0.30 %)."""
    data = scene_dict("vertical-chain")
    data["installation"]["drop_height_m"] = 300.0
    data["materials"]["chain_142"].update(cd_normal=0.0, cd_tangential=0.0, ca_normal=0.0, axial_damping_ratio=0.0)
    anchor = data["anchor"]
    anchor.update(tip_drag_coefficient=0.0, back_drag_coefficient=0.0)
    anchor["sections"] = [dict(sec, cd_normal=0.0, cd_tangential=0.0, ca_normal=0.0) for sec in anchor["sections"]]
    data["discretization"] = {"integrator": "implicit_euler"}
    scene = scene_from_dict(data)
    static = solve_statics(scene)
    sim = static.simulator
    sim.release()
    energies = [sim.mechanical_energy_j()]
    for k in range(1, 11):
        sim.advance_to(0.5 * k)
        energies.append(sim.mechanical_energy_j())
    released = abs(sim.model.body_f[L.BF_WEIGHT] - sim.model.body_f[L.BF_BUOYANCY]) * (
        static.tip_height_above_seabed_m - (sim.tip_state()[0][2] + scene.environment.water_depth_m))
    assert released > 1e7
    assert np.all(np.diff(energies) <= 1e-9 * released)
    assert energies[0] - energies[-1] < 1e-2 * released


def test_payout_and_haul_in_with_the_implicit_step():
    """Payout changes the tree at the top of a line every few steps: mass = mass per metre x length exactly
    (1e-9) and the line grows; a wire hauled in to half a segment and paid out again does not blow up."""
    sim = solve_statics(load_scene("gjoa-500", IMPLICIT)).simulator
    mooring = sim.model.lines["mooring_line"].index
    length0, mass0 = sim.line_length_m("mooring_line"), sim.line_mass_kg("mooring_line")
    n0 = sim.state.line_i[mooring, L.LI_NSEG]
    sim.set_payout_rate("mooring_line", 0.8)
    steps = int(4.0 / sim.dt)
    for k in range(1, steps + 1):
        sim.advance_to(sim.state.t + sim.dt)
        assert sim.line_length_m("mooring_line") == pytest.approx(length0 + 0.8 * sim.dt * k, rel=1e-9)
        assert sim.line_mass_kg("mooring_line") == pytest.approx(mass0 + 42.5 * 0.8 * sim.dt * k, rel=1e-9)
    assert sim.state.line_i[mooring, L.LI_NSEG] > n0

    no_mooring = {"water_depth_m": 150.0, "installation.components.mooring_line": False}
    scene = load_scene("gjoa-500", dict(IMPLICIT, **no_mooring))
    sim = solve_statics(scene).simulator
    wire = sim.model.lines["wire"].index
    sim.set_payout_rate("wire", -2.0)
    sim.advance_to(12.0)
    assert sim.state.line_i[wire, L.LI_CLAMPED] == 1
    sim.set_payout_rate("wire", 2.0)
    sim.advance_to(22.0)
    assert sim.line_mass_kg("wire") == pytest.approx(24.7 * sim.line_length_m("wire"), rel=1e-12)
    assert np.all(np.isfinite(sim.state.node_pos))


def test_kept_elimination_order_equals_a_rebuilt_one():
    """Within one ``advance`` call the step keeps its elimination order until a payout split or merge changes the
    tree; a call per step rebuilds it every step. Paying one line out and hauling the other in (splits and merges
    inside the run) and then releasing, both give the same states bit for bit."""
    runs = []
    for steps_per_call in (1, 40):
        sim = solve_statics(load_scene("gjoa-500", IMPLICIT)).simulator
        sim.set_payout_rate("mooring_line", 1.5)
        sim.set_payout_rate("wire", -4.0)
        counts0 = sim.state.line_i[:, L.LI_NSEG].copy()
        for _ in range(400 // steps_per_call):
            sim.advance_to(sim.state.t + steps_per_call * sim.dt)
        counts = sim.state.line_i[:, L.LI_NSEG]
        assert counts[sim.model.lines["mooring_line"].index] > counts0[sim.model.lines["mooring_line"].index]
        assert counts[sim.model.lines["wire"].index] < counts0[sim.model.lines["wire"].index]
        sim.release()
        for _ in range(40 // steps_per_call):
            sim.advance_to(sim.state.t + steps_per_call * sim.dt)
        runs.append((sim.state.node_pos.copy(), sim.state.node_vel.copy(), sim.state.body_state.copy()))
    for a, b in zip(*runs, strict=True):
        assert np.array_equal(a, b)


def test_blow_up_is_still_detected():
    """A step far beyond the linearisation's range (40x the cap) ends in SimulationDiverged naming a line, not in
    NaN results."""
    sim = solve_statics(load_scene("gjoa-500", IMPLICIT)).simulator
    sim.release()
    sim.dt = 40.0 * sim.model.dt_limit_s
    with pytest.raises(SimulationDiverged) as info:
        sim.advance_to(10.0)
    assert "line" in info.value.component
    assert np.all(np.isfinite(sim.state.body_state))


def test_implicit_runs_are_bit_identical():
    a = simulate_drop("gjoa-500", dict(IMPLICIT, vessel_spacing_m=120.0))
    b = simulate_drop("gjoa-500", dict(IMPLICIT, vessel_spacing_m=120.0))
    assert a.touchdown_speed_m_s == b.touchdown_speed_m_s
    assert np.array_equal(a.history, b.history)


def _two_segment_column(dv_middle_z: float) -> tuple:
    """A vertical column of three nodes (top held, two free) with the arrays ``update_active_set`` reads (the
    records' other arrays empty): the upper segment slack now, the lower taut; the solved dv of the middle node is
    ``dv_middle_z`` [m/s] and the bottom node's is 0. Returns (model, state, orow)."""
    node_pos = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -0.999], [0.0, 0.0, -2.0]])
    node_vel = np.zeros((3, 3))
    seg_i = np.zeros((2, L.N_SEG_I), np.int64)
    seg_i[:, L.SI_ACTIVE] = 1
    seg_i[0, [L.SI_A, L.SI_B]] = 0, 1
    seg_i[1, [L.SI_A, L.SI_B]] = 1, 2
    seg_f = np.ones((2, L.N_SEG_F))
    mat_f = np.zeros((1, L.N_MAT_F))
    mat_f[0, L.MF_EA], mat_f[0, L.MF_MASS], mat_f[0, L.MF_ZETA] = 1e9, 400.0, 0.3
    node_acc = np.zeros((3, 3))
    node_acc[1, 2] = dv_middle_z
    orow = np.zeros((3, 3), np.int64)
    orow[:, T.OR_EFF] = -1, 1, 2
    orow[0, T.OR_FLAGS] = np.int64(1) << 2  # segment 1 taut, segment 0 slack
    model = _record(ModelRecord, mat_f=mat_f)
    state = _record(StateRecord, node_pos=node_pos, node_vel=node_vel, seg_i=seg_i, seg_f=seg_f, node_acc=node_acc,
                    seg_chord=np.zeros((2, 4)))
    return model, state, orow


def _record(cls, **arrays):
    """A record of class ``cls`` holding ``arrays``, its other fields empty arrays of their dtype and rank."""
    return cls(*(arrays.get(f.name, np.zeros((0,) * f.ndim, f.dtype)) for f in cls.FIELDS))


def test_active_set_segments_enter_before_any_leaves():
    """A solve that predicts one slack segment taut and another taut one compressed flips only the entering one;
    the leaving one goes on the next pass if it is still predicted compressed. Reference: the rule of
    ``update_active_set`` (a wrong exit, frozen for the step, blew up a hanging loop at a 0.5 s step)."""
    # the middle node moves down 0.1 m/s over 0.1 s: upper segment +1 cm (taut), lower -1 cm (compressed)
    model, state, orow = _two_segment_column(-0.1)
    h = 0.1
    assert S.update_active_set(h, model, state, orow) == 1
    assert S.is_active(orow, 0) == 1 and S.is_active(orow, 1) == 1
    assert S.update_active_set(h, model, state, orow) == 1  # no entry left: the exit is taken
    assert S.is_active(orow, 1) == 0
    assert S.update_active_set(h, model, state, orow) == 0  # both changed once: frozen for the rest of the step

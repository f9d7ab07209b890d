"""The starts of a static solve (``moor_env.simulation.solve_statics``): the first try from the guess, the coarse
and middle presets' equilibria mapped onto the fine lines, the refusals they allow and the retry with the seabed
set growing, on scenes drawn by the statics benchmark."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L

# the loop against the anchor in strong current, 1 m chain (default preset): from the statics benchmark's draws
LOOP_ON_ANCHOR_IN_CURRENT = {
    "water_depth_m": 592.692, "vessel_spacing_m": 18.152, "mooring_line_length_m": 687.902,
    "vertical_chain_length_m": 13.058, "drop_height_m": 34.754, "current_scale": 1.2458,
    "current_direction_deg": 142.986, "anchor_mass_scale": 1.0731, "fidelity": "default"}


def _largest_residual_ratio(sim) -> float:
    """Largest free-node load and the anchor's net force over their weights, on the law the solver ends on."""
    from moor_env.physics.statics import SMOOTHING_FINAL

    sim.env_f[L.EF_SLACK_SMOOTHING] = SMOOTHING_FINAL
    try:
        sim.evaluate_loads()
        free = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
        g = sim.env_f[L.EF_G]
        nodes = np.abs(sim.work.node_force[free]).max(axis=1) / (sim.work.node_mass[free] * g)
        anchor = np.abs(sim.work.body_load[:3]).max() / (sim.model.anchor_mass_kg * g)
        return float(max(nodes.max(), anchor))
    finally:
        sim.env_f[L.EF_SLACK_SMOOTHING] = 0.0


def _coarse_start(sim):
    """The coarse start of a static solve of ``sim`` (as ``solve_statics`` makes it)."""
    from moor_env.coarse_start import CoarseStart
    from moor_env.simulation import _coarse_solve

    return CoarseStart(sim, functools.partial(_coarse_solve, progress=False))


# The statics benchmark's scene 740 (seed 0), as drawn: default lines, the vessels 255 m apart in 964 m of water, strong
# current. Which start converges on such a scene depends on the last digits of the solve and on the solver's stages.
COARSE_START_SCENE = {"water_depth_m": 963.8065563356558, "vessel_spacing_m": 254.65972886540072,
                      "mooring_line_length_m": 1192.868452759057, "vertical_chain_length_m": 14.145984018490493,
                      "drop_height_m": 76.63542612061332, "current_scale": 1.274645715641486,
                      "current_direction_deg": 19.315023282564194, "anchor_mass_scale": 1.0028828163037151,
                      "fidelity": "default"}


def test_coarse_start_solves_the_fine_lines():
    """Reference: the solver's tolerance on the discrete model's residual (1e-4 of each node's weight; the anchor's
    net force within 1e-4 of its weight in air, a looser test). From the equilibrium of the scene compiled at the
    fast preset's segment lengths (2 m chain), mapped onto the 1 m chain, Newton's method converges; the release
    point moves from the coarse one by the resolution's difference only (within 0.5 m). Lines no finer than the
    coarse ones get no coarse start."""
    from moor_env import Simulator, compile_scene

    scene = load_scene("gjoa-500", COARSE_START_SCENE)
    sim = Simulator(compile_scene(scene))
    assert _coarse_start(sim).start(progress=False) is not None
    assert _largest_residual_ratio(sim) < 1e-4
    coarse = solve_statics(load_scene("gjoa-500", {**COARSE_START_SCENE, "fidelity": "fast",
                                                   "discretization.fit_to_geometry": False}),
                           progress=False, method="newton")
    release = sim.state.node_pos[sim.model.release_node]
    assert np.linalg.norm(release - np.array(coarse.release_point_m)) < 0.5
    assert _coarse_start(coarse.simulator).start(progress=False) is None


def test_coarse_start_refuses_a_fibre_the_coarse_lines_lay_on_the_seabed(monkeypatch):
    """Where the coarse compile's equilibrium lays the fibre rope on the seabed (here one node) and
    the fine lines do not converge from it, the coarse start keeps the refusal with that cause and key for after the
    next start (``pending``, None returned); with ``REFUSED_FROM_NODES`` nodes or more it raises it at once
    (NoEquilibrium) instead of returning None (which would go on to a last full solve); where the fine lines
    converge, their own equilibrium is returned."""
    from moor_env import Simulator, compile_scene
    from moor_env import coarse_start as coarse_module
    from moor_env.errors import NoEquilibrium, StaticsNotConverged

    # which start converges on such a scene depends on the solver's stages and the last digits of the solve, so a
    # change of either can call for another line length or spacing where the fine lines converge
    long_line = {"mooring_line_length_m": 702.0, "vessel_spacing_m": 57.0, "current_scale": 0.0}
    with pytest.raises(NoEquilibrium):  # the reference: the scene itself is refused for its fibre
        solve_statics(load_scene("gjoa-500", long_line), progress=False, method="newton")
    sim = Simulator(compile_scene(load_scene("gjoa-500", long_line)))
    assert _coarse_start(sim).start(progress=False) is not None

    solve = coarse_module.solve_equilibrium

    def mapped_start_stalls(*args, **kwargs):
        if kwargs.get("mapped"):
            raise StaticsNotConverged("stalled", 1.0)
        return solve(*args, **kwargs)

    monkeypatch.setattr(coarse_module, "solve_equilibrium", mapped_start_stalls)
    start = _coarse_start(Simulator(compile_scene(load_scene("gjoa-500", long_line))))
    assert start.start(progress=False) is None
    assert start.fibre_resting == 1
    assert start.pending.key == "installation.mooring_line_length_m"
    assert start.pending.cause.startswith("the fibre rope") and "fast preset" in start.pending.cause
    with pytest.raises(NoEquilibrium) as pending:  # no middle start for 1 m chain: the pending refusal is raised
        solve_statics(load_scene("gjoa-500", long_line), progress=False, method="newton")
    assert "fast preset" in pending.value.cause
    monkeypatch.setattr(coarse_module, "REFUSED_FROM_NODES", 1)
    with pytest.raises(NoEquilibrium) as raised:
        _coarse_start(Simulator(compile_scene(load_scene("gjoa-500", long_line)))).start(progress=False)
    assert raised.value.key == "installation.mooring_line_length_m"
    assert raised.value.cause.startswith("the fibre rope") and "fast preset" in raised.value.cause


# The statics benchmark's scene 423 (seed 0), rounded: its coarse equilibrium rests one fibre node on the seabed,
# its own lines hang the fibre a few centimetres clear.
ONE_COARSE_FIBRE_NODE = {"water_depth_m": 1361.78, "vessel_spacing_m": 465.83, "mooring_line_length_m": 1611.93,
                         "vertical_chain_length_m": 12.44, "drop_height_m": 50.37, "current_scale": 0.36,
                         "current_direction_deg": 133.85, "anchor_mass_scale": 0.9255, "fidelity": "default"}


def test_fibre_the_coarse_equilibrium_lays_on_the_seabed_is_refused_before_the_fine_solve(monkeypatch):
    """Reference: the fine lines' own equilibrium (solved without the refusals) rests the fibre rope on the seabed.
    With the refusals, the scene is refused from the coarse equilibrium (two or more fibre nodes on the seabed)
    without a Newton solve of the fine lines."""
    from moor_env import Simulator, compile_scene
    from moor_env import simulation as simulation_module
    from moor_env.errors import NoEquilibrium
    from moor_env.physics.statics_checks import fibre_on_seabed

    long_line = {"mooring_line_length_m": 750.0, "vessel_spacing_m": 60.0, "current_scale": 0.0}
    model = compile_scene(load_scene("gjoa-500", long_line))
    own = simulation_module._hanging_equilibrium(model, 1e-3, False, "newton", checks=False)
    assert fibre_on_seabed(own.simulator)[0] >= 2
    fine_nodes = model.node_i.shape[0]
    solve = simulation_module.solve_equilibrium

    def not_on_the_fine_lines(sim: Simulator, **kwargs):
        assert sim.model.node_i.shape[0] != fine_nodes, "the fine lines were solved"
        return solve(sim, **kwargs)

    monkeypatch.setattr(simulation_module, "solve_equilibrium", not_on_the_fine_lines)
    _without_seabed_probe(monkeypatch)  # which refuses this scene first (tests/test_coarse_start.py)
    with pytest.raises(NoEquilibrium) as refused:
        solve_statics(compile_scene(load_scene("gjoa-500", long_line)), progress=False)
    assert refused.value.key == "installation.mooring_line_length_m"
    assert "of its nodes on it" in refused.value.cause and "fast preset" in refused.value.cause


def _without_seabed_probe(monkeypatch) -> None:
    """The coarse start's refusal from the equilibrium with the seabed bearing no fibre off, for a test of the
    refusals after it."""
    from moor_env.coarse_start import CoarseStart

    monkeypatch.setattr(CoarseStart, "_fibre_dip_through_seabed", lambda self: None)


def test_one_coarse_fibre_node_on_the_seabed_does_not_refuse_the_scene():
    """A scene whose first guess lays the fibre rope near the seabed and whose coarse equilibrium rests one fibre
    node on it is solved on its own lines, and there the fibre hangs clear of the seabed (the reference: the fine
    equilibrium's lowest fibre node, above 0 m)."""
    from moor_env import Simulator, compile_scene
    from moor_env.coarse_start import GUESS_NEAR_SEABED_M
    from moor_env.physics.statics_checks import fibre_on_seabed
    from moor_env.physics.statics_guess import first_guess

    model = compile_scene(load_scene("gjoa-500", ONE_COARSE_FIBRE_NODE))
    guess = Simulator(model)
    first_guess(guess)
    assert fibre_on_seabed(guess)[1] <= GUESS_NEAR_SEABED_M
    coarse = _coarse_start(Simulator(model)).equilibrium()
    assert fibre_on_seabed(coarse.simulator)[0] == 1
    result = solve_statics(model, progress=False)
    resting, lowest_m = fibre_on_seabed(result.simulator)
    assert resting == 0 and 0.0 < lowest_m < 0.5


# The statics benchmark's scene 623 (seed 0), rounded: the fast preset's equilibrium rests one fibre node 0.1 mm
# into the seabed, the default preset's hangs the fibre 6 cm clear, and the lines (fast preset fitted to a 0.5 m
# loop chain) converge from neither within their budgets but from the first guess in 224 iterations.
FIBRE_BARELY_ON_THE_SEABED = {"water_depth_m": 1131.22, "vessel_spacing_m": 323.57, "mooring_line_length_m": 1365.45,
                              "vertical_chain_length_m": 6.5, "drop_height_m": 89.8, "current_scale": 1.05,
                              "current_direction_deg": 330.86, "anchor_mass_scale": 0.91, "fidelity": "fast"}


def test_fibre_the_middle_preset_hangs_clear_is_not_refused():
    """Reference: the scene's own lines solved from the first guess without the refusals (Newton's method, 3000
    iterations) hang the fibre rope clear of the seabed. ``solve_statics`` solves it too (no NoEquilibrium from the
    fast preset's one resting node, which the default preset's equilibrium overrules), with the fibre clear."""
    from moor_env import Simulator, compile_scene
    from moor_env.physics.statics import solve_equilibrium
    from moor_env.physics.statics_checks import fibre_on_seabed

    model = compile_scene(load_scene("gjoa-500", FIBRE_BARELY_ON_THE_SEABED))
    own = Simulator(model)
    solve_equilibrium(own, progress=False, method="newton", max_iter=3000)
    assert fibre_on_seabed(own)[0] == 0
    assert fibre_on_seabed(_coarse_start(Simulator(model)).equilibrium().simulator)[0] == 1
    result = solve_statics(model, progress=False)
    resting, lowest_m = fibre_on_seabed(result.simulator)
    assert resting == 0 and 0.0 < lowest_m < 0.5


# The statics benchmark's scene 717 (seed 0), rounded: in strong current its coarse equilibrium needs more than 400
# iterations of the current's increments, and rests the fibre rope on the seabed.
CURRENT_IN_LONG_INCREMENTS = {"water_depth_m": 1447.57, "vessel_spacing_m": 623.08, "mooring_line_length_m": 1846.38,
                              "vertical_chain_length_m": 40.19, "drop_height_m": 52.87, "current_scale": 1.229,
                              "current_direction_deg": 296.29, "anchor_mass_scale": 1.0305, "fidelity": "default"}


def test_scene_whose_current_takes_long_increments_is_refused_without_the_fallback(monkeypatch):
    """Reference: the relaxation fallback refuses the unrounded scene for its fibre on the seabed (the statics
    benchmark, 58 s). With the current's increments given ``INCREMENT_ITERATIONS`` before the long stage, Newton's
    method reaches the coarse equilibrium and the scene is refused from it for the same cause (``method="auto"``,
    the fallback never runs)."""
    from moor_env.errors import NoEquilibrium
    from moor_env.physics import statics_relaxation

    monkeypatch.setattr(statics_relaxation, "solve_equilibrium", lambda *a, **k: pytest.fail("the fallback ran"))
    _without_seabed_probe(monkeypatch)  # which refuses this scene before the coarse equilibrium
    with pytest.raises(NoEquilibrium) as refused:
        solve_statics(load_scene("gjoa-500", CURRENT_IN_LONG_INCREMENTS), progress=False)
    assert refused.value.key == "installation.mooring_line_length_m"
    assert refused.value.cause.startswith("the fibre rope would rest on the seabed")
    assert "fast preset" in refused.value.cause


def test_first_try_from_the_guess_made_before_it_is_the_solve_from_the_guess():
    """``solve_statics`` makes the first guess itself (to look at the fibre) and starts the first Newton try from
    it without a new guess; reference: the solve that makes its own guess, on a scene in current with the loop
    resting on the anchor (the contact solve restarts from the start state). Iterations (or, where Newton's method
    stops short of the tolerance, the failure's message: iterations and residual) and node positions agree bit for
    bit. Whether this scene converges within the iterations depends on the last digits of the solve (the
    linear-algebra libraries' among them); that the two starts take the same path does not."""
    from moor_env import Simulator, compile_scene
    from moor_env.errors import StaticsNotConverged
    from moor_env.physics.statics import solve_equilibrium
    from moor_env.physics.statics_guess import first_guess

    def outcome(sim, **options):
        try:
            return solve_equilibrium(sim, progress=False, method="newton", **options).iterations
        except StaticsNotConverged as exc:
            return str(exc)

    model = compile_scene(load_scene("gjoa-500", LOOP_ON_ANCHOR_IN_CURRENT))
    own = Simulator(model)
    own_outcome = outcome(own)
    given = Simulator(model)
    first_guess(given)
    assert outcome(given, analytic_guess=False) == own_outcome
    assert np.array_equal(given.state.node_pos, own.state.node_pos)
    assert np.array_equal(given.state.body_state, own.state.body_state)


# The statics benchmark's scene 953 (seed 0), as drawn: fast preset fitted to the tight loop (0.5 m loop chain),
# the vessels 149 m apart in 987 m of water, strong current. Which start converges on such a scene depends on the last
# digits of the solve and on the solver's stages, so a change of either can call for another of the benchmark's
# scenes whose fast start fails. With the Newton steps' seabed set releasing the nodes a later solve lifts, no scene of
# the statics benchmark needs the default preset's start; with the set only growing (``seabed_set_grows``, the rule
# ``solve_statics`` retries an unsolved scene with), this one does, and the tests of that start run it so.
MIDDLE_START_SCENE = {"water_depth_m": 987.0481212000599, "vessel_spacing_m": 148.5188510787858,
                      "mooring_line_length_m": 1112.692231130019, "vertical_chain_length_m": 9.01042375360517,
                      "drop_height_m": 54.260466755347494, "current_scale": 1.3421137143341721,
                      "current_direction_deg": 76.76771449064344, "anchor_mass_scale": 0.9268851241965204,
                      "fidelity": "fast"}


def test_middle_start_solves_lines_the_fast_start_does_not():
    """Reference: the solver's tolerance on the discrete model's residual (1e-4 of each node's weight). On this
    scene, with the seabed set only growing, Newton's method does not converge from the fast preset's equilibrium
    mapped onto the scene's finer lines; from the default preset's it does, and ``solve_statics`` finds the
    equilibrium that way."""
    from moor_env import Simulator, compile_scene
    from moor_env.coarse_start import MIDDLE_PRESET, CoarseStart
    from moor_env.physics.statics import seabed_set_grows
    from moor_env.simulation import _coarse_solve

    with seabed_set_grows():
        model = compile_scene(load_scene("gjoa-500", MIDDLE_START_SCENE))
        assert _coarse_start(Simulator(model)).start(progress=False) is None
        sim = Simulator(model)
        middle = CoarseStart(sim, functools.partial(_coarse_solve, progress=False), MIDDLE_PRESET)
        assert middle.start(False) is not None
        assert _largest_residual_ratio(sim) < 1e-4
        result = solve_statics(model, progress=False)
        assert _largest_residual_ratio(result.simulator) < 1e-4


# The statics benchmark's scene 306 (seed 0), as drawn: default lines, the vessels 4.4 m apart in 1153 m of water,
# current 0.53. Like the scene above, which start converges depends on the last digits of the solve.
SOFTENED_START_SCENE = {"water_depth_m": 1152.750432296554, "vessel_spacing_m": 4.447825945775667,
                        "mooring_line_length_m": 1270.924536413232, "vertical_chain_length_m": 53.92111596418069,
                        "drop_height_m": 94.99920667039794, "current_scale": 0.5279093416835225,
                        "current_direction_deg": 201.81462124119798, "anchor_mass_scale": 1.0238357253902173,
                        "fidelity": "default"}


def test_mapped_start_converges_with_the_slack_law_softened_first(monkeypatch):
    """Reference: the solver's tolerance on the discrete model's residual (1e-4 of each node's weight). On this
    scene Newton's method does not converge from the first guess within its first budget and starts again from the
    fast preset's equilibrium mapped onto the default lines; that start is solved with the tension-only law's kink
    rounded more in the first stages (``statics_stages.soften_slack``), which converges by itself (the solve
    without them is not needed), and the rounding ends with the solve."""
    from moor_env import compile_scene
    from moor_env.physics import statics

    softened = []
    solve = statics._softened

    def spy(sim, start, args):
        report = solve(sim, start, args)
        softened.append((report, statics.seabed_set_releases()))
        return report

    monkeypatch.setattr(statics, "_softened", spy)
    result = solve_statics(compile_scene(load_scene("gjoa-500", SOFTENED_START_SCENE)), progress=False)
    assert _largest_residual_ratio(result.simulator) < 1e-4
    assert result.simulator.env_f[L.EF_SLACK_SMOOTHING] == 0.0  # the rounding ends with the solve
    assert softened and softened[-1][0] is not None and softened[-1][0].method == "newton"
    assert all(releases for _, releases in softened)  # solved so at the first attempt, not by the retry


# The statics benchmark's scene 791 (seed 0), as drawn: default lines, a long mooring line whose fibre rope the
# coarse equilibrium rests on the seabed (8 nodes) with the anchor tip 1.2 cm from its drop height before the
# drop-height corrections.
FIBRE_RESTING_BEFORE_CORRECTIONS = {"water_depth_m": 1210.8661203175666, "vessel_spacing_m": 125.86818232930739,
                                    "mooring_line_length_m": 1500.5177265448333,
                                    "vertical_chain_length_m": 15.372646723259168, "drop_height_m": 76.66947682093799,
                                    "current_scale": 0.2589837319400325, "current_direction_deg": 159.37689695691708,
                                    "anchor_mass_scale": 0.9096028223065737, "fidelity": "default"}


def test_coarse_equilibrium_resting_its_fibre_skips_the_drop_height_corrections():
    """Reference: the coarse compile's equilibrium with its drop-height corrections (the tip within 1 mm of its drop
    height) rests two or more fibre nodes on the seabed. The coarse start's solve keeps the equilibrium before the
    corrections (the tip still more than 1 mm off, fewer iterations), and it rests as many fibre nodes."""
    from moor_env import compile_scene
    from moor_env.coarse_start import REFUSED_FROM_NODES, coarse_keys
    from moor_env.physics.statics_checks import fibre_on_seabed
    from moor_env.simulation import _adjust_to_drop_height, _coarse_solve, _hanging_equilibrium

    scene = load_scene("gjoa-500", FIBRE_RESTING_BEFORE_CORRECTIONS)
    keys = coarse_keys(compile_scene(scene))
    coarse = compile_scene(scene.model_copy(update={"discretization": scene.discretization.model_copy(update=keys)}))
    target_z = -scene.environment.water_depth_m + scene.installation.drop_height_m
    corrected = _hanging_equilibrium(coarse, 1e-3, False, "newton", checks=False)
    assert abs(_adjust_to_drop_height(corrected.simulator, target_z)) < 1e-3
    resting = fibre_on_seabed(corrected.simulator)[0]
    assert resting >= REFUSED_FROM_NODES
    settled = _coarse_solve(coarse, progress=False)
    assert abs(_adjust_to_drop_height(settled.simulator, target_z)) > 1e-3
    assert settled.iterations < corrected.iterations
    assert fibre_on_seabed(settled.simulator)[0] == resting


# The statics benchmark's scene 953 (seed 0), as drawn: the fast preset fitted to a 0.5 m loop chain, the loop
# against the anchor in strong current. Like the scenes above, which start converges depends on the last digits of
# the solve.
FAST_START_BEFORE_THE_MIDDLE = {"water_depth_m": 987.0481212000599, "vessel_spacing_m": 148.5188510787858,
                                "mooring_line_length_m": 1112.692231130019, "vertical_chain_length_m": 9.01042375360517,
                                "drop_height_m": 54.260466755347494, "current_scale": 1.3421137143341721,
                                "current_direction_deg": 76.76771449064344, "anchor_mass_scale": 0.9268851241965204,
                                "fidelity": "fast"}


def test_fast_start_gets_its_softened_try_only_where_the_middle_start_follows(monkeypatch):
    """Reference: the solver's tolerance on the discrete model's residual (1e-4 of each node's weight). The fine
    lines' solve from the fast preset's equilibrium, with the default preset's start to follow, makes the softened
    try only (no full-budget solve without the rounding), and ``solve_statics`` converges on this scene through the
    default preset's start."""
    from moor_env import Simulator, compile_scene
    from moor_env.coarse_start import MIDDLE_PRESET, coarse_keys
    from moor_env.physics import statics
    from moor_env.physics.statics import seabed_set_grows

    with seabed_set_grows():
        model = compile_scene(load_scene("gjoa-500", FAST_START_BEFORE_THE_MIDDLE))
        assert coarse_keys(model, MIDDLE_PRESET) is not None
        softened = []
        solve = statics._by_newton

        def spy(sim, start, method, args):
            if sim.model is model:  # the fine lines' solves, not the coarse equilibrium's own
                softened.append(args["soften"])
            return solve(sim, start, method, args)

        monkeypatch.setattr(statics, "_by_newton", spy)
        assert _coarse_start(Simulator(model)).start(progress=False, softened_only=True) is None
        assert softened == [True]
        monkeypatch.undo()
        result = solve_statics(model, progress=False)
        assert _largest_residual_ratio(result.simulator) < 1e-4


def test_middle_start_shares_the_fast_equilibrium_and_starts_without_the_softening(monkeypatch):
    """Reference: the solver's tolerance on the discrete model's residual (1e-4 of each node's weight). On this
    scene the fine lines converge from neither the first guess nor the fast preset's equilibrium; the default
    preset's lines, their next start, take the fast preset's equilibrium already solved (the fast preset's compile
    is solved once, not again for them, and they are not tried from the first guess) and the fine lines' solve
    from the default preset's equilibrium converges in its first try, without the softened stages."""
    from moor_env import compile_scene
    from moor_env import simulation as simulation_module
    from moor_env.physics import statics
    from moor_env.physics.statics import seabed_set_grows

    with seabed_set_grows():
        model = compile_scene(load_scene("gjoa-500", FAST_START_BEFORE_THE_MIDDLE))
        compiles, mapped, middle_from_guess = [], [], []
        coarse_solve = simulation_module._coarse_solve
        by_newton = statics._by_newton

        def count_compiles(coarse_model, *args, **kwargs):
            compiles.append(coarse_model.scene.discretization.loop_chain_segment_m)
            return coarse_solve(coarse_model, *args, **kwargs)

        def spy(sim, start, method, args):
            if sim.model is model and args["mapped"]:
                mapped.append(args["soften"])
            if sim.model.scene.discretization.loop_chain_segment_m == 1.0 and not (args["mapped"] or args["warm"]):
                middle_from_guess.append(args["max_iter"])
            return by_newton(sim, start, method, args)

        monkeypatch.setattr(simulation_module, "_coarse_solve", count_compiles)
        monkeypatch.setattr(statics, "_by_newton", spy)
        result = solve_statics(model, progress=False)
        assert compiles == [2.0, 1.0]  # the fast preset's loop chain once, then the default preset's
        assert mapped == [True, False]  # from the fast preset's equilibrium softened, from the default's as it is
        assert middle_from_guess == []
        assert _largest_residual_ratio(result.simulator) < 1e-4


# The statics benchmark's scene 903 (seed 0), as drawn: fast lines, the vessels 10 m apart in 1101 m of water, a long
# mooring line, strong current. Like the scenes above, which rule solves it depends on the last digits of the solve.
RETRIED_WITH_THE_GROWING_SEABED_SET = {"water_depth_m": 1101.1614288158823, "vessel_spacing_m": 10.464257804553384,
                                       "mooring_line_length_m": 1408.7710732370308,
                                       "vertical_chain_length_m": 53.99714254227857,
                                       "drop_height_m": 41.552139770963976, "current_scale": 1.3682001361009521,
                                       "current_direction_deg": 72.96108949208447,
                                       "anchor_mass_scale": 1.0033647734443998, "fidelity": "fast"}


def test_unsolved_scene_is_solved_again_with_the_seabed_set_growing(monkeypatch):
    """Reference: the scene's cause (its fibre rope rests on the seabed in the equilibrium). With the Newton steps'
    seabed set releasing the nodes a later solve lifts this scene does not converge; ``solve_statics`` solves it
    again with the set only growing (before the relaxation of ``method="auto"``), which reaches the equilibrium and
    refuses the scene for its fibre."""
    from moor_env import simulation as simulation_module
    from moor_env.errors import NoEquilibrium, StaticsNotConverged
    from moor_env.physics import statics

    tries = []
    hanging = simulation_module._hanging_equilibrium

    def spy(model, tol_m, progress, method, **kwargs):
        tries.append((statics.seabed_set_releases(), method))
        try:
            return hanging(model, tol_m, progress, method, **kwargs)
        except (StaticsNotConverged, NoEquilibrium) as exc:
            tries.append(type(exc).__name__)
            raise

    monkeypatch.setattr(simulation_module, "_hanging_equilibrium", spy)
    with pytest.raises(NoEquilibrium, match="fibre rope would rest on the seabed"):
        solve_statics(load_scene("gjoa-500", RETRIED_WITH_THE_GROWING_SEABED_SET), progress=False)
    # Newton's method alone first; the retry, before any relaxation, with the method asked for ("auto")
    assert tries == [(True, "newton"), "StaticsNotConverged", (False, "auto"), "NoEquilibrium"]
    assert statics.seabed_set_releases()  # the rule is back after the retry

"""The coarse compile of a static solve's coarse start (moor_env.coarse_start)."""

from __future__ import annotations

import contextlib
import functools

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.coarse_start import PROBE_DIP_M, CoarseStart, coarse_keys
from moor_env.compile import compile_scene
from moor_env.errors import NoEquilibrium
from moor_env.fidelity import fidelity_presets
from moor_env.physics import layout as L
from tests.test_simulation_starts import ONE_COARSE_FIBRE_NODE

# the fast preset fitted to this scene makes the loop chain finer than the preset's own (0.5 m against 2 m) and the
# fibre rope and the wire coarser (50 m and 100 m against 20 m and 30 m)
FITTED_FAST = {"water_depth_m": 1107.0, "vessel_spacing_m": 222.0, "mooring_line_length_m": 1274.0,
               "vertical_chain_length_m": 9.7, "drop_height_m": 67.9, "fidelity": "fast"}


def test_coarse_compile_coarsens_only_the_finer_lines():
    """Reference: the fast preset's segment lengths (vertical and loop chain 2 m, fibre rope 20 m, wire 30 m) and
    the fitted model's (chain 1 m and 0.5 m, fibre rope 50 m, wire 100 m). A line finer than the preset's takes the
    preset's length; a line already coarser keeps its own (the coarse compile never refines a line)."""
    model = compile_scene(load_scene("gjoa-500", FITTED_FAST))
    disc = model.scene.discretization
    assert (disc.vertical_chain_segment_m, disc.loop_chain_segment_m, disc.fibre_segment_m,
            disc.wire_segment_m) == (1.0, 0.5, 50.0, 100.0)
    assert coarse_keys(model) == {"vertical_chain_segment_m": 2.0, "loop_chain_segment_m": 2.0,
                                  "fibre_segment_m": 50.0, "wire_segment_m": 100.0}


def test_no_coarse_compile_for_lines_no_finer_than_the_preset():
    """Reference: the fitted fast preset's lines against the accurate preset's, all finer than them: no coarse
    compile."""
    model = compile_scene(load_scene("gjoa-500", FITTED_FAST))
    disc = model.scene.discretization
    preset = {k: v for k, v in fidelity_presets()["accurate"].items() if k.endswith("_segment_m")}
    assert all(getattr(disc, k) >= v for k, v in preset.items())
    assert coarse_keys(model, "accurate") is None


# a long mooring line in calm water whose fibre rope rests on the seabed in the scene's own equilibrium
FIBRE_ON_THE_SEABED = {"mooring_line_length_m": 750.0, "vessel_spacing_m": 60.0, "current_scale": 0.0}
FAST_UNFITTED = {"fidelity": "fast", "discretization.fit_to_geometry": False}  # no line finer than the fast preset's

# The statics benchmark's scene 423 (tests/test_simulation_starts.py): it converges with the fibre rope a few
# centimetres clear of the seabed, and its first guess lays the loop's chain on the seabed.
FIBRE_CLEAR_WITH_THE_CHAIN_ON_THE_SEABED = ONE_COARSE_FIBRE_NODE


def _coarse_start(model):
    """The coarse start of a static solve of ``model`` (as ``solve_statics`` makes it), from the first guess."""
    from moor_env.physics.statics_guess import first_guess
    from moor_env.simulation import _coarse_solve
    from moor_env.simulator import Simulator

    sim = Simulator(model)
    first_guess(sim)
    return CoarseStart(sim, functools.partial(_coarse_solve, progress=False))


def test_equilibrium_with_the_fibre_through_the_seabed_refuses_a_fibre_it_dips_through_it(monkeypatch):
    """Reference: the scene's own equilibrium (its lines solved without the refusals) rests the fibre rope on the
    seabed. ``solve_statics`` refuses it from the coarse compile's equilibrium with the seabed bearing no fibre: one
    Newton solve, of the coarse lines with the fibre's ``MF_SEABED_D`` 0 and the line-anchor contact off (both
    restored after it); neither the fine lines nor the coarse lines with the seabed whole are solved."""
    from moor_env import coarse_start as coarse_module
    from moor_env import simulation as simulation_module
    from moor_env.physics.statics_checks import fibre_material, fibre_on_seabed

    model = compile_scene(load_scene("gjoa-500", FIBRE_ON_THE_SEABED))
    own = simulation_module._hanging_equilibrium(model, 1e-3, False, "newton", checks=False)
    assert fibre_on_seabed(own.simulator)[0] >= 1
    solved = []
    solve = coarse_module.solve_equilibrium

    def probe(sim, **kwargs):
        m = sim.model
        solved.append((m.node_i.shape[0], float(m.mat_f[fibre_material(m), L.MF_SEABED_D]),
                       float(m.contact_f[L.CF_ON])))
        return solve(sim, **kwargs)

    monkeypatch.setattr(coarse_module, "solve_equilibrium", probe)
    monkeypatch.setattr(simulation_module, "solve_equilibrium", lambda *a, **k: pytest.fail("a line was solved"))
    model = compile_scene(load_scene("gjoa-500", FIBRE_ON_THE_SEABED))
    with pytest.raises(NoEquilibrium) as refused:
        solve_statics(model, progress=False)
    assert refused.value.key == "installation.mooring_line_length_m"
    assert "the seabed bearing no fibre" in refused.value.cause and "fast preset" in refused.value.cause
    assert len(solved) == 1 and solved[0][0] < model.node_i.shape[0]
    assert solved[0][1:] == (0.0, 0.0)


def _probe_arrays(model):
    """The model arrays the probe changes for its solve: the material table and the contact's parameters."""
    return model.mat_f.copy(), model.contact_f.copy()


@pytest.mark.parametrize("fails", [False, True])
def test_probe_restores_the_model_it_solves(monkeypatch, fails):
    """Reference: the arrays of the model the probe solves before it. The probe sets the fibre's seabed width and the
    line-anchor contact to 0 for its solve and puts both back after it, whether the solve returns or raises: on the
    coarse compile, and on the scene's own model where no line is finer than the fast preset's (a model the caller
    goes on to solve)."""
    from moor_env import coarse_start as coarse_module
    from moor_env.errors import StaticsNotConverged

    if fails:
        def stalls(sim, **kwargs):
            assert sim.model.mat_f[coarse_module.fibre_material(sim.model), L.MF_SEABED_D] == 0.0
            raise StaticsNotConverged("stalled", 1.0)

        monkeypatch.setattr(coarse_module, "solve_equilibrium", stalls)
    for scene in (FIBRE_ON_THE_SEABED, {**FIBRE_ON_THE_SEABED, **FAST_UNFITTED}):
        start = _coarse_start(compile_scene(load_scene("gjoa-500", scene)))
        model = start._coarse_model()
        assert (model is start.sim.model) == (scene is not FIBRE_ON_THE_SEABED)
        before = _probe_arrays(model)
        dip = start._fibre_dip_through_seabed()
        assert (dip is None) == fails
        for saved, now in zip(before, _probe_arrays(model), strict=True):
            np.testing.assert_array_equal(now, saved)


def test_probe_is_not_solved_where_the_fibre_material_is_another_lines_too(monkeypatch):
    """Reference: the probe's problem lets every segment of the fibre's material through the seabed, so it is not
    the scene's without the fibre's seabed where another line has segments of that material: no solve then."""
    from moor_env import coarse_start as coarse_module
    from moor_env.physics.statics_checks import fibre_material

    model = compile_scene(load_scene("gjoa-500", {**FIBRE_ON_THE_SEABED, **FAST_UNFITTED}))
    assert _coarse_start(model)._fibre_dip_through_seabed() is not None
    wire = model.lines["wire"].index
    model.seg_i[np.nonzero(model.seg_i[:, L.SI_LINE] == wire)[0][0], L.SI_MAT] = fibre_material(model)
    monkeypatch.setattr(coarse_module, "solve_equilibrium", lambda *a, **k: pytest.fail("the probe was solved"))
    assert _coarse_start(model)._fibre_dip_through_seabed() is None


def test_chain_the_seabed_bears_keeps_a_clear_fibre_from_being_refused(monkeypatch):
    """Reference: the scene converges with the fibre rope clear of the seabed (scene 423 of
    tests/test_simulation_starts.py).
    Its coarse equilibrium with the seabed bearing no fibre does not dip the fibre through the seabed; with the
    seabed bearing nothing of any line, the loop's chain sinks through it and takes the fibre along, which would
    refuse the scene."""
    from moor_env import coarse_start as coarse_module

    model = compile_scene(load_scene("gjoa-500", FIBRE_CLEAR_WITH_THE_CHAIN_ON_THE_SEABED))
    assert _coarse_start(model)._fibre_dip_through_seabed() is None
    bears_fibre = coarse_module._fibre_through_seabed_and_contact_off

    @contextlib.contextmanager
    def bears_nothing(m):
        saved = m.mat_f[:, L.MF_SEABED_D].copy()
        m.mat_f[:, L.MF_SEABED_D] = 0.0
        try:
            with bears_fibre(m):
                yield
        finally:
            m.mat_f[:, L.MF_SEABED_D] = saved

    monkeypatch.setattr(coarse_module, "_fibre_through_seabed_and_contact_off", bears_nothing)
    resting, lowest_m = _coarse_start(model)._fibre_dip_through_seabed()
    assert resting >= 1 and lowest_m < -PROBE_DIP_M


# A scene of the envs' resolution (statics_env_resolution benchmark, seed 7), rounded: strong current, the fast
# preset's lines with 1 m chain; its first guess hangs the fibre rope 2 m above the seabed, and Newton's method from
# it stalls for 2000 iterations.
FIBRE_TWO_METRES_CLEAR_IN_THE_GUESS = {
    "water_depth_m": 1276.93, "vessel_spacing_m": 458.91, "mooring_line_length_m": 1615.01,
    "vertical_chain_length_m": 55.85, "drop_height_m": 51.3, "current_scale": 1.3827, "current_direction_deg": 145.16,
    "anchor_mass_scale": 1.0358, "fidelity": "fast", "discretization.fit_to_geometry": False,
    "discretization.vertical_chain_segment_m": 1.0, "discretization.loop_chain_segment_m": 1.0,
    "discretization.fibre_segment_m": 50.0, "discretization.wire_segment_m": 100.0}


def test_fibre_the_guess_hangs_a_little_clear_is_refused_from_the_probe():
    """Reference (not run here: about 9 s): the relaxation solver refuses the unrounded scene for its fibre rope on
    the seabed. The first guess hangs the fibre between ``GUESS_NEAR_SEABED_M`` and ``PROBE_NEAR_SEABED_M`` above
    the seabed (so only the probe is tried), and ``solve_statics`` refuses the scene for its fibre from the
    equilibrium with the seabed bearing no fibre, not after its own lines' solve (which stalls)."""
    from moor_env.coarse_start import GUESS_NEAR_SEABED_M, PROBE_NEAR_SEABED_M
    from moor_env.physics.statics_checks import fibre_on_seabed

    model = compile_scene(load_scene("gjoa-500", FIBRE_TWO_METRES_CLEAR_IN_THE_GUESS))
    start = _coarse_start(model)
    assert GUESS_NEAR_SEABED_M < fibre_on_seabed(start.sim)[1] <= PROBE_NEAR_SEABED_M
    with pytest.raises(NoEquilibrium) as refused:
        solve_statics(model, progress=False, method="newton")
    assert "the seabed bearing no fibre" in refused.value.cause

"""The coarse compile of a static solve's coarse start (moor_env.coarse_start)."""

from __future__ import annotations

from moor_env import load_scene
from moor_env.coarse_start import coarse_keys
from moor_env.compile import compile_scene
from moor_env.fidelity import fidelity_presets

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

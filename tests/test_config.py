"""Input validation: every bad input is refused with a message naming the key, its value and the range."""

from __future__ import annotations

import subprocess
import sys

import pytest

from moor_env import ConfigError, compile_scene, load_scene
from moor_env.config import bundled_scene_names


@pytest.mark.parametrize("name", bundled_scene_names())
def test_every_bundled_scene_loads_and_compiles(name):
    model = compile_scene(load_scene(name))
    assert model.dt_s > 0


@pytest.mark.parametrize(
    ("overrides", "key"),
    [
        ({"water_depth_m": 0.0}, "environment.water_depth_m"),
        ({"materials.chain_142.ea_n": -1.0e9}, "materials.chain_142.ea_n"),
        ({"vessel_spacing_m": "wide"}, "installation.vessel_spacing_m"),
        ({"no_such_key": 1}, "no_such_key"),
        ({"drop_height_m": 480.0}, "installation.drop_height_m"),
        ({"vertical_chain_length_m": 200.0}, "installation.vertical_chain_length_m"),
        ({"mooring_line_length_m": 300.0}, "installation.mooring_line_length_m"),
        ({"materials.wire_76.mbl_n": 5.0e5}, "materials.wire_76.mbl_n"),
        ({"dt_s": 0.01}, "discretization.dt_s"),
        ({"current_scale": -1.0}, "environment.current.scale"),
    ],
)
def test_bad_input_names_the_key(overrides, key):
    with pytest.raises(ConfigError) as info:
        compile_scene(load_scene("gjoa-500", overrides))
    assert info.value.key == key
    assert "allowed" in str(info.value)


def test_requested_step_beyond_stability_is_refused_with_the_limit():
    with pytest.raises(ConfigError, match=r"discretization.dt_s=0.001: allowed <= 0.000375"):
        compile_scene(load_scene("gjoa-500", {"dt_s": 0.001}))


def test_cli_reports_bad_input_on_one_line_with_exit_code_2():
    proc = subprocess.run([sys.executable, "-m", "moor_env.cli", "drop", "gjoa-500", "--set", "water_depth_m=-3"],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "environment.water_depth_m=-3.0: allowed >= 132.5 and <= 6000 m" in lines[0]


def test_fast_fit_takes_the_tight_line_resolution_for_waves_and_pre_release_moves():
    """configs/fidelity.yaml: the coarse branch of `fast` was validated on calm falls from a loop at rest only.
    gjoa-500 as bundled (50 m of slack, chord 6.5 deg) stays coarse; waves or a scripted vessel move before the
    release switch to tight_line (in waves with its in_waves keys: a 1 m loop chain)."""
    from moor_env.fidelity import fidelity_presets

    coarse = fidelity_presets()["fast"]["loop_chain_segment_m"]
    tight = fidelity_presets()["fast"]["tight_line"]["loop_chain_segment_m"]
    in_waves = fidelity_presets()["fast"]["tight_line"]["in_waves"]["loop_chain_segment_m"]
    loop = {name: load_scene("gjoa-500", {"fidelity": "fast", **ov}).discretization.loop_chain_segment_m
            for name, ov in {"calm": {}, "waves": {"sea_state_hs_m": 0.5},
                             "moves": {"release_time_s": 10.0, "installation.spacing_rate_m_s": 0.1},
                             "waits": {"release_time_s": 10.0}}.items()}
    assert loop == {"calm": coarse, "waves": in_waves, "moves": tight, "waits": coarse}

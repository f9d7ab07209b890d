"""Input validation: every bad input is refused with a message naming the key, its value and the range."""

from __future__ import annotations

import subprocess
import sys

import pytest

from moor_env import ConfigError, compile_scene, load_scene
from moor_env.config import SET_SHORTCUTS, bundled_scene_names, scene_dict, scene_from_dict, set_key_help
from moor_env.errors import closest
from moor_env.scene_geometry import max_drop_height_m, min_water_depth_m


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


def test_yaml_syntax_error_names_the_file_line_and_column(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("name: broken\nenvironment:\n  water_depth_m: 500\n installation: {}\n")
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    assert info.value.key == "scene" and info.value.value == str(path)
    assert "line 4, column" in str(info.value) and "\n" not in str(info.value)


def test_unknown_scene_key_is_named_with_the_nearest_known_one():
    data = scene_dict("gjoa-500")
    data["installation"]["drop_heigth_m"] = data["installation"].pop("drop_height_m")
    with pytest.raises(ConfigError) as info:
        scene_from_dict(data)
    assert info.value.key == "installation.drop_heigth_m"
    assert "did you mean installation.drop_height_m?" in str(info.value)


@pytest.mark.parametrize(("section", "name", "key", "allowed"), [
    ("environment", "water_depth_m", "environment.water_depth_m", "> 10 and <= 6000 m"),
    ("materials", "mbl_n", "materials.chain_seed004.mbl_n", "> 0 and <= 1e+09"),
    (None, "name", "name", "a value"),
])
def test_missing_required_key_is_named_with_its_range(section, name, key, allowed):
    data = scene_dict("seed004-chain-500")
    if section == "materials":
        data["materials"]["chain_seed004"].pop(name)
    else:
        (data if section is None else data[section]).pop(name)
    with pytest.raises(ConfigError) as info:
        scene_from_dict(data)
    assert info.value.key == key
    assert str(info.value) == f"{key}=(missing): allowed {allowed} (a required key)"


@pytest.mark.parametrize(("overrides", "key", "allowed"), [
    ({"drop_height_m": 437.0}, "installation.drop_height_m", "> 1 and <= 436.0 m"),
    ({"drop_height_m": 600.0}, "installation.drop_height_m", "> 1 and <= 436.0 m"),
    ({"water_depth_m": 132.0}, "environment.water_depth_m", ">= 132.5 and <= 6000 m"),
    ({"environment.water_depth_m": 132.0}, "environment.water_depth_m", ">= 132.5 and <= 6000 m"),
    ({"water_depth_m": 132.0, "drop_height_m": 68.5}, "installation.drop_height_m", "> 1 and <= 68.0 m"),
])
def test_drop_height_that_does_not_fit_names_the_key_set_with_the_scene_range(overrides, key, allowed):
    with pytest.raises(ConfigError) as info:
        load_scene("gjoa-500", overrides)
    assert info.value.key == key and info.value.allowed == allowed


def test_drop_height_limits_are_the_ones_the_consistency_check_applies():
    scene = load_scene("gjoa-500")
    assert max_drop_height_m(scene) == pytest.approx(436.0)
    assert min_water_depth_m(scene) == pytest.approx(132.5)
    assert load_scene("gjoa-500", {"drop_height_m": 436.0}).installation.drop_height_m == 436.0
    assert load_scene("gjoa-500", {"water_depth_m": 132.5}).environment.water_depth_m == 132.5


def test_set_reaches_list_entries_by_index():
    assert load_scene("gjoa-500", {"anchor.sections.0.length_m": 5.0}).anchor.sections[0].length_m == 5.0


def test_set_key_help_has_every_shortcut_with_its_unit():
    lines = {line.split()[0]: line for line in set_key_help()}
    assert list(lines) == list(SET_SHORTCUTS)
    assert "[m]" in lines["water_depth_m"] and "> 10 and <= 6000" in lines["water_depth_m"]
    assert "[integer]" in lines["sea_state_seed"]


@pytest.mark.parametrize(("word", "choices", "expected"), [
    ("water_dept_m", ["water_depth_m", "drop_height_m"], "water_depth_m"),
    ("frction", ["stiffness_pa_m", "friction_coefficient"], "friction_coefficient"),
    ("xyz", ["water_depth_m"], None),
])
def test_closest_name(word, choices, expected):
    assert closest(word, choices) == expected

"""The command line's user edges: every bad input is one line on stderr with exit code 2 and no traceback, checked
before any simulation time is spent; help lists the scenes and keys; human output is rounded, JSON is not."""

from __future__ import annotations

import json
import os

import pytest

from moor_env import cli
from moor_env.config import SET_SHORTCUTS, bundled_scene_names

SCENES = bundled_scene_names()


def _fail_if_called(*args, **kwargs):
    raise AssertionError("the run started although the input was invalid")


@pytest.fixture
def no_run(monkeypatch):
    """Any statics or drop started by the CLI fails the test."""
    monkeypatch.setattr(cli, "solve_statics", _fail_if_called)
    monkeypatch.setattr(cli, "simulate_drop", _fail_if_called)


def _error_line(capsys, argv: list[str]) -> str:
    """Run the CLI, expect exit code 2 and return its single stderr line."""
    code = cli.main(argv)
    captured = capsys.readouterr()
    assert code == 2, captured
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    return lines[0]


def test_malformed_yaml_names_the_file_and_the_line_and_column(tmp_path, capsys, no_run):
    path = tmp_path / "broken.yaml"
    path.write_text("name: broken\nenvironment:\n  water_depth_m: [500, 2\nanchor: {library: dpa_80t}\n")
    line = _error_line(capsys, ["drop", str(path)])
    assert str(path) in line
    assert "line 4, column 7" in line and "line 3, column 18" in line


@pytest.mark.parametrize(("target", "words"), [
    ("missing_dir/drop.png", "no directory"),
    (".", "this is a directory"),
    ("drop.notanimage", "a file ending in one of"),
])
def test_unusable_plot_path_is_refused_before_the_run(tmp_path, capsys, no_run, monkeypatch, target, words):
    monkeypatch.setattr(cli, "load_scene", _fail_if_called)
    line = _error_line(capsys, ["drop", "gjoa-500", "--plot", str(tmp_path / target)])
    assert line.startswith("moor-env: error: --plot=") and words in line


def test_unwritable_plot_directory_is_refused_before_the_run(tmp_path, capsys, no_run, monkeypatch):
    monkeypatch.setattr(cli, "load_scene", _fail_if_called)
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    line = _error_line(capsys, ["drop", "gjoa-500", "--plot", str(tmp_path / "drop.png")])
    assert "a writable file" in line and "permission denied" in line


def test_typo_of_a_required_scene_key_names_the_unknown_key_and_the_close_one(tmp_path, capsys, no_run):
    path = tmp_path / "typo.yaml"
    path.write_text("name: typo\nenvironment: {water_dept_m: 500.0}\nanchor: {library: dpa_80t}\ninstallation: {}\n")
    line = _error_line(capsys, ["static", str(path)])
    assert line.startswith("moor-env: error: environment.water_dept_m=500.0: allowed a key of environment")
    assert "did you mean environment.water_depth_m? it is required and missing" in line


def test_missing_required_scene_key_is_named_with_its_range(tmp_path, capsys, no_run):
    path = tmp_path / "missing.yaml"
    path.write_text("name: missing\nenvironment: {}\nanchor: {library: dpa_80t}\ninstallation: {}\n")
    line = _error_line(capsys, ["static", str(path)])
    assert line == "moor-env: error: environment.water_depth_m=(missing): allowed > 10 and <= 6000 m (a required key)"


@pytest.mark.parametrize(("item", "words"), [
    ("water_dept_m=300", "water_dept_m=300: allowed a --set shortcut or a dotted path"),
    ("water_dept_m=300", "did you mean water_depth_m?"),
    ("installation.drop_heigth_m=30", "did you mean installation.drop_height_m?"),
    ("environment.seabed.frction=0.3", "did you mean environment.seabed.friction_coefficient?"),
    ("materials.chain_14.ea_n=1e9", "did you mean materials.chain_142?"),
    ("environment.water_depth_m.x=1", "'environment.water_depth_m' is a value, not a section"),
    ("drop_height_m=high", "installation.drop_height_m='high': allowed a number"),
    ("sea_state_seed=1.5", "environment.sea_state.seed=1.5: allowed a whole number"),
    ("integrator=rk3", "did you mean rk2?"),
    ("fidelity=fastt", "did you mean fast?"),
    ("drop_height_m", "--set='drop_height_m': allowed KEY=VALUE"),
    ("anchor.sections.9.length_m=5", "allowed an index 0 .. 4 of anchor.sections"),
    ("catenary_line.fairlead_x_m=5", "it has no 'catenary_line' section"),
])
def test_bad_set_names_the_key_and_suggests_the_nearest(capsys, no_run, item, words):
    line = _error_line(capsys, ["static", "gjoa-500", "--set", item])
    assert words in line


@pytest.mark.parametrize(("sets", "words"), [
    (["drop_height_m=600"], "installation.drop_height_m=600.0: allowed > 1 and <= 436.0 m"),
    (["drop_height_m=450"], "installation.drop_height_m=450.0: allowed > 1 and <= 436.0 m"),
    (["water_depth_m=100"], "environment.water_depth_m=100.0: allowed >= 132.5 and <= 6000 m"),
    (["water_depth_m=5"], "environment.water_depth_m=5.0: allowed >= 132.5 and <= 6000 m"),
    (["water_depth_m=100", "drop_height_m=80"], "installation.drop_height_m=80.0: allowed > 1 and <= 36.0 m"),
])
def test_impossible_depth_and_drop_height_name_the_key_set_with_the_scene_range(capsys, no_run, sets, words):
    argv = ["drop", "gjoa-500"]
    for item in sets:
        argv += ["--set", item]
    line = _error_line(capsys, argv)
    assert words in line


@pytest.mark.parametrize(("scene", "words"), [
    ("gjoa-50", "did you mean gjoa-500?"),
    ("nothing-like-it", "one of " + ", ".join(SCENES) + " or a YAML path"),
    ("no_such_file.yaml", "an existing YAML file (file not found)"),
])
def test_unknown_scene_lists_the_bundled_ones(capsys, no_run, scene, words):
    line = _error_line(capsys, ["drop", scene])
    assert words in line


def test_usage_errors_are_one_line(capsys, no_run):
    assert "the following arguments are required: scene" in _error_line(capsys, ["drop"])
    assert "unrecognized arguments: --bogus" in _error_line(capsys, ["drop", "gjoa-500", "--bogus"])


@pytest.mark.parametrize("argv", [["--help"], ["drop", "--help"], ["static", "--help"]])
def test_help_lists_the_bundled_scenes_and_the_set_keys_with_units(capsys, argv):
    assert cli.main(argv) == 0
    out = capsys.readouterr().out
    for name in SCENES:
        assert f"\n  {name}\n" in out
    lines = {line.split()[0]: line for line in out.splitlines() if line.startswith("  ") and line.split()}
    for key in SET_SHORTCUTS:
        assert key in lines, key
    assert "[m]" in lines["drop_height_m"] and "<= 500" in lines["drop_height_m"]
    assert "[deg]" in lines["current_direction_deg"] and "[s]" in lines["dt_s"]
    assert "[choice]" in lines["integrator"] and "implicit_euler" in lines["integrator"]


class _FakeResult:
    DATA = {"status": "touchdown", "touchdown_time_s": 7.123456789, "touchdown_speed_m_s": 19.87654321,
            "tilt_deg": 1.2345678, "drift_m": 0.123456789, "release_point_m": [3.5758703, -0.0000001, -368.4775277],
            "max_tension_n": {"wire": 1187092.7296, "mooring_line": 191160.2558}, "n_steps": 12345,
            "dt_s": 0.000374999, "chain_past_back_end_m": None}

    def to_dict(self):
        return dict(self.DATA)


def test_human_output_is_rounded_and_json_keeps_full_precision(capsys, monkeypatch):
    calls = []
    monkeypatch.setattr(cli, "simulate_drop", lambda scene, **kw: calls.append(kw) or _FakeResult())
    assert cli.main(["drop", "gjoa-500"]) == 0
    out = {line.split(None, 1)[0]: line.split(None, 1)[1] for line in capsys.readouterr().out.splitlines()}
    assert out == {"status": "touchdown", "touchdown_time_s": "7.123", "touchdown_speed_m_s": "19.88",
                   "tilt_deg": "1.23", "drift_m": "0.123", "release_point_m": "[3.576, 0.000, -368.478]",
                   "max_tension": "wire 1.19 MN, mooring_line 191.2 kN", "n_steps": "12345", "dt_s": "0.000375",
                   "chain_past_back_end_m": "-"}
    assert cli.main(["drop", "gjoa-500", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == _FakeResult.DATA


def test_drop_shows_progress_unless_asked_not_to(capsys, monkeypatch):
    calls = []
    monkeypatch.setattr(cli, "simulate_drop", lambda scene, **kw: calls.append(kw) or _FakeResult())
    assert cli.main(["drop", "gjoa-500"]) == 0
    assert cli.main(["drop", "gjoa-500", "--no-progress"]) == 0
    assert [c["progress"] for c in calls] == [True, False]


def test_statics_and_fall_past_the_threshold_show_a_progress_bar(capsys, monkeypatch):
    """A statics solve shows its bar once it has run ``PROGRESS_AFTER_S`` (1 s; here made negative so that any solve
    counts as long), the fall its simulated time; both on stderr, gone from stdout."""
    from moor_env.physics import statics_stages

    monkeypatch.setattr(statics_stages, "PROGRESS_AFTER_S", -1.0)
    code = cli.main(["drop", "vertical-chain", "--set", "drop_height_m=2", "--set", "vertical_chain_length_m=4"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "statics" in captured.err and "s simulated" in captured.err
    assert "statics" not in captured.out and "simulated" not in captured.out


def test_a_real_drop_prints_rounded_results(capsys):
    code = cli.main(["drop", "vertical-chain", "--set", "drop_height_m=2", "--set", "vertical_chain_length_m=4",
                     "--no-progress"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    out = dict(line.split(None, 1) for line in captured.out.splitlines())
    assert out["status"] == "touchdown"
    speed = out["touchdown_speed_m_s"]
    assert len(speed.split(".")[1]) == 2 and float(speed) > 0
    assert captured.err == ""

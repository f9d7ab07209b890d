"""notebooks/policy_evaluation.ipynb executes end to end (nbclient) on the bundled policy: its learning curve, its
evaluation beside the baselines on a scenario file with the statistics, the report and the episode GIF. Parameters
come from MOOR_NB_* variables."""

from __future__ import annotations

import json
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from PIL import Image

from agents.scenarios import save_scenarios

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "notebooks" / "policy_evaluation.ipynb"
SCENARIOS = [{"id": "calm", "seed": 1, "options": {"sea_state_hs_m": 0.0, "current_scale": 0.0,
                                                  "water_depth_m": 500.0}},
             {"id": "waves", "seed": 2, "options": {"sea_state_hs_m": 2.0, "sea_state_tp_s": 8.0}}]
BUNDLED = "plan-v1-sac"


def test_notebook_is_stored_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)
    assert "parameters" in code[0].metadata.get("tags", [])


@pytest.mark.slow
def test_notebook_evaluates_and_animates_the_bundled_policy(tmp_path, monkeypatch):
    save_scenarios(SCENARIOS, tmp_path / "scenarios.json")
    out = tmp_path / "out"
    for key, value in {"RUN_DIR": BUNDLED, "SCENARIOS": tmp_path / "scenarios.json", "BASELINES": "crew,random",
                       "CURVE_BASELINES": "crew", "JOBS": 1, "OUT": out}.items():
        monkeypatch.setenv(f"MOOR_NB_{key}", str(value))

    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(nb, timeout=240, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}).execute()

    report = json.loads((out / "evaluation.json").read_text())
    assert [r["policy"] for r in report["results"]] == [BUNDLED, "crew", "random"]
    assert all(len(r["episodes"]) == len(SCENARIOS) for r in report["results"])
    assert report["statistics"]["paired"][0]["a"] == BUNDLED
    with Image.open(out / "episode.gif") as gif:
        assert gif.n_frames > 2  # the site, the fall, touchdown
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert ": finished," in text and "reproduce:" in text and "Task check" in text
    assert (out / "distributions.png").stat().st_size > 10_000
    assert (out / "learning_curve.png").stat().st_size > 10_000

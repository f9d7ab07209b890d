"""notebooks/policy_evaluation.ipynb executes end to end (nbclient): it trains a tiny run, evaluates it and the
baselines on a scenario file, writes the report and the episode GIF. Parameters come from MOOR_NB_* variables."""

from __future__ import annotations

import json
from pathlib import Path

import nbformat
import pytest
import yaml
from nbclient import NotebookClient
from PIL import Image

from agents.scenarios import save_scenarios
from tests.agents.conftest import tiny_train_config

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "notebooks" / "policy_evaluation.ipynb"
SCENARIOS = [{"id": "calm", "seed": 1, "options": {"sea_state_hs_m": 0.0, "current_scale": 0.0}},
             {"id": "waves", "seed": 2, "options": {"sea_state_hs_m": 2.0, "sea_state_tp_s": 8.0}}]


def test_notebook_is_stored_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)
    assert "parameters" in code[0].metadata.get("tags", [])


@pytest.mark.slow
def test_notebook_trains_evaluates_and_animates_a_tiny_run(tmp_path, monkeypatch):
    train_cfg = tiny_train_config(tmp_path / "runs", tmp_path / "equilibria")
    (tmp_path / "train.yaml").write_text(yaml.safe_dump(train_cfg))
    save_scenarios(SCENARIOS, tmp_path / "scenarios.json")
    out = tmp_path / "out"
    for key, value in {"RUN_DIR": tmp_path / "runs" / train_cfg["name"], "TRAIN_CONFIG": tmp_path / "train.yaml",
                       "SCENARIOS": tmp_path / "scenarios.json", "BASELINES": "crew,random", "JOBS": 1,
                       "OUT": out}.items():
        monkeypatch.setenv(f"MOOR_NB_{key}", str(value))

    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(nb, timeout=240, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}).execute()

    report = json.loads((out / "evaluation.json").read_text())
    assert [r["policy"] for r in report["results"]] == [train_cfg["name"], "crew", "random"]
    assert all(len(r["episodes"]) == len(SCENARIOS) for r in report["results"])
    with Image.open(out / "episode.gif") as gif:
        assert gif.n_frames > 2  # reset, control steps and the fall
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert f"{train_cfg['name']}/seed-0: finished" in text
    assert (out / "distributions.png").stat().st_size > 10_000

"""Evaluation: success criterion, statistics, JSON/markdown/plot outputs and the command line on a tiny set."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from agents.baselines import PLAN_ENV, make_baseline
from agents.evaluate import (
    bootstrap_ci,
    combine_seeds,
    evaluate_policy,
    main,
    markdown_table,
    t_interval,
    write_report,
)
from agents.scenarios import save_scenarios
from agents.success import success_of


@pytest.mark.parametrize(("speed", "tilt", "terms", "ok"), [
    (24.0, 1.99, {}, True),                      # at the required speed, just under 2 deg
    (23.99, 0.5, {}, False),                     # too slow
    (26.0, 2.0, {}, False),                      # 2 deg is not under 2 deg
    (26.0, 0.5, {"fibre_seabed": -1.0}, False),  # a limit exceeded
    (26.0, 0.5, {"tension": -1.0}, False),
    (26.0, 0.5, {"chain_pile": -0.3}, True),     # chain pile-up is scored, not a limit
])
def test_success_criterion(speed, tilt, terms, ok, tiny_cfg):
    assert success_of({"speed_m_s": speed, "tilt_deg": tilt}, terms, tiny_cfg) is ok
    assert success_of(None, {}, tiny_cfg) is False


def test_intervals():
    v = np.random.default_rng(0).normal(5.0, 1.0, 200)
    lo, hi = bootstrap_ci(v)
    assert lo < v.mean() < hi and hi - lo < 0.5
    lo, hi = t_interval(np.array([0.5, 0.6, 0.7]))
    assert lo == pytest.approx(0.6 - 4.302653 * 0.1 / math.sqrt(3), rel=1e-5)  # t_{0.975, 2} = 4.3027
    assert t_interval(np.array([0.4])) == (0.4, 0.4)


def test_results_json_table_and_plots(tmp_path, tiny_cfg, tiny_scenarios):
    crew = evaluate_policy(make_baseline("crew", PLAN_ENV, tiny_cfg), tiny_scenarios, PLAN_ENV, tiny_cfg,
                           progress=False)
    rnd = [evaluate_policy(make_baseline("random", PLAN_ENV, tiny_cfg, seed=s), tiny_scenarios, PLAN_ENV, tiny_cfg,
                           progress=False) for s in (0, 1)]
    both = combine_seeds(rnd, name="random x2")
    assert both["summary"]["seeds"] == 2 and both["summary"]["episodes"] == 2 * len(tiny_scenarios)
    assert len(both["summary"]["per_seed"]["success_rate"]) == 2
    assert [e["scenario"] for e in crew["episodes"]] == [s["id"] for s in tiny_scenarios]
    e = crew["episodes"][0]
    assert e["touchdown"] and e["touchdown_speed_m_s"] > 5.0 and e["steps"] == 1
    inside = sum(x["chain_past_back_end_m"] > 0.0 for x in crew["episodes"])  # from the env's touchdown info
    assert all(math.isfinite(x["chain_past_back_end_m"]) for x in crew["episodes"])
    assert crew["summary"]["chain_inside"] == inside
    assert e["reward"] == pytest.approx(sum(e["reward_terms"].values()))
    paths = write_report([crew, both], tmp_path, tiny_scenarios)
    data = json.loads(paths["json"].read_text())
    assert [r["policy"] for r in data["results"]] == ["crew", "random x2"]
    table = paths["markdown"].read_text()
    assert table == markdown_table([crew, both]) and table.count("\n") == 4
    assert "| crew | AnchorPlan-v0 | 3 (1) |" in table and "| random x2 | AnchorPlan-v0 | 6 (2) |" in table
    assert paths["plot"].stat().st_size > 10_000


def test_same_policy_same_results(tiny_cfg, tiny_scenarios):
    runs = [evaluate_policy(make_baseline("random", PLAN_ENV, tiny_cfg), tiny_scenarios, PLAN_ENV, tiny_cfg,
                            progress=False)["episodes"] for _ in range(2)]
    assert [e["reward"] for e in runs[0]] == [e["reward"] for e in runs[1]]


def test_command_line(tmp_path, tiny_cfg, tiny_scenarios, capsys):
    save_scenarios(tiny_scenarios[:2], tmp_path / "s.json")
    cfg_path = tmp_path / "tiny.yaml"
    cfg_path.write_text(json.dumps(tiny_cfg.model_dump(mode="json")))  # JSON is YAML
    rc = main(["crew", "random", "--scenarios", str(tmp_path / "s.json"), "--env", "release",
               "--env-config", str(cfg_path), "--out", str(tmp_path / "out"), "--no-progress",
               "--records", str(tmp_path / "rl_evaluation.json")])
    assert rc == 0
    out = capsys.readouterr().out
    assert "| crew | AnchorRelease-v0 | 2 (1) |" in out
    assert {p.name for p in (tmp_path / "out").iterdir()} == {"evaluation.json", "evaluation.md",
                                                              "distributions.png"}
    assert main(["nonsense-dir", "--scenarios", str(tmp_path / "s.json"), "--out", str(tmp_path / "x")]) == 2

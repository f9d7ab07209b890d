"""Evaluation statistics: Wilson interval, paired bootstrap and McNemar, IQM and its stratified bootstrap, the task
check, and the per-episode records of the evaluation entry point on a tiny run."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from agents.baselines import PLAN_ENV, make_baseline
from agents.evaluate import combine_seeds, evaluate_policy, main
from agents.report import episode_records, write_records
from agents.scenarios import save_scenarios
from agents.statistics import (
    compare_results,
    evaluation_statistics,
    format_statistics,
    iqm,
    iqm_interval,
    mcnemar_exact,
    paired_bootstrap_interval,
    paired_comparison,
    reward_order,
    stratified_bootstrap_iqm,
    success_rate,
    task_checks,
    wilson_interval,
)


def test_wilson_known_values():
    lo, hi = wilson_interval(8, 10)
    assert lo == pytest.approx(0.4902, abs=5e-4) and hi == pytest.approx(0.9433, abs=5e-4)
    assert wilson_interval(0, 10)[0] == pytest.approx(0.0, abs=1e-12)
    assert wilson_interval(10, 10)[1] == pytest.approx(1.0, abs=1e-12)
    assert wilson_interval(0, 10)[1] == pytest.approx(0.2775, abs=5e-4)  # 0/10: upper bound z^2 / (n + z^2)
    ci = stats.binomtest(8, 10).proportion_ci(confidence_level=0.95, method="wilson")
    assert (ci.low, ci.high) == pytest.approx(wilson_interval(8, 10), abs=1e-12)
    s = success_rate([True] * 8 + [False] * 2)
    assert s["successes"] == 8 and s["n"] == 10 and s["rate"] == 0.8 and s["ci"] == wilson_interval(8, 10)


def _known_pair():
    """40 scenarios: 20 both succeed, 12 only A, 3 only B, 5 neither: difference (12 - 3) / 40 = 0.225."""
    a = np.array([1] * 20 + [1] * 12 + [0] * 3 + [0] * 5, dtype=bool)
    b = np.array([1] * 20 + [0] * 12 + [1] * 3 + [0] * 5, dtype=bool)
    perm = np.random.default_rng(3).permutation(a.size)
    return a[perm], b[perm]


def test_paired_known_case():
    a, b = _known_pair()
    c = paired_comparison(a, b, "A", "B")
    assert c["difference"] == pytest.approx(0.225)
    assert c["only_a"] == 12 and c["only_b"] == 3 and c["n_scenarios"] == 40
    lo, hi = c["ci"]
    assert lo < 0.225 < hi and lo > 0.0
    # the bootstrap of a 0/1 mean difference has a standard error near sqrt((b + c)/n - d^2) / sqrt(n)
    se = np.sqrt((15 / 40 - 0.225**2) / 40)
    assert hi - lo == pytest.approx(2 * 1.96 * se, rel=0.15)
    assert c["mcnemar"][0]["p_value"] == pytest.approx(stats.binomtest(12, 15, 0.5).pvalue, rel=1e-12)
    assert c["mcnemar"][0]["p_value"] == pytest.approx(0.03515625)  # 2 * (1 + 15 + 105 + 455) / 2^15


@pytest.mark.parametrize(("only_a", "only_b"), [(0, 0), (5, 5), (0, 7), (9, 2), (30, 12)])
def test_mcnemar_matches_binomtest(only_a, only_b):
    n = only_a + only_b
    expected = 1.0 if n == 0 else stats.binomtest(only_a, n, 0.5).pvalue
    assert mcnemar_exact(only_a, only_b) == pytest.approx(expected, rel=1e-12)


def test_paired_bootstrap_is_seeded_and_paired():
    a, b = _known_pair()
    assert paired_bootstrap_interval(a, b, seed=7) == paired_bootstrap_interval(a, b, seed=7)
    x, y = np.random.default_rng(4).normal(0.0, 1.0, (2, 40))  # continuous scores: the seed shows in the interval
    assert paired_bootstrap_interval(x, y, seed=7) == paired_bootstrap_interval(x, y, seed=7)
    assert paired_bootstrap_interval(x, y, seed=7) != paired_bootstrap_interval(x, y, seed=8)
    assert paired_bootstrap_interval(a, a) == (0.0, 0.0)  # identical policies: no spread when paired
    # several runs of A against one run of B: the per-scenario mean over the runs is what is resampled
    c = paired_comparison(np.stack([a, a]), b)
    assert len(c["mcnemar"]) == 2 and c["only_a"] == 24 and c["ci"] == paired_comparison(a, b)["ci"]
    with pytest.raises(ValueError, match="scenario counts"):
        paired_bootstrap_interval(a, b[:-1])


def test_iqm_known_values():
    assert iqm(np.arange(1.0, 9.0)) == pytest.approx(4.5)  # middle half of 1..8: 3, 4, 5, 6
    x = np.array([0.0, 0.1, 0.5, 0.55, 0.6, 0.62, 0.9, 1.0])
    assert iqm(x) == pytest.approx((0.5 + 0.55 + 0.6 + 0.62) / 4)
    scores = np.random.default_rng(1).uniform(0, 1, (10, 3))
    assert iqm(scores) == pytest.approx(stats.trim_mean(scores, 0.25, axis=None))  # rliable's aggregate_iqm


def test_stratified_bootstrap_is_seeded_and_stratified():
    scores = np.random.default_rng(2).uniform(0, 1, (10, 3))
    ci = stratified_bootstrap_iqm(scores, samples=4000, seed=5)
    assert ci == stratified_bootstrap_iqm(scores, samples=4000, seed=5)
    assert ci[0] < iqm(scores) < ci[1]
    # a task with a constant score: resampling within tasks leaves the other tasks' values untouched
    const = np.column_stack([np.full(6, 0.3), np.linspace(0, 1, 6)])
    lo, hi = stratified_bootstrap_iqm(const, samples=2000)
    assert 0.0 <= lo <= hi <= 1.0
    r = iqm_interval(np.array([0.5, 0.6, 0.7, 0.55, 0.8]), samples=2000)
    assert r["runs"] == 5 and r["tasks"] == 1 and r["iqm"] == pytest.approx(np.mean([0.55, 0.6, 0.7]))


def _result(name, success, runs=None):
    episodes = []
    for r, row in enumerate(np.atleast_2d(success)):
        for i, s in enumerate(row):
            e = {"scenario": f"s{i}", "seed": i, "success": bool(s)}
            if runs:
                e["run"] = f"{name}/seed-{r}"
            episodes.append(e)
    return {"policy": name, "episodes": episodes}


def test_evaluation_statistics_and_task_check():
    n = 60
    rng = np.random.default_rng(0)
    rand = rng.random(n) < 0.1
    crew = rand | (rng.random(n) < 0.5)
    opt = crew | (rng.random(n) < 0.6)
    trained = np.stack([crew & (rng.random(n) < 0.9) for _ in range(4)])
    results = [_result("sac", trained, runs=True), _result("crew", crew), _result("random", rand),
               _result("optimiser", opt)]
    s = evaluation_statistics(results, samples=2000)
    assert s["success"]["crew"]["n"] == n and s["success"]["sac"]["n"] == 4 * n
    assert s["seeds"]["sac"]["runs"] == 4 and set(s["seeds"]) == {"sac"}
    assert [(c["a"], c["b"]) for c in s["paired"]] == [("sac", "crew"), ("crew", "random"), ("optimiser", "crew")]
    checks = {c["check"]: c["passed"] for c in s["checks"]}
    assert checks == {"crew beats random": True, "optimiser beats crew": True, "sac beats crew": False,
                      "mean reward orders the policies by success": None}  # the results hold no rewards
    text = format_statistics(s)
    assert "PASS  crew beats random" in text and "FAIL  sac beats crew" in text
    # a missing baseline is reported, not passed
    assert task_checks([], ["sac"])[0]["passed"] is None
    assert "NOT EVALUATED" in format_statistics(evaluation_statistics(results[:2], samples=200))
    json.dumps(s)  # plain JSON


def test_reward_order():
    """Four policies whose mean rewards rank them as their success rates, then one pair swapped."""
    def result(name, success, reward):
        return {"policy": name, "episodes": [{"scenario": f"s{i}", "seed": i, "success": s, "reward": r}
                                             for i, (s, r) in enumerate(zip(success, reward, strict=True))]}

    results = [result("crew", [1, 1, 0, 0], [0.6, 0.5, 0.2, 0.1]), result("random", [1, 0, 0, 0], [0.5] + [0.1] * 3),
               result("optimiser", [1, 1, 1, 0], [0.7] * 3 + [0.0]), result("sac", [1, 1, 1, 0], [0.8] * 3 + [0.1])]
    order = reward_order(results)
    assert order["pairs"] == 5 and order["same_order"] and order["discordant"] == []  # optimiser = sac: no pair
    assert order["by_reward"] == ["sac", "optimiser", "crew", "random"]
    results[1] = result("random", [1, 0, 0, 0], [0.9, 0.5, 0.5, math.nan])  # NaN (no episode) counts as 0
    order = reward_order(results)
    assert not order["same_order"] and order["discordant"] == [["crew", "random"]] and order["concordant"] == 4
    s = evaluation_statistics(results, samples=200)
    assert s["checks"][-1]["passed"] is False and s["reward_order"] == order
    assert "FAIL  mean reward orders the policies by success: 4 of 5 pairs in the same order" in format_statistics(s)


def test_compare_results_matches_scenarios_by_id_and_seed():
    a = _result("a", [True, False, True])
    b = _result("b", [False, False, True, True])
    b["episodes"] = b["episodes"][::-1]  # order does not matter, the extra scenario is left out
    c = compare_results(a, b, samples=500)
    assert c["n_scenarios"] == 3 and c["only_a"] == 1 and c["only_b"] == 0


def test_records_of_a_tiny_run(tmp_path, tiny_cfg, tiny_scenarios):
    crew = evaluate_policy(make_baseline("crew", PLAN_ENV, tiny_cfg), tiny_scenarios[:2], PLAN_ENV, tiny_cfg,
                           progress=False)
    rnd = combine_seeds([evaluate_policy(make_baseline("random", PLAN_ENV, tiny_cfg, seed=k), tiny_scenarios[:2],
                                         PLAN_ENV, tiny_cfg, progress=False, name=f"rnd/seed-{k}")
                         for k in (0, 1)], name="rnd")
    stats_ = evaluation_statistics([rnd, crew], samples=200)
    path = write_records([rnd, crew], tmp_path / "rl_evaluation.json", stats_)
    data = json.loads(path.read_text())  # strict JSON: NaN written as null
    recs = data["episodes"]
    assert len(recs) == 2 * 2 + 2 and recs == episode_records([rnd, crew])
    assert {r["run"] for r in recs if r["policy"] == "rnd"} == {"rnd/seed-0", "rnd/seed-1"}
    first = recs[-2]
    assert first["policy"] == "crew" and first["scenario"] == "calm" and first["seed"] == 1
    assert first["required_speed_m_s"] == tiny_cfg.reward.required_speed_m_s
    assert isinstance(first["success"], bool) and isinstance(first["limits_exceeded"], list)
    assert first["touchdown_speed_m_s"] > 5.0 and first["tilt_deg"] >= 0.0 and first["offset_m"] >= 0.0
    assert data["statistics"]["checks"][0]["check"] == "crew beats random"


def test_command_line_writes_records(tmp_path, tiny_cfg, tiny_scenarios, capsys):
    save_scenarios(tiny_scenarios[:2], tmp_path / "s.json")
    cfg_path = tmp_path / "tiny.yaml"
    cfg_path.write_text(json.dumps(tiny_cfg.model_dump(mode="json")))
    records = tmp_path / "results" / "rl_evaluation.json"
    rc = main(["crew", "random", "--scenarios", str(tmp_path / "s.json"), "--env", "plan", "--env-config",
               str(cfg_path), "--out", str(tmp_path / "out"), "--records", str(records), "--no-progress",
               "--bootstrap-samples", "300"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "Task check" in out and "crew beats random" in out and "NOT EVALUATED  optimiser beats crew" in out
    data = json.loads(records.read_text())
    assert [(r["policy"], r["scenario"]) for r in data["episodes"]] == [
        ("crew", "calm"), ("crew", "waves"), ("random", "calm"), ("random", "waves")]
    assert data["statistics"]["paired"][0]["samples"] == 300
    assert "statistics" in json.loads((tmp_path / "out" / "evaluation.json").read_text())

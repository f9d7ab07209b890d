"""Evaluation statistics: success rates with Wilson intervals, paired comparisons on shared scenarios, IQM over
training seeds, and the task check.

Everything here is numpy and the standard library (no scipy.stats, no rliable at import), so importing
:mod:`agents.evaluate` stays fast.

* **Success rate** of one policy: :func:`wilson_interval` (the Wilson score interval; unlike the normal
  approximation it stays inside [0, 1] and keeps its coverage near 0 and 1 and for a few dozen scenarios).
* **Paired comparison** of two policies on the same scenarios (:func:`paired_comparison`): the difference in
  success rate with a paired percentile bootstrap interval (:func:`paired_bootstrap_interval`: resample
  scenarios, the same indices for both policies), and the discordant counts (scenarios where only A succeeds,
  only B succeeds) with the exact McNemar p-value (:func:`mcnemar_exact`). Pairing removes the scenario-to-scenario
  spread (a hard geometry fails for every policy), which an unpaired comparison of two rates would count as noise.
* **Over training seeds**: the interquartile mean (IQM, the 25 % trimmed mean over all runs x tasks, as in rliable,
  Agarwal et al. 2021, "Deep Reinforcement Learning at the Edge of the Statistical Precipice") of the per-run
  success rates with a stratified bootstrap interval (:func:`iqm_interval`: runs resampled within each task,
  percentile method, as rliable's ``get_interval_estimates``). They are implemented here: rliable 1.2 needs
  ``arch<8``, and arch 7 does not import with pandas 3, while arch 8 refuses rliable's ``random_state`` argument,
  so rliable cannot run next to this project's dependencies. The test suite checks the IQM against
  ``scipy.stats.trim_mean(..., 0.25, axis=None)``, which is rliable's ``aggregate_iqm``.
* **Task check** (:func:`task_checks`): the crew beats random and the optimiser beats the crew, each with the
  paired interval of the difference above 0; every trained policy is checked against the crew the same way.
* **Reward and success** (:func:`reward_order`): whether ordering the policies by mean reward orders them by
  success rate (every pair of policies with different success rates ranked the same way by both), the check
  that the reward is aligned with what counts.

:func:`evaluation_statistics` computes all of it from the results of :func:`agents.evaluate.evaluate_policy`
(scenarios matched by id and seed; a policy trained with several seeds contributes one row per run, tagged
``run`` in its episodes), :func:`format_statistics` prints it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from statistics import NormalDist
from typing import Any

import numpy as np

CONFIDENCE = 0.95
BOOTSTRAP_SAMPLES = 10_000
BOOTSTRAP_SEED = 0
IQM_TRIM = 0.25
BASELINE_NAMES = ("random", "crew", "optimiser")
_CHUNK = 2_000_000  # bootstrap values drawn per chunk (bounds the index matrix's memory)


# --- one policy -------------------------------------------------------------------------------------------------
def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``successes / n``; ``(nan, nan)`` for ``n == 0``.

    ``centre = (p + z^2 / 2n) / (1 + z^2 / n)``, ``half = z / (1 + z^2 / n) * sqrt(p (1 - p) / n + z^2 / 4n^2)``
    with ``z`` the two-sided normal quantile of ``confidence`` (1.96 at 95 %). 8 of 10 gives [0.490, 0.943].
    """
    if n <= 0:
        return (math.nan, math.nan)
    if not 0 <= successes <= n:
        raise ValueError(f"successes {successes} outside [0, {n}]")
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    p = successes / n
    z2n = z * z / n
    centre = (p + z2n / 2.0) / (1.0 + z2n)
    half = z / (1.0 + z2n) * math.sqrt(p * (1.0 - p) / n + z2n / (4.0 * n))
    return (max(0.0, centre - half), min(1.0, centre + half))


def success_rate(success: Sequence[bool] | np.ndarray, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """``{successes, n, rate, ci}`` of a vector of episode successes, ``ci`` the Wilson interval."""
    s = np.asarray(success, dtype=bool).ravel()
    k, n = int(s.sum()), int(s.size)
    return {"successes": k, "n": n, "rate": k / n if n else math.nan, "ci": wilson_interval(k, n, confidence)}


# --- two policies on the same scenarios ---------------------------------------------------------------------------
def _percentile_interval(values: np.ndarray, confidence: float) -> tuple[float, float]:
    alpha = (1.0 - confidence) / 2.0
    lo, hi = np.quantile(values, [alpha, 1.0 - alpha])
    return (float(lo), float(hi))


def paired_bootstrap_interval(a: np.ndarray, b: np.ndarray, samples: int = BOOTSTRAP_SAMPLES,
                              seed: int = BOOTSTRAP_SEED, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Paired percentile bootstrap interval of ``mean(a) - mean(b)`` over scenarios (the last axis).

    ``a`` and ``b`` are success (or any score) arrays over the same scenarios in the same order: shape
    ``(n_scenarios,)`` or ``(n_runs, n_scenarios)`` (several training seeds of one policy; a row each). Each
    bootstrap sample draws ``n_scenarios`` scenario indices with replacement and uses the **same indices for
    both policies**, so a scenario's pair (and all runs on it) stays together. ``seed`` makes it reproducible.

    Hand-written rather than ``scipy.stats.bootstrap(..., paired=True)``: the statistic is the mean of the
    per-scenario difference, so one vectorised index matrix gives every resample at once; the percentile method
    matches rliable's; and scipy's default BCa interval is undefined for 0/1 data where the two policies agree on
    almost every scenario (every resample gives the same difference: scipy warns and returns NaN), a common
    case here, where this returns the degenerate interval it is (e.g. [0, 0]).
    """
    da = np.asarray(a, dtype=np.float64)
    db = np.asarray(b, dtype=np.float64)
    da = da.reshape(-1, da.shape[-1]).mean(axis=0)
    db = db.reshape(-1, db.shape[-1]).mean(axis=0)
    if da.shape != db.shape:
        raise ValueError(f"a and b cover different scenario counts: {da.size} and {db.size}")
    n = da.size
    if n == 0:
        return (math.nan, math.nan)
    d = da - db
    rng = np.random.default_rng(seed)
    means = np.empty(samples)
    step = max(1, _CHUNK // n)
    for start in range(0, samples, step):
        stop = min(samples, start + step)
        means[start:stop] = d[rng.integers(0, n, (stop - start, n))].mean(axis=1)
    return _percentile_interval(means, confidence)


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """Exact (binomial) McNemar p-value, two-sided, from the discordant counts.

    Under the null hypothesis (equal success probability) each discordant scenario goes either way with
    probability 1/2: ``p = min(1, 2 * P(X <= min(only_a, only_b)))`` with ``X ~ Binomial(only_a + only_b, 1/2)``,
    which equals ``scipy.stats.binomtest(only_a, only_a + only_b, 0.5).pvalue``. 1 without discordant pairs.
    """
    n = only_a + only_b
    if n == 0:
        return 1.0
    k = min(only_a, only_b)
    tail = sum(math.comb(n, i) for i in range(k + 1))
    return min(1.0, 2.0 * tail / 2**n)


def paired_comparison(a: np.ndarray, b: np.ndarray, name_a: str = "a", name_b: str = "b",
                      samples: int = BOOTSTRAP_SAMPLES, seed: int = BOOTSTRAP_SEED,
                      confidence: float = CONFIDENCE) -> dict[str, Any]:
    """``name_a`` minus ``name_b`` in success rate on the same scenarios.

    ``a``, ``b``: boolean success arrays ``(n_scenarios,)`` or ``(n_runs, n_scenarios)``; a single row is
    compared with every row of the other. Returns ``a``, ``b``, ``n_scenarios``, ``rate_a``, ``rate_b``,
    ``difference`` (rate_a - rate_b), ``ci`` (:func:`paired_bootstrap_interval`), ``samples``, ``seed``,
    ``only_a``, ``only_b`` (discordant counts summed over the row pairs) and ``mcnemar`` (one entry per row
    pair: ``{only_a, only_b, p_value}``; rows of several training seeds on one scenario are not independent, so
    each row pair gets its own exact test rather than one pooled test).
    """
    xa = np.atleast_2d(np.asarray(a, dtype=bool))
    xb = np.atleast_2d(np.asarray(b, dtype=bool))
    if xa.shape[1] != xb.shape[1]:
        raise ValueError(f"a and b cover different scenario counts: {xa.shape[1]} and {xb.shape[1]}")
    if xa.shape[0] != xb.shape[0] and 1 not in (xa.shape[0], xb.shape[0]):
        raise ValueError(f"runs do not pair: {xa.shape[0]} and {xb.shape[0]}")
    rows = max(xa.shape[0], xb.shape[0])
    pa = np.broadcast_to(xa, (rows, xa.shape[1]))
    pb = np.broadcast_to(xb, (rows, xb.shape[1]))
    tests = []
    for ra, rb in zip(pa, pb, strict=True):
        oa, ob = int(np.sum(ra & ~rb)), int(np.sum(~ra & rb))
        tests.append({"only_a": oa, "only_b": ob, "p_value": mcnemar_exact(oa, ob)})
    rate_a, rate_b = float(xa.mean()), float(xb.mean())
    return {"a": name_a, "b": name_b, "n_scenarios": int(xa.shape[1]), "rate_a": rate_a, "rate_b": rate_b,
            "difference": rate_a - rate_b,
            "ci": paired_bootstrap_interval(xa, xb, samples, seed, confidence), "samples": samples, "seed": seed,
            "only_a": sum(t["only_a"] for t in tests), "only_b": sum(t["only_b"] for t in tests), "mcnemar": tests}


# --- over training seeds ------------------------------------------------------------------------------------------
def iqm(scores: np.ndarray) -> float:
    """Interquartile mean: the mean of the middle half of all values (``int(0.25 n)`` cut at each end)."""
    v = np.sort(np.asarray(scores, dtype=np.float64).ravel())
    cut = int(IQM_TRIM * v.size)
    return float(v[cut: v.size - cut].mean()) if v.size else math.nan


def stratified_bootstrap_iqm(scores: np.ndarray, samples: int = BOOTSTRAP_SAMPLES, seed: int = BOOTSTRAP_SEED,
                             confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Percentile interval of the IQM under a stratified bootstrap of ``scores`` ``(n_runs, n_tasks)``.

    Each sample resamples the runs with replacement **within each task** (independently per task), the
    stratified bootstrap of rliable's ``StratifiedBootstrap`` without task resampling. One task (a scenario
    set scored as one success rate per run) reduces to resampling runs.
    """
    x = np.asarray(scores, dtype=np.float64)
    x = x.reshape(x.shape[0], -1)
    n_runs, n_tasks = x.shape
    if n_runs == 0:
        return (math.nan, math.nan)
    rng = np.random.default_rng(seed)
    total = n_runs * n_tasks
    cut = int(IQM_TRIM * total)
    values = np.empty(samples)
    step = max(1, _CHUNK // total)
    cols = np.arange(n_tasks)
    for start in range(0, samples, step):
        stop = min(samples, start + step)
        idx = rng.integers(0, n_runs, (stop - start, n_runs, n_tasks))
        res = np.sort(x[idx, cols].reshape(stop - start, total), axis=1)
        values[start:stop] = res[:, cut: total - cut].mean(axis=1)
    return _percentile_interval(values, confidence)


def iqm_interval(scores: np.ndarray, samples: int = BOOTSTRAP_SAMPLES, seed: int = BOOTSTRAP_SEED,
                 confidence: float = CONFIDENCE) -> dict[str, Any]:
    """``{iqm, ci, runs, tasks, samples, seed}`` of per-run scores ``(n_runs,)`` or ``(n_runs, n_tasks)``."""
    x = np.asarray(scores, dtype=np.float64)
    x = x.reshape(x.shape[0], -1) if x.ndim else x.reshape(1, 1)
    return {"iqm": iqm(x), "ci": stratified_bootstrap_iqm(x, samples, seed, confidence),
            "runs": int(x.shape[0]), "tasks": int(x.shape[1]), "samples": samples, "seed": seed}


# --- evaluation results -------------------------------------------------------------------------------------------
def _scenario_key(episode: dict[str, Any]) -> tuple[str, int]:
    return (str(episode["scenario"]), int(episode["seed"]))


def success_matrix(result: dict[str, Any]) -> tuple[list[tuple[str, int]], list[str], np.ndarray]:
    """Scenario keys ``(id, seed)`` (first-seen order), run labels and the success matrix ``(runs, scenarios)``
    of one evaluation result; episodes without ``run`` form one run named after the policy. A scenario missing
    from a run counts as a failure there."""
    runs: dict[str, dict[tuple[str, int], bool]] = {}
    keys: dict[tuple[str, int], None] = {}
    for e in result["episodes"]:
        run = str(e.get("run", result["policy"]))
        key = _scenario_key(e)
        keys[key] = None
        runs.setdefault(run, {})[key] = bool(e["success"])
    order = list(keys)
    matrix = np.array([[row.get(k, False) for k in order] for row in runs.values()], dtype=bool)
    return order, list(runs), matrix.reshape(len(runs), len(order))


def compare_results(a: dict[str, Any], b: dict[str, Any], samples: int = BOOTSTRAP_SAMPLES,
                    seed: int = BOOTSTRAP_SEED, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """:func:`paired_comparison` of two evaluation results on the scenarios both have (matched by id and seed)."""
    keys_a, _, ma = success_matrix(a)
    keys_b, _, mb = success_matrix(b)
    in_b = set(keys_b)
    common = [k for k in keys_a if k in in_b]
    ia = [keys_a.index(k) for k in common]
    ib = [keys_b.index(k) for k in common]
    return paired_comparison(ma[:, ia], mb[:, ib], a["policy"], b["policy"], samples, seed, confidence)


def task_checks(comparisons: list[dict[str, Any]], trained: Sequence[str] = ()) -> list[dict[str, Any]]:
    """The task check: crew beats random, optimiser beats crew, and each ``trained`` policy beats crew.

    Each check is ``{check, a, b, passed, difference, ci}``; ``passed`` is True where the paired interval of
    ``a - b`` lies above 0, False where it does not, None where the pair was not evaluated.
    """
    by_pair = {(c["a"], c["b"]): c for c in comparisons}
    wanted = [("crew", "random"), ("optimiser", "crew"), *((name, "crew") for name in trained)]
    checks = []
    for a, b in wanted:
        c = by_pair.get((a, b))
        checks.append({"check": f"{a} beats {b}", "a": a, "b": b,
                       "passed": None if c is None else bool(c["ci"][0] > 0.0),
                       "difference": None if c is None else c["difference"],
                       "ci": None if c is None else c["ci"]})
    return checks


def reward_order(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Do the policies' mean rewards order them as their success rates do?

    Returns ``by_success`` and ``by_reward`` (policy names, best first), ``pairs`` (pairs of policies whose success
    rates differ), ``concordant`` (of those, the pairs the mean reward ranks the same way), ``discordant`` (the
    others, as ``[better by success, better by reward]``) and ``same_order`` (no discordant pair). Episodes without
    a finite reward count as reward 0 (an episode that never started scores nothing); a result without any is
    left out.
    """
    rows = []
    for r in results:
        success = np.array([bool(e["success"]) for e in r["episodes"]], dtype=float)
        reward = np.array([e.get("reward", math.nan) for e in r["episodes"]], dtype=float)
        if not np.isfinite(reward).any():
            continue  # a result without rewards takes no part
        rows.append((r["policy"], float(success.mean()), float(np.where(np.isfinite(reward), reward, 0.0).mean())))
    discordant, pairs = [], 0
    for i, (a, sa, ra) in enumerate(rows):
        for b, sb, rb in rows[i + 1:]:
            if sa == sb:
                continue
            pairs += 1
            if (sa - sb) * (ra - rb) <= 0.0:
                discordant.append([a, b] if sa > sb else [b, a])
    return {"by_success": [n for n, _, _ in sorted(rows, key=lambda x: -x[1])],
            "by_reward": [n for n, _, _ in sorted(rows, key=lambda x: -x[2])],
            "mean_reward": {n: rw for n, _, rw in rows}, "success_rate": {n: sr for n, sr, _ in rows},
            "pairs": pairs, "concordant": pairs - len(discordant), "discordant": discordant,
            "same_order": not discordant}


def evaluation_statistics(results: list[dict[str, Any]], samples: int = BOOTSTRAP_SAMPLES,
                          seed: int = BOOTSTRAP_SEED, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """All statistics of a set of evaluation results (one per policy, same scenarios).

    Returns ``success`` (per policy: :func:`success_rate` over all its episodes), ``seeds`` (per policy with
    per-run results: :func:`iqm_interval` of the runs' success rates), ``paired`` (each trained policy minus
    crew, crew minus random, optimiser minus crew, where both were evaluated: :func:`compare_results`),
    ``reward_order`` (:func:`reward_order`) and ``checks`` (:func:`task_checks`, and whether the mean reward orders
    the policies by success). Policies named ``random``, ``crew``, ``optimiser`` are the baselines; the
    others count as trained policies.
    """
    by_name = {r["policy"]: r for r in results}
    trained = [r["policy"] for r in results if r["policy"] not in BASELINE_NAMES]
    success = {r["policy"]: success_rate([e["success"] for e in r["episodes"]], confidence) for r in results}
    seeds = {}
    for r in results:
        _, runs, m = success_matrix(r)
        if len(runs) > 1:
            seeds[r["policy"]] = {**iqm_interval(m.mean(axis=1), samples, seed, confidence),
                                  "per_run": dict(zip(runs, m.mean(axis=1).tolist(), strict=True))}
    pairs = [*((name, "crew") for name in trained), ("crew", "random"), ("optimiser", "crew")]
    paired = [compare_results(by_name[a], by_name[b], samples, seed, confidence)
              for a, b in pairs if a in by_name and b in by_name]
    order = reward_order(results)
    checks = task_checks(paired, trained)
    checks.append({"check": "mean reward orders the policies by success", "a": None, "b": None,
                   "passed": order["same_order"] if order["pairs"] else None, "difference": None, "ci": None,
                   "concordant": order["concordant"], "pairs": order["pairs"]})
    return {"confidence": confidence, "success": success, "seeds": seeds, "paired": paired, "reward_order": order,
            "checks": checks}


def _pct(x: float) -> str:
    return f"{100.0 * x:.1f} %"


def _pct_ci(ci: Sequence[float]) -> str:
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}] %"


def format_statistics(stats: dict[str, Any]) -> str:
    """The statistics as text: success rates, IQM over seeds, paired differences, and the task check."""
    level = f"{100 * stats['confidence']:.0f} %"
    lines = [f"Success rate (Wilson {level} interval):"]
    for name, s in stats["success"].items():
        lines.append(f"  {name}: {s['successes']}/{s['n']} = {_pct(s['rate'])} {_pct_ci(s['ci'])}")
    if stats["seeds"]:
        lines.append(f"Over training seeds (IQM of per-run success, stratified bootstrap {level}):")
        for name, s in stats["seeds"].items():
            lines.append(f"  {name}: IQM {_pct(s['iqm'])} {_pct_ci(s['ci'])} over {s['runs']} runs")
    if stats["paired"]:
        lines.append(f"Paired differences on the same scenarios (bootstrap {level}, exact McNemar):")
        for c in stats["paired"]:
            ps = ", ".join(f"{t['p_value']:.3g}" for t in c["mcnemar"])
            lines.append(f"  {c['a']} - {c['b']}: {100 * c['difference']:+.1f} points {_pct_ci(c['ci'])} "
                         f"on {c['n_scenarios']} scenarios; only {c['a']} {c['only_a']}, only {c['b']} "
                         f"{c['only_b']}; McNemar p = {ps}")
    lines.append("Task check (paired interval of the difference above 0):")
    for c in stats["checks"]:
        if c["passed"] is None:
            lines.append(f"  NOT EVALUATED  {c['check']}")
        elif c["difference"] is None:
            lines.append(f"  {'PASS' if c['passed'] else 'FAIL'}  {c['check']}: {c['concordant']} of {c['pairs']} "
                         f"pairs in the same order")
        else:
            lines.append(f"  {'PASS' if c['passed'] else 'FAIL'}  {c['check']}: {100 * c['difference']:+.1f} "
                         f"points {_pct_ci(c['ci'])}")
    return "\n".join(lines) + "\n"

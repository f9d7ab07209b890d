"""Evaluate policies (trained runs and baselines) on a fixed scenario set.

Python::

    from agents.evaluate import evaluate_policy, summarize, markdown_table
    from agents.baselines import make_baseline
    from agents.runs import load_run
    from agents.scenarios import held_out_scenarios

    scenarios = held_out_scenarios(12)
    crew = evaluate_policy(make_baseline("crew", "moor_env/AnchorPlan-v0"), scenarios)
    run = load_run("runs/plan-sac/seed-0")          # a RunPolicy: the SB3 model, its normalisation, its env
    trained = evaluate_policy(run, scenarios, env_id=run.env_id, env_config=run.env_config)
    print(markdown_table([trained, crew]))

Command line::

    python -m agents.evaluate runs/plan-sac crew random optimiser [--scenarios FILE] [--n-scenarios 24]
        [--records benchmarks/results/rl_evaluation.json] [--bootstrap-samples 10000] [--bootstrap-seed 0]

A result (``evaluate_policy``) is a dict: ``policy``, ``env_id``, ``episodes`` (one record per scenario,
:func:`agents.episodes.run_episode`: ``touchdown_speed_m_s``, ``tilt_deg``, ``reward``, ``success``,
``limits_exceeded``, ``sim_status``, ``chain_past_back_end_m`` ...) and ``summary`` (:func:`summarize`;
``chain_inside``: touchdowns whose vertical chain ended past the anchor's back end; the line-anchor contact keeps the
chain out, so it counts touchdowns where that contact was switched off or failed: docs/fall-accuracy.md). Several
results of one policy trained with different seeds combine with :func:`combine_seeds` (t-interval over the seeds'
means; each pooled episode keeps its ``run``).

**Statistics** (:mod:`agents.statistics`, :func:`agents.statistics.evaluation_statistics`): success rates with
Wilson intervals, paired differences on the same scenarios (trained policy minus crew, crew minus random, optimiser
minus crew: paired bootstrap interval, discordant counts, exact McNemar p-value), IQM over training seeds with a
stratified bootstrap interval, and the task check (crew beats random, optimiser beats crew, each trained policy
beats crew: PASS where the paired interval lies above 0). The command line prints them, stores them in
``evaluation.json`` and writes every policy's per-episode records (:func:`episode_records`) with them to
``--records`` (default ``benchmarks/results/rl_evaluation.json``).

**Success** (:func:`agents.success.success_of`): touchdown with tilt below ``SUCCESS_TILT_DEG`` (2 deg, the Gjoa
result; the DPA criterion is 5 deg) and speed at or above the env config's ``reward.required_speed_m_s`` (24 m/s),
and no limit exceeded: no line above its MBL, the release unit's rating not exceeded, no fibre on the seabed (the
``tension``, ``release_unit`` and ``fibre_seabed`` reward terms of the episode are all zero).
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import moor_env  # noqa: F401 - registers the envs
from agents.baselines import BASELINES, PLAN_ENV, PLAN_V1_ENV, RELEASE_ENV, is_plan_env, is_plan_v1, make_baseline
from agents.bundle import resolve_target
from agents.config import load_train_config
from agents.episodes import render_episode, run_episode
from agents.policy import Policy
from agents.report import markdown_table, write_records, write_report
from agents.runs import run_dirs
from agents.scenarios import (
    DEFAULT_COUNT,
    DEFAULT_SITE_COUNT,
    PLAN_V1_CONFIG,
    held_out_scenarios,
    held_out_sites,
    load_scenarios,
)
from agents.statistics import BOOTSTRAP_SAMPLES as STATS_BOOTSTRAP_SAMPLES
from agents.statistics import BOOTSTRAP_SEED, evaluation_statistics, format_statistics, wilson_interval
from agents.train_rllib import load_run_policies
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.errors import ConfigError

CONFIDENCE = 0.95
BOOTSTRAP_SAMPLES = 2000
ENV_ALIASES = {"plan": PLAN_ENV, "plan-v1": PLAN_V1_ENV, "release": RELEASE_ENV}
RECORDS_PATH = "benchmarks/results/rl_evaluation.json"


# --- evaluation (optionally in worker processes) --------------------------------------------------------------------
_WORKER: dict[str, Any] = {}


def _worker_init(policy: Policy, env_id: str, cfg: EnvConfig) -> None:
    try:
        import torch  # noqa: PLC0415 - torch (optional): one thread per worker where it is installed

        torch.set_num_threads(1)
    except ImportError:  # pragma: no cover - torch comes with the rl extra
        pass
    _WORKER.update(policy=policy, env_id=env_id, cfg=cfg, env=gym.make(env_id, config=cfg))


def _worker_run(scenario: dict[str, Any]) -> dict[str, Any]:
    w = _WORKER
    return run_episode(w["env"], w["policy"], scenario, w["env_id"], w["cfg"])


def evaluate_policy(policy: Policy, scenarios: list[dict[str, Any]], env_id: str = PLAN_ENV,
                    env_config: str | dict | EnvConfig = "anchor-release", n_jobs: int = 1,
                    progress: bool = True, name: str | None = None) -> dict[str, Any]:
    """Run ``policy`` once on every scenario; returns ``{policy, env_id, episodes, summary, wall_s}``.

    Parameters
    ----------
    policy : Policy
        A baseline (:func:`agents.baselines.make_baseline`) or a trained run (:func:`agents.runs.load_run`).
    scenarios : list of dict
        ``{id, seed, options}`` mappings (:func:`agents.scenarios.held_out_scenarios`).
    env_id, env_config :
        The env and its config (a trained run's own: ``run.env_id``, ``run.env_config``).
    n_jobs : int
        Worker processes (forked; each builds its own env). 1 runs in this process.
    progress : bool
        Show a tqdm bar over the scenarios.
    name : str, optional
        Label in tables and plots (default ``policy.name``).
    """
    cfg = env_config if isinstance(env_config, EnvConfig) else load_env_config(env_config)
    label = name or policy.name
    t0 = time.perf_counter()
    bar = tqdm(total=len(scenarios), desc=f"evaluate {label}", disable=not progress, leave=False)
    if n_jobs <= 1 or len(scenarios) == 1:
        _worker_init(policy, env_id, cfg)
        episodes = []
        for sc in scenarios:
            episodes.append(_worker_run(sc))
            bar.update()
        _WORKER.clear()
    else:
        ctx = mp.get_context("fork")
        with ctx.Pool(min(n_jobs, len(scenarios)), _worker_init, (policy, env_id, cfg)) as pool:
            episodes = []
            for rec in pool.imap(_worker_run, scenarios):
                episodes.append(rec)
                bar.update()
    bar.close()
    return {"policy": label, "env_id": env_id, "episodes": episodes, "summary": summarize(episodes),
            "wall_s": time.perf_counter() - t0}


# --- statistics ----------------------------------------------------------------------------------------------------
def bootstrap_ci(values: np.ndarray, seed: int = 0, samples: int = BOOTSTRAP_SAMPLES) -> tuple[float, float]:
    """Percentile bootstrap 95 % interval of the mean (over scenarios); NaNs dropped."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (math.nan, math.nan)
    rng = np.random.default_rng(seed)
    means = v[rng.integers(0, v.size, (samples, v.size))].mean(axis=1)
    alpha = (1.0 - CONFIDENCE) / 2.0
    return (float(np.quantile(means, alpha)), float(np.quantile(means, 1.0 - alpha)))


def t_interval(values: np.ndarray) -> tuple[float, float]:
    """Student-t 95 % interval of the mean (over training seeds); a single value gives (v, v)."""
    from scipy import stats  # noqa: PLC0415 - scipy.stats takes about 0.5 s to import; only this needs it

    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (math.nan, math.nan)
    if v.size == 1:
        return (float(v[0]), float(v[0]))
    half = stats.t.ppf(0.5 + CONFIDENCE / 2.0, v.size - 1) * v.std(ddof=1) / math.sqrt(v.size)
    return (float(v.mean() - half), float(v.mean() + half))


def _stats(values: np.ndarray) -> dict[str, float]:
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"mean": math.nan, "std": math.nan, "p10": math.nan, "p90": math.nan}
    return {"mean": float(v.mean()), "std": float(v.std(ddof=1)) if v.size > 1 else 0.0,
            "p10": float(np.quantile(v, 0.1)), "p90": float(np.quantile(v, 0.9))}


def summarize(episodes: list[dict[str, Any]]) -> dict[str, Any]:
    """Success rate with its Wilson 95 % interval; speed, tilt and reward statistics, the mean reward with a
    bootstrap 95 % interval over the scenarios."""
    col = {k: np.array([e[k] for e in episodes], dtype=np.float64)
           for k in ("success", "touchdown_speed_m_s", "tilt_deg", "reward")}
    limits: dict[str, int] = {}
    for e in episodes:
        for k in e["limits_exceeded"]:
            limits[k] = limits.get(k, 0) + 1
    return {
        "episodes": len(episodes),
        "touchdowns": int(sum(e["touchdown"] for e in episodes)),
        "success_rate": float(col["success"].mean()),
        "success_ci": wilson_interval(int(col["success"].sum()), len(episodes)),
        "speed_m_s": _stats(col["touchdown_speed_m_s"]),
        "tilt_deg": _stats(col["tilt_deg"]),
        "reward": {**_stats(col["reward"]), "ci": bootstrap_ci(col["reward"])},
        "limits_exceeded": limits,
        # records without the key count as not inside
        "chain_inside": int(sum(e.get("chain_past_back_end_m", math.nan) > 0.0 for e in episodes)),
    }


def combine_seeds(results: list[dict[str, Any]], name: str | None = None) -> dict[str, Any]:
    """One policy trained with several seeds: pooled episodes (each tagged with its ``run``, the seed result's
    policy name), and t-intervals over the seeds' means."""
    if not results:
        raise ValueError("combine_seeds needs at least one result")
    episodes = [{**e, "run": e.get("run", r["policy"])} for r in results for e in r["episodes"]]
    summary = summarize(episodes)
    per_seed = {k: [r["summary"][k] if k == "success_rate" else r["summary"][k]["mean"] for r in results]
                for k in ("success_rate", "speed_m_s", "tilt_deg", "reward")}
    summary["seeds"] = len(results)
    summary["per_seed"] = per_seed
    summary["success_ci"] = t_interval(per_seed["success_rate"]) if len(results) > 1 else summary["success_ci"]
    summary["reward"]["ci"] = t_interval(per_seed["reward"]) if len(results) > 1 else summary["reward"]["ci"]
    return {"policy": name or results[0]["policy"], "env_id": results[0]["env_id"], "episodes": episodes,
            "summary": summary, "wall_s": float(sum(r["wall_s"] for r in results)),
            "seed_results": [{"policy": r["policy"], "summary": r["summary"]} for r in results]}


# --- command line -----------------------------------------------------------------------------------------------------
def evaluate_targets(targets: list[str], scenarios: list[dict[str, Any]], env: str | None = None,
                     env_config: str = "anchor-release", n_jobs: int = 1, progress: bool = True,
                     optimiser: dict[str, int] | None = None, checkpoint: str = "final") -> list[dict[str, Any]]:
    """Evaluate run directories and baseline names; baselines run on ``env`` or else on the first run's env."""
    runs = [(t, load_run_policies(resolve_target(t), checkpoint)) for t in targets if t not in BASELINES]
    results = []
    env_id = ENV_ALIASES.get(env, env) if env else (runs[0][1][0].env_id if runs else PLAN_ENV)
    base_cfg = runs[0][1][0].env_config if runs and not env else load_env_config(env_config)
    for target in targets:
        if target in BASELINES:
            b_env = env_id if target != "optimiser" or is_plan_env(env_id) else PLAN_ENV
            kwargs = dict(optimiser or {}) if target == "optimiser" else {}
            policy = make_baseline(target, b_env, base_cfg, **kwargs)
            results.append(evaluate_policy(policy, scenarios, b_env, base_cfg, n_jobs, progress))
            continue
        policies = dict(runs)[target]
        per_seed = [evaluate_policy(p, scenarios, p.env_id, p.env_config, n_jobs, progress, name=p.name)
                    for p in policies]
        results.append(combine_seeds(per_seed, name=Path(target).name))
    return results


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line arguments of ``python -m agents.evaluate``."""
    p = argparse.ArgumentParser(prog="python -m agents.evaluate", description=__doc__.split("\n\n")[0])
    p.add_argument("targets", nargs="+", help="run directories and/or baseline names: " + ", ".join(BASELINES))
    p.add_argument("--scenarios", help="scenario file (JSON/YAML list of {id, seed, options}); default: held-out set")
    p.add_argument("--n-scenarios", type=int, default=None,
                   help="size of the default held-out set (AnchorPlan-v1: 500 sites, else 24 scenarios)")
    p.add_argument("--env", help="env of the baselines: plan, plan-v1, release or an env id (default: the first "
                                 "run's)")
    p.add_argument("--env-config", default=None, help="env config of the baselines without a run (default: "
                                                      "anchor-plan on AnchorPlan-v1, else anchor-release)")
    p.add_argument("--checkpoint", default="final", choices=("final", "best", "last"))
    p.add_argument("--out", default="runs/evaluation", help="output folder (JSON, markdown, plots)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes")
    p.add_argument("--population", type=int, default=8, help="optimiser: candidates per iteration")
    p.add_argument("--iterations", type=int, default=3, help="optimiser: cross-entropy iterations")
    p.add_argument("--render", action="store_true", help="also save a rendered episode of the first target")
    p.add_argument("--records", default=RECORDS_PATH, help="per-episode records and statistics (JSON)")
    p.add_argument("--bootstrap-samples", type=int, default=STATS_BOOTSTRAP_SAMPLES,
                   help="resamples of the paired and stratified bootstraps")
    p.add_argument("--bootstrap-seed", type=int, default=BOOTSTRAP_SEED, help="seed of the bootstraps")
    p.add_argument("--no-progress", action="store_true")
    return p.parse_args(argv)


def targets_env_id(targets: list[str], env: str | None = None) -> str:
    """The env an evaluation runs on: ``env`` (an alias of :data:`ENV_ALIASES` or an id), else the first trained
    target's, else ``AnchorPlan-v0``."""
    if env:
        return ENV_ALIASES.get(env, env)
    for target in targets:
        if target not in BASELINES:
            return load_train_config(run_dirs(resolve_target(target))[0] / "config.yaml").env.id
    return PLAN_ENV


def default_scenarios(env_id: str, n: int | None = None) -> list[dict[str, Any]]:
    """The held-out set of an env: :func:`~agents.scenarios.held_out_sites` on ``AnchorPlan-v1`` (``n`` default
    500), else :func:`~agents.scenarios.held_out_scenarios` (``n`` default 24)."""
    if is_plan_v1(env_id):
        return held_out_sites(n or DEFAULT_SITE_COUNT)
    return held_out_scenarios(n or DEFAULT_COUNT)


def main(argv: list[str] | None = None) -> int:
    """Entry point: evaluate, write the report, print the table."""
    args = parse_args(argv)
    try:
        env_id = targets_env_id(args.targets, args.env)
        env_config = args.env_config or (PLAN_V1_CONFIG if is_plan_v1(env_id) else "anchor-release")
        scenarios = load_scenarios(args.scenarios) if args.scenarios else default_scenarios(env_id, args.n_scenarios)
        optimiser = {"population": args.population, "iterations": args.iterations,
                     "elite": min(3, args.population)}
        results = evaluate_targets(args.targets, scenarios, args.env, env_config, args.jobs,
                                   not args.no_progress, optimiser, args.checkpoint)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    meta = {"argv": sys.argv[1:] if argv is None else argv}
    stats = evaluation_statistics(results, args.bootstrap_samples, args.bootstrap_seed)
    write_report(results, args.out, scenarios, meta, stats)
    write_records(results, args.records, stats, {**meta, "scenarios": scenarios})
    if args.render:
        first = args.targets[0]
        policy = (make_baseline(first, results[0]["env_id"], env_config) if first in BASELINES
                  else load_run_policies(resolve_target(first), args.checkpoint)[0])
        render_episode(policy, scenarios[0], Path(args.out) / "episode.png", results[0]["env_id"],
                       getattr(policy, "env_config", env_config))
    print(markdown_table(results))
    print(format_statistics(stats))
    print(f"written to {args.out}/ (evaluation.json, evaluation.md, distributions.png) and {args.records}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

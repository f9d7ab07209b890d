"""Learning curves: success against env steps for every training seed, with the baselines as levels.

Python::

    from agents.curves import learning_curves, baseline_levels, plot_learning_curves
    curves = {"SAC": learning_curves("runs/full"), "PPO": learning_curves("runs/plan-v1-ppo")}
    levels = baseline_levels(["crew", "optimiser"], "runs/full")
    plot_learning_curves(curves, levels, "docs/agents-learning-curves.png")

Command line::

    python -m agents.curves runs/full runs/plan-v1-ppo [--baselines crew optimiser] [--out curves.png]

The curves are the runs' own ``evaluations.json`` (:mod:`agents.train`'s evaluation callback: deterministic
episodes on the fixed training-distribution seeds ``eval.seed``, ``eval.seed + 1`` ...). The baselines' levels are
their success on those same episodes (:func:`eval_scenarios`), so the lines compare like with like.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from agents.baselines import is_plan_env, make_baseline
from agents.bundle import resolve_target
from agents.config import TrainConfig, load_train_config
from agents.evaluate import evaluate_policy
from agents.report import save_figure
from agents.runs import run_dirs
from moor_env.envs.config import load_env_config
from moor_env.errors import ConfigError


def learning_curves(target: str | Path) -> dict[str, list[tuple[int, float]]]:
    """``{run name: [(env steps, success rate), ...]}`` of a run, an experiment (its ``seed-*`` runs) or a bundled
    policy's folder, read from each run's ``evaluations.json``."""
    out = {}
    for run in run_dirs(resolve_target(str(target))):
        path = run / "evaluations.json"
        if path.is_file():
            out[run.name] = [(int(e["timesteps"]), float(e["success_rate"])) for e in json.loads(path.read_text())]
    return out


def eval_scenarios(cfg: TrainConfig) -> list[dict[str, Any]]:
    """The scenarios of a training config's evaluation callback (:mod:`agents.train`)."""
    return [{"id": f"train-{i}", "seed": cfg.eval.seed + i, "options": {}} for i in range(cfg.eval.episodes)]


def baseline_levels(names: list[str], target: str | Path, jobs: int = 1,
                    optimiser: dict[str, int] | None = None) -> dict[str, float]:
    """Success of each baseline on the evaluation episodes of the first run of ``target``."""
    cfg = load_train_config(run_dirs(resolve_target(str(target)))[0] / "config.yaml")
    env_cfg = load_env_config(cfg.env.config, cfg.env.overrides)
    scenarios = eval_scenarios(cfg)
    levels = {}
    for name in names:
        if name == "optimiser" and not is_plan_env(cfg.env.id):
            continue
        kwargs = dict(optimiser or {}) if name == "optimiser" else {}
        policy = make_baseline(name, cfg.env.id, env_cfg, **kwargs)
        result = evaluate_policy(policy, scenarios, cfg.env.id, env_cfg, n_jobs=jobs, progress=False)
        levels[name] = result["summary"]["success_rate"]
    return levels


def plot_learning_curves(curves: dict[str, dict[str, list[tuple[int, float]]]], levels: dict[str, float],
                         path: str | Path, title: str = "") -> Path:
    """Success against env steps: one thin line per seed, the mean over seeds thick, per experiment; the
    baselines as horizontal lines."""
    import matplotlib  # noqa: PLC0415 - matplotlib loads only to draw a figure

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415 - matplotlib, after its backend is chosen

    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (label, runs) in enumerate(curves.items()):
        colour = colours[k % len(colours)]
        for points in runs.values():
            steps, success = zip(*points, strict=True)
            ax.plot(steps, success, color=colour, lw=0.8, alpha=0.45)
        common = sorted(set.intersection(*(set(s for s, _ in p) for p in runs.values()))) if runs else []
        if common:
            mean = [np.mean([dict(p)[s] for p in runs.values()]) for s in common]
            ax.plot(common, mean, color=colour, lw=2.2, label=f"{label} (mean of {len(runs)} seeds)")
    for k, (name, level) in enumerate(levels.items()):
        ax.axhline(level, color="k", ls=("--", ":", "-.")[k % 3], lw=1.2, label=f"{name} {100 * level:.0f} %")
    ax.set_xlabel("env steps (installations)")
    ax.set_ylabel("success rate on the evaluation episodes")
    ax.set_ylim(0.0, 1.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    out = save_figure(fig, path)
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    """Plot the learning curves of the given runs with the baselines' levels."""
    p = argparse.ArgumentParser(prog="python -m agents.curves", description=__doc__.split("\n\n")[0])
    p.add_argument("targets", nargs="+", help="experiment or run directories, or bundled policy names")
    p.add_argument("--baselines", nargs="*", default=["crew", "optimiser"])
    p.add_argument("--out", default="runs/learning-curves.png")
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--population", type=int, default=8)
    p.add_argument("--iterations", type=int, default=3)
    args = p.parse_args(argv)
    try:
        curves = {Path(t).name: learning_curves(t) for t in args.targets}
        optimiser = {"population": args.population, "iterations": args.iterations, "elite": min(3, args.population)}
        levels = baseline_levels(args.baselines, args.targets[0], args.jobs, optimiser)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = plot_learning_curves(curves, levels, args.out)
    for name, runs in curves.items():
        for run, points in runs.items():
            print(f"{name}/{run}: " + ", ".join(f"{s}: {100 * v:.0f} %" for s, v in points))
    print(", ".join(f"{k} {100 * v:.1f} %" for k, v in levels.items()), f"-> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The main job: train a preset, evaluate it against the baselines on the held-out scenarios, print the table.

    python -m agents.main --config configs/agents/quick.yaml [--set key=value ...] [--n-scenarios 12] [--jobs 2]

Trains every seed of the config (resuming a run that exists, so a second call only evaluates), then evaluates the
trained policy, the crew rule of thumb, random actions and (on ``AnchorPlan-v0``) the per-scenario optimiser on
``held_out_scenarios(n)``; writes ``evaluation.json``, ``evaluation.md``, ``distributions.png`` and
``episode.png`` (a rendered held-out episode of the trained policy) into ``<out_dir>/<name>/evaluation/``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from agents.baselines import is_plan_env
from agents.config import load_train_config, parse_set
from agents.evaluate import evaluate_targets, markdown_table, render_episode, write_report
from agents.runs import load_run
from agents.scenarios import held_out_scenarios, load_scenarios
from agents.train import train
from moor_env.errors import ConfigError

MAIN_SCENARIOS = 12


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line arguments of ``python -m agents.main``."""
    p = argparse.ArgumentParser(prog="python -m agents.main", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", default="quick", help="training config (default: the quick preset)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="training config override")
    p.add_argument("--n-scenarios", type=int, default=MAIN_SCENARIOS, help="held-out scenarios to evaluate on")
    p.add_argument("--scenarios", help="scenario file instead of the held-out set (JSON/YAML {id, seed, options})")
    p.add_argument("--jobs", type=int, default=2, help="evaluation worker processes")
    p.add_argument("--population", type=int, default=6, help="optimiser baseline: candidates per iteration")
    p.add_argument("--iterations", type=int, default=2, help="optimiser baseline: cross-entropy iterations")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Train, evaluate, report."""
    args = parse_args(argv)
    t0 = time.perf_counter()
    try:
        cfg = load_train_config(args.config, parse_set(args.set))
        train(cfg, resume=True)
        t_train = time.perf_counter() - t0
        scenarios = load_scenarios(args.scenarios) if args.scenarios else held_out_scenarios(args.n_scenarios)
        experiment = Path(cfg.out_dir) / cfg.name
        baselines = ["crew", "random"] + (["optimiser"] if is_plan_env(cfg.env.id) else [])
        results = evaluate_targets([str(experiment), *baselines], scenarios, n_jobs=args.jobs,
                                   optimiser={"population": args.population, "iterations": args.iterations,
                                              "elite": min(3, args.population)})
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = experiment / "evaluation"
    write_report(results, out, scenarios, {"config": cfg.model_dump(mode="json"), "train_wall_s": t_train})
    policy = load_run(experiment / f"seed-{cfg.seeds[0]}")
    render_episode(policy, scenarios[0], out / "episode.png", policy.env_id, policy.env_config)
    print(markdown_table(results))
    print(f"train {t_train:.0f} s, total {time.perf_counter() - t0:.0f} s; report in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())

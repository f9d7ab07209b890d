"""The main job: train a preset, evaluate it beside the bundled policy and the baselines on held-out scenarios,
print the table and the statistics.

    python -m agents.main --config configs/agents/quick.yaml [--set key=value ...] [--n-scenarios 50] [--jobs 2]

Trains every seed of the config (resuming a run that exists, so a second call only evaluates), then evaluates the
bundled policy trained for the same env (:mod:`agents.bundle`, ``--bundled``), the preset just trained, the crew
rule of thumb, random actions and (on the plan envs) the per-scenario optimiser on the env's held-out set
(:func:`agents.evaluate.default_scenarios`: on ``AnchorPlan-v1`` sites the training never draws; 50 of them, so
that one scenario is 2 points of success). Prints the table and the statistics (:mod:`agents.statistics`: Wilson
intervals, paired differences against the crew with discordant counts, the task check); writes
``evaluation.json``, ``evaluation.md``, ``distributions.png``, ``rl_evaluation.json`` (per-episode records) and
``episode.png`` (a rendered held-out episode of the trained policy) into ``<out_dir>/<name>/evaluation/``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from agents.baselines import is_plan_env
from agents.bundle import bundled_path
from agents.config import load_train_config, parse_set
from agents.evaluate import default_scenarios, evaluate_targets, render_episode
from agents.report import markdown_table, write_records, write_report
from agents.runs import load_run
from agents.scenarios import load_scenarios
from agents.statistics import evaluation_statistics, format_statistics
from agents.train import train
from moor_env.errors import ConfigError

MAIN_SCENARIOS = 50
BUNDLED = {"moor_env/AnchorPlan-v1": "plan-v1-sac"}  # the bundled policy shown beside a preset of each env


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line arguments of ``python -m agents.main``."""
    p = argparse.ArgumentParser(prog="python -m agents.main", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", default="quick", help="training config (default: the quick preset)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="training config override")
    p.add_argument("--n-scenarios", type=int, default=MAIN_SCENARIOS, help="held-out scenarios to evaluate on")
    p.add_argument("--scenarios", help="scenario file instead of the held-out set (JSON/YAML {id, seed, options})")
    p.add_argument("--jobs", type=int, default=2, help="evaluation worker processes")
    p.add_argument("--population", type=int, default=8, help="optimiser baseline: candidates per iteration")
    p.add_argument("--iterations", type=int, default=3, help="optimiser baseline: cross-entropy iterations")
    p.add_argument("--bundled", default=None,
                   help="bundled policy to show beside the preset (default: the one for the preset's env; "
                        "'none' for none)")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Train, evaluate, report."""
    args = parse_args(argv)
    t0 = time.perf_counter()
    try:
        cfg = load_train_config(args.config, parse_set(args.set))
        train(cfg, resume=True)
        t_train = time.perf_counter() - t0
        env_id = cfg.env.id
        scenarios = load_scenarios(args.scenarios) if args.scenarios else default_scenarios(env_id, args.n_scenarios)
        experiment = Path(cfg.out_dir) / cfg.name
        bundled = args.bundled or BUNDLED.get(env_id)
        shown = [] if bundled in (None, "none") or bundled_path(bundled) is None else [bundled]
        baselines = ["crew", "random"] + (["optimiser"] if is_plan_env(env_id) else [])
        results = evaluate_targets([*shown, str(experiment), *baselines], scenarios,
                                   env=env_id, env_config=cfg.env.config, n_jobs=args.jobs,
                                   optimiser={"population": args.population, "iterations": args.iterations,
                                              "elite": min(3, args.population)})
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = experiment / "evaluation"
    stats = evaluation_statistics(results)
    meta = {"config": cfg.model_dump(mode="json"), "train_wall_s": t_train}
    write_report(results, out, scenarios, meta, stats)
    write_records(results, out / "rl_evaluation.json", stats, {**meta, "scenarios": scenarios})
    policy = load_run(experiment / f"seed-{cfg.seeds[0]}")
    render_episode(policy, scenarios[0], out / "episode.png", policy.env_id, policy.env_config)
    print(markdown_table(results))
    print(format_statistics(stats))
    print(f"train {t_train:.0f} s, total {time.perf_counter() - t0:.0f} s; report in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""AnchorRelease-v1: random commands, the crew and the bundled plan policy driven to its targets, on the same sites.

Run from the repository root::

    python benchmarks/release_v1_evaluation.py [--sites 500] [--jobs 2]

Every policy plays the same held-out sites (:func:`agents.scenarios.held_out_sites`, AnchorPlan-v1's site fields,
which AnchorRelease-v1's reset takes), each from the start geometry the env draws with the site's seed:

* ``random``: uniform commands of the five actions (:func:`agents.baselines.make_baseline`);
* ``crew``: the crew's plan on AnchorPlan-v1 driven to at full rate and released at the heave crest once reached
  (:class:`agents.sequential.LeverFollower` of :class:`agents.baselines.CrewPlanV1Policy`);
* ``plan-v1-sac``: the bundled AnchorPlan-v1 policy, which sets the targets from the site it observes, driven to
  by the same follower.

The statistics are :func:`agents.statistics.evaluation_statistics`'s: success with its Wilson interval per policy,
each policy minus the crew paired on the sites (bootstrap interval, discordant counts, exact McNemar p-value).
Writes the per-episode records to ``benchmarks/results/release_v1_evaluation.json`` and the table in
``docs/agents-results.md`` (``--docs-only``: only the table, from the committed JSON).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

from agents.baselines import RELEASE_V1_ENV, make_baseline, plan_geometry  # noqa: E402
from agents.bundle import resolve_target  # noqa: E402
from agents.evaluate import evaluate_policy  # noqa: E402
from agents.scenarios import PLAN_V1_CONFIG, held_out_sites  # noqa: E402
from agents.sequential import LeverFollower  # noqa: E402
from agents.statistics import evaluation_statistics  # noqa: E402
from agents.train_rllib import load_run_policies  # noqa: E402
from moor_env.envs.config import load_env_config  # noqa: E402

STEM = "release_v1_evaluation"
RESULTS = ROOT / "benchmarks" / "results" / f"{STEM}.json"
DOC = DOCS / "agents-results.md"
COMMAND = "python benchmarks/release_v1_evaluation.py"
BUNDLED = "plan-v1-sac"
RECORD_KEYS = ("policy", "scenario", "seed", "success", "touchdown_speed_m_s", "required_speed_m_s", "tilt_deg",
               "offset_m", "limits_exceeded", "reward", "steps", "forced_release", "moves_refused", "failure")


def follower_of_bundled(cfg, name: str = BUNDLED) -> LeverFollower:
    """The bundled AnchorPlan-v1 policy ``name`` as an AnchorRelease-v1 policy (its targets, followed)."""
    (plan,) = load_run_policies(resolve_target(name))
    follower = LeverFollower(plan, cfg, *plan_geometry(cfg))
    follower.name = name
    return follower


def _value(x):
    """A record value as strict JSON (NaN as None, numpy scalars as Python numbers)."""
    if hasattr(x, "item"):
        x = x.item()
    return None if isinstance(x, float) and not math.isfinite(x) else x


def evaluate(sites: int, jobs: int, progress: bool = True) -> dict:
    """Every policy on the first ``sites`` held-out sites; the records, the statistics and the run's metadata."""
    load_before = os.getloadavg()[0]
    cfg = load_env_config(PLAN_V1_CONFIG)
    scenarios = held_out_sites(sites)
    policies = {"random": make_baseline("random", RELEASE_V1_ENV, cfg),
                "crew": make_baseline("crew", RELEASE_V1_ENV, cfg), BUNDLED: follower_of_bundled(cfg)}
    t0 = time.perf_counter()
    results = [evaluate_policy(policy, scenarios, RELEASE_V1_ENV, cfg, jobs, progress, name=name)
               for name, policy in policies.items()]
    stats = evaluation_statistics(results)
    episodes = [{k: _value(({**e, "policy": r["policy"]}).get(k)) for k in RECORD_KEYS}
                for r in results for e in r["episodes"]]
    return {**run_record(load_before), "command": COMMAND, "config": PLAN_V1_CONFIG, "sites": sites, "jobs": jobs,
            "wall_s": time.perf_counter() - t0, "policies": list(policies),
            "statistics": {k: stats[k] for k in ("confidence", "success", "paired", "checks")}, "episodes": episodes}


def _pct_ci(ci) -> str:
    return f"[{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]"


def minus_crew(stats: dict, name: str) -> dict | None:
    """``name`` minus the crew from the statistics' paired comparisons (crew minus random turned round):
    difference, interval and the discordant counts (only ``name``, only crew); None where not compared."""
    for c in stats["paired"]:
        if (c["a"], c["b"]) == (name, "crew"):
            return {"difference": c["difference"], "ci": c["ci"], "only": c["only_a"], "only_crew": c["only_b"]}
        if (c["a"], c["b"]) == ("crew", name):
            return {"difference": -c["difference"], "ci": [-c["ci"][1], -c["ci"][0]], "only": c["only_b"],
                    "only_crew": c["only_a"]}
    return None


def results_block(data: dict) -> str:
    """The table of one run for ``docs/agents-results.md``."""
    stats = data["statistics"]
    rows = []
    for name in data["policies"]:
        eps = [e for e in data["episodes"] if e["policy"] == name]
        s = stats["success"][name]
        c = minus_crew(stats, name)
        diff = "-" if c is None else (f"{100 * c['difference']:+.1f} {_pct_ci(c['ci'])}; {c['only']} / "
                                      f"{c['only_crew']}")
        rows.append([name, len(eps), f"{100 * s['rate']:.1f} % {_pct_ci(s['ci'])}", diff,
                     f"{np.mean([e['steps'] for e in eps]):.1f}",
                     sum(bool(e["forced_release"]) for e in eps), sum(e["moves_refused"] or 0 for e in eps)])
    head = ["policy", "sites", "success [Wilson 95 % CI]",
            "minus crew, points [paired bootstrap 95 % CI]; sites only this / only crew succeeds",
            "mean steps (release step included)", "forced releases", "moves refused"]
    jobs = data["jobs"]
    note = (f"**{data['sites']} held-out sites** (the first {data['sites']} of `agents.scenarios.held_out_sites`), "
            f"every policy on the same sites and start geometries; {jobs} worker process{'es' if jobs > 1 else ''}, "
            f"{data['wall_s'] / 60:.0f} min.")
    return f"{note}\n\n{table(head, rows)}\n\n{run_line(data, COMMAND)}"


def docs_blocks(data: dict | None) -> list[tuple[Path, str, str]]:
    """The block this benchmark writes, rendered from its results JSON."""
    return [] if data is None else [(DOC, STEM, results_block(data))]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/release_v1_evaluation.json``."""
    return docs_blocks(load_result(STEM))


def main(argv: list[str] | None = None) -> int:
    """Evaluate, write the JSON and the docs table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sites", type=int, default=500, help="held-out sites")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--no-progress", action="store_true")
    parser.add_argument("--docs-only", action="store_true",
                        help=f"rewrite the docs table from {RESULTS.relative_to(ROOT)}, run nothing")
    args = parser.parse_args(argv)
    if not args.docs_only:
        write_results(RESULTS, evaluate(args.sites, args.jobs, not args.no_progress))
    write_blocks(docs_from_results())
    return 0


if __name__ == "__main__":
    sys.exit(main())

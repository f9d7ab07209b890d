"""Benchmark: does the committed RL evaluation still describe the code? The policies the checkout holds replayed.

``benchmarks/rl_evaluation.py`` writes every episode of every policy on AnchorPlan-v1's held-out sites to
``benchmarks/results/rl_evaluation.json``, with the commit it ran at. Later changes of the simulation (statics,
integrators, checks) move touchdown speeds and tilts a little, a site near a threshold may then flip between
success and failure, and a plan refused before its fall may install. This benchmark replays the policies that
need no training run (the crew's rule of thumb, random plans and the bundled SAC policy, ``plan-v1-sac``) on the
same sites with the same episode seeds at the current code and compares each episode with its committed record:
success agreement, the success rate then and now, and the change of touchdown speed, tilt and reward. The trained
runs' seeds (``runs/``) are not part of the checkout and are not replayed: the table says how far the simulation
under the committed evaluation has moved, not how those runs would score now.

    python benchmarks/rl_reproduction.py [--jobs 2]

Writes ``benchmarks/results/rl_reproduction.json`` and its table in ``docs/agents-results.md`` (``--docs-only``:
the table from the JSON).
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
from _machine import run_record  # noqa: E402
from rl_evaluation import BUNDLED, RESULTS_STEM, _short, _source_commit  # noqa: E402

from agents.evaluate import PLAN_V1_CONFIG, evaluate_targets  # noqa: E402
from agents.io import write_json_atomic  # noqa: E402
from agents.report import episode_records  # noqa: E402
from agents.scenarios import held_out_sites  # noqa: E402

STEM = "rl_reproduction"
OUT = ROOT / "benchmarks" / "results" / f"{STEM}.json"
DOC = DOCS / "agents-results.md"
COMMAND = "python benchmarks/rl_reproduction.py"
POLICIES = ("crew", "random", BUNDLED)


def _key(episode: dict) -> tuple[str, int]:
    return episode["scenario"], episode["seed"]


def compare(committed: list[dict], replayed: list[dict]) -> dict:
    """One policy's replayed episodes against its committed ones, paired by site and episode seed."""
    then = {_key(e): e for e in committed}
    pairs = [(then[_key(e)], e) for e in replayed if _key(e) in then]
    if not pairs or len(pairs) != len(committed) or len(pairs) != len(replayed):
        raise SystemExit(f"error: {len(pairs)} episodes pair up of {len(committed)} committed and {len(replayed)} "
                         "replayed: the held-out sites are not those of the committed evaluation")

    both = [(a, b) for a, b in pairs if a["touchdown_speed_m_s"] is not None and b["touchdown_speed_m_s"] is not None]
    speed = np.array([abs(b["touchdown_speed_m_s"] - a["touchdown_speed_m_s"]) for a, b in both] or [math.nan])
    tilt = np.array([abs(b["tilt_deg"] - a["tilt_deg"]) for a, b in both] or [math.nan])
    reward = np.array([b["reward"] - a["reward"] for a, b in pairs])
    return {"paired": len(pairs),
            "same_plan": int(sum(a["targets"] == b["targets"] for a, b in pairs)),
            "success_then": float(np.mean([a["success"] for a, _ in pairs])),
            "success_now": float(np.mean([b["success"] for _, b in pairs])),
            "success_agree": int(sum(a["success"] == b["success"] for a, b in pairs)),
            "lost": int(sum(a["success"] and not b["success"] for a, b in pairs)),
            "gained": int(sum(b["success"] and not a["success"] for a, b in pairs)),
            "touchdown_both": len(both),
            "touchdown_then_only": int(sum(a["touchdown_speed_m_s"] is not None and b["touchdown_speed_m_s"] is None
                                           for a, b in pairs)),
            "touchdown_now_only": int(sum(a["touchdown_speed_m_s"] is None and b["touchdown_speed_m_s"] is not None
                                          for a, b in pairs)),
            "identical_speed": int(sum(a["touchdown_speed_m_s"] == b["touchdown_speed_m_s"] for a, b in both)),
            "speed_diff_mean": float(speed.mean()), "speed_diff_max": float(speed.max()),
            "tilt_diff_max": float(tilt.max()), "reward_diff_mean": float(reward.mean())}


def reproduce(jobs: int, progress: bool) -> dict:
    """Replay :data:`POLICIES` on the committed evaluation's sites; the comparison per policy."""
    data = load_result(RESULTS_STEM)
    if data is None:
        raise SystemExit(f"error: no benchmarks/results/{RESULTS_STEM}.json to compare with")
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    sites = data["meta"]["sites"]
    results = evaluate_targets(list(POLICIES), held_out_sites(sites), None, PLAN_V1_CONFIG, jobs, progress)
    replayed = episode_records(results)
    policies = {p: compare([e for e in data["episodes"] if e["policy"] == p],
                           [e for e in replayed if e["policy"] == p]) for p in POLICIES}
    out = {**run_record(load_before), "source_commit": _source_commit(), "sites": sites, "jobs": jobs,
           "wall_s": time.perf_counter() - t0, "evaluation_commit": data["meta"].get("source_commit"),
           "evaluation_date": data["meta"]["date"], "policies": policies, "episodes": replayed}
    write_json_atomic(OUT, out)
    return out


def docs_blocks(result: dict | None) -> list[tuple[Path, str, str]]:
    """The table of ``docs/agents-results.md``'s ``rl_reproduction`` block."""
    if result is None:
        return []
    header = ["policy", "sites", "same plan", "success then", "success now", "same outcome", "lost / gained",
              "touchdown then only / now only", "speed identical", "mean / max abs speed change m/s",
              "max abs tilt change deg", "mean reward change"]
    rows = []
    for name, c in result["policies"].items():
        rows.append([name, c["paired"], c["same_plan"], f"{100 * c['success_then']:.1f} %",
                     f"{100 * c['success_now']:.1f} %", c["success_agree"], f"{c['lost']} / {c['gained']}",
                     f"{c['touchdown_then_only']} / {c['touchdown_now_only']}",
                     f"{c['identical_speed']} of {c['touchdown_both']}",
                     f"{c['speed_diff_mean']:.3f} / {c['speed_diff_max']:.3f}", f"{c['tilt_diff_max']:.3f}",
                     f"{c['reward_diff_mean']:+.4f}"])
    text = (f"The committed evaluation ran at code {_short(result['evaluation_commit'])} "
            f"({result['evaluation_date'][:10]}); replayed at {_short(result['source_commit'])}, the same sites "
            f"and episode seeds (speed and tilt changes over the episodes that touch down in both; \"now only\": "
            f"a plan refused then, e.g. for a line hanging through the anchor where the static problem left the "
            f"contact out, that installs now):\n\n"
            + table(header, rows) + "\n\n"
            + run_line(result, COMMAND)[:-1] + f", {result['jobs']} workers, {result['wall_s'] / 60:.1f} min.")
    return [(DOC, STEM, text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """The docs block from the committed JSON."""
    return docs_blocks(load_result(STEM))


def main(argv: list[str] | None = None) -> int:
    """Replay, write the JSON and the docs table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--no-progress", action="store_true")
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs table from the JSON, run nothing")
    args = parser.parse_args(argv)
    if not args.docs_only:
        reproduce(args.jobs, not args.no_progress)
    write_blocks(docs_from_results())
    return 0


if __name__ == "__main__":
    sys.exit(main())

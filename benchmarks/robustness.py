"""Robustness of AnchorRelease-v0 under random controls: episodes that end without a touchdown, and fallbacks.

Run from the repository root: ``python benchmarks/robustness.py [--episodes 200]``. Writes
``benchmarks/results/robustness.json`` and its table in ``docs/robustness.md`` (``--docs-only``: only the table,
from the committed JSON).

Each episode draws its scenario from the default config (seeds 5000, 5001, ...), once with the config's waves and
once with Hs 0, and is driven by the seeded random controls of ``benchmarks/pre_release_step.py`` (spacing and
winch rates redrawn every 10 s, release at a random step between 25 and 55). Counted: touchdowns, episodes that
ended otherwise (with their status), fallbacks (pre-release advances repeated at the scene's step after a
blow-up with the coarse pre-release step, or one that raised a line's running maximum tension above its breaking
load), and the largest running maximum tension of a line over its minimum breaking load at the release.
Each sea runs twice: the env as configured, and without the limit on how far a node may travel in one coarse
step (``control.pre_release_travel_segments: null``). The CPU figures include the reset's static solves; episode
costs are measured by ``benchmarks/bench_env.py``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import gymnasium as gym  # noqa: E402
from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402
from pre_release_step import ENV_ID, run_episode  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs

RESULTS = ROOT / "benchmarks" / "results" / "robustness.json"
SEAS = {"waves": {}, "calm": {"scenario.sea_state_hs_m": 0.0}}
CASES = {"env": {}, "no travel limit": {"control.pre_release_travel_segments": None}}
DOC = DOCS / "robustness.md"
COMMAND = "python benchmarks/robustness.py"


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The table of one run (docs/robustness.md)."""
    rows = []
    for key, s in result["summary"].items():
        sea, _, case = key.partition(", ")
        tm = s["pre_release_tension_over_mbl"]
        rows.append([sea, case, s["episodes"], s["touchdowns"], len(s["not_touchdown"]), s["fallbacks"],
                     s["fall_resolution"].get("tight_line", 0), f"{s['touchdown_speed_m_s_median']:.2f}",
                     f"{s['tilt_deg_median']:.2f}", f"{tm['median']:.3f} / {tm['p99']:.3f} / {tm['max']:.3f}",
                     f"{s['cpu_s_median']:.3f}"])
    text = "\n".join([run_line(result, COMMAND), "", table(
        ["sea", "case", "episodes", "touchdowns", "other ends", "fallbacks", "falls on tight_line",
         "touchdown speed median [m/s]", "tilt median [deg]",
         "largest line tension / MBL before release, median / p99 / max", "CPU s/episode (median)"], rows)])
    return [(DOC, "robustness", text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/robustness.json``."""
    return docs_blocks(load_result("robustness"))


def _summary(rows: list[dict]) -> dict:
    """Counts and medians of one sea and case."""
    over = np.array([r["pre_release_tension_over_mbl"] for r in rows])
    return {
        "episodes": len(rows),
        "touchdowns": sum(r["status"] == "touchdown" for r in rows),
        "fallbacks": int(sum(r["fallbacks"] for r in rows)),
        "not_touchdown": [{"seed": r["seed"], "status": r["status"]} for r in rows if r["status"] != "touchdown"],
        "fall_resolution": {k: sum(r["fall_resolution"] == k for r in rows)
                            for k in sorted({str(r["fall_resolution"]) for r in rows})},
        "touchdown_speed_m_s_median": float(np.median([r["speed_m_s"] for r in rows if r["speed_m_s"]])),
        "tilt_deg_median": float(np.median([r["tilt_deg"] for r in rows if r["tilt_deg"] is not None])),
        "pre_release_tension_over_mbl": {"median": float(np.median(over)), "p99": float(np.percentile(over, 99)),
                                         "max": float(over.max())},
        "cpu_s_median": float(np.median([r["cpu_s"] for r in rows])),
    }


def main(argv: list[str] | None = None) -> dict:
    """Run the episodes of both seas, write the JSON and print a table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200, help="episodes per sea")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs table from benchmarks/results/robustness.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return load_result("robustness")
    load_before = os.getloadavg()[0]
    summary = {}
    for sea, sea_overrides in SEAS.items():
        for case, overrides in CASES.items():
            env = gym.make(ENV_ID, overrides={**sea_overrides, **overrides})
            rows = [run_episode(env, seed) for seed in tqdm(range(5000, 5000 + args.episodes), desc=f"{sea}, {case}")]
            summary[f"{sea}, {case}"] = _summary(rows)
    result = {**run_record(load_before), "config": "anchor-release (default), scenarios drawn with seeds 5000..",
              "summary": summary}
    write_results(RESULTS, result)
    write_blocks(docs_blocks(result))
    print(docs_blocks(result)[0][2])
    return result


if __name__ == "__main__":
    main()

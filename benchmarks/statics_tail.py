"""Benchmark: a change of the static solver against another tree on the statics benchmark's slowest scenes.

The time distribution of ``benchmarks/statics.py`` has a long tail whose scenes react to small changes of the solver
(docs/statics.md, "The slowest scenes"): a change may make most of them faster and a few far slower, or leave one
unsolved. This benchmark solves the ``--slowest`` scenes of that benchmark's committed records (by their solve time)
and the ``--median`` scenes nearest its median, with this tree and, with ``--baseline-root DIR``, with another copy
of the package (a directory holding ``moor_env`` and ``configs``, e.g. ``mkdir baseline && git archive HEAD moor_env
configs | tar -x -C baseline``). Each tree runs in a subprocess per chunk of scenes, the two alternating chunk by
chunk (each first in every other chunk) so that both see the same machine load; even so one run's time ratio moves
with the machine's load (on a shared 2-core machine, repeated runs of one comparison spread over about 0.95-1.01),
so a change of a few percent in time needs several runs. Per scene it records the outcome, the iterations, the
release point and top tensions (to tell results equal bit for bit from results changed) and the CPU time from the
compiled scene to the result (``time.process_time``, one core, kernels compiled beforehand; a converged scene is
solved twice, seven times where it takes under 0.1 s, and the least time counts: a rare path's kernel compiles on
its first use, and a short solve is timed often enough for the least to be steady).

    python benchmarks/statics_tail.py [--slowest 60] [--median 60] [--chunks 6] [--baseline-root DIR]

Writes ``benchmarks/results/statics_tail.json`` and its table in ``docs/statics.md``; ``--docs-only`` rewrites the
table from the JSON. ``--root DIR --scenes FILE --out FILE`` solves a list of scenes with another tree (what the
subprocesses do).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
TREE = Path(sys.argv[sys.argv.index("--root") + 1]).resolve() if "--root" in sys.argv else ROOT
sys.path.insert(0, str(TREE))
sys.path.insert(1, str(Path(__file__).resolve().parent))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402

COMMAND = "python benchmarks/statics_tail.py"
DOC = DOCS / "statics.md"
OUT = RESULTS / "statics_tail.json"
REPEAT_BELOW_S = 0.1  # a converged solve shorter than this is timed FAST_SOLVES times, others twice
FAST_SOLVES = 7


def select_scenes(slowest: int, median: int) -> dict[str, list[dict]]:
    """The scenes (overrides of gjoa-500) of the statics benchmark's committed records: its ``slowest`` slowest and
    the ``median`` nearest its median (of those not refused by the config); a set of none is left out."""
    records = [r for r in json.loads((RESULTS / "statics.json").read_text())["records"] if "solve_s" in r]
    times = np.array([r["solve_s"] for r in records])
    by_time = np.argsort(-times, kind="stable")
    near = np.argsort(np.abs(times - np.median(times)), kind="stable")
    slow = [int(i) for i in by_time[:slowest]]
    taken = set(slow)
    middle = [int(i) for i in near if int(i) not in taken][:median]
    sets = {"slowest": [records[i]["scene"] for i in slow], "median": [records[i]["scene"] for i in middle]}
    return {name: scenes for name, scenes in sets.items() if scenes}


def solve_scenes(scenes: list[dict]) -> list[dict]:
    """Solve each scene with the tree on ``sys.path`` (see the module docstring); one record each."""
    from moor_env import load_scene
    from moor_env.compile import compile_scene
    from moor_env.errors import NoEquilibrium, SimulationDiverged, StaticsNotConverged
    from moor_env.simulation import solve_statics

    for preset in ("fast", "default", "accurate"):  # compiles the kernels (or loads them) before any timing
        solve_statics(load_scene("gjoa-500", {"fidelity": preset, "current_scale": 1.0}), progress=False)
    out = []
    for scene in scenes:
        best, record = float("inf"), {}
        for count in range(1, FAST_SOLVES + 1):
            model = compile_scene(load_scene("gjoa-500", scene))
            t0 = time.process_time()
            try:
                result = solve_statics(model, progress=False, method="newton")
                record = {"outcome": "converged", "iterations": result.iterations,
                          "release_point_m": result.release_point_m, "top_tensions_n": result.top_tensions_n}
            except NoEquilibrium:
                record = {"outcome": "no equilibrium"}
            except (StaticsNotConverged, SimulationDiverged):
                record = {"outcome": "unsolved"}
            best = min(best, time.process_time() - t0)
            if record["outcome"] != "converged" or (count >= 2 and best >= REPEAT_BELOW_S):
                break
        out.append({**record, "solve_s": best})
    return out


def run_tree(root: Path, scenes: list[dict], work: Path) -> list[dict]:
    """:func:`solve_scenes` with the tree at ``root``, in a subprocess."""
    scenes_file, out_file = work / "scenes.json", work / "records.json"
    scenes_file.write_text(json.dumps(scenes))
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--root", str(root), "--scenes", str(scenes_file),
                    "--out", str(out_file)], check=True)
    return json.loads(out_file.read_text())


def chunks(items: list, count: int) -> list[list]:
    """``items`` in ``count`` interleaved chunks (each a spread of the list, so that chunks cost alike)."""
    return [items[k::count] for k in range(count) if items[k::count]]


def _quantiles(seconds: list[float]) -> dict:
    ms = 1e3 * np.array(seconds)
    return {"median": float(np.median(ms)), "p90": float(np.percentile(ms, 90)), "max": float(ms.max()),
            "total_s": float(ms.sum() / 1e3)}


def _same(a: dict, b: dict) -> bool:
    keys = ("outcome", "iterations", "release_point_m", "top_tensions_n")
    return all(a.get(k) == b.get(k) for k in keys)


def summarize(records: list[dict], baseline: list[dict] | None) -> dict:
    """Times of this tree (and the baseline's), outcome changes and results equal bit for bit."""
    out = {"scenes": len(records), "this": _quantiles([r["solve_s"] for r in records])}
    if baseline is None:
        return out
    pairs = list(zip(records, baseline, strict=True))
    changes = [f"{b['outcome']} -> {r['outcome']}" for r, b in pairs if r["outcome"] != b["outcome"]]
    ratio = [r["solve_s"] / b["solve_s"] for r, b in pairs if b["solve_s"] > 0.0]
    return {**out, "baseline": _quantiles([b["solve_s"] for b in baseline]), "outcome_changes": changes,
            "same_results": sum(_same(r, b) for r, b in pairs), "time_ratio_median": float(np.median(ratio))}


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The table of docs/statics.md's ``statics_tail`` block."""
    against = "baseline" in next(iter(result["sets"].values()))
    header = ["scenes", "count", "median ms", "p90 ms", "max ms", "total s"]
    if against:
        header += ["baseline median / max ms", "baseline total s", "time ratio (median per scene)",
                   "same results bit for bit", "outcome changes"]
    rows = []
    for name, s in result["sets"].items():
        t = s["this"]
        row = [name, s["scenes"], f"{t['median']:.1f}", f"{t['p90']:.1f}", f"{t['max']:.0f}", f"{t['total_s']:.2f}"]
        if against:
            b = s["baseline"]
            row += [f"{b['median']:.1f} / {b['max']:.0f}", f"{b['total_s']:.2f}", f"{s['time_ratio_median']:.3f}",
                    f"{s['same_results']} of {s['scenes']}", "; ".join(s["outcome_changes"]) or "none"]
        rows.append(row)
    label = result.get("baseline_label")
    text = table(header, rows) + "\n\n" + run_line(result, COMMAND + (" --baseline-root DIR" if against else ""))
    if against:
        text += (" The baseline is another tree" + (f" ({label})" if label else "") + ", run alternately with this "
                 f"one in {result['chunks']} chunks of scenes.")
    return [(DOC, "statics_tail", text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """The docs block from the committed JSON."""
    result = load_result(OUT.stem)
    return docs_blocks(result) if result is not None else []


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slowest", type=int, default=60, help="the statics benchmark's slowest scenes")
    parser.add_argument("--median", type=int, default=60, help="its scenes nearest the median")
    parser.add_argument("--chunks", type=int, default=6, help="chunks of scenes the two trees alternate on")
    parser.add_argument("--baseline-root", type=Path, help="another tree to run alongside (see the docstring)")
    parser.add_argument("--baseline-label", default="", help="what the baseline tree is (kept in the JSON)")
    parser.add_argument("--root", type=Path, help="solve with another tree (with --scenes and --out)")
    parser.add_argument("--scenes", type=Path, help="with --root: a JSON list of scenes to solve")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs table from the JSON, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return
    if args.root is not None:
        args.out.write_text(json.dumps(solve_scenes(json.loads(args.scenes.read_text()))))
        return
    load_before = os.getloadavg()[0]
    sets = select_scenes(args.slowest, args.median)
    records = {name: [None] * len(scenes) for name, scenes in sets.items()}
    baseline = {name: [None] * len(scenes) for name, scenes in sets.items()} if args.baseline_root else None
    trees = [("baseline", args.baseline_root), ("this", ROOT)] if baseline else [("this", ROOT)]
    with tempfile.TemporaryDirectory() as work:
        for name, scenes in sets.items():
            for k, part in enumerate(chunks(list(range(len(scenes))), args.chunks)):
                print(f"{name}: chunk {k + 1} of {args.chunks} ({len(part)} scenes)", flush=True)
                chunk = [scenes[i] for i in part]
                for tree, root in trees[::-1] if k % 2 else trees:  # each tree goes first in every other chunk
                    target = baseline if tree == "baseline" else records
                    for i, record in zip(part, run_tree(root, chunk, Path(work)), strict=True):
                        target[name][i] = record
    result = {**run_record(load_before), "chunks": args.chunks, "baseline_label": args.baseline_label,
              "sets": {name: summarize(records[name], baseline[name] if baseline else None) for name in sets},
              "scenes": sets, "records": records, "baseline_records": baseline}
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    if args.out.resolve() == OUT.resolve():
        write_blocks(docs_blocks(result))
    print(docs_blocks(result)[0][2])


if __name__ == "__main__":
    main()

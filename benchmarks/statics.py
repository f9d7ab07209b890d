"""Speed and accuracy of the static solver over scenes drawn from wide ranges.

Draws scenes from the gjoa-500 installation with depth 300-1500 m, vessel spacing 0-0.5 depth, mooring line
0.95-1.3 depth, vertical chain 5-60 m, drop height 30-120 m, current scale 0-1.5 in any direction, anchor mass
+-10 % and a fidelity preset each (seeded). For each: the time to compile the scene and the time from the compiled
model to the result (one core, kernels compiled beforehand), and whether it converged, was refused as having no
equilibrium (with its cause) or failed. On the first ``--reference`` scenes the reference solver of
``moor_env/physics/statics_relaxation.py`` (the fallback) runs too: release point and top tensions are compared.

    python benchmarks/statics.py [--scenes 1000] [--reference 24] [--seed 0]

Writes ``benchmarks/results/statics.json``, ``docs/statics-times.png`` and the tables of ``docs/statics.md`` and
the README's statics block; ``--docs-only`` rewrites the tables from the JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _docs import load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402

from moor_env import load_scene  # noqa: E402
from moor_env.compile import compile_scene  # noqa: E402
from moor_env.errors import ConfigError, NoEquilibrium, SimulationDiverged, StaticsNotConverged  # noqa: E402
from moor_env.physics.statics_relaxation import solve as reference_solve  # noqa: E402
from moor_env.simulation import Simulator, solve_statics  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULT = ROOT / "benchmarks" / "results" / "statics.json"
DOC = ROOT / "docs" / "statics.md"
README = ROOT / "README.md"
FIGURE = ROOT / "docs" / "statics-times.png"
PRESETS = ("fast", "default", "accurate")
COMMAND = "python benchmarks/statics.py"


def draw_scene(rng: np.random.Generator) -> dict:
    """Overrides of one scene drawn from the benchmark's ranges."""
    depth = float(rng.uniform(300.0, 1500.0))
    return {
        "water_depth_m": depth,
        "vessel_spacing_m": float(rng.uniform(0.0, 0.5) * depth),
        "mooring_line_length_m": float(rng.uniform(0.95, 1.3) * depth),
        "vertical_chain_length_m": float(rng.uniform(5.0, 60.0)),
        "drop_height_m": float(rng.uniform(30.0, 120.0)),
        "current_scale": float(rng.uniform(0.0, 1.5)),
        "current_direction_deg": float(rng.uniform(0.0, 360.0)),
        "anchor_mass_scale": float(rng.uniform(0.9, 1.1)),
        "fidelity": PRESETS[int(rng.integers(len(PRESETS)))],
    }


def _warm_up() -> None:
    for preset in PRESETS:
        for current in (0.0, 1.0):
            solve_statics(load_scene("gjoa-500", {"fidelity": preset, "current_scale": current}), progress=False)


def run_scene(overrides: dict, reference: bool) -> dict:
    """Solve one scene; the record of times, outcome and (with ``reference``) the reference solver's answers."""
    record: dict = {"scene": overrides}
    t0 = time.perf_counter()
    try:
        model = compile_scene(load_scene("gjoa-500", overrides))
    except ConfigError as exc:
        record.update(outcome="refused by the config", cause=str(exc))
        return record
    record["compile_s"] = time.perf_counter() - t0
    record["nodes"] = int(model.node_i.shape[0])
    t0 = time.perf_counter()
    try:
        result = solve_statics(model, progress=False)
    except NoEquilibrium as exc:
        record.update(outcome="no equilibrium", cause=exc.cause, solve_s=time.perf_counter() - t0)
        return record
    except (StaticsNotConverged, SimulationDiverged) as exc:
        record.update(outcome="failed", cause=str(exc), solve_s=time.perf_counter() - t0)
        return record
    record.update(outcome="converged", solve_s=time.perf_counter() - t0, iterations=result.iterations,
                  method=result.method,
                  release_point_m=result.release_point_m, top_tensions_n=result.top_tensions_n)
    if reference:
        try:
            release, tensions, seconds = reference_solve(Simulator(compile_scene(load_scene("gjoa-500", overrides))))
            record["reference"] = {"release_point_m": release, "top_tensions_n": tensions, "solve_s": seconds}
        except StaticsNotConverged as exc:
            record["reference"] = {"failed": str(exc)}
    return record


def summarize(records: list[dict]) -> dict:
    """Per preset: counts by outcome and the solve and compile time distributions of the converged scenes."""
    out: dict = {}
    for preset in (*PRESETS, "all"):
        rows = [r for r in records if preset == "all" or r["scene"]["fidelity"] == preset]
        done = [r for r in rows if r["outcome"] == "converged"]
        solve = np.array([r["solve_s"] for r in done]) * 1e3
        total = np.array([r["solve_s"] + r["compile_s"] for r in done]) * 1e3
        out[preset] = {
            "scenes": len(rows),
            "converged": len(done),
            "no_equilibrium": sum(r["outcome"] == "no equilibrium" for r in rows),
            "refused_by_config": sum(r["outcome"] == "refused by the config" for r in rows),
            "failed": sum(r["outcome"] == "failed" for r in rows),
            "solve_ms": _quantiles(solve),
            "with_compile_ms": _quantiles(total),
            "iterations_median": float(np.median([r["iterations"] for r in done])) if done else None,
            "fallback": sum(r.get("method") == "relaxation" for r in done),
        }
    causes: dict = {}
    for r in records:
        if r["outcome"] in ("no equilibrium", "failed"):
            key = f"{r['outcome']}: {r['cause'].split(':')[0][:60]}"
            causes[key] = causes.get(key, 0) + 1
    out["causes"] = causes
    out["reference"] = _compare(records)
    return out


def _quantiles(ms: np.ndarray) -> dict:
    if ms.size == 0:
        return {}
    return {"median": float(np.median(ms)), "p90": float(np.percentile(ms, 90)),
            "p99": float(np.percentile(ms, 99)), "max": float(ms.max())}


def _compare(records: list[dict]) -> dict:
    rows = [r for r in records if "reference" in r and "release_point_m" in r.get("reference", {})]
    if not rows:
        return {"scenes": 0}
    release = [float(np.linalg.norm(np.subtract(r["release_point_m"], r["reference"]["release_point_m"])))
               for r in rows]
    tension = [max(abs(r["top_tensions_n"][k] / r["reference"]["top_tensions_n"][k] - 1.0)
                   for k in r["top_tensions_n"]) for r in rows]
    speedup = [r["reference"]["solve_s"] / r["solve_s"] for r in rows]
    return {"scenes": len(rows), "release_point_max_m": max(release), "top_tension_max_rel": max(tension),
            "reference_failed": sum("failed" in r.get("reference", {}) for r in records),
            "speedup_median": float(np.median(speedup)), "speedup_min": float(min(speedup)),
            "reference_solve_median_s": float(np.median([r["reference"]["solve_s"] for r in rows]))}


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The markdown of docs/statics.md and of the README's statics block."""
    s = result["summary"]
    rows = []
    for preset in (*PRESETS, "all"):
        p = s[preset]
        q, c = p["solve_ms"], p["with_compile_ms"]
        rows.append([preset, p["scenes"], p["converged"], p["fallback"], p["no_equilibrium"], p["refused_by_config"],
                     p["failed"],
                     *(f"{q.get(k, math.nan):.1f}" for k in ("median", "p90", "p99", "max")),
                     f"{c.get('median', math.nan):.1f}", f"{p['iterations_median']:.0f}"
                     if p["iterations_median"] is not None else "-"])
    main = table(["preset", "scenes", "converged", "of them by the fallback", "no equilibrium", "refused by config",
                  "failed", "median ms",
                  "p90 ms", "p99 ms", "max ms", "median ms with compile", "median iterations"], rows)
    ref = s["reference"]
    causes = "\n".join(f"- {k}: {v}" for k, v in sorted(s["causes"].items())) or "- none"
    cmp_text = (f"Against the reference solver on {ref['scenes']} of these scenes: release point within "
                f"{ref['release_point_max_m'] * 100:.2g} cm, "
                f"top tensions within {ref['top_tension_max_rel'] * 100:.2g} %; "
                f"the reference took {ref['reference_solve_median_s']:.2g} s per scene (median), "
                f"{ref['speedup_median']:.0f}x the Newton solver's time (least {ref['speedup_min']:.0f}x)."
                if ref.get("scenes") else "No reference comparison in this run.")
    line = run_line(result, COMMAND)
    doc = f"{main}\n\nScenes refused or failed, by cause:\n\n{causes}\n\n{cmp_text}\n\n{line}"
    a = s["all"]
    readme = (f"Hanging equilibrium from any geometry in {a['solve_ms']['median']:.1f} ms median, "
              f"{a['solve_ms']['p99']:.0f} ms p99 from a compiled scene "
              f"({a['converged']} of {a['scenes']} drawn scenes "
              f"converged, {a['no_equilibrium']} refused as having none, {a['failed']} failed; "
              f"`{COMMAND}`, {result['date'][:10]}; details in [docs/statics.md](docs/statics.md)).")
    return [(DOC, "statics", doc), (README, "statics", readme)]


def plot(records: list[dict]) -> None:
    """Distribution of the solve time per preset."""
    import matplotlib  # noqa: PLC0415  (optional plotting dependency)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(7, 4))
    for preset in PRESETS:
        ms = np.sort([r["solve_s"] * 1e3 for r in records if r["scene"]["fidelity"] == preset
                      and r["outcome"] == "converged"])
        if ms.size:
            ax.plot(ms, np.arange(1, ms.size + 1) / ms.size, label=preset)
    ax.set_xscale("log")
    ax.set_xlabel("solve time from a compiled scene [ms]")
    ax.set_ylabel("fraction of converged scenes")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(FIGURE, dpi=110)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=1000)
    parser.add_argument("--reference", type=int, default=24, help="scenes also solved by the reference solver")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs tables from the JSON")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_blocks(load_result("statics")))
        return 0
    load = os.getloadavg()[0]
    _warm_up()
    rng = np.random.default_rng(args.seed)
    scenes = [draw_scene(rng) for _ in range(args.scenes)]
    records = [run_scene(s, i < args.reference) for i, s in enumerate(tqdm(scenes, desc="statics scenes"))]
    result = {**run_record(load), "seed": args.seed, "summary": summarize(records), "records": records}
    RESULT.write_text(json.dumps(result, indent=1))
    plot(records)
    write_blocks(docs_blocks(result))
    print(json.dumps(result["summary"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Speed and accuracy of the static solver over scenes drawn from wide ranges.

Draws scenes from the gjoa-500 installation with depth 300-1500 m, vessel spacing 0-0.5 depth, mooring line
0.95-1.3 depth, vertical chain 5-60 m, drop height 30-120 m, current scale 0-1.5 in any direction, anchor mass
+-10 % and a fidelity preset each (seeded). For each: the time to compile the scene and the time from the compiled
model to the result by Newton's method (one core, kernels compiled beforehand, no fallback), and whether it
converged (and whether a line rests on the anchor there), was refused as having no equilibrium (with its cause),
is unsolved with a line resting on the anchor (no fallback is run there) or needs the fallback. Where it needs it, the
first ``--fallback`` of those scenes are solved again with the fallback (in a worker process, ``--fallback-limit``
seconds at most each). On the first ``--reference`` converged scenes of the fast and default presets the
relaxation solver (``moor_env/physics/statics_relaxation.py``) runs too (same limit), and on the first ``--moorpy``
converged scenes MoorPy (``benchmarks/_moorpy_scene.py``, a benchmark-only dependency): release point and top
tensions are compared.

    python benchmarks/statics.py [--scenes 1000] [--fallback 3] [--reference 6] [--moorpy 40] [--seed 0]

Writes ``benchmarks/results/statics.json``, ``docs/statics-times.png`` and the tables of ``docs/statics.md`` and
the README's statics block; ``--docs-only`` rewrites the tables from the JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
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
from moor_env.physics import layout as L  # noqa: E402
from moor_env.simulation import solve_statics  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULT = ROOT / "benchmarks" / "results" / "statics.json"
DOC = ROOT / "docs" / "statics.md"
README = ROOT / "README.md"
FIGURE = ROOT / "docs" / "statics-times.png"
PRESETS = ("fast", "default", "accurate")
COMMAND = "python benchmarks/statics.py"
ON_ANCHOR = "unsolved on the anchor"


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


# CPU time of this process: the solver runs on one core, and a busy machine does not inflate it as it does the wall
# time (the wall times are kept beside it in the records)
CLOCK = time.process_time


def _warm_up() -> None:
    """Compile (or load from the cache) the kernels before anything is timed: Newton's method on every preset, and
    the relaxation solver, whose reference runs in worker processes under a wall-time limit (a worker that had to
    compile its kernels would spend much of that limit on them)."""
    for preset in PRESETS:
        for current in (0.0, 1.0):
            solve_statics(load_scene("gjoa-500", {"fidelity": preset, "current_scale": current}), progress=False)
    solve_statics(load_scene("vertical-chain"), progress=False, method="relaxation")


def run_scene(overrides: dict) -> dict:
    """Solve one scene by Newton's method; the record of times and outcome. Times are the process's CPU time
    (:data:`CLOCK`) from the validated scene to the compiled model and from the model to the result; the wall
    times beside them (``*_wall_s``) also count whatever else the machine ran."""
    record: dict = {"scene": overrides}
    try:
        scene = load_scene("gjoa-500", overrides)
        t0, w0 = CLOCK(), time.perf_counter()
        model = compile_scene(scene)
    except ConfigError as exc:
        record.update(outcome="refused by the config", cause=str(exc))
        return record
    record.update(compile_s=CLOCK() - t0, compile_wall_s=time.perf_counter() - w0, nodes=int(model.node_i.shape[0]))
    t0, w0 = CLOCK(), time.perf_counter()
    try:
        result = solve_statics(model, progress=False, method="newton")
        record.update(outcome="converged", iterations=result.iterations, release_point_m=result.release_point_m,
                      top_tensions_n=result.top_tensions_n,
                      nodes_on_anchor=int(result.simulator.work.contact_out[L.CO_NODES]),
                      segments_on_anchor=int(result.simulator.work.contact_out[L.CO_SEGMENTS]),
                      segment_depth_m=result.simulator.deepest_segment_inside_m())
    except NoEquilibrium as exc:
        record.update(outcome="no equilibrium", cause=exc.cause)
    except (StaticsNotConverged, SimulationDiverged) as exc:
        # with a line resting on the anchor the fallback is not run (moor_env.physics.statics.solve_equilibrium)
        record.update(outcome=ON_ANCHOR if getattr(exc, "line_on_anchor", False) else "needs the fallback",
                      cause=str(exc))
    record.update(solve_s=CLOCK() - t0, solve_wall_s=time.perf_counter() - w0)
    if record["outcome"] == "converged":  # timed again: a rare path's kernel compiles on its first use
        model = compile_scene(scene)
        t0, w0 = CLOCK(), time.perf_counter()
        solve_statics(model, progress=False, method="newton")
        record.update(first_solve_s=record["solve_s"], solve_s=min(record["solve_s"], CLOCK() - t0),
                      solve_wall_s=min(record["solve_wall_s"], time.perf_counter() - w0))
    return record


def _worker(overrides: dict, method: str, queue) -> None:
    t0 = CLOCK()
    try:
        result = solve_statics(load_scene("gjoa-500", overrides), progress=False, method=method)
        queue.put({"converged": True, "method": result.method, "solve_s": CLOCK() - t0,
                   "release_point_m": result.release_point_m, "top_tensions_n": result.top_tensions_n})
    except Exception as exc:  # noqa: BLE001  (any failure of the solve is a result here)
        queue.put({"converged": False, "cause": f"{type(exc).__name__}: {exc}", "solve_s": CLOCK() - t0})


def run_in_worker(overrides: dict, method: str, limit_s: float) -> dict:
    """``solve_statics(method=method)`` of one scene in a worker process, stopped after ``limit_s``."""
    queue = multiprocessing.Queue()
    worker = multiprocessing.Process(target=_worker, args=(overrides, method, queue))
    worker.start()
    worker.join(limit_s)
    if worker.is_alive():
        worker.terminate()
        worker.join()
        return {"converged": False, "cause": f"not finished within {limit_s:g} s of wall time", "solve_s": math.nan}
    return queue.get() if not queue.empty() else {"converged": False, "cause": "worker ended without a result"}


def run_reference(records: list[dict], count: int, limit_s: float) -> None:
    """The relaxation solver on the first ``count`` converged scenes of the fast and default presets (the
    accurate meshes take it minutes), its answer stored in the record."""
    chosen = [r for r in records if r["outcome"] == "converged" and r["scene"]["fidelity"] != "accurate"][:count]
    for r in tqdm(chosen, desc="relaxation solver"):
        ref = run_in_worker(r["scene"], "relaxation", limit_s)
        r["reference"] = ref if ref["converged"] else {"failed": ref["cause"]}


def run_moorpy(records: list[dict], count: int) -> list[dict]:
    """MoorPy on the first ``count`` scenes our solver converged on: its answer beside ours."""
    from _moorpy_scene import moorpy_statics  # noqa: PLC0415  (MoorPy is a benchmark-only dependency)

    rows = []
    for r in [r for r in records if r["outcome"] == "converged"][:count]:
        mp = moorpy_statics(r["scene"])
        row = {"scene": r["scene"], "ours_s": r["solve_s"], "current": r["scene"]["current_scale"] > 0.0,
               "moorpy_failed": mp["failed"], "moorpy_s": mp.get("seconds"),
               "moorpy_one_s": mp.get("solve_seconds_one")}
        if not mp["failed"]:
            row["release_point_m"] = float(np.linalg.norm(np.subtract(mp["release_point_m"], r["release_point_m"])))
            row["top_tension_rel"] = {k: mp["top_tensions_n"][k] / r["top_tensions_n"][k] - 1.0
                                      for k in r["top_tensions_n"]}
        rows.append(row)
    return rows


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
            "needs_fallback": sum(r["outcome"] == "needs the fallback" for r in rows),
            "resting_on_anchor": sum(_resting(r) for r in done),
            "unsolved_on_anchor": sum(r["outcome"] == ON_ANCHOR for r in rows),
            "solve_ms": _quantiles(solve),
            "with_compile_ms": _quantiles(total),
            "iterations_median": float(np.median([r["iterations"] for r in done])) if done else None,
        }
    out["causes"] = cause_stats(records)[0]
    out["reference"] = _compare(records)
    out["resting_segments"] = _resting_segments(records)
    return out


def cause_stats(records: list[dict]) -> tuple[dict, dict]:
    """Scenes refused or not solved by Newton's method, by outcome and cause: their count and the quantiles of
    their solve time [ms]."""
    times: dict = {}
    for r in records:
        if r["outcome"] in ("no equilibrium", "needs the fallback", ON_ANCHOR):
            key = f"{r['outcome']}: {r['cause'].split(' (')[0].split(':')[0]}"
            times.setdefault(key, []).append(r["solve_s"] * 1e3)
    return {k: len(v) for k, v in times.items()}, {k: _quantiles(np.array(v)) for k, v in times.items()}


def _resting(record: dict) -> bool:
    """Whether a converged scene rests a line on the anchor: a node, or a segment over a rim."""
    return record.get("nodes_on_anchor", 0) + record.get("segments_on_anchor", 0) > 0


def _resting_segments(records: list[dict]) -> dict:
    """How deep the lines resting on the anchor lie inside it, segment interiors included."""
    depth = np.array([r["segment_depth_m"] for r in records
                      if r["outcome"] == "converged" and _resting(r) and "segment_depth_m" in r])
    if depth.size == 0:
        return {"scenes": 0}
    return {"scenes": int(depth.size), "max_m": float(depth.max()), "median_m": float(np.median(depth)),
            "deeper_than_5cm": int(np.sum(depth > 0.05))}


def _by_contact_text(records: list[dict]) -> str:
    """The converged scenes' solve times split by whether a line rests on the anchor, in words."""
    done = [r for r in records if r["outcome"] == "converged"]
    parts = []
    for label, rows in (("every line clear of the anchor", [r for r in done if not _resting(r)]),
                        ("a line resting on it", [r for r in done if _resting(r)])):
        q = _quantiles(np.array([r["solve_s"] for r in rows]) * 1e3)
        if q:
            parts.append(f"with {label} ({len(rows)}), {q['median']:.1f} ms median, {q['p90']:.1f} ms p90, "
                         f"{q['p99']:.1f} ms p99, {q['max']:.0f} ms at most")
    return "Converged scenes " + "; ".join(parts) + "." if parts else ""


def _quantiles(ms: np.ndarray) -> dict:
    if ms.size == 0:
        return {}
    return {"median": float(np.median(ms)), "p90": float(np.percentile(ms, 90)),
            "p99": float(np.percentile(ms, 99)), "max": float(ms.max())}


def _compare(records: list[dict]) -> dict:
    rows = [r for r in records if "release_point_m" in r.get("reference", {})]
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


def summarize_extras(fallbacks: list[dict], moorpy: list[dict]) -> dict:
    """The fallback sample and the MoorPy comparison in numbers."""
    out: dict = {"fallback": {"scenes": len(fallbacks), "converged": sum(f["converged"] for f in fallbacks),
                              "solve_s": [round(f["solve_s"], 2) for f in fallbacks]}}
    ok = [m for m in moorpy if not m["moorpy_failed"]]
    calm = [m for m in ok if not m["current"]]
    out["moorpy"] = {
        "scenes": len(moorpy), "failed": len(moorpy) - len(ok),
        "failed_in_current": sum(bool(m["moorpy_failed"]) and m["current"] for m in moorpy),
        "calm_scenes": len(calm),
        "calm_release_point_max_m": max((m["release_point_m"] for m in calm), default=math.nan),
        "calm_mooring_tension_max_rel": max((abs(m["top_tension_rel"]["mooring_line"]) for m in calm),
                                            default=math.nan),
        "current_release_point_max_m": max((m["release_point_m"] for m in ok if m["current"]), default=math.nan),
        "ours_median_ms": float(np.median([m["ours_s"] for m in ok]) * 1e3) if ok else math.nan,
        "moorpy_median_ms": float(np.median([m["moorpy_s"] for m in ok]) * 1e3) if ok else math.nan,
        "moorpy_one_solve_median_ms": float(np.median([m["moorpy_one_s"] for m in ok]) * 1e3) if ok else math.nan,
    }
    return out


CLOCK_TEXT = (" Times are CPU time of the solving process (`time.process_time`, one core), MoorPy's the same way; "
              "a converged scene is solved twice and the shorter time counts (a rare path's kernel compiles on its "
              "first use); the records keep the first time and the wall times beside them.")


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The markdown of docs/statics.md and of the README's statics block."""
    s = result["summary"]
    rows = []
    for preset in (*PRESETS, "all"):
        p = s[preset]
        q, c = p["solve_ms"], p["with_compile_ms"]
        rows.append([preset, p["scenes"], p["converged"], p.get("resting_on_anchor", 0), p["needs_fallback"],
                     p.get("unsolved_on_anchor", 0), p["no_equilibrium"], p["refused_by_config"],
                     *(f"{q.get(k, math.nan):.1f}" for k in ("median", "p90", "p99", "max")),
                     f"{c.get('median', math.nan):.1f}",
                     f"{p['iterations_median']:.0f}" if p["iterations_median"] is not None else "-"])
    main = table(["preset", "scenes", "Newton converged", "of them resting on the anchor", "needs the fallback",
                  "unsolved on the anchor", "no equilibrium", "refused by config",
                  "median ms", "p90 ms", "p99 ms", "max ms", "median ms with compile", "median iterations"], rows)
    ref = s["reference"]
    cause_ms = cause_stats(result["records"])[1]
    causes = "\n".join(f"- {k}: {v}{_cause_times(cause_ms.get(k))}" for k, v in sorted(s["causes"].items())) or "- none"
    cmp_text = (f"Against the relaxation solver on {ref['scenes']} of the converged scenes: release point within "
                f"{ref['release_point_max_m'] * 100:.2g} cm, top tensions within "
                f"{ref['top_tension_max_rel'] * 100:.2g} %; it took {ref['reference_solve_median_s']:.2g} s per scene "
                f"(median), {ref['speedup_median']:.0f}x the Newton solver's time (least {ref['speedup_min']:.0f}x)."
                if ref.get("scenes") else "No relaxation-solver comparison in this run.")
    seg = s.get("resting_segments", {})
    seg_text = (f"The contact acts on the nodes and on segments that cut in deeper than their nodes (a chain over "
                f"a rim): over the {seg['scenes']} scenes resting on the anchor the deepest point of a segment lies "
                f"{seg['median_m'] * 1e3:.2g} mm inside (median), {seg['max_m'] * 1e3:.2g} mm at most, more than "
                f"5 cm in {seg['deeper_than_5cm']}."
                if seg.get("scenes") else "")
    fb = s["fallback"]
    cpu_timed = any("solve_wall_s" in r for r in result["records"])
    limit = result.get("fallback_limit_s", math.nan)
    unit = " of CPU time" if cpu_timed else ""
    ran = ", ".join(f"not finished within {limit:g} s of wall time" if t is None or t != t else f"{t:g} s{unit}"
                    for t in fb["solve_s"])
    some = "the one scene that needs" if fb["scenes"] == 1 else f"the first {fb['scenes']} scenes that need"
    fb_text = (f"The fallback (`solve_statics` with `method=\"auto\"`) on {some} it: {fb['converged']} converged; "
               f"{ran}." if fb["scenes"] else "No scene needed the fallback.")
    mp = s["moorpy"]
    calm_text = (f"In calm water ({mp['calm_scenes']} scenes) its release point is within "
                 f"{mp['calm_release_point_max_m']:.2g} m and its mooring-line top tension within "
                 f"{mp['calm_mooring_tension_max_rel'] * 100:.2g} % of ours. " if mp.get("calm_scenes") else "")
    mp_text = (f"MoorPy 1.3 on the first {mp['scenes']} converged scenes: it failed on {mp['failed']} "
               f"({mp['failed_in_current']} of them in current: it lifts a suspended line's seabed there). "
               f"{calm_text}In current its release point differs from ours by up to "
               f"{mp['current_release_point_max_m']:.2g} m (it takes one uniform current over depth; "
               "`tests/test_moorpy_scene.py` checks the calm gjoa-500 scene within 0.5 m and 2 %). "
               f"Median time per scene: ours {mp['ours_median_ms']:.1f} ms, MoorPy "
               f"{mp['moorpy_median_ms']:.0f} ms with its wire-length search "
               f"({mp['moorpy_one_solve_median_ms']:.0f} ms "
               f"for one equilibrium solve), in the same process."
               if mp.get("scenes") else "No MoorPy comparison in this run.")
    line = run_line(result, COMMAND) + (CLOCK_TEXT if cpu_timed else "")
    split = _by_contact_text(result["records"])
    doc = (f"{main}\n\n" + (f"{split}\n\n" if split else "")
           + "Scenes refused or not solved by Newton's method, by cause (time from the compiled scene, "
           f"timed once: a rare path's kernel compiling on its first use would count):\n\n{causes}\n\n{fb_text}\n\n"
           f"{cmp_text}\n\n{mp_text}\n\n" + (f"{seg_text}\n\n" if seg_text else "") + line)
    a = s["all"]
    cpu = " of CPU time" if cpu_timed else ""
    readme = (f"Hanging equilibrium by Newton's method in {a['solve_ms']['median']:.1f} ms median, "
              f"{a['solve_ms']['p99']:.0f} ms p99{cpu} from a compiled scene; "
              f"{a['converged']} of {a['scenes']} drawn scenes "
              f"converge ({a.get('resting_on_anchor', 0)} with the loop resting on the anchor), "
              f"{a['no_equilibrium'] + a['refused_by_config']} are refused as having none, "
              f"{a['needs_fallback'] + a.get('unsolved_on_anchor', 0)} are not solved by Newton's method "
              f"(`{COMMAND}`, {result['date'][:10]}; "
              f"[docs/statics.md](docs/statics.md)).")
    return [(DOC, "statics", doc), (README, "statics", readme)]


def _cause_times(q: dict | None) -> str:
    """The time to a refusal or failure of one cause, in words (empty where not recorded)."""
    if not q:
        return ""
    return f" (after {q['median']:.0f} ms median, {q['p90']:.0f} ms p90, {q['max']:.0f} ms at most)"


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/statics.json``."""
    return docs_blocks(load_result("statics"))


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
    parser.add_argument("--fallback", type=int, default=3, help="scenes needing the fallback solved with it")
    parser.add_argument("--fallback-limit", type=float, default=60.0, help="seconds per fallback solve at most")
    parser.add_argument("--reference", type=int, default=6, help="converged scenes also solved by relaxation")
    parser.add_argument("--moorpy", type=int, default=40, help="converged scenes also solved by MoorPy")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs tables from the JSON")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return 0
    load = os.getloadavg()[0]
    _warm_up()
    rng = np.random.default_rng(args.seed)
    scenes = [draw_scene(rng) for _ in range(args.scenes)]
    records = [run_scene(scene) for scene in tqdm(scenes, desc="statics scenes")]
    run_reference(records, args.reference, args.fallback_limit)
    needing = [r["scene"] for r in records if r["outcome"] == "needs the fallback"][:args.fallback]
    fallbacks = [run_in_worker(s, "auto", args.fallback_limit) for s in tqdm(needing, desc="fallback")]
    moorpy = run_moorpy(records, args.moorpy) if args.moorpy else []
    summary = {**summarize(records), **summarize_extras(fallbacks, moorpy)}
    result = {**run_record(load), "seed": args.seed, "fallback_limit_s": args.fallback_limit, "summary": summary,
              "records": records,
              "fallback_records": fallbacks, "moorpy_records": moorpy}
    RESULT.write_text(json.dumps(result, indent=1))
    plot(records)
    write_blocks(docs_blocks(result))
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

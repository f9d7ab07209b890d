"""Benchmark: the gjoa-500 fall (release to touchdown) in our numba kernel and in MoorDyn-C v2, with accuracy.

Run from the repository root: ``python benchmarks/bench_drop.py``. One run does everything:

1. ours at default settings (1 m chain segments, symplectic Euler at 0.9 of its stability limit): a warm-up
   run compiles the kernels, then the best ``wall_dynamic_s`` of 3 runs;
2. MoorDyn (PyPI ``moordyn`` 2.7) on the same scene at its stable default settings in
   :func:`moor_env.crosscheck.moordyn.run_moordyn_drop` (same segments, RK4 at 0.7 of its stability limit,
   line damping off), seeded with our static equilibrium: best stepping wall time of 3 runs;
3. a converged reference touchdown speed: ours with 0.25 m chain segments (vertical chain and loop), checked
   against 0.5 m; both codes' errors are relative to it.

Writes ``benchmarks/results/bench_drop.json``, its table in ``docs/drop-speed.md`` and the README's headline line
(``--docs-only``: only those, from the committed JSON). Absolute times are
those of the machine the script runs on (named in the output); only the ratio carries over.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import machine  # noqa: E402

from moor_env import load_scene, simulate_drop, solve_statics  # noqa: E402
from moor_env.crosscheck.moordyn import run_moordyn_drop  # noqa: E402

SCENE = "gjoa-500"
REPEATS = 3
REFERENCE = {"discretization.vertical_chain_segment_m": 0.25, "discretization.loop_chain_segment_m": 0.25}
CHECK = {"discretization.vertical_chain_segment_m": 0.5, "discretization.loop_chain_segment_m": 0.5}
RESULTS = ROOT / "benchmarks" / "results" / "bench_drop.json"
DOC = DOCS / "drop-speed.md"
README = ROOT / "README.md"
COMMAND = "python benchmarks/bench_drop.py"


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The docs blocks of one run: the table (docs/drop-speed.md) and the README's headline line."""
    ours, md, ref = out["ours"], out["moordyn"], out["reference"]
    finer = md["at_0.7_dt"]
    rows = [[f"ours, default (1 m chain, symplectic Euler, dt {1e3 * ours['dt_s']:.2f} ms)",
             f"{ours['wall_dynamic_s_best_of_3']:.2f} s", f"{ours['touchdown_speed_m_s']:.2f} m/s",
             f"{ours['tilt_deg']:.2f} deg", f"{100 * ours['error_vs_reference']:+.2f} %"],
            [f"MoorDyn {out['moordyn_version']}, RK4 at 0.7 of its stability limit, same segments "
             f"(dt {1e3 * md['dt_s']:.2f} ms)", f"{md['wall_s_best_of_3']:.2f} s",
             f"{md['touchdown_speed_m_s']:.2f} m/s",
             f"{md['tilt_deg']:.2f} deg", f"{100 * md['error_vs_reference']:+.2f} % "
             f"({100 * finer['error_vs_reference']:+.2f} % at 0.7 of that step)"]]
    text = "\n".join([
        run_line({**out, "machine": out["measured_on"]}, COMMAND), "",
        table([f"{out['scene']} fall, release to touchdown", "wall time (best of 3)", "touchdown speed", "tilt",
               f"speed error vs converged reference ({ref['touchdown_speed_m_s']:.3f} m/s)"], rows), "",
        f"MoorDyn/ours: {out['ratio_moordyn_over_ours']:.1f}x the wall time. The reference is ours with 0.25 m "
        f"chain segments (dt {1e3 * ref['dt_s']:.3f} ms); at 0.5 m it differs by "
        f"{100 * ref['check_minus_reference_relative']:+.2f} %."])
    headline = (f"**Accuracy and speed of one fall** ({out['scene']}): {ours['touchdown_speed_m_s']:.2f} m/s at "
                f"touchdown, {100 * ours['error_vs_reference']:+.2f} % against the converged reference, in "
                f"{ours['wall_dynamic_s_best_of_3']:.2f} s; MoorDyn {out['moordyn_version']} on the same scene: "
                f"{100 * md['error_vs_reference']:+.2f} % in {md['wall_s_best_of_3']:.2f} s "
                f"({out['ratio_moordyn_over_ours']:.1f}x). `{COMMAND}`, run {out['date'][:10]}: "
                "[docs/drop-speed.md](docs/drop-speed.md).")
    return [(DOC, "bench_drop", text), (README, "headline-bench_drop", headline)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/bench_drop.json``."""
    return docs_blocks(load_result("bench_drop"))


def main() -> dict:
    if "--docs-only" in sys.argv[1:]:  # rewrite the docs tables from the committed JSON, run nothing
        write_blocks(docs_from_results())
        return load_result("bench_drop")
    from importlib.metadata import version

    import moordyn  # noqa: F401  (fail early when the oracle is missing)

    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    scene = load_scene(SCENE)
    t0 = time.perf_counter()
    simulate_drop(scene, history=False)  # warm-up: numba compile (or cache load)
    warmup_s = time.perf_counter() - t0

    ours_runs = [simulate_drop(scene, history=False) for _ in range(REPEATS)]
    ours = min(ours_runs, key=lambda r: r.wall_dynamic_s)
    speeds = {r.touchdown_speed_m_s for r in ours_runs}
    assert len(speeds) == 1, "our runs must be deterministic"

    static = solve_statics(scene)
    md_runs = [run_moordyn_drop(scene, static=static) for _ in range(REPEATS)]
    md = min(md_runs, key=lambda r: r["wall_s"])
    md_finer = run_moordyn_drop(scene, static=static, dt_s=0.7 * md["dt_s"])  # scatter of MoorDyn's result

    ref = simulate_drop(load_scene(SCENE, REFERENCE), history=False)
    check = simulate_drop(load_scene(SCENE, CHECK), history=False)
    v_ref = ref.touchdown_speed_m_s
    convergence = check.touchdown_speed_m_s / v_ref - 1.0

    def err(v: float) -> float:
        return v / v_ref - 1.0

    out = {
        "scene": SCENE,
        "measured_on": machine(),
        "python": platform.python_version(),
        "moordyn_version": version("moordyn"),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "note": "absolute wall times are those of the machine named in measured_on; best of 3 each",
        "load_average_1min": {"before": load_before,
                              "after": os.getloadavg()[0] if hasattr(os, "getloadavg") else None},
        "ours": {
            "wall_dynamic_s_best_of_3": ours.wall_dynamic_s,
            "wall_dynamic_s_all": [r.wall_dynamic_s for r in ours_runs],
            "warmup_compile_and_run_s": warmup_s,
            "touchdown_speed_m_s": ours.touchdown_speed_m_s,
            "touchdown_time_s": ours.touchdown_time_s,
            "tilt_deg": ours.tilt_deg,
            "error_vs_reference": err(ours.touchdown_speed_m_s),
            "dt_s": ours.dt_s,
            "n_steps": ours.n_steps,
            "n_nodes": ours.n_nodes,
            "settings": "default: 1 m chain segments, 5 m fibre, symplectic Euler at 0.9 x stability limit",
        },
        "moordyn": {
            "wall_s_best_of_3": md["wall_s"],
            "wall_s_all": [r["wall_s"] for r in md_runs],
            "touchdown_speed_m_s": md["touchdown_speed_m_s"],
            "touchdown_time_s": md["touchdown_time_s"],
            "tilt_deg": md["tilt_deg"],
            "error_vs_reference": err(md["touchdown_speed_m_s"]),
            "dt_s": md["dt_s"],
            "n_steps": md["n_steps"],
            "n_line_segments": md["n_line_segments"],
            "settings": "RK4 at 0.7 x stability limit, our segments, line damping off, 20 steps per Step call",
            "at_0.7_dt": {"dt_s": md_finer["dt_s"], "touchdown_speed_m_s": md_finer["touchdown_speed_m_s"],
                          "error_vs_reference": err(md_finer["touchdown_speed_m_s"]),
                          "tilt_deg": md_finer["tilt_deg"]},
        },
        "ratio_moordyn_over_ours": md["wall_s"] / ours.wall_dynamic_s,
        "reference": {
            "overrides": REFERENCE,
            "touchdown_speed_m_s": v_ref,
            "dt_s": ref.dt_s,
            "wall_dynamic_s": ref.wall_dynamic_s,
            "check_overrides": CHECK,
            "check_touchdown_speed_m_s": check.touchdown_speed_m_s,
            "check_minus_reference_relative": convergence,
        },
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(out, indent=2) + "\n")
    write_blocks(docs_blocks(out))

    line = (f"| {SCENE} fall to touchdown | ours {ours.wall_dynamic_s:.2f} s | MoorDyn {md['wall_s']:.2f} s | "
            f"MoorDyn/ours {out['ratio_moordyn_over_ours']:.1f}x | touchdown-speed error vs converged reference "
            f"(0.25 m chain, {v_ref:.3f} m/s; 0.5 m differs by {100 * convergence:+.2f} %): ours "
            f"{100 * err(ours.touchdown_speed_m_s):+.2f} %, MoorDyn {100 * err(md['touchdown_speed_m_s']):+.2f} % "
            f"(at 0.7 dtM {100 * err(md_finer['touchdown_speed_m_s']):+.2f} %) | "
            f"measured on {out['measured_on']} |")
    print(line)
    if not math.isfinite(out["ratio_moordyn_over_ours"]):
        raise SystemExit("benchmark produced a non-finite ratio")
    return out


if __name__ == "__main__":
    main()

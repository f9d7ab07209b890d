"""Benchmark: the gjoa-500 fall (release to touchdown) in our numba kernel and in MoorDyn-C v2, with accuracy.

Run from the repository root: ``python benchmarks/bench_drop.py``. One run does everything:

1. ours at default settings (1 m chain segments, symplectic Euler at 0.9 of its stability limit): a warm-up
   run compiles the kernels, then the best ``wall_dynamic_s`` of 3 runs;
2. MoorDyn (PyPI ``moordyn`` 2.7) on the same scene at its stable default settings in
   :func:`moor_env.crosscheck.moordyn.run_moordyn_drop` (same segments, RK4 at 0.7 of its stability limit,
   line damping off), seeded with our static equilibrium: best stepping wall time of 3 runs;
3. a converged reference touchdown speed: ours with 0.25 m chain segments (vertical chain and loop), checked
   against 0.5 m; both codes' errors are relative to it.

Writes ``benchmarks/results/bench_drop.json`` and prints one markdown line for the README. Absolute times are
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

from _machine import machine  # noqa: E402

from moor_env import load_scene, simulate_drop, solve_statics  # noqa: E402
from moor_env.crosscheck.moordyn import run_moordyn_drop  # noqa: E402

SCENE = "gjoa-500"
REPEATS = 3
REFERENCE = {"discretization.vertical_chain_segment_m": 0.25, "discretization.loop_chain_segment_m": 0.25}
CHECK = {"discretization.vertical_chain_segment_m": 0.5, "discretization.loop_chain_segment_m": 0.5}
RESULTS = ROOT / "benchmarks" / "results" / "bench_drop.json"


def main() -> dict:
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

"""Speed against error: our lumped-mass model over its knobs, and MoorDyn over its stable settings, per scene.

Run from the repository root (one command; a progress bar shows the runs)::

    python benchmarks/speed_vs_error.py            # --quick: about 10 minutes on a shared 2-core machine
    python benchmarks/speed_vs_error.py --full     # every knob level (tens of minutes)

What it does, per scene (``gjoa-500``; ``deep-1500``; ``wide`` = gjoa-500 with spacing 170 m and a 10 m vertical
chain; ``snap`` = gjoa-500 with spacing 170 m, whose chain loop snaps taut before touchdown; ``current-waves`` =
gjoa-500 with the current of seed 003, Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, chapter 8,
Hs 2 m and release after 20 s of waves):

1. **Reference**: our explicit symplectic Euler at 0.9 of its stability limit on a ladder of uniformly refined
   chain segments c (fibre 5 c, wire 10 c); the finest level is the reference and the two finest levels are
   compared (the convergence is printed and written; ``--full`` adds a time-step check of the reference).
2. **Our knobs**: element length per line, near and far from the anchor (vertical chain = near, loop chain =
   the rest of the bottom chain, fibre = far part of the mooring line, wire), time step and integrator
   (``symplectic_euler``, ``rk2``, ``implicit_euler`` at fractions and multiples of its default step), and
   components: the cut wire simulated after release or dropped, pre-release dynamics in calm water (10 s) or
   statics only, and (``current-waves``) release after the waves have acted versus from statics.
3. **The fidelity presets** of ``configs/fidelity.yaml`` (``fast``, ``default``, ``accurate``) on every scene,
   and both resolutions of ``fast`` (its slack-line keys and its ``tight_line`` keys) on every scene.
4. **MoorDyn 2.7** (``moor_env.crosscheck.moordyn``, RK4, line damping off, started from our statics) over its
   stable settings: chain (and fibre) segment length and time step as a fraction of its RK4 stability limit
   (on ``wide`` down to 0.25 m chain). The ratio of its cost to ours at equal error is printed; where its sweep
   never reaches an error, a lower bound (its most accurate run against our cheapest run at that error).
   ``current-waves`` is not supported by the MoorDyn bridge (no current, waves or pre-release phase).
5. **Node scaling** on ``deep-1500`` (wire kept): cost per simulated second against the number of line nodes,
   refining chain, fibre and wire together at a fixed time step (implicit and explicit), with log-log slopes.

Errors against the reference: touchdown speed (relative), tilt (deg; where the reference tilt is below 1 deg it
is reported as a spread across resolutions, not as an error), touchdown time (ms) and drift (m). Cost: wall time
of the dynamic part (pre-release phase if any, release and fall; statics excluded for both codes, MoorDyn is
seeded with our statics), best of 3 for runs under ``FAST_S``; our CPU time (``time.process_time``) alongside.

Writes ``benchmarks/results/speed_vs_error[_quick].json``, ``docs/speed_vs_error_<scene>.png``,
``docs/speed_vs_error_nodes.png``, ``docs/speed_vs_error.md`` (tables written by this script) and the README's
headline line (``--docs-only``: the markdown only, from the committed JSON).
Absolute times are those of the machine named in the output (its load average is recorded).

This script is the entry point; the study's cases, runs, analysis, plots and docs are in the package
``benchmarks/_speed_vs_error/``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

from tqdm import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import load_result, write_blocks  # noqa: E402
from _machine import machine  # noqa: E402
from _speed_vs_error.analysis import add_errors, cost_at, fit_slopes, fmt, metric_front  # noqa: E402
from _speed_vs_error.cases import (  # noqa: E402
    FIT_CHECK,
    IMPL,
    SCENES,
    SE,
    moordyn_cases,
    node_scaling_cases,
    our_cases,
    uniform,
)
from _speed_vs_error.markdown import docs_blocks, markdown, ratio_bound_note  # noqa: E402
from _speed_vs_error.plots import plot_nodes, plot_scene  # noqa: E402
from _speed_vs_error.runs import run_fit_check, run_md, run_ours, run_scaling  # noqa: E402

from moor_env import load_scene  # noqa: E402

RESULTS_DIR = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs"
TILT_SMALL_DEG = 1.0  # reference tilt below this: report a spread across resolutions, not an error


def write_docs(out: dict[str, Any]) -> None:
    """Pareto plots, the node-scaling plot and docs/speed_vs_error.md from the results."""
    DOCS.mkdir(exist_ok=True)
    for s, data in out["scenes"].items():
        plot_scene(s, data, DOCS / f"speed_vs_error_{s}.png")
    if out["node_scaling"]["series"]:
        plot_nodes(out["node_scaling"], DOCS / "speed_vs_error_nodes.png")
    (DOCS / "speed_vs_error.md").write_text(markdown(out))


def results_for_docs(full: bool = False) -> dict[str, Any]:
    """The committed results (quick unless ``full``), with the node-scaling slopes the docs read."""
    out = load_result("speed_vs_error" if full else "speed_vs_error_quick")
    fit_slopes(out["node_scaling"]["series"])
    return out


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/speed_vs_error_quick.json``."""
    return docs_blocks(results_for_docs())


# --- main ----------------------------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Command line: run the study (or only rewrite the docs from results) and return the results."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--quick", action="store_true", help="fewer knob levels (default; a few minutes)")
    group.add_argument("--full", action="store_true", help="every knob level")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of " + ", ".join(SCENES))
    parser.add_argument("--no-moordyn", action="store_true", help="skip the MoorDyn runs")
    parser.add_argument("--no-docs", action="store_true", help="do not write docs/ (JSON only)")
    parser.add_argument("-v", "--verbose", action="store_true", help="one line per run")
    parser.add_argument("--report-only", metavar="JSON", help="rewrite docs/ from a results file, no runs")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite docs/speed_vs_error.md and the README's headline from the committed "
                             "benchmarks/results/speed_vs_error[_quick].json (no plots, no runs)")
    args = parser.parse_args(argv)
    if args.docs_only:
        out = results_for_docs(args.full)
        (DOCS / "speed_vs_error.md").write_text(markdown(out))
        write_blocks(docs_blocks(out))
        return out
    if args.report_only:
        out = json.loads(Path(args.report_only).read_text())
        fit_slopes(out["node_scaling"]["series"])
        write_docs(out)
        write_blocks(docs_blocks(out))
        return out
    mode = "full" if args.full else "quick"
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in SCENES:
            parser.error(f"unknown scene {s!r}: one of {', '.join(SCENES)}")
    md_ok = not args.no_moordyn
    if md_ok:
        try:
            import moordyn  # noqa: F401
        except ImportError:
            print("moordyn not installed: MoorDyn fronts skipped (pip install 'moordyn>=2.7,<2.8')")
            md_ok = False

    t_start = time.perf_counter()
    load_before = os.getloadavg()[0]
    # warm-up: compile (or load) every kernel before any timing
    for integ in (SE, "rk2", IMPL):
        run_ours(SCENES["gjoa-500"], dict(uniform(4.0), integrator=integ))

    tasks: list[tuple[str, str, dict[str, Any]]] = []
    for s in scenes:
        tasks += [("ours", s, c) for c in our_cases(s, mode)]
        if md_ok and SCENES[s]["moordyn"]:
            tasks += [("moordyn", s, c) for c in moordyn_cases(mode, s)]
    scaling_cases = node_scaling_cases(mode)
    tasks += [("scaling", "deep-1500", c) for c in scaling_cases]
    tasks += [("fit", scene, {"label": f"fit check {geo}", "geometry": geo, "check": k == 3})
              for k, (scene, geo) in enumerate(FIT_CHECK)]

    results: dict[str, dict[str, Any]] = {s: {"ours": [], "moordyn": []} for s in scenes}
    scaling_runs: list[dict[str, Any]] = []
    fit_rows: list[dict[str, Any]] = []
    bar = tqdm(tasks, unit="run", desc="speed_vs_error", dynamic_ncols=True)
    for kind, s, case in bar:
        bar.set_postfix_str(f"{s}: {case.get('label', case.get('series', ''))}"[:60])
        spec = SCENES[s]
        t_task = time.perf_counter()
        if kind == "ours":
            r = run_ours(spec, case["overrides"])
            r.update(family=case["family"], label=case["label"], overrides={k: v for k, v in case["overrides"].items()})
            results[s]["ours"].append(r)
        elif kind == "moordyn":
            ref_cfg = load_scene(spec["scene"], {**spec["overrides"], **uniform(case["chain_m"]), "integrator": SE})
            r = run_md(spec, case, ref_cfg)
            r.update(family=case["family"], label=case["label"])
            results[s]["moordyn"].append(r)
        elif kind == "fit":
            r = run_fit_check(s, case["geometry"], case["check"])
            fit_rows.append(r)
        else:
            r = run_scaling(case)
            scaling_runs.append(r)
        if args.verbose:
            tqdm.write(f"{time.perf_counter() - t_task:7.1f} s  {s}: {case.get('label', case.get('series'))}: "
                       f"{r.get('status')} {fmt(r.get('speed'), '.4f')} m/s {fmt(r.get('tilt'), '.2f')} deg "
                       f"wall {fmt(r.get('wall_s'), '.3g')} s statics {fmt(r.get('wall_static_s'), '.3g')} s")
    bar.close()

    out: dict[str, Any] = {
        "mode": mode, "measured_on": machine(), "python": platform.python_version(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "scenes": {}, "equal_error": [],
    }
    try:
        from importlib.metadata import version

        out["moordyn_version"] = version("moordyn")
    except Exception:  # noqa: BLE001
        out["moordyn_version"] = None
    for s in scenes:
        ours, md = results[s]["ours"], results[s]["moordyn"]
        ladder = [r for r in ours if r["family"] == "reference ladder" and r.get("status") == "ok"]
        ref, chk = ladder[-1], ladder[-2]
        ref["is_reference"] = True
        add_errors(ours, ref)
        add_errors(md, ref)
        ref_info = dict(chain_m=ref["vertical_m"], speed=ref["speed"], tilt=ref["tilt"], time=ref["time"],
                        drift=ref["drift"], dt_s=ref["dt_s"], wall_s=ref["wall_s"], n_nodes=ref["n_nodes"])
        small = abs(ref["tilt"]) < TILT_SMALL_DEG
        data: dict[str, Any] = {
            "about": SCENES[s]["about"], "reference": ref_info, "tilt_small": small,
            "check": dict(chain_m=chk["vertical_m"], speed_err_pct=chk["speed_err_pct"],
                          tilt_err_deg=chk["tilt_err_deg"], time_err_ms=chk["time_err_ms"],
                          drift_err_m=chk["drift_err_m"]),
            "ours": ours, "moordyn": md,
            "front_ours_speed": metric_front(ours, "speed_err_pct", 1e-3),
            "front_moordyn_speed": metric_front(md, "speed_err_pct", 1e-3),
            "front_ours_tilt": metric_front(ours, "tilt_err_deg", 1e-3),
            "front_moordyn_tilt": metric_front(md, "tilt_err_deg", 1e-3),
        }
        dtc = [r for r in ours if r["family"] == "reference dt check" and r.get("status") == "ok"]
        if dtc:
            data["dt_check"] = {"speed_err_pct": dtc[0]["speed_err_pct"], "tilt_err_deg": dtc[0]["tilt_err_deg"]}
        ok_ours = [r for r in ours if r.get("status") == "ok"]
        ok_md = [r for r in md if r.get("status") == "ok"]
        data["speed_spread"] = {
            "ladder": [min(r["speed"] for r in ladder), max(r["speed"] for r in ladder)],
            "ours": [min(r["speed"] for r in ok_ours), max(r["speed"] for r in ok_ours)],
            "moordyn": [min(r["speed"] for r in ok_md), max(r["speed"] for r in ok_md)] if ok_md else None,
        }
        data["tilt_spread"] = {
            "ladder": [min(r["tilt"] for r in ladder), max(r["tilt"] for r in ladder)],
            "ours": [min(r["tilt"] for r in ok_ours), max(r["tilt"] for r in ok_ours)],
            "moordyn": [min(r["tilt"] for r in ok_md), max(r["tilt"] for r in ok_md)] if ok_md else None,
        }
        out["scenes"][s] = data
        if ok_md:
            targets = [("speed error [%]", "speed_err_pct", e) for e in (3.0, 1.0, 0.3)]
            if not small:
                targets += [("tilt error [deg]", "tilt_err_deg", e) for e in (0.5, 0.3)]
            for metric, key, e in targets:
                fo = metric_front(ours, key, 1e-3)
                fm = metric_front(md, key, 1e-3)
                co, cm = cost_at(fo, e), cost_at(fm, e)
                row = {"scene": s, "metric": metric, "error": e, "ours": co, "moordyn": cm}
                for k in ("measured", "interpolated"):
                    row[f"ratio_{k}"] = (cm[k] / co[k]) if (co[k] and cm[k]) else None
                if co["measured"] and not cm["measured"] and fm:
                    # MoorDyn never got there: its most accurate run bounds its cost from below
                    row["moordyn_best"] = {"error": fm[-1][1], "cost": fm[-1][0]}
                    row["ratio_lower_bound"] = fm[-1][0] / co["measured"]
                out["equal_error"].append(row)

    # node scaling
    series: dict[str, Any] = {}
    for r in scaling_runs:
        if r.get("status") != "ok":
            continue
        info = series.setdefault(r["series"], {"s": [], "n_nodes": [], "wall_per_sim_s": [], "cpu_per_sim_s": [],
                                               "dt_s_each": []})
        info["s"].append(r["s"])
        info["n_nodes"].append(r["n_nodes"])
        info["wall_per_sim_s"].append(r["wall_per_sim_s"])
        info["cpu_per_sim_s"].append(r["cpu_per_sim_s"])
        info["dt_s_each"].append(r["dt_s"])
    fit_slopes(series)
    out["node_scaling"] = {"runs": scaling_runs, "series": series}
    out["fit_check"] = fit_rows

    out["load_average_1min"] = {"before": load_before, "after": os.getloadavg()[0]}
    out["wall_total_s"] = time.perf_counter() - t_start
    suffix = "" if mode == "full" else "_quick"
    json_path = RESULTS_DIR / f"speed_vs_error{suffix}.json"
    out["json"] = str(json_path.relative_to(ROOT))
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(out, indent=1, default=float) + "\n")
    if not args.no_docs:
        write_docs(out)
        write_blocks(docs_blocks(out))

    # summary on stdout
    print(f"\nspeed_vs_error ({mode}) on {out['measured_on']}, load {load_before:.2f} -> "
          f"{out['load_average_1min']['after']:.2f}, {out['wall_total_s'] / 60:.1f} min")
    for s, data in out["scenes"].items():
        ref, chk = data["reference"], data["check"]
        print(f"  {s}: reference chain {ref['chain_m']:g} m {ref['speed']:.3f} m/s tilt {ref['tilt']:.2f} deg; "
              f"chain {chk['chain_m']:g} m differs {chk['speed_err_pct']:+.2f} % / {chk['tilt_err_deg']:+.2f} deg")
        for r in data["ours"]:
            if r["family"] in ("preset", "preset branches") and r.get("status") == "ok":
                print(f"    {r['label']:16s} {r['speed_err_pct']:+.2f} %  tilt {r['tilt_err_deg']:+.2f} deg  "
                      f"wall {r['wall_s'] * 1e3:.1f} ms  cpu {r['cpu_s'] * 1e3:.1f} ms")
    for row in out["equal_error"]:
        print(f"  {row['scene']}: {row['metric']} <= {row['error']:g}: ours {fmt(row['ours']['measured'])} s "
              f"(interp {fmt(row['ours']['interpolated'])}), MoorDyn {fmt(row['moordyn']['measured'])} s "
              f"(interp {fmt(row['moordyn']['interpolated'])}); MoorDyn/ours {fmt(row['ratio_measured'], '.1f')}x "
              f"(interp {fmt(row['ratio_interpolated'], '.1f')}x)" + ratio_bound_note(row))
    for name, info in series.items():
        print(f"  node scaling, {name}: slope {fmt(info['slope'], '.2f')} "
              f"(3 largest {fmt(info['slope_upper'], '.2f')})")
    return out


if __name__ == "__main__":
    main()

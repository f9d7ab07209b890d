"""docs/speed_vs_error.md and the README's headline line, rendered from the study's results."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from _speed_vs_error.analysis import fmt
from _speed_vs_error.cases import FIT_REFERENCE_C, SCENES
from _speed_vs_error.findings import findings, run_labelled, settings_of, slack_text
from _speed_vs_error.runs import FAST_S, REPEATS

README = Path(__file__).resolve().parents[2] / "README.md"


def fit_check_table(rows: list[dict[str, Any]]) -> list[str]:
    """The fit check: both ``fast`` resolutions and the preset's choice around the fit's bounds."""
    if not rows:
        return []
    L = ["## Fit check: where `fast` needs its fine loop chain", "",
         f"Geometries around the bounds of `fast`'s `tight_line` rule (calm, no waves), each against explicit "
         f"{FIT_REFERENCE_C:g} m chain (which differs from {FIT_REFERENCE_C / 2:g} m by the `ref. check` column where "
         "run). Touchdown-speed errors of the coarse (slack-line) and fine (tight-line) resolutions and of the "
         "preset itself, which picks one of them from the slack and chord angle.", "",
         "| scene | geometry | slack, chord angle | reference [m/s] | ref. check | slack-line branch | "
         "tight-line branch | fast picks | fast: error, CPU |", "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        ref, runs = row["reference"], row["runs"]
        chk = row.get("reference_check")
        chk_txt = (f"{100.0 * (chk['speed'] / ref['speed'] - 1.0):+.2f} %"
                   if chk and chk.get("status") == "ok" and ref.get("status") == "ok" else "")
        errs = {k: (f"{r['speed_err_pct']:+.2f} %" if "speed_err_pct" in r else r.get("status", "-"))
                for k, r in runs.items()}
        fast = runs["preset"]
        picks = "tight-line" if fast.get("loop_m") == runs["tight-line"].get("loop_m") else "slack-line"
        geo = ", ".join(f"{k.replace('_m', '')} {v:g} m" for k, v in row["geometry"].items())
        L.append(f"| {row['scene']} | {geo} | {slack_text(row['line_slack'])} | {fmt(ref.get('speed'), '.3f')} | "
                 f"{chk_txt} | {errs['slack-line']} | {errs['tight-line']} | {picks} | {errs['preset']}, "
                 f"{fmt(fast.get('cpu_s') and fast['cpu_s'] * 1e3, '.3g')} ms |")
    misses = [f"{row['scene']} {slack_text(row['line_slack'])} ({row['runs']['preset']['speed_err_pct']:+.2f} %)"
              for row in rows if abs(row["runs"]["preset"].get("speed_err_pct", 0.0)) > 3.0]
    L += ["", "Where `fast` misses 3 % here: " + ("; ".join(misses) if misses else "nowhere") + ". (Where the loop "
          "snaps taut in the last moments of the fall, the touchdown speed jumps with the snap's timing.)", ""]
    return L


def ratio_bound_note(row: dict[str, Any]) -> str:
    """Where MoorDyn never reached the error: its best error, and the ratio as a lower bound."""
    if row.get("ratio_lower_bound") is None:
        return ""
    best = row["moordyn_best"]
    return (f"; MoorDyn not reached (its best {best['error']:.3g} at {best['cost']:.3g} s): "
            f"MoorDyn/ours > {row['ratio_lower_bound']:.1f}x")


def spread_cells(spread: dict[str, Any], unit: str) -> str:
    """Table cells ``ladder | all our runs | MoorDyn's runs |`` of a spread (ranges)."""
    cells = [f"{spread[k][0]:.2f} .. {spread[k][1]:.2f}{unit}" if spread.get(k) else "-"
             for k in ("ladder", "ours", "moordyn")]
    return " | ".join(cells) + " |"


def markdown(out: dict[str, Any]) -> str:
    """docs/speed_vs_error.md from the study's results."""
    L: list[str] = []
    mode = out["mode"]
    L += ["# Speed against error", "",
          f"Written by `python benchmarks/speed_vs_error.py{' --full' if mode == 'full' else ''}` "
          f"({mode} mode) on {out['measured_on']}, {out['date']}; load average (1 min) "
          f"{fmt(out['load_average_1min']['before'], '.2f')} before, {fmt(out['load_average_1min']['after'], '.2f')} "
          f"after; {out['wall_total_s'] / 60:.1f} min in all. Raw results: `{out['json']}`. Absolute times are "
          "those of this machine; the ratios carry over. The machine is shared: a wall time also counts other jobs' "
          "share of it when the load is above its core count, so our CPU time (listed beside it) is the steadier "
          "measure of our cost; ratios to MoorDyn compare wall times taken in the same run.", "",
          "Cost is the wall time of the dynamic run (pre-release phase if any, release, fall to touchdown), best "
          f"of {REPEATS} for runs under {FAST_S:g} s; statics are excluded for both codes (MoorDyn starts from our "
          "equilibrium; ours are listed per run as `statics`). Errors are against the reference (the finest "
          "explicit level of each scene's ladder): touchdown speed (relative), tilt, touchdown time and drift. "
          "Element lengths are written vertical chain / loop chain / fibre / wire [m] (near to far from the "
          "anchor). MoorDyn runs RK4 with line damping off (see `moor_env/crosscheck/moordyn.py`), with "
          "dt as a fraction of its RK4 limit 2.83/omega_max; the `current-waves` scene is not supported by the "
          "MoorDyn bridge (no current, waves or pre-release phase), so it has no MoorDyn front. Ours runs each "
          "scene's line-anchor contact as its `discretization.line_anchor_contact: auto` sets it (on in every "
          "scene here: their chain catches up with the anchor), MoorDyn has none. Both start from the equilibrium "
          "as solved, whose vertical chain hangs exactly on the anchor's axis: where that chain catches up, a "
          "disturbance of it changes the landing (see [fall-accuracy.md](fall-accuracy.md)).", ""]
    L += findings(out)
    # references
    L += ["## References and their convergence", "",
          "| scene | reference (explicit) | speed [m/s] | tilt [deg] | time [s] | drift [m] | next-coarser level | "
          "speed diff | tilt diff | time diff | drift diff | ref. wall |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        ref, chk = data["reference"], data["check"]
        L.append(f"| {name} | chain {ref['chain_m']:g} m, dt {ref['dt_s'] * 1e3:.3g} ms | {ref['speed']:.3f} | "
                 f"{ref['tilt']:.2f} | {ref['time']:.4f} | {ref['drift']:.3f} | chain {chk['chain_m']:g} m | "
                 f"{chk['speed_err_pct']:+.2f} % | {chk['tilt_err_deg']:+.2f} deg | {chk['time_err_ms']:+.1f} ms | "
                 f"{chk['drift_err_m']:+.3f} m | {ref['wall_s']:.1f} s |")
    L.append("")
    for name, data in out["scenes"].items():
        if data.get("dt_check"):
            d = data["dt_check"]
            L.append(f"- {name}: the reference at half its time step differs by {d['speed_err_pct']:+.3f} % in "
                     f"speed and {d['tilt_err_deg']:+.3f} deg in tilt.")
    L.append("")
    # tilt spread where small
    L += ["## Spread of the touchdown speed", "",
          "Range of the touchdown speed over the reference ladder, over all our runs and over MoorDyn's runs.", "",
          "| scene | reference | ours: ladder | ours: all runs | MoorDyn: all runs |", "|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        L.append(f"| {name} | {data['reference']['speed']:.3f} m/s | {spread_cells(data['speed_spread'], '')}")
    L.append("")
    L += ["## Tilt where it is small: spread across resolutions", "",
          "| scene | reference tilt | ours: range over the reference ladder | ours: range over all runs | "
          "MoorDyn: range over its runs |", "|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        if data["tilt_small"]:
            L.append(f"| {name} | {data['reference']['tilt']:.2f} deg | {spread_cells(data['tilt_spread'], ' deg')}")
    L.append("")
    # equal-error ratios
    L += ["## Ours against MoorDyn at equal error", "",
          "Cost to reach an error on each code's measured front: `measured` is the cheapest run at or below that "
          "error, `interp.` interpolates log-log between the two front points around it.", "",
          "| scene | error | ours measured | ours interp. | MoorDyn measured | MoorDyn interp. | "
          "MoorDyn / ours (measured) | MoorDyn / ours (interp.) | MoorDyn not reached: its best, ratio bound |",
          "|---|---|---|---|---|---|---|---|---|"]
    for row in out["equal_error"]:
        best = row.get("moordyn_best")
        bound = (f"{best['error']:.3g} at {best['cost']:.3g} s: > {row['ratio_lower_bound']:.1f}x" if best else "")
        L.append(f"| {row['scene']} | {row['metric']} <= {row['error']:g} | {fmt(row['ours']['measured'], '.3g')} s | "
                 f"{fmt(row['ours']['interpolated'], '.3g')} s | {fmt(row['moordyn']['measured'], '.3g')} s | "
                 f"{fmt(row['moordyn']['interpolated'], '.3g')} s | {fmt(row['ratio_measured'], '.1f')}x | "
                 f"{fmt(row['ratio_interpolated'], '.1f')}x | {bound} |")
    L.append("")
    # presets
    L += ["## Fidelity presets (configs/fidelity.yaml) on every scene", "",
          "`fast` fits the scene: its `tight_line` resolution applies where the mooring line's slack at touchdown "
          "(`moor_env.config.mooring_line_slack`: free line length minus the chord from the release point, "
          "vertical chain straight above the touched-down anchor, to the second vessel) is below its "
          "`slack_below_m` or that chord is further than `chord_angle_above_deg` from the vertical (see the fit "
          "check below); the rows `fast, ... branch` run both of its resolutions on every scene.", "",
          "| scene | preset | slack, chord angle | settings | integrator | dt [ms] | nodes | wall [ms] | CPU [ms] | "
          "statics [s] | speed err | tilt (err) | time err | drift err |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        for r in data["ours"]:
            if r["family"] not in ("preset", "preset branches") or r.get("status") != "ok":
                continue
            tilt = f"{r['tilt']:.2f} deg" if data["tilt_small"] else f"{r['tilt_err_deg']:+.2f} deg"
            L.append(f"| {name} | {r['label'].replace('preset ', '')} | {slack_text(r.get('line_slack'))} | "
                     f"{settings_of(r)} | {r['integrator']} | "
                     f"{r['dt_s'] * 1e3:.3g} | {r['n_nodes']} | {r['wall_s'] * 1e3:.1f} | {r['cpu_s'] * 1e3:.1f} | "
                     f"{r['wall_static_s']:.2f} | {r['speed_err_pct']:+.2f} % | {tilt} | {r['time_err_ms']:+.1f} ms | "
                     f"{r['drift_err_m']:+.3f} m |")
    L.append("")
    L += fit_check_table(out.get("fit_check", []))
    # node scaling
    sc = out["node_scaling"]
    L += ["## Cost per simulated second against line nodes", "",
          "![node scaling](speed_vs_error_nodes.png)", "",
          "deep-1500 with the wire kept after release, release to touchdown, chain s / fibre 5 s / wire 10 s refined "
          "together; `fixed dt` series run every level at the finest level's default step (fixed temporal "
          "accuracy), the last series at each level's own explicit stability limit (which shrinks with the "
          "chain segment).", "",
          "| series | dt [ms] | nodes | CPU per simulated s [s] | fitted slope (all) | slope (3 largest) |",
          "|---|---|---|---|---|---|"]
    for series, info in sc["series"].items():
        L.append(f"| {series} | {fmt(info['dt_s'] * 1e3 if info['dt_s'] else None, '.3g')} | "
                 f"{', '.join(str(n) for n in info['n_nodes'])} | "
                 f"{', '.join(fmt(c, '.3g') for c in info['cpu_per_sim_s'])} | {info['slope']:.2f} | "
                 f"{fmt(info.get('slope_upper'), '.2f')} |")
    L.append("")
    # per scene tables
    for name, data in out["scenes"].items():
        L += [f"## {name}: {SCENES[name]['about']}", "", f"![{name}](speed_vs_error_{name}.png)", ""]
        fo = {tuple(p) for p in data["front_ours_speed"]}
        fm = {tuple(p) for p in data["front_moordyn_speed"]}
        L += ["Rows by cost; * marks the speed-error front of each code.", "",
              "| code | family | run | settings | dt [ms] | nodes | wall [ms] | CPU [ms] | speed err | "
              + ("tilt" if data["tilt_small"] else "tilt err") + " | time err | drift err |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        rows = [r for r in data["ours"] + data["moordyn"]]
        rows.sort(key=lambda r: r.get("wall_s", math.inf))
        for r in rows:
            if r.get("status") != "ok":
                dt = r.get("dt_s")
                L.append(f"| {r['code']} | {r['family']} | {r['label']} | {settings_of(r)} | "
                         f"{fmt(dt * 1e3 if dt else None, '.3g')} | - | - | - | {r['status']} | | | |")
                continue
            front = (r["wall_s"], max(abs(r["speed_err_pct"]), 1e-3)) in (fo if r["code"] == "ours" else fm)
            tilt = f"{r['tilt']:.2f}" if data["tilt_small"] else f"{r['tilt_err_deg']:+.2f}"
            L.append(f"| {r['code']}{' *' if front else ''} | {r['family']} | {r['label']} | {settings_of(r)} | "
                     f"{r['dt_s'] * 1e3:.3g} | {r.get('n_nodes', '-')} | {r['wall_s'] * 1e3:.1f} | "
                     f"{fmt(r.get('cpu_s') and r['cpu_s'] * 1e3, '.1f')} | {r['speed_err_pct']:+.2f} % | {tilt} | "
                     f"{r['time_err_ms']:+.1f} | {r['drift_err_m']:+.3f} |")
        L.append("")
    return "\n".join(L) + "\n"


def docs_blocks(out: dict[str, Any]) -> list[tuple[Path, str, str]]:
    """The README's headline line from the study's results (the whole of docs/speed_vs_error.md is
    :func:`markdown`)."""
    parts = []
    fast = run_labelled(out["scenes"]["gjoa-500"], "preset fast") if "gjoa-500" in out["scenes"] else None
    if fast is not None:
        parts.append(f"the `fast` preset lands the gjoa-500 fall within {fast['speed_err_pct']:+.2f} % of the "
                     f"converged reference in {fast['cpu_s'] * 1e3:.1f} ms CPU")
    for row in out["equal_error"]:
        if (row["scene"], row["metric"].split()[0], row["error"]) == ("gjoa-500", "speed", 1.0) \
                and row["ratio_measured"] is not None:
            parts.append(f"at {row['error']:g} % speed error MoorDyn takes {row['ratio_measured']:.0f}x our "
                         "wall time")
    mode = "" if out.get("mode") == "full" else " --quick"
    text = ("**Speed against error**: " + "; ".join(parts) + f". `python benchmarks/speed_vs_error.py{mode}`, run "
            f"{str(out['date'])[:10]}: [docs/speed_vs_error.md](docs/speed_vs_error.md).")
    return [(README, "headline-speed_vs_error", text)]

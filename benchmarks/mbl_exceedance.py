"""Where and when the lines' tensions exceed their MBL, and whether the peaks survive a smaller step, a finer
mesh and the explicit reference fall.

Run from the repository root: ``python benchmarks/mbl_exceedance.py [--episodes 80] [--seed 5000]``. Writes
``benchmarks/results/mbl_exceedance.json``, the figure ``docs/mbl-exceedance.png`` and the tables of
``docs/mbl-exceedance.md`` (``--docs-only``: only the tables, from the committed JSON).

A line's peak is the largest tension of any of its segments after any integration step, what the env's limit
check reads (``Simulator.state.line_f[:, LF_MAX_TENSION]``). Each peak is kept with its segment's position along
the line from the line's bottom end (the anchor for the vertical chain, the release unit for the mooring line),
its phase (before the release or in the fall), its time from the release and the anchor tip's height above the
seabed then. Parts:

* ``scene``: one drop in waves (gjoa-500 at 450 m, spacing 67.5 m, line 477 m, current 0.75, Hs 3.5 m, Tp 10 s,
  sea seed 3; released at once) with the fast, default and accurate presets, at 1/2 and 1/4 of their step, on a
  0.5 m chain and, for fast, with the explicit fall.
* ``sample``: the crew baseline (``agents/baselines.py``) on ``--episodes`` scenarios of ``AnchorPlan-v0`` drawn
  with seeds ``--seed``, ``--seed`` + 1, ..., each episode run as the env runs it and with one change
  (``SAMPLE_VARIANTS``). The crew's plan depends on the reset observation only, so every variant flies the same
  plan and, up to the change, the same episode.
* ``replay``: in the env's episodes with the largest peak in the fall (vertical chain) and before the release,
  the integration step that first took the line over its MBL, replayed from its start state in 1, 2, 4 and 8
  sub-steps, with the part of the segment's strain that its turn within the (last sub-)step leaves beyond the
  step's linearisation (:func:`_peak_tension.turn_strain`).
* ``levers``: calm drops from 500 m with the explicit fall on the default preset's 1 m chain and on a 0.5 m chain,
  one lever changed at a time from a spacing of 0.3 h and a mooring line of 1.04 h.
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

from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402
from _peak_tension import FALL, PRE_RELEASE, crew_episode, fall_peaks, make_env, replay_step  # noqa: E402
from fall_step import EXPLICIT_FALL  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from agents.baselines import PLAN_ENV, make_baseline  # noqa: E402
from agents.statistics import wilson_interval  # noqa: E402
from moor_env.config import load_scene  # noqa: E402
from moor_env.simulation import solve_statics  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "mbl_exceedance.json"
DOC = DOCS / "mbl-exceedance.md"
FIGURE = DOCS / "mbl-exceedance.png"
COMMAND = "python benchmarks/mbl_exceedance.py"
PRE = "control.pre_release_dt_s"
FINE = {"vertical_chain_segment_m": 0.5, "loop_chain_segment_m": 0.5, "fibre_segment_m": 50.0, "wire_segment_m": 100.0}
SCENE = {"water_depth_m": 450.0, "vessel_spacing_m": 67.5, "mooring_line_length_m": 477.0, "current_scale": 0.75,
         "sea_state_hs_m": 3.5, "sea_state_tp_s": 10.0, "sea_state_seed": 3}
HALF_CHAIN = {"discretization.vertical_chain_segment_m": 0.5, "discretization.loop_chain_segment_m": 0.5}
# name, scene overrides, step factor
SCENE_CASES = (
    ("fast", {"fidelity": "fast"}, 1.0), ("fast, 1/2 step", {"fidelity": "fast"}, 0.5),
    ("fast, 1/4 step", {"fidelity": "fast"}, 0.25), ("fast, 0.5 m chain", {"fidelity": "fast", **HALF_CHAIN}, 1.0),
    ("fast, explicit fall", {"fidelity": "fast", "fall_integrator": "symplectic_euler"}, 1.0),
    ("default", {"fidelity": "default"}, 1.0), ("default, 1/2 step", {"fidelity": "default"}, 0.5),
    ("default, 1/4 step", {"fidelity": "default"}, 0.25),
    ("default, 0.5 m chain", {"fidelity": "default", **HALF_CHAIN}, 1.0),
    ("accurate", {"fidelity": "accurate"}, 1.0), ("accurate, 1/2 step", {"fidelity": "accurate"}, 0.5),
)
# name, env overrides, fall mesh keys (None: the env's choice), fall step factor
SAMPLE_VARIANTS = (
    ("env", {}, None, 1.0),
    ("fall at 1/2 step", {}, None, 0.5),
    ("fall at 1/4 step", {}, None, 0.25),
    ("explicit fall", EXPLICIT_FALL, None, 1.0),
    ("explicit fall, 0.5 m chain", EXPLICIT_FALL, FINE, 1.0),
    ("pre-release step 0.1 s", {PRE: 0.1}, None, 1.0),
    ("pre-release step 0.05 s", {PRE: 0.05}, None, 1.0),
    ("pre-release step 0.025 s", {PRE: 0.025}, None, 1.0),
    ("pre-release 0.05 s, fall at 1/2 step", {PRE: 0.05}, None, 0.5),
    ("pre-release 0.05 s, explicit fall", {PRE: 0.05, **EXPLICIT_FALL}, None, 1.0),
)
# the variants beside the env's in the table of exceedances, with their short names there
REFINED = {"fall at 1/4 step": "fall 1/4 step", "explicit fall": "explicit", "explicit fall, 0.5 m chain":
           "explicit 0.5 m", "pre-release step 0.05 s": "pre-release 0.05 s",
           "pre-release 0.05 s, fall at 1/2 step": "0.05 s + fall 1/2", "pre-release 0.05 s, explicit fall":
           "0.05 s + explicit"}
KEPT_PEAKS = ("vertical_chain|fall", "mooring_line|fall", "mooring_line|pre-release")  # others kept from 0.5 MBL
LEVER_BASE = {"water_depth_m": 500.0, "vessel_spacing_m": 150.0, "mooring_line_length_m": 520.0, "fidelity": "default"}
LEVERS = (("spacing 0.3 h, line 1.04 h", {}), ("spacing 0.2 h", {"vessel_spacing_m": 100.0}),
          ("spacing 0.1 h", {"vessel_spacing_m": 50.0}), ("line 1.08 h", {"mooring_line_length_m": 540.0}),
          ("drop height 50 m", {"drop_height_m": 50.0}), ("drop height 100 m", {"drop_height_m": 100.0}),
          ("vertical chain 10 m", {"vertical_chain_length_m": 10.0}),
          ("vertical chain 30 m", {"vertical_chain_length_m": 30.0}))
SERIES_VARIANTS = ("env", "fall at 1/2 step", "fall at 1/4 step", "explicit fall", "explicit fall, 0.5 m chain")


def scene_drop(overrides: dict, step_factor: float) -> dict:
    """The ``scene`` drop (released at t = 0) with ``overrides``, stepped one step at a time at ``step_factor``
    times its fall step, peaks recorded after every step."""
    cfg = load_scene("gjoa-500", {**SCENE, **overrides})
    sim = solve_statics(cfg, progress=False).simulator
    return fall_peaks(sim, cfg.simulation.max_fall_time_s, step_factor)


def _ratios(rows: list[dict], key: str) -> list[float]:
    return [r["peaks"][key]["mbl_ratio"] for r in rows if key in r["peaks"]]


def summarize(rows: list[dict], variant: str) -> dict:
    """Exceedance counts (episodes, and peaks above the MBL by line and phase) and the peak-to-MBL distributions of
    one variant; an episode exceeds where the env's own maxima (``info["max_tension_n"]``) pass a line's MBL."""
    mine = [r for r in rows if r["variant"] == variant]
    exceeded = [r for r in mine if max(r["mbl_ratio"].values()) > 1.0]
    by_key = {}
    for r in mine:
        for key, p in r["peaks"].items():
            if p["mbl_ratio"] > 1.0:
                by_key[key] = by_key.get(key, 0) + 1
    dist = {}
    for key in ("vertical_chain|fall", "mooring_line|fall", "mooring_line|pre-release", "vertical_chain|pre-release",
                "wire|pre-release"):
        x = _ratios(mine, key)
        if x:
            dist[key] = {"median": float(np.median(x)), "p90": float(np.percentile(x, 90)), "max": float(max(x))}
    speeds = [r["speed_m_s"] for r in mine if r["speed_m_s"] is not None]
    return {"episodes": len(mine), "exceeded": len(exceeded), "wilson": wilson_interval(len(exceeded), len(mine)),
            "by_line_phase": by_key, "mbl_ratio": dist, "failures": sum(r["status"] != "touchdown" for r in mine),
            "speed_m_s_median": float(np.median(speeds)) if speeds else None,
            "cpu_s_median": float(np.median([r["cpu_s"] for r in mine]))}


def _at(p: dict | None) -> str:
    if not p:
        return "-"
    tip = "" if p.get("tip_height_m") is None else f", tip {p['tip_height_m']:.1f} m"
    return f"{p['tension_n'] / 1e6:.2f} MN at {p['position_m']:.1f} m, {p['t_s']:+.2f} s{tip}"


def _dist(d: dict | None) -> str:
    return "-" if not d else f"{d['median']:.2f} / {d['p90']:.2f} / {d['max']:.2f}"


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The tables of docs/mbl-exceedance.md."""
    run = run_line(result, COMMAND + f" --episodes {result['episodes']} --seed {result['seed']}")
    scene = table(["case", "fall step [ms]", "nodes", "touchdown [m/s]", "vertical chain peak (from the anchor)",
                   "mooring line peak (from the release unit)"],
                  [[c["case"], f"{c['step_ms']:.3g}", c["nodes"], f"{c['speed_m_s']:.2f}",
                    _at(c["peaks"].get("vertical_chain|fall")), _at(c["peaks"].get("mooring_line|fall"))]
                   for c in result["scene"]])
    sample_rows = []
    for name, s in result["summary"].items():
        lo, hi = (100 * x for x in s["wilson"])
        parts = [f"{k.replace('_', ' ').replace('|', ', ')} {v}" for k, v in sorted(s["by_line_phase"].items())]
        d = s["mbl_ratio"]
        sample_rows.append([name, f"{s['exceeded']} of {s['episodes']} ({100 * s['exceeded'] / s['episodes']:.0f} %, "
                            f"{lo:.0f}-{hi:.0f})", "; ".join(parts) or "-", _dist(d.get("vertical_chain|fall")),
                            _dist(d.get("mooring_line|fall")), _dist(d.get("mooring_line|pre-release")),
                            f"{s['speed_m_s_median']:.2f}", f"{s['cpu_s_median']:.2f}"])
    sample = table(["variant", "episodes over an MBL (95 % interval)", "peaks over the MBL (line, phase)",
                    "vertical chain, fall: peak/MBL median / p90 / max", "mooring line, fall",
                    "mooring line, pre-release", "touchdown median [m/s]", "CPU s/episode"], sample_rows)
    where_rows = [[w["seed"], f"{w['hs_m']:.2f}", f"{w['vessel_spacing_over_depth']:.2f}",
                   f"{w['mooring_line_length_over_depth']:.3f}", w["line"].replace("_", " "), w["phase"],
                   f"{w['position_m']:.1f}", f"{w['t_s']:+.2f}",
                   "-" if w["tip_height_m"] is None else f"{w['tip_height_m']:.1f}", f"**{w['mbl_ratio']:.2f}**"]
                  + [f"{w['refined'][v]:.2f}" for v in REFINED] for w in result["where"]]
    where = table(["seed", "Hs [m]", "spacing/h", "line/h", "line", "phase", "along the line [m]",
                   "from the release [s]", "tip above seabed [m]", "peak/MBL, env"] + list(REFINED.values()),
                  where_rows)
    hs = table(["Hs [m]"] + list(result["by_hs"]["variants"]),
               [[b] + [f"{k} of {n}" for k, n in counts] for b, counts in result["by_hs"]["bins"].items()])
    replay_rows = []
    for rp in result["replay"]:
        for r in rp["runs"]:
            replay_rows.append([f"seed {rp['seed']}, {rp['line'].replace('_', ' ')}, {rp['phase']}, segment at "
                                f"{rp['position_m']:.1f} m", r["substeps"], f"{r['step_ms']:.3g}",
                                f"{r['start_n'] / 1e6:.2f}", f"{r['end_n'] / 1e6:.2f}",
                                f"{r['start_strain'] * 100:+.3f}", f"{r['end_strain'] * 100:+.3f}",
                                f"{r['turn_strain'] * 100:+.3f} ({r['turn_n'] / 1e6:.2f} MN)"])
    replay = table(["step that first took the line over its MBL", "sub-steps", "sub-step [ms]",
                    "line peak at the start [MN]", "line peak at the end [MN]", "segment strain at the start [%]",
                    "at the end [%]", "of it from the last sub-step's turn [%] (x EA)"], replay_rows)
    lever_rows = []
    for lv in result["levers"]:
        lever_rows.append([lv["lever"], lv["chain"], f"{lv['speed_m_s']:.2f}",
                           _at(lv["peaks"].get("vertical_chain|fall")), _at(lv["peaks"].get("mooring_line|fall")),
                           f"{max(p['tension_n'] / lv['mbl_n'][k.split('|')[0]] for k, p in lv['peaks'].items()):.2f}"])
    levers = table(["lever (from spacing 0.3 h, line 1.04 h, 500 m, calm)", "chain", "touchdown [m/s]",
                    "vertical chain peak (from the anchor)", "mooring line peak (from the release unit)",
                    "largest peak/MBL"], lever_rows)
    return [(DOC, "mbl_exceedance:scene", run + "\n\n" + scene), (DOC, "mbl_exceedance:sample", run + "\n\n" + sample),
            (DOC, "mbl_exceedance:where", where), (DOC, "mbl_exceedance:hs", hs),
            (DOC, "mbl_exceedance:replay", replay), (DOC, "mbl_exceedance:levers", levers)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/mbl_exceedance.json``."""
    result = load_result("mbl_exceedance")
    return [] if result is None else docs_blocks(result)


def plot(result: dict, path: Path) -> None:
    """The vertical chain's largest tension in the fall of the worst env episode, per variant, and every episode's
    fall peak of the vertical chain against its MBL, per variant."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, (ax_t, ax_s) = plt.subplots(2, 1, figsize=(9, 8))
    series = result["series"]
    for k, (name, rows) in enumerate(series["runs"].items()):
        s = np.array(rows)
        ax_t.plot(s[:, 0], s[:, 1] / 1e6, lw=2.5 if k == 0 else 1.0, alpha=0.6 if k == 0 else 1.0, label=name)
    ax_t.axhline(series["mbl_n"] / 1e6, color="k", ls="--", lw=0.8, label="MBL")
    ax_t.set_xlabel("time since the release [s]")
    ax_t.set_ylabel("largest segment tension\nof the vertical chain [MN]")
    ax_t.set_title(f"Episode {series['seed']}: the env's fall and the same fall refined", fontsize=10)
    ax_t.legend(fontsize=8)
    names = list(result["summary"])
    rng = np.random.default_rng(0)
    for i, name in enumerate(names):
        rows = [r for r in result["rows"] if r["variant"] == name]
        for key, colour in (("vertical_chain|fall", "C0"), ("mooring_line|fall", "C2"),
                            ("mooring_line|pre-release", "C3")):
            y = _ratios(rows, key)
            ax_s.scatter(i + 0.25 * rng.uniform(-1, 1, len(y)), y, s=8, color=colour, alpha=0.6,
                         label=key.replace("_", " ").replace("|", ", ") if i == 0 else None)
    ax_s.axhline(1.0, color="k", ls="--", lw=0.8)
    ax_s.set_xticks(range(len(names)), names, rotation=25, ha="right", fontsize=8)
    ax_s.set_ylabel("peak / MBL")
    ax_s.set_title("Every crew episode's peaks, as the env runs it and refined", fontsize=10)
    ax_s.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    print(f"written {path}")


SCENARIO_KEYS = ("hs_m", "depth_m", "vessel_spacing_over_depth", "mooring_line_length_over_depth", "current_scale")


def compact_rows(rows: list[dict]) -> tuple[dict, list[dict]]:
    """The episode rows as the results keep them: each seed's scenario once (``SCENARIO_KEYS``, by seed) and per
    row the peaks that matter here (``KEPT_PEAKS``, and any other from half the MBL; the summaries hold all)."""
    scenarios = {str(r["seed"]): {k: r[k] for k in SCENARIO_KEYS} for r in rows}
    kept = [{**{k: v for k, v in r.items() if k not in SCENARIO_KEYS},
             "cpu_s": round(r["cpu_s"], 4), "speed_m_s": None if r["speed_m_s"] is None else round(r["speed_m_s"], 4),
             "peaks": {k: p for k, p in r["peaks"].items() if k in KEPT_PEAKS or p["mbl_ratio"] >= 0.5}}
            for r in rows]
    return scenarios, kept


def worst(rows: list[dict], phase: str, line: str | None = None) -> tuple[int, str, dict] | None:
    """(seed, line, peak) of the env variant's largest peak/MBL in ``phase`` (of ``line``, or of any line)."""
    best = None
    for r in rows:
        for key, p in r["peaks"].items():
            name, ph = key.split("|")
            if (r["variant"] == "env" and ph == phase and line in (None, name)
                    and (best is None or p["mbl_ratio"] > best[2]["mbl_ratio"])):
                best = (r["seed"], name, p)
    return best


def main(argv: list[str] | None = None) -> dict:
    """Run the four parts; write the JSON, the figure and the docs tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=80)
    parser.add_argument("--seed", type=int, default=5000, help="seed of the first scenario")
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs tables from the committed JSON")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return {}
    load_before = os.getloadavg()[0]
    scene = [{"case": name, **scene_drop(ov, f)} for name, ov, f in tqdm(SCENE_CASES, desc="scene")]
    levers = []
    for name, ov in tqdm(LEVERS, desc="levers"):
        for chain, res in (("1 m", {}), ("0.5 m", HALF_CHAIN)):
            cfg = load_scene("gjoa-500", {**LEVER_BASE, **ov, **res})
            sim = solve_statics(cfg, progress=False).simulator
            levers.append({"lever": name, "chain": chain, **fall_peaks(sim, cfg.simulation.max_fall_time_s)})
    policy = make_baseline("crew", PLAN_ENV)
    envs = {name: make_env(ov, keys, f) for name, ov, keys, f in SAMPLE_VARIANTS}
    rows = []
    for seed in tqdm(range(args.seed, args.seed + args.episodes), desc="crew episodes"):
        for name, env in envs.items():
            rows.append({"variant": name, **crew_episode(env, policy, seed)})
    summary = {name: summarize(rows, name) for name, *_ in SAMPLE_VARIANTS}
    by_seed = {(r["variant"], r["seed"]): r for r in rows}
    where = []
    for r in rows:
        if r["variant"] != "env":
            continue
        for key, p in r["peaks"].items():
            if p["mbl_ratio"] > 1.0:
                line, phase = key.split("|")
                where.append({"seed": r["seed"], "hs_m": r["hs_m"], "line": line, "phase": phase, **p,
                              **{k: r[k] for k in ("vessel_spacing_over_depth", "mooring_line_length_over_depth")},
                              "refined": {v: by_seed[(v, r["seed"])]["peaks"].get(key, {}).get("mbl_ratio", 0.0)
                                          for v in REFINED}})
    bins = {"< 1": (0.0, 1.0), "1-2": (1.0, 2.0), ">= 2": (2.0, 99.0)}
    hs_variants = ("env", "pre-release 0.05 s, explicit fall")
    by_hs = {"variants": hs_variants, "bins": {
        b: [(sum(1 for r in rows if r["variant"] == v and lo <= r["hs_m"] < hi and max(r["mbl_ratio"].values()) > 1),
             sum(1 for r in rows if r["variant"] == v and lo <= r["hs_m"] < hi)) for v in hs_variants]
        for b, (lo, hi) in bins.items()}}
    replay = []
    for phase in (FALL, PRE_RELEASE):
        w = worst(rows, phase)
        if w is None:
            continue
        seed, line, _ = w
        start, segment = crew_episode(envs["env"], policy, seed, keep_states=True)[1][f"{line}|{phase}"]
        replay.append({"seed": seed, "line": line, "phase": phase, **replay_step(start, line, segment)})
    w = worst(rows, FALL, "vertical_chain")
    series = {"seed": w[0], "mbl_n": float(envs["env"].unwrapped.core.mbl["vertical_chain"]),
              "runs": {v: crew_episode(envs[v], policy, w[0], series=True)["series"] for v in SERIES_VARIANTS}}
    result = {**run_record(load_before), "episodes": args.episodes, "seed": args.seed, "env": PLAN_ENV,
              "policy": "crew", "scene": scene, "levers": levers, "summary": summary, "where": where, "by_hs": by_hs,
              "replay": replay, "series": series, "rows": rows}
    result["scenarios"], result["rows"] = compact_rows(rows)
    write_results(RESULTS, result)
    plot(result, FIGURE)
    write_blocks(docs_blocks(result))
    for name, s in summary.items():
        print(f"{name}: {s['exceeded']} of {s['episodes']} over an MBL; {s['by_line_phase']}; {s['mbl_ratio']}")
    return result


if __name__ == "__main__":
    main()

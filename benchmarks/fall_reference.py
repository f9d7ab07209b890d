"""The env's fall and resolution choices in waves against the explicit reference fall, and what decides the
outcomes on which the integrators disagree.

Run from the repository root: ``python benchmarks/fall_reference.py [--episodes 72] [--calm] [--trace-seed 1002]``.
Writes ``benchmarks/results/fall_reference.json`` (``fall_reference_calm.json`` with ``--calm``), its tables in
``docs/fall-accuracy.md`` (``--docs-only``: only the tables, from the committed JSON) and the figure
``docs/fall-snap.png``.

Each episode draws its scenario from the default config (seeds 1000, 1001, ...; with waves unless ``--calm``) and
is driven by the seeded random controls of ``benchmarks/pre_release_step.py``. Cases:

* ``reference``: the ``fast`` preset's calm tight_line resolution throughout (1/0.5/50/100 m) with the fall
  integrated explicitly (symplectic Euler at 0.9 times its stability limit, about 0.17 ms;
  ``fidelity.discretization.fall_integrator: symplectic_euler``), the integrator of the validated ``default``
  fidelity;
* ``default``: what the env does (in waves: tight_line with its ``in_waves`` keys, a 1 m loop chain, throughout;
  the implicit fall at the model's 11.25 ms step);
* ``default, fall step growing 3x`` and ``2x``: the same with the fall's step grown where the lines move slowly,
  up to 3 and 2 times the model's step (``discretization.fall_step_growth_max``);
* ``default, fall at 2x its step``: the same with the implicit fall at twice the model's step (22.5 ms in waves);
* ``tight_line, 0.5 m loop``: the reference's resolution with the implicit fall (5.6 ms), the env's choice in
  waves before the ``in_waves`` keys;
* ``tight_line, 1 m loop``: the reference's resolution with the 1 m loop chain of its ``in_waves`` keys
  throughout and the implicit fall at its step (11.25 ms); in waves the same as ``default``;
* ``coarse throughout``: the coarse resolution (2/2/20/30 m) before and after the release, implicit;
* ``coarse, fine fall``: coarse before the release, remeshed onto the 0.5 m tight_line for the implicit fall;
* ``coarse, explicit fall``: coarse throughout with the explicit fall (on 2 m chain, about 0.7 ms).

Compared with the reference: touchdown speed and tilt per episode (absolute differences, and the signed mean of
the speed difference), over all episodes and split by where the reference's chain ends (see below), and how many
episodes land fast and vertical (``FAST_M_S`` or faster, under ``VERTICAL_DEG``). CPU per episode excludes the
reset (the equilibrium solve of a new scenario is cached by an untimed reset first).

The trace (``--trace-seed``) records, every 10 ms of the fall, the anchor's tilt, the tension of the vertical
chain's bottom segment (the one on the anchor) and how far the chain has fallen past the anchor's back end
(``Simulator.line_past_back_end_m``; also recorded at every touchdown: about 0 where the chain has landed on the
back end, positive where it has passed into the anchor, as it does without the line-anchor contact), on the 0.5 m
tight_line resolution: explicit (the reference), implicit at 5.6 ms and at 1.4 ms.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402
from fall_step import EXPLICIT_FALL, scale_fall_step  # noqa: E402
from pre_release_step import run_episode  # noqa: E402
from remesh_at_release import TIGHT, TIGHT_WAVES, make_case_env  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from agents.statistics import paired_bootstrap_interval  # noqa: E402
from moor_env.envs import anchor_release  # noqa: E402
from moor_env.envs import core as envcore  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "fall_reference.json"
FIGURE = ROOT / "docs" / "fall-snap.png"
FAST_M_S = 25.8  # the reference's clean landings reach 25.9-26.5 m/s on the default geometry
VERTICAL_DEG = 1.0
ON_BACK_END_M = 0.05  # a chain whose end is within this of the back end (or past it) has reached the anchor
INSIDE_M = 0.05  # past the back end by more than this: inside the anchor, beyond the contact's penetration
TRACE_INTERVAL_S = 0.01
DEFAULT_EPISODES = 72
# name, env overrides, pre-release resolution forced ({}: coarse; None: the env's), fall resolution (False: env's),
# fall step as a multiple of the fall model's step
LOOP_05M = "tight_line, 0.5 m loop"
LOOP_1M = "tight_line, 1 m loop"
GROWING_STEP = "default, fall step growing 3x"
CASES = (
    ("reference", EXPLICIT_FALL, TIGHT, TIGHT, 1.0),
    ("default", {}, None, False, 1.0),
    (GROWING_STEP, {"fidelity.discretization.fall_step_growth_max": 3.0}, None, False, 1.0),
    ("default, fall step growing 2x", {"fidelity.discretization.fall_step_growth_max": 2.0}, None, False, 1.0),
    ("default, fall at 2x its step", {}, None, False, 2.0),
    (LOOP_05M, {}, TIGHT, TIGHT, 1.0),
    (LOOP_1M, {}, TIGHT_WAVES, TIGHT_WAVES, 1.0),
    ("coarse throughout", {}, {}, None, 1.0),
    ("coarse, fine fall", {}, {}, TIGHT, 1.0),
    ("coarse, explicit fall", EXPLICIT_FALL, {}, None, 1.0),
)


def timed_episode(env, seed: int) -> dict:
    """:func:`run_episode` after an untimed reset of the same seed (which solves or loads the equilibrium), with
    ``Simulator.line_past_back_end_m`` of the vertical chain at the end (at touchdown)."""
    env.reset(seed=seed)
    cpu0 = time.process_time()
    row = run_episode(env, seed)
    row["cpu_s"] = time.process_time() - cpu0
    row["chain_past_back_end_m"], row["chain_off_axis_m"] = env.unwrapped.core.sim.line_past_back_end_m(
        "vertical_chain")
    return row


def summary(rows: list[dict], case: str, reference: str, seeds: set[int] | None = None) -> dict:
    """Differences to the reference over the episodes (of ``seeds``, default all) where both touched down."""
    by_seed = {r["seed"]: r for r in rows if r["case"] == reference}
    mine = [r for r in rows if r["case"] == case and (seeds is None or r["seed"] in seeds)]
    pairs = [(r, by_seed[r["seed"]]) for r in mine
             if r["speed_m_s"] is not None and by_seed[r["seed"]]["speed_m_s"] is not None]
    dv = np.array([r["speed_m_s"] - ref["speed_m_s"] for r, ref in pairs])
    dt = np.abs([r["tilt_deg"] - ref["tilt_deg"] for r, ref in pairs])
    return {"episodes": len(pairs), "failures": sum(r["status"] != "touchdown" for r in mine),
            "fast_and_vertical": sum(1 for r in mine if r["speed_m_s"] is not None and r["speed_m_s"] >= FAST_M_S
                                     and r["tilt_deg"] < VERTICAL_DEG),
            "cpu_s_median": float(np.median([r["cpu_s"] for r in mine])),
            "chain_past_back_end_at_touchdown": sum(1 for r in mine if r["chain_past_back_end_m"] > INSIDE_M),
            "chain_past_back_end_m_median": float(np.median([r["chain_past_back_end_m"] for r in mine])),
            "dspeed_m_s": {"median": float(np.median(np.abs(dv))), "p90": float(np.percentile(np.abs(dv), 90)),
                           "signed_mean": float(dv.mean())},
            "dtilt_deg": {"median": float(np.median(dt)), "p90": float(np.percentile(dt, 90))}}


def trace_fall(env, seed: int) -> dict:
    """One episode with the fall recorded every ``TRACE_INTERVAL_S``: time since the release [s], tilt [deg],
    tension of the segment on the anchor [N] and ``Simulator.line_past_back_end_m`` of the vertical chain [m, m]."""
    samples: list[tuple[float, ...]] = []
    plain = anchor_release.run_advance

    def recording(core_, adv, chunk_s=None, on_chunk=None):
        if adv.phase != envcore.PHASE_FALL:
            return plain(core_, adv, chunk_s, on_chunk)
        t0 = core_.sim.state.t

        def record():
            sim = core_.sim
            sim.evaluate_loads()
            chain = core_.lines["vertical_chain"]
            st = sim.state
            first = st.line_i[chain, L.LI_SEG_START]  # segments run bottom up: the first one hangs on the anchor
            samples.append((st.t - t0, sim.tilt_deg(), float(sim.work.seg_tension[first]),
                            *sim.line_past_back_end_m("vertical_chain")))

        return plain(core_, adv, TRACE_INTERVAL_S, record)

    anchor_release.run_advance = recording
    try:
        row = run_episode(env, seed)
    finally:
        anchor_release.run_advance = plain
    return {"speed_m_s": row["speed_m_s"], "tilt_deg": row["tilt_deg"], "samples": samples}


def plot_traces(traces: dict[str, dict], seed: int, path: Path) -> None:
    """Tilt and the anchor's chain tension against time since the release, one line per run."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, (ax_tilt, ax_t, ax_c) = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for k, (name, tr) in enumerate(traces.items()):
        s = np.array(tr["samples"])
        label = f"{name}: {tr['speed_m_s']:.2f} m/s, {tr['tilt_deg']:.2f} deg"
        style = {"lw": 4, "alpha": 0.4} if k == 0 else {"lw": 1.2}  # the reference wide, under the others
        ax_tilt.plot(s[:, 0], s[:, 1], label=label, **style)
        ax_t.plot(s[:, 0], s[:, 2] / 1e3, **style)
        line = ax_c.plot(s[:, 0], s[:, 3], **style)[0]
        ax_c.plot(s[:, 0], s[:, 4], ls=":", color=line.get_color(), **style)
    ax_tilt.set_ylabel("anchor tilt [deg]")
    ax_tilt.legend(fontsize=8)
    ax_t.set_ylabel("chain tension\non the anchor [kN]")
    ax_c.axhline(0.0, color="0.5", lw=0.8)
    ax_c.set_ylabel("chain past the back end [m]\nsolid: along the axis\ndotted: off the axis")
    ax_c.set_xlabel("time since the release [s]")
    fig.suptitle(f"Fall of episode {seed} (waves): the vertical chain catches up with the anchor's back end",
                 fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    print(f"written {path}")


DOC = DOCS / "fall-accuracy.md"
SPLITS = (("behind_anchor", "behind"), ("on_back_end", "on the back end"))  # (JSON key, label)


def docs_blocks(result: dict, stem: str) -> list[tuple[Path, str, str]]:
    """The tables of one run (``stem``: ``fall_reference`` or ``fall_reference_calm``) in docs/fall-accuracy.md:
    all episodes, and split by where the reference's chain ends."""
    rows = []
    for name, s in result["summary"].items():
        speed, tilt = s["dspeed_m_s"], s["dtilt_deg"]
        n = s["episodes"] + s["failures"]
        if name == "reference":
            diffs = ["-", "-", "-"]
        else:
            diffs = [f"{speed['median']:.3f} / {speed['p90']:.3f}", f"{speed['signed_mean']:+.3f}",
                     f"{tilt['median']:.2f} / {tilt['p90']:.2f}"]
        rows.append([name, *diffs, f"{s['fast_and_vertical']} of {n}",
                     f"{s['chain_past_back_end_at_touchdown']} of {n}", f"{s['cpu_s_median']:.3f}"])
    ref = result["summary"]["reference"]
    episodes = ref["episodes"] + ref["failures"]
    command = ("python benchmarks/fall_reference.py" + (" --calm" if stem.endswith("_calm") else "")
               + (f" --episodes {episodes}" if episodes != DEFAULT_EPISODES else ""))
    text = [run_line(result, command) + f" Reference: {result['reference']}; fast and vertical: "
            f"{result['fast_and_vertical']}.", "",
            table(["case", "speed diff median / p90 [m/s]", "signed mean [m/s]", "tilt diff median / p90 [deg]",
                   "fast and vertical", "chain inside", "CPU s/episode"], rows)]
    loop = LOOP_1M if LOOP_1M in result["summary"] else "default"
    for case, base in ((loop, LOOP_05M), (GROWING_STEP, "default")):
        paired = paired_cases(result["rows"], case, base)
        if paired is not None:
            text += ["", f"Paired on the episodes, `{case}` minus `{base}`: mean absolute speed difference to the "
                     f"reference {paired['mean']:+.3f} m/s [{paired['ci'][0]:+.3f}, {paired['ci'][1]:+.3f}] (paired "
                     f"bootstrap 95 %, {paired['episodes']} episodes)."]
    split_rows = []
    for part, label in SPLITS:
        split = result.get(f"summary_reference_chain_{part}")
        if split is None:
            continue
        for name, s in split.items():
            if name in ("seeds", "reference"):
                continue
            speed, tilt = s["dspeed_m_s"], s["dtilt_deg"]
            split_rows.append([f"{label} ({len(split['seeds'])})", name, f"{speed['median']:.3f} / {speed['p90']:.3f}",
                               f"{speed['signed_mean']:+.3f}", f"{tilt['median']:.2f} / {tilt['p90']:.2f}"])
    split_text = table(["reference chain ends (episodes)", "case", "speed diff median / p90 [m/s]",
                        "signed mean [m/s]", "tilt diff median / p90 [deg]"], split_rows)
    return [(DOC, stem, "\n".join(text)), (DOC, f"{stem}:split", split_text)]


def paired_cases(rows: list[dict], case: str, base: str) -> dict | None:
    """Mean over the episodes of |speed - reference| of ``case`` minus that of ``base``, with its paired
    bootstrap interval (None where a case is missing)."""
    by_case: dict[str, dict[int, float | None]] = {}
    for r in rows:
        by_case.setdefault(r["case"], {})[r["seed"]] = r["speed_m_s"]
    ref, a, b = by_case.get("reference"), by_case.get(case), by_case.get(base)
    if ref is None or a is None or b is None:
        return None
    seeds = [k for k, v in ref.items() if v is not None and a.get(k) is not None and b.get(k) is not None]
    da = np.abs([a[k] - ref[k] for k in seeds])
    db = np.abs([b[k] - ref[k] for k in seeds])
    low, high = paired_bootstrap_interval(da, db)
    return {"episodes": len(seeds), "mean": float(np.mean(da - db)), "ci": [low, high]}


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/fall_reference[_calm].json``."""
    out = []
    for stem in ("fall_reference", "fall_reference_calm"):
        result = load_result(stem)
        if result is not None:
            out += docs_blocks(result, stem)
    return out


def main(argv: list[str] | None = None) -> dict:
    """Run every case on every episode and the trace; write the JSON and the figure, print a table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=DEFAULT_EPISODES)
    parser.add_argument("--calm", action="store_true", help="no waves (Hs 0); writes fall_reference_calm.json")
    parser.add_argument("--trace-seed", type=int, default=1002, help="episode whose fall is traced (-1: none)")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/fall_reference*.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return {}
    load_before = os.getloadavg()[0]
    sea = {"scenario.sea_state_hs_m": 0.0} if args.calm else {}
    envs = {name: make_case_env({**sea, **ov}, pre, fall) for name, ov, pre, fall, _ in CASES}
    for name, *_, factor in CASES:
        if factor != 1.0:
            scale_fall_step(envs[name].unwrapped.core, factor)
    rows = []
    for seed in tqdm(range(1000, 1000 + args.episodes), desc="episodes"):
        for name, env in envs.items():
            rows.append({"case": name, **timed_episode(env, seed)})
    reference = CASES[0][0]
    result = {**run_record(load_before),
              "config": "anchor-release (default), scenarios drawn with seeds 1000.." + (", Hs 0" if args.calm else ""),
              "reference": "tight_line throughout, explicit fall (symplectic Euler, 0.9x its limit)",
              "fast_and_vertical": f"speed >= {FAST_M_S} m/s and tilt < {VERTICAL_DEG} deg",
              "summary": {name: summary(rows, name, reference) for name, *_ in CASES}}
    # the reference's falls split by where its chain ends: on the anchor's back end (or past it, see
    # Simulator.line_past_back_end_m) or behind it
    reached = {r["seed"] for r in rows if r["case"] == reference and r["chain_past_back_end_m"] > -ON_BACK_END_M}
    behind = {r["seed"] for r in rows if r["case"] == reference} - reached
    for part, seeds in (("reference_chain_on_back_end", reached), ("reference_chain_behind_anchor", behind)):
        if seeds:
            result[f"summary_{part}"] = {"seeds": sorted(seeds),
                                         **{name: summary(rows, name, reference, seeds) for name, *_ in CASES}}
    result["rows"] = rows
    if args.trace_seed >= 0:
        runs = {"reference (explicit fall)": make_case_env({**sea, **EXPLICIT_FALL}, TIGHT, TIGHT),
                "implicit, 5.6 ms": make_case_env(sea, TIGHT, TIGHT),
                "implicit, 1.4 ms": make_case_env(sea, TIGHT, TIGHT)}
        scale_fall_step(runs["implicit, 1.4 ms"].unwrapped.core, 0.25)
        traces = {name: trace_fall(env, args.trace_seed) for name, env in runs.items()}
        result["trace"] = {"seed": args.trace_seed, "interval_s": TRACE_INTERVAL_S, "runs": traces}
        if not args.calm:
            plot_traces(traces, args.trace_seed, FIGURE)
    write_results(RESULTS.with_name("fall_reference" + ("_calm" if args.calm else "") + ".json"), result)
    write_blocks(docs_blocks(result, "fall_reference" + ("_calm" if args.calm else "")))
    print("| case | episodes | failures | speed diff median / p90 [m/s] | signed mean [m/s] | tilt diff median / p90 "
          "[deg] | fast and vertical | chain past the back end at touchdown (episodes, median m) | CPU s/episode |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, s in result["summary"].items():
        speed, tilt = s["dspeed_m_s"], s["dtilt_deg"]
        print(f"| {name} | {s['episodes']} | {s['failures']} | {speed['median']:.3f} / {speed['p90']:.3f} | "
              f"{speed['signed_mean']:+.3f} | {tilt['median']:.2f} / {tilt['p90']:.2f} | "
              f"{s['fast_and_vertical']} of {args.episodes} | {s['chain_past_back_end_at_touchdown']}, "
              f"{s['chain_past_back_end_m_median']:+.2f} | {s['cpu_s_median']:.3f} |")
    for part, label in SPLITS:
        split = result.get(f"summary_reference_chain_{part}")
        if split is None:
            continue
        print(f"\nepisodes whose reference chain ends {label} ({len(split['seeds'])}): speed diff median / "
              "p90, signed mean [m/s]; tilt diff median / p90 [deg]")
        for name, *_ in CASES[1:]:
            speed, tilt = split[name]["dspeed_m_s"], split[name]["dtilt_deg"]
            print(f"| {name} | {speed['median']:.3f} / {speed['p90']:.3f} | {speed['signed_mean']:+.3f} | "
                  f"{tilt['median']:.2f} / {tilt['p90']:.2f} |")
    return result


if __name__ == "__main__":
    main()

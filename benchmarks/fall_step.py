"""Time-step convergence of the fall in AnchorRelease-v0 episodes (the scene's implicit step after the release).

Run from the repository root: ``python benchmarks/fall_step.py [--episodes 12] [--factors 2 1 0.5 0.25]
[--calm] [--explicit-reference]``. Writes ``benchmarks/results/fall_step.json`` (``fall_step_calm.json`` with
``--calm``; ``fall_step_explicit[_calm].json`` with ``--explicit-reference``) and its table in
``docs/fall-accuracy.md`` (``--docs-only``: only the tables, from the committed JSON).

Each episode draws its scenario from the default config (seeds 1000, 1001, ...; ``--calm``: Hs 0) and is driven
by the seeded random controls of ``benchmarks/pre_release_step.py`` (spacing and winch rates redrawn every 10 s,
release at a random step between 25 and 55). It is run with the fall's step at each factor of the scene's step
(the default config's fall: the ``fast`` preset's tight_line resolution, 5.6 ms calm, in waves with its
``in_waves`` keys, 1 m loop chain, 11.25 ms) and everything else unchanged, so
the pre-release phase and the state at the release are the same bit for bit; the finest factor is the
reference, or with ``--explicit-reference`` the same fall integrated by symplectic Euler at 0.9 times its
stability limit (``fidelity.discretization.fall_integrator: symplectic_euler``: the integrator of the validated
``default`` fidelity; about 0.17 ms on the 0.5 m loop chain, 0.34 ms on 1 m). Compared: touchdown speed and
tilt, over all episodes and over those whose reference chain ends behind the anchor's back end (the others' chain
has fallen into the anchor, which the model has no contact to stop: ``docs/fall-accuracy.md``). Two
neighbouring factors that agree with each other and not with the coarser ones show the step the fall converges
at.
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
from moor_env.envs import core as envcore  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "fall_step.json"
EXPLICIT = 0.0  # the factor key of the explicit reference (sorts first)
EXPLICIT_FALL = {"fidelity.discretization.fall_integrator": "symplectic_euler"}


def scale_fall_step(core: envcore.InstallationCore, factor: float) -> None:
    """Make ``core`` integrate every fall at ``factor`` times the scene's step (the pre-release is untouched)."""
    begin = core.begin_step

    def begin_step(action):
        adv = begin(action)
        if adv is not None and adv.phase == envcore.PHASE_FALL:
            adv = envcore.Advance(adv.t_end_s, adv.detect_touchdown, adv.phase, adv.dt_s * factor)
            core.pending = adv
        return adv

    core.begin_step = begin_step


def _summary(rows: list[dict], factor: float, seeds: set[int] | None = None) -> dict:
    mine = [r for r in rows if r["factor"] == factor and r.get("dspeed_m_s") is not None
            and (seeds is None or r["seed"] in seeds)]
    speed = np.abs([r["dspeed_m_s"] for r in mine])
    tilt = np.abs([r["dtilt_deg"] for r in mine])
    return {"episodes": len(mine), "fall_dt_s_median": float(np.median([r["fall_dt_s"] for r in mine])),
            "cpu_s_median": float(np.median([r["cpu_s"] for r in mine])),
            "dspeed_m_s": {"median": float(np.median(speed)), "p90": float(np.percentile(speed, 90)),
                           "max": float(speed.max())},
            "dtilt_deg": {"median": float(np.median(tilt)), "p90": float(np.percentile(tilt, 90)),
                          "max": float(tilt.max())}}


DOC = DOCS / "fall-accuracy.md"
STEMS = ("fall_step_explicit", "fall_step_explicit_calm", "fall_step", "fall_step_calm")


def _factor_rows(summary: dict) -> list[list]:
    return [[name, s["episodes"], f"{1e3 * s['fall_dt_s_median']:.2f}",
             f"{s['dspeed_m_s']['median']:.3f} / {s['dspeed_m_s']['p90']:.2f} / {s['dspeed_m_s']['max']:.2f}",
             f"{s['dtilt_deg']['median']:.2f} / {s['dtilt_deg']['p90']:.2f} / {s['dtilt_deg']['max']:.2f}",
             f"{s['cpu_s_median']:.3f}"] for name, s in summary.items()]


def docs_blocks(result: dict, stem: str) -> list[tuple[Path, str, str]]:
    """The table of one run (``stem``: its JSON's name, see ``STEMS``) in docs/fall-accuracy.md; with the split
    by where the reference's chain ends where the run has it."""
    flags = (" --explicit-reference --factors 2 1 0.5 0.25 0.125" if "_explicit" in stem else "") + \
        (" --calm" if stem.endswith("_calm") else "")
    header = ["fall step", "episodes", "step [ms]", "touchdown speed diff median / p90 / max [m/s]",
              "tilt diff median / p90 / max [deg]", "CPU s/episode (median)"]
    reference = result.get("reference", f"{result['reference_factor']:g}x the scene's step")
    lines = [run_line(result, "python benchmarks/fall_step.py" + flags) + f" Reference: {reference}.", "",
             table(header, _factor_rows(result["summary_abs_differences_to_reference"]))]
    behind = result.get("summary_reference_chain_behind_anchor")
    if behind:
        through = result.get("reference_chain_through_anchor_seeds", [])
        lines += ["", f"The episodes whose reference chain ends behind the anchor's back end "
                      f"({next(iter(behind.values()))['episodes']}; through it: {len(through)}):", "",
                  table(header, _factor_rows(behind))]
    return [(DOC, stem, "\n".join(lines))]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/fall_step*.json``."""
    out = []
    for stem in STEMS:
        result = load_result(stem)
        if result is not None:
            out += docs_blocks(result, stem)
    return out


def main(argv: list[str] | None = None) -> dict:
    """Run every factor on every episode, write the JSON and print a table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--factors", type=float, nargs="+", default=[2.0, 1.0, 0.5, 0.25],
                        help="fall step as multiples of the scene's step; the smallest is the reference")
    parser.add_argument("--calm", action="store_true", help="no waves (Hs 0); writes fall_step_calm.json")
    parser.add_argument("--explicit-reference", action="store_true",
                        help="the reference is the fall integrated explicitly (symplectic Euler at its stability "
                             "limit) instead of the finest factor; writes fall_step_explicit[_calm].json")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/fall_step*.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return {}
    load_before = os.getloadavg()[0]
    factors = sorted(set(args.factors))
    if args.explicit_reference:
        factors = [EXPLICIT] + factors
    overrides = {"scenario.sea_state_hs_m": 0.0} if args.calm else {}
    envs = {}
    for factor in factors:
        if factor == EXPLICIT:
            envs[factor] = gym.make(ENV_ID, overrides={**overrides, **EXPLICIT_FALL})
        else:
            envs[factor] = gym.make(ENV_ID, overrides=overrides)
            scale_fall_step(envs[factor].unwrapped.core, factor)
    rows = []
    for seed in tqdm(range(1000, 1000 + args.episodes), desc="episodes"):
        episode = []
        for factor in factors:  # the finest first: the reference
            row = {"factor": factor, **run_episode(envs[factor], seed)}
            # the env's simulator after the fall (remeshed at the release); the explicit one holds its fall step
            row["fall_dt_s"] = row["scene_dt_s"] * factor if factor != EXPLICIT else envs[factor].unwrapped.core.sim.dt
            ref = episode[0] if episode else row
            if row["speed_m_s"] is not None and ref["speed_m_s"] is not None:
                row.update(dspeed_m_s=row["speed_m_s"] - ref["speed_m_s"], dtilt_deg=row["tilt_deg"] - ref["tilt_deg"])
            episode.append(row)
        rows += episode
    summary = {f"{factor:g}x": _summary(rows, factor) for factor in factors[1:]}
    # split by where the reference's vertical chain ends at touchdown: past the anchor's back end (fallen into the
    # body, which the model has no contact to stop; docs/fall-accuracy.md) or behind it
    ref_rows = [r for r in rows if r["factor"] == factors[0] and r.get("chain_past_back_end_m") is not None]
    behind = {r["seed"] for r in ref_rows if r["chain_past_back_end_m"] <= 0.0}
    through = {r["seed"] for r in ref_rows} - behind
    name = "fall_step" + ("_explicit" if args.explicit_reference else "") + ("_calm" if args.calm else "")
    result = {**run_record(load_before),
              "config": "anchor-release (default), scenarios drawn with seeds 1000.." + (", Hs 0" if args.calm else ""),
              "reference": "explicit (symplectic Euler, 0.9x its limit)" if args.explicit_reference else
              f"{factors[0]:g}x the scene's step", "reference_factor": factors[0],
              "summary_abs_differences_to_reference": summary,
              "reference_chain_through_anchor_seeds": sorted(through),
              "summary_reference_chain_behind_anchor": {f"{factor:g}x": _summary(rows, factor, behind)
                                                        for factor in factors[1:]} if behind else None,
              "rows": rows}
    write_results(RESULTS.with_name(name + ".json"), result)
    write_blocks(docs_blocks(result, name))
    print(f"reference: {result['reference']}")
    print("| fall step | episodes | step [ms] | touchdown speed diff median / p90 / max [m/s] | "
          "tilt diff median / p90 / max [deg] | CPU s/episode (median) |")
    print("|---|---|---|---|---|---|")
    for name, s in summary.items():
        print(f"| {name} | {s['episodes']} | {1e3 * s['fall_dt_s_median']:.2f} | "
              f"{s['dspeed_m_s']['median']:.3f} / {s['dspeed_m_s']['p90']:.3f} / {s['dspeed_m_s']['max']:.3f} | "
              f"{s['dtilt_deg']['median']:.2f} / {s['dtilt_deg']['p90']:.2f} / {s['dtilt_deg']['max']:.2f} | "
              f"{s['cpu_s_median']:.3f} |")
    if behind:
        print(f"\nepisodes whose reference chain ends behind the anchor's back end ({len(behind)}; through it: "
              f"{len(through)})")
        for name, s in result["summary_reference_chain_behind_anchor"].items():
            print(f"| {name} | {s['episodes']} | {s['dspeed_m_s']['median']:.3f} / {s['dspeed_m_s']['p90']:.3f} / "
                  f"{s['dspeed_m_s']['max']:.3f} | {s['dtilt_deg']['median']:.2f} / {s['dtilt_deg']['p90']:.2f} / "
                  f"{s['dtilt_deg']['max']:.2f} |")
    return result


if __name__ == "__main__":
    main()

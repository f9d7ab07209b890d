"""Accuracy and cost of the envs' resolution choices around the release (``moor_env.remesh``, AnchorRelease-v0).

Run from the repository root: ``python benchmarks/remesh_at_release.py [--episodes 12]``. Writes
``benchmarks/results/remesh_at_release.json``, its tables in ``docs/remesh-at-release.md`` (``--docs-only``: only
the tables, from the committed JSON) and prints them.

A calm scenario whose loop starts slack runs the pre-release phase on the env's fidelity preset's own
resolution (``fast``: 2 m chain, 20 m fibre, 30 m wire) and, at the release, moves the state onto the preset's
``tight_line`` resolution (1 m vertical / 0.5 m loop chain, 50 m fibre, 100 m wire) where the geometry or the
line's motion of that moment needs it; in waves, or with a loop tight from the start, tight_line runs
throughout (in waves with its ``in_waves`` keys: a 1 m loop chain). Episodes draw their scenario from the
default config (seeds 2000, 2001, ...; the calm part with ``sea_state_hs_m`` 0) and are driven by seeded random
controls (the policy of ``benchmarks/pre_release_step.py``: spacing and winch rates redrawn every 10 s, release at
a random step 25-55). Cases, each part against its own reference:

* calm, ``fine throughout`` (the reference): tight_line from the equilibrium on;
* calm, ``default``: what the env does;
* calm, ``coarse, fine fall``: coarse before the release in every scenario, the fall always on tight_line
  (isolates what the coarse pre-release phase and the remesh change);
* calm, ``coarse throughout``: never fine (what the fit saves the tight cases from);
* waves, ``default`` (the reference): tight_line throughout, with its ``in_waves`` keys;
* waves, ``coarse, fine fall``: the calm design applied in waves (why it is not);
* each part's reference released one scene step (5.6 ms calm, 11.25 ms in waves) later: the outcome's own
  sensitivity to the release instant, against which the differences are to be read.

A third part (``waves check``) is why ``fast`` takes its tight_line resolution in any waves
(``waves_above_hs_m: 0``): the default geometry (500 m, spacing 0.1 h, line 1.08 h, no current; slack, coarse in
calm water) held for 59 s at Hs 0-1 m, six sea-state seeds each, falling on the coarse and on the tight_line
resolution (with its ``in_waves`` keys above Hs 0) from the same coarse pre-release state. A fourth
(``held calm``) sets that geometry's calm falls against the explicit reference fall: tight_line throughout with
the fall integrated explicitly, eight seeds; the episodes with random controls are set against it in
``benchmarks/fall_reference.py``.

Compared with the reference: touchdown speed and tilt; CPU per episode (reset without the static solve, which
is cached, the pre-release phase and the fall).
"""

from __future__ import annotations

import argparse
import math
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
from fall_step import EXPLICIT_FALL  # noqa: E402
from pre_release_step import ReferenceVariants, run_episode  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from moor_env.config import fidelity_presets, tight_line_keys  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "remesh_at_release.json"
ENV_ID = "moor_env/AnchorRelease-v0"
RULE = fidelity_presets()["fast"]["tight_line"]
TIGHT = tight_line_keys(RULE)  # calm water
TIGHT_WAVES = tight_line_keys(RULE, math.inf)  # in waves, with the rule's in_waves keys
FINE = {f"fidelity.discretization.{k}": v for k, v in TIGHT.items()}


CALM = {"scenario.sea_state_hs_m": 0.0}
# part, case name, env overrides, pre-release resolution forced (None: the env's), fall forced (False: the env's)
CASES = (
    ("calm", "fine throughout", {**CALM, **FINE}, None, False),
    ("calm", "default", CALM, None, False),
    ("calm", "coarse, fine fall", CALM, {}, TIGHT),
    ("calm", "coarse throughout", CALM, {}, None),
    ("calm", "reference released one step later", {**CALM, **FINE}, None, False),
    ("waves", "default", {}, None, False),
    ("waves", "coarse, fine fall", {}, {}, TIGHT_WAVES),
    ("waves", "reference released one step later", {}, None, False),
)


def make_case_env(overrides: dict, pre_release, fall, late: bool = False):
    """The env of a case (see the module docstring): ``pre_release`` / ``fall`` force the resolution keys of the
    factory's choice (None / False: the env's own; ``fall`` None: the preset's), ``late`` releases one scene step
    late."""
    env = gym.make(ENV_ID, overrides=overrides)
    factory = env.unwrapped.core.factory
    if pre_release is not None:
        factory.pre_release_resolution = lambda scenario: dict(pre_release)
    if fall is not False:
        factory.fall_resolution = lambda scene, spacing_m, length_m, speed_m_s: None if fall is None else dict(fall)
    if late:
        ReferenceVariants(env.unwrapped.core, delay_steps=1)
    return env


WAVES_SCENE = {"water_depth_m": 500.0, "vessel_spacing_over_depth": 0.1, "mooring_line_length_over_depth": 1.08,
               "current_scale": 0.0, "anchor_mass_scale": 1.0}
WAVES_HS_M = (0.0, 0.1, 0.25, 0.5, 1.0)


def waves_check(seeds: int = 6) -> list[dict]:
    """Coarse against tight_line fall after the same held, coarse pre-release phase, by Hs (see the docstring)."""
    env = gym.make(ENV_ID)
    factory = env.unwrapped.core.factory
    factory.pre_release_resolution = lambda scenario: {}
    hold = np.array([0.0, 0.0, -1.0], np.float32)
    out = []
    for hs in tqdm(WAVES_HS_M, desc="waves check"):
        for seed in range(seeds):
            row = {"hs_m": hs, "seed": seed}
            for name, keys in (("tight_line", tight_line_keys(RULE, hs)), ("coarse", None)):
                factory.fall_resolution = lambda scene, spacing_m, length_m, speed_m_s, keys=keys: keys
                env.reset(seed=seed, options={**WAVES_SCENE, "sea_state_hs_m": hs})
                for _ in range(59):
                    env.step(hold)
                info = env.step(np.array([0.0, 0.0, 1.0], np.float32))[4]
                row[name] = {"speed_m_s": info["touchdown"]["speed_m_s"], "tilt_deg": info["touchdown"]["tilt_deg"]}
            row["dspeed_m_s"] = row["coarse"]["speed_m_s"] - row["tight_line"]["speed_m_s"]
            row["dtilt_deg"] = row["coarse"]["tilt_deg"] - row["tight_line"]["tilt_deg"]
            out.append(row)
    return out


HELD_CALM_CASES = (  # name, env overrides, pre-release resolution forced, fall resolution forced (None: coarse)
    ("reference: tight_line throughout, explicit fall", EXPLICIT_FALL, TIGHT, TIGHT),
    ("tight_line throughout", {}, TIGHT, TIGHT),
    ("coarse, fine fall", {}, {}, TIGHT),
    ("coarse throughout (the env's choice)", {}, {}, None),
)


def held_calm_check(seeds: int = 8) -> list[dict]:
    """The default geometry held 59 s in calm water and released, on each resolution choice and against the
    explicit reference fall (touchdown speed and tilt per seed and case)."""
    hold = np.array([0.0, 0.0, -1.0], np.float32)
    out = []
    for name, overrides, pre, fall in tqdm(HELD_CALM_CASES, desc="held calm"):
        env = make_case_env({**CALM, **overrides}, pre, fall)
        for seed in range(seeds):
            env.reset(seed=seed, options={**WAVES_SCENE, "sea_state_hs_m": 0.0})
            for _ in range(59):
                env.step(hold)
            td = env.step(np.array([0.0, 0.0, 1.0], np.float32))[4]["touchdown"]
            out.append({"case": name, "seed": seed, "speed_m_s": td["speed_m_s"], "tilt_deg": td["tilt_deg"]})
    return out


def _held_calm_table(rows: list[dict]) -> str:
    """Each case of :func:`held_calm_check` against its reference, seed by seed."""
    ref = {r["seed"]: r for r in rows if r["case"] == HELD_CALM_CASES[0][0]}
    lines = []
    for name, *_ in HELD_CALM_CASES:
        mine = [r for r in rows if r["case"] == name]
        if name == HELD_CALM_CASES[0][0]:
            speeds = [r["speed_m_s"] for r in mine]
            lines.append([name, len(mine), f"{min(speeds):.2f}-{max(speeds):.2f} m/s", "-", "-"])
            continue
        dv = np.array([r["speed_m_s"] - ref[r["seed"]]["speed_m_s"] for r in mine])
        dt = np.abs([r["tilt_deg"] - ref[r["seed"]]["tilt_deg"] for r in mine])
        lines.append([name, len(mine), f"{np.median(np.abs(dv)):.3f} / {np.abs(dv).max():.3f}", f"{dv.mean():+.3f}",
                      f"{np.median(dt):.2f} / {dt.max():.2f}"])
    return table(["case", "seeds", "touchdown speed diff median / max [m/s] (reference: its speeds)",
                  "signed mean [m/s]", "tilt diff median / max [deg]"], lines)


def _summary(rows: list[dict]) -> dict:
    out = {"episodes": len(rows), "cpu_s_median": float(np.median([x["cpu_s"] for x in rows])),
           "tight_falls": int(sum(x["fall_resolution"] == "tight_line" for x in rows)),
           # episodes without a touchdown are left out of the differences: count them so that none is hidden
           "failures": int(sum(x["status"] != "touchdown" for x in rows))}
    for key in ("dspeed_m_s", "dtilt_deg"):
        v = np.abs([x[key] for x in rows if x.get(key) is not None])
        if v.size:
            out[key] = {"median": float(np.median(v)), "p90": float(np.percentile(v, 90)), "max": float(v.max())}
    return out


DOC = DOCS / "remesh-at-release.md"
COMMAND = "python benchmarks/remesh_at_release.py"


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The two tables of one run (docs/remesh-at-release.md): the cases, and the waves check."""
    rows = []
    for label, s in result["summary_abs_differences_to_each_parts_reference"].items():
        head = [label, f"{s['tight_falls']}/{s['episodes']}", s["failures"]]
        if label in ("calm: fine throughout", "waves: default"):
            rows.append(head + ["reference", "reference", f"{s['cpu_s_median']:.3f}"])
            continue
        d, t = s["dspeed_m_s"], s["dtilt_deg"]
        rows.append(head + [f"{d['median']:.3f} / {d['p90']:.3f} / {d['max']:.3f}",
                            f"{t['median']:.2f} / {t['p90']:.2f} / {t['max']:.2f}", f"{s['cpu_s_median']:.3f}"])
    cases = "\n".join([run_line(result, COMMAND), "", table(
        ["case", "falls on tight_line", "failures", "touchdown speed diff median / p90 / max [m/s]",
         "tilt diff median / p90 / max [deg]", "CPU s/episode (median)"], rows)])
    waves = result["waves_check"]
    hs_values = sorted({r["hs_m"] for r in waves})
    check = []
    for hs in hs_values:
        d = np.abs([r["dspeed_m_s"] for r in waves if r["hs_m"] == hs])
        t = np.abs([r["dtilt_deg"] for r in waves if r["hs_m"] == hs])
        check.append([f"{hs:g}", d.size, f"{np.median(d):.3f} / {d.max():.3f}", f"{np.median(t):.2f} / {t.max():.2f}"])
    check_text = table(["Hs [m]", "seeds", "touchdown speed diff, median abs / max abs [m/s]",
                        "tilt diff, median abs / max abs [deg]"], check)
    blocks = [(DOC, "remesh_at_release", cases), (DOC, "remesh_at_release:waves_check", check_text)]
    if "held_calm" in result:
        blocks.append((DOC, "remesh_at_release:held_calm", _held_calm_table(result["held_calm"])))
    return blocks


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/remesh_at_release.json``."""
    return docs_blocks(load_result("remesh_at_release"))


def main(argv: list[str] | None = None) -> dict:
    """Run every case on every episode, write the JSON and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/remesh_at_release.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return load_result("remesh_at_release")
    load_before = os.getloadavg()[0]
    envs = {(part, name): make_case_env(ov, pre, fall, name.startswith("reference"))
            for part, name, ov, pre, fall in CASES}
    rows = []
    for seed in tqdm(range(2000, 2000 + args.episodes), desc="episodes"):
        ref: dict[str, dict] = {}
        for part, name, *_ in CASES:
            env = envs[part, name]
            env.reset(seed=seed)  # solves (or loads) the equilibrium outside the timed episode
            row = {"part": part, "case": name, **run_episode(env, seed)}
            ref.setdefault(part, row)
            if row["speed_m_s"] is not None and ref[part]["speed_m_s"] is not None:
                row.update(dspeed_m_s=row["speed_m_s"] - ref[part]["speed_m_s"],
                           dtilt_deg=row["tilt_deg"] - ref[part]["tilt_deg"])
            rows.append(row)
    waves = waves_check()
    held = held_calm_check()
    summary = {f"{part}: {name}": _summary([r for r in rows if r["part"] == part and r["case"] == name])
               for part, name, *_ in CASES}
    result = {
        **run_record(load_before),
        "config": "anchor-release (default), scenarios drawn with seeds 2000..; calm part with Hs 0",
        "summary_abs_differences_to_each_parts_reference": summary,
        "rows": rows,
        "waves_check": waves,
        "held_calm": held,
    }
    write_results(RESULTS, result)
    write_blocks(docs_blocks(result))
    print("| case | falls on tight_line | failures | touchdown speed diff median / p90 / max [m/s] | "
          "tilt diff median / p90 / max [deg] | CPU s/episode (median) |")
    print("|---|---|---|---|---|---|")
    for label, s in summary.items():
        tight = f"{s['tight_falls']}/{s['episodes']} | {s['failures']}"
        if label in ("calm: fine throughout", "waves: default"):
            print(f"| {label} | {tight} | reference | reference | {s['cpu_s_median']:.3f} |")
            continue
        d, t = s["dspeed_m_s"], s["dtilt_deg"]
        print(f"| {label} | {tight} | {d['median']:.3f} / {d['p90']:.3f} / {d['max']:.3f} | "
              f"{t['median']:.2f} / {t['p90']:.2f} / {t['max']:.2f} | {s['cpu_s_median']:.3f} |")
    print("\nwaves check: coarse minus tight_line fall, default geometry held 59 s (6 seeds per Hs)")
    print("| Hs [m] | touchdown speed diff, median abs / max abs [m/s] | tilt diff, median abs / max abs [deg] |")
    print("|---|---|---|")
    for hs in WAVES_HS_M:
        d = np.abs([r["dspeed_m_s"] for r in waves if r["hs_m"] == hs])
        t = np.abs([r["dtilt_deg"] for r in waves if r["hs_m"] == hs])
        print(f"| {hs:g} | {np.median(d):.3f} / {d.max():.3f} | {np.median(t):.2f} / {t.max():.2f} |")
    return result


if __name__ == "__main__":
    main()

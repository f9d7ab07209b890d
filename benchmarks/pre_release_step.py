"""Accuracy of the coarse pre-release step (``control.pre_release_dt_s``, ``pre_release_dt_calm_s`` without waves) of
AnchorRelease-v0.

Run from the repository root: ``python benchmarks/pre_release_step.py [--calm] [--episodes 12] [--steps 0.1 0.2]``.
Writes ``benchmarks/results/pre_release_step.json`` (``pre_release_step_calm.json`` with ``--calm``) and its table in
``docs/pre-release-step.md`` (``--docs-only``: only the tables, from the committed JSON).

Each episode draws its scenario from the default config (``configs/envs/anchor-release.yaml``, seeds 1000, 1001,
...) and is driven by seeded random controls (spacing and winch rates redrawn every 10 s, release at a random
step between 25 and 55). It is run with the pre-release phase at the scene's own step (the reference) and at
each coarse step; the fall always runs at the scene's step. Compared with the reference: touchdown speed and
tilt, and the anchor's vertical velocity and height at the release. Two runs give the reference's own
uncertainty: the release delayed by one scene step, and the pre-release phase at half the scene's step (a
refinement; if it moves the outcome, the reference is not converged at that level either).
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

import gymnasium as gym  # noqa: E402
from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from moor_env.envs import core as envcore  # noqa: E402
from moor_env.envs.resolution import even_step_s  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "pre_release_step.json"
ENV_ID = "moor_env/AnchorRelease-v0"


class ReferenceVariants:
    """The reference's perturbations, applied to one core: release ``delay_steps`` scene steps late, or the
    pre-release phase at ``step_factor`` times the scene's step."""

    def __init__(self, core: envcore.InstallationCore, delay_steps: int = 0, step_factor: float = 1.0) -> None:
        self.core = core
        self.delay_steps = delay_steps
        self.step_factor = step_factor
        self._begin = core.begin_step
        self._pre_release = core._pre_release
        core.begin_step = self.begin_step
        if step_factor != 1.0:
            core._pre_release = self.pre_release

    def pre_release(self, t_end_s: float, phase: str) -> envcore.Advance:
        sim = self.core.sim
        return envcore.Advance(t_end_s, False, phase, even_step_s(t_end_s - sim.state.t, self.step_factor * sim.dt))

    def begin_step(self, action):
        core = self.core
        if action[2] > 0 and self.delay_steps:
            sim = core.sim
            sim.set_vessel_motion(sim.state.t, 1.0, np.zeros(2), ramp_s=core.ramp_s)
            envcore.run_advance(core, self.pre_release(sim.state.t + self.delay_steps * sim.dt, "control"))
        return self._begin(action)


def run_episode(env, seed: int) -> dict:
    """One episode with seeded random controls; the release state and the touchdown."""
    core = env.unwrapped.core
    rng = np.random.default_rng(seed)
    release_step = int(rng.integers(25, 56))
    rates = rng.uniform(-1.0, 1.0, 2)
    cpu0 = time.process_time()
    env.reset(seed=seed)
    release = {}
    tension_over_mbl = 0.0
    for k in range(60):
        if k % 10 == 0:
            rates = rng.uniform(-1.0, 1.0, 2)
        if k == release_step:
            b = core.sim.state.body_state
            release = {"vz_m_s": float(b[L.BS_VEL + 2]), "z_m": float(b[L.BS_POS + 2]), "tilt_deg": core.sim.tilt_deg()}
        _, _, terminated, truncated, info = env.step(np.array([rates[0], rates[1], 1.0 if k >= release_step else -1.0],
                                                              np.float32))
        if terminated or truncated:
            break
        if k < release_step:
            tension_over_mbl = largest_tension_over_mbl(core)
    td = info.get("touchdown", {})
    return {"seed": seed, "status": info["sim_status"], "cpu_s": time.process_time() - cpu0,
            "speed_m_s": td.get("speed_m_s"), "tilt_deg": td.get("tilt_deg"),
            "chain_past_back_end_m": td.get("chain_past_back_end_m"), "release": release,
            "scene_dt_s": core.sim.dt, "fallbacks": core.fallbacks, "scenario": core.scenario,
            "fall_resolution": info.get("fall_resolution"), "pre_release_tension_over_mbl": tension_over_mbl}


def largest_tension_over_mbl(core) -> float:
    """The largest running maximum tension of a line so far (what the env's limit check reads) over the line's
    minimum breaking load."""
    line_f = core.sim.state.line_f
    return max(line_f[info.index, L.LF_MAX_TENSION] / core.mbl[name] for name, info in core.sim.model.lines.items())


def _summary(rows: list[dict], case: str) -> dict:
    """Differences over the episodes where both the case and the reference touched down; ``failures``: episodes
    of the case that did not (a blow-up the fallback could not undo), counted apart so that none is hidden."""
    mine = [x for x in rows if x["case"] == case]
    r = [x for x in mine if x.get("dspeed_m_s") is not None]
    out = {"episodes": len(r), "failures": sum(x["status"] != "touchdown" for x in mine),
           "failed_seeds": [x["seed"] for x in mine if x["status"] != "touchdown"],
           "fallbacks": int(sum(x["fallbacks"] for x in mine)),
           "cpu_s_median": float(np.median([x["cpu_s"] for x in r]))}
    for key in ("dspeed_m_s", "dtilt_deg", "release_dvz_m_s", "release_dz_m"):
        v = np.abs([x[key] for x in r])
        out[key] = {"median": float(np.median(v)), "max": float(v.max())}
    return out


DOC = DOCS / "pre-release-step.md"


def docs_blocks(result: dict, stem: str) -> list[tuple[Path, str, str]]:
    """The table of one run (``stem``: its JSON's name, ``pre_release_step`` or ``pre_release_step_calm``) in
    docs/pre-release-step.md."""
    rows = []
    for name, s in result["summary_abs_differences_to_reference"].items():
        rows.append([name, s["episodes"], s["failures"],
                     f"{s['dspeed_m_s']['median']:.3f} / {s['dspeed_m_s']['max']:.2f}",
                     f"{s['dtilt_deg']['median']:.2f} / {s['dtilt_deg']['max']:.2f}",
                     f"{s['release_dvz_m_s']['median']:.3f} / {s['release_dvz_m_s']['max']:.3f}", s["fallbacks"],
                     f"{s['cpu_s_median']:.3f}"])
    command = "python benchmarks/pre_release_step.py" + (" --calm" if stem.endswith("_calm") else "")
    text = "\n".join([run_line(result, command), "", table(
        ["case", "compared", "failures", "touchdown speed diff median / max [m/s]", "tilt diff median / max [deg]",
         "anchor heave velocity diff at release median / max [m/s]", "fallbacks", "CPU s/episode (median)"], rows)])
    return [(DOC, stem, text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/pre_release_step[_calm].json``."""
    out = []
    for stem in ("pre_release_step", "pre_release_step_calm"):
        result = load_result(stem)
        if result is not None:
            out += docs_blocks(result, stem)
    return out


def main(argv: list[str] | None = None) -> dict:
    """Run every case on every episode, write the JSON and print a table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--steps", type=float, nargs="+", default=None,
                        help="pre-release steps [s] (default 0.1 0.2 0.25 0.5; with --calm 0.1 0.25 0.5)")
    parser.add_argument("--calm", action="store_true",
                        help="no waves (Hs 0 in every scenario); writes pre_release_step_calm.json")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/pre_release_step*.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return {}
    if args.steps is None:
        args.steps = [0.1, 0.25, 0.5] if args.calm else [0.1, 0.2, 0.25, 0.5]
    sea = {"scenario.sea_state_hs_m": 0.0} if args.calm else {}
    results = RESULTS.with_name("pre_release_step_calm.json") if args.calm else RESULTS
    load_before = os.getloadavg()[0]
    cases = [("reference", None, 0, 1.0), ("release one step later", None, 1, 1.0), ("half step", None, 0, 0.5)]
    cases += [(f"pre_release_dt_s={dt:g}", dt, 0, 1.0) for dt in args.steps]
    envs = {}
    rows = []
    for seed in tqdm(range(1000, 1000 + args.episodes), desc="episodes"):
        ref = None
        for name, dt, delay, factor in cases:
            if name not in envs:
                # both keys: the calm one would otherwise take over wherever Hs is 0
                envs[name] = gym.make(ENV_ID, overrides={"control.pre_release_dt_s": dt,
                                                         "control.pre_release_dt_calm_s": dt, **sea})
                ReferenceVariants(envs[name].unwrapped.core, delay, factor)
            row = {"case": name, **run_episode(envs[name], seed)}
            if ref is None:
                ref = row
            if row["speed_m_s"] is not None and ref["speed_m_s"] is not None:
                row.update(dspeed_m_s=row["speed_m_s"] - ref["speed_m_s"], dtilt_deg=row["tilt_deg"] - ref["tilt_deg"],
                           release_dvz_m_s=row["release"]["vz_m_s"] - ref["release"]["vz_m_s"],
                           release_dz_m=row["release"]["z_m"] - ref["release"]["z_m"])
            rows.append(row)
    summary = {name: _summary(rows, name) for name, *_ in cases[1:]}
    result = {
        **run_record(load_before),
        "config": "anchor-release (default), scenarios drawn with seeds 1000.." + (", Hs 0" if args.calm else ""),
        "summary_abs_differences_to_reference": summary,
        "rows": rows,
    }
    write_results(results, result)
    write_blocks(docs_blocks(result, results.stem))
    print("| case | compared | failures | touchdown speed diff median / max [m/s] | tilt diff median / max [deg] | "
          "release vz diff median / max [m/s] | fallbacks | CPU s/episode (median) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, s in summary.items():
        print(f"| {name} | {s['episodes']} | {s['failures']} | "
              f"{s['dspeed_m_s']['median']:.3f} / {s['dspeed_m_s']['max']:.3f} | "
              f"{s['dtilt_deg']['median']:.2f} / {s['dtilt_deg']['max']:.2f} | "
              f"{s['release_dvz_m_s']['median']:.3f} / {s['release_dvz_m_s']['max']:.3f} | {s['fallbacks']} | "
              f"{s['cpu_s_median']:.3f} |")
    return result


if __name__ == "__main__":
    main()

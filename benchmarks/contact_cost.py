"""Benchmark: the line-anchor contact's cost per step and what it changes at touchdown.

Run from the repository root: ``python benchmarks/contact_cost.py`` (``--docs-only``: the table from the committed
JSON). For each scene and integrator it runs the fall with the contact off and on (``discretization.
line_anchor_contact``), best wall time per step of ``REPEATS`` runs after a warm-up, and records the touchdown
speed, the chain resting on the anchor and how far the chain passed the back end. Writes
``benchmarks/results/contact_cost.json`` and its table in ``docs/fall-accuracy.md``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.simulation import run_drop  # noqa: E402

CASES = [("vertical-chain", "symplectic_euler"), ("vertical-chain", "implicit_euler"),
         ("gjoa-500", "symplectic_euler"), ("gjoa-500", "implicit_euler")]
REPEATS = 3
COMMAND = "python benchmarks/contact_cost.py"
DOC = DOCS / "fall-accuracy.md"


def _fall(scene: str, integrator: str, contact: str) -> dict:
    """Best of ``REPEATS`` falls from the scene's equilibrium (statics once)."""
    static = solve_statics(load_scene(scene, {"integrator": integrator,
                                              "discretization.line_anchor_contact": contact}), progress=False)
    saved = static.simulator.state.copy()
    best = None
    for _ in range(REPEATS + 1):  # the first run compiles
        static.simulator.state = saved.copy()
        result = run_drop(static.simulator, history=False)
        per_step = result.wall_dynamic_s / result.n_steps
        if best is None or per_step < best["us_per_step"] * 1e-6:
            best = {"us_per_step": 1e6 * per_step, "touchdown_speed_m_s": result.touchdown_speed_m_s,
                    "tilt_deg": result.tilt_deg, "chain_past_back_end_m": result.chain_past_back_end_m,
                    "chain_on_anchor_m": result.chain_on_anchor_m, "contact_peak_force_n": result.contact_peak_force_n,
                    "contact_peak_depth_m": result.contact_peak_depth_m, "n_steps": result.n_steps,
                    "dt_s": result.dt_s}
    return best


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The table of one run."""
    rows = []
    for case in out["cases"]:
        off, on = case["off"], case["on"]
        rows.append([case["scene"], case["integrator"], f"{off['touchdown_speed_m_s']:.3f}",
                     f"{on['touchdown_speed_m_s']:.3f}", f"{off['chain_past_back_end_m']:+.2f}",
                     f"{on['chain_past_back_end_m']:+.2f}", f"{on['chain_on_anchor_m']:.1f}",
                     f"{1e3 * on['contact_peak_depth_m']:.1f}", f"{on['contact_peak_force_n'] / 1e6:.2f}",
                     f"{off['us_per_step']:.1f}", f"{on['us_per_step']:.1f}",
                     f"{100 * (on['us_per_step'] / off['us_per_step'] - 1):+.0f} %"])
    text = "\n".join([run_line(out, COMMAND), "", table(
        ["scene", "integrator", "touchdown [m/s] without contact", "with", "chain past back end [m] without",
         "with", "chain on anchor [m]", "deepest node [mm]", "peak contact force [MN]", "us/step without", "with",
         "cost"], rows)])
    return [(DOC, "contact_cost", text)]


def main() -> None:
    if "--docs-only" in sys.argv:
        write_blocks(docs_blocks(load_result("contact_cost")))
        return
    load = os.getloadavg()[0]
    cases = [{"scene": scene, "integrator": integrator, "off": _fall(scene, integrator, "off"),
              "on": _fall(scene, integrator, "on")} for scene, integrator in CASES]
    out = {**run_record(load), "cases": cases}
    write_results(RESULTS / "contact_cost.json", out)
    write_blocks(docs_blocks(out))


if __name__ == "__main__":
    main()

"""Benchmark: the line-anchor contact's cost per step and what it changes at touchdown.

Run from the repository root: ``python benchmarks/contact_cost.py`` (``--docs-only``: the table from the committed
JSON). For each scene and integrator it runs the fall with the contact off and on
(``discretization.line_anchor_contact``), the least CPU time per step of interleaved runs after a warm-up and the
median ratio over the pairs of runs (process time: the machine may be shared), and records the touchdown speed, the
chain resting on the anchor and how far the chain passed the back end; for the implicit fall also the linear solves
per step and how many of them the contact's set asked for. Writes ``benchmarks/results/contact_cost.json`` and its
table in ``docs/fall-accuracy.md``.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.physics import implicit as imp  # noqa: E402
from moor_env.physics import implicit_contact as ic  # noqa: E402
from moor_env.physics import implicit_contact_set as ics  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402
from moor_env.physics.implicit_active_set import update_active_set  # noqa: E402
from moor_env.physics.implicit_assembly import assemble  # noqa: E402
from moor_env.simulation import run_drop  # noqa: E402

CASES = [("vertical-chain", "symplectic_euler"), ("vertical-chain", "implicit_euler"),
         ("gjoa-500", "symplectic_euler"), ("gjoa-500", "implicit_euler")]
REPEATS = 40  # interleaved falls each way at least, and ...
MIN_SECONDS = 15.0  # ... at least this much CPU time per case, up to MAX_REPEATS (the cheap falls are noisiest)
MAX_REPEATS = 400
COMMAND = "python benchmarks/contact_cost.py"
DOC = DOCS / "fall-accuracy.md"


def prepared(scene: str, integrator: str, contact: str):
    """The scene's simulator at equilibrium and its state (statics once)."""
    static = solve_statics(load_scene(scene, {"integrator": integrator,
                                              "discretization.line_anchor_contact": contact}), progress=False)
    return static.simulator, static.simulator.state.copy()


def _fall(sim, saved) -> tuple[float, dict]:
    """One fall from the saved state: CPU seconds per step (process time: the machine is shared) and the result."""
    sim.state = saved.copy()
    builds0 = sim.work.near_skin[L.NEAR_BUILDS]
    cpu0 = time.process_time()
    result = run_drop(sim, history=False)
    per_step = (time.process_time() - cpu0) / result.n_steps
    return per_step, {"touchdown_speed_m_s": result.touchdown_speed_m_s, "tilt_deg": result.tilt_deg,
                      "chain_past_back_end_m": result.chain_past_back_end_m,
                      "chain_on_anchor_m": result.chain_on_anchor_m,
                      "contact_peak_force_n": result.contact_peak_force_n,
                      "contact_peak_depth_m": result.contact_peak_depth_m, "n_steps": result.n_steps,
                      "dt_s": result.dt_s, "list_builds": int(sim.work.near_skin[L.NEAR_BUILDS] - builds0)}


def solves_per_step(sim, saved) -> dict:
    """Implicit fall only: linear solves per step and how many of them the contact set asked for, replaying each
    step's solve loop (``implicit.implicit_euler_update``) from Python before the kernel takes the step (not
    timed)."""
    sim.state = saved.copy()
    sim.release()
    solves = contact_solves = steps = 0
    while True:
        sim.evaluate_loads()
        model, state = sim.records()
        body_node = int(np.flatnonzero(state.node_i[:, L.NI_KIND] == L.NODE_BODY)[0])
        tree, orow = state.pos0.view(np.int64), state.vel0.view(np.int64)
        nq = imp.prepare(False, body_node, state, tree, orow)
        contact = model.contact_f[L.CF_ON] != 0.0
        if contact:
            ics.init_contact_set(sim.dt, model, state)
        for it in range(imp.MAX_ACTIVE_SET_SOLVES):
            solves += 1
            assemble(sim.dt, it == 0, body_node, model, state, orow)
            if contact:
                ic.assemble_contact(sim.dt, model, state)
            imp.eliminate(nq, state, tree, orow)
            imp.couple_body(sim.dt, body_node, model, state)
            imp.back_substitute(nq, state, tree, orow)
            changed = update_active_set(sim.dt, model, state, orow)
            changed_contact = ics.update_contact_set(sim.dt, model, state) if contact else 0
            contact_solves += changed_contact > 0 and it + 1 < imp.MAX_ACTIVE_SET_SOLVES
            if changed + changed_contact == 0:
                break
        steps += 1
        status, _ = sim.advance_to(sim.state.t + sim.dt, detect_touchdown=True)
        if status == L.STATUS_TOUCHDOWN:
            break
    return {"steps": steps, "solves_per_step": solves / steps, "contact_solves_per_step": contact_solves / steps}


def _case(scene: str, integrator: str) -> dict:
    """Contact off and on, interleaved (the machine's load drifts) after a warm-up each, ``REPEATS`` falls each
    or more (``MIN_SECONDS``); the fastest CPU time per step of each, and the median over the pairs of falls of
    the ratio on / off (a second estimate of the cost, less sensitive to one lucky fall)."""
    runs = {contact: prepared(scene, integrator, contact) for contact in ("off", "on")}
    out = {}
    for contact, (sim, saved) in runs.items():
        _, out[contact] = _fall(sim, saved)  # compiles
        out[contact]["us_per_step"] = math.inf
    ratios = []
    cpu0 = time.process_time()
    while len(ratios) < MAX_REPEATS and (len(ratios) < REPEATS or time.process_time() - cpu0 < MIN_SECONDS):
        pair = {}
        for contact, (sim, saved) in runs.items():
            pair[contact], _ = _fall(sim, saved)
            out[contact]["us_per_step"] = min(out[contact]["us_per_step"], 1e6 * pair[contact])
        ratios.append(pair["on"] / pair["off"])
    out["on"]["pairs"] = len(ratios)
    out["on"]["median_pair_ratio"] = float(np.median(ratios))
    if integrator == "implicit_euler":
        for contact, (sim, saved) in runs.items():
            out[contact].update(solves_per_step(sim, saved))
    return {"scene": scene, "integrator": integrator, **out}


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
                     f"{100 * (on['us_per_step'] / off['us_per_step'] - 1):+.0f} % "
                     f"({100 * (on['median_pair_ratio'] - 1):+.0f} %, {on['pairs']})",
                     f"{on['list_builds']} / {on['n_steps']}",
                     f"{off['solves_per_step']:.2f} / {on['solves_per_step']:.2f} "
                     f"({on['contact_solves_per_step']:.2f})" if "solves_per_step" in on else "-"])
    text = "\n".join([run_line(out, COMMAND), "", table(
        ["scene", "integrator", "touchdown [m/s] without contact", "with", "chain past back end [m] without",
         "with", "chain on anchor [m]", "deepest node [mm]", "peak contact force [MN]", "us/step without", "with",
         "cost (median over pairs of falls, pairs)", "contact lists built / steps",
         "solves/step without / with (asked by the contact)"], rows)])
    return [(DOC, "contact_cost", text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/contact_cost.json``."""
    return docs_blocks(load_result("contact_cost"))


def main() -> None:
    if "--docs-only" in sys.argv:
        write_blocks(docs_from_results())
        return
    load = os.getloadavg()[0]
    cases = [_case(scene, integrator) for scene, integrator in CASES]
    out = {**run_record(load), "cases": cases}
    write_results(RESULTS / "contact_cost.json", out)
    write_blocks(docs_blocks(out))


if __name__ == "__main__":
    main()

"""Benchmark: the catch-up scenes against MoorDyn, with and without the line-anchor contact, on the straight and
the disturbed vertical chain.

Run from the repository root: ``python benchmarks/contact_crosscheck.py`` (``--docs-only``: the tables from the
committed JSON). For each scene it records the touchdown speed and tilt of

- ours, explicit (the scene's integrator), with the contact off and on, from the static equilibrium as solved
  (its vertical chain hangs exactly on the anchor's axis, in the scene's plane);
- ours with every free line node of that equilibrium moved out of the plane by a seeded normal offset of
  ``OFFSET_M`` (1 mm; ``SEEDS``), contact on and off;
- MoorDyn 2.7 (``moor_env.crosscheck.moordyn``, RK4, started from our equilibrium) with its line damping off and
  with the scene's ratio, at its default step (0.7 of its RK4 limit) and at half of it, and from the disturbed
  equilibrium at half its default step (MoorDyn has no line-body contact and no current: those cells stay empty).

A second table sweeps MoorDyn's line damping ratio and step on the spacing 110 m scene. Writes
``benchmarks/results/contact_crosscheck.json`` and two blocks in ``docs/fall-accuracy.md``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.crosscheck.moordyn import run_moordyn_drop  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402
from moor_env.simulation import run_drop  # noqa: E402

COMMAND = "python benchmarks/contact_crosscheck.py"
DOC = DOCS / "fall-accuracy.md"
OFFSET_M = 1e-3
SEEDS = (0, 1, 2)
CASES = [("vertical-chain", "vertical-chain", {}, True),
         ("gjoa-500", "gjoa-500", {}, True),
         ("spacing 110 m", "gjoa-500", {"vessel_spacing_m": 110.0}, True),
         ("seed current", "gjoa-500", {"current_scale": 1.0}, False),
         ("spacing 170 m, 10 m vertical chain", "gjoa-500",
          {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0}, True)]
SWEEP_SCENE = ("gjoa-500", {"vessel_spacing_m": 110.0})
SWEEP_ZETAS = (None, 0.1, 0.03, 0.0)  # None: the scene's ratio
SWEEP_DT_FACTORS = (1.0, 0.5, 0.35)


def disturb(sim, offset_m: float, seed: int, axis: int = 1) -> None:
    """Move every free line node of ``sim``'s state along ``axis`` (1: out of the scene's plane, 0: in it,
    horizontally) by ``offset_m`` times a seeded standard normal draw, in place."""
    free = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
    sim.state.node_pos[free, axis] += offset_m * np.random.default_rng(seed).standard_normal(int(free.sum()))


def _ours(sim, saved) -> dict:
    """Our fall from the saved state."""
    sim.state = saved.copy()
    r = run_drop(sim, history=False)
    return {"speed": r.touchdown_speed_m_s, "tilt": r.tilt_deg, "past_back_end_m": r.chain_past_back_end_m,
            "on_anchor_m": r.chain_on_anchor_m, "peak_force_n": r.contact_peak_force_n}


def _md(scene, static, dt_s=None, zeta=0.0) -> dict:
    """One MoorDyn fall from ``static``'s state."""
    r = run_moordyn_drop(scene, static=static, dt_s=dt_s, damping_ratio=zeta)
    return {"speed": r["touchdown_speed_m_s"], "tilt": r["tilt_deg"], "dt_s": r["dt_s"], "status": r["status"]}


def _prepared(name: str, overrides: dict, contact: str):
    """Scene, its statics' simulator and state with the contact switch set."""
    scene = load_scene(name, {**overrides, "discretization.line_anchor_contact": contact})
    static = solve_statics(scene, progress=False)
    return scene, static, static.simulator.state.copy()


def run_case(label: str, name: str, overrides: dict, moordyn: bool) -> dict:
    """Every run of one scene (module docstring)."""
    out: dict = {"label": label, "scene": name, "overrides": overrides}
    prepared = {c: _prepared(name, overrides, c) for c in ("off", "on")}
    for contact, (_, static, saved) in prepared.items():
        out[f"ours_{contact}"] = _ours(static.simulator, saved)
        out[f"ours_{contact}_disturbed"] = []
        for seed in SEEDS:
            static.simulator.state = saved.copy()
            disturb(static.simulator, OFFSET_M, seed)
            out[f"ours_{contact}_disturbed"].append(_ours(static.simulator, static.simulator.state.copy()))
    if moordyn:
        scene, static, saved = prepared["off"]
        static.simulator.state = saved.copy()
        base = _md(scene, static)
        out["md_undamped"] = [base, _md(scene, static, 0.5 * base["dt_s"])]
        out["md_damped"] = [_md(scene, static, base["dt_s"], None), _md(scene, static, 0.5 * base["dt_s"], None)]
        out["md_undamped_disturbed"] = []
        for seed in SEEDS:
            static.simulator.state = saved.copy()
            disturb(static.simulator, OFFSET_M, seed)
            out["md_undamped_disturbed"].append(_md(scene, static, 0.5 * base["dt_s"]))
    print(f"{label}: ours off {out['ours_off']['speed']:.3f} on {out['ours_on']['speed']:.3f}"
          + (f", MoorDyn {out['md_undamped'][1]['speed']:.3f}" if moordyn else ""), flush=True)
    return out


def damping_sweep() -> list[dict]:
    """MoorDyn on the sweep scene over damping ratios and steps (steps relative to the undamped default)."""
    name, overrides = SWEEP_SCENE
    scene, static, _ = _prepared(name, overrides, "off")
    base_dt = _md(scene, static)["dt_s"]
    rows = []
    for zeta in SWEEP_ZETAS:
        for factor in SWEEP_DT_FACTORS:
            rows.append({"zeta": zeta, "dt_factor": factor, **_md(scene, static, factor * base_dt, zeta)})
    return rows


def _cell(runs: list[dict] | dict | None) -> str:
    """``speed (tilt)``, or the range over several runs."""
    if not runs:
        return "-"
    runs = runs if isinstance(runs, list) else [runs]
    s = [r["speed"] for r in runs]
    t = [r["tilt"] for r in runs]
    if len(runs) == 1:
        return f"{s[0]:.2f} ({t[0]:.1f})"
    return f"{min(s):.2f}-{max(s):.2f} ({min(t):.1f}-{max(t):.1f})"


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The scene table and the damping sweep."""
    rows = []
    for c in out["cases"]:
        md = c.get("md_undamped")
        rows.append([c["label"], _cell(c["ours_off"]), _cell(c["ours_on"]), f"{c['ours_on']['past_back_end_m']:+.2f}",
                     _cell(c["ours_on_disturbed"]), _cell(c["ours_off_disturbed"]),
                     " / ".join(_cell(r) for r in md) if md else "-",
                     " / ".join(_cell(r) for r in c["md_damped"]) if md else "-",
                     _cell(c.get("md_undamped_disturbed"))])
    main = "\n".join([run_line(out, COMMAND) + f" Disturbed: free nodes {1e3 * out['offset_m']:g} mm out of the "
                      f"plane (seeded normal), seeds {', '.join(str(s) for s in out['seeds'])}. Touchdown speed "
                      "[m/s] (tilt [deg]).", "", table(
        ["scene", "ours, no contact", "ours, contact", "chain past back end [m], contact",
         "ours disturbed, contact", "ours disturbed, no contact", "MoorDyn, no damping, default / half step",
         "MoorDyn, scene damping, default / half step", "MoorDyn disturbed, no damping, half step"], rows)])
    sweep_rows = []
    by_zeta: dict = {}
    for r in out["damping_sweep"]:
        by_zeta.setdefault(r["zeta"], []).append(r)
    for zeta, runs in by_zeta.items():
        sweep_rows.append(["scene's (0.3)" if zeta is None else f"{zeta:g}"] + [_cell(r) for r in runs])
    sweep = table(["MoorDyn damping ratio"] + [f"step {f:g} x default ({1e3 * out['damping_sweep'][i]['dt_s']:.2f} ms)"
                                               for i, f in enumerate(SWEEP_DT_FACTORS)], sweep_rows)
    return [(DOC, "contact_crosscheck", main), (DOC, "contact_crosscheck:damping", sweep)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/contact_crosscheck.json``."""
    return docs_blocks(load_result("contact_crosscheck"))


def main() -> None:
    if "--docs-only" in sys.argv:
        write_blocks(docs_from_results())
        return
    load = os.getloadavg()[0]
    cases = [run_case(*case) for case in CASES]
    sweep = damping_sweep()
    out = {**run_record(load), "offset_m": OFFSET_M, "seeds": list(SEEDS), "cases": cases, "damping_sweep": sweep}
    write_results(RESULTS / "contact_crosscheck.json", out)
    write_blocks(docs_blocks(out))


if __name__ == "__main__":
    main()

"""Benchmark: how far the gjoa-500 touchdown speed with the line-anchor contact is converged, and what its spread
is made of.

Run from the repository root: ``python benchmarks/contact_convergence.py`` (``--docs-only``: the table from the
committed JSON). gjoa-500 with the contact on, explicit fall, over the model's knobs: chain segment (1, 0.5,
0.25 m; fibre 5 and wire 10 times it), the step halved, the contact stiffness halved and doubled, no friction,
a stick zone five times narrower, the implicit fall, and the contact off. Each variant falls from the static
equilibrium as solved (the vertical chain exactly on the anchor's axis) and from that equilibrium with every free
line node moved by a seeded normal offset: 0.06 mm in the scene's plane (horizontally), 1 um and 1 mm out of it
(``SEEDS`` each). Writes ``benchmarks/results/contact_convergence.json`` and its table in ``docs/fall-accuracy.md``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402
from contact_crosscheck import disturb  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402
from moor_env.simulation import run_drop  # noqa: E402

COMMAND = "python benchmarks/contact_convergence.py"
DOC = DOCS / "fall-accuracy.md"
SEEDS = (0, 1, 2)
OFFSETS = [("in plane 0.06 mm", 0, 6e-5), ("out of plane 1 um", 1, 1e-6), ("out of plane 1 mm", 1, 1e-3)]


def _chain(c: float) -> dict:
    """Chain segment ``c`` near the anchor and in the loop, fibre 5 c, wire 10 c."""
    return {"discretization.vertical_chain_segment_m": c, "discretization.loop_chain_segment_m": c,
            "discretization.fibre_segment_m": 5.0 * c, "discretization.wire_segment_m": 10.0 * c}


# (label, scene overrides, contact_f slots set after compiling)
VARIANTS = [("chain 1 m (the scene's)", _chain(1.0), {}),
            ("chain 0.5 m", _chain(0.5), {}),
            ("chain 0.25 m", _chain(0.25), {}),
            ("chain 1 m, step halved", {"discretization.dt_safety": 0.45}, {}),
            ("chain 1 m, stiffness x 0.5", {"discretization.contact_stiffness_scale": 0.5}, {}),
            ("chain 1 m, stiffness x 2", {"discretization.contact_stiffness_scale": 2.0}, {}),
            ("chain 1 m, no friction", {}, {L.CF_MU: 0.0}),
            ("chain 1 m, stick speed 0.01 m/s", {}, {L.CF_STICK_SPEED: 0.01}),
            ("chain 1 m, implicit fall", {"fall_integrator": "implicit_euler"}, {}),
            ("chain 1 m, no contact", {"discretization.line_anchor_contact": "off"}, {})]


def _fall(sim, saved) -> dict:
    """One fall from the saved state."""
    sim.state = saved.copy()
    r = run_drop(sim, history=False)
    return {"speed": r.touchdown_speed_m_s, "tilt": r.tilt_deg, "past_back_end_m": r.chain_past_back_end_m}


def run_variant(label: str, overrides: dict, contact_slots: dict) -> dict:
    """The straight and the disturbed falls of one variant."""
    scene = load_scene("gjoa-500", {"integrator": "symplectic_euler", "discretization.line_anchor_contact": "on",
                                    **overrides})
    static = solve_statics(scene, progress=False)
    sim = static.simulator
    for slot, value in contact_slots.items():
        sim.model.contact_f[slot] = value
    saved = sim.state.copy()
    out = {"label": label, "straight": _fall(sim, saved), "disturbed": {}}
    for name, axis, offset in OFFSETS:
        runs = []
        for seed in SEEDS:
            sim.state = saved.copy()
            disturb(sim, offset, seed, axis)
            runs.append(_fall(sim, sim.state.copy()))
        out["disturbed"][name] = runs
    speeds = [r["speed"] for runs in out["disturbed"].values() for r in runs]
    print(f"{label}: straight {out['straight']['speed']:.3f}, disturbed {min(speeds):.3f}-{max(speeds):.3f}",
          flush=True)
    return out


def _range(runs: list[dict], key: str, fmt: str) -> str:
    """``min-max`` of one quantity over runs."""
    v = [r[key] for r in runs]
    return f"{min(v):{fmt}}-{max(v):{fmt}}"


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The table of one run: touchdown speed [m/s] and tilt [deg] per variant and start state."""
    rows = []
    for v in out["variants"]:
        cells = [v["label"], f"{v['straight']['speed']:.3f} ({v['straight']['tilt']:.1f})"]
        cells += [f"{_range(runs, 'speed', '.2f')} ({_range(runs, 'tilt', '.1f')})" for runs in v["disturbed"].values()]
        rows.append(cells)
    names = list(out["variants"][0]["disturbed"])
    text = "\n".join([run_line(out, COMMAND) + f" gjoa-500, contact on unless said, explicit fall unless said; "
                      f"seeds {', '.join(str(s) for s in out['seeds'])}. Touchdown speed [m/s] (tilt [deg]).", "",
                      table(["variant", "straight start"] + [f"disturbed {n}" for n in names], rows)])
    return [(DOC, "contact_convergence", text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/contact_convergence.json``."""
    return docs_blocks(load_result("contact_convergence"))


def main() -> None:
    if "--docs-only" in sys.argv:
        write_blocks(docs_from_results())
        return
    load = os.getloadavg()[0]
    variants = [run_variant(*v) for v in VARIANTS]
    out = {**run_record(load), "seeds": list(SEEDS), "variants": variants}
    write_results(RESULTS / "contact_convergence.json", out)
    write_blocks(docs_blocks(out))


if __name__ == "__main__":
    main()

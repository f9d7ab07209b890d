"""AnchorRelease-v1's quasi-static positioning step against the dynamic simulation of the same move.

Run from the repository root: ``python benchmarks/positioning_quasi_static.py`` (``--settle-s 180``). Writes
``benchmarks/results/positioning_quasi_static.json`` and its table in ``docs/positioning.md`` (``--docs-only``:
only the table, from the committed JSON).

AnchorRelease-v1 moves the levers in steps of ``positioning.step_s`` (60 s) and takes the hanging equilibrium of
the geometry reached, solved fresh, as the state after each step. Here each case starts from the equilibrium of
a geometry A on a calm site (Hs 0; with or without current; chain tangential drag nominal), and the move to B is
simulated with the simulator's own actuators over the same 60 s at constant rate: the second vessel's DP
(:func:`moor_env.envs.actuators.drive`), the mooring-line winch, and the installation vessel's wire winch (the
wire's top pays out and hauls in as the mooring line's does), with the implicit integrator at
``control.pre_release_dt_calm_s`` as the env's pre-release phase runs (:func:`moor_env.envs.core.run_advance`).
The vessels then hold station for ``--settle-s``. The chain stopper is left out: the model does not pass chain
through the release unit while it runs.

Measured against the equilibrium solved directly at B (the env's step): the release point's distance and the
anchor tip's height difference at the end of the move and after settling, the top tensions of the mooring line
and the wire, the peak tension during the move against the larger of the two static values (the dynamic
overshoot, as a fraction of the line's MBL) and the anchor's tilt at the end of the move.
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

from moor_env.envs import actuators, measures  # noqa: E402
from moor_env.envs.config import load_env_config  # noqa: E402
from moor_env.envs.core import Advance, InstallationCore, run_advance  # noqa: E402
from moor_env.envs.levers import episode_scenario  # noqa: E402
from moor_env.envs.positioning import LEVER_STATE, plan_targets  # noqa: E402
from moor_env.envs.resolution import even_step_s  # noqa: E402
from moor_env.envs.reward import PHASE_CONTROL  # noqa: E402
from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402

STEM = "positioning_quasi_static"
RESULTS = ROOT / "benchmarks" / "results" / f"{STEM}.json"
DOC = DOCS / "positioning.md"
COMMAND = "python benchmarks/positioning_quasi_static.py"
CONFIG = "anchor-plan"
SETTLE_S = 180.0
CHECKPOINTS_S = (60.0, 180.0)  # after the end of the move; the last one is the settling time
CHAIN_CD_TANGENTIAL = 0.0069  # nominal (configs/envs/anchor-plan.yaml)
# two sites within AnchorPlan-v1's depth range, each with a geometry A inside the levers' ranges
GEOMETRIES = {
    "400 m": (400.0, {"vessel_spacing_m": 80.0, "mooring_line_length_m": 432.0, "vertical_chain_length_m": 30.0,
                      "drop_height_m": 60.0}),
    "600 m": (600.0, {"vessel_spacing_m": 150.0, "mooring_line_length_m": 648.0, "vertical_chain_length_m": 20.0,
                      "drop_height_m": 80.0}),
}
CURRENTS = {"calm": 0.0, "current": 1.0}  # current_scale (1: the seed profile, 0.8 m/s at the surface)
# moves over one 60 s step at the default rates: DP 0.5 m/s, mooring-line winch 0.3 m/s, wire winch 0.5 m/s
MOVES = {
    "DP +30 m": {"vessel_spacing_m": 30.0},
    "DP -30 m": {"vessel_spacing_m": -30.0},
    "winch +18 m": {"mooring_line_length_m": 18.0},
    "winch -18 m": {"mooring_line_length_m": -18.0},
    "DP +30 m, winch +18 m": {"vessel_spacing_m": 30.0, "mooring_line_length_m": 18.0},
    "wire +30 m": {"drop_height_m": 30.0},
}


def _site(depth_m: float, current_scale: float) -> dict:
    return {"water_depth_m": depth_m, "current_scale": current_scale, "current_direction_deg": 0.0,
            "sea_state_hs_m": 0.0, "sea_state_tp_s": 10.0, "sea_state_seed": 0,
            "chain_cd_tangential": CHAIN_CD_TANGENTIAL, "anchor_mass_scale": 1.0, "soil_fraction": 0.5,
            "penetration_ratio": 1.0}


def _start(core: InstallationCore, site: dict, levers: dict) -> None:
    """The core at the equilibrium of ``levers`` on ``site`` (AnchorRelease-v1's ``_settle``)."""
    factory = core.factory
    targets = plan_targets(levers, site["water_depth_m"], 0.0, core.cfg.levers, factory.anchor_length_m,
                           factory.fairlead_depth_m)
    if core.start(episode_scenario(site, targets)) is not None:
        raise RuntimeError("a calm site needs no warm-up")


def _state(core: InstallationCore) -> dict:
    """Release point, tip height, top tensions and tilt of the core's present state."""
    sim = core.sim
    tops = sim.top_tensions_n()
    return {"release_point_m": sim.state.node_pos[sim.model.release_node].tolist(),
            "tip_height_m": float(sim.tip_state()[0][2] + core.depth),
            "mooring_line_tension_n": tops["mooring_line"], "wire_tension_n": tops["wire"],
            "tilt_deg": sim.tilt_deg()}


def _advance(core: InstallationCore, t_end_s: float, dt_max_s: float) -> None:
    """Integrate to ``t_end_s`` in equal implicit steps of at most ``dt_max_s`` (the env's pre-release advance)."""
    dt = even_step_s(t_end_s - core.sim.state.t, dt_max_s)
    error = run_advance(core, Advance(t_end_s, False, PHASE_CONTROL, dt))[1]
    if error is not None:
        raise error


def _move(core: InstallationCore, site: dict, lever_a: dict, move: dict, dt_max_s: float | None,
          settle_s: float) -> dict:
    """From A's equilibrium, the 60 s move at constant rates, then the vessels holding for ``settle_s``, in
    implicit steps of at most ``dt_max_s`` (None: the scene's step): the states at the end of the move and at the
    checkpoints, and the peak tensions of the move."""
    _start(core, site, lever_a)
    sim = core.sim
    dt_max_s = sim.dt if dt_max_s is None else dt_max_s
    step_s = core.cfg.positioning.step_s
    t0 = sim.state.t
    sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0
    # DP and winch at constant rate over the step; the wire's top hauls in (negative payout) to raise the anchor
    actuators.drive(sim, t0, step_s, move.get("vessel_spacing_m", 0.0) / step_s,
                    move.get("mooring_line_length_m", 0.0) / step_s, core.ramp_s)
    sim.set_payout_rate("wire", -move.get("drop_height_m", 0.0) / step_s)
    _advance(core, t0 + step_s, dt_max_s)
    peaks = measures.max_tensions_n(sim, core.lines)
    states = {"0": _state(core)}
    actuators.stop_winch(sim)
    sim.set_payout_rate("wire", 0.0)
    actuators.hold(sim, t0 + step_s, max(settle_s, sim.dt), core.ramp_s)
    for after in [c for c in CHECKPOINTS_S if c < settle_s] + ([settle_s] if settle_s > 0.0 else []):
        _advance(core, t0 + step_s + after, dt_max_s)
        states[f"{after:g}"] = _state(core)
    return {"states": states, "peak_tension_n": {k: peaks[k] for k in ("mooring_line", "wire")}, "dt_s": sim.dt
            if dt_max_s == sim.dt else even_step_s(step_s, dt_max_s), "line_length_m": core.line_length_total_m(),
            "spacing_m": core.spacing_m()}


def run_case(core: InstallationCore, site: dict, lever_a: dict, move: dict, settle_s: float) -> dict:
    """One move: the static equilibria at A and B, the dynamic move at the scene's step (the reference) and the
    move alone at the env's calm pre-release step (module docstring)."""
    lever_b = {name: lever_a[name] + move.get(name, 0.0) for name in LEVER_STATE}
    _start(core, site, lever_b)
    static_b = _state(core)
    _start(core, site, lever_a)
    static_a = _state(core)
    mbl = {k: core.mbl[k] for k in ("mooring_line", "wire")}
    dynamic = _move(core, site, lever_a, move, None, settle_s)
    coarse_s = core.cfg.control.pre_release_dt_calm_s
    try:
        coarse = _move(core, site, lever_a, move, coarse_s, 0.0)
    except SimulationDiverged as exc:
        coarse = {"error": str(exc)}
    return {"lever_a": lever_a, "lever_b": lever_b, "static_a": static_a, "static_b": static_b, "mbl_n": mbl,
            "dynamic": dynamic, "coarse_step_s": coarse_s, "coarse": coarse}


def _difference(d: dict, b: dict) -> dict:
    """State ``d`` against state ``b``: release-point distance, tip height difference, tensions in % of ``b``."""
    return {"release_point_m": float(np.linalg.norm(np.subtract(d["release_point_m"], b["release_point_m"]))),
            "tip_height_m": d["tip_height_m"] - b["tip_height_m"],
            **{f"{line}_tension_pct": 100.0 * (d[f"{line}_tension_n"] / b[f"{line}_tension_n"] - 1.0)
               for line in ("mooring_line", "wire")}}


def compare(case: dict) -> dict:
    """The dynamic states against the static one at B (end of the move and each checkpoint), the peak tensions of
    the move against the larger static value of A and B, and the move at the env's coarse step against the
    reference at the end of the move."""
    b, dyn = case["static_b"], case["dynamic"]
    overshoot = {}
    for line in ("mooring_line", "wire"):
        static = max(case["static_a"][f"{line}_tension_n"], b[f"{line}_tension_n"])
        peak = dyn["peak_tension_n"][line]
        overshoot[line] = {"peak_over_mbl": peak / case["mbl_n"][line], "static_over_mbl": static / case["mbl_n"][line],
                           "overshoot_over_mbl": (peak - static) / case["mbl_n"][line]}
    coarse = case["coarse"]
    if "error" not in coarse:
        peak = coarse["peak_tension_n"]["mooring_line"]
        coarse = {**_difference(coarse["states"]["0"], dyn["states"]["0"]),
                  "peak_mooring_line_over_mbl": peak / case["mbl_n"]["mooring_line"]}
    return {"at": {when: _difference(d, b) for when, d in dyn["states"].items()}, "overshoot": overshoot,
            "tilt_end_of_move_deg": dyn["states"]["0"]["tilt_deg"], "tilt_static_b_deg": b["tilt_deg"],
            "coarse_step_end_of_move": coarse}


def measure(settle_s: float, progress: bool = True) -> dict:
    """Every case of :data:`GEOMETRIES` x :data:`CURRENTS` x :data:`MOVES`."""
    load_before = os.getloadavg()[0]
    core = InstallationCore(load_env_config(CONFIG))
    plan = [(g, c, m) for g in GEOMETRIES for c in CURRENTS for m in MOVES]
    cases = []
    for g, c, m in tqdm(plan, desc="moves", disable=not progress):
        depth, lever_a = GEOMETRIES[g]
        row = {"geometry": g, "sea": c, "move": m}
        try:
            case = run_case(core, _site(depth, CURRENTS[c]), lever_a, MOVES[m], settle_s)
        except (ConfigError, StaticsNotConverged, SimulationDiverged) as exc:  # reported, not hidden
            cases.append({**row, "error": f"{type(exc).__name__}: {exc}"})
            continue
        cases.append({**row, **case, "comparison": compare(case)})
    return {**run_record(load_before), "config": CONFIG, "settle_s": settle_s, "checkpoints_s": list(CHECKPOINTS_S),
            "chain_cd_tangential": CHAIN_CD_TANGENTIAL, "cases": cases}


def _worst(cases: list[dict], when: str, key: str) -> float:
    return max(abs(c["comparison"]["at"][when][key]) for c in cases if "comparison" in c)


def _coarse_cell(cmp_: dict) -> str:
    coarse = cmp_["coarse_step_end_of_move"]
    if "error" in coarse:
        return "diverged"
    return (f"{coarse['mooring_line_tension_pct']:+.1f} % / {coarse['wire_tension_pct']:+.1f} %, peak "
            f"{coarse['peak_mooring_line_over_mbl']:.3f} MBL")


def docs_blocks(result: dict | None) -> list[tuple[Path, str, str]]:
    """The table of one run (docs/positioning.md)."""
    if result is None:
        return []
    settle = f"{result['settle_s']:g}"
    rows = []
    for c in result["cases"]:
        label = [c["geometry"], c["sea"], c["move"]]
        if "comparison" not in c:
            rows.append(label + [c["error"]] + [""] * 7)
            continue
        cmp_ = c["comparison"]
        end, late = cmp_["at"]["0"], cmp_["at"][settle]
        ml, wire = cmp_["overshoot"]["mooring_line"], cmp_["overshoot"]["wire"]
        rows.append(label + [
            f"{end['release_point_m']:.2f} / {late['release_point_m']:.2f}",
            f"{end['tip_height_m']:+.2f} / {late['tip_height_m']:+.2f}",
            f"{end['mooring_line_tension_pct']:+.1f} / {late['mooring_line_tension_pct']:+.1f}",
            f"{end['wire_tension_pct']:+.1f} / {late['wire_tension_pct']:+.1f}",
            f"{ml['static_over_mbl']:.3f} / {ml['overshoot_over_mbl']:+.3f}",
            f"{wire['static_over_mbl']:.3f} / {wire['overshoot_over_mbl']:+.3f}",
            f"{cmp_['tilt_end_of_move_deg']:.2f} ({cmp_['tilt_static_b_deg']:.2f})", _coarse_cell(cmp_)])
    step = next((c["coarse_step_s"] for c in result["cases"] if "coarse_step_s" in c), None)
    head = ["depth", "sea", "move (60 s)", f"release point [m], end / +{settle} s",
            f"tip height [m], end / +{settle} s", f"mooring-line tension [%], end / +{settle} s",
            f"wire tension [%], end / +{settle} s", "mooring line: static / overshoot [MBL]",
            "wire: static / overshoot [MBL]", "tilt end of move (static B) [deg]",
            f"move at a {step:g} s step: mooring-line / wire tension against the reference, end of move"]
    ok = [c for c in result["cases"] if "comparison" in c]
    diverged = sum("error" in c["comparison"]["coarse_step_end_of_move"] for c in ok)
    summary = (f"Largest over the {len(ok)} cases, at the end of the move / after {settle} s: release point "
               f"{_worst(ok, '0', 'release_point_m'):.2f} / {_worst(ok, settle, 'release_point_m'):.2f} m, tip height "
               f"{_worst(ok, '0', 'tip_height_m'):.2f} / {_worst(ok, settle, 'tip_height_m'):.2f} m, mooring-line "
               f"tension {_worst(ok, '0', 'mooring_line_tension_pct'):.1f} / "
               f"{_worst(ok, settle, 'mooring_line_tension_pct'):.1f} %, wire tension "
               f"{_worst(ok, '0', 'wire_tension_pct'):.1f} / {_worst(ok, settle, 'wire_tension_pct'):.1f} %; "
               f"largest overshoot of the mooring line "
               f"{max(c['comparison']['overshoot']['mooring_line']['overshoot_over_mbl'] for c in ok):+.3f} MBL, "
               f"of the wire {max(c['comparison']['overshoot']['wire']['overshoot_over_mbl'] for c in ok):+.3f} MBL. "
               f"At the {step:g} s step {diverged} of the {len(ok)} moves diverged.")
    text = f"{table(head, rows)}\n\n{summary}\n\n{run_line(result, COMMAND)}"
    return [(DOC, STEM, text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/positioning_quasi_static.json``."""
    return docs_blocks(load_result(STEM))


def main(argv: list[str] | None = None) -> dict | None:
    """Measure, write the JSON and the docs table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settle-s", type=float, default=SETTLE_S, help="hold after the move [s]")
    parser.add_argument("--no-progress", action="store_true")
    parser.add_argument("--docs-only", action="store_true",
                        help=f"rewrite the docs table from {RESULTS.relative_to(ROOT)}, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return load_result(STEM)
    result = measure(args.settle_s, not args.no_progress)
    write_results(RESULTS, result)
    write_blocks(docs_blocks(result))
    return result


if __name__ == "__main__":
    main()

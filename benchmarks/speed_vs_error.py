"""Speed against error: our lumped-mass model over its knobs, and MoorDyn over its stable settings, per scene.

Run from the repository root (one command; a progress bar shows the runs)::

    python benchmarks/speed_vs_error.py            # --quick: about 10 minutes on a shared 2-core machine
    python benchmarks/speed_vs_error.py --full     # every knob level (tens of minutes)

What it does, per scene (``gjoa-500``; ``deep-1500``; ``wide`` = gjoa-500 with spacing 170 m and a 10 m vertical
chain; ``snap`` = gjoa-500 with spacing 170 m, whose chain loop snaps taut before touchdown; ``current-waves`` =
gjoa-500 with the seed 003 current, Hs 2 m and release after 20 s of waves):

1. **Reference**: our explicit symplectic Euler at 0.9 of its stability limit on a ladder of uniformly refined
   chain segments c (fibre 5 c, wire 10 c); the finest level is the reference and the two finest levels are
   compared (the convergence is printed and written; ``--full`` adds a time-step check of the reference).
2. **Our knobs**: element length per line, near and far from the anchor (vertical chain = near, loop chain =
   the rest of the bottom chain, fibre = far part of the mooring line, wire), time step and integrator
   (``symplectic_euler``, ``rk2``, ``implicit_euler`` at fractions and multiples of its default step), and
   components: the cut wire simulated after release or dropped, pre-release dynamics in calm water (10 s) or
   statics only, and (``current-waves``) release after the waves have acted versus from statics.
3. **The fidelity presets** of ``configs/fidelity.yaml`` (``fast``, ``default``, ``accurate``) on every scene,
   and both resolutions of ``fast`` (its slack-line keys and its ``tight_line`` keys) on every scene.
4. **MoorDyn 2.7** (``moor_env.crosscheck.moordyn``, RK4, line damping off, started from our statics) over its
   stable settings: chain (and fibre) segment length and time step as a fraction of its RK4 stability limit
   (on ``wide`` down to 0.25 m chain). The ratio of its cost to ours at equal error is printed; where its sweep
   never reaches an error, a lower bound (its most accurate run against our cheapest run at that error).
   ``current-waves`` is not supported by the MoorDyn bridge (no current, waves or pre-release phase).
5. **Node scaling** on ``deep-1500`` (wire kept): cost per simulated second against the number of line nodes,
   refining chain, fibre and wire together at a fixed time step (implicit and explicit), with log-log slopes.

Errors against the reference: touchdown speed (relative), tilt (deg; where the reference tilt is below 1 deg it
is reported as a spread across resolutions, not as an error), touchdown time (ms) and drift (m). Cost: wall time
of the dynamic part (pre-release phase if any, release and fall; statics excluded for both codes, MoorDyn is
seeded with our statics), best of 3 for runs under ``FAST_S``; our CPU time (``time.process_time``) alongside.

Writes ``benchmarks/results/speed_vs_error[_quick].json``, ``docs/speed_vs_error_<scene>.png``,
``docs/speed_vs_error_nodes.png``, ``docs/speed_vs_error.md`` (tables written by this script) and the README's
headline line (``--docs-only``: the markdown only, from the committed JSON).
Absolute times are those of the machine named in the output (its load average is recorded).
"""

from __future__ import annotations

import argparse
import copy
import datetime
import json
import math
import os
import platform
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _docs import load_result, write_blocks  # noqa: E402
from _machine import machine  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.compile import compile_scene  # noqa: E402
from moor_env.config import (  # noqa: E402
    TIGHT_LINE,
    SceneConfig,
    fidelity_presets,
    mooring_line_slack,
    scene_from_dict,
    tight_line_keys,
)
from moor_env.errors import ConfigError, SimulationDiverged  # noqa: E402
from moor_env.physics import layout as LY  # noqa: E402
from moor_env.simulation import (  # noqa: E402
    INTEGRATOR_IMPLICIT_EULER,
    INTEGRATOR_RK2,
    INTEGRATOR_SYMPLECTIC_EULER,
    run_drop,
)

RESULTS_DIR = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs"
FAST_S = 1.0  # runs faster than this are repeated (best of 3)
REPEATS = 3
TILT_SMALL_DEG = 1.0  # reference tilt below this: report a spread across resolutions, not an error
V, LP, F, W = ("discretization.vertical_chain_segment_m", "discretization.loop_chain_segment_m",
               "discretization.fibre_segment_m", "discretization.wire_segment_m")
IMPL = "implicit_euler"
SE = "symplectic_euler"

SCENES: dict[str, dict[str, Any]] = {
    "gjoa-500": {"scene": "gjoa-500", "overrides": {}, "moordyn": True,
                 "about": "seed 003 ch. 8: 500 m, spacing 50 m, 50 m vertical chain, calm"},
    "deep-1500": {"scene": "deep-1500", "overrides": {}, "moordyn": True,
                  "about": "1500 m, spacing 150 m, 1540 m mooring line, calm"},
    "wide": {"scene": "gjoa-500", "overrides": {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0},
             "moordyn": True, "about": "gjoa-500 with spacing 170 m and a 10 m vertical chain (large tilt)"},
    "snap": {"scene": "gjoa-500", "overrides": {"vessel_spacing_m": 170.0}, "moordyn": True,
             "about": "gjoa-500 with spacing 170 m (50 m vertical chain): the loop snaps taut before touchdown"},
    "current-waves": {"scene": "gjoa-500",
                      "overrides": {"current_scale": 1.0, "sea_state_hs_m": 2.0, "release_time_s": 20.0},
                      "moordyn": False,
                      "about": "gjoa-500 with the seed 003 current (0.8/0.6/0.2 m/s), Hs 2 m Tp 10 s, release at 20 s"},
}

# chain segment ladders of the reference (explicit); the last level is the reference, the one before its check
LADDER = {"quick": {"gjoa-500": [2.0, 1.0, 0.5, 0.25], "deep-1500": [2.0, 1.0, 0.5, 0.25],
                    "wide": [2.0, 1.0, 0.5, 0.25, 0.125], "snap": [2.0, 1.0, 0.5, 0.25],
                    "current-waves": [4.0, 2.0, 1.0]},
          "full": {"gjoa-500": [4.0, 2.0, 1.0, 0.5, 0.25], "deep-1500": [4.0, 2.0, 1.0, 0.5, 0.25],
                   "wide": [4.0, 2.0, 1.0, 0.5, 0.25, 0.125], "snap": [4.0, 2.0, 1.0, 0.5, 0.25],
                   "current-waves": [4.0, 2.0, 1.0, 0.5]}}
# (levels are powers of two: the statics solver stalls at some others, e.g. 0.18 m chain on `wide`; on gjoa-500
# it fails at uniform 0.125 m after about 5 minutes)


def uniform(c: float) -> dict[str, float]:
    """Uniform refinement: chain c everywhere, fibre 5 c, wire 10 c."""
    return {V: c, LP: c, F: 5.0 * c, W: 10.0 * c}


def res(v: float, lp: float, f: float, w: float) -> dict[str, float]:
    """Element lengths: vertical chain (near), loop chain, fibre (far), wire."""
    return {V: v, LP: lp, F: f, W: w}


BASE = res(1.0, 1.0, 5.0, 10.0)


def our_cases(scene: str, mode: str) -> list[dict[str, Any]]:
    """Our runs of one scene: (family, label, overrides)."""
    full = mode == "full"
    # current-waves statics take 5-80 s per resolution (Newton under current): few resolutions in quick mode
    light = scene == "current-waves" and not full
    cases: list[dict[str, Any]] = []

    def add(family: str, label: str, ov: dict[str, Any]) -> None:
        cases.append({"family": family, "label": label, "overrides": ov})

    for c in LADDER[mode][scene]:
        add("reference ladder", f"explicit c={c:g} m", dict(uniform(c), integrator=SE))
    if full:
        c = LADDER[mode][scene][-1]
        add("reference dt check", f"explicit c={c:g} m, dt x0.5", dict(uniform(c), integrator=SE,
                                                                       **{"discretization.dt_safety": 0.45}))
    # element length per line, near (vertical chain) and far (loop, fibre), both integrators
    near = [0.5, 2.0, 5.0, 10.0] if full else [2.0, 5.0]
    loop = [0.5, 2.0, 4.0, 8.0] if full else [2.0, 4.0]
    fibre = [20.0, 50.0, 200.0] if full else [20.0, 200.0]
    wire = [30.0, 100.0]
    for integ in ([SE, IMPL] if full else [] if light else [IMPL]):
        tag = "explicit" if integ == SE else "implicit"
        for v in near:
            add("near/far resolution", f"{tag} vertical {v:g} m", dict(BASE, **{V: v}, integrator=integ))
        for lp in loop:
            add("near/far resolution", f"{tag} loop {lp:g} m", dict(BASE, **{LP: lp}, integrator=integ))
        for f in fibre:
            add("near/far resolution", f"{tag} fibre {f:g} m", dict(BASE, **{F: f}, integrator=integ))
        if full:
            for w in wire:
                add("near/far resolution", f"{tag} wire {w:g} m", dict(BASE, **{W: w}, integrator=integ))
    # combined settings for the implicit front
    combos = [(1, 1, 20, 30), (1, 2, 20, 30), (2, 2, 20, 30), (2, 4, 20, 30), (4, 4, 50, 100),
              (0.5, 1, 20, 30), (0.5, 0.5, 5, 10), (0.25, 0.25, 2.5, 10)]
    if full:
        combos += [(1, 0.5, 20, 30), (2, 1, 20, 30), (4, 8, 100, 200), (10, 4, 50, 100), (0.5, 0.25, 5, 10)]
    if light:
        combos = [(1, 2, 20, 30), (2, 2, 20, 30), (2, 4, 20, 30)]
    for v, lp, f, w in combos:
        add("combined resolution", f"implicit {v:g}/{lp:g}/{f:g}/{w:g}", dict(res(v, lp, f, w), integrator=IMPL))
    if full:
        for v, lp, f, w in [(2, 2, 20, 30), (2, 4, 20, 30), (4, 4, 50, 100), (1, 2, 20, 30)]:
            add("combined resolution", f"explicit {v:g}/{lp:g}/{f:g}/{w:g}", dict(res(v, lp, f, w), integrator=SE))
    # time step and integrator at the base resolution (and a coarse one for the implicit step)
    if 1.0 not in LADDER[mode][scene]:
        add("integrator / time step", "explicit 1 m", dict(BASE, integrator=SE))
    add("integrator / time step", "rk2 1 m", dict(BASE, integrator="rk2"))
    add("integrator / time step", "explicit 1 m, dt x0.5", dict(BASE, integrator=SE,
                                                                 **{"discretization.dt_safety": 0.45}))
    steps = [0.1, 0.3, 1.0, 2.0] if full else [0.1, 0.3, 1.0] if light else [0.3, 1.0, 2.0]
    for base_name, base in (("1/1/5/10", BASE), ("1/2/20/30", res(1, 2, 20, 30))):
        for k in steps:
            add("integrator / time step", f"implicit {base_name}, dt x{k:g}",
                dict(base, integrator=IMPL, _dt_multiple=k))
    # components
    for integ in (SE, IMPL):
        tag = "explicit" if integ == SE else "implicit"
        add("components", f"{tag} 1 m, wire kept after release",
            dict(BASE, integrator=integ, **{"installation.components.keep_wire_after_release": True}))
    if scene == "current-waves":
        add("components", "implicit 1 m, release from statics (no wave phase)", dict(BASE, integrator=IMPL,
                                                                                     release_time_s=0.0))
        add("components", "explicit 1 m, release from statics (no wave phase)", dict(BASE, integrator=SE,
                                                                                     release_time_s=0.0))
    else:
        for integ in (SE, IMPL):
            tag = "explicit" if integ == SE else "implicit"
            add("components", f"{tag} 1 m, 10 s pre-release dynamics (calm)",
                dict(BASE, integrator=integ, release_time_s=10.0))
    for name in fidelity_presets():
        if scene == "current-waves" and name == "accurate":
            continue  # its statics alone take many minutes under current (77 s at 0.5 m chain)
        add("preset", f"preset {name}", {"fidelity": name})
    for branch, keys in preset_branches("fast").items():
        add("preset branches", f"fast, {branch} branch", dict(keys, fidelity="custom"))
    return cases


# geometries around the fit's bounds: gjoa-500 at other spacings and line lengths, deep-1500 at wider spacings
FIT_CHECK = ([("gjoa-500", {"vessel_spacing_m": s}) for s in (70.0, 85.0, 100.0, 120.0, 140.0)]
             + [("gjoa-500", {"mooring_line_length_m": ln}) for ln in (505.0, 515.0, 530.0)]
             + [("deep-1500", {"vessel_spacing_m": s}) for s in (200.0, 250.0)])
FIT_REFERENCE_C = 0.5  # explicit chain of the fit check's references (0.25 m checked on one geometry)


def run_fit_check(scene: str, geometry: dict[str, Any], check_reference: bool) -> dict[str, Any]:
    """Both ``fast`` resolutions and the preset's choice on one geometry, against explicit 0.5 m chain."""
    spec = {"scene": scene, "overrides": geometry}
    ref = run_ours(spec, dict(uniform(FIT_REFERENCE_C), integrator=SE))
    row: dict[str, Any] = {"scene": scene, "geometry": geometry, "reference": ref,
                           "line_slack": mooring_line_slack(load_scene(scene, geometry), tip_height_m=0.0)}
    if check_reference:
        row["reference_check"] = run_ours(spec, dict(uniform(FIT_REFERENCE_C / 2), integrator=SE))
    runs = {name: run_ours(spec, dict(keys, fidelity="custom")) for name, keys in preset_branches("fast").items()}
    runs["preset"] = run_ours(spec, {"fidelity": "fast"})
    for r in runs.values():
        if r.get("status") == "ok" and ref.get("status") == "ok":
            r["speed_err_pct"] = 100.0 * (r["speed"] / ref["speed"] - 1.0)
    row["runs"] = runs
    return row


def preset_branches(name: str) -> dict[str, dict[str, Any]]:
    """Both resolutions of a preset with a ``tight_line`` entry, as explicit overrides: the slack-line one
    (the preset's own keys) and the tight-line one (its ``tight_line`` keys over them)."""
    preset = dict(fidelity_presets()[name])
    tight = preset.pop(TIGHT_LINE, None)
    if tight is None:
        return {}
    slack = {f"discretization.{k}": v for k, v in preset.items()}
    tight = {f"discretization.{k}": v for k, v in tight_line_keys(tight).items()}  # calm-water keys
    return {"slack-line": slack, "tight-line": {**slack, **tight}}


def moordyn_cases(mode: str, scene: str) -> list[dict[str, Any]]:
    """MoorDyn settings: chain segment c (fibre 5 c, exactly our segments and statics of that level), dt as a
    fraction of its RK4 stability limit. On ``wide`` the quick sweep goes on to 0.5 and 0.25 m chain, towards
    the 0.3 deg tilt error target."""
    if mode == "full":
        grid = [(c, fr) for c in (0.5, 1.0, 2.0, 4.0) for fr in (0.9, 0.7, 0.5, 0.35)] + [(0.25, 0.9), (0.25, 0.5)]
    else:
        grid = [(c, fr) for c in (1.0, 2.0, 4.0) for fr in (0.9, 0.5)]
        if scene == "wide":
            grid += [(0.5, 0.9), (0.25, 0.9)]
    return [{"family": "moordyn", "label": f"MoorDyn c={c:g} m, dt {fr:g} x limit", "chain_m": c, "fraction": fr}
            for c, fr in grid]


# --- running -------------------------------------------------------------------------------------------------
_STATICS: dict[str, Any] = {}
_CODES = {SE: INTEGRATOR_SYMPLECTIC_EULER, "rk2": INTEGRATOR_RK2, IMPL: INTEGRATOR_IMPLICIT_EULER}


def _static_key(cfg: SceneConfig) -> tuple[str, SceneConfig]:
    """Statics do not depend on the integrator or time step: one equilibrium per resolution and scene, solved
    with the validated explicit path (symplectic Euler at its default step for any relaxation). The release time
    and whether the wire is kept after release do not change the compiled arrays or the equilibrium either."""
    data = cfg.model_dump(mode="json")
    data["fidelity"] = "custom"
    data["installation"]["release_time_s"] = 0.0  # what happens at and after the release: not in the statics
    data["installation"]["components"]["keep_wire_after_release"] = False
    disc = data["discretization"]
    disc.update(integrator=SE, dt_s=None, dt_safety=0.9)
    return json.dumps(data, sort_keys=True), scene_from_dict(data)


def statics_for(cfg: SceneConfig):
    """Cached hanging equilibrium of ``cfg``'s resolution and components."""
    key, static_cfg = _static_key(cfg)
    if key not in _STATICS:
        _STATICS[key] = solve_statics(static_cfg)
    return _STATICS[key]


def scene_config(spec: dict[str, Any], ov: dict[str, Any]) -> SceneConfig:
    """Scene with the study scene's overrides and the run's (``_dt_multiple``: implicit step as a multiple of
    its default)."""
    ov = dict(ov)
    multiple = ov.pop("_dt_multiple", None)
    cfg = load_scene(spec["scene"], {**spec["overrides"], **ov})
    if multiple is not None:
        model = compile_scene(cfg)
        cfg = load_scene(spec["scene"], {**spec["overrides"], **ov, "dt_s": multiple * model.dt_s})
    return cfg


def _timed(static, model) -> list[tuple[Any, float]]:
    """Run the fall of ``model`` from a copy of the cached equilibrium: best of 3 when fast. Returns the
    (DropResult, CPU seconds) of each repeat."""
    runs = []
    for _ in range(REPEATS):
        sim = copy.deepcopy(static.simulator)
        sim.model = model  # the run's integrator and time step; arrays identical to the statics' model
        sim.dt = model.dt_s
        sim.integrator_code = _CODES[model.integrator]
        c0 = time.process_time()
        r = run_drop(sim, static.wall_static_s, history=False)
        runs.append((r, time.process_time() - c0))
        if r.wall_dynamic_s > FAST_S:
            break
    return runs


def run_ours(spec: dict[str, Any], ov: dict[str, Any]) -> dict[str, Any]:
    """One of our runs from the cached statics (best of 3 when fast)."""
    out: dict[str, Any] = {"code": "ours"}
    try:
        cfg = scene_config(spec, ov)
        model = compile_scene(cfg)  # the run's integrator and time step (statics are shared)
    except ConfigError as exc:
        out.update(status="refused", message=str(exc))
        return out
    d = cfg.discretization
    out.update(integrator=d.integrator, vertical_m=d.vertical_chain_segment_m, loop_m=d.loop_chain_segment_m,
               fibre_m=d.fibre_segment_m, wire_m=d.wire_segment_m, dt_s=model.dt_s,
               line_slack=mooring_line_slack(cfg, tip_height_m=0.0),
               keep_wire=cfg.installation.components.keep_wire_after_release,
               release_time_s=cfg.installation.release_time_s)
    try:
        static = statics_for(cfg)
    except Exception as exc:  # noqa: BLE001  (statics failure is a result of the study, not a crash)
        out.update(status="statics failed", message=f"{type(exc).__name__}: {exc}")
        return out
    out["wall_static_s"] = static.wall_static_s
    try:
        runs = _timed(static, model)
    except SimulationDiverged as exc:
        out.update(status="diverged", message=str(exc))
        return out
    best = min(runs, key=lambda x: x[0].wall_dynamic_s)[0]
    out.update(n_nodes=best.n_nodes, n_steps=best.n_steps, wall_s=best.wall_dynamic_s,
               wall_all=[r.wall_dynamic_s for r, _ in runs], cpu_s=min(c for _, c in runs), n_repeats=len(runs),
               t_end_s=best.release_time_s + (best.touchdown_time_s or 0.0))
    if best.touchdown_speed_m_s is None:
        out.update(status="no touchdown")
        return out
    out.update(status="ok", speed=best.touchdown_speed_m_s, tilt=best.tilt_deg, time=best.touchdown_time_s,
               drift=best.drift_m)
    return out


def run_md(spec: dict[str, Any], case: dict[str, Any], ref_cfg: SceneConfig) -> dict[str, Any]:
    """One MoorDyn run (best of 3 when fast) at chain segment c and dt = fraction x RK4 limit."""
    from moor_env.crosscheck.moordyn import build_moordyn_input, run_moordyn_drop
    from moor_env.crosscheck.moordyn_input import omega_dt_limit

    out: dict[str, Any] = {"code": "moordyn", "chain_m": case["chain_m"], "fraction": case["fraction"]}
    static = statics_for(ref_cfg)  # our equilibrium at the same segments: MoorDyn starts exactly from it
    seg = None
    built = build_moordyn_input(ref_cfg, static, dt_s=1.0, scheme="rk4", segment_length_m=seg)
    dt = case["fraction"] * omega_dt_limit("rk4", 0.0) / built["omega_max_rad_s"]
    out.update(dt_s=dt, fibre_m=ref_cfg.discretization.fibre_segment_m,
               n_nodes=int(sum(ln.n_seg - 1 for ln in built["lines"]) + len(built["free_points"])))
    runs = []
    for _ in range(REPEATS):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = run_moordyn_drop(ref_cfg, dt_s=dt, scheme="rk4", segment_length_m=seg, static=static,
                                     damping_ratio=0.0)
        except SimulationDiverged as exc:
            out.update(status="diverged", message=str(exc))
            return out
        runs.append(r)
        if r["wall_s"] > FAST_S or r["touchdown_speed_m_s"] is None:
            break
    best = min(runs, key=lambda x: x["wall_s"])
    if best["touchdown_speed_m_s"] is None:
        out.update(status="no touchdown")
        return out
    out.update(status="ok", speed=best["touchdown_speed_m_s"], tilt=best["tilt_deg"], time=best["touchdown_time_s"],
               drift=best["drift_m"], n_steps=best["n_steps"], wall_s=best["wall_s"],
               wall_all=[r["wall_s"] for r in runs], n_repeats=len(runs))
    return out


def node_scaling_cases(mode: str) -> list[dict[str, Any]]:
    """deep-1500 with the wire kept, release to touchdown, chain s / fibre 5 s / wire 10 s, fixed steps. (The
    whole fall, not a fixed time: ``run_drop`` loops for ever when ``max_fall_time_s`` ends between two steps.)"""
    levels = [4.0, 2.0, 1.0, 0.5, 0.25] if mode == "full" else [4.0, 2.0, 1.0, 0.5]
    finest = levels[-1]
    cases = []
    for s in levels:
        common = dict(uniform(s), **{"installation.components.keep_wire_after_release": True})
        cases.append({"series": "implicit, fixed dt", "s": s,
                      "overrides": dict(common, integrator=IMPL, _fixed_dt_from=finest)})
        cases.append({"series": "explicit, fixed dt", "s": s,
                      "overrides": dict(common, integrator=SE, _fixed_dt_from=finest)})
        cases.append({"series": "explicit, dt at its stability limit", "s": s,
                      "overrides": dict(common, integrator=SE)})
        cases.append({"series": "implicit, fixed dt, hanging (3 s before release)", "s": s,
                      "overrides": dict(common, integrator=IMPL, _fixed_dt_from=finest, _hanging=True)})
    return cases


def run_scaling(case: dict[str, Any]) -> dict[str, Any]:
    """Cost per simulated second of one node-scaling case (best of 3 when fast)."""
    spec = SCENES["deep-1500"]
    ov = dict(case["overrides"])
    finest = ov.pop("_fixed_dt_from", None)
    hanging = ov.pop("_hanging", False)
    if finest is not None:  # the finest level's default step, for every level of the series
        fine_ov = dict(ov, **uniform(finest))
        ov["dt_s"] = compile_scene(load_scene(spec["scene"], {**spec["overrides"], **fine_ov})).dt_s
    cfg = scene_config(spec, ov)
    model = compile_scene(cfg)
    static = statics_for(cfg)
    if hanging:  # the hanging system, no release: no segment goes slack, one implicit solve per step
        walls, cpus = [], []
        for _ in range(REPEATS):
            sim = copy.deepcopy(static.simulator)
            sim.model, sim.dt, sim.integrator_code = model, model.dt_s, _CODES[model.integrator]
            sim.set_vessel_motion(0.0, 5.0, np.zeros(sim.vessel_mean_m.shape[0]))
            sim.advance_to(model.dt_s)
            t0, c0 = time.perf_counter(), time.process_time()
            _, n = sim.advance_to(3.0)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        t_sim = n * model.dt_s
        nodes = int(np.sum(sim.state.node_i[:, LY.NI_KIND] != LY.NODE_INACTIVE))
        return {"series": case["series"], "s": case["s"], "status": "ok", "n_nodes": nodes, "n_steps": n,
                "dt_s": model.dt_s, "t_sim_s": t_sim, "wall_s": min(walls), "cpu_s": min(cpus),
                "wall_per_sim_s": min(walls) / t_sim, "cpu_per_sim_s": min(cpus) / t_sim,
                "wall_static_s": static.wall_static_s}
    runs = _timed(static, model)
    best = min(runs, key=lambda x: x[0].wall_dynamic_s)[0]
    t_sim = best.n_steps * best.dt_s
    cpu = min(c for _, c in runs)
    return {"series": case["series"], "s": case["s"], "status": "ok", "n_nodes": best.n_nodes,
            "n_steps": best.n_steps, "dt_s": best.dt_s, "t_sim_s": t_sim, "wall_s": best.wall_dynamic_s,
            "cpu_s": cpu, "wall_per_sim_s": best.wall_dynamic_s / t_sim, "cpu_per_sim_s": cpu / t_sim,
            "wall_static_s": static.wall_static_s}


# --- analysis ------------------------------------------------------------------------------------------------
def add_errors(runs: list[dict[str, Any]], ref: dict[str, Any]) -> None:
    """Errors against the reference run (in place)."""
    for r in runs:
        if r.get("status") != "ok":
            continue
        r["speed_err_pct"] = 100.0 * (r["speed"] / ref["speed"] - 1.0)
        r["tilt_err_deg"] = r["tilt"] - ref["tilt"]
        r["time_err_ms"] = 1000.0 * (r["time"] - ref["time"])
        r["drift_err_m"] = r["drift"] - ref["drift"]


def pareto(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Cost-error front: by increasing cost, each point more accurate than every cheaper one."""
    front: list[tuple[float, float]] = []
    for cost, err in sorted(points):
        if not front or err < front[-1][1]:
            front.append((cost, err))
    return front


def cost_at(front: list[tuple[float, float]], err: float) -> dict[str, float | None]:
    """Cost to reach ``err`` on a front: the cheapest measured run at or below it (``measured``) and the log-log
    interpolation between the two front points around it (``interpolated``); None if never reached."""
    reach = [c for c, e in front if e <= err]
    if not reach:
        return {"measured": None, "interpolated": None}
    measured = min(reach)
    interp = measured
    for (c1, e1), (c2, e2) in zip(front, front[1:], strict=False):
        if e2 <= err < e1:
            lo1, lo2 = math.log(max(e1, 1e-9)), math.log(max(e2, 1e-9))
            w = (math.log(max(err, 1e-9)) - lo1) / (lo2 - lo1)
            interp = math.exp(math.log(c1) + w * (math.log(c2) - math.log(c1)))
            break
    return {"measured": measured, "interpolated": interp}


def metric_front(runs: list[dict[str, Any]], key: str, floor: float) -> list[tuple[float, float]]:
    """Front of |key| against wall time (errors below ``floor`` are shown at ``floor``); the reference run
    itself (error 0 by definition) is left out."""
    return pareto([(r["wall_s"], max(abs(r[key]), floor)) for r in runs
                   if r.get("status") == "ok" and not r.get("is_reference")])


def fmt(x: Any, spec: str = ".3g", none: str = "-") -> str:
    """Format a number or a dash."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return none
    return format(x, spec)


# --- plots and markdown --------------------------------------------------------------------------------------
INTEG_STYLE = {SE: ("tab:blue", "symplectic Euler"), "rk2": ("tab:cyan", "RK2"), IMPL: ("tab:orange", "implicit Euler")}


def plot_scene(name: str, data: dict[str, Any], path: Path) -> None:
    """Pareto plot of one scene: speed error and tilt (error or value) against wall time, both codes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ours = [r for r in data["ours"] if r.get("status") == "ok" and not r.get("is_reference")]
    md = [r for r in data["moordyn"] if r.get("status") == "ok"]
    small = data["tilt_small"]
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 5.0))
    for ax, key, floor, label in ((axes[0], "speed_err_pct", 1e-3, "|touchdown speed error| [%]"),
                                  (axes[1], "tilt_err_deg", 1e-3, "|tilt error| [deg]")):
        if key == "tilt_err_deg" and small:
            label = "tilt [deg] (reference tilt small: spread, not error)"
        for integ, (color, lab) in INTEG_STYLE.items():
            pts = [r for r in ours if r["integrator"] == integ]
            if not pts:
                continue
            ys = [r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor) for r in pts]
            ax.scatter([r["wall_s"] for r in pts], ys, s=22, color=color, label=f"ours, {lab}", zorder=3,
                       edgecolor="k", linewidth=0.3)
        presets = [r for r in ours if r["family"] == "preset"]
        for r in presets:
            y = r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor)
            ax.annotate(r["label"].replace("preset ", ""), (r["wall_s"], y), fontsize=8, xytext=(4, 4),
                        textcoords="offset points")
        if md:
            ys = [r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor) for r in md]
            ax.scatter([r["wall_s"] for r in md], ys, s=30, marker="s", color="tab:green", label="MoorDyn RK4",
                       zorder=3, edgecolor="k", linewidth=0.3)
        if not (key == "tilt_err_deg" and small):
            for rows, color in ((ours, "tab:red"), (md, "tab:green")):
                fr = metric_front(rows, key, floor)
                if fr:
                    xs, ys = [], []
                    for c, e in fr:  # staircase
                        if xs:
                            xs.append(c)
                            ys.append(ys[-1])
                        xs.append(c)
                        ys.append(e)
                    ax.plot(xs, ys, color=color, lw=1.2, zorder=2,
                            label="front, ours" if color == "tab:red" else "front, MoorDyn")
            ax.set_yscale("log")
            target = 1.0 if key == "speed_err_pct" else 0.3
            ax.axhline(target, color="gray", ls=":", lw=1)
            conv = abs(data["check"][key])
            if conv > floor:
                ax.axhline(conv, color="tab:purple", ls="--", lw=0.8,
                           label=f"reference vs next-coarser level ({conv:.2g})")
        ax.set_xscale("log")
        ax.set_xlabel("wall time of the dynamic run [s] (best of 3 when < 1 s)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, loc="best")
    if not small:
        axes[1].legend(fontsize=8, loc="best")
    ref = data["reference"]
    fig.suptitle(f"{name}: {SCENES[name]['about']}\nreference: explicit, chain {ref['chain_m']:g} m "
                 f"({ref['speed']:.3f} m/s, tilt {ref['tilt']:.2f} deg)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_nodes(scaling: dict[str, Any], path: Path) -> None:
    """Cost per simulated second against line nodes, log-log, with fitted slopes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    colors = {"implicit, fixed dt": "tab:orange", "explicit, fixed dt": "tab:blue",
              "explicit, dt at its stability limit": "tab:gray",
              "implicit, fixed dt, hanging (3 s before release)": "tab:brown"}
    for series, info in scaling["series"].items():
        n = np.array(info["n_nodes"], float)
        c = np.array(info["cpu_per_sim_s"], float)
        ax.loglog(n, c, "o-", color=colors.get(series, "k"),
                  label=f"{series} ({fmt(info['dt_s'], '.3g')} s): slope {info['slope']:.2f}"
                  + (f", {info['slope_upper']:.2f} on the 3 largest" if info.get("slope_upper") is not None else ""))
    ax.set_xlabel("line nodes")
    ax.set_ylabel("CPU time per simulated second [s]")
    ax.set_title("deep-1500, wire kept, release to touchdown: chain s, fibre 5 s, wire 10 s", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def settings_of(r: dict[str, Any]) -> str:
    """Short settings column of one run."""
    if r["code"] == "moordyn":
        return f"chain {r['chain_m']:g} / fibre {r['fibre_m']:g} m"
    if "vertical_m" not in r:
        return "-"
    extra = []
    if r.get("keep_wire"):
        extra.append("wire kept")
    return f"{r['vertical_m']:g}/{r['loop_m']:g}/{r['fibre_m']:g}/{r['wire_m']:g}" + (
        " " + ", ".join(extra) if extra else "")


def fit_check_table(rows: list[dict[str, Any]]) -> list[str]:
    """The fit check: both ``fast`` resolutions and the preset's choice around the fit's bounds."""
    if not rows:
        return []
    L = ["## Fit check: where `fast` needs its fine loop chain", "",
         f"Geometries around the bounds of `fast`'s `tight_line` rule (calm, no waves), each against explicit "
         f"{FIT_REFERENCE_C:g} m chain (which differs from {FIT_REFERENCE_C / 2:g} m by the `ref. check` column where "
         "run). Touchdown-speed errors of the coarse (slack-line) and fine (tight-line) resolutions and of the "
         "preset itself, which picks one of them from the slack and chord angle.", "",
         "| scene | geometry | slack, chord angle | reference [m/s] | ref. check | slack-line branch | "
         "tight-line branch | fast picks | fast: error, CPU |", "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        ref, runs = row["reference"], row["runs"]
        chk = row.get("reference_check")
        chk_txt = (f"{100.0 * (chk['speed'] / ref['speed'] - 1.0):+.2f} %"
                   if chk and chk.get("status") == "ok" and ref.get("status") == "ok" else "")
        errs = {k: (f"{r['speed_err_pct']:+.2f} %" if "speed_err_pct" in r else r.get("status", "-"))
                for k, r in runs.items()}
        fast = runs["preset"]
        picks = "tight-line" if fast.get("loop_m") == runs["tight-line"].get("loop_m") else "slack-line"
        geo = ", ".join(f"{k.replace('_m', '')} {v:g} m" for k, v in row["geometry"].items())
        L.append(f"| {row['scene']} | {geo} | {slack_text(row['line_slack'])} | {fmt(ref.get('speed'), '.3f')} | "
                 f"{chk_txt} | {errs['slack-line']} | {errs['tight-line']} | {picks} | {errs['preset']}, "
                 f"{fmt(fast.get('cpu_s') and fast['cpu_s'] * 1e3, '.3g')} ms |")
    misses = [f"{row['scene']} {slack_text(row['line_slack'])} ({row['runs']['preset']['speed_err_pct']:+.2f} %)"
              for row in rows if abs(row["runs"]["preset"].get("speed_err_pct", 0.0)) > 3.0]
    L += ["", "Where `fast` misses 3 % here: " + ("; ".join(misses) if misses else "nowhere") + ". (Where the loop "
          "snaps taut in the last moments of the fall, the touchdown speed jumps with the snap's timing.)", ""]
    return L


def slack_text(line_slack: list[float] | None) -> str:
    """``slack m, angle deg`` of the mooring line at touchdown, or a dash."""
    return "-" if line_slack is None else f"{line_slack[0]:.1f} m, {line_slack[1]:.1f} deg"


def ratio_bound_note(row: dict[str, Any]) -> str:
    """Where MoorDyn never reached the error: its best error, and the ratio as a lower bound."""
    if row.get("ratio_lower_bound") is None:
        return ""
    best = row["moordyn_best"]
    return (f"; MoorDyn not reached (its best {best['error']:.3g} at {best['cost']:.3g} s): "
            f"MoorDyn/ours > {row['ratio_lower_bound']:.1f}x")


def _run(data: dict[str, Any], label: str) -> dict[str, Any] | None:
    """The run of a scene with this label (ours or MoorDyn), if it succeeded."""
    for r in data["ours"] + data["moordyn"]:
        if r["label"] == label and r.get("status") == "ok":
            return r
    return None


def preset_findings(sc: dict[str, Any]) -> list[str]:
    """The presets against the targets for ``fast`` (3 % speed, 0.5 deg tilt where large, 10 ms CPU on
    gjoa-500)."""
    rows = []
    for name, data in sc.items():
        parts = []
        for label in ("preset fast", "preset default", "preset accurate"):
            r = _run(data, label)
            if r is None:
                continue
            tilt = "" if data["tilt_small"] else f", tilt {r['tilt_err_deg']:+.2f} deg"
            cpu = f"{r['cpu_s'] * 1e3:.3g} ms" if r["cpu_s"] < 1.0 else f"{r['cpu_s']:.3g} s"
            parts.append(f"{label.replace('preset ', '')} {r['speed_err_pct']:+.2f} %{tilt} at {cpu} CPU")
        fast = _run(data, "preset fast")
        branch = ""
        if fast and fast.get("line_slack") is not None:
            branch = f" (slack {slack_text(fast['line_slack'])}: fast {settings_of(fast)})"
        rows.append(f"{name}{branch}: " + ", ".join(parts))
    return ["- **Presets** (CPU of the dynamic run): " + "; ".join(rows) + ". `fast` on a slack line uses its "
            "coarse resolution (the loop chain hardly moves during the fall), where the line tightens its "
            "`tight_line` one (the loop chain carries the tilt and the snap there, see `near and far` below and "
            "the `fast, ... branch` rows of the preset table: the coarse branch is 4-5 % slow on `wide` and `snap`)."
            " On `current-waves` every preset's error is a spread, not a discretization error (below). The "
            "fit check table shows where the coarse branch fails (a coarse loop goes taut too early, 4-9 % slow) "
            "and that the rule's bounds keep `fast` on the fine one there."]


def moordyn_findings(out: dict[str, Any]) -> list[str]:
    """The two equal-error targets (1 % speed on gjoa-500, 0.3 deg tilt on wide) in words."""
    lines = []
    for row in out["equal_error"]:
        target = (row["scene"], row["metric"].split()[0], row["error"])
        if target not in (("gjoa-500", "speed", 1.0), ("wide", "tilt", 0.3)):
            continue
        what = f"{row['metric'].split()[0]} error <= {row['error']:g} on {row['scene']}"
        if row["ratio_measured"] is not None:
            lines.append(f"{what}: MoorDyn/ours {row['ratio_measured']:.1f}x (measured), "
                         f"{fmt(row['ratio_interpolated'], '.1f')}x (interpolated)")
        elif row.get("ratio_lower_bound") is not None:
            best = row["moordyn_best"]
            lines.append(f"{what}: MoorDyn's sweep never got there (its best {best['error']:.2f} at "
                         f"{best['cost']:.3g} s), so MoorDyn/ours > {row['ratio_lower_bound']:.1f}x, a lower bound "
                         f"taken at its most accurate run against our cheapest run at the target "
                         f"({row['ours']['measured']:.3g} s)")
        else:
            lines.append(f"{what}: not reached by our runs")
    if not lines:
        return []
    return ["- **Equal error against MoorDyn** (same run, same machine): " + "; ".join(lines)
            + ". On `wide` the reference itself moves by the `wide` check difference between its two finest levels "
            "(see References), which is larger than 0.3 deg: a 0.3 deg tilt error there is within the "
            "reference's own uncertainty."]


def findings(out: dict[str, Any]) -> list[str]:
    """The summary section: numbers pulled from the results, the reading of them in words."""
    sc = out["scenes"]
    L = ["## Findings", ""]
    conv = []
    for name, data in sc.items():
        chk = data["check"]
        ok = abs(chk["speed_err_pct"]) < 0.3 and abs(chk["tilt_err_deg"]) < 0.1
        conv.append(f"{name} {'converged' if ok else 'NOT converged'} ({chk['speed_err_pct']:+.2f} %, "
                    f"{chk['tilt_err_deg']:+.2f} deg between chain {chk['chain_m']:g} m and "
                    f"{data['reference']['chain_m']:g} m)")
    L.append("- **References.** " + "; ".join(conv) + ". Converged means within 0.3 % and 0.1 deg.")
    if "wide" in sc:
        lad = [r for r in sc["wide"]["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        L.append("- **The wide case's tilt does not converge with resolution**: over chain "
                 + ", ".join(f"{r['vertical_m']:g}" for r in lad) + " m it is "
                 + ", ".join(f"{r['tilt']:.2f}" for r in lad) + " deg and the speed "
                 + ", ".join(f"{r['speed']:.2f}" for r in lad) + " m/s (explicit at its stability limit; halving "
                 "the reference's step moves it by less, see below). Below about 0.5 m the slack loop folds at the "
                 "segment scale (a 142 mm chain link is about 0.85 m long, and a lumped line has no bending "
                 "stiffness), so the finest level is a reference with that uncertainty, not a converged answer; "
                 "errors on this scene below the difference of its two finest levels are not meaningful.")
    if "current-waves" in sc:
        d = sc["current-waves"]
        sp = d["speed_spread"]
        lad = [r for r in d["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        L.append(f"- **current-waves is not converged either**: its touchdown speed ranges over "
                 f"{sp['ladder'][0]:.2f} .. {sp['ladder'][1]:.2f} m/s on the reference ladder ("
                 + ", ".join(f"{r['speed']:.2f}" for r in lad) + " m/s at chain "
                 + ", ".join(f"{r['vertical_m']:g}" for r in lad) + " m) and "
                 f"{sp['ours'][0]:.2f} .. {sp['ours'][1]:.2f} m/s over all runs, tilt "
                 f"{d['tilt_spread']['ours'][0]:.2f} .. {d['tilt_spread']['ours'][1]:.2f} deg. Two things move it: the "
                 "loop chain's resolution (the ladder rises by 2-4 % per halving, and the coarse `fast` branch "
                 "sits with the 2 m level), and, with the current pushing the loop, where the slack chain ends up "
                 "on the anchor, which switches between outcomes (about 26.3 m/s and 0.2 deg, or about 25.2 m/s and "
                 "1.2-1.6 deg) with small differences in time step or integrator (the explicit time step is "
                 "converged at 1 m, see the rk2 and dt x0.5 rows; implicit 1 m reaches the reference only at a "
                 "tenth of its step). Errors on this scene are spreads, not discretization errors: no `fast` "
                 "setting measured here comes within 3 % of the 1 m reference, and the reference itself is 5 % "
                 "from its next-coarser level.")
    L += preset_findings(sc) + moordyn_findings(out)
    # components
    comp = []
    for name, data in sc.items():
        base_e = _run(data, "explicit c=1 m")
        kept = _run(data, "explicit 1 m, wire kept after release")
        pre = _run(data, "explicit 1 m, 10 s pre-release dynamics (calm)")
        stat = _run(data, "explicit 1 m, release from statics (no wave phase)")
        if base_e and kept:
            comp.append(f"{name}: keeping the wire {kept['speed_err_pct'] - base_e['speed_err_pct']:+.3f} % "
                        f"speed at {kept['cpu_s'] / base_e['cpu_s']:.2f}x the CPU time")
        if base_e and pre:
            diff = pre["speed_err_pct"] - base_e["speed_err_pct"]
            comp.append(f"{name}: 10 s of calm pre-release dynamics {diff:+.3f} % at "
                        f"{pre['cpu_s'] / base_e['cpu_s']:.1f}x")
        if base_e and stat:
            comp.append(f"{name}: releasing from statics instead of after 20 s of waves "
                        f"{stat['speed_err_pct'] - base_e['speed_err_pct']:+.2f} % and "
                        f"{stat['tilt_err_deg'] - base_e['tilt_err_deg']:+.2f} deg")
    if comp:
        L.append("- **Components** (explicit, 1 m chain; differences to the same run without the component): "
                 + "; ".join(comp) + ". The cut wire and calm pre-release dynamics change nothing measurable and "
                 "are left out by default (the wire is dropped at release; pre-release dynamics run only when "
                 "`release_time_s` > 0); with waves the pre-release dynamics decide the outcome.")
    near = []
    for name in ("wide", "snap", "gjoa-500"):
        if name not in sc:
            continue
        d = sc[name]
        parts = []
        for lab in ("implicit vertical 5 m", "implicit loop 4 m", "implicit fibre 200 m"):
            r, b = _run(d, lab), _run(d, "implicit 1/1/5/10, dt x1")
            if r and b:
                parts.append(f"{lab.replace('implicit ', '')} {r['speed_err_pct'] - b['speed_err_pct']:+.2f} % / "
                             f"{r['tilt_err_deg'] - b['tilt_err_deg']:+.2f} deg")
        if parts:
            near.append(f"{name}: " + ", ".join(parts))
    if near:
        L.append("- **Near and far** (implicit, one line coarsened from 1/1/5/10 m; change of speed error / tilt "
                 "error): " + "; ".join(near) + ". The loop chain next to the vertical chain carries the snap and "
                 "the tilt; the vertical chain and the fibre (far) can be coarse.")
    sc_nodes = out["node_scaling"]["series"]
    if sc_nodes:
        L.append("- **Node scaling** (deep-1500): log-log slopes of CPU time per simulated second against nodes: "
                 + "; ".join(f"{k} {v['slope']:.2f}" + (f" ({v['slope_upper']:.2f} on the 3 largest)"
                                                         if v.get("slope_upper") is not None else "")
                             for k, v in sc_nodes.items())
                 + ". At a fixed step the explicit cost is linear; the implicit cost is linear while the line hangs "
                 "(one solve per step) and grows faster during the fall because the active-set iteration "
                 "(`implicit.MAX_ACTIVE_SET_SOLVES` = 8) re-solves whenever a segment goes slack or taut within "
                 "the step, which happens more often the more segments there are (bounded: at most 8 O(N) solves "
                 "per step). The explicit cost at its own stability limit grows as N^2 (the step shrinks with "
                 "the segment).")
    stat_costs = []
    for name, data in sc.items():
        lad = [r for r in data["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        if lad:
            stat_costs.append(f"{name} " + ", ".join(f"{r['wall_static_s']:.1f}" for r in lad))
    L.append("- **Statics** (not in the cost above; seconds over the ladder levels): " + "; ".join(stat_costs)
             + ". Under current the static solve costs far more than the fall. At some resolutions it stalls: "
             "on `wide`, 0.18 m chain had not finished after 60 s (0.125 m: under 1 s) and 0.0625 m chain not "
             "after 15 minutes; hence ladders of powers of two.")
    L.append("")
    return L


def spread_cells(spread: dict[str, Any], unit: str) -> str:
    """Table cells ``ladder | all our runs | MoorDyn's runs |`` of a spread (ranges)."""
    cells = [f"{spread[k][0]:.2f} .. {spread[k][1]:.2f}{unit}" if spread.get(k) else "-"
             for k in ("ladder", "ours", "moordyn")]
    return " | ".join(cells) + " |"


def markdown(out: dict[str, Any]) -> str:
    """docs/speed_vs_error.md from the study's results."""
    L: list[str] = []
    mode = out["mode"]
    L += ["# Speed against error", "",
          f"Written by `python benchmarks/speed_vs_error.py{' --full' if mode == 'full' else ''}` "
          f"({mode} mode) on {out['measured_on']}, {out['date']}; load average (1 min) "
          f"{fmt(out['load_average_1min']['before'], '.2f')} before, {fmt(out['load_average_1min']['after'], '.2f')} "
          f"after; {out['wall_total_s'] / 60:.1f} min in all. Raw results: `{out['json']}`. Absolute times are "
          "those of this machine; the ratios carry over. The machine is shared: a wall time also counts other jobs' "
          "share of it when the load is above its core count, so our CPU time (listed beside it) is the steadier "
          "measure of our cost; ratios to MoorDyn compare wall times taken in the same run.", "",
          "Cost is the wall time of the dynamic run (pre-release phase if any, release, fall to touchdown), best "
          f"of {REPEATS} for runs under {FAST_S:g} s; statics are excluded for both codes (MoorDyn starts from our "
          "equilibrium; ours are listed per run as `statics`). Errors are against the reference (the finest "
          "explicit level of each scene's ladder): touchdown speed (relative), tilt, touchdown time and drift. "
          "Element lengths are written vertical chain / loop chain / fibre / wire [m] (near to far from the "
          "anchor). MoorDyn runs RK4 with line damping off (see `moor_env/crosscheck/moordyn.py`), with "
          "dt as a fraction of its RK4 limit 2.83/omega_max; the `current-waves` scene is not supported by the "
          "MoorDyn bridge (no current, waves or pre-release phase), so it has no MoorDyn front. Ours runs each "
          "scene's line-anchor contact as its `discretization.line_anchor_contact: auto` sets it (on in every "
          "scene here: their chain catches up with the anchor), MoorDyn has none. Both start from the equilibrium "
          "as solved, whose vertical chain hangs exactly on the anchor's axis: where that chain catches up, a "
          "disturbance of it changes the landing (see [fall-accuracy.md](fall-accuracy.md)).", ""]
    L += findings(out)
    # references
    L += ["## References and their convergence", "",
          "| scene | reference (explicit) | speed [m/s] | tilt [deg] | time [s] | drift [m] | next-coarser level | "
          "speed diff | tilt diff | time diff | drift diff | ref. wall |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        ref, chk = data["reference"], data["check"]
        L.append(f"| {name} | chain {ref['chain_m']:g} m, dt {ref['dt_s'] * 1e3:.3g} ms | {ref['speed']:.3f} | "
                 f"{ref['tilt']:.2f} | {ref['time']:.4f} | {ref['drift']:.3f} | chain {chk['chain_m']:g} m | "
                 f"{chk['speed_err_pct']:+.2f} % | {chk['tilt_err_deg']:+.2f} deg | {chk['time_err_ms']:+.1f} ms | "
                 f"{chk['drift_err_m']:+.3f} m | {ref['wall_s']:.1f} s |")
    L.append("")
    for name, data in out["scenes"].items():
        if data.get("dt_check"):
            d = data["dt_check"]
            L.append(f"- {name}: the reference at half its time step differs by {d['speed_err_pct']:+.3f} % in "
                     f"speed and {d['tilt_err_deg']:+.3f} deg in tilt.")
    L.append("")
    # tilt spread where small
    L += ["## Spread of the touchdown speed", "",
          "Range of the touchdown speed over the reference ladder, over all our runs and over MoorDyn's runs.", "",
          "| scene | reference | ours: ladder | ours: all runs | MoorDyn: all runs |", "|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        L.append(f"| {name} | {data['reference']['speed']:.3f} m/s | {spread_cells(data['speed_spread'], '')}")
    L.append("")
    L += ["## Tilt where it is small: spread across resolutions", "",
          "| scene | reference tilt | ours: range over the reference ladder | ours: range over all runs | "
          "MoorDyn: range over its runs |", "|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        if data["tilt_small"]:
            L.append(f"| {name} | {data['reference']['tilt']:.2f} deg | {spread_cells(data['tilt_spread'], ' deg')}")
    L.append("")
    # equal-error ratios
    L += ["## Ours against MoorDyn at equal error", "",
          "Cost to reach an error on each code's measured front: `measured` is the cheapest run at or below that "
          "error, `interp.` interpolates log-log between the two front points around it.", "",
          "| scene | error | ours measured | ours interp. | MoorDyn measured | MoorDyn interp. | "
          "MoorDyn / ours (measured) | MoorDyn / ours (interp.) | MoorDyn not reached: its best, ratio bound |",
          "|---|---|---|---|---|---|---|---|---|"]
    for row in out["equal_error"]:
        best = row.get("moordyn_best")
        bound = (f"{best['error']:.3g} at {best['cost']:.3g} s: > {row['ratio_lower_bound']:.1f}x" if best else "")
        L.append(f"| {row['scene']} | {row['metric']} <= {row['error']:g} | {fmt(row['ours']['measured'], '.3g')} s | "
                 f"{fmt(row['ours']['interpolated'], '.3g')} s | {fmt(row['moordyn']['measured'], '.3g')} s | "
                 f"{fmt(row['moordyn']['interpolated'], '.3g')} s | {fmt(row['ratio_measured'], '.1f')}x | "
                 f"{fmt(row['ratio_interpolated'], '.1f')}x | {bound} |")
    L.append("")
    # presets
    L += ["## Fidelity presets (configs/fidelity.yaml) on every scene", "",
          "`fast` fits the scene: its `tight_line` resolution applies where the mooring line's slack at touchdown "
          "(`moor_env.config.mooring_line_slack`: free line length minus the chord from the release point, "
          "vertical chain straight above the touched-down anchor, to the second vessel) is below its "
          "`slack_below_m` or that chord is further than `chord_angle_above_deg` from the vertical (see the fit "
          "check below); the rows `fast, ... branch` run both of its resolutions on every scene.", "",
          "| scene | preset | slack, chord angle | settings | integrator | dt [ms] | nodes | wall [ms] | CPU [ms] | "
          "statics [s] | speed err | tilt (err) | time err | drift err |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, data in out["scenes"].items():
        for r in data["ours"]:
            if r["family"] not in ("preset", "preset branches") or r.get("status") != "ok":
                continue
            tilt = f"{r['tilt']:.2f} deg" if data["tilt_small"] else f"{r['tilt_err_deg']:+.2f} deg"
            L.append(f"| {name} | {r['label'].replace('preset ', '')} | {slack_text(r.get('line_slack'))} | "
                     f"{settings_of(r)} | {r['integrator']} | "
                     f"{r['dt_s'] * 1e3:.3g} | {r['n_nodes']} | {r['wall_s'] * 1e3:.1f} | {r['cpu_s'] * 1e3:.1f} | "
                     f"{r['wall_static_s']:.2f} | {r['speed_err_pct']:+.2f} % | {tilt} | {r['time_err_ms']:+.1f} ms | "
                     f"{r['drift_err_m']:+.3f} m |")
    L.append("")
    L += fit_check_table(out.get("fit_check", []))
    # node scaling
    sc = out["node_scaling"]
    L += ["## Cost per simulated second against line nodes", "",
          "![node scaling](speed_vs_error_nodes.png)", "",
          "deep-1500 with the wire kept after release, release to touchdown, chain s / fibre 5 s / wire 10 s refined "
          "together; `fixed dt` series run every level at the finest level's default step (fixed temporal "
          "accuracy), the last series at each level's own explicit stability limit (which shrinks with the "
          "chain segment).", "",
          "| series | dt [ms] | nodes | CPU per simulated s [s] | fitted slope (all) | slope (3 largest) |",
          "|---|---|---|---|---|---|"]
    for series, info in sc["series"].items():
        L.append(f"| {series} | {fmt(info['dt_s'] * 1e3 if info['dt_s'] else None, '.3g')} | "
                 f"{', '.join(str(n) for n in info['n_nodes'])} | "
                 f"{', '.join(fmt(c, '.3g') for c in info['cpu_per_sim_s'])} | {info['slope']:.2f} | "
                 f"{fmt(info.get('slope_upper'), '.2f')} |")
    L.append("")
    # per scene tables
    for name, data in out["scenes"].items():
        L += [f"## {name}: {SCENES[name]['about']}", "", f"![{name}](speed_vs_error_{name}.png)", ""]
        fo = {tuple(p) for p in data["front_ours_speed"]}
        fm = {tuple(p) for p in data["front_moordyn_speed"]}
        L += ["Rows by cost; * marks the speed-error front of each code.", "",
              "| code | family | run | settings | dt [ms] | nodes | wall [ms] | CPU [ms] | speed err | "
              + ("tilt" if data["tilt_small"] else "tilt err") + " | time err | drift err |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        rows = [r for r in data["ours"] + data["moordyn"]]
        rows.sort(key=lambda r: r.get("wall_s", math.inf))
        for r in rows:
            if r.get("status") != "ok":
                dt = r.get("dt_s")
                L.append(f"| {r['code']} | {r['family']} | {r['label']} | {settings_of(r)} | "
                         f"{fmt(dt * 1e3 if dt else None, '.3g')} | - | - | - | {r['status']} | | | |")
                continue
            front = (r["wall_s"], max(abs(r["speed_err_pct"]), 1e-3)) in (fo if r["code"] == "ours" else fm)
            tilt = f"{r['tilt']:.2f}" if data["tilt_small"] else f"{r['tilt_err_deg']:+.2f}"
            L.append(f"| {r['code']}{' *' if front else ''} | {r['family']} | {r['label']} | {settings_of(r)} | "
                     f"{r['dt_s'] * 1e3:.3g} | {r.get('n_nodes', '-')} | {r['wall_s'] * 1e3:.1f} | "
                     f"{fmt(r.get('cpu_s') and r['cpu_s'] * 1e3, '.1f')} | {r['speed_err_pct']:+.2f} % | {tilt} | "
                     f"{r['time_err_ms']:+.1f} | {r['drift_err_m']:+.3f} |")
        L.append("")
    return "\n".join(L) + "\n"


def write_docs(out: dict[str, Any]) -> None:
    """Pareto plots, the node-scaling plot and docs/speed_vs_error.md from the results."""
    DOCS.mkdir(exist_ok=True)
    for s, data in out["scenes"].items():
        plot_scene(s, data, DOCS / f"speed_vs_error_{s}.png")
    if out["node_scaling"]["series"]:
        plot_nodes(out["node_scaling"], DOCS / "speed_vs_error_nodes.png")
    (DOCS / "speed_vs_error.md").write_text(markdown(out))


README = ROOT / "README.md"


def docs_blocks(out: dict[str, Any]) -> list[tuple[Path, str, str]]:
    """The README's headline line from the study's results (the whole of docs/speed_vs_error.md is
    :func:`markdown`)."""
    parts = []
    fast = _run(out["scenes"]["gjoa-500"], "preset fast") if "gjoa-500" in out["scenes"] else None
    if fast is not None:
        parts.append(f"the `fast` preset lands the gjoa-500 fall within {fast['speed_err_pct']:+.2f} % of the "
                     f"converged reference in {fast['cpu_s'] * 1e3:.1f} ms CPU")
    for row in out["equal_error"]:
        if (row["scene"], row["metric"].split()[0], row["error"]) == ("gjoa-500", "speed", 1.0) \
                and row["ratio_measured"] is not None:
            parts.append(f"at {row['error']:g} % speed error MoorDyn takes {row['ratio_measured']:.0f}x our "
                         "wall time")
    mode = "" if out.get("mode") == "full" else " --quick"
    text = ("**Speed against error**: " + "; ".join(parts) + f". `python benchmarks/speed_vs_error.py{mode}`, run "
            f"{str(out['date'])[:10]}: [docs/speed_vs_error.md](docs/speed_vs_error.md).")
    return [(README, "headline-speed_vs_error", text)]


def results_for_docs(full: bool = False) -> dict[str, Any]:
    """The committed results (quick unless ``full``), with the node-scaling slopes the docs read."""
    out = load_result("speed_vs_error" if full else "speed_vs_error_quick")
    fit_slopes(out["node_scaling"]["series"])
    return out


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/speed_vs_error_quick.json``."""
    return docs_blocks(results_for_docs())


def fit_slopes(series: dict[str, Any]) -> None:
    """Log-log slopes of CPU time per simulated second against nodes (all levels, and the 3 largest), in place.
    CPU rather than wall time: on a shared machine the wall time also counts the other jobs' share."""
    for info in series.values():
        n, c = np.log(info["n_nodes"]), np.log(info["cpu_per_sim_s"])
        info["slope"] = float(np.polyfit(n, c, 1)[0]) if len(n) >= 2 else None
        order = np.argsort(n)[-3:]
        info["slope_upper"] = float(np.polyfit(n[order], c[order], 1)[0]) if len(n) >= 3 else None
        dts = set(info["dt_s_each"])
        info["dt_s"] = dts.pop() if len(dts) == 1 else None


# --- main ----------------------------------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--quick", action="store_true", help="fewer knob levels (default; a few minutes)")
    group.add_argument("--full", action="store_true", help="every knob level")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of " + ", ".join(SCENES))
    parser.add_argument("--no-moordyn", action="store_true", help="skip the MoorDyn runs")
    parser.add_argument("--no-docs", action="store_true", help="do not write docs/ (JSON only)")
    parser.add_argument("-v", "--verbose", action="store_true", help="one line per run")
    parser.add_argument("--report-only", metavar="JSON", help="rewrite docs/ from a results file, no runs")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite docs/speed_vs_error.md and the README's headline from the committed "
                             "benchmarks/results/speed_vs_error[_quick].json (no plots, no runs)")
    args = parser.parse_args(argv)
    if args.docs_only:
        out = results_for_docs(args.full)
        (DOCS / "speed_vs_error.md").write_text(markdown(out))
        write_blocks(docs_blocks(out))
        return out
    if args.report_only:
        out = json.loads(Path(args.report_only).read_text())
        fit_slopes(out["node_scaling"]["series"])
        write_docs(out)
        write_blocks(docs_blocks(out))
        return out
    mode = "full" if args.full else "quick"
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in SCENES:
            parser.error(f"unknown scene {s!r}: one of {', '.join(SCENES)}")
    md_ok = not args.no_moordyn
    if md_ok:
        try:
            import moordyn  # noqa: F401
        except ImportError:
            print("moordyn not installed: MoorDyn fronts skipped (pip install 'moordyn>=2.7,<2.8')")
            md_ok = False

    t_start = time.perf_counter()
    load_before = os.getloadavg()[0]
    # warm-up: compile (or load) every kernel before any timing
    for integ in (SE, "rk2", IMPL):
        run_ours(SCENES["gjoa-500"], dict(uniform(4.0), integrator=integ))

    tasks: list[tuple[str, str, dict[str, Any]]] = []
    for s in scenes:
        tasks += [("ours", s, c) for c in our_cases(s, mode)]
        if md_ok and SCENES[s]["moordyn"]:
            tasks += [("moordyn", s, c) for c in moordyn_cases(mode, s)]
    scaling_cases = node_scaling_cases(mode)
    tasks += [("scaling", "deep-1500", c) for c in scaling_cases]
    tasks += [("fit", scene, {"label": f"fit check {geo}", "geometry": geo, "check": k == 3})
              for k, (scene, geo) in enumerate(FIT_CHECK)]

    results: dict[str, dict[str, Any]] = {s: {"ours": [], "moordyn": []} for s in scenes}
    scaling_runs: list[dict[str, Any]] = []
    fit_rows: list[dict[str, Any]] = []
    bar = tqdm(tasks, unit="run", desc="speed_vs_error", dynamic_ncols=True)
    for kind, s, case in bar:
        bar.set_postfix_str(f"{s}: {case.get('label', case.get('series', ''))}"[:60])
        spec = SCENES[s]
        t_task = time.perf_counter()
        if kind == "ours":
            r = run_ours(spec, case["overrides"])
            r.update(family=case["family"], label=case["label"], overrides={k: v for k, v in case["overrides"].items()})
            results[s]["ours"].append(r)
        elif kind == "moordyn":
            ref_cfg = load_scene(spec["scene"], {**spec["overrides"], **uniform(case["chain_m"]), "integrator": SE})
            r = run_md(spec, case, ref_cfg)
            r.update(family=case["family"], label=case["label"])
            results[s]["moordyn"].append(r)
        elif kind == "fit":
            r = run_fit_check(s, case["geometry"], case["check"])
            fit_rows.append(r)
        else:
            r = run_scaling(case)
            scaling_runs.append(r)
        if args.verbose:
            tqdm.write(f"{time.perf_counter() - t_task:7.1f} s  {s}: {case.get('label', case.get('series'))}: "
                       f"{r.get('status')} {fmt(r.get('speed'), '.4f')} m/s {fmt(r.get('tilt'), '.2f')} deg "
                       f"wall {fmt(r.get('wall_s'), '.3g')} s statics {fmt(r.get('wall_static_s'), '.3g')} s")
    bar.close()

    out: dict[str, Any] = {
        "mode": mode, "measured_on": machine(), "python": platform.python_version(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "scenes": {}, "equal_error": [],
    }
    try:
        from importlib.metadata import version

        out["moordyn_version"] = version("moordyn")
    except Exception:  # noqa: BLE001
        out["moordyn_version"] = None
    for s in scenes:
        ours, md = results[s]["ours"], results[s]["moordyn"]
        ladder = [r for r in ours if r["family"] == "reference ladder" and r.get("status") == "ok"]
        ref, chk = ladder[-1], ladder[-2]
        ref["is_reference"] = True
        add_errors(ours, ref)
        add_errors(md, ref)
        ref_info = dict(chain_m=ref["vertical_m"], speed=ref["speed"], tilt=ref["tilt"], time=ref["time"],
                        drift=ref["drift"], dt_s=ref["dt_s"], wall_s=ref["wall_s"], n_nodes=ref["n_nodes"])
        small = abs(ref["tilt"]) < TILT_SMALL_DEG
        data: dict[str, Any] = {
            "about": SCENES[s]["about"], "reference": ref_info, "tilt_small": small,
            "check": dict(chain_m=chk["vertical_m"], speed_err_pct=chk["speed_err_pct"],
                          tilt_err_deg=chk["tilt_err_deg"], time_err_ms=chk["time_err_ms"],
                          drift_err_m=chk["drift_err_m"]),
            "ours": ours, "moordyn": md,
            "front_ours_speed": metric_front(ours, "speed_err_pct", 1e-3),
            "front_moordyn_speed": metric_front(md, "speed_err_pct", 1e-3),
            "front_ours_tilt": metric_front(ours, "tilt_err_deg", 1e-3),
            "front_moordyn_tilt": metric_front(md, "tilt_err_deg", 1e-3),
        }
        dtc = [r for r in ours if r["family"] == "reference dt check" and r.get("status") == "ok"]
        if dtc:
            data["dt_check"] = {"speed_err_pct": dtc[0]["speed_err_pct"], "tilt_err_deg": dtc[0]["tilt_err_deg"]}
        ok_ours = [r for r in ours if r.get("status") == "ok"]
        ok_md = [r for r in md if r.get("status") == "ok"]
        data["speed_spread"] = {
            "ladder": [min(r["speed"] for r in ladder), max(r["speed"] for r in ladder)],
            "ours": [min(r["speed"] for r in ok_ours), max(r["speed"] for r in ok_ours)],
            "moordyn": [min(r["speed"] for r in ok_md), max(r["speed"] for r in ok_md)] if ok_md else None,
        }
        data["tilt_spread"] = {
            "ladder": [min(r["tilt"] for r in ladder), max(r["tilt"] for r in ladder)],
            "ours": [min(r["tilt"] for r in ok_ours), max(r["tilt"] for r in ok_ours)],
            "moordyn": [min(r["tilt"] for r in ok_md), max(r["tilt"] for r in ok_md)] if ok_md else None,
        }
        out["scenes"][s] = data
        if ok_md:
            targets = [("speed error [%]", "speed_err_pct", e) for e in (3.0, 1.0, 0.3)]
            if not small:
                targets += [("tilt error [deg]", "tilt_err_deg", e) for e in (0.5, 0.3)]
            for metric, key, e in targets:
                fo = metric_front(ours, key, 1e-3)
                fm = metric_front(md, key, 1e-3)
                co, cm = cost_at(fo, e), cost_at(fm, e)
                row = {"scene": s, "metric": metric, "error": e, "ours": co, "moordyn": cm}
                for k in ("measured", "interpolated"):
                    row[f"ratio_{k}"] = (cm[k] / co[k]) if (co[k] and cm[k]) else None
                if co["measured"] and not cm["measured"] and fm:
                    # MoorDyn never got there: its most accurate run bounds its cost from below
                    row["moordyn_best"] = {"error": fm[-1][1], "cost": fm[-1][0]}
                    row["ratio_lower_bound"] = fm[-1][0] / co["measured"]
                out["equal_error"].append(row)

    # node scaling
    series: dict[str, Any] = {}
    for r in scaling_runs:
        if r.get("status") != "ok":
            continue
        info = series.setdefault(r["series"], {"s": [], "n_nodes": [], "wall_per_sim_s": [], "cpu_per_sim_s": [],
                                               "dt_s_each": []})
        info["s"].append(r["s"])
        info["n_nodes"].append(r["n_nodes"])
        info["wall_per_sim_s"].append(r["wall_per_sim_s"])
        info["cpu_per_sim_s"].append(r["cpu_per_sim_s"])
        info["dt_s_each"].append(r["dt_s"])
    fit_slopes(series)
    out["node_scaling"] = {"runs": scaling_runs, "series": series}
    out["fit_check"] = fit_rows

    out["load_average_1min"] = {"before": load_before, "after": os.getloadavg()[0]}
    out["wall_total_s"] = time.perf_counter() - t_start
    suffix = "" if mode == "full" else "_quick"
    json_path = RESULTS_DIR / f"speed_vs_error{suffix}.json"
    out["json"] = str(json_path.relative_to(ROOT))
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(out, indent=1, default=float) + "\n")
    if not args.no_docs:
        write_docs(out)
        write_blocks(docs_blocks(out))

    # summary on stdout
    print(f"\nspeed_vs_error ({mode}) on {out['measured_on']}, load {load_before:.2f} -> "
          f"{out['load_average_1min']['after']:.2f}, {out['wall_total_s'] / 60:.1f} min")
    for s, data in out["scenes"].items():
        ref, chk = data["reference"], data["check"]
        print(f"  {s}: reference chain {ref['chain_m']:g} m {ref['speed']:.3f} m/s tilt {ref['tilt']:.2f} deg; "
              f"chain {chk['chain_m']:g} m differs {chk['speed_err_pct']:+.2f} % / {chk['tilt_err_deg']:+.2f} deg")
        for r in data["ours"]:
            if r["family"] in ("preset", "preset branches") and r.get("status") == "ok":
                print(f"    {r['label']:16s} {r['speed_err_pct']:+.2f} %  tilt {r['tilt_err_deg']:+.2f} deg  "
                      f"wall {r['wall_s'] * 1e3:.1f} ms  cpu {r['cpu_s'] * 1e3:.1f} ms")
    for row in out["equal_error"]:
        print(f"  {row['scene']}: {row['metric']} <= {row['error']:g}: ours {fmt(row['ours']['measured'])} s "
              f"(interp {fmt(row['ours']['interpolated'])}), MoorDyn {fmt(row['moordyn']['measured'])} s "
              f"(interp {fmt(row['moordyn']['interpolated'])}); MoorDyn/ours {fmt(row['ratio_measured'], '.1f')}x "
              f"(interp {fmt(row['ratio_interpolated'], '.1f')}x)" + ratio_bound_note(row))
    for name, info in series.items():
        print(f"  node scaling, {name}: slope {fmt(info['slope'], '.2f')} "
              f"(3 largest {fmt(info['slope_upper'], '.2f')})")
    return out


if __name__ == "__main__":
    main()

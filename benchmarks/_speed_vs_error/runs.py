"""The runs of the speed-against-error study: ours from a cached hanging equilibrium per resolution (best of
``REPEATS`` when fast), MoorDyn from the same equilibrium, the node-scaling runs and the fit-check rows.
"""

from __future__ import annotations

import copy
import json
import time
import warnings
from typing import Any

import numpy as np

from _speed_vs_error.cases import FIT_REFERENCE_C, IMPL, SCENES, SE, preset_branches, uniform
from moor_env import load_scene, solve_statics
from moor_env.compile import compile_scene
from moor_env.config import SceneConfig, mooring_line_slack, scene_from_dict
from moor_env.errors import ConfigError, SimulationDiverged
from moor_env.physics import layout as LY
from moor_env.simulation import (
    INTEGRATOR_IMPLICIT_EULER,
    INTEGRATOR_RK2,
    INTEGRATOR_SYMPLECTIC_EULER,
    run_drop,
)

FAST_S = 1.0  # runs faster than this are repeated (best of 3)
REPEATS = 3
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

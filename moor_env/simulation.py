"""Python API of the simulation: statics, release and fall of a compiled scene.

Last stage of ``YAML -> SceneConfig -> Model -> kernels -> results``: :func:`solve_statics` and
:func:`simulate_drop` are the one-call entry points used by the command line; they drive a
:class:`~moor_env.simulator.Simulator` (the state, its records and the kernel calls).
"""

from __future__ import annotations

import functools
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from moor_env.coarse_start import FIRST_TRY_ITERATIONS, MIDDLE_PRESET, REFUSED_FROM_NODES, CoarseStart
from moor_env.compile import VESSEL_SECOND, Model, compile_scene
from moor_env.config import SceneConfig, load_scene
from moor_env.errors import StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg
from moor_env.physics.integrate import INTEGRATOR_IMPLICIT_EULER, INTEGRATOR_RK2, INTEGRATOR_SYMPLECTIC_EULER
from moor_env.physics.records import STATE_NAMES, SimState
from moor_env.physics.statics import (
    MAX_ITERATIONS,
    n_static_dofs,
    seabed_set_grows,
    seabed_set_releases,
    solve_equilibrium,
)
from moor_env.physics.statics_checks import check_anchor_clearance, check_fibre_clearance, fibre_on_seabed
from moor_env.physics.statics_guess import change_line_length, first_guess
from moor_env.simulator import Simulator, integrator_code

STATE_ARRAY_FIELDS = STATE_NAMES  # the arrays of a SimState, in order
__all__ = ["INTEGRATOR_IMPLICIT_EULER", "INTEGRATOR_RK2", "INTEGRATOR_SYMPLECTIC_EULER", "STATE_ARRAY_FIELDS",
           "DropResult", "SimState", "Simulator", "StaticResult", "integrator_code", "run_drop", "simulate_drop",
           "solve_statics"]


# --- statics -------------------------------------------------------------------------------------------------
@dataclass
class StaticResult:
    """Equilibrium before release."""

    simulator: Simulator
    release_point_m: list[float] | None
    tip_height_above_seabed_m: float | None
    tilt_deg: float | None
    top_tensions_n: dict[str, float]
    wire_length_m: float | None
    iterations: int
    wall_static_s: float
    method: str = "newton"  # the solver that finished: "newton", or "relaxation" (the fallback)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        d = {k: v for k, v in asdict(self).items() if k != "simulator"}
        d["n_nodes"] = int(np.sum(self.simulator.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE))
        return d


def _adjust_to_drop_height(sim: Simulator, target_z: float) -> float:
    """Error of the tip height against the target [m], positive when the tip hangs too high."""
    tip, _ = sim.tip_state()
    return float(tip[2] - target_z)


def _secant_gain(gain: float, last: tuple[float, float] | None, err: float) -> float:
    """The tip's drop per metre of wire paid out (or of held chain top lowered), from the last correction's
    effect: ``last`` = (error before it, correction) [m], ``err`` the error after it [m]; ``gain`` kept where
    there is none or the measured one is implausible.

    Why: paid out wire lowers the tip by 0.95-0.99 m per metre (the release point also swings towards the
    mooring line), so a correction by the error alone shrinks it some twenty- to hundredfold, and an error of
    decimetres (strong current) took three warm solves; with the measured gain the second correction lands
    within micrometres."""
    if last is None:
        return gain
    measured = (last[0] - err) / last[1]
    return measured if 0.5 <= measured <= 2.0 else gain


def _equilibrium(sim: Simulator, progress: bool, method: str, checks: bool, finer: CoarseStart | None = None):
    """:func:`solve_equilibrium` by ``method``. With ``checks``, a scene whose first guess lays the fibre rope near
    the seabed is refused first where the coarse compile's equilibrium with the seabed bearing no fibre dips the
    fibre through it or, for lines finer than the coarse start's (``moor_env.coarse_start``), where the coarse
    equilibrium rests several fibre nodes on it (:meth:`CoarseStart.refuse_fibre_on_seabed`); then Newton's method
    from the first guess gets ``FIRST_TRY_ITERATIONS`` (lines finer than the coarse start's; others the full
    ``MAX_ITERATIONS`` at once), then the coarse start (:meth:`CoarseStart.start`, the fast preset's equilibrium, then
    the default preset's for lines finer than that; a refusal either start left pending is raised where both
    fail, the fast preset's unless the default preset's equilibrium hangs the fibre clear), then the first guess
    again with ``MAX_ITERATIONS``; the relaxation fallback last. Where the default preset's start follows, the fast
    preset's gets only its softened try (``SOFTENED_START_ITERATIONS``) of its full budget. ``finer``: where this
    solve is the default preset's start of finer lines, their coarse start; its equilibrium is this solve's coarse
    start too, and where it hangs the fibre clear of the seabed this solve begins with it instead of a first try
    from the guess (where it rests fibre nodes, the start from it has a refusal pending, and the guess may still
    reach an equilibrium with the fibre clear).

    Why that order: a solve from the first guess that has not converged in a hundred iterations or two mostly stalls
    (with the loop resting against the anchor in current); from the coarse start most of those converge in fewer
    iterations than the stalled solve has already taken. Why 150 for the first try: on the statics benchmark's
    scenes the first tries that converged took 140 iterations at most without the line-anchor contact and 122 with
    it; against 200, the budget lost on the others is a quarter shorter, which takes 3 % off the Newton iterations
    (weighted by nodes) over the 1000 scenes and 15 % off the slowest scene's (4 % and 10 % at the p99 on the envs'
    resolution's), with no outcome changed on either; 120 cuts off a first try that converges in 122, and its scene
    (no equilibrium) is refused after the coarse start instead, at three times the cost. Why not the coarse start
    first: on most scenes it costs more than the first guess (its compile and solve, and tens of Newton iterations
    for the sag). Why the fast preset's start gets only its softened try where the default preset's follows: on the
    statics benchmark, every fine solve that converged from the fast preset's equilibrium did so within that try
    (9-240 iterations), while the two that went on to the full budget did not converge in it (0.36 and 0.50 s) and
    then converged from the default preset's. Why the default preset's lines start from the fast preset's
    equilibrium when they are the start of finer lines: the finer lines did not converge from the first guess, and
    the default preset's lines did not either in any of the eight such solves on the two statics benchmarks' scenes."""
    if method == "relaxation":
        return solve_equilibrium(sim, progress=progress, method=method)
    solve = functools.partial(_coarse_solve, progress=progress)
    coarse = CoarseStart(sim, solve)
    if finer is not None:
        coarse.share(finer)
    guessed = checks and n_static_dofs(sim) > 0
    if guessed:  # the first try starts from this guess
        first_guess(sim)
        coarse.refuse_fibre_on_seabed()
    budgets = (FIRST_TRY_ITERATIONS, MAX_ITERATIONS) if coarse.keys is not None else (MAX_ITERATIONS,)
    failure = None
    for k, budget in enumerate(budgets):
        if k == 0 and len(budgets) > 1 and finer is not None and finer.fibre_resting == 0:
            continue  # the finer lines' first try failed from the guess, and the fibre hangs clear: start shared
        if k > 0:
            middle = CoarseStart(sim, functools.partial(_coarse_solve, progress=progress, finer=coarse),
                                 MIDDLE_PRESET)
            report = coarse.start(progress, softened_only=middle.keys is not None)
            pending = coarse.pending
            if report is None:
                report = middle.start(progress, unsoftened_first=True)
                if middle.fibre_resting == 0:  # nearer the fine lines, it hangs the fibre clear
                    pending = None
                pending = middle.pending or pending
            if report is not None:
                return report
            if pending is not None:
                raise pending
            sim.state = sim.model.initial_state()
        try:
            return solve_equilibrium(sim, progress=progress, method="newton", max_iter=budget,
                                     analytic_guess=not (guessed and k == 0))
        except StaticsNotConverged as exc:
            failure = exc
    if method == "newton" or failure.line_on_anchor:  # the relaxation leaves the line-anchor contact out
        raise failure
    sim.state = sim.model.initial_state()
    return solve_equilibrium(sim, progress=progress, method="relaxation")


def _coarse_solve(model: Model, progress: bool, finer: CoarseStart | None = None) -> StaticResult:
    """The coarse start's solve: the hanging equilibrium of a coarse compile by Newton's method, without the
    refusals of an equilibrium (the fine lines' own equilibrium is checked). An equilibrium that rests
    ``REFUSED_FROM_NODES`` or more fibre nodes on the seabed is returned before its drop-height corrections
    (``settle_resting_fibre``). ``finer``: the coarse start of the finer lines this compile is the default
    preset's start of (:func:`_equilibrium`)."""
    return _hanging_equilibrium(model, 1e-3, progress, "newton", checks=False, settle_resting_fibre=True,
                                finer=finer)


def solve_statics(scene: SceneConfig | Model, tol_m: float = 1e-3, progress: bool = True,
                  method: str = "auto") -> StaticResult:
    """Hanging equilibrium before release, drop height held at its set value (seed 003: Landhaug 2015, *Dynamic
    Simulation of Dart Anchor Installation*, Model 1).

    For an installation scene with a wire, the wire's unstretched length is corrected (at its top) until the
    anchor tip hangs ``drop_height_m`` above the seabed within ``tol_m``; without a wire, the held chain top
    is moved instead; each correction is followed by a warm Newton solve, and each after the first divides the
    error by the tip's response to the last one (a secant step). ``method``: "auto" (Newton's method, and the slow
    relaxation solver where it does not converge), "newton" or "relaxation" (one of them only;
    :func:`moor_env.physics.statics.solve_equilibrium`).
    With "auto" and "newton", a scene whose fibre rope the scene's coarse equilibrium lays on the seabed is refused
    before its own lines are solved (``moor_env.coarse_start``). With "auto" and "newton", a scene that Newton's
    method does not solve is solved once more with the Newton steps' seabed set only growing
    (:func:`moor_env.physics.statics.seabed_set_grows`), and only then, with "auto", by the relaxation: on the
    statics benchmark's 1000 scenes the set's releases take a sixth off the Newton iterations (weighted by nodes;
    two fifths at the envs' resolution) and leave one scene unsolved that the growing set refuses for its fibre on
    the seabed.

    Raises
    ------
    moor_env.errors.NoEquilibrium
        The scene has none (the cause and the key to change are named).
    moor_env.errors.StaticsNotConverged
    """
    t0 = time.perf_counter()
    model = scene if isinstance(scene, Model) else compile_scene(scene)
    if method == "relaxation" or not seabed_set_releases():
        return _hanging_equilibrium(model, tol_m, progress, method, checks=True, t0=t0)
    try:
        return _hanging_equilibrium(model, tol_m, progress, "newton", checks=True, t0=t0)
    except StaticsNotConverged:
        with seabed_set_grows():
            return _hanging_equilibrium(model, tol_m, progress, method, checks=True, t0=t0)


def _hanging_equilibrium(model: Model, tol_m: float, progress: bool, method: str, checks: bool,
                         t0: float | None = None, settle_resting_fibre: bool = False,
                         finer: CoarseStart | None = None) -> StaticResult:
    """:func:`solve_statics` of a compiled model; ``checks`` False skips the refusals of an equilibrium (fibre on
    the seabed, a line through the anchor): the coarse start maps such an equilibrium too, and the fine lines'
    own equilibrium is then checked. ``t0``: the ``time.perf_counter`` the wall time counts from (the compile
    included where given). ``finer``: as :func:`_equilibrium`'s. ``settle_resting_fibre``: an equilibrium that
    rests ``REFUSED_FROM_NODES`` or more fibre nodes on the seabed is kept without its drop-height corrections.
    Why: the coarse start refuses such a scene, and the corrections (the wire lengthened or shortened by the tip's
    height error) do not change that: on the statics benchmark's scenes (``benchmarks/statics.py``, 1000 drawn,
    seed 0), all 94 coarse equilibria that rested two or more fibre nodes before their corrections rested two or
    more after them, the tip having been 0.6 cm from its drop height (median), 10 cm at most."""
    t0 = time.perf_counter() if t0 is None else t0
    sim = Simulator(model)
    report = _equilibrium(sim, progress, method, checks, finer)
    iterations = report.iterations
    finished = report.method
    sc = model.scene
    settled = settle_resting_fibre and fibre_on_seabed(sim)[0] >= REFUSED_FROM_NODES
    if sc.kind == "dart_installation" and model.release_node >= 0 and not settled:
        target = -sc.environment.water_depth_m + sc.installation.drop_height_m
        gain, last = 1.0, None  # the tip's drop per metre of correction; the last (error, correction)
        for _ in range(8):
            err = _adjust_to_drop_height(sim, target)
            if abs(err) < tol_m:
                break
            gain = _secant_gain(gain, last, err)
            last = (err, err / gain)
            if model.wire_end_node >= 0:
                change_line_length(sim.state, model.lines["wire"].index, last[1])
            else:
                sim.state.node_pos[model.release_node, 2] -= last[1]
            warm = solve_equilibrium(sim, warm=True, progress=progress, method=method)
            iterations += warm.iterations
            finished = "relaxation" if warm.method == "relaxation" else finished
        else:
            err = _adjust_to_drop_height(sim, target)
            if abs(err) >= tol_m:
                raise StaticsNotConverged(f"the anchor tip hangs {err:+.3g} m from its drop height after 8 wire "
                                          f"corrections (tolerance {tol_m:g} m)", None)
        if checks:
            check_fibre_clearance(sim)
            check_anchor_clearance(sim, finished)
    sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0
    wall = time.perf_counter() - t0
    release = None
    tip_h = tilt = None
    if model.body_active:
        tip, _ = sim.tip_state()
        tip_h = float(tip[2] + sc.environment.water_depth_m)
        tilt = sim.tilt_deg()
    if model.release_node >= 0:
        release = sim.state.node_pos[model.release_node].tolist()
    wire_len = sim.line_length_m("wire") if "wire" in model.lines else None
    return StaticResult(simulator=sim, release_point_m=release, tip_height_above_seabed_m=tip_h, tilt_deg=tilt,
                        top_tensions_n=sim.top_tensions_n(), wire_length_m=wire_len, iterations=iterations,
                        wall_static_s=wall, method=finished)


# --- drop ----------------------------------------------------------------------------------------------------
@dataclass
class DropResult:
    """Outcome of a release and fall (times from the release instant)."""

    status: str
    touchdown_time_s: float | None
    touchdown_speed_m_s: float | None
    touchdown_vertical_speed_m_s: float | None
    tilt_deg: float | None
    drift_m: float | None
    release_point_m: list[float] | None
    release_time_s: float
    chain_on_seabed_m: float
    chain_past_back_end_m: float | None  # Simulator.line_past_back_end_m of the vertical chain, at the end
    line_anchor_contact: bool  # whether the lines' contact with the anchor was modelled (contact_model)
    contact_peak_force_n: float | None  # the contact's largest net force on the anchor during the fall
    contact_peak_depth_m: float | None  # the deepest a node went inside the anchor's surface during the fall
    chain_on_anchor_m: float | None  # Simulator.line_on_anchor_m of the vertical chain, at the end
    max_tension_n: dict[str, float]
    n_nodes: int
    n_steps: int
    dt_s: float
    wall_static_s: float
    wall_dynamic_s: float
    history: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, L.N_HIST)))
    snapshots: list = field(repr=False, default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (history and snapshots left out)."""
        return {k: v for k, v in asdict(self).items() if k not in ("history", "snapshots")}


def simulate_drop(scene: str | Path | SceneConfig, overrides: dict[str, Any] | None = None,
                  keep_snapshots: bool = False, history: bool = True, progress: bool = False) -> DropResult:
    """Statics, optional pre-release dynamics, release, fall to touchdown.

    Parameters
    ----------
    scene : str, Path or SceneConfig
        Bundled scene name, YAML path or a loaded scene.
    overrides : dict, optional
        ``--set`` style overrides (see :data:`moor_env.config.SET_SHORTCUTS`).
    keep_snapshots : bool
        Store node positions and the anchor axis every ``simulation.snapshot_interval_s`` (for plots).
    history : bool
        Record the tip state every ``simulation.record_interval_s`` (every as many steps; a fall whose step grows,
        ``discretization.fall_step_growth_max``, records at its steps' own times, further apart).
    progress : bool
        Show a progress bar over simulated time.

    Raises
    ------
    SimulationDiverged
        If the integration blows up (time and component named).
    """
    cfg = scene if isinstance(scene, SceneConfig) else load_scene(scene, overrides)
    static = solve_statics(cfg)
    sim = static.simulator
    return run_drop(sim, static.wall_static_s, keep_snapshots=keep_snapshots, history=history, progress=progress)


def run_drop(sim: Simulator, wall_static_s: float = 0.0, keep_snapshots: bool = False,
             history: bool = True, progress: bool = False) -> DropResult:
    """Pre-release phase (if ``release_time_s`` > 0), release and fall of a simulator at equilibrium."""
    sc = sim.model.scene
    inst = sc.installation
    t0 = time.perf_counter()
    release_time = inst.release_time_s if inst is not None else 0.0
    max_fall = sc.simulation.max_fall_time_s
    window = release_time + max_fall + 1.0
    speeds = np.zeros(sim.vessel_mean_m.shape[0])
    if inst is not None and sim.vessel_mean_m.shape[0] > VESSEL_SECOND and inst.spacing_rate_m_s:
        speeds[VESSEL_SECOND] = inst.spacing_rate_m_s
    sim.set_vessel_motion(0.0, window, speeds)
    if inst is not None and inst.payout_rate_m_s and "mooring_line" in sim.model.lines:
        sim.set_payout_rate("mooring_line", inst.payout_rate_m_s)
    n_steps = 0
    if release_time > 0:
        _, n = sim.advance_to(release_time)
        n_steps += n
    if "mooring_line" in sim.model.lines:
        sim.set_payout_rate("mooring_line", 0.0)
    sim.release()
    hist_every = max(1, int(round(sc.simulation.record_interval_s / sim.dt))) if history else 0
    tip0, _ = sim.tip_state()
    snapshots = []
    t_stop = sim.state.t + max_fall
    status = L.STATUS_TIME_LIMIT
    interval = sc.simulation.snapshot_interval_s if keep_snapshots else (0.25 if progress else max_fall)
    bar = tqdm(total=round(max_fall, 2), unit="s sim", disable=not progress, leave=False,
               bar_format="{l_bar}{bar}| {n:.2f}/{total:.0f} s simulated [{elapsed}]")
    t_fall0 = sim.state.t
    while sim.state.t < t_stop - 0.5 * sim.dt:  # the kernel's own end test: an advance that ends short of
        # t_stop by less than half a step takes no step towards it
        if keep_snapshots:
            snapshots.append(_snapshot(sim))
        status, n = sim.advance_to(min(sim.state.t + interval, t_stop), detect_touchdown=sim.model.body_active,
                                   history_every=hist_every)
        n_steps += n
        bar.update(round(sim.state.t - t_fall0, 2) - bar.n)
        if status == L.STATUS_TOUCHDOWN:
            break
    bar.close()
    if keep_snapshots:
        snapshots.append(_snapshot(sim))
    wall = time.perf_counter() - t0
    td = sim.work.touchdown
    touched = status == L.STATUS_TOUCHDOWN
    max_tension = {name: float(sim.state.line_f[info.index, L.LF_MAX_TENSION])
                   for name, info in sim.model.lines.items()}
    chain = {sc.installation.chain_material} if inst is not None else None
    vertical = sim.model.body_active and "vertical_chain" in sim.model.lines
    contact_on = bool(sim.model.contact_f[L.CF_ON])
    contact = sim.contact_report()
    result = DropResult(
        status="touchdown" if touched else "no touchdown within max_fall_time_s",
        touchdown_time_s=float(td[L.TD_TIME] - sim.release_time_s) if touched else None,
        touchdown_speed_m_s=float(np.linalg.norm(td[L.TD_VEL:L.TD_VEL + 3])) if touched else None,
        touchdown_vertical_speed_m_s=float(-td[L.TD_VEL + 2]) if touched else None,
        tilt_deg=float(tilt_deg(td[L.TD_AXIS + 2])) if touched else None,
        drift_m=float(np.hypot(td[L.TD_TIP] - tip0[0], td[L.TD_TIP + 1] - tip0[1])) if touched else None,
        release_point_m=None if sim.release_point_m is None else [float(v) for v in sim.release_point_m],
        release_time_s=float(sim.release_time_s),
        chain_on_seabed_m=sim.line_length_on_seabed_m(chain),
        chain_past_back_end_m=sim.line_past_back_end_m("vertical_chain")[0] if vertical else None,
        line_anchor_contact=contact_on,
        contact_peak_force_n=contact["peak_force_n"] if contact_on else None,
        contact_peak_depth_m=contact["peak_depth_m"] if contact_on else None,
        chain_on_anchor_m=sim.line_on_anchor_m("vertical_chain") if vertical else None,
        max_tension_n=max_tension,
        n_nodes=int(np.sum(sim.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE)),
        n_steps=n_steps, dt_s=sim.dt, wall_static_s=wall_static_s, wall_dynamic_s=wall,
        history=sim.history(), snapshots=snapshots,
    )
    return result


def _snapshot(sim: Simulator) -> dict[str, Any]:
    st = sim.state
    lines = {}
    for name, info in sim.model.lines.items():
        li = st.line_i[info.index]
        if not st.seg_i[li[L.LI_SEG_START], L.SI_ACTIVE]:
            continue
        segs = range(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])
        nodes = [st.seg_i[segs[0], L.SI_A]] + [st.seg_i[s, L.SI_B] for s in segs]
        lines[name] = st.node_pos[nodes].copy()
    active = sim.model.body_active
    return {"t": st.t, "lines": lines, "tip": sim.tip_state()[0] if active else None,
            "back": sim.back_end_m() if active else None}

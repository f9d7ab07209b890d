"""Static equilibrium of the discrete model: the hanging system before release (seed 003: Landhaug 2015,
*Dynamic Simulation of Dart Anchor Installation*, section 8.2, Model 1).

The equilibrium is an exact rest state of the dynamic model (its own load kernel with every velocity zero, so
that current drag acts as a static load): a release from it starts without a transient. It is found by the Newton
kernel of ``physics/statics_newton.py`` (analytic Jacobian solved in O(N) over the tree of lines, the seabed
contact as an active set, pseudo-transient continuation) from the first guess of ``physics/statics_guess.py``:
every line in the discrete model's own equilibrium without current, a grounded line across the seabed from its
touchdown nodes, excess line laid on the seabed. The calm equilibrium takes a few iterations; the scene's current
is then applied in one stage, solved as pseudo time stepping that turns into Newton's method. Where that stage
does not converge within a hundred iterations, the current is applied in increments from the calm equilibrium
instead, and where those do not reach it, in one long stage.

Where the scene models the lines' contact with the anchor's body (``contact_model``), it is part of the static
problem (``physics/statics_contact.py``): a loop that hangs beside the vertical chain rests against the anchor and
pushes it aside. The lines are solved without it first (:func:`solve_equilibrium`); from a state with a line
through the anchor (that equilibrium, or the first guess), the first stage is solved with the contact's stiffness
raised in steps from a hundred-thousandth of its own (``statics_stages.CONTACT_RAMP``), so that the line is
pushed out gradually and the loop follows.

All of it runs on the tension-only law smoothed at strain scale ``SMOOTHING_FINAL`` (it differs from the exact law
by less than EA 1e-8 / 2 on a segment at zero strain, far less elsewhere; only a mapped start's first stages are
smoothed more, below) and the exact seabed contact.
:func:`solve_equilibrium` finishes with the slow solver of ``physics/statics_relaxation.py`` where Newton's method
does not converge (``method="auto"``), except where a line rests on the anchor: the relaxation does not converge
there either, so the solve stops with the vessel spacing named as the key to change. Before that fallback,
``moor_env.simulation.solve_statics`` tries Newton's method from a coarse compile's equilibrium mapped onto the
lines (``mapped``) where it has not converged from the first guess within a few hundred iterations; such a start
is solved first with the tension-only law's kink rounded more (``statics_stages.soften_slack``), and again without
that where it does not converge so.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses

import numpy as np
from tqdm.auto import tqdm

from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics import statics_relaxation
from moor_env.physics.statics_checks import anchor_intrusion
from moor_env.physics.statics_guess import first_guess
from moor_env.physics.statics_newton import (
    C_ITERATIONS,
    C_MAX_STEP,
    C_RESIDUAL,
    C_SEABED_RELEASE,
    C_STATUS,
    C_TAU,
    N_CTL,
    SMOOTHING_FINAL,
    STATUS_CONVERGED,
    STATUS_NONFINITE,
    STEP_TOLERANCE_M,
    TAU_START_S,
)
from moor_env.physics.statics_relaxation import StaticsReport
from moor_env.physics.statics_stages import (
    PROGRESS_AFTER_S,
    STAGE_STEP_M,
    STAGE_TOLERANCE,
    Stage,
    apply_current,
    body_root,
    restore_state,
    soften_slack,
    stiffen_contact,
)

__all__ = ["SMOOTHING_FINAL", "n_static_dofs", "seabed_set_grows", "seabed_set_releases", "solve_equilibrium",
           "solve_newton"]

MAX_ITERATIONS = 2000
RAMP_DEPTH_M = 0.01  # a start with a line deeper than this inside the anchor takes the ramp (at rest: < 1 mm)
SOFTENED_START_ITERATIONS = 400  # a mapped start's iterations at most with the slack law softened first (per solve)
METHODS = ("auto", "newton", "relaxation")
_SEABED_RELEASE = contextvars.ContextVar("seabed_release", default=True)


@contextlib.contextmanager
def seabed_set_grows():
    """Within the block, every Newton step's seabed set only grows after its first solve
    (``physics/statics_newton.py``, ``C_SEABED_RELEASE``): the rule for a scene that the releases leave unsolved
    (``moor_env.simulation.solve_statics``). The setting is a context variable: it holds in this thread (and
    context), not in threads started elsewhere."""
    token = _SEABED_RELEASE.set(False)
    try:
        yield
    finally:
        _SEABED_RELEASE.reset(token)


def seabed_set_releases() -> bool:
    """Whether the Newton steps' seabed sets release the nodes a later solve lifts (False within
    :func:`seabed_set_grows`)."""
    return _SEABED_RELEASE.get()


def n_static_dofs(sim) -> int:
    """Number of unknowns of the static problem (3 per free node, 5 for a held anchor)."""
    free = int(np.count_nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE))
    return 3 * free + (5 if body_root(sim) >= 0 else 0)


def solve_equilibrium(sim, tol_rel: float = 1e-4, max_iter: int = MAX_ITERATIONS, max_step_m: float = 20.0,
                      warm: bool = False, analytic_guess: bool = True, progress: bool = True,
                      method: str = "auto", mapped: bool = False, softened_only: bool = False) -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place.

    ``method``: "auto" runs :func:`solve_newton` and, where it does not converge, the slow, robust solver of
    ``physics/statics_relaxation.py`` from the same start; "newton" and "relaxation" run one of them only.
    Other parameters and exceptions as :func:`solve_newton`; the report's ``method`` says which solver finished.
    ``softened_only``: a mapped start with the full budget gets its softened try only (:func:`_softened`), for a
    caller with a nearer start to try next.

    Where the scene models the line-anchor contact, the lines are solved without it first: an equilibrium with no
    line inside the anchor is one of the contact problem too (every contact force is zero), and most scenes have
    one. Where a line ends inside the anchor, the contact problem is solved from that equilibrium; where the solve
    without the contact does not converge with a line inside the anchor at its start or end, from the start (a
    warm start that already rests on the anchor goes to the contact problem at once). Where it does not converge
    and no line lay inside the anchor at its start or end, the contact problem is not tried: it would take the
    same first steps and, mostly, the same iterations to the end. Where a contact
    solve does not converge and a line lay inside the anchor at its start or end, no fallback is run (the
    relaxation, which leaves the contact out, does not reach those either): :class:`StaticsNotConverged` names the
    vessel spacing; the iterations reported count both solves.
    """
    if method not in METHODS:
        raise ConfigError("method", method, "one of " + ", ".join(METHODS))
    start = sim.state.copy()
    if method != "relaxation":
        args = {"tol_rel": tol_rel, "max_iter": max_iter, "max_step_m": max_step_m, "warm": warm,
                "analytic_guess": analytic_guess, "progress": progress, "mapped": mapped}
        softened = mapped and max_iter > SOFTENED_START_ITERATIONS
        report = _softened(sim, start, args) if softened else None
        if report is None and softened and softened_only:
            raise StaticsNotConverged(f"static equilibrium not reached from the mapped start within its "
                                      f"{SOFTENED_START_ITERATIONS} softened iterations", None)
        if report is None:
            report = _by_newton(sim, start, method, {**args, "soften": False})
        if report is not None:
            return report
        restore_state(sim.state, start)
    with _contact_off(sim):
        try:
            with tqdm(desc="statics (relaxation)", unit="s relaxed", disable=not progress, leave=False,
                      delay=PROGRESS_AFTER_S) as bar:
                return statics_relaxation.solve_equilibrium(sim, tol_rel=tol_rel, warm=warm,
                                                            analytic_guess=analytic_guess, tick=bar.update)
        except SimulationDiverged as exc:
            raise _as_not_converged(exc) from exc


def _softened(sim, start, args: dict) -> StaticsReport | None:
    """A mapped start's first try: Newton's method with the slack law softened first
    (``statics_stages.soften_slack``), ``SOFTENED_START_ITERATIONS`` at most in each solve (without the line-anchor
    contact, then with it); None (the state back at ``start``) where it does not converge, and the mapped start is
    solved again without it. Only for a mapped start's full budget: within a shorter one the softened stages would
    leave the last stage too few iterations."""
    try:
        return _by_newton(sim, start, "newton", {**args, "soften": True,
                                                 "max_iter": min(args["max_iter"], SOFTENED_START_ITERATIONS)})
    except StaticsNotConverged:
        restore_state(sim.state, start)
        return None


def _by_newton(sim, start, method: str, args: dict) -> StaticsReport | None:
    """:func:`solve_newton` without the line-anchor contact, then with it where needed (:func:`solve_equilibrium`);
    None where the fallback is to run. ``start``: the state to go back to; ``args``: solve_newton's keywords."""
    contact = _contact_modelled(sim)
    try:
        if contact and args["warm"] and _depth_inside_anchor(sim) > 0.0:
            return solve_newton(sim, **args, contact=True)
        failure = None
        try:
            clear = solve_newton(sim, **args, contact=False)
            if not (contact and _depth_inside_anchor(sim) > 0.0):
                return clear
        except (StaticsNotConverged, SimulationDiverged) as exc:
            failure = exc
        if not contact or (failure is not None and not getattr(failure, "inside_anchor", True)):
            raise failure
        if failure is not None:
            restore_state(sim.state, start)
            return solve_newton(sim, **args, contact=True)
        # from the equilibrium without the contact, in the scene's current
        report = solve_newton(sim, **{**args, "warm": True, "analytic_guess": False, "soften": False}, contact=True)
        return dataclasses.replace(report, iterations=report.iterations + clear.iterations)
    except (StaticsNotConverged, SimulationDiverged) as exc:
        if method == "newton" or getattr(exc, "line_on_anchor", False):
            raise _as_not_converged(exc) from exc
        return None


@contextlib.contextmanager
def _contact_off(sim):
    """The simulator's line-anchor contact off for the block, restored whatever it raises."""
    contact_f = sim.model.contact_f
    saved = contact_f[L.CF_ON]
    contact_f[L.CF_ON] = 0.0
    try:
        yield
    finally:
        contact_f[L.CF_ON] = saved


def _as_not_converged(exc: Exception) -> StaticsNotConverged:
    """A blow-up of the pseudo dynamics of a static solve is a statics failure, not a simulation result."""
    if isinstance(exc, StaticsNotConverged):
        return exc
    return StaticsNotConverged(f"static solve failed: its relaxation diverged ({exc})")


def _stop(st) -> None:
    st.node_vel[:] = 0.0
    st.body_state[L.BS_VEL:L.BS_VEL + 3] = 0.0
    st.body_state[L.BS_OMEGA:L.BS_OMEGA + 3] = 0.0


def solve_newton(sim, tol_rel: float = 1e-4, max_iter: int = MAX_ITERATIONS, max_step_m: float = 20.0,
                 warm: bool = False, analytic_guess: bool = True, progress: bool = True,
                 contact: bool = True, mapped: bool = False, soften: bool = False) -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place by Newton's method.

    The calm equilibrium is solved first from the guess, then the scene's current in one stage of at most
    ``SHORT_STAGE`` iterations; where that stage does not converge, the current is applied again from the calm
    equilibrium in increments (``INCREMENT_ITERATIONS`` at most), each solved to ``STAGE_TOLERANCE``, halved or
    doubled by how hard the last one was, and where they do not reach it, in one stage with the iterations left.
    Where the start has a line more than ``RAMP_DEPTH_M`` inside the anchor, the first stage is preceded by the
    contact's stiffness ramp (module docstring).

    Parameters
    ----------
    sim : Simulator
    tol_rel : float
        Converged when every unknown's residual is below ``tol_rel`` times its weight scale (node weight;
        anchor weight, and anchor weight times length for its moments) and the step below ``STEP_TOLERANCE_M``.
    max_iter : int
        Iterations at most.
    max_step_m : float
        Longest node move of a step [m].
    warm : bool
        Start from the current state in the scene's current (a small change of an equilibrium, e.g. a corrected
        wire length).
    analytic_guess : bool
        Start from the discrete catenary guess (:func:`moor_env.physics.statics_guess.first_guess`); otherwise
        from the current state, however poor.
    progress : bool
        Show a progress bar once a solve has taken more than a second.
    contact : bool
        Solve with the line-anchor contact where the scene models it; False leaves it out.
    mapped : bool
        With ``warm``: the state is an equilibrium of a coarser compile of the scene mapped onto this one
        (:func:`moor_env.remesh.remesh_state`), whose slack segments start slack (``statics_stages.slack_counts``).
    soften : bool
        Solve the first stage on the smoothed slack law first (``statics_stages.soften_slack``).

    Raises
    ------
    StaticsNotConverged
    moor_env.errors.NoEquilibrium
        From the first guess: the scene has no equilibrium (named cause and key).
    """
    with contextlib.nullcontext() if contact else _contact_off(sim):
        return _newton(sim, tol_rel, max_iter, max_step_m, warm, analytic_guess, progress, mapped, soften)


def _newton(sim, tol_rel: float, max_iter: int, max_step_m: float, warm: bool, analytic_guess: bool,
            progress: bool, mapped: bool, soften: bool) -> StaticsReport:
    n_dofs = n_static_dofs(sim)
    if n_dofs == 0:  # nothing to solve (e.g. an anchor held at its drop height, no lines)
        return StaticsReport(0, 0.0, 0.0, 0, "newton")
    if analytic_guess and not warm:
        first_guess(sim)
    ctl = np.zeros(N_CTL)
    ctl[C_TAU] = 1e3 if warm else TAU_START_S
    ctl[C_MAX_STEP] = max_step_m
    ctl[C_SEABED_RELEASE] = 1.0 if seabed_set_releases() else 0.0
    current = float(sim.env_f[L.EF_CUR_SCALE])
    stage = Stage(sim, ctl, max_iter, progress, not warm or mapped)
    sim.env_f[L.EF_SLACK_SMOOTHING] = SMOOTHING_FINAL
    sim.env_f[L.EF_SEABED_SMOOTHING] = 0.0
    depth_m = _depth_inside_anchor(sim)
    start_inside = _line_inside(sim) > 0.0
    try:
        calm = 0.0 if current > 0.0 and not warm else current
        if depth_m > RAMP_DEPTH_M:
            stiffen_contact(stage, calm)
        if soften:
            soften_slack(stage, calm)
        final = calm == current
        done = stage.run(calm, tol_rel if final else STAGE_TOLERANCE, STEP_TOLERANCE_M if final else STAGE_STEP_M,
                         max_iter, turning=final)
        if done and not final:
            apply_current(stage, current, tol_rel, max_iter)
    except StaticsNotConverged as exc:  # the anchor's 5x5 system singular
        exc.line_on_anchor = depth_m > 0.0 or _depth_inside_anchor(sim) > 0.0
        exc.inside_anchor = start_inside or _line_inside(sim) > 0.0
        raise
    finally:
        sim.env_f[L.EF_CUR_SCALE] = current
        sim.env_f[L.EF_SLACK_SMOOTHING] = 0.0
        stage.close()
        _stop(sim.state)
        sim.evaluate_loads()
    iterations = int(ctl[C_ITERATIONS])
    if ctl[C_STATUS] != STATUS_CONVERGED:
        reason = "a non-finite residual" if ctl[C_STATUS] == STATUS_NONFINITE else f"{iterations} iterations"
        on_anchor = depth_m > 0.0 or _depth_inside_anchor(sim) > 0.0
        where = (" with the loop against the anchor (a larger installation.vessel_spacing_m keeps it clear)"
                 if on_anchor else "")
        raise StaticsNotConverged(f"static equilibrium not reached after {reason}{where} (largest residual/weight "
                                  f"{ctl[C_RESIDUAL]:.3g}, tolerance {tol_rel:g})", float(ctl[C_RESIDUAL]),
                                  line_on_anchor=on_anchor,
                                  inside_anchor=start_inside or _line_inside(sim) > 0.0)
    return StaticsReport(iterations, float(ctl[C_RESIDUAL]), 0.0, n_dofs, "newton")


def _contact_modelled(sim) -> bool:
    return bool(sim.model.body_active and sim.model.contact_f[L.CF_ON] != 0.0)


def _depth_inside_anchor(sim) -> float:
    """How deep the deepest point of a line lies inside the anchor [m] where the scene models their contact (else
    0): its nodes, and with the segments' contact (``physics/segment_contact.py``) any point of its segments (a
    line held by a segment over a rim has its nodes outside)."""
    return _line_inside(sim) if _contact_modelled(sim) else 0.0


def _line_inside(sim) -> float:
    """How deep the deepest point of a line lies inside the anchor [m], whether or not the contact is on: its
    nodes, and where the scene has the segments' contact, any point of its segments."""
    if sim.model.contact_f[L.CF_SEGMENTS] != 0.0:
        return sim.deepest_segment_inside_m()
    return anchor_intrusion(sim)[0]

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
pushes it aside. The first guess hangs the lines as if the anchor were not there; where it puts a line inside the
anchor, the calm problem is first solved with the contact's stiffness raised in decades from a hundred-thousandth
of its own (``CONTACT_RAMP``), so that the line is pushed out gradually and the loop follows.

All of it runs on the tension-only law smoothed at strain scale ``SMOOTHING_FINAL`` (it differs from the exact law
by less than EA 1e-8 / 2 on a segment at zero strain, far less elsewhere) and the exact seabed contact.
:func:`solve_equilibrium` finishes with the slow solver of ``physics/statics_relaxation.py`` where Newton's method
does not converge (``method="auto"``), except where a line rests on the anchor: the relaxation does not converge
there either, so the solve stops with the vessel spacing named as the key to change.
"""

from __future__ import annotations

import contextlib
import time

import numpy as np
from tqdm.auto import tqdm

from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics import statics_relaxation
from moor_env.physics.statics_guess import deepest_inside_anchor, first_guess
from moor_env.physics.statics_newton import (
    C_CAP,
    C_CUTS,
    C_ITERATIONS,
    C_MAX_STEP,
    C_RESIDUAL,
    C_STATUS,
    C_STEP_TOL,
    C_TAU,
    C_TOL,
    N_CTL,
    SMOOTHING_FINAL,
    STATUS_CONVERGED,
    STATUS_NONFINITE,
    STATUS_RUNNING,
    STEP_TOLERANCE_M,
    TAU_START_S,
    newton_statics,
)
from moor_env.physics.statics_relaxation import StaticsReport
from moor_env.physics.statics_system import SLACK_PATIENCE

__all__ = ["SMOOTHING_FINAL", "n_static_dofs", "solve_equilibrium", "solve_newton"]

MAX_ITERATIONS = 2000
CHUNK_ITERATIONS = 50
SHORT_STAGE = 100  # iterations of the first try of the scene's current in one stage
INCREMENT_ITERATIONS = 400  # iterations of the second try, in increments
STAGE_TOLERANCE = 1e-2  # residual/weight to which a current increment before the last is solved
STAGE_STEP_M = 1e-2  # and its step
STAGE_ITERATIONS = 40  # iterations of one current increment before it is retried at a quarter
EASY_STAGE = 8  # an increment solved in this many iterations doubles the next (in twice as many, keeps it)
SMALLEST_CURRENT_STEP = 1.0 / 256.0  # of the scene's current scale
PROGRESS_AFTER_S = 1.0
CONTACT_RAMP = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)  # shares of the contact stiffness before its own
METHODS = ("auto", "newton", "relaxation")


def body_root(sim) -> int:
    """The node that attaches the lines to the anchor when the anchor is a static unknown, else -1."""
    if not sim.model.body_active:
        return -1
    body = np.nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_BODY)[0]
    return int(body[0]) if body.size else -1


def n_static_dofs(sim) -> int:
    """Number of unknowns of the static problem (3 per free node, 5 for a held anchor)."""
    free = int(np.count_nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE))
    return 3 * free + (5 if body_root(sim) >= 0 else 0)


def solve_equilibrium(sim, tol_rel: float = 1e-4, max_iter: int = MAX_ITERATIONS, max_step_m: float = 20.0,
                      warm: bool = False, analytic_guess: bool = True, progress: bool = True,
                      method: str = "auto") -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place.

    ``method``: "auto" runs :func:`solve_newton` and, where it does not converge, the slow, robust solver of
    ``physics/statics_relaxation.py`` from the same start; "newton" and "relaxation" run one of them only.
    Other parameters and exceptions as :func:`solve_newton`; the report's ``method`` says which solver finished.

    Where the scene models the line-anchor contact, the lines are solved without it first: an equilibrium with no
    line inside the anchor is one of the contact problem too (every contact force is zero), and most scenes have
    one. Where a line ends inside the anchor, or that solve does not converge, the contact problem is solved
    (from a warm start that already rests on the anchor, at once). Where it does not converge with a line resting
    on the anchor, no fallback is run (the relaxation does not reach those either, in minutes):
    :class:`StaticsNotConverged` names the vessel spacing.
    """
    if method not in METHODS:
        raise ConfigError("method", method, "one of " + ", ".join(METHODS))
    start = sim.state.copy()
    if method != "relaxation":
        report = _by_newton(sim, start, method, (tol_rel, max_iter, max_step_m, warm, analytic_guess, progress))
        if report is not None:
            return report
        _restore(sim.state, start)
    with _contact_off(sim):
        try:
            with tqdm(desc="statics (relaxation)", unit="s relaxed", disable=not progress, leave=False,
                      delay=PROGRESS_AFTER_S) as bar:
                return statics_relaxation.solve_equilibrium(sim, tol_rel=tol_rel, warm=warm,
                                                            analytic_guess=analytic_guess, tick=bar.update)
        except SimulationDiverged as exc:
            raise _as_not_converged(exc) from exc


def _by_newton(sim, start, method: str, args: tuple) -> StaticsReport | None:
    """:func:`solve_newton` without the line-anchor contact, then with it where needed (:func:`solve_equilibrium`);
    None where the fallback is to run. ``start``: the state to go back to; ``args``: solve_newton's from tol_rel
    to progress."""
    contact = bool(sim.model.body_active and sim.model.contact_f[L.CF_ON] != 0.0)
    warm = args[3]
    if contact and warm and _line_inside_anchor(sim):
        return solve_newton(sim, *args, contact=True)
    failure = None
    try:
        report = solve_newton(sim, *args, contact=False)
        if not (contact and _line_inside_anchor(sim)):
            return report
    except (StaticsNotConverged, SimulationDiverged) as exc:
        failure = exc
    if contact:
        _restore(sim.state, start)
        try:
            return solve_newton(sim, *args, contact=True)
        except (StaticsNotConverged, SimulationDiverged) as exc:
            if method == "newton" or failure is None or getattr(exc, "line_on_anchor", False):
                raise _as_not_converged(exc) from exc
    if method == "newton":
        raise _as_not_converged(failure) from failure
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


def _restore(st, saved) -> None:
    for name in ("node_pos", "node_vel", "body_state", "seg_f", "line_f"):
        getattr(st, name)[...] = getattr(saved, name)
    st.t = saved.t


def _stop(st) -> None:
    st.node_vel[:] = 0.0
    st.body_state[L.BS_VEL:L.BS_VEL + 3] = 0.0
    st.body_state[L.BS_OMEGA:L.BS_OMEGA + 3] = 0.0


def _slack_counts(st, warm: bool) -> np.ndarray:
    """Slack counts to start from. From the first guess a segment slack in the start state is slack in the
    equilibrium sought (the guess lays excess line on the seabed shortened), so K lets it go at once. From a warm
    start none is counted: a corrected wire length leaves the whole wire slack by a few millimetres, and K without
    the wire's stiffness would let the release point drop in the first step."""
    if warm:
        return np.zeros(st.seg_i.shape[0])
    seg = st.seg_i
    length = np.linalg.norm(st.node_pos[seg[:, L.SI_B]] - st.node_pos[seg[:, L.SI_A]], axis=1)
    return np.where(length < st.seg_f[:, L.SF_L0], float(SLACK_PATIENCE), 0.0)


class _Stage:
    """Runs the kernel in chunks on one current scale, with the progress bar."""

    def __init__(self, sim, ctl: np.ndarray, max_iter: int, progress: bool, warm: bool) -> None:
        self.sim, self.ctl, self.max_iter, self.progress = sim, ctl, max_iter, progress
        self.seg_age = _slack_counts(sim.state, warm)
        self.t0 = time.perf_counter()
        self.bar = None

    def run(self, scale: float, tol_rel: float, step_tol_m: float, budget: int) -> bool:
        """Solve at current scale ``scale`` within ``budget`` iterations; True once converged."""
        sim, ctl = self.sim, self.ctl
        sim.env_f[L.EF_CUR_SCALE] = scale
        ctl[C_TOL] = tol_rel
        ctl[C_STEP_TOL] = step_tol_m
        ctl[C_STATUS] = STATUS_RUNNING
        ctl[C_CAP] = 0.0
        ctl[C_CUTS] = 0.0
        end = min(self.max_iter, int(ctl[C_ITERATIONS]) + budget)
        model, state = sim.records()
        body = body_root(sim)
        while ctl[C_ITERATIONS] < end and ctl[C_STATUS] == STATUS_RUNNING:
            try:
                newton_statics(ctl, min(CHUNK_ITERATIONS, end - int(ctl[C_ITERATIONS])), body, model, state,
                               self.seg_age)
            except np.linalg.LinAlgError as exc:  # the anchor's 5x5 system singular or not finite
                raise StaticsNotConverged(f"static Newton step failed: {exc}") from exc
            self._show()
        return ctl[C_STATUS] == STATUS_CONVERGED

    def _show(self) -> None:
        if self.progress and self.bar is None and time.perf_counter() - self.t0 > PROGRESS_AFTER_S:
            self.bar = tqdm(total=self.max_iter, desc="statics", unit="it", leave=False)
        if self.bar is not None:
            self.bar.n = int(self.ctl[C_ITERATIONS])
            self.bar.set_postfix(residual=f"{self.ctl[C_RESIDUAL]:.2g}")
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def solve_newton(sim, tol_rel: float = 1e-4, max_iter: int = MAX_ITERATIONS, max_step_m: float = 20.0,
                 warm: bool = False, analytic_guess: bool = True, progress: bool = True,
                 contact: bool = True) -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place by Newton's method.

    The calm equilibrium is solved first from the guess, then the scene's current in one stage of at most
    ``SHORT_STAGE`` iterations; where that stage does not converge, the current is applied again from the calm
    equilibrium in increments (``INCREMENT_ITERATIONS`` at most), each solved to ``STAGE_TOLERANCE``, halved or
    doubled by how hard the last one was, and where they do not reach it, in one stage with the iterations left.
    Where the first guess puts a line inside the anchor, the calm stage is preceded by the contact's stiffness
    ramp (module docstring).

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

    Raises
    ------
    StaticsNotConverged
    moor_env.errors.NoEquilibrium
        From the first guess: the scene has no equilibrium (named cause and key).
    """
    with contextlib.nullcontext() if contact else _contact_off(sim):
        return _newton(sim, tol_rel, max_iter, max_step_m, warm, analytic_guess, progress)


def _newton(sim, tol_rel: float, max_iter: int, max_step_m: float, warm: bool, analytic_guess: bool,
            progress: bool) -> StaticsReport:
    n_dofs = n_static_dofs(sim)
    if n_dofs == 0:  # nothing to solve (e.g. an anchor held at its drop height, no lines)
        return StaticsReport(0, 0.0, 0.0, 0, "newton")
    if analytic_guess and not warm:
        first_guess(sim)
    ctl = np.zeros(N_CTL)
    ctl[C_TAU] = 1e3 if warm else TAU_START_S
    ctl[C_MAX_STEP] = max_step_m
    current = float(sim.env_f[L.EF_CUR_SCALE])
    stage = _Stage(sim, ctl, max_iter, progress, warm)
    sim.env_f[L.EF_SLACK_SMOOTHING] = SMOOTHING_FINAL
    sim.env_f[L.EF_SEABED_SMOOTHING] = 0.0
    on_anchor = not warm and _line_inside_anchor(sim)
    try:
        calm = 0.0 if current > 0.0 and not warm else current
        if on_anchor:
            _stiffen_contact(stage, calm)
        final = calm == current
        done = stage.run(calm, tol_rel if final else STAGE_TOLERANCE, STEP_TOLERANCE_M if final else STAGE_STEP_M,
                         max_iter)
        if done and not final:
            _apply_current(stage, current, tol_rel, max_iter)
    finally:
        sim.env_f[L.EF_CUR_SCALE] = current
        sim.env_f[L.EF_SLACK_SMOOTHING] = 0.0
        stage.close()
        _stop(sim.state)
        sim.evaluate_loads()
    iterations = int(ctl[C_ITERATIONS])
    if ctl[C_STATUS] != STATUS_CONVERGED:
        reason = "a non-finite residual" if ctl[C_STATUS] == STATUS_NONFINITE else f"{iterations} iterations"
        on_anchor = on_anchor or _line_inside_anchor(sim)
        where = (" with a line resting on the anchor (a larger installation.vessel_spacing_m keeps the loop clear of "
                 "it)" if on_anchor else "")
        exc = StaticsNotConverged(f"static equilibrium not reached after {reason}{where} (largest residual/weight "
                                  f"{ctl[C_RESIDUAL]:.3g}, tolerance {tol_rel:g})", float(ctl[C_RESIDUAL]))
        exc.line_on_anchor = on_anchor
        raise exc
    return StaticsReport(iterations, float(ctl[C_RESIDUAL]), 0.0, n_dofs, "newton")


def _line_inside_anchor(sim) -> bool:
    """Whether the scene models the line-anchor contact and a line node lies inside the anchor now."""
    return bool(sim.model.body_active and sim.model.contact_f[L.CF_ON] != 0.0
                and deepest_inside_anchor(sim.state.node_pos, sim.state.node_i, sim.state.body_state,
                                          sim.model.contact_shape, -float(sim.env_f[L.EF_DEPTH]))[0] > 0.0)


def _stiffen_contact(stage: _Stage, current: float) -> None:
    """Solve the calm problem (to the stage tolerance) at each share of the line-anchor contact's stiffness in
    ``CONTACT_RAMP``; the stiffness is its own again afterwards.

    Why: from a guess that hangs a line through the anchor, the full stiffness's first step throws the line out
    to the nearest face at once, and the loop, held by its slack bottom alone, does not find its way back (most
    such scenes ended unsolved after 2000 iterations); soft first, the line is pushed out as the loop follows."""
    contact_f = stage.sim.model.contact_f
    stiffness = float(contact_f[L.CF_STIFFNESS])
    try:
        for share in CONTACT_RAMP:
            contact_f[L.CF_STIFFNESS] = stiffness * share
            stage.ctl[C_TAU] = TAU_START_S
            stage.run(current, STAGE_TOLERANCE, STAGE_STEP_M, STAGE_ITERATIONS)
    finally:
        contact_f[L.CF_STIFFNESS] = stiffness
    stage.ctl[C_TAU] = TAU_START_S


def _apply_current(stage: _Stage, current: float, tol_rel: float, max_iter: int) -> bool:
    """From the calm equilibrium to the scene's current: in one short stage, else in increments, else in one stage
    with the iterations left; True once converged.

    Why this order: most scenes take the current in one stage within a few tens of iterations; of those that do
    not, most reach it in increments within a few hundred, and a few only in one long stage."""
    sim, ctl = stage.sim, stage.ctl
    calm = sim.state.copy()
    calm_age = stage.seg_age.copy()
    step_tol = STEP_TOLERANCE_M if tol_rel < STAGE_TOLERANCE else STAGE_STEP_M
    ctl[C_TAU] = TAU_START_S  # pseudo time stepping first: the current swings the lines' soft modes
    if stage.run(current, tol_rel, step_tol, SHORT_STAGE):
        return True
    _restore(sim.state, calm)
    stage.seg_age[:] = calm_age
    if _increments(stage, current, tol_rel, step_tol, min(max_iter, int(ctl[C_ITERATIONS]) + INCREMENT_ITERATIONS)):
        return True
    _restore(sim.state, calm)
    stage.seg_age[:] = calm_age
    ctl[C_TAU] = TAU_START_S
    return stage.run(current, tol_rel, step_tol, max_iter)


def _increments(stage: _Stage, current: float, tol_rel: float, step_tol: float, max_iter: int) -> bool:
    """The current in increments from the calm equilibrium (the state), each solved to ``STAGE_TOLERANCE``, doubled
    or halved by how hard the last one was; True once the scene's current is solved within ``max_iter`` (total)."""
    sim, ctl = stage.sim, stage.ctl
    solved, increment, last, last_age = 0.0, 0.25 * current, sim.state.copy(), stage.seg_age.copy()
    while ctl[C_ITERATIONS] < max_iter:
        scale = min(solved + increment, current)
        final = scale >= current
        retry = increment > SMALLEST_CURRENT_STEP * current
        ctl[C_TAU] = TAU_START_S
        start = int(ctl[C_ITERATIONS])
        budget = STAGE_ITERATIONS if retry else max_iter - start
        if stage.run(scale, tol_rel if final else max(STAGE_TOLERANCE, tol_rel),
                     step_tol if final else STAGE_STEP_M, budget):
            if final:
                return True
            used = int(ctl[C_ITERATIONS]) - start
            increment *= 2.0 if used <= EASY_STAGE else (1.0 if used <= 2 * EASY_STAGE else 0.5)
            solved, last, last_age = scale, sim.state.copy(), stage.seg_age.copy()
        elif not retry:
            return False
        else:  # back to the last equilibrium with a smaller increment
            _restore(sim.state, last)
            stage.seg_age[:] = last_age
            increment *= 0.25
    return False

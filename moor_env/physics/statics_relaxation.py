"""Fallback static solver: slow and robust, independent of the Newton solver of ``physics/statics.py`` (which calls
it where its own Newton and relaxation rounds do not converge) and the reference of ``benchmarks/statics.py``.
Pseudo-transient Newton with a finite-difference Jacobian, scipy sparse LU and rounds of explicit dynamic
relaxation, on the same discrete residual.

The residual is the net load on every free node and on the anchor, computed by the *same* kernel as the
dynamics with all velocities zero (so current drag acts as a static load and the static state is an exact
rest state of the dynamic model: no start-up transient). It is driven to zero by pseudo-transient
continuation, a damped Newton method robust from poor first guesses (slack segments, a line through the
seabed):

    (D / tau^2 - J) dx = F(x),        tau grows as the residual falls (switched evolution relaxation),

where D holds the node masses and anchor inertia, and J = dF/dx is built by finite differences with a
distance-2 colouring of the node graph (about ten residual evaluations per Jacobian whatever the node count).
For large tau this is Newton's method and converges quadratically. The unknowns, the residual and the Jacobian
are in ``physics/statics_residual.py``, the analytic first guess in ``physics/statics_analytic_guess.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from moor_env.errors import StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.statics_analytic_guess import first_guess
from moor_env.physics.statics_residual import StaticProblem


@dataclass
class StaticsReport:
    """Outcome of a static solve."""

    iterations: int
    residual_n: float
    max_step_m: float
    n_dofs: int
    method: str = "relaxation"  # "newton" (physics/statics.py) or "relaxation" (this module)


FINAL_SLACK_SMOOTHING = 1e-8
CONTINUATION_ITERATIONS = 30
RELAXATION_ROUNDS = 10  # rounds of 30 s relaxation + Newton always tried when Newton fails from the guess
MAX_RELAXATION_ROUNDS = 30  # beyond RELAXATION_ROUNDS, only while the rounds still shrink the residual ...
ROUND_PROGRESS = 0.9  # ... to below this fraction of the best so far (a fine slack loop creeps in slowly) ...
STALLED_ROUNDS = 2  # ... in one of the last this many rounds (one round stalled at 2.2e-4, the next converged)


def solve_equilibrium(sim, tol_rel: float = 1e-4, max_iter: int = 300, max_step_m: float = 20.0,
                      warm: bool = False, analytic_guess: bool = True, tick=None) -> StaticsReport:
    """Drive the simulator's current state to static equilibrium in place.

    Strategy (each stage is cheap when the previous one did its job):

    1. an analytic elastic-catenary first guess (``analytic_guess``; otherwise the current state is used,
       however poor);
    2. a short kinetic-damping dynamic relaxation (:func:`relax_dynamically`) with the dynamic kernel, which
       settles the near-slack bottom of a chain loop where the tension-only kink stalls Newton's method;
    3. pseudo-transient Newton (:func:`_solve_phase`) on a smoothed slack law EA (e + sqrt(e^2 + s^2)) / 2,
       s = 1e-6 then ``FINAL_SLACK_SMOOTHING`` = 1e-8 (it then differs from the exact law by less than
       EA * 1e-8 / 2, 9 N for the 142 mm chain, on a fully slack segment, and by far less on taut ones), with the
       elastic stiffness of slack segments in the Jacobian;
    4. if Newton fails: rounds of 30 s relaxation and Newton, ``RELAXATION_ROUNDS`` of them, then more (up to
       ``MAX_RELAXATION_ROUNDS``) while one of the last ``STALLED_ROUNDS`` rounds still cut the remaining
       residual by ``ROUND_PROGRESS``: a finely resolved slack loop pushed by current creeps towards equilibrium
       over many rounds (measured: 500 m, spacing 50 m, 0.5 m loop chain, the seed current: 0.03 -> 2.2e-4 of
       the tolerance scale over 10 rounds, halving every one or two, then one round without progress and
       convergence in the next).

    ``warm`` skips stages 1-2 for small changes of an equilibrium (e.g. a corrected wire length).
    """
    if StaticProblem(sim).n_dofs == 0:  # nothing to solve (e.g. an anchor held at its drop height, no lines)
        return StaticsReport(0, 0.0, 0.0, 0)
    if warm:
        try:
            return _continuation(sim, 1e-7, tol_rel, max_iter, max_step_m, 1.0)
        except StaticsNotConverged:
            pass
    elif analytic_guess:
        first_guess(sim)
    relax_dynamically(sim, max_time_s=2.0, tick=tick)
    try:
        return _continuation(sim, 1e-6, tol_rel, max_iter, max_step_m, 1.0)
    except StaticsNotConverged:
        pass
    # large changes from the guess (a strong current pushes the hanging system tens of metres): alternate
    # relaxation, which moves the slow pendulum-like modes, with Newton, which finishes once close
    best = math.inf
    stalled = 0
    for rounds in range(1, MAX_RELAXATION_ROUNDS + 1):
        relax_dynamically(sim, max_time_s=30.0, tick=tick)
        try:
            return _continuation(sim, 1e-6, tol_rel, 150, max_step_m, 1.0)
        except StaticsNotConverged as exc:
            residual = math.inf if exc.residual_rel is None else exc.residual_rel
            stalled = 0 if residual < ROUND_PROGRESS * best else stalled + 1
            if rounds >= RELAXATION_ROUNDS and stalled >= STALLED_ROUNDS:
                break
            best = min(best, residual)
    raise StaticsNotConverged(f"static equilibrium not reached after {rounds} relaxation rounds "
                              f"(largest residual/weight {best:.3g})", best)


def _continuation(sim, smoothing: float, tol_rel: float, max_iter: int, max_step_m: float,
                  tau0_s: float) -> StaticsReport:
    iterations = 0
    try:
        while smoothing > FINAL_SLACK_SMOOTHING * 1.0001:
            sim.env_f[L.EF_SLACK_SMOOTHING] = smoothing
            iterations += _solve_phase(sim, 10 * tol_rel, CONTINUATION_ITERATIONS, max_step_m, tau0_s,
                                       strict=False).iterations
            smoothing *= 0.1
            tau0_s = 1e3
        sim.env_f[L.EF_SLACK_SMOOTHING] = FINAL_SLACK_SMOOTHING
        report = _solve_phase(sim, tol_rel, max_iter, max_step_m, tau0_s)
    finally:
        sim.env_f[L.EF_SLACK_SMOOTHING] = 0.0
    report.iterations += iterations
    return report


def _solve_phase(sim, tol_rel: float, max_iter: int, max_step_m: float, tau0_s: float,
                 strict: bool = True) -> StaticsReport:
    """One pseudo-transient Newton solve of the simulator's state, in place.

    Parameters
    ----------
    sim : Simulator
        Its state is the first guess and receives the solution.
    tol_rel : float
        Converged when every dof's residual is below ``tol_rel`` times its own weight scale (node weight,
        anchor weight, anchor weight times length for moments).
    max_iter : int
    max_step_m : float
        Largest node move per iteration [m].
    tau0_s : float
        Initial pseudo time step [s].
    strict : bool
        Raise when not converged (otherwise return the state reached, for continuation steps).

    Raises
    ------
    StaticsNotConverged
    """
    prob = StaticProblem(sim)
    if prob.n_dofs == 0:
        return StaticsReport(0, 0.0, 0.0, 0)
    x = prob.get_x()
    axis0 = sim.state.body_state[L.BS_AXIS: L.BS_AXIS + 3].copy()
    r = prob.residual()
    mass, weight = prob.scales()
    tau = tau0_s
    step_norm = math.inf
    for it in range(1, max_iter + 1):
        ratio = np.abs(r) / weight
        if ratio.max() < tol_rel and step_norm < 1e-4:
            _commit_axis(prob, x, axis0, sim)
            return StaticsReport(it - 1, float(np.abs(r).max()), step_norm, prob.n_dofs)
        jac = prob.jacobian(x, r, axis0, 1e-6, 1e-7)
        lhs = sp.diags(mass / tau**2) - jac
        dx = spla.spsolve(lhs.tocsc(), r)
        if not np.all(np.isfinite(dx)):
            tau *= 0.25
            continue
        node_step = np.abs(dx[: prob.n_node_dofs]).max(initial=0.0)
        body_step = np.abs(dx[prob.n_node_dofs:]).max(initial=0.0)
        biggest = max(node_step, body_step)
        if biggest > max_step_m:
            dx *= max_step_m / biggest
        x_new = x + dx
        prob.set_x(x_new, axis0)
        r_new = prob.residual()
        old, new = np.linalg.norm(r / weight), np.linalg.norm(r_new / weight)
        if not np.isfinite(new) or new > 4.0 * old + 1e-12:
            tau *= 0.25
            prob.set_x(x, axis0)
            r = prob.residual()
            continue
        x, r = x_new, r_new
        step_norm = float(np.abs(dx).max())
        tau = min(tau * max(min(old / max(new, 1e-300), 10.0), 0.5), 1e12)
        if prob.body:
            _commit_axis(prob, x, axis0, sim)
            axis0 = sim.state.body_state[L.BS_AXIS: L.BS_AXIS + 3].copy()
            x[prob.n_node_dofs + 3:] = 0.0
            prob.set_basis()
            r = prob.residual()
    if not strict:
        return StaticsReport(max_iter, float(np.abs(r).max()), step_norm, prob.n_dofs)
    residual_rel = float(np.max(np.abs(r) / weight))
    raise StaticsNotConverged(
        f"static equilibrium not reached in {max_iter} iterations (largest residual/weight {residual_rel:.3g})",
        residual_rel)


def relax_dynamically(sim, max_time_s: float = 120.0, chunk_steps: int = 25, tol_rel: float = 5e-3,
                      tick=None) -> float:
    """Kinetic-damping dynamic relaxation with the dynamic kernel: integrate from the current state and zero
    every velocity whenever the total kinetic energy starts to fall (it has just passed an energy peak, the
    best estimate of the rest position along the dominant motion). Robust from any guess, linear in cost;
    used when Newton cannot start from the guess.

    Returns the simulated relaxation time [s] used. The state's time and the blow-up limits are restored.
    """
    st = sim.state
    limits = sim.env_f[L.EF_SPEED_LIMIT], sim.env_f[L.EF_STRAIN_LIMIT]
    sim.env_f[L.EF_SPEED_LIMIT] = 1e9
    sim.env_f[L.EF_STRAIN_LIMIT] = 1e9
    prob = StaticProblem(sim)
    previous = 0.0
    elapsed = 0.0
    try:
        while elapsed < max_time_s:
            st.t = 0.0  # vessels stay at their mean positions: no wave ramp, no spacing move
            sim.advance_to(chunk_steps * sim.dt)
            if tick is not None:
                tick(chunk_steps * sim.dt)
            elapsed += chunk_steps * sim.dt
            free = st.node_i[:, L.NI_KIND] == L.NODE_FREE
            kinetic = float(np.sum(sim.work.node_mass[free] * np.sum(st.node_vel[free] ** 2, axis=1)))
            if sim.model.body_active:
                body_v = st.body_state[L.BS_VEL:L.BS_VEL + 3]
                kinetic += sim.model.body_f[L.BF_MASS_AXIAL] * float(body_v @ body_v)
            if kinetic < previous:
                st.node_vel[:] = 0.0
                st.body_state[L.BS_VEL:L.BS_VEL + 3] = 0.0
                st.body_state[L.BS_OMEGA:L.BS_OMEGA + 3] = 0.0
                previous = 0.0
                r = prob.residual()
                _, weight = prob.scales()
                if np.max(np.abs(r) / weight) < tol_rel:
                    break
            else:
                previous = kinetic
    finally:
        sim.env_f[L.EF_SPEED_LIMIT], sim.env_f[L.EF_STRAIN_LIMIT] = limits
        st.t = 0.0
        st.node_vel[:] = 0.0
        st.body_state[L.BS_VEL:L.BS_VEL + 3] = 0.0
        st.body_state[L.BS_OMEGA:L.BS_OMEGA + 3] = 0.0
    return elapsed


def _commit_axis(prob: StaticProblem, x: np.ndarray, axis0: np.ndarray, sim) -> None:
    prob.set_x(x, axis0)
    if prob.body:
        sim.state.body_state[L.BS_OMEGA: L.BS_OMEGA + 3] = 0.0

"""The static solver's stages: the Newton kernel run in chunks on one current scale (:class:`Stage`), the scene's
current applied from the calm equilibrium (:func:`apply_current`), the line-anchor contact's stiffness raised
in steps (:func:`stiffen_contact`) and the slack law's kink sharpened in steps (:func:`soften_slack`); the order
of the stages is ``physics/statics.py``'s.
"""

from __future__ import annotations

import time

import numpy as np
from tqdm.auto import tqdm

from moor_env.errors import StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.statics_newton import (
    C_CAP,
    C_CUTS,
    C_ITERATIONS,
    C_RESIDUAL,
    C_STATUS,
    C_STEP_TOL,
    C_TAU,
    C_TOL,
    SMOOTHING_FINAL,
    STATUS_CONVERGED,
    STATUS_RUNNING,
    STEP_TOLERANCE_M,
    TAU_START_S,
    newton_statics,
)
from moor_env.physics.statics_system import SLACK_PATIENCE

CHUNK_ITERATIONS = 50
SHORT_STAGE = 100  # iterations of the first try of the scene's current in one stage
INCREMENT_ITERATIONS = 800  # iterations of the second try, in increments (apply_current)
STAGE_TOLERANCE = 1e-2  # residual/weight to which a current increment before the last is solved
STAGE_STEP_M = 1e-2  # and its step
STAGE_ITERATIONS = 40  # iterations of one current increment before it is retried at a quarter
EASY_STAGE = 8  # an increment solved in this many iterations doubles the next (in twice as many, keeps it)
SMALLEST_CURRENT_STEP = 1.0 / 256.0  # of the scene's current scale
CONTACT_RAMP = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 0.3)  # shares of the contact stiffness before its own
SEGMENTS_FROM_SHARE = 1e-1  # the share from which the ramp has the segments' contact on
PROGRESS_AFTER_S = 1.0
TURNING_AFTER = 100  # iterations of a stage after which its system takes the turning of segment contacts' normals
# (a multiple of CHUNK_ITERATIONS: it is switched between chunks)
TURNING_BELOW = 1.0  # and while the residual is below this (of a node's weight: near the stage's solution)
# strain scales of the tension-only law's rounded kink, before its own, on which a mapped start is solved first
SLACK_SMOOTHING_RAMP = (1e-4, 1e-6)
SMOOTHED_STAGE_ITERATIONS = 100  # iterations at most at each of them


def body_root(sim) -> int:
    """The node that attaches the lines to the anchor when the anchor is a static unknown, else -1."""
    if not sim.model.body_active:
        return -1
    body = np.nonzero(sim.state.node_i[:, L.NI_KIND] == L.NODE_BODY)[0]
    return int(body[0]) if body.size else -1


def restore_state(st, saved) -> None:
    """Put the positions, velocities, anchor and line states of ``saved`` back into ``st``."""
    for name in ("node_pos", "node_vel", "body_state", "seg_f", "line_f"):
        getattr(st, name)[...] = getattr(saved, name)
    st.t = saved.t


def slack_counts(st, slack_at_start: bool) -> np.ndarray:
    """Slack counts to start from. Where ``slack_at_start``, a segment slack in the start state is slack in the
    equilibrium sought, so K lets it go at once: from the first guess (it lays excess line on the seabed
    shortened) and from a coarse equilibrium mapped onto finer lines (each keeps its segment's strain). Otherwise
    none is counted: a corrected wire length leaves the whole wire slack by a few millimetres, and K without the
    wire's stiffness would let the release point drop in the first step."""
    if not slack_at_start:
        return np.zeros(st.seg_i.shape[0])
    seg = st.seg_i
    length = np.linalg.norm(st.node_pos[seg[:, L.SI_B]] - st.node_pos[seg[:, L.SI_A]], axis=1)
    return np.where(length < st.seg_f[:, L.SF_L0], float(SLACK_PATIENCE), 0.0)


class Stage:
    """Runs the kernel in chunks on one current scale, with the progress bar."""

    def __init__(self, sim, ctl: np.ndarray, max_iter: int, progress: bool, slack_at_start: bool) -> None:
        self.sim, self.ctl, self.max_iter, self.progress = sim, ctl, max_iter, progress
        self.seg_age = slack_counts(sim.state, slack_at_start)
        self.t0 = time.perf_counter()
        self.bar = None

    def run(self, scale: float, tol_rel: float, step_tol_m: float, budget: int, turning: bool = False) -> bool:
        """Solve at current scale ``scale`` within ``budget`` iterations; True once converged. With ``turning``,
        after ``TURNING_AFTER`` iterations and while the residual is below ``TURNING_BELOW`` (the stage creeps
        near its solution), the system takes the turning of the segment contacts' normals
        (``physics/statics_contact.py``, ``CF_TURNING``). Why only where the caller asks (a solve's last stage,
        not the current's increments or long stage): in the long stage of the current on a coarse start of the
        envs' resolution, the turning left a scene unsolved that converges without it (and is then refused for
        its fibre on the seabed). Why below a node's weight and not the stage tolerance (1e-2): on the statics
        benchmark the two scenes whose last stages creep at residuals between the two take 1780 and 1231 Newton
        iterations in all with it, 2123 and 1392 with the stage tolerance (4532 and 2145 without the turning),
        with no outcome changed there or on the envs' resolution."""
        sim, ctl = self.sim, self.ctl
        sim.env_f[L.EF_CUR_SCALE] = scale
        ctl[C_TOL] = tol_rel
        ctl[C_STEP_TOL] = step_tol_m
        ctl[C_STATUS] = STATUS_RUNNING
        ctl[C_CAP] = 0.0
        ctl[C_CUTS] = 0.0
        start = int(ctl[C_ITERATIONS])
        end = min(self.max_iter, start + budget)
        model, state = sim.records()
        body = body_root(sim)
        contact_f = sim.model.contact_f
        try:
            while ctl[C_ITERATIONS] < end and ctl[C_STATUS] == STATUS_RUNNING:
                creeping = (turning and ctl[C_ITERATIONS] >= start + TURNING_AFTER
                            and ctl[C_RESIDUAL] < TURNING_BELOW)
                contact_f[L.CF_TURNING] = 1.0 if creeping else 0.0
                try:
                    newton_statics(ctl, min(CHUNK_ITERATIONS, end - int(ctl[C_ITERATIONS])), body, model, state,
                                   self.seg_age)
                except np.linalg.LinAlgError as exc:  # the anchor's 5x5 system singular or not finite
                    raise StaticsNotConverged(f"static Newton step failed: {exc}") from exc
                self._show()
        finally:
            contact_f[L.CF_TURNING] = 0.0
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


def stiffen_contact(stage: Stage, scale: float) -> None:
    """Solve the problem at current scale ``scale`` (to the stage tolerance) at each share of the line-anchor
    contact's stiffness in ``CONTACT_RAMP``; the stiffness is its own again afterwards.

    Why: from a state that hangs a line through the anchor, the full stiffness's first step throws the line out to
    the nearest face at once, and the loop, held by its slack bottom alone, does not find its way back (from there
    most such scenes do not converge within 2000 iterations); soft first, the line is pushed out as the loop
    follows. The segments' contact (``CF_SEGMENTS``) is off below ``SEGMENTS_FROM_SHARE``: a line through the
    anchor has whole segments inside it, whose deepest points would push it out along their own faces; it comes in
    at a tenth of the stiffness, where the nodes are out and only the segments over a rim still cut in. Why there:
    on the statics benchmark's scenes, entering at the full stiffness left a few resting scenes cycling at a
    residual of about one node weight (a rim cut by centimetres pushed out at once), and entering from 1e-2 left
    the spacing-0 scene of gjoa-500 unsolved. Why 0.3 after the decades: from a tenth straight to the full
    stiffness, one of the statics benchmark's 1000 scenes (7 m spacing in 1465 m of water, current 1.27) wandered
    at residuals up to 200 node weights and stopped just short of the tolerance after 2000 iterations; with the
    step at 0.3 it converges, and the other scenes resting on the anchor take 6 % less time in all. At spacings
    near zero which ramp converges varies from scene to scene: a random plan of AnchorPlan-v1's held-out sites
    (the vessels 0.43 m apart in 473 m of water) converges without the step at 0.3 and not with it."""
    contact_f = stage.sim.model.contact_f
    stiffness, segments = float(contact_f[L.CF_STIFFNESS]), float(contact_f[L.CF_SEGMENTS])
    try:
        for share in CONTACT_RAMP:
            contact_f[L.CF_SEGMENTS] = segments if share >= SEGMENTS_FROM_SHARE else 0.0
            contact_f[L.CF_STIFFNESS] = stiffness * share
            stage.ctl[C_TAU] = TAU_START_S
            stage.run(scale, STAGE_TOLERANCE, STAGE_STEP_M, STAGE_ITERATIONS)
    finally:
        contact_f[L.CF_STIFFNESS] = stiffness
        contact_f[L.CF_SEGMENTS] = segments
    stage.ctl[C_TAU] = TAU_START_S


def soften_slack(stage: Stage, scale: float) -> None:
    """Solve the problem at current scale ``scale`` (to the stage tolerance, ``SMOOTHED_STAGE_ITERATIONS`` at most
    each) on the tension-only law smoothed at each strain scale of ``SLACK_SMOOTHING_RAMP``; the smoothing is
    ``SMOOTHING_FINAL`` again afterwards.

    Why: a coarse equilibrium mapped onto finer lines (``moor_env.remesh``) puts many short segments near zero
    strain, where the law's kink makes the Newton step jump between slack and taut states; a smoothed kink (1e-4:
    EA 1e-4 / 2, 87 kN on the 142 mm chain) gives the solve a smooth problem whose equilibrium lies near the
    exact one, and the kink sharpens from there. On the statics benchmark's slowest scenes the mapped starts
    converge in fewer iterations so, and some that did not converge at all do; a few converge only without it
    (``physics/statics.py`` solves those again from the mapped state)."""
    try:
        for strain in SLACK_SMOOTHING_RAMP:
            stage.sim.env_f[L.EF_SLACK_SMOOTHING] = strain
            stage.run(scale, STAGE_TOLERANCE, STAGE_STEP_M, SMOOTHED_STAGE_ITERATIONS)
    finally:
        stage.sim.env_f[L.EF_SLACK_SMOOTHING] = SMOOTHING_FINAL


def apply_current(stage: Stage, current: float, tol_rel: float, max_iter: int) -> bool:
    """From the calm equilibrium to the scene's current: in one short stage, else in increments, else in one stage
    with the iterations left; True once converged.

    Why this order: most scenes take the current in one stage within a few tens of iterations; of those that do
    not, most reach it in increments within a few hundred, and a few only in one long stage. Why
    ``INCREMENT_ITERATIONS`` 800: in strong current the increments of some scenes are still advancing after
    several hundred iterations, and the long stage from the calm equilibrium fails where they are cut off. On the
    statics benchmark's 169 slowest or unsolved scenes, 800 against 400 solves one more scene, refuses two more
    for their fibre within 100 ms (with 400, one of them needs the relaxation fallback, 58 s, to be refused) and
    refuses six others 4-15x sooner, with no scene losing its equilibrium; 1200 leaves too few iterations to one
    scene that only the long stage solves."""
    sim, ctl = stage.sim, stage.ctl
    calm = sim.state.copy()
    calm_age = stage.seg_age.copy()
    step_tol = STEP_TOLERANCE_M if tol_rel < STAGE_TOLERANCE else STAGE_STEP_M
    ctl[C_TAU] = TAU_START_S  # pseudo time stepping first: the current swings the lines' soft modes
    if stage.run(current, tol_rel, step_tol, SHORT_STAGE):
        return True
    restore_state(sim.state, calm)
    stage.seg_age[:] = calm_age
    if _increments(stage, current, tol_rel, step_tol, min(max_iter, int(ctl[C_ITERATIONS]) + INCREMENT_ITERATIONS)):
        return True
    restore_state(sim.state, calm)
    stage.seg_age[:] = calm_age
    ctl[C_TAU] = TAU_START_S
    return stage.run(current, tol_rel, step_tol, max_iter)


def _increments(stage: Stage, current: float, tol_rel: float, step_tol: float, max_iter: int) -> bool:
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
            restore_state(sim.state, last)
            stage.seg_age[:] = last_age
            increment *= 0.25
    return False

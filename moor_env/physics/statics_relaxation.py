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
For large tau this is Newton's method and converges quadratically.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from moor_env.errors import StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.catenary import Section, shape, solve_grounded, solve_suspended, trim
from moor_env.physics.integrate import set_constrained_nodes
from moor_env.physics.statics_guess import change_line_length


@dataclass
class StaticsReport:
    """Outcome of a static solve."""

    iterations: int
    residual_n: float
    max_step_m: float
    n_dofs: int
    method: str = "relaxation"  # "newton" (physics/statics.py) or "relaxation" (this module)


class _Problem:
    """Degrees of freedom and residual of the static problem for a simulator state."""

    def __init__(self, sim) -> None:
        self.sim = sim
        st = sim.state
        kinds = st.node_i[:, L.NI_KIND]
        self.free = np.nonzero(kinds == L.NODE_FREE)[0]
        self.body = bool(sim.model.body_active and self._body_is_free())
        self.n_node_dofs = 3 * self.free.size
        self.n_dofs = self.n_node_dofs + (5 if self.body else 0)
        self.basis = np.zeros((2, 3))
        self._build_graph()

    def _body_is_free(self) -> bool:
        # the anchor is a static unknown only when something holds it (a line attached to its back tip)
        return bool(np.any(self.sim.state.node_i[:, L.NI_KIND] == L.NODE_BODY))

    def _build_graph(self) -> None:
        st = self.sim.state
        nn = st.node_i.shape[0]
        vertex = -np.ones(nn, dtype=np.int64)
        vertex[self.free] = np.arange(self.free.size)
        body_vertex = self.free.size
        kinds = st.node_i[:, L.NI_KIND]
        owner = np.arange(nn)
        welded = kinds == L.NODE_WELDED
        owner[welded] = st.node_i[welded, L.NI_REF]
        if self.body:
            vertex[kinds == L.NODE_BODY] = body_vertex
        vertex_of = vertex[owner]
        self.vertex_of = vertex_of
        n_vert = self.free.size + (1 if self.body else 0)
        nbrs: list[set[int]] = [set() for _ in range(n_vert)]
        for s in np.nonzero(st.seg_i[:, L.SI_ACTIVE])[0]:
            a, b = vertex_of[st.seg_i[s, L.SI_A]], vertex_of[st.seg_i[s, L.SI_B]]
            if a >= 0 and b >= 0 and a != b:
                nbrs[a].add(b)
                nbrs[b].add(a)
        color = -np.ones(n_vert, dtype=np.int64)
        if self.body:
            color[body_vertex] = 0
        for v in range(self.free.size):
            taken = set()
            for u in nbrs[v]:
                taken.add(color[u])
                for w in nbrs[u]:
                    taken.add(color[w])
            c = 1
            while c in taken:
                c += 1
            color[v] = c
        self.colors = color
        self.neighbours = nbrs
        self.body_vertex = body_vertex

    # --- dof <-> state -----------------------------------------------------------------------------------
    def get_x(self) -> np.ndarray:
        st = self.sim.state
        x = np.zeros(self.n_dofs)
        x[: self.n_node_dofs] = st.node_pos[self.free].ravel()
        if self.body:
            x[self.n_node_dofs: self.n_node_dofs + 3] = st.body_state[L.BS_POS: L.BS_POS + 3]
            self._set_basis()
        return x

    def _set_basis(self) -> None:
        e = self.sim.state.body_state[L.BS_AXIS: L.BS_AXIS + 3]
        trial = np.array([1.0, 0.0, 0.0]) if abs(e[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u1 = np.cross(e, trial)
        u1 /= np.linalg.norm(u1)
        self.basis[0] = u1
        self.basis[1] = np.cross(e, u1)

    def set_x(self, x: np.ndarray, axis0: np.ndarray) -> None:
        st = self.sim.state
        st.node_pos[self.free] = x[: self.n_node_dofs].reshape(-1, 3)
        st.node_vel[:] = 0.0
        if self.body:
            st.body_state[L.BS_POS: L.BS_POS + 3] = x[self.n_node_dofs: self.n_node_dofs + 3]
            phi = x[self.n_node_dofs + 3] * self.basis[0] + x[self.n_node_dofs + 4] * self.basis[1]
            st.body_state[L.BS_AXIS: L.BS_AXIS + 3] = _rotate(axis0, phi)
            st.body_state[L.BS_VEL: L.BS_VEL + 3] = 0.0
            st.body_state[L.BS_OMEGA: L.BS_OMEGA + 3] = 0.0

    def residual(self) -> np.ndarray:
        sim = self.sim
        st = sim.state
        set_constrained_nodes(*sim.records(), st.t)
        sim.evaluate_loads()
        r = np.zeros(self.n_dofs)
        r[: self.n_node_dofs] = sim.work.node_force[self.free].ravel()
        if self.body:
            load = sim.work.body_load
            r[self.n_node_dofs: self.n_node_dofs + 3] = load[:3]
            r[self.n_node_dofs + 3] = load[3:6] @ self.basis[0]
            r[self.n_node_dofs + 4] = load[3:6] @ self.basis[1]
        return r

    def scales(self) -> tuple[np.ndarray, np.ndarray]:
        """Mass per dof (for the pseudo-time term) and force scale per dof (for the tolerance)."""
        sim = self.sim
        g = sim.env_f[L.EF_G]
        mass = np.repeat(np.maximum(sim.work.node_mass[self.free], 1e-6), 3)
        weight = np.repeat(np.maximum(sim.work.node_mass[self.free], 1e-6) * g, 3)
        if self.body:
            bf = sim.model.body_f
            mass = np.concatenate([mass, [bf[L.BF_MASS_AXIAL]] * 3, [bf[L.BF_M22]] * 2])
            w = bf[L.BF_WEIGHT]
            weight = np.concatenate([weight, [w] * 3, [w * bf[L.BF_LENGTH]] * 2])
        return mass, weight

    def jacobian(self, x: np.ndarray, r0: np.ndarray, axis0: np.ndarray, eps_m: float, eps_rad: float):
        """Finite-difference Jacobian of the residual plus the elastic stiffness EA/l0 q q^T of every slack
        segment between free nodes (inexact Newton, as usual in cable statics): with the exact law's zero
        stiffness a node between two slack segments would look unsupported to Newton's method."""
        return self._fd_jacobian(x, r0, axis0, eps_m, eps_rad) - self._slack_stiffness()

    def _slack_stiffness(self):
        st = self.sim.state
        mat_f = self.sim.model.mat_f
        segs = np.nonzero(st.seg_i[:, L.SI_ACTIVE])[0]
        a = st.seg_i[segs, L.SI_A]
        b = st.seg_i[segs, L.SI_B]
        d = st.node_pos[b] - st.node_pos[a]
        length = np.linalg.norm(d, axis=1)
        l0 = st.seg_f[segs, L.SF_L0]
        slack = (length <= l0) & (length > 0)
        va, vb = self.vertex_of[a[slack]], self.vertex_of[b[slack]]
        q = d[slack] / length[slack, None]
        k = mat_f[st.seg_i[segs[slack], L.SI_MAT], L.MF_EA] / l0[slack]
        blocks = k[:, None, None] * q[:, :, None] * q[:, None, :]
        rows, cols, vals = [], [], []
        for i in range(blocks.shape[0]):
            for u, w, sign in ((va[i], va[i], 1.0), (vb[i], vb[i], 1.0), (va[i], vb[i], -1.0), (vb[i], va[i], -1.0)):
                if u < 0 or w < 0 or u >= self.free.size or w >= self.free.size:
                    continue
                for r in range(3):
                    for c in range(3):
                        rows.append(3 * u + r)
                        cols.append(3 * w + c)
                        vals.append(sign * blocks[i, r, c])
        return sp.csc_matrix((vals, (rows, cols)), shape=(self.n_dofs, self.n_dofs))

    def _fd_jacobian(self, x: np.ndarray, r0: np.ndarray, axis0: np.ndarray, eps_m: float, eps_rad: float):
        rows, cols, vals = [], [], []
        n_colors = int(self.colors.max()) + 1 if self.colors.size else 0
        for c in range(1, n_colors):
            members = np.nonzero(self.colors[: self.free.size] == c)[0]
            if members.size == 0:
                continue
            for d in range(3):
                xp = x.copy()
                xp[3 * members + d] += eps_m
                self.set_x(xp, axis0)
                dr = (self.residual() - r0) / eps_m
                for v in members:
                    col = 3 * v + d
                    for u in (v, *self.neighbours[v]):
                        rr = self._rows(u)
                        rows.extend(rr)
                        cols.extend([col] * len(rr))
                        vals.extend(dr[rr])
        if self.body:
            base = self.n_node_dofs
            touched = [self.body_vertex, *self.neighbours[self.body_vertex]]
            for k in range(5):
                xp = x.copy()
                xp[base + k] += eps_m if k < 3 else eps_rad
                self.set_x(xp, axis0)
                dr = (self.residual() - r0) / (eps_m if k < 3 else eps_rad)
                for u in touched:
                    rr = self._rows(u)
                    rows.extend(rr)
                    cols.extend([base + k] * len(rr))
                    vals.extend(dr[rr])
        self.set_x(x, axis0)
        return sp.csc_matrix((vals, (rows, cols)), shape=(self.n_dofs, self.n_dofs))

    def _rows(self, vertex: int) -> list[int]:
        if self.body and vertex == self.body_vertex:
            return list(range(self.n_node_dofs, self.n_node_dofs + 5))
        return [3 * vertex, 3 * vertex + 1, 3 * vertex + 2]


def _rotate(axis: np.ndarray, phi: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(phi))
    if angle == 0.0:
        return axis.copy()
    k = phi / angle
    out = axis * math.cos(angle) + np.cross(k, axis) * math.sin(angle) + k * (k @ axis) * (1.0 - math.cos(angle))
    return out / np.linalg.norm(out)


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
    if _Problem(sim).n_dofs == 0:  # nothing to solve (e.g. an anchor held at its drop height, no lines)
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
    prob = _Problem(sim)
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
            prob._set_basis()
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
    prob = _Problem(sim)
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


def _commit_axis(prob: _Problem, x: np.ndarray, axis0: np.ndarray, sim) -> None:
    prob.set_x(x, axis0)
    if prob.body:
        sim.state.body_state[L.BS_OMEGA: L.BS_OMEGA + 3] = 0.0


# --- first guesses from the analytic elastic catenary ----------------------------------------------------------
def _line_sections(sim, line_name: str) -> tuple[list, np.ndarray]:
    """Catenary sections and the unstretched arc length of each interior node of a line (bottom to top)."""
    st, m = sim.state, sim.model
    idx = m.lines[line_name].index
    start, nseg = st.line_i[idx, L.LI_SEG_START], st.line_i[idx, L.LI_NSEG]
    g = sim.env_f[L.EF_G]
    sections: list = []
    for s in range(start, start + nseg):
        mat = st.seg_i[s, L.SI_MAT]
        w = m.mat_f[mat, L.MF_SUBMERGED] * g
        ea = m.mat_f[mat, L.MF_EA]
        if sections and sections[-1].weight_n_m == w and sections[-1].ea_n == ea:
            sections[-1] = Section(w, ea, sections[-1].length_m + st.seg_f[s, L.SF_L0])
        else:
            sections.append(Section(w, ea, st.seg_f[s, L.SF_L0]))
    arcs = np.cumsum(st.seg_f[start:start + nseg, L.SF_L0])[:-1]
    return sections, arcs


def _place_line(sim, line_name: str, origin: np.ndarray, h: float, v_a: float, direction: float = 1.0) -> None:
    """Put a line's interior nodes on the catenary (H, V_A) starting at ``origin`` (its bottom end)."""
    st, m = sim.state, sim.model
    sections, arcs = _line_sections(sim, line_name)
    x, z = shape(h, v_a, sections, arcs)
    idx = m.lines[line_name].index
    nodes = st.line_i[idx, L.LI_NODE_START] + np.arange(arcs.size)
    st.node_pos[nodes, 0] = origin[0] + direction * x
    st.node_pos[nodes, 1] = origin[1]
    st.node_pos[nodes, 2] = origin[2] + z


def first_guess(sim) -> None:
    """Set the simulator's node positions and anchor pose to an analytic estimate of the equilibrium
    (elastic catenaries without current), so that the Newton solve starts with every line in tension."""
    m = sim.model
    if m.scene.kind == "catenary_line":
        _guess_catenary_line(sim)
    elif m.release_node >= 0:
        _guess_installation(sim)


def _guess_catenary_line(sim) -> None:
    st, m = sim.state, sim.model
    idx = m.lines["line"].index
    a = st.node_pos[st.line_i[idx, L.LI_BOTTOM]].copy()
    b = st.node_pos[st.line_i[idx, L.LI_TOP]].copy()
    dx, dz = float(b[0] - a[0]), float(b[2] - a[2])
    sections, arcs = _line_sections(sim, "line")
    grounded = solve_grounded(dx, dz, sections) if abs(a[2] + sim.env_f[L.EF_DEPTH]) < 1e-6 else None
    if grounded is None:
        h, v_a = solve_suspended(dx, dz, sections)
        _place_line(sim, "line", a, h, v_a)
        return
    h, length_on_bottom = grounded
    rest = trim(sections, length_on_bottom)
    x_s, z_s = shape(h, 0.0, rest, np.maximum(arcs - length_on_bottom, 0.0))
    ea0 = sections[0].ea_n
    on_bottom = arcs <= length_on_bottom
    x = np.where(on_bottom, arcs * (1.0 + h / ea0), length_on_bottom * (1.0 + h / ea0) + x_s)
    z = np.where(on_bottom, 0.0, z_s)
    nodes = st.line_i[idx, L.LI_NODE_START] + np.arange(arcs.size)
    st.node_pos[nodes, 0] = a[0] + x
    st.node_pos[nodes, 2] = a[2] + z


def _guess_installation(sim) -> None:
    st, m = sim.state, sim.model
    g = sim.env_f[L.EF_G]
    rho = sim.env_f[L.EF_RHO]
    release = st.node_pos[m.release_node].copy()
    anchor_weight = m.anchor_submerged_mass_kg * g
    vc_sections, _ = _line_sections(sim, "vertical_chain")
    hang = anchor_weight + sum(s.weight_n_m * s.length_m for s in vc_sections)
    h_m = v_m = 0.0
    if m.wire_end_node >= 0:
        ru = st.node_f[m.wire_end_node]
        hang += (ru[L.NF_POINT_MASS] - rho * ru[L.NF_POINT_VOLUME]) * g
        wire = m.lines["wire"].index
        top_a = st.node_pos[st.line_i[wire, L.LI_TOP]]
        target_tip_z = -sim.env_f[L.EF_DEPTH] + m.scene.installation.drop_height_m
        vc_total = sum(s.length_m for s in vc_sections)
        _, vc_rise = shape(0.0, anchor_weight, vc_sections, np.array([vc_total]))
        for _ in range(50):
            wire_sections, _ = _line_sections(sim, "wire")
            if "mooring_line" in m.lines:
                ml_sections, _ = _line_sections(sim, "mooring_line")
                top_b = st.node_pos[st.line_i[m.lines["mooring_line"].index, L.LI_TOP]]
                h_m, v_m = solve_suspended(float(top_b[0] - release[0]), float(top_b[2] - release[2]), ml_sections)
            # the wire holds the release node against the chain below and the mooring line beside it
            h_w, v_w = h_m, hang - v_m
            x_w, z_w = shape(h_w, v_w, wire_sections, np.array([sum(s.length_m for s in wire_sections)]))
            new = np.array([top_a[0] + x_w[0], 0.0, top_a[2] - z_w[0]])
            moved = float(np.linalg.norm(new - release))
            release = new
            tip_error = release[2] - vc_rise[0] - m.body_f[L.BF_LENGTH] - target_tip_z
            change_line_length(st, wire, tip_error)
            if moved < 1e-7 and abs(tip_error) < 1e-7:
                break
        st.node_pos[m.release_node] = release
        _place_line(sim, "wire", release, h_w, v_w, direction=-1.0)
    if "mooring_line" in m.lines:
        _place_line(sim, "mooring_line", release, h_m, v_m)
    # vertical chain hangs straight below the release point, stretched by the anchor and its own weight
    total = sum(s.length_m for s in vc_sections)
    _, z_top = shape(0.0, anchor_weight, vc_sections, np.array([total]))
    back = release - np.array([0.0, 0.0, z_top[0]])
    _place_line(sim, "vertical_chain", back, 0.0, anchor_weight)
    b = st.body_state
    b[L.BS_POS: L.BS_POS + 3] = back - m.body_f[L.BF_S_BACK] * b[L.BS_AXIS: L.BS_AXIS + 3]

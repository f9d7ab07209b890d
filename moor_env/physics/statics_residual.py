"""Degrees of freedom, residual and finite-difference Jacobian of the static problem of a simulator state, for
the relaxation solver of ``physics/statics_relaxation.py``.

The unknowns are the positions of the free nodes and, where a line holds the anchor, its position and two small
rotations about axes normal to its axis. The residual is the net load on those unknowns from the *same* kernel as
the dynamics with all velocities zero. The Jacobian is built by finite differences with a distance-2 colouring of
the node graph (about ten residual evaluations per Jacobian whatever the node count).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from moor_env.physics import layout as L
from moor_env.physics.integrate import set_constrained_nodes


class StaticProblem:
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
        """The unknowns of the current state (node positions, then the anchor's position and zero rotations)."""
        st = self.sim.state
        x = np.zeros(self.n_dofs)
        x[: self.n_node_dofs] = st.node_pos[self.free].ravel()
        if self.body:
            x[self.n_node_dofs: self.n_node_dofs + 3] = st.body_state[L.BS_POS: L.BS_POS + 3]
            self.set_basis()
        return x

    def set_basis(self) -> None:
        """Two unit axes normal to the anchor's axis, about which its rotation unknowns turn it."""
        e = self.sim.state.body_state[L.BS_AXIS: L.BS_AXIS + 3]
        trial = np.array([1.0, 0.0, 0.0]) if abs(e[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u1 = np.cross(e, trial)
        u1 /= np.linalg.norm(u1)
        self.basis[0] = u1
        self.basis[1] = np.cross(e, u1)

    def set_x(self, x: np.ndarray, axis0: np.ndarray) -> None:
        """Write the unknowns ``x`` into the state at rest; the anchor axis is ``axis0`` turned by the rotations."""
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
        """Net load on every unknown [N, N m] at the current state, all velocities zero."""
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

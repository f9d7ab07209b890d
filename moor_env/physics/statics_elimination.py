"""O(N) solution of one static step's linear system (``physics/statics_system.py`` assembles it): block
elimination over the tree of lines (``physics/tree.py``), leaves first, the anchor's five unknowns (position, two
tilt angles) at the root, then back substitution from the root. The lines' contact with the anchor's body couples
nodes to the anchor outside the tree; those couplings are carried exactly through the elimination
(``physics/statics_contact.py``).

The passes over the nodes take no reference counts (``_jit.jit_no_refcount``): in a reference-counted kernel every
3x3 block view pays atomics, which cost more than the block's arithmetic. Only the anchor's 5x5 solve allocates, so
it and :func:`eliminate`, which calls it, stay reference counted.
"""

from __future__ import annotations

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.linalg3 import inverse3
from moor_env.physics.statics_contact import pass_on_eliminated, pass_on_parent
from moor_env.physics.tree import OR_EFF, OR_ORDER, TR_DEG, TR_NB, TR_SEG


@jit_step
def _solve_body(inv_tau2, p, basis, res_body, model, state, smat, rho_p, dq, contact, bmat, cmat, body_a, body_r):
    """The anchor's five unknowns from the lines' impedance ``smat`` and right-hand side ``rho_p`` at node p.

    (J^T S J + K_geo + D_b / tau^2) dq = R_b + J^T rho, with J the body node's motion per unknown (translation,
    then rotation about basis[0] and basis[1]); with ``contact``, plus the couplings the eliminated lines passed
    on (J^T B_p + C_p J + A) dq and their right-hand side (``physics/statics_contact.py``). Writes dq and returns
    the body node's motion J dq in ``rho_p``.
    """
    body_state = state.body_state
    node_force = state.node_force
    body_f = model.body_f
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    sp = state.node_f[p, L.NF_BODY_S]
    jac = np.zeros((3, 5))
    for c in range(3):
        jac[c, c] = 1.0
        jac[c, 3] = -sp * basis[1, c]  # s (u1 x e) = -s u2
        jac[c, 4] = sp * basis[0, c]  # s (u2 x e) = s u1
    a = jac.T @ smat @ jac
    rhs = res_body + jac.T @ rho_p
    geo = sp * (ex * node_force[p, 0] + ey * node_force[p, 1] + ez * node_force[p, 2])
    geo += body_f[L.BF_S_BUOY] * body_f[L.BF_BUOYANCY] * ez
    for c in range(3):
        a[c, c] += body_f[L.BF_MASS_AXIAL] * inv_tau2
    for c in range(3, 5):
        a[c, c] += body_f[L.BF_M22] * inv_tau2 + geo
    if contact:
        a += jac.T @ bmat[p] + cmat[p] @ jac + body_a
        rhs += body_r
    sol = np.linalg.solve(a, rhs)
    dq[:] = sol
    rho_p[:] = jac @ sol


@jit_step
def eliminate(inv_tau2, nq, body_node, basis, res_body, dq, model, state, dmat, coupling, tree, orow, contact,
              bmat, cmat, coupled, body_a, body_r, blocks):
    """Solve the assembled system in place: ``state.node_acc`` holds the right-hand side in and the step out (the
    anchor's in ``dq``), by block elimination over the tree, leaves first (x_c = D_c^-1 (r_c - K_cp x_p) once the
    parent p is known). With ``contact``, nodes coupled to the anchor outside the tree carry their coupling along
    (``physics/statics_contact.py``). ``blocks``: scratch (4, 3, 3), ``statics_system.new_scratch``'s last."""
    _eliminate_leaves(nq, state, dmat, coupling, tree, orow, contact, bmat, cmat, coupled, body_a, body_r, blocks)
    if body_node >= 0:
        rho_p = blocks[3, 1]
        rho_p[:] = state.node_acc[body_node]
        _solve_body(inv_tau2, body_node, basis, res_body, model, state, dmat[body_node], rho_p, dq, contact, bmat,
                    cmat, body_a, body_r)
        state.node_acc[body_node, :] = rho_p
    _substitute_back(nq, dq, state, dmat, coupling, tree, orow, contact, bmat, coupled, blocks[3, 0])


@jit_no_refcount
def _eliminate_leaves(nq, state, dmat, coupling, tree, orow, contact, bmat, cmat, coupled, body_a, body_r, blocks):
    """:func:`eliminate`'s pass from the leaves to the root: each node's block inverted into ``dmat``, its
    right-hand side solved in ``state.node_acc``, both passed on to its parent. The 3x3 products are written out:
    numpy's would allocate for every node."""
    seg_i = state.seg_i
    node_acc = state.node_acc
    inv = blocks[1]
    kpc_inv = blocks[2]
    r = blocks[3, 0]
    for k in range(nq):
        c = orow[k, OR_ORDER]
        inverse3(dmat[c], inv)
        for i in range(3):
            r[i] = inv[i, 0] * node_acc[c, 0] + inv[i, 1] * node_acc[c, 1] + inv[i, 2] * node_acc[c, 2]
        for i in range(3):
            node_acc[c, i] = r[i]
            for j in range(3):
                dmat[c, i, j] = inv[i, j]
        linked = contact and coupled[c] != 0
        if linked:
            pass_on_eliminated(c, inv, state, bmat, cmat, body_a, body_r)
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        p = tree[c, TR_NB]
        cp = 0 if orow[seg_i[s, L.SI_A], OR_EFF] == c else 1  # coupling[s, cp] = K_cp, coupling[s, 1 - cp] = K_pc
        pc = 1 - cp
        if linked:
            pass_on_parent(c, p, coupling[s, pc], coupling[s, cp], bmat, cmat, coupled)
        for i in range(3):
            for j in range(3):
                kpc_inv[i, j] = (coupling[s, pc, i, 0] * inv[0, j] + coupling[s, pc, i, 1] * inv[1, j]
                                 + coupling[s, pc, i, 2] * inv[2, j])
        for i in range(3):
            for j in range(3):
                dmat[p, i, j] -= (kpc_inv[i, 0] * coupling[s, cp, 0, j] + kpc_inv[i, 1] * coupling[s, cp, 1, j]
                                  + kpc_inv[i, 2] * coupling[s, cp, 2, j])
            node_acc[p, i] -= (coupling[s, pc, i, 0] * node_acc[c, 0] + coupling[s, pc, i, 1] * node_acc[c, 1]
                               + coupling[s, pc, i, 2] * node_acc[c, 2])


@jit_no_refcount
def _substitute_back(nq, dq, state, dmat, coupling, tree, orow, contact, bmat, coupled, r):
    """:func:`eliminate`'s pass from the root to the leaves: x_c = D_c^-1 r_c - D_c^-1 K_cp x_p (less the
    anchor's coupling), the parent's step known. ``r``: scratch (3)."""
    seg_i = state.seg_i
    node_acc = state.node_acc
    for k in range(nq - 1, -1, -1):
        c = orow[k, OR_ORDER]
        if contact and coupled[c] != 0:  # x_c -= D_c^-1 B_c dq
            for i in range(3):
                node_acc[c, i] -= bmat[c, i, 0] * dq[0] + bmat[c, i, 1] * dq[1] + bmat[c, i, 2] * dq[2] + \
                    bmat[c, i, 3] * dq[3] + bmat[c, i, 4] * dq[4]
        if tree[c, TR_DEG] != -1:
            continue
        s = tree[c, TR_SEG]
        p = tree[c, TR_NB]
        cp = 0 if orow[seg_i[s, L.SI_A], OR_EFF] == c else 1
        for i in range(3):
            r[i] = (coupling[s, cp, i, 0] * node_acc[p, 0] + coupling[s, cp, i, 1] * node_acc[p, 1]
                    + coupling[s, cp, i, 2] * node_acc[p, 2])
        for i in range(3):
            node_acc[c, i] -= dmat[c, i, 0] * r[0] + dmat[c, i, 1] * r[1] + dmat[c, i, 2] * r[2]

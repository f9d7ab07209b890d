"""Block tridiagonal-on-a-tree linear solves shared by the implicit step and the static Newton solve.

The node graph of a scene (welded nodes merged into their parent, vessel and fixed nodes prescribed, the
anchor's attachment node as the root of its component) is a tree, so a symmetric block system whose
off-diagonal blocks sit on the segments is solved in O(N) without fill-in by block Gaussian elimination leaves
first. Every coupling block is of the form -G with G = alpha q q^T + beta I (q a segment's unit tangent).

The ordering is built by peeling leaves: each node keeps its degree and the *sums* of its neighbours' and
segments' indices; when its degree is 1 those sums are its parent and its parent segment. It depends on the
topology alone, so callers may keep it between solves. A closed loop of lines is broken by lagging the coupling
of its extra edges (their stiffness stays on the diagonal), which keeps the solve defined.

Scratch layout: ``tree`` and ``orow`` are int64 arrays with one row per node (views of float workspaces).
Symmetric 3x3 blocks are stored as (xx, yy, zz, xy, xz, yz).
"""

from __future__ import annotations

from moor_env.physics._jit import jit_step
from moor_env.physics.layout import NI_KIND, NI_REF, NODE_FREE, NODE_WELDED, SI_A, SI_ACTIVE, SI_B
from moor_env.physics.linalg3 import inv_sym3

TR_DEG = 0  # remaining degree; -1 once eliminated below its parent, -2 once eliminated as a root
TR_NB = 1  # sum of remaining neighbour indices (the parent once the degree is 1)
TR_SEG = 2  # sum of remaining segment indices (the parent segment once the degree is 1)
OR_ORDER = 0  # elimination order (row k: k-th node eliminated)
OR_EFF = 1  # effective unknown of a node: itself (free / body root), its parent (welded), or -1 (prescribed)
OR_FLAGS = 2  # free for the caller (the implicit step keeps its active set there)


@jit_step
def add_sym(mm, n, xx, yy, zz, xy, xz, yz):
    mm[n, 0] += xx
    mm[n, 1] += yy
    mm[n, 2] += zz
    mm[n, 3] += xy
    mm[n, 4] += xz
    mm[n, 5] += yz


@jit_step
def effective_unknown(n, body_node, node_i):
    """The unknown that carries node n: itself (free, or the body root), its parent (welded), or -1."""
    kind = node_i[n, NI_KIND]
    if kind == NODE_FREE or n == body_node:
        return n
    if kind == NODE_WELDED:
        p = node_i[n, NI_REF]
        if node_i[p, NI_KIND] == NODE_FREE or p == body_node:
            return p
    return -1


@jit_step
def build_tree(body_node, node_i, seg_i, tree, orow):
    """Effective unknown of every node, tree degrees and neighbour/segment sums."""
    nn = node_i.shape[0]
    for n in range(nn):
        orow[n, OR_EFF] = effective_unknown(n, body_node, node_i)
        tree[n, TR_DEG] = 0
        tree[n, TR_NB] = 0
        tree[n, TR_SEG] = 0
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0:
            continue
        ea = orow[seg_i[s, SI_A], OR_EFF]
        eb = orow[seg_i[s, SI_B], OR_EFF]
        if ea == eb:
            continue  # both prescribed, or a welded node and its parent: internal
        if ea >= 0 and eb >= 0:
            tree[ea, TR_DEG] += 1
            tree[ea, TR_NB] += eb
            tree[ea, TR_SEG] += s
            tree[eb, TR_DEG] += 1
            tree[eb, TR_NB] += ea
            tree[eb, TR_SEG] += s


@jit_step
def count_unknowns(body_node, orow):
    """Number of unknowns of an order kept from the previous step (every one of them is in the order)."""
    nq = 0
    for n in range(orow.shape[0]):
        if orow[n, OR_EFF] == n and n != body_node:
            nq += 1
    return nq


@jit_step
def order(body_node, node_i, seg_i, tree, orow):
    """Leaves-first elimination order into orow[:, OR_ORDER]; returns the number of unknowns ordered."""
    nn = node_i.shape[0]
    n_unknown = 0
    nq = 0
    for n in range(nn):
        if orow[n, OR_EFF] == n and n != body_node:
            n_unknown += 1
            if tree[n, TR_DEG] <= 1:
                orow[nq, OR_ORDER] = n
                nq += 1
    head = 0
    while True:
        while head < nq:
            c = orow[head, OR_ORDER]
            head += 1
            if tree[c, TR_DEG] == 1:
                p = tree[c, TR_NB]
                tree[p, TR_DEG] -= 1
                tree[p, TR_NB] -= c
                tree[p, TR_SEG] -= tree[c, TR_SEG]
                if p != body_node and tree[p, TR_DEG] == 1:
                    orow[nq, OR_ORDER] = p
                    nq += 1
                tree[c, TR_DEG] = -1
            else:
                tree[c, TR_DEG] = -2
        if nq >= n_unknown:
            return nq
        # a cycle: eliminate its first node below one neighbour and lag the coupling of its other edges
        c = -1
        for n in range(nn):
            if orow[n, OR_EFF] == n and n != body_node and tree[n, TR_DEG] >= 2:
                c = n
                break
        if c < 0:
            return nq
        parent = -1
        pseg = -1
        for s in range(seg_i.shape[0]):
            if seg_i[s, SI_ACTIVE] == 0:
                continue
            ea = orow[seg_i[s, SI_A], OR_EFF]
            eb = orow[seg_i[s, SI_B], OR_EFF]
            if ea == eb or ea < 0 or eb < 0 or (ea != c and eb != c):
                continue
            x = eb if ea == c else ea
            if tree[x, TR_DEG] < 0:
                continue
            if parent < 0:
                parent = x
                pseg = s
            else:
                tree[x, TR_DEG] -= 1
                tree[x, TR_NB] -= c
                tree[x, TR_SEG] -= s
                if x != body_node and tree[x, TR_DEG] == 1:
                    orow[nq, OR_ORDER] = x
                    nq += 1
        tree[c, TR_DEG] = 1
        tree[c, TR_NB] = parent
        tree[c, TR_SEG] = pseg
        orow[nq, OR_ORDER] = c
        nq += 1


@jit_step
def invert_block(node_mm, node_acc, c):
    """Eliminate node c: node_mm[c] <- D_c^-1, node_acc[c] <- y_c = D_c^-1 r_c."""
    i11, i22, i33, i12, i13, i23 = inv_sym3(node_mm[c, 0], node_mm[c, 1], node_mm[c, 2], node_mm[c, 3],
                                             node_mm[c, 4], node_mm[c, 5])
    node_mm[c, 0] = i11
    node_mm[c, 1] = i22
    node_mm[c, 2] = i33
    node_mm[c, 3] = i12
    node_mm[c, 4] = i13
    node_mm[c, 5] = i23
    rx = node_acc[c, 0]
    ry = node_acc[c, 1]
    rz = node_acc[c, 2]
    node_acc[c, 0] = i11 * rx + i12 * ry + i13 * rz
    node_acc[c, 1] = i12 * rx + i22 * ry + i23 * rz
    node_acc[c, 2] = i13 * rx + i23 * ry + i33 * rz


@jit_step
def schur_into_parent(node_mm, node_acc, c, p, alpha, beta, qx, qy, qz):
    """D_p -= G D_c^-1 G and r_p += G y_c for the coupling -G (G = alpha q q^T + beta I) of an eliminated c."""
    i11 = node_mm[c, 0]
    i22 = node_mm[c, 1]
    i33 = node_mm[c, 2]
    i12 = node_mm[c, 3]
    i13 = node_mm[c, 4]
    i23 = node_mm[c, 5]
    yx = node_acc[c, 0]
    yy = node_acc[c, 1]
    yz = node_acc[c, 2]
    wx = i11 * qx + i12 * qy + i13 * qz
    wy = i12 * qx + i22 * qy + i23 * qz
    wz = i13 * qx + i23 * qy + i33 * qz
    a2 = alpha * alpha * (qx * wx + qy * wy + qz * wz)
    ab = alpha * beta
    b2 = beta * beta
    add_sym(node_mm, p, -(a2 * qx * qx + 2.0 * ab * qx * wx + b2 * i11),
             -(a2 * qy * qy + 2.0 * ab * qy * wy + b2 * i22),
             -(a2 * qz * qz + 2.0 * ab * qz * wz + b2 * i33),
             -(a2 * qx * qy + ab * (qx * wy + wx * qy) + b2 * i12),
             -(a2 * qx * qz + ab * (qx * wz + wx * qz) + b2 * i13),
             -(a2 * qy * qz + ab * (qy * wz + wy * qz) + b2 * i23))
    gy = alpha * (qx * yx + qy * yy + qz * yz)
    node_acc[p, 0] += gy * qx + beta * yx
    node_acc[p, 1] += gy * qy + beta * yy
    node_acc[p, 2] += gy * qz + beta * yz


@jit_step
def back_from_parent(node_mm, node_acc, c, p, alpha, beta, qx, qy, qz):
    """x_c = y_c + D_c^-1 G x_p once the parent's solution is in node_acc[p]."""
    dpx = node_acc[p, 0]
    dpy = node_acc[p, 1]
    dpz = node_acc[p, 2]
    qd = alpha * (qx * dpx + qy * dpy + qz * dpz)
    gx = qd * qx + beta * dpx
    gy = qd * qy + beta * dpy
    gz = qd * qz + beta * dpz
    node_acc[c, 0] += node_mm[c, 0] * gx + node_mm[c, 3] * gy + node_mm[c, 4] * gz
    node_acc[c, 1] += node_mm[c, 3] * gx + node_mm[c, 1] * gy + node_mm[c, 5] * gz
    node_acc[c, 2] += node_mm[c, 4] * gx + node_mm[c, 5] * gy + node_mm[c, 2] * gz

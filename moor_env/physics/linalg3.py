"""3x3 linear algebra of the kernels: symmetric helpers by the adjugate, a general inverse by pivoted elimination.

A symmetric 3x3 system A x = r is solved as x = adj(A) r / det(A), with the cofactors C_ij of A (adj(A) = C^T)
and det(A) = a_11 C_11 + a_12 C_12 + a_13 C_13 (expansion along the first row); its cofactors are symmetric too
and six of them suffice: :func:`inv_sym3` (the inverse, as 6 entries, for the block elimination of ``tree.py``)
and :func:`solve_sym3` (one solve with a shifted matrix, for the explicit node accelerations). There every block
carries the node mass over the time step squared, which keeps it well conditioned.

:func:`inverse3` inverts a general 3x3 matrix (the static solver's blocks, which its drag stiffness makes
unsymmetric) by Gaussian elimination with partial pivoting. Why not the adjugate: a static block holds a chain
segment's axial stiffness EA / l0 (7e9 N/m for 0.25 m of 142 mm chain) beside the transverse stiffness of a
line near zero tension (1-100 N/m), and the adjugate's rounding error in the stiff direction grows with the
square of that ratio. The elimination multiplies that error by (EA / l0)^2 into the parent's block: at a ratio of
7e7 (100 N/m) some 1e7-1e8 N/m, as much as the line's own axial stiffness over its length. At a chain loop
hanging in a U, the adjugate turns the step at the loop's bottom around (a linear residual of a third of the
right-hand side), and Newton's method wanders for hundreds of iterations near the solution. Pivoted elimination
keeps the error proportional to the ratio (tens of N/m there).

Symmetric matrices are passed as their six entries (xx, yy, zz, xy, xz, yz).
"""

from __future__ import annotations

from moor_env.physics._jit import jit, jit_step


@jit_step
def inv_sym3(a11, a22, a33, a12, a13, a23):
    """Inverse of the symmetric 3x3 [[a11, a12, a13], [a12, a22, a23], [a13, a23, a33]] as 6 entries."""
    c11 = a22 * a33 - a23 * a23
    c12 = a13 * a23 - a12 * a33
    c13 = a12 * a23 - a13 * a22
    c22 = a11 * a33 - a13 * a13
    c23 = a12 * a13 - a11 * a23
    c33 = a11 * a22 - a12 * a12
    inv = 1.0 / (a11 * c11 + a12 * c12 + a13 * c13)
    return c11 * inv, c22 * inv, c33 * inv, c12 * inv, c13 * inv, c23 * inv


@jit
def solve_sym3(m, a, b, c, d, e, f, rx, ry, rz):
    """Solve (m I + S) x = r for the symmetric S = [[a, d, e], [d, b, f], [e, f, c]]."""
    a11 = m + a
    a22 = m + b
    a33 = m + c
    c11 = a22 * a33 - f * f
    c12 = e * f - d * a33
    c13 = d * f - e * a22
    c22 = a11 * a33 - e * e
    c23 = d * e - a11 * f
    c33 = a11 * a22 - d * d
    det = a11 * c11 + d * c12 + e * c13
    inv = 1.0 / det
    return (
        (c11 * rx + c12 * ry + c13 * rz) * inv,
        (c12 * rx + c22 * ry + c23 * rz) * inv,
        (c13 * rx + c23 * ry + c33 * rz) * inv,
    )


@jit_step(inline="always")
def _minus(u, f, v):
    """u - f v for 3-vectors held as tuples."""
    return (u[0] - f * v[0], u[1] - f * v[1], u[2] - f * v[2])


@jit_step
def inverse3(m, out):
    """Inverse of the general 3x3 matrix ``m`` into ``out``, by Gaussian elimination with partial pivoting."""
    rows = ((m[0, 0], m[0, 1], m[0, 2]), (m[1, 0], m[1, 1], m[1, 2]), (m[2, 0], m[2, 1], m[2, 2]))
    units = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    p = 0
    if abs(m[1, 0]) > abs(m[p, 0]):
        p = 1
    if abs(m[2, 0]) > abs(m[p, 0]):
        p = 2
    q, r = (1, 2) if p == 0 else ((0, 2) if p == 1 else (0, 1))
    a, ea = rows[p], units[p]
    b, eb = rows[q], units[q]
    c, ec = rows[r], units[r]
    f = b[0] / a[0]
    b, eb = _minus(b, f, a), _minus(eb, f, ea)
    f = c[0] / a[0]
    c, ec = _minus(c, f, a), _minus(ec, f, ea)
    if abs(c[1]) > abs(b[1]):
        b, c, eb, ec = c, b, ec, eb
    f = c[1] / b[1]
    c, ec = _minus(c, f, b), _minus(ec, f, eb)
    for j in range(3):  # back substitution, column by column of the permuted identity
        x2 = ec[j] / c[2]
        x1 = (eb[j] - b[2] * x2) / b[1]
        out[0, j] = (ea[j] - a[1] * x1 - a[2] * x2) / a[0]
        out[1, j] = x1
        out[2, j] = x2

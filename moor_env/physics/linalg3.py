"""3x3 linear algebra of the kernels: one symmetric and one general helper, by the adjugate.

A 3x3 system A x = r is solved as x = adj(A) r / det(A), with the cofactors C_ij of A (adj(A) = C^T) and
det(A) = a_11 C_11 + a_12 C_12 + a_13 C_13 (expansion along the first row). For a symmetric A the cofactors are
symmetric too and six of them suffice: :func:`inv_sym3` (the inverse, as 6 entries, for the block elimination of
``tree.py``) and :func:`solve_sym3` (one solve with a shifted matrix, for the explicit node accelerations).
:func:`inverse3` inverts a general 3x3 matrix (the static solver's blocks, which its drag stiffness makes
unsymmetric).

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


@jit_step
def inverse3(m, out):
    """Inverse of the general 3x3 matrix ``m`` into ``out``."""
    c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
    c01 = m[0, 2] * m[2, 1] - m[0, 1] * m[2, 2]
    c02 = m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]
    c10 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
    c11 = m[0, 0] * m[2, 2] - m[0, 2] * m[2, 0]
    c12 = m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]
    c20 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
    c21 = m[0, 1] * m[2, 0] - m[0, 0] * m[2, 1]
    c22 = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    inv = 1.0 / (m[0, 0] * c00 + m[0, 1] * c10 + m[0, 2] * c20)
    out[0, 0] = c00 * inv
    out[0, 1] = c01 * inv
    out[0, 2] = c02 * inv
    out[1, 0] = c10 * inv
    out[1, 1] = c11 * inv
    out[1, 2] = c12 * inv
    out[2, 0] = c20 * inv
    out[2, 1] = c21 * inv
    out[2, 2] = c22 * inv

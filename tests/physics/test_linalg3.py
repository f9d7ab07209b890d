"""The kernels' 3x3 linear algebra (``moor_env/physics/linalg3.py``) against numpy and closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env.physics.linalg3 import inv_sym3, inverse3, solve_sym3


def _inverse(m: np.ndarray) -> np.ndarray:
    out = np.empty((3, 3))
    inverse3(np.ascontiguousarray(m, dtype=float), out)
    return out


def test_inverse3_of_general_matrices():
    """Reference: numpy's inverse. Tolerance: m^-1 m within 1e-12 of the identity on 200 random matrices, and
    on matrices whose first (or first two) leading entries are zero, which need the rows exchanged."""
    rng = np.random.default_rng(5)
    for m in rng.normal(size=(200, 3, 3)):
        assert np.abs(_inverse(m) @ m - np.eye(3)).max() < 1e-12
    for m in ([[0.0, 1.0, 2.0], [1.0, 0.0, 3.0], [4.0, 5.0, 0.0]], [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
              [[0.0, 2.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 4.0]]):
        m = np.array(m)
        assert np.abs(_inverse(m) @ m - np.eye(3)).max() < 1e-12
        assert np.allclose(_inverse(m), np.linalg.inv(m), rtol=0.0, atol=1e-14)


@pytest.mark.parametrize("transverse_n_m", [1e4, 1e2, 1.0])
def test_inverse3_keeps_the_stiff_direction_of_a_chain_block(transverse_n_m):
    """A static block of a chain segment near zero tension: axial stiffness k_a = 7e9 N/m (EA / l0 of 0.25 m of
    142 mm chain) along q, transverse k_t across it, with a small unsymmetric part S (the current drag's turn,
    1e-3 k_t). Reference: the closed-form inverse of k_a q q^T + k_t (I - q q^T), q^T inv q = 1 / k_a (S changes it
    only at second order, by about |S|^2 / (k_t k_a^2)). Tolerance: the block elimination multiplies the error of
    q^T inv q by k_a^2 into the parent's block, which must stay below 1e-4 of k_a (0.7 MN/m); pivoted
    elimination's error there is at most 5e3 N/m at these ratios, the adjugate's up to 4e8 N/m at k_t = 100 N/m."""
    rng = np.random.default_rng(11)
    k_axial = 7e9
    for _ in range(100):
        q = rng.normal(size=3)
        q /= np.linalg.norm(q)
        projection = np.outer(q, q)
        skew = rng.normal(size=(3, 3)) * 1e-3 * transverse_n_m
        skew -= skew.T
        block = k_axial * projection + transverse_n_m * (np.eye(3) - projection) + skew
        error_n_m = abs(q @ _inverse(block) @ q - 1.0 / k_axial) * k_axial**2
        assert error_n_m < 1e-4 * k_axial


def test_symmetric_helpers_match_numpy():
    """Reference: numpy's inverse and solve of a symmetric positive definite matrix. Tolerance 1e-12 relative."""
    rng = np.random.default_rng(2)
    for _ in range(50):
        a = rng.normal(size=(3, 3))
        s = a @ a.T + 0.1 * np.eye(3)
        entries = (s[0, 0], s[1, 1], s[2, 2], s[0, 1], s[0, 2], s[1, 2])
        i11, i22, i33, i12, i13, i23 = inv_sym3(*entries)
        inv = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
        assert np.allclose(inv, np.linalg.inv(s), rtol=1e-12, atol=0.0)
        r = rng.normal(size=3)
        x = solve_sym3(2.0, *entries, *r)
        assert np.allclose(x, np.linalg.solve(s + 2.0 * np.eye(3), r), rtol=1e-12, atol=1e-14)

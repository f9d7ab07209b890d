"""The analytic elastic catenary's kernels (``physics/catenary_kernels.py``): the static solver's first guess."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env.physics import catenary_kernels as K
from moor_env.physics.catenary import Section, solve_suspended

# chain + polyester + chain, from the bottom: weight [N/m], EA [N], length [m] (the gjoa-500 mooring line's kind)
SECTIONS = [(1375.0, 1.3e9, 150.0), (30.0, 2.0e8, 350.0), (1375.0, 1.3e9, 60.0)]


def _arrays(sections):
    w, ea, length = (np.array(c, dtype=float) for c in zip(*sections, strict=True))
    return w, ea, length


@pytest.mark.parametrize(("dx", "dz"), [(400.0, 300.0), (520.0, 80.0), (150.0, 450.0), (545.0, -20.0)])
def test_suspended_newton_matches_the_reference_catenary(dx, dz):
    """Reference: ``catenary.solve_suspended`` (scipy's hybrid root finder on the same closed form, to 1e-13).
    Newton's method converges from the parabola's estimate and agrees with it and with the nested bracketing it
    stands in for to 1e-8 of the line's weight; the line then ends at B within the solve's tolerance (1e-10 of
    its length and span)."""
    w, ea, length = _arrays(SECTIONS)
    total, weight = float(length.sum()), float((w * length).sum())
    h, va, converged = K._suspended_newton(dx, dz, w, ea, length, total, weight)
    assert converged
    h_ref, va_ref = solve_suspended(dx, dz, [Section(*s) for s in SECTIONS])
    assert abs(h - h_ref) < 1e-8 * weight and abs(va - va_ref) < 1e-8 * weight
    h_br = K._suspended_h(dx, dz, w, ea, length, total, weight, 1e-9 * weight + 1e-6, 10.0 * weight + 1.0)
    va_br = K.suspended_va(h_br, dz, w, ea, length, total, weight)
    assert abs(h - h_br) < 1e-8 * weight and abs(va - va_br) < 1e-8 * weight
    x, z, _ = K.walk(h, va, w, ea, length, 0.0, total)
    tol_m = 1e-10 * (total + np.hypot(dx, dz))  # the solve's own tolerance
    assert abs(x - dx) < tol_m and abs(z - dz) < tol_m


def test_suspended_newton_declines_a_vertical_span():
    """A vertical span (H = 0) is left to the bracketing, which hang_line still solves: its 60 m of slack hang as
    a loop about 30 m below end A, clear of a seabed 100 m down."""
    w, ea, length = _arrays(SECTIONS)
    total, weight = float(length.sum()), float((w * length).sum())
    assert not K._suspended_newton(0.0, 500.0, w, ea, length, total, weight)[2]
    out = np.zeros((0, 2))
    h, va, mode = K.hang_line(0.0, 500.0, -100.0, w, ea, length, np.zeros(0), out)
    assert mode == 0 and h < 1e-3 * weight and va < 0.0


def test_walk_jacobian_matches_finite_differences():
    """The closed-form partial derivatives of the end point against central differences (relative 1e-6)."""
    w, ea, length = _arrays(SECTIONS)
    h, v0 = 3.0e5, -2.0e5
    _, _, x_h, x_v, z_h, z_v = K._walk_jacobian(h, v0, w, ea, length)
    eps_h, eps_v = 1e-4 * h, 1e-4 * abs(v0)
    plus, minus = K._walk_jacobian(h + eps_h, v0, w, ea, length), K._walk_jacobian(h - eps_h, v0, w, ea, length)
    assert x_h == pytest.approx((plus[0] - minus[0]) / (2 * eps_h), rel=1e-6)
    assert z_h == pytest.approx((plus[1] - minus[1]) / (2 * eps_h), rel=1e-6)
    plus, minus = K._walk_jacobian(h, v0 + eps_v, w, ea, length), K._walk_jacobian(h, v0 - eps_v, w, ea, length)
    assert x_v == pytest.approx((plus[0] - minus[0]) / (2 * eps_v), rel=1e-6)
    assert z_v == pytest.approx((plus[1] - minus[1]) / (2 * eps_v), rel=1e-6)

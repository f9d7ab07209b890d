"""Anchor alone: the free fall against the closed-form 1-DOF solution and the RIFLEX result of seed 003
(Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, Table 8-4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from moor_env import compile_scene, load_scene, simulate_drop
from moor_env.physics import layout as L


def _closed_form(model):
    """m dv/dt = W' - k v^2 with m the inertial mass, W' weight minus buoyancy, k = 1/2 rho C A (axial)."""
    bf = model.body_f
    rho = model.env_f[L.EF_RHO]
    props = model.extras["anchor"]
    quad = props.quadrature
    axial_cd_area = bf[L.BF_TIP_CDA] + bf[L.BF_BACK_CDA] + quad[:, L.BQ_CDT_PID] @ quad[:, L.BQ_DS]
    k = 0.5 * rho * axial_cd_area
    mass = bf[L.BF_MASS_AXIAL]
    weight = bf[L.BF_WEIGHT] - bf[L.BF_BUOYANCY]
    v_t = math.sqrt(weight / k)
    return mass, k, v_t


def test_speed_history_matches_closed_form():
    """Reference: closed form v(t) = v_t tanh(k v_t t / m) of m dv/dt = W' - k v^2. Tolerance 0.5 %."""
    result = simulate_drop("anchor-only")
    mass, k, v_t = _closed_form(compile_scene(load_scene("anchor-only")))
    hist = result.history
    t = hist[:, L.H_TIME]
    speed = -hist[:, L.H_TIP_VEL + 2]
    exact = v_t * np.tanh(k * v_t * t / mass)
    late = t > 0.5
    assert np.max(np.abs(speed[late] / exact[late] - 1.0)) < 0.005
    h = 68.5
    v_touch = v_t * math.sqrt(1.0 - math.exp(-2.0 * k * h / mass))
    assert result.touchdown_speed_m_s == pytest.approx(v_touch, rel=0.005)


def test_against_seed_riflex_anchor_only():
    """Reference: seed 003 Table 8-4 (RIFLEX): 26.2 m/s at about 4.5 s from the 68.5 m drop. Tolerance 4 %."""
    result = simulate_drop("anchor-only")
    assert result.touchdown_speed_m_s == pytest.approx(26.2, rel=0.04)
    assert result.touchdown_time_s == pytest.approx(4.5, rel=0.04)
    assert result.tilt_deg < 1e-6


def test_terminal_velocity_against_seed():
    """Reference: seed 003 Table 8-4, terminal velocity about 33.3 m/s (RIFLEX, seabed stiffness off).
    A 450 m fall reaches 99.99 % of terminal velocity. Tolerance 4 %."""
    result = simulate_drop("anchor-only", {"drop_height_m": 450.0})
    assert result.touchdown_speed_m_s == pytest.approx(33.3, rel=0.04)


def test_anchor_only_starts_at_the_drop_height():
    """The anchor alone has no static unknowns: it must start exactly at the set drop height."""
    from moor_env import solve_statics

    static = solve_statics(load_scene("anchor-only"))
    assert static.tip_height_above_seabed_m == pytest.approx(68.5, abs=1e-9)

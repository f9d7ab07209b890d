"""The line-anchor contact in the fall: the vertical chain lands on the anchor instead of passing into it.

References: seed 003's 1-DOF limits of the vertical-chain scene (Landhaug 2015, *Dynamic Simulation of Dart Anchor
Installation*; the extract's section 4.6): the anchor alone lands at 26.30 m/s (the slack chain adds nothing), the
anchor and its 50 m chain as one column at 26.8 m/s (the chain's weight added, its lengthwise drag negligible).
"""

from __future__ import annotations

import pytest

from moor_env import load_scene, simulate_drop, solve_statics
from moor_env.physics import layout as L
from moor_env.simulation import run_drop

ANCHOR_ALONE_M_S = 26.30
ANCHOR_AND_COLUMN_M_S = 26.8


def _drop(scene: str, **overrides):
    return simulate_drop(scene, overrides)


@pytest.fixture(scope="module")
def explicit():
    return _drop("vertical-chain")


@pytest.fixture(scope="module")
def implicit():
    return _drop("vertical-chain", integrator="implicit_euler")


def test_vertical_chain_lands_between_the_one_dof_limits(explicit):
    """Reference: between the 1-DOF limits 26.30 and 26.8 m/s. Why there: the chain gains on the anchor all the
    fall (its lengthwise terminal speed is 41 m/s, the anchor's touchdown speed 26.3 m/s) and what reaches the back
    end stops on it: by touchdown 9 of the 50 m rest on the anchor, adding their momentum and weight (34 kN on the
    anchor's 688 kN net), while the rest of the column still falls freely behind it. Nothing passes into the
    anchor: the chain ends within 5 cm of the back end and no node went more than 5 cm inside."""
    assert explicit.line_anchor_contact
    assert ANCHOR_ALONE_M_S < explicit.touchdown_speed_m_s < ANCHOR_AND_COLUMN_M_S
    assert explicit.chain_on_anchor_m > 5.0
    assert explicit.chain_past_back_end_m < 0.05
    assert explicit.contact_peak_depth_m < 0.05
    assert explicit.contact_peak_force_n > 0.0


@pytest.mark.parametrize("change", [{"dt_s": 0.5}, {"discretization.contact_stiffness_scale": 2.0},
                                    {"discretization.contact_stiffness_scale": 0.5}])
def test_vertical_chain_converged_explicit(explicit, change):
    """Reference: the explicit fall itself; touchdown speed within 0.2 % with the step halved or the contact
    stiffness halved or doubled (the step cannot be doubled: it is 0.9 of the explicit stability limit)."""
    overrides = {k: (v * explicit.dt_s if k == "dt_s" else v) for k, v in change.items()}
    result = _drop("vertical-chain", **overrides)
    assert result.touchdown_speed_m_s == pytest.approx(explicit.touchdown_speed_m_s, rel=0.002)
    assert result.contact_peak_depth_m < 0.05


@pytest.mark.parametrize("change", [{"dt_s": 0.5}, {"dt_s": 2.0}, {"discretization.contact_stiffness_scale": 2.0},
                                    {"discretization.contact_stiffness_scale": 0.5}])
def test_vertical_chain_converged_implicit(implicit, change):
    """Reference: the implicit fall at its default step (11.25 ms); touchdown speed within 0.2 % with the step or
    the contact stiffness halved or doubled; and within 0.3 % of the explicit fall (measured 0.15 %: backward Euler
    makes each landing inelastic within a step)."""
    overrides = {k: (v * implicit.dt_s if k == "dt_s" else v) for k, v in change.items()}
    result = _drop("vertical-chain", integrator="implicit_euler", **overrides)
    assert result.touchdown_speed_m_s == pytest.approx(implicit.touchdown_speed_m_s, rel=0.002)
    assert result.chain_past_back_end_m < 0.05


def test_implicit_close_to_explicit(explicit, implicit):
    """Reference: the explicit fall; the implicit one within 0.3 % (module docstring of test above), resting
    chain within 3 m of it, and no node inside the anchor at the start of any step."""
    assert implicit.touchdown_speed_m_s == pytest.approx(explicit.touchdown_speed_m_s, rel=0.003)
    assert abs(implicit.chain_on_anchor_m - explicit.chain_on_anchor_m) <= 3.0
    assert implicit.contact_peak_depth_m < 0.05


def test_contact_only_where_the_chain_catches_up():
    """Reference: the 1-DOF catch-up estimate (physics/contact_setup.py): with the DNV tangential drag (0.4456)
    the chain never reaches the anchor and the contact is off, the fall then the one without contact bit for bit;
    with the seed's 0.0069 it is on."""
    dnv = {"chain_cd_tangential": 0.4456}
    auto = _drop("vertical-chain", **dnv)
    off = _drop("vertical-chain", **dnv, **{"discretization.line_anchor_contact": "off"})
    assert not auto.line_anchor_contact and auto.contact_peak_force_n is None
    assert auto.touchdown_speed_m_s == off.touchdown_speed_m_s
    assert auto.touchdown_speed_m_s == pytest.approx(10.57, abs=0.1)


def test_contact_peaks_count_from_the_release():
    """Reference: the contact's record is zeroed at the release, so a simulator that fell once and is restored
    to its equilibrium reports the second fall's peaks only (the same as the first, bit for bit)."""
    static = solve_statics(load_scene("vertical-chain", {"drop_height_m": 20.0, "vertical_chain_length_m": 20.0}))
    sim = static.simulator
    saved = sim.state.copy()
    first = run_drop(sim, history=False)
    sim.state = saved
    sim.work.contact_out[L.CO_PEAK_FORCE] = 1e12
    second = run_drop(sim, history=False)
    assert second.contact_peak_force_n == first.contact_peak_force_n
    assert second.touchdown_speed_m_s == first.touchdown_speed_m_s


@pytest.mark.parametrize("scene, overrides", [
    ("gjoa-500", {}), ("gjoa-500", {"integrator": "implicit_euler"}), ("gjoa-500", {"fidelity": "fast"}),
    ("gjoa-500", {"current_scale": 1.0}), ("gjoa-500", {"vessel_spacing_m": 110.0}),
    ("gjoa-500", {"vessel_spacing_m": 0.0}), ("gjoa-500", {"vessel_spacing_m": 0.0, "integrator": "implicit_euler"}),
    ("vertical-chain", {"vertical_chain_length_m": 10.0}), ("deep-1500", {"fidelity": "fast"}),
])
def test_no_chain_inside_the_anchor_in_bundled_scenes(scene, overrides):
    """Reference: the contact's purpose; in the bundled scenes and their catch-up variants (at spacing 0 the
    fall starts with the loop resting on the anchor) no node goes more than 5 cm inside the anchor during the fall
    and the vertical chain ends behind the back end (within 5 cm)."""
    result = _drop(scene, **overrides)
    assert result.status == "touchdown"
    assert result.line_anchor_contact
    assert result.contact_peak_depth_m < 0.05
    assert result.chain_past_back_end_m < 0.05


@pytest.mark.parametrize("scene", ["vertical-chain", "gjoa-500"])
def test_broad_phase_leaves_out_only_nodes_that_cannot_reach(scene):
    """Reference: the implicit fall with every free node a candidate of the contact set (a speed limit of 1e12 m/s
    puts all of them inside the broad phase's radius, ``implicit_contact_set.init_contact_set``): the fall at the
    default limit is the same bit for bit, so the broad phase drops no node that the contact set would take."""
    implicit = {"integrator": "implicit_euler"}
    default = _drop(scene, **implicit)
    everyone = _drop(scene, **implicit, **{"simulation.speed_limit_m_s": 1e12})
    assert default.touchdown_speed_m_s == everyone.touchdown_speed_m_s
    assert default.contact_peak_force_n == everyone.contact_peak_force_n
    assert default.chain_on_anchor_m == everyone.chain_on_anchor_m

"""Contact between line segments and the anchor's surface (moor_env.physics.segment_contact).

The anchor is the DPA of the node contact's tests (``test_contact.py``: 13 m long, 1.2 m diameter); the chain
piece and the contact's parameters are theirs (1 m of the 142 mm chain, 442 kg per node).
"""

from __future__ import annotations

import numpy as np
import pytest

from moor_env.physics import layout as L
from moor_env.physics import segment_contact as G
from tests.physics.test_contact import MASS_KG, RADIUS_M, S_BACK_M, SHAPE, body, params, point

DT_S = 2e-4
ALL = np.full(1, -1, np.int64)  # no list of segments near the anchor: the passes visit all


def _rim_segment(state):
    """A segment from 1 cm behind the back end face, 0.3 m in from its rim, to 1 cm beside the shaft, 0.95 m ahead
    of the back end (``test_contact.test_segment_across_the_back_rim``): both nodes outside, its interior cuts the
    rim; inside the corner the depth is min(R - rho, a - back), deepest where the two are equal (closed form)."""
    a0, rho0 = S_BACK_M - 0.01, RADIUS_M - 0.3
    a1, rho1 = S_BACK_M + 0.95, RADIUS_M + 0.01
    t_ref = ((RADIUS_M - rho0) - (a0 - S_BACK_M)) / ((a1 - a0) + (rho1 - rho0))
    depth_ref = RADIUS_M - (rho0 + t_ref * (rho1 - rho0))
    return point(state, a0, rho0, angle=0.0), point(state, a1, rho1, angle=0.0), t_ref, depth_ref


def _two_nodes(x0, x1, kinds=(L.NODE_FREE, L.NODE_FREE)):
    node_pos = np.array([x0, x1], float)
    node_i = np.zeros((2, L.N_NODE_I), np.int64)
    node_i[:, L.NI_KIND] = kinds
    seg_i = np.zeros((1, L.N_SEG_I), np.int64)
    seg_i[0, L.SI_B] = 1
    seg_i[0, L.SI_ACTIVE] = 1
    return node_pos, node_i, seg_i


def test_segment_across_the_rim_is_pushed_off_it():
    """Reference: the closed-form deepest point of the rim segment (depth and t within 1e-6 m and 1e-6): both nodes
    are outside, so the excess is that depth. The deepest point is the kink where the back face's depth meets the
    shaft's, so the contact's direction is the combination g = l n_face + (1 - l) n_shaft perpendicular to the
    segment (l = (n_shaft . s) / (n_shaft . s - n_face . s)); the contact acts along g / |g| on the excess e |g|
    with the stiffness factor |g|^2 (1e-9)."""
    state = body(axis=(0.0, 0.0, -1.0))
    x0, x1, t_ref, depth_ref = _rim_segment(state)
    e, t, px, py, pz, nx, ny, nz, scale, node_inside = G.segment_geometry(*x0, *x1, state, SHAPE)[:10]
    assert not node_inside and t == pytest.approx(t_ref, abs=1e-6)
    axis = state[L.BS_AXIS:L.BS_AXIS + 3]
    radial = point(state, 0.0, 1.0, angle=0.0) - point(state, 0.0, 0.0, angle=0.0)
    seg = (x1 - x0) / np.linalg.norm(x1 - x0)
    share = (radial @ seg) / (radial @ seg - (-axis) @ seg)
    g = share * (-axis) + (1.0 - share) * radial
    assert scale == pytest.approx(g @ g, abs=1e-9)
    assert e == pytest.approx(depth_ref * np.linalg.norm(g), abs=1e-6)
    assert np.allclose([nx, ny, nz], g / np.linalg.norm(g), atol=1e-9) and abs(np.array([nx, ny, nz]) @ seg) < 1e-9
    assert np.allclose([px, py, pz], x0 + t * (x1 - x0), atol=1e-12)


@pytest.mark.parametrize("depth_m", [0.0, 0.005])
def test_no_excess_where_the_nodes_hold_the_segment(depth_m):
    """Reference: a segment along the shaft with both nodes at one depth (on the surface, 5 mm inside) is held by
    the node contact alone: the depth is the same all along it, the excess zero (1e-12 m); a segment 10 cm clear
    of the shaft has a gap of 10 cm (negative excess, 1e-9 m)."""
    state = body(axis=(0.2, 0.1, -1.0), pos=(1.0, 2.0, -300.0))
    x0 = point(state, -2.0, RADIUS_M - depth_m)
    x1 = point(state, -1.0, RADIUS_M - depth_m)
    assert G.segment_geometry(*x0, *x1, state, SHAPE)[0] == pytest.approx(0.0, abs=1e-12)
    far0, far1 = point(state, -2.0, RADIUS_M + 0.1), point(state, -1.0, RADIUS_M + 0.1)
    assert G.segment_geometry(*far0, *far1, state, SHAPE)[0] == pytest.approx(-0.1, abs=1e-9)


def test_excess_fades_as_the_deepest_point_reaches_a_node():
    """Reference: continuity of the law: where the segment's deepest point is one of its nodes (a node 2 cm inside
    the shaft, the other far outside), the excess is zero (1e-9 m); a chord of the shaft from that node to one 1 cm
    outside cuts deeper than its nodes once it is long enough to bow in (its sagitta beyond the depths' linear
    interpolation), and ever more so as it lengthens."""
    state = body(axis=(0.0, 0.0, -1.0))
    inside = point(state, -1.0, RADIUS_M - 0.02, angle=0.0)
    outside = point(state, -1.0, RADIUS_M + 1.0, angle=0.0)
    assert G.segment_geometry(*inside, *outside, state, SHAPE)[0] == pytest.approx(0.0, abs=1e-9)
    excess = []
    for angle in (0.4, 0.6, 0.8):  # chords of the shaft from the inside node, ever longer
        other = point(state, -1.0, RADIUS_M + 0.01, angle=angle)
        excess.append(G.segment_geometry(*inside, *other, state, SHAPE)[0])
    assert 0.0 < excess[0] < excess[1] < excess[2]


def test_shares_and_the_reaction_on_the_body():
    """Reference: the force at p* is k e along the normal (no velocity), shared (1 - t, t) between the nodes; the
    body takes its opposite at p* (force and moment about the COG, 1e-9 relative); a node held by a vessel takes
    no share (its share leaves the model with the vessel), and the body still takes the whole reaction."""
    state = body(axis=(0.0, 0.0, -1.0))
    x0, x1, _, _ = _rim_segment(state)
    cf = params()
    t = G.segment_geometry(*x0, *x1, state, SHAPE)[1]
    for kinds in ((L.NODE_FREE, L.NODE_FREE), (L.NODE_VESSEL, L.NODE_FREE)):
        node_pos, node_i, seg_i = _two_nodes(x0, x1, kinds)
        node_vel = np.zeros((2, 3))
        node_force = np.zeros((2, 3))
        load = G.add_segment_contact_loads(node_pos, node_vel, node_i, np.full(2, MASS_KG), seg_i, node_force,
                                           state, SHAPE, cf, -1e9, np.zeros(L.N_CONTACT_OUT), ALL, False)
        e, fx, fy, fz, px, py, pz, *_rest = G.segment_contact(node_pos, node_vel, node_i, np.full(2, MASS_KG), 0,
                                                              1, state, SHAPE, cf)
        f = np.array([fx, fy, fz])
        assert e > 0.15 and np.linalg.norm(f) == pytest.approx(cf[L.CF_STIFFNESS] * e, rel=1e-12)
        share_a = 1.0 - t if kinds[0] == L.NODE_FREE else 0.0
        assert np.allclose(node_force, [share_a * f, t * f], rtol=1e-12, atol=0.0)
        r = np.array([px, py, pz]) - state[L.BS_POS:L.BS_POS + 3]
        assert np.allclose(load[:3], -f, rtol=1e-9) and np.allclose(load[3:6], np.cross(r, -f), rtol=1e-9)
        assert load[6] == pytest.approx(e, rel=1e-12)


def _drop_across_the_shaft(restitution, v_in=5.0, steps=6000):
    """Two free nodes 1.6 m apart, each 0.2 m outside the horizontal shaft's radius sideways, fall onto its top at
    ``v_in`` [m/s] (no gravity): only their segment can touch. Symplectic Euler at ``DT_S``. Returns the nodes'
    velocities along z and the excess per step, and the net impulse of the contact on the nodes [N s]."""
    state = body(axis=(1.0, 0.0, 0.0))
    node_pos = np.array([[-2.0, -0.8, RADIUS_M + 0.05], [-2.0, 0.8, RADIUS_M + 0.05]])
    node_vel = np.array([[0.0, 0.0, -v_in], [0.0, 0.0, -v_in]])
    _, node_i, seg_i = _two_nodes(node_pos[0], node_pos[1])
    mass = np.full(2, MASS_KG)
    cf = params(restitution=restitution)
    vz, excess, impulse, out = [], [], np.zeros(3), np.zeros(L.N_CONTACT_OUT)
    for _ in range(steps):
        force = np.zeros((2, 3))
        load = G.add_segment_contact_loads(node_pos, node_vel, node_i, mass, seg_i, force, state, SHAPE, cf, -1e9,
                                           out, ALL, False)
        excess.append(load[6])
        impulse += force.sum(axis=0) * DT_S
        node_vel += force / MASS_KG * DT_S
        node_pos += node_vel * DT_S
        vz.append(node_vel[:, 2].copy())
    return np.array(vz), np.array(excess), impulse, cf


@pytest.mark.parametrize("restitution", [0.0, 0.5])
def test_segment_dropped_across_the_shaft(restitution):
    """References: the nodes' momentum change equals the contact's impulse (1e-9 relative: Newton's second law
    step by step); the rebound speed is restitution times the impact speed (restitution 0: at rest on the shaft,
    below 1 % of the impact speed; 0.5: within 5 %), since the law damps the point at its own inertia (two nodes
    of m sharing it equally: 2 m); the energy (kinetic, and the spring's k e^2 / 2, e the excess) after the contact
    is at most that before it; the penetration stays below a centimetre (the
    stiffness is chosen for 1 cm at 15 m/s, so about 5 / 15 of it at 5 m/s, times sqrt(2) for the doubled
    inertia: 0.5 cm)."""
    v_in = 5.0
    vz, excess, impulse, cf = _drop_across_the_shaft(restitution, v_in)
    momentum = 2 * MASS_KG * (vz[-1] - (-v_in))
    assert impulse[2] == pytest.approx(momentum.mean(), rel=1e-9)
    assert np.allclose(vz[-1, 0], vz[-1, 1], rtol=1e-12)
    assert vz[-1, 0] == pytest.approx(restitution * v_in, abs=0.01 * v_in if restitution == 0.0 else 0.05 * v_in)
    energy = 0.5 * 2 * MASS_KG * vz[:, 0] ** 2 + 0.5 * cf[L.CF_STIFFNESS] * excess ** 2
    assert excess[0] == 0.0 and energy[-1] <= energy[0]
    assert 0.0 < excess.max() < 0.01

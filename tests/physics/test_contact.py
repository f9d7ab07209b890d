"""Contact between line nodes and the anchor's surface, the law alone (moor_env.physics.contact).

The drop tests integrate one node (a 1 m piece of the 142 mm chain, 442 kg) with symplectic Euler at 0.2 ms, about
0.6 of the explicit step of that chain (0.34 ms), onto the DPA of seed 003 (Landhaug 2015, *Dynamic Simulation of
Dart Anchor Installation*; 13 m long, 1.2 m diameter) with the stiffness :func:`contact_parameters` chooses for
it (15 m/s, 1 cm).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from moor_env.physics import anchor_surface as S
from moor_env.physics import contact as C
from moor_env.physics import contact_setup as CS
from moor_env.physics import layout as L

MASS_KG = 442.0
EA_N = 1.74e9
DT_S = 2e-4
S_TIP_M = 6.381
LENGTH_M = 13.0
S_BACK_M = S_TIP_M - LENGTH_M
RADIUS_M = 0.6
SHAPE = CS.anchor_shape([0.1, 0.2838, 7.6162, 4.9, 0.1], [1.2] * 5, S_TIP_M)


def body(axis=(0.0, 0.0, -1.0), pos=(0.0, 0.0, 0.0), vel=(0.0, 0.0, 0.0), omega=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Anchor state with unit ``axis`` (back to tip) and ``omega`` made perpendicular to it."""
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    w = np.asarray(omega, float)
    w = w - (w @ e) * e
    state = np.zeros(L.N_BODY_STATE)
    state[L.BS_POS:L.BS_POS + 3] = pos
    state[L.BS_VEL:L.BS_VEL + 3] = vel
    state[L.BS_AXIS:L.BS_AXIS + 3] = e
    state[L.BS_OMEGA:L.BS_OMEGA + 3] = w
    return state


def params(restitution=0.0, mu=0.3, speed=15.0, mass=MASS_KG) -> np.ndarray:
    return CS.contact_parameters(EA_N, 1.0, mass, speed, restitution=restitution, friction_coefficient=mu)


def point(state, a, rho, angle=0.3) -> np.ndarray:
    """The point at axial coordinate ``a`` and radius ``rho`` of the anchor in ``state``."""
    e = state[L.BS_AXIS:L.BS_AXIS + 3]
    p = np.cross(e, [1.0, 0.0, 0.0] if abs(e[0]) < 0.9 else [0.0, 1.0, 0.0])
    p /= np.linalg.norm(p)
    q = np.cross(e, p)
    return state[L.BS_POS:L.BS_POS + 3] + a * e + rho * (math.cos(angle) * p + math.sin(angle) * q)


def test_parameters_as_documented():
    """Reference: the module docstring's numbers for the 142 mm chain in 1 m segments (m = 442 kg, EA = 1.74e9 N,
    15 m/s, 1 cm, restitution 0): omega = 15 / (e * 0.01) = 552 rad/s, k = m omega^2 = 1.35e8 N/m, below
    0.1 * 4 EA / l = 6.96e8 N/m. The cap applies where the speed asks for more. The restitution round trip
    e = exp(-zeta pi / sqrt(1 - zeta^2)) to 1e-12."""
    cf = params()
    assert cf[L.CF_STIFFNESS] == pytest.approx(MASS_KG * (15.0 / math.e / 0.01) ** 2, rel=1e-12)
    assert cf[L.CF_STIFFNESS] == pytest.approx(1.35e8, rel=0.01)
    assert cf[L.CF_ZETA] == 1.0
    assert params(speed=100.0)[L.CF_STIFFNESS] == pytest.approx(0.1 * 4.0 * EA_N, rel=1e-12)
    for e in (0.1, 0.5, 0.9):
        zeta = CS.zeta_from_restitution(e)
        assert math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta * zeta)) == pytest.approx(e, rel=1e-12)
    with pytest.raises(ValueError, match="contact_speed_m_s"):
        params(speed=0.0)


def test_signed_distance_on_each_patch():
    """Reference: distances by hand to the back end face, the tip face, the shaft (the fins' envelope is the
    shaft's 1.2 m diameter in this model) and the back rim, inside and outside, on a tilted, moving anchor
    (exact to rounding, 1e-12 m); the normal and the closest point x - sd n, whose own distance is 0."""
    state = body(axis=(0.3, -0.2, -1.0), pos=(5.0, -3.0, -400.0))
    e = state[L.BS_AXIS:L.BS_AXIS + 3]
    cases = [  # (a, rho, sd, feature, outward normal along e)
        (S_BACK_M - 0.25, 0.3, 0.25, S.FEATURE_BACK, -1.0),
        (S_BACK_M + 0.02, 0.3, -0.02, S.FEATURE_BACK, -1.0),
        (S_TIP_M + 0.4, 0.1, 0.4, S.FEATURE_FRONT, 1.0),
        (S_TIP_M - 0.03, 0.2, -0.03, S.FEATURE_FRONT, 1.0),
        (-1.0, RADIUS_M + 0.2, 0.2, S.FEATURE_SHAFT, 0.0),
        (-5.0, RADIUS_M - 0.04, -0.04, S.FEATURE_SHAFT, 0.0),
        (S_BACK_M - 0.3, RADIUS_M + 0.4, 0.5, S.FEATURE_RIM, -0.6),
    ]
    for a, rho, sd_ref, feature_ref, n_along_e in cases:
        x = point(state, a, rho)
        sd, nx, ny, nz, *_hess, feature = S.surface_distance(*x, state, SHAPE)
        n = np.array([nx, ny, nz])
        assert sd == pytest.approx(sd_ref, abs=1e-12)
        assert feature == feature_ref
        assert n @ e == pytest.approx(n_along_e, abs=1e-12)
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
        closest = x - sd * n
        assert S.surface_distance(*closest, state, SHAPE)[0] == pytest.approx(0.0, abs=1e-12)


def test_signed_distance_on_a_stepped_body():
    """Reference: distances by hand on a body of a 0.4 m radius nose ahead of a 0.6 m radius tail (two tail
    sections merged): the step facing the tip is an annulus from 0.4 to 0.6 m; just behind it, inside the nose's
    radius, the nearest surface is the step's inner rim (the nose's end is covered); deeper, the nose's shaft.
    Tolerance 1e-12 m."""
    shape = CS.anchor_shape([2.0, 3.0, 3.0], [0.8, 1.2, 1.2], 4.0)
    assert shape.shape[0] == 2
    assert list(shape[:, L.CS_FRONT_INNER]) == [0.0, 0.4]
    assert list(shape[:, L.CS_BACK_INNER]) == [0.4, 0.0]
    state = body(axis=(0.0, 0.0, -1.0))
    step = 2.0  # the step's axial coordinate
    cases = [  # (a, rho, sd, feature)
        (step + 0.1, 0.55, 0.1, S.FEATURE_FRONT),
        (step + 0.1, 0.45, 0.05, S.FEATURE_SHAFT),
        (step - 0.02, 0.5, -0.02, S.FEATURE_FRONT),
        (step - 0.01, 0.35, -math.hypot(0.01, 0.05), S.FEATURE_RIM),
        (step + 0.3, 0.35, -0.05, S.FEATURE_SHAFT),
        (step - 0.2, 0.1, -math.hypot(0.2, 0.3), S.FEATURE_RIM),
    ]
    for a, rho, sd_ref, feature_ref in cases:
        x = point(state, a, rho)
        sd, nx, ny, nz, *_hess, feature = S.surface_distance(*x, state, shape)
        assert (sd, feature) == (pytest.approx(sd_ref, abs=1e-12), feature_ref)
        n = np.array([nx, ny, nz])
        assert S.surface_distance(*(x - sd * n), state, shape)[0] == pytest.approx(0.0, abs=1e-12)


def test_segment_across_the_back_rim():
    """Reference: a segment from 1 cm behind the back end face, 0.3 m in from its rim, to 1 cm beside the shaft,
    0.95 m ahead of the back end: both nodes are outside, its interior cuts the rim. Inside the corner the depth is
    min(R - rho, a - back), so along the chord the deepest point is where the two are equal (closed form, solved
    for t). Tolerance 1e-6 m and 1e-4 in t; a segment that stays outside reports a negative depth; the deepest over
    the segments of a line finds it."""
    state = body(axis=(0.0, 0.0, -1.0))
    a0, rho0 = S_BACK_M - 0.01, RADIUS_M - 0.3
    a1, rho1 = S_BACK_M + 0.95, RADIUS_M + 0.01
    x0, x1 = point(state, a0, rho0, angle=0.0), point(state, a1, rho1, angle=0.0)
    t_ref = ((RADIUS_M - rho0) - (a0 - S_BACK_M)) / ((a1 - a0) + (rho1 - rho0))
    depth_ref = RADIUS_M - (rho0 + t_ref * (rho1 - rho0))
    assert depth_ref > 0.2
    assert S.surface_distance(*x0, state, SHAPE)[0] > 0.0 and S.surface_distance(*x1, state, SHAPE)[0] > 0.0
    depth, t = S.segment_depth(*x0, *x1, state, SHAPE)
    assert depth == pytest.approx(depth_ref, abs=1e-6) and t == pytest.approx(t_ref, abs=1e-4)
    outside = S.segment_depth(*x1, *point(state, a1 + 1.0, rho1, angle=0.0), state, SHAPE)[0]
    assert outside == pytest.approx(-0.01, abs=1e-6)
    node_pos = np.array([x0, x1, point(state, a1 + 1.0, rho1, angle=0.0)])
    seg_i = np.zeros((2, L.N_SEG_I), np.int64)
    seg_i[:, L.SI_A] = [0, 1]
    seg_i[:, L.SI_B] = [1, 2]
    seg_i[:, L.SI_ACTIVE] = 1
    deepest, which = S.deepest_segment_point(node_pos, seg_i, state, SHAPE)
    assert which == 0 and deepest == pytest.approx(depth_ref, abs=1e-6)
    seg_i[0, L.SI_ACTIVE] = 0
    assert S.deepest_segment_point(node_pos, seg_i, state, SHAPE) == (0.0, -1)


def test_normal_derivative_matches_finite_differences():
    """Reference: the Hessian of the signed distance (dn/dx) against central differences of the normal (step
    1e-6 m) on the shaft, outside the rim and on a face; 1e-6 relative to the largest entry (1 / radius)."""
    state = body(axis=(0.2, 0.1, -1.0), pos=(1.0, 2.0, -300.0))
    for a, rho in ((-2.0, RADIUS_M - 0.01), (-2.0, RADIUS_M + 0.3), (S_BACK_M - 0.2, RADIUS_M + 0.1),
                   (S_BACK_M + 0.01, 0.2)):
        hess, fd = _hessian_and_differences(point(state, a, rho, angle=1.1), state, SHAPE)
        assert np.abs(hess - fd).max() <= 1e-6 / RADIUS_M
    stepped = CS.anchor_shape([2.0, 6.0], [0.8, 1.2], 4.0)
    for a, rho in ((1.9, 0.3), (4.1, 0.5)):  # inside near the step's inner rim, outside the nose's rim
        hess, fd = _hessian_and_differences(point(state, a, rho, angle=0.4), state, stepped)
        assert np.abs(hess - fd).max() <= 1e-6 * np.abs(hess).max()


def _hessian_and_differences(x, state, shape):
    """dn/dx of :func:`surface_distance` at x and its central differences (step 1e-6 m)."""
    hxx, hyy, hzz, hxy, hxz, hyz = S.surface_distance(*x, state, shape)[4:10]
    fd = np.zeros((3, 3))
    for j in range(3):
        d = np.zeros(3)
        d[j] = 1e-6
        fd[:, j] = (np.array(S.surface_distance(*(x + d), state, shape)[1:4])
                    - np.array(S.surface_distance(*(x - d), state, shape)[1:4])) / 2e-6
    return np.array([[hxx, hxy, hxz], [hxy, hyy, hyz], [hxz, hyz, hzz]]), fd


def _jacobian_cases():
    """States in contact: (name, body, node position, node velocity, contact params)."""
    moving = body(axis=(0.1, -0.2, -1.0), pos=(3.0, 1.0, -450.0), vel=(0.4, -0.3, -20.0), omega=(0.05, 0.08, 0.0))
    e = moving[L.BS_AXIS:L.BS_AXIS + 3]
    side = np.cross(e, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)

    def node(a, rho, w, angle=0.3):
        """Node at (a, rho) moving at ``w`` relative to the body point there."""
        x = point(moving, a, rho, angle)
        r = x - moving[L.BS_POS:L.BS_POS + 3]
        return x, moving[L.BS_VEL:L.BS_VEL + 3] + np.cross(moving[L.BS_OMEGA:L.BS_OMEGA + 3], r) + w

    return [
        ("back face, sliding", moving, *node(S_BACK_M + 0.004, 0.3, 3.0 * e + 2.0 * side), params()),
        ("back face, viscous from N", moving, *node(S_BACK_M + 2e-4, 0.2, -0.001 * e + 0.02 * side), params()),
        ("back face, viscous at the cap", moving, *node(S_BACK_M + 0.006, 0.2, 8.0 * e + 0.5 * side), params()),
        ("shaft, sliding", moving, *node(-3.0, RADIUS_M - 0.008, 4.0 * e + 1.5 * side, angle=0.7), params()),
        ("shaft, restitution 0.5", moving, *node(-3.0, RADIUS_M - 0.005, 0.3 * e + 0.8 * side, angle=2.0),
         params(restitution=0.5)),
        ("tip face, no friction", moving, *node(S_TIP_M - 0.003, 0.4, -2.0 * e), params(mu=0.0)),
    ]


@pytest.mark.parametrize("case", range(6))
def test_jacobian_matches_central_differences(case):
    """Reference: dF/dx and dF/dv of the law against central differences of the force (steps 1e-7 m, 1e-7 m/s),
    1e-6 relative to the largest entry, on the back face, the shaft and the tip face of a moving, turning anchor,
    in every friction regime (sliding, viscous from the normal force, viscous at the damping cap)."""
    name, state, x, v, cf = _jacobian_cases()[case]
    jac = np.zeros((2, 3, 3))
    depth, *_ = C.node_contact(*x, *v, MASS_KG, state, SHAPE, cf, jac)
    assert depth > 0.0, name
    h = 1e-7
    for which in (0, 1):
        fd = np.zeros((3, 3))
        for j in range(3):
            d = np.zeros(3)
            d[j] = h
            args_p = (x + d, v) if which == 0 else (x, v + d)
            args_m = (x - d, v) if which == 0 else (x, v - d)
            fp = np.array(C.contact_force(*args_p[0], *args_p[1], MASS_KG, state, SHAPE, cf)[1:])
            fm = np.array(C.contact_force(*args_m[0], *args_m[1], MASS_KG, state, SHAPE, cf)[1:])
            fd[:, j] = (fp - fm) / (2.0 * h)
        scale = np.abs(jac[which]).max()
        assert np.abs(jac[which] - fd).max() <= 1e-6 * scale, (name, which, jac[which], fd)


def drop(v_in, v_tangential=0.0, restitution=0.0, mu=0.3, g=0.0, mass=MASS_KG, t_end=0.1, body_mass=None,
         where="back"):
    """Symplectic Euler of one node dropped onto the anchor (fixed, or free in translation with ``body_mass``).

    The node starts 1 mm outside the back end face (``where='back'``) or the shaft (``'shaft'``), moving into it
    at ``v_in`` and along it at ``v_tangential``. Returns a dict of per-step arrays.
    """
    state = body()
    cf = params(restitution=restitution, mu=mu, mass=mass)
    k = cf[L.CF_STIFFNESS]
    e = state[L.BS_AXIS:L.BS_AXIS + 3]
    if where == "back":
        x = point(state, S_BACK_M - 1e-3, 0.2, angle=0.0)
        normal = -e
    else:
        x = point(state, -2.0, RADIUS_M + 1e-3, angle=0.0)
        normal = (x - (x @ e) * e) / np.linalg.norm(x - (x @ e) * e)
    along = np.cross(normal, [0.0, 1.0, 0.0]) if where == "back" else e
    along /= np.linalg.norm(along)
    v = -v_in * normal + v_tangential * along
    gravity = np.array([0.0, 0.0, -g])
    rows = {k_: [] for k_ in ("x", "v", "f", "depth", "energy", "shadow", "body_v")}
    load = np.zeros(6)
    for _ in range(int(round(t_end / DT_S))):
        depth, fx, fy, fz = C.contact_force(*x, *v, mass, state, SHAPE, cf)
        f = np.array([fx, fy, fz])
        spring = k * depth * normal if depth > 0.0 else np.zeros(3)
        energy = 0.5 * mass * v @ v - mass * gravity @ x + 0.5 * k * depth * depth
        # symplectic Euler conserves H + (dt / 2) F_conservative . v exactly for a linear force (the test's
        # shadow energy); the contact's dampers may only take from it
        for key, value in (("x", x), ("v", v), ("f", f), ("depth", depth), ("energy", energy),
                           ("shadow", energy + 0.5 * DT_S * (spring + mass * gravity) @ v),
                           ("body_v", state[L.BS_VEL:L.BS_VEL + 3].copy())):
            rows[key].append(np.copy(value))
        if body_mass is not None:
            load[:] = 0.0
            C.add_contact_reaction(load, state, *x, *f)
            state[L.BS_VEL:L.BS_VEL + 3] += DT_S * load[:3] / body_mass
            state[L.BS_POS:L.BS_POS + 3] += DT_S * state[L.BS_VEL:L.BS_VEL + 3]
        v = v + DT_S * (f / mass + gravity)
        x = x + DT_S * v
    out = {k_: np.array(v_) for k_, v_ in rows.items()}
    out["normal"] = normal
    return out


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
def test_drop_impulse_equals_momentum_change(restitution):
    """Reference: a node meeting a fixed face at 12 m/s with restitution e leaves at e * 12 m/s, so the contact's
    impulse is m (1 + e) 12 m/s along the normal. Tolerance 1 % of m * 12 m/s (the integrator's step, 0.11 of a
    contact period over 2 pi, is the error)."""
    run = drop(12.0, restitution=restitution)
    impulse = run["f"].sum(axis=0) * DT_S
    v_out = run["v"][-1] @ run["normal"]
    assert v_out == pytest.approx(restitution * 12.0, abs=0.01 * 12.0)
    assert impulse @ run["normal"] == pytest.approx(MASS_KG * (1.0 + restitution) * 12.0, rel=0.01)
    assert np.linalg.norm(impulse - (impulse @ run["normal"]) * run["normal"]) < 1e-9 * np.linalg.norm(impulse)


def test_drop_on_free_body_conserves_momentum():
    """Reference: momentum conservation. A node hitting an anchor (85.2 t, free in translation, restitution 0)
    ends with the common velocity (m v0) / (m + M), and the anchor's momentum change equals the node's
    impulse, opposite. Tolerances 1 % of the common velocity and 1e-9 relative on the momentum balance."""
    big = 85181.0
    run = drop(12.0, body_mass=big, t_end=0.2)
    impulse = run["f"].sum(axis=0) * DT_S
    node_dp = MASS_KG * (run["v"][-1] - run["v"][0])
    # the row of the last step holds the state before its update: the last force is not in the velocities
    applied = impulse - DT_S * run["f"][-1]
    body_dp = big * (run["body_v"][-1] - run["body_v"][0])
    common = MASS_KG * 12.0 / (MASS_KG + big)
    assert np.linalg.norm(node_dp - applied) < 1e-9 * MASS_KG * 12.0
    assert np.linalg.norm(body_dp + applied) < 1e-9 * MASS_KG * 12.0
    assert -(run["v"][-1] @ run["normal"]) == pytest.approx(common, rel=0.01)
    assert -(run["body_v"][-1] @ run["normal"]) == pytest.approx(common, rel=0.01)


@pytest.mark.parametrize("v_in", [6.0, 10.0, 15.0])
def test_restitution_zero_no_rebound(v_in):
    """Reference: with restitution 0 the contact is critically damped and not cut at zero force, so the node
    never leaves: its speed away from the face stays below 1 % of the impact speed once it is back outside."""
    run = drop(v_in, t_end=0.15)
    outside = run["depth"] == 0.0
    outside[: int(np.argmax(run["depth"] > 0.0))] = False
    outward = run["v"] @ run["normal"]
    assert np.all(outward[outside] < 0.01 * v_in)
    assert abs(outward[-1]) < 0.01 * v_in


@pytest.mark.parametrize("v_in, mass", [(10.0, MASS_KG), (15.0, MASS_KG), (15.0, 2.0 * MASS_KG),
                                        (15.0, 0.25 * MASS_KG)])
def test_penetration_at_the_chains_impact_speeds(v_in, mass):
    """Reference: the chain meets the anchor at up to 10-15 m/s relative (its lengthwise terminal speed, 41 m/s,
    against the anchor's 26 m/s at touchdown). With the stiffness chosen for the chain's node mass at that mass
    (1, 2 and 0.25 m segments), the peak penetration is 1 cm at 15 m/s; limit 5 cm (and 1.5 cm)."""
    run = drop(v_in, mass=mass)
    assert run["depth"].max() < 0.05
    assert run["depth"].max() < 0.015 * v_in / 15.0


@pytest.mark.parametrize("restitution, v_tangential, g", [(0.0, 0.0, 9.81), (0.0, 3.0, 9.81), (0.5, 2.0, 0.0),
                                                          (0.5, 0.0, 9.81)])
def test_energy_never_grows(restitution, v_tangential, g):
    """Reference: the contact's springs store and its dampers and friction dissipate, so the node's energy
    (kinetic, gravity, contact spring) never grows: step by step in symplectic Euler's conserved form
    (H + dt/2 F . v, exact for linear forces; growth allowed: 1e-4 of the start, the step that enters the
    contact) and between any two instants for the plain energy outside the contact."""
    run = drop(12.0, v_tangential=v_tangential, restitution=restitution, g=g)
    start = run["shadow"][0]
    assert np.diff(run["shadow"]).max() <= 1e-4 * start
    assert run["energy"][-1] <= run["energy"][0]
    outside = run["energy"][run["depth"] == 0.0]
    if outside.size > 1:
        assert np.diff(outside).max() <= 1e-9 * start


def test_contact_power_is_never_positive():
    """Reference: the law's power beyond its spring, (F - k d n) . w, is -c (w.n)^2 + F_t . w_t <= 0 for any
    state (random states on every patch of a moving, turning anchor; exact up to rounding, 1e-9 relative)."""
    rng = np.random.default_rng(7)
    cf = params(restitution=0.3)
    for _ in range(300):
        state = body(axis=rng.normal(size=3), pos=rng.normal(size=3), vel=rng.normal(size=3) * 10,
                     omega=rng.normal(size=3) * 0.2)
        a = rng.uniform(S_BACK_M - 0.01, S_TIP_M + 0.01)
        x = point(state, a, rng.uniform(0.0, RADIUS_M + 0.01), angle=rng.uniform(0, 2 * math.pi))
        v = rng.normal(size=3) * 5.0
        depth, fx, fy, fz = C.contact_force(*x, *v, MASS_KG, state, SHAPE, cf)
        if depth == 0.0:
            continue
        n = np.array(S.surface_distance(*x, state, SHAPE)[1:4])
        r = x - state[L.BS_POS:L.BS_POS + 3]
        w = v - state[L.BS_VEL:L.BS_VEL + 3] - np.cross(state[L.BS_OMEGA:L.BS_OMEGA + 3], r)
        f = np.array([fx, fy, fz])
        power = (f - cf[L.CF_STIFFNESS] * depth * n) @ w
        assert power <= 1e-9 * np.linalg.norm(f) * np.linalg.norm(w)


def test_friction_bounded_by_mu_times_normal():
    """Reference: Coulomb's bound |F_t| <= mu F_n at every step of an oblique impact on the shaft (mu = 0.3), and
    the full mu F_n while sliding fast (rounding: 1e-9 relative)."""
    run = drop(10.0, v_tangential=5.0, where="shaft")
    n = run["normal"]
    fn = run["f"] @ n
    ft = np.linalg.norm(run["f"] - np.outer(fn, n), axis=1)
    contact = run["depth"] > 0.0
    assert np.all(ft[contact] <= 0.3 * np.maximum(fn[contact], 0.0) * (1 + 1e-9))
    sliding = contact & (np.linalg.norm(run["v"] - np.outer(run["v"] @ n, n), axis=1) > 1.0) & (fn > 0.0)
    assert sliding.sum() > 5
    assert ft[sliding] == pytest.approx(0.3 * fn[sliding], rel=1e-9)


@pytest.mark.parametrize("push_fraction", [0.3, 0.9, 1.5])
def test_friction_sticks_below_the_stick_speed(push_fraction):
    """Reference: a node resting on the back end face under its weight W (384.3 kg/m submerged, 1 m) and pushed
    along it by a fraction of mu W: below 1 it creeps at push / (mu W) times the stick speed (0.05 m/s; within
    1 %), never faster than the stick speed; above 1 it slides, accelerating at (push - mu W) / m (within 1 %)."""
    state = body()
    cf = params()
    weight = 384.3 * 9.81
    e = state[L.BS_AXIS:L.BS_AXIS + 3]
    normal = -e
    along = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    along /= np.linalg.norm(along)
    push = push_fraction * 0.3 * weight
    x = point(state, S_BACK_M + weight / cf[L.CF_STIFFNESS], 0.1)
    v = np.zeros(3)
    speeds = []
    for _ in range(int(round(1.0 / DT_S))):
        depth, fx, fy, fz = C.contact_force(*x, *v, MASS_KG, state, SHAPE, cf)
        v = v + DT_S * ((np.array([fx, fy, fz]) - weight * normal + push * along) / MASS_KG)
        x = x + DT_S * v
        speeds.append(v @ along)
    if push_fraction < 1.0:
        assert speeds[-1] == pytest.approx(push_fraction * cf[L.CF_STICK_SPEED], rel=0.01)
        assert max(speeds) <= cf[L.CF_STICK_SPEED]
    else:
        accel = (speeds[-1] - speeds[-1001]) / (1000 * DT_S)
        assert accel == pytest.approx((push - 0.3 * weight) / MASS_KG, rel=0.01)


def test_reaction_on_the_body():
    """Reference: Newton's third law and the moment of -F at the node about the COG, (x - r_G) x (-F) (exact)."""
    state = body(axis=(0.2, 0.0, -1.0), pos=(1.0, 2.0, 3.0))
    x = point(state, S_BACK_M + 0.01, 0.3)
    cf = params()
    depth, fx, fy, fz = C.contact_force(*x, 0.0, 0.0, -5.0, MASS_KG, state, SHAPE, cf)
    assert depth > 0.0
    load = np.zeros(6)
    C.add_contact_reaction(load, state, *x, fx, fy, fz)
    f = np.array([fx, fy, fz])
    assert np.array_equal(load[:3], -f)
    assert np.allclose(load[3:], np.cross(x - state[L.BS_POS:L.BS_POS + 3], -f), rtol=1e-14, atol=0.0)


def test_no_force_outside_and_far_away():
    """Reference: outside the surface (by 1 mm, and 50 m away) the force and its Jacobian are exactly zero."""
    state = body()
    cf = params()
    jac = np.ones((2, 3, 3))
    for x in (point(state, S_BACK_M - 1e-3, 0.3), point(state, -2.0, RADIUS_M + 1e-3), np.array([50.0, 0, 0])):
        assert C.node_contact(*x, 0.0, 0.0, -5.0, MASS_KG, state, SHAPE, cf, jac) == (0.0, 0.0, 0.0, 0.0)
        assert not jac.any()


def _catch_up(cd_tangential):
    """The seed's DPA (1-DOF: C = 1.10 on 1.131 m^2, 70.1 t net, 85.2 t with flooded water, 68.5 m) and its
    142 mm chain (442 kg/m, 384.3 kg/m net, D = 0.2008 m) with the given tangential drag."""
    rho, g = 1025.0, 9.81
    return CS.chain_catch_up(68.5, 85.2e3, 70.1e3 * g, 0.5 * rho * 1.10 * 1.131, 442.0, 384.3 * g,
                             0.5 * rho * cd_tangential * math.pi * 0.2008)


def test_catch_up_of_the_seeds_chain():
    """Reference: seed 003's 1-DOF fall of the DPA alone, 26.3 m/s at 4.48 s (the extract's closed form, within
    0.05 m/s and 0.02 s), the chain's lengthwise terminal speed sqrt(w / (1/2 rho C_D,T pi D)) = 41.1 m/s
    (0.1 m/s); with C_D,T = 0.0069 the freely falling chain gains metres on the anchor (the contact is needed,
    at 41.1 - 26.3 = 14.8 m/s), with the DNV 0.4456 (terminal 5.1 m/s) it falls behind (no contact)."""
    seed = _catch_up(0.0069)
    assert seed.anchor_speed_m_s == pytest.approx(26.3, abs=0.05)
    assert seed.anchor_touchdown_s == pytest.approx(4.48, abs=0.02)
    assert seed.chain_terminal_m_s == pytest.approx(41.1, abs=0.1)
    assert seed.gain_m > 5.0 and seed.needed(1.0)
    assert seed.contact_speed_m_s == pytest.approx(14.8, abs=0.1)
    dnv = _catch_up(0.4456)
    assert dnv.chain_terminal_m_s == pytest.approx(5.1, abs=0.1)
    assert not dnv.needed(1.0) and not dnv.needed(0.25)
    assert dnv.contact_speed_m_s == CS.MIN_CONTACT_SPEED_M_S


def test_implicit_linearisation_is_the_laws_derivative():
    """Reference: the law's exact Jacobians (:func:`contact.node_contact`). The implicit step's block
    h C + h^2 K (``implicit_contact.contact_terms``) is h (-dF/dv) + h^2 k n n^T where the friction's damping is at
    its cap (then -dF/dv = c I, symmetric), and k = n^T (-dF/dx) n (1e-9 relative)."""
    from moor_env.physics import implicit_contact as IC

    state = body()
    cf = params()
    h = 0.01125
    x = point(state, S_BACK_M + 0.006, 0.2)
    v = np.array([0.3, 0.0, -8.0])
    jac = np.zeros((2, 3, 3))
    depth, *_ = C.node_contact(*x, *v, MASS_KG, state, SHAPE, cf, jac)
    d, nx, ny, nz, wx, wy, wz = IC.contact_state(*x, *v, state, SHAPE)
    assert d == pytest.approx(depth, rel=1e-12)
    block = IC.contact_terms(h, IC.SET_IN, d, nx, ny, nz, wx, wy, wz, MASS_KG, cf, 0.0, 0.0, 0.0)[:6]
    n = np.array([nx, ny, nz])
    k = n @ (-jac[0]) @ n
    assert k == pytest.approx(cf[L.CF_STIFFNESS], rel=1e-9)
    expected = h * -jac[1] + h * h * k * np.outer(n, n)
    got = np.array([[block[0], block[3], block[4]], [block[3], block[1], block[5]], [block[4], block[5], block[2]]])
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


@pytest.mark.parametrize("modes, segments, expected", [
    ((), (), False),
    (("SET_OUT", "SET_MISSED"), (), False),  # a missed node carries no law
    (("SET_OUT", "SET_COMING"), (), True),  # a coming node carries an entering node's
    (("SET_IN",), (), True),
    (("SET_LEFT",), (), True),  # its start-of-step force is taken back in the solve
    (("SET_ENTERED",), (), True),
    (("SET_OUT",), ("SET_IN",), True),  # a segment in the set always carries its law
])
def test_any_law_sees_every_node_and_segment_with_a_law(modes, segments, expected):
    """The implicit step skips the contact's terms and reaction where :func:`implicit_contact.any_law` says no
    candidate and no segment carries a law; an entry past the list's end (-1) is not read."""
    from moor_env.physics import implicit_contact as IC

    def listed(names, size=6):
        out = np.zeros(size, np.int64)  # zeros past the end: node 0 in SET_OUT, never read
        for k, name in enumerate(names):
            out[k] = ((k + 3) << IC.SET_BITS) | getattr(IC, name)
        if len(names) < size:
            out[len(names)] = -1
            out[len(names) + 1:] = (9 << IC.SET_BITS) | IC.SET_IN  # stale entries past the end
        return out

    assert IC.any_law(listed(modes), listed(segments)) is expected


def test_any_law_on_lists_without_an_end_marker():
    """A list as long as the nodes (segments) has no -1 after its last entry; an empty one has no entry at all."""
    from moor_env.physics import implicit_contact as IC

    full_out = np.array([(3 << IC.SET_BITS) | IC.SET_OUT, (4 << IC.SET_BITS) | IC.SET_MISSED])
    full_in = np.array([(3 << IC.SET_BITS) | IC.SET_OUT, (4 << IC.SET_BITS) | IC.SET_IN])
    empty = np.zeros(0, np.int64)
    assert IC.any_law(full_out, empty) is False
    assert IC.any_law(full_in, empty) is True
    assert IC.any_law(empty, np.array([(2 << IC.SET_BITS) | IC.SET_ENTERED])) is True
    assert IC.any_law(empty, empty) is False

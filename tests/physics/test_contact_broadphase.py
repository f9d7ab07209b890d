"""The contact's list of what lies near the anchor, reused across steps (moor_env.physics.contact_broadphase).

Reference: a pass over every node and segment. The list may only leave out what lies outside the anchor's
bounding sphere, where the contact's force is zero: the loads with the lists are those of a pass over all, and a
fall with lists reused for many steps is the same bit for bit as one whose lists are rebuilt at every step (each
``advance`` call rebuilds them at its first step).
"""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L
from moor_env.physics.anchor_surface import bounding_radius_m
from moor_env.physics.contact_broadphase import ROUNDING_M, SKIN_M, covers_step, note_moved, prepare_near
from moor_env.physics.loads import compute_loads


def _released(scene: str, **overrides):
    sim = solve_statics(load_scene(scene, overrides), progress=False).simulator
    sim.release()
    return sim


def _fall(sim, steps_per_call: int, n_steps: int) -> np.ndarray:
    """Positions and velocities after ``n_steps`` steps taken ``steps_per_call`` per call."""
    done = 0
    while done < n_steps:
        take = min(steps_per_call, n_steps - done)
        sim.advance_to(sim.state.t + take * sim.dt)
        done += take
    return np.concatenate([sim.state.node_pos.ravel(), sim.state.node_vel.ravel(), sim.state.body_state])


@pytest.mark.parametrize("scene, overrides, n_steps", [
    ("vertical-chain", {}, 9000),  # the chain lands on the back end
    ("vertical-chain", {"integrator": "implicit_euler"}, 400),  # the segment pass uses the list too
    # the loop over the back end's rim: segments in the implicit step's set on about a third of the steps
    ("gjoa-500", {"integrator": "implicit_euler", "vessel_spacing_m": 0.0}, 300),
    ("gjoa-500", {"integrator": "implicit_euler"}, 300),
    ("gjoa-500", {"vessel_spacing_m": 0.0}, 4000),  # the loop rests on the anchor from the start
])
def test_reused_lists_change_nothing(scene, overrides, n_steps):
    """Reference: the same fall with the lists rebuilt at every step (one step per call); tolerance: none."""
    reused = _fall(_released(scene, **overrides), n_steps, n_steps)
    fresh = _fall(_released(scene, **overrides), 1, n_steps)
    assert np.array_equal(reused, fresh)


def _segment_distance_m(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    d = b - a
    t = np.clip(-np.dot(a - c, d) / np.dot(d, d), 0.0, 1.0) if np.dot(d, d) > 0 else 0.0
    return float(np.linalg.norm(a + t * d - c))


@pytest.mark.parametrize("integrator, steps_per_call, calls", [
    ("symplectic_euler", 50, 250),
    ("implicit_euler", 5, 78),  # the skin closed at the nodes' speed relative to the anchor
])
def test_lists_hold_everything_inside_the_sphere_between_rebuilds(integrator, steps_per_call, calls):
    """Reference: the bounding sphere (``anchor_surface.bounding_radius_m``) at the end of every call of the
    vertical-chain fall, where the lists can be as old as the call's steps: while the skin is open, every free node
    and every segment reaching into the sphere is listed."""
    sim = _released("vertical-chain", integrator=integrator)
    model, state = sim.records()
    radius = bounding_radius_m(model.contact_shape)
    checked = 0
    for _ in range(calls):
        sim.advance_to(sim.state.t + steps_per_call * sim.dt)
        model, state = sim.records()
        if not state.near_skin[L.NEAR_MOVED_M] < SKIN_M:
            continue  # out of date: the next step rebuilds them
        centre = state.body_state[L.BS_POS:L.BS_POS + 3]
        nodes, segs = _listed(state.near_nodes), _listed(state.near_segs)
        for n in np.flatnonzero(state.node_i[:, L.NI_KIND] == L.NODE_FREE):
            if np.linalg.norm(state.node_pos[n] - centre) <= radius:
                assert n in nodes
                checked += 1
        for s in np.flatnonzero(state.seg_i[:, L.SI_ACTIVE] != 0):
            a, b = state.node_pos[state.seg_i[s, L.SI_A]], state.node_pos[state.seg_i[s, L.SI_B]]
            if _segment_distance_m(a, b, centre) <= radius:
                assert s in segs
    assert checked > 100  # the chain did come near


def _listed(near: np.ndarray) -> set[int]:
    end = np.flatnonzero(near < 0)
    return set(near[:end[0] if end.size else near.size].tolist())


@pytest.mark.parametrize("integrator, steps_per_call", [("symplectic_euler", 400), ("implicit_euler", 20)])
def test_listed_loads_equal_a_pass_over_all(integrator, steps_per_call):
    """Reference: the same load evaluation passing over every node and segment (``NEAR_ON`` 0); tolerance: none.
    The vertical chain is thrown at the anchor at 40 m/s. At the end of every call, where the lists are still in
    date, the contact's forces on the nodes and the anchor and its record are the same bit for bit with the lists
    as without; in several of those calls the anchor's centre of gravity alone moved more than the skin, so the
    lists were rebuilt within the call when the skin closed."""
    sim = _released("vertical-chain", integrator=integrator)
    free = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
    sim.state.node_vel[free, 2] -= 40.0
    compared = rebuilt = 0
    for _ in range(30):
        cog = sim.state.body_state[L.BS_POS:L.BS_POS + 3].copy()
        status, _ = sim.advance_to(sim.state.t + steps_per_call * sim.dt, detect_touchdown=True)
        model, state = sim.records()
        if not state.near_skin[L.NEAR_MOVED_M] < SKIN_M:
            continue
        rebuilt += np.linalg.norm(state.body_state[L.BS_POS:L.BS_POS + 3] - cog) > SKIN_M
        out = []
        for on in (1.0, 0.0):
            state.near_skin[L.NEAR_ON] = on
            compute_loads(model, state)
            out.append((state.node_force.copy(), state.body_load.copy(), state.contact_out.copy()))
        for listed, everything in zip(out[0], out[1], strict=True):
            assert np.array_equal(listed, everything)
        compared += 1
        if status == L.STATUS_TOUCHDOWN:
            break
    assert compared >= 5 and rebuilt >= 3
    assert sim.contact_report()["peak_force_n"] > 0.0  # the chain did hit the anchor


def test_lists_are_rebuilt_when_the_skin_closes():
    """Reference: the rule of ``contact_broadphase.prepare_near``: the lists are kept while the nodes and the COG
    can have closed less than ``SKIN_M - ROUNDING_M`` on each other by the end of the coming step (at the speeds
    the last step ended with, the anchor not turning), rebuilt from there on and at the first step of a call;
    ``note_moved`` adds dt times the closing speed, keeps that speed and ends the lists' use. The implicit
    step's segment pass uses the list only while the step's reach fits in the skin and the speeds are known."""
    sim = _released("vertical-chain")
    model, state = sim.records()
    prepare_near(model, state, False, 0.1)
    assert state.near_skin[L.NEAR_ON] == 1.0 and state.near_skin[L.NEAR_MOVED_M] == 0.0
    assert not covers_step(model, state, 1e-6)  # no speed known at the first step of a call
    note_moved(state, 0.5, 4.0)  # 0.5 s at 4 m/s
    assert state.near_skin[L.NEAR_MOVED_M] == 2.0 and state.near_skin[L.NEAR_ON] == 0.0
    assert state.near_skin[L.NEAR_SPEED_M_S] == 4.0
    # steps of 0.1 s at 4 m/s close 0.4 m
    for moved, same_topology, kept in ((SKIN_M - 0.5, True, True), (SKIN_M - 0.3, True, False),
                                       (SKIN_M - ROUNDING_M, True, False), (0.0, False, False)):
        state.near_skin[L.NEAR_SPEED_M_S] = 4.0
        state.near_nodes[0] = 123456  # a mark a rebuild overwrites
        state.near_skin[L.NEAR_MOVED_M] = moved
        prepare_near(model, state, same_topology, 0.1)
        assert (state.near_nodes[0] == 123456) == kept
        assert state.near_skin[L.NEAR_MOVED_M] == (moved if kept else 0.0)
        assert covers_step(model, state, 0.1) == same_topology
    state.near_skin[L.NEAR_SPEED_M_S] = 4.0
    state.near_skin[L.NEAR_MOVED_M] = 1.5
    assert covers_step(model, state, 0.1) and not covers_step(model, state, 0.2)


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler"])
def test_closing_speed_bounds_every_node_against_the_cog(integrator):
    """Reference: the free nodes' velocities and the COG's after each step of the vertical-chain fall (the chain
    catches up with the anchor). The speed the skin is closed at bounds every free node's speed relative to the
    COG: the implicit step gives the fastest relative speed itself (equal within rounding of the norm), the
    explicit step the fastest node's speed plus the COG's (a bound on the relative one by the triangle
    inequality). Tolerance 1e-12 relative."""
    sim = _released("vertical-chain", integrator=integrator)
    free = sim.state.node_i[:, L.NI_KIND] == L.NODE_FREE
    for _ in range(60):
        sim.advance_to(sim.state.t + 5 * sim.dt)
        _, state = sim.records()
        v = state.node_vel[free]
        vg = state.body_state[L.BS_VEL:L.BS_VEL + 3]
        relative = np.sqrt(np.max(np.sum((v - vg) ** 2, axis=1)))
        closing = state.near_skin[L.NEAR_SPEED_M_S]
        if integrator == "implicit_euler":
            assert closing == pytest.approx(relative, rel=1e-12)
        else:
            summed = np.sqrt(np.max(np.sum(v ** 2, axis=1))) + np.linalg.norm(vg)
            assert closing == pytest.approx(summed, rel=1e-12)

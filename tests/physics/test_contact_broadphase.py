"""The contact's list of what lies near the anchor, reused across steps (moor_env.physics.contact_broadphase).

Reference: a pass over every node and segment. The list may only leave out what lies outside the anchor's
bounding sphere, where the contact's force is zero, so a fall with lists reused for many steps is the same bit for
bit as one whose lists are rebuilt at every step (each ``advance`` call rebuilds them at its first step).
"""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import load_scene, solve_statics
from moor_env.physics import layout as L
from moor_env.physics.anchor_surface import bounding_radius_m
from moor_env.physics.contact_broadphase import SKIN_M


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


def test_lists_hold_everything_inside_the_sphere_between_rebuilds():
    """Reference: the bounding sphere (``anchor_surface.bounding_radius_m``) at the end of every 50-step call of the
    vertical-chain fall, where the lists are up to 49 steps old: every free node and every segment reaching into it
    is listed, and what the lists leave out lay beyond the sphere plus the skin when they were built."""
    sim = _released("vertical-chain")
    model, state = sim.records()
    radius = bounding_radius_m(model.contact_shape)
    checked = 0
    for _ in range(250):
        sim.advance_to(sim.state.t + 50 * sim.dt)
        model, state = sim.records()
        centre = state.body_state[L.BS_POS:L.BS_POS + 3]
        nodes = set(state.near_nodes[:np.argmax(np.append(state.near_nodes, -1) < 0)].tolist())
        segs = set(state.near_segs[:np.argmax(np.append(state.near_segs, -1) < 0)].tolist())
        assert 0.0 <= state.near_skin[L.NEAR_MOVED_M] < SKIN_M + 1.0
        for n in np.flatnonzero(state.node_i[:, L.NI_KIND] == L.NODE_FREE):
            if np.linalg.norm(state.node_pos[n] - centre) <= radius:
                assert n in nodes
                checked += 1
        for s in np.flatnonzero(state.seg_i[:, L.SI_ACTIVE] != 0):
            a, b = state.node_pos[state.seg_i[s, L.SI_A]], state.node_pos[state.seg_i[s, L.SI_B]]
            if _segment_distance_m(a, b, centre) <= radius:
                assert s in segs
    assert checked > 100  # the chain did come near

"""The static step's seabed set (``physics/statics_system.py``): which nodes the step holds on the seabed."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env import Simulator, compile_scene, load_scene
from moor_env.physics import layout as L
from moor_env.physics.statics_system import SEABED_BACK, SEABED_DOWN, SEABED_LEFT, _predict_seabed
from moor_env.physics.tree import OR_EFF, build_tree


@pytest.fixture(scope="module")
def grounded():
    """gjoa-500's records, the tree's unknowns and a free node of a line that can touch the seabed, 10 cm above
    it (the only node with a seabed contact area); the seabed's height [m]."""
    sim = Simulator(compile_scene(load_scene("gjoa-500")))
    sim.evaluate_loads()  # the nodes' seabed contact areas
    _, state = sim.records()
    orow = np.zeros((state.node_i.shape[0], 3), np.int64)
    tree = np.zeros_like(orow)
    build_tree(-1, state.node_i, state.seg_i, tree, orow)
    free = (state.node_i[:, L.NI_KIND] == L.NODE_FREE) & (state.node_contact > 0.0)
    node = int(np.nonzero(free)[0][0])
    state.node_contact[np.arange(state.node_contact.size) != node] = 0.0  # the others cannot touch the seabed
    seabed = -float(sim.env_f[L.EF_DEPTH])
    state.node_pos[node, 2] = seabed + 0.1
    return state, orow, node, seabed


def _predict(grounded, node_down, step_z_m, release):
    state, orow, node, seabed = grounded
    state.node_acc[:] = 0.0
    state.node_acc[orow[node, OR_EFF], 2] = step_z_m
    return _predict_seabed(-1, state, seabed, node_down, orow, release)


def test_a_node_leaves_the_seabed_set_once_per_step(grounded):
    """Reference: the set's rule (``statics_system._predict_seabed``). A node the step carries 10 cm below the
    seabed joins the set; lifted again by a later solve it leaves it where releases are allowed; carried below
    again it rejoins and stays, however the later solves lift it (the solves cannot cycle). Without releases
    the set only grows."""
    node = grounded[2]
    node_down = np.zeros(grounded[0].node_i.shape[0], np.int64)
    assert _predict(grounded, node_down, -0.2, True) == 1 and node_down[node] == SEABED_DOWN
    assert _predict(grounded, node_down, 0.0, False) == 0 and node_down[node] == SEABED_DOWN
    assert _predict(grounded, node_down, 0.0, True) == 1 and node_down[node] == SEABED_LEFT
    assert _predict(grounded, node_down, -0.2, True) == 1 and node_down[node] == SEABED_BACK
    assert _predict(grounded, node_down, 0.0, True) == 0 and node_down[node] == SEABED_BACK
    assert np.count_nonzero(node_down) == 1

"""Morison drag's derivatives (``physics/hydro.py``) against finite differences of the drag itself."""

from __future__ import annotations

import numpy as np
import pytest

from moor_env.physics.hydro import slender_drag, slender_drag_turn

Q = np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5, 0.81])


@pytest.mark.parametrize("vr", [(0.6, -0.2, 0.05), (0.0, 0.0, 0.3), tuple(0.4 * Q),
                                tuple(0.5 * np.cross(Q, [1.0, 0.0, 0.0]))])
def test_drag_turn_matches_finite_differences(vr):
    """(d f / d q) P of a segment turning: the drag at q turned by a small angle in each direction across it
    (q + eps P e_j, normalised) against the closed form, within 1e-6 of the drag's scale, for currents at two
    angles to the segment, along it (no normal component) and across it (no tangential one)."""
    q = Q.copy()
    cn, ct = 120.0, 4.0
    out = np.zeros((3, 3))
    slender_drag_turn(*vr, *q, cn, ct, out)
    proj = np.eye(3) - np.outer(q, q)
    eps = 1e-6
    scale = cn * float(np.dot(vr, vr))
    for j in range(3):
        turn = eps * proj[:, j]
        f_plus = np.array(slender_drag(*vr, *((q + turn) / np.linalg.norm(q + turn)), cn, ct))
        f_minus = np.array(slender_drag(*vr, *((q - turn) / np.linalg.norm(q - turn)), cn, ct))
        assert np.allclose((f_plus - f_minus) / (2 * eps), out[:, j], atol=1e-6 * scale)

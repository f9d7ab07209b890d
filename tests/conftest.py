"""Shared fixtures: the numba kernels compile once per test session (warm-up on a tiny scene)."""

from __future__ import annotations

import pytest

from moor_env import simulate_drop


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels():
    """Compile (or load from cache) every kernel once, on the cheapest scene with a line."""
    simulate_drop("vertical-chain", {"drop_height_m": 2.0, "vertical_chain_length_m": 4.0})
    return True


@pytest.fixture
def refuse_spacing_below_20_m(monkeypatch):
    """AnchorRelease-v1 finds no equilibrium for a vessel spacing below 20 m (as it finds none for a line too
    short): the refusal mechanism of a positioning move, independent of where the statics' real limits lie."""
    from moor_env.envs.anchor_release_v1 import AnchorReleaseV1Env
    from moor_env.errors import NoEquilibrium

    settle = AnchorReleaseV1Env._settle

    def refusing(self, levers):
        if levers["vessel_spacing_m"] < 20.0:
            raise NoEquilibrium("installation.vessel_spacing_m", levers["vessel_spacing_m"], "20 m or more",
                                "refused by the test")
        settle(self, levers)

    monkeypatch.setattr(AnchorReleaseV1Env, "_settle", refusing)

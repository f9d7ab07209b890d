"""Shared fixtures: the numba kernels compile once per test session (warm-up on a tiny scene)."""

from __future__ import annotations

import pytest

from moor_env import simulate_drop


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels():
    """Compile (or load from cache) every kernel once, on the cheapest scene with a line."""
    simulate_drop("vertical-chain", {"drop_height_m": 2.0, "vertical_chain_length_m": 4.0})
    return True

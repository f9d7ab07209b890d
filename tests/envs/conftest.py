"""Fixtures of the env tests: overrides for the ``tiny`` and the default env config."""

from __future__ import annotations

import pytest

import moor_env  # noqa: F401 - registers the envs


@pytest.fixture(scope="session")
def tiny() -> dict:
    """Overrides for ``config="tiny"`` (none: every reset solves its equilibrium)."""
    return {}


@pytest.fixture(scope="session")
def default_overrides() -> dict:
    """Overrides for the default config (none)."""
    return {}

"""Fixtures of the env tests: the ``tiny`` env config with equilibria cached in a per-session folder."""

from __future__ import annotations

import pytest

import moor_env  # noqa: F401 - registers the envs


@pytest.fixture(scope="session")
def tiny(tmp_path_factory) -> dict:
    """Overrides for ``config="tiny"``: equilibria on disk in a fresh session folder (not the user's cache)."""
    return {"statics.dir": str(tmp_path_factory.mktemp("equilibria"))}


@pytest.fixture(scope="session")
def default_overrides(tmp_path_factory) -> dict:
    """Overrides for the default config: a session equilibrium folder."""
    return {"statics.dir": str(tmp_path_factory.mktemp("equilibria-default"))}

"""Trained policies shipped with the package, one folder each, loadable by name.

A folder ``agents/bundled/<name>/`` is a stable-baselines3 run directory as :mod:`agents.train` writes it, kept
small: ``model.zip``, ``vecnormalize.json`` (the observation normalisation), ``config.yaml`` (the training
config), ``env_config.yaml`` and ``meta.json`` (the command that trained it, its seed, steps and time).
``python -m agents.evaluate <name> crew ...`` and :func:`bundled_path` find it by its name.
"""

from __future__ import annotations

from pathlib import Path

BUNDLED_DIR = Path(__file__).resolve().parent


def bundled_names() -> list[str]:
    """Names of the bundled policies."""
    return sorted(p.name for p in BUNDLED_DIR.iterdir() if (p / "model.zip").is_file())


def bundled_path(name: str) -> Path | None:
    """The folder of the bundled policy ``name``, None if there is none."""
    path = BUNDLED_DIR / name
    return path if name and "/" not in name and (path / "model.zip").is_file() else None


def resolve_target(target: str) -> str:
    """A run directory as given, or the folder of a bundled policy of that name (where no such path exists)."""
    if Path(target).exists():
        return target
    path = bundled_path(target)
    return str(path) if path is not None else target

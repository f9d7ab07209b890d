"""Trained policies shipped with the package, one folder each, loadable by name.

A folder ``agents/bundled/<name>/`` is a stable-baselines3 run directory as :mod:`agents.train` writes it, kept
small: ``model.zip``, ``vecnormalize.json`` (the observation normalisation), ``config.yaml`` (the training
config), ``env_config.yaml``, ``evaluations.json`` (its learning curve) and ``meta.json`` (the run's metadata with
``reproduce``: the commands that trained and chose it). ``python -m agents.evaluate <name> crew ...`` and
:func:`bundled_path` find it by its name; :func:`bundle` (``python -m agents.bundle RUN_DIR --name NAME
--reproduce "..."``) copies a run in.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import yaml

BUNDLED_DIR = Path(__file__).resolve().parent / "bundled"
BUNDLED_FILES = ("model.zip", "vecnormalize.json", "config.yaml", "env_config.yaml", "evaluations.json")


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


def bundle(run_dir: str | Path, name: str, reproduce: str, into: Path = BUNDLED_DIR,
           commit: str | None = None) -> Path:
    """Copy the final model of a run directory into ``into/name`` with its metadata and ``reproduce`` (the
    commands that trained and chose it); ``commit``: the source commit where the run's own metadata has none
    (trained from an exported tree)."""
    run_dir, out = Path(run_dir), Path(into) / name
    missing = [f for f in (*BUNDLED_FILES, "meta.json") if not (run_dir / f).is_file()]
    if missing:
        raise FileNotFoundError(f"{run_dir}: no {', '.join(missing)} (a finished agents.train run directory?)")
    out.mkdir(parents=True, exist_ok=True)
    for f in BUNDLED_FILES:
        shutil.copyfile(run_dir / f, out / f)
    config = yaml.safe_load((out / "config.yaml").read_text())
    config["out_dir"] = "runs"  # where the run went on the machine that trained it means nothing here
    (out / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    meta = json.loads((run_dir / "meta.json").read_text())
    # the paths and arguments of the machine that trained it: ``reproduce`` says how to train it again
    meta = {k: v for k, v in meta.items() if k not in ("moor_env_path", "argv")}
    meta.update(reproduce=reproduce, bundled_from=f"{run_dir.parent.name}/{run_dir.name}")
    if commit and not meta.get("git_commit"):
        meta["git_commit"] = commit
    (out / "meta.json").write_text(json.dumps(meta, indent=1) + "\n")
    return out


def main(argv: list[str] | None = None) -> int:
    """Command line of :func:`bundle`."""
    p = argparse.ArgumentParser(prog="python -m agents.bundle", description="copy a trained run into the package")
    p.add_argument("run_dir")
    p.add_argument("--name", required=True)
    p.add_argument("--reproduce", required=True, help="the commands that trained and chose the run")
    p.add_argument("--commit", help="source commit of a run trained from an exported tree")
    args = p.parse_args(argv)
    print(bundle(args.run_dir, args.name, args.reproduce, commit=args.commit))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``python -m moor_env.envs.precompute --config anchor-release --jobs 2``: solve and store the hanging
equilibria of every discrete scenario combination of an env config ahead of training
(see :mod:`moor_env.envs.equilibria`)."""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import time
from typing import Any

from moor_env.envs.config import _values, load_env_config
from moor_env.envs.equilibria import EquilibriumCache, discrete_grid
from moor_env.envs.scenario import representative_scenario
from moor_env.envs.scene import SceneFactory


def solve_grid_row(args: tuple[dict[str, Any], dict[str, float]]) -> tuple[str, float]:
    """Solve (or find cached) the equilibria of one :func:`~moor_env.envs.equilibria.discrete_grid` row of an env
    config (``args``: the config as a mapping and the row) in every sea state of the config; where they came
    from and the wall time [s]. Runs in worker processes."""
    cfg_data, row = args
    cfg = load_env_config(cfg_data)
    factory = SceneFactory(cfg)
    cache = EquilibriumCache(cfg.statics)
    t0 = time.perf_counter()
    scenario = {**representative_scenario(cfg), **row}
    origins = []
    # calm and wavy scenarios start from equilibria at different resolutions (SceneFactory.pre_release_resolution)
    for hs_m in sorted(set(_values(cfg.scenario.sea_state_hs_m)) | {scenario["sea_state_hs_m"]}):
        try:
            origins.append(cache.state(factory.statics_data({**scenario, "sea_state_hs_m": hs_m}))[1])
        except Exception as exc:  # noqa: BLE001 - report and go on with the grid
            return f"failed: {exc}", time.perf_counter() - t0
    return ", ".join(dict.fromkeys(origins)), time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    """Solve and store the equilibria of every discrete scenario combination of a config."""
    parser = argparse.ArgumentParser(prog="python -m moor_env.envs.precompute", description=main.__doc__)
    parser.add_argument("--config", default="anchor-release", help="env config name or YAML path")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes")
    args = parser.parse_args(argv)
    cfg = load_env_config(args.config)
    if not cfg.statics.disk:
        print("statics.disk is false: nothing would be kept", file=sys.stderr)
        return 2
    grid = discrete_grid(cfg)
    print(f"{len(grid)} equilibria for config '{cfg.name}'")
    data = cfg.model_dump()
    t0 = time.perf_counter()
    if args.jobs > 1:
        with mp.get_context("spawn").Pool(args.jobs) as pool:
            results = pool.imap(solve_grid_row, [(data, row) for row in grid])
            for i, (origin, wall) in enumerate(results):
                print(f"{i + 1}/{len(grid)} {grid[i]} {origin} {wall:.2f} s", flush=True)
    else:
        for i, row in enumerate(grid):
            origin, wall = solve_grid_row((data, row))
            print(f"{i + 1}/{len(grid)} {row} {origin} {wall:.2f} s", flush=True)
    print(f"done in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

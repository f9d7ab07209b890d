"""Solve the hanging equilibria a training config and the held-out set will need, ahead of time.

    python -m agents.precompute --config full [--n-scenarios 24] [--jobs 2]

Every reset starts from a cached equilibrium (:mod:`moor_env.envs.equilibria`); a combination not yet cached
costs a static solve of seconds, far more than the episode. This solves every discrete combination of the
training config's scenario distribution and every geometry of the held-out set once, into the on-disk cache
(keyed on the physics sources, so an edited solver starts a fresh cache).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import sys
import time

from tqdm import tqdm

from agents.config import load_train_config, parse_set
from agents.scenarios import held_out_scenarios
from moor_env.envs.config import SCENARIO_RANGES, load_env_config
from moor_env.envs.equilibria import DYNAMIC_ONLY_FIELDS, discrete_grid
from moor_env.envs.precompute import solve_grid_row

STATICS_FIELDS = tuple(n for n in SCENARIO_RANGES if n not in DYNAMIC_ONLY_FIELDS)


def equilibrium_rows(train_config, n_scenarios: int) -> list[dict[str, float]]:
    """Distinct statics-relevant field combinations of the training distribution and the held-out set."""
    env_cfg = load_env_config(train_config.env.config, train_config.env.overrides)
    rows = discrete_grid(env_cfg)
    for sc in held_out_scenarios(n_scenarios) if n_scenarios > 0 else []:
        rows.append({k: float(sc["options"][k]) for k in STATICS_FIELDS})
    seen, unique = set(), []
    for row in rows:
        key = tuple(sorted(row.items()))
        if key not in seen:
            seen.add(key)
            unique.append(row)
    return unique


def precompute(train_config, n_scenarios: int, jobs: int = 1, progress: bool = True) -> dict[str, int]:
    """Solve every row of :func:`equilibrium_rows`; returns counts by origin (cache hit, solved, failed)."""
    env_cfg = load_env_config(train_config.env.config, train_config.env.overrides)
    data = env_cfg.model_dump()
    rows = equilibrium_rows(train_config, n_scenarios)
    counts: dict[str, int] = {}
    bar = tqdm(total=len(rows), desc="equilibria", disable=not progress)
    if jobs > 1:
        with mp.get_context("fork").Pool(jobs) as pool:
            results = list(_iter_bar(pool.imap(solve_grid_row, [(data, r) for r in rows]), bar))
    else:
        results = list(_iter_bar((solve_grid_row((data, r)) for r in rows), bar))
    bar.close()
    for row, (origin, _) in zip(rows, results, strict=True):
        key = "failed" if origin.startswith("failed") else origin
        if key == "failed":
            print(f"equilibrium {row}: {origin}", file=sys.stderr)
        counts[key] = counts.get(key, 0) + 1
    return counts


def _iter_bar(items, bar):
    for item in items:
        bar.update()
        yield item


def main(argv: list[str] | None = None) -> int:
    """Entry point."""
    p = argparse.ArgumentParser(prog="python -m agents.precompute", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", default="quick", help="training config whose env distribution to cover")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--n-scenarios", type=int, default=24, help="held-out set size to cover (0: none)")
    p.add_argument("--jobs", type=int, default=1)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    counts = precompute(load_train_config(args.config, parse_set(args.set)), args.n_scenarios, args.jobs)
    print(f"{counts} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

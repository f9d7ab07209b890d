"""Throughput of Ray RLlib PPO (agents/train_rllib.py) on one machine against a plain single-process env loop.

    python benchmarks/bench_rllib.py [--config rllib-release] [--runners 1 2] [--batch 256] [--iterations 4]
                                     [--set env.overrides.scenario.current_scale=0.0 ...]

For each env-runner count, trains ``--iterations`` PPO iterations of ``--batch`` env steps on a fresh local Ray
instance and reports the steady-state rate (iterations after the first, which also pays for actor warm-up): env
steps/s and episodes/s over the iterations' wall time, sampling and learning together. The reference is the same
env stepped in this process with uniform random actions after a few untimed episodes (PPO's initial Gaussian
policy also releases on about half of the steps, so episodes are comparably short).

Every reset solves its hanging equilibrium (milliseconds, part of the measured throughput). Writes
``benchmarks/results/bench_rllib.json`` with the machine, the load averages and the versions, and the table in
``docs/rllib.md`` from ``bench_rllib*.json`` (``--docs-only``: only the table, from the committed JSON).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _docs import DOCS, RESULTS, load_result, table, write_blocks  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from agents.config import parse_set  # noqa: E402
from agents.io import write_json_atomic  # noqa: E402
from agents.train_rllib import load_rllib_config, train_rllib  # noqa: E402
from moor_env.envs.config import load_env_config  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "bench_rllib.json"


def cpu_model() -> str:
    """The CPU's model name (Linux ``/proc/cpuinfo``)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def random_episodes(env: gym.Env, episodes: int, first_seed: int) -> int:
    """Run episodes with uniform random actions; the number of env steps taken."""
    steps = 0
    for k in tqdm(range(episodes), desc="plain loop", unit="episode", leave=False):
        env.reset(seed=first_seed + k)
        done = False
        while not done:
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            steps += 1
            done = terminated or truncated
    return steps


def plain_loop(env_id: str, env_config, episodes: int, warmup: int = 3, seed: int = 0) -> dict:
    """Uniform random actions in this process after ``warmup`` untimed episodes: env steps/s and episodes/s."""
    env = gym.make(env_id, config=env_config)
    env.action_space.seed(seed)
    random_episodes(env, warmup, 10**6 + seed)
    t0 = time.perf_counter()
    steps = random_episodes(env, episodes, seed)
    wall = time.perf_counter() - t0
    env.close()
    return {"episodes": episodes, "env_steps": steps, "wall_s": wall, "env_steps_per_s": steps / wall,
            "episodes_per_s": episodes / wall, "loadavg_after": os.getloadavg()}


def rllib_run(config: str, overrides: dict, runners: int, batch: int, iterations: int, out_dir: str) -> dict:
    """``iterations`` PPO iterations with ``runners`` env runners on a fresh local Ray; steady-state rates."""
    import ray  # noqa: PLC0415

    cfg = load_rllib_config(config, {
        **overrides, "name": f"bench-{runners}", "out_dir": out_dir, "total_timesteps": batch * iterations,
        "env_runners.num_env_runners": runners, "env_runners.rollout_fragment_length": "auto",
        "ppo.train_batch_size_per_learner": batch, "ppo.minibatch_size": min(128, batch),
        "checkpoint.every_iterations": 10**6, "ray.num_cpus": os.cpu_count(), "progress_bar": False})
    load_before = os.getloadavg()
    _, meta = train_rllib(cfg)
    ray.shutdown()
    rows = json.loads((Path(out_dir) / cfg.name / "seed-0" / "progress.json").read_text())
    steady = rows[1:] or rows
    d_steps = steady[-1]["env_steps"] - (rows[0]["env_steps"] if len(rows) > 1 else 0)
    d_eps = steady[-1]["episodes"] - (rows[0]["episodes"] if len(rows) > 1 else 0)
    wall = sum(r["iteration_s"] for r in steady)
    return {"env_runners": runners, "iterations": len(rows), "build_s": meta["build_s"],
            "first_iteration_s": rows[0]["iteration_s"], "steady_env_steps": d_steps, "steady_episodes": d_eps,
            "steady_wall_s": wall, "env_steps_per_s": d_steps / wall, "episodes_per_s": d_eps / wall,
            "overall_env_steps_per_s": meta["env_steps_per_s"], "loadavg_before": load_before,
            "loadavg_after": os.getloadavg(), "rows": rows}


DOC = DOCS / "rllib.md"
STEMS = ("bench_rllib", "bench_rllib_envs4")


def docs_blocks(results: dict[str, dict]) -> list[tuple[Path, str, str]]:
    """The throughput table (docs/rllib.md) from the runs ``results`` (JSON name -> result)."""
    plain = [r["plain_loop"] for r in results.values()]
    steps = [p["env_steps_per_s"] for p in plain]
    eps = [p["episodes_per_s"] for p in plain]
    rows = [["plain loop, one process, random actions (same windows)", f"{min(steps):.0f}-{max(steps):.0f}",
             f"{min(eps):.0f}-{max(eps):.0f}"]]
    notes = []
    for stem, result in results.items():
        per_runner = result["overrides"].get("env_runners.num_envs_per_env_runner")
        for r in result["rllib"]:
            setup = f"RLlib PPO, {r['env_runners']} env runner{'s' if r['env_runners'] > 1 else ''}" + \
                (f" x {per_runner} envs" if per_runner else "")
            rows.append([setup, f"{r['env_steps_per_s']:.0f}", f"{r['episodes_per_s']:.0f}"])
        m = result["machine"]
        load = result["loadavg_start"][0]
        notes.append(f"`benchmarks/results/{stem}.json`" + (f" (run {result['date'][:10]})" if "date" in result else "")
                     + f": {m['cpu']}, {m['cpu_count']} logical cores, 1-min load average {load:.1f} at the start, "
                     f"PPO batches of {result['batch']} env steps")
    return [(DOC, "bench_rllib", table(["setup", "env steps/s", "episodes/s"], rows) + "\n\n" +
             "; ".join(notes) + ".")]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/bench_rllib*.json``."""
    results = {stem: load_result(stem) for stem in STEMS}
    return docs_blocks({stem: r for stem, r in results.items() if r is not None})


def main(argv: list[str] | None = None) -> int:
    """Run the plain loop and the RLlib runs; write the JSON."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--config", default="rllib-release")
    p.add_argument("--runners", type=int, nargs="+", default=[1, 2])
    p.add_argument("--batch", type=int, default=256, help="env steps per PPO iteration")
    p.add_argument("--iterations", type=int, default=4)
    p.add_argument("--episodes", type=int, default=40, help="episodes of the plain loop")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="RLlib config override (also the plain loop's env): env.overrides.scenario.current_scale=0")
    p.add_argument("--out", default=str(OUT))
    p.add_argument("--docs-only", action="store_true",
                   help="rewrite the docs table from benchmarks/results/bench_rllib*.json, run nothing")
    args = p.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return 0
    overrides = parse_set(args.set)
    cfg = load_rllib_config(args.config, overrides)
    env_cfg = load_env_config(cfg.env.config, cfg.env.overrides)
    result = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
              "machine": {"host": platform.node(), "cpu": cpu_model(), "cpu_count": os.cpu_count(),
                          "python": platform.python_version()},
              "config": args.config, "overrides": overrides, "env_id": cfg.env.id, "env_config": env_cfg.name,
              "batch": args.batch,
              "loadavg_start": os.getloadavg(), "plain_loop": plain_loop(cfg.env.id, env_cfg, args.episodes),
              "rllib": []}
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.runners:
            result["rllib"].append(rllib_run(args.config, overrides, n, args.batch, args.iterations, tmp))
    plain = result["plain_loop"]["env_steps_per_s"]
    for r in result["rllib"]:
        r["ratio_to_plain_loop"] = r["env_steps_per_s"] / plain
    write_json_atomic(args.out, result)
    if Path(args.out).resolve().parent == RESULTS.resolve() and Path(args.out).stem in STEMS:
        write_blocks(docs_from_results())
    print(f"plain loop: {plain:.1f} env steps/s, {result['plain_loop']['episodes_per_s']:.2f} episodes/s")
    for r in result["rllib"]:
        print(f"rllib {r['env_runners']} runner(s): {r['env_steps_per_s']:.1f} env steps/s, "
              f"{r['episodes_per_s']:.2f} episodes/s ({r['ratio_to_plain_loop']:.2f}x the plain loop), "
              f"start-up {r['build_s']:.0f} s, load {r['loadavg_before'][0]:.1f}-{r['loadavg_after'][0]:.1f}")
    print(f"written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Benchmark: AnchorRelease-v0 steps and episodes per second, single env, async vector env and batched env (threads in
one process, and worker processes).

Run from the repository root: ``python benchmarks/bench_env.py [--episodes 3] [--repeats 3] [--quick]``. Every env
runs the default config (``configs/envs/anchor-release.yaml``: the ``fast`` fidelity preset, 1 s control steps, the
pre-release phase integrated with ``control.pre_release_dt_s``) on the default scene's geometry (gjoa-500: depth
500 m, spacing 0.1 h, line 1.08 h, no current) with the sea state drawn from the config (Hs 0-3 m, so most resets
simulate the 20 s wave warm-up). The policy holds the vessels for 59 steps and releases on the 60th, so one episode
is 59 s of pre-release control plus the fall to touchdown, after the reset's warm-up. The equilibrium is solved
before timing starts (it is cached). With waves the env runs the `fast` preset's tight_line resolution with its
``in_waves`` keys (1 m loop chain) throughout. A second variant (``calm default scene``) keeps the bundled gjoa-500
scene as it is, without waves (Hs 0, no warm-up): its slack loop hangs and falls on the coarse resolution. A third
runs the pre-release phase at the scene's own step (``control.pre_release_dt_s`` and ``pre_release_dt_calm_s`` null)
for comparison. The ``fresh geometry`` variant (single env, calm water, no current) draws every episode's geometry
from the config's ranges (depth, spacing, line length, anchor mass), so every reset solves a new equilibrium on a
newly compiled model; it records the reset and whole-episode times (median) and where the time goes, and again
on the same geometries with the fall's step growing up to 3x (``discretization.fall_step_growth_max``).
``--variant NAME`` runs one variant and merges its rows into the committed JSON (the other rows keep their numbers).

Measured for each env: wall time, CPU time of every process involved (``/proc`` for worker processes), transitions
(env steps that are not autoresets) and episodes per second, per second per core used. Every row runs ``--repeats``
times, round robin, and the table shows each row's median round (all rounds are in the JSON): on this shared machine
one row's rate moves by tens of percent between minutes. The batched over async ratio is given both ways: best
median row over best median row, and within each round (rows a minute apart, so both see the same minute of the
machine), with the spread of the rounds. Writes ``benchmarks/results/bench_env.json``, its table in
``docs/env-speed.md`` and the README's headline line (``--docs-only``: only those, from the committed JSON). The
1-minute load average before and after is recorded with the results.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import gymnasium as gym  # noqa: E402
from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from moor_env.envs import AnchorReleaseVectorEnv  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "bench_env.json"
ENV_ID = "moor_env/AnchorRelease-v0"
SCENE = {"water_depth_m": 500.0, "vessel_spacing_over_depth": 0.1, "mooring_line_length_over_depth": 1.08,
         "current_scale": 0.0, "anchor_mass_scale": 1.0}
OVERRIDES = {f"scenario.{k}": v for k, v in SCENE.items()}  # autoresets draw from the config: fix it there
CALM = {"scenario.sea_state_hs_m": 0.0}  # the bundled default scene as it is: no waves
FRESH = {"scenario.sea_state_hs_m": 0.0, "scenario.current_scale": 0.0}  # geometry from the config's ranges
FRESH_LABEL = "fresh geometry"
# the same with the fall's step grown where the lines move slowly (docs/fall-accuracy.md; off in the presets)
FRESH_GROWING = {**FRESH, "fidelity.discretization.fall_step_growth_max": 3.0}
FRESH_GROWING_LABEL = "fresh geometry, fall step growing 3x"
RELEASE_STEP = 59  # 0-based: 59 holding steps, release on the 60th
SINGLE_EPISODES_FACTOR = 4  # the single env's episodes are cheap and its CPU per episode is the target: more of them


def _proc_cpu_s(pid: int) -> float:
    """utime + stime of a live process [s] (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _actions(k: np.ndarray) -> np.ndarray:
    act = np.zeros((k.size, 3), np.float32)
    act[:, 2] = np.where(k >= RELEASE_STEP, 1.0, -1.0)
    return act


def bench_single(episodes: int, overrides: dict) -> dict:
    env = gym.make(ENV_ID, overrides=overrides)
    env.reset(seed=0)  # solves (or loads) the equilibrium, compiles nothing new; then one untimed episode
    for k in range(RELEASE_STEP + 1):  # (compiles the fall's model, makes the advancer)
        env.step(_actions(np.array([k]))[0])
    advancer = env.unwrapped.core.advancer
    advancer.kernel_s = 0.0
    steps = 0
    resets_wall = 0.0
    episode_cpu = []
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for ep in tqdm(range(episodes), desc="single env", leave=False):
        t, c = time.perf_counter(), time.process_time()
        env.reset(seed=100 + ep)
        resets_wall += time.perf_counter() - t
        for k in range(RELEASE_STEP + 1):
            _, _, terminated, truncated, info = env.step(_actions(np.array([k]))[0])
            steps += 1
            if terminated or truncated:
                break
        episode_cpu.append(time.process_time() - c)
        assert info["sim_status"] == "touchdown", info["sim_status"]
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    env.close()
    return {"env": "single", "num_envs": 1, "cores": 1, "episodes": episodes, "transitions": steps,
            "wall_s": wall, "cpu_s": cpu, "reset_wall_s_mean": resets_wall / episodes, "kernel_s": advancer.kernel_s,
            "episode_cpu_s": {"min": min(episode_cpu), "median": float(np.median(episode_cpu)),
                              "max": max(episode_cpu)}}


class _FreshRun:
    """One fresh-geometry env and the times of its episodes (:func:`bench_fresh_geometry`)."""

    def __init__(self, overrides: dict) -> None:
        self.env = gym.make(ENV_ID, overrides=overrides)
        self.steps = 0
        for seed in (0, 1):  # compiles the kernels; then the timed episodes draw geometries not seen before
            self._play(seed)
        self.steps = self.redraws = 0
        self.equilibria = self.env.unwrapped.core.equilibria
        self.solves0, self.solve_s0 = self.equilibria.solves, self.equilibria.solve_wall_s
        self.times: dict[str, list[float]] = {k: [] for k in ("reset_wall", "reset_cpu", "episode_wall",
                                                               "episode_cpu", "release_wall")}
        self.origins: set[str] = set()

    def _play(self, seed: int) -> tuple[dict, dict, float]:
        """Reset and the episode's steps: reset info (with the reset's wall and CPU time [s]), last step's info,
        wall time of the last step [s]."""
        t, c = time.perf_counter(), time.process_time()
        _, info = self.env.reset(seed=seed)
        info = {**info, "reset_wall_s": time.perf_counter() - t, "reset_cpu_s": time.process_time() - c}
        for k in range(RELEASE_STEP + 1):
            tf = time.perf_counter()
            _, _, terminated, truncated, step_info = self.env.step(_actions(np.array([k]))[0])
            self.steps += 1
            if terminated or truncated:
                break
        return info, step_info, time.perf_counter() - tf

    def episode(self, seed: int) -> None:
        """One timed episode, on an equilibrium solved afresh (the equilibria kept in memory are shared by every
        env of the process, so another variant's episode on the same geometry would have left this one's)."""
        self.equilibria.memory.clear()
        t, c = time.perf_counter(), time.process_time()
        info, step_info, release_wall = self._play(seed)
        assert step_info["sim_status"] == "touchdown", step_info["sim_status"]
        self.redraws += info["scenario_redraws"]
        self.origins.add(info["statics"])
        self.times["release_wall"].append(release_wall)
        self.times["episode_wall"].append(time.perf_counter() - t)
        self.times["episode_cpu"].append(time.process_time() - c)
        self.times["reset_wall"].append(info["reset_wall_s"])
        self.times["reset_cpu"].append(info["reset_cpu_s"])

    def result(self) -> dict:
        """Totals and the median and spread of every time."""
        def stats(values: list[float]) -> dict[str, float]:
            return {"min": min(values), "median": float(np.median(values)), "p90": float(np.percentile(values, 90)),
                    "max": max(values)}

        solves = self.equilibria.solves - self.solves0
        tm = self.times
        self.env.close()
        return {"env": "single", "num_envs": 1, "cores": 1, "episodes": len(tm["episode_wall"]),
                "transitions": self.steps, "wall_s": sum(tm["episode_wall"]), "cpu_s": sum(tm["episode_cpu"]),
                "statics": sorted(self.origins), "solves": solves,
                "solve_wall_s_mean": (self.equilibria.solve_wall_s - self.solve_s0) / max(solves, 1),
                "scenario_redraws": self.redraws, "reset_wall_s": stats(tm["reset_wall"]),
                "reset_cpu_s": stats(tm["reset_cpu"]), "episode_wall_s": stats(tm["episode_wall"]),
                "episode_cpu_s": stats(tm["episode_cpu"]), "release_step_wall_s": stats(tm["release_wall"])}


def bench_fresh_geometry(episodes: int, variants: dict[str, dict]) -> dict[str, dict]:
    """Single env, calm water, every episode on a new geometry drawn from the config's ranges (a new equilibrium
    and compiled model at every reset): reset and whole-episode wall and CPU time, median and spread, for each
    of ``variants`` (name: overrides), which play each geometry in turn (the machine's drift hits them alike)."""
    runs = {name: _FreshRun(overrides) for name, overrides in variants.items()}
    for ep in tqdm(range(episodes), desc="fresh geometry", leave=False):
        for run in runs.values():
            run.episode(10_000 + ep)
    return {name: run.result() for name, run in runs.items()}


def _run_vector(env, n: int, episodes_per_env: int, cpu_fn) -> dict:
    env.reset(seed=0)
    if hasattr(env, "batch"):
        env.batch.kernel_s = 0.0
    k = np.zeros(n, dtype=np.int64)
    autoreset = np.zeros(n, dtype=bool)
    done_episodes = 0
    transitions = 0
    wall0, cpu0 = time.perf_counter(), cpu_fn()
    while done_episodes < episodes_per_env * n:
        _, _, terminated, truncated, info = env.step(_actions(k))
        transitions += int(np.sum(~autoreset))
        ended = (terminated | truncated) & ~autoreset
        done_episodes += int(np.sum(ended))
        k = np.where(autoreset, 0, k + 1)
        autoreset = terminated | truncated
    wall, cpu = time.perf_counter() - wall0, cpu_fn() - cpu0
    return {"episodes": done_episodes, "transitions": transitions, "wall_s": wall, "cpu_s": cpu}


def _cpu_of(pids: list[int]):
    """CPU seconds of this process and the worker processes ``pids``, as a function for ``_run_vector``."""
    return lambda: time.process_time() + sum(_proc_cpu_s(p) for p in pids)


def bench_async(n: int, episodes_per_env: int, overrides: dict) -> dict:
    env = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="async", overrides=overrides)
    out = _run_vector(env, n, episodes_per_env, _cpu_of([p.pid for p in env.processes]))
    env.close()
    return {"env": "async", "num_envs": n, "cores": min(n, os.cpu_count() or 1), **out}


def bench_workers(n: int, episodes_per_env: int, workers: int, overrides: dict) -> dict:
    env = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", overrides=overrides,
                       num_workers=workers)
    out = _run_vector(env, n, episodes_per_env, _cpu_of([p.pid for p in env.processes]))
    env.close()
    return {"env": "batched, worker processes", "num_envs": n, "cores": min(workers, os.cpu_count() or 1),
            "workers": workers, **out}


def bench_batched(n: int, episodes_per_env: int, threads: int, overrides: dict) -> dict:
    env = AnchorReleaseVectorEnv(num_envs=n, overrides=overrides, num_threads=threads)
    env.batch.kernel_s = 0.0
    out = _run_vector(env, n, episodes_per_env, time.process_time)
    env.close()
    return {"env": "batched", "num_envs": n, "cores": min(threads, os.cpu_count() or 1), "threads": threads, **out,
            "kernel_s": env.batch.kernel_s}


def _rates(row: dict) -> dict:
    row["transitions_per_s"] = row["transitions"] / row["wall_s"]
    row["episodes_per_s"] = row["episodes"] / row["wall_s"]
    row["episodes_per_s_per_core"] = row["episodes_per_s"] / row["cores"]
    row["cpu_s_per_episode"] = row["cpu_s"] / row["episodes"]
    row["wall_s_per_episode_per_core"] = row["wall_s"] * row["cores"] / row["episodes"]
    row["cpu_ms_per_transition"] = 1e3 * row["cpu_s"] / row["transitions"]
    if "kernel_s" in row:
        row["kernel_share_of_cpu"] = row["kernel_s"] / row["cpu_s"]
    return row


def _best_ratio(rows: list[dict], label: str) -> float:
    """Best batched row over best async row of ``label`` in ``rows``, transitions per second."""
    mine = [r for r in rows if r["variant"] == label]
    best = max(r["transitions_per_s"] for r in mine if r["env"].startswith("batched"))
    return best / max(r["transitions_per_s"] for r in mine if r["env"] == "async")


def round_ratios(rounds: list[list[dict]], labels: list[str]) -> dict[str, dict[str, float | list[float]]]:
    """:func:`_best_ratio` within each round (rows measured minutes apart, paired against the machine's drift):
    the per-round values with their minimum, median and maximum, by variant."""
    out = {}
    for label in labels:
        values = [_best_ratio(rows, label) for rows in rounds]
        out[label] = {"per_round": values, "min": min(values), "median": float(np.median(values)),
                      "max": max(values)}
    return out


DOC = DOCS / "env-speed.md"
README = ROOT / "README.md"
COMMAND = "python benchmarks/bench_env.py"


def env_table(rows: list[dict]) -> str:
    """The rows (each one's median round) as a markdown table."""
    out = []
    for r in rows:
        share = f"{r['kernel_share_of_cpu']:.0%}" if "kernel_share_of_cpu" in r else "-"
        procs = f"{r['workers']} procs" if "workers" in r else r.get("threads", r["cores"])
        out.append([r["variant"], r["env"], r["num_envs"], procs, f"{r['transitions_per_s']:.1f}",
                    f"{r['episodes_per_s']:.3f}", f"{r['episodes_per_s_per_core']:.3f}",
                    f"{r['cpu_s_per_episode']:.3f}", f"{r['cpu_ms_per_transition']:.3f}", share])
    return table(["variant", "env", "envs", "threads/procs", "transitions/s", "episodes/s", "episodes/s/core",
                  "CPU s/episode", "CPU ms/transition", "kernel share"], out)


def fresh_table(fresh: dict, growing: dict | None = None) -> str:
    """The ``fresh geometry`` run (and the one with the growing fall step, where given) as a line and a markdown
    table (milliseconds)."""
    def ms(stats: dict) -> str:
        return f"{1e3 * stats['median']:.1f} / {1e3 * stats['p90']:.1f}"

    def row(label: str, run: dict) -> list:
        return [label, run["episodes"], ms(run["reset_wall_s"]), ms(run["reset_cpu_s"]),
                f"{1e3 * run['solve_wall_s_mean']:.1f}", ms(run["episode_wall_s"]), ms(run["episode_cpu_s"]),
                ms(run["release_step_wall_s"])]

    date = fresh["date"][:19].replace("T", " ")
    head = (f"`{COMMAND} --variant fresh-geometry`, run {date} UTC on {fresh['machine']} (1-min load average "
            f"{fresh['load_average_1min']['before']:.1f} -> {fresh['load_average_1min']['after']:.1f}): single "
            f"env, calm water, no current, {fresh['episodes']} episodes, each on a new geometry drawn from the "
            f"config's ranges ({fresh['solves']} static solves, {fresh['scenario_redraws']} redraws). Times in ms, "
            "median / 90th percentile; `release step` is the last step (remesh and fall to touchdown).")
    rows = [row(FRESH_LABEL, fresh)]
    if growing is not None:
        head += (f" `{FRESH_GROWING_LABEL}`: the same geometries with `discretization.fall_step_growth_max: 3` "
                 "([fall-accuracy.md](fall-accuracy.md)).")
        rows.append(row(FRESH_GROWING_LABEL, growing))
    return head + "\n\n" + table(["variant", "episodes", "reset", "reset CPU", "solve (mean)", "episode",
                                  "episode CPU", "release step"], rows)


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The docs blocks of one run: the table with the batched/async ratios (docs/env-speed.md) and the README's
    headline line."""
    rows = result["rows"]
    labels = list(result["batched_over_async_transitions"])
    within = result.get("batched_over_async_within_rounds") or round_ratios(result["rounds"], labels)
    lines = [run_line(result, COMMAND) + f" {len(result['rounds'])} rounds of every row, round robin; the table "
             "shows each row's median round.", "", env_table(rows), ""]
    for label in labels:
        ratio = result["batched_over_async_transitions"][label]
        b = result["batched_over_async_bound_from_kernel_cost"][label]
        w = within[label]
        lines.append(f"- {label}: best batched over best async row, transitions per second, {ratio:.2f}x "
                     f"(within each round: {', '.join(f'{x:.2f}' for x in w['per_round'])}); bound with free "
                     f"Python and IPC (async CPU per transition over the single env's kernel CPU per transition): "
                     f"{b['async_cpu_ms_per_transition']:.3f} / {b['single_kernel_ms_per_transition']:.3f} ms = "
                     f"{b['batched_over_async_upper_bound']:.2f}x.")
    fresh = result.get("fresh_geometry")
    if fresh is not None:
        lines += ["", fresh_table(fresh, result.get("fresh_geometry_growing")), ""]
    single = {r["variant"]: r for r in rows if r["env"] == "single"}
    calm, waves = single.get("calm default scene"), single.get("default config")
    ratios = result["batched_over_async_transitions"]
    parts = []
    if calm is not None:
        parts.append(f"{1e3 * calm['cpu_s_per_episode']:.0f} ms CPU per episode on the calm default scene")
    if waves is not None:
        parts.append(f"{1e3 * waves['cpu_s_per_episode']:.0f} ms with the config's waves")
    best = max((r for r in rows if r["variant"] == "calm default scene"), key=lambda r: r["transitions_per_s"],
               default=None)
    headline = ("**Env speed** (single env, 60 s of control plus the fall): " + ", ".join(parts) + ". ")
    if best is not None:
        headline += (f"The batched vector env steps {best['transitions_per_s']:.0f} transitions/s calm, "
                     f"{ratios['calm default scene']:.2f}x the async one ({ratios['default config']:.2f}x in waves). ")
    headline += f"`{COMMAND}`, run {result['date'][:10]}: [docs/env-speed.md](docs/env-speed.md)."
    return [(DOC, "bench_env", "\n".join(lines)), (README, "headline-bench_env", headline)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/bench_env.json``."""
    return docs_blocks(load_result("bench_env"))


def main(argv: list[str] | None = None) -> dict:
    """Run every configuration, write the JSON and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=3, help="episodes per env slot")
    parser.add_argument("--quick", action="store_true", help="1 episode per slot (a smoke run)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="rounds of every row (round robin); the table shows each row's median round")
    parser.add_argument("--no-compare", action="store_true",
                        help="only the default config (no calm scene, no pre-release at the scene's step)")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/bench_env.json, run nothing")
    parser.add_argument("--variant", choices=["fresh-geometry"],
                        help="run only this variant and merge it into benchmarks/results/bench_env.json")
    parser.add_argument("--fresh-episodes", type=int, default=40, help="episodes of the fresh geometry variant")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return load_result("bench_env")
    episodes = 1 if args.quick else args.episodes
    load_before = os.getloadavg()[0]
    if args.variant == "fresh-geometry":
        result = load_result("bench_env")
        variants = {"fresh_geometry": FRESH, "fresh_geometry_growing": FRESH_GROWING}
        runs = bench_fresh_geometry(4 if args.quick else args.fresh_episodes, variants)
        for key, fresh in runs.items():
            result[key] = {**run_record(load_before), "python": platform.python_version(),
                           "config": "anchor-release (default)", "overrides": variants[key], **fresh}
        result["targets"] = {**result.get("targets", {}), "fresh_reset_wall_s_median": 0.020,
                             "fresh_episode_wall_s_median": 0.040}
        RESULTS.write_text(json.dumps(result, indent=2))
        write_blocks(docs_blocks(result))
        print(fresh_table(result["fresh_geometry"], result["fresh_geometry_growing"]))
        return result
    variants = [("default config", OVERRIDES)]
    if not args.no_compare:
        variants.append(("pre-release at the scene's step", {**OVERRIDES, "control.pre_release_dt_s": None,
                                                             "control.pre_release_dt_calm_s": None}))
        variants.insert(1, ("calm default scene", {**OVERRIDES, **CALM}))
    rounds: list[list[dict]] = []
    for round_index in range(max(1, args.repeats)):
        rows = []
        for label, overrides in variants:
            # (bench, its arguments before the overrides): envs, episodes per env, threads or worker processes
            runs = [(bench_single, SINGLE_EPISODES_FACTOR * episodes), (bench_async, 2, episodes),
                    (bench_async, 8, episodes), (bench_batched, 2, episodes, 2), (bench_batched, 8, episodes, 2),
                    (bench_batched, 16, episodes, 2), (bench_batched, 32, episodes, 2), (bench_batched, 8, episodes, 1),
                    (bench_workers, 16, episodes, 2), (bench_workers, 32, episodes, 2)]
            for bench, *bench_args in runs:
                rows.append({"variant": label, "round": round_index, **_rates(bench(*bench_args, overrides))})
                print(rows[-1], flush=True)
        rounds.append(rows)
    # the machine is shared and its speed drifts by tens of percent over minutes: each row's median round
    rows = [sorted(same, key=lambda r: r["transitions_per_s"])[len(same) // 2] for same in zip(*rounds, strict=True)]
    ratios = {}
    bounds = {}
    for label, _ in variants:
        mine = [r for r in rows if r["variant"] == label]
        pick = {"single": next(r for r in mine if r["env"] == "single"),
                "async": max((r for r in mine if r["env"] == "async"), key=lambda r: r["transitions_per_s"])}
        ratios[label] = _best_ratio(rows, label)  # best median row against best median row
        # with every core busy, throughput ratio = ratio of CPU per transition; the batched env runs the same
        # kernel as the single env, so it cannot spend less than the single env's kernel time per transition
        kernel_ms = 1e3 * pick["single"]["kernel_s"] / pick["single"]["transitions"]
        bounds[label] = {"async_cpu_ms_per_transition": pick["async"]["cpu_ms_per_transition"],
                         "single_kernel_ms_per_transition": kernel_ms,
                         "batched_over_async_upper_bound": pick["async"]["cpu_ms_per_transition"] / kernel_ms}
    previous = load_result("bench_env") if RESULTS.is_file() else {}
    result = {
        **run_record(load_before),
        "python": platform.python_version(),
        "config": "anchor-release (default)",
        "scenario": SCENE,
        "episode": f"{RELEASE_STEP} control steps of 1 s, release, fall to touchdown",
        "rows": rows,
        "rounds": rounds,
        "batched_over_async_transitions": ratios,
        "batched_over_async_within_rounds": round_ratios(rounds, [label for label, _ in variants]),
        "batched_over_async_bound_from_kernel_cost": bounds,
        "targets": {**previous.get("targets", {}), "episode_cpu_s": 0.050, "batched_over_async": 3.0},
    }
    if "fresh_geometry" in previous:  # measured by --variant fresh-geometry
        result["fresh_geometry"] = previous["fresh_geometry"]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(result, indent=2))
    blocks = docs_blocks(result)
    write_blocks(blocks)
    print(f"\nwritten {RESULTS.relative_to(ROOT)}; {result['machine']}; load {load_before:.2f} -> "
          f"{result['load_average_1min']['after']:.2f}\n")
    print(blocks[0][2])  # the table and the batched/async ratios as docs/env-speed.md shows them
    return result


if __name__ == "__main__":
    main()

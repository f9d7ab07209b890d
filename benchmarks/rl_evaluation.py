"""AnchorPlan-v1: the trained policies against the crew, random plans and the per-scenario optimiser.

Run from the repository root after training the full preset (``python -m agents.train --config
configs/agents/full.yaml``, five seeds under ``runs/full``)::

    python benchmarks/rl_evaluation.py [--run runs/full] [--sites 500] [--jobs 2]
    python benchmarks/rl_evaluation.py --confirm 500   # the run and the crew on a second held-out set

Every policy plays the same held-out sites (:func:`agents.scenarios.held_out_sites`: drawn from the env's site
distribution with seeds that training never uses). The trained run counts each of its seeds as one run (IQM over
the seeds with a stratified bootstrap interval); the bundled policy (``plan-v1-sac``, one seed of that run) is
evaluated on its own, as the main job shows it. Writes the per-episode records and the statistics to
``benchmarks/results/rl_evaluation.json`` (:func:`agents.report.write_records`), the learning curves and the
speed/tilt distributions to ``docs/``, and the table in ``docs/agents-results.md`` and the README's headline
(``--docs-only``: only the text, from the committed JSON).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import DOCS, load_result, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402

from agents.curves import baseline_levels, learning_curves, plot_learning_curves  # noqa: E402
from agents.evaluate import PLAN_V1_CONFIG, evaluate_targets  # noqa: E402
from agents.io import write_json_atomic  # noqa: E402
from agents.report import episode_records, markdown_table, plot_distributions, write_records  # noqa: E402
from agents.runs import run_dirs  # noqa: E402
from agents.scenarios import CONFIRMATION_SITE_SEED, held_out_sites  # noqa: E402
from agents.statistics import evaluation_statistics, format_statistics  # noqa: E402
from moor_env.errors import ConfigError  # noqa: E402

RESULTS_STEM = "rl_evaluation"
RESULTS = ROOT / "benchmarks" / "results" / f"{RESULTS_STEM}.json"
DOC = DOCS / "agents-results.md"
README = ROOT / "README.md"
COMMAND = "python benchmarks/rl_evaluation.py"
BUNDLED = "plan-v1-sac"
BASELINES = ("crew", "random", "optimiser")
OPTIMISER = {"population": 8, "iterations": 3, "elite": 3}


def _run_meta(run: Path) -> list[dict]:
    """What each seed of the trained run was: seed, env steps, training wall time, source commit."""
    out = []
    for d in run_dirs(run):
        meta = json.loads((Path(d) / "meta.json").read_text())
        out.append({k: meta.get(k) for k in ("seed", "timesteps", "train_wall_s", "git_commit")})
    return out


# what the evaluation itself writes: a change there is its own output, not an edit of the evaluated code
OUTPUTS = ("benchmarks/results/", "docs/", "README.md")


def _source_commit() -> str | None:
    """The commit of the evaluated code, None outside a git checkout (``+dirty`` where files other than the
    evaluation's own outputs differ from it)."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True)
        status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                                capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    edited = [line[3:] for line in status.stdout.splitlines() if not line[3:].startswith(OUTPUTS)]
    return head.stdout.strip() + ("+dirty" if edited else "")


def evaluate(run: Path, sites: int, jobs: int, progress: bool = True) -> dict:
    """Evaluate the run, the bundled policy and the baselines on ``sites`` held-out sites; the records."""
    load_before = os.getloadavg()[0]
    scenarios = held_out_sites(sites)
    targets = [str(run), BUNDLED, *BASELINES]
    t0 = time.perf_counter()
    results = evaluate_targets(targets, scenarios, None, PLAN_V1_CONFIG, jobs, progress, OPTIMISER)
    stats = evaluation_statistics(results)
    summaries = [{k: r[k] for k in ("policy", "env_id", "summary", "wall_s")} for r in results]
    meta = {**run_record(load_before), "source_commit": _source_commit(), "command": COMMAND, "sites": sites,
            "jobs": jobs, "optimiser": OPTIMISER,
            "wall_s": time.perf_counter() - t0, "summaries": summaries,
            "trained_run": {"name": run.name, "seeds": _run_meta(run)}}
    write_records(results, RESULTS, stats, meta)
    plot_distributions(results, DOCS / "agents-distributions.png")
    return {"results": results, "statistics": stats}


def _results_from_records(data: dict) -> list[dict]:
    """The evaluated policies of a results JSON as evaluation results (policy, episodes), in the table's order."""
    order = [s["policy"] for s in data["meta"]["summaries"]]
    return [{"policy": name, "episodes": [e for e in data["episodes"] if e["policy"] == name]} for name in order]


def add_run(run: Path, jobs: int, progress: bool = True) -> dict:
    """Evaluate one more trained run on the same held-out sites and add it to the results JSON: its records, its
    row, and the statistics recomputed over every policy (its paired difference to the crew included)."""
    data = load_result(RESULTS_STEM)
    meta = data["meta"]
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    (added,) = evaluate_targets([str(run)], held_out_sites(meta["sites"]), None, PLAN_V1_CONFIG, jobs, progress)
    results = [r for r in _results_from_records(data) if r["policy"] != added["policy"]] + [added]
    summaries = [s for s in meta["summaries"] if s["policy"] != added["policy"]]
    summaries.append({k: added[k] for k in ("policy", "env_id", "summary", "wall_s")})
    runs = [a for a in meta.get("added_runs", []) if a["name"] != added["policy"]]
    runs.append({"name": run.name, "seeds": _run_meta(run), "source_commit": _source_commit(),
                 **run_record(load_before), "wall_s": time.perf_counter() - t0})
    meta = {**meta, "summaries": summaries, "added_runs": runs}
    stats = evaluation_statistics(results)
    kept = {"confirmation": data["confirmation"]} if "confirmation" in data else None
    write_records(results, RESULTS, stats, meta, kept)
    plot_distributions(results, DOCS / "agents-distributions.png")
    return {"results": results, "statistics": stats}


def confirm_run(run: Path, sites: int, jobs: int, progress: bool = True) -> dict:
    """The trained run and the crew on a second held-out set (:data:`CONFIRMATION_SITE_SEED`), stored in the
    results JSON under ``confirmation``: a check of the first set's result that no design choice has looked at."""
    data = load_result(RESULTS_STEM)
    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    results = evaluate_targets([str(run), "crew"], held_out_sites(sites, seed=CONFIRMATION_SITE_SEED), None,
                               PLAN_V1_CONFIG, jobs, progress)
    data["confirmation"] = {"run": run.name, "sites": sites, "site_seed": CONFIRMATION_SITE_SEED,
                            "source_commit": _source_commit(), **run_record(load_before),
                            "wall_s": time.perf_counter() - t0, "statistics": evaluation_statistics(results),
                            "episodes": episode_records(results)}
    write_json_atomic(RESULTS, data)
    return data["confirmation"]


def _versus_crew(stats: dict, run: str) -> tuple[dict | None, dict]:
    """A trained run's IQM over its seeds (None for a single policy) and its paired difference to the crew."""
    return stats["seeds"].get(run), next(c for c in stats["paired"] if c["a"] == run and c["b"] == "crew")


def _confirmation_text(data: dict) -> str:
    """`` On a second held-out set ...`` where the results hold a confirmation, else ``""``."""
    conf = data.get("confirmation")
    if not conf:
        return ""
    stats, run = conf["statistics"], conf["run"]
    seeds, diff = _versus_crew(stats, run)
    return (f"On a second held-out set of {conf['sites']} sites (`--confirm {conf['sites']}`, drawn the same way with "
            f"another seed, looked at by no design choice; code at {_short(conf.get('source_commit'))}): `{run}` "
            f"IQM {100 * seeds['iqm']:.1f} % [{100 * seeds['ci'][0]:.1f}, {100 * seeds['ci'][1]:.1f}] %, crew "
            f"{100 * stats['success']['crew']['rate']:.1f} %, `{run}` minus crew {100 * diff['difference']:+.1f} "
            f"points (paired 95 % interval [{100 * diff['ci'][0]:+.1f}, {100 * diff['ci'][1]:+.1f}]; only "
            f"`{run}` {diff['only_a']}, only crew {diff['only_b']} site-runs).")


def plot_curves(runs: dict[str, Path], jobs: int) -> Path:
    """Success against env steps of every seed of each run (label -> run), the crew and the optimiser as levels
    on the same evaluation episodes."""
    levels = baseline_levels(["crew", "optimiser"], next(iter(runs.values())), jobs)
    curves = {label: learning_curves(run) for label, run in runs.items()}
    return plot_learning_curves(curves, levels, DOCS / "agents-learning-curves.png")


def _pct(x: float) -> str:
    return f"{100.0 * x:.0f} %"


def headline(data: dict) -> str:
    """The README's RL line: the trained run's IQM, the crew, the paired difference, the optimiser."""
    meta, stats = data["meta"], data["statistics"]
    seeds, diff = _versus_crew(stats, meta["trained_run"]["name"])
    success = stats["success"]
    return (f"**RL** (AnchorPlan-v1, {meta['sites']} held-out sites, every policy on the same ones): SAC trained "
            f"with {seeds['runs']} seeds succeeds on {_pct(seeds['iqm'])} (IQM, 95 % interval "
            f"[{100 * seeds['ci'][0]:.0f}, {100 * seeds['ci'][1]:.0f}] %), the crew's rule of thumb on "
            f"{_pct(success['crew']['rate'])}, random plans on {_pct(success['random']['rate'])}, the per-site "
            f"optimiser on {_pct(success['optimiser']['rate'])}; trained minus crew {100 * diff['difference']:+.1f} "
            f"points (paired 95 % interval [{100 * diff['ci'][0]:+.1f}, {100 * diff['ci'][1]:+.1f}])"
            f"{_added_headline(data)}{_confirmation_headline(data)}. `{COMMAND}`, run {meta['date'][:10]}: "
            f"[docs/agents-results.md](docs/agents-results.md).")


def _added_headline(data: dict) -> str:
    """``; PPO (5 seeds) 80 % (IQM)`` for every added run."""
    parts = []
    for added in data["meta"].get("added_runs", []):
        seeds = data["statistics"]["seeds"].get(added["name"])
        if seeds is not None:
            parts.append(f"; `{added['name']}` ({seeds['runs']} seeds) {_pct(seeds['iqm'])} (IQM)")
    return "".join(parts)


def _confirmation_headline(data: dict) -> str:
    """``; on a second held-out set ... +x points [a, b]`` where the results hold a confirmation."""
    conf = data.get("confirmation")
    if not conf:
        return ""
    _, diff = _versus_crew(conf["statistics"], conf["run"])
    return (f"; on a second held-out set of {conf['sites']} sites trained minus crew {100 * diff['difference']:+.1f} "
            f"points [{100 * diff['ci'][0]:+.1f}, {100 * diff['ci'][1]:+.1f}]")


def results_block(data: dict) -> str:
    """The table and the statistics for ``docs/agents-results.md``."""
    meta = data["meta"]
    seeds = ", ".join(f"seed {s['seed']} {s['timesteps']} steps" for s in meta["trained_run"]["seeds"])
    load = meta["load_average_1min"]
    opt = meta["optimiser"]
    lines = [f"`{COMMAND}`, run {meta['date'][:19].replace('T', ' ')} UTC on {meta['machine']} (1-min load average "
             f"{load['before']:.1f} -> {load['after']:.1f}), code at {_short(meta.get('source_commit'))}, "
             f"{meta['sites']} held-out sites, {meta['jobs']} "
             f"workers, {meta['wall_s'] / 60:.0f} min. `{meta['trained_run']['name']}`: {seeds}; "
             f"`{BUNDLED}`: its bundled seed; optimiser: {opt['population']} candidates x {opt['iterations']} "
             f"cross-entropy iterations per site.{_added_line(meta)}", "",
             markdown_table(meta["summaries"]).rstrip("\n"), "",
             "```text", format_statistics(data["statistics"]).rstrip("\n"), "```"]
    if data.get("confirmation"):
        lines += ["", _confirmation_text(data)]
    return "\n".join(lines)


def _short(commit: str | None) -> str:
    """``21410d2`` of a full commit hash, with `` with edits`` where the tree differed from it."""
    if not commit:
        return "an unknown commit"
    return commit[:7] + (" with edits" if commit.endswith("+dirty") else "")


def _added_line(meta: dict) -> str:
    """The runs evaluated later on the same sites, with their seeds and source commit."""
    out = ""
    for added in meta.get("added_runs", []):
        seeds = ", ".join(f"seed {s['seed']} {s['timesteps']} steps" for s in added["seeds"])
        out += (f" `{added['name']}` ({seeds}) added on {added['date'][:19].replace('T', ' ')} UTC, code at "
                f"{_short(added['source_commit'])}.")
    return out


def docs_blocks(data: dict | None) -> list[tuple[Path, str, str]]:
    """The blocks this benchmark writes, rendered from its results JSON."""
    if data is None:
        return []
    return [(DOC, RESULTS_STEM, results_block(data)), (README, f"headline-{RESULTS_STEM}", headline(data))]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/rl_evaluation.json``."""
    return docs_blocks(load_result(RESULTS_STEM))


def main(argv: list[str] | None = None) -> int:
    """Evaluate, write the JSON, the figures and the docs text."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", default="runs/full", help="the trained run (a folder of seed-* runs)")
    parser.add_argument("--sites", type=int, default=500, help="held-out sites")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--add", help="evaluate one more trained run on the same sites and add it to the results")
    parser.add_argument("--curves", nargs="*", default=None, metavar="LABEL=RUN",
                        help="learning curves to plot (default: SAC=the --run; none with --add)")
    parser.add_argument("--confirm", type=int, metavar="SITES",
                        help="evaluate the --run and the crew on a second held-out set of SITES sites")
    parser.add_argument("--no-progress", action="store_true")
    parser.add_argument("--docs-only", action="store_true",
                        help=f"rewrite the docs text from {RESULTS.relative_to(ROOT)}, run nothing")
    args = parser.parse_args(argv)
    if not args.docs_only:
        run = Path(args.add or args.run)
        plots_curves = args.curves is not None or not (args.add or args.confirm)  # their levels cost minutes
        curves = (dict(c.split("=", 1) for c in args.curves) if args.curves else {"SAC": args.run}) if plots_curves \
            else {}
        try:
            for path in (run, *curves.values()):
                run_dirs(path)
        except ConfigError as exc:
            print(f"error: {exc} (train it: python -m agents.train --config configs/agents/full.yaml)",
                  file=sys.stderr)
            return 2
        if args.confirm:
            confirm_run(run, args.confirm, args.jobs, not args.no_progress)
        elif args.add:
            add_run(run, args.jobs, not args.no_progress)
        else:
            evaluate(run, args.sites, args.jobs, not args.no_progress)
        if plots_curves:
            plot_curves({label: Path(path) for label, path in curves.items()}, args.jobs)
    write_blocks(docs_from_results())
    return 0


if __name__ == "__main__":
    sys.exit(main())

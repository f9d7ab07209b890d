"""Benchmark: the static solver at the resolution the envs solve their equilibria on.

``benchmarks/statics.py`` draws its scenes at the three presets' own segment lengths. The envs run the ``fast``
preset fitted per episode: where the mooring line tightens during the fall, or in waves, its ``tight_line`` entry
(``configs/fidelity.yaml``: 1 m vertical chain, 50 m fibre, 100 m wire, the loop chain at 0.5 m in calm water and
1 m in waves) replaces the preset's lengths, and the equilibrium is solved on those lines. This benchmark draws
scenes from the same ranges as ``benchmarks/statics.py`` (its ``draw_scene``, another seed), gives each the
``tight_line`` resolution of a calm sea or of waves in turn, and records the outcome of ``solve_statics`` and its
CPU time from the validated scene (compile included; kernels compiled beforehand), by the envs' method
(``statics.method``: Newton's method, no relaxation fallback). Scenes the solver leaves unsolved are listed with
their overrides.

    python benchmarks/statics_env_resolution.py [--scenes 1000] [--seed 7]

Writes ``benchmarks/results/statics_env_resolution.json`` and its table in ``docs/statics.md`` (``--docs-only``:
the table from the JSON).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _docs import load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402
from statics import draw_scene  # noqa: E402

from moor_env import load_scene  # noqa: E402
from moor_env.envs.config import StaticsConfig  # noqa: E402
from moor_env.errors import ConfigError, NoEquilibrium, SimulationDiverged, StaticsNotConverged  # noqa: E402
from moor_env.fidelity import tight_line_keys, tight_line_rule  # noqa: E402
from moor_env.simulation import solve_statics  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
STEM = "statics_env_resolution"
RESULT = ROOT / "benchmarks" / "results" / f"{STEM}.json"
DOC = ROOT / "docs" / "statics.md"
COMMAND = "python benchmarks/statics_env_resolution.py"
PRESET = "fast"
SEAS = {"calm": 0.0, "waves": 2.0}  # significant wave height [m] that selects the tight_line keys
OUTCOMES = ("converged", "no equilibrium", "refused by config", "unsolved")
METHOD = StaticsConfig().method  # the envs' solve_statics method


def env_overrides(overrides: dict, hs_m: float) -> dict:
    """A drawn scene at the envs' resolution: the ``fast`` preset with its ``tight_line`` keys for a sea of
    significant wave height ``hs_m`` [m], not fitted again to the geometry."""
    keys = tight_line_keys(tight_line_rule(PRESET), hs_m)
    return {**overrides, "fidelity": PRESET, "discretization.fit_to_geometry": False,
            **{f"discretization.{k}": v for k, v in keys.items()}}


def solve(overrides: dict) -> dict:
    """Outcome and CPU time [s] of one scene, from its validated config to the result."""
    try:
        scene = load_scene("gjoa-500", overrides)
    except ConfigError:
        return {"outcome": "refused by config", "solve_s": 0.0}
    t0 = time.process_time()
    record = {"outcome": "converged"}
    try:
        record["iterations"] = solve_statics(scene, progress=False, method=METHOD).iterations
    except NoEquilibrium:
        record = {"outcome": "no equilibrium"}
    except ConfigError:
        record = {"outcome": "refused by config"}
    except (StaticsNotConverged, SimulationDiverged) as exc:
        record = {"outcome": "unsolved", "error": str(exc)}
    return {**record, "solve_s": time.process_time() - t0}


def run(count: int, seed: int) -> dict:
    """Draw and solve ``count`` scenes, the seas in turn."""
    load_before = os.getloadavg()[0]
    for sea in SEAS.values():  # compiles the kernels (or loads them) before any timing
        solve(env_overrides({"current_scale": 1.0}, sea))
    rng = np.random.default_rng(seed)
    records = []
    for i in tqdm(range(count), desc="statics at the envs' resolution", unit="scene"):
        sea = list(SEAS)[i % len(SEAS)]
        overrides = env_overrides(draw_scene(rng), SEAS[sea])
        records.append({"sea": sea, "scene": overrides, **solve(overrides)})
    result = {**run_record(load_before), "seed": seed, "method": METHOD, "records": records}
    RESULT.write_text(json.dumps(result, indent=1) + "\n")
    return result


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The table of ``docs/statics.md``'s ``statics_env_resolution`` block, with the unsolved scenes listed."""
    rows = []
    for sea in [*SEAS, "all"]:
        recs = [r for r in result["records"] if sea in ("all", r["sea"])]
        solved = [r["solve_s"] for r in recs if r["outcome"] != "refused by config"]
        ms = 1e3 * np.array(solved)
        rows.append([sea, len(recs), *(sum(r["outcome"] == o for r in recs) for o in OUTCOMES),
                     f"{np.median(ms):.1f}", f"{np.percentile(ms, 99):.0f}", f"{ms.max():.0f}"])
    text = table(["sea (tight_line keys)", "scenes", *OUTCOMES, "median ms", "p99 ms", "max ms"], rows)
    unsolved = [r for r in result["records"] if r["outcome"] == "unsolved"]
    if unsolved:
        keys = ("water_depth_m", "vessel_spacing_m", "mooring_line_length_m", "vertical_chain_length_m",
                "drop_height_m", "current_scale", "current_direction_deg", "anchor_mass_scale")
        lines = [f"- {r['sea']}: " + ", ".join(f"{k} {r['scene'][k]:.4g}" for k in keys) for r in unsolved]
        text += ("\n\nUnsolved (overrides of gjoa-500 at the resolution above, rounded; exact in the JSON):\n\n"
                 + "\n".join(lines))
    method = result.get("method", "auto")
    text += "\n\n" + run_line(result, COMMAND)[:-1] + (f", seed {result['seed']}, `solve_statics(method=\"{method}\")` "
                                                       "as the envs run it. CPU time from the validated scene "
                                                       "(compile included), kernels compiled beforehand.")
    return [(DOC, STEM, text)]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """The docs block from the committed JSON."""
    result = load_result(STEM)
    return docs_blocks(result) if result is not None else []


def main(argv: list[str] | None = None) -> int:
    """Run, write the JSON and the docs table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--docs-only", action="store_true", help="rewrite the docs table from the JSON, run nothing")
    args = parser.parse_args(argv)
    if not args.docs_only:
        run(args.scenes, args.seed)
    write_blocks(docs_from_results())
    return 0


if __name__ == "__main__":
    sys.exit(main())

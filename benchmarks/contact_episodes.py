"""Benchmark: how deep the chain goes into the anchor over random env episodes, with the line-anchor contact.

Run from the repository root: ``python benchmarks/contact_episodes.py [--episodes N]`` (default 1000;
``--docs-only``: the table from the committed JSON). Each episode is ``AnchorRelease-v0`` with its default config
and seeded random controls (``pre_release_step.run_episode``: random spacing and winch rates, release after
25-55 s). Recorded per episode: whether the contact was on, the deepest a chain node went inside the anchor's
surface during the fall (``Simulator.contact_report``), the deepest point of any segment, its interior included,
at the equilibrium, after each pre-release step and at touchdown (``Simulator.deepest_segment_inside_m``), how far
the vertical chain ended past the back end, and the touchdown speed. Writes
``benchmarks/results/contact_episodes.json`` and its table in ``docs/fall-accuracy.md``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import DOCS, RESULTS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402
from pre_release_step import run_episode  # noqa: E402

import moor_env  # noqa: E402, F401 - registers the envs
from moor_env.physics import layout as L  # noqa: E402

COMMAND = "python benchmarks/contact_episodes.py"
DOC = DOCS / "fall-accuracy.md"
LIMIT_M = 0.05


class SegmentDepth(gym.Wrapper):
    """Keeps the deepest point of any segment inside the anchor over the reset's equilibrium and the state after
    every step (``segment_depth_m``)."""

    def reset(self, **kwargs):
        """Reset and measure the equilibrium."""
        out = self.env.reset(**kwargs)
        self.segment_depth_m = self.unwrapped.core.sim.deepest_segment_inside_m()
        return out

    def step(self, action):
        """Step and keep the deeper of the last and the present state."""
        out = self.env.step(action)
        self.segment_depth_m = max(self.segment_depth_m, self.unwrapped.core.sim.deepest_segment_inside_m())
        return out


def episode(env: SegmentDepth, seed: int) -> dict:
    """One random episode and what the contact did in its fall."""
    row = run_episode(env, seed)
    sim = env.unwrapped.core.sim
    report = sim.contact_report()
    return {"seed": seed, "status": row["status"], "speed_m_s": row["speed_m_s"],
            "contact": bool(sim.model.contact_f[L.CF_ON]), "peak_depth_m": report["peak_depth_m"],
            "segment_depth_m": env.segment_depth_m, "peak_force_n": report["peak_force_n"],
            "chain_past_back_end_m": row["chain_past_back_end_m"]}


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The table of one run."""
    s = out["summary"]
    text = "\n".join([run_line(out, COMMAND + f" --episodes {s['episodes']}"), "", table(
        ["episodes", "touched down", "contact on", "deepest node inside the anchor in the fall, max / p99 [mm]",
         f"episodes deeper than {1e3 * LIMIT_M:.0f} mm",
         "deepest segment point inside, at rest, pre-release and at touchdown, max / p99 [mm]",
         f"episodes with a segment deeper than {1e3 * LIMIT_M:.0f} mm", "chain past the back end, max [m]"],
        [[s["episodes"], s["touchdowns"], s["contact_on"],
          f"{1e3 * s['depth_max_m']:.1f} / {1e3 * s['depth_p99_m']:.1f}", s["deeper_than_limit"],
          f"{1e3 * s['segment_depth_max_m']:.1f} / {1e3 * s['segment_depth_p99_m']:.1f}",
          s["segment_deeper_than_limit"], f"{s['chain_past_max_m']:+.3f}"]])])
    return [(DOC, "contact_episodes", text)]


def summarize(rows: list[dict]) -> dict:
    """Counts and extremes over the episodes."""
    depth = np.array([r["peak_depth_m"] for r in rows])
    segment = np.array([r["segment_depth_m"] for r in rows])
    past = [r["chain_past_back_end_m"] for r in rows if r["chain_past_back_end_m"] is not None]
    return {"episodes": len(rows), "touchdowns": sum(r["speed_m_s"] is not None for r in rows),
            "contact_on": sum(r["contact"] for r in rows), "depth_max_m": float(depth.max()),
            "depth_p99_m": float(np.quantile(depth, 0.99)), "deeper_than_limit": int(np.sum(depth > LIMIT_M)),
            "segment_depth_max_m": float(segment.max()), "segment_depth_p99_m": float(np.quantile(segment, 0.99)),
            "segment_deeper_than_limit": int(np.sum(segment > LIMIT_M)),
            "chain_past_max_m": float(max(past)) if past else float("nan")}


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/contact_episodes.json``."""
    return docs_blocks(load_result("contact_episodes"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--docs-only", action="store_true")
    args = parser.parse_args()
    if args.docs_only:
        write_blocks(docs_from_results())
        return
    load = os.getloadavg()[0]
    env = SegmentDepth(gym.make("moor_env/AnchorRelease-v0"))
    rows = [episode(env, seed) for seed in tqdm(range(args.episodes), unit="episode")]
    out = {**run_record(load), "summary": summarize(rows), "episodes": rows}
    write_results(RESULTS / "contact_episodes.json", out)
    write_blocks(docs_blocks(out))


if __name__ == "__main__":
    main()

"""AnchorPlan-v1: what one installation costs, and what setting the plan's geometry directly changes.

Run from the repository root: ``python benchmarks/bench_plan_v1.py [--sites 60] [--positioned 30]``. Writes
``benchmarks/results/bench_plan_v1.json`` and its tables in ``docs/agents.md`` (``--docs-only``: only the tables,
from the committed JSON).

**Cost**: CPU time of one episode (reset and step: the fresh equilibrium of the chosen geometry with its compile,
the waves' warm-up, the wait for the release phase, the fall) on the first held-out sites
(:func:`agents.scenarios.held_out_sites`), for the crew's plans and for uniform random plans (which include
geometries without an equilibrium, refused at once, and a few whose static solve stops short: "refused" counts
both).

**Set directly against positioned**: the env puts the vessels and the winch at the plan's spacing and line length
when it solves the equilibrium. Here the same crew plans are also reached the way a crew would: from an arrival
geometry (spacing 0.25 h, line 1.06 h, the rest as planned) the second vessel closes in under its DP limits and
the winch hauls or pays out at its rate (the ``control`` section, one command a second), the loop settles for
60 s (``--settle-s``), and the release waits for the same heave phase. The differences in touchdown speed, tilt
and landing point, and how often the speed and tilt criteria agree, are the error of setting the geometry
directly. The vertical chain and the drop height are set in both (the model has no chain payout through the
release unit nor a wire winch before the release). A third run sets the plan directly and releases it as long
after the warm-up as the positioned one: the part of the differences that another part of the same wave train
makes on its own.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import gymnasium as gym  # noqa: E402
from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record, write_results  # noqa: E402

from agents.baselines import PLAN_V1_ENV, make_baseline, spacing_speed_m_s  # noqa: E402
from agents.scenarios import held_out_sites  # noqa: E402
from moor_env.envs.anchor_plan import next_upcrossing_s  # noqa: E402
from moor_env.envs.core import run_advance  # noqa: E402
from moor_env.envs.levers import episode_scenario, lever_targets  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "bench_plan_v1.json"
DOC = DOCS / "agents.md"
COMMAND = "python benchmarks/bench_plan_v1.py"
REFUSED = ("no equilibrium", "statics not converged")  # info["failure"] of a plan refused before its fall
ARRIVAL = {"vessel_spacing_over_depth": 0.25, "mooring_line_length_over_depth": 1.06}
SETTLE_S = 60.0
MOVE_LIMIT_S = 900.0
ON_TARGET_M = 0.5


def _touchdown(core) -> dict | None:
    if core.touchdown is None:
        return None
    tip = core.sim.work.touchdown[L.TD_TIP:L.TD_TIP + 2]
    return {"speed_m_s": core.touchdown["speed_m_s"], "tilt_deg": core.touchdown["tilt_deg"],
            "tip_xy_m": [float(tip[0]), float(tip[1])]}


def cost_rows(env, policy, sites: list[dict], label: str) -> list[dict]:
    """CPU time of reset + step of every site under ``policy``."""
    rows = []
    for sc in tqdm(sites, desc=f"cost {label}", leave=False):
        t0 = time.process_time()
        obs, info = env.reset(seed=sc["seed"], options=sc["options"])
        _, _, _, _, info = env.step(policy.act(obs, info))
        rows.append({"cpu_s": time.process_time() - t0, "failure": info["failure"], "success": info["success"]})
    return rows


def positioned(env, sc: dict, targets: dict, settle_s: float = SETTLE_S, arrival: dict | None = None) -> dict:
    """The crew's plan reached from the ``arrival`` geometry (default :data:`ARRIVAL`; ``{}``: the plan's own, so
    nothing moves and the release only comes later) under the DP and winch limits (module docstring)."""
    u = env.unwrapped
    core, c = u.core, u.cfg.control
    u.reset(seed=sc["seed"], options=sc["options"])
    depth = u.site["water_depth_m"]
    core.max_steps = 2**62  # no truncation while positioning
    adv = core.start(episode_scenario(u.site, {**targets, **(ARRIVAL if arrival is None else arrival)}))
    error = run_advance(core, adv)[1] if adv is not None else None
    core.finish_start(error)
    goal_spacing = targets["vessel_spacing_over_depth"] * depth
    goal_line = targets["mooring_line_length_over_depth"] * depth
    t0 = core.sim.state.t
    while core.sim.state.t - t0 < MOVE_LIMIT_S:
        e_s, e_l = goal_spacing - core.spacing_m(), goal_line - core.line_length_total_m()
        if abs(e_s) < ON_TARGET_M and abs(e_l) < ON_TARGET_M and abs(core.spacing_rate) < 0.01:
            break
        v = spacing_speed_m_s(e_s, c.spacing_rate_max_m_s, c.spacing_accel_max_m_s2)
        rate = float(np.clip(e_l / c.interval_s, -c.haul_rate_max_m_s, c.payout_rate_max_m_s))
        a = [v / c.spacing_rate_max_m_s, rate / (c.payout_rate_max_m_s if rate > 0 else c.haul_rate_max_m_s), -1.0]
        if core.finish_step(*run_advance(core, core.begin_step(a)))[2]:
            return {"status": core.status}
    move_s = core.sim.state.t - t0
    core.finish_step(*run_advance(core, core.begin_hold(core.sim.state.t + settle_s)))
    t_ref, delay = core.sim.state.t, 0.0
    if core.hs > 0.0:
        t_ref = next_upcrossing_s(core, core.sim.state.t, 3.0 * core.tp)
        delay = targets["release_phase"] * core.tp
    if t_ref + delay > core.sim.state.t + 0.5 * core.sim.dt:
        core.finish_step(*run_advance(core, core.begin_hold(t_ref + delay)))
    core.finish_step(*run_advance(core, core.begin_step([0.0, 0.0, 1.0])))
    return {"status": core.status, "move_s": move_s, "touchdown": _touchdown(core),
            "spacing_error_m": goal_spacing - core.spacing_m(), "line_error_m": goal_line - core.line_length_total_m()}


def positioning_rows(env, crew, sites: list[dict], settle_s: float = SETTLE_S) -> list[dict]:
    """Each site's crew plan set directly (the env) and positioned (:func:`positioned`)."""
    u = env.unwrapped
    rows = []
    for sc in tqdm(sites, desc="set vs positioned", leave=False):
        obs, info = env.reset(seed=sc["seed"], options=sc["options"])
        action = crew.act(obs, info)
        _, _, _, _, info = env.step(action)
        direct = {"status": info["sim_status"], "touchdown": _touchdown(u.core), "success": info["success"],
                  "required_speed_m_s": info["site"]["required_speed_m_s"]}
        targets = lever_targets(action, u.site["water_depth_m"], u.cfg.levers, u.core.factory.anchor_length_m,
                                u.core.factory.fairlead_depth_m)
        moved = positioned(env, sc, targets, settle_s)
        # the same geometry set directly, released as long after the warm-up as the positioned one: what another
        # part of the same wave train alone changes
        later = positioned(env, sc, targets, settle_s + moved.get("move_s", 0.0), arrival={})
        rows.append({"id": sc["id"], "direct": direct, "positioned": moved, "later": later})
    return rows


def summarize(cost: dict[str, list[dict]], pos: list[dict]) -> dict:
    """Medians and counts of the cost and positioning rows."""
    out = {"cost": {}, "positioning": {}}
    for label, rows in cost.items():
        cpu = np.array([r["cpu_s"] for r in rows])
        out["cost"][label] = {"episodes": len(rows), "cpu_s_median": float(np.median(cpu)),
                              "cpu_s_mean": float(cpu.mean()), "cpu_s_p95": float(np.quantile(cpu, 0.95)),
                              # refused before the fall (REFUSED); the key keeps its name for the committed runs
                              "no_equilibrium": sum(str(r["failure"]).startswith(REFUSED) for r in rows),
                              "success": sum(r["success"] for r in rows)}
    out["positioning"] = {case: _differences(pos, case) for case in ("positioned", "later")}
    return out


def _differences(pos: list[dict], case: str) -> dict:
    """``case`` against the plan set directly, over the sites where both touched down."""
    both = [r for r in pos if r["direct"]["touchdown"] and r[case].get("touchdown")]
    d = {k: np.array([abs(r[case]["touchdown"][k] - r["direct"]["touchdown"][k]) for r in both])
         for k in ("speed_m_s", "tilt_deg")}
    land = np.array([np.hypot(*np.subtract(r[case]["touchdown"]["tip_xy_m"], r["direct"]["touchdown"]["tip_xy_m"]))
                     for r in both])
    speed_signed = [r[case]["touchdown"]["speed_m_s"] - r["direct"]["touchdown"]["speed_m_s"] for r in both]

    def meets(r, which):  # the speed and tilt criteria of success
        td = r[which]["touchdown"]
        return td["speed_m_s"] >= r["direct"]["required_speed_m_s"] and td["tilt_deg"] < 2.0

    return {"sites": len(pos), "both_touched_down": len(both),
            "move_s_median": float(np.median([r["positioned"]["move_s"] for r in both])),
            "dspeed_m_s": {"median": float(np.median(d["speed_m_s"])), "max": float(d["speed_m_s"].max()),
                           "mean_signed": float(np.mean(speed_signed))},
            "dtilt_deg": {"median": float(np.median(d["tilt_deg"])), "max": float(d["tilt_deg"].max())},
            "landing_point_m": {"median": float(np.median(land)), "max": float(land.max())},
            "speed_tilt_met_direct": sum(meets(r, "direct") for r in both),
            "speed_tilt_met_case": sum(meets(r, case) for r in both),
            "speed_tilt_agree": sum(meets(r, "direct") == meets(r, case) for r in both)}


def docs_blocks(result: dict) -> list[tuple[Path, str, str]]:
    """The two tables of one run (docs/agents.md)."""
    s = result["summary"]
    cost = table(["plans", "episodes", "CPU s median", "CPU s mean", "CPU s p95", "refused"],
                 [[label, c["episodes"], f"{c['cpu_s_median']:.3f}", f"{c['cpu_s_mean']:.3f}",
                   f"{c['cpu_s_p95']:.3f}", c["no_equilibrium"]] for label, c in s["cost"].items()])
    labels = {"positioned": "positioned from spacing 0.25 h, line 1.06 h",
              "later": "set directly, released as late as positioned"}
    pos = table(["against the plan set directly", "sites (both touched down)", "settle [s]",
                 "move to the plan [s] median", "speed diff median / max [m/s]", "mean speed diff [m/s]",
                 "tilt diff median / max [deg]", "landing point diff median / max [m]",
                 "speed and tilt criteria met: set / this / agree"],
                [[labels[case], f"{p['sites']} ({p['both_touched_down']})", f"{result['settle_s']:.0f}",
                  f"{p['move_s_median']:.0f}", f"{p['dspeed_m_s']['median']:.2f} / {p['dspeed_m_s']['max']:.2f}",
                  f"{p['dspeed_m_s']['mean_signed']:+.2f}",
                  f"{p['dtilt_deg']['median']:.2f} / {p['dtilt_deg']['max']:.2f}",
                  f"{p['landing_point_m']['median']:.2f} / {p['landing_point_m']['max']:.2f}",
                  f"{p['speed_tilt_met_direct']} / {p['speed_tilt_met_case']} / {p['speed_tilt_agree']}"]
                 for case, p in s["positioning"].items()])
    line = run_line(result, COMMAND)
    return [(DOC, "bench_plan_v1:cost", f"{cost}\n\n{line}"), (DOC, "bench_plan_v1:positioning", f"{pos}\n\n{line}")]


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/bench_plan_v1.json``."""
    return docs_blocks(load_result("bench_plan_v1"))


def main(argv: list[str] | None = None) -> dict:
    """Measure, write the JSON and the docs tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sites", type=int, default=60, help="held-out sites of the cost measurement")
    parser.add_argument("--positioned", type=int, default=30, help="held-out sites set directly and positioned")
    parser.add_argument("--settle-s", type=float, default=SETTLE_S, help="hold after positioning, before the phase")
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/bench_plan_v1.json, run nothing")
    args = parser.parse_args(argv)
    if args.docs_only:
        write_blocks(docs_from_results())
        return load_result("bench_plan_v1")
    load_before = os.getloadavg()[0]
    env = gym.make(PLAN_V1_ENV)
    cfg = env.unwrapped.cfg
    sites = held_out_sites(max(args.sites, args.positioned))
    env.reset(seed=0)
    env.step(np.zeros(5, np.float32))  # compile (numba cache) before anything is timed
    crew = make_baseline("crew", PLAN_V1_ENV, cfg)
    cost = {"crew": cost_rows(env, crew, sites[:args.sites], "crew"),
            "random": cost_rows(env, make_baseline("random", PLAN_V1_ENV, cfg), sites[:args.sites], "random")}
    pos = positioning_rows(env, crew, sites[:args.positioned], args.settle_s)
    result = {**run_record(load_before), "config": "anchor-plan", "settle_s": args.settle_s,
              "summary": summarize(cost, pos), "positioning_rows": pos}
    write_results(RESULTS, result)
    write_blocks(docs_blocks(result))
    for _, _, text in docs_blocks(result):
        print(text, "\n")
    return result


if __name__ == "__main__":
    main()

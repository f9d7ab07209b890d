"""Benchmark: cost per step of the implicit Euler line integrator (``moor_env/physics/implicit.py``).

Run from the repository root: ``python benchmarks/bench_implicit_step.py [--repeats 5] [--rounds 3]
[--no-breakdown] [--baseline-root DIR]``. Writes ``benchmarks/results/bench_implicit_step.json`` and its tables in
``docs/implicit-step.md`` (``--docs-only``: only the tables, from the committed JSON).

``--baseline-root DIR`` times another copy of the package as well (a directory holding ``moor_env`` and
``configs``, e.g. ``mkdir baseline && git archive HEAD moor_env configs | tar -x -C baseline``), in a subprocess
per round, alternating with this tree's rounds so that both see the same machine load; the JSON then holds both,
their ratio and the relative change of the outputs. ``--root DIR`` runs this script on another tree (what the
baseline subprocess does).

Four cases of gjoa-500 with implicit lines on meshes set explicitly (the ``fast`` preset's coarse keys, or its
``tight_line`` keys), each from its static equilibrium:

- ``hanging_waves``: a pre-release phase: waves (Hs 2 m, Tp 9 s, ramped in), 79 s of hanging
  at a 0.1 s implicit step (AnchorRelease-v0's ``control.pre_release_dt_s`` is 0.2 s);
- ``fall_fast``: release and fall to touchdown at the model's own step on the coarse ``fast`` mesh;
- ``fall_fine``: the same on the fine ``tight_line`` mesh (1 m / 0.5 m chain, 50 m fibre, 100 m wire);
- ``fall_fast_after_waves``: the fall on the coarse mesh after the ``hanging_waves`` phase (which is not timed
  here): a fall that tilts, so that its outputs check more of the kernel.

Each case restarts from a copy of its equilibrium state and times ``Simulator.advance_to`` alone (plain wall time on
a shared machine: the load average is recorded; the minimum and median of ``--rounds`` x ``--repeats`` runs are
reported). The outputs (touchdown speed and tilt, and a hash of the final state) are recorded so that a change of
the kernel can be checked to leave the results unchanged (bit for bit where the hash matches).

The breakdown times each piece of one implicit step in a jitted loop at a fixed state taken from the case
(loads ``compute_loads``; a rebuild of the elimination order, which a step pays only after a topology change or
at the first step of an ``advance`` call; the assembly of a step's first solve, and of a later one, which starts
from what the first kept and adds the segments' springs; elimination with back substitution; active-set update)
and counts the active-set solves per step over the case.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

ROOT = Path(__file__).resolve().parent.parent
TREE = Path(sys.argv[sys.argv.index("--root") + 1]).resolve() if "--root" in sys.argv else ROOT
sys.path.insert(0, str(TREE))

from _docs import DOCS, load_result, run_line, table, write_blocks  # noqa: E402
from _machine import run_record  # noqa: E402

from moor_env import load_scene, solve_statics  # noqa: E402
from moor_env.physics import layout as L  # noqa: E402
from moor_env.physics._jit import jit  # noqa: E402
from moor_env.physics.anchor import tilt_deg  # noqa: E402

try:  # the breakdown needs the record kernels; a baseline tree from before them is timed on whole runs only
    from moor_env.physics import implicit as imp  # noqa: E402
    from moor_env.physics.implicit_active_set import update_active_set  # noqa: E402
    from moor_env.physics.implicit_assembly import assemble  # noqa: E402
    from moor_env.physics.integrate import compute_loads, speed_step_factor  # noqa: E402
except ImportError:
    compute_loads = None

RESULTS = ROOT / "benchmarks" / "results" / "bench_implicit_step.json"
SCENE = "gjoa-500"
# the meshes are set explicitly (not left to the fast preset's fit to the scene), so that they stay put
COARSE = {"fidelity": "fast", "integrator": "implicit_euler", "discretization.vertical_chain_segment_m": 2.0,
          "discretization.loop_chain_segment_m": 2.0, "discretization.fibre_segment_m": 20.0,
          "discretization.wire_segment_m": 30.0}
FINE = dict(COARSE, **{"discretization.vertical_chain_segment_m": 1.0, "discretization.loop_chain_segment_m": 0.5,
                       "discretization.fibre_segment_m": 50.0, "discretization.wire_segment_m": 100.0})
WAVES = dict(COARSE, sea_state_hs_m=2.0, sea_state_tp_s=9.0)
HANG_DT_S = 0.1  # the env's pre-release step
HANG_S = 79.0  # 20 s wave warm-up + 59 s of control
PIECE_LOOPS = 3000


class Case:
    """A simulator at equilibrium and how to run the timed part from a copy of that state."""

    def __init__(self, name: str, overrides: dict, fall: bool, hang_first: bool = False) -> None:
        self.name = name
        self.sim = solve_statics(load_scene(SCENE, overrides)).simulator
        self.fall = fall
        self.hang_first = hang_first
        self.start = self.sim.state.copy()
        self.t_end_s = HANG_S

    def reset(self) -> None:
        """Back to the equilibrium, vessel tracks sampled for the run."""
        sim = self.sim
        sim.state = self.start.copy()
        sim.dt = sim.model.dt_s if self.fall else HANG_DT_S
        sim.set_vessel_motion(0.0, HANG_S + 20.0, np.zeros(sim.vessel_mean_m.shape[0]))
        if self.hang_first:
            sim.dt = HANG_DT_S
            sim.advance_to(HANG_S)
            sim.dt = sim.model.dt_s
        if self.fall:
            sim.release()

    def run(self) -> tuple[float, int]:
        """Wall time [s] and steps of the timed part."""
        sim = self.sim
        self.reset()
        t0 = time.perf_counter()
        if self.fall:
            _, n = sim.advance_to(sim.state.t + sim.model.scene.simulation.max_fall_time_s, detect_touchdown=True)
        else:
            _, n = sim.advance_to(HANG_S)
        wall = time.perf_counter() - t0
        self.t_end_s = sim.state.t
        return wall, n

    def outputs(self) -> dict:
        """Touchdown speed and tilt (fall) or tip state (hanging), and a hash of the final state."""
        sim = self.sim
        st = sim.state
        digest = hashlib.sha256()
        for arr in (st.node_pos, st.node_vel, st.body_state):
            digest.update(np.ascontiguousarray(arr).tobytes())
        out = {"t_s": st.t, "state_sha256": digest.hexdigest()[:16]}
        if self.fall:
            td = sim.work.touchdown
            out["touchdown_speed_m_s"] = float(np.linalg.norm(td[L.TD_VEL:L.TD_VEL + 3]))
            out["touchdown_tilt_deg"] = float(tilt_deg(td[L.TD_AXIS + 2]))
        else:
            tip, vel = sim.tip_state()
            out["tip_z_m"] = float(tip[2])
            out["tip_vz_m_s"] = float(vel[2])
        return out


@jit
def _loop_loads(k, model, state):
    for _ in range(k):
        compute_loads(model, state)


@jit
def _body_node(model, state):
    if model.body_f[L.BF_ACTIVE] != 0.0:
        for n in range(state.node_i.shape[0]):
            if state.node_i[n, L.NI_KIND] == L.NODE_BODY:
                return n
    return -1


@jit
def _loop_order(k, model, state):
    tree = state.pos0.view(np.int64)
    orow = state.vel0.view(np.int64)
    body_node = _body_node(model, state)
    nq = 0
    for _ in range(k):
        nq = imp.prepare(False, body_node, state, tree, orow)
    return nq


@jit
def _solve_once(first, stage, h, nq, body_node, model, state, tree, orow):
    """One solve of the step's current active set, up to ``stage`` (0 assembly, 1 + elimination and back
    substitution, 2 + active-set update); returns the set's changes (stage 2)."""
    assemble(h, first, body_node, model, state, orow)
    if stage >= 1:
        imp.eliminate(nq, state, tree, orow)
        if body_node >= 0:
            imp.couple_body(h, body_node, model, state)
        imp.back_substitute(nq, state, tree, orow)
    if stage >= 2:
        return update_active_set(h, model, state, orow)
    return 0


@jit
def _loop_solve(k, stage, h, model, state):
    """``k`` later solves at a fixed state, each from the blocks one first solve kept, up to ``stage`` (see
    :func:`_solve_once`)."""
    tree = state.pos0.view(np.int64)
    orow = state.vel0.view(np.int64)
    body_node = _body_node(model, state)
    nq = imp.prepare(False, body_node, state, tree, orow)
    compute_loads(model, state)
    _solve_once(True, 0, h, nq, body_node, model, state, tree, orow)
    for _ in range(k):
        _solve_once(False, stage, h, nq, body_node, model, state, tree, orow)
    return nq


@jit
def _loop_first_assembly(k, h, model, state):
    """``k`` load evaluations, each followed by the assembly of a step's first solve."""
    tree = state.pos0.view(np.int64)
    orow = state.vel0.view(np.int64)
    body_node = _body_node(model, state)
    imp.prepare(False, body_node, state, tree, orow)
    for _ in range(k):
        compute_loads(model, state)
        assemble(h, True, body_node, model, state, orow)


def _time_loop(fn, *args) -> float:
    """Best of 5 wall times of one call of a jitted loop [s]."""
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        fn(*args)
        best = min(best, time.perf_counter() - t0)
    return best


def piece_costs(case: Case) -> dict:
    """Cost [us] of each piece of one implicit step at the state reached half-way through the case."""
    sim = case.sim
    case.reset()
    sim.advance_to(0.5 * (sim.state.t + case.t_end_s))
    st, w = sim.state, sim.work
    records = sim.records()
    k = PIECE_LOOPS
    _loop_loads(1, *records)
    out = {"loads_us": _time_loop(_loop_loads, k, *records) / k * 1e6}
    # what a solve leaves changed: restored before each stage's loop so that every stage starts from this state
    scratch = (w.node_force, w.node_mm, w.node_mass, w.node_contact, w.node_acc, w.seg_tension, w.body_acc)
    saved = [a.copy() for a in scratch]
    _loop_order(1, *records)
    out["order_rebuild_us"] = _time_loop(_loop_order, k, *records) / k * 1e6
    stage_us = []
    for stage in range(3):
        for arr, s in zip(scratch, saved, strict=True):
            arr[...] = s
        _loop_solve(1, stage, sim.dt, *records)
        stage_us.append(_time_loop(_loop_solve, k, stage, sim.dt, *records) / k * 1e6)
    for arr, s in zip(scratch, saved, strict=True):
        arr[...] = s
    _loop_first_assembly(1, sim.dt, *records)
    out["assemble_first_us"] = _time_loop(_loop_first_assembly, k, sim.dt, *records) / k * 1e6 - out["loads_us"]
    out["assemble_us"] = stage_us[0]
    out["eliminate_back_substitute_us"] = stage_us[1] - stage_us[0]
    out["update_active_set_us"] = stage_us[2] - stage_us[1]
    out.update(n_nodes_slots=int(st.node_i.shape[0]), n_segment_slots=int(st.seg_i.shape[0]),
               n_active_segments=int(np.sum(st.seg_i[:, L.SI_ACTIVE])),
               n_free_nodes=int(np.sum(st.node_i[:, L.NI_KIND] == L.NODE_FREE)))
    return out


def solves_per_step(case: Case) -> dict:
    """Active-set solves per step over the case, replaying each step's loop from Python (not timed)."""
    sim = case.sim
    case.reset()
    st, w = sim.state, sim.work
    end = case.t_end_s
    counts = []
    while st.t < end - 0.5 * sim.dt:
        h = sim.dt * (speed_step_factor(st.node_i, st.node_vel, sim.step_growth_max)
                      if sim.step_growth_max > 1.0 else 1.0)
        sim.evaluate_loads()
        model, state = sim.records()
        body_node = _body_node(model, state)
        tree = w.pos0.view(np.int64)
        orow = w.vel0.view(np.int64)
        nq = imp.prepare(False, body_node, state, tree, orow)
        n = 0
        for it in range(imp.MAX_ACTIVE_SET_SOLVES):
            n += 1
            if _solve_once(it == 0, 2, h, nq, body_node, model, state, tree, orow) == 0:
                break
        counts.append(n)
        status, _ = sim.advance_to(st.t + sim.dt, detect_touchdown=case.fall)
        if status == L.STATUS_TOUCHDOWN:
            break
    c = np.array(counts)
    return {"steps": int(c.size), "mean_solves": float(c.mean()), "max_solves": int(c.max()),
            "histogram": {str(v): int(np.sum(c == v)) for v in np.unique(c)}}


def time_rounds(cases: list[Case], repeats: int, bar) -> tuple[dict, dict]:
    """Wall times [s] of ``repeats`` runs of every case, interleaved so that load changes hit every case alike."""
    walls = {case.name: [] for case in cases}
    steps = {}
    for _ in range(repeats):
        for case in cases:
            wall, steps[case.name] = case.run()
            walls[case.name].append(wall)
            bar.update()
    return walls, steps


def run_baseline(root: Path, repeats: int, out: Path) -> dict:
    """Time the package in ``root`` with this script in a subprocess (whole runs only)."""
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--root", str(root), "--rounds", "1",
                    "--repeats", str(repeats), "--no-breakdown", "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads(out.read_text())["cases"]


def compare(current: dict, baseline: list[dict]) -> dict:
    """Baseline's best time per step, the ratio current / baseline, and the outputs' relative changes."""
    out = {}
    for name, r in current.items():
        best = min(b[name]["us_per_step_min"] for b in baseline)
        old = baseline[0][name]["outputs"]
        changes = {k: (r["outputs"][k] - v) / abs(v) if v else r["outputs"][k] - v for k, v in old.items()
                   if isinstance(v, float) and k != "t_s"}
        out[name] = {"baseline_us_per_step_min": best, "ratio": r["us_per_step_min"] / best,
                     "same_state_bits": r["outputs"]["state_sha256"] == old["state_sha256"],
                     "output_relative_change": changes, "baseline_outputs": old}
    return out


DOC = DOCS / "implicit-step.md"
COMMAND = "python benchmarks/bench_implicit_step.py"
PIECES = (("loads_us", "loads"), ("order_rebuild_us", "order rebuild"),
          ("assemble_first_us", "assembly, first solve"), ("assemble_us", "assembly, later solve"),
          ("eliminate_back_substitute_us", "elimination and back substitution"),
          ("update_active_set_us", "active-set update"))


def docs_blocks(out: dict) -> list[tuple[Path, str, str]]:
    """The tables of one run (docs/implicit-step.md): cost per step by case (with the baseline's ratio where the run
    had one), and the breakdown of one step."""
    cases = out["cases"]
    against = out.get("against_baseline") or {}
    header = ["case", "dt [ms]", "steps", "us/step min", "us/step median", "active-set solves per step mean / max"]
    if against:
        header += ["ratio to baseline", "same state bits"]
    rows = []
    for name, r in cases.items():
        solves = r.get("active_set_solves")
        row = [name, f"{1e3 * r['dt_s']:.2f}", r["steps"], f"{r['us_per_step_min']:.2f}",
               f"{r['us_per_step_median']:.2f}",
               f"{solves['mean_solves']:.2f} / {solves['max_solves']}" if solves else "-"]
        if against:
            c = against.get(name)
            row += [f"{c['ratio']:.3f}", "yes" if c["same_state_bits"] else "no"] if c else ["-", "-"]
        rows.append(row)
    text = [run_line(out, COMMAND) + f" {out['rounds']} rounds x {out['repeats']} timed runs of every case.", "",
            table(header, rows)]
    if against:
        label = out.get("baseline", {}).get("label")
        text += ["", "The baseline is another tree timed alternately with this one" + (f" ({label})" if label else "")
                 + "; the ratio is this tree's best time per step over the baseline's."]
    pieces = [[name] + [f"{r['pieces_us'][k]:.2f}" for k, _ in PIECES] +
              [f"{r['pieces_us']['n_active_segments']} of {r['pieces_us']['n_segment_slots']}"]
              for name, r in cases.items() if "pieces_us" in r]
    blocks = [(DOC, "bench_implicit_step", "\n".join(text))]
    if pieces:
        blocks.append((DOC, "bench_implicit_step:pieces", table(
            ["case"] + [f"{label} [us]" for _, label in PIECES] + ["active segments"], pieces)))
    return blocks


def docs_from_results() -> list[tuple[Path, str, str]]:
    """:func:`docs_blocks` of the committed ``benchmarks/results/bench_implicit_step.json``."""
    return docs_blocks(load_result("bench_implicit_step"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of every case per round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-breakdown", action="store_true", help="time whole runs only")
    parser.add_argument("--baseline-root", type=Path, help="another tree to time alongside (see the docstring)")
    parser.add_argument("--baseline-label", default="", help="what the baseline tree is (kept in the JSON)")
    parser.add_argument("--root", type=Path, help="run on another tree (used for the baseline)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument("--docs-only", action="store_true",
                        help="rewrite the docs tables from benchmarks/results/bench_implicit_step.json, run nothing")
    args = parser.parse_args()
    if args.docs_only:
        write_blocks(docs_from_results())
        return
    load_before = os.getloadavg()[0]
    cases = [Case("hanging_waves", WAVES, fall=False), Case("fall_fast", COARSE, fall=True),
             Case("fall_fine", FINE, fall=True), Case("fall_fast_after_waves", WAVES, fall=True, hang_first=True)]
    results = {}
    for case in cases:
        case.run()  # warm-up (compile or cache load)
    bar = tqdm(total=len(cases) * args.repeats * args.rounds, desc="timed runs", leave=False)
    walls = {case.name: [] for case in cases}
    baseline = []
    baseline_out = [args.out.with_name(args.out.stem + f"_baseline_{k}.json") for k in range(args.rounds)]
    for k in range(args.rounds):
        if args.baseline_root is not None:
            baseline.append(run_baseline(args.baseline_root, args.repeats, baseline_out[k]))
        round_walls, steps = time_rounds(cases, args.repeats, bar)
        for name, w in round_walls.items():
            walls[name] += w
    bar.close()
    for case in cases:
        case.run()
        w = np.array(walls[case.name])
        results[case.name] = {"dt_s": case.sim.dt, "steps": steps[case.name], "wall_min_s": float(w.min()),
                              "wall_median_s": float(np.median(w)),
                              "us_per_step_min": float(w.min() / steps[case.name] * 1e6),
                              "us_per_step_median": float(np.median(w) / steps[case.name] * 1e6),
                              "outputs": case.outputs()}
        if not args.no_breakdown:
            results[case.name]["pieces_us"] = piece_costs(case)
            results[case.name]["active_set_solves"] = solves_per_step(case)
    out = {**run_record(load_before), "repeats": args.repeats, "rounds": args.rounds, "cases": results}
    if baseline:
        out["baseline"] = {"label": args.baseline_label}  # where the other tree lay on that machine means nothing here
        out["against_baseline"] = compare(results, baseline)
        for path in baseline_out:
            path.unlink()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    if args.root is None and args.out.resolve() == RESULTS.resolve():
        write_blocks(docs_blocks(out))
    for name, r in results.items():
        print(f"{name:22s} {r['outputs']}", f"baseline: {out['against_baseline'][name]}" if baseline else "")
    print("\n\n".join(text for _, _, text in docs_blocks(out)))  # the tables as docs/implicit-step.md shows them
    print(f"load average {load_before:.2f} -> {out['load_average_1min']['after']:.2f}; wrote {args.out}")


if __name__ == "__main__":
    main()

"""Advance many simulators in one numba call: the integration of every env (single and batched).

Each scene keeps its own arrays (node counts differ between scenes and change under payout), so every array
argument of the physics entry point :func:`moor_env.physics.integrate.advance` is passed as a tuple of the
scenes' arrays (references, no copy), and :func:`advance_many` calls ``advance`` for each listed scene in a loop,
without the GIL. Tuples rather than numba typed lists: typed-list methods are compiled anew in every process
(measured 3.5 s for the five array types), whereas a tuple signature is compiled once and then loaded from
numba's disk cache. Every call uses tuples of ``BATCH_WIDTH`` (8) arrays, padded with dummies.

Why the single env goes through this kernel too (with one scene): LLVM optimises ``advance`` together with its
caller (inlining, constant arguments), and with the kernels' fastmath ``contract`` flag the fused multiply-adds
it chooses can depend on that context. Measured: the states after 10 s of waves and the fall were bit-identical between
``Simulator.advance_to`` and a loop kernel, but the interpolated touchdown record differed by 1 ulp. Sharing
one compiled kernel (one specialisation: fixed tuple length) makes row i of the batched env equal the single env
bit for bit.

Why no ``prange``: the threading layer available here is GNU OpenMP, which is not fork-safe (an
``AsyncVectorEnv`` forked after a parallel region aborts), and numba's fork-safe ``workqueue`` layer is not
thread-safe. The batched env instead calls this GIL-free kernel from ``num_threads`` Python threads on
disjoint groups of scenes of about equal cost (:func:`balanced_groups`; one numba call per up to 8 scenes).

The argument list mirrors ``Simulator.advance_to``; if the physics changes ``advance``'s signature, this module
follows (see ``_slot_arrays``).
"""

from __future__ import annotations

import time
import weakref
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from moor_env.errors import SimulationDiverged
from moor_env.physics import layout as L
from moor_env.physics.integrate import advance
from moor_env.simulation import Simulator

BATCH_WIDTH = 8  # scenes per kernel call (tuple length of the one compiled specialisation)

# (name, dtype, ndim) of every per-scene array argument of ``advance``, in call order
_ARRAY_ARGS: tuple[tuple[str, type, int], ...] = (
    ("node_pos", np.float64, 2), ("node_vel", np.float64, 2), ("body_state", np.float64, 1),
    ("node_i", np.int64, 2), ("node_f", np.float64, 2), ("seg_i", np.int64, 2), ("seg_f", np.float64, 2),
    ("mat_f", np.float64, 2), ("line_i", np.int64, 2), ("line_f", np.float64, 2), ("body_f", np.float64, 1),
    ("body_q", np.float64, 2), ("env_f", np.float64, 1), ("current_profile", np.float64, 2),
    ("tracks", np.float64, 3), ("node_force", np.float64, 2), ("node_mm", np.float64, 2),
    ("node_mass", np.float64, 1), ("node_contact", np.float64, 1), ("node_acc", np.float64, 2),
    ("seg_tension", np.float64, 1), ("body_load", np.float64, 1), ("body_acc", np.float64, 1),
    ("pos0", np.float64, 2), ("vel0", np.float64, 2), ("body0", np.float64, 1), ("touchdown", np.float64, 1),
    ("hist", np.float64, 2), ("hist_count", np.int64, 1),
)


@numba.njit(cache=True, nogil=True)
def advance_many(slots, t, t_end, dt, integrator, body_active, detect, node_pos, node_vel, body_state, node_i,
                 node_f, seg_i, seg_f, mat_f, line_i, line_f, body_f, body_q, env_f, current_profile, tracks,
                 node_force, node_mm, node_mass, node_contact, node_acc, seg_tension, body_load, body_acc, pos0,
                 vel0, body0, touchdown, hist, hist_count, out_status, out_t, out_steps, out_fail_kind,
                 out_fail_index):
    """``advance`` for the scenes listed in ``slots``; results in the ``out_*`` arrays at the slot index."""
    for k in range(slots.shape[0]):
        i = slots[k]
        status, t_reached, n_steps, fail_kind, fail_index = advance(
            t[i], t_end[i], dt[i], integrator[i], body_active[i], detect[i], node_pos[i], node_vel[i],
            body_state[i], node_i[i], node_f[i], seg_i[i], seg_f[i], mat_f[i], line_i[i], line_f[i], body_f[i],
            body_q[i], env_f[i], current_profile[i], tracks[i], node_force[i], node_mm[i], node_mass[i],
            node_contact[i], node_acc[i], seg_tension[i], body_load[i], body_acc[i], pos0[i], vel0[i], body0[i],
            touchdown[i], hist[i], hist_count[i], 0)
        out_status[i] = status
        out_t[i] = t_reached
        out_steps[i] = n_steps
        out_fail_kind[i] = fail_kind
        out_fail_index[i] = fail_index


def _slot_arrays(sim: Simulator) -> list[np.ndarray]:
    """The simulator's arrays in ``advance``'s argument order (checked for dtype, rank and layout)."""
    st, m, w = sim.state, sim.model, sim.work
    sources = {
        "node_pos": st.node_pos, "node_vel": st.node_vel, "body_state": st.body_state, "node_i": st.node_i,
        "node_f": st.node_f, "seg_i": st.seg_i, "seg_f": st.seg_f, "mat_f": m.mat_f, "line_i": st.line_i,
        "line_f": st.line_f, "body_f": m.body_f, "body_q": m.body_q, "env_f": sim.env_f,
        "current_profile": m.current_profile, "tracks": sim.tracks, "node_force": w.node_force,
        "node_mm": w.node_mm, "node_mass": w.node_mass, "node_contact": w.node_contact, "node_acc": w.node_acc,
        "seg_tension": w.seg_tension, "body_load": w.body_load, "body_acc": w.body_acc, "pos0": w.pos0,
        "vel0": w.vel0, "body0": w.body0, "touchdown": w.touchdown, "hist": w.hist, "hist_count": w.hist_count,
    }
    out = []
    for name, dtype, ndim in _ARRAY_ARGS:
        arr = sources[name]
        if arr.dtype != dtype or arr.ndim != ndim or not arr.flags.c_contiguous:
            raise TypeError(f"simulator array '{name}' is {arr.dtype}[{arr.ndim}d], expected C-contiguous "
                            f"{np.dtype(dtype)}[{ndim}d]")
        out.append(arr)
    return out


_TRACKS = [name for name, _, _ in _ARRAY_ARGS].index("tracks")


def _dummy(dtype, ndim: int) -> np.ndarray:
    return np.zeros((1,) * ndim, dtype=dtype)


def balanced_groups(items: list[tuple[int, tuple[Simulator, float, bool, float]]], n_groups: int
                    ) -> list[list[tuple[int, tuple[Simulator, float, bool, float]]]]:
    """Split ``(slot, job)`` items into at most ``n_groups`` groups of about equal cost (longest first, each to the
    least loaded group).

    Why: one env step of a scene that releases integrates its whole fall (hundreds of steps) while the others
    integrate one control interval, and the step waits for the slowest thread; interleaved groups put the falls
    wherever they happened to be. The cost estimate is steps to the end time times node slots (a fall counts its
    whole ``max_fall_time_s``, which only makes it go first). Grouping never changes a result: every scene's
    integration is independent of the others in the call.
    """
    n = min(n_groups, len(items))
    if n <= 1:
        return [items] if items else []
    costs = [(t_end - sim.state.t) / dt * sim.state.node_pos.shape[0] for _, (sim, t_end, _, dt) in items]
    groups: list[list] = [[] for _ in range(n)]
    loads = [0.0] * n
    for k in sorted(range(len(items)), key=lambda k: -costs[k]):
        g = loads.index(min(loads))
        groups[g].append(items[k])
        loads[g] += costs[k]
    return groups


class BatchAdvancer:
    """Advance any number of simulators with :func:`advance_many`, ``BATCH_WIDTH`` scenes per kernel call.

    Every call passes tuples of exactly ``BATCH_WIDTH`` arrays (unused positions hold dummies), so the single env
    (one scene) and the batched env (many) run one and the same compiled specialisation of the kernel: numba
    compiles a tuple signature per tuple length, and two specialisations may contract floating-point operations
    differently (see the module docstring).

    The per-call Python work is kept small (it is paid on every env step): a simulator's argument list is built
    and checked once and reused while its state stays the same object (only the vessel tracks are re-read, since
    ``set_vessel_motion`` may replace them); the dummies are built once.

    Parameters
    ----------
    num_threads : int
        Threads that call the kernel on interleaved groups of the scenes (1: all in the calling thread).
    """

    def __init__(self, num_threads: int = 1) -> None:
        self.num_threads = max(1, int(num_threads))
        self.pool = ThreadPoolExecutor(self.num_threads - 1) if self.num_threads > 1 else None
        self.dummies = [_dummy(dtype, ndim) for _, dtype, ndim in _ARRAY_ARGS]
        self._columns: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # simulator -> (state, arrays)
        self.kernel_s = 0.0  # CPU time inside the kernel, summed over threads (benchmarks/bench_env.py)

    def _column(self, sim: Simulator) -> list[np.ndarray]:
        """``advance``'s per-scene arrays of ``sim``, cached while its state is the same object (the entry holds
        it, so a new state can never pass for an old one; the entry goes with the simulator)."""
        entry = self._columns.get(sim)
        if entry is None or entry[0] is not sim.state:
            entry = (sim.state, _slot_arrays(sim))
            self._columns[sim] = entry
        column = entry[1]
        tracks = sim.tracks
        if column[_TRACKS] is not tracks:
            if tracks.dtype != np.float64 or tracks.ndim != 3 or not tracks.flags.c_contiguous:
                raise TypeError("simulator array 'tracks' must be C-contiguous float64[3d]")
            column[_TRACKS] = tracks
        return column

    def _call(self, chunk: list[tuple[Simulator, float, bool, float]]) -> tuple[tuple[np.ndarray, ...], float]:
        """One kernel call on up to BATCH_WIDTH scenes; returns the output arrays and the kernel's CPU time."""
        w = BATCH_WIDTH
        t = np.zeros(w)
        t_end = np.zeros(w)
        dt = np.ones(w)
        integ = np.zeros(w, np.int64)
        body_active = np.zeros(w, np.bool_)
        detect = np.zeros(w, np.bool_)
        columns = [self.dummies] * w
        for i, (sim, t_stop, det, step_s) in enumerate(chunk):
            columns[i] = self._column(sim)
            t[i] = sim.state.t
            t_end[i] = t_stop
            dt[i] = step_s
            integ[i] = sim.integrator_code
            body_active[i] = sim.model.body_active
            detect[i] = det
        out = (np.zeros(w, np.int64), np.zeros(w), np.zeros(w, np.int64), np.zeros(w, np.int64), np.zeros(w, np.int64))
        t0 = time.thread_time()
        advance_many(np.arange(len(chunk), dtype=np.int64), t, t_end, dt, integ, body_active, detect,
                     *zip(*columns, strict=True), *out)
        return out, time.thread_time() - t0

    def _run_group(self, group: list[tuple[int, tuple[Simulator, float, bool, float]]]
                   ) -> tuple[list[tuple[int, tuple]], float]:
        results = []
        kernel_s = 0.0
        for start in range(0, len(group), BATCH_WIDTH):
            chunk = group[start:start + BATCH_WIDTH]
            (status, t_out, _, kind, index), seconds = self._call([job for _, job in chunk])
            kernel_s += seconds
            for j, (slot, _) in enumerate(chunk):
                results.append((slot, (int(status[j]), float(t_out[j]), int(kind[j]), int(index[j]))))
        return results, kernel_s

    def run(self, jobs: dict[int, tuple[Simulator, float, bool, float]]
            ) -> dict[int, tuple[int | None, SimulationDiverged | None]]:
        """Advance ``{slot: (simulator, t_end_s, detect_touchdown, dt_s)}``.

        Returns
        -------
        dict
            ``{slot: (status, None)}`` or ``{slot: (None, SimulationDiverged)}`` as ``Simulator.advance_to``
            would have returned or raised.
        """
        groups = balanced_groups(sorted(jobs.items()), self.num_threads)
        if len(groups) <= 1 or self.pool is None:
            done = [self._run_group(g) for g in groups]
        else:
            # the kernel holds no GIL; the calling thread takes the first group itself rather than waiting idle
            futures = [self.pool.submit(self._run_group, g) for g in groups[1:]]
            done = [self._run_group(groups[0])] + [f.result() for f in futures]
        raw = [r for group_results, _ in done for r in group_results]
        self.kernel_s += sum(seconds for _, seconds in done)
        results = {}
        for slot, (status, t_reached, kind, index) in raw:
            sim = jobs[slot][0]
            sim.state.t = t_reached
            if status >= L.STATUS_NONFINITE:
                results[slot] = (None, SimulationDiverged(t_reached, sim.component_name(kind, index),
                                                          L.STATUS_NAMES[status]))
            else:
                results[slot] = (status, None)
        return results

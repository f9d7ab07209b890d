"""Advance many simulators in one numba call: the integration of every env (single and batched).

Each scene keeps its own arrays (node counts differ between scenes), so the kernel cannot take one stacked array
per field. It takes one int64 *address table* instead: for every scene, the rows of its model and state records
(``physics/records.py``), then those of its slot's outputs (:data:`SlotRecord`) and of the backup of its state, in
that order (``ROW_*``; ``physics/record_table.py`` writes and checks the rows). :func:`advance_many` rebuilds each
scene's records as views on that memory and calls the physics entry point
:func:`moor_env.physics.integrate.advance` for each scene in a loop, without the GIL; a field added to the records
is in the table with no edit here.

Why addresses: numba unboxes every array argument on every call, with the GIL held. Passed as arrays (a tuple of 8
arrays per argument, 232 arrays) they would cost 56-75 us per call before the first step (measured with nothing to
integrate), a fifth of a calm scene's control step; the kernel takes four small arrays whatever the number of
scenes, and a one-scene call with nothing to integrate costs 16 us, most of it the load evaluation the kernel does
(below). The addresses stay valid because :class:`BatchAdvancer` keeps every record referenced while its entry is
in use, checks dtype, rank and C layout when it builds an entry, and rebuilds the entry when the simulator's
records change (``Simulator.records``: a new state object, new work arrays, new vessel tracks).

After each scene's advance the kernel evaluates the loads at the state reached and checks it
(:func:`~moor_env.physics.integrate.end_state_status`; an advance that takes a backup also fails where it raised a
line's running maximum tension above the line's breaking load), then the lines' top tensions (unless it blew up),
so the observation's tensions (``Simulator.top_tensions_n``) need no second kernel call and that work runs on the
batch's threads. An env slot also passes its :class:`~moor_env.envs.measures.SlotBuffers`: the kernel then writes
the quantities its observation reads (``M_*``, :func:`~moor_env.envs.measures.measure_scene`) and, where the
advance asks for it, first copies the state into a backup (the env repeats a diverged coarse pre-release advance
from it). Done in Python on every env step they cost a numpy copy of nine arrays and a dozen small kernel and numpy
calls; done here (and with the observations normalised for all slots at once) the batched env's Python per slot and
step is about 48 us rather than 68 us (calm default scene, 16 slots, one thread, profiler off).

Why the single env goes through this kernel too (with one scene): LLVM optimises ``advance`` together with its
caller (inlining, constant arguments), and under the kernels' fastmath flags (``physics/_jit.py``) how it rounds
may depend on that context. Sharing one compiled kernel (one specialisation, any number of scenes) makes row i of
the batched env equal the single env bit for bit.

Why no ``prange``: numba's threading layer without TBB installed is GNU OpenMP, which is not fork-safe (an
``AsyncVectorEnv`` forked after a parallel region aborts), and numba's fork-safe ``workqueue`` layer is not
thread-safe. The batched env instead calls this GIL-free kernel from ``num_threads`` Python threads on
disjoint groups of scenes of about equal cost (:func:`balanced_groups`; one numba call per group).
"""

from __future__ import annotations

import time
import weakref
from collections import namedtuple
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from moor_env.envs.measures import N_SPEC, SlotBuffers, measure_scene
from moor_env.errors import SimulationDiverged
from moor_env.physics import layout as L
from moor_env.physics.integrate import advance, end_state_status
from moor_env.physics.line import top_tensions
from moor_env.physics.loads import compute_accelerations
from moor_env.physics.record_table import N_TABLE_COLUMNS, copy_rows, record_from_table, table_rows
from moor_env.physics.records import F8, I8, MODEL_FIELDS, STATE_FIELDS, STATE_NAMES, Field, ModelRecord, StateRecord
from moor_env.simulator import Simulator

SlotRecord = namedtuple("SlotRecord", ["measures", "measure_spec"])
SlotRecord.__doc__ = "An env slot's arrays for the kernel: its measures (``M_*``) and what to measure (``SPEC_*``)."
SlotRecord.FIELDS = (Field("measures", F8, 1), Field("measure_spec", I8, 1))
# the rows of a scene in the address table: its model record, state record, slot record and the state's backup
ROW_MODEL = 0
ROW_STATE = ROW_MODEL + len(ModelRecord.FIELDS)
ROW_SLOT = ROW_STATE + len(StateRecord.FIELDS)
ROW_BACKUP = ROW_SLOT + len(SlotRecord.FIELDS)
N_ROWS = ROW_BACKUP + len(STATE_FIELDS)
# columns of a scene's per-call scalars (float64 table) and results (int64 / float64 tables)
IN_T, IN_T_END, IN_DT, IN_INTEGRATOR, IN_DETECT, IN_BACKUP, IN_STEP_GROWTH = range(7)
# IN_BACKUP (a job's ``take_backup``): 0 an advance at the scene's step; TAKE_BACKUP a coarse one, the state backed
# up first; BACKED_UP a later chunk of a coarse one (backed up before its first chunk). Both coarse kinds are
# checked against the lines' breaking loads, so that chunking a coarse advance never changes its result.
TAKE_BACKUP = 1
BACKED_UP = 2
N_IN = 7
OUT_STATUS, OUT_STEPS, OUT_FAIL_KIND, OUT_FAIL_INDEX = range(4)

@numba.njit(cache=True, nogil=True)
def advance_many(scalars, addresses, out_i, out_t):
    """``advance`` for every scene of the tables, then the loads at the state reached.

    Parameters
    ----------
    scalars : float64[n, N_IN]
        t, t_end, dt [s], integrator code, detect touchdown (0/1), back the state up first (0/1), the implicit
        step's largest growth (``Simulator.step_growth_max``) (``IN_*`` columns).
    addresses : int64[n, N_ROWS, record_table.N_TABLE_COLUMNS]
        Each scene's table rows (``ROW_*``; see the module docstring).
    out_i : int64[n, 4]
        Status, steps taken, failing component kind and index (``OUT_*`` columns).
    out_t : float64[n]
        Time reached [s].
    """
    for i in range(scalars.shape[0]):
        a = addresses[i]
        model = record_from_table(ModelRecord, a, ROW_MODEL)
        state = record_from_table(StateRecord, a, ROW_STATE)
        slot = record_from_table(SlotRecord, a, ROW_SLOT)
        coarse = scalars[i, IN_BACKUP] != 0.0
        if scalars[i, IN_BACKUP] == TAKE_BACKUP:
            copy_rows(a, ROW_STATE, ROW_BACKUP, N_ROWS - ROW_BACKUP)
        # a coarse advance is checked against the lines' breaking loads: their running maxima before it
        max_tension_before = state.line_f[:, L.LF_MAX_TENSION].copy() if coarse else np.empty(0)
        status, t_reached, n_steps, fail_kind, fail_index = advance(
            model, state, scalars[i, IN_T], scalars[i, IN_T_END], scalars[i, IN_DT],
            np.int64(scalars[i, IN_INTEGRATOR]), scalars[i, IN_DETECT] != 0.0, 0, scalars[i, IN_STEP_GROWTH])
        if status < L.STATUS_NONFINITE:
            max_strain, worst_seg = compute_accelerations(model, state)
            failed, kind, index = end_state_status(model, state, max_strain, worst_seg, max_tension_before)
            if failed != L.STATUS_RUNNING:
                status, fail_kind, fail_index = failed, kind, index
        if status < L.STATUS_NONFINITE:
            top_tensions(state.line_i, state.seg_i, state.node_i, state.node_force, state.seg_tension,
                         state.top_tension)
            if slot.measure_spec.shape[0] == N_SPEC:
                measure_scene(model, state, t_reached, slot.measure_spec, slot.measures)
        out_i[i, OUT_STATUS] = status
        out_i[i, OUT_STEPS] = n_steps
        out_i[i, OUT_FAIL_KIND] = fail_kind
        out_i[i, OUT_FAIL_INDEX] = fail_index
        out_t[i] = t_reached


_NO_SLOT = SlotRecord(np.zeros(0), np.zeros(0, dtype=np.int64))  # a job without SlotBuffers: nothing measured


class _Entry:
    """A simulator's address table for its current records, slot buffers and backup, with the records it points
    into (kept alive)."""

    __slots__ = ("records", "buffers", "backup", "table")

    def __init__(self, sim: Simulator, records: tuple, buffers: SlotBuffers | None) -> None:
        model, state = records
        st = sim.state
        # without a backup the state's own arrays stand in for the backup's (written only by an advance that
        # takes a backup, which needs one)
        backup = st if buffers is None or buffers.backup is None else buffers.backup
        if backup is not st:
            for name in STATE_NAMES:
                if getattr(backup, name).shape != getattr(st, name).shape:
                    raise TypeError(f"backup array '{name}' is {getattr(backup, name).shape}, the state's "
                                    f"{getattr(st, name).shape}")
        slot = _NO_SLOT if buffers is None else SlotRecord(buffers.measures, buffers.spec)
        self.records = (model, state, slot, backup)
        self.buffers = buffers
        self.backup = None if buffers is None else buffers.backup
        self.table = np.concatenate([table_rows(model), table_rows(state), table_rows(slot),
                                     table_rows([getattr(backup, name) for name in STATE_NAMES], STATE_FIELDS)])

    def refresh_model(self, model: ModelRecord) -> None:
        """Point at the simulator's current model record (``set_vessel_motion`` may replace the vessel tracks)."""
        if self.records[0] is not model:
            self.table[ROW_MODEL:ROW_MODEL + len(MODEL_FIELDS)] = table_rows(model)
            self.records = (model, *self.records[1:])


def _job_parts(job: tuple) -> tuple[Simulator, float, bool, float, SlotBuffers | None, int]:
    """A job with its optional entries filled in: (simulator, t_end_s, detect, dt_s, buffers, take_backup), the
    last 0, ``TAKE_BACKUP`` (or True) or ``BACKED_UP``."""
    sim, t_stop, detect, step_s, *rest = job
    return sim, t_stop, detect, step_s, rest[0] if rest else None, int(rest[1]) if len(rest) > 1 else 0


def balanced_groups(items: list[tuple[int, tuple]], n_groups: int) -> list[list[tuple[int, tuple]]]:
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
    costs = [(job[1] - job[0].state.t) / job[3] * job[0].state.node_pos.shape[0] for _, job in items]
    groups: list[list] = [[] for _ in range(n)]
    loads = [0.0] * n
    for k in sorted(range(len(items)), key=lambda k: -costs[k]):
        g = loads.index(min(loads))
        groups[g].append(items[k])
        loads[g] += costs[k]
    return groups


class BatchAdvancer:
    """Advance any number of simulators with :func:`advance_many`, one kernel call per thread's group of scenes.

    The per-call Python work is kept small (it is paid on every env step): a simulator's address table is built
    and checked once and reused while its state stays the same object (only the vessel tracks' row is re-read,
    since ``set_vessel_motion`` may replace them).

    Parameters
    ----------
    num_threads : int
        Threads that call the kernel on groups of the scenes (1: all in the calling thread).
    """

    def __init__(self, num_threads: int = 1) -> None:
        self.num_threads = max(1, int(num_threads))
        self.pool = ThreadPoolExecutor(self.num_threads - 1) if self.num_threads > 1 else None
        self._entries: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # simulator -> _Entry
        self.kernel_s = 0.0  # CPU time inside the kernel, summed over threads (benchmarks/bench_env.py)

    def _entry(self, sim: Simulator, buffers: SlotBuffers | None) -> _Entry:
        """``sim``'s address table, cached while its state record, slot buffers and backup are the same objects
        (the entry holds them, so a new one can never pass for an old one; the entry goes with the simulator)."""
        records = sim.records()
        entry = self._entries.get(sim)
        if entry is None or entry.records[1] is not records[1] or entry.buffers is not buffers or (
                buffers is not None and entry.backup is not buffers.backup):
            entry = _Entry(sim, records, buffers)
            self._entries[sim] = entry
        entry.refresh_model(records[0])
        return entry

    def _call(self, jobs: list[tuple]) -> tuple[np.ndarray, np.ndarray, float]:
        """One kernel call on the scenes of ``jobs``; returns ``out_i``, ``out_t`` and the kernel's CPU time."""
        n = len(jobs)
        scalars = np.empty((n, N_IN))
        addresses = np.empty((n, N_ROWS, N_TABLE_COLUMNS), dtype=np.int64)
        entries = []  # keeps every array referenced until the call returns
        for i, job in enumerate(jobs):
            sim, t_stop, detect, step_s, buffers, backup = _job_parts(job)
            if backup == TAKE_BACKUP and (buffers is None or buffers.backup is None):
                raise ValueError("an advance that takes a backup needs SlotBuffers with a backup state")
            entry = self._entry(sim, buffers)
            entries.append(entry)
            addresses[i] = entry.table
            scalars[i] = (sim.state.t, t_stop, step_s, sim.integrator_code, detect, backup, sim.step_growth_max)
        out_i = np.zeros((n, 4), dtype=np.int64)
        out_t = np.zeros(n)
        t0 = time.thread_time()
        advance_many(scalars, addresses, out_i, out_t)
        return out_i, out_t, time.thread_time() - t0

    def _run_group(self, group: list[tuple[int, tuple]]) -> tuple[list[tuple[int, tuple]], float]:
        out_i, out_t, seconds = self._call([job for _, job in group])
        results = [(slot, (int(out_i[j, OUT_STATUS]), float(out_t[j]), int(out_i[j, OUT_FAIL_KIND]),
                           int(out_i[j, OUT_FAIL_INDEX]))) for j, (slot, _) in enumerate(group)]
        return results, seconds

    def run(self, jobs: dict[int, tuple]) -> dict[int, tuple[int | None, SimulationDiverged | None]]:
        """Advance ``{slot: (simulator, t_end_s, detect_touchdown, dt_s[, slot_buffers, take_backup])}``: with
        :class:`~moor_env.envs.measures.SlotBuffers` the kernel also measures the state reached and, with
        ``take_backup`` (``TAKE_BACKUP`` or True), first copies the state into the buffers' backup; a coarse
        advance, and a later chunk of one (``BACKED_UP``), is also checked against the lines' breaking loads.

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
        self.kernel_s += sum(seconds for _, seconds in done)
        results = {}
        for slot, (status, t_reached, kind, index) in (r for group_results, _ in done for r in group_results):
            sim = jobs[slot][0]
            sim.state.t = t_reached
            if status >= L.STATUS_NONFINITE:
                results[slot] = (None, SimulationDiverged(t_reached, sim.component_name(kind, index),
                                                          L.STATUS_NAMES[status]))
            else:
                sim.note_loads_evaluated()
                buffers = _job_parts(jobs[slot])[4]
                if buffers is not None:
                    buffers.record = sim.loads_record()
                results[slot] = (status, None)
        return results

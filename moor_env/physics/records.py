"""The kernels' two records: the compiled model and the simulation state (in the spirit of MuJoCo's mjModel and
mjData). The list of arrays is written here and nowhere else.

Every dynamics kernel takes ``(model, state)``:

- :data:`ModelRecord` holds what a kernel call reads and never changes: materials, the anchor's constants and
  quadrature, the environment, the current profile and the sampled vessel tracks (:data:`MODEL_FIELDS`). Python
  may change their contents between calls (the vessel-track window, the statics' smoothing levels);
- :data:`StateRecord` holds what the kernels change: the simulation state proper (:data:`STATE_FIELDS`: positions,
  velocities, the anchor's state and the topology that payout and release change; what a copy, a backup or a
  remesh of the state carries, Python's :class:`SimState`) followed by the work arrays (:data:`WORK_FIELDS`: the
  loads of the last evaluation, integrator scratch and outputs such as the touchdown record; Python's
  :data:`Workspace`, allocated from the sizes given here).

Both are ``collections.namedtuple`` classes of arrays (numba types them as named tuples and caches the kernels
that take them). A field is read-only, the array it holds is changed in place; a scalar that a kernel or the
caller changes lives in a small array, never in a field. A kernel unpacks what it needs first
(``node_pos = state.node_pos``; an attribute read inside a loop costs a reference count per pass); the column layout
of every array is in ``physics/layout.py``. Kernels called every time step that allocate nothing are compiled with
``_jit.jit_no_refcount``, which spares the reference counting of the records' arrays on each call.

Adding an array is one line in the field lists below plus its use: a model array is taken from the compiled scene's
attribute of the same name (``compile.Model``) unless the simulator passes its own copy; a state array is set from
the compiled scene's initial state (``compile.Model.initial_state``); a work array is allocated from its shape.
The batched env's address table (``physics/record_table.py``) is derived from the same lists.
"""

from __future__ import annotations

from collections import namedtuple
from typing import NamedTuple

import numpy as np

from moor_env.physics.layout import N_BODY_STATE, N_CONTACT_CACHE, N_CONTACT_OUT, N_HIST, N_NEAR, N_TD

HISTORY_CAPACITY = 20000  # rows of the tip history a simulator records


class Field(NamedTuple):
    """One array of a record: name, dtype, rank and, for a work array, its shape (``"nodes"``, ``"segs"``,
    ``"lines"`` or an int per dimension)."""

    name: str
    dtype: type
    ndim: int
    shape: tuple = ()


F8 = np.float64
I8 = np.int64

MODEL_FIELDS: tuple[Field, ...] = (
    Field("mat_f", F8, 2),  # one row per material (MF_*)
    Field("body_f", F8, 1),  # the anchor's constants (BF_*; BF_ACTIVE: an anchor is simulated)
    Field("body_q", F8, 2),  # the anchor's Morison quadrature stations (BQ_*)
    Field("env_f", F8, 1),  # water, seabed, current, limits, vessel-track timing (EF_*)
    Field("current_profile", F8, 2),  # (depth [m], speed factor) rows
    Field("tracks", F8, 3),  # sampled vessel motion: (vessel, sample, position and velocity)
    Field("contact_f", F8, 1),  # line-anchor contact parameters (CF_*; CF_ON: modelled)
    Field("contact_shape", F8, 2),  # the anchor's surface as coaxial cylinders (CS_*)
)

STATE_FIELDS: tuple[Field, ...] = (
    Field("node_pos", F8, 2),  # [m]
    Field("node_vel", F8, 2),  # [m/s]
    Field("body_state", F8, 1),  # the anchor (BS_*)
    Field("node_i", I8, 2),  # node kinds and references (NI_*; release and payout change them)
    Field("node_f", F8, 2),  # point masses, volumes, drag, body coordinate (NF_*)
    Field("seg_i", I8, 2),  # segment ends, material, line, active (SI_*)
    Field("seg_f", F8, 2),  # unstretched lengths (SF_*)
    Field("line_i", I8, 2),  # slot ranges and counts of each line (LI_*)
    Field("line_f", F8, 2),  # winch rate, payout limits, running maximum tension (LF_*)
)

WORK_FIELDS: tuple[Field, ...] = (
    Field("node_force", F8, 2, ("nodes", 3)),  # net load on each node [N]
    Field("node_mm", F8, 2, ("nodes", 6)),  # added-mass matrix (xx yy zz xy xz yz); implicit step's blocks
    Field("node_mass", F8, 1, ("nodes",)),  # structural mass [kg]
    Field("node_contact", F8, 1, ("nodes",)),  # seabed contact area [m^2]
    Field("node_acc", F8, 2, ("nodes", 3)),  # acceleration [m/s^2]; implicit step's right-hand sides
    Field("seg_tension", F8, 1, ("segs",)),  # [N]
    Field("seg_chord", F8, 2, ("segs", 4)),  # implicit step: chord [m] a segment's spring is linearised at, flag
    Field("seg_gain", F8, 2, ("segs", 5)),  # implicit step: each segment's block G_s of the solve (alpha, beta, q)
    Field("node_base", F8, 2, ("nodes", 9)),  # implicit step: blocks, right-hand sides less springs, contact
    Field("body_load", F8, 1, (6,)),  # force and moment on the anchor
    Field("body_acc", F8, 1, (6,)),  # its linear and angular acceleration
    Field("pos0", F8, 2, ("nodes", 3)),  # step-start positions (RK2); implicit step's tree (int64 view)
    Field("vel0", F8, 2, ("nodes", 3)),  # step-start velocities (RK2); implicit step's order and set flags
    Field("body0", F8, 1, (N_BODY_STATE,)),  # step-start anchor state
    Field("touchdown", F8, 1, (N_TD,)),  # the tip's touchdown record (TD_*)
    Field("hist", F8, 2, (HISTORY_CAPACITY, N_HIST)),  # tip history rows (H_*)
    Field("hist_count", I8, 1, (1,)),  # rows of ``hist`` used
    Field("top_tension", F8, 1, ("lines",)),  # each line's load on its vessel [N]
    Field("contact_out", F8, 1, (N_CONTACT_OUT,)),  # what the line-anchor contact did (CO_*)
    Field("contact_set", I8, 1, ("nodes",)),  # implicit step: its contact candidates (implicit_contact_set)
    Field("contact_cache", F8, 2, ("nodes", N_CONTACT_CACHE)),  # implicit step: its candidates' state (CC_*)
    Field("segment_set", I8, 1, ("segs",)),  # implicit step: its segments in contact (implicit_contact_set)
    Field("near_nodes", I8, 1, ("nodes",)),  # the free nodes near the anchor (contact_broadphase)
    Field("near_segs", I8, 1, ("segs",)),  # the segments near it
    Field("near_skin", F8, 1, (N_NEAR,)),  # whether the lists are in use, how far they can be out of date (NEAR_*)
)

MODEL_NAMES = tuple(f.name for f in MODEL_FIELDS)
STATE_NAMES = tuple(f.name for f in STATE_FIELDS)
WORK_NAMES = tuple(f.name for f in WORK_FIELDS)

ModelRecord = namedtuple("ModelRecord", MODEL_NAMES)
ModelRecord.__doc__ = "What the kernels read and never change (:data:`MODEL_FIELDS`)."
ModelRecord.FIELDS = MODEL_FIELDS
StateRecord = namedtuple("StateRecord", STATE_NAMES + WORK_NAMES)
StateRecord.__doc__ = ("What the kernels change: the state, then the work arrays (:data:`STATE_FIELDS`, "
                       ":data:`WORK_FIELDS`).")
StateRecord.FIELDS = STATE_FIELDS + WORK_FIELDS
Workspace = namedtuple("Workspace", WORK_NAMES)
Workspace.__doc__ = "A simulator's work arrays (:data:`WORK_FIELDS`), allocated by :func:`new_workspace`."
Workspace.FIELDS = WORK_FIELDS


class SimState:
    """The simulation state proper: the arrays of :data:`STATE_FIELDS` (keywords of the same names), the time
    ``t`` [s] and whether the anchor has been ``released``. The arrays are changed in place, never replaced."""

    __slots__ = STATE_NAMES + ("t", "released")

    def __init__(self, t: float = 0.0, released: bool = False, **arrays: np.ndarray) -> None:
        if arrays.keys() != set(STATE_NAMES):
            missing = sorted(set(STATE_NAMES) - arrays.keys())
            unknown = sorted(arrays.keys() - set(STATE_NAMES))
            raise TypeError(f"SimState takes the arrays {', '.join(STATE_NAMES)}; missing {missing}, unknown {unknown}")
        for name in STATE_NAMES:
            setattr(self, name, arrays[name])
        self.t = t
        self.released = released

    def copy(self) -> SimState:
        """Deep copy (arrays copied)."""
        return SimState(t=self.t, released=self.released, **{name: getattr(self, name).copy() for name in STATE_NAMES})

    def __repr__(self) -> str:
        return f"SimState(t={self.t!r}, released={self.released!r}, nodes={self.node_pos.shape[0]})"


def new_workspace(n_nodes: int, n_segs: int, n_lines: int) -> Workspace:
    """Work arrays of :data:`WORK_FIELDS` for a model of these slot counts, zeroed."""
    sizes = {"nodes": n_nodes, "segs": n_segs, "lines": n_lines}
    return Workspace(*(np.zeros(tuple(sizes.get(d, d) for d in f.shape), dtype=f.dtype) for f in WORK_FIELDS))


def model_record(model, **own: np.ndarray) -> ModelRecord:
    """The model record of a compiled scene (``compile.Model``): its arrays of the field names, except those a
    simulator keeps its own copy of, given as keywords (``env_f``, ``tracks``)."""
    return ModelRecord(*(own[name] if name in own else getattr(model, name) for name in MODEL_NAMES))


def state_record(state: SimState, work: Workspace) -> StateRecord:
    """The state record of a state and a workspace (their arrays, not copies)."""
    return StateRecord(*(getattr(state, name) for name in STATE_NAMES), *work)

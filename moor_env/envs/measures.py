"""What an episode slot reads from its simulator: the kernel's measures, the mooring line, loads, touchdown.

The batch kernel (:func:`moor_env.envs.batch.advance_many`) measures what the observation reads right after each
advance (:func:`measure_scene`, the ``M_*`` quantities, into the slot's :class:`SlotBuffers`); the functions below
read those measures, or the simulator's state where they are not current. Every reading is a pure function of the
simulator's state: the observation, the reward's :class:`~moor_env.envs.reward.StepRecord` and the step info are
made of them.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from moor_env.compile import VESSEL_INSTALLATION, VESSEL_SECOND
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg
from moor_env.physics.environment import current_velocity
from moor_env.physics.vessels import track_state
from moor_env.simulation import Simulator
from moor_env.simulator import SimState

# what the kernel measures after an advance for an env slot's observation (``SlotBuffers.measures``)
M_TILT_DEG = 0  # anchor axis from vertical, tip down [deg]
M_AXIS_RATE_DEG_S = 1  # angular speed of the axis (spin about it left out) [deg/s]
M_HEAVE_M = 2  # installation vessel z [m]
M_HEAVE_RATE_M_S = 3
M_CURRENT_X_M_S = 4  # surface current
M_CURRENT_Y_M_S = 5
M_TIP_Z_M = 6
M_LOOP_Z_M = 7  # lowest node of the summarised line (inf if it has no active segment)
M_FIBRE_Z_M = 8  # lowest node on its segments of the summarised material (inf if none)
M_LINE_L0_M = 9  # unstretched length of its active segments
M_RELEASE_POS = 10  # 3: release node position [m]
M_RELEASE_VEL = 13  # 3 [m/s]
M_WIRE_TENSION_N = 16  # top tension of the spec's wire line (0 if none)
M_LINE_TENSION_N = 17  # top tension of the summarised line (0 if none)
N_MEASURES = 18
# measure_spec entries (-1: none)
SPEC_RELEASE_NODE, SPEC_LINE, SPEC_MATERIAL, SPEC_WIRE, SPEC_VESSEL = range(5)
N_SPEC = 5


@numba.njit(cache=True, nogil=True)
def segment_travel_s(node_i, node_vel, seg_i, seg_f, line_i):
    """The time [s] in which the fastest free node, at its present speed, travels the length of the shortest
    active segment (a payout line's top segment left out: it shortens to half its nominal length before it
    merges, whatever the mesh); infinite where nothing moves. One pass in a kernel: the env reads it before every
    coarse advance."""
    speed2 = 0.0
    for n in range(node_i.shape[0]):
        if node_i[n, L.NI_KIND] == L.NODE_FREE:
            speed2 = max(speed2, node_vel[n, 0] ** 2 + node_vel[n, 1] ** 2 + node_vel[n, 2] ** 2)
    shortest = math.inf
    for s in range(seg_i.shape[0]):
        if seg_i[s, L.SI_ACTIVE] != 0:
            line = seg_i[s, L.SI_LINE]
            top = line_i[line, L.LI_SEG_START] + line_i[line, L.LI_NSEG] - 1
            if line_i[line, L.LI_PAYOUT] == 0 or s != top:
                shortest = min(shortest, seg_f[s, L.SF_L0])
    if speed2 == 0.0 or shortest == math.inf:
        return math.inf
    return shortest / math.sqrt(speed2)


@numba.njit(cache=True, nogil=True)
def line_summary(node_pos, seg_i, seg_f, line_i, line, material):
    """Over the active segments of ``line``: the lowest node z, the lowest z of nodes on segments of
    ``material`` (inf if none) and the total unstretched length [m].

    One pass in a kernel because the observation needs it every step (numpy masks over the segment table cost
    more than the rest of the observation).
    """
    start = line_i[line, L.LI_SEG_START]
    z_min = math.inf
    z_mat = math.inf
    length = 0.0
    for s in range(start, start + line_i[line, L.LI_SEG_CAP]):
        if seg_i[s, L.SI_ACTIVE] != 1 or seg_i[s, L.SI_LINE] != line:
            continue
        z = min(node_pos[seg_i[s, L.SI_A], 2], node_pos[seg_i[s, L.SI_B], 2])
        z_min = min(z_min, z)
        if seg_i[s, L.SI_MAT] == material:
            z_mat = min(z_mat, z)
        length += seg_f[s, L.SF_L0]
    return z_min, z_mat, length


@numba.njit(cache=True, nogil=True)
def measure_scene(model, state, t, spec, out):
    """The ``M_*`` quantities of a scene at time ``t`` [s] into ``out`` (the lines' top tensions
    ``state.top_tension`` [N] already evaluated at this state); ``spec`` names the release node, the line and
    material to summarise, the wire line and the vessel whose heave is read (``SPEC_*``, -1: none)."""
    env_f, node_pos, node_vel = model.env_f, state.node_pos, state.node_vel
    body_state, top_tension = state.body_state, state.top_tension
    ex = body_state[L.BS_AXIS]
    ey = body_state[L.BS_AXIS + 1]
    ez = body_state[L.BS_AXIS + 2]
    wx = body_state[L.BS_OMEGA]
    wy = body_state[L.BS_OMEGA + 1]
    wz = body_state[L.BS_OMEGA + 2]
    w_axial = wx * ex + wy * ey + wz * ez
    out[M_TILT_DEG] = tilt_deg(ez)
    out[M_AXIS_RATE_DEG_S] = math.degrees(math.sqrt((wx - w_axial * ex) ** 2 + (wy - w_axial * ey) ** 2
                                                    + (wz - w_axial * ez) ** 2))
    out[M_HEAVE_M] = out[M_HEAVE_RATE_M_S] = 0.0
    if spec[SPEC_VESSEL] >= 0:
        _, _, hz, _, _, hvz = track_state(model.tracks, spec[SPEC_VESSEL], t, env_f)
        out[M_HEAVE_M] = hz
        out[M_HEAVE_RATE_M_S] = hvz
    cx, cy, _ = current_velocity(0.0, env_f, model.current_profile)
    out[M_CURRENT_X_M_S] = cx
    out[M_CURRENT_Y_M_S] = cy
    out[M_TIP_Z_M] = body_state[L.BS_POS + 2] + model.body_f[L.BF_S_TIP] * ez
    out[M_LOOP_Z_M] = out[M_FIBRE_Z_M] = math.inf
    out[M_LINE_L0_M] = out[M_LINE_TENSION_N] = 0.0
    if spec[SPEC_LINE] >= 0:
        loop_z, fibre_z, length = line_summary(node_pos, state.seg_i, state.seg_f, state.line_i, spec[SPEC_LINE],
                                               spec[SPEC_MATERIAL])
        out[M_LOOP_Z_M] = loop_z
        out[M_FIBRE_Z_M] = fibre_z
        out[M_LINE_L0_M] = length
        out[M_LINE_TENSION_N] = top_tension[spec[SPEC_LINE]]
    out[M_WIRE_TENSION_N] = top_tension[spec[SPEC_WIRE]] if spec[SPEC_WIRE] >= 0 else 0.0
    node = spec[SPEC_RELEASE_NODE]
    for c in range(3):
        out[M_RELEASE_POS + c] = node_pos[node, c] if node >= 0 else 0.0
        out[M_RELEASE_VEL + c] = node_vel[node, c] if node >= 0 else 0.0


class SlotBuffers:
    """An env slot's arrays for the batch kernel besides its simulator's.

    Parameters
    ----------
    spec : sequence of int
        What :func:`measure_scene` measures (``SPEC_*`` order: release node, line and material to summarise, wire
        line, vessel; -1 for none).
    state : SimState, optional
        A state of the simulation's shapes: the backup's buffers are made like it (needed for an advance with
        ``take_backup``).

    Attributes
    ----------
    measures : ndarray (N_MEASURES,)
        The ``M_*`` quantities the kernel measured after the last advance that did not blow up.
    record :
        The simulator's loads record (``Simulator.loads_record``) the measures belong to: they are current while it
        still is.
    backup : SimState or None
        The state before the last advance that took a backup (its ``t`` and ``released`` set by the caller).
    """

    __slots__ = ("spec", "measures", "record", "backup", "_values", "_values_record")

    def __init__(self, spec, state: SimState | None = None) -> None:
        self.spec = np.array(spec, dtype=np.int64).reshape(N_SPEC)
        self.measures = np.full(N_MEASURES, np.nan)
        self.record = None
        self.backup = None if state is None else state.copy()
        self._values: list[float] = []
        self._values_record = None

    def current_measures(self, sim: Simulator) -> list[float] | None:
        """The measures as Python floats if they are of ``sim``'s current state (nothing changed it since the kernel
        measured), else None. Converted once per advance (an env step reads them several times), so the list is shared:
        read it, do not change it."""
        record = self.record
        if record is None or sim.loads_record() is not record:
            return None
        if self._values_record is not record:
            self._values = self.measures.tolist()
            self._values_record = record
        return self._values


def slot_buffers(sim: Simulator, lines: dict[str, int], fibre_mat: int, backup: bool) -> SlotBuffers:
    """The kernel's buffers for ``sim``: measure what the observation reads (the mooring line summarised with the
    fibre, material ``fibre_mat``, as the material), and a backup of the state where pre-release advances may
    take one. ``lines``: line indices by name."""
    spec = [0] * N_SPEC
    spec[SPEC_RELEASE_NODE] = sim.model.release_node
    spec[SPEC_LINE] = lines["mooring_line"]
    spec[SPEC_MATERIAL] = fibre_mat
    spec[SPEC_WIRE] = lines.get("wire", -1)
    spec[SPEC_VESSEL] = VESSEL_INSTALLATION
    return SlotBuffers(spec, sim.state if backup else None)


def kernel_measures(sim: Simulator, buffers: SlotBuffers) -> list[float]:
    """The kernel's ``M_*`` measures of the current state (:func:`measure_scene`), measured
    here where the state is not the one the kernel left (a reset without a warm-up)."""
    measured = buffers.current_measures(sim)
    if measured is None:
        sim.top_tensions_n()  # the loads, where they are not current
        measure_scene(*sim.records(), sim.state.t, buffers.spec, buffers.measures)
        measured = buffers.measures.tolist()
    return measured


def mooring_line(sim: Simulator, buffers: SlotBuffers, line: int, fibre_mat: int) -> tuple[float, float, float]:
    """:func:`line_summary` of the mooring line (index ``line``) with the fibre as the
    material: lowest node z, lowest fibre node z, unstretched length [m]. The kernel's measure where it is current
    (every step after its advance), else evaluated here (after a reset without a warm-up or an in-place change
    such as the release)."""
    m = buffers.current_measures(sim)
    if m is not None:
        return m[M_LOOP_Z_M], m[M_FIBRE_Z_M], m[M_LINE_L0_M]
    st = sim.state
    return line_summary(st.node_pos, st.seg_i, st.seg_f, st.line_i, line, fibre_mat)


def spacing_m(sim: Simulator) -> float:
    """Distance between the two vessels' mean positions [m]."""
    v = sim.vessel_mean_m
    return float(v[VESSEL_SECOND, 0] - v[VESSEL_INSTALLATION, 0])


def max_tensions_n(sim: Simulator, lines: dict[str, int]) -> dict[str, float]:
    """Running maximum tension of each line by name [N] (``lines``: line indices by name)."""
    maxima = sim.state.line_f[:, L.LF_MAX_TENSION].tolist()
    return {name: maxima[i] for name, i in lines.items()}


def touchdown(sim: Simulator, target_xy: np.ndarray, chain_material: str) -> dict[str, float]:
    """The anchor's touchdown: speed, vertical speed, tilt, horizontal offset of the tip from ``target_xy``, fall
    time, chain (of ``chain_material``) on the seabed and how far the vertical chain has fallen past the anchor's
    back end."""
    td = sim.work.touchdown
    vel = td[L.TD_VEL:L.TD_VEL + 3]
    speed = float(np.linalg.norm(vel))
    tilt = float(tilt_deg(td[L.TD_AXIS + 2]))
    offset = float(np.hypot(td[L.TD_TIP] - target_xy[0], td[L.TD_TIP + 1] - target_xy[1]))
    pile = float(sim.line_length_on_seabed_m({chain_material}))
    return {"speed_m_s": speed, "vertical_speed_m_s": float(-vel[2]), "tilt_deg": tilt,
            "offset_m": offset, "fall_time_s": float(td[L.TD_TIME] - sim.release_time_s),
            "chain_on_seabed_m": pile, "chain_past_back_end_m": sim.line_past_back_end_m("vertical_chain")[0]}

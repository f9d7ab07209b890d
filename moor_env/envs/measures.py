"""What an episode slot reads from its simulator: the kernel's measures, the mooring line, loads, touchdown.

Every reading here is a pure function of the simulator's state (and the slot's buffers of the batch kernel,
:class:`~moor_env.envs.batch.SlotBuffers`): the observation, the reward's :class:`~moor_env.envs.reward.StepRecord`
and the step info are made of them.
"""

from __future__ import annotations

import numpy as np

from moor_env.compile import VESSEL_INSTALLATION, VESSEL_SECOND
from moor_env.envs import batch as B
from moor_env.envs.batch import SlotBuffers, line_summary, measure_scene
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg
from moor_env.simulation import Simulator


def slot_buffers(sim: Simulator, lines: dict[str, int], fibre_mat: int, backup: bool) -> SlotBuffers:
    """The kernel's buffers for ``sim``: measure what the observation reads (the mooring line summarised with the
    fibre, material ``fibre_mat``, as the material), and a backup of the state where pre-release advances may
    take one. ``lines``: line indices by name."""
    spec = [0] * B.N_SPEC
    spec[B.SPEC_RELEASE_NODE] = sim.model.release_node
    spec[B.SPEC_LINE] = lines["mooring_line"]
    spec[B.SPEC_MATERIAL] = fibre_mat
    spec[B.SPEC_WIRE] = lines.get("wire", -1)
    spec[B.SPEC_VESSEL] = VESSEL_INSTALLATION
    return SlotBuffers(spec, sim.state if backup else None)


def kernel_measures(sim: Simulator, buffers: SlotBuffers) -> list[float]:
    """The kernel's ``M_*`` measures of the current state (:func:`moor_env.envs.batch.measure_scene`), measured
    here where the state is not the one the kernel left (a reset without a warm-up)."""
    measured = buffers.current_measures(sim)
    if measured is None:
        sim.top_tensions_n()  # the loads, where they are not current
        measure_scene(*sim.records(), sim.state.t, buffers.spec, buffers.measures)
        measured = buffers.measures.tolist()
    return measured


def mooring_line(sim: Simulator, buffers: SlotBuffers, line: int, fibre_mat: int) -> tuple[float, float, float]:
    """:func:`~moor_env.envs.batch.line_summary` of the mooring line (index ``line``) with the fibre as the
    material: lowest node z, lowest fibre node z, unstretched length [m]. The kernel's measure where it is current
    (every step after its advance), else evaluated here (after a reset without a warm-up or an in-place change
    such as the release)."""
    m = buffers.current_measures(sim)
    if m is not None:
        return m[B.M_LOOP_Z_M], m[B.M_FIBRE_Z_M], m[B.M_LINE_L0_M]
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

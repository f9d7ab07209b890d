"""Checks of a static equilibrium before it is accepted: the fibre rope clear of the seabed, the lines clear of
the anchor (``moor_env.simulation.solve_statics`` refuses an equilibrium that fails them).
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.errors import NoEquilibrium, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics._jit import jit
from moor_env.physics.anchor_surface import surface_distance
from moor_env.physics.contact import may_touch

ANCHOR_CLEARANCE_M = 0.05  # deepest a line node may lie inside the anchor in an equilibrium that is accepted


def fibre_material(model) -> int:
    """The mooring line's fibre rope's row of the material table (``MF_*`` columns), or -1 without one."""
    if "mooring_line" not in model.lines or model.scene.installation.fibre_material not in model.material_names:
        return -1
    return model.material_names.index(model.scene.installation.fibre_material)


def fibre_nodes(sim) -> np.ndarray:
    """Which nodes belong to the mooring line's fibre rope (the ends of its active fibre segments): a boolean mask
    over the nodes, all False without a fibre."""
    m = sim.model
    st = sim.state
    nodes = np.zeros(st.node_pos.shape[0], dtype=bool)
    fibre = fibre_material(m)
    if fibre < 0:
        return nodes
    line = m.lines["mooring_line"].index
    start, nseg = st.line_i[line, L.LI_SEG_START], st.line_i[line, L.LI_NSEG]
    segs = st.seg_i[start:start + nseg]
    segs = segs[(segs[:, L.SI_ACTIVE] == 1) & (segs[:, L.SI_MAT] == fibre)]
    nodes[segs[:, L.SI_A]] = True
    nodes[segs[:, L.SI_B]] = True
    return nodes


def fibre_on_seabed(sim) -> tuple[int, float]:
    """The mooring line's fibre rope against the seabed in the simulator's state: how many of its nodes lie below
    the seabed (resting on it) and the height of its lowest node above the seabed [m] (inf without a fibre)."""
    nodes = fibre_nodes(sim)
    if not nodes.any():
        return 0, math.inf
    height = sim.state.node_pos[nodes, 2] + sim.env_f[L.EF_DEPTH]
    return int(np.count_nonzero(height < 0.0)), float(np.min(height))


def fibre_refusal(sim, where: str = "") -> NoEquilibrium:
    """The refusal of a scene whose fibre rope would rest on the seabed; ``where``: the state it was found in, in
    words (appended to the cause)."""
    inst = sim.model.scene.installation
    return NoEquilibrium("installation.mooring_line_length_m", inst.mooring_line_length_m,
                         "a shorter line or a larger vessel_spacing_m",
                         "the fibre rope would rest on the seabed" + (f" ({where})" if where else ""))


def check_fibre_clearance(sim) -> None:
    """Refuse an equilibrium in which the mooring line's fibre rope rests on the seabed (it must not touch it).

    Raises
    ------
    NoEquilibrium
    """
    if fibre_on_seabed(sim)[0] > 0:
        raise fibre_refusal(sim)


@jit
def deepest_inside_anchor(node_pos, node_i, body_state, shape, seabed_z):
    """The deepest a free node above the seabed (``seabed_z`` [m]) lies inside the anchor's surface [m] (0 where
    none does) and that node (-1 where none does); the contact law's surface (``physics/anchor_surface.py``)."""
    deepest = 0.0
    node = -1
    for n in range(node_i.shape[0]):
        if not may_touch(node_pos, node_i, n, body_state, shape, seabed_z):
            continue
        depth = -surface_distance(node_pos[n, 0], node_pos[n, 1], node_pos[n, 2], body_state, shape)[0]
        if depth > deepest:
            deepest = depth
            node = n
    return deepest, node


def check_anchor_clearance(sim, solver: str = "newton") -> None:
    """Refuse an equilibrium in which a line lies more than ``ANCHOR_CLEARANCE_M`` inside the anchor where the
    scene models their contact. From Newton's method, which solves the contact, it means a load the contact's
    stiffness cannot carry (the penalty holds a resting line within millimetres); from the relaxation solver
    (``solver="relaxation"``), which leaves the contact out, a loop hanging through the anchor.

    Raises
    ------
    NoEquilibrium
        From Newton's method, naming ``discretization.contact_stiffness_scale``.
    StaticsNotConverged
        From the relaxation solver.
    """
    if sim.model.contact_f[L.CF_ON] == 0.0:
        return
    depth_m, line = anchor_intrusion(sim)
    if depth_m <= ANCHOR_CLEARANCE_M:
        return
    name = (line or "line").replace("_", " ")
    if solver == "relaxation":
        raise StaticsNotConverged(f"the relaxation solver leaves the line-anchor contact out, and its equilibrium "
                                  f"hangs the {name} {depth_m:.2g} m through the anchor (a larger "
                                  "installation.vessel_spacing_m keeps the loop clear of it)", None, True)
    scale = sim.model.scene.discretization.contact_stiffness_scale
    raise NoEquilibrium("discretization.contact_stiffness_scale", scale, "a stiffer line-anchor contact",
                        f"the {name} would press {depth_m:.2g} m into the anchor")


def anchor_intrusion(sim) -> tuple[float, str]:
    """How deep the deepest line node lies inside the anchor [m] and its line's name ("" where none does, or
    without an anchor)."""
    m, st = sim.model, sim.state
    if not m.body_active:
        return 0.0, ""
    depth, node = deepest_inside_anchor(st.node_pos, st.node_i, st.body_state, m.contact_shape,
                                        -float(sim.env_f[L.EF_DEPTH]))
    names = {line.index: name for name, line in m.lines.items()}
    segs = np.nonzero((st.seg_i[:, L.SI_A] == node) | (st.seg_i[:, L.SI_B] == node))[0]
    return depth, names.get(int(st.seg_i[segs[0], L.SI_LINE]), "") if node >= 0 and segs.size else ""

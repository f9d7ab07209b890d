"""Analytic first guess of the relaxation solver: node positions and anchor pose from elastic catenaries without
current (``physics/catenary.py``), so that its Newton solve starts with every line in tension.
"""

from __future__ import annotations

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics.catenary import Section, shape, solve_grounded, solve_suspended, trim
from moor_env.physics.statics_guess import change_line_length


def _line_sections(sim, line_name: str) -> tuple[list, np.ndarray]:
    """Catenary sections and the unstretched arc length of each interior node of a line (bottom to top)."""
    st, m = sim.state, sim.model
    idx = m.lines[line_name].index
    start, nseg = st.line_i[idx, L.LI_SEG_START], st.line_i[idx, L.LI_NSEG]
    g = sim.env_f[L.EF_G]
    sections: list = []
    for s in range(start, start + nseg):
        mat = st.seg_i[s, L.SI_MAT]
        w = m.mat_f[mat, L.MF_SUBMERGED] * g
        ea = m.mat_f[mat, L.MF_EA]
        if sections and sections[-1].weight_n_m == w and sections[-1].ea_n == ea:
            sections[-1] = Section(w, ea, sections[-1].length_m + st.seg_f[s, L.SF_L0])
        else:
            sections.append(Section(w, ea, st.seg_f[s, L.SF_L0]))
    arcs = np.cumsum(st.seg_f[start:start + nseg, L.SF_L0])[:-1]
    return sections, arcs


def _place_line(sim, line_name: str, origin: np.ndarray, h: float, v_a: float, direction: float = 1.0) -> None:
    """Put a line's interior nodes on the catenary (H, V_A) starting at ``origin`` (its bottom end)."""
    st, m = sim.state, sim.model
    sections, arcs = _line_sections(sim, line_name)
    x, z = shape(h, v_a, sections, arcs)
    idx = m.lines[line_name].index
    nodes = st.line_i[idx, L.LI_NODE_START] + np.arange(arcs.size)
    st.node_pos[nodes, 0] = origin[0] + direction * x
    st.node_pos[nodes, 1] = origin[1]
    st.node_pos[nodes, 2] = origin[2] + z


def first_guess(sim) -> None:
    """Set the simulator's node positions and anchor pose to an analytic estimate of the equilibrium
    (elastic catenaries without current), so that the Newton solve starts with every line in tension."""
    m = sim.model
    if m.scene.kind == "catenary_line":
        _guess_catenary_line(sim)
    elif m.release_node >= 0:
        _guess_installation(sim)


def _guess_catenary_line(sim) -> None:
    st, m = sim.state, sim.model
    idx = m.lines["line"].index
    a = st.node_pos[st.line_i[idx, L.LI_BOTTOM]].copy()
    b = st.node_pos[st.line_i[idx, L.LI_TOP]].copy()
    dx, dz = float(b[0] - a[0]), float(b[2] - a[2])
    sections, arcs = _line_sections(sim, "line")
    grounded = solve_grounded(dx, dz, sections) if abs(a[2] + sim.env_f[L.EF_DEPTH]) < 1e-6 else None
    if grounded is None:
        h, v_a = solve_suspended(dx, dz, sections)
        _place_line(sim, "line", a, h, v_a)
        return
    h, length_on_bottom = grounded
    rest = trim(sections, length_on_bottom)
    x_s, z_s = shape(h, 0.0, rest, np.maximum(arcs - length_on_bottom, 0.0))
    ea0 = sections[0].ea_n
    on_bottom = arcs <= length_on_bottom
    x = np.where(on_bottom, arcs * (1.0 + h / ea0), length_on_bottom * (1.0 + h / ea0) + x_s)
    z = np.where(on_bottom, 0.0, z_s)
    nodes = st.line_i[idx, L.LI_NODE_START] + np.arange(arcs.size)
    st.node_pos[nodes, 0] = a[0] + x
    st.node_pos[nodes, 2] = a[2] + z


def _guess_installation(sim) -> None:
    st, m = sim.state, sim.model
    g = sim.env_f[L.EF_G]
    rho = sim.env_f[L.EF_RHO]
    release = st.node_pos[m.release_node].copy()
    anchor_weight = m.anchor_submerged_mass_kg * g
    vc_sections, _ = _line_sections(sim, "vertical_chain")
    hang = anchor_weight + sum(s.weight_n_m * s.length_m for s in vc_sections)
    h_m = v_m = 0.0
    if m.wire_end_node >= 0:
        ru = st.node_f[m.wire_end_node]
        hang += (ru[L.NF_POINT_MASS] - rho * ru[L.NF_POINT_VOLUME]) * g
        wire = m.lines["wire"].index
        top_a = st.node_pos[st.line_i[wire, L.LI_TOP]]
        target_tip_z = -sim.env_f[L.EF_DEPTH] + m.scene.installation.drop_height_m
        vc_total = sum(s.length_m for s in vc_sections)
        _, vc_rise = shape(0.0, anchor_weight, vc_sections, np.array([vc_total]))
        for _ in range(50):
            wire_sections, _ = _line_sections(sim, "wire")
            if "mooring_line" in m.lines:
                ml_sections, _ = _line_sections(sim, "mooring_line")
                top_b = st.node_pos[st.line_i[m.lines["mooring_line"].index, L.LI_TOP]]
                h_m, v_m = solve_suspended(float(top_b[0] - release[0]), float(top_b[2] - release[2]), ml_sections)
            # the wire holds the release node against the chain below and the mooring line beside it
            h_w, v_w = h_m, hang - v_m
            x_w, z_w = shape(h_w, v_w, wire_sections, np.array([sum(s.length_m for s in wire_sections)]))
            new = np.array([top_a[0] + x_w[0], 0.0, top_a[2] - z_w[0]])
            moved = float(np.linalg.norm(new - release))
            release = new
            tip_error = release[2] - vc_rise[0] - m.body_f[L.BF_LENGTH] - target_tip_z
            change_line_length(st, wire, tip_error)
            if moved < 1e-7 and abs(tip_error) < 1e-7:
                break
        st.node_pos[m.release_node] = release
        _place_line(sim, "wire", release, h_w, v_w, direction=-1.0)
    if "mooring_line" in m.lines:
        _place_line(sim, "mooring_line", release, h_m, v_m)
    # vertical chain hangs straight below the release point, stretched by the anchor and its own weight
    total = sum(s.length_m for s in vc_sections)
    _, z_top = shape(0.0, anchor_weight, vc_sections, np.array([total]))
    back = release - np.array([0.0, 0.0, z_top[0]])
    _place_line(sim, "vertical_chain", back, 0.0, anchor_weight)
    b = st.body_state
    b[L.BS_POS: L.BS_POS + 3] = back - m.body_f[L.BF_S_BACK] * b[L.BS_AXIS: L.BS_AXIS + 3]

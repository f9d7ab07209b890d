"""First guess of the static solver: every line on its elastic catenary, the anchor hanging below its chain.

The installation's lines meet at the release point R: the vertical chain hangs from it with the anchor, the
mooring line runs from it to the second vessel, and the wire holds it from the installation vessel. R's
horizontal position follows from the balance of the wire and the mooring line (each a catenary with the same
horizontal force), its height from the drop height (anchor tip ``drop_height_m`` above the seabed); the wire's
unstretched length is set so that it reaches there. The fixed-point rounds of this balance run in one kernel
(:func:`balance_rounds`: each round hangs the mooring line with ``catenary_kernels.hang_line`` and walks the wire).
Current is left to the Newton solve.

Scenes with no equilibrium are refused here, before any Newton iteration (:class:`moor_env.errors.NoEquilibrium`):
a release point that the drop height puts above the installation vessel's fairlead, and a mooring line so short
that it would have to carry more than its minimum breaking load.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.errors import NoEquilibrium
from moor_env.physics import layout as L
from moor_env.physics._jit import jit
from moor_env.physics.catenary_kernels import hang_line, walk, walk_arcs
from moor_env.physics.discrete_catenary import discrete_grounded, discrete_hang
from moor_env.physics.loads import set_constrained_nodes

BALANCE_ROUNDS = 60
MIN_WIRE_M = 1.0  # shortest wire the solver accepts between the installation vessel and the release point


def line_arrays(sim, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sections of a line from its bottom end (weight [N/m], EA [N], length [m], MBL [N], material index) and the
    unstretched arc length of each interior node from the bottom [m]."""
    st, m = sim.state, sim.model
    idx = m.lines[name].index
    start, nseg = st.line_i[idx, L.LI_SEG_START], st.line_i[idx, L.LI_NSEG]
    mats = st.seg_i[start:start + nseg, L.SI_MAT]
    lengths = st.seg_f[start:start + nseg, L.SF_L0]
    breaks = np.nonzero(np.diff(mats))[0] + 1
    first = np.concatenate([[0], breaks])
    sec_mat = mats[first]
    sec_len = np.add.reduceat(lengths, first)
    g = sim.env_f[L.EF_G]
    sec_w = m.mat_f[sec_mat, L.MF_SUBMERGED] * g
    sec_ea = m.mat_f[sec_mat, L.MF_EA]
    arcs = np.cumsum(lengths)[:-1]
    return sec_w, sec_ea, sec_len, sec_mat, arcs


def _interior_nodes(sim, name: str) -> np.ndarray:
    st, m = sim.state, sim.model
    idx = m.lines[name].index
    return st.line_i[idx, L.LI_NODE_START] + np.arange(st.line_i[idx, L.LI_NSEG] - 1)


def _hang(sim, name: str, a: np.ndarray, b: np.ndarray, place: bool) -> tuple[float, float, float, int]:
    """Hang a line from point a (its bottom end) to b; returns (H, V_A, top tension) [N] of the continuous elastic
    catenary and its mode (``catenary.hang_line``: 0 suspended, 1 grounded, 2 folded on the seabed) and, with
    ``place``, puts its interior nodes where the discrete model is in equilibrium
    (``physics/discrete_catenary.py``): its segments are chords, shorter than the arcs of a tightly curved
    catenary, and near a touchdown with little horizontal force the catenary bends within one segment."""
    sec_w, sec_ea, sec_len, _, arcs = line_arrays(sim, name)
    horizontal = b[:2] - a[:2]
    dx = float(np.hypot(*horizontal))
    u = horizontal / dx if dx > 1e-9 else np.array([1.0, 0.0])
    seabed_dz = min(-sim.env_f[L.EF_DEPTH] - float(a[2]), 0.0)
    if not place:  # the forces only: no interior points to walk to
        arcs = arcs[:0]
    out = np.zeros((arcs.size, 2))
    dz = float(b[2] - a[2])
    h, v_a, mode = hang_line(dx, dz, seabed_dz, sec_w, sec_ea, sec_len, arcs, out)
    if place:
        _discrete_shape(sim, name, out, h, v_a, mode, dx, dz, seabed_dz)
        nodes = _interior_nodes(sim, name)
        pos = sim.state.node_pos
        pos[nodes, 0] = a[0] + u[0] * out[:, 0]
        pos[nodes, 1] = a[1] + u[1] * out[:, 0]
        pos[nodes, 2] = a[2] + out[:, 1]
    top = math.hypot(h, v_a + float(np.sum(sec_w * sec_len)))
    return h, v_a, top, mode


def _discrete_shape(sim, name: str, out: np.ndarray, h: float, v_a: float, mode: int, dx: float, dz: float,
                    seabed_dz: float) -> None:
    """Replace the continuous shape in ``out`` by the discrete model's equilibrium: hanging free where it stays
    clear of the seabed, else across the seabed from the touchdown nodes nearest the catenary's (the discrete
    line may hang clear where the catenary just touches, and touch where it just hangs clear)."""
    node_w, seg_l0, seg_ea = _lumped(sim, name)
    walked = np.zeros((seg_l0.size, 2))
    if mode == 0:
        _, _, ok = discrete_hang(dx, dz, h, v_a, node_w, seg_l0, seg_ea, walked)
        if ok and np.min(walked[:, 1]) >= seabed_dz:
            out[:] = walked[:-1]
            return
    n = seg_l0.size
    if n >= 3:
        low = np.nonzero(out[:, 1] <= seabed_dz + 1e-9)[0]
        lowest = int(np.argmin(out[:, 1]))
        t_a, t_b = (int(low[0]) + 1, int(low[-1]) + 1) if low.size else (lowest + 1, lowest + 1)
        grounded = np.zeros_like(out)
        _, _, found = discrete_grounded(dx, dz, seabed_dz, h, min(max(t_a, 1), n - 1), min(max(t_b, 1), n - 1),
                                        node_w, seg_l0, seg_ea, grounded)
        if found:
            out[:] = grounded
            return
    if mode != 0:
        _, _, ok = discrete_hang(dx, dz, h, v_a, node_w, seg_l0, seg_ea, walked)
        if ok and np.min(walked[:, 1]) >= seabed_dz:
            out[:] = walked[:-1]


def _lumped(sim, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per segment of a line from its bottom: weight of the node at its start [N] (half of each neighbouring
    segment's submerged weight), unstretched length [m], EA [N]."""
    st, m = sim.state, sim.model
    idx = m.lines[name].index
    start, nseg = st.line_i[idx, L.LI_SEG_START], st.line_i[idx, L.LI_NSEG]
    mats = st.seg_i[start:start + nseg, L.SI_MAT]
    seg_l0 = st.seg_f[start:start + nseg, L.SF_L0].copy()
    half = 0.5 * m.mat_f[mats, L.MF_SUBMERGED] * sim.env_f[L.EF_G] * seg_l0
    node_w = np.zeros(nseg)
    node_w[1:] = half[:-1] + half[1:]
    return node_w, seg_l0, m.mat_f[mats, L.MF_EA].copy()


def _hang_vertical(sim, name: str, bottom: np.ndarray, bottom_force_n: float) -> float:
    """Hang a line straight up from ``bottom`` carrying ``bottom_force_n`` there; returns its stretched height."""
    sec_w, sec_ea, sec_len, _, arcs = line_arrays(sim, name)
    out = np.zeros((arcs.size, 2))
    walk_arcs(0.0, bottom_force_n, sec_w, sec_ea, sec_len, arcs, out)
    sim.state.node_pos[_interior_nodes(sim, name)] = bottom + out[:, 1, None] * np.array([0.0, 0.0, 1.0])
    return walk(0.0, bottom_force_n, sec_w, sec_ea, sec_len, 0.0, float(np.sum(sec_len)))[1]


def first_guess(sim) -> int:
    """Set the simulator's node positions and anchor pose to the elastic-catenary estimate of the equilibrium;
    returns the mooring line's shape mode (0 suspended, 1 grounded, 2 folded; 0 without one).

    Raises
    ------
    NoEquilibrium
        The scene has none (the key to change is named).
    """
    st = sim.state
    set_constrained_nodes(*sim.records(), st.t)
    if sim.model.scene.kind == "catenary_line":
        line = sim.model.lines["line"].index
        _hang(sim, "line", st.node_pos[st.line_i[line, L.LI_BOTTOM]].copy(),
              st.node_pos[st.line_i[line, L.LI_TOP]].copy(), place=True)
    elif sim.model.release_node >= 0:
        return _guess_installation(sim)
    return 0


def _guess_installation(sim) -> int:
    st, m = sim.state, sim.model
    sc = m.scene
    g = sim.env_f[L.EF_G]
    anchor_weight = m.anchor_submerged_mass_kg * g
    sec_w, sec_ea, sec_len, _, _ = line_arrays(sim, "vertical_chain")
    vc_rise = walk(0.0, anchor_weight, sec_w, sec_ea, sec_len, 0.0, float(np.sum(sec_len)))[1]
    hang = anchor_weight + float(np.sum(sec_w * sec_len))
    target_z = -sim.env_f[L.EF_DEPTH] + sc.installation.drop_height_m + m.body_f[L.BF_LENGTH] + vc_rise
    release = st.node_pos[m.release_node].copy()
    if m.wire_end_node >= 0:
        rho = sim.env_f[L.EF_RHO]
        unit = st.node_f[m.wire_end_node]
        hang += (unit[L.NF_POINT_MASS] - rho * unit[L.NF_POINT_VOLUME]) * g
        release = _balance_release_point(sim, release, target_z, hang)
    else:
        release[2] = target_z  # the held chain top is placed so that the tip hangs at the drop height
        if "mooring_line" in m.lines:
            _check_mooring_line(sim, release)
    st.node_pos[m.release_node] = release
    mode = 0
    if "mooring_line" in m.lines:
        mode = _hang(sim, "mooring_line", release, _top(sim, "mooring_line"), place=True)[3]
    back = release - np.array([0.0, 0.0, vc_rise])
    _hang_vertical(sim, "vertical_chain", back, anchor_weight)
    b = st.body_state
    b[L.BS_AXIS: L.BS_AXIS + 3] = (0.0, 0.0, -1.0)
    b[L.BS_POS: L.BS_POS + 3] = back - m.body_f[L.BF_S_BACK] * b[L.BS_AXIS: L.BS_AXIS + 3]
    b[L.BS_VEL: L.BS_VEL + 3] = 0.0
    b[L.BS_OMEGA: L.BS_OMEGA + 3] = 0.0
    set_constrained_nodes(*sim.records(), st.t)
    return mode


def _top(sim, name: str) -> np.ndarray:
    st = sim.state
    return st.node_pos[st.line_i[sim.model.lines[name].index, L.LI_TOP]].copy()


def _check_mooring_line(sim, release: np.ndarray) -> tuple[float, float]:
    """(H, V_A) of the mooring line hung from ``release``; refuses a line that would exceed its MBL."""
    h, v_a, top, _ = _hang(sim, "mooring_line", release, _top(sim, "mooring_line"), place=False)
    _, _, _, sec_mat, _ = line_arrays(sim, "mooring_line")
    mbl = float(np.min(sim.model.mat_f[sec_mat, L.MF_MBL]))
    if max(top, math.hypot(h, v_a)) > mbl:
        inst = sim.model.scene.installation
        raise NoEquilibrium("installation.mooring_line_length_m", inst.mooring_line_length_m,
                            "a longer line or a smaller vessel_spacing_m",
                            f"the mooring line is too short: it would carry {max(top, math.hypot(h, v_a)) / 1e6:.3g} "
                            f"MN against its MBL of {mbl / 1e6:.3g} MN")
    return h, v_a


@jit
def balance_rounds(release, u, top_a, top_m, target_z, hang_n, seabed_z, sec_w, sec_ea, sec_len, m_w, m_ea, m_len):
    """Fixed-point rounds of the release point's balance (at most ``BALANCE_ROUNDS``): the mooring line (sections
    ``m_*``, none without one) hung from ``release`` to its top ``top_m`` gives (H, V) there, and the wire from its
    top ``top_a`` carrying H and the rest of ``hang_n`` [N] reaches the new release point, its unstretched sections
    ``sec_len`` scaled so that it ends at ``target_z``. ``release``, its horizontal direction to the mooring line
    ``u`` and ``sec_len`` are updated in place; returns the mooring line's (H, V) [N] at the release point."""
    no_arcs = np.empty(0)
    no_out = np.empty((0, 2))
    h_m = v_m = 0.0
    for _ in range(BALANCE_ROUNDS):
        if m_len.shape[0] > 0:
            tx, ty = top_m[0] - release[0], top_m[1] - release[1]
            norm = math.hypot(tx, ty)
            h_m, v_m, _ = hang_line(norm, top_m[2] - release[2], min(seabed_z - release[2], 0.0), m_w, m_ea, m_len,
                                    no_arcs, no_out)
            if norm > 1e-9:
                u[0], u[1] = tx / norm, ty / norm
        v_w = max(hang_n - v_m, 1e-3 * hang_n)
        x_w, z_w, _ = walk(h_m, v_w, sec_w, sec_ea, sec_len, 0.0, np.sum(sec_len))
        new_x, new_y = top_a[0] + x_w * u[0], top_a[1] + x_w * u[1]
        error = top_a[2] - z_w - target_z
        sec_len *= 1.0 + error / np.sum(sec_len)
        moved = math.hypot(new_x - release[0], new_y - release[1])
        release[0], release[1], release[2] = new_x, new_y, target_z
        if moved < 1e-6 and abs(error) < 1e-6:
            break
    return h_m, v_m


def _balance_release_point(sim, release: np.ndarray, target_z: float, hang_n: float) -> np.ndarray:
    """Release point where the wire (holding ``hang_n`` below it) balances the mooring line, at ``target_z``;
    sets the wire's unstretched length and places its nodes."""
    st, m = sim.state, sim.model
    wire = m.lines["wire"].index
    top_a = _top(sim, "wire")
    inst = m.scene.installation
    if top_a[2] - target_z < MIN_WIRE_M:
        highest = inst.drop_height_m - (target_z - top_a[2]) - MIN_WIRE_M
        raise NoEquilibrium("installation.drop_height_m", inst.drop_height_m, f"<= {highest:.1f} m",
                            "the anchor cannot hang that high: the release point would be above the installation "
                            "vessel's fairlead")
    sec_w, sec_ea, sec_len, _, arcs = line_arrays(sim, "wire")
    sec_len = sec_len.copy()
    u = np.array([1.0, 0.0])
    mooring = "mooring_line" in m.lines
    m_w, m_ea, m_len = line_arrays(sim, "mooring_line")[:3] if mooring else (sec_w[:0], sec_ea[:0], sec_len[:0])
    h_m, v_m = balance_rounds(release, u, top_a, _top(sim, "mooring_line") if mooring else top_a, target_z, hang_n,
                              -float(sim.env_f[L.EF_DEPTH]), sec_w, sec_ea, sec_len, m_w, m_ea, m_len)
    if mooring:  # the line's strength at the balanced release point, not on the way there
        _check_mooring_line(sim, release)
    start, nseg = st.line_i[wire, L.LI_SEG_START], st.line_i[wire, L.LI_NSEG]
    total = float(np.sum(sec_len))
    st.seg_f[start:start + nseg, L.SF_L0] *= total / float(np.sum(st.seg_f[start:start + nseg, L.SF_L0]))
    arcs = np.cumsum(st.seg_f[start:start + nseg, L.SF_L0])[:-1]
    out = np.zeros((arcs.size, 2))
    walk_arcs(h_m, max(hang_n - v_m, 1e-3 * hang_n), sec_w, sec_ea, sec_len, arcs, out)
    nodes = _interior_nodes(sim, "wire")
    st.node_pos[nodes, 0] = release[0] - out[:, 0] * u[0]
    st.node_pos[nodes, 1] = release[1] - out[:, 0] * u[1]
    st.node_pos[nodes, 2] = release[2] + out[:, 1]
    return release


def change_line_length(state, line: int, delta_m: float) -> None:
    """Lengthen (or shorten) a line's unstretched length by ``delta_m`` by scaling all its segments alike,
    so that no segment leaves the stable length range however large the change (e.g. a 15 m wire stretch
    over 10 m segments)."""
    start, nseg = state.line_i[line, L.LI_SEG_START], state.line_i[line, L.LI_NSEG]
    lengths = state.seg_f[start:start + nseg, L.SF_L0]
    lengths *= 1.0 + delta_m / lengths.sum()


def suspending_offset_m(sim, margin_m: float = 5.0, steps: int = 40) -> float:
    """How much further the second vessel would have to stand from the release point for the mooring line to hang
    clear of the seabed (by ``margin_m``) [m]; 0 where it already does."""
    release = sim.state.node_pos[sim.model.release_node].copy()
    top = _top(sim, "mooring_line")
    horizontal = top[:2] - release[:2]
    dx = float(np.hypot(*horizontal))
    u = horizontal / dx if dx > 1e-9 else np.array([1.0, 0.0])
    total = float(np.sum(line_arrays(sim, "mooring_line")[2]))
    for k in range(steps + 1):
        offset = k * total / steps
        b = top.copy()
        b[:2] = release[:2] + u * (dx + offset)
        lifted = release.copy()
        lifted[2] += margin_m  # the seabed margin: as if the seabed were margin_m higher
        if _hang(sim, "mooring_line", lifted, b + [0.0, 0.0, margin_m], place=False)[3] == 0:
            return offset
    return total

"""Map a simulation state onto another line resolution of the same scene.

Why: the resolution a dart-anchor scene needs is set by the fall. Where the mooring line tightens while the
anchor falls, a coarse chain loop goes taut too early (``tight_line`` in ``configs/fidelity.yaml``); where it
stays slack and at rest the coarse one is within 0.2 % (docs/speed_vs_error.md). In the envs the geometry and
motion that decide the fall's resolution are only known at the release, after the agent has moved the vessel and
the winch. So a calm episode whose loop starts slack runs coarse and, if the loop is tight or moving at the
release, the state is mapped onto the resolution the fall needs (:mod:`moor_env.envs.core`);
``benchmarks/remesh_at_release.py`` measures what the coarse phase and the mapping change (docs/remesh-at-release.md).

The mapping, per line, from its bottom node up: each run of segments of one material keeps its unstretched
length and is split again into equal segments of the length the target model was compiled with for that run
(as :mod:`moor_env.compile` splits it), so mass per metre times length is conserved exactly. Node positions and
velocities are interpolated linearly in the unstretched arc coordinate: a new node inside an old segment lies on
its chord at that segment's strain, so the tension carries over; the sag within one old segment is not known and
is not invented. Connection nodes (anchor back tip, release point, wire end, vessels) and the anchor's state are
copied. Running tension maxima and winch rates carry over.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.compile import Model
from moor_env.physics import layout as L
from moor_env.physics.records import SimState


def remesh_state(state: SimState, source: Model, target: Model) -> SimState:
    """``state`` of a simulation of ``source`` as a state of ``target``, a compile of the same scene at another
    resolution (same lines, materials and connection nodes).

    Raises
    ------
    ValueError
        If the models do not have the same lines and materials, or a line needs more segments than the target
        compiled room for (payout capacity).
    """
    if list(source.lines) != list(target.lines) or source.material_names != target.material_names:
        raise ValueError("remesh needs two compiles of one scene: lines or materials differ")
    out = target.initial_state()
    out.body_state[:] = state.body_state
    out.t, out.released = state.t, state.released
    for name, info in source.lines.items():
        _copy_ends(state, info.index, out, target.lines[name].index)
    for name, info in source.lines.items():
        _remesh_line(state, info.index, out, target, target.lines[name].index, name)
    return out


def _copy_ends(state: SimState, src_line: int, out: SimState, dst_line: int) -> None:
    """Connection nodes of a line: state and kind (a release or a dropped wire changes kinds)."""
    for end in (L.LI_BOTTOM, L.LI_TOP):
        a = state.line_i[src_line, end]
        b = out.line_i[dst_line, end]
        out.node_pos[b] = state.node_pos[a]
        out.node_vel[b] = state.node_vel[a]
        out.node_i[b, L.NI_KIND] = state.node_i[a, L.NI_KIND]


def _runs(seg_i: np.ndarray, seg_f: np.ndarray, start: int, nseg: int) -> list[tuple[int, float, int]]:
    """(material, unstretched length [m], segment count) of each run of one material, bottom up."""
    runs: list[tuple[int, float, int]] = []
    for s in range(start, start + nseg):
        mat, l0 = int(seg_i[s, L.SI_MAT]), float(seg_f[s, L.SF_L0])
        if runs and runs[-1][0] == mat:
            runs[-1] = (mat, runs[-1][1] + l0, runs[-1][2] + 1)
        else:
            runs.append((mat, l0, 1))
    return runs


def _new_lengths(runs: list[tuple[int, float, int]], target_runs: list[tuple[int, float, int]], name: str
                 ) -> tuple[list[float], list[int]]:
    """Segment lengths and materials of the line re-split at the target's segment length of each run."""
    lengths: list[float] = []
    mats: list[int] = []
    for k, (mat, length, _) in enumerate(runs):
        if k >= len(target_runs) or target_runs[k][0] != mat:
            raise ValueError(f"line '{name}': material runs differ between the two resolutions")
        seg_m = target_runs[k][1] / target_runs[k][2]
        n = max(1, math.ceil(length / seg_m - 1e-9))
        lengths += [length / n] * n
        mats += [mat] * n
    return lengths, mats


def _line_nodes(state: SimState, line: int, nseg: int) -> np.ndarray:
    """Global node indices of a line's local nodes 0..nseg (bottom, interior, top)."""
    li = state.line_i[line]
    interior = li[L.LI_NODE_START] + np.arange(nseg - 1)
    return np.concatenate(([li[L.LI_BOTTOM]], interior, [li[L.LI_TOP]])).astype(np.int64)


def _remesh_line(state: SimState, src: int, out: SimState, target: Model, dst: int, name: str) -> None:
    li_src = state.line_i[src]
    li = out.line_i[dst]
    start, cap = int(li[L.LI_SEG_START]), int(li[L.LI_SEG_CAP])
    out.line_f[dst, L.LF_RATE] = state.line_f[src, L.LF_RATE]
    out.line_f[dst, L.LF_MAX_TENSION] = state.line_f[src, L.LF_MAX_TENSION]
    li[L.LI_CLAMPED] = li_src[L.LI_CLAMPED]
    li[L.LI_PAYOUT] = li_src[L.LI_PAYOUT]
    nseg_src = int(li_src[L.LI_NSEG])
    if not state.seg_i[li_src[L.LI_SEG_START], L.SI_ACTIVE]:  # a dropped line stays dropped
        out.seg_i[start:start + cap, L.SI_ACTIVE] = 0
        out.node_i[li[L.LI_NODE_START]:li[L.LI_NODE_START] + li[L.LI_NODE_CAP], L.NI_KIND] = L.NODE_INACTIVE
        return
    runs = _runs(state.seg_i, state.seg_f, int(li_src[L.LI_SEG_START]), nseg_src)
    target_runs = _runs(target.seg_i, target.seg_f, start, int(target.line_i[dst, L.LI_NSEG]))
    lengths, mats = _new_lengths(runs, target_runs, name)
    nseg = len(lengths)
    if nseg > cap:
        raise ValueError(f"line '{name}' needs {nseg} segments at the target resolution; the model has room for {cap}")
    li[L.LI_NSEG] = nseg
    # state along the old line, by unstretched arc coordinate
    old_nodes = _line_nodes(state, src, nseg_src)
    s_old = np.concatenate(([0.0], np.cumsum(state.seg_f[li_src[L.LI_SEG_START]:li_src[L.LI_SEG_START] + nseg_src,
                                                         L.SF_L0])))
    s_new = np.concatenate(([0.0], np.cumsum(lengths)))[1:-1]
    new_nodes = _line_nodes(out, dst, nseg)
    interior = new_nodes[1:-1]
    for c in range(3):
        out.node_pos[interior, c] = np.interp(s_new, s_old, state.node_pos[old_nodes, c])
        out.node_vel[interior, c] = np.interp(s_new, s_old, state.node_vel[old_nodes, c])
    node_start, node_cap = int(li[L.LI_NODE_START]), int(li[L.LI_NODE_CAP])
    out.node_i[node_start:node_start + node_cap, L.NI_KIND] = L.NODE_INACTIVE
    out.node_i[interior, L.NI_KIND] = L.NODE_FREE
    top = new_nodes[-1]
    out.node_pos[node_start + nseg - 1:node_start + node_cap] = out.node_pos[top]
    out.node_vel[node_start + nseg - 1:node_start + node_cap] = 0.0
    # segment table as compile lays it out: active segments first, spares at the top node
    l_nom = out.line_f[dst, L.LF_L_NOM]
    for k in range(cap):
        s = start + k
        if k < nseg:
            out.seg_i[s] = (new_nodes[k], new_nodes[k + 1], mats[k], dst, 1)
            out.seg_f[s, L.SF_L0] = lengths[k]
        else:
            out.seg_i[s] = (top, top, mats[-1], dst, 0)
            out.seg_f[s, L.SF_L0] = l_nom

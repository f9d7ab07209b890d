"""The implicit step's active set: which segments are taut (carry their linearised axial law) during the step.

The set is predicted to the *end* of the step (``physics/implicit.py``): it starts from the segments taut now, and
after each solve :func:`update_active_set` predicts every segment's strain and tension at the end of the step from
the solution; a segment is in the set iff both are positive. Each segment may change set once per step.

Storage: two bits per segment in the flag words of the ordering scratch (bits 2 (s & 31) and 2 (s & 31) + 1 of
word s >> 5 of ``orow[:, OR_FLAGS]``: segment s is taut / has changed set in this step), so the set needs no
array of its own.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics._jit import jit_no_refcount, jit_step
from moor_env.physics.layout import MF_EA, SF_L0, SI_A, SI_ACTIVE, SI_B, SI_MAT
from moor_env.physics.line import axial_tension_n, segment_axis
from moor_env.physics.tree import OR_EFF, OR_FLAGS

SET_TOLERANCE = 1e-6  # strain by which a segment must miss its predicted set before the step is solved again
TURN_TOLERANCE = 1e-4  # end strain beyond its linearisation at which an active segment is linearised again


@jit_step
def is_active(orow, s):
    """Bit 2s of the flag words: segment s is in the active (taut) set (the words hold 32 segments per node;
    a segment beyond that, which no compiled model has, is never active and so stays explicit)."""
    if (s >> 5) >= orow.shape[0]:
        return 0
    return (orow[s >> 5, OR_FLAGS] >> (2 * (s & 31))) & 1


@jit_step
def _is_frozen(orow, s):
    """Bit 2s + 1: segment s has already changed set once in this step."""
    return (orow[s >> 5, OR_FLAGS] >> (2 * (s & 31) + 1)) & 1


@jit_step
def _freeze(orow, s):
    """Freeze segment s in its set for the rest of the step."""
    orow[s >> 5, OR_FLAGS] |= np.int64(1) << (2 * (s & 31) + 1)


@jit_step
def _flip(orow, s):
    """Toggle the active bit of segment s and freeze it for the rest of the step."""
    orow[s >> 5, OR_FLAGS] ^= np.int64(1) << (2 * (s & 31))
    orow[s >> 5, OR_FLAGS] |= np.int64(1) << (2 * (s & 31) + 1)


@jit_step
def chord_point(s, seg_chord, kq, l0):
    """Length [m], unit tangent and transverse stiffness kt [N/m] of segment s at its re-linearisation point
    (``seg_chord[s, :3]``: the end chord a solve predicted, or a direction at a chosen length,
    :func:`_enter_along_end_chord`): kt = T_e / length, T_e = kq (length - l0) its
    elastic tension there (>= 0, so that the block stays positive semi-definite)."""
    dx = seg_chord[s, 0]
    dy = seg_chord[s, 1]
    dz = seg_chord[s, 2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    kt = max(kq * (length - l0), 0.0) / length
    return length, dx / length, dy / length, dz / length, kt


@jit_step
def init_active_set(seg_i, seg_tension, seg_chord, orow):
    """Initial active set: the coupling segments taut at the start of the step; none re-linearised."""
    nn = orow.shape[0]
    for w in range(min(nn, ((seg_i.shape[0] - 1) >> 5) + 1)):
        orow[w, OR_FLAGS] = 0
    for s in range(seg_i.shape[0]):
        seg_chord[s, 3] = 0.0
        if seg_i[s, SI_ACTIVE] == 0 or not (seg_tension[s] > 0.0) or (s >> 5) >= nn:
            continue
        if orow[seg_i[s, SI_A], OR_EFF] != orow[seg_i[s, SI_B], OR_EFF]:
            orow[s >> 5, OR_FLAGS] |= np.int64(1) << (2 * (s & 31))


@jit_no_refcount
def update_active_set(h, model, state, orow):
    """Predict every segment's strain and tension at the end of the step from the solved dv (``state.node_acc``);
    a segment is active (taut) iff both are positive. Returns the number of segments that changed set or were
    linearised again (0: the solve stands).

    Entries and re-linearisations first: while some slack segment is predicted taut or some taut one was turned
    beyond its linearisation (:func:`_pass_active_set`), no taut one leaves the set in the same pass (they are
    judged again on the next solve). A solve that misses a taut segment misplaces the nodes it would have held,
    and the segments beside them can then look compressed; as a segment changes set at most once per step,
    letting them leave on that evidence froze a wrong set. Measured: a hanging chain loop at a 0.5 s step dropped
    five consecutive loop segments from the set while a fibre segment went taut, and the next step stretched them
    105 % (blow-up); at a 0.2 s step a taut polyester segment left while the loop's chain was re-linearised,
    and the next solve stretched it 44 %.
    """
    entries, exits, turns = _pass_active_set(h, model, state, orow, False)
    if entries > 0 or turns > 0 or exits == 0:
        return entries + turns
    return _pass_active_set(h, model, state, orow, True)[1]


@jit_no_refcount
def _pass_active_set(h, model, state, orow, flip_exits):
    """One pass of :func:`update_active_set`: flip the slack segments predicted taut (and, with ``flip_exits``,
    the taut ones predicted slack); returns (entries, exits, turns), the exits counted whether flipped or not.

    The solve holds an active segment to its spring linearised about a point (its chord at the start of the step,
    or the end chord an earlier solve predicted, ``seg_chord``), but the nodes move by h v1, so the segment ends
    at its chord d1 = d0 + h (v_b - v_a + dv_b - dv_a), which for a segment turning at v_perp across itself is
    about (h v_perp)^2 / (2 l0) longer than the linear prediction; the next load evaluation would read EA times
    that stretch, a tension no impulse of the step accounted for. Where the excess strain passes
    ``TURN_TOLERANCE`` and the chord is taut, the segment (first pass only, ``turns``) is linearised again at d1
    and held in the set for the rest of the step: the next solve is one more Newton iteration of backward Euler
    on its spring. Measured on a crew episode's fall (1 m chain, 11.25 ms): a segment going taut while turning at
    15 m/s ended 1.4 % strained (24 MN) after one solve, 0.01 % after two more.
    """
    mat_f, node_pos, node_vel = model.mat_f, state.node_pos, state.node_vel
    seg_i, seg_f, node_acc = state.seg_i, state.seg_f, state.node_acc
    seg_chord = state.seg_chord
    entries = 0
    exits = 0
    turns = 0
    nn = orow.shape[0]
    for s in range(seg_i.shape[0]):
        if seg_i[s, SI_ACTIVE] == 0 or (s >> 5) >= nn:
            continue
        frozen = _is_frozen(orow, s) == 1
        active = is_active(orow, s) == 1
        if frozen and not active:
            continue
        a = seg_i[s, SI_A]
        b = seg_i[s, SI_B]
        ea = orow[a, OR_EFF]
        eb = orow[b, OR_EFF]
        if ea == eb:
            continue
        m = seg_i[s, SI_MAT]
        l0 = seg_f[s, SF_L0]
        relinearised = seg_chord[s, 3] != 0.0
        if relinearised:
            length, qx, qy, qz, kt = chord_point(s, seg_chord, 0.0, l0)
        else:
            length, qx, qy, qz = segment_axis(node_pos, a, b)
        rate0 = ((node_vel[b, 0] - node_vel[a, 0]) * qx + (node_vel[b, 1] - node_vel[a, 1]) * qy
                 + (node_vel[b, 2] - node_vel[a, 2]) * qz) / l0
        ddx = 0.0
        ddy = 0.0
        ddz = 0.0
        if eb >= 0:
            ddx += node_acc[eb, 0]
            ddy += node_acc[eb, 1]
            ddz += node_acc[eb, 2]
        if ea >= 0:
            ddx -= node_acc[ea, 0]
            ddy -= node_acc[ea, 1]
            ddz -= node_acc[ea, 2]
        drate = (ddx * qx + ddy * qy + ddz * qz) / l0
        rate1 = rate0 + drate  # strain rate at the end of the step
        if relinearised:  # linear about the chord p: |p| + (d1 - p) . q
            strain1 = (length - l0) / l0 + (h * rate1 * l0 + (node_pos[b, 0] - node_pos[a, 0] - seg_chord[s, 0]) * qx
                                            + (node_pos[b, 1] - node_pos[a, 1] - seg_chord[s, 1]) * qy
                                            + (node_pos[b, 2] - node_pos[a, 2] - seg_chord[s, 2]) * qz) / l0
        else:
            strain1 = (length - l0) / l0 + h * rate1
        ea_ = mat_f[m, MF_EA]
        t1 = axial_tension_n(mat_f, m, l0, strain1, rate1)
        if active and not flip_exits:
            d1x = node_pos[b, 0] - node_pos[a, 0] + h * (node_vel[b, 0] - node_vel[a, 0] + ddx)
            d1y = node_pos[b, 1] - node_pos[a, 1] + h * (node_vel[b, 1] - node_vel[a, 1] + ddy)
            d1z = node_pos[b, 2] - node_pos[a, 2] + h * (node_vel[b, 2] - node_vel[a, 2] + ddz)
            strain_chord = math.sqrt(d1x * d1x + d1y * d1y + d1z * d1z) / l0 - 1.0
            if strain_chord - strain1 > TURN_TOLERANCE and strain_chord > SET_TOLERANCE:
                seg_chord[s, 0] = d1x
                seg_chord[s, 1] = d1y
                seg_chord[s, 2] = d1z
                seg_chord[s, 3] = 1.0
                turns += 1
                if not frozen:
                    _freeze(orow, s)
                continue
        if frozen:
            continue
        if active:
            if strain1 < -SET_TOLERANCE or t1 < -SET_TOLERANCE * ea_:
                exits += 1
                if flip_exits:
                    _flip(orow, s)
        elif strain1 > SET_TOLERANCE and t1 > SET_TOLERANCE * ea_:
            entries += 1
            _flip(orow, s)
            _enter_along_end_chord(s, h, l0, strain1, node_pos, node_vel, a, b, ddx, ddy, ddz, seg_chord)
    return entries, exits, turns


@jit_step
def _enter_along_end_chord(s, h, l0, strain1, node_pos, node_vel, a, b, ddx, ddy, ddz, seg_chord):
    """Segment s enters the set: where the solve turned its end chord d1 beyond its linear prediction
    ``strain1`` by ``TURN_TOLERANCE``, linearise it at l0 d1 / |d1|, along the direction the solve gave it, so that
    the next solve does not leave it to a turn check and one more solve. Not at d1 itself: the solve without its
    spring overstretched it, and linearised there (at its elastic tension at that length) it held the chain
    back: 40 fresh-geometry falls at a step growing up to 3x landed 0.2 m/s slower on average."""
    d1x = node_pos[b, 0] - node_pos[a, 0] + h * (node_vel[b, 0] - node_vel[a, 0] + ddx)
    d1y = node_pos[b, 1] - node_pos[a, 1] + h * (node_vel[b, 1] - node_vel[a, 1] + ddy)
    d1z = node_pos[b, 2] - node_pos[a, 2] + h * (node_vel[b, 2] - node_vel[a, 2] + ddz)
    d1 = math.sqrt(d1x * d1x + d1y * d1y + d1z * d1z)
    if d1 / l0 - 1.0 - strain1 > TURN_TOLERANCE:
        seg_chord[s, 0] = d1x * l0 / d1
        seg_chord[s, 1] = d1y * l0 / d1
        seg_chord[s, 2] = d1z * l0 / d1
        seg_chord[s, 3] = 1.0

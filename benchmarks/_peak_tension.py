"""Peak line tensions of a drop or an env episode, located along the line and in time, and the replay of the
integration step that made one (used by ``benchmarks/mbl_exceedance.py``)."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
from fall_step import scale_fall_step

from agents.baselines import PLAN_ENV
from agents.policy import EpisodeContext
from moor_env.envs import anchor_plan
from moor_env.envs import core as envcore
from moor_env.physics import layout as L
from moor_env.simulation import Simulator

FALL, PRE_RELEASE = "fall", "pre-release"
SERIES_BIN_S = 0.005  # the fall's series keeps the largest tension of every bin of this length [s]


def update_peaks(sim: Simulator, lines: dict[str, int], peaks: dict, phase: str, t_s: float) -> list[str]:
    """Fold the segment tensions the workspace holds (``sim.work.seg_tension``) into ``peaks[line|phase]``: the
    largest tension [N], its segment, the segment's mid-point along the line from its bottom end [m], ``t_s`` and
    the anchor tip's height above the seabed [m]. Returns the lines whose peak grew."""
    st, tension = sim.state, sim.work.seg_tension
    grew = []
    for name, li in lines.items():
        first, count = st.line_i[li, L.LI_SEG_START], st.line_i[li, L.LI_NSEG]
        if not st.seg_i[first, L.SI_ACTIVE]:
            continue
        seg = tension[first:first + count]
        j = int(np.argmax(seg))
        key = f"{name}|{phase}"
        if seg[j] > peaks.get(key, {}).get("tension_n", 0.0):
            l0 = st.seg_f[first:first + count, L.SF_L0]
            tip_h = float(sim.tip_state()[0][2] + sim.env_f[L.EF_DEPTH]) if sim.model.body_active else None
            peaks[key] = {"tension_n": float(seg[j]), "segment": j, "segments": int(count),
                          "position_m": float(l0[:j].sum() + 0.5 * l0[j]), "t_s": float(t_s), "tip_height_m": tip_h}
            grew.append(name)
    return grew


def fall_peaks(sim: Simulator, max_fall_s: float, step_factor: float = 1.0) -> dict:
    """Release ``sim`` (at its equilibrium) and fall to touchdown one step at a time; the peaks per line."""
    cpu0 = time.process_time()
    sim.set_vessel_motion(0.0, max_fall_s + 1.0, np.zeros(sim.vessel_mean_m.shape[0]))
    sim.release()
    sim.dt *= step_factor
    lines = {name: info.index for name, info in sim.model.lines.items() if name != "wire"}  # dropped at the release
    peaks: dict = {}
    t0, status = sim.state.t, L.STATUS_TIME_LIMIT
    while sim.state.t - t0 < max_fall_s - 0.5 * sim.dt and status != L.STATUS_TOUCHDOWN:
        status, _ = sim.advance_to(sim.state.t + sim.dt, detect_touchdown=True)
        sim.evaluate_loads()
        update_peaks(sim, lines, peaks, FALL, sim.state.t - t0)
    td = sim.work.touchdown
    touched = status == L.STATUS_TOUCHDOWN
    return {"step_ms": sim.dt * 1e3, "nodes": int(np.sum(sim.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE)),
            "speed_m_s": float(np.linalg.norm(td[L.TD_VEL:L.TD_VEL + 3])) if touched else None,
            "mbl_n": {n: float(sim.model.mat_f[sim.state.seg_i[sim.state.line_i[i, L.LI_SEG_START], L.SI_MAT],
                                               L.MF_MBL]) for n, i in lines.items()},
            "peaks": peaks, "cpu_s": time.process_time() - cpu0}


def make_env(overrides: dict, fall_keys: dict | None, step_factor: float):
    """``AnchorPlan-v0`` with env-config ``overrides``, the fall on ``fall_keys`` (None: the env's choice) and at
    ``step_factor`` times its step."""
    env = gym.make(PLAN_ENV, overrides=overrides)
    core = env.unwrapped.core
    if fall_keys is not None:
        core.factory.fall_resolution = lambda scene, spacing_m, length_m, speed_m_s: dict(fall_keys)
    if step_factor != 1.0:
        scale_fall_step(core, step_factor)
    return env


def crew_episode(env, policy, seed: int, keep_states: bool = False, series: bool = False) -> dict:
    """One crew episode with every line's peak before the release and in the fall (times from the release).

    ``keep_states``: also return, per ``line|phase``, the start of the step that first took the line over its MBL
    (of the step that produced its peak where none did): the simulator, state, vessel tracks, environment array
    and step in force then, and the segment (for :func:`replay_step`). ``series``: the
    vertical chain's largest segment tension in every ``SERIES_BIN_S`` of the fall.
    """
    core = env.unwrapped.core
    peaks: dict = {}
    starts: dict = {}
    bins: dict[int, float] = {}
    plain = anchor_plan.run_advance

    def recording(core_, adv, chunk_s=None, on_chunk=None):
        if adv.phase == envcore.PHASE_WARMUP:  # the env's maxima count from the first observation
            return plain(core_, adv, chunk_s, on_chunk)
        phase = FALL if adv.phase == envcore.PHASE_FALL else PRE_RELEASE
        start = [None]

        def snapshot():
            s = core_.sim
            return (s, s.state.copy(), s.tracks.copy(), s.env_f.copy(), adv.dt_s) if keep_states else None

        start[0] = snapshot()

        def record():
            sim = core_.sim
            t_s = sim.state.t - core_.t0
            for name in update_peaks(sim, core_.lines, peaks, phase, t_s):
                key = f"{name}|{phase}"
                if keep_states and (starts.get(key, (None, None, 0.0))[2] <= core_.mbl[name]):
                    starts[key] = (start[0], peaks[key]["segment"], peaks[key]["tension_n"])
            start[0] = snapshot()
            if series and phase == FALL:
                st, vc = sim.state, core_.lines["vertical_chain"]
                first = st.line_i[vc, L.LI_SEG_START]
                k = int((st.t - sim.release_time_s) / SERIES_BIN_S)
                top = float(sim.work.seg_tension[first:first + st.line_i[vc, L.LI_NSEG]].max())
                bins[k] = max(bins.get(k, 0.0), top)

        return plain(core_, adv, adv.dt_s, record)

    anchor_plan.run_advance = recording
    cpu0 = time.process_time()
    try:
        obs, info = env.reset(seed=seed)
        policy.begin_episode(EpisodeContext(PLAN_ENV, None, info["scenario"], seed, obs, info))
        info = env.step(policy.act(obs, info))[4]
    finally:
        anchor_plan.run_advance = plain
    release_s = core.sim.release_time_s - core.t0 if core.released else 0.0
    for p in peaks.values():
        p["t_s"] -= release_s
    sc = core.scenario
    row = {"seed": seed, "hs_m": core.hs, "depth_m": core.depth,
           **{k: sc.get(k) for k in ("vessel_spacing_over_depth", "mooring_line_length_over_depth", "current_scale")},
           "status": info["sim_status"], "speed_m_s": info.get("touchdown", {}).get("speed_m_s"),
           "cpu_s": time.process_time() - cpu0,
           "mbl_ratio": {n: round(v / core.mbl[n], 4) for n, v in info["max_tension_n"].items()},
           "peaks": {k: _rounded({**p, "mbl_ratio": p["tension_n"] / core.mbl[k.split("|")[0]]})
                     for k, p in peaks.items()}}
    if series:
        row["series"] = [[round(k * SERIES_BIN_S, 3), round(v)] for k, v in sorted(bins.items())]
    return (row, {k: v[:2] for k, v in starts.items()}) if keep_states else row


def _rounded(peak: dict) -> dict:
    """A peak record with its numbers to the digits that matter (the results JSON holds hundreds of them)."""
    digits = {"tension_n": 0, "mbl_ratio": 4, "position_m": 2, "t_s": 3, "tip_height_m": 2}
    return {k: round(v, digits[k]) if v is not None else v for k, v in peak.items() if k in digits}


def turn_strain(d0_m: np.ndarray, dv1_m_s: np.ndarray, step_s: float, l0_m: float) -> float:
    """Strain a segment ends a step with beyond what a linearisation about its start direction predicts: its
    nodes move by h v1, so it ends at |d0 + h dv1|, where the linearisation sees |d0| + h dv1 . d0 / |d0|
    (``d0_m``: the segment's vector at the start, ``dv1_m_s``: its nodes' relative end velocity). About
    (h v_perp)^2 / (2 l0^2) for a segment of length l0 turned at v_perp across it."""
    length = float(np.linalg.norm(d0_m))
    linear = length + step_s * float(dv1_m_s @ d0_m) / length
    return (float(np.linalg.norm(d0_m + step_s * dv1_m_s)) - linear) / l0_m


def replay_step(start: tuple, line: str, segment: int, divisions=(1, 2, 4, 8)) -> dict:
    """The step that began at ``start`` (from :func:`crew_episode`) integrated again in 1, 2, 4 and 8 sub-steps.

    Per division: the line's largest segment tension at the start and at the end [N]; the strain of the peak
    segment at its start and end; and the part of its end strain that comes from its turn in the last sub-step:
    both integrators move a node by h v1 (its end velocity), so the segment ends at |d0 + h dv1| while a
    linearisation about its start direction q0 sees |d0| + h dv1 . q0 (d0: the segment before the sub-step, dv1:
    the relative end velocity of its nodes); the difference, times EA, is the tension the turn adds."""
    sim, state, tracks, env_f, step_s = start
    li = sim.model.lines[line].index
    s = int(state.line_i[li, L.LI_SEG_START]) + segment
    first, count = int(state.line_i[li, L.LI_SEG_START]), int(state.line_i[li, L.LI_NSEG])
    a, b = state.seg_i[s, L.SI_A], state.seg_i[s, L.SI_B]
    ea, l0 = sim.model.mat_f[state.seg_i[s, L.SI_MAT], L.MF_EA], state.seg_f[s, L.SF_L0]

    def line_max() -> float:
        sim.evaluate_loads()
        return float(sim.work.seg_tension[first:first + count].max())

    out = []
    for n in divisions:
        sim.state, sim.tracks = state.copy(), tracks.copy()
        sim.env_f[:] = env_f
        sim.dt = step_s / n
        at_start = line_max()
        d0 = None
        for _ in range(n):
            d0 = sim.state.node_pos[b] - sim.state.node_pos[a]
            sim.advance_to(sim.state.t + sim.dt, detect_touchdown=sim.state.released)
        st = sim.state
        d1 = st.node_pos[b] - st.node_pos[a]
        dv1 = st.node_vel[b] - st.node_vel[a]
        turn = turn_strain(d0, dv1, sim.dt, l0)
        out.append({"substeps": n, "step_ms": step_s / n * 1e3, "start_n": at_start, "end_n": line_max(),
                    "start_strain": float(np.linalg.norm(state.node_pos[b] - state.node_pos[a]) / l0 - 1.0),
                    "end_strain": float(np.linalg.norm(d1) / l0 - 1.0), "turn_strain": float(turn),
                    "turn_n": float(ea * turn)})
    lengths = state.seg_f[first:s + 1, L.SF_L0]
    return {"position_m": float(lengths.sum() - 0.5 * lengths[-1]), "runs": out}

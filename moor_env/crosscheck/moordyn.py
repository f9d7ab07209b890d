"""The same dart-anchor drop in MoorDyn-C v2 (PyPI ``moordyn`` 2.7), for cross-code validation.

:func:`run_moordyn_drop` builds a MoorDyn v2 input file from a compiled scene, starts MoorDyn from *our*
static equilibrium (MoorDyn's own stationary and dynamic-relaxation solvers do not converge on these
scenes), releases at t = 0 and steps until the anchor tip reaches the seabed.

The scene's mapping onto MoorDyn (the anchor as a Body with Rods, equivalent line types, the seeded initial
state, MoorDyn's internal line damping switched off by default and why) is described in
:mod:`moor_env.crosscheck.moordyn_input`, which writes the input file.

Other modelling differences that remain
---------------------------------------
1. **Line Morison loads**: MoorDyn evaluates drag and added mass per node with the node tangent (from the two
   neighbouring nodes); we evaluate each half segment with the segment tangent. Same limit as the segments
   shrink; identical on a straight line. Both become arbitrary where slack chain nodes pass each other.
2. **Anchor-end node of the chain**: MoorDyn adds the end node's added mass (half a chain segment, about
   16 kg per metre of segment) to the Body; ours adds its mass but not its added mass (< 2e-4 of the
   anchor's).
3. **Normal drag and added mass along the anchor**: ours integrates by midpoint quadrature
   (``anchor.quadrature_points``) with exact added-mass moments, MoorDyn lumps them on Rod nodes (trapezoid,
   ``rod_segment_m``). Both converge to the same integrals.
4. **Seabed** (only line nodes that reach it before the tip does; ``min_line_z_m`` reports the lowest line
   node at touchdown): MoorDyn's contact area is ``d l`` with the buoyancy diameter ``d``, ours uses D;
   MoorDyn's friction is ``min(mu FricDamp v, mu F_z)``, ours ``mu F_z min(v / v_f, 1)``; ``FricDamp`` is
   set so that both ramps agree for a resting chain node.
5. **Time integration**: ours is symplectic Euler (or RK2) at our stability limit, MoorDyn RK4 at ``dt_s``.
6. **Sensitivity of the slack chain**: where the slack chain piles onto the anchor (gjoa-500 with its 50 m
   vertical chain) MoorDyn's result is nearly chaotic: over time steps of 0.2-0.55 ms its touchdown speed
   scatters between -2.9 % and +0.07 % of ours, and the runs at the low end have buckled sideways (tilt
   0.4-1.3 deg; large, oscillating lateral drag appears at the corner between the vertical chain and the
   loop). Ours varies by < 0.05 % with time step (0.15-0.34 ms) and integrator and stays vertical. The
   vertical-chain case converges in MoorDyn (0.03 % between 0.5 and 0.25 ms); the 170 m / 10 m tilt case
   scatters by -1.0..+0.14 % in speed and 0.03 deg in tilt.

Not supported (raises ``ValueError``): current, waves, a pre-release phase (``release_time_s`` > 0),
payout or spacing rates, ``keep_wire_after_release``.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from moor_env.config import SceneConfig, load_scene
from moor_env.crosscheck.moordyn_input import DEFAULT_ROD_SEGMENT_M, MDLine, build_moordyn_input, check_supported
from moor_env.errors import SimulationDiverged
from moor_env.physics.anchor import tilt_deg
from moor_env.simulation import StaticResult, solve_statics


@contextlib.contextmanager
def _quiet(log_path: Path):
    """Send the C library's stdout/stderr chatter to ``log_path`` (MoorDyn prints on creation)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(log_path, "ab") as fh:
        os.dup2(fh.fileno(), 1)
        os.dup2(fh.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])


def _seed_state(md, state_path: Path, lines: list[MDLine], free_points: dict[int, np.ndarray],
                n_bodies: int, n_rods: int, n_points: int) -> None:
    """Overwrite MoorDyn's saved state with our static positions (zero velocities) and load it back."""
    import moordyn  # noqa: PLC0415 - moordyn (optional: the test and dev extras)

    moordyn.SaveState(md, str(state_path))
    raw = state_path.read_bytes()
    head = raw[:9]  # b"MoorDyn" + major + minor version bytes
    words = np.frombuffer(raw[9:], dtype="<u8").copy()
    values = words.view("<f8")
    n_inst = int(words[1])
    expected = n_bodies + n_rods + n_points + len(lines)
    if n_inst != expected:
        raise RuntimeError(f"unexpected MoorDyn state layout: {n_inst} instances, expected {expected}")
    i = 2
    blocks = []
    for _ in range(n_inst):
        rows, cols = int(words[i]), int(words[i + 1])
        i += 2
        blocks.append((i, rows, cols))
        i += rows * cols
    if i != words.size or int(words[0]) != words.size - 1:
        raise RuntimeError("unexpected MoorDyn state file size")
    for pid, p in free_points.items():
        start, rows, cols = blocks[n_bodies + n_rods + pid - 1]
        block = values[start:start + rows * cols].reshape(rows, cols)
        block[0, :3] = p
        block[0, 3:6] = 0.0
    for k, ln in enumerate(lines):
        start, rows, cols = blocks[n_bodies + n_rods + n_points + k]
        if rows != ln.n_seg - 1 or cols < 6:
            raise RuntimeError(f"unexpected MoorDyn state block for line {k + 1}: {rows} x {cols}")
        block = values[start:start + rows * cols].reshape(rows, cols)
        block[:, :3] = ln.positions[1:-1]
        block[:, 3:] = 0.0
    state_path.write_bytes(head + words.tobytes())
    moordyn.LoadState(md, str(state_path))
    check = state_path.with_suffix(".check")
    moordyn.SaveState(md, str(check))  # what MoorDyn now holds must be exactly what we wrote
    if check.read_bytes() != head + words.tobytes():
        raise RuntimeError("MoorDyn did not take the seeded initial state")


def run_moordyn_drop(scene: str | Path | SceneConfig, dt_s: float | None = None, scheme: str = "rk4",
                     segment_length_m: float | dict[str, float] | None = None,
                     rod_segment_m: float = DEFAULT_ROD_SEGMENT_M, static: StaticResult | None = None,
                     overrides: dict[str, Any] | None = None, max_fall_time_s: float | None = None,
                     damping_ratio: float | None = 0.0, history_interval_s: float | None = None,
                     steps_per_call: int = 20) -> dict[str, Any]:
    """Release the anchor of a scene in MoorDyn from our static equilibrium and fall to touchdown.

    Parameters
    ----------
    scene : str, Path or SceneConfig
        Bundled scene name, YAML path or loaded scene (``overrides`` apply to names and paths).
    dt_s : float, optional
        MoorDyn time step ``dtM`` [s]. Default: 0.7 of the scheme's stability limit (:func:`omega_dt_limit`,
        2.83 for RK4 at zeta <= 0.3) on the fastest axial segment mode, at most 1 ms (0.5 ms for 1 m chain).
    scheme : str
        MoorDyn ``tScheme`` (``rk4`` default; ``rk2`` is MoorDyn's own default).
    segment_length_m : float or dict, optional
        Line segment length: a float applies to the chain material, a dict maps material names to lengths.
        Default: exactly our segments.
    rod_segment_m : float
        Segment length of the anchor Rods (drag/added-mass lumping) [m].
    static : StaticResult, optional
        Our equilibrium of the same scene, to reuse.
    max_fall_time_s : float, optional
        Stop without touchdown after this time [s] (default: ``simulation.max_fall_time_s``).
    damping_ratio : float or None
        MoorDyn internal damping ratio of every line; None uses the scene's ratios (see the module notes
        on why the default is 0).
    history_interval_s : float, optional
        Record the tip state about this often.
    steps_per_call : int
        MoorDyn steps per ``Step`` call from Python while the tip is far from the seabed (fewer calls, less
        Python overhead); near the seabed every call is one step, so the touchdown is interpolated inside
        one ``dtM`` whatever this is.

    Returns
    -------
    dict
        ``status``, ``touchdown_speed_m_s``, ``touchdown_vertical_speed_m_s``, ``tilt_deg`` (from vertical),
        ``touchdown_time_s``, ``drift_m``, ``wall_s`` (stepping only), ``wall_setup_s``, ``dt_s``,
        ``scheme``, ``n_steps``, ``n_line_segments``, ``min_line_z_m`` (lowest line node at touchdown),
        ``line_types`` (the equivalent MoorDyn line types), ``input_text`` and ``history`` (rows of time, tip
        position, tip velocity, axis every ``history_interval_s``; empty without it).

    Raises
    ------
    ValueError
        For scene features the cross-check does not model (current, waves, pre-release phase...).
    SimulationDiverged
        If MoorDyn reports a non-finite state.
    """
    import moordyn  # noqa: PLC0415 - moordyn (optional: the test and dev extras)

    t_setup = time.perf_counter()
    cfg = scene if isinstance(scene, SceneConfig) else load_scene(scene, overrides)
    check_supported(cfg)
    if static is None:
        static = solve_statics(cfg)
    built = build_moordyn_input(cfg, static, dt_s=dt_s, scheme=scheme, segment_length_m=segment_length_m,
                                rod_segment_m=rod_segment_m, damping_ratio=damping_ratio)
    dt_md = built["dt_s"]
    depth = cfg.environment.water_depth_m
    max_fall = cfg.simulation.max_fall_time_s if max_fall_time_s is None else max_fall_time_s
    lines: list[MDLine] = built["lines"]
    with tempfile.TemporaryDirectory(prefix="moordyn_xcheck_") as tmp:
        tmpdir = Path(tmp)
        infile = tmpdir / "scene.txt"
        infile.write_text(built["text"])
        log = tmpdir / "moordyn.log"
        md = None
        try:
            with _quiet(log):
                md = moordyn.Create(str(infile))
                if md is None:
                    raise RuntimeError("MoorDyn could not read the generated input file")
                moordyn.SetVerbosity(md, moordyn.LEVEL_ERR)
                moordyn.Init_NoIC(md, [], [])
                n_bodies = moordyn.GetNumberBodies(md)
                n_rods = moordyn.GetNumberRods(md)
                n_points = moordyn.GetNumberPoints(md)
                _seed_state(md, tmpdir / "state.bin", lines, built["free_points"], n_bodies, n_rods, n_points)
            tip_rod = moordyn.GetRod(md, built["tip_rod"])
            back_rod = moordyn.GetRod(md, built["back_rod"])
            md_lines = [moordyn.GetLine(md, k + 1) for k in range(len(lines))]
            n_back = built["back_rod_nseg"]
            tip0 = np.array(moordyn.GetRodNodePos(tip_rod, 0))
            wall_setup = time.perf_counter() - t_setup

            t = 0.0
            n_steps = 0
            p0 = tip0
            v0 = np.array(moordyn.GetRodNodeVel(tip_rod, 0))
            e0 = _axis(moordyn, tip_rod, back_rod, n_back)
            td = None
            hist: list[list[float]] = []
            next_hist = history_interval_s if history_interval_s else math.inf
            t_wall = time.perf_counter()
            with _quiet(log):
                while t < max_fall - 1e-12:
                    # coarse calls far above the seabed, single MoorDyn steps once the tip may arrive within
                    # two calls, so that touchdown is interpolated inside one dtM as in our kernel
                    k = steps_per_call
                    if k > 1 and p0[2] + depth <= 2.0 * k * dt_md * (abs(v0[2]) + 1.0):
                        k = 1
                    h = k * dt_md * (1.0 - 1e-9 / k)  # no round-off sliver of an extra internal step
                    try:
                        moordyn.Step(md, [], [], t, h)
                    except RuntimeError as exc:
                        raise SimulationDiverged(t, "MoorDyn", f"non-finite ({exc})") from None
                    n_steps += k
                    t_new = t + h
                    p1 = np.array(moordyn.GetRodNodePos(tip_rod, 0))
                    v1 = np.array(moordyn.GetRodNodeVel(tip_rod, 0))
                    e1 = _axis(moordyn, tip_rod, back_rod, n_back)
                    if not np.all(np.isfinite(p1)):
                        raise SimulationDiverged(t_new, "MoorDyn", "non-finite")
                    if t_new >= next_hist - 1e-12:
                        hist.append([t_new, *p1, *v1, *e1])
                        next_hist += history_interval_s
                    if p1[2] <= -depth:
                        w = (p0[2] + depth) / (p0[2] - p1[2])
                        e = e0 + w * (e1 - e0)
                        e /= np.linalg.norm(e)
                        td = (t + w * h, p0 + w * (p1 - p0), v0 + w * (v1 - v0), e)
                        break
                    t, p0, v0, e0 = t_new, p1, v1, e1
            wall = time.perf_counter() - t_wall
            min_z = min((min(moordyn.GetLineNodePos(ln, i)[2] for i in range(moordyn.GetLineN(ln) + 1))
                         for ln in md_lines), default=None)
        finally:
            if md is not None:
                with _quiet(log):
                    moordyn.Close(md)
    result: dict[str, Any] = {
        "status": "touchdown" if td is not None else "no touchdown within max_fall_time_s",
        "touchdown_time_s": None, "touchdown_speed_m_s": None, "touchdown_vertical_speed_m_s": None,
        "tilt_deg": None, "drift_m": None, "wall_s": wall, "wall_setup_s": wall_setup, "dt_s": dt_md,
        "scheme": scheme, "n_steps": n_steps, "n_line_segments": [ln.n_seg for ln in lines],
        "min_line_z_m": None if min_z is None else float(min_z), "line_types": built["line_types"],
        "axial_cda_m2": built["axial_cda_m2"], "omega_max_rad_s": built["omega_max_rad_s"],
        "input_text": built["text"], "history": np.array(hist).reshape(-1, 10),
    }
    if td is not None:
        t_td, p_td, v_td, e_td = td
        result.update(
            touchdown_time_s=float(t_td), touchdown_speed_m_s=float(np.linalg.norm(v_td)),
            touchdown_vertical_speed_m_s=float(-v_td[2]),
            tilt_deg=float(tilt_deg(e_td[2])),
            drift_m=float(math.hypot(p_td[0] - tip0[0], p_td[1] - tip0[1])))
    return result


def _axis(moordyn, tip_rod, back_rod, n_back: int) -> np.ndarray:
    """Unit anchor axis, back tip -> tip."""
    tip = np.array(moordyn.GetRodNodePos(tip_rod, 0))
    back = np.array(moordyn.GetRodNodePos(back_rod, n_back))
    e = tip - back
    return e / np.linalg.norm(e)

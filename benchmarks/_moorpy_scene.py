"""The hanging installation scene of ``gjoa-500`` (with overrides) built and solved in MoorPy, for the statics
benchmark: an independent continuous-catenary answer to compare ``moor_env.solve_statics`` with.

The model, all in MoorPy's quasi-static catenary lines and points, with every material number taken from the
compiled scene (``moor_env.compile.compile_scene``) so that both solvers see the same inputs:

- the wire: one line from the free point R (end A) up to a fixed point at the installation vessel's fairlead
  (x = 0, end B); its unstretched length is the unknown of a 1-D root find around ``solveEquilibrium`` that puts
  the anchor point at ``drop_height_m`` + anchor length above the seabed;
- R: a free point with the release unit's mass and volume;
- the vertical chain: one line from the anchor point (end A) up to R (end B);
- the anchor: a free point mass at its back end carrying the anchor's submerged weight (no length, no tilt:
  MoorPy has no rigid slender body here, so the anchor cannot tilt in a current and its back end is where the
  drop height is measured from, the anchor hanging vertical below it);
- the mooring line: loop chain then fibre from R to a fixed point at the second vessel's fairlead
  (x = ``vessel_spacing_m``). MoorPy's ``Line`` holds one line type and its multi-type ``Subsystem`` is a
  planar, unfinished model in MoorPy 1.3 (``System.addSubsystem`` is commented out there), so the two types
  are two lines joined by a massless free connection point, the usual way of a multi-segment line in MoorPy;
- the seabed is flat at the water depth.

MoorPy derives a line's submerged weight from its mass and ``d_vol`` and uses ``d_vol`` as the drag diameter
too, so ``d_vol`` is set to give our submerged mass per metre and the drag coefficients are scaled by
``diameter_m / d_vol`` so that the drag per metre is ours (normal on ``diameter_m``, tangential on
``pi * diameter_m``).

Current: MoorPy 1.3 takes only a uniform current on its lines (``System(current=...)``). The lines get the
depth average of the scene's profile (``environment.current.profile`` rows scaled by ``current_scale``, falling
linearly to zero at the seabed as in ``moor_env.physics.environment``) over the water column from the fairlead
depth to the seabed, in ``current_direction_deg``. MoorPy's points carry no current drag in its statics, so
the release unit's (its ``drag_area_m2``) and the anchor's (its normal drag, the anchor hanging vertical) are
added as constant external forces at the profile's local speed at their target depths.

Where MoorPy fails: with a current, on scenes whose mooring-line loop reaches the seabed (the chain-fibre
joint on the seabed), its ``solveEquilibrium`` cycles and stops with a ``SolveError`` (the same scenes solve
without current). MoorPy drops the seabed of a suspended line in a current (its catenary puts the seabed out of
reach), and the seabed only acts on a line's end A and on points.

MoorPy is a benchmark-only dependency: it is imported inside :func:`moorpy_statics`.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import time

import numpy as np

from moor_env import load_scene
from moor_env.compile import compile_scene, hanging_curve
from moor_env.physics import layout as L

WIRE_TOL_M = 1e-3  # anchor height error accepted by the wire-length search (as solve_statics' tol_m) [m]
EQ_TOL_M = 1e-3  # position tolerance of each MoorPy solveEquilibrium [m] (1e-4 makes its solver cycle and fail
#                  on short vertical chains in a current)
MAX_WIRE_ITERATIONS = 40
N_SEGS = 40  # catenary profile points per line (MoorPy sums the current drag over them)


def _depth_average_speed(profile: np.ndarray, top_depth: float, bottom_depth: float) -> float:
    """Mean of the piecewise-linear speed profile (depth, speed rows ending at the seabed) over a depth range."""
    d = np.concatenate(([top_depth], profile[(profile[:, 0] > top_depth) & (profile[:, 0] < bottom_depth), 0],
                        [bottom_depth]))
    u = np.array([_speed_at(profile, x) for x in d])
    return float(np.trapezoid(u, d) / (bottom_depth - top_depth)) if bottom_depth > top_depth else float(u[0])


def _speed_at(profile: np.ndarray, depth: float) -> float:
    """Unscaled speed of the profile at a depth (as ``moor_env.physics.environment.current_speed``)."""
    if depth <= profile[0, 0]:
        return float(profile[0, 1])
    return float(np.interp(depth, profile[:, 0], profile[:, 1]))


def _line_type(model, name: str) -> dict:
    """MoorPy line type of one compiled material: our EA, mass, submerged weight and drag per metre."""
    row = model.mat_f[model.material_names.index(name)]
    rho = model.scene.environment.water_density_kg_m3
    mass, submerged, diameter = row[L.MF_MASS], row[L.MF_SUBMERGED], row[L.MF_D]
    displaced = mass - submerged  # kg/m of water displaced
    d_vol = math.sqrt(4.0 * displaced / (rho * math.pi)) if displaced > 0 else diameter
    ratio = diameter / d_vol
    g = model.scene.environment.gravity_m_s2
    return {"name": name, "m": mass, "EA": row[L.MF_EA], "d_vol": d_vol, "w": submerged * g,
            "Cd": row[L.MF_CDN] * ratio, "CdAx": row[L.MF_CDT] * ratio, "material": name, "d_nom": diameter,
            "MBL": row[L.MF_MBL]}


def _failure(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}"[:300]


def moorpy_statics(overrides: dict) -> dict:
    """Solve the hanging scene ``gjoa-500`` + ``overrides`` in MoorPy.

    Returns
    -------
    dict
        ``release_point_m`` [x, y, z] of R [m]; ``top_tensions_n`` {"wire", "mooring_line", "vertical_chain"}:
        the wire's and the mooring line's tensions at their vessel fairleads and the vertical chain's at R [N];
        ``seconds``: wall time of the MoorPy solve including the wire-length search (not the scene's compile);
        ``solve_seconds_one``: wall time of one ``solveEquilibrium`` at the final wire length, started from the
        straight initial layout of a fresh system; ``wire_length_m``: the wire's unstretched length found;
        ``failed``: None, or a one-line reason (a MoorPy error such as ``LineError`` 'End B is below the seabed'
        or a 'Singular matrix', a ``SolveError`` of a non-converged equilibrium, a wire-length search that did
        not converge, a scene our config refuses), the other values then None; ``messages``: the kinds of line
        MoorPy printed (its solver's warnings, such as 'dsolve2 is going in circles'). Never raises.
    """
    out: dict = {"release_point_m": None, "top_tensions_n": None, "seconds": None, "solve_seconds_one": None,
                 "wire_length_m": None, "failed": None}
    try:
        model = compile_scene(load_scene("gjoa-500", overrides))
    except Exception as exc:  # noqa: BLE001  (a refused scene is a result, not an error)
        out["failed"] = "scene: " + _failure(exc)
        return out
    # MoorPy is a benchmark-only dependency: imported here, not at module level. The PyPI wheel of MoorPy 1.3 has
    # live breakpoint() calls on some failure paths; PYTHONBREAKPOINT=0 turns them into no-ops.
    os.environ["PYTHONBREAKPOINT"] = "0"
    try:
        import moorpy as mp  # noqa: PLC0415
    except Exception as exc:  # noqa: BLE001
        out["failed"] = "import moorpy: " + _failure(exc)
        return out
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed):
            out.update(_solve(mp, model))
    except Exception as exc:  # noqa: BLE001  (LineError, SolveError, LinAlgError 'Singular matrix', ...)
        out["failed"] = _failure(exc)
    out["messages"] = _distinct_messages(printed.getvalue())
    return out


def _distinct_messages(text: str) -> list[str]:
    """The kinds of line MoorPy printed during the solve (numbers stripped), e.g. 'dsolve2 is going in circles
    detected at iteration #'."""
    number = re.compile(r"(?<![A-Za-z\d])[-+]?\d[\d.eE+-]*")
    kinds = dict.fromkeys(number.sub("#", line.strip()) for line in text.splitlines() if line.strip())
    return list(kinds)[:10]


def _build(mp, model):
    """The MoorPy System of the scene with the wire at its straight initial length; (system, points, lines)."""
    scene = model.scene
    env, inst = scene.environment, scene.installation
    depth, g, rho = env.water_depth_m, env.gravity_m_s2, env.water_density_kg_m3
    props = model.extras["anchor"]
    z_back = -depth + inst.drop_height_m + props.length_m
    z_release = z_back + inst.vertical_chain_length_m
    z_fair = -inst.fairlead_depth_m

    kwargs = {}
    theta = math.radians(env.current.direction_deg)
    direction = np.array([math.cos(theta), math.sin(theta), 0.0])
    profile = model.current_profile
    scale = env.current.scale
    if scale > 0.0:
        kwargs["current"] = scale * _depth_average_speed(profile, inst.fairlead_depth_m, depth) * direction
    ms = mp.System(depth=depth, rho=rho, g=g, **kwargs)

    def point_drag(cda: float, z: float) -> np.ndarray:
        u = scale * _speed_at(profile, -z)
        return 0.5 * rho * cda * u * u * direction

    chain, fibre = inst.chain_material, inst.fibre_material
    types = {name: ms.setLineType(name=name, lineType=_line_type(model, name))
             for name in (inst.wire_material, chain, fibre)}
    ru = scene.release_unit
    anchor_cda = float(np.sum(model.body_q[:, L.BQ_CDN_D] * model.body_q[:, L.BQ_DS]))
    vessel_a = ms.addPoint(1, [0.0, 0.0, z_fair])
    vessel_b = ms.addPoint(1, [inst.vessel_spacing_m, 0.0, z_fair])
    release = ms.addPoint(0, [0.0, 0.0, z_release], m=ru.mass_kg, v=ru.volume_m3,
                          fExt=point_drag(ru.drag_area_m2, z_release))
    anchor = ms.addPoint(0, [0.0, 0.0, z_back], m=model.anchor_submerged_mass_kg, v=0.0,
                         fExt=point_drag(anchor_cda, z_back - 0.5 * props.length_m))
    wire_len = z_fair - z_release
    wire = ms.addLine(wire_len, types[inst.wire_material], nSegs=N_SEGS,
                      pointA=release.number, pointB=vessel_a.number)
    vertical = ms.addLine(inst.vertical_chain_length_m, types[chain], nSegs=N_SEGS,
                          pointA=anchor.number, pointB=release.number)
    loop = inst.bottom_chain_length_m - inst.vertical_chain_length_m
    rope = inst.mooring_line_length_m - inst.bottom_chain_length_m
    sections = [(types[chain], loop), (types[fibre], rope)]
    sections = [s for s in sections if s[1] > 1e-9]
    start = np.array([0.0, 0.0, z_release])
    end = np.array([inst.vessel_spacing_m, 0.0, z_fair])
    lower = release
    mooring = []
    if len(sections) == 2:
        # the connection point starts on the compiler's first-guess hanging curve, at the chain-fibre joint
        curve = hanging_curve(start, end, loop + rope, -depth)
        s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))))
        joint = np.array([np.interp(loop / (loop + rope) * s[-1], s, curve[:, k]) for k in range(3)])
        joint[2] = max(joint[2], -depth)
        lower = ms.addPoint(0, joint)
        mooring.append(ms.addLine(loop, sections[0][0], nSegs=N_SEGS, pointA=lower.number, pointB=release.number))
        sections = sections[1:]
    mooring.append(ms.addLine(sections[0][1], sections[0][0], nSegs=N_SEGS, pointA=lower.number,
                              pointB=vessel_b.number))
    ms.initialize()
    return ms, {"release": release, "anchor": anchor}, {"wire": wire, "vertical": vertical, "mooring": mooring}, \
        z_back


def _solve(mp, model) -> dict:
    t0 = time.process_time()
    ms, points, lines, z_target = _build(mp, model)
    wire = lines["wire"]

    def error(length: float) -> float:
        wire.setL(length)
        ms.solveEquilibrium(tol=EQ_TOL_M, maxIter=500)
        return float(points["anchor"].r[2] - z_target)

    # the anchor sinks about one metre per metre of wire (less the stretch): Newton with slope -1, then secant
    l0 = wire.L
    f0 = error(l0)
    l1 = l0 + f0
    f1 = error(l1)
    for _ in range(MAX_WIRE_ITERATIONS):
        if abs(f1) < WIRE_TOL_M:
            break
        slope = (f1 - f0) / (l1 - l0) if l1 != l0 else -1.0
        if not (-2.0 < slope < -0.2):  # a secant off the physical range: fall back to slope -1
            slope = -1.0
        l0, f0 = l1, f1
        l1 = l1 - f1 / slope
        if l1 <= 0.0:
            raise RuntimeError(f"wire-length search left the physical range (length {l1:.3g} m)")
        f1 = error(l1)
    else:
        raise RuntimeError(f"wire-length search did not converge: anchor {f1:+.3g} m off after "
                           f"{MAX_WIRE_ITERATIONS} iterations")
    seconds = time.process_time() - t0
    release = points["release"].r.copy()
    tensions = {"wire": float(wire.TB), "mooring_line": float(lines["mooring"][-1].TB),
                "vertical_chain": float(lines["vertical"].TB)}

    # one equilibrium solve at the final wire length, from the straight initial layout (a fresh system)
    ms2, _, lines2, _ = _build(mp, model)
    lines2["wire"].setL(l1)
    t1 = time.process_time()
    ms2.solveEquilibrium(tol=EQ_TOL_M, maxIter=500)
    solve_one = time.process_time() - t1
    return {"release_point_m": [float(v) for v in release], "top_tensions_n": tensions, "seconds": seconds,
            "solve_seconds_one": solve_one, "wire_length_m": float(l1)}

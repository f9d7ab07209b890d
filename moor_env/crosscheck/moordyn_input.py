"""Scene -> MoorDyn v2 input file (PyPI ``moordyn`` 2.7): the mapping of the MoorDyn cross-check
(:mod:`moor_env.crosscheck.moordyn` runs it).

How the scene maps onto MoorDyn
-------------------------------
- **Anchor**: a ``Free`` Body at the anchor's COG carrying body-fixed Rods, one per run of consecutive anchor
  sections with the same outer diameter, normal Cd and Ca (for the Gjoa DPA: 8.0 m forward at Cd 0.8 and the
  5.0 m finned aft part at Cd 8, both D = 1.2 m, Ca 1). The Body carries our mass (structure + flooded water)
  at the COG and our pitch inertia about the COG, given as an *isotropic* inertia so that the tensor is the
  same in any frame (our model tracks no roll; nothing in either model applies a moment about the axis). The
  Rods are massless (``Mass/m`` 0): they supply buoyancy (outer volume, exact centre of buoyancy), normal
  Morison drag and normal added mass. Body volume, drag and added mass are 0.
- **Axial drag**: MoorDyn Rods have no side skin friction (``Cdt`` is hard-coded to 0) and apply ``CdEnd`` on
  *both* end faces of every Rod, on the axial relative velocity. Our tip and back pressure drag and the skin
  friction of every section all act along the axis on the same axial relative velocity (the points of a
  rigid body share their axial velocity), so together they are one axial force 1/2 rho C A |v_a| v_a with
  C A = tip CdA + back CdA + sum(Cd_t pi D ds) (1.10 x 1.131 m^2 for the DPA). MoorDyn gets it as
  ``CdEnd = C / 2`` on the tip Rod (two faces) and 0 on the others; an axial force through the axis has no
  moment, so where it acts does not matter. ``CaEnd`` = 0 (we have no axial added mass either).
- **Lines**: each run of one material in one of our lines is a MoorDyn Line with the *same* segments (or
  ``segment_length_m``), joined by ``Free`` Points (release point, chain/fibre junction); the anchor end is
  a Point fixed on the Body at the back tip, the second vessel a ``Fixed`` Point. MoorDyn uses one diameter
  ``d`` for buoyancy, drag and added mass; we use a hydrodynamic diameter D plus an explicit submerged mass.
  ``d`` is chosen from the displaced volume per metre, ``pi/4 d^2 = (m - m_sub)/rho`` (chain: d = 0.2677 m
  for D = 0.2008 m), and ``Cd`` and ``CdAx`` are scaled by ``D/d``, ``Ca`` and ``CaAx`` by ``(D/d)^2``, so
  weight, buoyancy, drag and added mass per metre are identical.
- **Release**: at t = 0 the chain top is a ``Free`` Point; the wire is not modelled (the supported scenes
  drop it at release: ``keep_wire_after_release: false``, release at t = 0).
- **Initial state**: MoorDyn is created, initialised without its IC solve (``Init_NoIC``), its state is saved
  (``SaveState``), every free Point and internal line node is overwritten with our static node positions
  (zero velocities) and the state is loaded back (``LoadState``). With ``segment_length_m`` the MoorDyn nodes
  are interpolated along our static polyline (by unstretched arc length) and start slightly off equilibrium.
- **Touchdown**: the tip (node 0 of the tip Rod) crossing z = -water_depth, interpolated linearly inside the
  last step, as in our kernel.

Internal line damping: off in MoorDyn by default (``damping_ratio=0``)
----------------------------------------------------------------------
Our segments are tension-only including their damping: ``T = max(0, EA e + BA e_dot)`` for strain e > 0,
else 0, with ``BA = zeta l0 sqrt(EA m)`` (exactly MoorDyn's rule for an input ``BA = -zeta``). MoorDyn
applies ``BA e_dot / l`` whether or not the segment is taut (``Line::getStateDeriv``), so a *slack,
shortening* segment pushes. That is what happens in these drops: the chain above the anchor falls faster
than the anchor (its axial drag is tiny), goes slack and shortens, and with the scene's zeta = 0.3 MoorDyn
turns it into a viscous column that pushes the anchor (vertical-chain: +1.1 % touchdown speed) or buckles
sideways and tilts it (gjoa-500: about -4 % and 1.2-1.7 deg of tilt, where ours stays vertical). No MoorDyn
2.7 input removes this: a ``BA`` table depends on the strain *rate* only (and divides by it, NaN at rest),
the viscoelastic models damp slack segments too. Switching MoorDyn's damping off (``damping_ratio=0``,
stable with RK4 for omega dt < 2.83) removes the compressive force and leaves a smaller, known difference:
MoorDyn then has no damping of taut segments either (ours with zeta = 0 instead of 0.3 changes the
touchdown speed by 0.1 % on vertical-chain and gjoa-500, 0.6 % on the 170 m / 10 m tilt case).
``damping_ratio=None`` uses the scene's ratios (the artefact is then present).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from moor_env.config import SceneConfig
from moor_env.physics import layout as L
from moor_env.simulation import StaticResult

DEFAULT_DT_FRACTION = 0.7  # fraction of the scheme's stability limit used by the default dt (checked converged)
DEFAULT_ROD_SEGMENT_M = 0.25


@dataclass
class MDLine:
    """One MoorDyn line: a run of one material between two of our nodes."""

    material: str
    point_a: int  # MoorDyn point id
    point_b: int
    length_m: float
    n_seg: int
    positions: np.ndarray  # (n_seg + 1, 3) initial node positions, A -> B


def omega_dt_limit(scheme: str, zeta: float) -> float:
    """Largest omega*dt for which MoorDyn's explicit ``rk2`` (midpoint) or ``rk4`` is stable on a segment's
    axial mode with damping ratio ``zeta`` while taut (eigenvalues omega(-zeta +- i sqrt(1 - zeta^2))) and
    while slack (MoorDyn keeps the damping: a real eigenvalue -2 zeta omega). 0 if unstable at any step.
    """
    scheme = scheme.lower()
    if scheme == "rk2":
        coeffs = [1.0, 1.0, 0.5]
    elif scheme == "rk4":
        coeffs = [1.0, 1.0, 1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0]
    else:
        raise ValueError(f"no stability limit known for scheme {scheme!r}: give dt_s")
    root = np.sqrt(complex(zeta * zeta - 1.0))
    lams = np.array([-zeta + root, -zeta - root, -2.0 * zeta])

    def stable(h: float) -> bool:
        z = h * lams
        return bool(np.all(np.abs(sum(c * z**k for k, c in enumerate(coeffs))) <= 1.0 + 1e-14))

    if not stable(1e-3):
        return 0.0
    lo, hi = 1e-3, 8.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def moordyn_line_type(scene: SceneConfig, material: str) -> dict[str, float]:
    """MoorDyn line-type columns equivalent to one of our materials.

    MoorDyn's single diameter ``d`` is chosen from the displaced volume (so weight minus buoyancy is our
    submerged weight) and the coefficients are rescaled so that drag and added mass per metre are ours.
    """
    mat = scene.materials[material]
    rho = scene.environment.water_density_kg_m3
    m = mat.mass_per_length_kg_m
    m_sub = mat.submerged_mass_per_length_kg_m
    if m_sub is None:
        m_sub = m - rho * math.pi / 4.0 * mat.diameter_m**2
    displaced = (m - m_sub) / rho
    if displaced <= 0.0:
        raise ValueError(f"material {material!r}: MoorDyn needs a positive displaced volume per metre")
    d = math.sqrt(4.0 * displaced / math.pi)
    r = mat.diameter_m / d
    return {"d": d, "w": m, "EA": mat.ea_n, "BA": -mat.axial_damping_ratio, "Cd": mat.cd_normal * r,
            "Ca": mat.ca_normal * r * r, "CdAx": mat.cd_tangential * r, "CaAx": mat.ca_tangential * r * r,
            "D_ours": mat.diameter_m}


def check_supported(scene: SceneConfig) -> None:
    if scene.kind != "dart_installation":
        raise ValueError("run_moordyn_drop needs a dart_installation scene")
    env = scene.environment
    inst = scene.installation
    if env.current.scale != 0.0 and any(abs(v) > 0 for _, v in env.current.profile):
        raise ValueError("current is not modelled in the MoorDyn cross-check (set current_scale 0)")
    if env.sea_state.hs_m > 0.0:
        raise ValueError("waves are not modelled in the MoorDyn cross-check (sea_state.hs_m must be 0)")
    if inst.release_time_s > 0.0 or inst.spacing_rate_m_s != 0.0 or inst.payout_rate_m_s != 0.0:
        raise ValueError("the MoorDyn cross-check releases at t = 0 from statics (no pre-release phase)")
    if inst.components.wire and inst.components.keep_wire_after_release:
        raise ValueError("keep_wire_after_release is not modelled in the MoorDyn cross-check")


def _line_nodes(sim, name: str) -> tuple[list[int], list[int], list[float]]:
    """Global node indices (bottom -> top), segment materials and unstretched lengths of one of our lines."""
    st = sim.state
    li = st.line_i[sim.model.lines[name].index]
    segs = range(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])
    nodes = [int(st.seg_i[segs[0], L.SI_A])] + [int(st.seg_i[s, L.SI_B]) for s in segs]
    mats = [int(st.seg_i[s, L.SI_MAT]) for s in segs]
    l0 = [float(st.seg_f[s, L.SF_L0]) for s in segs]
    return nodes, mats, l0


def _resample(points: np.ndarray, l0: np.ndarray, n: int) -> np.ndarray:
    """``n + 1`` points at equal unstretched arc length along a polyline with segment lengths ``l0``."""
    s = np.concatenate([[0.0], np.cumsum(l0)])
    u = np.linspace(0.0, s[-1], n + 1)
    return np.stack([np.interp(u, s, points[:, c]) for c in range(3)], axis=1)


def omega_max(line_types: dict[str, dict[str, float]], lines: list[MDLine], free_points: set[int]) -> float:
    """Upper bound (Gershgorin) of the fastest axial mode of the MoorDyn lines [rad/s]:
    omega^2 <= 2 sum(EA/l) / m over the segments meeting at a node (exact for a uniform line), over internal
    line nodes and ``free_points`` (points on the body or fixed have no line-scale mode)."""
    stiff: dict[tuple[str, int], float] = {}
    mass: dict[tuple[str, int], float] = {}
    for k, ln in enumerate(lines):
        lt = line_types[ln.material]
        l_seg = ln.length_m / ln.n_seg
        for key in (("p", ln.point_a), ("p", ln.point_b)):
            stiff[key] = stiff.get(key, 0.0) + lt["EA"] / l_seg
            mass[key] = mass.get(key, 0.0) + 0.5 * lt["w"] * l_seg
        if ln.n_seg > 1:
            stiff[("l", k)] = 2.0 * lt["EA"] / l_seg
            mass[("l", k)] = lt["w"] * l_seg
    omegas = [math.sqrt(2.0 * stiff[key] / mass[key]) for key in stiff if key[0] == "l" or key[1] in free_points]
    return max(omegas) if omegas else 0.0


def build_moordyn_input(scene: SceneConfig, static: StaticResult, dt_s: float | None = None, scheme: str = "rk4",
                        segment_length_m: float | dict[str, float] | None = None,
                        rod_segment_m: float = DEFAULT_ROD_SEGMENT_M,
                        damping_ratio: float | None = 0.0) -> dict[str, Any]:
    """The MoorDyn v2 input text for a scene at its static equilibrium, and what is needed to seed it.

    Returns
    -------
    dict
        ``text`` (input file), ``lines`` (list of ``MDLine``), ``free_points`` ({point id: position}),
        ``tip_rod``/``back_rod`` (MoorDyn rod ids, 1-based), ``back_rod_nseg``, ``dt_s``, ``line_types``,
        ``axial_cda_m2``, ``omega_max_rad_s``, ``fric_damp``. ``damping_ratio``: as in
        :func:`run_moordyn_drop`.
    """
    sim = static.simulator
    model = sim.model
    props = model.extras["anchor"]
    env = scene.environment
    inst = scene.installation
    rho = env.water_density_kg_m3
    body = sim.state.body_state
    cog = body[L.BS_POS:L.BS_POS + 3].copy()
    axis = body[L.BS_AXIS:L.BS_AXIS + 3].copy()

    # --- anchor rods: runs of sections with equal outer diameter, normal Cd and Ca ---------------------
    groups: list[list] = []
    x0 = 0.0
    for sec in scene.anchor.sections:
        key = (sec.outer_diameter_m, sec.cd_normal, sec.ca_normal)
        if groups and groups[-1][0] == key:
            groups[-1][2] += sec.length_m
        else:
            groups.append([key, x0, sec.length_m])
        x0 += sec.length_m
    q = model.body_q
    axial_cda = props.tip_cda_m2 + props.back_cda_m2 + float(np.sum(q[:, L.BQ_CDT_PID] * q[:, L.BQ_DS]))
    rod_types, rods = [], []
    for k, ((diam, cdn, can), x_start, length) in enumerate(groups):
        area = math.pi / 4.0 * diam**2
        cd_end = 0.5 * axial_cda / area if k == 0 else 0.0
        rod_types.append(f"anchor{k + 1} {diam:.10g} 0 {cdn:.10g} {can:.10g} {cd_end:.10g} 0")
        s_a = props.cog_from_tip_m - x_start  # axial coordinate from the COG, + towards the tip
        s_b = s_a - length
        ra, rb = s_a * axis, s_b * axis
        nseg = max(2, math.ceil(length / rod_segment_m - 1e-9))
        rods.append(f"{k + 1} anchor{k + 1} Body1 {ra[0]:.10g} {ra[1]:.10g} {ra[2]:.10g} "
                    f"{rb[0]:.10g} {rb[1]:.10g} {rb[2]:.10g} {nseg} -")

    # --- lines and points -----------------------------------------------------------------------------
    points: list[str] = []
    point_of_node: dict[int, int] = {}
    free_points: dict[int, np.ndarray] = {}
    pos = sim.state.node_pos
    kinds = sim.state.node_i[:, L.NI_KIND]

    def point_for(node: int) -> int:
        if node in point_of_node:
            return point_of_node[node]
        pid = len(points) + 1
        kind = kinds[node]
        p = pos[node]
        if kind == L.NODE_BODY:
            rel = model.node_f[node, L.NF_BODY_S] * axis
            points.append(f"{pid} Body1 {rel[0]:.10g} {rel[1]:.10g} {rel[2]:.10g} 0 0 0 0")
        elif kind == L.NODE_VESSEL:
            points.append(f"{pid} Fixed {p[0]:.10g} {p[1]:.10g} {p[2]:.10g} 0 0 0 0")
        else:  # release point (held before release, free after) and material junctions
            points.append(f"{pid} Free {p[0]:.10g} {p[1]:.10g} {p[2]:.10g} 0 0 0 0")
            free_points[pid] = p.copy()
        point_of_node[node] = pid
        return pid

    if isinstance(segment_length_m, (int, float)):
        seg_override = {inst.chain_material: float(segment_length_m)}
    else:
        seg_override = dict(segment_length_m or {})
    md_lines: list[MDLine] = []
    for name in model.lines:
        if name == "wire":
            continue  # dropped at release in the supported scenes
        nodes, mats, l0 = _line_nodes(sim, name)
        start = 0
        while start < len(mats):
            end = start
            while end + 1 < len(mats) and mats[end + 1] == mats[start]:
                end += 1
            material = model.material_names[mats[start]]
            run_nodes = nodes[start:end + 2]
            run_l0 = np.array(l0[start:end + 1])
            length = float(run_l0.sum())
            pa, pb = point_for(run_nodes[0]), point_for(run_nodes[-1])
            poly = pos[run_nodes].copy()
            if material in seg_override:
                n = max(1, math.ceil(length / seg_override[material] - 1e-9))
                poly = _resample(poly, run_l0, n)
            else:
                n = len(run_l0)
                if np.ptp(run_l0) > 1e-9 * length:
                    poly = _resample(poly, run_l0, n)
            md_lines.append(MDLine(material, pa, pb, length, n, poly))
            start = end + 1

    line_types = {ln.material: moordyn_line_type(scene, ln.material) for ln in md_lines}
    if damping_ratio is not None:
        for lt in line_types.values():
            lt["BA"] = -damping_ratio
    w_max = omega_max(line_types, md_lines, set(free_points))
    if dt_s is None:
        dt_s = 1e-3
        if w_max > 0:
            zeta = max(-lt["BA"] for lt in line_types.values())
            limit = omega_dt_limit(scheme, zeta)
            if limit <= 0.0:
                raise ValueError(f"MoorDyn {scheme} is unstable on undamped lines: use rk4 or line damping")
            dt_s = min(dt_s, DEFAULT_DT_FRACTION * limit / w_max)

    # seabed friction: MoorDyn's saturated damping mu*FricDamp*v reaches mu*F_z at our ramp speed v_f for a
    # resting chain node (F_z = its submerged weight)
    sb = env.seabed
    chain = scene.materials.get(inst.chain_material)
    fric_damp = 200.0
    if chain is not None and md_lines:
        seg = min(ln.length_m / ln.n_seg for ln in md_lines if ln.material == inst.chain_material) \
            if any(ln.material == inst.chain_material for ln in md_lines) else 1.0
        m_sub = chain.submerged_mass_per_length_kg_m
        if m_sub is None:
            m_sub = chain.mass_per_length_kg_m - rho * math.pi / 4 * chain.diameter_m**2
        fric_damp = m_sub * env.gravity_m_s2 * seg / sb.friction_velocity_m_s

    out = ["--------------------- MoorDyn Input File ------------------------------------",
           f"moor_env cross-check of scene '{scene.name}' (generated by moor_env.crosscheck.moordyn)"]
    if md_lines:
        out += ["---------------------- LINE TYPES ------------------------------------------",
                "TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx",
                "(name) (m) (kg/m) (N) (N-s/-) (N-m^2) (-) (-) (-) (-)"]
        for mname, lt in line_types.items():
            out.append(f"{mname} {lt['d']:.10g} {lt['w']:.10g} {lt['EA']:.10g} {lt['BA']:.10g} 0 "
                       f"{lt['Cd']:.10g} {lt['Ca']:.10g} {lt['CdAx']:.10g} {lt['CaAx']:.10g}")
    out += ["---------------------- ROD TYPES ------------------------------------",
            "TypeName Diam Mass/m Cd Ca CdEnd CaEnd",
            "(name) (m) (kg/m) (-) (-) (-) (-)", *rod_types,
            "---------------------- BODIES ---------------------------------------",
            "ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG* I* Volume CdA* Ca*",
            "(#) (-) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kg-m^2) (m^3) (m^2) (-)",
            f"1 Free {cog[0]:.10g} {cog[1]:.10g} {cog[2]:.10g} 0 0 0 {props.mass_kg:.10g} 0 "
            f"{props.inertia_kg_m2:.10g} 0 0 0",
            "---------------------- RODS ----------------------------------------",
            "ID RodType Attachment Xa Ya Za Xb Yb Zb NumSegs RodOutputs",
            "(#) (name) (#/key) (m) (m) (m) (m) (m) (m) (-) (-)", *rods]
    if points:
        out += ["---------------------- POINTS ---------------------------------------",
                "ID Attachment X Y Z Mass Volume CdA Ca",
                "(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)", *points]
    if md_lines:
        out += ["---------------------- LINES ----------------------------------------",
                "ID LineType AttachA AttachB UnstrLen NumSegs LineOutputs",
                "(#) (name) (#) (#) (m) (-) (-)"]
        for k, ln in enumerate(md_lines):
            out.append(f"{k + 1} {ln.material} {ln.point_a} {ln.point_b} {ln.length_m:.12g} {ln.n_seg} -")
    out += ["---------------------- OPTIONS -----------------------------------------",
            f"{dt_s:.10g} dtM", f"{scheme} tScheme", f"{env.gravity_m_s2:.10g} g", f"{rho:.10g} rho",
            f"{env.water_depth_m:.10g} WtrDpth", f"{sb.stiffness_pa_m:.10g} kBot", f"{sb.damping_pa_s_m:.10g} cBot",
            f"{sb.friction_coefficient:.10g} FrictionCoefficient", f"{fric_damp:.10g} FricDamp",
            "1 StatDynFricScale", "0 TmaxIC", "1 disableOutput", "1 disableOutTime", "0 writeLog",
            "------------------------- need this line -------------------------------------", ""]
    return {"text": "\n".join(out), "lines": md_lines, "free_points": free_points, "tip_rod": 1,
            "back_rod": len(groups), "back_rod_nseg": int(rods[-1].split()[-2]), "dt_s": dt_s,
            "line_types": line_types, "axial_cda_m2": axial_cda, "omega_max_rad_s": w_max,
            "fric_damp": fric_damp}

"""Scene config -> compiled model: flat arrays for the kernels and every derived quantity, computed here only.

Second stage of ``YAML -> SceneConfig -> Model -> kernels -> results``. A component the scene does not need is
not built: an ``anchor-only`` scene has no nodes at all, ``vertical-chain`` has one line and no wire.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from moor_env.config import SceneConfig
from moor_env.errors import ConfigError
from moor_env.physics import layout as L
from moor_env.physics.stability import stable_time_step
from moor_env.scene_geometry import submerged_mass_per_length

VESSEL_INSTALLATION = 0
VESSEL_SECOND = 1
PAYOUT_EXTRA_FRACTION = 1.0  # capacity for paying out as much again as the initial line length
PAYOUT_EXTRA_SEGMENTS = 40
IMPLICIT_STABLE_MULTIPLE = 3.0  # implicit_euler measured stable to 3x its accuracy cap (physics/stability.py)


@dataclass
class LineInfo:
    """Names and roles of one compiled line."""

    name: str
    index: int
    materials: tuple[str, ...]
    material_lengths_m: tuple[float, ...]


@dataclass
class Model:
    """A compiled scene: arrays for the kernels (see ``physics.layout``) plus metadata for Python.

    Arrays whose content changes during a run (topology under payout, node kinds at release) are copied
    into each simulation state; the model itself is never modified.
    """

    scene: SceneConfig
    node_i: np.ndarray
    node_f: np.ndarray
    seg_i: np.ndarray
    seg_f: np.ndarray
    mat_f: np.ndarray
    line_i: np.ndarray
    line_f: np.ndarray
    body_f: np.ndarray
    body_q: np.ndarray
    env_f: np.ndarray
    current_profile: np.ndarray
    node_pos0: np.ndarray
    body_state0: np.ndarray
    material_names: tuple[str, ...]
    lines: dict[str, LineInfo]
    vessel_base_m: np.ndarray
    release_node: int = -1
    wire_end_node: int = -1
    body_active: bool = False
    dt_s: float = 0.0
    dt_limit_s: float = 0.0
    dt_governed_by: str = ""
    integrator: str = "symplectic_euler"
    anchor_mass_kg: float = 0.0
    anchor_submerged_mass_kg: float = 0.0
    extras: dict = field(default_factory=dict)

    def arrays(self) -> dict[str, np.ndarray]:
        """The kernel arrays by name (views of the model's arrays)."""
        return {k: getattr(self, k) for k in ("node_i", "node_f", "seg_i", "seg_f", "mat_f", "line_i", "line_f",
                                              "env_f")}


class _Builder:
    """Accumulates nodes, segments and lines; turns them into arrays."""

    def __init__(self) -> None:
        self.node_kind: list[int] = []
        self.node_ref: list[int] = []
        self.node_line: list[int] = []
        self.node_f: list[list[float]] = []
        self.node_pos: list[np.ndarray] = []
        self.segs: list[tuple[int, int, int, int, int, float]] = []
        self.lines: list[list] = []

    def add_node(self, kind: int, pos, ref: int = -1, line: int = -1, mass=0.0, volume=0.0, cda=0.0, ca=0.0,
                 body_s=0.0) -> int:
        self.node_kind.append(kind)
        self.node_ref.append(ref)
        self.node_line.append(line)
        self.node_f.append([mass, volume, cda, ca, body_s])
        self.node_pos.append(np.asarray(pos, dtype=float))
        return len(self.node_kind) - 1

    def add_line(self, bottom: int, top: int, sections: list[tuple[int, float, float]], points: np.ndarray,
                 payout: bool, l_nom_top: float) -> int:
        """Add a line of ``sections`` = (material, length, segment length) from bottom to top.

        ``points`` is a (k, 3) polyline from the bottom node to the top node used as the initial shape.
        """
        line = len(self.lines)
        lengths: list[float] = []
        mats: list[int] = []
        for mat, length, seg_len in sections:
            n = max(1, int(math.ceil(length / seg_len - 1e-9)))
            lengths += [length / n] * n
            mats += [mat] * n
        nseg = len(lengths)
        extra = 0
        if payout:
            extra = max(PAYOUT_EXTRA_SEGMENTS, int(PAYOUT_EXTRA_FRACTION * sum(lengths) / l_nom_top))
        seg_cap = nseg + extra
        node_cap = seg_cap - 1
        positions = _points_at_arclength(points, np.cumsum(lengths)[:-1] / sum(lengths))
        node_start = len(self.node_kind)
        for k in range(node_cap):
            if k < nseg - 1:
                self.add_node(L.NODE_FREE, positions[k], line=line)
            else:
                self.add_node(L.NODE_INACTIVE, positions[-1] if nseg > 1 else points[-1], line=line)
        seg_start = len(self.segs)
        for k in range(seg_cap):
            if k < nseg:
                a = bottom if k == 0 else node_start + k - 1
                b = top if k == nseg - 1 else node_start + k
                self.segs.append((a, b, mats[k], line, 1, lengths[k]))
            else:
                self.segs.append((top, top, mats[-1], line, 0, l_nom_top))
        self.lines.append([seg_start, seg_cap, nseg, node_start, node_cap, bottom, top, int(payout), 0, l_nom_top])
        return line


def _points_at_arclength(points: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Points at the given fractions (0..1) of the arc length of a polyline."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    u = fractions * cum[-1]
    return np.stack([np.interp(u, cum, points[:, c]) for c in range(3)], axis=1).reshape(-1, 3)


def hanging_curve(start, end, length: float, seabed_z: float, n: int = 400) -> np.ndarray:
    """A first-guess hanging shape of given length between two points: the chord plus a parabolic sag,
    sized by bisection so that its arc length is ``length``, clipped at the seabed.
    """
    start = np.asarray(start, float)
    end = np.asarray(end, float)
    u = np.linspace(0.0, 1.0, n)
    chord = start[None, :] + u[:, None] * (end - start)[None, :]

    def curve(sag: float) -> np.ndarray:
        pts = chord.copy()
        pts[:, 2] -= sag * 4.0 * u * (1.0 - u)
        pts[:, 2] = np.maximum(pts[:, 2], seabed_z)
        return pts

    def arclength(sag: float) -> float:
        return float(np.sum(np.linalg.norm(np.diff(curve(sag), axis=0), axis=1)))

    if arclength(0.0) >= length:
        return curve(0.0)
    lo, hi = 0.0, max(length, 1.0)
    while arclength(hi) < length and hi < 1e7:
        hi *= 2.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if arclength(mid) < length:
            lo = mid
        else:
            hi = mid
    return curve(0.5 * (lo + hi))


def _material_arrays(scene: SceneConfig) -> tuple[np.ndarray, tuple[str, ...]]:
    names = tuple(scene.materials)
    mat_f = np.zeros((len(names), L.N_MAT_F))
    for i, name in enumerate(names):
        m = scene.materials[name]
        mat_f[i] = [m.ea_n, m.mass_per_length_kg_m, submerged_mass_per_length(scene, name), m.diameter_m,
                    m.cd_normal, m.cd_tangential, m.ca_normal, m.ca_tangential, m.axial_damping_ratio, m.mbl_n]
    return mat_f, names


def _env_arrays(scene: SceneConfig) -> tuple[np.ndarray, np.ndarray]:
    env = scene.environment
    env_f = np.zeros(L.N_ENV_F)
    env_f[L.EF_DEPTH] = env.water_depth_m
    env_f[L.EF_G] = env.gravity_m_s2
    env_f[L.EF_RHO] = env.water_density_kg_m3
    env_f[L.EF_KBOT] = env.seabed.stiffness_pa_m
    env_f[L.EF_CBOT] = env.seabed.damping_pa_s_m
    env_f[L.EF_MU] = env.seabed.friction_coefficient
    env_f[L.EF_FRIC_V] = env.seabed.friction_velocity_m_s
    theta = math.radians(env.current.direction_deg)
    env_f[L.EF_CUR_DX] = math.cos(theta)
    env_f[L.EF_CUR_DY] = math.sin(theta)
    env_f[L.EF_CUR_SCALE] = env.current.scale
    env_f[L.EF_TRACK_T0] = 0.0
    env_f[L.EF_TRACK_DT] = 1.0
    env_f[L.EF_SPEED_LIMIT] = scene.simulation.speed_limit_m_s
    env_f[L.EF_STRAIN_LIMIT] = scene.simulation.strain_limit
    rows = [p for p in env.current.profile if p[0] < env.water_depth_m]
    rows.append((env.water_depth_m, 0.0))
    return env_f, np.array(rows, dtype=float)


@dataclass
class AnchorProperties:
    """Derived mass, buoyancy and hydrodynamic integrals of the anchor (all about the COG of the body,
    structure plus flooded water)."""

    mass_kg: float
    structural_mass_kg: float
    flooded_water_kg: float
    displaced_volume_m3: float
    cog_from_tip_m: float
    inertia_kg_m2: float
    s_buoyancy_m: float
    s_tip_m: float
    s_back_m: float
    added_mass: tuple[float, float, float]
    quadrature: np.ndarray
    tip_cda_m2: float
    back_cda_m2: float
    length_m: float

    water_density_kg_m3: float

    @property
    def submerged_mass_kg(self) -> float:
        """Mass minus displaced water: what weight minus buoyancy accelerates [kg]."""
        return self.mass_kg - self.water_density_kg_m3 * self.displaced_volume_m3


def anchor_properties(scene: SceneConfig) -> AnchorProperties:
    """Mass, COG, pitch inertia, buoyancy and Morison integrals of the anchor from its sections."""
    anchor = scene.anchor
    assert anchor is not None
    rho = scene.environment.water_density_kg_m3
    x0 = 0.0
    rows = []
    for sec in anchor.sections:
        rows.append((x0, sec))
        x0 += sec.length_m
    length = x0
    m_struct = sum(anchor.mass_scale * s.mass_per_length_kg_m * s.length_m for _, s in rows)
    m_water = sum(rho * math.pi / 4 * s.flooded_diameter_m**2 * s.length_m for _, s in rows)
    mass = m_struct + m_water
    moment = sum((anchor.mass_scale * s.mass_per_length_kg_m + rho * math.pi / 4 * s.flooded_diameter_m**2)
                 * s.length_m * (x + 0.5 * s.length_m) for x, s in rows)
    x_g = moment / mass
    inertia = 0.0
    volume = 0.0
    vol_moment = 0.0
    a0 = a1 = a2 = 0.0
    for x, s in rows:
        xc = x + 0.5 * s.length_m
        ms = anchor.mass_scale * s.mass_per_length_kg_m * s.length_m
        mw = rho * math.pi / 4 * s.flooded_diameter_m**2 * s.length_m
        ro, ri = 0.5 * s.outer_diameter_m, 0.5 * s.flooded_diameter_m
        lever = x_g - xc
        inertia += ms * (s.length_m**2 / 12 + (ro**2 + ri**2) / 4 + lever**2)
        inertia += mw * (s.length_m**2 / 12 + ri**2 / 4 + lever**2)
        v = math.pi / 4 * s.outer_diameter_m**2 * s.length_m
        volume += v
        vol_moment += v * xc
        ma = rho * s.ca_normal * math.pi / 4 * s.outer_diameter_m**2
        s_hi, s_lo = x_g - x, x_g - x - s.length_m  # axial coordinates (+ towards tip) of the section ends
        a0 += ma * (s_hi - s_lo)
        a1 += ma * (s_hi**2 - s_lo**2) / 2
        a2 += ma * (s_hi**3 - s_lo**3) / 3
    counts = _quadrature_counts([s.length_m for _, s in rows], anchor.quadrature_points)
    quad = []
    for (x, s), n in zip(rows, counts, strict=True):
        ds = s.length_m / n
        for k in range(n):
            xq = x + (k + 0.5) * ds
            quad.append([x_g - xq, ds, s.cd_normal * s.outer_diameter_m, s.cd_tangential * math.pi * s.outer_diameter_m])
    first, last = anchor.sections[0], anchor.sections[-1]
    props = AnchorProperties(
        mass_kg=mass, structural_mass_kg=m_struct, flooded_water_kg=m_water, displaced_volume_m3=volume,
        cog_from_tip_m=x_g, inertia_kg_m2=inertia, s_buoyancy_m=x_g - vol_moment / volume, s_tip_m=x_g,
        s_back_m=x_g - length, added_mass=(a0, a1, a2), quadrature=np.array(quad),
        tip_cda_m2=anchor.tip_drag_coefficient * math.pi / 4 * first.outer_diameter_m**2,
        back_cda_m2=anchor.back_drag_coefficient * math.pi / 4 * last.outer_diameter_m**2, length_m=length,
        water_density_kg_m3=rho,
    )
    return props


def _quadrature_counts(lengths: list[float], total: int) -> list[int]:
    full = sum(lengths)
    counts = [max(1, int(round(total * ln / full))) for ln in lengths]
    return counts


def _body_arrays(props: AnchorProperties, scene: SceneConfig, point_masses: list[tuple[float, float]]):
    g = scene.environment.gravity_m_s2
    rho = scene.environment.water_density_kg_m3
    a0, a1, a2 = props.added_mass
    mp = sum(m for m, _ in point_masses)
    mps = sum(m * s for m, s in point_masses)
    mps2 = sum(m * s * s for m, s in point_masses)
    body_f = np.zeros(L.N_BODY_F)
    body_f[L.BF_ACTIVE] = 1.0
    body_f[L.BF_MASS_AXIAL] = props.mass_kg + mp
    body_f[L.BF_M11] = props.mass_kg + a0 + mp
    body_f[L.BF_M12] = a1 + mps
    body_f[L.BF_M22] = props.inertia_kg_m2 + a2 + mps2
    body_f[L.BF_WEIGHT] = props.mass_kg * g
    body_f[L.BF_BUOYANCY] = rho * g * props.displaced_volume_m3
    body_f[L.BF_S_BUOY] = props.s_buoyancy_m
    body_f[L.BF_S_TIP] = props.s_tip_m
    body_f[L.BF_S_BACK] = props.s_back_m
    body_f[L.BF_TIP_CDA] = props.tip_cda_m2
    body_f[L.BF_BACK_CDA] = props.back_cda_m2
    body_f[L.BF_LENGTH] = props.length_m
    return body_f


def compile_scene(scene: SceneConfig) -> Model:
    """Build the kernel arrays of a scene and derive its time step.

    Raises
    ------
    ConfigError
        If ``discretization.dt_s`` is beyond the stability limit (it is refused, not reduced). For
        ``implicit_euler`` the default step is the accuracy cap and requests up to 3x it are accepted.
    """
    if scene.kind == "catenary_line":
        model = _compile_catenary_line(scene)
    else:
        model = _compile_installation(scene)
    _set_time_step(model, scene)
    return model


def _finish(scene: SceneConfig, b: _Builder, body_f, body_q, body_state0, line_names, vessel_base, **extra) -> Model:
    mat_f, mat_names = _material_arrays(scene)
    env_f, profile = _env_arrays(scene)
    nn = len(b.node_kind)
    node_i = np.zeros((nn, L.N_NODE_I), dtype=np.int64)
    node_f = np.zeros((nn, L.N_NODE_F))
    if nn:
        node_i[:, L.NI_KIND] = b.node_kind
        node_i[:, L.NI_REF] = b.node_ref
        node_i[:, L.NI_LINE] = b.node_line
        node_f[:] = np.array(b.node_f)
    node_pos = np.array(b.node_pos).reshape(nn, 3)
    ns = len(b.segs)
    seg_i = np.zeros((ns, L.N_SEG_I), dtype=np.int64)
    seg_f = np.zeros((ns, L.N_SEG_F))
    for s, (a, bb, m, line, active, l0) in enumerate(b.segs):
        seg_i[s] = [a, bb, m, line, active]
        seg_f[s, L.SF_L0] = l0
    nl = len(b.lines)
    line_i = np.zeros((nl, L.N_LINE_I), dtype=np.int64)
    line_f = np.zeros((nl, L.N_LINE_F))
    lines: dict[str, LineInfo] = {}
    for li, row in enumerate(b.lines):
        line_i[li] = row[:9]
        l_nom = row[9]
        line_f[li, L.LF_L_NOM] = l_nom
        line_f[li, L.LF_L_MIN_TOP] = 0.5 * l_nom
        line_f[li, L.LF_L_MAX_TOP] = 1.5 * l_nom
        name, mats, lens = line_names[li]
        lines[name] = LineInfo(name=name, index=li, materials=tuple(mats), material_lengths_m=tuple(lens))
    return Model(scene=scene, node_i=node_i, node_f=node_f, seg_i=seg_i, seg_f=seg_f, mat_f=mat_f, line_i=line_i,
                 line_f=line_f, body_f=body_f, body_q=body_q, env_f=env_f, current_profile=profile,
                 node_pos0=node_pos, body_state0=body_state0, material_names=mat_names, lines=lines,
                 vessel_base_m=np.asarray(vessel_base, float).reshape(-1, 3), **extra)


def _mat_index(scene: SceneConfig, name: str) -> int:
    return list(scene.materials).index(name)


def _compile_installation(scene: SceneConfig) -> Model:
    inst = scene.installation
    disc = scene.discretization
    assert inst is not None
    comp = inst.components
    depth = scene.environment.water_depth_m
    seabed = -depth
    props = anchor_properties(scene)
    z_tip = seabed + inst.drop_height_m
    z_back = z_tip + props.length_m
    vessel_base = np.array([[0.0, 0.0, -inst.fairlead_depth_m], [inst.vessel_spacing_m, 0.0, -inst.fairlead_depth_m]])
    b = _Builder()
    line_names: list[tuple[str, list[str], list[float]]] = []
    point_masses: list[tuple[float, float]] = []
    release_node = wire_end = -1
    if comp.vertical_chain:
        chain = _mat_index(scene, inst.chain_material)
        z_release = z_back + inst.vertical_chain_length_m
        ru = scene.release_unit
        release_kind = L.NODE_FREE if comp.wire else L.NODE_FIXED
        release_node = b.add_node(release_kind, (0.0, 0.0, z_release))
        back = b.add_node(L.NODE_BODY, (0.0, 0.0, z_back), body_s=props.s_back_m)
        l_vc = inst.vertical_chain_length_m
        seg_vc = disc.vertical_chain_segment_m
        pts = np.array([[0.0, 0.0, z_back], [0.0, 0.0, z_release]])
        b.add_line(back, release_node, [(chain, l_vc, seg_vc)], pts, payout=False, l_nom_top=seg_vc)
        line_names.append(("vertical_chain", [inst.chain_material], [l_vc]))
        first_len = l_vc / max(1, math.ceil(l_vc / seg_vc - 1e-9))
        point_masses.append((0.5 * first_len * scene.materials[inst.chain_material].mass_per_length_kg_m,
                             props.s_back_m))
        if comp.mooring_line:
            top_b = b.add_node(L.NODE_VESSEL, vessel_base[VESSEL_SECOND], ref=VESSEL_SECOND)
            loop_chain = inst.bottom_chain_length_m - inst.vertical_chain_length_m
            fibre = inst.mooring_line_length_m - inst.bottom_chain_length_m
            sections = []
            names, lens = [], []
            if loop_chain > 1e-9:
                sections.append((chain, loop_chain, disc.loop_chain_segment_m))
                names.append(inst.chain_material)
                lens.append(loop_chain)
            if fibre > 1e-9:
                sections.append((_mat_index(scene, inst.fibre_material), fibre, disc.fibre_segment_m))
                names.append(inst.fibre_material)
                lens.append(fibre)
            pts = hanging_curve((0.0, 0.0, z_release), vessel_base[VESSEL_SECOND], loop_chain + fibre, seabed)
            l_nom = sections[-1][2]
            b.add_line(release_node, top_b, sections, pts, payout=True, l_nom_top=l_nom)
            line_names.append(("mooring_line", names, lens))
        if comp.wire:
            top_a = b.add_node(L.NODE_VESSEL, vessel_base[VESSEL_INSTALLATION], ref=VESSEL_INSTALLATION)
            wire_end = b.add_node(L.NODE_WELDED, (0.0, 0.0, z_release), ref=release_node, mass=ru.mass_kg,
                                  volume=ru.volume_m3, cda=ru.drag_area_m2, ca=ru.added_mass_coefficient)
            wire_len = vessel_base[0, 2] - z_release
            pts = np.array([[0.0, 0.0, z_release], vessel_base[VESSEL_INSTALLATION]])
            b.add_line(wire_end, top_a, [(_mat_index(scene, inst.wire_material), wire_len, disc.wire_segment_m)], pts,
                       payout=True, l_nom_top=disc.wire_segment_m)
            line_names.append(("wire", [inst.wire_material], [wire_len]))
    body_f = _body_arrays(props, scene, point_masses)
    body_state0 = np.zeros(L.N_BODY_STATE)
    body_state0[L.BS_POS + 2] = z_tip + props.s_tip_m
    body_state0[L.BS_AXIS + 2] = -1.0
    model = _finish(scene, b, body_f, props.quadrature, body_state0, line_names, vessel_base,
                    release_node=release_node, wire_end_node=wire_end, body_active=True,
                    anchor_mass_kg=props.mass_kg, anchor_submerged_mass_kg=props.submerged_mass_kg)
    model.extras["anchor"] = props
    return model


def _compile_catenary_line(scene: SceneConfig) -> Model:
    line = scene.catenary_line
    assert line is not None
    depth = scene.environment.water_depth_m
    b = _Builder()
    anchor_pos = (line.anchor_x_m, 0.0, -depth)
    fair = np.array([[line.fairlead_x_m, 0.0, -line.fairlead_depth_m]])
    bottom = b.add_node(L.NODE_FIXED, anchor_pos)
    top = b.add_node(L.NODE_VESSEL, fair[0], ref=0)
    sections = [(_mat_index(scene, m), length, scene.discretization.catenary_segment_m) for m, length in line.segments]
    total = sum(length for _, length in line.segments)
    pts = hanging_curve(anchor_pos, fair[0], total, -depth)
    b.add_line(bottom, top, sections, pts, payout=False, l_nom_top=scene.discretization.catenary_segment_m)
    names = [("line", [m for m, _ in line.segments], [length for _, length in line.segments])]
    body_f = np.zeros(L.N_BODY_F)
    return _finish(scene, b, body_f, np.zeros((0, L.N_BODY_Q)), np.zeros(L.N_BODY_STATE), names, fair)


def derived_time_step(model: Model, integrator: str, dt_safety: float, key: str = "discretization.integrator"
                      ) -> tuple[float, float, str]:
    """The step ``integrator`` takes on ``model``'s mesh when none is set: ``dt_safety`` times its limit.

    Returns (step [s], largest step accepted [s], what sets it). The implicit step's limit is an accuracy cap, not
    a stability limit: steps up to ``IMPLICIT_STABLE_MULTIPLE`` times it are accepted. An integrator the mesh
    does not allow raises a ConfigError naming ``key``.
    """
    try:
        limit, governed = stable_time_step(model.arrays(), integrator)
    except ValueError as exc:
        raise ConfigError(key, integrator, "symplectic_euler, or rk2 with axial damping", str(exc)) from None
    if not math.isfinite(limit):
        limit = 0.01  # anchor alone: the rigid body has no stiff mode; resolve the fall finely
        governed = "anchor-only default"
    default = dt_safety * limit
    if integrator == "implicit_euler" and governed != "anchor-only default":
        # the implicit step is capped for accuracy, not stability: runs stay stable to a few times the cap
        limit *= IMPLICIT_STABLE_MULTIPLE
        governed = f"{governed}; refused beyond {IMPLICIT_STABLE_MULTIPLE:g}x that accuracy cap"
    return default, limit, governed


def fall_time_step(model: Model) -> tuple[str, float] | None:
    """Integrator and step [s] of the fall where ``discretization.fall_integrator`` sets one other than the
    scene's integrator (always the derived step: ``dt_s`` belongs to the scene's integrator); else None."""
    disc = model.scene.discretization
    if disc.fall_integrator is None or disc.fall_integrator == model.integrator:
        return None
    return disc.fall_integrator, derived_time_step(model, disc.fall_integrator, disc.dt_safety,
                                                   "discretization.fall_integrator")[0]


def _set_time_step(model: Model, scene: SceneConfig) -> None:
    disc = scene.discretization
    model.integrator = disc.integrator
    default, limit, governed = derived_time_step(model, disc.integrator, disc.dt_safety)
    model.dt_limit_s = limit
    model.dt_governed_by = governed
    if disc.dt_s is None:
        model.dt_s = default
    elif disc.dt_s > limit:
        raise ConfigError("discretization.dt_s", disc.dt_s, f"<= {limit:.4g} s",
                          f"stability limit of {disc.integrator} set by the {governed}")
    else:
        model.dt_s = disc.dt_s

"""Scene config -> compiled model: the arrays of the kernels' records and every derived quantity, computed here only.

Second stage of ``YAML -> SceneConfig -> Model -> kernels -> results``. The compiled :class:`Model` holds the
model record's arrays (``physics/records.py``: materials, anchor, environment, current profile; a simulator adds
its own environment copy and vessel tracks) and the initial state (:meth:`Model.initial_state`). A component the
scene does not need is not built: an ``anchor-only`` scene has no nodes at all, ``vertical-chain`` has one line and
no wire.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from moor_env.anchor_properties import anchor_properties, body_arrays
from moor_env.config import SceneConfig
from moor_env.contact_model import contact_arrays
from moor_env.errors import ConfigError
from moor_env.line_mesh import MeshBuilder, hanging_curve
from moor_env.physics import layout as L
from moor_env.physics.records import SimState
from moor_env.physics.stability import stable_time_step
from moor_env.scene_geometry import submerged_mass_per_length

VESSEL_INSTALLATION = 0
VESSEL_SECOND = 1
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

    The arrays of ``records.MODEL_FIELDS`` are attributes of the same names; those of ``records.STATE_FIELDS``
    are the initial state, copied into each simulation state by :meth:`initial_state` (their content changes
    during a run: topology under payout, node kinds at release). The model itself is never modified.
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
    contact_f: np.ndarray
    contact_shape: np.ndarray
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

    def initial_state(self) -> SimState:
        """A new simulation state at the compiled geometry, at rest (arrays copied)."""
        return SimState(node_pos=self.node_pos0.copy(), node_vel=np.zeros_like(self.node_pos0),
                        body_state=self.body_state0.copy(), node_i=self.node_i.copy(), node_f=self.node_f.copy(),
                        seg_i=self.seg_i.copy(), seg_f=self.seg_f.copy(), line_i=self.line_i.copy(),
                        line_f=self.line_f.copy())

    def arrays(self) -> dict[str, np.ndarray]:
        """The kernel arrays by name (views of the model's arrays)."""
        return {k: getattr(self, k) for k in ("node_i", "node_f", "seg_i", "seg_f", "mat_f", "line_i", "line_f",
                                              "env_f")}


def _material_arrays(scene: SceneConfig) -> tuple[np.ndarray, tuple[str, ...]]:
    names = tuple(scene.materials)
    mat_f = np.zeros((len(names), L.N_MAT_F))
    for i, name in enumerate(names):
        m = scene.materials[name]
        mat_f[i] = [m.ea_n, m.mass_per_length_kg_m, submerged_mass_per_length(scene, name), m.diameter_m,
                    m.cd_normal, m.cd_tangential, m.ca_normal, m.ca_tangential, m.axial_damping_ratio, m.mbl_n,
                    m.diameter_m]
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


def _finish(scene: SceneConfig, b: MeshBuilder, body_f, body_q, body_state0, line_names, vessel_base, props=None,
            **extra) -> Model:
    mat_f, mat_names = _material_arrays(scene)
    contact_f, contact_shape = contact_arrays(scene, props)
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
                 contact_f=contact_f, contact_shape=contact_shape, node_pos0=node_pos, body_state0=body_state0,
                 material_names=mat_names, lines=lines,
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
    b = MeshBuilder()
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
    body_f = body_arrays(props, scene, point_masses)
    body_state0 = np.zeros(L.N_BODY_STATE)
    body_state0[L.BS_POS + 2] = z_tip + props.s_tip_m
    body_state0[L.BS_AXIS + 2] = -1.0
    model = _finish(scene, b, body_f, props.quadrature, body_state0, line_names, vessel_base, props=props,
                    release_node=release_node, wire_end_node=wire_end, body_active=True,
                    anchor_mass_kg=props.mass_kg, anchor_submerged_mass_kg=props.submerged_mass_kg)
    model.extras["anchor"] = props
    return model


def _compile_catenary_line(scene: SceneConfig) -> Model:
    line = scene.catenary_line
    assert line is not None
    depth = scene.environment.water_depth_m
    b = MeshBuilder()
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

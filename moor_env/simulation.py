"""Python API of the simulation: statics, release, fall and touchdown of a compiled scene.

Last stage of ``YAML -> SceneConfig -> Model -> kernels -> results``. :class:`Simulator` owns one state and a
preallocated workspace and calls the kernels; :func:`solve_statics` and :func:`simulate_drop` are the one-call
entry points used by the command line.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from moor_env.compile import VESSEL_SECOND, Model, compile_scene, fall_time_step
from moor_env.config import SceneConfig, load_scene
from moor_env.errors import SimulationDiverged, StaticsNotConverged
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg
from moor_env.physics.integrate import (
    FAIL_BODY,
    FAIL_NODE,
    FAIL_SEGMENT,
    INTEGRATOR_IMPLICIT_EULER,
    INTEGRATOR_RK2,
    INTEGRATOR_SYMPLECTIC_EULER,
    advance,
    compute_accelerations,
)
from moor_env.physics.line import top_tensions
from moor_env.physics.statics import solve_equilibrium
from moor_env.physics.statics_guess import change_line_length, check_fibre_clearance
from moor_env.physics.vessels import fill_tracks, jonswap_components, track_samples, wave_track_coefficients

HISTORY_CAPACITY = 20000


def integrator_code(name: str) -> int:
    """The kernels' code of an integrator named as in ``discretization.integrator``."""
    return {"rk2": INTEGRATOR_RK2, "implicit_euler": INTEGRATOR_IMPLICIT_EULER}.get(name, INTEGRATOR_SYMPLECTIC_EULER)


@dataclass
class SimState:
    """Everything that changes during a run (positions, velocities, and the topology under payout)."""

    node_pos: np.ndarray
    node_vel: np.ndarray
    body_state: np.ndarray
    node_i: np.ndarray
    node_f: np.ndarray
    seg_i: np.ndarray
    seg_f: np.ndarray
    line_i: np.ndarray
    line_f: np.ndarray
    t: float = 0.0
    released: bool = False

    def copy(self) -> SimState:
        """Deep copy (arrays copied)."""
        return SimState(self.node_pos.copy(), self.node_vel.copy(), self.body_state.copy(), self.node_i.copy(),
                        self.node_f.copy(), self.seg_i.copy(), self.seg_f.copy(), self.line_i.copy(),
                        self.line_f.copy(), self.t, self.released)


# the array fields of SimState, in order
STATE_ARRAY_FIELDS = ("node_pos", "node_vel", "body_state", "node_i", "node_f", "seg_i", "seg_f", "line_i", "line_f")


class Workspace:
    """Scratch arrays for the kernels, allocated once per simulator."""

    def __init__(self, n_nodes: int, n_segs: int, n_lines: int) -> None:
        self.node_force = np.zeros((n_nodes, 3))
        self.node_mm = np.zeros((n_nodes, 6))
        self.node_mass = np.zeros(n_nodes)
        self.node_contact = np.zeros(n_nodes)
        self.node_acc = np.zeros((n_nodes, 3))
        self.seg_tension = np.zeros(n_segs)
        self.body_load = np.zeros(6)
        self.body_acc = np.zeros(6)
        self.pos0 = np.zeros((n_nodes, 3))
        self.vel0 = np.zeros((n_nodes, 3))
        self.body0 = np.zeros(L.N_BODY_STATE)
        self.touchdown = np.zeros(L.N_TD)
        self.hist = np.zeros((HISTORY_CAPACITY, L.N_HIST))
        self.hist_count = np.zeros(1, dtype=np.int64)
        self.top_tension = np.zeros(n_lines)  # the lines' loads on their vessels [N] (``top_tensions_n``)


class Simulator:
    """One simulation of a compiled model.

    Parameters
    ----------
    model : Model
        From :func:`moor_env.compile.compile_scene`.
    """

    def __init__(self, model: Model) -> None:
        self.model = model
        self.env_f = model.env_f.copy()
        self.work = Workspace(model.node_i.shape[0], model.seg_i.shape[0], model.line_i.shape[0])
        self.state = SimState(node_pos=model.node_pos0.copy(), node_vel=np.zeros_like(model.node_pos0),
                              body_state=model.body_state0.copy(), node_i=model.node_i.copy(),
                              node_f=model.node_f.copy(), seg_i=model.seg_i.copy(), seg_f=model.seg_f.copy(),
                              line_i=model.line_i.copy(), line_f=model.line_f.copy())
        self.dt = model.dt_s
        self.integrator_code = integrator_code(model.integrator)
        self.fall_integration = fall_time_step(model)  # (integrator, step [s]) of the fall, or None; checked here, not
        # at the release, so that a fall integrator the mesh does not allow is refused before any step
        self.vessel_mean_m = model.vessel_base_m.copy()
        self.tracks = np.zeros((1, 2, 6))
        self.sea = _sea_components(model.scene)
        self._wave_coefficients = wave_track_coefficients(self.sea, self.env_f[L.EF_G])
        self.set_vessel_motion(0.0, 1.0, np.zeros(self.vessel_mean_m.shape[0]))
        self.release_point_m: np.ndarray | None = None
        self.release_time_s: float | None = None
        self._loads_of: tuple[SimState, float] | None = None  # (state, t) whose loads the workspace holds

    # --- inputs --------------------------------------------------------------------------------------------
    def set_vessel_motion(self, t0_s: float, duration_s: float, horizontal_speed_m_s: np.ndarray,
                          ramp_s: float | None = None) -> None:
        """Sample the vessel tracks for ``[t0_s, t0_s + duration_s]`` from the current mean positions.

        ``horizontal_speed_m_s`` moves each vessel along x at constant speed over the window (the spacing
        change); the mean positions advance accordingly.
        """
        nv = self.vessel_mean_m.shape[0]
        if nv == 0:
            return
        speeds = np.asarray(horizontal_speed_m_s, float).reshape(nv)
        waves = self.sea is not None
        sample_dt = min(0.05, duration_s) if waves else max(duration_s, 1e-3)
        shape = (nv, track_samples(duration_s, sample_dt), 6)
        # the same window length (every control step) is written in place: the kernels' array stays put
        tracks = self.tracks if self.tracks.shape == shape else np.empty(shape)
        fill_tracks(tracks, t0_s, sample_dt, self.vessel_mean_m, speeds, *self._wave_coefficients)
        if waves and ramp_s is None:
            ramp_s = self.sea["ramp_s"]
        if waves and ramp_s and t0_s < ramp_s:  # past the ramp the factor is 1
            times = t0_s + sample_dt * np.arange(tracks.shape[1])
            factor = np.clip(times / ramp_s, 0.0, 1.0)
            smooth = factor * factor * (3.0 - 2.0 * factor)
            mean = self.vessel_mean_m[:, None, :] + speeds[:, None, None] * (times - t0_s)[None, :, None] * np.array(
                [1.0, 0.0, 0.0])
            tracks[:, :, :3] = mean + smooth[None, :, None] * (tracks[:, :, :3] - mean)
            tracks[:, :, 3:] = speeds[:, None, None] * np.array([1.0, 0.0, 0.0]) + smooth[None, :, None] * (
                tracks[:, :, 3:] - speeds[:, None, None] * np.array([1.0, 0.0, 0.0]))
        self.tracks = tracks
        self.env_f[L.EF_TRACK_T0] = t0_s
        self.env_f[L.EF_TRACK_DT] = sample_dt
        self.vessel_mean_m[:, 0] += speeds * duration_s

    def set_payout_rate(self, line: str, rate_m_s: float) -> None:
        """Winch rate of a line's top [m/s]; positive pays out."""
        info = self.model.lines[line]
        if not self.state.line_i[info.index, L.LI_PAYOUT]:
            raise ValueError(f"line '{line}' has no winch at its top")
        self.state.line_f[info.index, L.LF_RATE] = rate_m_s
        self._loads_of = None

    # --- kernels -------------------------------------------------------------------------------------------
    def evaluate_loads(self) -> tuple[float, int]:
        """Loads and accelerations at the current state (fills the workspace)."""
        st, m, w = self.state, self.model, self.work
        self._loads_of = None  # callers (statics) move nodes in place between evaluations: no record kept
        return compute_accelerations(st.node_pos, st.node_vel, st.body_state, m.body_active, st.node_i, st.node_f,
                                     st.seg_i, st.seg_f, m.mat_f, st.line_f, m.body_f, m.body_q, self.env_f,
                                     m.current_profile, w.node_force, w.node_mm, w.node_mass, w.node_contact,
                                     w.node_acc, w.seg_tension, w.body_load, w.body_acc)

    def advance_to(self, t_end_s: float, detect_touchdown: bool = False, history_every: int = 0) -> tuple[int, int]:
        """Integrate to ``t_end_s`` (or touchdown when ``detect_touchdown``).

        Returns
        -------
        status : int
            ``layout.STATUS_TIME_LIMIT`` or ``layout.STATUS_TOUCHDOWN``.
        n_steps : int

        Raises
        ------
        SimulationDiverged
            On a blow-up, naming the time and the component.
        """
        st, m, w = self.state, self.model, self.work
        status, t, n_steps, fail_kind, fail_index = advance(
            st.t, t_end_s, self.dt, self.integrator_code, m.body_active, detect_touchdown, st.node_pos, st.node_vel,
            st.body_state, st.node_i, st.node_f, st.seg_i, st.seg_f, m.mat_f, st.line_i, st.line_f, m.body_f,
            m.body_q, self.env_f, m.current_profile, self.tracks, w.node_force, w.node_mm, w.node_mass,
            w.node_contact, w.node_acc, w.seg_tension, w.body_load, w.body_acc, w.pos0, w.vel0, w.body0,
            w.touchdown, w.hist, w.hist_count, history_every)
        st.t = t
        if status >= L.STATUS_NONFINITE:
            raise SimulationDiverged(t, self.component_name(fail_kind, fail_index), L.STATUS_NAMES[status])
        return status, n_steps

    def note_loads_evaluated(self) -> None:
        """Record that the workspace holds the loads of the current state: the batch kernel
        (:func:`moor_env.envs.batch.advance_many`) evaluates them after every advance, so
        :meth:`top_tensions_n` need not. Any change of the state in place (release, winch rate, statics) drops
        the record; a new state object or time never matches it."""
        self._loads_of = (self.state, self.state.t)

    def _loads_current(self) -> bool:
        key = self._loads_of
        return key is not None and key[0] is self.state and key[1] == self.state.t

    def loads_record(self) -> tuple[SimState, float] | None:
        """The record of :meth:`note_loads_evaluated` while it is of the current state (None otherwise): an object
        that callers may keep to tell later whether the state is still the one the kernel left."""
        return self._loads_of if self._loads_current() else None

    def component_name(self, fail_kind: int, index: int) -> str:
        """Human name of a failing component reported by the kernel."""
        if fail_kind == FAIL_BODY:
            return "anchor"
        if fail_kind == FAIL_SEGMENT:
            line = int(self.state.seg_i[index, L.SI_LINE])
            name = self._line_name(line)
            return f"line '{name}' segment {index - self.state.line_i[line, L.LI_SEG_START]}"
        if fail_kind == FAIL_NODE:
            line = int(self.state.node_i[index, L.NI_LINE])
            if line < 0:
                return f"connection node {index}"
            return f"line '{self._line_name(line)}' node {index - self.state.line_i[line, L.LI_NODE_START] + 1}"
        return "unknown"

    def _line_name(self, index: int) -> str:
        return next(name for name, info in self.model.lines.items() if info.index == index)

    # --- events --------------------------------------------------------------------------------------------
    def release(self) -> None:
        """Open the release unit: the chain top goes free; the wire (if kept) recoils, else it is dropped. From
        here on the fall's integrator and step (``discretization.fall_integrator``) apply, where set."""
        st, m = self.state, self.model
        if st.released:
            return
        self._loads_of = None
        if self.fall_integration is not None:
            self.integrator_code = integrator_code(self.fall_integration[0])
            self.dt = self.fall_integration[1]
        if m.release_node >= 0:
            self.release_point_m = st.node_pos[m.release_node].copy()
            st.node_i[m.release_node, L.NI_KIND] = L.NODE_FREE
        else:
            self.release_point_m = self.tip_state()[0] if m.body_active else None
        if m.wire_end_node >= 0:
            wire = m.lines["wire"].index
            if m.scene.installation.components.keep_wire_after_release:
                st.node_i[m.wire_end_node, L.NI_KIND] = L.NODE_FREE
            else:
                _deactivate_line(st, wire)
        st.released = True
        self.release_time_s = st.t

    # --- outputs -------------------------------------------------------------------------------------------
    def tip_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Anchor tip position [m] and velocity [m/s]."""
        b = self.state.body_state
        s = self.model.body_f[L.BF_S_TIP]
        e = b[L.BS_AXIS: L.BS_AXIS + 3]
        w = b[L.BS_OMEGA: L.BS_OMEGA + 3]
        return b[L.BS_POS: L.BS_POS + 3] + s * e, b[L.BS_VEL: L.BS_VEL + 3] + s * np.cross(w, e)

    def back_end_m(self) -> np.ndarray:
        """Centre of the anchor's back end (the tip minus its length along the axis) [m]."""
        axis = self.state.body_state[L.BS_AXIS:L.BS_AXIS + 3]
        return self.tip_state()[0] - self.model.body_f[L.BF_LENGTH] * axis

    def tilt_deg(self) -> float:
        """Angle of the anchor axis from vertical (tip down) [deg]."""
        ez = self.state.body_state[L.BS_AXIS + 2]
        return float(tilt_deg(ez))

    def line_past_back_end_m(self, line: str) -> tuple[float, float]:
        """How far ``line`` reaches past the anchor's back end: the largest distance of one of its nodes beyond the
        back end along the anchor's axis towards the tip [m] (negative: every node is behind the back end), and
        that node's distance from the axis [m].

        Why: the lines have no contact with the anchor's body. A chain that falls faster than the anchor (lengthwise,
        with the seed's tangential drag, it does) reaches the back end during the fall and passes into the body
        instead of piling onto it; where this happens, the touchdown rests on a part of the fall the model does not
        represent (README, "Accuracy of the fall").
        """
        st = self.state
        idx = self.model.lines[line].index
        first = st.line_i[idx, L.LI_SEG_START]
        nodes = st.seg_i[first:first + st.line_i[idx, L.LI_NSEG], L.SI_B]
        axis = st.body_state[L.BS_AXIS:L.BS_AXIS + 3]
        rel = st.node_pos[nodes] - self.back_end_m()
        along = rel @ axis
        k = int(np.argmax(along))
        return float(along[k]), float(np.linalg.norm(rel[k] - along[k] * axis))

    def top_tensions_n(self) -> dict[str, float]:
        """Load of each line on its vessel (top-segment tension plus the top half-segment's weight and drag),
        or the top segment's tension for a line ending at a connection node [N], at the current state
        (:func:`moor_env.physics.line.top_tensions`; the batch kernel leaves them with the loads)."""
        st, w = self.state, self.work
        if not self._loads_current():
            self.evaluate_loads()
            top_tensions(st.line_i, st.seg_i, st.node_i, w.node_force, w.seg_tension, w.top_tension)
        values = w.top_tension.tolist()
        return {name: values[info.index] for name, info in self.model.lines.items()}

    def line_length_on_seabed_m(self, material_names: set[str] | None = None, tolerance_m: float = 0.5) -> float:
        """Unstretched length of segments with both ends within ``tolerance_m`` of the seabed [m]."""
        st = self.state
        floor = -self.env_f[L.EF_DEPTH] + tolerance_m
        total = 0.0
        for s in np.nonzero(st.seg_i[:, L.SI_ACTIVE])[0]:
            name = self.model.material_names[st.seg_i[s, L.SI_MAT]]
            if material_names is not None and name not in material_names:
                continue
            if st.node_pos[st.seg_i[s, L.SI_A], 2] <= floor and st.node_pos[st.seg_i[s, L.SI_B], 2] <= floor:
                total += st.seg_f[s, L.SF_L0]
        return total

    def line_mass_kg(self, line: str) -> float:
        """Mass in air of a line from its unstretched segment lengths [kg]."""
        st = self.state
        idx = self.model.lines[line].index
        segs = np.nonzero((st.seg_i[:, L.SI_LINE] == idx) & (st.seg_i[:, L.SI_ACTIVE] == 1))[0]
        return float(np.sum(self.model.mat_f[st.seg_i[segs, L.SI_MAT], L.MF_MASS] * st.seg_f[segs, L.SF_L0]))

    def line_length_m(self, line: str) -> float:
        """Unstretched length of a line [m]."""
        st = self.state
        idx = self.model.lines[line].index
        segs = np.nonzero((st.seg_i[:, L.SI_LINE] == idx) & (st.seg_i[:, L.SI_ACTIVE] == 1))[0]
        return float(np.sum(st.seg_f[segs, L.SF_L0]))

    def mechanical_energy_j(self) -> float:
        """Kinetic + gravitational/buoyancy potential + elastic energy [J] (added mass included in kinetic)."""
        st, m = self.state, self.model
        self.evaluate_loads()
        w = self.work
        g = self.env_f[L.EF_G]
        rho = self.env_f[L.EF_RHO]
        free = np.nonzero(st.node_i[:, L.NI_KIND] == L.NODE_FREE)[0]
        v = st.node_vel[free]
        mm = w.node_mm[free]
        kinetic = 0.5 * np.sum(w.node_mass[free] * np.sum(v * v, axis=1))
        kinetic += 0.5 * np.sum(mm[:, 0] * v[:, 0] ** 2 + mm[:, 1] * v[:, 1] ** 2 + mm[:, 2] * v[:, 2] ** 2
                                + 2 * (mm[:, 3] * v[:, 0] * v[:, 1] + mm[:, 4] * v[:, 0] * v[:, 2]
                                       + mm[:, 5] * v[:, 1] * v[:, 2]))
        potential = 0.0
        elastic = 0.0
        for s in np.nonzero(st.seg_i[:, L.SI_ACTIVE])[0]:
            a, b, mat = st.seg_i[s, L.SI_A], st.seg_i[s, L.SI_B], st.seg_i[s, L.SI_MAT]
            l0 = st.seg_f[s, L.SF_L0]
            potential += m.mat_f[mat, L.MF_SUBMERGED] * g * 0.5 * l0 * (st.node_pos[a, 2] + st.node_pos[b, 2])
            length = np.linalg.norm(st.node_pos[b] - st.node_pos[a])
            if length > l0:
                elastic += 0.5 * m.mat_f[mat, L.MF_EA] / l0 * (length - l0) ** 2
        for n in np.nonzero((st.node_i[:, L.NI_KIND] == L.NODE_FREE) | (st.node_i[:, L.NI_KIND] == L.NODE_WELDED))[0]:
            potential += (st.node_f[n, L.NF_POINT_MASS] - rho * st.node_f[n, L.NF_POINT_VOLUME]) * g * st.node_pos[n, 2]
        if m.body_active:
            b = st.body_state
            bf = m.body_f
            e = b[L.BS_AXIS: L.BS_AXIS + 3]
            vel = b[L.BS_VEL: L.BS_VEL + 3]
            va = vel @ e
            vn = vel - va * e
            rot = np.cross(b[L.BS_OMEGA: L.BS_OMEGA + 3], e)
            kinetic += 0.5 * bf[L.BF_MASS_AXIAL] * va**2 + 0.5 * (
                bf[L.BF_M11] * vn @ vn + 2 * bf[L.BF_M12] * vn @ rot + bf[L.BF_M22] * rot @ rot)
            z_g = b[L.BS_POS + 2]
            potential += bf[L.BF_WEIGHT] * z_g - bf[L.BF_BUOYANCY] * (z_g + bf[L.BF_S_BUOY] * e[2])
        return float(kinetic + potential + elastic)

    def history(self) -> np.ndarray:
        """Recorded tip history rows (see ``layout.H_*``)."""
        return self.work.hist[: self.work.hist_count[0]].copy()


def _deactivate_line(st: SimState, line: int) -> None:
    segs = st.seg_i[:, L.SI_LINE] == line
    st.seg_i[segs, L.SI_ACTIVE] = 0
    nodes = st.node_i[:, L.NI_LINE] == line
    st.node_i[nodes, L.NI_KIND] = L.NODE_INACTIVE
    for end in (L.LI_BOTTOM, L.LI_TOP):
        st.node_i[st.line_i[line, end], L.NI_KIND] = L.NODE_INACTIVE
    st.line_i[line, L.LI_PAYOUT] = 0


def _sea_components(scene: SceneConfig) -> dict | None:
    sea = scene.environment.sea_state
    if sea.hs_m <= 0.0:
        return None
    amp, omega, phase = jonswap_components(sea.hs_m, sea.tp_s, sea.gamma, sea.n_components, sea.seed)
    return {"amplitude": amp, "omega": omega, "phase": phase, "natural_period_s": sea.vessel_natural_period_s,
            "damping_ratio": sea.vessel_damping_ratio, "ramp_s": 2.0 * sea.tp_s}


# --- statics -------------------------------------------------------------------------------------------------
@dataclass
class StaticResult:
    """Equilibrium before release."""

    simulator: Simulator
    release_point_m: list[float] | None
    tip_height_above_seabed_m: float | None
    tilt_deg: float | None
    top_tensions_n: dict[str, float]
    wire_length_m: float | None
    iterations: int
    wall_static_s: float
    method: str = "newton"  # the solver that finished: "newton", or "relaxation" (the fallback)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        d = {k: v for k, v in asdict(self).items() if k != "simulator"}
        d["n_nodes"] = int(np.sum(self.simulator.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE))
        return d


def _adjust_to_drop_height(sim: Simulator, target_z: float) -> float:
    """Error of the tip height against the target [m], positive when the tip hangs too high."""
    tip, _ = sim.tip_state()
    return float(tip[2] - target_z)


def solve_statics(scene: SceneConfig | Model, tol_m: float = 1e-3, progress: bool = True,
                  method: str = "auto") -> StaticResult:
    """Hanging equilibrium before release (seed 003 Model 1), drop height held at its set value.

    For an installation scene with a wire, the wire's unstretched length is corrected (at its top) until the
    anchor tip hangs ``drop_height_m`` above the seabed within ``tol_m``; without a wire, the held chain top
    is moved instead. ``method``: "auto" (Newton's method, and the slow relaxation solver where it does not
    converge), "newton" or "relaxation" (one of them only; :func:`moor_env.physics.statics.solve_equilibrium`).

    Raises
    ------
    moor_env.errors.NoEquilibrium
        The scene has none (the cause and the key to change are named).
    moor_env.errors.StaticsNotConverged
    """
    t0 = time.perf_counter()
    model = scene if isinstance(scene, Model) else compile_scene(scene)
    sim = Simulator(model)
    report = solve_equilibrium(sim, progress=progress, method=method)
    iterations = report.iterations
    finished = report.method
    sc = model.scene
    if sc.kind == "dart_installation" and model.release_node >= 0:
        target = -sc.environment.water_depth_m + sc.installation.drop_height_m
        for _ in range(8):
            err = _adjust_to_drop_height(sim, target)
            if abs(err) < tol_m:
                break
            if model.wire_end_node >= 0:
                change_line_length(sim.state, model.lines["wire"].index, err)
            else:
                sim.state.node_pos[model.release_node, 2] -= err
            warm = solve_equilibrium(sim, warm=True, progress=progress, method=method)
            iterations += warm.iterations
            finished = "relaxation" if warm.method == "relaxation" else finished
        else:
            err = _adjust_to_drop_height(sim, target)
            if abs(err) >= tol_m:
                raise StaticsNotConverged(f"the anchor tip hangs {err:+.3g} m from its drop height after 8 wire "
                                          f"corrections (tolerance {tol_m:g} m)", None)
        check_fibre_clearance(sim)
    sim.state.line_f[:, L.LF_MAX_TENSION] = 0.0
    wall = time.perf_counter() - t0
    release = None
    tip_h = tilt = None
    if model.body_active:
        tip, _ = sim.tip_state()
        tip_h = float(tip[2] + sc.environment.water_depth_m)
        tilt = sim.tilt_deg()
    if model.release_node >= 0:
        release = sim.state.node_pos[model.release_node].tolist()
    wire_len = sim.line_length_m("wire") if "wire" in model.lines else None
    return StaticResult(simulator=sim, release_point_m=release, tip_height_above_seabed_m=tip_h, tilt_deg=tilt,
                        top_tensions_n=sim.top_tensions_n(), wire_length_m=wire_len, iterations=iterations,
                        wall_static_s=wall, method=finished)


# --- drop ----------------------------------------------------------------------------------------------------
@dataclass
class DropResult:
    """Outcome of a release and fall (times from the release instant)."""

    status: str
    touchdown_time_s: float | None
    touchdown_speed_m_s: float | None
    touchdown_vertical_speed_m_s: float | None
    tilt_deg: float | None
    drift_m: float | None
    release_point_m: list[float] | None
    release_time_s: float
    chain_on_seabed_m: float
    chain_past_back_end_m: float | None  # Simulator.line_past_back_end_m of the vertical chain, at the end
    max_tension_n: dict[str, float]
    n_nodes: int
    n_steps: int
    dt_s: float
    wall_static_s: float
    wall_dynamic_s: float
    history: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, L.N_HIST)))
    snapshots: list = field(repr=False, default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (history and snapshots left out)."""
        return {k: v for k, v in asdict(self).items() if k not in ("history", "snapshots")}


def simulate_drop(scene: str | Path | SceneConfig, overrides: dict[str, Any] | None = None,
                  keep_snapshots: bool = False, history: bool = True, progress: bool = False) -> DropResult:
    """Statics, optional pre-release dynamics, release, fall to touchdown.

    Parameters
    ----------
    scene : str, Path or SceneConfig
        Bundled scene name, YAML path or a loaded scene.
    overrides : dict, optional
        ``--set`` style overrides (see :data:`moor_env.config.SET_SHORTCUTS`).
    keep_snapshots : bool
        Store node positions and the anchor axis every ``simulation.snapshot_interval_s`` (for plots).
    history : bool
        Record the tip state every ``simulation.record_interval_s``.
    progress : bool
        Show a progress bar over simulated time.

    Raises
    ------
    SimulationDiverged
        If the integration blows up (time and component named).
    """
    cfg = scene if isinstance(scene, SceneConfig) else load_scene(scene, overrides)
    static = solve_statics(cfg)
    sim = static.simulator
    return run_drop(sim, static.wall_static_s, keep_snapshots=keep_snapshots, history=history, progress=progress)


def run_drop(sim: Simulator, wall_static_s: float = 0.0, keep_snapshots: bool = False,
             history: bool = True, progress: bool = False) -> DropResult:
    """Pre-release phase (if ``release_time_s`` > 0), release and fall of a simulator at equilibrium."""
    sc = sim.model.scene
    inst = sc.installation
    t0 = time.perf_counter()
    release_time = inst.release_time_s if inst is not None else 0.0
    max_fall = sc.simulation.max_fall_time_s
    window = release_time + max_fall + 1.0
    speeds = np.zeros(sim.vessel_mean_m.shape[0])
    if inst is not None and sim.vessel_mean_m.shape[0] > VESSEL_SECOND and inst.spacing_rate_m_s:
        speeds[VESSEL_SECOND] = inst.spacing_rate_m_s
    sim.set_vessel_motion(0.0, window, speeds)
    if inst is not None and inst.payout_rate_m_s and "mooring_line" in sim.model.lines:
        sim.set_payout_rate("mooring_line", inst.payout_rate_m_s)
    n_steps = 0
    if release_time > 0:
        _, n = sim.advance_to(release_time)
        n_steps += n
    if "mooring_line" in sim.model.lines:
        sim.set_payout_rate("mooring_line", 0.0)
    sim.release()
    hist_every = max(1, int(round(sc.simulation.record_interval_s / sim.dt))) if history else 0
    tip0, _ = sim.tip_state()
    snapshots = []
    t_stop = sim.state.t + max_fall
    status = L.STATUS_TIME_LIMIT
    interval = sc.simulation.snapshot_interval_s if keep_snapshots else (0.25 if progress else max_fall)
    bar = tqdm(total=round(max_fall, 2), unit="s sim", disable=not progress, leave=False,
               bar_format="{l_bar}{bar}| {n:.2f}/{total:.0f} s simulated [{elapsed}]")
    t_fall0 = sim.state.t
    while sim.state.t < t_stop - 1e-9:
        if keep_snapshots:
            snapshots.append(_snapshot(sim))
        status, n = sim.advance_to(min(sim.state.t + interval, t_stop), detect_touchdown=sim.model.body_active,
                                   history_every=hist_every)
        n_steps += n
        bar.update(round(sim.state.t - t_fall0, 2) - bar.n)
        if status == L.STATUS_TOUCHDOWN:
            break
    bar.close()
    if keep_snapshots:
        snapshots.append(_snapshot(sim))
    wall = time.perf_counter() - t0
    td = sim.work.touchdown
    touched = status == L.STATUS_TOUCHDOWN
    max_tension = {name: float(sim.state.line_f[info.index, L.LF_MAX_TENSION])
                   for name, info in sim.model.lines.items()}
    chain = {sc.installation.chain_material} if inst is not None else None
    result = DropResult(
        status="touchdown" if touched else "no touchdown within max_fall_time_s",
        touchdown_time_s=float(td[L.TD_TIME] - sim.release_time_s) if touched else None,
        touchdown_speed_m_s=float(np.linalg.norm(td[L.TD_VEL:L.TD_VEL + 3])) if touched else None,
        touchdown_vertical_speed_m_s=float(-td[L.TD_VEL + 2]) if touched else None,
        tilt_deg=float(tilt_deg(td[L.TD_AXIS + 2])) if touched else None,
        drift_m=float(np.hypot(td[L.TD_TIP] - tip0[0], td[L.TD_TIP + 1] - tip0[1])) if touched else None,
        release_point_m=None if sim.release_point_m is None else [float(v) for v in sim.release_point_m],
        release_time_s=float(sim.release_time_s),
        chain_on_seabed_m=sim.line_length_on_seabed_m(chain),
        chain_past_back_end_m=sim.line_past_back_end_m("vertical_chain")[0]
        if sim.model.body_active and "vertical_chain" in sim.model.lines else None,
        max_tension_n=max_tension,
        n_nodes=int(np.sum(sim.state.node_i[:, L.NI_KIND] != L.NODE_INACTIVE)),
        n_steps=n_steps, dt_s=sim.dt, wall_static_s=wall_static_s, wall_dynamic_s=wall,
        history=sim.history(), snapshots=snapshots,
    )
    return result


def _snapshot(sim: Simulator) -> dict[str, Any]:
    st = sim.state
    lines = {}
    for name, info in sim.model.lines.items():
        li = st.line_i[info.index]
        if not st.seg_i[li[L.LI_SEG_START], L.SI_ACTIVE]:
            continue
        segs = range(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])
        nodes = [st.seg_i[segs[0], L.SI_A]] + [st.seg_i[s, L.SI_B] for s in segs]
        lines[name] = st.node_pos[nodes].copy()
    active = sim.model.body_active
    return {"t": st.t, "lines": lines, "tip": sim.tip_state()[0] if active else None,
            "back": sim.back_end_m() if active else None}

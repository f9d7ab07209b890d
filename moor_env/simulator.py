"""The simulator: one state of a compiled scene, its work arrays and the kernel calls that advance it.

:class:`Simulator` owns a :class:`~moor_env.physics.records.SimState` and a
:data:`~moor_env.physics.records.Workspace`, keeps the kernels' model and state records of them
(:meth:`Simulator.records`) and reads results off the state. The one-call entry points (statics, drop) are in
``moor_env/simulation.py``.
"""

from __future__ import annotations

import numpy as np

from moor_env.compile import Model, fall_time_step
from moor_env.config import SceneConfig
from moor_env.errors import SimulationDiverged
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg
from moor_env.physics.anchor_surface import deepest_segment_point, length_on_surface
from moor_env.physics.integrate import (
    FAIL_BODY,
    FAIL_NODE,
    FAIL_SEGMENT,
    INTEGRATOR_IMPLICIT_EULER,
    INTEGRATOR_RK2,
    INTEGRATOR_SYMPLECTIC_EULER,
    advance,
)
from moor_env.physics.line import top_tensions
from moor_env.physics.loads import compute_accelerations
from moor_env.physics.records import (
    ModelRecord,
    SimState,
    StateRecord,
    model_record,
    new_workspace,
    state_record,
)
from moor_env.physics.vessels import fill_tracks, jonswap_components, track_samples, wave_track_coefficients


def integrator_code(name: str) -> int:
    """The kernels' code of an integrator named as in ``discretization.integrator``."""
    return {"rk2": INTEGRATOR_RK2, "implicit_euler": INTEGRATOR_IMPLICIT_EULER}.get(name, INTEGRATOR_SYMPLECTIC_EULER)


class Simulator:
    """One simulation of a compiled model.

    Parameters
    ----------
    model : Model
        From :func:`moor_env.compile.compile_scene`.

    Attributes
    ----------
    model : Model
        The compiled scene (replace it only by one of the same mesh, e.g. for another integrator).
    state : SimState
        The simulation state; replace it to restore another (its arrays are changed in place, never replaced).
    work : Workspace
        The work arrays: the loads of the last evaluation, integrator scratch, touchdown record, tip history.
    env_f : ndarray
        This simulator's environment array (``layout.EF_*``; a copy of the model's, changed in place).
    tracks : ndarray
        The sampled vessel motion the kernels read (:meth:`set_vessel_motion`).
    dt : float
        The integration step [s].
    step_growth_max : float
        How many times an implicit step may grow where the lines move slower than its cap assumes
        (:func:`~moor_env.physics.integrate.speed_step_factor`); 1 (fixed steps) until the release, then
        ``discretization.fall_step_growth_max``.
    """

    def __init__(self, model: Model) -> None:
        self.model = model
        self.env_f = model.env_f.copy()
        self.work = new_workspace(model.node_i.shape[0], model.seg_i.shape[0], model.line_i.shape[0])
        self.state = model.initial_state()
        self.dt = model.dt_s
        self.integrator_code = integrator_code(model.integrator)
        self.step_growth_max = 1.0
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
        self._records: tuple[ModelRecord | None, StateRecord | None] = (None, None)
        self._records_of: tuple = (None, None, None)  # the model, state and work the records were made of

    # --- the kernels' records ------------------------------------------------------------------------------
    def records(self) -> tuple[ModelRecord, StateRecord]:
        """The model and state records every kernel takes (``physics/records.py``). Each is built once and again
        only when one of the attributes it is made of (model, env_f, tracks; state, work) has been replaced by
        another object since: arrays changed in place need nothing."""
        model, state = self._records
        if model is None or model.tracks is not self.tracks or model.env_f is not self.env_f or (
                self._records_of[0] is not self.model):
            model = model_record(self.model, env_f=self.env_f, tracks=self.tracks)
        if state is None or self._records_of[1] is not self.state or self._records_of[2] is not self.work:
            state = state_record(self.state, self.work)
        self._records = (model, state)
        self._records_of = (self.model, self.state, self.work)
        return self._records

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
        """Loads and accelerations at the current state (fills the work arrays)."""
        self._loads_of = None  # callers (statics) move nodes in place between evaluations: no record kept
        return compute_accelerations(*self.records())

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
        st = self.state
        status, t, n_steps, fail_kind, fail_index = advance(*self.records(), st.t, t_end_s, self.dt,
                                                            self.integrator_code, detect_touchdown, history_every,
                                                            self.step_growth_max)
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
        self.step_growth_max = m.scene.discretization.fall_step_growth_max
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
        self.work.contact_out[:] = 0.0  # the contact's peaks count from the release

    # --- outputs -------------------------------------------------------------------------------------------
    def tip_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Anchor tip position [m] and velocity [m/s]."""
        b = self.state.body_state
        s = self.model.body_f[L.BF_S_TIP]
        e = b[L.BS_AXIS: L.BS_AXIS + 3]
        w = b[L.BS_OMEGA: L.BS_OMEGA + 3]
        w_x_e = np.array([w[1] * e[2] - w[2] * e[1], w[2] * e[0] - w[0] * e[2], w[0] * e[1] - w[1] * e[0]])
        return b[L.BS_POS: L.BS_POS + 3] + s * e, b[L.BS_VEL: L.BS_VEL + 3] + s * w_x_e

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

        Why: a chain that falls faster than the anchor (lengthwise, with the seed's tangential drag, it does)
        reaches the back end during the fall. With the line-anchor contact (``discretization.line_anchor_contact``)
        it lands there and this is about 0; without it the chain passes into the body.
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

    def line_on_anchor_m(self, line: str, tolerance_m: float = 0.05) -> float:
        """Unstretched length of ``line`` resting on the anchor: its segments with both ends within ``tolerance_m``
        of the anchor's surface or inside it [m] (:func:`moor_env.physics.anchor_surface.length_on_surface`)."""
        st = self.state
        idx = self.model.lines[line].index
        return float(length_on_surface(st.node_pos, st.seg_i, st.seg_f, st.line_i[idx, L.LI_SEG_START],
                                       st.line_i[idx, L.LI_NSEG], st.body_state, self.model.contact_shape,
                                       tolerance_m))

    def deepest_segment_inside_m(self) -> float:
        """How deep the deepest point of any line lies inside the anchor's surface now, segment interiors included
        [m] (0 where none does, without an anchor, or where the scene does not model the contact, whose surface
        it measures; :func:`moor_env.physics.anchor_surface.deepest_segment_point`). The contact holds nodes and
        segments out to within its penalty's depth (``physics/contact.py``, ``physics/segment_contact.py``)."""
        if not self.model.body_active:
            return 0.0
        st = self.state
        return float(deepest_segment_point(st.node_pos, st.seg_i, st.body_state, self.model.contact_shape)[0])

    def contact_report(self) -> dict[str, float]:
        """What the line-anchor contact did since the release: its peak net force on the anchor [N] and the deepest
        a node went inside the anchor's surface [m] (zeros where the contact is off)."""
        out = self.work.contact_out
        return {"peak_force_n": float(out[L.CO_PEAK_FORCE]), "peak_depth_m": float(out[L.CO_PEAK_DEPTH])}

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

"""The observation: 27 physical quantities, normalised and clipped (:data:`OBS_SPEC`).

:func:`raw_observation` assembles the vector in physical units from the batch kernel's measures of the state
(:func:`moor_env.envs.measures.measure_scene`) and the slot's own bookkeeping; :func:`normalise_observations` turns
rows of them into what the agent sees.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.envs import measures as M

# --- observation: (name, unit, offset, scale, meaning); normalised value = (raw - offset) / scale ----------------
OBS_SPEC: tuple[tuple[str, str, float, float, str], ...] = (
    ("time_fraction", "-", 0.5, 0.5, "time since the first observation / control.max_pre_release_s"),
    ("released", "-", 0.5, 0.5, "1 after the release, else 0"),
    ("vessel_spacing_m", "m", 125.0, 100.0, "horizontal distance between the two vessels' mean positions"),
    ("spacing_rate_m_s", "m/s", 0.0, 0.5, "second vessel's speed away from the installation vessel"),
    ("line_length_over_depth", "-", 1.06, 0.1, "mooring line length (vertical chain + loop chain + fibre) / depth"),
    ("payout_rate_m_s", "m/s", 0.0, 0.3, "mooring-line winch rate, + pays out"),
    ("release_node_dx_m", "m", 0.0, 5.0, "release node x minus its x at the start of the episode"),
    ("release_node_dy_m", "m", 0.0, 5.0, "release node y minus its y at the start"),
    ("release_node_dz_m", "m", 0.0, 5.0, "release node z minus its z at the start"),
    ("release_node_vx_m_s", "m/s", 0.0, 1.0, "release node velocity x"),
    ("release_node_vy_m_s", "m/s", 0.0, 1.0, "release node velocity y"),
    ("release_node_vz_m_s", "m/s", 0.0, 1.0, "release node velocity z (up +)"),
    ("tilt_deg", "deg", 0.0, 5.0, "anchor axis angle from vertical"),
    ("tilt_rate_deg_s", "deg/s", 0.0, 5.0, "angular speed of the anchor axis"),
    ("wire_tension_mn", "MN", 1.25, 1.25, "installation wire load on its vessel (0 after release)"),
    ("mooring_line_tension_mn", "MN", 0.5, 0.5, "mooring line load on the second vessel"),
    ("vessel_heave_m", "m", 0.0, 2.0, "installation vessel heave"),
    ("vessel_heave_rate_m_s", "m/s", 0.0, 1.0, "installation vessel heave velocity"),
    ("current_surface_x_m_s", "m/s", 0.0, 1.0, "surface current, x (towards the second vessel)"),
    ("current_surface_y_m_s", "m/s", 0.0, 1.0, "surface current, y"),
    ("water_depth_m", "m", 500.0, 200.0, "water depth"),
    ("tip_height_m", "m", 68.5, 20.0, "anchor tip height above the seabed"),
    ("loop_bottom_height_m", "m", 80.0, 60.0, "lowest mooring-line node above the seabed"),
    ("fibre_clearance_m", "m", 100.0, 100.0, "lowest fibre-rope node above the seabed"),
    ("sea_state_hs_m", "m", 1.5, 1.5, "significant wave height (forecast)"),
    ("sea_state_tp_s", "s", 10.0, 3.0, "peak period (forecast)"),
    ("vertical_chain_length_m", "m", 50.0, 25.0, "chain hanging between the anchor and the release node"),
)
OBS_NAMES: tuple[str, ...] = tuple(row[0] for row in OBS_SPEC)
OBS_UNITS: tuple[str, ...] = tuple(row[1] for row in OBS_SPEC)
OBS_OFFSET = np.array([row[2] for row in OBS_SPEC])
OBS_SCALE = np.array([row[3] for row in OBS_SPEC])
OBS_CLIP = 5.0


def normalise_observations(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of raw observations (physical units, float64[n, len(OBS_NAMES)]) normalised, clipped to +-OBS_CLIP and
    as float32, with a mask of the rows that were finite (a row that is not must be replaced by its slot's last
    observation). Row by row the same numbers whatever the number of rows, so that the batched env's rows equal
    the single env's observations."""
    obs = (raw - OBS_OFFSET) / OBS_SCALE
    finite = np.isfinite(obs).all(axis=1)
    np.clip(obs, -OBS_CLIP, OBS_CLIP, out=obs)
    return obs.astype(np.float32), finite


def raw_observation(m: list[float], *, time_fraction: float, released: bool, spacing_m: float,
                    spacing_rate_m_s: float, payout_rate_m_s: float, depth_m: float, vertical_chain_m: float,
                    fairlead_depth_m: float, release_ref: np.ndarray, hs_m: float, tp_s: float) -> list[float]:
    """Observation in physical units (see :data:`OBS_SPEC`) from the kernel's measures ``m`` (``M_*`` of
    :mod:`moor_env.envs.measures`) and the slot's own state: the applied rates, the scenario's depth, vertical
    chain, fairlead depth and sea state, and the release node's position at the start (``release_ref``).

    Python floats: it runs every step, where small numpy operations cost more than the arithmetic.
    """
    fibre = m[M.M_FIBRE_Z_M] + depth_m
    loop_bottom = m[M.M_LOOP_Z_M] + depth_m
    return [
        time_fraction,
        1.0 if released else 0.0,
        spacing_m,
        spacing_rate_m_s,
        (m[M.M_LINE_L0_M] + vertical_chain_m) / depth_m,
        payout_rate_m_s,
        m[M.M_RELEASE_POS] - release_ref[0],
        m[M.M_RELEASE_POS + 1] - release_ref[1],
        m[M.M_RELEASE_POS + 2] - release_ref[2],
        m[M.M_RELEASE_VEL],
        m[M.M_RELEASE_VEL + 1],
        m[M.M_RELEASE_VEL + 2],
        m[M.M_TILT_DEG],
        m[M.M_AXIS_RATE_DEG_S],
        m[M.M_WIRE_TENSION_N] / 1e6,
        m[M.M_LINE_TENSION_N] / 1e6,
        m[M.M_HEAVE_M] + fairlead_depth_m,
        m[M.M_HEAVE_RATE_M_S],
        m[M.M_CURRENT_X_M_S],
        m[M.M_CURRENT_Y_M_S],
        depth_m,
        m[M.M_TIP_Z_M] + depth_m,
        loop_bottom if math.isfinite(loop_bottom) else 0.0,
        fibre if math.isfinite(fibre) else 1000.0,
        hs_m,
        tp_s,
        vertical_chain_m,
    ]

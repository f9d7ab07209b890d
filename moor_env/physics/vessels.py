"""Vessel tops: prescribed tracks from a sea state and a slow spacing change.

Sea state: a JONSWAP spectrum (DNV-RP-C205 eq. 3.5.5) discretised into ``n`` equal-width frequency bins
between 0.5 and 3 times the peak frequency, with phases drawn from ``numpy.random.default_rng(seed)``.

Motion transfer (documented simplification, not a vessel RAO from diffraction): each vessel's heave and
surge follow the wave surface elevation and the horizontal orbital displacement (deep water) at the
vessel, filtered by a second-order low pass with natural period ``T_n`` and damping ratio ``zeta``:

    H(w) = 1 / (1 - (w/w_n)^2 + 2 i zeta w/w_n)

Long waves are followed one to one; short waves are filtered out, as for a large installation vessel.
Waves propagate along +x; the second vessel sees them with the phase lag k * spacing.

Tracks are sampled once per run (Python/numpy) at a fixed interval and interpolated linearly in the
kernel, so no trigonometry is evaluated per time step.
"""

from __future__ import annotations

import math

import numpy as np

from moor_env.physics._jit import jit
from moor_env.physics.layout import EF_TRACK_DT, EF_TRACK_T0


def jonswap_components(hs_m: float, tp_s: float, gamma: float, n_components: int, seed: int):
    """Wave components of a JONSWAP sea.

    Returns
    -------
    amplitude_m, omega_rad_s, phase_rad : ndarray, shape (n_components,)
        Component amplitudes [m], angular frequencies [rad/s] and random phases [rad].
    """
    wp = 2.0 * math.pi / tp_s
    edges = np.linspace(0.5 * wp, 3.0 * wp, n_components + 1)
    omega = 0.5 * (edges[1:] + edges[:-1])
    dw = edges[1] - edges[0]
    sigma = np.where(omega <= wp, 0.07, 0.09)
    pm = 5.0 / 16.0 * hs_m**2 * wp**4 * omega**-5 * np.exp(-1.25 * (omega / wp) ** -4)
    a_gamma = 1.0 - 0.287 * math.log(gamma)
    spectrum = a_gamma * pm * gamma ** np.exp(-0.5 * ((omega - wp) / (sigma * wp)) ** 2)
    amplitude = np.sqrt(2.0 * spectrum * dw)
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * math.pi, n_components)
    return amplitude, omega, phase


def motion_transfer(omega: np.ndarray, natural_period_s: float, damping_ratio: float) -> np.ndarray:
    """Complex heave/surge transfer H(w) of the documented second-order low pass."""
    r = omega * natural_period_s / (2.0 * math.pi)
    return 1.0 / (1.0 - r**2 + 2j * damping_ratio * r)


def wave_track_coefficients(sea: dict | None, gravity: float
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(amplitude [m], omega [rad/s], wave number [1/m], phase [rad]) of each wave component of the vessels'
    motion, the motion transfer included (:func:`fill_tracks`' arguments); empty arrays for a calm sea (None or
    no amplitude). Constant for a sea state: a simulator computes them once, not on every window it samples."""
    empty = np.zeros(0)
    if sea is None or not np.any(sea["amplitude"] > 0):
        return empty, empty, empty, empty
    omega = sea["omega"]
    transfer = motion_transfer(omega, sea["natural_period_s"], sea["damping_ratio"])
    return sea["amplitude"] * np.abs(transfer), omega, omega**2 / gravity, sea["phase"] + np.angle(transfer)


def track_samples(duration_s: float, sample_dt_s: float) -> int:
    """Samples of a window of ``duration_s`` at ``sample_dt_s`` (one past its end, for the interpolation)."""
    return int(math.ceil(duration_s / sample_dt_s)) + 2


def sample_tracks(base_xyz: np.ndarray, spacing_velocity_m_s: np.ndarray, t0_s: float, duration_s: float,
                  sample_dt_s: float, sea: dict | None, gravity: float) -> np.ndarray:
    """Sample vessel positions and velocities on a uniform time grid.

    Parameters
    ----------
    base_xyz : ndarray, shape (n_vessels, 3)
        Mean positions at ``t0_s`` [m].
    spacing_velocity_m_s : ndarray, shape (n_vessels,)
        Constant horizontal (x) speed of each vessel over the window [m/s].
    t0_s, duration_s, sample_dt_s : float
        Start time, length and sampling interval of the window [s].
    sea : dict or None
        ``amplitude``, ``omega``, ``phase`` arrays and ``natural_period_s``, ``damping_ratio``; None is calm.
    gravity : float
        [m/s^2], for the deep-water wave number.

    Returns
    -------
    ndarray, shape (n_vessels, n_samples, 6)
        Position [m] and velocity [m/s] at ``t0_s + k * sample_dt_s``.
    """
    tracks = np.empty((base_xyz.shape[0], track_samples(duration_s, sample_dt_s), 6))
    fill_tracks(tracks, t0_s, sample_dt_s, np.ascontiguousarray(base_xyz, dtype=np.float64),
                np.ascontiguousarray(spacing_velocity_m_s, dtype=np.float64), *wave_track_coefficients(sea, gravity))
    return tracks


@jit
def fill_tracks(tracks, t0, sample_dt, base_xyz, speed, amplitude, omega, wavenumber, phase):
    """Write the tracks: each vessel's mean position moving at ``speed`` along x, plus its wave-following heave
    and surge (position and velocity).

    Component j moves with arg = omega_j t - k_j x_v + phase_j (``amplitude`` and ``phase`` include the motion
    transfer; x_v is the mean x at ``t0``): elevation eta = a cos(arg), deep-water horizontal orbital
    displacement a sin(arg). The samples are uniform in time, so (cos, sin) of arg advance from sample to sample
    by one rotation (angle addition) instead of two trigonometric calls per sample and component. A kernel: the
    env samples a window every step, where numpy's per-call cost dominated.
    """
    n = tracks.shape[1]
    for v in range(tracks.shape[0]):
        for i in range(n):
            t = t0 + sample_dt * i
            tracks[v, i, 0] = base_xyz[v, 0] + speed[v] * (t - t0)
            tracks[v, i, 1] = base_xyz[v, 1]
            tracks[v, i, 2] = base_xyz[v, 2]
            tracks[v, i, 3] = speed[v]
            tracks[v, i, 4] = 0.0
            tracks[v, i, 5] = 0.0
        for j in range(omega.shape[0]):
            arg = omega[j] * t0 - wavenumber[j] * base_xyz[v, 0] + phase[j]
            c = math.cos(arg)
            s = math.sin(arg)
            rc = math.cos(omega[j] * sample_dt)
            rs = math.sin(omega[j] * sample_dt)
            a = amplitude[j]
            aw = a * omega[j]
            for i in range(n):
                tracks[v, i, 2] += a * c
                tracks[v, i, 5] -= aw * s
                tracks[v, i, 0] += a * s
                tracks[v, i, 3] += aw * c
                c, s = c * rc - s * rs, s * rc + c * rs


@jit
def track_state(tracks, vessel, t, env_f):
    """Linearly interpolated (x, y, z, vx, vy, vz) of ``vessel`` at time ``t``."""
    n = tracks.shape[1]
    u = (t - env_f[EF_TRACK_T0]) / env_f[EF_TRACK_DT]
    if u <= 0.0:
        i = 0
        w = 0.0
    elif u >= n - 1:
        i = n - 2
        w = 1.0
    else:
        i = int(u)
        w = u - i
    return (
        (1.0 - w) * tracks[vessel, i, 0] + w * tracks[vessel, i + 1, 0],
        (1.0 - w) * tracks[vessel, i, 1] + w * tracks[vessel, i + 1, 1],
        (1.0 - w) * tracks[vessel, i, 2] + w * tracks[vessel, i + 1, 2],
        (1.0 - w) * tracks[vessel, i, 3] + w * tracks[vessel, i + 1, 3],
        (1.0 - w) * tracks[vessel, i, 4] + w * tracks[vessel, i + 1, 4],
        (1.0 - w) * tracks[vessel, i, 5] + w * tracks[vessel, i + 1, 5],
    )

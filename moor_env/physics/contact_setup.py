"""The numbers of the line-anchor contact (``physics/contact.py``): the anchor's surface, the law's parameters, and
whether a scene needs the contact at all.

Stiffness (:func:`contact_parameters`, slots ``CF_*`` of ``layout``): chosen so that a node of the chain meeting the
surface at the characteristic speed v_c penetrates ``penetration_m`` (1 cm) at most (the peak penetration of the
damped oscillator is v_c P(zeta) / omega, omega = sqrt(k / m), P(1) = 1/e), and never above ``axial_fraction``
(0.1) times 4 EA / l, the stiffness that would put the node's contact frequency on the segment's axial mode
2 sqrt(EA / (m l)): the fastest mode of the model, which sets the explicit step, then rises by at most 5 %, inside
the step's safety factor (0.9); the implicit step has no such limit. For the 142 mm chain in 1 m segments
(m = 442 kg, EA = 1.74e9 N) at v_c = 15 m/s: k = 1.35e8 N/m (omega = 552 rad/s, 2 % of 4 EA / l), 4.4 mm
at 6 m/s.

Characteristic speed and the switch (:func:`chain_catch_up`): along its length the chain falls like a body of its
own weight and tangential drag, v_c(t) = V_c tanh(g_c t / V_c), and the anchor like its own 1-DOF axial body
(seed 003, Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, the free-fall balance of section
3.1). The contact is needed where the chain falling freely behind the anchor gains on it by at least half a
segment before the anchor lands (the chain's first node starts one segment behind the back end); where the
chain's drag is the DNV value (C_D,T = 0.4456, its terminal speed 5 m/s) it never does. The characteristic speed
is the chain's lengthwise terminal speed less the anchor's touchdown speed (41.1 - 26.3 = 14.8 m/s for the
seed's chain and DPA), the fastest a chain node can meet the landing anchor, and at least 5 m/s.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from moor_env.physics.layout import (
    CF_MU,
    CF_ON,
    CF_RESTITUTION,
    CF_SEGMENTS,
    CF_SPEED,
    CF_STICK_SPEED,
    CF_STIFFNESS,
    CF_ZETA,
    CS_BACK,
    CS_BACK_INNER,
    CS_FRONT_INNER,
    CS_RADIUS,
    N_CONTACT_F,
    N_CONTACT_SHAPE,
)

RESTITUTION = 0.0  # a chain landing on the anchor piles up: its links collapse onto each other, it does not bounce
FRICTION_COEFFICIENT = 0.3  # wet steel on steel
STICK_SPEED_M_S = 0.05  # as the seabed's default friction velocity
PENETRATION_M = 0.01  # peak penetration of a chain node at the characteristic speed
AXIAL_FRACTION = 0.1  # stiffness cap as a fraction of 4 EA / l (the segment's axial mode)


def anchor_shape(section_lengths_m, section_diameters_m, s_tip_m: float) -> np.ndarray:
    """The anchor's surface as coaxial cylinders (rows of ``CS_*`` columns), front (tip) to back.

    Parameters
    ----------
    section_lengths_m, section_diameters_m : sequence of float
        Length and outer diameter of each section, listed from the tip backwards (as the anchor config).
    s_tip_m : float
        Axial coordinate of the tip from the COG (+ towards the tip) [m].
    """
    rows: list[list[float]] = []
    front = s_tip_m
    for length, diameter in zip(section_lengths_m, section_diameters_m, strict=True):
        back = front - length
        radius = 0.5 * diameter
        if rows and rows[-1][CS_RADIUS] == radius:
            rows[-1][CS_BACK] = back
        else:
            rows.append([front, back, radius, 0.0, 0.0])
        front = back
    for i in range(len(rows) - 1):
        # where two cylinders meet, the wider one's end is an annulus outside the narrower one's radius; the
        # narrower one's end is covered (its inner radius is its own radius: no face)
        narrow = min(rows[i][CS_RADIUS], rows[i + 1][CS_RADIUS])
        rows[i][CS_BACK_INNER] = narrow
        rows[i + 1][CS_FRONT_INNER] = narrow
    shape = np.zeros((len(rows), N_CONTACT_SHAPE))
    shape[:] = rows
    return shape


def zeta_from_restitution(restitution: float) -> float:
    """Damping ratio of a linear spring-dashpot whose restitution is ``restitution`` (1 at 0: critical)."""
    if not 0.0 <= restitution <= 1.0:
        raise ValueError(f"restitution {restitution} outside [0, 1]")
    if restitution == 0.0:
        return 1.0
    log_e = math.log(restitution)
    return -log_e / math.sqrt(math.pi**2 + log_e**2)


def peak_penetration_factor(zeta: float) -> float:
    """P(zeta): the peak penetration of a node meeting the surface at speed v is v P / omega."""
    if zeta >= 1.0:
        # overdamped: the peak of (exp(r1 t) - exp(r2 t)) / (r1 - r2) times omega
        if zeta == 1.0:
            return math.exp(-1.0)
        s = math.sqrt(zeta * zeta - 1.0)
        r1, r2 = -zeta + s, -zeta - s
        t = math.log(r2 / r1) / (r1 - r2)
        return (math.exp(r1 * t) - math.exp(r2 * t)) / (r1 - r2)
    s = math.sqrt(1.0 - zeta * zeta)
    return math.exp(-zeta / s * math.atan2(s, zeta))


def contact_parameters(ea_n: float, segment_m: float, node_mass_kg: float, contact_speed_m_s: float,
                       restitution: float = RESTITUTION, friction_coefficient: float = FRICTION_COEFFICIENT,
                       stick_speed_m_s: float = STICK_SPEED_M_S, penetration_m: float = PENETRATION_M,
                       axial_fraction: float = AXIAL_FRACTION, on: bool = True) -> np.ndarray:
    """The ``contact_f`` slots for the line that meets the anchor (the chain), as the module docstring derives.

    Parameters
    ----------
    ea_n, segment_m, node_mass_kg : float
        Axial stiffness [N], segment length [m] and node mass [kg] of the line's finest segments near the anchor.
    contact_speed_m_s : float
        Characteristic speed at which its nodes meet the anchor's surface [m/s].
    restitution, friction_coefficient, stick_speed_m_s : float
        Normal restitution, Coulomb coefficient, and the sliding speed of the regularised stick zone [m/s].
    penetration_m : float
        Peak penetration of a node meeting the surface at ``contact_speed_m_s`` [m].
    axial_fraction : float
        Cap of the stiffness as a fraction of 4 EA / l.
    on : bool
        Whether the kernels apply the contact.
    """
    for name, value in (("ea_n", ea_n), ("segment_m", segment_m), ("node_mass_kg", node_mass_kg),
                        ("contact_speed_m_s", contact_speed_m_s), ("stick_speed_m_s", stick_speed_m_s),
                        ("penetration_m", penetration_m), ("axial_fraction", axial_fraction)):
        if not value > 0.0:
            raise ValueError(f"{name} {value} must be positive")
    if friction_coefficient < 0.0:
        raise ValueError(f"friction_coefficient {friction_coefficient} must not be negative")
    zeta = zeta_from_restitution(restitution)
    omega = contact_speed_m_s * peak_penetration_factor(zeta) / penetration_m
    stiffness = min(node_mass_kg * omega * omega, axial_fraction * 4.0 * ea_n / segment_m)
    out = np.zeros(N_CONTACT_F)
    out[CF_ON] = 1.0 if on else 0.0
    out[CF_STIFFNESS] = stiffness
    out[CF_RESTITUTION] = restitution
    out[CF_ZETA] = zeta
    out[CF_SPEED] = contact_speed_m_s
    out[CF_MU] = friction_coefficient
    out[CF_STICK_SPEED] = stick_speed_m_s
    out[CF_SEGMENTS] = 1.0
    return out


MIN_CONTACT_SPEED_M_S = 5.0  # floor of the characteristic speed where the chain barely catches up
CATCH_UP_FRACTION = 0.5  # contact is needed where the chain gains this fraction of a segment on the anchor


class CatchUp(NamedTuple):
    """The 1-DOF estimate of how the chain behind the anchor gains on it during the fall."""

    gain_m: float  # how far the freely falling chain gains on the anchor before it lands [m]
    anchor_touchdown_s: float  # the anchor's fall time [s]
    anchor_speed_m_s: float  # its touchdown speed [m/s]
    chain_terminal_m_s: float  # the chain's lengthwise terminal speed [m/s]

    @property
    def contact_speed_m_s(self) -> float:
        """Characteristic contact speed: the chain's terminal speed less the anchor's touchdown speed, at least
        :data:`MIN_CONTACT_SPEED_M_S` [m/s]."""
        return max(self.chain_terminal_m_s - self.anchor_speed_m_s, MIN_CONTACT_SPEED_M_S)

    def needed(self, segment_m: float) -> bool:
        """Whether the chain gains at least :data:`CATCH_UP_FRACTION` of a segment of ``segment_m`` [m]."""
        return self.gain_m >= CATCH_UP_FRACTION * segment_m


def _fall(mass_kg: float, net_weight_n: float, drag_n_s2_m2: float):
    """Distance and speed of a 1-DOF body falling from rest against quadratic drag, as functions of time."""
    accel = net_weight_n / mass_kg
    terminal = math.sqrt(net_weight_n / drag_n_s2_m2) if drag_n_s2_m2 > 0.0 else math.inf

    def distance(t):
        if math.isinf(terminal):
            return 0.5 * accel * t * t
        y = accel * t / terminal
        return terminal * terminal / accel * (y + math.log1p(math.exp(-2.0 * y)) - math.log(2.0))

    def speed(t):
        return accel * t if math.isinf(terminal) else terminal * math.tanh(accel * t / terminal)

    return distance, speed, terminal


def chain_catch_up(drop_height_m: float, anchor_mass_kg: float, anchor_net_weight_n: float,
                   anchor_drag_n_s2_m2: float, chain_mass_kg_m: float, chain_net_weight_n_m: float,
                   chain_drag_n_s2_m3: float) -> CatchUp:
    """How far a chain falling freely along its length gains on the anchor during its fall (module docstring).

    Parameters
    ----------
    drop_height_m : float
        The anchor tip's height above the seabed at the release [m].
    anchor_mass_kg, anchor_net_weight_n, anchor_drag_n_s2_m2 : float
        The anchor's axial mass (with flooded water), weight less buoyancy, and axial drag F / v^2 (end faces and
        skin friction).
    chain_mass_kg_m, chain_net_weight_n_m, chain_drag_n_s2_m3 : float
        Per metre: the chain's mass (no tangential added mass), submerged weight and lengthwise drag
        1/2 rho C_D,T pi D.
    """
    if anchor_net_weight_n <= 0.0 or chain_net_weight_n_m <= 0.0:
        return CatchUp(-math.inf, math.inf, 0.0, 0.0)
    anchor_x, anchor_v, _ = _fall(anchor_mass_kg, anchor_net_weight_n, anchor_drag_n_s2_m2)
    chain_x, _, chain_terminal = _fall(chain_mass_kg_m, chain_net_weight_n_m, chain_drag_n_s2_m3)
    lo, hi = 0.0, 1.0
    while anchor_x(hi) < drop_height_m:
        hi *= 2.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if anchor_x(mid) < drop_height_m else (lo, mid)
    t_land = 0.5 * (lo + hi)
    gain = float(max(chain_x(t) - anchor_x(t) for t in np.linspace(0.0, t_land, 201)))
    return CatchUp(gain, t_land, anchor_v(t_land), chain_terminal)

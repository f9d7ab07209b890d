"""Tip penetration of a dart anchor from its impact energy, and the touchdown speed a required penetration needs.

Pure functions of numbers (scalars or numpy arrays); nothing here touches a simulator or an env.

Model
-----
The anchor enters the seabed with kinetic energy ``E_k = m v^2 / 2`` and releases potential energy
``W' g z_tip`` as it sinks to its final tip depth ``z_tip`` (``W'`` its submerged mass). The soil absorbs the
**total energy** ``E = E_k + W' g z_tip``. In normally consolidated clay the undrained strength grows linearly
with depth (``s_u = k z``) and the shaft friction acts over the embedded length, so the resistance at depth ``z``
grows as ``z^2`` and the work to reach ``z_tip`` as ``z_tip^3``::

    R z_tip^3 = m v^2 / 2 + W' g z_tip                                                   (1)

with ``R`` [J/m^3] the soil's **embedment resistance** for a given anchor geometry (``R ~ k D`` times a shape
and friction factor). This is the total-energy scaling of O'Loughlin, Richardson, Randolph and Gaudin,
"Penetration of dynamically installed anchors in clay", Géotechnique 63(11), 2013, who found total energy to
correlate the tip embedment of anchors of different mass and geometry impacting at different speeds, with the
normalised embedment growing as the cube root of the normalised total energy. (1) has one positive root
(:func:`tip_penetration_m`, closed form); solved for ``v`` it gives the touchdown speed a required penetration
needs (:func:`required_speed_m_s`); where the anchor's weight alone reaches the depth, that speed is 0.

Calibration
-----------
Landhaug, "Dynamic Simulation of Dart Anchor Installation" (MSc thesis, NTNU 2015), section 3.3, reports the
Gjoa installation of two 80 t DPAs (after Lieng et al. 2010, OTC-20758): the tip penetrations predicted for
25 m/s impact with the True (1975) method were **20.5 m and 25.5 m** at the two anchor sites. ``R`` of each site
(:data:`SOILS`: ``gjoa-1``, ``gjoa-2``) is fitted to that point with the DPA of the thesis: mass 79.4 t (the
anchor model, Table 6-1; :data:`GJOA_ANCHOR_MASS_KG`) and submerged mass 65.5 t (the real anchor, Table 5-1;
:data:`GJOA_SUBMERGED_FRACTION`). This gives ``R`` = 4409 J/m^3 (gjoa-1) and 2485 J/m^3 (gjoa-2). The thesis
itself gives no penetration relation: it models the fall only, and the True method is not public.

Uncertainty and validity
------------------------
* **Speed dependence is assumed, not fitted**: both Gjoa predictions are at one speed, so they fix the soil
  (``R``) but not how depth grows with speed; that comes from (1). At 25 m/s the model gives
  ``d ln z / d ln v`` = 0.49 (gjoa-1) and 0.46 (gjoa-2): depth grows about as the square root of speed, in line
  with O'Loughlin et al.'s "smaller dependence on the impact velocity". Strain-rate effects in the clay (not
  modelled) make depth still less sensitive to speed, so above the calibration point the required speed from
  (1) is, if anything, too low.
* **Against the field**: the measured Gjoa penetrations were 24.5 m and 31 m at measured 24.5 m/s and 27 m/s
  (the thesis lists them in the same order as the predictions; pairing them by that order is an assumption).
  The model at those speeds gives 20.3 m and 26.4 m: 15-17 % shallower, as the True-method predictions it is
  calibrated to were. A required speed from the model is therefore on the conservative (high) side.
* **Inverse sensitivity**: ``d ln v / d ln z`` is about 2.1 at the calibration points, so a 15 % uncertainty in
  penetration is about 30 % in the required speed. Treat the required speed as a scenario difficulty with that
  uncertainty, not as a design value.
* **Range**: DPA-like anchors (13 m, 1.2 m shaft, fins; about 75-85 t), impact speeds about 20-30 m/s (the
  field and model-test speeds the thesis reports, sections 3.3 and 5.4), normally consolidated clay with strength
  rising linearly with depth, tip penetrations about 15-32 m. Outside it the functions still return numbers (an
  extrapolation); a different anchor geometry needs its own ``R``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G_M_S2 = 9.81
GJOA_ANCHOR_MASS_KG = 79_400.0
GJOA_SUBMERGED_MASS_KG = 65_500.0
GJOA_SUBMERGED_FRACTION = GJOA_SUBMERGED_MASS_KG / GJOA_ANCHOR_MASS_KG
GJOA_PREDICTION_SPEED_M_S = 25.0
GJOA_PREDICTED_PENETRATION_M = {"gjoa-1": 20.5, "gjoa-2": 25.5}
VALID_SPEED_M_S = (20.0, 30.0)
VALID_PENETRATION_M = (15.0, 32.0)


@dataclass(frozen=True)
class Soil:
    """A seabed for the penetration model: its embedment resistance ``R`` [J/m^3] in ``R z^3 = E_total``."""

    name: str
    resistance_j_per_m3: float
    source: str = ""

    def __post_init__(self) -> None:
        if not self.resistance_j_per_m3 > 0.0:
            raise ValueError(f"soil {self.name!r}: resistance_j_per_m3 must be > 0, got {self.resistance_j_per_m3}")

    @classmethod
    def calibrated(cls, name: str, tip_penetration_m: float, speed_m_s: float,
                   anchor_mass_kg: float = GJOA_ANCHOR_MASS_KG, submerged_mass_kg: float | None = None,
                   source: str = "") -> Soil:
        """The soil in which an anchor impacting at ``speed_m_s`` reaches ``tip_penetration_m`` (equation 1)."""
        ws = float(submerged_mass(anchor_mass_kg, submerged_mass_kg))
        z = float(tip_penetration_m)
        energy = 0.5 * anchor_mass_kg * speed_m_s**2 + ws * G_M_S2 * z
        return cls(name, float(energy / z**3), source)


def submerged_mass(anchor_mass_kg: float | np.ndarray, submerged_mass_kg: float | np.ndarray | None = None):
    """``submerged_mass_kg`` where given, else the anchor mass times the Gjoa DPA's submerged fraction (0.825)."""
    if submerged_mass_kg is not None:
        return submerged_mass_kg
    return np.asarray(anchor_mass_kg, dtype=np.float64) * GJOA_SUBMERGED_FRACTION


def between(a: Soil, b: Soil, fraction: float | np.ndarray):
    """Embedment resistance ``fraction`` of the way from soil ``a`` to ``b``, geometrically (log-linear)."""
    t = np.asarray(fraction, dtype=np.float64)
    return np.exp((1.0 - t) * np.log(a.resistance_j_per_m3) + t * np.log(b.resistance_j_per_m3))


SOILS: dict[str, Soil] = {
    name: Soil.calibrated(
        name, z, GJOA_PREDICTION_SPEED_M_S,
        source=f"Gjoa DPA site predicted {z:g} m tip penetration at 25 m/s (Landhaug 2015, section 3.3)")
    for name, z in GJOA_PREDICTED_PENETRATION_M.items()
}


def _resistance(soil: Soil | float | np.ndarray) -> np.ndarray:
    r = soil.resistance_j_per_m3 if isinstance(soil, Soil) else soil
    return np.asarray(r, dtype=np.float64)


def _result(value: np.ndarray):
    return float(value) if np.ndim(value) == 0 else value


def tip_penetration_m(speed_m_s, soil: Soil | float | np.ndarray, anchor_mass_kg=GJOA_ANCHOR_MASS_KG,
                      submerged_mass_kg=None):
    """Tip penetration [m] of an anchor touching down at ``speed_m_s`` in ``soil`` (module docstring, eq. 1).

    ``soil`` is a :class:`Soil` or an embedment resistance [J/m^3]; arguments broadcast as numpy arrays
    (a float comes back for scalar input). The positive root of ``z^3 + p z + q = 0`` with
    ``p = -W' g / R``, ``q = -m v^2 / (2 R)`` (Cardano where one real root, the trigonometric form where three).
    """
    r = _resistance(soil)
    m = np.asarray(anchor_mass_kg, dtype=np.float64)
    ws = np.asarray(submerged_mass(m, submerged_mass_kg), dtype=np.float64)
    v = np.asarray(speed_m_s, dtype=np.float64)
    p = -ws * G_M_S2 / r
    q = -0.5 * m * v * v / r
    disc = (q / 2.0) ** 2 + (p / 3.0) ** 3
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.sqrt(np.maximum(disc, 0.0))
        cardano = np.cbrt(-q / 2.0 + root) + np.cbrt(-q / 2.0 - root)
        arg = np.clip(3.0 * q / (2.0 * p) * np.sqrt(-3.0 / p), -1.0, 1.0)
        trig = 2.0 * np.sqrt(-p / 3.0) * np.cos(np.arccos(arg) / 3.0)
    return _result(np.where(disc >= 0.0, cardano, trig))


def required_speed_m_s(required_penetration_m, soil: Soil | float | np.ndarray,
                       anchor_mass_kg=GJOA_ANCHOR_MASS_KG, submerged_mass_kg=None):
    """Touchdown speed [m/s] at which the anchor reaches ``required_penetration_m`` in ``soil``.

    ``v = sqrt(2 (R z^3 - W' g z) / m)`` from equation (1); 0 where the anchor's weight alone reaches the depth.
    Inverse of :func:`tip_penetration_m`; the same broadcasting. Its uncertainty is about twice the relative
    uncertainty of the penetration model (module docstring).
    """
    r = _resistance(soil)
    m = np.asarray(anchor_mass_kg, dtype=np.float64)
    ws = np.asarray(submerged_mass(m, submerged_mass_kg), dtype=np.float64)
    z = np.asarray(required_penetration_m, dtype=np.float64)
    kinetic = r * z**3 - ws * G_M_S2 * z
    return _result(np.sqrt(np.maximum(kinetic, 0.0) * 2.0 / m))

"""The anchor's derived properties: mass, centre of gravity, pitch inertia, buoyancy, added mass and the Morison
quadrature of its sections, and the kernels' ``body_f`` array made of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from moor_env.config import SceneConfig
from moor_env.physics import layout as L


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
            quad.append([x_g - xq, ds, s.cd_normal * s.outer_diameter_m,
                         s.cd_tangential * math.pi * s.outer_diameter_m])
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


def body_arrays(props: AnchorProperties, scene: SceneConfig, point_masses: list[tuple[float, float]]):
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

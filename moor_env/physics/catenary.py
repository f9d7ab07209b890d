"""Analytic elastic catenary of a multi-material line in a vertical plane (no current, no bending).

Used for first guesses of the static solver and as the analytic reference of the statics tests. With
horizontal force H (constant along the line) and vertical force V(s) = V_A + W(s) at unstretched arc length
s from end A (W is the submerged weight of the line below s), a uniform section of weight w per metre and
stiffness EA spans (Faltinsen 1990; seed 000: Wingerei 2008, *Dynamics and damping in mooring lines*,
eqs. 2.14-2.18; seed 004: Melozzi 2021, *Hydrodynamics of floating systems, Project 2, Task 1: Analysis of a
mooring cable*, section 2.3)::

    dx = H/w [asinh(V1/H) - asinh(V0/H)] + H ds / EA
    dz = H/w [sqrt(1 + (V1/H)^2) - sqrt(1 + (V0/H)^2)] + (V1^2 - V0^2) / (2 w EA)

With the lower end on a frictionless seabed, the grounded part lies flat, carries H and stretches by H/EA.

The functions here work on :class:`Section` lists and are the analytic references of the statics tests; the
same equations as numba kernels on arrays, for the static solver's first guess, are in
``physics/catenary_kernels.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, root


@dataclass(frozen=True)
class Section:
    """A uniform piece of line: submerged weight [N/m], axial stiffness [N], unstretched length [m]."""

    weight_n_m: float
    ea_n: float
    length_m: float


def _offsets(h: float, v0: np.ndarray, w: float, ea: float, ds: np.ndarray):
    v1 = v0 + w * ds
    if h <= 0.0:  # vertical line in tension
        return np.zeros_like(ds), ds + (v1**2 - v0**2) / (2.0 * w * ea)
    dx = h / w * (np.arcsinh(v1 / h) - np.arcsinh(v0 / h)) + h * ds / ea
    dz = h / w * (np.sqrt(1.0 + (v1 / h) ** 2) - np.sqrt(1.0 + (v0 / h) ** 2)) + (v1**2 - v0**2) / (2.0 * w * ea)
    return dx, dz


def shape(h: float, v_a: float, sections: list[Section], s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (x, z) relative to end A of the points at unstretched arc lengths ``s`` [m]."""
    s = np.asarray(s, float)
    x = np.zeros_like(s)
    z = np.zeros_like(s)
    start = 0.0
    x0 = z0 = 0.0
    v0 = v_a
    for sec in sections:
        inside = (s >= start - 1e-12) & (s <= start + sec.length_m + 1e-12)
        if np.any(inside):
            dx, dz = _offsets(h, np.full(int(inside.sum()), v0), sec.weight_n_m, sec.ea_n, s[inside] - start)
            x[inside] = x0 + dx
            z[inside] = z0 + dz
        dx, dz = _offsets(h, np.array([v0]), sec.weight_n_m, sec.ea_n, np.array([sec.length_m]))
        x0 += float(dx[0])
        z0 += float(dz[0])
        v0 += sec.weight_n_m * sec.length_m
        start += sec.length_m
    return x, z


def span(h: float, v_a: float, sections: list[Section]) -> tuple[float, float]:
    """End B relative to end A (x, z) for forces (H, V_A) [m]."""
    total = sum(sec.length_m for sec in sections)
    x, z = shape(h, v_a, sections, np.array([total]))
    return float(x[0]), float(z[0])


def solve_suspended(dx: float, dz: float, sections: list[Section]) -> tuple[float, float]:
    """Horizontal force H and vertical force at end A (V_A, + upwards along the line) [N] of a fully
    suspended line whose end B sits at (dx, dz) from end A (dx > 0)."""
    total = sum(sec.length_m for sec in sections)
    weight = sum(sec.weight_n_m * sec.length_m for sec in sections)
    chord = float(np.hypot(dx, dz))
    ratio = max(total / max(chord, 1e-9), 1.0 + 1e-6)
    h0 = max(weight * dx / max(chord, 1e-9) / (6.0 * np.sqrt(max(ratio - 1.0, 1e-6))), 1e-3 * weight)
    v0 = weight * (dz / max(chord, 1e-9)) * 0.5 - 0.5 * weight

    def residual(p):
        x, z = span(float(np.exp(p[0])), p[1] * weight, sections)
        return [(x - dx) / total, (z - dz) / total]

    best = None
    for h_try in (h0, 10 * h0, 0.1 * h0, weight, 0.01 * weight):
        sol = root(residual, [np.log(h_try), v0 / weight], method="hybr", options={"xtol": 1e-13})
        err = np.max(np.abs(residual(sol.x)))
        if best is None or err < best[0]:
            best = (err, sol.x)
        if err < 1e-10:
            break
    if best[0] > 1e-6:
        raise RuntimeError(f"suspended catenary not found (relative error {best[0]:.2g})")
    return float(np.exp(best[1][0])), float(best[1][1] * weight)


def solve_grounded(dx: float, dz: float, sections: list[Section]) -> tuple[float, float] | None:
    """Horizontal force H [N] and grounded (unstretched) length [m] of a line whose end A lies on a
    frictionless seabed with end B at (dx, dz) beside and above it; the suspended part leaves the seabed
    horizontally. None if the line does not touch the seabed in that geometry (it lifts end A)."""
    total = sum(sec.length_m for sec in sections)
    ea0 = sections[0].ea_n

    def mismatch(grounded: float) -> float:
        rest = trim(sections, grounded)
        h = _h_for_height(dz, rest)
        x, _ = span(h, 0.0, rest)
        return grounded * (1.0 + h / ea0) + x - dx

    g_max = total - dz * (1.0 - 1e-6)
    if g_max <= 0.0 or mismatch(0.0) <= 0.0 or mismatch(g_max) >= 0.0:
        return None
    grounded = brentq(mismatch, 0.0, g_max, xtol=1e-10)
    return _h_for_height(dz, trim(sections, grounded)), grounded


def trim(sections: list[Section], grounded: float) -> list[Section]:
    """The sections left after removing ``grounded`` metres from end A."""
    out = []
    left = grounded
    for sec in sections:
        if left >= sec.length_m:
            left -= sec.length_m
            continue
        out.append(Section(sec.weight_n_m, sec.ea_n, sec.length_m - left))
        left = 0.0
    return out


def _h_for_height(dz: float, sections: list[Section]) -> float:
    weight = sum(sec.weight_n_m * sec.length_m for sec in sections)

    def f(log_h: float) -> float:
        return span(float(np.exp(log_h)), 0.0, sections)[1] - dz

    lo, hi = np.log(1e-6 * weight + 1e-9), np.log(1e3 * weight + 1.0)
    if f(lo) * f(hi) > 0:
        return float(np.exp(lo))
    return float(np.exp(brentq(f, lo, hi, xtol=1e-12)))


def tension_at(h: float, v_a: float, sections: list[Section], s: float) -> float:
    """Tension at unstretched arc length ``s`` from end A [N]."""
    v = v_a
    start = 0.0
    for sec in sections:
        take = min(max(s - start, 0.0), sec.length_m)
        v += sec.weight_n_m * take
        start += sec.length_m
    return float(np.hypot(h, v))

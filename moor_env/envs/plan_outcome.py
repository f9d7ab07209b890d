"""AnchorPlan-v1's outcome: success of an installation, its normalised margins and the reward, a smooth surrogate
of success.

Pure functions of what the episode measured (:class:`InstallationRecord`); nothing here touches a simulator.

**Success** (:func:`is_success`): touchdown at or above the site's required speed, tilt below
``success.tilt_max_deg`` (2 deg, the Gjoa result against the DPA's 5 deg criterion), the tip within
``success.offset_max_m`` (2 m, the Gjoa radius) of where it hung, and no limit exceeded (:data:`PLAN_LIMITS`): no
line above its MBL, the release unit within its rating, no fibre on the seabed (the env's own checks,
:mod:`moor_env.envs.reward`), and no more than ``success.chain_pile_allowance_m`` of chain on the seabed at
touchdown (seed 003, Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*: no chain pile-up while the
anchor penetrates).

**Margins** (:func:`margins`): each criterion as a signed distance from its threshold in units of its
``success.*_scale`` (positive: met), so that success is every margin positive (the speed, load, fibre and pile
margins at 0 still succeed, as their criteria are inclusive):

====================  =========================================================  ==========
margin                value                                                      unit
====================  =========================================================  ==========
speed                 speed - required speed                                     1 m/s
tilt                  tilt_max_deg - tilt                                        0.5 deg
offset                offset_max_m - offset                                      0.5 m
tension               1 - max over the lines of (peak tension / MBL)             0.1
release_unit          1 - peak wire load / release unit rating                   0.1
fibre_seabed          lowest fibre clearance - reward.fibre_clearance_m          2 m
chain_pile            chain_pile_allowance_m - chain on the seabed at touchdown  5 m
====================  =========================================================  ==========

**Reward** (:func:`smooth_success`): the logistic function of the soft minimum of the margins,
``sigmoid(-T log sum_i exp(-m_i / T))`` with temperature ``success.softmin_temperature`` (0.25): about 1 when
every criterion is met with room to spare, 0.5 near the binding threshold, about 0 when one fails by several
units. Its gradient follows the margin that binds; the soft minimum lies at most ``T log 7`` (0.49) below the
minimum. An episode without touchdown (no equilibrium, a numerical failure, no touchdown in time) scores 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from moor_env.envs.config import EnvConfig

MARGIN_NAMES: tuple[str, ...] = ("speed", "tilt", "offset", "tension", "release_unit", "fibre_seabed", "chain_pile")
PLAN_LIMITS: tuple[str, ...] = ("tension", "release_unit", "fibre_seabed", "chain_pile")


@dataclass
class InstallationRecord:
    """What one AnchorPlan-v1 installation measured.

    ``touchdown``: the env's touchdown measures (speed, tilt, offset, chain on the seabed ...; None without a
    touchdown); ``required_speed_m_s`` of the site; ``tension_ratio``: the largest peak tension over MBL of any line;
    ``wire_load_ratio``: the wire's peak load over the release unit's rating (both None where nothing was
    simulated, e.g. no equilibrium); ``fibre_clearance_m``: the fibre
    rope's lowest clearance above the seabed where the env checked it; ``exceeded``: the env's limit flags
    (``tension``, ``release_unit``, ``fibre_seabed``); ``failure``: why the installation never reached the seabed
    (None if it did).
    """

    touchdown: dict[str, float] | None
    required_speed_m_s: float
    tension_ratio: float | None = None
    wire_load_ratio: float | None = None
    fibre_clearance_m: float = math.inf
    exceeded: dict[str, bool] = field(default_factory=dict)
    failure: str | None = None


def margins(record: InstallationRecord, cfg: EnvConfig) -> dict[str, float | None]:
    """Normalised margins of every criterion (module docstring); None for the touchdown's where there is none."""
    s = cfg.success
    td = record.touchdown
    loads = record.tension_ratio is not None
    return {
        "speed": (td["speed_m_s"] - record.required_speed_m_s) / s.speed_scale_m_s if td else None,
        "tilt": (s.tilt_max_deg - td["tilt_deg"]) / s.tilt_scale_deg if td else None,
        "offset": (s.offset_max_m - td["offset_m"]) / s.offset_scale_m if td else None,
        "tension": (1.0 - record.tension_ratio) / s.load_scale if loads else None,
        "release_unit": (1.0 - record.wire_load_ratio) / s.load_scale if loads else None,
        "fibre_seabed": (min((record.fibre_clearance_m - cfg.reward.fibre_clearance_m) / s.fibre_scale_m, 1e6)
                         if loads else None),
        "chain_pile": (s.chain_pile_allowance_m - td["chain_on_seabed_m"]) / s.chain_pile_scale_m if td else None,
    }


def limits_exceeded(record: InstallationRecord, cfg: EnvConfig) -> list[str]:
    """The limits of :data:`PLAN_LIMITS` the installation exceeded: the env's flags and the chain pile-up."""
    out = [name for name in PLAN_LIMITS[:3] if record.exceeded.get(name, False)]
    td = record.touchdown
    if td and td["chain_on_seabed_m"] > cfg.success.chain_pile_allowance_m:
        out.append("chain_pile")
    return out


def is_success(record: InstallationRecord, cfg: EnvConfig) -> bool:
    """Success of the installation (module docstring)."""
    td = record.touchdown
    if not td or record.failure is not None:
        return False
    s = cfg.success
    return bool(td["speed_m_s"] >= record.required_speed_m_s and td["tilt_deg"] < s.tilt_max_deg
                and td["offset_m"] <= s.offset_max_m and not limits_exceeded(record, cfg))


def soft_minimum(values: list[float], temperature: float) -> float:
    """``-T log sum exp(-v / T)``: at most ``T log n`` below ``min(values)``, smooth in every value."""
    low = min(values)
    return low - temperature * math.log(sum(math.exp(-(v - low) / temperature) for v in values))


def smooth_success(margin: dict[str, float | None], temperature: float) -> float:
    """The reward: logistic function of the soft minimum of the margins (0 where any is None: no touchdown)."""
    values = list(margin.values())
    if any(v is None for v in values):
        return 0.0
    x = soft_minimum(values, temperature)
    return 1.0 / (1.0 + math.exp(-x)) if x > -700.0 else 0.0


def outcome(record: InstallationRecord, cfg: EnvConfig) -> dict[str, Any]:
    """``{margins, limits_exceeded, success, reward}`` of an installation."""
    m = margins(record, cfg)
    reward = smooth_success(m, cfg.success.softmin_temperature) if record.failure is None else 0.0
    return {"margins": m, "limits_exceeded": limits_exceeded(record, cfg), "success": is_success(record, cfg),
            "reward": reward}

"""What counts as a successful installation, from an episode's touchdown record and its reward terms.

**Success**: touchdown with tilt below :data:`SUCCESS_TILT_DEG` (2 deg, the Gjoa result; the DPA criterion is
5 deg) and speed at or above the env config's ``reward.required_speed_m_s`` (24 m/s), and no limit exceeded: no
line above its MBL, the release unit's rating not exceeded, no fibre on the seabed (the ``tension``,
``release_unit`` and ``fibre_seabed`` reward terms of the episode, :data:`LIMIT_TERMS`, are all zero).

``AnchorPlan-v1`` judges its installations itself (``info["success"]``, :mod:`moor_env.envs.plan_outcome`: the
site's required speed, the offset and the chain pile-up included); :func:`episode_success` and
:func:`agents.episodes.run_episode` take its verdict.
"""

from __future__ import annotations

from typing import Any

from moor_env.envs.config import EnvConfig

SUCCESS_TILT_DEG = 2.0
LIMIT_TERMS = ("tension", "release_unit", "fibre_seabed")


def success_of(touchdown: dict[str, Any] | None, terms: dict[str, float], cfg: EnvConfig) -> bool:
    """Success of one episode from its touchdown record and its summed reward terms (module docstring)."""
    if not touchdown:
        return False
    limits_ok = all(terms.get(k, 0.0) == 0.0 for k in LIMIT_TERMS)
    return bool(touchdown["tilt_deg"] < SUCCESS_TILT_DEG
                and touchdown["speed_m_s"] >= cfg.reward.required_speed_m_s and limits_ok)


def episode_success(info: dict[str, Any], cfg: EnvConfig) -> bool:
    """Success of a one-step episode: ``AnchorPlan-v1``'s own ``info["success"]`` (its site's required speed, the
    offset and the chain pile-up included, :mod:`moor_env.envs.plan_outcome`), else from ``AnchorPlan-v0``'s final
    info, which sums the reward terms."""
    if "success" in info:
        return bool(info["success"])
    return success_of(info.get("touchdown"), info["reward_terms"], cfg)

"""Discretization presets (``configs/fidelity.yaml``) and the resolution a scene's geometry calls for.

A scene names a preset (``fidelity: fast | default | accurate | custom``); :func:`apply_fidelity` fills the
``discretization`` keys the scene does not set from it, and :func:`fit_fidelity` switches to the preset's
``tight_line`` resolution where the scene's mooring line is pulled or moving during the fall.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from moor_env.errors import ConfigError, did_you_mean
from moor_env.scene_geometry import mooring_line_slack

if TYPE_CHECKING:
    from moor_env.config import SceneConfig

FIDELITY_PATH = Path(__file__).resolve().parent.parent / "configs" / "fidelity.yaml"


def fidelity_presets() -> dict[str, dict[str, Any]]:
    """The discretization presets of ``configs/fidelity.yaml`` by name."""
    with open(FIDELITY_PATH, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def apply_fidelity(data: dict[str, Any]) -> dict[str, Any]:
    """Fill the ``discretization`` keys a scene does not set from its ``fidelity`` preset (``default`` if
    none); ``custom`` uses only what the scene sets."""
    name = data.get("fidelity", "default")
    if name == "custom":
        return data
    presets = fidelity_presets()
    if name not in presets:
        raise ConfigError("fidelity", name, "one of " + ", ".join([*presets, "custom"]),
                          did_you_mean(str(name), [*presets, "custom"]))
    disc = data.setdefault("discretization", {})
    if not isinstance(disc, dict):
        return data
    for key, value in presets[name].items():
        if key != TIGHT_LINE:
            disc.setdefault(key, value)
    return data


TIGHT_LINE = "tight_line"  # preset entry: the resolution used where the mooring line tightens during the fall


def tight_line_rule(fidelity: str) -> dict[str, Any] | None:
    """The ``tight_line`` entry of a fidelity preset (the thresholds of :func:`tight_line_needed` and the
    discretization keys it sets), or None for a preset without one and for ``custom``."""
    if fidelity == "custom":
        return None
    return fidelity_presets().get(fidelity, {}).get(TIGHT_LINE)


TIGHT_LINE_THRESHOLDS = ("slack_below_m", "chord_angle_above_deg", "waves_above_hs_m", "moving_above_m_s")
TIGHT_LINE_IN_WAVES = "in_waves"  # tight_line entry: keys that replace its own in waves above waves_above_hs_m


def tight_line_needed(rule: dict[str, Any], slack_m: float, chord_angle_deg: float, hs_m: float,
                      line_speed_m_s: float = 0.0) -> bool:
    """Whether the fall needs the ``tight_line`` resolution of ``rule``: the mooring line has less than
    ``slack_below_m`` of slack at touchdown, its chord is further than ``chord_angle_above_deg`` from the vertical
    (:func:`mooring_line_slack`), the significant wave height ``hs_m`` exceeds ``waves_above_hs_m``, or the
    line's fastest node at the release is faster than ``moving_above_m_s`` [m/s]. The coarse resolution was
    validated on falls from a calm loop at rest only."""
    return (slack_m < rule["slack_below_m"] or chord_angle_deg > rule["chord_angle_above_deg"]
            or hs_m > rule["waves_above_hs_m"] or line_speed_m_s > rule["moving_above_m_s"])


def tight_line_keys(rule: dict[str, Any], hs_m: float = 0.0) -> dict[str, Any]:
    """The discretization keys of a ``tight_line`` rule (without its thresholds) for a sea of significant wave
    height ``hs_m`` [m]: above the rule's ``waves_above_hs_m`` its ``in_waves`` keys replace the others."""
    keys = {k: v for k, v in rule.items() if k not in TIGHT_LINE_THRESHOLDS and k != TIGHT_LINE_IN_WAVES}
    if hs_m > rule["waves_above_hs_m"]:
        keys.update(rule.get(TIGHT_LINE_IN_WAVES, {}))
    return keys


def fit_fidelity(scene: SceneConfig, data: dict[str, Any]) -> dict[str, Any] | None:
    """``data`` with its preset's ``tight_line`` resolution where the scene needs it, else None.

    A preset's ``tight_line`` entry (thresholds and discretization keys) applies where the mooring line from the
    release point, when the anchor touches down, has less slack than ``slack_below_m`` or a chord steeper from
    the vertical than ``chord_angle_above_deg`` (:func:`mooring_line_slack`), or in waves higher than
    ``waves_above_hs_m``, or with vessel or winch moves before the release (:func:`tight_line_needed`): there the
    chain loop is pulled or moving during the fall, a coarse loop goes taut too early, and it carries the tilt and
    the snap; a slack line hanging nearly straight down and at rest in calm water does not need it.
    Keys the scene sets explicitly still win. The geometry checked is the scene's at its release (after
    ``release_time_s`` of spacing move and payout). With ``discretization.fit_to_geometry`` false nothing is
    fitted: the envs, whose agents change the geometry before the release, apply the same rule to the drawn
    scenario at the reset and again, for the fall, at the release (:mod:`moor_env.remesh`).
    """
    rule = tight_line_rule(data.get("fidelity", "default"))
    if rule is None or not scene.discretization.fit_to_geometry:
        return None
    geometry = mooring_line_slack(scene, tip_height_m=0.0)
    inst = scene.installation
    moves = inst is not None and inst.release_time_s > 0.0 and (inst.spacing_rate_m_s or inst.payout_rate_m_s)
    # a scripted pre-release move leaves the loop moving at the release by an amount not known before the run
    if geometry is None or not tight_line_needed(rule, *geometry, scene.environment.sea_state.hs_m,
                                                 math.inf if moves else 0.0):
        return None
    fitted = copy.deepcopy(data)
    disc = fitted.setdefault("discretization", {})
    for key, value in tight_line_keys(rule, scene.environment.sea_state.hs_m).items():
        disc.setdefault(key, value)
    return apply_fidelity(fitted)

"""How finely an episode is simulated: the mesh (the fidelity preset's ``tight_line`` rule, the remesh at the
release) and the integration step before the release.

A fidelity preset (``configs/fidelity.yaml``) may carry a ``tight_line`` entry: a finer resolution for a mooring
line that is tight at touchdown, moves fast, or is in waves (its ``in_waves`` keys there). :class:`TightLineRule`
decides from the geometry which resolution a scenario starts on (:meth:`TightLineRule.pre_release`) and which
its fall needs (:meth:`TightLineRule.fall`); :func:`remesh_for_fall` moves a simulation onto the fall's mesh
(:func:`moor_env.remesh.remesh_state`), and where the remesh is refused the episode falls on the mesh it has.

Why the resolution is chosen per scenario: a calm, slack loop held until the release falls on the coarse
resolution about as close to the explicit reference fall as on the fine one, at a fraction of the cost; a coarse
pre-release phase in front of a loop that is tight, moving or in waves changes the touchdown by more than the
outcome's own sensitivity to the release instant, the fall there needing the fine resolution anyway
(``benchmarks/remesh_at_release.py``, docs/remesh-at-release.md).

Before the release the implicit integrator may take a coarser step than the scene's
(:func:`pre_release_step_s`); an advance that diverges with it is repeated at the scene's step
(:meth:`moor_env.envs.core.InstallationCore.fallback`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from moor_env.compile import Model
from moor_env.config import SceneConfig, line_slack_geometry, tight_line_keys, tight_line_needed
from moor_env.envs.config import ControlConfig
from moor_env.envs.measures import segment_travel_s
from moor_env.physics import layout as L
from moor_env.physics.integrate import INTEGRATOR_IMPLICIT_EULER
from moor_env.remesh import remesh_state
from moor_env.simulation import Simulator

KeysBySea = tuple[dict[str, Any] | None, dict[str, Any] | None]


def tight_line_keys_by_sea(rule: dict[str, Any], explicit: dict[str, Any]) -> KeysBySea:
    """The rule's discretization keys in calm water and in waves (its ``in_waves`` entry), less those the scene
    sets explicitly (``explicit``: its ``discretization`` mapping); None where none are left."""
    return tuple({k: v for k, v in tight_line_keys(rule, hs_m).items() if k not in explicit} or None
                 for hs_m in (0.0, math.inf))


class TightLineRule:
    """A preset's ``tight_line`` rule applied to one scene family.

    Parameters
    ----------
    rule : dict
        The preset's ``tight_line`` entry (:func:`moor_env.config.tight_line_rule`).
    keys_by_sea : tuple
        :func:`tight_line_keys_by_sea` of the rule.
    anchor_length_m, fairlead_depth_m : float
        The geometry the rule's slack estimate needs (the same in every scenario of a config).
    """

    def __init__(self, rule: dict[str, Any], keys_by_sea: KeysBySea, anchor_length_m: float,
                 fairlead_depth_m: float) -> None:
        self.rule = rule
        self.keys_by_sea = keys_by_sea
        self.anchor_length_m = anchor_length_m
        self.fairlead_depth_m = fairlead_depth_m

    def needed(self, depth_m: float, vertical_chain_m: float, spacing_m: float, line_length_m: float, hs_m: float,
               line_speed_m_s: float) -> bool:
        """Whether the line needs the fine resolution (:func:`moor_env.config.tight_line_needed`)."""
        geometry = line_slack_geometry(water_depth_m=depth_m, tip_height_m=0.0, anchor_length_m=self.anchor_length_m,
                                       vertical_chain_m=vertical_chain_m, fairlead_depth_m=self.fairlead_depth_m,
                                       spacing_m=spacing_m, line_length_m=line_length_m)
        return tight_line_needed(self.rule, *geometry, hs_m, line_speed_m_s)

    def keys(self, hs_m: float) -> dict[str, Any] | None:
        """The rule's keys for a sea of significant wave height ``hs_m`` [m] (its ``in_waves`` keys in waves),
        None where there are none to set."""
        waves = hs_m > self.rule["waves_above_hs_m"]
        keys = self.keys_by_sea[1 if waves else 0]
        return None if keys is None else dict(keys)

    def pre_release(self, scenario: dict[str, Any]) -> dict[str, Any]:
        """Discretization keys of a scenario before its release: the rule's keys where its starting geometry
        (at rest) or its waves need them, else none (the preset's own resolution)."""
        depth = float(scenario["water_depth_m"])
        hs_m = float(scenario["sea_state_hs_m"])
        tight = self.needed(depth, float(scenario["vertical_chain_length_m"]),
                            float(scenario["vessel_spacing_over_depth"]) * depth,
                            float(scenario["mooring_line_length_over_depth"]) * depth,
                            hs_m, 0.0)  # the equilibrium is at rest
        return (self.keys(hs_m) or {}) if tight else {}

    def fall(self, scene: SceneConfig, spacing_m: float, line_length_m: float,
             line_speed_m_s: float) -> dict[str, Any] | None:
        """Discretization keys the fall needs, or None for the preset's own resolution: the rule's keys where the
        mooring line, at the spacing and line length (vertical chain included) [m] of the release, will be tight
        at touchdown, where there are waves, or where its fastest node moves faster than the rule's
        ``moving_above_m_s`` [m/s]."""
        inst = scene.installation
        hs_m = scene.environment.sea_state.hs_m
        tight = self.needed(scene.environment.water_depth_m, inst.vertical_chain_length_m, spacing_m,
                            line_length_m, hs_m, line_speed_m_s)
        return self.keys(hs_m) if tight else None


def line_speed_m_s(sim: Simulator, lines: list[int]) -> float:
    """Speed of the fastest free node of the lines of index ``lines`` [m/s]."""
    st = sim.state
    free = (st.node_i[:, L.NI_KIND] == L.NODE_FREE) & np.isin(st.node_i[:, L.NI_LINE], lines)
    return float(np.sqrt(np.max(np.sum(st.node_vel[free] ** 2, axis=1), initial=0.0)))


def has_resolution(sim: Simulator, keys: dict[str, Any] | None) -> bool:
    """Whether the simulation already runs at the discretization ``keys`` (None: the preset's own)."""
    current = sim.model.scene.discretization
    return keys is None or all(getattr(current, k) == v for k, v in keys.items())


def remesh_for_fall(old: Simulator, model: Model) -> tuple[Simulator | None, str | None]:
    """A simulator of ``model`` holding ``old``'s state remeshed onto it, with ``old``'s sea and vessel tracks;
    (None, the reason) where the remesh is refused (e.g. paid out beyond the fine model's segment slots)."""
    sim = Simulator(model)
    try:
        sim.state = remesh_state(old.state, old.model, model)
    except ValueError as exc:
        return None, str(exc)
    sim.env_f[:] = old.env_f
    sim.vessel_mean_m[:] = old.vessel_mean_m
    sim.tracks = old.tracks.copy()
    return sim, None


def pre_release_step_s(sim: Simulator, hs_m: float, cfg: ControlConfig) -> float:
    """The largest integration step before the release [s]: ``control.pre_release_dt_s`` (in a sea without waves,
    ``hs_m`` 0, ``control.pre_release_dt_calm_s`` where set), shortened by :func:`travel_step_s` where the lines
    move fast, never below the scene's step; the scene's step where neither is set or the integrator is explicit
    (the explicit ones are bound by the lines' axial stability limit whether or not the anchor falls)."""
    step = cfg.pre_release_dt_s
    if hs_m == 0.0 and cfg.pre_release_dt_calm_s is not None:
        step = cfg.pre_release_dt_calm_s
    target = sim.dt
    if sim.integrator_code == INTEGRATOR_IMPLICIT_EULER and step is not None:
        if cfg.pre_release_travel_segments is not None:
            step = min(step, travel_step_s(sim, cfg.pre_release_travel_segments))
        target = max(step, sim.dt)
    return target


def travel_step_s(sim: Simulator, segments: float) -> float:
    """The step [s] in which the fastest free node, at its present speed, travels ``segments`` lengths of the
    shortest active segment (:func:`~moor_env.envs.measures.segment_travel_s`); infinite where nothing moves."""
    st = sim.state
    return segments * segment_travel_s(st.node_i, st.node_vel, st.seg_i, st.seg_f, st.line_i)


def even_step_s(span_s: float, max_step_s: float) -> float:
    """``span_s`` / n [s] for the smallest whole n that keeps the step at or below ``max_step_s``: an advance of
    ``span_s`` in steps of it ends exactly at its end time."""
    return span_s / max(1, math.ceil(span_s / max_step_s - 1e-9))

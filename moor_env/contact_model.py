"""The line-anchor contact of a scene: whether its chain can catch up with the anchor, and the kernels' arrays.

``discretization.line_anchor_contact`` chooses: ``on``, ``off``, or ``auto`` (the default), which models the
contact only where the chain behind the anchor can reach it during the fall, by the 1-DOF estimate of
``physics/contact_setup.chain_catch_up`` (the seed's chain with C_D,T 0.0069 gains 7 m on the DPA over a 68.5 m
drop; with the DNV 0.4456 it falls behind). Where it is off the kernels skip it and lines pass through the anchor.

Where it is on, the hanging equilibrium includes it too (``physics/statics_contact.py``): the loop that hangs
beside the vertical chain (mostly at vessel spacings below a fifth of the depth) rests against the anchor, and a
fall starts from that rest state.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics.contact_setup import CatchUp, anchor_shape, chain_catch_up, contact_parameters
from moor_env.scene_geometry import submerged_mass_per_length

if TYPE_CHECKING:
    from moor_env.anchor_properties import AnchorProperties
    from moor_env.config import SceneConfig


def scene_catch_up(scene: SceneConfig, props: AnchorProperties) -> CatchUp | None:
    """The 1-DOF catch-up estimate of the scene's bottom chain on its anchor; None without an anchor or a chain
    attached to it."""
    inst = scene.installation
    if scene.anchor is None or inst is None or not (inst.components.vertical_chain or inst.components.mooring_line):
        return None
    chain = scene.materials[inst.chain_material]
    g = scene.environment.gravity_m_s2
    rho = scene.environment.water_density_kg_m3
    quad = props.quadrature
    skin = float(np.sum(quad[:, L.BQ_CDT_PID] * quad[:, L.BQ_DS]))
    return chain_catch_up(inst.drop_height_m, props.mass_kg, props.submerged_mass_kg * g,
                          0.5 * rho * (props.tip_cda_m2 + props.back_cda_m2 + skin), chain.mass_per_length_kg_m,
                          submerged_mass_per_length(scene, inst.chain_material) * g,
                          0.5 * rho * chain.cd_tangential * np.pi * chain.diameter_m)


def contact_arrays(scene: SceneConfig, props: AnchorProperties | None) -> tuple[np.ndarray, np.ndarray]:
    """``contact_f`` (``CF_*``) and ``contact_shape`` (``CS_*`` rows) of a scene; contact off (and a one-row
    placeholder shape) where it has no anchor, no chain on it, or the switch or the estimate says so."""
    off = np.zeros(L.N_CONTACT_F), np.zeros((1, L.N_CONTACT_SHAPE))
    if props is None:
        return off
    catch_up = scene_catch_up(scene, props)
    if catch_up is None:
        return off
    inst = scene.installation
    disc = scene.discretization
    chain = scene.materials[inst.chain_material]
    segment = disc.vertical_chain_segment_m if inst.components.vertical_chain else disc.loop_chain_segment_m
    switch = disc.line_anchor_contact
    on = switch == "on" or (switch == "auto" and catch_up.needed(segment))
    contact_f = contact_parameters(chain.ea_n, segment, chain.mass_per_length_kg_m * segment,
                                   catch_up.contact_speed_m_s, on=on)
    contact_f[L.CF_STIFFNESS] *= disc.contact_stiffness_scale
    shape = anchor_shape([s.length_m for s in scene.anchor.sections],
                         [s.outer_diameter_m for s in scene.anchor.sections], props.s_tip_m)
    return contact_f, shape

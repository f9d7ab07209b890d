"""Energy conservation of the integrator when nothing dissipates."""

from __future__ import annotations

from moor_env import Simulator, solve_statics
from moor_env.config import scene_dict, scene_from_dict


def _conservative_vertical_chain():
    data = scene_dict("vertical-chain")
    data["installation"]["drop_height_m"] = 300.0
    chain = data["materials"]["chain_142"]
    chain.update(cd_normal=0.0, cd_tangential=0.0, ca_normal=0.0, axial_damping_ratio=0.0)
    anchor = data["anchor"]
    anchor.update(tip_drag_coefficient=0.0, back_drag_coefficient=0.0)
    anchor["sections"] = [dict(sec, cd_normal=0.0, cd_tangential=0.0, ca_normal=0.0) for sec in anchor["sections"]]
    return scene_from_dict(data)


def test_mechanical_energy_conserved_over_5_s_fall():
    """Reference: exact conservation (no drag, no added mass, no internal damping, seabed not reached).
    Symplectic Euler keeps the energy error bounded; tolerance 0.1 % of the energy released in the fall."""
    scene = _conservative_vertical_chain()
    static = solve_statics(scene)
    sim: Simulator = static.simulator
    sim.release()
    e0 = sim.mechanical_energy_j()
    energies = []
    potential_drop = 0.0
    for k in range(1, 11):
        sim.advance_to(0.5 * k)
        energies.append(sim.mechanical_energy_j())
        potential_drop = max(potential_drop, abs(sim.model.body_f[5] - sim.model.body_f[6]) * (
            static.tip_height_above_seabed_m - (sim.tip_state()[0][2] + scene.environment.water_depth_m)))
    assert sim.state.t >= 5.0 - sim.dt
    worst = max(abs(e - e0) for e in energies)
    assert potential_drop > 1e7
    assert worst < 1e-3 * potential_drop

"""The fall's resolution is fitted at the release (SceneFactory.fall_resolution, moor_env.remesh).

In calm water the pre-release phase runs on the fidelity preset's own resolution (`fast`: 2 m chain); at the release
the preset's tight_line resolution (configs/fidelity.yaml) takes over where the mooring line, at the spacing and
line length of that moment, will be tight at touchdown. In waves, or where the loop is tight from the start, the
tight_line resolution runs from the start (SceneFactory.pre_release_resolution). Reference for the geometry: the
default scene (500 m, spacing 0.1 h = 50 m, line 1.08 h) keeps 50 m of slack with its chord 6.5 deg from vertical
(coarse in calm water); 59 s of widening at the DP limits (27.25 m) and hauling in at the winch limit (17.7 m)
leaves 28.5 m of slack at 10.0 deg (tight).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.config import fidelity_presets
from moor_env.envs import load_env_config
from moor_env.envs.scenario import representative_scenario
from moor_env.envs.scene import SceneFactory
from moor_env.physics.integrate import INTEGRATOR_SYMPLECTIC_EULER
from moor_env.physics.stability import stable_time_step

SCENE = {"water_depth_m": 500.0, "vessel_spacing_over_depth": 0.1, "mooring_line_length_over_depth": 1.08,
         "current_scale": 0.0, "sea_state_hs_m": 0.0}
FAST = fidelity_presets()["fast"]
WAVES_LOOP_M = FAST["tight_line"]["in_waves"]["loop_chain_segment_m"]  # tight_line's loop in waves


def _episode(env, options, action):
    env.reset(seed=0, options=options)
    core = env.unwrapped.core
    calm = options["sea_state_hs_m"] == 0.0
    expected = FAST["loop_chain_segment_m"] if calm else WAVES_LOOP_M
    assert core.sim.model.scene.discretization.loop_chain_segment_m == expected
    for _ in range(59):
        env.step(np.asarray(action, np.float32))
    _, _, terminated, _, info = env.step(np.array([0.0, 0.0, 1.0], np.float32))
    assert terminated and info["sim_status"] == "touchdown"
    return info, core.sim.model.scene.discretization.loop_chain_segment_m


@pytest.fixture(scope="module")
def env(default_overrides):
    return gym.make("moor_env/AnchorRelease-v0", overrides=default_overrides)


def test_slack_calm_release_falls_on_the_preset_resolution(env):
    info, loop_m = _episode(env, SCENE, [0.0, 0.0, -1.0])
    assert info["fall_resolution"] == "preset" and loop_m == FAST["loop_chain_segment_m"]


def test_a_loop_tightened_before_the_release_falls_on_the_tight_line_resolution(env):
    info, loop_m = _episode(env, SCENE, [1.0, -1.0, -1.0])
    assert info["spacing_m"] == pytest.approx(50.0 + 27.25, abs=1e-6)  # 0.05, 0.1, .. 0.5 m/s, then 0.5 m/s
    assert info["fall_resolution"] == "tight_line" and loop_m == FAST["tight_line"]["loop_chain_segment_m"]


def test_waves_run_the_tight_line_resolution_from_the_start(env):
    """In waves with the tight_line rule's in_waves keys: a 1 m loop chain (configs/fidelity.yaml)."""
    info, loop_m = _episode(env, {**SCENE, "sea_state_hs_m": 0.5}, [0.0, 0.0, -1.0])
    assert info["fall_resolution"] == "tight_line" and loop_m == WAVES_LOOP_M
    assert WAVES_LOOP_M != FAST["tight_line"]["loop_chain_segment_m"]
    vertical_m = env.unwrapped.core.sim.model.scene.discretization.vertical_chain_segment_m
    assert vertical_m == FAST["tight_line"]["vertical_chain_segment_m"]  # the keys in_waves leaves alone


def test_pre_release_resolution_follows_the_sea_state_and_the_starting_geometry():
    cfg = load_env_config("anchor-release")
    factory = SceneFactory(cfg)
    scenario = {**representative_scenario(cfg), **SCENE}
    assert factory.pre_release_resolution(scenario) == {}
    waves = factory.pre_release_resolution({**scenario, "sea_state_hs_m": 0.2})
    assert waves["loop_chain_segment_m"] == WAVES_LOOP_M
    # calm, but tight from the start (spacing 0.3 h): fine from the start too, with the calm tight_line keys
    tight = factory.pre_release_resolution({**scenario, "vessel_spacing_over_depth": 0.3})
    assert tight == {**waves, "loop_chain_segment_m": FAST["tight_line"]["loop_chain_segment_m"]}
    assert factory.scene({**scenario, "sea_state_hs_m": 0.2}).discretization.loop_chain_segment_m == WAVES_LOOP_M


def test_fall_resolution_thresholds_and_explicit_keys():
    cfg = load_env_config("anchor-release")
    factory = SceneFactory(cfg)
    scene = factory.scene({**representative_scenario(cfg), **SCENE})
    assert factory.fall_resolution(scene, 50.0, 540.0, 0.0) is None
    assert factory.fall_resolution(scene, 77.25, 522.3, 0.0) == {k: FAST["tight_line"][k] for k in (
        "vertical_chain_segment_m", "loop_chain_segment_m", "fibre_segment_m", "wire_segment_m")}
    assert factory.fall_resolution(scene, 50.0, 500.0, 0.0) is not None  # 10 m of slack
    assert factory.fall_resolution(scene, 50.0, 540.0, 0.2) is not None  # slack, but the loop still moves
    # a key set explicitly in the config wins over the tight_line entry; with all of them set nothing changes
    pinned = load_env_config("anchor-release", {"fidelity.discretization.loop_chain_segment_m": 2.0})
    assert "loop_chain_segment_m" not in SceneFactory(pinned).fall_resolution(scene, 77.25, 522.3, 0.0)
    explicit = {f"fidelity.discretization.{k}": v for k, v in FAST.items() if k.endswith("_segment_m")}
    pinned_all = SceneFactory(load_env_config("anchor-release", explicit))
    assert pinned_all.fall_resolution(scene, 77.25, 522.3, 0.0) is None


def test_a_refused_remesh_keeps_the_preset_resolution_and_says_why(env, monkeypatch):
    import moor_env.envs.resolution as core_module

    def refuse(state, source, target):
        raise ValueError("line 'mooring_line' needs 999 segments")

    monkeypatch.setattr(core_module, "remesh_state", refuse)
    info, loop_m = _episode(env, SCENE, [1.0, -1.0, -1.0])
    assert info["fall_resolution"].startswith("preset (remesh refused: line 'mooring_line' needs 999")
    assert loop_m == FAST["loop_chain_segment_m"] and info["touchdown"]["speed_m_s"] > 20.0


def test_an_explicit_fall_after_the_implicit_pre_release(default_overrides, env):
    """``fidelity.discretization.fall_integrator``: the remeshed fall runs symplectic Euler at 0.9 times its own
    stability limit on the fall's mesh, from the same equilibrium (statics key unchanged) and pre-release phase."""
    explicit = gym.make("moor_env/AnchorRelease-v0",
                        overrides={**default_overrides, "fidelity.discretization.fall_integrator": "symplectic_euler"})
    info, loop_m = _episode(explicit, SCENE, [1.0, -1.0, -1.0])
    sim = explicit.unwrapped.core.sim
    assert info["fall_resolution"] == "tight_line" and loop_m == FAST["tight_line"]["loop_chain_segment_m"]
    assert sim.integrator_code == INTEGRATOR_SYMPLECTIC_EULER
    assert sim.dt == pytest.approx(0.9 * stable_time_step(sim.model.arrays(), "symplectic_euler")[0], rel=1e-12)
    assert sim.dt < 1e-3 < sim.model.dt_s  # the implicit model's own step stays what it was
    env.reset(seed=0, options=SCENE)
    assert explicit.unwrapped.core.statics_key == env.unwrapped.core.statics_key

"""Vector envs: make_vec sync/async, and the batched env's rows equal single envs bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.compile import compile_scene
from moor_env.envs import AnchorReleaseVectorEnv
from moor_env.envs.core import InstallationCore
from moor_env.envs.scenario import draw_scenario


def _actions(n_envs, n_steps, seed=0):
    rng = np.random.default_rng(seed)
    acts = rng.uniform(-1, 1, (n_steps, n_envs, 3)).astype(np.float32)
    acts[..., 2] = np.where(rng.uniform(size=(n_steps, n_envs)) < 0.25, 1.0, -1.0)  # release now and then
    return acts


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_modes(tiny, mode):
    env = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=2, vectorization_mode=mode, config="tiny",
                       overrides=tiny)
    obs, info = env.reset(seed=0)
    assert obs.shape == (2, 27)
    for act in _actions(2, 6):
        obs, reward, terminated, truncated, info = env.step(act)
        assert np.all(np.isfinite(obs)) and np.all(np.isfinite(reward))
    env.close()


# the coarse pre-release step (implicit integrator only) with its fallback path is covered by the last case
COARSE = {"fidelity.discretization.integrator": "implicit_euler", "control.pre_release_dt_s": 0.13}
# the `fast` preset: coarse chain before the release, every tiny fall remeshed onto its tight_line chain
REMESH = {"fidelity": {"fidelity": "fast", "discretization.fibre_segment_m": 20.0,
                       "discretization.wire_segment_m": 30.0}}
# the same with the fall's step growing where the lines move slowly (the kernel's step-growth column)
GROWING = {"fidelity": {**REMESH["fidelity"], "discretization.fall_step_growth_max": 3.0}}


@pytest.mark.parametrize(("n", "threads", "extra"), [(3, 1, {}), (3, 2, {}), (10, 2, {}), (3, 2, COARSE),
                                                     (3, 2, REMESH), (3, 2, GROWING)])
def test_batched_rows_equal_single_envs(tiny, n, threads, extra):  # 10 on 2 threads: groups of 5 per kernel call
    steps = 40
    overrides = {**tiny, **extra}
    batched = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, vectorization_mode="vector_entry_point",
                           config="tiny", overrides=overrides, num_threads=threads)
    assert isinstance(batched, AnchorReleaseVectorEnv)
    sync = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, vectorization_mode="sync", config="tiny",
                        overrides=overrides)
    obs_b, info_b = batched.reset(seed=21)
    obs_s, info_s = sync.reset(seed=21)
    assert np.array_equal(obs_b, obs_s)
    ended = remeshed = 0
    growths = set()
    for act in _actions(n, steps, seed=4):
        out_b = batched.step(act)
        out_s = sync.step(act)
        for k in range(4):
            assert np.array_equal(out_b[k], out_s[k]), (k, out_b[k], out_s[k])
        assert np.array_equal(out_b[4]["_reward_terms"], out_s[4]["_reward_terms"])
        for term, values in out_s[4]["reward_terms"].items():
            batched_values = out_b[4]["reward_terms"][term]
            assert np.array_equal(batched_values, values), (term, batched_values - values)
        ended += int(np.sum(out_b[2] | out_b[3]))
        remeshed += sum(e.unwrapped.core.fall_resolution == "tight_line" for e in sync.envs)
        growths |= {e.unwrapped.core.sim.step_growth_max for e in sync.envs}
    assert ended >= n  # autoresets happened on the way
    assert (remeshed > 0) == (extra in (REMESH, GROWING))
    assert max(growths) == (3.0 if extra is GROWING else 1.0)
    batched.close()
    sync.close()


def test_batched_reset_mask_and_options(tiny):
    env = AnchorReleaseVectorEnv(num_envs=2, config="tiny", overrides=tiny)
    obs, info = env.reset(seed=0, options={"sea_state_hs_m": 0.0})
    assert np.all(info["scenario"]["sea_state_hs_m"] == 0.0)
    obs2, info2 = env.reset(options={"reset_mask": np.array([False, True])})
    assert np.array_equal(obs2[0], obs[0]) and list(info2["_scenario"]) == [False, True]
    frames = AnchorReleaseVectorEnv(num_envs=1, config="tiny", overrides=tiny, render_mode="rgb_array")
    frames.reset(seed=0)
    (frame,) = frames.render()
    assert frame.ndim == 3


@pytest.mark.parametrize("fall", [{}, {"fidelity.discretization.fall_integrator": "implicit_euler"}],
                         ids=["scene-integrator", "fall-integrator"])
def test_derived_model_equals_compiled(tiny, fall):
    """An episode's model is the cached statics model with its sea state, Cd_t and fall integrator: check it
    against a compile."""
    core = InstallationCore(gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, **fall}
                                     ).unwrapped.cfg)
    rng = np.random.default_rng(0)
    for _ in range(3):
        scenario = draw_scenario(core.cfg, rng, {"sea_state_hs_m": float(rng.uniform(0.5, 3))})
        core.start(scenario)
        derived = core.sim.model
        fresh = compile_scene(core.factory.scene(scenario))
        assert derived.scene == fresh.scene
        assert derived.dt_s == fresh.dt_s
        for name, arr in fresh.arrays().items():
            assert np.array_equal(getattr(derived, name), arr), name
        for name in ("body_f", "body_q", "current_profile", "node_pos0", "body_state0", "vessel_base_m"):
            assert np.array_equal(getattr(derived, name), getattr(fresh, name)), name


def test_merge_infos_equals_gymnasium_add_info(tiny):
    """The batched env's one-pass info merge against Gymnasium's env-by-env ``_add_info`` on real step, touchdown
    and reset infos (keys present in some envs only, nested dicts, strings, bools, floats)."""
    from moor_env.envs.vector_infos import _same_layout, merge_infos

    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny)
    infos = [env.reset(seed=0)[1]]
    for a in ([0.0, 0.0, -1.0], [0.5, 0.5, 1.0]):  # a control step, then release: touchdown info
        infos.append(env.step(np.array(a, np.float32))[4])
    infos.append(env.reset(seed=1)[1])
    vector = AnchorReleaseVectorEnv(num_envs=6, config="tiny", overrides=tiny)
    items = list(zip([0, 2, 3, 5], infos, strict=True))
    expected: dict = {}
    for i, info in items:
        expected = vector._add_info(expected, info, i)
    merged = merge_infos(items, 6)

    def check(a, b):
        assert list(a) == list(b)
        for key in a:
            if isinstance(a[key], dict):
                check(a[key], b[key])
            else:
                assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, key
                assert all(x == y for x, y in zip(a[key].tolist(), b[key].tolist(), strict=True)), key

    check(merged, expected)
    # every slot with the same keys (the usual step): the all-slots path, against the same reference
    envs = _stepped_envs(tiny, 3)
    vector = AnchorReleaseVectorEnv(num_envs=3, config="tiny", overrides=tiny)
    for action in ([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]):  # a control step, then touchdown infos
        same = list(enumerate(env.step(np.array(action, np.float32))[4] for env in envs))
        assert _same_layout(same)
        expected = {}
        for i, info in same:
            expected = vector._add_info(expected, info, i)
        check(merge_infos(same, 3), expected)


def _stepped_envs(tiny, n: int) -> list:
    envs = [gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides=tiny) for _ in range(n)]
    for seed, env in enumerate(envs):
        env.reset(seed=seed)
    return envs


def test_batched_fallback_matches_single_env(tiny):
    """A coarse pre-release advance that blows up is repeated at the scene's step in the batched env as in the
    single env (here it blows up again: a strain limit below the hanging chain's static strain)."""
    overrides = {**tiny, **COARSE, "scene_overrides.simulation.strain_limit": 1e-4}
    batched = AnchorReleaseVectorEnv(num_envs=2, config="tiny", overrides=overrides)
    sync = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=2, vectorization_mode="sync", config="tiny",
                        overrides=overrides)
    batched.reset(seed=3, options={"sea_state_hs_m": 0.0})
    sync.reset(seed=3, options={"sea_state_hs_m": 0.0})
    act = np.array([[0.0, 0.0, -1.0]] * 2, np.float32)
    out_b, out_s = batched.step(act), sync.step(act)
    assert np.all(out_b[2]) and np.array_equal(out_b[1], out_s[1]) and np.array_equal(out_b[0], out_s[0])
    assert list(out_b[4]["sim_status"]) == list(out_s[4]["sim_status"])
    assert all(s.startswith("diverged") for s in out_b[4]["sim_status"])
    assert [core.fallbacks for core in batched.cores] == [1, 1]
    assert [env.unwrapped.core.fallbacks for env in sync.envs] == [1, 1]


def test_balanced_groups_put_a_fall_apart_from_the_control_steps():
    """Reference: longest-first list scheduling. One fall (30 s at 5 ms on 300 node slots) against seven 1 s
    control steps at 0.1 s: the fall gets a group to itself, the control steps share the other; nothing is lost."""
    from types import SimpleNamespace

    from moor_env.envs.batch import balanced_groups

    def job(t_span_s, dt_s, nodes):
        sim = SimpleNamespace(state=SimpleNamespace(t=10.0, node_pos=np.zeros((nodes, 3))))
        return (sim, 10.0 + t_span_s, False, dt_s)

    items = [(i, job(1.0, 0.1, 190)) for i in range(7)]
    items.insert(3, (7, job(30.0, 0.005, 300)))
    groups = balanced_groups(items, 2)
    assert [slot for slot, _ in groups[0]] == [7]
    assert sorted(slot for slot, _ in groups[1]) == list(range(7))
    assert balanced_groups(items[:1], 4) == [items[:1]] and balanced_groups([], 2) == []

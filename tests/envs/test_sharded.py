"""The batched env over worker processes (moor_env.envs.sharded): rows and infos equal the in-process batched
env bit for bit, reset masks and options pass through, worker failures surface in the main process."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from moor_env.envs import AnchorReleaseVectorEnv
from moor_env.envs.sharded import ShardedVectorEnv, _shard_bounds
from moor_env.errors import ConfigError


def _check_infos(a: dict, b: dict) -> None:
    """Equal keys, dtypes, shapes and values; ``statics`` (where the equilibrium came from: solved, memory or
    disk cache) is only checked for layout, since every process has a cache of its own."""
    assert list(a) == list(b)
    for key in a:
        if key == "statics":
            assert a[key].shape == b[key].shape
        elif isinstance(a[key], dict):
            _check_infos(a[key], b[key])
        else:
            assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, key
            assert all(x == y for x, y in zip(a[key].tolist(), b[key].tolist(), strict=True)), key


def test_shard_bounds_cover_every_slot_once():
    for n, k in ((1, 1), (5, 2), (16, 3), (3, 3)):
        bounds = _shard_bounds(n, k)
        assert bounds[0][0] == 0 and bounds[-1][1] == n and len(bounds) == k
        assert all(b1 == a2 for (_, b1), (a2, _) in zip(bounds[:-1], bounds[1:], strict=True))
        assert max(b - a for a, b in bounds) - min(b - a for a, b in bounds) <= 1


def test_sharded_rows_and_infos_equal_the_batched_env(tiny):
    n, steps = 5, 30
    sharded = gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, vectorization_mode="vector_entry_point",
                           config="tiny", overrides=tiny, num_workers=2)
    assert isinstance(sharded, ShardedVectorEnv) and sharded.sizes == [2, 3]
    batched = AnchorReleaseVectorEnv(num_envs=n, config="tiny", overrides=tiny, num_threads=1)
    obs_s, info_s = sharded.reset(seed=7)
    obs_b, info_b = batched.reset(seed=7)
    assert np.array_equal(obs_s, obs_b)
    _check_infos(info_s, info_b)
    rng = np.random.default_rng(2)
    ended = 0
    for _ in range(steps):
        act = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        act[:, 2] = np.where(rng.uniform(size=n) < 0.2, 1.0, -1.0)
        out_s, out_b = sharded.step(act), batched.step(act)
        for k in range(4):
            assert np.array_equal(out_s[k], out_b[k]), (k, out_s[k], out_b[k])
        _check_infos(out_s[4], out_b[4])
        ended += int(np.sum(out_s[2] | out_s[3]))
    assert ended >= n  # touchdowns (their infos) and autoresets happened on the way
    obs_s, info_s = sharded.reset(options={"reset_mask": np.array([False, False, True, False, False]),
                                           "sea_state_hs_m": 0.0})
    obs_b, info_b = batched.reset(options={"reset_mask": np.array([False, False, True, False, False]),
                                           "sea_state_hs_m": 0.0})
    assert np.array_equal(obs_s, obs_b)
    _check_infos(info_s, info_b)
    sharded.close()
    batched.close()
    assert sharded.processes == []


def test_worker_failure_is_raised_in_the_main_process(tiny):
    env = ShardedVectorEnv(num_envs=2, num_workers=2, config="tiny", overrides=tiny)
    with pytest.raises(RuntimeError, match="call reset"):  # both shards refuse
        env.step(np.zeros((2, 3), np.float32))
    env.close()
    # only the local shard (slot 0) reset: the worker's failure comes back with its traceback (a failed worker
    # ends, as gymnasium's AsyncVectorEnv workers do)
    env = ShardedVectorEnv(num_envs=2, num_workers=2, config="tiny", overrides=tiny)
    env.reset(seed=1, options={"reset_mask": np.array([True, False])})
    with pytest.raises(RuntimeError, match=r"worker 1 \(slots 1\.\.1\):(.|\n)*call reset"):
        env.step(np.zeros((2, 3), np.float32))
    env.close()
    assert env.processes == [] and env.local is None


def test_blocking_workers_give_the_same_rows(tiny):
    """spin_s=0 (block on the pipe at once) changes only when a process wakes, never a result."""
    envs = [ShardedVectorEnv(num_envs=3, num_workers=2, config="tiny", overrides=tiny, spin_s=s) for s in (0, 0.01)]
    outs = [env.reset(seed=3)[0] for env in envs]
    assert np.array_equal(*outs)
    act = np.tile(np.array([0.3, -0.2, -1.0], np.float32), (3, 1))
    for _ in range(5):
        outs = [env.step(act) for env in envs]
        for k in range(4):
            assert np.array_equal(outs[0][k], outs[1][k])
    for env in envs:
        env.close()


def test_bad_worker_settings_name_the_field(tiny):
    with pytest.raises(ConfigError, match="num_workers"):
        ShardedVectorEnv(num_envs=2, num_workers=0, config="tiny", overrides=tiny)
    with pytest.raises(ConfigError, match="spin_s"):
        ShardedVectorEnv(num_envs=2, num_workers=2, config="tiny", overrides=tiny, spin_s=-1.0)
    with pytest.raises(ConfigError, match="num_threads"):
        gym.make_vec("moor_env/AnchorRelease-v0", num_envs=2, vectorization_mode="vector_entry_point",
                     config="tiny", overrides=tiny, num_workers=2, num_threads=2)

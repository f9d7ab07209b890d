"""The vector entry point of ``moor_env/AnchorRelease-v0`` (:func:`make_vector_env`).

``gym.make_vec("moor_env/AnchorRelease-v0", num_envs=8)`` (or ``vectorization_mode="vector_entry_point"``)
returns the batched :class:`~moor_env.envs.vector_env.AnchorReleaseVectorEnv`; with ``num_workers`` > 1 it
returns :class:`~moor_env.envs.sharded.ShardedVectorEnv` instead: the slots split over that many processes (this
one and ``num_workers - 1`` workers).
"""

from __future__ import annotations

from typing import Any

from gymnasium.vector import VectorEnv

from moor_env.envs.sharded import ShardedVectorEnv
from moor_env.envs.vector_env import AnchorReleaseVectorEnv
from moor_env.errors import ConfigError


def make_vector_env(num_envs: int = 1, num_workers: int = 1, **kwargs: Any) -> VectorEnv:
    """The vector entry point of AnchorRelease-v0 (``gym.make_vec(..., num_workers=k)``).

    ``num_workers`` 1 (default): :class:`AnchorReleaseVectorEnv` in this process, the kernel on ``num_threads``
    threads. More: :class:`~moor_env.envs.sharded.ShardedVectorEnv`, the slots split over that many processes
    (this one steps the first shard, ``k - 1`` workers the others; ``context`` picks the start method and
    ``spin_s`` how long a process polls its pipe), which also spreads the per-scene Python over the cores.
    """
    if num_workers == 1:
        kwargs.pop("context", None)
        kwargs.pop("spin_s", None)
        return AnchorReleaseVectorEnv(num_envs, **kwargs)
    if "num_threads" in kwargs:
        raise ConfigError("num_threads", kwargs["num_threads"], "not set with num_workers > 1 (one thread each)")
    return ShardedVectorEnv(num_envs, num_workers, **kwargs)

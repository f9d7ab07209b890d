"""The batched AnchorRelease-v0 vector env split over worker processes (``num_workers`` > 1).

:class:`~moor_env.envs.vector.AnchorReleaseVectorEnv` runs its kernel on threads, but the per-scene Python of
every step (actions, observation, reward, info) runs on one core under the GIL; measured on the calm default
scene it is about a third of the CPU per transition, and with it the threads gained little on two cores
(benchmarks/bench_env.py). :class:`ShardedVectorEnv` gives each of ``num_workers`` processes a contiguous shard
of the slots, each shard an ``AnchorReleaseVectorEnv`` with one kernel call per step, so both the kernel and
the Python run on every core. One message per shard per step carries the actions out and the shard's results
back (a gymnasium ``AsyncVectorEnv`` sends one per scene); the infos travel as the slots' plain dicts and are
merged here (:func:`~moor_env.envs.vector.merge_infos`), since numpy's layout costs 25x more to pickle.

Row i is the row of the in-process batched env and of the single env reset with seed ``seed + i`` (tested):
the shards get the slots' own seeds and run the same code.
"""

from __future__ import annotations

import multiprocessing as mp
import traceback
from typing import Any

import numpy as np
from gymnasium.vector import VectorEnv

from moor_env.envs.vector import AnchorReleaseVectorEnv, init_vector_env, merge_infos
from moor_env.errors import ConfigError

CLOSE_TIMEOUT_S = 10.0


def _shard_bounds(num_envs: int, num_workers: int) -> list[tuple[int, int]]:
    """Contiguous slot ranges of about equal size, one per worker."""
    edges = np.linspace(0, num_envs, num_workers + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def _serve(conn, num_envs: int, cfg, max_episode_steps: int | None, render_mode: str | None) -> None:
    """A worker: one in-process batched env of ``num_envs`` slots, driven by (command, argument) messages."""
    env = None
    try:
        env = AnchorReleaseVectorEnv(num_envs, cfg, max_episode_steps=max_episode_steps, render_mode=render_mode,
                                     num_threads=1)
        conn.send(("ok", None))
        while True:
            command, argument = conn.recv()
            if command == "step":
                conn.send(("ok", env.step_slots(argument)))
            elif command == "reset":
                seeds, options = argument
                conn.send(("ok", env.reset_slots(seed=seeds, options=options)))
            elif command == "render":
                conn.send(("ok", env.render()))
            elif command == "close":
                break
    except (KeyboardInterrupt, EOFError):
        pass
    except Exception:  # noqa: BLE001 - any failure goes back to the main process, which raises it
        conn.send(("error", traceback.format_exc()))
    finally:
        if env is not None:
            env.close()
        conn.close()


class ShardedVectorEnv(VectorEnv):
    """``num_envs`` AnchorRelease-v0 episodes on ``num_workers`` processes, each stepping its shard of the slots
    with one batch-kernel call (next-step autoreset, as :class:`AnchorReleaseVectorEnv`).

    Made by ``gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, num_workers=k)`` with k > 1.

    Parameters
    ----------
    num_envs : int
    num_workers : int
        Worker processes (at most ``num_envs``); one per core is the fastest on an otherwise idle machine.
    config, overrides, max_episode_steps, render_mode :
        As for :class:`AnchorReleaseVectorEnv` (the config is validated here, before any worker starts).
    context : str, optional
        ``multiprocessing`` start method ("fork", "forkserver", "spawn"); default: the platform's, as
        gymnasium's ``AsyncVectorEnv``.
    """

    metadata = AnchorReleaseVectorEnv.metadata

    def __init__(self, num_envs: int = 2, num_workers: int = 2, config="anchor-release",
                 overrides: dict[str, Any] | None = None, max_episode_steps: int | None = None,
                 render_mode: str | None = None, context: str | None = None) -> None:
        self.connections: list = []
        self.processes: list = []
        if num_workers < 1:
            raise ConfigError("num_workers", num_workers, ">= 1")
        init_vector_env(self, num_envs, config, overrides, render_mode)
        self.bounds = _shard_bounds(num_envs, min(num_workers, num_envs))
        self.sizes = [b - a for a, b in self.bounds]
        self._obs = np.zeros(self.observation_space.shape, dtype=np.float32)
        ctx = mp.get_context(context)
        for size in self.sizes:
            parent, child = ctx.Pipe()
            process = ctx.Process(target=_serve, args=(child, size, self.cfg, max_episode_steps, render_mode),
                                  daemon=True)
            process.start()
            child.close()
            self.connections.append(parent)
            self.processes.append(process)
        self._collect()  # each worker reports that its env was made

    def _collect(self, workers=None) -> list[Any]:
        """The replies of ``workers`` (default: all), in order; a worker's failure is raised here with its
        traceback."""
        workers = range(len(self.connections)) if workers is None else workers
        replies = [(k, *self.connections[k].recv()) for k in workers]
        errors = [f"worker {k} (slots {self.bounds[k][0]}..{self.bounds[k][1] - 1}):\n{value}"
                  for k, status, value in replies if status == "error"]
        if errors:
            raise RuntimeError("a ShardedVectorEnv worker failed:\n" + "\n".join(errors))
        return [value for _, _, value in replies]

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every slot (or those in ``options["reset_mask"]``); seed i is ``seed + i`` for an int seed."""
        n = self.num_envs
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"seed list has {len(seeds)} entries, num_envs is {n}")
        options = dict(options) if options else {}
        mask = np.asarray(options.pop("reset_mask", np.ones(n, dtype=np.bool_)), dtype=np.bool_)
        if mask.shape != (n,) or not mask.any():
            raise ValueError(f"options['reset_mask'] must be a bool array of shape ({n},) with a True entry")
        active = []
        for k, (a, b) in enumerate(self.bounds):
            if mask[a:b].any():
                self.connections[k].send(("reset", (seeds[a:b], {**options, "reset_mask": mask[a:b]})))
                active.append(k)
        infos = []
        for k, (shard_obs, shard_infos) in zip(active, self._collect(active), strict=True):
            a, b = self.bounds[k]
            self._obs[a:b] = shard_obs
            infos += [(a + i, info) for i, info in shard_infos]
        return self._obs.copy(), merge_infos(infos, n)

    def step(self, actions):
        """Step every slot; a slot that ended on the previous step is reset instead (next-step autoreset)."""
        actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)
        for conn, (a, b) in zip(self.connections, self.bounds, strict=True):
            conn.send(("step", actions[a:b]))
        obs, rewards, terminated, truncated, shard_infos = zip(*self._collect(), strict=True)
        infos = [(a + i, info) for (a, _), pairs in zip(self.bounds, shard_infos, strict=True) for i, info in pairs]
        self._obs[...] = np.concatenate(obs)
        return (self._obs.copy(), np.concatenate(rewards), np.concatenate(terminated), np.concatenate(truncated),
                merge_infos(infos, self.num_envs))

    def render(self):
        """One frame per slot (``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array":
            return None
        for conn in self.connections:
            conn.send(("render", None))
        return tuple(frame for frames in self._collect() for frame in frames)

    def close_extras(self, **kwargs: Any) -> None:
        """Stop the workers (terminated if they do not end within ``CLOSE_TIMEOUT_S``)."""
        for conn in self.connections:
            try:
                conn.send(("close", None))
            except (BrokenPipeError, OSError):
                pass
        for process in self.processes:
            process.join(CLOSE_TIMEOUT_S)
            if process.is_alive():
                process.terminate()
        for conn in self.connections:
            conn.close()
        self.connections, self.processes = [], []

"""The batched AnchorRelease-v0 vector env split over worker processes (``num_workers`` > 1).

The in-process :class:`~moor_env.envs.vector_env.AnchorReleaseVectorEnv` runs its kernel on threads, but the
per-scene Python of every step (actions, observation, reward, info) runs on one core under the GIL; measured on
the calm default scene it is about a third of the CPU per transition, and with it the threads gained little on
two cores (benchmarks/bench_env.py). :class:`ShardedVectorEnv` splits the slots into ``num_workers`` contiguous
shards, each an ``AnchorReleaseVectorEnv`` with one kernel call per step, so both the kernel and the Python run
on every core. The calling process steps the first shard itself while ``num_workers - 1`` worker processes step
the others, so that no process waits idle for the rest. One message per worker per step carries the actions out
and the shard's results back (a gymnasium ``AsyncVectorEnv`` sends one per scene); the infos travel as the
slots' plain dicts and are merged here (:func:`~moor_env.envs.vector_infos.merge_infos`), since numpy's layout costs
25x more to pickle.

Why every process polls its pipe for ``spin_s`` before it blocks on it: on a virtual machine a process that
blocks lets its virtual CPU halt, and waking it is slow (measured here: a pipe round trip of 40-100 us after
1 ms idle, and a step of 16 calm slots on two worker processes took 0.8-1.5 ms of wall time for about 0.6 ms of
work in each). The messages of one step follow each other within about a millisecond, so a short poll catches
them with the CPU still running; past ``spin_s`` (a pause of the training loop) the process blocks and costs
nothing.

Row i is the row of the in-process batched env and of the single env reset with seed ``seed + i`` (tested):
the shards get the slots' own seeds and run the same code.
"""

from __future__ import annotations

import multiprocessing as mp
import time
import traceback
from typing import Any

import numpy as np
from gymnasium.vector import VectorEnv

from moor_env.envs.vector_env import AnchorReleaseVectorEnv, init_vector_env
from moor_env.envs.vector_infos import merge_infos
from moor_env.errors import ConfigError

CLOSE_TIMEOUT_S = 10.0
SPIN_S = 0.002  # how long a process polls its pipe before it blocks on it [s] (module docstring)


def _shard_bounds(num_envs: int, num_workers: int) -> list[tuple[int, int]]:
    """Contiguous slot ranges of about equal size, one per worker."""
    edges = np.linspace(0, num_envs, num_workers + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def _receive(conn, spin_s: float) -> Any:
    """The next message on ``conn``, polled for up to ``spin_s`` [s] before blocking (module docstring)."""
    if spin_s > 0.0 and not conn.poll():
        deadline = time.perf_counter() + spin_s
        while not conn.poll() and time.perf_counter() < deadline:
            pass
    return conn.recv()


def _serve(conn, num_envs: int, cfg, max_episode_steps: int | None, render_mode: str | None,
           spin_s: float) -> None:
    """A worker: one in-process batched env of ``num_envs`` slots, driven by (command, argument) messages."""
    env = None
    try:
        env = AnchorReleaseVectorEnv(num_envs, cfg, max_episode_steps=max_episode_steps, render_mode=render_mode,
                                     num_threads=1)
        conn.send(("ok", None))
        while True:
            command, argument = _receive(conn, spin_s)
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
    """``num_envs`` AnchorRelease-v0 episodes on ``num_workers`` processes (this one and ``num_workers - 1``
    workers), each stepping its shard of the slots with one batch-kernel call (next-step autoreset, as
    :class:`AnchorReleaseVectorEnv`).

    Made by ``gym.make_vec("moor_env/AnchorRelease-v0", num_envs=n, num_workers=k)`` with k > 1.

    Parameters
    ----------
    num_envs : int
    num_workers : int
        Processes that step the slots, this one included (at most ``num_envs``); one per core is the fastest on
        an otherwise idle machine.
    config, overrides, max_episode_steps, render_mode :
        As for :class:`AnchorReleaseVectorEnv` (the config is validated here, before any worker starts).
    context : str, optional
        ``multiprocessing`` start method ("fork", "forkserver", "spawn"); default: the platform's, as
        gymnasium's ``AsyncVectorEnv``.
    spin_s : float, optional
        How long a process polls for the next message before it blocks [s], >= 0 (module docstring; 0: block at
        once).
    """

    metadata = AnchorReleaseVectorEnv.metadata

    def __init__(self, num_envs: int = 2, num_workers: int = 2, config="anchor-release",
                 overrides: dict[str, Any] | None = None, max_episode_steps: int | None = None,
                 render_mode: str | None = None, context: str | None = None, spin_s: float = SPIN_S) -> None:
        self.connections: list = []
        self.processes: list = []
        self.local = None
        if num_workers < 1:
            raise ConfigError("num_workers", num_workers, ">= 1")
        if not spin_s >= 0.0:
            raise ConfigError("spin_s", spin_s, ">= 0 s")
        init_vector_env(self, num_envs, config, overrides, render_mode)
        self.spin_s = float(spin_s)
        self.bounds = _shard_bounds(num_envs, min(num_workers, num_envs))
        self.sizes = [b - a for a, b in self.bounds]
        self._obs = np.zeros(self.observation_space.shape, dtype=np.float32)
        ctx = mp.get_context(context)
        for size in self.sizes[1:]:  # the workers first: a forked one should not inherit the local shard
            parent, child = ctx.Pipe()
            process = ctx.Process(target=_serve, args=(child, size, self.cfg, max_episode_steps, render_mode,
                                                       self.spin_s), daemon=True)
            process.start()
            child.close()
            self.connections.append(parent)
            self.processes.append(process)
        self.local = AnchorReleaseVectorEnv(self.sizes[0], self.cfg, max_episode_steps=max_episode_steps,
                                            render_mode=render_mode, num_threads=1)
        self._collect()  # each worker reports that its env was made

    def _collect(self, shards=None) -> list[Any]:
        """The replies of the workers of ``shards`` (default: all; worker k steps shard k > 0 and talks on
        ``connections[k - 1]``), in order; a worker's failure is raised here with its traceback."""
        shards = range(1, len(self.bounds)) if shards is None else shards
        replies = [(k, *_receive(self.connections[k - 1], self.spin_s)) for k in shards]
        errors = [f"worker {k} (slots {self.bounds[k][0]}..{self.bounds[k][1] - 1}):\n{value}"
                  for k, status, value in replies if status == "error"]
        if errors:
            raise RuntimeError("a ShardedVectorEnv worker failed:\n" + "\n".join(errors))
        return [value for _, _, value in replies]

    def _all_shards(self, command: str, arguments: dict[int, Any], local_call) -> dict[int, Any]:
        """Send ``command`` with ``arguments[k]`` to the worker of every shard k > 0 in ``arguments``, run
        ``local_call(arguments[0])`` here meanwhile (if shard 0 is in them), and return every shard's result.
        The workers' replies are read even when the local call raises, so that no reply is left in a pipe."""
        workers = [k for k in arguments if k > 0]
        for k in workers:
            self.connections[k - 1].send((command, arguments[k]))
        local_error = None
        results = {}
        try:
            if 0 in arguments:
                results[0] = local_call(arguments[0])
        except Exception as error:  # noqa: BLE001 - raised below, after the workers' replies are read
            local_error = error
        try:
            results.update(zip(workers, self._collect(workers), strict=True))
        except RuntimeError as worker_error:
            raise worker_error from local_error
        if local_error is not None:
            raise local_error
        return results

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
        arguments = {k: (seeds[a:b], {**options, "reset_mask": mask[a:b]})
                     for k, (a, b) in enumerate(self.bounds) if mask[a:b].any()}
        results = self._all_shards("reset", arguments,
                                   lambda argument: self.local.reset_slots(seed=argument[0], options=argument[1]))
        infos = []
        for k, (shard_obs, shard_infos) in sorted(results.items()):
            a, b = self.bounds[k]
            self._obs[a:b] = shard_obs
            infos += [(a + i, info) for i, info in shard_infos]
        return self._obs.copy(), merge_infos(infos, n)

    def step(self, actions):
        """Step every slot; a slot that ended on the previous step is reset instead (next-step autoreset)."""
        actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)
        results = self._all_shards("step", {k: actions[a:b] for k, (a, b) in enumerate(self.bounds)},
                                   self.local.step_slots)
        obs, rewards, terminated, truncated, shard_infos = zip(*(results[k] for k in range(len(self.bounds))),
                                                               strict=True)
        infos = [(a + i, info) for (a, _), pairs in zip(self.bounds, shard_infos, strict=True) for i, info in pairs]
        self._obs[...] = np.concatenate(obs)
        return (self._obs.copy(), np.concatenate(rewards), np.concatenate(terminated), np.concatenate(truncated),
                merge_infos(infos, self.num_envs))

    def render(self):
        """One frame per slot (``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array":
            return None
        results = self._all_shards("render", dict.fromkeys(range(len(self.bounds))),
                                   lambda _: self.local.render())
        return tuple(frame for k in range(len(self.bounds)) for frame in results[k])

    def close_extras(self, **kwargs: Any) -> None:
        """Close the local shard and stop the workers (terminated if they do not end within ``CLOSE_TIMEOUT_S``)."""
        if self.local is not None:
            self.local.close()
            self.local = None
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

"""Train PPO with Ray RLlib on ``AnchorRelease-v0`` or ``AnchorPlan-v0``: the scale-out path to many machines.

    python -m agents.train_rllib --config configs/agents/rllib-release.yaml [--set key=value ...] [--address ADDR]

The config is YAML data validated by :class:`agents.rllib_config.RllibConfig` (errors name the dotted key). The env
is registered for the Ray workers with ``tune.register_env`` under :data:`RLLIB_ENV_NAME`; its creator
(:func:`make_rllib_env`) runs inside each worker process (which imports this module and with it ``moor_env``,
registering the env ids), so every worker builds its own env from the env config.

Ray: with no address (config ``ray.address``, ``--address`` or the ``RAY_ADDRESS`` variable) a local instance is
started on this machine (``ray.num_cpus`` CPUs); with one, the run joins that cluster (``ray start --head`` on
one node, ``ray start --address=HEAD:6379`` on the others) and the env runners spread over its nodes.

Run directory ``<out_dir>/<name>/seed-<seed>/``: ``rllib_config.yaml`` (resolved config), ``env_config.yaml``,
``meta.json`` (versions, git commit, the cluster's CPUs and nodes, status, env steps, wall time, throughput),
``progress.json`` (one row per iteration) and ``checkpoints/iter-<N>/`` (RLlib ``save_to_path``) with
``checkpoints/latest.json`` naming the newest, written after it. :class:`RllibPolicy` loads a run's policy for
:func:`agents.evaluate.evaluate_policy`.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import moor_env  # noqa: F401 - registers the env ids (also in each Ray worker, which imports this module)
from agents.config import parse_set
from agents.io import write_json_atomic, write_yaml_atomic
from agents.policy import Policy
from agents.rllib_config import RllibConfig, load_rllib_config
from agents.runs import git_state, load_run, run_dirs, versions
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.errors import ConfigError

RLLIB_ENV_NAME = "moor_env-rllib"
MODULE_PATH = ("learner_group", "learner", "rl_module", "default_policy")


# --- env and algorithm ------------------------------------------------------------------------------------------------
def make_rllib_env(env_context: dict[str, Any]):
    """Env creator registered with ``tune.register_env``; runs inside each Ray worker.

    ``env_context`` (RLlib's ``EnvContext``, a dict) holds ``id`` and ``config`` (the env config as a mapping).
    """
    return gym.make(env_context["id"], config=dict(env_context["config"]))


def build_ppo_config(cfg: RllibConfig, env_cfg: EnvConfig):
    """The RLlib ``PPOConfig`` of a run (new API stack)."""
    # ray (optional, the rl extra) loads only to train or to load an RLlib run
    from ray.rllib.algorithms.ppo import PPOConfig  # noqa: PLC0415
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig  # noqa: PLC0415

    runners = cfg.env_runners
    return (
        PPOConfig()
        .environment(RLLIB_ENV_NAME, env_config={"id": cfg.env.id, "config": env_cfg.model_dump(mode="json")})
        .env_runners(num_env_runners=runners.num_env_runners, num_envs_per_env_runner=runners.num_envs_per_env_runner,
                     num_cpus_per_env_runner=runners.num_cpus_per_env_runner,
                     rollout_fragment_length=runners.rollout_fragment_length,
                     sample_timeout_s=runners.sample_timeout_s)
        .learners(num_learners=cfg.num_learners)
        .training(**cfg.ppo.model_dump())
        .rl_module(model_config=DefaultModelConfig(**cfg.model.model_dump()))
        .debugging(seed=cfg.seed)
    )


def checked_ppo_config(cfg: RllibConfig, env_cfg: EnvConfig):
    """:func:`build_ppo_config` passed through RLlib's own cross-field checks (batch sizes, fragment lengths);
    a failed check is a ConfigError carrying RLlib's message."""
    ppo = build_ppo_config(cfg, env_cfg)
    try:
        ppo.validate()
    except ValueError as exc:
        raise ConfigError("config", cfg.name, "settings RLlib accepts", str(exc).split("\n")[0]) from None
    return ppo


def connect_ray(cfg: RllibConfig, address: str | None = None) -> dict[str, Any]:
    """Join the cluster (``address``, else ``ray.address``, else ``RAY_ADDRESS``) or start a local instance.

    An already initialised Ray (e.g. a test's ``ray.init``) is used as it is. Returns the cluster's CPUs and nodes.
    """
    import ray  # noqa: PLC0415 - ray (optional, the rl extra)

    if not ray.is_initialized():
        address = address or cfg.ray.address or os.environ.get("RAY_ADDRESS")
        kwargs: dict[str, Any] = {"include_dashboard": False, "runtime_env": cfg.ray.runtime_env}
        if address is None and cfg.ray.num_cpus is not None:
            kwargs["num_cpus"] = cfg.ray.num_cpus
        ray.init(address=address, **kwargs)
    nodes = [n for n in ray.nodes() if n.get("Alive")]
    return {"address": ray.get_runtime_context().gcs_address, "cluster_cpus": ray.cluster_resources().get("CPU", 0.0),
            "nodes": len(nodes), "ray": ray.__version__}


# --- run directory ----------------------------------------------------------------------------------------------------
def run_dir_of(cfg: RllibConfig) -> Path:
    """``<out_dir>/<name>/seed-<seed>``."""
    return Path(cfg.out_dir) / cfg.name / f"seed-{cfg.seed}"


def save_checkpoint(algo: Any, run_dir: Path, iteration: int, keep: int) -> Path:
    """Save to ``checkpoints/iter-<N>`` (via a temporary folder renamed into place), then point ``latest.json``
    at it and delete all but the newest ``keep``; an interrupted save leaves the previous checkpoint intact."""
    root = run_dir / "checkpoints"
    final = root / f"iter-{iteration:06d}"
    tmp = root / f".iter-{iteration:06d}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    algo.save_to_path(str(tmp.resolve()))
    shutil.rmtree(final, ignore_errors=True)
    os.replace(tmp, final)
    write_json_atomic(root / "latest.json", {"iteration": iteration, "path": final.name})
    for old in sorted(root.glob("iter-*"))[:-keep]:
        shutil.rmtree(old, ignore_errors=True)
    return final


def latest_checkpoint(run_dir: str | Path) -> Path:
    """The newest checkpoint folder of a run (``checkpoints/latest.json``)."""
    pointer = Path(run_dir) / "checkpoints" / "latest.json"
    if not pointer.is_file():
        raise ConfigError("run_dir", str(run_dir), "an RLlib run directory with checkpoints/latest.json")
    return pointer.parent / json.loads(pointer.read_text())["path"]


def _metric(result: dict[str, Any], *keys: str) -> float:
    node: Any = result
    for k in keys:
        if not isinstance(node, dict) or k not in node:
            return math.nan
        node = node[k]
    try:
        return float(node)
    except (TypeError, ValueError):
        return math.nan


def iteration_row(result: dict[str, Any], wall_s: float, steps_before: int) -> dict[str, Any]:
    """One ``progress.json`` row from an RLlib result dict: steps, episodes, returns, losses, throughput."""
    steps = int(_metric(result, "env_runners", "num_env_steps_sampled_lifetime"))
    it_s = _metric(result, "time_this_iter_s")
    return {
        "iteration": int(result["training_iteration"]),
        "env_steps": steps,
        "episodes": int(_metric(result, "env_runners", "num_episodes_lifetime")),
        "episode_return_mean": _metric(result, "env_runners", "episode_return_mean"),
        "episode_len_mean": _metric(result, "env_runners", "episode_len_mean"),
        "total_loss": _metric(result, "learners", "default_policy", "total_loss"),
        "entropy": _metric(result, "learners", "default_policy", "entropy"),
        "iteration_s": it_s,
        "sample_s": _metric(result, "env_runners", "sample"),
        "wall_s": wall_s,
        "env_steps_per_s": (steps - steps_before) / it_s if it_s > 0 else math.nan,
    }


def _meta(cfg: RllibConfig, cluster: dict[str, Any]) -> dict[str, Any]:
    return {"name": cfg.name, "seed": cfg.seed, "framework": "rllib", "status": "running", "env_steps": 0,
            "train_wall_s": 0.0, "started": time.strftime("%Y-%m-%dT%H:%M:%S"), **git_state(),
            "versions": {**versions(), "ray": cluster["ray"]}, "cluster": cluster, "cpu_count": os.cpu_count(),
            "argv": sys.argv[1:]}


# --- training ---------------------------------------------------------------------------------------------------------
def train_rllib(cfg: RllibConfig, address: str | None = None) -> tuple[Path, dict[str, Any]]:
    """Train until ``cfg.total_timesteps`` env steps are sampled; returns the run directory and its ``meta``.

    ``meta`` holds ``env_steps``, ``train_wall_s`` (the training loop), ``build_s`` (starting the algorithm and its
    actors) and ``env_steps_per_s`` (env steps / training-loop wall time: sampling and learning together).
    """
    import torch  # noqa: PLC0415 - torch (optional, the rl extra)
    from ray import tune  # noqa: PLC0415 - ray (optional)

    env_cfg = load_env_config(cfg.env.config, cfg.env.overrides)
    ppo = checked_ppo_config(cfg, env_cfg)
    run_dir = run_dir_of(cfg)
    cluster = connect_ray(cfg, address)
    tune.register_env(RLLIB_ENV_NAME, make_rllib_env)
    torch.set_num_threads(cfg.torch_threads)
    write_yaml_atomic(run_dir / "rllib_config.yaml", cfg.model_dump(mode="json"))
    write_yaml_atomic(run_dir / "env_config.yaml", env_cfg.model_dump(mode="json"))
    meta = _meta(cfg, cluster)
    write_json_atomic(run_dir / "meta.json", meta)

    t_build = time.perf_counter()
    algo = ppo.build_algo()
    meta["build_s"] = time.perf_counter() - t_build
    rows: list[dict[str, Any]] = []
    steps = 0
    bar = tqdm(total=cfg.total_timesteps, desc=f"rllib {cfg.name}", unit="step", disable=not cfg.progress_bar)
    t0 = time.perf_counter()
    try:
        while steps < cfg.total_timesteps:
            row = iteration_row(algo.train(), time.perf_counter() - t0, steps)
            bar.update(min(row["env_steps"], cfg.total_timesteps) - min(steps, cfg.total_timesteps))
            bar.set_postfix(ret=f"{row['episode_return_mean']:.3f}", sps=f"{row['env_steps_per_s']:.0f}")
            steps = row["env_steps"]
            rows.append(row)
            write_json_atomic(run_dir / "progress.json", rows)
            if row["iteration"] % cfg.checkpoint.every_iterations == 0 or steps >= cfg.total_timesteps:
                save_checkpoint(algo, run_dir, row["iteration"], cfg.checkpoint.keep)
    finally:
        bar.close()
        wall_s = time.perf_counter() - t0
        meta.update(status="finished" if steps >= cfg.total_timesteps else "interrupted", env_steps=steps,
                    iterations=len(rows), train_wall_s=wall_s, env_steps_per_s=steps / wall_s if wall_s > 0 else 0.0,
                    finished=time.strftime("%Y-%m-%dT%H:%M:%S"))
        write_json_atomic(run_dir / "meta.json", meta)
        algo.stop()
    return run_dir, meta


# --- policy of a trained run ------------------------------------------------------------------------------------------
class RllibPolicy(Policy):
    """The RLModule of an RLlib run acting deterministically (the mean of its Gaussian), for ``evaluate_policy``.

    Attributes: ``module``, ``env_id``, ``env_config`` (:class:`EnvConfig`), ``name``, ``run_dir``.
    """

    def __init__(self, module: Any, env_id: str, env_config: EnvConfig, name: str, run_dir: Path | None = None):
        self.module, self.env_id, self.env_config, self.name, self.run_dir = module, env_id, env_config, name, run_dir
        self._dist_cls = module.get_inference_action_dist_cls()

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The deterministic action, clipped to the action box [-1, 1]."""
        import torch  # noqa: PLC0415 - torch (optional, the rl extra)

        with torch.no_grad():
            out = self.module.forward_inference({"obs": torch.as_tensor(np.asarray(obs, np.float32)[None])})
            action = self._dist_cls.from_logits(out["action_dist_inputs"]).to_deterministic().sample()
        return np.clip(action.numpy()[0], -1.0, 1.0).astype(np.float32)

    @classmethod
    def load(cls, run_dir: str | Path) -> RllibPolicy:
        """Load the newest checkpoint's policy module of a run directory (no Ray instance needed)."""
        from ray.rllib.core.rl_module.rl_module import RLModule  # noqa: PLC0415 - ray (optional, the rl extra)

        run_dir = Path(run_dir)
        cfg = load_rllib_config(run_dir / "rllib_config.yaml")
        module = RLModule.from_checkpoint(str(latest_checkpoint(run_dir).joinpath(*MODULE_PATH).resolve()))
        return cls(module, cfg.env.id, load_env_config(run_dir / "env_config.yaml"), f"{cfg.name}/{run_dir.name}",
                   run_dir)


def is_rllib_run(run_dir: str | Path) -> bool:
    """Whether a folder is an RLlib run directory (holds ``rllib_config.yaml``)."""
    return (Path(run_dir) / "rllib_config.yaml").is_file()


def load_run_policies(path: str | Path, checkpoint: str = "final") -> list[Policy]:
    """One policy per seed of a run or experiment directory, RLlib (this module; its final checkpoint) or
    stable-baselines3 (:func:`agents.runs.load_run` with ``checkpoint``): ``runs/<name>/seed-<k>`` or
    ``runs/<name>`` holding ``seed-*/``."""
    path = Path(path)
    rllib = [path] if is_rllib_run(path) else sorted(p for p in path.glob("seed-*") if is_rllib_run(p))
    if rllib:
        return [RllibPolicy.load(p) for p in rllib]
    return [load_run(p, checkpoint) for p in run_dirs(path)]


# --- command line -----------------------------------------------------------------------------------------------------
def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line arguments of ``python -m agents.train_rllib``."""
    p = argparse.ArgumentParser(prog="python -m agents.train_rllib", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", required=True, help="configs/agents/rllib-*.yaml or a bundled name (rllib-release)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config key (dotted, value read as YAML), e.g. env_runners.num_env_runners=8")
    p.add_argument("--address", help="Ray cluster to join (default: ray.address, then RAY_ADDRESS, else local)")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Entry point: train, then print the run directory and the throughput."""
    args = parse_args(argv)
    try:
        cfg = load_rllib_config(args.config, parse_set(args.set))
        run_dir, meta = train_rllib(cfg, args.address)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    cl = meta["cluster"]
    print(f"run: {run_dir}")
    print(f"throughput: {meta['env_steps_per_s']:.1f} env steps/s ({meta['env_steps']} steps in "
          f"{meta['train_wall_s']:.1f} s, {meta['iterations']} iterations; start-up {meta['build_s']:.1f} s) on "
          f"{cl['nodes']} node(s), {cl['cluster_cpus']:.0f} CPUs, {cfg.env_runners.num_env_runners} env runner(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

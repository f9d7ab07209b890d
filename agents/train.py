"""Train stable-baselines3 PPO, SAC or TD3 on ``AnchorPlan-v0`` or ``AnchorRelease-v0`` from a YAML config.

    python -m agents.train --config configs/agents/quick.yaml [--set key=value ...] [--resume]

One run directory per seed, ``<out_dir>/<name>/seed-<seed>/``:

* ``config.yaml`` (the resolved training config), ``env_config.yaml`` (the resolved env config),
  ``scene.yaml`` (the scene the scenarios modify, fidelity and overrides applied), ``meta.json`` (package version,
  git commit and whether the tree was dirty, library versions, seed, status, timesteps, training time);
* ``checkpoints/step-<N>/`` (``model.zip``, ``vecnormalize.json`` and ``.pkl``, ``replay_buffer.pkl`` for
  off-policy algorithms) and ``checkpoints/latest.json`` naming the newest: ``--resume`` continues from it;
* ``best/`` (the evaluation callback's best model), ``model.zip`` + ``vecnormalize.*`` (final), ``evaluations.json``
  (mean reward and success rate at every evaluation), ``tb/`` (TensorBoard: ``tensorboard --logdir runs``).

Every file is written to a temporary name in its folder and moved into place (``os.replace``), and a checkpoint's
pointer is written after its files, so an interrupted run loses nothing it had saved.

stable-baselines3 and torch (the optional ``rl`` extra) are imported inside the functions that use them, so that
importing this module (and :mod:`agents.main`) needs neither.
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

import moor_env
from agents.config import TrainConfig, load_train_config, parse_set
from agents.evaluate import evaluate_policy
from agents.io import write_atomic, write_json_atomic, write_yaml_atomic
from agents.runs import ObsNormalizer, RunPolicy, algo_class, git_state, latest_checkpoint, versions
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.envs.scene import SceneFactory
from moor_env.errors import ConfigError


# --- environments -------------------------------------------------------------------------------------------------
class _MakeEnv:
    """Picklable env factory for SubprocVecEnv workers."""

    def __init__(self, env_id: str, env_config: EnvConfig) -> None:
        self.env_id, self.env_config = env_id, env_config

    def __call__(self) -> gym.Env:
        from stable_baselines3.common.monitor import Monitor  # noqa: PLC0415 - stable_baselines3 (optional)

        return Monitor(gym.make(self.env_id, config=self.env_config))


def make_vec_env(cfg: TrainConfig, env_cfg: EnvConfig):
    """The training VecEnv: subprocess workers, in-process (dummy) or the native batched env."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor  # noqa: PLC0415 - stable_baselines3 (optional)

    if cfg.vec_env == "batched":
        from agents.vec_adapter import GymnasiumVecEnvAdapter  # noqa: PLC0415 - subclasses stable_baselines3's VecEnv

        vec = gym.make_vec(cfg.env.id, cfg.n_envs, vectorization_mode="vector_entry_point", config=env_cfg)
        return VecMonitor(GymnasiumVecEnvAdapter(vec))
    fns = [_MakeEnv(cfg.env.id, env_cfg) for _ in range(cfg.n_envs)]
    if cfg.vec_env == "subproc" and cfg.n_envs > 1:
        return SubprocVecEnv(fns, start_method="fork")
    return DummyVecEnv(fns)


def wrap_normalize(venv: Any, cfg: TrainConfig, gamma: float):
    """VecNormalize when the config asks for it."""
    from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415 - stable_baselines3 (optional)

    if not (cfg.normalize.obs or cfg.normalize.reward):
        return venv
    return VecNormalize(venv, norm_obs=cfg.normalize.obs, norm_reward=cfg.normalize.reward,
                        clip_obs=cfg.normalize.clip_obs, gamma=gamma)


def build_model(cfg: TrainConfig, venv: Any, seed: int, tb_dir: Path | None):
    """A fresh SB3 model from the validated hyperparameters."""
    import torch  # noqa: PLC0415 - torch (optional)
    from stable_baselines3.common.noise import NormalActionNoise  # noqa: PLC0415 - stable_baselines3 (optional)

    params = cfg.algo_params().model_dump()
    if cfg.algo == "td3":
        std = params.pop("action_noise_std")
        n = venv.action_space.shape[0]
        params["action_noise"] = NormalActionNoise(np.zeros(n), std * np.ones(n)) if std > 0 else None
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU, "elu": torch.nn.ELU,
                  "leaky_relu": torch.nn.LeakyReLU}[cfg.policy.activation]
    policy_kwargs = {"net_arch": list(cfg.policy.net_arch), "activation_fn": activation}
    return algo_class(cfg.algo)("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, policy_kwargs=policy_kwargs,
                                tensorboard_log=str(tb_dir) if tb_dir else None, **params)


# --- run directory ---------------------------------------------------------------------------------------------------
def write_run_files(run_dir: Path, cfg: TrainConfig, env_cfg: EnvConfig, seed: int) -> dict[str, Any]:
    """Resolved config, env config, scene and metadata of a new run."""
    write_yaml_atomic(run_dir / "config.yaml", cfg.model_dump(mode="json"))
    write_yaml_atomic(run_dir / "env_config.yaml", env_cfg.model_dump(mode="json"))
    write_yaml_atomic(run_dir / "scene.yaml", SceneFactory(env_cfg).base)
    meta = {"name": cfg.name, "seed": seed, "status": "running", "timesteps": 0, "train_wall_s": 0.0,
            "started": time.strftime("%Y-%m-%dT%H:%M:%S"), **git_state(), "versions": versions(),
            "cpu_count": os.cpu_count(), "argv": sys.argv[1:], "moor_env_path": str(Path(moor_env.__file__).parent)}
    write_json_atomic(run_dir / "meta.json", meta)
    return meta


def save_model_files(folder: Path, model: Any, venv: Any, replay_buffer: bool) -> None:
    """Model, normalisation statistics (JSON and VecNormalize pickle) and the replay buffer, each atomically."""
    from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415 - stable_baselines3 (optional)

    folder.mkdir(parents=True, exist_ok=True)
    write_atomic(folder / "model.zip", lambda tmp: model.save(tmp))
    if isinstance(venv, VecNormalize):
        write_atomic(folder / "vecnormalize.pkl", lambda tmp: venv.save(tmp))
        write_json_atomic(folder / "vecnormalize.json", ObsNormalizer.from_vecnormalize(venv).to_dict())
    if replay_buffer and hasattr(model, "replay_buffer") and model.replay_buffer is not None:
        write_atomic(folder / "replay_buffer.pkl", lambda tmp: model.save_replay_buffer(tmp))


# --- callbacks --------------------------------------------------------------------------------------------------------
def _callbacks(cfg: TrainConfig, run_dir: Path, venv: Any, env_cfg: EnvConfig, meta: dict[str, Any],
               t_start: float, wall_before_s: float):
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415 - stable_baselines3 (optional)

    class CheckpointCallback(BaseCallback):
        """Every ``checkpoint.freq_steps``: save model, statistics and buffer, then move the pointer."""

        def __init__(self) -> None:
            super().__init__()
            self.next_at = 0

        def _on_training_start(self) -> None:
            self.next_at = self.num_timesteps + cfg.checkpoint.freq_steps

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_at:
                self.next_at += cfg.checkpoint.freq_steps
                save_checkpoint(run_dir, self.model, venv, cfg, meta, wall_before_s + time.perf_counter() - t_start)
            return True

    class EvalCallback(BaseCallback):
        """Every ``eval.freq_steps``: deterministic episodes on fixed seeds; logs reward and success rate,
        saves ``best/`` when the mean reward improves (atomically)."""

        def __init__(self) -> None:
            super().__init__()
            self.next_at = 0
            path = run_dir / "evaluations.json"
            self.history = json.loads(path.read_text()) if path.is_file() else []
            self.best = max((h["mean_reward"] for h in self.history), default=-math.inf)
            self.scenarios = [{"id": f"train-{i}", "seed": cfg.eval.seed + i, "options": {}}
                              for i in range(cfg.eval.episodes)]

        def _on_training_start(self) -> None:
            self.next_at = self.num_timesteps + cfg.eval.freq_steps

        def _on_step(self) -> bool:
            if self.num_timesteps < self.next_at:
                return True
            self.next_at += cfg.eval.freq_steps
            policy = RunPolicy(self.model, ObsNormalizer.from_vecnormalize(venv), cfg.env.id, env_cfg, cfg.name)
            res = evaluate_policy(policy, self.scenarios, cfg.env.id, env_cfg, progress=False)["summary"]
            entry = {"timesteps": self.num_timesteps, "mean_reward": res["reward"]["mean"],
                     "success_rate": res["success_rate"], "speed_m_s": res["speed_m_s"]["mean"],
                     "tilt_deg": res["tilt_deg"]["mean"]}
            self.history.append(entry)
            for key in ("mean_reward", "success_rate", "speed_m_s", "tilt_deg"):
                self.logger.record(f"eval/{key}", entry[key])
            if entry["mean_reward"] > self.best:
                self.best = entry["mean_reward"]
                save_model_files(run_dir / "best", self.model, venv, replay_buffer=False)
            write_json_atomic(run_dir / "evaluations.json", self.history)
            return True

    class ProgressCallback(BaseCallback):
        """A tqdm bar over the run's timesteps, with the last evaluation's success rate."""

        def __init__(self, evaluator: Any) -> None:
            super().__init__()
            self.evaluator, self.bar = evaluator, None

        def _on_training_start(self) -> None:
            self.bar = tqdm(total=cfg.total_timesteps, initial=self.num_timesteps, desc=f"train {run_dir.name}",
                            unit="step", disable=not cfg.progress_bar)

        def _on_step(self) -> bool:
            self.bar.update(self.num_timesteps - self.bar.n)
            if self.evaluator.history:
                last = self.evaluator.history[-1]
                self.bar.set_postfix(eval_reward=f"{last['mean_reward']:.2f}",
                                     success=f"{last['success_rate']:.2f}", refresh=False)
            return True

        def _on_training_end(self) -> None:
            self.bar.close()

    evaluator = EvalCallback()
    return [CheckpointCallback(), evaluator, ProgressCallback(evaluator)]


def save_checkpoint(run_dir: Path, model: Any, venv: Any, cfg: TrainConfig, meta: dict[str, Any],
                    wall_s: float) -> Path:
    """Write ``checkpoints/step-<N>/``, then the pointer and the metadata; prune old checkpoints."""
    ckpt_root = run_dir / "checkpoints"
    folder = ckpt_root / f"step-{model.num_timesteps:09d}"
    save_model_files(folder, model, venv, cfg.checkpoint.replay_buffer)
    write_json_atomic(ckpt_root / "latest.json", {"folder": folder.name, "timesteps": model.num_timesteps,
                                                  "train_wall_s": wall_s})
    meta.update(timesteps=model.num_timesteps, train_wall_s=wall_s)
    write_json_atomic(run_dir / "meta.json", meta)
    old = sorted(p for p in ckpt_root.glob("step-*") if p.is_dir())[: -cfg.checkpoint.keep]
    for p in old:
        shutil.rmtree(p, ignore_errors=True)
    return folder


# --- training ---------------------------------------------------------------------------------------------------------
def train_seed(cfg: TrainConfig, seed: int, resume: bool = False) -> Path:
    """Train (or resume) one seed; returns its run directory."""
    import torch  # noqa: PLC0415 - torch (optional)
    from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415 - stable_baselines3 (optional)

    torch.set_num_threads(cfg.torch_threads)
    run_dir = Path(cfg.out_dir) / cfg.name / f"seed-{seed}"
    env_cfg = load_env_config(cfg.env.config, cfg.env.overrides)
    ckpt = latest_checkpoint(run_dir) if resume else None
    meta_path = run_dir / "meta.json"
    if ckpt is None and (run_dir / "config.yaml").exists():
        if not resume:
            raise ConfigError("name", cfg.name, f"a new run name ({run_dir} exists: pass --resume or change it)")
        if json.loads(meta_path.read_text()).get("status") == "finished":
            print(f"{run_dir}: already finished")
            return run_dir
    venv = make_vec_env(cfg, env_cfg)
    gamma = cfg.algo_params().gamma
    tb_dir = run_dir / "tb" if cfg.tensorboard else None
    wall_before = 0.0
    if ckpt is not None:
        stored = load_train_config(run_dir / "config.yaml")
        if stored.model_dump(exclude={"total_timesteps"}) != cfg.model_dump(exclude={"total_timesteps"}):
            raise ConfigError("config", cfg.name, "the config the run was started with (only total_timesteps "
                              "may change on --resume)")
        if (ckpt / "vecnormalize.pkl").is_file():
            venv = VecNormalize.load(str(ckpt / "vecnormalize.pkl"), venv)
        model = algo_class(cfg.algo).load(ckpt / "model.zip", env=venv, device="cpu",
                                          tensorboard_log=str(tb_dir) if tb_dir else None)
        if (ckpt / "replay_buffer.pkl").is_file():
            model.load_replay_buffer(ckpt / "replay_buffer.pkl")
        meta = json.loads(meta_path.read_text())
        meta.update(status="running", resumed_from=ckpt.name)
        wall_before = float(json.loads((run_dir / "checkpoints" / "latest.json").read_text())["train_wall_s"])
        write_yaml_atomic(run_dir / "config.yaml", cfg.model_dump(mode="json"))
    else:
        meta = write_run_files(run_dir, cfg, env_cfg, seed)
        venv = wrap_normalize(venv, cfg, gamma)
        model = build_model(cfg, venv, seed, tb_dir)
    t_start = time.perf_counter()
    remaining = cfg.total_timesteps - model.num_timesteps
    if remaining > 0:
        model.learn(remaining, callback=_callbacks(cfg, run_dir, venv, env_cfg, meta, t_start, wall_before),
                    reset_num_timesteps=False, tb_log_name="train")
    wall = wall_before + time.perf_counter() - t_start
    save_model_files(run_dir, model, venv, replay_buffer=False)
    save_checkpoint(run_dir, model, venv, cfg, meta, wall)
    meta.update(status="finished", finished=time.strftime("%Y-%m-%dT%H:%M:%S"))
    write_json_atomic(meta_path, meta)
    venv.close()
    return run_dir


def train(cfg: TrainConfig, resume: bool = False) -> list[Path]:
    """Train every seed of the config in turn; returns the run directories."""
    return [train_seed(cfg, seed, resume) for seed in cfg.seeds]


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line arguments of ``python -m agents.train``."""
    p = argparse.ArgumentParser(prog="python -m agents.train", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", required=True, help="configs/agents/<name>.yaml or a bundled name (quick, full ...)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config key (dotted, value read as YAML), e.g. hyperparams.learning_rate=1e-3")
    p.add_argument("--resume", action="store_true", help="continue each seed from its newest checkpoint")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Entry point."""
    args = parse_args(argv)
    try:
        cfg = load_train_config(args.config, parse_set(args.set))
        dirs = train(cfg, args.resume)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for d in dirs:
        print(f"run: {d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

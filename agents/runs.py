"""Trained run directories: the metadata written into them and the stable-baselines3 policies loaded from them.

A run directory ``runs/<name>/seed-<k>/`` (:mod:`agents.train`) holds the model (``model.zip``), the observation
normalisation (``vecnormalize.json``), ``checkpoints/`` and ``best/``; :func:`load_run` turns it into a
:class:`RunPolicy` for :func:`agents.evaluate.evaluate_policy`. stable-baselines3 and torch load only when a model
is loaded or built, so baseline-only evaluations run without them.
"""

from __future__ import annotations

import json
import math
import platform
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import moor_env
from agents.config import load_train_config
from agents.policy import Policy
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.errors import ConfigError

REPO_ROOT = Path(__file__).resolve().parent.parent


# --- run metadata -----------------------------------------------------------------------------------------------------
def git_state() -> dict[str, Any]:
    """Commit hash of the source tree and whether it had uncommitted changes (None outside a git checkout)."""
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO_ROOT, capture_output=True, text=True,
                                timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO_ROOT,
                               capture_output=True, text=True, timeout=10, check=True).stdout.strip() != ""
        return {"git_commit": commit, "git_dirty": dirty}
    except (OSError, subprocess.SubprocessError):
        return {"git_commit": None, "git_dirty": None}


def versions() -> dict[str, str]:
    """Versions of the package and the libraries a run depends on."""
    # stable_baselines3 and torch are optional (the rl extra): loaded only to record their versions
    import stable_baselines3  # noqa: PLC0415
    import torch  # noqa: PLC0415

    return {"moor_env": moor_env.__version__ if hasattr(moor_env, "__version__") else _dist_version(),
            "stable_baselines3": stable_baselines3.__version__, "torch": torch.__version__,
            "gymnasium": gym.__version__, "numpy": np.__version__, "python": platform.python_version()}


def _dist_version() -> str:
    try:
        return version("moor_env")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        return "unknown"


# --- policies of trained runs ---------------------------------------------------------------------------------------
class ObsNormalizer:
    """VecNormalize's observation transform from its saved statistics (JSON, no pickle needed to evaluate)."""

    def __init__(self, mean: np.ndarray | None, var: np.ndarray | None, clip_obs: float, epsilon: float) -> None:
        self.mean = None if mean is None else np.asarray(mean, dtype=np.float64)
        self.var = None if var is None else np.asarray(var, dtype=np.float64)
        self.clip_obs, self.epsilon = clip_obs, epsilon

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """Normalised observation (identity without statistics)."""
        if self.mean is None:
            return np.asarray(obs, dtype=np.float32)
        z = (np.asarray(obs, dtype=np.float64) - self.mean) / np.sqrt(self.var + self.epsilon)
        return np.clip(z, -self.clip_obs, self.clip_obs).astype(np.float32)

    @classmethod
    def from_vecnormalize(cls, venv: Any) -> ObsNormalizer:
        """From a live ``VecNormalize`` (or identity for any other VecEnv)."""
        from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415 - stable_baselines3 (optional)

        if not isinstance(venv, VecNormalize) or not venv.norm_obs:
            return cls(None, None, math.inf, 0.0)
        return cls(venv.obs_rms.mean.copy(), venv.obs_rms.var.copy(), venv.clip_obs, venv.epsilon)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (``vecnormalize.json``)."""
        return {"mean": None if self.mean is None else self.mean.tolist(),
                "var": None if self.var is None else self.var.tolist(),
                "clip_obs": None if math.isinf(self.clip_obs) else self.clip_obs, "epsilon": self.epsilon}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ObsNormalizer:
        """Inverse of :meth:`to_dict`."""
        return cls(d["mean"], d["var"], math.inf if d["clip_obs"] is None else d["clip_obs"], d["epsilon"])


class RunPolicy(Policy):
    """A trained SB3 model acting deterministically on normalised observations.

    Attributes: ``model`` (the SB3 algorithm), ``normalizer``, ``env_id``, ``env_config`` (:class:`EnvConfig`),
    ``name``, ``run_dir``.
    """

    def __init__(self, model: Any, normalizer: ObsNormalizer, env_id: str, env_config: EnvConfig, name: str,
                 run_dir: Path | None = None) -> None:
        self.model, self.normalizer = model, normalizer
        self.env_id, self.env_config, self.name, self.run_dir = env_id, env_config, name, run_dir

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The model's deterministic action."""
        action, _ = self.model.predict(self.normalizer(obs), deterministic=True)
        return np.asarray(action, dtype=np.float32)

    @classmethod
    def load(cls, run_dir: str | Path, checkpoint: str = "final") -> RunPolicy:
        """Load ``final`` (``model.zip``), ``best`` or ``last`` (newest checkpoint) of a run directory."""
        run_dir = Path(run_dir)
        cfg = load_train_config(run_dir / "config.yaml")
        env_cfg = load_env_config(run_dir / "env_config.yaml")
        where = {"final": run_dir, "best": run_dir / "best"}.get(checkpoint)
        if checkpoint == "last":
            where = latest_checkpoint(run_dir)
        if where is None or not (where / "model.zip").is_file():
            raise ConfigError("checkpoint", f"{run_dir}:{checkpoint}", "final, best or last of a saved run",
                              "no model.zip there (training unfinished? try --checkpoint last)")
        model = algo_class(cfg.algo).load(where / "model.zip", device="cpu")
        norm_path = where / "vecnormalize.json"
        normalizer = (ObsNormalizer.from_dict(json.loads(norm_path.read_text())) if norm_path.is_file()
                      else ObsNormalizer(None, None, math.inf, 0.0))
        return cls(model, normalizer, cfg.env.id, env_cfg, f"{cfg.name}/{run_dir.name}", run_dir)


def algo_class(algo: str):
    """The SB3 class of ``ppo``, ``sac`` or ``td3``."""
    from stable_baselines3 import PPO, SAC, TD3  # noqa: PLC0415 - stable_baselines3 (optional)

    return {"ppo": PPO, "sac": SAC, "td3": TD3}[algo]


def latest_checkpoint(run_dir: Path) -> Path | None:
    """The checkpoint folder ``checkpoints/latest.json`` names, if complete."""
    pointer = run_dir / "checkpoints" / "latest.json"
    if not pointer.is_file():
        return None
    folder = run_dir / "checkpoints" / json.loads(pointer.read_text())["folder"]
    return folder if (folder / "model.zip").is_file() else None


def load_run(run_dir: str | Path, checkpoint: str = "final"):
    """Load one trained run directory (``runs/<name>/seed-<k>``) as a :class:`RunPolicy`.

    ``checkpoint``: ``final`` (``model.zip``), ``best`` (the evaluation callback's best) or ``last`` (the newest
    checkpoint; what ``--resume`` continues from).
    """
    return RunPolicy.load(run_dir, checkpoint)


def run_dirs(path: str | Path) -> list[Path]:
    """A run directory itself, or the ``seed-*`` run directories below an experiment directory."""
    path = Path(path)
    if (path / "config.yaml").is_file():
        return [path]
    seeds = sorted(p for p in path.glob("seed-*") if (p / "config.yaml").is_file())
    if not seeds:
        raise ConfigError("run_dir", str(path), "a run directory (with config.yaml) or one holding seed-*/ runs")
    return seeds

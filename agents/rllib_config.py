"""Configuration of a Ray RLlib PPO run (``python -m agents.train_rllib``): YAML data validated by
:class:`RllibConfig`, whose errors name the dotted key, its value and what is allowed.

Sections: the env and its config, the budget and seed, the Ray connection (:class:`RaySection`), sampling
(:class:`EnvRunnerSection`), PPO (:class:`PPOSection`, RLlib's names), the policy and value MLP
(:class:`ModelSection`), checkpoints and outputs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from pydantic import Field, model_validator

from agents.config import EnvSection, _KeyedError, _Strict, load_model_config

ACTIVATIONS = ("tanh", "relu", "elu", "swish", "linear")


class RaySection(_Strict):
    """Where to run: a local Ray instance (no address) or an existing cluster."""

    address: str | None = Field(None, description="cluster to join ('auto', 'HOST:6379', 'ray://HOST:10001'); "
                                                   "None: RAY_ADDRESS if set, else a local instance")
    num_cpus: int | None = Field(None, ge=1, le=4096, description="CPUs of a local instance (None: all)")
    runtime_env: dict[str, Any] | None = Field(None, description="Ray runtime_env, e.g. {working_dir: .}")


class EnvRunnerSection(_Strict):
    """RLlib ``config.env_runners(...)``: sampling processes (actors) and envs per process."""

    num_env_runners: int = Field(2, ge=0, le=4096, description="remote sampling actors (0: sample in the driver)")
    num_envs_per_env_runner: int = Field(1, ge=1, le=256)
    num_cpus_per_env_runner: int = Field(1, ge=1, le=64)
    rollout_fragment_length: int | Literal["auto"] = "auto"
    sample_timeout_s: float = Field(600.0, gt=0.0)

    @model_validator(mode="after")
    def _fragment(self) -> EnvRunnerSection:
        if isinstance(self.rollout_fragment_length, int) and self.rollout_fragment_length < 1:
            raise _KeyedError("env_runners.rollout_fragment_length", self.rollout_fragment_length, ">= 1 or 'auto'")
        return self


class PPOSection(_Strict):
    """RLlib ``PPOConfig.training(...)`` arguments (RLlib's names and meaning)."""

    lr: float = Field(3e-4, gt=0.0, le=1.0)
    gamma: float = Field(0.99, ge=0.0, le=1.0)
    lambda_: float = Field(0.95, ge=0.0, le=1.0, description="GAE lambda")
    clip_param: float = Field(0.2, gt=0.0, le=10.0)
    vf_clip_param: float = Field(10.0, gt=0.0)
    vf_loss_coeff: float = Field(1.0, ge=0.0, le=100.0)
    entropy_coeff: float = Field(0.0, ge=0.0, le=10.0)
    use_kl_loss: bool = True
    kl_coeff: float = Field(0.2, ge=0.0, le=100.0)
    kl_target: float = Field(0.01, gt=0.0, le=10.0)
    grad_clip: float | None = Field(None, gt=0.0)
    train_batch_size_per_learner: int = Field(4000, ge=2, description="env steps per training iteration")
    minibatch_size: int = Field(128, ge=1)
    num_epochs: int = Field(10, ge=1, le=1000)


class ModelSection(_Strict):
    """RLlib ``DefaultModelConfig``: the MLP of the policy and value heads."""

    fcnet_hiddens: list[int] = Field(default_factory=lambda: [64, 64], min_length=1)
    fcnet_activation: Literal[ACTIVATIONS] = "tanh"  # type: ignore[valid-type]
    vf_share_layers: bool = False

    @model_validator(mode="after")
    def _sizes(self) -> ModelSection:
        for i, n in enumerate(self.fcnet_hiddens):
            if not 1 <= n <= 4096:
                raise _KeyedError(f"model.fcnet_hiddens[{i}]", n, "1 .. 4096")
        return self


class CheckpointSection(_Strict):
    """Checkpoints every ``every_iterations`` iterations and at the end; the newest ``keep`` are kept."""

    every_iterations: int = Field(10, ge=1)
    keep: int = Field(2, ge=1, le=1000)


class RllibConfig(_Strict):
    """A Ray RLlib PPO run: env, budget, seed, Ray connection, sampling, PPO, model, checkpoints, outputs."""

    name: str = Field(..., min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    env: EnvSection = EnvSection(id="moor_env/AnchorRelease-v0")
    total_timesteps: int = Field(..., ge=1, description="train until this many env steps are sampled")
    seed: int = Field(0, ge=0, lt=2**31)
    ray: RaySection = RaySection()
    env_runners: EnvRunnerSection = EnvRunnerSection()
    num_learners: int = Field(0, ge=0, le=1024, description="remote learner actors (0: learn in the driver)")
    torch_threads: int = Field(1, ge=1, le=256, description="torch threads of the driver's learner")
    ppo: PPOSection = PPOSection()
    model: ModelSection = ModelSection()
    checkpoint: CheckpointSection = CheckpointSection()
    progress_bar: bool = True
    out_dir: str = "runs"

    @model_validator(mode="after")
    def _batches(self) -> RllibConfig:
        if self.ppo.minibatch_size > self.ppo.train_batch_size_per_learner:
            raise _KeyedError("ppo.minibatch_size", self.ppo.minibatch_size,
                              f"<= ppo.train_batch_size_per_learner = {self.ppo.train_batch_size_per_learner}")
        return self


def load_rllib_config(config: str | Path | dict[str, Any], overrides: dict[str, Any] | None = None) -> RllibConfig:
    """Load (bundled name such as ``rllib-release`` or a path), override (``{dotted key: value}``) and validate
    (:func:`agents.config.load_model_config`).

    Raises
    ------
    ConfigError
        Naming the first invalid key, its value and what is allowed.
    """
    return load_model_config(RllibConfig, config, overrides)

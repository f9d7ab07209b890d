"""Training configs: ``configs/agents/*.yaml`` -> validated :class:`TrainConfig` (pure YAML data, never evaluated).

Every value is checked by pydantic; an invalid one raises :class:`~moor_env.errors.ConfigError` naming the
dotted key, e.g. ``hyperparams.learning_rate=-1.0: allowed > 0.0`` or ``hyperparams.n_step=64: allowed a known
key (this one does not exist)``. The algorithm's hyperparameters are checked against a schema per algorithm
(:data:`HYPERPARAMS`), so a PPO key in a SAC config is refused by name.
"""

from __future__ import annotations

import copy
import re
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from moor_env.config import CONFIG_DIR
from moor_env.envs.config import _KeyedError, _to_config_error
from moor_env.errors import ConfigError

AGENT_CONFIG_DIR = CONFIG_DIR / "agents"
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu")
_EXPONENT_FLOAT = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class PPOParams(_Strict):
    """stable-baselines3 PPO constructor arguments (same names and meaning)."""

    learning_rate: float = Field(3e-4, gt=0.0, le=1.0)
    n_steps: int = Field(256, ge=2, description="steps per env per update")
    batch_size: int = Field(64, ge=2)
    n_epochs: int = Field(10, ge=1, le=1000)
    gamma: float = Field(0.99, ge=0.0, le=1.0)
    gae_lambda: float = Field(0.95, ge=0.0, le=1.0)
    clip_range: float = Field(0.2, gt=0.0, le=10.0)
    ent_coef: float = Field(0.0, ge=0.0, le=10.0)
    vf_coef: float = Field(0.5, ge=0.0, le=10.0)
    max_grad_norm: float = Field(0.5, gt=0.0, le=1000.0)
    target_kl: float | None = Field(None, gt=0.0)
    normalize_advantage: bool = True
    use_sde: bool = False


class _OffPolicyParams(_Strict):
    learning_rate: float = Field(3e-4, gt=0.0, le=1.0)
    buffer_size: int = Field(100_000, ge=1)
    learning_starts: int = Field(100, ge=0)
    batch_size: int = Field(256, ge=1)
    tau: float = Field(0.005, gt=0.0, le=1.0)
    gamma: float = Field(0.99, ge=0.0, le=1.0)
    train_freq: int = Field(1, ge=1, description="update every this many steps (per env)")
    gradient_steps: int = Field(1, ge=-1, description="-1: as many as env steps collected")


class SACParams(_OffPolicyParams):
    """stable-baselines3 SAC constructor arguments (same names and meaning)."""

    ent_coef: float | str = Field("auto", description="a number, 'auto' or 'auto_<initial value>'")
    target_update_interval: int = Field(1, ge=1)
    target_entropy: float | Literal["auto"] = "auto"
    use_sde: bool = False

    @model_validator(mode="after")
    def _ent_coef(self) -> SACParams:
        if isinstance(self.ent_coef, str) and not (self.ent_coef == "auto" or self.ent_coef.startswith("auto_")):
            raise _KeyedError("ent_coef", self.ent_coef, "a number, 'auto' or 'auto_<float>'")
        return self


class TD3Params(_OffPolicyParams):
    """stable-baselines3 TD3 constructor arguments, plus ``action_noise_std`` (Gaussian exploration noise)."""

    policy_delay: int = Field(2, ge=1)
    target_policy_noise: float = Field(0.2, ge=0.0, le=10.0)
    target_noise_clip: float = Field(0.5, ge=0.0, le=10.0)
    action_noise_std: float = Field(0.1, ge=0.0, le=10.0, description="std of NormalActionNoise (0: none)")


HYPERPARAMS: dict[str, type[_Strict]] = {"ppo": PPOParams, "sac": SACParams, "td3": TD3Params}


class EnvSection(_Strict):
    """Which env to train on and its config (``configs/envs``)."""

    id: Literal["moor_env/AnchorPlan-v0", "moor_env/AnchorPlan-v1", "moor_env/AnchorRelease-v0"] = \
        "moor_env/AnchorPlan-v0"
    config: str = Field("anchor-release", description="bundled env config name or YAML path")
    overrides: dict[str, Any] = Field(default_factory=dict, description="{dotted key: value} into the env config")


class NormalizeSection(_Strict):
    """VecNormalize: running mean/std of observations (and optionally returns)."""

    obs: bool = True
    reward: bool = False
    clip_obs: float = Field(10.0, gt=0.0)


class PolicySection(_Strict):
    """Network of the SB3 MLP policy."""

    net_arch: list[int] = Field(default_factory=lambda: [64, 64], min_length=1)
    activation: Literal[ACTIVATIONS] = "tanh"  # type: ignore[valid-type]

    @model_validator(mode="after")
    def _sizes(self) -> PolicySection:
        for i, n in enumerate(self.net_arch):
            if not 1 <= n <= 4096:
                raise _KeyedError(f"policy.net_arch[{i}]", n, "1 .. 4096")
        return self


class EvalSection(_Strict):
    """Evaluation callback: deterministic episodes on fixed training-distribution seeds."""

    freq_steps: int = Field(1000, ge=1, description="evaluate every this many env steps (all envs together)")
    episodes: int = Field(8, ge=1, le=1000)
    seed: int = Field(1_000_000, ge=0, description="first reset seed of the evaluation episodes")


class CheckpointSection(_Strict):
    """Checkpoint callback (atomic writes; ``--resume`` continues from the newest)."""

    freq_steps: int = Field(1000, ge=1)
    keep: int = Field(3, ge=1, le=1000, description="newest checkpoints kept")
    replay_buffer: bool = Field(True, description="also save an off-policy replay buffer (for resume)")


class TrainConfig(_Strict):
    """A training run: env, algorithm, budget, seeds, vectorisation, normalisation, callbacks, outputs."""

    name: str = Field(..., min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    env: EnvSection = EnvSection()
    algo: Literal["ppo", "sac", "td3"] = "ppo"
    total_timesteps: int = Field(..., ge=1)
    seeds: list[int] = Field(default_factory=lambda: [0], min_length=1)
    n_envs: int = Field(2, ge=1, le=256)
    vec_env: Literal["subproc", "dummy", "batched"] = "subproc"
    normalize: NormalizeSection = NormalizeSection()
    policy: PolicySection = PolicySection()
    hyperparams: dict[str, Any] = Field(default_factory=dict)
    eval: EvalSection = EvalSection()
    checkpoint: CheckpointSection = CheckpointSection()
    tensorboard: bool = True
    progress_bar: bool = True
    torch_threads: int = Field(1, ge=1, le=256)
    out_dir: str = "runs"

    @model_validator(mode="after")
    def _consistent(self) -> TrainConfig:
        try:
            HYPERPARAMS[self.algo].model_validate(self.hyperparams)
        except ValidationError as exc:
            raise _KeyedError(*_error_parts(exc, "hyperparams")) from None
        if self.vec_env == "batched" and self.env.id != "moor_env/AnchorRelease-v0":
            raise _KeyedError("vec_env", self.vec_env, "subproc or dummy (only AnchorRelease-v0 has a batched env)")
        for i, s in enumerate(self.seeds):
            if not 0 <= s < 2**31:
                raise _KeyedError(f"seeds[{i}]", s, "0 .. 2**31-1")
        if len(set(self.seeds)) != len(self.seeds):
            raise _KeyedError("seeds", self.seeds, "distinct seeds")
        return self

    def algo_params(self) -> _Strict:
        """The validated hyperparameters with the algorithm's defaults filled in."""
        return HYPERPARAMS[self.algo].model_validate(self.hyperparams)


def _error_parts(exc: ValidationError, prefix: str = "") -> tuple[str, Any, str]:
    """(dotted key, value, allowed) of a pydantic error, worded as the env configs' errors."""
    err = _to_config_error(exc)
    key = err.key if not prefix else f"{prefix}.{err.key}" if err.key != "env config" else prefix
    return key, err.value, err.allowed


def parse_set(items: list[str]) -> dict[str, Any]:
    """``["a.b=1", "c=[1, 2]"]`` -> ``{"a.b": 1, "c": [1, 2]}``; values are read as YAML data (never code)."""
    out = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ConfigError("--set", item, "key=value")
        try:
            value = yaml.safe_load(raw)
        except yaml.YAMLError:
            raise ConfigError(key, raw, "a YAML value") from None
        if isinstance(value, str) and _EXPONENT_FLOAT.fullmatch(value.strip()):
            value = float(value)  # YAML 1.1 reads 1e-3 (no dot) as a string
        out[key.strip()] = value
    return out


def _set_dotted(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``a.b.c``; below ``env.overrides`` the rest of the key is one env-config key (``control.interval_s``)."""
    parts = key.split(".")
    if parts[:2] == ["env", "overrides"] and len(parts) > 2:
        env = data.setdefault("env", {})
        overrides = env.setdefault("overrides", {}) if isinstance(env, dict) else None
        if not isinstance(overrides, dict):
            raise ConfigError(key, value, "a key inside a section", "'env.overrides' is not a section")
        overrides[".".join(parts[2:])] = value
        return
    node = data
    for part in parts[:-1]:
        nxt = node.setdefault(part, {})
        if not isinstance(nxt, dict):
            raise ConfigError(key, value, "a key inside a section", f"'{part}' is not a section")
        node = nxt
    node[parts[-1]] = value


def read_config_data(config: str | Path) -> dict[str, Any]:
    """Read a config's YAML: a bundled name (``quick``) or a path."""
    path = Path(config)
    if path.suffix not in (".yaml", ".yml"):
        path = AGENT_CONFIG_DIR / f"{config}.yaml"
    if not path.is_file():
        names = ", ".join(sorted(p.stem for p in AGENT_CONFIG_DIR.glob("*.yaml")))
        raise ConfigError("config", str(config), f"one of {names} or an existing YAML path")
    with open(path, encoding="utf-8") as fh:
        data = yaml.safe_load(fh) or {}
    if not isinstance(data, dict):
        raise ConfigError("config", str(path), "a YAML mapping")
    return data


def load_model_config(model: type[BaseModel], config: str | Path | dict[str, Any],
                      overrides: dict[str, Any] | None = None) -> Any:
    """Read (bundled name or path) or copy ``config``, apply ``{dotted key: value}`` overrides, validate as
    ``model``.

    Raises
    ------
    ConfigError
        Naming the first invalid key, its value and what is allowed.
    """
    data = copy.deepcopy(config) if isinstance(config, dict) else read_config_data(config)
    for key, value in (overrides or {}).items():
        _set_dotted(data, key, value)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(*_error_parts(exc)) from None


def load_train_config(config: str | Path | dict[str, Any], overrides: dict[str, Any] | None = None) -> TrainConfig:
    """Load, override (``{dotted key: value}``) and validate a training config (:func:`load_model_config`)."""
    return load_model_config(TrainConfig, config, overrides)

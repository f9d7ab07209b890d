"""Gymnasium environments of the dart-anchor installation.

* ``moor_env/AnchorRelease-v0`` (:class:`AnchorReleaseEnv`): sequential control of vessel spacing, mooring-line
  payout and the release moment; batched vector env :class:`AnchorReleaseVectorEnv`.
* ``moor_env/AnchorPlan-v0`` (:class:`AnchorPlanEnv`): one step sets spacing, payout and release delay.
* ``moor_env/AnchorPlan-v1`` (:class:`AnchorPlanV1Env`): one step on an observed site sets the crew's five levers
  (spacing, payout, vertical chain, drop height, release phase) as absolute targets.
* ``moor_env/AnchorRelease-v1`` (:class:`AnchorReleaseV1Env`): the same levers and installation, commanded step by
  step under the actuators' rate limits, with a confirmed release.

All are registered when ``moor_env`` is imported. Settings: ``configs/envs/*.yaml`` (:func:`load_env_config`).
"""

from moor_env.envs.actuators import ACTION_NAMES
from moor_env.envs.anchor_plan import AnchorPlanEnv
from moor_env.envs.anchor_plan_v1 import AnchorPlanV1Env
from moor_env.envs.anchor_release import AnchorReleaseEnv
from moor_env.envs.anchor_release_v1 import AnchorReleaseV1Env
from moor_env.envs.config import SCENARIO_FIELDS, EnvConfig, load_env_config
from moor_env.envs.observation import OBS_NAMES, OBS_SPEC
from moor_env.envs.reward import REWARD_TERMS
from moor_env.envs.vector_env import AnchorReleaseVectorEnv

__all__ = [
    "ACTION_NAMES",
    "OBS_NAMES",
    "OBS_SPEC",
    "REWARD_TERMS",
    "SCENARIO_FIELDS",
    "AnchorPlanEnv",
    "AnchorPlanV1Env",
    "AnchorReleaseEnv",
    "AnchorReleaseV1Env",
    "AnchorReleaseVectorEnv",
    "EnvConfig",
    "load_env_config",
]

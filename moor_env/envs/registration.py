"""Gymnasium registration of the moor_env environments (called when ``moor_env`` is imported).

Each env is registered under the ``moor_env/`` namespace and, for ``gym.make("moor_env:AnchorRelease-v0")``
(import the module, then look the id up), under its plain name as well.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

ENVS = {
    "AnchorRelease-v0": {
        # returns the env inside a TimeLimit of control.max_pre_release_s / control.interval_s steps (60 by
        # default), taken from the env's own config so that Gymnasium's truncation and the env's truncation
        # penalty always fall on the same step
        "entry_point": "moor_env.envs.anchor_release:make_anchor_release",
        "vector_entry_point": "moor_env.envs.vector:make_vector_env",
    },
    "AnchorPlan-v0": {
        "entry_point": "moor_env.envs.anchor_plan:AnchorPlanEnv",
    },
    "AnchorPlan-v1": {
        "entry_point": "moor_env.envs.anchor_plan_v1:AnchorPlanV1Env",
    },
    "AnchorRelease-v1": {
        "entry_point": "moor_env.envs.anchor_release_v1:AnchorReleaseV1Env",
    },
}


def register_envs() -> None:
    """Register every env id that is not registered yet (safe to call repeatedly)."""
    for name, kwargs in ENVS.items():
        for env_id in (f"moor_env/{name}", name):
            if env_id not in registry:
                register(id=env_id, **kwargs)

"""The policy interface shared by trained agents and baselines."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class EpisodeContext:
    """What a policy may know when an episode starts.

    Learned policies and the crew rule use only ``obs`` and ``info`` (the reset observation and info); the
    optimiser baseline also uses ``env_id``, ``env_config``, ``scenario`` and ``seed`` to replay the scenario.
    """

    env_id: str
    env_config: Any
    scenario: dict[str, Any]
    seed: int
    obs: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)


class Policy:
    """Base class: a deterministic (or self-seeded) mapping from observations to actions in [-1, 1]^3."""

    name = "policy"

    def begin_episode(self, ctx: EpisodeContext) -> None:
        """Called after each ``env.reset``; stateless policies ignore it."""

    def act(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        """The action for this observation (``info`` is the last step's or the reset's info)."""
        raise NotImplementedError

"""Use a Gymnasium ``VectorEnv`` with next-step autoreset (the native batched ``AnchorReleaseVectorEnv``) as a
stable-baselines3 ``VecEnv``.

SB3 expects a finished slot to come back already reset, with the final observation in
``infos[i]["terminal_observation"]``; Gymnasium's next-step autoreset instead resets it on the following
``step``. The adapter keeps the final observation and resets the finished slots at once with
``reset(options={"reset_mask": done})`` (the slot's own generator continues, so the scenario sequence is the
one the vector env would draw).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv


class GymnasiumVecEnvAdapter(VecEnv):
    """SB3 view of a Gymnasium vector env that supports ``options["reset_mask"]``."""

    def __init__(self, vec_env: Any) -> None:
        self.vec = vec_env
        super().__init__(vec_env.num_envs, vec_env.single_observation_space, vec_env.single_action_space)
        self._actions = None
        self._seed: int | None = None

    def reset(self) -> np.ndarray:
        """Reset every slot (with the seed given to :meth:`seed`, once)."""
        obs, _ = self.vec.reset(seed=self._seed)
        self._seed = None
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Store the actions for :meth:`step_wait`."""
        self._actions = actions

    def step_wait(self):
        """Step every slot; finished ones are reset before returning (SB3 convention)."""
        obs, rewards, terminated, truncated, infos = self.vec.step(self._actions)
        dones = terminated | truncated
        info_list = [self._slot_info(infos, i) for i in range(self.num_envs)]
        for i in np.flatnonzero(dones):
            info_list[i]["terminal_observation"] = obs[i].copy()
            info_list[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        if dones.any():
            reset_obs, _ = self.vec.reset(options={"reset_mask": dones})
            obs = np.where(dones[:, None], reset_obs, obs)
        return obs, rewards.astype(np.float32), dones, info_list

    @staticmethod
    def _slot_info(infos: dict[str, Any], i: int) -> dict[str, Any]:
        """Slot ``i`` of Gymnasium's batched info dict (``_key`` masks say which slots carry ``key``)."""
        out = {}
        for key, value in infos.items():
            if key.startswith("_"):
                continue
            mask = infos.get(f"_{key}")
            if mask is None or mask[i]:
                out[key] = GymnasiumVecEnvAdapter._slot_info(value, i) if isinstance(value, dict) else value[i]
        return out

    def seed(self, seed: int | None = None):
        """Seed slot i with ``seed + i`` at the next reset."""
        self._seed = seed
        return [None if seed is None else seed + i for i in range(self.num_envs)]

    def close(self) -> None:
        """Close the vector env."""
        self.vec.close()

    def get_attr(self, attr_name: str, indices=None):
        """The vector env's attribute, once per slot."""
        return [getattr(self.vec, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        """Set an attribute on the vector env."""
        setattr(self.vec, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        """Call a method of the vector env once per slot asked for."""
        return [getattr(self.vec, method_name)(*method_args, **method_kwargs) for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None):
        """The batched env's slots are not wrapped."""
        return [False] * len(self._indices(indices))

    def _indices(self, indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)

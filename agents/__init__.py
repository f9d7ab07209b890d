"""Agents for the moor_env environments: training, baselines and evaluation.

* :mod:`agents.scenarios`: the fixed, seeded held-out scenario set (:func:`held_out_scenarios`) and scenario files.
* :mod:`agents.baselines`: random, rule-of-thumb crew and per-scenario optimiser policies (:func:`make_baseline`).
* :mod:`agents.success`: what counts as a successful installation (:func:`success_of`).
* :mod:`agents.evaluate`: run policies on scenarios (:func:`evaluate_policy`), summaries with confidence
  intervals, JSON, markdown tables and plots; ``python -m agents.evaluate RUN_DIR|baseline-name``.
* :mod:`agents.runs`: trained run directories: their metadata and the policies loaded from them (:func:`load_run`).
* :mod:`agents.train`: stable-baselines3 PPO / SAC / TD3 from a YAML config; ``python -m agents.train``.
* :mod:`agents.train_rllib`: Ray RLlib PPO, the scale-out path; ``python -m agents.train_rllib``.
* :mod:`agents.main`: the main job (train a preset, evaluate it against the baselines, print the table).

A policy is any object with ``name``, ``act(obs, info) -> action`` and ``begin_episode(ctx)``
(:class:`agents.policy.Policy`).
"""

from agents.policy import EpisodeContext, Policy

__all__ = ["EpisodeContext", "Policy"]

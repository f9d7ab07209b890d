"""One episode of a policy on one scenario: run it to its end into an episode record (:func:`run_episode`), or
run it and save three rendered frames (:func:`render_episode`).

The record holds ``touchdown_speed_m_s``, ``tilt_deg``, ``reward``, ``reward_terms``, ``success``
(:func:`agents.success.success_of`, or AnchorPlan-v1's own verdict), ``limits_exceeded``, ``sim_status``,
``chain_past_back_end_m``, ``steps``, ``release_s`` and ``wall_s`` (on AnchorRelease-v1 also ``forced_release``
and ``moves_refused``: the positioning steps whose move had no equilibrium); a reset that fails (no equilibrium)
gives a record without touchdown.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import moor_env  # noqa: F401 - registers the envs
from agents.baselines import PLAN_ENV, is_plan_v1
from agents.policy import EpisodeContext, Policy
from agents.report import save_figure
from agents.success import LIMIT_TERMS, success_of
from moor_env.envs.config import EnvConfig, load_env_config
from moor_env.errors import ConfigError, StaticsNotConverged


def run_episode(env: gym.Env, policy: Policy, scenario: dict[str, Any], env_id: str, cfg: EnvConfig) -> dict:
    """Run ``policy`` on one scenario to the episode's end; returns the episode record."""
    t0 = time.perf_counter()
    record: dict[str, Any] = {"scenario": scenario["id"], "seed": scenario["seed"],
                              "required_speed_m_s": float(cfg.reward.required_speed_m_s)}
    try:
        obs, info = env.reset(seed=scenario["seed"], options=scenario["options"])
    except (ConfigError, StaticsNotConverged) as exc:
        return {**record, **_no_touchdown(f"reset failed: {exc}"), "wall_s": time.perf_counter() - t0}
    policy.begin_episode(EpisodeContext(env_id, cfg, scenario["options"], scenario["seed"], obs, info))
    terms: dict[str, float] = {}
    total, steps, refused, done = 0.0, 0, 0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs, info))
        total += float(reward)
        steps += 1
        refused += bool(info.get("move_refused"))
        for k, v in info["reward_terms"].items():
            terms[k] = terms.get(k, 0.0) + float(v)
        done = terminated or truncated
    td = info.get("touchdown")
    record.update({
        "sim_status": info["sim_status"],
        "touchdown": bool(td),
        "touchdown_speed_m_s": float(td["speed_m_s"]) if td else math.nan,
        "tilt_deg": float(td["tilt_deg"]) if td else math.nan,
        "offset_m": float(td["offset_m"]) if td else math.nan,
        "chain_past_back_end_m": float(td["chain_past_back_end_m"]) if td else math.nan,
        "reward": total,
        "reward_terms": terms,
        "limits_exceeded": [k for k in LIMIT_TERMS if terms.get(k, 0.0) != 0.0],
        "success": success_of(td, terms, cfg),
        "steps": steps,
        "release_s": _release_time(info),
    })
    if "success" in info:  # AnchorPlan-v1 judges its own installation (moor_env.envs.plan_outcome)
        record.update(success=bool(info["success"]), limits_exceeded=list(info["limits_exceeded"]),
                      required_speed_m_s=float(info["site"]["required_speed_m_s"]), failure=info["failure"],
                      margins=dict(info["margins"]), targets=dict(info["targets"]),
                      max_tension_n=dict(info["max_tension_n"]))
    if "forced_release" in info:  # AnchorRelease-v1 positions step by step before it releases
        record.update(forced_release=bool(info["forced_release"]), moves_refused=refused)
    record["wall_s"] = time.perf_counter() - t0
    return record


def _release_time(info: dict[str, Any]) -> float:
    plan = info.get("plan")
    if plan is not None:
        return math.nan if plan["release_s"] is None else float(plan["release_s"])
    return float(info.get("t_s", math.nan))


def _no_touchdown(status: str) -> dict[str, Any]:
    return {"sim_status": status, "touchdown": False, "touchdown_speed_m_s": math.nan, "tilt_deg": math.nan,
            "offset_m": math.nan, "chain_past_back_end_m": math.nan, "reward": math.nan, "reward_terms": {},
            "limits_exceeded": [],
            "success": False, "steps": 0, "release_s": math.nan}


def render_episode(policy: Policy, scenario: dict[str, Any], path: str | Path, env_id: str = PLAN_ENV,
                   env_config: str | dict | EnvConfig = "anchor-release") -> dict[str, Any]:
    """Run one episode with ``render_mode="rgb_array"`` and save three frames (hanging, mid-fall, touchdown; on
    AnchorPlan-v1 the site instead of the hanging state)."""
    import matplotlib  # noqa: PLC0415 - matplotlib loads only to draw a figure

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415 - matplotlib, after its backend is chosen

    cfg = env_config if isinstance(env_config, EnvConfig) else load_env_config(env_config)
    env = gym.make(env_id, config=cfg, render_mode="rgb_array")
    first = []
    env.reset(seed=scenario["seed"], options=scenario["options"])
    first.append(env.render())
    env.close()
    env = gym.make(env_id, config=cfg, render_mode="rgb_array")
    record = run_episode(env, policy, scenario, env_id, cfg)
    count = env.unwrapped.fall_frame_count()
    fall = env.unwrapped.fall_frames([count // 2, count - 1]) if count else []
    # AnchorPlan-v1 simulates nothing before its action: its first frame shows the site
    titles = ["site" if is_plan_v1(env_id) else "hanging", "falling", "touchdown"]
    frames = first + (fall if fall else [env.render()])
    titles = titles[: len(frames)]
    fig, axes = plt.subplots(1, len(frames), figsize=(5.5 * len(frames), 4))
    for ax, frame, title in zip(np.atleast_1d(axes), frames, titles, strict=True):
        ax.imshow(frame)
        ax.set_title(title)
        ax.axis("off")
    fig.suptitle(f"{policy.name} on {scenario['id']}: {record['touchdown_speed_m_s']:.2f} m/s, "
                 f"tilt {record['tilt_deg']:.2f} deg")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
    env.close()
    return record

"""Write an animation of one AnchorRelease-v0 episode (GIF via Pillow) and optionally a still frame.

``python -m moor_env.envs.video --out docs/env-episode.gif --frame docs/env-frame.png`` runs a scripted
episode of the default scene (depth 500 m, spacing 0.2 h, Hs 1.5 m): the second vessel closes in and the
winch hauls in for ``--move-s`` seconds, the anchor is released at ``--release-s`` and the fall is drawn every
0.25 s. ``--policy random`` steps random actions instead; ``--set KEY=VALUE`` fixes scenario fields.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import moor_env  # noqa: F401 - registers the envs
from moor_env.config import parse_set_value

DEFAULT_SCENARIO = {"water_depth_m": 500.0, "vessel_spacing_over_depth": 0.2, "mooring_line_length_over_depth": 1.08,
                    "current_scale": 1.0, "current_direction_deg": 0.0, "sea_state_hs_m": 1.5,
                    "sea_state_tp_s": 9.0, "anchor_mass_scale": 1.0}


def record_episode(env, policy: str = "scripted", seed: int = 0, options: dict[str, Any] | None = None,
                   release_s: float = 20.0, move_s: float = 15.0) -> tuple[list[np.ndarray], dict[str, Any]]:
    """Frames (``render_mode="rgb_array_list"`` env) and the final info of one episode."""
    obs, info = env.reset(seed=seed, options=options)
    env.action_space.seed(seed)
    frames: list[np.ndarray] = list(env.render())
    interval = env.unwrapped.cfg.control.interval_s
    k = 0
    while True:
        t = k * interval
        if policy == "random":
            action = env.action_space.sample()
        else:
            release = 1.0 if t >= release_s else -1.0
            action = np.array([-0.6 if t < move_s else 0.0, -0.4 if t < move_s else 0.0, release], np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        frames += env.render()
        k += 1
        if terminated or truncated:
            return frames, info


def write_gif(frames: list[np.ndarray], path: str | Path, fps: float = 8.0) -> Path:
    """Save frames as an animated GIF (Pillow, which matplotlib depends on)."""
    from PIL import Image  # noqa: PLC0415 - Pillow (a matplotlib dependency) loads only to write a GIF

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(f).convert("P", palette=Image.Palette.ADAPTIVE, colors=128) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0, optimize=True)
    return path


def main(argv: list[str] | None = None) -> int:
    """Record one episode to a GIF."""
    parser = argparse.ArgumentParser(prog="python -m moor_env.envs.video", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/env-episode.gif", help="GIF path")
    parser.add_argument("--frame", default=None, help="also save one frame of the fall as PNG")
    parser.add_argument("--config", default="anchor-release")
    parser.add_argument("--policy", choices=("scripted", "random"), default="scripted")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--release-s", type=float, default=20.0, help="scripted release time [s]")
    parser.add_argument("--move-s", type=float, default=15.0, help="scripted vessel move and haul-in time [s]")
    parser.add_argument("--fps", type=float, default=8.0)
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE", help="fix a scenario field")
    args = parser.parse_args(argv)
    options = dict(DEFAULT_SCENARIO)
    for item in args.set:
        key, _, value = item.partition("=")
        options[key] = parse_set_value(value)
    env = gym.make("moor_env/AnchorRelease-v0", config=args.config, render_mode="rgb_array_list")
    frames, info = record_episode(env, args.policy, args.seed, options, args.release_s, args.move_s)
    path = write_gif(frames, args.out, args.fps)
    td = info.get("touchdown", {})
    print(f"{path}: {len(frames)} frames, {info['sim_status']}"
          + (f", {td['speed_m_s']:.2f} m/s, tilt {td['tilt_deg']:.2f} deg" if td else ""))
    if args.frame:
        from PIL import Image  # noqa: PLC0415 - Pillow loads only to write the still frame

        fall = [f for f in frames[-12:]]
        pick = fall[len(fall) // 2] if fall else frames[-1]
        Path(args.frame).parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(pick).save(args.frame)
        print(f"{args.frame}: one frame of the fall")
    env.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

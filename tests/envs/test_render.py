"""Rendering: rgb_array frames before and during the fall, frame lists, and the GIF helper."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from moor_env.envs.video import record_episode, write_gif

HOLD = np.array([0.0, 0.0, -1.0], np.float32)
RELEASE = np.array([0.0, 0.0, 1.0], np.float32)


def test_rgb_array_frames(tiny):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "render.width_px": 480,
                                                                           "render.height_px": 320},
                   render_mode="rgb_array")
    env.reset(seed=0, options={"current_scale": 1.0})
    frame = env.render()
    assert frame.shape == (320, 480, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 20  # not blank
    env.step(HOLD)
    moved = env.render()
    assert not np.array_equal(frame, moved)
    env.step(RELEASE)
    fall = env.unwrapped.fall_frames()
    assert len(fall) >= 3  # 0.25 s frames over a fall of more than a second
    assert all(f.shape == frame.shape for f in fall)
    assert not np.array_equal(fall[0], fall[-1])
    env.close()


def test_frame_list_and_gif(tiny, tmp_path):
    env = gym.make("moor_env/AnchorRelease-v0", config="tiny", overrides={**tiny, "render.width_px": 320,
                                                                           "render.height_px": 240},
                   render_mode="rgb_array_list")
    frames, info = record_episode(env, "scripted", seed=0, options={"sea_state_hs_m": 1.0}, release_s=0.5,
                                  move_s=0.25)
    assert info["sim_status"] == "touchdown"
    assert len(frames) >= 3 + 4  # reset, 2 control steps, fall frames, touchdown
    path = write_gif(frames, tmp_path / "episode.gif")
    assert path.stat().st_size > 1000
    from PIL import Image

    with Image.open(path) as gif:
        assert gif.n_frames == len(frames)

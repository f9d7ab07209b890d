"""Figures of a drop: line and anchor snapshots during the fall, tip speed and tilt histories."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from moor_env.errors import ConfigError
from moor_env.physics import layout as L
from moor_env.physics.anchor import tilt_deg_array

if TYPE_CHECKING:
    from moor_env.simulation import DropResult


def check_plot_path(path: str | Path) -> Path:
    """Check that a figure can be written to ``path`` before any simulation time is spent on it.

    Raises
    ------
    ConfigError
        Naming ``--plot`` and the path when it is a directory, its directory does not exist or is not writable,
        the file exists and is not writable, or its suffix is not a figure type.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: PLC0415 - matplotlib loads only with --plot

    suffixes = sorted("." + s for s in FigureCanvasAgg.get_supported_filetypes())
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise ConfigError("--plot", str(path), "a file path (e.g. drop.png)", "this is a directory")
    if path.suffix.lower() not in suffixes:
        raise ConfigError("--plot", str(path), "a file ending in one of " + ", ".join(suffixes))
    if not parent.is_dir():
        raise ConfigError("--plot", str(path), "a file in an existing directory", f"no directory {parent}")
    if not os.access(parent, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise ConfigError("--plot", str(path), "a writable file", "permission denied")
    return path


def plot_drop(result: DropResult, path: str | Path, title: str = "") -> Path:
    """Write a PNG with snapshots (x-z plane) and speed/tilt histories of a drop.

    Parameters
    ----------
    result : DropResult
        From ``simulate_drop(..., keep_snapshots=True)``.
    path : str or Path
        Output PNG file.
    title : str
        Figure title.
    """
    import matplotlib  # noqa: PLC0415 - matplotlib loads only to draw a figure

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415 - matplotlib, after its backend is chosen

    fig = plt.figure(figsize=(12, 6.5), constrained_layout=True)
    grid = fig.add_gridspec(2, 2, width_ratios=[1.25, 1])
    ax_scene = fig.add_subplot(grid[:, 0])
    ax_speed = fig.add_subplot(grid[0, 1])
    ax_tilt = fig.add_subplot(grid[1, 1])
    cmap = plt.get_cmap("viridis")
    snaps = result.snapshots
    colors = {"vertical_chain": "tab:red", "mooring_line": "tab:blue", "wire": "0.5"}
    for k, snap in enumerate(snaps):
        shade = cmap(k / max(len(snaps) - 1, 1))
        for name, pts in snap["lines"].items():
            ax_scene.plot(pts[:, 0], pts[:, 2], color=colors.get(name, shade),
                          alpha=0.25 + 0.75 * k / max(len(snaps) - 1, 1), lw=1.0, label=name if k == 0 else None)
        if snap["tip"] is not None:
            label = f"anchor t={snap['t']:.1f} s" if k in (0, len(snaps) - 1) else None
            ax_scene.plot([snap["back"][0], snap["tip"][0]], [snap["back"][2], snap["tip"][2]], color=shade, lw=4,
                          solid_capstyle="butt", label=label)
    hist = result.history
    if hist.shape[0]:
        t = hist[:, L.H_TIME] - result.release_time_s
        speed = np.linalg.norm(hist[:, L.H_TIP_VEL:L.H_TIP_VEL + 3], axis=1)
        tilt = tilt_deg_array(np.ascontiguousarray(hist[:, L.H_AXIS + 2]))
        ax_speed.plot(t, speed, label="tip speed")
        ax_speed.plot(t, -hist[:, L.H_TIP_VEL + 2], "--", label="vertical")
        ax_tilt.plot(t, tilt, color="tab:purple")
    ax_tilt.axhline(5.0, color="tab:red", ls=":", label="5 deg criterion")
    ax_tilt.axhline(2.0, color="tab:orange", ls=":", label="2 deg target")
    ax_scene.set(xlabel="x [m]", ylabel="z [m]", title="snapshots during the fall")
    ax_scene.set_aspect("equal", adjustable="datalim")
    ax_scene.legend(fontsize=7, loc="lower right")
    ax_speed.set(xlabel="time since release [s]", ylabel="speed [m/s]", title="anchor tip speed")
    ax_speed.legend(fontsize=8)
    ax_tilt.set(xlabel="time since release [s]", ylabel="tilt [deg]", title="anchor tilt from vertical")
    ax_tilt.legend(fontsize=8)
    if result.touchdown_speed_m_s is not None:
        fig.suptitle(f"{title}  touchdown {result.touchdown_speed_m_s:.2f} m/s, tilt {result.tilt_deg:.2f} deg, "
                     f"t = {result.touchdown_time_s:.2f} s")
    else:
        fig.suptitle(f"{title}  {result.status}")
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

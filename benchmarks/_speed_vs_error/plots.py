"""Plots of the speed-against-error study: the cost-error plane of each scene and the node scaling."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from _speed_vs_error.analysis import fmt, metric_front
from _speed_vs_error.cases import IMPL, SCENES, SE

INTEG_STYLE = {SE: ("tab:blue", "symplectic Euler"), "rk2": ("tab:cyan", "RK2"), IMPL: ("tab:orange", "implicit Euler")}


def plot_scene(name: str, data: dict[str, Any], path: Path) -> None:
    """Pareto plot of one scene: speed error and tilt (error or value) against wall time, both codes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ours = [r for r in data["ours"] if r.get("status") == "ok" and not r.get("is_reference")]
    md = [r for r in data["moordyn"] if r.get("status") == "ok"]
    small = data["tilt_small"]
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 5.0))
    for ax, key, floor, label in ((axes[0], "speed_err_pct", 1e-3, "|touchdown speed error| [%]"),
                                  (axes[1], "tilt_err_deg", 1e-3, "|tilt error| [deg]")):
        if key == "tilt_err_deg" and small:
            label = "tilt [deg] (reference tilt small: spread, not error)"
        for integ, (color, lab) in INTEG_STYLE.items():
            pts = [r for r in ours if r["integrator"] == integ]
            if not pts:
                continue
            ys = [r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor) for r in pts]
            ax.scatter([r["wall_s"] for r in pts], ys, s=22, color=color, label=f"ours, {lab}", zorder=3,
                       edgecolor="k", linewidth=0.3)
        presets = [r for r in ours if r["family"] == "preset"]
        for r in presets:
            y = r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor)
            ax.annotate(r["label"].replace("preset ", ""), (r["wall_s"], y), fontsize=8, xytext=(4, 4),
                        textcoords="offset points")
        if md:
            ys = [r["tilt"] if (key == "tilt_err_deg" and small) else max(abs(r[key]), floor) for r in md]
            ax.scatter([r["wall_s"] for r in md], ys, s=30, marker="s", color="tab:green", label="MoorDyn RK4",
                       zorder=3, edgecolor="k", linewidth=0.3)
        if not (key == "tilt_err_deg" and small):
            for rows, color in ((ours, "tab:red"), (md, "tab:green")):
                fr = metric_front(rows, key, floor)
                if fr:
                    xs, ys = [], []
                    for c, e in fr:  # staircase
                        if xs:
                            xs.append(c)
                            ys.append(ys[-1])
                        xs.append(c)
                        ys.append(e)
                    ax.plot(xs, ys, color=color, lw=1.2, zorder=2,
                            label="front, ours" if color == "tab:red" else "front, MoorDyn")
            ax.set_yscale("log")
            target = 1.0 if key == "speed_err_pct" else 0.3
            ax.axhline(target, color="gray", ls=":", lw=1)
            conv = abs(data["check"][key])
            if conv > floor:
                ax.axhline(conv, color="tab:purple", ls="--", lw=0.8,
                           label=f"reference vs next-coarser level ({conv:.2g})")
        ax.set_xscale("log")
        ax.set_xlabel("wall time of the dynamic run [s] (best of 3 when < 1 s)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, loc="best")
    if not small:
        axes[1].legend(fontsize=8, loc="best")
    ref = data["reference"]
    fig.suptitle(f"{name}: {SCENES[name]['about']}\nreference: explicit, chain {ref['chain_m']:g} m "
                 f"({ref['speed']:.3f} m/s, tilt {ref['tilt']:.2f} deg)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_nodes(scaling: dict[str, Any], path: Path) -> None:
    """Cost per simulated second against line nodes, log-log, with fitted slopes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    colors = {"implicit, fixed dt": "tab:orange", "explicit, fixed dt": "tab:blue",
              "explicit, dt at its stability limit": "tab:gray",
              "implicit, fixed dt, hanging (3 s before release)": "tab:brown"}
    for series, info in scaling["series"].items():
        n = np.array(info["n_nodes"], float)
        c = np.array(info["cpu_per_sim_s"], float)
        ax.loglog(n, c, "o-", color=colors.get(series, "k"),
                  label=f"{series} ({fmt(info['dt_s'], '.3g')} s): slope {info['slope']:.2f}"
                  + (f", {info['slope_upper']:.2f} on the 3 largest" if info.get("slope_upper") is not None else ""))
    ax.set_xlabel("line nodes")
    ax.set_ylabel("CPU time per simulated second [s]")
    ax.set_title("deep-1500, wire kept, release to touchdown: chain s, fibre 5 s, wire 10 s", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

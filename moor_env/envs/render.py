"""Frames of the installation for ``render_mode="rgb_array"`` (matplotlib Agg, no display needed).

:func:`snapshot` copies the geometry of a frame out of an episode slot; :class:`FrameRenderer` draws it.

Left panel: the whole water column in the x-z plane (vertical exaggeration as needed): sea surface, seabed,
both vessels (with their wave motion), the installation wire, the vertical chain, the mooring line (chain dark,
fibre rope orange), the anchor and current arrows over depth. Right panel: a true-scale zoom on the anchor with
the planned landing point.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from moor_env.physics import layout as L
from moor_env.physics.environment import current_velocity
from moor_env.physics.vessels import track_state

WATER = "#dceefb"
SEABED = "#b49a6e"
WIRE = "#6b6b6b"
CHAIN = "#202020"
FIBRE = "#e08a1e"
ANCHOR = "#b0182b"


def snapshot(core) -> dict[str, Any]:
    """Geometry for a frame of an episode slot (:class:`~moor_env.envs.core.InstallationCore`; copies): line
    polylines with materials, anchor, vessels, current."""
    sim = core.sim
    st = sim.state
    m = sim.model
    lines = {}
    for name, idx in core.lines.items():
        li = st.line_i[idx]
        if not st.seg_i[li[L.LI_SEG_START], L.SI_ACTIVE]:
            continue
        segs = np.arange(li[L.LI_SEG_START], li[L.LI_SEG_START] + li[L.LI_NSEG])
        nodes = np.concatenate([[st.seg_i[segs[0], L.SI_A]], st.seg_i[segs, L.SI_B]])
        mats = [m.material_names[k] for k in st.seg_i[segs, L.SI_MAT]]
        lines[name] = (st.node_pos[nodes].copy(), mats)
    tip, vel = sim.tip_state()
    vessels = []
    for v in range(sim.vessel_mean_m.shape[0]):
        x, y, z, *_ = track_state(sim.tracks, v, st.t, sim.env_f)
        vessels.append((x, z))
    profile = m.current_profile
    depths = np.linspace(0.0, core.depth * 0.95, 6)
    current = [(-d, *current_velocity(-d, sim.env_f, profile)[:2]) for d in depths]
    return {"t_s": core.time_s, "depth_m": core.depth, "lines": lines, "tip": tip.copy(),
            "back": sim.back_end_m(), "tip_speed_m_s": float(np.linalg.norm(vel)),
            "tilt_deg": sim.tilt_deg(), "vessels": vessels, "current": current, "released": core.released,
            "status": core.status, "chain_material": core.chain_material,
            "fibre_material": m.material_names[core.fibre_mat], "hs_m": core.hs, "target_xy": core.target_xy}


class FrameRenderer:
    """Draws snapshots (:func:`snapshot`) into RGB arrays.

    Parameters
    ----------
    width_px, height_px : int
        Frame size [pixels].
    """

    def __init__(self, width_px: int = 720, height_px: int = 480) -> None:
        # matplotlib (about 0.3 s to import) loads with the first renderer, not with the envs
        from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: PLC0415
        from matplotlib.figure import Figure  # noqa: PLC0415

        self.dpi = 100
        self.fig = Figure(figsize=(width_px / self.dpi, height_px / self.dpi), dpi=self.dpi)
        self.canvas = FigureCanvasAgg(self.fig)
        self.width_px = width_px
        self.height_px = height_px

    def draw(self, snap: dict[str, Any]) -> np.ndarray:
        """One frame, shape (height_px, width_px, 3), dtype uint8."""
        fig = self.fig
        fig.clear()
        ax = fig.add_axes((0.07, 0.09, 0.58, 0.82))
        zoom = fig.add_axes((0.72, 0.09, 0.26, 0.82))
        self._overview(ax, snap)
        self._zoom(zoom, snap)
        released = "falling" if snap["released"] and snap["status"] == "running" else snap["status"]
        if not snap["released"]:
            released = "hanging" if snap["status"] == "running" else snap["status"]
        fig.suptitle(f"t = {snap['t_s']:6.1f} s   {released}   tilt {snap['tilt_deg']:.2f} deg   "
                     f"tip speed {snap['tip_speed_m_s']:.1f} m/s   Hs {snap['hs_m']:.1f} m", fontsize=9)
        self.canvas.draw()
        frame = np.asarray(self.canvas.buffer_rgba())[:, :, :3].copy()
        return frame

    def draw_site(self, depth_m: float, lines: list[str]) -> np.ndarray:
        """A frame of a site before anything is simulated (AnchorPlan-v1 after its reset): the water column to
        scale with the seabed, and ``lines`` of text describing the site."""
        fig = self.fig
        fig.clear()
        ax = fig.add_axes((0.07, 0.09, 0.4, 0.82))
        ax.set_xlim(-0.3 * depth_m, 0.3 * depth_m)
        ax.set_ylim(-depth_m - 0.06 * depth_m, 0.08 * depth_m)
        ax.axhspan(-depth_m, 0.0, color=WATER, zorder=0)
        ax.axhspan(-depth_m - 0.1 * depth_m, -depth_m, color=SEABED, zorder=1)
        ax.axhline(0.0, color="#2a6fb0", lw=0.8, zorder=1)
        ax.set_ylabel("z [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        fig.text(0.52, 0.88, "\n".join(lines), va="top", fontsize=8, family="monospace")
        fig.suptitle("site (nothing simulated before the plan)", fontsize=9)
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[:, :, :3].copy()

    @staticmethod
    def _draw_lines(ax, snap: dict[str, Any], lw: float = 1.0) -> None:
        # one collection per material: a fine mesh has hundreds of segments, one artist each would take seconds
        from matplotlib.collections import LineCollection  # noqa: PLC0415 - matplotlib loads with the renderer

        for name, (pos, mats) in snap["lines"].items():
            x, z = pos[:, 0], pos[:, 2]
            if name == "wire":
                ax.plot(x, z, color=WIRE, lw=0.8 * lw, zorder=3)
                continue
            xz = np.column_stack([x, z])
            fibre = np.array([mat == snap["fibre_material"] for mat in mats], dtype=bool)
            for mask, color, width in ((~fibre, CHAIN, 1.6 * lw), (fibre, FIBRE, 1.0 * lw)):
                k = np.flatnonzero(mask)
                if k.size:
                    segments = np.stack([xz[k], xz[k + 1]], axis=1)
                    ax.add_collection(LineCollection(segments, colors=color, linewidths=width, capstyle="round",
                                                     zorder=4))

    def _overview(self, ax, snap: dict[str, Any]) -> None:
        from matplotlib.patches import Polygon  # noqa: PLC0415 - matplotlib loads with the first renderer

        depth = snap["depth_m"]
        xs = [v[0] for v in snap["vessels"]]
        for pos, _ in snap["lines"].values():
            xs += [pos[:, 0].min(), pos[:, 0].max()]
        x_lo, x_hi = min(xs) - 60.0, max(xs) + 40.0
        ax.set_xlim(x_lo, x_hi)
        ax.set_ylim(-depth - 0.06 * depth, 0.08 * depth)
        ax.axhspan(-depth, 0.0, color=WATER, zorder=0)
        ax.axhspan(-depth - 0.1 * depth, -depth, color=SEABED, zorder=1)
        ax.axhline(0.0, color="#2a6fb0", lw=0.8, zorder=1)
        hull_w = 0.09 * (x_hi - x_lo)
        hull_h = 0.025 * depth
        for i, (x, z) in enumerate(snap["vessels"]):
            hull = Polygon([(x - hull_w / 2, z + hull_h), (x + hull_w / 2, z + hull_h), (x + 0.35 * hull_w, z - hull_h),
                            (x - 0.35 * hull_w, z - hull_h)], closed=True, color="#3c4a5a" if i == 0 else "#5b7d4f",
                           zorder=5)
            ax.add_patch(hull)
            ax.text(x, z + 1.6 * hull_h, "installation" if i == 0 else "2nd vessel", ha="center", fontsize=7)
        self._draw_lines(ax, snap)
        tip, back = snap["tip"], snap["back"]
        ax.plot([back[0], tip[0]], [back[2], tip[2]], color=ANCHOR, lw=3.0, zorder=6, solid_capstyle="butt")
        ax.plot([snap["target_xy"][0]], [-depth], marker="v", color=ANCHOR, ms=5, zorder=6)
        # current arrows: 1 m/s is 12 % of the panel width
        scale = 0.12 * (x_hi - x_lo)
        x0 = x_lo + 0.03 * (x_hi - x_lo)
        for z, ux, _uy in snap["current"]:
            if abs(ux) > 1e-3:
                ax.annotate("", xy=(x0 + ux * scale + (0 if ux > 0 else 0.2 * scale), z),
                            xytext=(x0 + (0 if ux > 0 else 0.2 * scale), z),
                            arrowprops={"arrowstyle": "->", "color": "#2a6fb0", "lw": 1.0}, zorder=2)
        if any(abs(c[1]) > 1e-3 for c in snap["current"]):
            ax.text(x0, -0.05 * depth, "current", color="#2a6fb0", fontsize=7, va="top")
        ax.set_xlabel("x [m]", fontsize=8)
        ax.set_ylabel("z [m]", fontsize=8)
        ax.tick_params(labelsize=7)

    def _zoom(self, ax, snap: dict[str, Any]) -> None:
        from matplotlib.patches import Polygon  # noqa: PLC0415 - matplotlib loads with the first renderer

        depth = snap["depth_m"]
        tip, back = snap["tip"], snap["back"]
        cx = 0.5 * (tip[0] + back[0])
        cz = 0.5 * (tip[2] + back[2])
        half_h = 22.0
        half_w = half_h * (ax.get_position().width * self.width_px) / (ax.get_position().height * self.height_px)
        cz = max(cz, -depth + half_h - 4.0)
        ax.set_xlim(cx - half_w, cx + half_w)
        ax.set_ylim(cz - half_h, cz + half_h)
        ax.set_aspect("equal", adjustable="box")
        ax.axhspan(-depth, cz + half_h + 10, color=WATER, zorder=0)
        ax.axhspan(-depth - 50, -depth, color=SEABED, zorder=1)
        self._draw_lines(ax, snap, lw=1.8)
        axis = tip - back
        axis /= max(np.linalg.norm(axis), 1e-9)
        normal = np.array([-axis[2], 0.0, axis[0]])
        r = 0.6
        body = [back + r * normal, tip + r * normal - 1.0 * axis, tip, tip - 1.0 * axis - r * normal, back - r * normal]
        ax.add_patch(Polygon([(p[0], p[2]) for p in body], closed=True, color=ANCHOR, zorder=6))
        for side in (1, -1):  # fins on the aft 5 m
            fin = [back + side * r * normal, back + side * 1.6 * normal + 0.5 * axis,
                   back + 5.0 * axis + side * r * normal]
            ax.add_patch(Polygon([(p[0], p[2]) for p in fin], closed=True, color="#7a0f1d", zorder=6))
        ax.plot([snap["target_xy"][0]], [-depth], marker="v", color=ANCHOR, ms=6, zorder=7)
        ax.set_title(f"anchor, tip {tip[2] + depth:.1f} m above seabed", fontsize=8)
        ax.tick_params(labelsize=7)


class PlanFrames:
    """The frames of the one-step plan envs (a mixin before ``gym.Env``): the fall recorded by the step
    (``self._fall_snapshots``) drawn by a renderer made on first use (``self._renderer``, ``self.cfg.render``)."""

    _renderer: FrameRenderer | None
    _fall_snapshots: list[dict]

    def fall_frames(self, which: list[int] | None = None) -> list[np.ndarray]:
        """Frames of the last fall, one every ``render.fall_frame_interval_s`` (``which``: only those of these
        indices, negative from the end)."""
        snaps = self._fall_snapshots if which is None else [self._fall_snapshots[i] for i in which]
        return [self._draw(s) for s in snaps]

    def fall_frame_count(self) -> int:
        """Frames :meth:`fall_frames` holds."""
        return len(self._fall_snapshots)

    def _frames(self) -> FrameRenderer:
        if self._renderer is None:
            self._renderer = FrameRenderer(self.cfg.render.width_px, self.cfg.render.height_px)
        return self._renderer

    def _draw(self, snap: dict) -> np.ndarray:
        return self._frames().draw(snap)

    def close(self):
        """Drop the figure."""
        self._renderer = None

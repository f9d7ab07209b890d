"""Evaluation reports: the markdown table, the speed and tilt plot, the per-episode records and the report files.

Pure functions of evaluation results (:func:`agents.evaluate.evaluate_policy`); nothing here runs an episode.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from agents.io import write_atomic, write_json_atomic, write_text_atomic
from agents.success import SUCCESS_TILT_DEG

RECORD_KEYS = ("policy", "run", "scenario", "seed", "success", "touchdown_speed_m_s", "required_speed_m_s",
               "tilt_deg", "offset_m", "limits_exceeded", "reward", "failure", "targets")


# --- tables and plots -------------------------------------------------------------------------------------------------
def _fmt_ci(ci: tuple[float, float], digits: int) -> str:
    return f"[{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"


def markdown_table(results: list[dict[str, Any]]) -> str:
    """One row per result: success rate with its 95 % interval, speed, tilt, reward, limits, touchdowns whose chain
    fell into the anchor (:func:`summarize`), cost."""
    head = ("| policy | env | episodes (seeds) | success [95 % CI] | speed m/s mean ± sd | tilt deg mean ± sd (p90) "
            "| reward mean [95 % CI] | limits exceeded | chain inside | wall s |\n"
            "|---|---|---|---|---|---|---|---|---|---|")
    rows = [head]
    for r in results:
        s = r["summary"]
        limits = ", ".join(f"{k} {v}" for k, v in sorted(s["limits_exceeded"].items())) or "none"
        rows.append(
            f"| {r['policy']} | {r['env_id'].split('/')[-1]} | {s['episodes']} ({s.get('seeds', 1)}) "
            f"| {100 * s['success_rate']:.0f} % {_fmt_ci(tuple(100 * x for x in s['success_ci']), 0)} "
            f"| {s['speed_m_s']['mean']:.2f} ± {s['speed_m_s']['std']:.2f} "
            f"| {s['tilt_deg']['mean']:.2f} ± {s['tilt_deg']['std']:.2f} ({s['tilt_deg']['p90']:.2f}) "
            f"| {s['reward']['mean']:.3f} {_fmt_ci(s['reward']['ci'], 3)} | {limits} | {s.get('chain_inside', 0)} "
            f"| {r['wall_s']:.0f} |")
    return "\n".join(rows) + "\n"


def plot_distributions(results: list[dict[str, Any]], path: str | Path, required_speed_m_s: float = 24.0) -> Path:
    """Touchdown speed and tilt per policy (box plots over the scenarios, points on top) with the thresholds.

    Where the episodes carry their own required speed (AnchorPlan-v1: the site's soil sets it), the left panel
    shows the speed over the required speed (success at or above 0) instead of the speed."""
    import matplotlib  # noqa: PLC0415 - matplotlib loads only to draw a figure

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415 - matplotlib, after its backend is chosen

    per_site = any(e.get("margins") is not None or e.get("required_speed_m_s") is not None
                   for r in results for e in r["episodes"])
    speed_key = "speed_over_required_m_s" if per_site else "touchdown_speed_m_s"
    fig, axes = plt.subplots(1, 2, figsize=(max(11.0, 2.0 * len(results)), 4.6))
    labels = [textwrap.fill(r["policy"], 16) for r in results]
    panels = ((axes[0], speed_key, 0.0 if per_site else required_speed_m_s,
               "speed over the required speed [m/s]" if per_site else "touchdown speed [m/s]"),
              (axes[1], "tilt_deg", SUCCESS_TILT_DEG, "tilt at touchdown [deg]"))
    for ax, key, limit, unit in panels:
        data = [np.array([_value(e, key) for e in r["episodes"]], dtype=float) for r in results]
        data = [d[np.isfinite(d)] for d in data]
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(labels) + 1), labels, fontsize=8)
        for i, d in enumerate(data, start=1):
            jitter = np.random.default_rng(i).uniform(-0.12, 0.12, d.size)
            ax.plot(i + jitter, d, "o", ms=3, alpha=0.6)
        ax.axhline(limit, color="k", ls="--", lw=1)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
    axes[0].set_title("speed (dashed: the site's required speed)" if per_site
                      else f"speed (dashed: required {required_speed_m_s:g} m/s)")
    axes[1].set_title(f"tilt (dashed: success below {SUCCESS_TILT_DEG:g} deg)")
    fig.tight_layout()
    out = save_figure(fig, path)
    plt.close(fig)
    return out


def _value(episode: dict[str, Any], key: str) -> float:
    if key == "speed_over_required_m_s":
        speed, required = episode.get("touchdown_speed_m_s"), episode.get("required_speed_m_s")
        return math.nan if speed is None or required is None else speed - required
    return episode[key]


def save_figure(fig: Any, path: str | Path) -> Path:
    return write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=110, format=Path(path).suffix.lstrip(".")))


def _json_value(value: Any) -> Any:
    """A record value as strict JSON: NaN and infinities become None, numpy scalars Python numbers."""
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def episode_records(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One flat record per episode of every result, keys :data:`RECORD_KEYS` (``run``: the training run of a
    policy trained with several seeds, else the policy; missing values None)."""
    records = []
    for r in results:
        for e in r["episodes"]:
            rec = {**e, "policy": r["policy"], "run": e.get("run", r["policy"])}
            records.append({k: _json_value(rec.get(k)) for k in RECORD_KEYS})
    return records


def write_records(results: list[dict[str, Any]], path: str | Path, statistics: dict[str, Any] | None = None,
                  meta: dict[str, Any] | None = None, extra: dict[str, Any] | None = None) -> Path:
    """Write the per-episode records of every policy (:func:`episode_records`) and the statistics as JSON, with the
    top-level entries of ``extra`` beside them."""
    data = {"meta": meta or {}, "statistics": statistics or {}, "episodes": episode_records(results), **(extra or {})}
    return write_json_atomic(path, data)


def write_report(results: list[dict[str, Any]], out_dir: str | Path, scenarios: list[dict[str, Any]],
                 meta: dict[str, Any] | None = None, statistics: dict[str, Any] | None = None) -> dict[str, Path]:
    """Write ``evaluation.json`` (with ``statistics`` where given), ``evaluation.md`` and ``distributions.png``
    into ``out_dir``."""
    out = Path(out_dir)
    table = markdown_table(results)
    body = {"meta": meta or {}, "scenarios": scenarios, "results": results}
    if statistics is not None:
        body["statistics"] = statistics
    paths = {
        "json": write_json_atomic(out / "evaluation.json", body),
        "markdown": write_text_atomic(out / "evaluation.md", table),
        "plot": plot_distributions(results, out / "distributions.png"),
    }
    return paths



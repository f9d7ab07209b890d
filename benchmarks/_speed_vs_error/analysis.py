"""Errors against a scene's reference, cost-error fronts and the cost at equal error, node-scaling slopes, and
the number format of the study's tables.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def add_errors(runs: list[dict[str, Any]], ref: dict[str, Any]) -> None:
    """Errors against the reference run (in place)."""
    for r in runs:
        if r.get("status") != "ok":
            continue
        r["speed_err_pct"] = 100.0 * (r["speed"] / ref["speed"] - 1.0)
        r["tilt_err_deg"] = r["tilt"] - ref["tilt"]
        r["time_err_ms"] = 1000.0 * (r["time"] - ref["time"])
        r["drift_err_m"] = r["drift"] - ref["drift"]


def pareto(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Cost-error front: by increasing cost, each point more accurate than every cheaper one."""
    front: list[tuple[float, float]] = []
    for cost, err in sorted(points):
        if not front or err < front[-1][1]:
            front.append((cost, err))
    return front


def cost_at(front: list[tuple[float, float]], err: float) -> dict[str, float | None]:
    """Cost to reach ``err`` on a front: the cheapest measured run at or below it (``measured``) and the log-log
    interpolation between the two front points around it (``interpolated``); None if never reached."""
    reach = [c for c, e in front if e <= err]
    if not reach:
        return {"measured": None, "interpolated": None}
    measured = min(reach)
    interp = measured
    for (c1, e1), (c2, e2) in zip(front, front[1:], strict=False):
        if e2 <= err < e1:
            lo1, lo2 = math.log(max(e1, 1e-9)), math.log(max(e2, 1e-9))
            w = (math.log(max(err, 1e-9)) - lo1) / (lo2 - lo1)
            interp = math.exp(math.log(c1) + w * (math.log(c2) - math.log(c1)))
            break
    return {"measured": measured, "interpolated": interp}


def metric_front(runs: list[dict[str, Any]], key: str, floor: float) -> list[tuple[float, float]]:
    """Front of |key| against wall time (errors below ``floor`` are shown at ``floor``); the reference run
    itself (error 0 by definition) is left out."""
    return pareto([(r["wall_s"], max(abs(r[key]), floor)) for r in runs
                   if r.get("status") == "ok" and not r.get("is_reference")])


def fmt(x: Any, spec: str = ".3g", none: str = "-") -> str:
    """Format a number or a dash."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return none
    return format(x, spec)


def fit_slopes(series: dict[str, Any]) -> None:
    """Log-log slopes of CPU time per simulated second against nodes (all levels, and the 3 largest), in place.
    CPU rather than wall time: on a shared machine the wall time also counts the other jobs' share."""
    for info in series.values():
        n, c = np.log(info["n_nodes"]), np.log(info["cpu_per_sim_s"])
        info["slope"] = float(np.polyfit(n, c, 1)[0]) if len(n) >= 2 else None
        order = np.argsort(n)[-3:]
        info["slope_upper"] = float(np.polyfit(n[order], c[order], 1)[0]) if len(n) >= 3 else None
        dts = set(info["dt_s_each"])
        info["dt_s"] = dts.pop() if len(dts) == 1 else None

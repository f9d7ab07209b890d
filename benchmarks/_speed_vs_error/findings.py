"""The findings section of docs/speed_vs_error.md: the numbers pulled from the study's results, the reading of
them in words; and the short cells (settings, slack) the tables share.
"""

from __future__ import annotations

from typing import Any

from _speed_vs_error.analysis import fmt


def settings_of(r: dict[str, Any]) -> str:
    """Short settings column of one run."""
    if r["code"] == "moordyn":
        return f"chain {r['chain_m']:g} / fibre {r['fibre_m']:g} m"
    if "vertical_m" not in r:
        return "-"
    extra = []
    if r.get("keep_wire"):
        extra.append("wire kept")
    return f"{r['vertical_m']:g}/{r['loop_m']:g}/{r['fibre_m']:g}/{r['wire_m']:g}" + (
        " " + ", ".join(extra) if extra else "")


def slack_text(line_slack: list[float] | None) -> str:
    """``slack m, angle deg`` of the mooring line at touchdown, or a dash."""
    return "-" if line_slack is None else f"{line_slack[0]:.1f} m, {line_slack[1]:.1f} deg"


def run_labelled(data: dict[str, Any], label: str) -> dict[str, Any] | None:
    """The run of a scene with this label (ours or MoorDyn), if it succeeded."""
    for r in data["ours"] + data["moordyn"]:
        if r["label"] == label and r.get("status") == "ok":
            return r
    return None


def preset_findings(sc: dict[str, Any]) -> list[str]:
    """The presets against the targets for ``fast`` (3 % speed, 0.5 deg tilt where large, 10 ms CPU on
    gjoa-500)."""
    rows = []
    for name, data in sc.items():
        parts = []
        for label in ("preset fast", "preset default", "preset accurate"):
            r = run_labelled(data, label)
            if r is None:
                continue
            tilt = "" if data["tilt_small"] else f", tilt {r['tilt_err_deg']:+.2f} deg"
            cpu = f"{r['cpu_s'] * 1e3:.3g} ms" if r["cpu_s"] < 1.0 else f"{r['cpu_s']:.3g} s"
            parts.append(f"{label.replace('preset ', '')} {r['speed_err_pct']:+.2f} %{tilt} at {cpu} CPU")
        fast = run_labelled(data, "preset fast")
        branch = ""
        if fast and fast.get("line_slack") is not None:
            branch = f" (slack {slack_text(fast['line_slack'])}: fast {settings_of(fast)})"
        rows.append(f"{name}{branch}: " + ", ".join(parts))
    return ["- **Presets** (CPU of the dynamic run): " + "; ".join(rows) + ". `fast` on a slack line uses its "
            "coarse resolution (the loop chain hardly moves during the fall), where the line tightens its "
            "`tight_line` one (the loop chain carries the tilt and the snap there, see `near and far` below and "
            "the `fast, ... branch` rows of the preset table: the coarse branch is 4-5 % slow on `wide` and `snap`)."
            " On `current-waves` every preset's error is a spread, not a discretization error (below). The "
            "fit check table shows where the coarse branch fails (a coarse loop goes taut too early, 4-9 % slow) "
            "and that the rule's bounds keep `fast` on the fine one there."]


def moordyn_findings(out: dict[str, Any]) -> list[str]:
    """The two equal-error targets (1 % speed on gjoa-500, 0.3 deg tilt on wide) in words."""
    lines = []
    for row in out["equal_error"]:
        target = (row["scene"], row["metric"].split()[0], row["error"])
        if target not in (("gjoa-500", "speed", 1.0), ("wide", "tilt", 0.3)):
            continue
        what = f"{row['metric'].split()[0]} error <= {row['error']:g} on {row['scene']}"
        if row["ratio_measured"] is not None:
            lines.append(f"{what}: MoorDyn/ours {row['ratio_measured']:.1f}x (measured), "
                         f"{fmt(row['ratio_interpolated'], '.1f')}x (interpolated)")
        elif row.get("ratio_lower_bound") is not None:
            best = row["moordyn_best"]
            lines.append(f"{what}: MoorDyn's sweep never got there (its best {best['error']:.2f} at "
                         f"{best['cost']:.3g} s), so MoorDyn/ours > {row['ratio_lower_bound']:.1f}x, a lower bound "
                         f"taken at its most accurate run against our cheapest run at the target "
                         f"({row['ours']['measured']:.3g} s)")
        else:
            lines.append(f"{what}: not reached by our runs")
    if not lines:
        return []
    return ["- **Equal error against MoorDyn** (same run, same machine): " + "; ".join(lines)
            + ". On `wide` the reference itself moves by the `wide` check difference between its two finest levels "
            "(see References), which is larger than 0.3 deg: a 0.3 deg tilt error there is within the "
            "reference's own uncertainty."]


def findings(out: dict[str, Any]) -> list[str]:
    """The summary section: numbers pulled from the results, the reading of them in words."""
    sc = out["scenes"]
    L = ["## Findings", ""]
    conv = []
    for name, data in sc.items():
        chk = data["check"]
        ok = abs(chk["speed_err_pct"]) < 0.3 and abs(chk["tilt_err_deg"]) < 0.1
        conv.append(f"{name} {'converged' if ok else 'NOT converged'} ({chk['speed_err_pct']:+.2f} %, "
                    f"{chk['tilt_err_deg']:+.2f} deg between chain {chk['chain_m']:g} m and "
                    f"{data['reference']['chain_m']:g} m)")
    L.append("- **References.** " + "; ".join(conv) + ". Converged means within 0.3 % and 0.1 deg.")
    if "wide" in sc:
        lad = [r for r in sc["wide"]["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        L.append("- **The wide case's tilt does not converge with resolution**: over chain "
                 + ", ".join(f"{r['vertical_m']:g}" for r in lad) + " m it is "
                 + ", ".join(f"{r['tilt']:.2f}" for r in lad) + " deg and the speed "
                 + ", ".join(f"{r['speed']:.2f}" for r in lad) + " m/s (explicit at its stability limit; halving "
                 "the reference's step moves it by less, see below). Below about 0.5 m the slack loop folds at the "
                 "segment scale (a 142 mm chain link is about 0.85 m long, and a lumped line has no bending "
                 "stiffness), so the finest level is a reference with that uncertainty, not a converged answer; "
                 "errors on this scene below the difference of its two finest levels are not meaningful.")
    if "current-waves" in sc:
        d = sc["current-waves"]
        sp = d["speed_spread"]
        lad = [r for r in d["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        L.append(f"- **current-waves is not converged either**: its touchdown speed ranges over "
                 f"{sp['ladder'][0]:.2f} .. {sp['ladder'][1]:.2f} m/s on the reference ladder ("
                 + ", ".join(f"{r['speed']:.2f}" for r in lad) + " m/s at chain "
                 + ", ".join(f"{r['vertical_m']:g}" for r in lad) + " m) and "
                 f"{sp['ours'][0]:.2f} .. {sp['ours'][1]:.2f} m/s over all runs, tilt "
                 f"{d['tilt_spread']['ours'][0]:.2f} .. {d['tilt_spread']['ours'][1]:.2f} deg. Two things move it: the "
                 "loop chain's resolution (the ladder rises by 2-4 % per halving, and the coarse `fast` branch "
                 "sits with the 2 m level), and, with the current pushing the loop, where the slack chain ends up "
                 "on the anchor, which switches between outcomes (about 26.3 m/s and 0.2 deg, or about 25.2 m/s and "
                 "1.2-1.6 deg) with small differences in time step or integrator (the explicit time step is "
                 "converged at 1 m, see the rk2 and dt x0.5 rows; implicit 1 m reaches the reference only at a "
                 "tenth of its step). Errors on this scene are spreads, not discretization errors: no `fast` "
                 "setting measured here comes within 3 % of the 1 m reference, and the reference itself is 5 % "
                 "from its next-coarser level.")
    L += preset_findings(sc) + moordyn_findings(out)
    # components
    comp = []
    for name, data in sc.items():
        base_e = run_labelled(data, "explicit c=1 m")
        kept = run_labelled(data, "explicit 1 m, wire kept after release")
        pre = run_labelled(data, "explicit 1 m, 10 s pre-release dynamics (calm)")
        stat = run_labelled(data, "explicit 1 m, release from statics (no wave phase)")
        if base_e and kept:
            comp.append(f"{name}: keeping the wire {kept['speed_err_pct'] - base_e['speed_err_pct']:+.3f} % "
                        f"speed at {kept['cpu_s'] / base_e['cpu_s']:.2f}x the CPU time")
        if base_e and pre:
            diff = pre["speed_err_pct"] - base_e["speed_err_pct"]
            comp.append(f"{name}: 10 s of calm pre-release dynamics {diff:+.3f} % at "
                        f"{pre['cpu_s'] / base_e['cpu_s']:.1f}x")
        if base_e and stat:
            comp.append(f"{name}: releasing from statics instead of after 20 s of waves "
                        f"{stat['speed_err_pct'] - base_e['speed_err_pct']:+.2f} % and "
                        f"{stat['tilt_err_deg'] - base_e['tilt_err_deg']:+.2f} deg")
    if comp:
        L.append("- **Components** (explicit, 1 m chain; differences to the same run without the component): "
                 + "; ".join(comp) + ". The cut wire and calm pre-release dynamics change nothing measurable and "
                 "are left out by default (the wire is dropped at release; pre-release dynamics run only when "
                 "`release_time_s` > 0); with waves the pre-release dynamics decide the outcome.")
    near = []
    for name in ("wide", "snap", "gjoa-500"):
        if name not in sc:
            continue
        d = sc[name]
        parts = []
        for lab in ("implicit vertical 5 m", "implicit loop 4 m", "implicit fibre 200 m"):
            r, b = run_labelled(d, lab), run_labelled(d, "implicit 1/1/5/10, dt x1")
            if r and b:
                parts.append(f"{lab.replace('implicit ', '')} {r['speed_err_pct'] - b['speed_err_pct']:+.2f} % / "
                             f"{r['tilt_err_deg'] - b['tilt_err_deg']:+.2f} deg")
        if parts:
            near.append(f"{name}: " + ", ".join(parts))
    if near:
        L.append("- **Near and far** (implicit, one line coarsened from 1/1/5/10 m; change of speed error / tilt "
                 "error): " + "; ".join(near) + ". The loop chain next to the vertical chain carries the snap and "
                 "the tilt; the vertical chain and the fibre (far) can be coarse.")
    sc_nodes = out["node_scaling"]["series"]
    if sc_nodes:
        L.append("- **Node scaling** (deep-1500): log-log slopes of CPU time per simulated second against nodes: "
                 + "; ".join(f"{k} {v['slope']:.2f}" + (f" ({v['slope_upper']:.2f} on the 3 largest)"
                                                         if v.get("slope_upper") is not None else "")
                             for k, v in sc_nodes.items())
                 + ". At a fixed step the explicit cost is linear; the implicit cost is linear while the line hangs "
                 "(one solve per step) and grows faster during the fall because the active-set iteration "
                 "(`implicit.MAX_ACTIVE_SET_SOLVES` = 8) re-solves whenever a segment goes slack or taut within "
                 "the step, which happens more often the more segments there are (bounded: at most 8 O(N) solves "
                 "per step). The explicit cost at its own stability limit grows as N^2 (the step shrinks with "
                 "the segment).")
    stat_costs = []
    for name, data in sc.items():
        lad = [r for r in data["ours"] if r["family"] == "reference ladder" and r.get("status") == "ok"]
        if lad:
            stat_costs.append(f"{name} " + ", ".join(f"{r['wall_static_s']:.1f}" for r in lad))
    L.append("- **Statics** (not in the cost above; seconds over the ladder levels): " + "; ".join(stat_costs)
             + ". Under current the static solve costs far more than the fall. At some resolutions it stalls: "
             "on `wide`, 0.18 m chain had not finished after 60 s (0.125 m: under 1 s) and 0.0625 m chain not "
             "after 15 minutes; hence ladders of powers of two.")
    L.append("")
    return L

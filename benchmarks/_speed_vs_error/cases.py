"""The cases of the speed-against-error study: its scenes, the reference ladders, our knob settings per scene,
MoorDyn's settings, the node-scaling series and the geometries of the ``fast`` preset's fit check.
"""

from __future__ import annotations

from typing import Any

from moor_env.config import TIGHT_LINE, fidelity_presets, tight_line_keys

V, LP, F, W = ("discretization.vertical_chain_segment_m", "discretization.loop_chain_segment_m",
               "discretization.fibre_segment_m", "discretization.wire_segment_m")
IMPL = "implicit_euler"
SE = "symplectic_euler"

SCENES: dict[str, dict[str, Any]] = {
    "gjoa-500": {"scene": "gjoa-500", "overrides": {}, "moordyn": True,
                 "about": ('seed 003 (Landhaug 2015, "Dynamic Simulation of Dart Anchor Installation") ch. 8: '
                           "500 m, spacing 50 m, 50 m vertical chain, calm")},
    "deep-1500": {"scene": "deep-1500", "overrides": {}, "moordyn": True,
                  "about": "1500 m, spacing 150 m, 1540 m mooring line, calm"},
    "wide": {"scene": "gjoa-500", "overrides": {"vessel_spacing_m": 170.0, "vertical_chain_length_m": 10.0},
             "moordyn": True, "about": "gjoa-500 with spacing 170 m and a 10 m vertical chain (large tilt)"},
    "snap": {"scene": "gjoa-500", "overrides": {"vessel_spacing_m": 170.0}, "moordyn": True,
             "about": "gjoa-500 with spacing 170 m (50 m vertical chain): the loop snaps taut before touchdown"},
    "current-waves": {"scene": "gjoa-500",
                      "overrides": {"current_scale": 1.0, "sea_state_hs_m": 2.0, "release_time_s": 20.0},
                      "moordyn": False,
                      "about": "gjoa-500 with the seed 003 current (0.8/0.6/0.2 m/s), Hs 2 m Tp 10 s, release at 20 s"},
}

# chain segment ladders of the reference (explicit); the last level is the reference, the one before its check
LADDER = {"quick": {"gjoa-500": [2.0, 1.0, 0.5, 0.25], "deep-1500": [2.0, 1.0, 0.5, 0.25],
                    "wide": [2.0, 1.0, 0.5, 0.25, 0.125], "snap": [2.0, 1.0, 0.5, 0.25],
                    "current-waves": [4.0, 2.0, 1.0]},
          "full": {"gjoa-500": [4.0, 2.0, 1.0, 0.5, 0.25], "deep-1500": [4.0, 2.0, 1.0, 0.5, 0.25],
                   "wide": [4.0, 2.0, 1.0, 0.5, 0.25, 0.125], "snap": [4.0, 2.0, 1.0, 0.5, 0.25],
                   "current-waves": [4.0, 2.0, 1.0, 0.5]}}
# (levels are powers of two: the statics solver stalls at some others, e.g. 0.18 m chain on `wide`; on gjoa-500
# it fails at uniform 0.125 m after about 5 minutes)


def uniform(c: float) -> dict[str, float]:
    """Uniform refinement: chain c everywhere, fibre 5 c, wire 10 c."""
    return {V: c, LP: c, F: 5.0 * c, W: 10.0 * c}


def res(v: float, lp: float, f: float, w: float) -> dict[str, float]:
    """Element lengths: vertical chain (near), loop chain, fibre (far), wire."""
    return {V: v, LP: lp, F: f, W: w}


BASE = res(1.0, 1.0, 5.0, 10.0)


def our_cases(scene: str, mode: str) -> list[dict[str, Any]]:
    """Our runs of one scene: (family, label, overrides)."""
    full = mode == "full"
    # current-waves statics take 5-80 s per resolution (Newton under current): few resolutions in quick mode
    light = scene == "current-waves" and not full
    cases: list[dict[str, Any]] = []

    def add(family: str, label: str, ov: dict[str, Any]) -> None:
        cases.append({"family": family, "label": label, "overrides": ov})

    for c in LADDER[mode][scene]:
        add("reference ladder", f"explicit c={c:g} m", dict(uniform(c), integrator=SE))
    if full:
        c = LADDER[mode][scene][-1]
        add("reference dt check", f"explicit c={c:g} m, dt x0.5", dict(uniform(c), integrator=SE,
                                                                       **{"discretization.dt_safety": 0.45}))
    # element length per line, near (vertical chain) and far (loop, fibre), both integrators
    near = [0.5, 2.0, 5.0, 10.0] if full else [2.0, 5.0]
    loop = [0.5, 2.0, 4.0, 8.0] if full else [2.0, 4.0]
    fibre = [20.0, 50.0, 200.0] if full else [20.0, 200.0]
    wire = [30.0, 100.0]
    for integ in ([SE, IMPL] if full else [] if light else [IMPL]):
        tag = "explicit" if integ == SE else "implicit"
        for v in near:
            add("near/far resolution", f"{tag} vertical {v:g} m", dict(BASE, **{V: v}, integrator=integ))
        for lp in loop:
            add("near/far resolution", f"{tag} loop {lp:g} m", dict(BASE, **{LP: lp}, integrator=integ))
        for f in fibre:
            add("near/far resolution", f"{tag} fibre {f:g} m", dict(BASE, **{F: f}, integrator=integ))
        if full:
            for w in wire:
                add("near/far resolution", f"{tag} wire {w:g} m", dict(BASE, **{W: w}, integrator=integ))
    # combined settings for the implicit front
    combos = [(1, 1, 20, 30), (1, 2, 20, 30), (2, 2, 20, 30), (2, 4, 20, 30), (4, 4, 50, 100),
              (0.5, 1, 20, 30), (0.5, 0.5, 5, 10), (0.25, 0.25, 2.5, 10)]
    if full:
        combos += [(1, 0.5, 20, 30), (2, 1, 20, 30), (4, 8, 100, 200), (10, 4, 50, 100), (0.5, 0.25, 5, 10)]
    if light:
        combos = [(1, 2, 20, 30), (2, 2, 20, 30), (2, 4, 20, 30)]
    for v, lp, f, w in combos:
        add("combined resolution", f"implicit {v:g}/{lp:g}/{f:g}/{w:g}", dict(res(v, lp, f, w), integrator=IMPL))
    if full:
        for v, lp, f, w in [(2, 2, 20, 30), (2, 4, 20, 30), (4, 4, 50, 100), (1, 2, 20, 30)]:
            add("combined resolution", f"explicit {v:g}/{lp:g}/{f:g}/{w:g}", dict(res(v, lp, f, w), integrator=SE))
    # time step and integrator at the base resolution (and a coarse one for the implicit step)
    if 1.0 not in LADDER[mode][scene]:
        add("integrator / time step", "explicit 1 m", dict(BASE, integrator=SE))
    add("integrator / time step", "rk2 1 m", dict(BASE, integrator="rk2"))
    add("integrator / time step", "explicit 1 m, dt x0.5", dict(BASE, integrator=SE,
                                                                 **{"discretization.dt_safety": 0.45}))
    steps = [0.1, 0.3, 1.0, 2.0] if full else [0.1, 0.3, 1.0] if light else [0.3, 1.0, 2.0]
    for base_name, base in (("1/1/5/10", BASE), ("1/2/20/30", res(1, 2, 20, 30))):
        for k in steps:
            add("integrator / time step", f"implicit {base_name}, dt x{k:g}",
                dict(base, integrator=IMPL, _dt_multiple=k))
    # components
    for integ in (SE, IMPL):
        tag = "explicit" if integ == SE else "implicit"
        add("components", f"{tag} 1 m, wire kept after release",
            dict(BASE, integrator=integ, **{"installation.components.keep_wire_after_release": True}))
    if scene == "current-waves":
        add("components", "implicit 1 m, release from statics (no wave phase)", dict(BASE, integrator=IMPL,
                                                                                     release_time_s=0.0))
        add("components", "explicit 1 m, release from statics (no wave phase)", dict(BASE, integrator=SE,
                                                                                     release_time_s=0.0))
    else:
        for integ in (SE, IMPL):
            tag = "explicit" if integ == SE else "implicit"
            add("components", f"{tag} 1 m, 10 s pre-release dynamics (calm)",
                dict(BASE, integrator=integ, release_time_s=10.0))
    for name in fidelity_presets():
        if scene == "current-waves" and name == "accurate":
            continue  # its statics alone take many minutes under current (77 s at 0.5 m chain)
        add("preset", f"preset {name}", {"fidelity": name})
    for branch, keys in preset_branches("fast").items():
        add("preset branches", f"fast, {branch} branch", dict(keys, fidelity="custom"))
    return cases


# geometries around the fit's bounds: gjoa-500 at other spacings and line lengths, deep-1500 at wider spacings
FIT_CHECK = ([("gjoa-500", {"vessel_spacing_m": s}) for s in (70.0, 85.0, 100.0, 120.0, 140.0)]
             + [("gjoa-500", {"mooring_line_length_m": ln}) for ln in (505.0, 515.0, 530.0)]
             + [("deep-1500", {"vessel_spacing_m": s}) for s in (200.0, 250.0)])
FIT_REFERENCE_C = 0.5  # explicit chain of the fit check's references (0.25 m checked on one geometry)


def preset_branches(name: str) -> dict[str, dict[str, Any]]:
    """Both resolutions of a preset with a ``tight_line`` entry, as explicit overrides: the slack-line one
    (the preset's own keys) and the tight-line one (its ``tight_line`` keys over them)."""
    preset = dict(fidelity_presets()[name])
    tight = preset.pop(TIGHT_LINE, None)
    if tight is None:
        return {}
    slack = {f"discretization.{k}": v for k, v in preset.items()}
    tight = {f"discretization.{k}": v for k, v in tight_line_keys(tight).items()}  # calm-water keys
    return {"slack-line": slack, "tight-line": {**slack, **tight}}


def moordyn_cases(mode: str, scene: str) -> list[dict[str, Any]]:
    """MoorDyn settings: chain segment c (fibre 5 c, exactly our segments and statics of that level), dt as a
    fraction of its RK4 stability limit. On ``wide`` the quick sweep goes on to 0.5 and 0.25 m chain, towards
    the 0.3 deg tilt error target."""
    if mode == "full":
        grid = [(c, fr) for c in (0.5, 1.0, 2.0, 4.0) for fr in (0.9, 0.7, 0.5, 0.35)] + [(0.25, 0.9), (0.25, 0.5)]
    else:
        grid = [(c, fr) for c in (1.0, 2.0, 4.0) for fr in (0.9, 0.5)]
        if scene == "wide":
            grid += [(0.5, 0.9), (0.25, 0.9)]
    return [{"family": "moordyn", "label": f"MoorDyn c={c:g} m, dt {fr:g} x limit", "chain_m": c, "fraction": fr}
            for c, fr in grid]


def node_scaling_cases(mode: str) -> list[dict[str, Any]]:
    """deep-1500 with the wire kept, release to touchdown, chain s / fibre 5 s / wire 10 s, fixed steps. (The
    whole fall, not a fixed time: ``run_drop`` loops for ever when ``max_fall_time_s`` ends between two steps.)"""
    levels = [4.0, 2.0, 1.0, 0.5, 0.25] if mode == "full" else [4.0, 2.0, 1.0, 0.5]
    finest = levels[-1]
    cases = []
    for s in levels:
        common = dict(uniform(s), **{"installation.components.keep_wire_after_release": True})
        cases.append({"series": "implicit, fixed dt", "s": s,
                      "overrides": dict(common, integrator=IMPL, _fixed_dt_from=finest)})
        cases.append({"series": "explicit, fixed dt", "s": s,
                      "overrides": dict(common, integrator=SE, _fixed_dt_from=finest)})
        cases.append({"series": "explicit, dt at its stability limit", "s": s,
                      "overrides": dict(common, integrator=SE)})
        cases.append({"series": "implicit, fixed dt, hanging (3 s before release)", "s": s,
                      "overrides": dict(common, integrator=IMPL, _fixed_dt_from=finest, _hanging=True)})
    return cases

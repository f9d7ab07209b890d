"""Command line: ``moor-env drop SCENE`` and ``moor-env static SCENE``.

Exit codes: 0 success, 2 invalid input (one line on stderr naming the key, its value and the allowed range),
3 numerical failure (blow-up or statics not converged, with time and component), 130 interrupted.
Human output is rounded to the digits that mean something (:func:`format_value`); ``--json`` keeps full precision.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from moor_env.config import SET_SHORTCUTS, bundled_scene_names, load_scene, parse_set_value, set_key_help
from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged
from moor_env.plotting import check_plot_path, plot_drop
from moor_env.simulation import simulate_drop, solve_statics


class _OneLineParser(argparse.ArgumentParser):
    """Usage errors on one line (``moor-env drop: error: ...; see moor-env drop --help``), exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _epilog() -> str:
    scenes = "\n".join(f"  {name}" for name in bundled_scene_names())
    keys = "\n".join(f"  {line}" for line in set_key_help())
    return (f"bundled scenes (configs/scenes/*.yaml):\n{scenes}\n\n"
            f"--set shortcuts (KEY [unit] allowed range  dotted path it sets):\n{keys}\n"
            "  any dotted path into the scene works too, e.g. environment.seabed.friction_coefficient=0.3")


def _build_parser() -> argparse.ArgumentParser:
    epilog = _epilog()
    fmt = argparse.RawDescriptionHelpFormatter
    parser = _OneLineParser(prog="moor-env", description="Dart anchor installation simulator.", epilog=epilog,
                            formatter_class=fmt)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_OneLineParser)
    for name, text in (("drop", "statics, release and fall to touchdown"), ("static", "equilibrium before release")):
        p = sub.add_parser(name, help=text, description=text, epilog=epilog, formatter_class=fmt)
        p.add_argument("scene", help="bundled scene name (e.g. gjoa-500, listed below) or a YAML path")
        p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene value: a shortcut listed below or a dotted path (repeatable)")
        p.add_argument("--json", action="store_true", help="print one JSON object, full precision")
        if name == "drop":
            p.add_argument("--plot", metavar="FILE.png", help="draw snapshots and speed/tilt histories")
            p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    return parser


def _parse_sets(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            example = key.strip() if key.strip() in SET_SHORTCUTS else "drop_height_m"
            raise ConfigError("--set", item, f"KEY=VALUE, e.g. --set {example}=50 (keys: see moor-env drop --help)")
        out[key.strip()] = parse_set_value(value)
    return out


# --- human output: rounded to meaningful digits ----------------------------------------------------------------
def _tension(value_n: float) -> str:
    return f"{value_n / 1e6:.3g} MN" if abs(value_n) >= 1e6 else f"{value_n / 1e3:.1f} kN"


def format_value(key: str, value: Any) -> str:
    """A result value for people: speeds 0.01 m/s, angles 0.01 deg, positions and lengths 0.001 m, tensions
    0.1 kN (3 significant digits in MN from 1 MN), times 0.001 s (a time step 3 significant digits), other floats
    4 significant digits; lists and dicts element by element; None as ``-``."""
    if value is None:
        return "-"
    if isinstance(value, dict):
        return ", ".join(f"{k} {format_value(key, v)}" for k, v in value.items()) or "-"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(format_value(key, v) for v in value) + "]"
    if isinstance(value, bool) or not isinstance(value, float):
        return str(value)
    if not math.isfinite(value):
        return str(value)
    if key.endswith("_n"):
        text = _tension(value)
    elif key.endswith(("_m_s", "_deg")):
        text = f"{value:.2f}"
    elif key.endswith("_m"):
        text = f"{value:.3f}"
    elif key == "dt_s":
        text = f"{value:.3g}"
    elif key.endswith("_s"):
        text = f"{value:.3f}"
    else:
        text = f"{value:.4g}"
    return text[1:] if text.startswith("-") and float(text.split()[0]) == 0.0 else text


def format_human(data: dict[str, Any]) -> list[str]:
    """One ``key  value`` line per result; a tension key loses its ``_n`` (its values carry kN or MN)."""
    return [f"{key.removesuffix('_n'):32s} {format_value(key, value)}" for key, value in data.items()]


def _run(args: argparse.Namespace) -> dict[str, Any]:
    if getattr(args, "plot", None):
        check_plot_path(args.plot)
    scene = load_scene(args.scene, _parse_sets(args.sets))
    if args.command == "static":
        return solve_statics(scene).to_dict()
    result = simulate_drop(scene, keep_snapshots=bool(args.plot), progress=not args.no_progress)
    if args.plot:
        plot_drop(result, args.plot, title=scene.name)
    return result.to_dict()


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``moor-env``; returns the exit code."""
    try:
        args = _build_parser().parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed on one line
        return exc.code if isinstance(exc.code, int) else 2
    try:
        data = _run(args)
    except ConfigError as exc:
        print(f"moor-env: error: {exc}", file=sys.stderr)
        return 2
    except (SimulationDiverged, StaticsNotConverged) as exc:
        print(f"moor-env: numerical failure: {exc}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("moor-env: interrupted", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(data))
    else:
        print("\n".join(format_human(data)))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

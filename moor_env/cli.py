"""Command line: ``moor-env drop SCENE`` and ``moor-env static SCENE``.

Exit codes: 0 success, 2 invalid input (one line on stderr naming the key, its value and the allowed range),
3 numerical failure (blow-up or statics not converged, with time and component).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from moor_env.config import SET_SHORTCUTS, load_scene, parse_set_value
from moor_env.errors import ConfigError, SimulationDiverged, StaticsNotConverged


def _parse_sets(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise ConfigError("--set", item, "KEY=VALUE with KEY one of " + ", ".join(SET_SHORTCUTS))
        key, value = item.split("=", 1)
        out[key.strip()] = parse_set_value(value)
    return out


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="moor-env", description="Dart anchor installation simulator.")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("drop", "statics, release and fall to touchdown"), ("static", "equilibrium before release")):
        p = sub.add_parser(name, help=text)
        p.add_argument("scene", help="bundled scene name (e.g. gjoa-500) or a YAML path")
        p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene value; keys: " + ", ".join(SET_SHORTCUTS) + " or a dotted path")
        p.add_argument("--json", action="store_true", help="print one JSON object")
        if name == "drop":
            p.add_argument("--plot", metavar="FILE.png", help="draw snapshots and speed/tilt histories")
            p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``moor-env``."""
    args = _build_parser().parse_args(argv)
    try:
        scene = load_scene(args.scene, _parse_sets(args.sets))
        if args.command == "static":
            from moor_env.simulation import solve_statics

            data = solve_statics(scene).to_dict()
        else:
            from moor_env.simulation import simulate_drop

            result = simulate_drop(scene, keep_snapshots=bool(args.plot), progress=not args.no_progress)
            data = result.to_dict()
            if args.plot:
                from moor_env.plotting import plot_drop

                plot_drop(result, args.plot, title=scene.name)
    except ConfigError as exc:
        print(f"moor-env: error: {exc}", file=sys.stderr)
        return 2
    except (SimulationDiverged, StaticsNotConverged) as exc:
        print(f"moor-env: numerical failure: {exc}", file=sys.stderr)
        return 3
    if args.json:
        print(json.dumps(data))
    else:
        for key, value in data.items():
            print(f"{key:32s} {value}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

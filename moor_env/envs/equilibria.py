"""Cache of hanging equilibria (the start state of every episode).

The static solve (:func:`moor_env.solve_statics`) takes 0.1-5 s on the env's fidelity (more with current), far
longer than a control step, so equilibria are cached in memory and on disk, keyed on everything in the scene
that can change the static solution:

* the scene with its **sea state** reset to calm and seed 0, the pre-release **rates and release time** set
  to 0 (none of them enters the static problem: waves are ramped in from zero amplitude after the solve),
* and the chain's **tangential drag coefficient** set to the bundled scene's value. Under current it acts on the
  small axial component of the current along the loop; measured on gjoa-500 with the seed 003 current, Cd_t
  0.0069 and 0.0100 put the release node at the same position to 0.1 mm. Randomising it per episode therefore
  does not need a new solve (a documented approximation: the start state is the equilibrium for the
  nominal Cd_t).

The key also holds a hash of the physics sources (``moor_env/physics/*.py``, ``compile.py``,
``simulation.py``, ``config.py``) and of ``configs/fidelity.yaml`` (the scene names a preset, whose resolution
decides the topology), so an edited solver or preset never returns stale states. The state stored is the
solver's output bit for bit, so a cached and a fresh start give identical episodes.

``python -m moor_env.envs.precompute --config anchor-release --jobs 2`` solves every combination of a config's
discrete scenario fields (:func:`discrete_grid`) ahead of training.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import json
import os
import tempfile
import time
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from moor_env.config import FIDELITY_PATH, scene_from_dict
from moor_env.envs.config import SCENARIO_RANGES, EnvConfig, StaticsCacheConfig, _values
from moor_env.errors import StaticsNotConverged
from moor_env.simulation import SimState, solve_statics

# Scenario fields that do not change the static solution (see the module docstring).
DYNAMIC_ONLY_FIELDS = ("sea_state_hs_m", "sea_state_tp_s", "sea_state_seed", "chain_cd_tangential")

_ARRAYS = ("node_pos", "node_vel", "body_state", "node_i", "node_f", "seg_i", "seg_f", "line_i", "line_f")
_PACKAGE = Path(__file__).resolve().parent.parent


def physics_source_hash() -> str:
    """Hash of every source file that can change a static solution."""
    digest = hashlib.sha256()
    files = sorted((_PACKAGE / "physics").glob("*.py")) + [_PACKAGE / n for n in ("compile.py", "simulation.py",
                                                                                  "config.py")]
    files.append(FIDELITY_PATH)  # a scene names its preset; the resolution it stands for is in this file
    for path in files:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def plain_copy(data: Any) -> Any:
    """Deep copy of a scene mapping (dicts, lists and scalars, as read from YAML): 3x faster than a JSON round
    trip (23 against 70 us for the default scene), which every reset did twice."""
    if isinstance(data, dict):
        return {key: plain_copy(value) for key, value in data.items()}
    if isinstance(data, list):
        return [plain_copy(value) for value in data]
    return data


def statics_scene_dict(scene_data: dict[str, Any], chain_material: str, nominal_chain_cd_t: float) -> dict[str, Any]:
    """The scene mapping the equilibrium is solved for: sea state calm, no pre-release rates, nominal Cd_t, no
    fall integrator.

    Only the branches it changes are copied (``environment`` with its ``current``, ``installation``, the materials
    and ``discretization``); the rest is shared with ``scene_data``, which every reset made afresh (a deep copy
    cost about as much as the rest of the reset's scene bookkeeping).
    """
    data = dict(scene_data)
    environment = scene_data["environment"]
    data["environment"] = {**environment, "sea_state": {}}
    if "current" in environment:
        data["environment"]["current"] = dict(environment["current"])
    data["installation"] = {**scene_data["installation"], "release_time_s": 0.0, "spacing_rate_m_s": 0.0,
                            "payout_rate_m_s": 0.0}
    materials = dict(scene_data["materials"])
    materials[chain_material] = {**materials[chain_material], "cd_tangential": nominal_chain_cd_t}
    data["materials"] = materials
    if "discretization" in data:  # the fall's integrator: no part of the hanging state
        data["discretization"] = {k: v for k, v in data["discretization"].items() if k != "fall_integrator"}
    return data


def scene_text(data: dict[str, Any]) -> str:
    """The canonical JSON text of a scene mapping that its cache keys hash (made once per reset and passed on: it
    costs about 50 us for the default scene, and a reset needs three keys of it)."""
    return json.dumps(data, sort_keys=True, default=str)


def scene_key(data: dict[str, Any], source_hash: str, text: str | None = None) -> str:
    """Cache key of a statics scene mapping (``text``: its :func:`scene_text`, where already made)."""
    if text is None:
        text = scene_text(data)
    return hashlib.sha256((source_hash + text).encode()).hexdigest()[:32]


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/moor_env/equilibria`` (``~/.cache`` when unset)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "moor_env" / "equilibria"


_SHARED_MEMORY: OrderedDict[str, SimState] = OrderedDict()  # one LRU per process, shared by every env
# Statics that did not converge, by key: a failed solve costs as much as tens of successful ones, and a training
# run draws the same geometry again and again; the solver's message is kept to raise again at once.
_SHARED_FAILURES: dict[str, str] = {}


class EquilibriumCache:
    """Hanging equilibria by statics-scene key: an LRU in memory (shared by all envs of a process), optionally
    ``.npz`` files on disk.

    Parameters
    ----------
    config : StaticsCacheConfig
    """

    def __init__(self, config: StaticsCacheConfig) -> None:
        self.config = config
        self.source_hash = physics_source_hash()
        self.memory = _SHARED_MEMORY
        self.dir: Path | None = None
        if config.disk:
            self.dir = (Path(config.dir) if config.dir else default_cache_dir()) / self.source_hash
        self.hits = 0
        self.disk_hits = 0
        self.solves = 0
        self.solve_wall_s = 0.0

    def state(self, statics_data: dict[str, Any], text: str | None = None) -> tuple[SimState, str]:
        """Equilibrium state (a private copy) of a statics scene mapping (``text``: its :func:`scene_text`, where
        already made), and where it came from.

        Raises
        ------
        ConfigError, StaticsNotConverged
            From the scene validation or the solver.
        """
        key = scene_key(statics_data, self.source_hash, text)
        if self.config.memory_entries > 0 and key in self.memory:
            self.memory.move_to_end(key)
            self.hits += 1
            return self.memory[key].copy(), "memory"
        failure = _SHARED_FAILURES.get(key) or self._load_failure(key)
        if failure is not None:
            _SHARED_FAILURES[key] = failure
            raise StaticsNotConverged(f"{failure} (cached failure of this geometry)")
        state = self._load(key)
        origin = "disk"
        if state is None:
            t0 = time.perf_counter()
            scene = scene_from_dict(json.loads(json.dumps(statics_data)))
            try:
                state = solve_statics(scene).simulator.state.copy()
            except StaticsNotConverged as exc:
                self.solve_wall_s += time.perf_counter() - t0
                _SHARED_FAILURES[key] = str(exc)
                self._write_atomic(self._failure_path(key), str(exc).encode())
                raise
            self.solve_wall_s += time.perf_counter() - t0
            self.solves += 1
            origin = "solved"
            self._save(key, state)
        else:
            self.disk_hits += 1
        if self.config.memory_entries > 0:
            self.memory[key] = state
            while len(self.memory) > self.config.memory_entries:
                self.memory.popitem(last=False)
        return state.copy(), origin

    def _path(self, key: str) -> Path | None:
        return None if self.dir is None else self.dir / f"{key}.npz"

    def _load(self, key: str) -> SimState | None:
        path = self._path(key)
        if path is None or not path.is_file():
            return None
        try:
            with np.load(path) as data:
                arrays = {name: data[name].copy() for name in _ARRAYS}
                return SimState(**arrays, t=float(data["t"]), released=bool(data["released"]))
        except (OSError, KeyError, ValueError):
            return None  # a damaged or foreign file: solve again (and overwrite it)

    def _failure_path(self, key: str) -> Path | None:
        return None if self.dir is None else self.dir / f"{key}.failed"

    def _load_failure(self, key: str) -> str | None:
        path = self._failure_path(key)
        try:
            return path.read_text() if path is not None and path.is_file() else None
        except OSError:
            return None

    def _save(self, key: str, state: SimState) -> None:
        buffer = io.BytesIO()
        np.savez(buffer, **{name: getattr(state, name) for name in _ARRAYS}, t=state.t, released=state.released)
        self._write_atomic(self._path(key), buffer.getvalue())

    @staticmethod
    def _write_atomic(path: Path | None, payload: bytes) -> None:
        if path is None:
            return
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
            with os.fdopen(fd, "wb") as fh:
                fh.write(payload)
            os.replace(tmp, path)  # atomic: concurrent workers never read a half-written file
        except OSError:
            pass  # a read-only home: the memory cache still works

    def stats(self) -> dict[str, float]:
        """Counters: memory hits, disk hits, solves and their wall time [s]."""
        return {"memory_hits": self.hits, "disk_hits": self.disk_hits, "solves": self.solves,
                "solve_wall_s": self.solve_wall_s}


# --- precomputation ------------------------------------------------------------------------------------------
def discrete_grid(cfg: EnvConfig) -> list[dict[str, float]]:
    """Every combination of the statics-relevant scenario fields of a config.

    Raises
    ------
    ValueError
        If a statics-relevant field is continuous (uniform): it has no finite grid.
    """
    names = [n for n in SCENARIO_RANGES if n not in DYNAMIC_ONLY_FIELDS]
    values = []
    for name in names:
        if not cfg.scenario.is_discrete(name):
            raise ValueError(f"scenario.{name} is continuous: every reset solves its own equilibrium")
        values.append(_values(getattr(cfg.scenario, name)))
    grid = [dict(zip(names, combo, strict=True)) for combo in itertools.product(*values)]
    # the current direction does not matter without current: keep one direction there
    seen, unique = set(), []
    for row in grid:
        if row["current_scale"] == 0.0:
            row = {**row, "current_direction_deg": 0.0}
        k = tuple(sorted(row.items()))
        if k not in seen:
            seen.add(k)
            unique.append(row)
    return unique

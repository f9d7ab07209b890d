"""Hanging equilibria: the start state of every episode, solved at every reset.

Every reset solves the equilibrium of its scenario's statics scene with :func:`moor_env.solve_statics`, from
the scene's compiled model (:meth:`~moor_env.envs.scene.SceneFactory.compiled`, which the episode's model is
derived from). On the default config in calm water, without current, a reset on a new geometry costs a few
milliseconds, the solve and the compile about half each (``benchmarks/bench_env.py --variant fresh-geometry``
measures the reset, the solve and the whole episode: docs/env-speed.md). A geometry without an equilibrium is
refused at once (:class:`~moor_env.errors.NoEquilibrium`) and the reset draws again
(:func:`~moor_env.envs.scenario.start_episode`), as it does for a geometry Newton's method leaves unsolved
(``statics.method: newton``, the default). Why not the relaxation fallback (``auto``): on the 1000 scenes of
``benchmarks/statics_env_resolution.py`` at the envs' resolution, it changed no outcome but one, a scene refused
for its fibre on the seabed after about 9 s of relaxation, where Newton's method leaves it unsolved in 0.3 s; a
reset that stalls for seconds without a word is worse than a draw.

Kept: an in-memory LRU of the last ``statics.memory_entries`` (64) equilibria, shared by the envs of a process,
with their compiled models in the scene factory. A geometry drawn again (an evaluation set, a fixed
``reset(options=...)``) then resets in a median 0.7 ms of CPU instead of 9.5 ms; a new geometry costs the same
with and without it (9.8 against 10.0 ms; 20 resets each, 3 rounds, in a busier minute than the run above), and
64 geometries hold about 10 MB.
Nothing is kept on disk: continuous draws never repeat a geometry, and a repeat in another process costs one
10 ms reset.

The statics scene is the episode's scene with its **sea state** reset to calm and seed 0, the pre-release
**rates and release time** set to 0 (none of them enters the static problem: waves are ramped in from zero
amplitude after the solve), and the chain's **tangential drag coefficient** set to the bundled scene's value.
Under current Cd_t acts on the small axial component of the current along the loop; measured on gjoa-500 with the
current of seed 003 (Landhaug 2015, *Dynamic Simulation of Dart Anchor Installation*, chapter 8), Cd_t 0.0069 and
0.0100 put the release node at the same position to 0.1 mm, so the equilibrium is solved for the nominal Cd_t (a
documented approximation) and episodes that differ only in the sea state or Cd_t share one solve and one compile.
The solver is deterministic, so a kept and a fresh start give identical episodes.
"""

from __future__ import annotations

import hashlib
import json
from collections import OrderedDict
from typing import Any

from moor_env.compile import Model
from moor_env.envs.config import StaticsConfig
from moor_env.simulation import SimState, solve_statics


def plain_copy(data: Any) -> Any:
    """Deep copy of a scene mapping (dicts, lists and scalars, as read from YAML): 3x faster than a JSON round
    trip (23 against 70 us for the default scene), which every reset did twice."""
    if isinstance(data, dict):
        return {key: plain_copy(value) for key, value in data.items()}
    if isinstance(data, list):
        return [plain_copy(value) for value in data]
    return data


FALL_KEYS = ("fall_integrator", "fall_step_growth_max")  # discretization keys that only the fall reads


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
    if "discretization" in data:  # the fall's own keys: no part of the hanging state
        data["discretization"] = {k: v for k, v in data["discretization"].items() if k not in FALL_KEYS}
    return data


def scene_text(data: dict[str, Any]) -> str:
    """The canonical JSON text of a scene mapping that its cache keys hash (made once per reset and passed on: it
    costs about 50 us for the default scene, and a reset needs three keys of it)."""
    return json.dumps(data, sort_keys=True, default=str)


def scene_key(data: dict[str, Any], text: str | None = None) -> str:
    """Key of a statics scene mapping (``text``: its :func:`scene_text`, where already made): the compiled
    models and the equilibria are kept under it."""
    if text is None:
        text = scene_text(data)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


_SHARED_MEMORY: OrderedDict[str, SimState] = OrderedDict()  # one LRU per process, shared by every env


class Equilibria:
    """Hanging equilibria by statics-scene key: solved with :func:`~moor_env.solve_statics` from the compiled
    statics model, the last ``config.memory_entries`` of them kept in an LRU shared by all envs of a process.

    Parameters
    ----------
    config : StaticsConfig
    """

    def __init__(self, config: StaticsConfig) -> None:
        self.config = config
        self.memory = _SHARED_MEMORY
        self.hits = 0
        self.solves = 0
        self.solve_wall_s = 0.0

    def state(self, key: str, model: Model) -> tuple[SimState, str]:
        """Equilibrium state of the compiled statics model ``model`` (kept under ``key``, its
        :func:`scene_key`), the caller's own to change, and where it came from (``"memory"`` or ``"solved"``).

        Raises
        ------
        NoEquilibrium, ConfigError, StaticsNotConverged
            From the solver.
        """
        keep = self.config.memory_entries > 0
        if keep and key in self.memory:
            self.memory.move_to_end(key)
            self.hits += 1
            return self.memory[key].copy(), "memory"
        result = solve_statics(model, progress=False, method=self.config.method)
        self.solve_wall_s += result.wall_static_s
        self.solves += 1
        state = result.simulator.state
        if not keep:
            return state, "solved"
        self.memory[key] = state
        while len(self.memory) > self.config.memory_entries:
            self.memory.popitem(last=False)
        return state.copy(), "solved"

    def stats(self) -> dict[str, float]:
        """Counters: memory hits, solves and the solves' wall time [s]."""
        return {"memory_hits": self.hits, "solves": self.solves, "solve_wall_s": self.solve_wall_s}

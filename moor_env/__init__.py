"""moor_env: dart (torpedo) anchor installation, simulated with a numba lumped-mass model.

Data flows one way: ``configs/scenes/*.yaml`` -> :func:`load_scene` (validated :class:`SceneConfig`) ->
:func:`compile_scene` (flat arrays) -> numba kernels (``moor_env.physics``) -> :class:`DropResult` /
:class:`StaticResult`.
"""

from moor_env.compile import Model, compile_scene
from moor_env.config import SceneConfig, load_scene
from moor_env.errors import ConfigError, MoorEnvError, SimulationDiverged, StaticsNotConverged
from moor_env.simulation import DropResult, Simulator, StaticResult, simulate_drop, solve_statics

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "DropResult",
    "Model",
    "MoorEnvError",
    "SceneConfig",
    "SimulationDiverged",
    "Simulator",
    "StaticResult",
    "StaticsNotConverged",
    "compile_scene",
    "load_scene",
    "simulate_drop",
    "solve_statics",
]

# Gymnasium environments (moor_env/AnchorRelease-v0, moor_env/AnchorPlan-v0): registered on import.
try:
    from moor_env.envs.registration import register_envs as _register_envs
except ImportError:  # pragma: no cover - gymnasium missing: the physics API still works
    pass
else:
    _register_envs()

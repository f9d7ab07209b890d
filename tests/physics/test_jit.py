"""The kernels' compile options (``moor_env/physics/_jit.py``): a result must not depend on whether the kernels
were compiled in the running process or loaded from numba's on-disk cache."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

# A static solve whose path is sensitive in the last bit: 320 Newton iterations in strong current on a deep, wide
# scene (from the statics benchmark's draws). With the fastmath "contract" flag the freshly compiled kernels took
# 320 iterations and the cached ones 321, ending ulps apart.
PROBE = """
import hashlib
import numpy as np
from moor_env import load_scene, solve_statics
scene = load_scene("gjoa-500", {"water_depth_m": 961.729, "vessel_spacing_m": 297.38, "mooring_line_length_m": 1186.71,
                                "vertical_chain_length_m": 36.987, "drop_height_m": 48.12, "current_scale": 1.4549,
                                "current_direction_deg": 106.655, "anchor_mass_scale": 1.0451, "fidelity": "fast"})
static = solve_statics(scene, progress=False)
digest = hashlib.sha256()
for array in (static.simulator.state.node_pos, static.simulator.state.body_state):
    digest.update(np.ascontiguousarray(array).tobytes())
print(static.iterations, digest.hexdigest())
"""


@pytest.mark.slow
def test_cold_and_warm_cache_give_the_same_equilibrium_bit_for_bit(tmp_path):
    """Reference: the same static solve in a process that compiles every kernel (empty ``NUMBA_CACHE_DIR``) and in a
    second process that loads them from the cache the first one wrote; iteration count and the bytes of every node
    position and of the anchor state equal (tolerance: none)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    runs = [subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
            for _ in range(2)]
    cold, warm = (run.stdout.strip() for run in runs)
    assert cold and cold == warm

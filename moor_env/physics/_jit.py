"""numba options for every kernel, in one place.

``jit`` is ``numba.njit`` with ``cache=True``, ``nogil=True`` and a fastmath flag set *without* ``nnan`` and
``ninf`` (enabling every fastmath flag would turn NaN checks into no-ops and blow-ups would go unnoticed).

numba's on-disk cache is keyed on the file of the jitted entry point only; an edit to a jitted callee
in another module would leave a stale entry point in the cache (numba issues #1833, #9483). Unless the user
sets ``NUMBA_CACHE_DIR`` themselves, the cache therefore lives in a folder keyed on a hash of all kernel
sources, so that any edit to any kernel module starts a fresh cache.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path

import numba

# No "reassoc" and no "contract": with either, a kernel compiled in the running process and the same kernel loaded
# from the cache round differently (with "contract", a static solve in strong current took 320 Newton iterations
# freshly compiled and 321 from the cache), so a result would depend on whether the cache was warm; with "nsz" and
# "arcp" alone both agree bit for bit (tests/physics/test_jit.py).
FASTMATH_FLAGS = {"nsz", "arcp"}


def _kernel_source_hash() -> str:
    digest = hashlib.sha256()
    for path in sorted(Path(__file__).resolve().parent.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    digest.update(numba.__version__.encode())
    return digest.hexdigest()[:16]


def _configure_cache_dir() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    target = Path(base) / "moor_env" / "numba" / _kernel_source_hash()
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError:
        target = Path(tempfile.gettempdir()) / "moor_env_numba" / _kernel_source_hash()
        target.mkdir(parents=True, exist_ok=True)
    numba.config.CACHE_DIR = str(target)


_configure_cache_dir()

jit = functools.partial(numba.njit, cache=True, nogil=True, fastmath=FASTMATH_FLAGS)

# ``jit`` with numpy's error model: a float division by zero gives inf or NaN (which the blow-up checks of
# ``integrate.advance`` end cleanly) instead of raising ZeroDivisionError out of the kernel. Without a zero test
# before every division LLVM schedules the arithmetic freely: the time-stepping modules (integrate, implicit) are
# ~30 % faster per implicit step (benchmarks/bench_implicit_step.py); results move by rounding only (1e-11 to
# 1e-9 relative at touchdown). The line-anchor contact's modules (anchor_surface, contact, segment_contact and
# the broad phase), called per node or segment near the anchor at every step, use it too.
jit_step = functools.partial(jit, error_model="numpy")

# ``jit_step`` without numba's reference counting (NRT), for the kernels that take the records
# (``physics/records.py``) every time step and allocate nothing, the step itself included (``integrate.step``,
# ``implicit.implicit_euler_update``). numba increments and decrements the reference count of every array argument
# it unpacks on each call, an atomic operation each, and a record holds about thirty arrays: on the vertical chain
# that was about a tenth of an explicit step. Such a kernel may not allocate (numba refuses to compile it) nor keep
# an array beyond the call. The static solver's passes over the nodes and segments (its residual, assembly,
# elimination and contact terms) are such kernels too: without the counts, and with the assembly writing each
# segment's blocks once, a step's linear solve on gjoa-500 takes 28 % less time (default and accurate presets).
# A kernel without reference counting compiles the reference-counted kernels it calls without them as well, so
# the kernels that allocate (the Newton kernel, the anchor's 5x5 solve) and those that lead to them (the step's
# solve, the elimination) stay reference counted and call the passes.
#
# Calls cost too: numba passes an array as its seven to nine fields, so a call that LLVM does not inline passes
# tens of arguments, and a call that takes the records about three hundred. The line-anchor contact's helpers
# called per node or segment (the anchor's surface distance, the law, the cheap segment tests) and its passes
# called per step are therefore inlined by numba (``inline="always"``) into the load evaluation and the implicit
# step: as calls they cost as much as the law itself (on the vertical chain, inlining halved the law's cost per
# node).
jit_no_refcount = functools.partial(jit_step, _nrt=False)

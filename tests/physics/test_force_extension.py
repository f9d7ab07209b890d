"""What docs/model.md ("Adding a force") promises about the kernels' records (moor_env.physics.records): the list
of arrays is written once, every array in it is read by a kernel, the batched env's address table and its
records follow the field lists with no further edit, and the force laws are called from one place each."""

from __future__ import annotations

import ast
from collections import namedtuple
from pathlib import Path

import numba
import numpy as np
import pytest

import moor_env
from moor_env.physics.record_table import record_from_table, table_rows
from moor_env.physics.records import (
    F8,
    MODEL_FIELDS,
    MODEL_NAMES,
    STATE_FIELDS,
    STATE_NAMES,
    WORK_FIELDS,
    WORK_NAMES,
    Field,
    StateRecord,
)

PACKAGE = Path(moor_env.__file__).resolve().parent
ROOT = PACKAGE.parent
JIT_DECORATORS = {"jit", "jit_step", "jit_no_refcount", "njit"}
# where the arrays are named: the field lists, and the compiled scene that makes them (compile.Model)
DEFINITION = {PACKAGE / "physics" / "records.py", PACKAGE / "compile.py"}


def _sources():
    """(path, syntax tree) of every module of moor_env and agents."""
    for path in sorted(PACKAGE.rglob("*.py")) + sorted((ROOT / "agents").rglob("*.py")):
        yield path, ast.parse(path.read_text(), filename=str(path))


def _is_kernel(fn: ast.FunctionDef) -> bool:
    for d in fn.decorator_list:
        target = d.func if isinstance(d, ast.Call) else d
        name = target.id if isinstance(target, ast.Name) else getattr(target, "attr", None)
        if name in JIT_DECORATORS:
            return True
    return False


def _kernel_reads() -> dict[str, set[str]]:
    """Record field name -> the kernels that read it as ``model.<name>`` or ``state.<name>``."""
    reads: dict[str, set[str]] = {}
    for path, tree in _sources():
        for fn in ast.walk(tree):
            if not (isinstance(fn, ast.FunctionDef) and _is_kernel(fn)):
                continue
            for node in ast.walk(fn):
                if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                        and node.value.id in ("model", "state")):
                    reads.setdefault(node.attr, set()).add(f"{path.relative_to(ROOT)}:{fn.name}")
    return reads


def test_every_record_array_is_read_by_a_kernel():
    """An array in a field list that no kernel reads would be dead weight carried by every copy and table."""
    reads = _kernel_reads()
    unread = [f.name for f in MODEL_FIELDS + STATE_FIELDS + WORK_FIELDS if f.name not in reads]
    assert not unread, f"record arrays no kernel reads: {unread}"


@pytest.mark.parametrize("names", [MODEL_NAMES, STATE_NAMES, WORK_NAMES], ids=["model", "state", "work"])
def test_no_module_lists_a_record_by_hand(names):
    """No module outside the definition names every array of a record in a literal or as keywords of one call
    (such a list would need an edit for every new array). Lists of a few arrays chosen for a purpose (what the
    statics restores) are not a record's list and are allowed."""
    found = []
    for path, tree in _sources():
        if path in DEFINITION:
            continue
        for node in ast.walk(tree):
            if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
                listed = {e.value for e in node.elts if isinstance(e, ast.Constant)}
            elif isinstance(node, ast.Call):
                listed = {kw.arg for kw in node.keywords}
            else:
                continue
            if set(names) <= listed:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not found, f"hand-written lists of the record's arrays: {found}"


@numba.njit
def _read_extended(table):
    """The extended state record rebuilt from its table rows: the new array's sum and a state array's."""
    state = record_from_table(_EXTENDED, table, 0)
    return state.node_pos.sum(), state.extra_n.sum()


_EXTRA = Field("extra_n", F8, 1, ("nodes",))
_EXTENDED = namedtuple("ExtendedState", StateRecord._fields + (_EXTRA.name,))
_EXTENDED.FIELDS = StateRecord.FIELDS + (_EXTRA,)


def test_a_new_field_reaches_a_kernel_through_the_table_with_no_other_edit():
    """A record class with one more field (a new work array) is written into the batched env's address table and
    rebuilt in a kernel by the same code: nothing lists the arrays but ``FIELDS``. Reference: numpy sums of the
    same arrays (exact: the kernel reads the same memory)."""
    nodes = 7
    arrays = []
    for field in StateRecord.FIELDS:
        shape = tuple(nodes if d == "nodes" else 5 if d in ("segs", "lines") else d for d in field.shape)
        arrays.append(np.zeros(shape or (nodes,) * field.ndim, dtype=field.dtype))
    arrays[0] = np.arange(nodes * 3, dtype=np.float64).reshape(nodes, 3)  # node_pos
    extra = np.linspace(0.0, 1.0, nodes)
    record = _EXTENDED(*arrays, extra)
    table = table_rows(record)
    assert table.shape[0] == len(StateRecord.FIELDS) + 1
    assert _read_extended(table) == (record.node_pos.sum(), extra.sum())


def _callers(function: str) -> list[str]:
    """Modules of moor_env that call ``function`` (by its name)."""
    calls = []
    for path, tree in _sources():
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                name = node.func.id if isinstance(node.func, ast.Name) else getattr(node.func, "attr", None)
                if name == function:
                    calls.append(str(path.relative_to(PACKAGE)))
    return sorted(set(calls))


@pytest.mark.parametrize(("law", "callers"), [
    ("segment_loads", ["physics/loads.py"]),
    ("add_point_loads", ["physics/loads.py"]),
    ("seabed_force", ["physics/loads.py"]),
    ("body_loads", ["physics/loads.py"]),
    ("add_contact_loads", ["physics/loads.py"]),
    ("add_segment_contact_loads", ["physics/loads.py"]),
    ("add_point_loads_dv", ["physics/implicit_assembly.py"]),
    ("add_seabed_dv", ["physics/implicit_assembly.py"]),
    ("add_slender_drag_dv", ["physics/implicit_assembly.py"]),
])
def test_each_force_law_is_called_from_one_place(law, callers):
    """Every integrator and the statics reach a force through ``loads.compute_loads``, and the implicit step its
    derivative through ``implicit_assembly.assemble``: a law called elsewhere would be a second path to keep in
    step."""
    assert _callers(law) == callers

"""Records from an address table: how one kernel call takes the records of many scenes.

The batched env advances scenes of different sizes in one numba call, so there is no stacked array per field.
Passing every scene's records as arguments would unbox each of their arrays with the GIL held on every call
(measured with the flat arguments: 56-75 us per call for 8 scenes before the first step). Instead the caller
writes, for every scene and every array of its records, the array's data address, shape and size into one int64
table (:func:`table_rows`, which checks dtype, rank and C layout) and keeps the arrays alive; the kernel rebuilds
each record as views on that memory (:func:`record_from_table`), field by field in the order of the record class's
``FIELDS`` (``physics/records.py``), so a field added there is in the table and in the record with no further
edit.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.extending import intrinsic, overload

from moor_env.physics._jit import jit

# columns of a table row: data address, the shape (0 beyond the array's rank), number of elements
T_ADDRESS = 0
T_SHAPE = 1  # 3 columns
T_SIZE = 4
N_TABLE_COLUMNS = 5


@intrinsic
def _address_pointer(typingctx, address):
    """An int64 memory address as a ``void*`` (for ``numba.carray``)."""
    if address != types.int64:
        return None

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(types.voidptr))

    return types.voidptr(types.int64), codegen


def record_from_table(cls, table, first):
    """In a kernel: the record of class ``cls`` (a named tuple class with ``FIELDS``) whose arrays are described
    by rows ``first``, ``first + 1``, ... of ``table`` (int64, ``N_TABLE_COLUMNS`` columns)."""
    raise NotImplementedError("record_from_table runs in numba kernels only")


@overload(record_from_table)
def _record_from_table(cls, table, first):
    """The implementation for ``cls``: one ``numba.carray`` per field, of the field's dtype and rank (generated
    from ``FIELDS`` when a kernel is compiled)."""
    if not isinstance(cls, types.NamedTupleClass):
        return None
    views = []
    for k, field in enumerate(cls.instance_class.FIELDS):
        shape = ", ".join(f"table[first + {k}, {T_SHAPE + d}]" for d in range(field.ndim))
        views.append(f"numba.carray(_address_pointer(table[first + {k}, {T_ADDRESS}]), ({shape},), "
                     f"np.{np.dtype(field.dtype).name})")
    source = "def impl(cls, table, first):\n    return cls(" + ", ".join(views) + ")\n"
    namespace = {"numba": numba, "np": np, "_address_pointer": _address_pointer}
    exec(source, namespace)  # the code above, generated from the field list only
    return namespace["impl"]


@jit
def copy_rows(table, source, target, count):
    """Copy the arrays of rows ``source``.. onto those of rows ``target``.. (``count`` rows of equal sizes), word by
    word: every record array is of 8-byte elements, and an int64 copy keeps float bits exactly."""
    for k in range(count):
        n = table[source + k, T_SIZE]
        src = numba.carray(_address_pointer(table[source + k, T_ADDRESS]), (n,), np.int64)
        dst = numba.carray(_address_pointer(table[target + k, T_ADDRESS]), (n,), np.int64)
        for i in range(n):
            dst[i] = src[i]


def table_row(name: str, array: np.ndarray, dtype: type, ndim: int) -> list[int]:
    """Address, shape and size of one array, after checking it is what the kernel will read it as.

    Raises
    ------
    TypeError
        Naming the array, if its dtype, rank or layout differs.
    """
    if array.dtype != dtype or array.ndim != ndim or not array.flags.c_contiguous:
        raise TypeError(f"simulator array '{name}' is {array.dtype}[{array.ndim}d], expected C-contiguous "
                        f"{np.dtype(dtype)}[{ndim}d]")
    return [array.ctypes.data, *array.shape, *([0] * (3 - ndim)), array.size]


def table_rows(record, fields=None) -> np.ndarray:
    """The table rows of a record (or of any sequence of arrays described by ``fields``, default the record's
    ``FIELDS``), checked by :func:`table_row`."""
    fields = record.FIELDS if fields is None else fields
    return np.array([table_row(f.name, a, f.dtype, f.ndim) for f, a in zip(fields, record, strict=True)],
                    dtype=np.int64).reshape(len(fields), N_TABLE_COLUMNS)

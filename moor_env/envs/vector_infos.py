"""Gymnasium's vector ``info`` layout built from the slots' own info dicts (:func:`merge_infos`).

The batched envs keep one plain dict per slot (they cross a process boundary 25x cheaper than numpy arrays) and
merge them key by key at the end of a step into what ``VectorEnv._add_info`` would have built env by env.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def merge_infos(infos: list[tuple[int, dict[str, Any]]], num_envs: int) -> dict[str, Any]:
    """Gymnasium's vector ``info`` layout (``VectorEnv._add_info`` applied env by env, same keys, dtypes and
    ``_key`` masks; nested dicts recursively) built key by key: one array per key per step instead of a
    lookup-and-assign per env and key, which cost more than the rest of the batched env's bookkeeping.
    """
    if len(infos) == num_envs and _same_layout(infos):
        return _merge_full(infos)
    keys: dict[str, None] = {}
    for _, info in infos:
        keys.update(dict.fromkeys(info))
    out: dict[str, Any] = {}
    for key in keys:
        present = [(i, info[key]) for i, info in infos if key in info]
        first = present[0][1]
        every_slot = len(present) == num_envs and all(i == k for k, (i, _) in enumerate(present))
        numeric = type(first) in (int, float, bool) or issubclass(type(first), np.number)
        if isinstance(first, dict):
            array = merge_infos(present, num_envs)
        elif numeric and every_slot:  # the common case, in one call
            array = np.array([value for _, value in present], dtype=type(first))
        else:
            if numeric:
                array = np.zeros(num_envs, dtype=type(first))
            elif isinstance(first, np.ndarray):
                array = np.zeros((num_envs, *first.shape), dtype=first.dtype)
            else:
                array = np.full(num_envs, fill_value=None, dtype=object)
            for i, value in present:
                array[i] = value
        if every_slot:
            mask = np.ones(num_envs, dtype=np.bool_)
        else:
            mask = np.zeros(num_envs, dtype=np.bool_)
            mask[[i for i, _ in present]] = True
        out[key], out[f"_{key}"] = array, mask
    return out


def _same_layout(infos: list[tuple[int, dict[str, Any]]]) -> bool:
    """Whether the infos are of slots 0, 1, ... in order and all have the same keys in the same order (the usual
    step, where every slot reports the same fields)."""
    keys = list(infos[0][1])
    return all(i == k and list(info) == keys for k, (i, info) in enumerate(infos))


def _merge_full(infos: list[tuple[int, dict[str, Any]]]) -> dict[str, Any]:
    """:func:`merge_infos` of infos that :func:`_same_layout` accepts: every key present in every slot, so every
    mask is all True and no per-slot assignment is needed. The Python floats (most values: reward terms, times,
    tensions), at the top level and in nested dicts of floats with the same keys in every slot, go into one array
    in one call, each key a row of it; other nested dicts are merged recursively."""
    num_envs = len(infos)
    dicts = [info for _, info in infos]
    first = dicts[0]
    floats = [key for key, value in first.items() if type(value) is float]
    nested = [key for key, value in first.items() if _float_dict(value) and _same_keys(dicts, key)]
    rows: dict[str, Any] = {}
    if floats or nested:
        flat: list[float] = []
        for d in dicts:  # one flat list to numpy (faster than a list of rows)
            flat += [d[key] for key in floats]
            for key in nested:
                flat += d[key].values()
        block = np.array(flat, dtype=np.float64).reshape(num_envs, -1).T.copy()
        rows = dict(zip(floats, block, strict=False))
        k = len(floats)
        for key in nested:
            subkeys = list(first[key])
            sub_masks = np.ones((len(subkeys), num_envs), dtype=np.bool_)
            rows[key] = {}
            for j, sub in enumerate(subkeys):
                rows[key][sub], rows[key][f"_{sub}"] = block[k + j], sub_masks[j]
            k += len(subkeys)
    masks = np.ones((len(first), num_envs), dtype=np.bool_)
    out: dict[str, Any] = {}
    for k, (key, value) in enumerate(first.items()):
        kind = type(value)
        if key in rows:
            array = rows[key]
        elif isinstance(value, dict):
            array = merge_infos([(i, info[key]) for i, info in infos], num_envs)
        elif kind in (int, bool) or issubclass(kind, np.number):
            array = np.array([d[key] for d in dicts], dtype=kind)
        elif isinstance(value, np.ndarray):
            array = np.zeros((num_envs, *value.shape), dtype=value.dtype)
            for i, d in enumerate(dicts):
                array[i] = d[key]
        elif kind is str:
            array = np.full(num_envs, fill_value=None, dtype=object)
            array[:] = [d[key] for d in dicts]
        else:
            array = _object_items(infos, key)
        out[key], out[f"_{key}"] = array, masks[k]
    return out


def _same_keys(dicts: list[dict[str, Any]], key: str) -> bool:
    """Whether ``d[key]`` is a dict with the keys of the first one, in the same order, in every one of ``dicts``."""
    keys = tuple(dicts[0][key])
    return all(type(d[key]) is dict and tuple(d[key]) == keys for d in dicts)


def _float_dict(value: Any) -> bool:
    """Whether ``value`` is a non-empty dict of Python floats (merged into :func:`_merge_full`'s block)."""
    return type(value) is dict and len(value) > 0 and all(type(v) is float for v in value.values())


def _object_items(infos: list[tuple[int, dict[str, Any]]], key: str) -> np.ndarray:
    """The values of ``key`` as a 1-d object array, element by element (a list of sequences given to numpy at once
    would become a 2-d array)."""
    array = np.full(len(infos), fill_value=None, dtype=object)
    for i, info in infos:
        array[i] = info[key]
    return array

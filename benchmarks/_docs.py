"""Generated blocks in the docs: every benchmark writes its tables between ``<!-- BEGIN name -->`` and
``<!-- END name -->`` in a markdown file, so that a rerun (or ``--docs-only``) updates them."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
RESULTS = ROOT / "benchmarks" / "results"


def _markers(name: str) -> tuple[str, str]:
    return f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"


def _span(text: str, name: str, doc_path: Path) -> tuple[int, int]:
    begin, end = _markers(name)
    i = text.find(begin)
    j = text.find(end, i + len(begin)) if i >= 0 else -1
    if i < 0 or j < 0:
        raise KeyError(f"{doc_path}: no block {name!r} (markers {begin!r} ... {end!r})")
    return i + len(begin), j


def read_block(doc_path: Path, name: str) -> str:
    """The text between the block's markers in ``doc_path``, without the surrounding newlines."""
    text = Path(doc_path).read_text()
    i, j = _span(text, name, Path(doc_path))
    return text[i:j].strip("\n")


def write_block(doc_path: Path, name: str, markdown_text: str) -> bool:
    """Replace the text between ``<!-- BEGIN name -->`` and ``<!-- END name -->`` in ``doc_path`` with
    ``markdown_text``; the file must hold the markers. Returns whether the file changed."""
    path = Path(doc_path)
    text = path.read_text()
    i, j = _span(text, name, path)
    body = markdown_text.strip("\n")
    new = text[:i] + "\n" + body + ("\n" if body else "") + text[j:]
    if new != text:
        path.write_text(new)
    return new != text


def write_blocks(blocks: list[tuple[Path, str, str]]) -> None:
    """:func:`write_block` for every ``(doc_path, name, markdown_text)``; prints what changed."""
    for doc_path, name, markdown_text in blocks:
        changed = write_block(doc_path, name, markdown_text)
        print(f"{Path(doc_path).relative_to(ROOT)}: block {name} {'written' if changed else 'unchanged'}")


def load_result(stem: str) -> dict | None:
    """``benchmarks/results/<stem>.json``, or None where it does not exist."""
    path = RESULTS / f"{stem}.json"
    return json.loads(path.read_text()) if path.exists() else None


def table(header: list[str], rows: list[list]) -> str:
    """A markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def day(result: dict) -> str:
    """The date of a run (YYYY-MM-DD) from its JSON."""
    return str(result.get("date", ""))[:10] or "undated"


def run_line(result: dict, command: str) -> str:
    """One line under a table: the command, when and where it ran, the machine's load."""
    when = str(result.get("date", "")).replace("T", " ").replace("+00:00", " UTC")
    machine = result.get("machine") or result.get("measured_on")
    if isinstance(machine, dict):
        machine = f"{machine.get('cpu')}, {machine.get('cpu_count')} logical cores"
    load = result.get("load_average_1min")
    text = f"`{command}`"
    if when:
        text += f", run {when}"
    if machine:
        text += f" on {machine}"
    if isinstance(load, dict) and load.get("before") is not None:
        text += f" (1-min load average {load['before']:.1f} -> {load['after']:.1f})"
    return re.sub(r"\s+", " ", text) + "."

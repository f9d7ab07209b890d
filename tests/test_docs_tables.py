"""The docs' tables are the benchmarks' own: each benchmark renders its blocks from its committed results JSON
(``python benchmarks/<name>.py --docs-only``), and the docs must hold exactly that text. No simulation runs."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from _docs import read_block  # noqa: E402

BENCHMARKS = ("bench_drop", "bench_env", "bench_implicit_step", "bench_plan_v1", "bench_rllib", "contact_convergence",
              "contact_cost", "contact_crosscheck", "contact_episodes", "fall_reference",
              "fall_step", "mbl_exceedance", "positioning_quasi_static", "pre_release_step", "release_v1_evaluation",
              "remesh_at_release", "rl_evaluation", "rl_reproduction", "robustness", "speed_vs_error", "statics",
              "statics_env_resolution", "statics_tail")


@pytest.mark.parametrize("name", BENCHMARKS)
def test_docs_blocks_equal_the_rendered_results(name: str) -> None:
    module = importlib.import_module(name)
    blocks = module.docs_from_results()
    assert blocks, f"{name} renders no docs block from benchmarks/results"
    for doc_path, block, text in blocks:
        assert read_block(doc_path, block) == text.strip("\n"), (
            f"{Path(doc_path).relative_to(ROOT)}: block {block!r} differs from what {name} renders from its JSON; "
            f"run `python benchmarks/{name}.py --docs-only`")


def test_speed_vs_error_doc_is_rendered_from_its_results() -> None:
    module = importlib.import_module("speed_vs_error")
    expected = module.markdown(module.results_for_docs())
    assert (ROOT / "docs" / "speed_vs_error.md").read_text() == expected, (
        "docs/speed_vs_error.md differs from its results; run `python benchmarks/speed_vs_error.py --docs-only`")


def test_readme_is_a_short_guide() -> None:
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert "/work/" not in text
    assert "session" not in text.lower()
    assert "<!-- BEGIN statics -->" in text and "<!-- END statics -->" in text

"""The implicit step's solves as ``benchmarks/contact_cost.py`` counts them (replaying each step's solve loop)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from contact_cost import prepared, solves_per_step  # noqa: E402


def test_chain_resting_on_the_anchor_needs_no_second_solve():
    """The vertical chain's implicit fall, 7-9 m of it resting on the back end of the accelerating anchor by
    touchdown: the contact's set asks for at most 0.15 solves per step beyond the first (measured 0.08: nodes
    grazing the back face); a set that predicts a node outside at its present velocity alone asks for about one
    every other step, the resting chain landing again in each."""
    sim, saved = prepared("vertical-chain", "implicit_euler", "on")
    counts = solves_per_step(sim, saved)
    assert counts["contact_solves_per_step"] <= 0.15
    assert counts["solves_per_step"] <= 1.2

"""The env docstrings' tables match the code (observation names and units, actions, reward terms)."""

from __future__ import annotations

import re

from moor_env.envs import (
    ACTION_NAMES,
    OBS_SPEC,
    REWARD_TERMS,
    AnchorPlanEnv,
    AnchorPlanV1Env,
    AnchorReleaseEnv,
    AnchorReleaseV1Env,
)
from moor_env.envs.anchor_plan import PLAN_ACTION_NAMES
from moor_env.envs.anchor_release_v1 import OBS_NAMES_V1, STATE_OBS_SPEC
from moor_env.envs.levers import LEVER_NAMES
from moor_env.envs.positioning import POSITIONING_ACTIONS
from moor_env.envs.site import SITE_OBS_SPEC

SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State", "Episode End",
            "Arguments", "Version History")


def _section(doc: str, name: str) -> str:
    match = re.search(rf"^\s*## {name}\s*$(.*?)(?=^\s*## |\Z)", doc, flags=re.M | re.S)
    assert match, f"section '{name}' missing"
    return match.group(1)


def _table(text: str) -> list[list[str]]:
    rows = [line.strip() for line in text.splitlines() if line.strip().startswith("|")]
    cells = [[c.strip() for c in row.strip("|").split("|")] for row in rows]
    return [c for c in cells[2:]]  # drop header and separator


def test_sections_in_order():
    for env in (AnchorReleaseEnv, AnchorPlanEnv, AnchorPlanV1Env, AnchorReleaseV1Env):
        positions = [env.__doc__.find(f"## {name}") for name in SECTIONS]
        assert all(p >= 0 for p in positions) and positions == sorted(positions), env.__name__


def _check_observations(doc: str, spec) -> None:
    """The Observation Space table lists ``spec`` in order with its units, offsets and scales, and its shape."""
    obs = _table(_section(doc, "Observation Space"))
    assert [int(r[0]) for r in obs] == list(range(len(spec)))
    for row, (name, unit, offset, scale, _) in zip(obs, spec, strict=True):
        assert row[1] == name and row[2] == unit
        assert float(row[3]) == offset and float(row[4]) == scale, name
    assert f"({len(spec)},)" in _section(doc, "Observation Space")


def test_release_tables_match_code():
    doc = AnchorReleaseEnv.__doc__
    _check_observations(doc, OBS_SPEC)
    actions = _table(_section(doc, "Action Space"))
    assert [r[1] for r in actions] == list(ACTION_NAMES)
    assert f"({len(ACTION_NAMES)},)" in _section(doc, "Action Space")
    rewards = _table(_section(doc, "Rewards"))
    assert [r[0] for r in rewards] == list(REWARD_TERMS)


def test_plan_tables_match_code():
    doc = AnchorPlanEnv.__doc__
    actions = _table(_section(doc, "Action Space"))
    assert [r[1] for r in actions] == list(PLAN_ACTION_NAMES)
    assert f"({len(OBS_SPEC)},)" in _section(doc, "Observation Space")


def test_plan_v1_tables_match_code():
    doc = AnchorPlanV1Env.__doc__
    actions = _table(_section(doc, "Action Space"))
    assert [r[1] for r in actions] == list(LEVER_NAMES)
    assert f"({len(LEVER_NAMES)},)" in _section(doc, "Action Space")
    _check_observations(doc, SITE_OBS_SPEC)


def test_release_v1_tables_match_code():
    """Actions in order; the observation table lists the entries after the site's (9 ..) with units, offsets
    and scales."""
    doc = AnchorReleaseV1Env.__doc__
    actions = _table(_section(doc, "Action Space"))
    assert [r[1] for r in actions] == list(POSITIONING_ACTIONS)
    assert f"({len(POSITIONING_ACTIONS)},)" in _section(doc, "Action Space")
    obs = _table(_section(doc, "Observation Space"))
    first = len(OBS_NAMES_V1) - len(STATE_OBS_SPEC)
    assert [int(r[0]) for r in obs] == list(range(first, len(OBS_NAMES_V1)))
    for row, (name, unit, offset, scale) in zip(obs, STATE_OBS_SPEC, strict=True):
        assert (row[1], row[2], float(row[3]), float(row[4])) == (name, unit, offset, scale)
    assert f"({len(OBS_NAMES_V1)},)" in _section(doc, "Observation Space")

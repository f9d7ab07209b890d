"""Reward and episode end of one step, as pure functions of what the step did (:class:`StepRecord`).

The episode slot (:class:`moor_env.envs.core.InstallationCore`) reads the simulator after each integration into a
:class:`StepRecord`; :func:`step_outcome` turns it into the reward terms (every key of :data:`REWARD_TERMS`,
their sum is the reward), whether the episode terminated or was truncated, the status to report and the limits
exceeded so far. Nothing here touches a simulator. The terms and their defaults are tabled in the Rewards
section of :class:`moor_env.envs.AnchorReleaseEnv`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from moor_env.envs.config import RewardConfig

# --- reward terms (every key in info["reward_terms"] at every step; their sum is the reward) ------------------
REWARD_TERMS: tuple[str, ...] = ("speed", "tilt", "offset", "tension", "release_unit", "fibre_seabed",
                                 "chain_pile", "time", "truncation", "failure", "no_touchdown")
# limits penalised once per episode, at the step where they are first exceeded
LIMITS: tuple[str, ...] = ("tension", "release_unit", "fibre_seabed")

# --- what an integration did ------------------------------------------------------------------------------------
PHASE_WARMUP = "warmup"
PHASE_CONTROL = "control"
PHASE_FALL = "fall"
PHASE_HOLD = "hold"

STATUS_TOUCHDOWN = "touchdown"
STATUS_NO_TOUCHDOWN = "no touchdown within max_fall_time_s"
STATUS_TIME_LIMIT = "time limit"


@dataclass
class StepRecord:
    """What one step of an episode did, as the reward and the episode end see it.

    ``phase`` is the integration's (:data:`PHASE_CONTROL`, :data:`PHASE_HOLD`, else the fall); ``failed`` is
    true where the step diverged (``error`` says how) or the episode could not start. The rest is read only when
    not ``failed``: ``steps`` control steps taken (this one included) of ``max_steps``; ``elapsed_s`` of
    simulated time the step costs; every line's running maximum tension and its MBL [N], by line name; the
    release unit's rating [N]; the fibre rope's lowest clearance above the seabed [m]; ``touchdown`` (the fall
    only: the touchdown measures, None without touchdown); ``exceeded``: the limits of :data:`LIMITS` exceeded in
    earlier steps.
    """

    phase: str | None
    failed: bool = False
    error: str | None = None
    steps: int = 0
    max_steps: int = 0
    elapsed_s: float = 0.0
    max_tension_n: dict[str, float] = field(default_factory=dict)
    mbl_n: dict[str, float] = field(default_factory=dict)
    release_unit_limit_n: float = 0.0
    fibre_clearance_m: float = 0.0
    touchdown: dict[str, float] | None = None
    exceeded: dict[str, bool] = field(default_factory=lambda: dict.fromkeys(LIMITS, False))


@dataclass
class StepOutcome:
    """Reward terms (their sum is ``reward``), episode end, the status to report (None: unchanged) and the limits
    exceeded up to and including this step."""

    terms: dict[str, float]
    reward: float
    terminated: bool
    truncated: bool
    status: str | None
    exceeded: dict[str, bool]


def step_outcome(record: StepRecord, rcfg: RewardConfig) -> StepOutcome:
    """The reward terms and the episode end of one step (see the module docstring)."""
    terms = dict.fromkeys(REWARD_TERMS, 0.0)
    terminated = truncated = False
    status = None
    exceeded = dict(record.exceeded)
    if record.failed:
        if record.error is not None:
            status = f"diverged: {record.error}"
        terms["failure"] = -rcfg.failure_penalty
        terminated = True
    elif record.phase == PHASE_CONTROL:
        terms["time"] = -rcfg.time_cost_per_s * record.elapsed_s
        _limit_terms(record, rcfg, terms, exceeded)
        if record.steps >= record.max_steps:
            truncated = True
            terms["truncation"] = -rcfg.truncation_penalty
            status = STATUS_TIME_LIMIT
    elif record.phase == PHASE_HOLD:
        terms["time"] = -rcfg.time_cost_per_s * record.elapsed_s
        _limit_terms(record, rcfg, terms, exceeded)
    else:  # the fall
        terminated = True
        _limit_terms(record, rcfg, terms, exceeded)
        if record.touchdown is not None:
            status = STATUS_TOUCHDOWN
            _touchdown_terms(record.touchdown, rcfg, terms)
        else:
            status = STATUS_NO_TOUCHDOWN
            terms["no_touchdown"] = -rcfg.no_touchdown_penalty
    return StepOutcome(terms, float(sum(terms.values())), terminated, truncated, status, exceeded)


def _limit_terms(record: StepRecord, rcfg: RewardConfig, terms: dict[str, float], exceeded: dict[str, bool]) -> None:
    """Penalties of the limits first exceeded in this step (into ``terms``, marked in ``exceeded``)."""
    maxima = record.max_tension_n
    if not exceeded["tension"]:
        if any(maxima[name] > record.mbl_n[name] for name in maxima):
            exceeded["tension"] = True
            terms["tension"] = -rcfg.tension_penalty
    if not exceeded["release_unit"] and "wire" in maxima:
        # running maximum over the wire's segments: exceeds the load at the unit by at most the wire's weight
        if maxima["wire"] > record.release_unit_limit_n:
            exceeded["release_unit"] = True
            terms["release_unit"] = -rcfg.release_unit_penalty
    if not exceeded["fibre_seabed"]:
        if record.fibre_clearance_m < rcfg.fibre_clearance_m:
            exceeded["fibre_seabed"] = True
            terms["fibre_seabed"] = -rcfg.fibre_seabed_penalty


def _touchdown_terms(td: dict[str, float], rcfg: RewardConfig, terms: dict[str, float]) -> None:
    """The touchdown's speed, tilt, offset and chain-pile terms (into ``terms``)."""
    speed, tilt, offset, pile = td["speed_m_s"], td["tilt_deg"], td["offset_m"], td["chain_on_seabed_m"]
    terms["speed"] = rcfg.speed_weight * min(1.0, max(0.0, 1.0 - max(0.0, rcfg.required_speed_m_s - speed)
                                                      / rcfg.speed_falloff_m_s))
    terms["tilt"] = rcfg.tilt_weight * (1.0 - tilt / rcfg.tilt_criterion_deg)
    if tilt > rcfg.tilt_criterion_deg:
        terms["tilt"] -= rcfg.tilt_excess_penalty
    terms["offset"] = rcfg.offset_weight * (1.0 - min(offset / rcfg.offset_tolerance_m, 2.0))
    excess = max(0.0, pile - rcfg.chain_pile_allowance_m)
    if excess > 0.0:
        terms["chain_pile"] = -rcfg.chain_pile_penalty * min(1.0, excess / rcfg.chain_pile_scale_m)

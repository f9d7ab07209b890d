"""Typed errors raised by moor_env.

Every error a user can trigger by input names the offending key, its value and the allowed range, so
that the command line can print it on one line and exit with code 2.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class _Missing:
    """The value of a required key that is not given (:data:`MISSING`)."""

    def __repr__(self) -> str:
        return "(missing)"


MISSING = _Missing()


class MoorEnvError(Exception):
    """Base class of all errors raised by moor_env."""


class ConfigError(MoorEnvError, ValueError):
    """A scene or env setting is unknown, of the wrong type, out of range or physically inconsistent.

    Parameters
    ----------
    key : str
        Dotted path of the setting, e.g. ``environment.water_depth_m``.
    value : object
        The value that was given; :data:`MISSING` for a required key that is not.
    allowed : str
        The allowed range or set, in words, e.g. ``> 0`` or ``10 .. 5000``.
    reason : str, optional
        Extra explanation for cross-field checks.
    """

    def __init__(self, key: str, value: object, allowed: str, reason: str = "") -> None:
        self.key = key
        self.value = value
        self.allowed = allowed
        self.reason = reason
        text = f"{key}={value!r}: allowed {allowed}"
        if reason:
            text += f" ({reason})"
        super().__init__(text)


class SimulationDiverged(MoorEnvError, RuntimeError):
    """The time integration blew up (non-finite or unphysical state).

    Parameters
    ----------
    time_s : float
        Simulated time at which the blow-up was detected [s].
    component : str
        Which part of the model failed first, e.g. ``line 'mooring' segment 12`` or ``anchor``.
    reason : str
        ``non-finite``, ``speed above limit``, ``strain above limit``, or ``tension above breaking load`` (only an
        env's coarse pre-release advance, which the env then repeats at the scene's step).
    """

    def __init__(self, time_s: float, component: str, reason: str) -> None:
        self.time_s = float(time_s)
        self.component = component
        self.reason = reason
        super().__init__(f"simulation diverged at t={self.time_s:.6f} s in {component}: {reason}")


class StaticsNotConverged(MoorEnvError, RuntimeError):
    """The static equilibrium solver did not reach its tolerance.

    Parameters
    ----------
    message : str
    residual_rel : float, optional
        Largest residual over its degree of freedom's weight scale when the solver stopped (None if unknown).
    line_on_anchor : bool
        A line lay inside the anchor's surface at the start or the end of the solve (where the scene models their
        contact): the relaxation fallback, which leaves the contact out, is not run for it.
    inside_anchor : bool
        A line lay inside the anchor's surface at the start or the end of the solve, whether or not that solve
        modelled the contact (a solve without it is then worth repeating with it).
    """

    def __init__(self, message: str, residual_rel: float | None = None, line_on_anchor: bool = False,
                 inside_anchor: bool = False) -> None:
        self.residual_rel = residual_rel
        self.line_on_anchor = line_on_anchor
        self.inside_anchor = inside_anchor or line_on_anchor
        super().__init__(message)


def closest(word: str, choices: Iterable[str]) -> str | None:
    """The choice closest to a mistyped ``word``, or None if none is close: a close whole name first, else a name
    whose beginning is close to ``word`` (``frction`` -> ``friction_coefficient``)."""
    names = list(choices)
    close = difflib.get_close_matches(word, names, n=1, cutoff=0.6)
    if not close:
        heads = {name[:len(word)]: name for name in reversed(names) if len(name) > len(word)}
        close = [heads[h] for h in difflib.get_close_matches(word, list(heads), n=1, cutoff=0.75)]
    return close[0] if close else None


def did_you_mean(word: str, choices: Iterable[str], prefix: str = "") -> str:
    """``did you mean PREFIXNAME?`` for the :func:`closest` choice, or "" if none is close."""
    name = closest(word, choices)
    return f"did you mean {prefix}{name}?" if name else ""


class NoEquilibrium(ConfigError):
    """The scene has no static equilibrium before release (the solver refuses it at once).

    Parameters
    ----------
    key : str
        The setting to change, e.g. ``installation.mooring_line_length_m``.
    value : object
        Its value.
    allowed : str
        What would give an equilibrium, in words.
    cause : str
        Why there is none, e.g. ``the mooring line is too short``.
    """

    def __init__(self, key: str, value: object, allowed: str, cause: str) -> None:
        self.cause = cause
        super().__init__(key, value, allowed, f"no static equilibrium: {cause}")

"""The coarse equilibrium of a static solve: the scene's hanging equilibrium with its lines that are finer than the
``COARSE_PRESET`` preset's at that preset's segment lengths, the others at their own
(``moor_env.simulation.solve_statics``).

It serves three ways, each solved at most once per solve (:class:`CoarseStart`):

- **Refusal at once.** Where the first guess lays the fibre rope within ``PROBE_NEAR_SEABED_M`` of the seabed, the
  coarse compile is solved with the seabed bearing every line but the fibre (and without the line-anchor contact),
  and where that equilibrium dips the fibre more than ``PROBE_DIP_M`` through the seabed, the scene is refused
  (:meth:`CoarseStart.refuse_fibre_on_seabed`). On the statics benchmark's scenes that refuses 56 of the 127 scenes
  without an equilibrium in 9 ms (median; 18 ms at most, compile included), among them the five slowest to refuse
  otherwise (0.27-0.75 s); no scene with an equilibrium is refused so, on those scenes or on the envs'
  resolution's 1000. Why within 5 m and not the 1 m below: all 127 lay the fibre within 1 m, but on the envs'
  resolution a scene in strong current whose first guess hangs the fibre 2 m clear has none either (Newton's
  method stalls on it for 2000 iterations; refused so in 18 ms), and 5 m leaves room for a current that lowers the
  fibre further; the 26 scenes with an equilibrium the wider trigger adds on the statics benchmark cost 0.5 % more
  Newton iterations (weighted by nodes) over its 1000 scenes.
  Otherwise, where the first guess lays the fibre within ``GUESS_NEAR_SEABED_M``, the coarse equilibrium is solved
  before the fine lines, and where it rests ``REFUSED_FROM_NODES`` or more fibre nodes on the seabed the scene is
  refused (:class:`~moor_env.errors.NoEquilibrium`) without solving the fine lines.
  Why: the fine lines of such a scene mostly do not converge (the fibre lying on the seabed in current is nearly
  free sideways), so a solve of them runs into its budgets before the scene is refused. The numbers were measured on
  the statics benchmark's scenes (``benchmarks/statics.py``, 1000 drawn, seed 0), of which 876 are valid with lines
  finer than the coarse ones: 758 converge, 112 have no equilibrium, 6 are unsolved. All 112 lay the fibre on the
  seabed in the calm first guess, against 20 of the 758 within the trigger. The 98 scenes whose coarse equilibrium
  rests two or more fibre nodes on the seabed all have no equilibrium; of the 19 that rest one (a 20 m fibre
  segment touching at one end), 12 have none and 7 converge with the fibre 1.4-8.5 cm clear on their own lines, so
  one node decides nothing; where it rests none, no scene is refused for its fibre (the other 2 without an
  equilibrium are scenes whose coarse solve does not converge).
- **Start.** Where Newton's method does not converge from the first guess, the coarse equilibrium mapped onto the
  fine lines (:func:`moor_env.remesh.remesh_state`) is a start already in the scene's current and contact; it
  differs from the fine equilibrium by the sag within each coarse segment (:meth:`CoarseStart.start`). Where the
  fine lines do not converge from it either and they are finer than ``MIDDLE_PRESET``'s, the equilibrium at that
  preset's segment lengths (itself solved from the coarse one, which it shares) is the next start. Why: on the
  statics benchmark, four of the six scenes left unsolved with the loop resting on the anchor in current had
  accurate-preset lines whose solve from the fast preset's equilibrium stalled; from the default preset's, three of
  them converge. That nearer start is solved as it is first (``SOFTENED_START_ITERATIONS``), and only then with
  the slack law softened: over the 1000 scenes of each statics benchmark, of the seven fine solves from the
  default preset's equilibrium, six converged only without the softened stages (3-311 iterations, after softened
  tries of 0.07-0.23 s that did not) and the seventh converges either way (2 iterations as it is).
- **Refusal after a start.** Where the coarse equilibrium rests its fibre rope on the seabed and the fine lines do
  not converge from it within ``FIRST_TRY_ITERATIONS``, the scene is refused; with ``REFUSED_FROM_NODES`` or more
  fibre nodes on the seabed at once, with fewer (one node: a 20 m fibre segment touching at one end) only after the
  middle preset's start has failed too (:attr:`CoarseStart.pending`), and not where the middle preset's
  equilibrium hangs the fibre clear of the seabed (it is nearer the fine lines): the first guess then gets its
  full budget. Why: a scene of the statics benchmark (fast preset fitted to a 0.5 m loop chain) whose fast-preset
  equilibrium rests one fibre node 0.1 mm into the seabed has an equilibrium with the fibre 6 cm clear, reached
  from the first guess in 224 iterations (and, at some of its digits, from the default preset's equilibrium in
  103), not within 2000 from the fast preset's; refusing it after the first start would be a false refusal.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
from collections.abc import Callable
from typing import TYPE_CHECKING

from moor_env.compile import Model, compile_scene
from moor_env.errors import MoorEnvError, NoEquilibrium, SimulationDiverged, StaticsNotConverged
from moor_env.fidelity import fidelity_presets
from moor_env.physics import layout as L
from moor_env.physics.statics import MAX_ITERATIONS, SOFTENED_START_ITERATIONS, solve_equilibrium
from moor_env.physics.statics_checks import fibre_material, fibre_on_seabed, fibre_refusal
from moor_env.physics.statics_guess import first_guess
from moor_env.remesh import remesh_state
from moor_env.simulator import Simulator

if TYPE_CHECKING:
    from moor_env.simulation import StaticResult

COARSE_PRESET = "fast"  # the preset whose segment lengths the coarse compile takes
MIDDLE_PRESET = "default"  # the second start's, for lines finer than its own (CoarseStart.start)
FIRST_TRY_ITERATIONS = 150  # Newton iterations from the first guess before the coarse start is tried
GUESS_NEAR_SEABED_M = 1.0  # a first guess with the fibre this close to the seabed has the coarse solve go first
REFUSED_FROM_NODES = 2  # fibre nodes of the coarse equilibrium on the seabed that refuse the scene at once
PROBE_NEAR_SEABED_M = 5.0  # a first guess with the fibre this close to the seabed has the probe solved first [m]
PROBE_ITERATIONS = 100  # Newton iterations of the equilibrium with the fibre through the seabed at most
PROBE_DIP_M = 0.5  # how far the fibre must dip below the seabed in it to refuse the scene


@functools.cache
def _segments(preset: str) -> tuple[tuple[str, float], ...]:
    """The segment lengths of a preset (read once: every static solve asks)."""
    return tuple((k, v) for k, v in fidelity_presets()[preset].items() if k.endswith("_segment_m"))


def coarse_keys(model: Model, preset: str = COARSE_PRESET) -> dict | None:
    """The segment lengths of the coarse compile: ``preset``'s where the model's lines are finer, the model's own
    where they are not (a fitted preset may be coarser than ``preset`` on the fibre and the wire, and a coarse
    compile that refined them would cost more and map less exactly); None where no line is finer."""
    disc = model.scene.discretization
    keys = {k: max(v, getattr(disc, k)) for k, v in _segments(preset)}
    return None if all(getattr(disc, k) == v for k, v in keys.items()) else keys


class CoarseStart:
    """The coarse equilibrium of one static solve of ``sim`` (its lines finer than ``preset``'s at that preset's
    segment lengths, :func:`coarse_keys`), solved on first use.

    ``solve(model)`` is the hanging equilibrium of a compiled model without the refusals of an
    equilibrium (:class:`~moor_env.simulation.StaticResult`): the coarse one is checked here, the fine lines'
    own equilibrium by the caller.
    """

    def __init__(self, sim: Simulator, solve: Callable[[Model], StaticResult], preset: str = COARSE_PRESET) -> None:
        self.sim = sim
        self.preset = preset
        self.keys = coarse_keys(sim.model, preset)
        self._solve = solve
        self._result: StaticResult | None = None
        self._model: Model | None = None
        self._solved = False
        self.pending: NoEquilibrium | None = None  # a refusal to raise if the next start fails too
        self.fibre_resting: int | None = None  # fibre nodes on the seabed in the equilibrium mapped by start()

    def share(self, other: CoarseStart) -> None:
        """Take ``other``'s coarse equilibrium (solved on first use) where it is of the same coarse compile: the
        default preset's lines' own coarse start is the fine lines' (the fast preset's lengths are no finer than
        the default preset's on any line)."""
        if other.keys is not None and other.keys == self.keys:
            self._result = other.equilibrium()
            self._solved = True

    def _coarse_model(self) -> Model:
        """The coarse compile (compiled on the first call); the simulator's own model where no line is finer."""
        if self.keys is None:
            return self.sim.model
        if self._model is None:
            scene = self.sim.model.scene
            self._model = compile_scene(
                scene.model_copy(update={"discretization": scene.discretization.model_copy(update=self.keys)}))
        return self._model

    def equilibrium(self) -> StaticResult | None:
        """The coarse equilibrium, or None where the lines are no finer than the coarse ones or it is not reached;
        solved on the first call."""
        if self.keys is None or self._solved:
            return self._result
        self._solved = True
        try:
            self._result = self._solve(self._coarse_model())
        except (MoorEnvError, ValueError):
            pass
        return self._result

    def _fibre_dip_through_seabed(self) -> tuple[int, float] | None:
        """The fibre rope below the seabed in the coarse compile's equilibrium with the seabed bearing every line but
        the fibre rope and without the line-anchor contact (``PROBE_ITERATIONS`` at most, from its first guess): its
        nodes below the seabed and the lowest one's height above it [m], where that lies more than ``PROBE_DIP_M``
        below it; None otherwise (the solve not converged included), and without a solve where the scene has no
        fibre rope or its material is another line's too.

        Why this refuses the scene: an equilibrium of the scene that hangs the fibre clear of the seabed is an
        equilibrium of this problem too (the seabed bears nothing of the fibre in it). The one found dips the fibre
        through the seabed, so the scene has no equilibrium with the fibre clear of it, and an equilibrium with the
        fibre on the seabed is refused anyway (``statics_checks.check_fibre_clearance``). That takes this problem to
        have that one equilibrium, and three approximations: the coarse lines hang as the fine ones, the wire keeps
        its first guess's length (the drop-height corrections change it by centimetres to decimetres), and the
        anchor's contact, left out, moves the loop's chain and not the fibre. ``PROBE_DIP_M`` is the margin for them
        (a dip of any depth would refuse by the argument itself); on the benchmarks' scenes no scene with an
        equilibrium is refused so. It is the lighter problem: no seabed contact to settle for a nearly weightless
        rope, no contact with the anchor."""
        probe = Simulator(self._coarse_model())
        if not _fibre_alone_in_its_material(probe.model):
            return None
        try:
            first_guess(probe)
            with _fibre_through_seabed_and_contact_off(probe.model):
                solve_equilibrium(probe, method="newton", max_iter=PROBE_ITERATIONS, analytic_guess=False,
                                  progress=False)
        except (MoorEnvError, ValueError):
            return None
        resting, lowest = fibre_on_seabed(probe)
        return (resting, lowest) if lowest < -PROBE_DIP_M else None

    def refuse_fibre_on_seabed(self) -> None:
        """Refuse the scene at once where the first guess (the simulator's state) lays the fibre rope within
        ``PROBE_NEAR_SEABED_M`` of the seabed and the coarse compile's equilibrium with the seabed bearing no fibre
        dips the fibre through it (:meth:`_fibre_dip_through_seabed`), or within ``GUESS_NEAR_SEABED_M`` and the
        coarse equilibrium rests ``REFUSED_FROM_NODES`` or more fibre nodes on it, the latter only where the lines
        are finer than the coarse ones (module docstring).

        Raises
        ------
        moor_env.errors.NoEquilibrium
        """
        height = fibre_on_seabed(self.sim)[1]
        if height > PROBE_NEAR_SEABED_M:
            return
        dip = self._fibre_dip_through_seabed()
        if dip is not None:
            raise fibre_refusal(self.sim, f"{dip[0]} of its nodes, the lowest {-dip[1]:.3g} m under it, in the "
                                          f"equilibrium with the seabed bearing no fibre, at the {self.preset} "
                                          f"preset's segment lengths where finer")
        if self.keys is None or height > GUESS_NEAR_SEABED_M:
            return
        coarse = self.equilibrium()
        resting = 0 if coarse is None else fibre_on_seabed(coarse.simulator)[0]
        if resting >= REFUSED_FROM_NODES:
            raise fibre_refusal(self.sim, f"{resting} of its nodes on it in the equilibrium of the scene at the "
                                          f"{self.preset} preset's segment lengths where finer")

    def start(self, progress: bool, softened_only: bool = False, unsoftened_first: bool = False):
        """Solve the fine lines from the coarse equilibrium mapped onto them; the report (iterations of both
        solves), or None where that start is not to be had (lines no finer than the coarse ones, the coarse scene
        unsolved, lines that do not map) or Newton's method does not converge from it. ``softened_only``: the
        fine lines get only the softened try of their full budget (``solve_equilibrium``), where a nearer start
        follows; ``unsoftened_first``: they get ``SOFTENED_START_ITERATIONS`` without the softened stages first,
        then the softened try only (a start near the fine lines, module docstring).

        Raises
        ------
        moor_env.errors.NoEquilibrium
            Where the coarse equilibrium lays ``REFUSED_FROM_NODES`` or more fibre nodes on the seabed and the fine
            lines do not converge from it within ``FIRST_TRY_ITERATIONS``: the scene is refused as the coarse
            compile refuses it, the cause saying so, at once instead of after a last full solve from the first guess
            (where fine lines converge from a coarse equilibrium, theirs lies within decimetres of it on the scenes
            traced, so a fibre resting on the seabed in one rests there in the other unless it barely touches).
            With fewer (it barely touches) the refusal is kept in :attr:`pending` and None returned.
        """
        coarse = self.equilibrium()
        if coarse is None:
            return None
        sim = self.sim
        self.fibre_resting = fibre_on_seabed(coarse.simulator)[0]
        refusal = _fibre_refusal(self.fibre_resting, sim, self.preset)
        certain = self.fibre_resting >= REFUSED_FROM_NODES
        budget = MAX_ITERATIONS if refusal is None else FIRST_TRY_ITERATIONS
        tries = [(budget, softened_only)]
        if unsoftened_first and budget > SOFTENED_START_ITERATIONS:
            tries = [(SOFTENED_START_ITERATIONS, False), (budget, True)]
        for max_iter, softened in tries:
            try:
                sim.state = remesh_state(coarse.simulator.state, coarse.simulator.model, sim.model)
            except ValueError:  # lines that do not map
                return None
            try:
                report = solve_equilibrium(sim, warm=True, progress=progress, method="newton", mapped=True,
                                           max_iter=max_iter, softened_only=softened)
            except MoorEnvError as exc:
                if not isinstance(exc, (StaticsNotConverged, SimulationDiverged)):
                    return None
                continue
            return dataclasses.replace(report, iterations=report.iterations + coarse.iterations)
        if refusal is not None:
            if certain:
                raise refusal
            self.pending = refusal
        return None


@contextlib.contextmanager
def _fibre_through_seabed_and_contact_off(model: Model):
    """The model's seabed bearing nothing of the fibre rope (its ``MF_SEABED_D`` 0) and its line-anchor contact off
    for the block, both restored whatever it raises."""
    fibre = fibre_material(model)
    if fibre < 0:
        raise ValueError("the model has no fibre rope")
    bearing, contact = model.mat_f[fibre, L.MF_SEABED_D], model.contact_f[L.CF_ON]
    model.mat_f[fibre, L.MF_SEABED_D], model.contact_f[L.CF_ON] = 0.0, 0.0
    try:
        yield
    finally:
        model.mat_f[fibre, L.MF_SEABED_D], model.contact_f[L.CF_ON] = bearing, contact


def _fibre_alone_in_its_material(model: Model) -> bool:
    """Whether the model has a fibre rope whose material no other line's active segment shares (the probe without
    the fibre's seabed lets every segment of that material through the seabed)."""
    fibre = fibre_material(model)
    if fibre < 0:
        return False
    seg_i = model.seg_i
    shared = ((seg_i[:, L.SI_ACTIVE] == 1) & (seg_i[:, L.SI_MAT] == fibre)
              & (seg_i[:, L.SI_LINE] != model.lines["mooring_line"].index))
    return not shared.any()


def _fibre_refusal(resting: int, fine: Simulator, preset: str) -> NoEquilibrium | None:
    """The refusal of ``fine``'s scene where the coarse equilibrium (at ``preset``'s segment lengths) rests
    ``resting`` fibre nodes on the seabed, its cause saying where it was found, or None where it rests none."""
    if resting == 0:
        return None
    return fibre_refusal(fine, f"in the equilibrium of the scene at the {preset} preset's segment lengths where finer; "
                               f"its own lines did not converge within {FIRST_TRY_ITERATIONS} iterations from it")

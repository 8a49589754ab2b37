"""``roa`` and ``candidate`` on a loop with functions, and the loop a class of it runs on.

The loop: :func:`proved_loop` (the recasting in deviations, its square roots' lower bounds proved),
:func:`boxed_loop` (recast again with a box's parameters as bounded constants), :func:`box_robust` and
:func:`robust_of` (the box's parameters or the disturbances as balls), :func:`comparison_box` (where
regions are compared and simulated). The classes' entries (:mod:`lyapcheck.models.classes.runs`) are
given them in one :class:`~lyapcheck.models.classes.contexts.FunctionsRun`, in the order of
:mod:`lyapcheck.models.classes.registry`, by the one runner
(:func:`lyapcheck.models.surfaces.certify.certify_model`).

``roa`` (:func:`run_roa`; over a box :func:`box_roa`) and ``candidate`` (:func:`run_candidate`; over a box
:func:`box_candidate`): lists of routes run by the one driver of the region classes
(:mod:`lyapcheck.models.classes.region_driver`): the ball-arithmetic region on the true field first, then
the SOS route of :mod:`lyapcheck.models.classes.regions` (the classes' one SOS implementation, both kinds
of loop), the set kept simulated on the true loop (:class:`LoopSimulation`, :func:`simulated_check`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Sequence

from lyapcheck.errors import ModelFileError
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.language.recast import RecastModel, written_poly
from lyapcheck.models.classes.recast_classes import (EPSILONS, Loop, base_loop,
                                             common_denominator, jacobian, lie,
                                             prove_denominators, prove_nonnegative, prove_root_bounds,
                                             quadratic_candidate,
                                             certificate_head, for_v, state_square, v_names)
from lyapcheck.models.classes import regions
from lyapcheck.models.engines.search import Budget, Search
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Poly, to_fmpq
from lyapcheck.tolerances import CONVERGED_BALL_RADIUS, FLOW_CHECK_MARGIN
from lyapcheck.exact import read_rational

if TYPE_CHECKING:
    from lyapcheck.models.classes.contexts import FunctionsRun
    from lyapcheck.models.classes.shaped_quadratic import Shaped
    from lyapcheck.models.engines.numeric import SetCrossCheck

# -- the loop they run on ------------------------------------------------------------------------------

def class_budget(seconds: float) -> Budget:
    """One class's time budget, named after the limit it comes from (the message says which)."""
    return Budget(seconds, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")


def functions_run(model: RecastModel, classes: Sequence[str], candidate: Poly | None, time_limit_s: float,
                  box: ModelBox | None, results: dict[str, ConditionResult]) -> FunctionsRun:
    """The loop the chosen classes run on (:class:`~lyapcheck.models.classes.contexts.FunctionsRun`): the
    proved recasting (over a box, at its centre), and over a box the loop recast with its parameters as
    bounded constants, its square roots' bounds proved where a class on the relations needs it; one-line
    :class:`ModelFileError` where the loop cannot be proved or recast so."""
    from lyapcheck.models.classes.contexts import FunctionsRun

    if box is None:
        loop = proved_loop(model, time_limit_s)
        return FunctionsRun(model=model, loop=loop, proved=loop, box=None, candidate=candidate, results=results)
    budget = class_budget(time_limit_s)
    loop = proved_loop(model, time_limit_s)  # the box's centre
    boxed = boxed_loop(model, box)
    proved = boxed
    if {"quadratic", "sos_gas", "candidate", "barrier", "reach_avoid"} & set(classes):
        proved, _ = prove_root_bounds(boxed, Search(boxed.ring, budget))
    return FunctionsRun(model=model, loop=loop, proved=proved, box=box, candidate=candidate, results=results)


def proved_loop(model: RecastModel, time_limit_s: float) -> Loop:
    """The loop in deviations with its square roots' lower bounds proved; a one-line
    :class:`ModelFileError` naming the equation of a root whose argument is not proved >= 0."""
    base = base_loop(model.system)
    loop, unproved = prove_root_bounds(base, Search(base.ring, class_budget(time_limit_s)))
    if unproved:
        raise ModelFileError(model.source, model.key_of(unproved[0]),
                             f"'{unproved[0]}': its argument could not be proved non-negative (sqrt of something that "
                             "can be negative, or of something no SOS proof here shows non-negative): write the loop "
                             "so that the root's argument is >= 0")
    return loop


def boxed_loop(model: RecastModel, box: ModelBox) -> Loop:
    """The loop with the box's parameters as bounded constants (after the states), each at the box's
    centre with its half-width; a one-line :class:`ModelFileError` where the recasting cannot keep
    one a variable or the equilibrium is not proved to stay put over the box."""
    from lyapcheck.models.language.recast import recast_with_constants

    where = f"--box {', '.join(box.names)}"
    try:
        system = recast_with_constants(model, {name: box.center(name) for name in box.names})
    except ModelFileError as exc:
        why = str(exc).removeprefix(exc.source + ": ")
        raise ModelFileError(model.source, where, f"the loop cannot be recast with the box's parameters as "
                                                  f"variables ({why}): certify points with --set") from None
    if not box_robust(model, box, system).vanishes():
        raise ModelFileError(model.source, where, "the equilibrium is not proved to stay put over the box (the "
                                                  "right-hand sides at the equilibrium are not exactly 0 for every "
                                                  "value of it, in ball arithmetic)")
    return base_loop(system, fixed={name: box.half(name) for name in box.names})


def box_robust(model: RecastModel, box: ModelBox, system: Any = None, disturbed: bool = True) -> Any:
    """The box's parameters (and, ``disturbed``, the model's disturbances where the recasting keeps
    them) as balls for the ball-arithmetic route; without them the disturbances are at 0."""
    from lyapcheck.models.language.recast import recast_with_constants
    from lyapcheck.models.classes.recast_interval import Robust

    constants = {name: box.center(name) for name in box.names}
    bounds = {name: box.half(name) for name in box.names}
    if model.disturbances and system is None and disturbed:
        try:
            system = recast_with_constants(model, {**{d: Fraction(0) for d in model.disturbances}, **constants})
            bounds = {**dict(model.disturbances), **bounds}
        except ModelFileError:
            system = None
    if system is None:
        system = recast_with_constants(model, constants)
        bounds = {name: box.half(name) for name in box.names}
    return Robust(system, bounds, box)


@dataclass(frozen=True)
class LoopSimulation:
    """A loop with functions simulated from a grid of ``box`` (deviations ``lo``, ``hi``): a certified set
    checked on the true loop (:func:`simulated_check`) and its share of the box
    (:class:`~lyapcheck.models.classes.region_driver.SimulatedLoop`)."""

    loop: Loop
    box: tuple[Any, Any]

    def simulate(self, result: ConditionResult) -> None:
        simulated_check(self.loop, result, self.box)

    def share(self, result: ConditionResult) -> float:
        """The share of fixed uniform samples of the box in the certified set (as :func:`regions.box_share`)."""
        import numpy as np

        lo, hi = self.box
        Z = lo + (hi - lo) * np.random.default_rng(0).random((4000, self.loop.n))
        eq = np.array([float(self.loop.system.values[s]) for s in self.loop.system.states])
        value, = certified_value(self.loop, result)
        return float(np.mean(value(Z + eq) <= float(Fraction(result.certificate["level"]))))


def box_roa(model: RecastModel, loop: Loop, box: ModelBox, budget: Budget) -> ConditionResult:
    """``roa`` over a box: the ball-arithmetic route with the parameters as balls (no other route
    proves a set for every value of a box here)."""
    from lyapcheck.models.classes.recast_interval import interval_roa
    from lyapcheck.models.classes.region_driver import OutOfTime, Route, drive
    from lyapcheck.models.engines import reasons

    robust = box_robust(model, box)
    if not robust.vanishes():  # a disturbance moves the equilibrium: the set for every value of the box, d = 0
        robust = box_robust(model, box, disturbed=False)
    domain = comparison_box(model, loop)

    def failed(tried: list[str]) -> ConditionResult:
        why = reasons.reason("no region of attraction was proved for every value of the box (over a box only ball "
                             "arithmetic proves one, on loops of 1 to 3 states)", ("box", "domain", "time"), tried)
        return ConditionResult("roa", "not_certified", why.summary, numbers=why.numbers(), property="ROA")

    routes = [Route("ball arithmetic, the parameters as balls", lambda b: interval_roa(loop, b, domain, robust))]
    return drive("roa", routes, budget, LoopSimulation(loop, domain), failed,
                 OutOfTime("a region of attraction", ("time",)))


def box_candidate(model: RecastModel, loop: Loop, proved: Loop, box: ModelBox, V: Poly, budget: Budget
                  ) -> ConditionResult:
    """``candidate`` over a box: the user's V (of the states; ``loop`` the box's centre, ``proved`` the loop
    recast with the box's parameters as bounded constants, :func:`boxed_loop`) proved for every value of
    the box. First GAS on ``proved``'s relations (:func:`global_candidate`: the parameters' bounds are
    relations there); else its largest level by ball arithmetic with the parameters as balls, the level
    sampled where ``V' < 0`` (:func:`~lyapcheck.models.classes.recast_interval.interval_candidate`), then, for
    a quadratic V, upwards from the local level (:func:`~lyapcheck.models.classes.recast_ball_level.ball_level`).
    Each certificate states the box (``parameter_box``); the simulated figures are the centre's."""
    from lyapcheck.models.classes.recast_ball_level import ball_level
    from lyapcheck.models.classes.recast_interval import interval_candidate
    from lyapcheck.models.classes.region_driver import OutOfTime, Route, drive
    from lyapcheck.models.engines import reasons

    def relations(budget: Budget) -> ConditionResult | str:
        boxed_v = in_ring(loop.ring, proved.ring, V)
        if boxed_v is None:
            return "on the relations: V uses a function the loop recast with the box's parameters does not have"
        found = global_candidate(proved, boxed_v, Search(proved.ring, budget))
        if isinstance(found, ConditionResult) and found.status == "certified":
            found.certificate["parameter_box"] = box.to_json()
            return found
        # (a denominator not proved positive on these relations refuses this route only: ball arithmetic follows)
        return "on the relations with the box's parameters bounded: " + (
            found.summary if isinstance(found, ConditionResult) else
            "V' < 0 was not proved everywhere" if found else "V was not proved positive definite")

    # the disturbances at 0, as at a point (a candidate's claim never covers every disturbance value:
    # registry.ZERO_DISTURBANCE_ONLY), the box's parameters as balls
    robust = box_robust(model, box, disturbed=False)
    domain = comparison_box(model, loop)
    routes = [Route("GAS on the relations, the parameters bounded", relations),
              Route("ball arithmetic, the parameters as balls",
                    lambda b: interval_candidate(loop, V, b, domain, robust)),
              Route("ball arithmetic from the local level",
                    lambda b: ball_level(loop, V, b, "candidate", "the candidate, proved by ball arithmetic from its "
                                         "exact local level upwards, for every value of the box", robust))]

    def failed(tried: list[str]) -> ConditionResult:
        why = reasons.reason("the candidate V was not proved a Lyapunov function for every value of the box, nor any "
                             "level set of it a region of attraction for every value (ball arithmetic with the box's "
                             "parameters as balls)", ("other_candidate", "box", "domain", "time"), tried)
        return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers(), property="ROA")

    return drive("candidate", routes, budget, LoopSimulation(loop, domain), failed,
                 OutOfTime("a proof with the candidate V", ("time",)))


def in_ring(source: Any, target: Any, p: Poly) -> Poly | None:
    """``p`` moved from ``source`` to ``target`` by the variables' names (:meth:`Ring.restrict` to the names they
    share, then :meth:`Ring.embed`); None where it uses one ``target`` lacks (an auxiliary the other recasting
    names differently)."""
    from lyapcheck.sos.polynomials import Ring

    shared = Ring(tuple(name for name in source.names if name in target.names))
    try:
        return shared.embed(source.restrict(p, shared), target)
    except ValueError:
        return None


def robust_of(model: RecastModel) -> Any:
    """The model's disturbances for claims covering them (None without any, or where the recasting
    could not keep them)."""
    from lyapcheck.models.classes.recast_interval import Robust

    return Robust(model.robust, dict(model.disturbances)) if model.robust is not None else None


def comparison_box(model: RecastModel, loop: Loop) -> tuple[Any, Any]:
    """The box (deviations ``lo``, ``hi``) in which regions are compared and the V-s iteration
    samples: the model's ``[domain]``, else ``+-pi`` in an angle and ``+-DEFAULT_HALF_WIDTH`` elsewhere."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import DEFAULT_HALF_WIDTH

    eq = np.array([float(v) for v in model.equilibrium])
    if model.domain is not None:
        lo = np.array([float(model.domain[s][0]) for s in model.states]) - eq
        hi = np.array([float(model.domain[s][1]) for s in model.states]) - eq
        return lo, hi
    hw = np.array([np.pi if s in loop.angles else DEFAULT_HALF_WIDTH for s in model.states])
    return -hw, hw


def run_roa(loop: Loop, lin: ConditionResult, budget: Budget, box: tuple[Any, Any], interval: bool = True,
            robust: Any = None, flow: bool = False) -> ConditionResult:
    """``roa``, by the routes of :func:`~lyapcheck.models.classes.region_driver.drive`: first a V fitted to
    simulations and proved by ball arithmetic on the true field
    (:mod:`lyapcheck.models.classes.recast_interval`; loops of 1 to 3 states), the set it proves then
    enlarged, with ``flow`` (a model with a ``[domain]``), by boxes of the domain proved by validated
    integration to flow into it (:mod:`lyapcheck.models.classes.flow_region`); where that proves nothing,
    the linearization's V and its largest level on the recasting's relations, then the V-s
    iteration from it, at 4 to 6 states the shaped quadratic V's level on the relations too
    (:func:`shaped_relations`), and the region covering most of the box (``interval`` False: that route
    only), at 4 to 6 states against the shaped V's proved by ball arithmetic (:func:`with_shaped`);
    where the relations prove no level, the quadratic Vs' largest levels by ball arithmetic
    (:func:`quadratic_ball_level`). The shaped V is designed once (:func:`shaped_design`) for all of them."""
    from lyapcheck.models.classes.region_driver import Ends, OutOfTime, Route, drive
    from lyapcheck.models.classes.shaped_quadratic import SHAPE_STATES
    from lyapcheck.models.engines import reasons

    from functools import cache

    search = Search(loop.ring, budget)

    @cache
    def linearized() -> Any:
        """The Jacobian at the equilibrium (or why none exists), once: the relations' and the last route's V."""
        return jacobian(loop)

    @cache
    def designed() -> Shaped | str:
        """The shaped quadratic V at 4 to 6 states (:func:`shaped_design`), once: the relations' second V and
        the ball-arithmetic proofs' (or why there is none)."""
        return shaped_design(loop, linearized(), budget, box)

    label = "the linearization (J^T P + P J = -I)"

    def ball(budget: Budget) -> ConditionResult | str:
        """A V fitted to simulations, proved by ball arithmetic; with ``flow``, the boxes flowing into its set."""
        from lyapcheck.models.classes.recast_interval import interval_roa

        if not interval:
            return "ball arithmetic: not tried"
        found = interval_roa(loop, budget, box, robust)
        if isinstance(found, ConditionResult) and flow:  # (boxes proved to flow into the set: the region only grows)
            from lyapcheck.models.classes.flow_region import extend

            extend(loop, found, budget, box, certified_value(loop, found)[0])
        return found

    def relations(budget: Budget) -> ConditionResult | Ends | str:
        """The linearization's V, its largest level on the recasting's relations, then enlarged
        (:func:`regions.relations_enlarge`), and at 4 to 6 states the shaped V's level there; the region
        covering most of the box, then kept against the shaped V's by ball arithmetic where that covers more."""
        J = linearized()
        V0 = None if isinstance(J, str) else quadratic_candidate(loop, J)
        if V0 is None and isinstance(J, str):  # (a kink at the equilibrium: linearization may still prove LES)
            return Ends(f"no region of attraction was proved: the Jacobian does not exist at the equilibrium ({J}), "
                        "so the SOS route has no quadratic V to start from, and a piecewise-linear proof of "
                        "linearization holds in a neighbourhood whose size it does not bound", ("candidate",),
                        f"no Jacobian: {J}")
        if V0 is None:
            return Ends("no region of attraction was proved: the linearization gives no quadratic V to start the "
                        "search from (see linearization)", ("candidate",),
                        f"the linearization gives no quadratic V ({lin.summary})")
        first = regions.certify_region(loop, V0, search, label)
        shaped: regions.Region | str | None = None
        if loop.n in SHAPE_STATES:  # (4 to 6 states: the shaped V's level too, where its program is built)
            shaped = shaped_relations(loop, designed(), search, box)
        if isinstance(first, str) and not isinstance(shaped, regions.Region):
            return f"{label}: {first}" + ("" if shaped is None else f"; {SHAPED_RELATIONS_LABEL}: {shaped}")
        found: list[regions.Region] = []
        lines: list[str] = []
        if isinstance(first, regions.Region):
            more, tried = regions.relations_enlarge(loop, first, budget, box)
            found += [first, *more]
            lines += [f"{label}: level {float(first.level):.6g}{proved_when(first)}", *tried]
        else:
            lines.append(f"{label}: {first}")
        if isinstance(shaped, regions.Region):
            found.append(shaped)
            lines.append(f"{SHAPED_RELATIONS_LABEL}: level {float(shaped.level):.6g}{proved_when(shaped)}")
        elif shaped is not None:
            lines.append(f"{SHAPED_RELATIONS_LABEL}: {shaped}")
        result = regions.best_region(loop, found, [*skipped, *lines], box, search)
        if result.status == "certified" and loop.n in SHAPE_STATES:  # (against the shaped V's by ball arithmetic)
            simulated_check(loop, result, box)
            result = with_shaped(loop, linearized(), budget, box, result, designed())
        return result

    def local(budget: Budget) -> ConditionResult | str:
        """A quadratic V's largest level by ball arithmetic from the exact local one: the linearization's, and at
        4 to 6 states the shaped V's beside it (:func:`quadratic_ball_level`)."""
        return quadratic_ball_level(loop, linearized(), budget, box,
                                    designed() if loop.n in SHAPE_STATES else None)

    routes = [Route("ball arithmetic on the true field", ball), Route(label, relations),
              Route("ball arithmetic from the local level", local)]
    skipped: list[str] = []  # (every route's reason so far: the relations' certified result quotes them)

    def failed(tried: list[str]) -> ConditionResult:
        return regions.best_region(loop, [], tried, box, search)

    return drive("roa", routes, budget, LoopSimulation(loop, box), failed,
                 OutOfTime("a region of attraction", ("time", "domain")), tried=skipped)



#: starts per state of the grid over the box on which a certified region is simulated (2 states; the
#: same count, uniform, for more)
SIMULATED_GRID: Final = 40
#: how long each is simulated (the loop's time unit); a start in the set that has not converged by
#: then is simulated ten times longer with V watched along it (:func:`set_cross_check`)
SIMULATED_HORIZON: Final = 30.0
#: a start farther than this many box sizes from the equilibrium is stopped there (it does not
#: converge in this horizon; its re-simulation, if it started in a certified set, is not stopped)
SIMULATED_ESCAPE: Final = 10.0
#: converged: ending this close to the equilibrium
CONVERGED_RADIUS: Final = CONVERGED_BALL_RADIUS


def proved_when(region: regions.Region) -> str:
    """`` (the largest proved when ...)`` where a budget ended the region's level search, "" otherwise."""
    return f" (the largest proved when {region.stopped})" if region.stopped else ""


def converging(loop: Loop, starts: Any, box: tuple[Any, Any], max_steps: int | None = None) -> tuple[Any, Any]:
    """Which starts (deviations, rows) of the true loop converge in :data:`SIMULATED_HORIZON`: to the
    equilibrium, and to it modulo 2 pi in an angle (two boolean arrays). A start farther than
    :data:`SIMULATED_ESCAPE` times the ``box``'s largest width is stopped there; ``max_steps``: each row's step
    budget (a row it stops has not converged). The simulated region of attraction of :func:`simulated_check`
    and of the shaped V's design (:mod:`lyapcheck.models.classes.shaped_quadratic`)."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import distances, simulate_ends

    system = loop.system
    lo, hi = box
    eq = np.array([float(system.values[s]) for s in system.states])
    dev, simulated = simulate_ends(system, np.asarray(starts) + eq, SIMULATED_HORIZON,
                                   escape=SIMULATED_ESCAPE * float(np.max(np.asarray(hi) - np.asarray(lo))),
                                   max_steps=max_steps)
    return (simulated.ok & (distances(system, dev) < CONVERGED_RADIUS),
            simulated.ok & (distances(system, dev, tuple(loop.angles)) < CONVERGED_RADIUS))


def simulated_check(loop: Loop, result: ConditionResult, box: tuple[Any, Any], max_steps: int | None = None) -> None:
    """Simulate the true loop from a grid of the box: the share of the simulated region of
    attraction the certified set covers (``roa_share``, with the box the ``[domain]``), and every
    start in the set that does not converge (modulo 2 pi in an angle) checked again
    (:func:`set_cross_check`): a soundness violation only when that check is conclusive.
    ``max_steps``: each row's step budget (a row it stops counts as not converged: a start in the
    set is then checked again)."""
    import numpy as np

    system = loop.system
    lo, hi = box
    count = SIMULATED_GRID ** 2
    if loop.n == 2:
        axes = [np.linspace(lo[i], hi[i], SIMULATED_GRID) for i in range(2)]
        Z = np.column_stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")])
    else:
        Z = lo + (hi - lo) * np.random.default_rng(0).random((count, loop.n))
    eq = np.array([float(system.values[s]) for s in system.states])
    value, = certified_value(loop, result)
    in_set = value(Z + eq) <= float(Fraction(result.certificate["level"]))
    inside = in_set
    if "flow" in result.certificate:  # the region is the set and the boxes proved to flow into it
        from lyapcheck.models.classes.flow_region import in_boxes

        inside = in_set | in_boxes(result.certificate, system.states, Z)
    to_zero, modulo = converging(loop, Z, box, max_steps)
    result.numbers["simulated_starts"] = int(len(Z))
    if to_zero.any():  # (no simulated start converged in the horizon: no share to state, not a share of 0)
        result.numbers["roa_share"] = float(np.mean(inside[to_zero]))
    result.numbers["simulated_roa_share_of_box"] = float(np.mean(to_zero))
    # a region proved by ball arithmetic claims convergence to the equilibrium itself, not modulo 2 pi
    angles = () if result.certificate.get("kind") == "interval" else tuple(loop.angles)
    suspicious = in_set & ~(to_zero if not angles else modulo)
    again = Z[suspicious] + eq
    if "flow" in result.certificate:  # a start in a proved box that does not converge: checked again, below
        stray = inside & ~in_set & ~to_zero
        result.numbers["flow_box_starts_not_converged"] = int(np.sum(stray))
        if stray.any():
            arrived, left_out = flow_cross_check(loop, result, Z[stray] + eq, value)
            result.numbers["flow_box_starts_not_in_set_at_their_time"] = int(np.sum(left_out))
            if left_out.any():
                result.numbers["soundness_violation"] = True
            again = np.concatenate([again, arrived])  # (now in the set: the set's own check follows them)
    if len(again):  # (its figures add soundness_violation only where it is found, never remove one)
        result.numbers.update(set_cross_check(loop, result, again, angles).numbers())


def flow_cross_check(loop: Loop, result: ConditionResult, starts: Any, value: Callable[[Any], Any]
                     ) -> tuple[Any, Any]:
    """Starts (states, rows) in the certificate's flow boxes that did not converge in the first simulation,
    each simulated up to the least time stated for a box holding it (the claim: every start of the box is
    in the set ``{V <= level}`` by then; the set is invariant, so the least time is the one to test). Returns
    the states reached by the starts that are then in the set (rows, for the set's own cross-check) and which
    starts are not (floats, with a relative margin of FLOW_CHECK_MARGIN: a soundness alarm); a start whose
    integration stopped before its time (a step budget, an escape) is neither."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import simulate_ends

    system = loop.system
    eq = np.array([float(system.values[s]) for s in system.states])
    level = float(Fraction(result.certificate["level"]))
    times = np.full(len(starts), np.inf)
    for entry in result.certificate["flow"]["boxes"]:
        lo = np.array([float(read_rational(entry["box"][s][0])) for s in system.states])
        hi = np.array([float(read_rational(entry["box"][s][1])) for s in system.states])
        held = np.all((starts - eq >= lo) & (starts - eq <= hi), axis=1)
        times[held] = np.minimum(times[held], float(read_rational(entry["t"])))
    ends = np.array(starts, dtype=np.float64)
    reached = np.zeros(len(starts), dtype=bool)  # (a row the integrator stopped before its time is not judged)
    for t in np.unique(times[np.isfinite(times)]):
        rows = times == t
        dev, simulated = simulate_ends(system, starts[rows], float(t))
        ends[rows] = dev + eq
        reached[rows] = simulated.ok
    inside = value(ends) <= level * (1 + FLOW_CHECK_MARGIN)
    return ends[reached & inside], reached & ~inside


def certified_value(loop: Loop, result: ConditionResult, *others: Poly) -> list[Any]:
    """The certified set's V as a float function of the states (rows, not deviations): ``V(z, a(x) -
    a(x_eq))``, and +inf outside the box of a ball-arithmetic region (its set is ``{V <= level}``
    within that box); then each of ``others`` (polynomials of the loop's ring, in deviations) as
    such a function. The loop is compiled once and the variables at the last states are shared
    (a cross-check reads V, q and D at every step of its trajectories)."""
    import numpy as np

    from lyapcheck.models.engines.numeric import NumericPoly
    from lyapcheck.models.engines.recast_numeric import FloatLoop
    from lyapcheck.models.engines.recast_sos import poly_from_json

    system = loop.system
    eq = np.array([float(system.values[s]) for s in system.states])
    field = FloatLoop(system)
    shift = np.array([float(system.values[n]) if n in system.values else 0.0 for n in system.ring.names])
    last: list[Any] = [None, None]  # the last states given and the loop's variables there

    def variables(X: Any) -> Any:
        if X is not last[0]:
            last[:] = [X, np.column_stack(field.columns(np.atleast_2d(np.asarray(X, dtype=np.float64)))) - shift]
        return last[1]

    def function(p: Poly) -> Any:
        poly = NumericPoly(system.ring, p)
        return lambda X: poly(variables(X))

    V = function(poly_from_json(loop.ring, result.certificate["V"], "V"))
    corners = result.certificate.get("box")
    lo = None if corners is None else np.array([float(Fraction(corners[s][0])) for s in system.states])
    hi = None if corners is None else np.array([float(Fraction(corners[s][1])) for s in system.states])

    def value(X: Any) -> Any:
        out = V(X)
        if lo is not None:
            Z = np.atleast_2d(np.asarray(X, dtype=np.float64)) - eq
            out = np.where(np.all((Z >= lo) & (Z <= hi), axis=1), out, np.inf)
        return out

    return [value, *(function(p) for p in others)]


def set_cross_check(loop: Loop, result: ConditionResult, starts: Any, angles: tuple[str, ...]
                    ) -> SetCrossCheck:
    """Starts (states, rows) in the certified set that did not converge in the first simulation,
    simulated ten times longer with V watched (:func:`lyapcheck.models.engines.numeric.check_certified_set`):
    a violation when one leaves the set, or, with the certificate's decrease ``V' <= -epsilon |z|^2 /
    D``, stays outside a small ball longer than that decrease allows; the others still converging
    are counted as not checked. Returns the :class:`lyapcheck.models.engines.numeric.SetCrossCheck`."""
    import numpy as np

    from lyapcheck.models.engines.numeric import CertifiedDecrease, ModelSystem, check_certified_set
    from lyapcheck.models.engines.recast_numeric import ATOL, RTOL, FloatLoop, distances
    from lyapcheck.models.engines.recast_sos import poly_from_json

    system = loop.system
    eq = np.array([float(system.values[s]) for s in system.states])
    cert = result.certificate
    decrease = None
    if "epsilon" in cert and "denominator" in cert:
        value, q, D = certified_value(loop, result, state_square(loop),
                                      poly_from_json(loop.ring, cert["denominator"], "denominator"))
        decrease = CertifiedDecrease(epsilon=float(read_rational(cert["epsilon"])), q=q, D=D)
    else:
        value, = certified_value(loop, result)
    field = FloatLoop(system)
    batch = ModelSystem(lambda y, d=None: field(y), len(starts))  # type: ignore[arg-type]
    return check_certified_set(batch, starts, 10 * SIMULATED_HORIZON, value=value, level=float(Fraction(cert["level"])),
                               converged=lambda X: distances(system, X - eq, angles) < CONVERGED_RADIUS,
                               rtol=RTOL, atol=ATOL, decrease=decrease)


def global_candidate(loop: Loop, V: Poly, search: Search) -> ConditionResult | bool:
    """The user's V (shifted) decreasing everywhere on the recasting's relations (GAS, exact): the certified
    result, else whether V was at least proved positive definite (``V >= eps |x - x_eq|^2``); a
    ``not_applicable`` result where a denominator of its flows is not proved positive. Over a box ``loop``
    is the loop recast with the box's parameters as bounded constants (:func:`boxed_loop`): their relations
    join the others, so the proof holds for every value of the box."""
    loop = for_v(loop, V)
    ring = loop.ring
    l2 = state_square(loop)
    names = v_names(loop, V)
    N, D, distinct = common_denominator(loop, names)
    dens, failed = prove_denominators(loop, distinct, search)
    if failed is not None:
        return ConditionResult("candidate", "not_applicable", f"the denominator {written_poly(ring, failed)} could not "
                               "be proved positive on the recasting's set")
    for eps in EPSILONS:
        pos = prove_nonnegative(loop, V - l2 * to_fmpq(eps), search, "Pc")
        if pos is None:
            continue
        dec = prove_nonnegative(loop, -lie(loop, V, N) - l2 * to_fmpq(eps), search, "Dc")
        if dec is not None:
            cert = certificate_head(loop, V, eps, D, dens)
            cert.update({"positivity": pos.to_json(ring), "decrease": dec.to_json(ring)})
            return ConditionResult("candidate", "certified", f"the candidate proves global asymptotic stability: "
                                   f"V >= {eps} |x - x_eq|^2 and V' <= -{eps} |x - x_eq|^2 / D on the recasting's "
                                   "relations (exact)", certificate=cert, property="GAS")
        return True
    return False


def run_candidate(loop: Loop, V: Poly, budget: Budget, box: tuple[Any, Any]) -> ConditionResult:
    """The user's V (shifted), by the routes of :func:`~lyapcheck.models.classes.region_driver.drive`: a global
    decrease first (GAS), else its largest certified level (ROA): by ball arithmetic on the true field (no global
    positivity needed: the set is compact and V' < 0 on it), on the recasting's relations, then, for a quadratic
    V, by ball arithmetic from its exact local level upwards."""
    from lyapcheck.models.classes.recast_ball_level import ball_level
    from lyapcheck.models.classes.recast_interval import interval_candidate
    from lyapcheck.models.classes.region_driver import Ends, OutOfTime, Route, drive
    from lyapcheck.models.engines import reasons

    on = for_v(loop, V)
    # what the relations route found (its search's result: the failure's figures and solves)
    region: list[ConditionResult] = []
    tried: list[str] = []
    positive: list[bool] = []  # (whether the first route proved V positive definite on the relations)

    def relations_gas(budget: Budget) -> ConditionResult | str:
        """V decreasing everywhere on the recasting's relations (GAS); a denominator not proved positive ends it."""
        found = global_candidate(loop, V, Search(loop.ring, budget))
        if isinstance(found, ConditionResult):
            return found
        positive.append(found)
        return ("on the recasting's relations: V' < 0 was not proved everywhere" if found
                else "on the recasting's relations: V was not proved positive definite")

    def interval(budget: Budget) -> ConditionResult | str:
        return interval_candidate(on, V, budget, box)

    def relations_level(budget: Budget) -> ConditionResult | Ends | str:
        """V's largest level on the recasting's relations (where V is proved positive definite there)."""
        if not positive[-1]:
            return Ends("the candidate V could not be proved positive definite (V >= eps |x - x_eq|^2), and no level "
                        "set of it was proved a region of attraction on the true loop", ("other_candidate", "domain"))
        found = regions.region_of_attraction(on, budget, [("the candidate", V)], box, name="candidate",
                                             **critical_plan(on, V, box))
        found.numbers.setdefault("tried_first", tried[-1])
        if found.status == "certified":
            return found
        region.append(found)
        return "; ".join(found.numbers.get("detail", []))

    def local(budget: Budget) -> ConditionResult | str:
        return ball_level(on, V, budget, "candidate", "the candidate, proved by ball arithmetic from its exact local "
                                                      "level upwards")

    routes = [Route("GAS on the recasting's relations", relations_gas),
              Route("ball arithmetic on the true field", interval),
              Route("the candidate's level on the recasting's relations", relations_level),
              Route("ball arithmetic from the local level", local)]

    def failed(tried: list[str]) -> ConditionResult:
        result = region[-1]  # (the relations' search: its figures and solves stand)
        if budget.left() <= 0:  # the time limit cut the search: inconclusive, as a class at its limit is
            why = reasons.out_of_time("a region of attraction from the candidate", budget.seconds, tried,
                                      ("time", "other_candidate"))
            result.status = "inconclusive"
        else:
            why = reasons.reason("the candidate's derivative could not be proved negative definite (V' <= 0 alone "
                                 "needs LaSalle's argument, which this class does not make), and no level set of it "
                                 "was proved a region of attraction", ("other_candidate", "domain", "time"), tried)
        result.summary = why.summary
        result.numbers["detail"] = why.detail
        return result

    return drive("candidate", routes, budget, LoopSimulation(on, box), failed,
                 OutOfTime("a proof with the candidate V", ("time",)), tried=tried)


def linearization_ball_level(loop: Loop, J: Any, budget: Budget) -> ConditionResult | str:
    """``roa`` where the SOS route proved no level of the linearization's V: ``z^T P z`` over the states
    (``J^T P + P J = -I``), its largest level by ball arithmetic from the exact local one
    (:func:`lyapcheck.models.classes.recast_ball_level.ball_level`, any number of states); why not otherwise."""
    from lyapcheck.models.classes.recast_ball_level import ball_level, state_quadratic

    V = None if isinstance(J, str) else state_quadratic(loop, J)
    if V is None:
        return "ball arithmetic from the local level: the linearization gives no quadratic V in the states"
    return ball_level(loop, V, budget, "roa", "the linearization (J^T P + P J = -I) in the states, proved by ball "
                                              "arithmetic from its exact local level upwards")


def shaped_design(loop: Loop, J: Any, budget: Budget, box: tuple[Any, Any]) -> Shaped | str:
    """The quadratic V shaped for a large region (4 to 6 states: the proposal of
    :func:`lyapcheck.models.classes.shaped_quadratic.shaped_quadratic`, floating point), or why there is none
    (one line). ``roa`` designs it once per run (:func:`run_roa`): the SOS route and the ball-arithmetic
    proofs of the same V take it from there."""
    import time

    from lyapcheck.models.classes.shaped_quadratic import shaped_quadratic

    if isinstance(J, str):
        return f"a shaped quadratic V: no Jacobian ({J})"
    # (the design's work is bounded by its rounds; the class's time is only its safety net)
    shaped = shaped_quadratic(loop, J, box, deadline=time.perf_counter() + max(budget.left(), 0.0),
                              converges=lambda starts: converging(loop, starts, box)[0])
    if shaped is None:
        return "a shaped quadratic V: the linearization gives no positive definite P to start from"
    if not shaped.improved:
        return (f"a shaped quadratic V: no start or round of the design improved on the linearization's V (sampled "
                f"share of {shaped.aimed_at} {100 * shaped.linearization_share:.3g} %)")
    return shaped


def state_form(loop: Loop, P: Sequence[Sequence[Fraction]]) -> Poly:
    """``z^T P z`` over the states (deviations), a polynomial of the loop's ring."""
    ring = loop.ring
    z = [ring.gen(s) for s in loop.system.states]
    return sum((z[i] * z[j] * to_fmpq(P[i][j]) for i in range(loop.n) for j in range(loop.n)), ring.zero())


def shaped_ball_level(loop: Loop, J: Any, budget: Budget, box: tuple[Any, Any],
                      design: Shaped | str | None = None) -> ConditionResult | str:
    """``roa`` from a quadratic V shaped for a large region (``design``, :func:`shaped_design`'s, designed
    here when None), rounded to rationals, checked positive definite exactly and its largest level proved
    by ball arithmetic on the true loop (:func:`~lyapcheck.models.classes.recast_ball_level.ball_level`, the
    same proof as the linearization's V); why not otherwise (one line: the class then keeps the
    linearization's)."""
    from lyapcheck.models.classes.recast_ball_level import ball_level
    from lyapcheck.models.classes.shaped_quadratic import rational_form

    shaped = shaped_design(loop, J, budget, box) if design is None else design
    if isinstance(shaped, str):
        return shaped
    P = rational_form(shaped.P)
    if P is None:
        return "a shaped quadratic V: the proposed P, rounded to rationals, is not positive definite (exact)"
    found = ball_level(loop, state_form(loop, P), budget, "roa", f"a quadratic V shaped to cover {shaped.aimed_at} "
                                                                 "on samples of the true field (lyapcheck.models."
                                                                 "classes.shaped_quadratic), proved by ball "
                                                                 "arithmetic from its exact local level upwards")
    if isinstance(found, str):
        return f"a shaped quadratic V: {found}"
    found.numbers["shaping"] = {"rounds": shaped.rounds, "start": shaped.start,
                                "aimed_at": shaped.aimed_at, "sampled_share": shaped.share,
                                "linearization_sampled_share": shaped.linearization_share}
    simulated_check(loop, found, box)
    return found


#: the shaped V's level on the recasting's relations: its label (``V_from``)
SHAPED_RELATIONS_LABEL: Final = ("a quadratic V shaped for a large region on samples of the true field "
                                 "(lyapcheck.models.classes.shaped_quadratic), its part invariant under the "
                                 "loop's sign symmetries, level proved on the recasting's relations")


def critical_start_of(loop: Loop, P: Sequence[Sequence[Fraction]], box: tuple[Any, Any]) -> Fraction:
    """Where the SOS level search of ``V = z^T P z`` on the relations starts (:data:`regions.CRITICAL_PLAN`):
    from the level at which sampling the true field first sees ``V' >= 0`` (rate 0: the SOS decrease's
    margin is ``eps |z|^2``, tiny). Floats: only the order of the attempts rests on it."""
    import numpy as np

    from lyapcheck.models.classes.shaped_quadratic import Sampler

    critical = Sampler(loop, box).critical_level(np.array([[float(x) for x in row] for row in P]), 0.0)
    return regions.critical_start(critical)


def critical_plan(loop: Loop, V: Poly, box: tuple[Any, Any]) -> dict[str, Any]:
    """The SOS level search's start and steps for a user's ``V`` (``candidate``): at 4 to 6 states, where ``V``
    is a quadratic form in the states (an LQR cost-to-go ``z^T S z``), from its sampled critical level
    (:func:`critical_start_of`, :data:`regions.CRITICAL_PLAN`: the quadrotor's ``z^T S z`` reaches level
    2.76 in 11 solves, where the search from V's value at a tenth of the states was cut by the class's
    time at 2e-4); otherwise the default search (no arguments)."""
    from lyapcheck.models.classes.shaped_quadratic import SHAPE_STATES
    from lyapcheck.models.engines.interval_region import quadratic_form

    import numpy as np

    P = quadratic_form(loop.ring, V, loop.n) if loop.n in SHAPE_STATES else None
    if P is None:
        return {}
    try:
        start = critical_start_of(loop, P, box)
    except (np.linalg.LinAlgError, ValueError, OverflowError):  # (P proved positive definite, yet singular or
        return {}  # not finite in floats, so no sampled level: the default search)
    return {"start": start, "plan": regions.CRITICAL_PLAN}


def shaped_relations(loop: Loop, design: Shaped | str, search: Search, box: tuple[Any, Any]
                     ) -> regions.Region | str:
    """The shaped V's largest level on the recasting's relations (SOS, exact check; issue 42), or why none
    (one line). The design's ``P`` (floats) keeps only the entries that couple states the loop's sign
    symmetries change alike (:func:`regions.state_characters`): the block-diagonal part of a positive
    definite matrix is positive definite, and an invariant V keeps the level program's symmetry blocks (the
    quadrotor's attempts: 0.3 to 2 s each instead of 10 to 48 s with the coupling entries of about 1 %).
    The search starts at half the sampled critical level of the V tried
    (:data:`regions.CRITICAL_PLAN`), within :data:`~lyapcheck.tolerances.SHAPED_RELATIONS_SOLVES` solves."""
    import numpy as np

    from lyapcheck import tolerances
    from lyapcheck.models.classes.shaped_quadratic import rational_form
    from lyapcheck.models.engines.search import BudgetExhausted

    if isinstance(design, str):
        return design
    characters = regions.state_characters(loop)
    n = loop.n
    invariant = np.array([[design.P[i][j] if characters[i] == characters[j] else 0.0 for j in range(n)]
                          for i in range(n)])
    P = rational_form(invariant)
    if P is None:
        return "a shaped quadratic V: its invariant part, rounded to rationals, is not positive definite (exact)"
    within = search.within(tolerances.SHAPED_RELATIONS_SOLVES, "for the shaped V's level on the relations",
                           "lyapcheck.tolerances.SHAPED_RELATIONS_SOLVES")
    try:
        return regions.certify_region(loop, state_form(loop, P), within, SHAPED_RELATIONS_LABEL,
                                      start=critical_start_of(loop, P, box), plan=regions.CRITICAL_PLAN)
    except BudgetExhausted as exc:  # (no level proved before the solves or the class's time ran out)
        return f"no level proved: {exc}"


def quadratic_ball_level(loop: Loop, J: Any, budget: Budget, box: tuple[Any, Any],
                         design: Shaped | str | None = None) -> ConditionResult | str:
    """``roa`` by a quadratic V's level proved by ball arithmetic where the SOS route proved none: at 4 to 6
    states the shaped V (:func:`shaped_ball_level`, from ``design`` where given) and then the linearization's
    (:func:`linearization_ball_level`, in the time left), the certified set covering the larger share of
    the simulated region of attraction kept (``roa_share``; tie: the larger volume), the other's outcome
    in ``numbers["other_quadratic"]``; below 4 states or above 6 the linearization's alone."""
    from lyapcheck.models.classes.shaped_quadratic import SHAPE_STATES

    if loop.n not in SHAPE_STATES:  # (the driver simulates the set it keeps)
        return linearization_ball_level(loop, J, budget)
    shaped = shaped_ball_level(loop, J, budget, box, design)
    linear = linearization_ball_level(loop, J, budget)
    if isinstance(linear, ConditionResult):  # (simulated here: the two are compared by their shares)
        simulated_check(loop, linear, box)
    if isinstance(shaped, str) or isinstance(linear, str):
        kept, other = (linear, shaped) if isinstance(shaped, str) else (shaped, linear)
        if isinstance(kept, ConditionResult):
            kept.numbers["other_quadratic"] = str(other)
        return kept
    kept, other = (shaped, linear) if not larger(loop, linear, shaped) else (linear, shaped)
    kept.numbers["other_quadratic"] = not_kept(other)
    return kept


def with_shaped(loop: Loop, J: Any, budget: Budget, box: tuple[Any, Any], result: ConditionResult,
                design: Shaped | str | None = None) -> ConditionResult:
    """A region the SOS route certified at 4 to 6 states against the shaped V's proved by ball arithmetic
    (:func:`shaped_ball_level`, from ``design`` where given, in the time left): the ball-arithmetic one only
    where it covers more of the simulated region of attraction (or as much with a larger volume, both
    volumes known); the other's outcome in ``numbers["other_quadratic"]``. A ball-arithmetic proof cut by
    the class's time keeps ``result`` (a proof in hand)."""
    from lyapcheck.models.classes.shaped_quadratic import SHAPE_STATES
    from lyapcheck.models.engines.search import BudgetExhausted

    if loop.n not in SHAPE_STATES:
        return result
    try:
        shaped: ConditionResult | str = shaped_ball_level(loop, J, budget, box, design)
    except BudgetExhausted as exc:
        shaped = f"a shaped quadratic V by ball arithmetic: {exc}"
    if isinstance(shaped, ConditionResult) and larger(loop, shaped, result):
        shaped.numbers["other_quadratic"] = not_kept(result)
        return shaped
    result.numbers["other_quadratic"] = shaped if isinstance(shaped, str) else not_kept(shaped)
    return result


def not_kept(other: ConditionResult) -> str:
    """One line on a certified region the class did not keep."""
    return (f"{other.numbers.get('V_from')}: level {float(other.numbers.get('level', 0.0)):.6g}, roa_share "
            f"{other.numbers.get('roa_share', '-')} (not kept)")


def larger(loop: Loop, a: ConditionResult, b: ConditionResult) -> bool:
    """Whether the certified ``a`` covers more than ``b``: a larger share of the simulated region of
    attraction (``roa_share``), or the same share and a larger volume where both sets are ellipsoids of
    the states (:func:`region_key`); otherwise not (``b`` stays)."""
    share_a, volume_a = region_key(loop, a)
    share_b, volume_b = region_key(loop, b)
    if share_a != share_b:
        return share_a > share_b
    return volume_a is not None and volume_b is not None and volume_a > volume_b


def region_key(loop: Loop, result: ConditionResult) -> tuple[float, float | None]:
    """How two certified sets compare: the share of the simulated region of attraction (``roa_share``, 0
    where none was measured), then, for an ellipsoid ``{z^T P z <= level}`` of the states, the log of its
    volume (``n/2 log level - 1/2 log det P``, floats: a comparison of two proved sets, not a claim; None
    for any other V)."""
    import numpy as np

    from lyapcheck.models.engines.interval_region import quadratic_form
    from lyapcheck.models.engines.recast_sos import poly_from_json

    P = quadratic_form(loop.ring, poly_from_json(loop.ring, result.certificate["V"], "V"), loop.n)
    level = float(Fraction(result.certificate["level"]))
    volume = None if P is None or level <= 0 else \
        loop.n / 2 * float(np.log(level)) - float(np.linalg.slogdet(np.array([[float(x) for x in row] for row in P]))[1]) / 2
    return float(result.numbers.get("roa_share", 0.0)), volume

"""The search of each class on each kind of loop, as its entry in :mod:`lyapcheck.models.classes.registry`
names it (``run_field``, ``run_functions``).

Each takes the loop's run context (:class:`~lyapcheck.models.classes.contexts.FieldRun` or
:class:`~lyapcheck.models.classes.contexts.FunctionsRun`) and the class's
:class:`~lyapcheck.models.engines.search.Budget`, and returns the class's
:class:`~lyapcheck.results.ConditionResult`. What is decided for every class alike (a class needing an
input that was not given, ``roa`` once GAS is certified, the disturbances a claim covers, the
ball-arithmetic engine after SOS) is the runner's, :func:`lyapcheck.models.surfaces.certify.certify_model`,
not an entry's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Final

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.contexts import FieldRun, FunctionsRun
    from lyapcheck.models.engines.search import Budget, Search
    from lyapcheck.models.loop.field import StateField
    from lyapcheck.results import ConditionResult

#: over a box, sos_gas's V may depend on the parameters up to these degrees, in turn
BOX_PARAM_DEGREES: Final = (0, 1)


# -- a polynomial or rational loop (the field multiplied through and scaled, but for linearization) ---------

def linearization_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """The Jacobian at the equilibrium, exactly (for every value of a box)."""
    from lyapcheck.models.classes import linearization

    return linearization.run_over_box(ctx.shifted) if ctx.box is not None else linearization.run(ctx.shifted)


def _stability(ctx: "FieldRun", budget: "Budget",
               attempt: Callable[["StateField", "Search"], "ConditionResult"]) -> "ConditionResult":
    """A stability class, robust first where it can be (:func:`lyapcheck.models.classes.field_regions.
    covering_disturbances`)."""
    from lyapcheck.models.classes.field_regions import covering_disturbances
    from lyapcheck.models.engines.search import Search

    nominal = ctx.nominal
    if nominal is None:
        raise ValueError("the field was not multiplied through")
    return covering_disturbances(ctx.model, ctx.robust, nominal, ctx.enters,
                                 lambda f: attempt(f, Search(f.ring, budget)))


def quadratic_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """A quadratic V (:func:`lyapcheck.models.classes.lyapunov.run`)."""
    from lyapcheck.models.classes import lyapunov

    sc = ctx.cleared
    return _stability(ctx, budget, lambda f, search: lyapunov.run(sc, "quadratic", (2,), search, field=f))


def sos_gas_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """A polynomial V of the searched degrees (over a box, V may depend on the parameters)."""
    from lyapcheck.degrees import searched_degrees
    from lyapcheck.models.classes import cascade_lyapunov, lyapunov, vector_lyapunov

    sc = ctx.cleared
    # where the dense and clique forms of a degree found nothing and one reached a size limit, a vector
    # Lyapunov function of the network's subsystems, once (vector_lyapunov.fallback), then, where the
    # subsystems form a cascade, one ISS-Lyapunov function per subsystem (cascade_lyapunov.fallback)
    return _stability(ctx, budget, lambda f, search: lyapunov.run(
        sc, "sos_gas", searched_degrees(lyapunov.SOS_GAS_DEGREES), search, param_degrees=BOX_PARAM_DEGREES, field=f,
        fallback=lambda tried: vector_lyapunov.fallback(sc, f, "sos_gas", search, tried)
        or cascade_lyapunov.fallback(sc, f, "sos_gas", search, tried)))


def roa_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """A region of attraction by SOS (:func:`lyapcheck.models.classes.field_regions.run_roa`): common to every
    disturbance value first, else with the disturbances at 0 (where GAS with d = 0 is certified, the
    whole state space)."""
    from lyapcheck.models.classes.claims import roa_after_gas
    from lyapcheck.models.classes.field_regions import covers, run_roa

    sc = ctx.cleared
    lin = ctx.results.get("linearization")
    memo: dict[str, Any] = {}
    if ctx.robust is not None:
        found = run_roa(sc, budget, lin, ctx.robust, memo)
        if found.status == "certified":
            return covers(found, "all")
    answered = roa_after_gas(ctx.results, "zero", over_box=ctx.box is not None)  # (GAS with d = 0)
    if answered is not None:
        return answered
    return covers(run_roa(sc, budget, lin, ctx.nominal, memo), ctx.nominal_covers)


def candidate_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """The user's V, tried on the nominal loop (over a box, for every value of it: the field's ring carries the
    box's parameters, :func:`lyapcheck.models.classes.field_regions.run_candidate`)."""
    from lyapcheck.models.classes.field_regions import covers, run_candidate

    return covers(run_candidate(ctx.cleared, ctx.candidate, budget), ctx.nominal_covers)


def sos_bound_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """Every output's ultimate bound (:func:`lyapcheck.models.classes.bounds.run`)."""
    from lyapcheck.models.classes import bounds
    from lyapcheck.models.engines.search import Search

    sc = ctx.cleared
    return bounds.run(sc, Search(sc.ring, budget))


def barrier_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """A barrier (:func:`lyapcheck.models.classes.barrier.run`)."""
    from lyapcheck.models.classes import barrier
    from lyapcheck.models.engines.search import Search

    sc = ctx.cleared
    return barrier.run(sc, Search(sc.ring, budget))


def reach_avoid_field(ctx: "FieldRun", budget: "Budget") -> "ConditionResult":
    """A reach-avoid function (:func:`lyapcheck.models.classes.reach_avoid.run`)."""
    from lyapcheck.models.classes import reach_avoid
    from lyapcheck.models.engines.search import Search

    sc = ctx.cleared
    return reach_avoid.run(sc, Search(sc.ring, budget))


# -- a loop with functions (its recasting; over a box, recast with the box's parameters as constants) -------

def linearization_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """The recasting's Jacobian at the equilibrium; over a box, the Jacobian of every value of it, on the
    loop recast with the box's parameters as bounded constants
    (:func:`~lyapcheck.models.classes.recast_classes.linearization_over_box`)."""
    if ctx.box is not None:
        from lyapcheck.models.classes.recast_classes import linearization_over_box

        return linearization_over_box(ctx.proved, ctx.box)
    return ctx.linearization(budget)


def _relations(name: str, degrees: Any, ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """``quadratic`` or ``sos_gas`` on the recasting's relations (another equilibrium refutes it), with a
    V common to every value of a box."""
    from lyapcheck.models.classes.lyapunov_relations import run_relations
    from lyapcheck.models.classes.recast_classes import refute_global

    return refute_global(ctx.loop, name) or run_relations(ctx.proved, budget, name, degrees)


def quadratic_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """A quadratic V on the recasting's relations."""
    return _relations("quadratic", (2,), ctx, budget)


def sos_gas_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """A polynomial V of the searched degrees on the recasting's relations."""
    from lyapcheck.degrees import searched_degrees
    from lyapcheck.models.classes.lyapunov import RELATIONS_GAS_DEGREES

    return _relations("sos_gas", searched_degrees(RELATIONS_GAS_DEGREES), ctx, budget)


def roa_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """A region of attraction (:func:`lyapcheck.models.classes.recast_regions.run_roa`; over a box, by ball
    arithmetic with the parameters as balls, :func:`~lyapcheck.models.classes.recast_regions.box_roa`)."""
    from lyapcheck.models.classes.recast_regions import box_roa, comparison_box, robust_of, run_roa

    if ctx.box is not None:
        return box_roa(ctx.model, ctx.loop, ctx.box, budget)
    return run_roa(ctx.loop, ctx.linearization(budget), budget, comparison_box(ctx.model, ctx.loop),
                   robust=robust_of(ctx.model), flow=ctx.model.domain is not None)


def candidate_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """The user's V (:func:`lyapcheck.models.classes.recast_regions.run_candidate`; over a box, for every value of
    it, :func:`~lyapcheck.models.classes.recast_regions.box_candidate`)."""
    from lyapcheck.models.classes.recast_regions import box_candidate, comparison_box, run_candidate

    if ctx.candidate is None:
        raise ValueError("the candidate class runs with --candidate")
    if ctx.box is not None:
        return box_candidate(ctx.model, ctx.loop, ctx.proved, ctx.box, ctx.candidate, budget)
    return run_candidate(ctx.loop, ctx.candidate, budget, comparison_box(ctx.model, ctx.loop))


def sos_bound_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """Every output's ultimate bound (:func:`lyapcheck.models.classes.bounds.run_functions`)."""
    from lyapcheck.models.classes.bounds import run_functions

    return run_functions(ctx.model, budget, ctx.box)


def barrier_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """A barrier (:func:`lyapcheck.models.classes.barrier.run_functions`)."""
    from lyapcheck.models.classes.barrier import run_functions

    return run_functions(ctx.model, ctx.proved, budget, ctx.box)


def reach_avoid_functions(ctx: "FunctionsRun", budget: "Budget") -> "ConditionResult":
    """A reach-avoid function (:func:`lyapcheck.models.classes.reach_avoid.run_functions`)."""
    from lyapcheck.models.classes.reach_avoid import run_functions

    return run_functions(ctx.model, ctx.proved, budget, ctx.box)


__all__ = ["BOX_PARAM_DEGREES", "linearization_field", "quadratic_field", "sos_gas_field", "roa_field",
           "candidate_field", "sos_bound_field", "barrier_field", "reach_avoid_field", "linearization_functions",
           "quadratic_functions", "sos_gas_functions", "roa_functions", "candidate_functions",
           "sos_bound_functions", "barrier_functions", "reach_avoid_functions"]

"""The search of each class on the discrete-time kinds of loop, as its entry in
:mod:`lyapcheck.models.classes.registry` names it (``run_map``, ``run_map_functions``, ``run_sampled``).

Each takes the loop's run context (:class:`~lyapcheck.models.classes.contexts.MapRun`,
:class:`~lyapcheck.models.classes.contexts.MapFunctionsRun` or
:class:`~lyapcheck.models.classes.contexts.SampledRun`) and the class's
:class:`~lyapcheck.models.engines.search.Budget`, and returns the class's
:class:`~lyapcheck.results.ConditionResult`, as :mod:`lyapcheck.models.classes.runs` does for continuous
loops. What is decided for every class alike (a class without an entry for the kind of loop, an input that
was not given, ``roa`` once GAS is certified) is the runner's,
:func:`lyapcheck.models.surfaces.certify.certify_model`, not an entry's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.contexts import MapFunctionsRun, MapRun, SampledRun
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.results import ConditionResult


# -- a polynomial discrete-time map (shifted to its fixed point; lyapcheck.models.loop.discrete) -------------

def linearization_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """The map's Jacobian at the fixed point, by the discrete-time test
    (:func:`lyapcheck.models.classes.discrete_linearization.run`)."""
    from lyapcheck.models.classes import discrete_linearization

    if ctx.shifted.box is not None:
        return linearization_map_box(ctx, budget)
    return discrete_linearization.run(ctx.shifted)


def linearization_map_box(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """Over a box: one Stein certificate for every Jacobian of the box
    (:func:`lyapcheck.models.classes.discrete_lyapunov.run_linearization_box`)."""
    from lyapcheck.models.classes import discrete_lyapunov

    return discrete_lyapunov.run_linearization_box(ctx.shifted, budget)


def quadratic_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """A quadratic V with ``V(F(e)) < V(e)`` (:func:`lyapcheck.models.classes.discrete_lyapunov.run`)."""
    from lyapcheck.models.classes import discrete_lyapunov

    return discrete_lyapunov.run(ctx.shifted, "quadratic", budget=budget)


def sos_gas_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """A polynomial V of the searched degrees (:func:`lyapcheck.models.classes.discrete_lyapunov.run`)."""
    from lyapcheck.models.classes import discrete_lyapunov

    return discrete_lyapunov.run(ctx.shifted, "sos_gas", budget=budget)


def roa_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """The linearization's quadratic V on its largest proved level
    (:func:`lyapcheck.models.classes.discrete_regions.run_roa`)."""
    from lyapcheck.models.classes import discrete_regions

    return discrete_regions.run_roa(ctx.model, ctx.shifted, budget)


def candidate_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """The user's V on its largest proved level (:func:`lyapcheck.models.classes.discrete_regions.run_candidate`)."""
    from lyapcheck.models.classes import discrete_regions

    if ctx.candidate is None:
        raise ValueError("the candidate class runs with --candidate")
    return discrete_regions.run_candidate(ctx.model, ctx.shifted, ctx.candidate, budget)


def barrier_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """A barrier ``lam B - B(F)`` SOS, or an unsafe iterate proved
    (:func:`lyapcheck.models.classes.discrete_safety.run_barrier`)."""
    from lyapcheck.models.classes import discrete_safety, discrete_safety_box

    if ctx.shifted.box is not None:  # one B for every value of the box, or an unsafe corner (centre) first
        return discrete_safety_box.run("barrier", ctx.model, ctx.shifted, budget)
    return discrete_safety.run_barrier(ctx.model, ctx.shifted, budget)


def reach_avoid_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """A V falling by eps per step outside the goal, or an unsafe iterate proved
    (:func:`lyapcheck.models.classes.discrete_safety.run_reach_avoid`)."""
    from lyapcheck.models.classes import discrete_safety, discrete_safety_box

    if ctx.shifted.box is not None:  # one V for every value of the box, or an unsafe corner (centre) first
        return discrete_safety_box.run("reach_avoid", ctx.model, ctx.shifted, budget)
    return discrete_safety.run_reach_avoid(ctx.model, ctx.shifted, budget)


def sos_bound_map(ctx: "MapRun", budget: "Budget") -> "ConditionResult":
    """A V with ``V(F(x, d)) <= lam V(x) + 1 - lam`` for every bounded disturbance, and each output's
    ``y^2 <= B + V - 1`` (:func:`lyapcheck.models.classes.discrete_bounds.run`)."""
    from lyapcheck.models.classes import discrete_bounds

    return discrete_bounds.run(ctx.model, ctx.shifted, budget)


# -- a discrete-time map with functions (lyapcheck.models.classes.discrete_functions) -----------------------

def linearization_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """The exact Jacobian of the map at its fixed point, by the discrete-time test
    (:func:`lyapcheck.models.classes.discrete_functions.linearization`; at a kink at the fixed point the
    piecewise-linear step form, :func:`lyapcheck.models.classes.piecewise_linearization.run_map`); over a box,
    one ``P`` for every Jacobian of the box in ball arithmetic
    (:func:`lyapcheck.models.classes.discrete_functions_box.linearization`)."""
    from lyapcheck.models.classes import discrete_functions, discrete_functions_box, piecewise_linearization

    if ctx.box is not None:
        return discrete_functions_box.linearization(ctx.model, ctx.box)
    result = discrete_functions.linearization(ctx.model)
    if result.status == "not_applicable":  # a kink at the fixed point: the piecewise-linear step form instead
        return piecewise_linearization.run_map(ctx.model, result.summary, budget) or result
    return result


def _map_relations(ctx: "MapFunctionsRun", name: "Literal['quadratic', 'sos_gas']", budget: "Budget"
                   ) -> "ConditionResult":
    """``quadratic`` or ``sos_gas`` on the recasting's relations; over a box, one V of the states for every
    value of it, the box's parameters bounded variables of the relations
    (:func:`lyapcheck.models.classes.map_relations.on_relations_box`)."""
    from lyapcheck.models.classes import map_relations

    return map_relations.run(ctx.model, name, budget, box=ctx.box)


def quadratic_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A quadratic V of the states with ``V(F) <= (1 - mu) V - W`` on the recasting's relations
    (:func:`lyapcheck.models.classes.map_relations.run`)."""
    return _map_relations(ctx, "quadratic", budget)


def sos_gas_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A polynomial V of the states of the searched degrees, on the recasting's relations
    (:func:`lyapcheck.models.classes.map_relations.run`)."""
    return _map_relations(ctx, "sos_gas", budget)


def sos_bound_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A V of the states with ``V(F(x, d)) <= lam V(x) + 1 - lam`` on the recasting's relations and the
    disturbances' box, and each output's ``y^2 <= B + V - 1``
    (:func:`lyapcheck.models.classes.map_relations_bounds.run`); over a box, one bound for every value of it (the
    box's parameters bounded variables of the relations)."""
    from lyapcheck.models.classes import map_relations_bounds

    return map_relations_bounds.run(ctx.model, budget, box=ctx.box)


def barrier_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A barrier of the states with ``B(F) <= lam B`` on the recasting's relations
    (:func:`lyapcheck.models.classes.map_relations_safety.run_barrier`); over a box, one B for every value of
    it (the box's parameters bounded variables of the relations), refuted at a corner or the centre."""
    from lyapcheck.models.classes import map_relations_safety, map_relations_safety_box

    box = ctx.box
    refute = None if box is None else (lambda: map_relations_safety_box.refute("barrier", ctx.model, box))
    return map_relations_safety.run_barrier(ctx.model, budget, box=box, refute=refute)


def reach_avoid_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A V of the states falling by eps per step outside the goal on the recasting's relations
    (:func:`lyapcheck.models.classes.map_relations_reach.run`); refuted by an unsafe iterate proved before any is
    in the goal; over a box, one V for every value of it, refuted at a corner or the centre."""
    from lyapcheck.models.classes import map_relations_reach, map_relations_safety_box

    box = ctx.box
    refute = None if box is None else (lambda: map_relations_safety_box.refute("reach_avoid", ctx.model, box))
    return map_relations_reach.run(ctx.model, budget, box=box, refute=refute)


def roa_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """A quadratic V's largest level proved by ball arithmetic on the true map
    (:func:`lyapcheck.models.classes.discrete_functions.roa`); over a box, with its parameters as balls
    (:func:`lyapcheck.models.classes.discrete_functions_box.roa`)."""
    from lyapcheck.models.classes import discrete_functions, discrete_functions_box

    if ctx.box is not None:
        return discrete_functions_box.roa(ctx.model, ctx.box, budget)
    return discrete_functions.roa(ctx.model, budget)


def candidate_map_functions(ctx: "MapFunctionsRun", budget: "Budget") -> "ConditionResult":
    """The user's quadratic V, its largest level proved by ball arithmetic on the true map
    (:func:`lyapcheck.models.classes.discrete_functions.candidate`); over a box, for every value of it
    (:func:`lyapcheck.models.classes.discrete_functions_box.candidate`)."""
    from lyapcheck.models.classes import discrete_functions, discrete_functions_box

    if ctx.box is not None:
        return discrete_functions_box.candidate(ctx.model, ctx.box, budget)
    return discrete_functions.candidate(ctx.model, budget)


# -- a sampled-data loop (lyapcheck.models.classes.sampled) ---------------------------------------------------

def linearization_sampled(ctx: "SampledRun", budget: "Budget") -> "ConditionResult":
    """The Jacobian over one sampling period, decided in ball arithmetic
    (:func:`lyapcheck.models.classes.sampled.linearization`)."""
    from lyapcheck.models.classes import sampled

    return sampled.linearization(ctx.model)


def roa_sampled(ctx: "SampledRun", budget: "Budget") -> "ConditionResult":
    """A region of attraction of the sampled-data loop on its true flow over one period
    (:func:`lyapcheck.models.classes.sampled_regions.roa`)."""
    from lyapcheck.models.classes import sampled_regions

    return sampled_regions.roa(ctx.model, budget)


__all__ = ["linearization_map", "linearization_map_box", "quadratic_map", "sos_gas_map", "roa_map", "candidate_map",
           "barrier_map", "reach_avoid_map", "sos_bound_map",
           "linearization_map_functions", "quadratic_map_functions", "sos_gas_map_functions", "roa_map_functions",
           "candidate_map_functions", "sos_bound_map_functions", "barrier_map_functions",
           "reach_avoid_map_functions", "linearization_sampled", "roa_sampled"]

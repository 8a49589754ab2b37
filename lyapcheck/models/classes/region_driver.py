"""The one driver of a continuous region class (``roa``, ``candidate``) on any loop (issue 41, item 1).

A class is an ordered list of :class:`Route`: each proves a set (or, for ``candidate``, GAS) by one
engine (SOS on the cleared field or on the recasting's relations, ball arithmetic on the true field,
validated integration) and says in one line why it did not. :func:`drive` is what every class does
with that list, once:

- the routes run in order within the class's budget;
- the result kept is the first certified one (:data:`FIRST`), or, with :data:`LARGEST_SHARE`, the
  certified one covering the largest share of the loop's simulated region (routes marked ``compare``
  then run after a certified one);
- a route that runs out of time (:class:`~lyapcheck.models.engines.search.BudgetExhausted`) ends the
  search: ``inconclusive`` in the words of :func:`~lyapcheck.models.engines.reasons.out_of_time`, or,
  with a result already kept, that result;
- every route's reason is a line of the ``not_certified`` result's detail, which the class words
  (its ``failed``);
- the kept set is simulated on the true loop once (:class:`SimulatedLoop`; a GAS claim has no set; a
  route that compared sets by their simulated shares returns its set simulated already).

What a route returns:

=====================================  ============================================================
``ConditionResult``, ``certified``     a proof: kept (first) or compared (largest share)
``ConditionResult``, any other status  the class's answer as the route gives it (a refusal, such as a
                                       denominator not proved positive: no later route changes it)
:class:`Ends`                          ``not_certified`` in the route's own sentence, the lines so far
                                       its detail (what every later route needs is missing)
``str``                                why this route proved nothing: the next route runs
=====================================  ============================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Final, Literal, Protocol, Sequence, Union

from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult

#: the policies of :func:`drive`: the first certified route's result, or the largest simulated share
FIRST: Final = "first"
LARGEST_SHARE: Final = "largest share"
Policy = Literal["first", "largest share"]


@dataclass(frozen=True)
class Ends:
    """A route's ``not_certified`` answer that ends the class (module docstring): ``sentence`` and the
    ``steps`` to try next (:func:`~lyapcheck.models.engines.reasons.reason`), ``line`` its own detail line
    after the earlier routes' (none: the sentence says it all)."""

    sentence: str
    steps: tuple[str, ...]
    line: str | None = None


Outcome = Union[ConditionResult, Ends, str]


@dataclass(frozen=True)
class Route:
    """One engine of a region class: its ``name`` (the detail's words where it runs out of time), its
    ``run(budget)`` (an :data:`Outcome`), and whether it may run after a certified route's result to
    compare with it (``compare``; policy :data:`LARGEST_SHARE` only)."""

    name: str
    run: Callable[[Budget], Outcome]
    compare: bool = False


class SimulatedLoop(Protocol):
    """What the driver needs of a loop: its certified set simulated on the true loop (figures added to
    ``result.numbers``, a start in the set that does not converge checked again) and the share of the
    simulated region of attraction a certified set covers (for :data:`LARGEST_SHARE`)."""

    def simulate(self, result: ConditionResult) -> None:
        ...

    def share(self, result: ConditionResult) -> float:
        ...


@dataclass(frozen=True)
class OutOfTime:
    """How the class says it ran out of time: what it searched for and the steps to try next
    (:func:`~lyapcheck.models.engines.reasons.out_of_time`)."""

    thing: str
    steps: tuple[str, ...]


def drive(name: str, routes: Sequence[Route], budget: Budget, loop: SimulatedLoop,
          failed: Callable[[list[str]], ConditionResult], late: OutOfTime, policy: Policy = FIRST,
          tried: list[str] | None = None) -> ConditionResult:
    """Class ``name`` by its ``routes`` (module docstring). ``failed(tried)``: the class's ``not_certified``
    result from every route's reason, in order; ``late``: its words when the time runs out; ``tried``: the
    list the reasons are appended to (given, a route may quote the reasons of the routes before it)."""
    if policy not in (FIRST, LARGEST_SHARE):
        raise ValueError(f"policy must be {FIRST!r} or {LARGEST_SHARE!r}; got {policy!r}")
    tried = [] if tried is None else tried
    kept: ConditionResult | None = None
    kept_share = 0.0
    for route in routes:
        if kept is not None and (policy == FIRST or not route.compare):
            continue
        try:
            found = route.run(budget)
        except BudgetExhausted as exc:
            if kept is not None:  # (a comparing route cut short: the proof in hand stands)
                break
            why = reasons.out_of_time(late.thing, budget.seconds, [*tried, f"{route.name}: {exc}"], late.steps)
            return ConditionResult(name, "inconclusive", why.summary, numbers=why.numbers(), property="ROA")
        if isinstance(found, str):
            tried.append(found)
            continue
        if kept is not None and (isinstance(found, Ends) or found.status != "certified"):
            continue  # (a comparing route that proved nothing: the proof in hand stands)
        if isinstance(found, Ends):
            why = reasons.reason(found.sentence, found.steps, [*tried, *([found.line] if found.line else [])])
            return ConditionResult(name, "not_certified", why.summary, numbers=why.numbers(), property="ROA")
        if found.status != "certified":
            return found
        # (largest share: a later route's result kept only where it covers more; GAS covers everything)
        share = 0.0 if policy == FIRST else 1.0 if found.proves() != "ROA" else loop.share(found)
        if kept is None or share > kept_share:
            kept, kept_share = found, share
    if kept is None:
        return failed(tried)
    # (a set to simulate; a GAS claim holds everywhere; a route that compared sets by their shares has
    # simulated the one it returns already)
    if kept.proves() == "ROA" and "simulated_starts" not in kept.numbers:
        loop.simulate(kept)
    return kept


__all__ = ["FIRST", "LARGEST_SHARE", "Policy", "Ends", "Outcome", "Route", "SimulatedLoop",
           "OutOfTime", "drive"]

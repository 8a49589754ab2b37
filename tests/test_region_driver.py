"""The one driver of the continuous region classes (issue 41, item 1: ``roa`` and ``candidate`` on any loop):
its routes in order, the policy of the result kept, the reasons stated, the time limit, the set simulated once.

The routes here are stand-ins (each returns what a route returns: a certified result, a reason, an end); what the
real routes prove is tested with the classes (test_regions_relations, test_candidate_box, test_interval_region)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest

from lyapcheck.models.classes.region_driver import FIRST, LARGEST_SHARE, Ends, OutOfTime, Route, drive
from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult

LATE = OutOfTime("a region of attraction", ("time", "domain"))


@dataclass
class Loop:
    """A loop whose simulation records what it was asked to simulate; a set's share is its ``share`` figure."""

    simulated: list[ConditionResult] = field(default_factory=list)

    def simulate(self, result: ConditionResult) -> None:
        self.simulated.append(result)
        result.numbers["roa_share"] = result.numbers["share"]

    def share(self, result: ConditionResult) -> float:
        return float(result.numbers["share"])


def region(share: float, prop: str = "ROA") -> ConditionResult:
    return ConditionResult("roa", "certified", f"a set covering {share}", numbers={"share": share}, property=prop)


def failed(tried: list[str]) -> ConditionResult:
    return ConditionResult("roa", "not_certified", "none", numbers={"detail": list(tried)}, property="ROA")


def route(name: str, outcome: Any, ran: list[str], compare: bool = False) -> Route:
    def run(budget: Budget) -> Any:
        ran.append(name)
        if isinstance(outcome, BaseException):
            raise outcome
        return outcome
    return Route(name, run, compare)


def test_first_certified_wins_later_routes_do_not_run_and_the_kept_set_is_simulated_once() -> None:
    ran: list[str] = []
    loop = Loop()
    small, large = region(0.2), region(0.9)
    routes = [route("a", "a: nothing", ran), route("b", small, ran), route("c", large, ran, compare=True)]
    kept = drive("roa", routes, Budget(10.0, "test"), loop, failed, LATE)
    assert kept is small and ran == ["a", "b"]
    assert loop.simulated == [small] and small.numbers["roa_share"] == 0.2


def test_largest_share_runs_the_comparing_routes_and_keeps_the_set_covering_most() -> None:
    ran: list[str] = []
    loop = Loop()
    small, large, other = region(0.2), region(0.9), region(0.95)
    routes = [route("b", small, ran), route("c", large, ran, compare=True), route("d", other, ran)]
    kept = drive("roa", routes, Budget(10.0, "test"), loop, failed, LATE, policy=LARGEST_SHARE)
    assert kept is large and ran == ["b", "c"]  # ("d" does not compare: not run after a proof)
    assert loop.simulated == [large]
    # a comparing route that proves nothing, ends or refuses leaves the proof in hand
    ran.clear()
    refusal = ConditionResult("roa", "not_applicable", "a denominator is not proved positive")
    routes = [route("b", small, ran), route("c", refusal, ran, compare=True),
              route("d", Ends("no V", ("candidate",)), ran, compare=True), route("e", "e: none", ran, compare=True)]
    assert drive("roa", routes, Budget(10.0, "test"), Loop(), failed, LATE, policy=LARGEST_SHARE) is small
    assert ran == ["b", "c", "d", "e"]


def test_every_reason_in_order_reaches_the_class_sentence_when_nothing_is_proved() -> None:
    ran: list[str] = []
    loop = Loop()
    result = drive("roa", [route("a", "a: no level", ran), route("b", "b: too large", ran)], Budget(10.0, "test"),
                   loop, failed, LATE)
    assert result.status == "not_certified" and result.numbers["detail"] == ["a: no level", "b: too large"]
    assert loop.simulated == []


def test_an_end_stops_the_routes_and_states_the_lines_so_far() -> None:
    ran: list[str] = []
    end = Ends("no region: the linearization gives no V", ("candidate",), "no Jacobian")
    result = drive("roa", [route("a", "a: no level", ran), route("b", end, ran), route("c", region(0.5), ran)],
                   Budget(10.0, "test"), Loop(), failed, LATE)
    assert ran == ["a", "b"] and result.status == "not_certified"
    assert result.summary.startswith("no region: the linearization gives no V; try")
    assert result.numbers["detail"] == ["a: no level", "no Jacobian"]


def test_a_refusal_is_the_class_answer_as_given() -> None:
    ran: list[str] = []
    refusal = ConditionResult("candidate", "not_applicable", "a denominator is not proved positive")
    result = drive("candidate", [route("a", refusal, ran), route("b", region(0.5), ran)], Budget(10.0, "test"),
                   Loop(), failed, LATE)
    assert result is refusal and ran == ["a"]


def test_out_of_time_is_inconclusive_naming_the_limit_and_keeps_a_proof_already_in_hand() -> None:
    ran: list[str] = []
    late = BudgetExhausted("time limit of 10 s reached (lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S)")
    result = drive("roa", [route("a", "a: no level", ran), route("the SOS level", late, ran)], Budget(10.0, "test"),
                   Loop(), failed, LATE)
    assert result.status == "inconclusive"
    assert result.summary.startswith("the time limit of 10 s was reached while searching for a region of attraction")
    assert "--time-limit" in result.summary
    assert result.numbers["detail"] == ["a: no level", f"the SOS level: {late}"]
    kept = region(0.3)
    loop = Loop()
    result = drive("roa", [route("b", kept, ran), route("c", late, ran, compare=True)], Budget(10.0, "test"), loop,
                   failed, LATE, policy=LARGEST_SHARE)
    assert result is kept and loop.simulated == [kept]


def test_a_gas_claim_is_not_simulated_and_a_policy_is_checked() -> None:
    loop = Loop()
    gas = region(1.0, prop="GAS")
    assert drive("candidate", [route("a", gas, [])], Budget(10.0, "test"), loop, failed, LATE, policy=FIRST) is gas
    assert loop.simulated == []
    with pytest.raises(ValueError, match="policy"):
        drive("roa", [], Budget(10.0, "test"), loop, failed, LATE, policy="best")  # type: ignore[arg-type]

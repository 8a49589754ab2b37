"""Work budgets decide outcomes, the clock only guards (issue 40, item 9: "Same outcome under load").

A search's steps are bounded by counts of solves (:class:`~lyapcheck.models.engines.search.SolveLimit`):
the recast sos_gas search per template (``TEMPLATE_SOLVES``), the recast V-s iteration
(``VS_SOLVES``, ``VS_LEVEL_SOLVES``) and the polynomial roa class's enlarging rounds
(``ROA_ENLARGE_SOLVES``), all in :mod:`lyapcheck.tolerances`. These tests make each budget tiny
(monkeypatch) so that it decides, and run the same search twice: once on the real clock, once on
a clock that makes the machine look thousands of times slower (every reading of the class's
:class:`~lyapcheck.models.engines.search.Budget` is 30 s later than the one before). The outcome, its
reason and the solves made must be the same; under the wall-clock step limits these budgets
replaced, the slow clock cut every step short. The class's time limit itself stays a safety net,
named as one.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import pytest

from lyapcheck import tolerances
from lyapcheck.models.classes import lyapunov, lyapunov_relations, recast_classes as rc
from lyapcheck.models.engines import search as search_module
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.language.modelfile import load_model, parse_any_model
from lyapcheck.models.engines.search import Budget
from lyapcheck.results import ConditionResult
from tests.conftest import ROOT
from tests.recast_loops import PENDULUM

MODELS = ROOT / "examples" / "models"
#: a class time limit no search here comes near, even on the slow clock (the safety net only)
SAFETY_NET_S = 1e7
#: how much later each reading of the slow clock is than the one before, seconds
JUMP_S = 30.0


class SlowClock:
    """A clock whose every reading is :data:`JUMP_S` later than the last: to a wall-clock step
    limit of seconds, every step looks thousands of times slower than it is."""

    def __init__(self) -> None:
        self.readings = 0

    def __call__(self) -> float:
        self.readings += 1
        return time.perf_counter() + JUMP_S * self.readings


def idle_and_loaded(monkeypatch: pytest.MonkeyPatch, run: Callable[[], Any]) -> tuple[Any, Any, SlowClock]:
    """``run()`` on the real clock, then on a :class:`SlowClock` (its readings counted, so that a
    test can show the clock was consulted and did not matter)."""
    idle = run()
    clock = SlowClock()
    with monkeypatch.context() as m:
        m.setattr(search_module, "_now", clock)
        loaded = run()
    return idle, loaded, clock


def programs(result: ConditionResult) -> list[str]:
    return [entry["program"] for entry in result.solver.get("solves", [])]


def sos_gas(loop: Any, budget: Budget) -> ConditionResult:
    """The class sos_gas on a loop with functions (lyapunov.run_relations), at its degrees."""
    return lyapunov_relations.run_relations(loop, budget, "sos_gas", lyapunov.RELATIONS_GAS_DEGREES)


def searched_loop() -> Any:
    """A loop with functions whose sos_gas search is not_certified, and takes more than one solve in a
    template (facial reduction): recast-tanh-neuron."""
    text = (MODELS / "recast-tanh-neuron.toml").read_text()
    return rc.base_loop(parse_any_model(text, "recast-tanh-neuron.toml").system)


def test_a_template_budget_of_solves_decides_sos_gas_whatever_the_clock_says(monkeypatch: pytest.MonkeyPatch) -> None:
    """One solve per template: each template of the recast sos_gas search stops after its first
    solve, the class is not_certified saying so (the constant in the detail), and a clock that
    makes every template look minutes long changes nothing."""
    loop = searched_loop()
    full = sos_gas(loop, Budget(SAFETY_NET_S, "test"))
    monkeypatch.setattr(tolerances, "TEMPLATE_SOLVES", 1)
    idle, loaded, clock = idle_and_loaded(monkeypatch, lambda: sos_gas(loop, Budget(SAFETY_NET_S, "test")))
    assert clock.readings > 3  # the budget's clock was read: it just decided nothing
    for result in (idle, loaded):
        assert result.status == "not_certified", result.summary
        assert "the search's budget of 1 solve per template was spent" in result.summary
        assert "TEMPLATE_SOLVES" not in result.summary  # the constant's name is for the detail
        spent = [line for line in result.numbers["detail"] if "lyapcheck.tolerances.TEMPLATE_SOLVES" in line]
        assert spent and all("budget of 1 solve per template was spent" in line for line in spent)
    assert (loaded.status, loaded.summary, loaded.numbers["detail"]) == (idle.status, idle.summary,
                                                                         idle.numbers["detail"])
    assert programs(loaded) == programs(idle)
    # the budget did the deciding: the default budget's search goes on with more solves
    assert full.status == "not_certified" and len(programs(full)) > len(programs(idle))


def test_the_class_time_limit_is_a_safety_net_named_as_one() -> None:
    """A class whose clock has run out stops at its next solve, inconclusive, and the detail says
    that the wall-clock limit is the safety net (not a work budget)."""
    result = sos_gas(searched_loop(), Budget(0.0, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S"))
    assert result.status == "inconclusive", result.summary
    assert "time limit" in result.summary and "--time-limit" in result.summary
    detail = " ".join(result.numbers["detail"])
    assert "a safety net: lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S" in detail


def pendulum_region(budget_s: float = SAFETY_NET_S) -> ConditionResult:
    from lyapcheck.models.classes.recast_regions import comparison_box, run_roa

    model = parse_any_model(PENDULUM, "pendulum.toml")
    loop = rc.base_loop(model.system)
    return run_roa(loop, rc.linearization(loop), Budget(budget_s, "test"), comparison_box(model, loop),
                   interval=False)


@pytest.mark.slow
def test_the_v_s_iteration_stops_at_its_budget_of_solves_whatever_the_clock_says(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The recast V-s iteration (the route without ball arithmetic) with a budget of 5 solves: it
    stops there, saying so, and keeps the regions it proved; the same region, level and detail on
    a clock that makes each of its steps look minutes long."""
    monkeypatch.setattr(tolerances, "VS_SOLVES", 5)
    idle, loaded, clock = idle_and_loaded(monkeypatch, pendulum_region)
    assert clock.readings > 5
    for result in (idle, loaded):
        assert result.status == "certified", result.summary
        tried = result.numbers["tried"]  # what the class tried, in its JSON
        assert any("the search's budget of 5 solves for the V-s iteration was spent "
                   "(lyapcheck.tolerances.VS_SOLVES)" in line for line in tried), tried
    assert loaded.certificate == idle.certificate
    assert loaded.numbers["tried"] == idle.numbers["tried"]


@pytest.mark.slow
def test_a_level_step_budget_of_solves_ends_the_iteration(monkeypatch: pytest.MonkeyPatch) -> None:
    """A level step of the V-s iteration with a budget of 2 solves (its growth and bisection take
    12 or more): the step keeps the largest level it proved before the budget was spent (the level
    search is monotone, issue 42) and its line names that budget; the region of the linearization's
    V is still proved."""
    monkeypatch.setattr(tolerances, "VS_LEVEL_SOLVES", 2)
    result = pendulum_region()
    assert result.status == "certified", result.summary
    tried = result.numbers["tried"]
    assert any("the search's budget of 2 solves per level step was spent (lyapcheck.tolerances.VS_LEVEL_SOLVES)"
               in line for line in tried), tried


@pytest.mark.slow
def test_the_roa_rounds_stop_at_their_budget_of_solves_whatever_the_clock_says(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The polynomial roa class on the reversed Van der Pol oscillator with a budget of 6 solves
    for its enlarging rounds (its own search takes over a hundred): the rounds stop there and say
    so in the class's history; the certified set is the same on a clock that makes the class look
    hours long (its safety net far beyond either)."""
    monkeypatch.setattr(tolerances, "ROA_ENLARGE_SOLVES", 6)
    model = load_model(MODELS / "van-der-pol-reversed.toml")

    def roa() -> ConditionResult:
        return certify_model(model, classes=("roa",), time_limit_s=SAFETY_NET_S).results["roa"]

    idle, loaded, clock = idle_and_loaded(monkeypatch, roa)
    assert clock.readings > 6
    for result in (idle, loaded):
        assert result.status == "certified", result.summary
        stops = [h["stopped"] for h in result.numbers["rounds"] if "stopped" in h]
        assert stops == ["the search's budget of 6 solves for the enlarging rounds was spent "
                         "(lyapcheck.tolerances.ROA_ENLARGE_SOLVES)"], result.numbers["rounds"]
    assert loaded.certificate == idle.certificate
    assert loaded.numbers["rounds"] == idle.numbers["rounds"]


def test_a_step_budget_counts_the_solves_of_every_search_inside_it() -> None:
    """:meth:`Search.within` nests: an inner step's solves count against the outer budget too, and
    the first budget spent stops the next solve before it starts (no solve is made past it)."""
    from lyapcheck.sos.polynomials import Ring

    outer = search_module.Search(Ring(["x"]), Budget(SAFETY_NET_S, "test")).within(3, "for the test", "OUTER")
    inner = outer.within(10, "per step", "INNER")
    assert inner.log is outer.log and inner.limits[0] is outer.limits[0]
    inner.limits[-1].used = outer.limits[0].used = 3  # as after three solves inside the inner step
    with pytest.raises(search_module.SolvesSpent) as spent:
        inner.solve(None, None)  # type: ignore[arg-type]  # raises before it reads the program
    assert spent.value.limit is outer.limits[0]
    assert str(spent.value) == "the search's budget of 3 solves for the test was spent (OUTER)"
    assert isinstance(spent.value, search_module.BudgetExhausted)  # every class's handler catches it
    assert outer.log == []

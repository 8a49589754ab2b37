"""The level search of a fixed V (issue 42, item 2): monotone (a proved level is never lost because a
larger one failed or the work ran out), and a quadratic V of the linearization always gets a proved
level on the true loop, at 2 states and at 4 (the cart-pole closed with an LQR gain)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from lyapcheck.models.classes import recast_classes as rc
from lyapcheck.models.classes import regions
from lyapcheck.models.classes.claims import covered
from lyapcheck.models.classes.level_search import largest_proved_level
from lyapcheck.models.classes.recast_ball_level import ball_level, state_quadratic
from lyapcheck.models.classes.recast_interval import check_interval
from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search
from lyapcheck.models.language.modelfile import load_any_model, parse_any_model
from tests.recast_loops import PENDULUM, SPRING

CARTPOLE = Path(__file__).parent / "data" / "cartpole-lqr.toml"

THREE_STATES = """
[model]
name = "a pendulum with a first-order actuator"
states = ["theta", "omega", "u"]
[dynamics]
theta = "omega"
omega = "-sin(theta) - omega + u"
u = "-2*u - tanh(omega)"
"""


def search_of(attempt: Any, first: Fraction) -> Any:
    return largest_proved_level(attempt, first, growth=Fraction(4), growth_steps=10, halvings=16, bisections=7)


@pytest.mark.parametrize("truth", [Fraction(5), Fraction(1, 3), Fraction(1, 10 ** 4)])
def test_the_search_returns_the_largest_level_it_proved_and_never_one_that_failed(truth: Fraction) -> None:
    tried: list[Fraction] = []

    def attempt(level: Fraction) -> Fraction | None:
        tried.append(level)
        return level if level <= truth else None

    found = search_of(attempt, Fraction(1))
    assert found.level is not None and found.proof == found.level
    assert found.level == max(t for t in tried if t <= truth)  # the largest proved, kept to the end
    assert found.failed is not None and found.failed > found.level
    assert found.level > truth / 2  # the bisection closed in on the truth from the proved side


def test_a_failure_above_a_proved_level_never_discards_it_even_when_the_checker_is_not_monotone() -> None:
    # proves 1 and 3 but not 4 nor 2: whatever fails later, the search keeps the largest level proved
    proved = {Fraction(1), Fraction(3)}
    found = search_of(lambda level: level if level in proved else None, Fraction(1))
    assert found.level == Fraction(1)
    found = largest_proved_level(lambda level: level if level in proved else None, Fraction(3), growth=Fraction(4),
                                 growth_steps=3, halvings=4, bisections=3)
    assert found.level == Fraction(3)


def test_running_out_of_work_keeps_the_proved_level_and_says_so() -> None:
    def attempt(level: Fraction) -> Fraction | None:
        if level > 1:
            raise BudgetExhausted("the budget of the test")
        return level

    found = search_of(attempt, Fraction(1))
    assert found.level == Fraction(1) and "budget of the test" in found.stopped
    with pytest.raises(BudgetExhausted):  # nothing proved: the exhaustion is the answer
        search_of(attempt, Fraction(2))


def test_the_recast_level_search_keeps_its_proved_level_when_a_larger_attempt_runs_out(monkeypatch: Any) -> None:
    """The real search of ``certify_region`` with real certificates; the level attempts above a threshold
    run out of work (as the class's time limit or a budget of solves would)."""
    model = parse_any_model(SPRING, "spring.toml")
    loop = rc.base_loop(model.system)
    V0 = rc.quadratic_candidate(loop, rc.jacobian(loop))
    assert V0 is not None
    free = regions.certify_region(loop, V0, Search(loop.ring, Budget(60, "test")), "free")
    assert not isinstance(free, str)
    threshold = free.level / 3
    original = regions.relations_level_attempt

    def limited(field: Any, V: Any, F: Any, level: Fraction, search: Any, build: Any) -> Any:
        if level > threshold:
            raise BudgetExhausted("out of work above the threshold")
        return original(field, V, F, level, search, build)

    monkeypatch.setattr(regions, "relations_level_attempt", limited)
    kept = regions.certify_region(loop, V0, Search(loop.ring, Budget(60, "test")), "limited")
    assert not isinstance(kept, str)
    assert 0 < kept.level <= threshold
    assert kept.level * 2 > threshold or kept.level == regions._scale_of(loop, V0)  # the largest below it tried


@pytest.mark.parametrize("text", [SPRING, PENDULUM, THREE_STATES], ids=["spring", "pendulum", "three-states"])
def test_a_quadratic_v_of_the_linearization_gets_a_level_by_ball_arithmetic_and_verify_rechecks_it(text: str) -> None:
    model = parse_any_model(text, "loop.toml")
    loop = rc.base_loop(model.system)
    J = rc.jacobian(loop)
    assert not isinstance(J, str)
    V0 = state_quadratic(loop, J)  # z^T P z in the states themselves (an angle too)
    assert V0 is not None
    result = ball_level(loop, V0, Budget(120, "test"), "candidate", "the linearization")
    assert not isinstance(result, str), result
    assert result.status == "certified" and result.certificate["boundary"] == "exact"
    assert result.numbers["level"] >= result.numbers["local_level"] > 0
    stated = {"certificate": result.certificate, "level": result.numbers["level"],
              "summary": covered(None, result.summary)}
    ok, why = check_interval(loop, stated)
    assert ok, why
    # a level far above the proved one is refused by the same check (the faces or the decrease fail)
    inflated = dict(result.certificate, level=str(Fraction(result.certificate["level"]) * 10 ** 6))
    ok, _ = check_interval(loop, {**stated, "certificate": inflated, "level": None})
    assert not ok


def test_the_cartpole_lqr_cost_to_go_gets_a_level_at_4_states(monkeypatch: Any) -> None:
    """At 4 states the SOS level program is too large (said so, not "no level found"), and the ball
    arithmetic proves the exact local level; the larger attempts are cut by a small count of cells."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes import recast_regions

    model = load_any_model(CARTPOLE, candidate=CARTPOLE.read_text().splitlines()[5].lstrip("# "))
    loop = rc.for_v(recast_regions.proved_loop(model, 60), model.candidate_v)
    V = model.candidate_v
    why = regions.certify_region(loop, V, Search(loop.ring, Budget(60, "test")), "the LQR cost-to-go")
    assert isinstance(why, str) and "not built" in why and "no level found" not in why
    monkeypatch.setattr(tolerances, "BALL_LEVEL_CELLS", 200)
    result = ball_level(loop, V, Budget(120, "test"), "candidate", "the LQR cost-to-go")
    assert not isinstance(result, str), result
    assert result.status == "certified" and result.numbers["level"] >= result.numbers["local_level"] > 0
    ok, why = check_interval(loop, {"certificate": result.certificate, "level": result.numbers["level"],
                                    "summary": covered(None, result.summary)})
    assert ok, why


def test_other_steps_bracket_the_truth_geometrically_and_stop_where_asked() -> None:
    """``LevelSteps`` (regions.largest_level's search): down by quarters from a failed first level, a geometric
    bisection, and ``more`` ending it at a relative width; never a level above the truth, never lost."""
    import math

    from lyapcheck.models.classes.level_search import LevelSteps

    truth = Fraction(3, 1000)
    tried: list[Fraction] = []

    def attempt(level: Fraction) -> Fraction | None:
        tried.append(level)
        return level if level <= truth else None

    def more(lo: Fraction | None, hi: Fraction | None) -> bool:
        return hi is None or lo is None or (hi - lo) > hi / 100

    steps = LevelSteps(down=lambda c: c / 4, between=lambda lo, hi: Fraction(math.sqrt(lo * hi)).limit_denominator(10**9),
                       above=Fraction(1), more=more)
    found = largest_proved_level(attempt, Fraction(1), growth=Fraction(8), growth_steps=1, halvings=30,
                                 bisections=30, steps=steps)
    assert tried[:5] == [Fraction(1), Fraction(1, 4), Fraction(1, 16), Fraction(1, 64), Fraction(1, 256)]
    assert found.level is not None and found.level <= truth and found.failed is not None
    assert found.failed - found.level <= found.failed / 100  # stopped by ``more``, at the width asked
    assert found.level == max(t for t in tried if t <= truth)
    # a first level proved with ``above`` as the bracket's top: the bisection starts between them
    tried.clear()
    found = largest_proved_level(attempt, Fraction(1, 1000), growth=Fraction(8), growth_steps=1, halvings=30,
                                 bisections=30, steps=LevelSteps(above=Fraction(1, 100), more=more))
    assert tried[0] == Fraction(1, 1000) and Fraction(1, 1000) < tried[1] < Fraction(1, 100)
    assert found.level is not None and truth * Fraction(99, 100) <= found.level <= truth


def test_a_failure_that_names_a_smaller_failing_level_lowers_the_bracket_at_once() -> None:
    from lyapcheck.models.classes.level_search import LevelSteps

    truth, refuted_from = Fraction(9), Fraction(10)  # levels above 9 fail; each failure shows a point at V = 10

    def run(failed_at: Any) -> tuple[Any, list[Fraction]]:
        tried: list[Fraction] = []

        def attempt(level: Fraction) -> Fraction | None:
            tried.append(level)
            return level if level <= truth else None

        found = largest_proved_level(attempt, Fraction(1), growth=Fraction(4), growth_steps=10, halvings=0,
                                     bisections=3, steps=LevelSteps(failed_at=failed_at))
        return found, tried

    plain, plain_tried = run(None)
    lowered, lowered_tried = run(lambda c: min(c, refuted_from))
    # without it the bracket is (4, 16] and the middles are 10, 7, 8.5; with it (4, 10]: 7, 8.5, 9.25
    assert plain_tried[:3] == lowered_tried[:3] == [1, 4, 16]
    assert plain.failed == 10 and lowered.failed == 9.25  # (the plain one failed at its first middle, 10)
    assert all(t < refuted_from for t in lowered_tried[3:]) and any(t >= refuted_from for t in plain_tried[3:])
    assert lowered.level is not None and plain.level is not None and lowered.level >= plain.level
    assert lowered.level == max(t for t in lowered_tried if t <= truth)


def test_a_failing_level_below_a_proved_one_does_not_move_the_bracket_under_it() -> None:
    from lyapcheck.models.classes.level_search import LevelSteps

    def attempt(level: Fraction) -> Fraction | None:
        return level if level <= 6 else None

    # a route's smaller failing level at or below a proved level (a float's rounding) is ignored
    found = largest_proved_level(attempt, Fraction(1), growth=Fraction(4), growth_steps=10, halvings=0,
                                 bisections=3, steps=LevelSteps(failed_at=lambda c: Fraction(2)))
    assert found.level is not None and found.level > 4 and found.failed is not None and found.failed > found.level


def test_the_jumped_search_caps_only_the_sampled_level_and_grows_from_the_local_one_after_it_fails() -> None:
    from lyapcheck.models.classes.recast_ball_level import jumped_search

    calls: list[tuple[Fraction, int | None]] = []

    def attempt(level: Fraction, cap: int | None = None) -> Fraction | None:
        calls.append((level, cap))
        return level if level <= Fraction(1, 100) else None  # the sampled level 1 is far too large

    found = jumped_search(attempt, Fraction(1, 10 ** 6), Fraction(1), lambda x: x, jump_cells=123)
    assert calls[1] == (Fraction(1), 123)  # the sampled level, within the jump's cells
    assert all(cap is None for level, cap in calls if level != 1)  # every other attempt with the whole cells
    assert found.level is not None and Fraction(1, 400) < found.level <= Fraction(1, 100)
    assert found.level == max(level for level, _ in calls if level <= Fraction(1, 100))

"""``roa``'s SOS route at 4 to 6 states with the shaped quadratic V (issue 42,
:func:`lyapcheck.models.classes.recast_regions.shaped_relations`): the level search from the V's sampled
critical level loses no level the search would prove, the V keeps the loop's sign symmetries, and the
class keeps the largest of the sets it proved (the linearization's and the shaped V's on the relations,
the shaped V's by ball arithmetic), whose certificate ``verify`` proves again."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np
import pytest

from lyapcheck import tolerances
from lyapcheck.models.classes import recast_classes as rc
from lyapcheck.models.classes import recast_regions, regions
from lyapcheck.models.classes.level_search import largest_proved_level
from lyapcheck.models.classes.recast_classes import _dyadic
from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import RecastModel

#: a damped pendulum driving a damped oscillator through a product (4 states, one angle): the
#: linearization's V decreases only on a thin ellipsoid (about 2 % of the box at its proved level), and
#: the loop is invariant under (a, u) -> -(a, u) with (b, w) kept
DRIVEN = """
[model]
name = "a pendulum driving an oscillator"
states = ["a", "u", "b", "w"]
[dynamics]
a = "u"
u = "-sin(a) - 2*u"
b = "w"
w = "-b - w/5 - a*u"
[domain]
a = [-1, 1]
u = [-1, 1]
b = [-1, 1]
w = [-1, 1]
"""
BOX = (-np.ones(4), np.ones(4))


def driven() -> tuple[Any, Any]:
    model = parse_any_model(DRIVEN, "driven.toml")
    assert isinstance(model, RecastModel)  # (a loop with functions: sin)
    loop = rc.base_loop(model.system)
    J = rc.jacobian(loop)
    assert not isinstance(J, str)
    return loop, J


def critical_search(attempt: Any, critical: float) -> Any:
    plan = regions.CRITICAL_PLAN
    return largest_proved_level(attempt, regions.critical_start(critical), growth=plan.growth,
                                growth_steps=plan.growth_steps, halvings=plan.halvings,
                                bisections=plan.bisections, rounded=_dyadic)


@pytest.mark.parametrize("ratio", [2.0 ** -14, 1 / 50, 0.3, 0.7, 1.0, 1.9, 9.0, 60.0])
def test_the_search_from_the_critical_level_does_not_lose_a_level_it_would_prove(ratio: float) -> None:
    """Whatever the sampled critical level says (the true largest level from 2^-14 to 60 times it), the
    search started at half of it proves a level within 1/64 (and the 12-bit rounding) of the largest one,
    never one that fails; the default search from a small level gets no more."""
    critical = 1.37
    truth = Fraction(critical * ratio)

    def attempt(level: Fraction) -> Fraction | None:
        return level if level <= truth else None

    found = critical_search(attempt, critical)
    assert found.level is not None and found.level <= truth
    assert found.level >= truth * (1 - Fraction(1, 2 ** regions.CRITICAL_PLAN.bisections) - Fraction(1, 2 ** 10))
    default = regions.LevelPlan()
    before = largest_proved_level(attempt, Fraction(1, 1000), growth=default.growth,
                                  growth_steps=default.growth_steps, halvings=default.halvings,
                                  bisections=default.bisections, rounded=_dyadic)
    assert before.level is not None
    assert found.level >= before.level * (1 - Fraction(1, 2 ** regions.CRITICAL_PLAN.bisections))


def test_a_search_cut_short_keeps_the_level_it_proved_from_the_critical_start() -> None:
    """Monotone: the work running out above the first level leaves that level, said so."""
    first = regions.critical_start(1.0)

    def attempt(level: Fraction) -> Fraction | None:
        if level > first:
            raise BudgetExhausted("the test's solves were spent")
        return level

    found = critical_search(attempt, 1.0)
    assert found.level == first and "test's solves" in found.stopped


def test_the_shaped_v_keeps_the_loops_sign_symmetry_and_its_level_is_proved_from_its_critical_start() -> None:
    loop, J = driven()
    characters = regions.state_characters(loop)
    assert characters[0] == characters[1] != characters[2] == characters[3]
    design = recast_regions.shaped_design(loop, J, Budget(120, "test"), BOX)
    assert not isinstance(design, str), design
    search = Search(loop.ring, Budget(120, "test"))
    found = recast_regions.shaped_relations(loop, design, search, BOX)
    assert isinstance(found, regions.Region), found
    from lyapcheck.models.engines.interval_region import quadratic_form

    P = quadratic_form(loop.ring, found.V, loop.n)
    assert P is not None
    assert all(P[i][j] == 0 for i in (0, 1) for j in (2, 3))  # no entry couples the two characters
    solves = len(search.log)
    assert 0 < solves <= tolerances.SHAPED_RELATIONS_SOLVES
    # the default search of the same V from a tenth of a state: no larger level, more solves
    default = Search(loop.ring, Budget(120, "test"))
    free = regions.certify_region(loop, found.V, default, "default")
    assert isinstance(free, regions.Region), free
    assert found.level >= free.level * (1 - Fraction(1, 2 ** regions.CRITICAL_PLAN.bisections))
    assert solves < len(default.log)
    # the linearization's V covers far less of the box than the shaped V's proved set
    V0 = rc.quadratic_candidate(loop, J)
    assert V0 is not None
    linear = regions.certify_region(loop, V0, Search(loop.ring, Budget(120, "test")), "linear")
    assert isinstance(linear, regions.Region), linear
    assert regions.box_share(loop, found, BOX) > 2 * regions.box_share(loop, linear, BOX)


def test_a_budget_spent_before_any_level_is_said_in_one_line(monkeypatch: Any) -> None:
    loop, J = driven()
    design = recast_regions.shaped_design(loop, J, Budget(120, "test"), BOX)
    assert not isinstance(design, str), design
    monkeypatch.setattr(tolerances, "SHAPED_RELATIONS_SOLVES", 1)
    why = recast_regions.shaped_relations(loop, design, Search(loop.ring, Budget(120, "test")), BOX)
    assert isinstance(why, str) and "SHAPED_RELATIONS_SOLVES" in why


@pytest.mark.slow
def test_the_route_keeps_the_largest_proved_set_and_verify_proves_it_again(monkeypatch: Any, tmp_path: Any) -> None:
    """The class on the 4-state loop: the linearization's V and the shaped V on the relations, then the shaped
    V by ball arithmetic (its cells cut down here: a short test); the set kept covers at least the share of
    every other one, and its certificate passes verify's check."""
    from lyapcheck import api

    monkeypatch.setattr(tolerances, "ELLIPSOID_LEVEL_TOTAL_CELLS", 3000)
    monkeypatch.setattr(tolerances, "ELLIPSOID_JUMP_CELLS", 1500)
    monkeypatch.setattr(tolerances, "BALL_LEVEL_CELLS", 1500)
    path = tmp_path / "driven.toml"
    path.write_text(DRIVEN)
    doc = api.certify(model=str(path), classes="roa").to_json()
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified", roa["summary"]
    assert roa["V_from"] == recast_regions.SHAPED_RELATIONS_LABEL
    lines = roa["tried"]
    linear = [line for line in lines if line.startswith("the linearization (J^T P + P J = -I): level ")]
    prefix = f"{recast_regions.SHAPED_RELATIONS_LABEL}: level "
    shaped = [line[len(prefix):] for line in lines if line.startswith(prefix)]
    assert linear and shaped, lines
    assert roa["level"] == pytest.approx(float(shaped[0].split(" ")[0]), rel=1e-5)
    # the ball-arithmetic proof of the shaped V: not kept, with no larger share than the kept set's
    other = roa["other_quadratic"]
    if "not kept" in other:
        share = other.split("roa_share ")[1].split(" ")[0]
        assert share == "-" or float(share) <= roa["roa_share"]
    refused = [(c.check, c.message) for c in api.verify(doc).checks if not c.ok]
    assert refused == []


def test_a_ball_proof_cut_by_the_clock_keeps_the_sos_set(monkeypatch: Any) -> None:
    """with_shaped: the comparing ball-arithmetic proof running out of time leaves the proved set standing
    (it was an inconclusive class before: the driver saw the exhaustion with no result kept)."""
    loop, J = driven()
    V0 = rc.quadratic_candidate(loop, J)
    assert V0 is not None
    search = Search(loop.ring, Budget(120, "test"))
    region = regions.certify_region(loop, V0, search, "the linearization")
    assert isinstance(region, regions.Region), region
    result = regions.best_region(loop, [region], [], BOX, search)
    assert result.status == "certified"

    def out_of_time(*args: Any, **kwargs: Any) -> Any:
        raise BudgetExhausted("time limit of the test reached")

    monkeypatch.setattr(recast_regions, "shaped_ball_level", out_of_time)
    kept = recast_regions.with_shaped(loop, J, Budget(120, "test"), BOX, result, "a design (test)")
    assert kept is result and "time limit of the test" in kept.numbers["other_quadratic"]


def test_a_quadratic_candidate_at_4_states_is_searched_from_its_critical_level() -> None:
    """``candidate``'s SOS level search of a user's ``z^T S z`` starts from its sampled critical level
    (:func:`recast_regions.critical_plan`); a V that is not a quadratic form in the states, or a loop below 4
    states, keeps the default search."""
    loop, J = driven()
    design = recast_regions.shaped_design(loop, J, Budget(120, "test"), BOX)
    assert not isinstance(design, str), design
    V = recast_regions.state_form(loop, [[Fraction(x).limit_denominator(10 ** 6) for x in row] for row in design.P])
    plan = recast_regions.critical_plan(loop, V, BOX)
    assert plan["plan"] == regions.CRITICAL_PLAN and plan["start"] > 0
    ring = loop.ring
    assert recast_regions.critical_plan(loop, V + ring.gen("a") ** 4, BOX) == {}  # not a quadratic form
    found = regions.region_of_attraction(loop, Budget(120, "test"), [("the candidate", V)], BOX, name="candidate",
                                         **plan)
    assert found.status == "certified", found.summary
    # the same level as the default search's, to its last bisection
    free = regions.certify_region(loop, V, Search(ring, Budget(120, "test")), "default")
    assert isinstance(free, regions.Region), free
    assert Fraction(found.certificate["level"]) >= free.level * (1 - Fraction(1, 2 ** regions.CRITICAL_PLAN.bisections))
    pendulum = rc.base_loop(parse_any_model(PENDULUM_2, "p.toml").system)  # type: ignore[union-attr]
    z = [pendulum.ring.gen(s) for s in pendulum.system.states]
    assert recast_regions.critical_plan(pendulum, z[0] ** 2 + z[1] ** 2, (BOX[0][:2], BOX[1][:2])) == {}


#: a 2-state loop: below the sizes at which the candidate's search starts from the critical level
PENDULUM_2 = """
[model]
name = "a damped pendulum"
states = ["a", "u"]
[dynamics]
a = "u"
u = "-sin(a) - u"
"""

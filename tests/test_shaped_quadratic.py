"""The quadratic V shaped for a large region at 4 to 6 states (issue 42,
:mod:`lyapcheck.models.classes.shaped_quadratic`): a proposal only. Its rational form is kept only when
exactly positive definite; the class keeps it only when ball arithmetic proves a level of it (otherwise the
linearization's V, never a claim of the shaped one); the certificate it gives is the ball-arithmetic kind,
which ``verify``'s check proves again and refuses at an inflated level."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np
import pytest

from lyapcheck import tolerances
from lyapcheck.models.classes import recast_classes as rc
from lyapcheck.models.classes import recast_regions, shaped_quadratic
from lyapcheck.models.classes.claims import covered
from lyapcheck.models.classes.recast_interval import check_interval
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import parse_any_model

#: two pendulums coupled through a spring, one damped strongly and one weakly: the linearization's
#: V (J^T P + P J = -I) is a thin ellipsoid, a loop with functions at 4 states
COUPLED = """
[model]
name = "two coupled pendulums"
states = ["a", "u", "b", "w"]
[dynamics]
a = "u"
u = "-sin(a) - 3*u + (b - a)/2"
b = "w"
w = "-sin(b) - w/5 - (b - a)/2"
[domain]
a = [-1, 1]
u = [-1, 1]
b = [-1, 1]
w = [-1, 1]
"""


def coupled() -> tuple[Any, Any, tuple[Any, Any]]:
    model = parse_any_model(COUPLED, "coupled.toml")
    loop = rc.base_loop(model.system)
    J = rc.jacobian(loop)
    assert not isinstance(J, str)
    return loop, J, (-np.ones(4), np.ones(4))


def test_rational_form_is_exact_and_refuses_what_rounds_to_indefinite() -> None:
    P = np.array([[2.0, 0.3], [0.3, 1.0]])
    R = shaped_quadratic.rational_form(P)
    assert R is not None and R[0][1] == R[1][0] == Fraction(3, 10)
    # positive definite in floats by 1e-9, singular once rounded to 6 digits: refused
    near = np.array([[1.0, 1.0 - 1e-9], [1.0 - 1e-9, 1.0]])
    assert np.min(np.linalg.eigvalsh(near)) > 0
    assert shaped_quadratic.rational_form(near) is None


def test_the_design_improves_the_sampled_share_of_the_box_over_the_linearization() -> None:
    loop, J, box = coupled()
    import time

    shaped = shaped_quadratic.shaped_quadratic(loop, J, box, deadline=time.perf_counter() + 60)
    assert shaped is not None and shaped.rounds >= 1
    assert shaped.improved and shaped.share > shaped.linearization_share
    # the proposal is scaled to its sampled critical level: a sampled point of {V <= 1/2} decreases
    sampler = shaped_quadratic.Sampler(loop, box)
    assert sampler.critical_level(shaped.P) > 0.5


def test_the_design_aims_at_the_converging_samples_when_a_simulation_is_given() -> None:
    """With ``converges``, the targets are the first SHAPE_TARGET_STARTS box samples it calls converging (here
    a ball of radius 1: the design's share is then the share of that ball at the critical level, not the
    box's); where fewer than SHAPE_MIN_TARGETS converge, the box's samples stay the targets."""
    loop, J, box = coupled()
    import time

    def in_ball(starts: np.ndarray) -> np.ndarray:
        return np.sum(starts ** 2, axis=1) <= 1.0

    sampler = shaped_quadratic.Sampler(loop, box, in_ball)
    first = sampler.box_points[:shaped_quadratic.SHAPE_TARGET_STARTS]
    assert sampler.aimed_at == shaped_quadratic.TARGET_SIMULATED
    assert np.array_equal(sampler.targets, first[in_ball(first)])
    shaped = shaped_quadratic.shaped_quadratic(loop, J, box, deadline=time.perf_counter() + 60, converges=in_ball)
    assert shaped is not None and shaped.aimed_at == shaped_quadratic.TARGET_SIMULATED
    assert shaped.share == sampler.share(shaped.P, 1.0)
    assert shaped.share != shaped_quadratic.Sampler(loop, box).share(shaped.P, 1.0)
    none = shaped_quadratic.Sampler(loop, box, lambda starts: np.zeros(len(starts), dtype=bool))
    assert none.aimed_at == shaped_quadratic.TARGET_BOX and none.targets is none.box_points


#: a box long in the angles, short in the rates: the starts score differently and the best sets of the
#: coupled pendulums reach far past its short sides
LOPSIDED = (-np.array([2.5, 0.3, 2.5, 0.3]), np.array([2.5, 0.3, 2.5, 0.3]))


def test_the_best_scored_start_begins_the_rounds(monkeypatch: Any) -> None:
    loop, J, _ = coupled()
    import time

    monkeypatch.setattr(shaped_quadratic, "SHAPE_ROUNDS", 0)  # (the start alone)
    shaped = shaped_quadratic.shaped_quadratic(loop, J, LOPSIDED, deadline=time.perf_counter() + 60)
    assert shaped is not None and shaped.rounds == 0
    # each start scored independently, as the design scores it: the share of the box at its critical level
    Jf = np.array([[float(x) for x in row] for row in J])
    mu = 2 * float(np.min(-np.linalg.eigvals(Jf).real))
    sampler = shaped_quadratic.Sampler(loop, LOPSIDED)
    scores = {}
    for name, P in shaped_quadratic.starts(Jf, mu, LOPSIDED):
        c = sampler.critical_level(P, shaped_quadratic.SHAPE_SCORE_RATE * mu)
        scores[name] = sampler.share(P / c, 1.0)
    assert len(set(scores.values())) > 1  # (the starts differ: the choice is a choice)
    best = max(scores, key=lambda k: scores[k])
    assert shaped.start == best and shaped.share == shaped.start_share == scores[best]
    assert shaped.improved and shaped.share > shaped.linearization_share


@pytest.mark.slow
def test_the_shaped_set_reaches_past_the_box_where_that_covers_more() -> None:
    """The rounds do not keep the set inside the [domain] box (nor inside it widened twice, as before):
    the set kept reaches past the box's short sides, and covers more of the box than the start did."""
    loop, J, _ = coupled()
    import time

    shaped = shaped_quadratic.shaped_quadratic(loop, J, LOPSIDED, deadline=time.perf_counter() + 60)
    assert shaped is not None and shaped.rounds >= 1
    assert shaped.share > shaped.start_share
    extent = np.sqrt(np.diag(np.linalg.inv(shaped.P)))  # {z^T P z <= 1}'s half-width along each state
    assert np.max(extent / LOPSIDED[1]) > 2
    sampler = shaped_quadratic.Sampler(loop, LOPSIDED)
    assert sampler.critical_level(shaped.P) > 0.5


def test_a_shaped_v_whose_proof_fails_is_not_kept(monkeypatch: Any) -> None:
    """A proposed P positive definite but whose V' has no negative definite Hessian at the equilibrium
    (J^T P + P J indefinite): ball arithmetic proves no level, the class keeps the linearization's V."""
    loop, J, box = coupled()
    Jf = np.array([[float(x) for x in row] for row in J])
    bad = np.diag([1.0, 1e-3, 1.0, 1e-3])
    assert np.max(np.linalg.eigvalsh(Jf.T @ bad + bad @ Jf)) > 0
    monkeypatch.setattr(shaped_quadratic, "shaped_quadratic",
                        lambda *a, **k: shaped_quadratic.Shaped(P=bad, share=1.0, linearization_share=0.0, rounds=1,
                                                                improved=True))
    monkeypatch.setattr(tolerances, "BALL_LEVEL_CELLS", 300)
    monkeypatch.setattr(tolerances, "BALL_LEVEL_TOTAL_CELLS", 600)
    result = recast_regions.quadratic_ball_level(loop, J, Budget(120, "test"), box)
    assert not isinstance(result, str), result
    assert result.status == "certified"
    assert result.numbers["V_from"].startswith("the linearization")
    assert "shaped" in result.numbers["other_quadratic"] and "Hessian" in result.numbers["other_quadratic"]


@pytest.mark.slow
def test_the_larger_quadratic_set_is_kept_and_verify_rechecks_the_shaped_one(monkeypatch: Any) -> None:
    loop, J, box = coupled()
    monkeypatch.setattr(tolerances, "BALL_LEVEL_CELLS", 2000)
    monkeypatch.setattr(tolerances, "BALL_LEVEL_TOTAL_CELLS", 4000)
    monkeypatch.setattr(tolerances, "ELLIPSOID_LEVEL_TOTAL_CELLS", 4000)
    result = recast_regions.quadratic_ball_level(loop, J, Budget(300, "test"), box)
    assert not isinstance(result, str), result
    assert result.status == "certified" and result.certificate["kind"] == "interval"
    assert result.certificate["boundary"] == "exact"
    kept = result.numbers["V_from"]
    other = result.numbers["other_quadratic"]
    assert "not kept" in other
    # the kept one covers at least the other's share of the simulated region (the rule of the choice)
    other_share = other.split("roa_share ")[1].split(" ")[0]
    if other_share != "-":
        assert result.numbers.get("roa_share", 0.0) >= float(other_share)
    assert kept.startswith(("a quadratic V shaped", "the linearization")), (kept, other)
    # the shaped V's own proof, whichever the rule kept: a certified set that verify re-proves, and refuses inflated
    shaped = recast_regions.shaped_ball_level(loop, J, Budget(300, "test"), box)
    assert not isinstance(shaped, str), shaped
    assert shaped.numbers["V_from"].startswith("a quadratic V shaped")
    shaping = shaped.numbers["shaping"]
    assert shaping["aimed_at"] == shaped_quadratic.TARGET_SIMULATED
    assert shaping["sampled_share"] >= shaping["linearization_sampled_share"]  # (both 1.0 here: all converge)
    result = shaped
    stated = {"certificate": result.certificate, "level": result.numbers["level"],
              "summary": covered(None, result.summary)}
    ok, why = check_interval(loop, stated)
    assert ok, why
    inflated = dict(result.certificate, level=str(Fraction(result.certificate["level"]) * 10 ** 4))
    ok, _ = check_interval(loop, {**stated, "certificate": inflated, "level": None})
    assert not ok


def test_below_four_states_the_linearization_alone_is_tried(monkeypatch: Any) -> None:
    from tests.recast_loops import PENDULUM

    model = parse_any_model(PENDULUM, "pendulum.toml")
    loop = rc.base_loop(model.system)
    J = rc.jacobian(loop)

    def never(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the shaped V is tried at 4 to 6 states only")

    monkeypatch.setattr(shaped_quadratic, "shaped_quadratic", never)
    result = recast_regions.quadratic_ball_level(loop, J, Budget(60, "test"), (-np.ones(2) * 3, np.ones(2) * 3))
    assert not isinstance(result, str) and result.numbers["V_from"].startswith("the linearization")
    assert "other_quadratic" not in result.numbers

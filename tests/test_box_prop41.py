"""Proposition 4.1's conditions over a box: one P at the vertices covers every gain set, and a
refuted corner refutes the box."""

from __future__ import annotations

import random
from fractions import Fraction

import pytest
import sympy as sp

from lyapcheck import exact, verify
from lyapcheck.answers import answers_of
from lyapcheck.api import certify_box
from lyapcheck.paper.boxes.prop41 import box_vertices, certify_prop41_box, verify_prop41_box
from lyapcheck.paper.boxes.box import corner_problems, parse_box, problem_at_point
from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions import prop41
from lyapcheck.paper.params import problem_from_sources
from symbolic import _generated
from tests.conftest import PAPER_TOML

#: the paper's gains with a slow LOS speed (4 mm/s in the paper): eq. stabCond is feasible there
SLOW_BOX = ["alpha_d=540..660", "k_d=0.1..0.2", "los_speed=0.05 mm/s..0.1 mm/s"]


@pytest.mark.parametrize("dynamics", ["derived", "printed"])
def test_the_entries_the_vertices_span_are_monomials(dynamics: str) -> None:
    """The covering argument needs a11, a12, a22, g = rho_sup and e = |E_0| monotone in every
    parameter: each is a signed monomial in the positive parameters (on the derivation)."""
    names = ("alpha_d", "sigma0", "k_d", "delta_los", "los_speed", "e11", "e11_hat")
    symbols = {n: sp.Symbol(n, positive=True) for n in names}
    data = getattr(_generated, dynamics)(**symbols)
    A = data["A"]
    assert A[1][0] == 0
    for expr in (A[0][0], A[0][1], A[1][1], data["rho_sup"], data["E"][0]):
        coefficient, rest = sp.sympify(expr).as_coeff_Mul()
        powers = rest.as_powers_dict()
        assert coefficient != 0 and all(base in symbols.values() and exponent.is_integer
                                        for base, exponent in powers.items() if base != 1), expr


@pytest.fixture(scope="module")
def problem():  # type: ignore[no-untyped-def]
    return problem_from_sources(PAPER_TOML, {})


def test_a_certified_box_holds_at_interior_gain_sets_and_rechecks(problem) -> None:  # type: ignore[no-untyped-def]
    box = parse_box(SLOW_BOX)
    result = certify_prop41_box(problem, box)
    assert result["status"] == "certified", result["summary"]
    assert verify_prop41_box(problem, box, "derived", result)[0]
    P = exact.from_json(result["certificate"]["P"])
    rng = random.Random(7)
    for _ in range(5):  # the box's P at gain sets strictly inside it, with their own exact dynamics
        point = {name: lo + Fraction(rng.randint(1, 999), 1000) * (hi - lo) for name, lo, hi in box.bounds}
        system = build_system(problem_at_point(problem, point), "derived")
        assert prop41.exact_check(system, P, iss=False)[0]
    # the vertices are the product of the entries' ranges over the corners
    systems = [build_system(p, "derived") for p in corner_problems(problem, box)]
    assert len(box_vertices(systems, iss=False)) == 16  # a11, a12, a22, g vary; e = 0 for the GES form


def test_tampering_and_a_wider_box_fail_the_recheck(problem) -> None:  # type: ignore[no-untyped-def]
    box = parse_box(SLOW_BOX)
    result = certify_prop41_box(problem, box)
    assert result["status"] == "certified"
    forged = {**result, "certificate": {**result["certificate"], "P": [["1", "0"], ["0", "-1"]]}}
    assert not verify_prop41_box(problem, box, "derived", forged)[0]
    wider = parse_box(["alpha_d=540..660", "k_d=0.1..0.2", "los_speed=0.05 mm/s..0.2 mm/s"])
    ok, why = verify_prop41_box(problem, wider, "derived", result)
    assert not ok and "vertices" in why
    assert not verify_prop41_box(problem, box, "derived", result, iss=True)[0]  # the other variant


def test_a_box_around_the_papers_gains_is_refuted_at_a_corner_and_verify_rechecks_it() -> None:
    done = certify_box(PAPER_TOML, ["alpha_d=540..660", "k_d=0.1..0.2"], classes="prop41_ges,prop41_iss")
    doc = done.to_json()
    for cls in ("prop41_ges", "prop41_iss"):
        assert doc["conditions"][cls]["status"] == "refuted"
    assert verify(doc).valid
    # a refuting point outside the box, or a point of the box the bound does not refute, is rejected
    outside = {**doc["conditions"]["prop41_ges"]["refutation"], "point": {"alpha_d": "700", "k_d": "1/10"}}
    doc["conditions"]["prop41_ges"]["refutation"] = outside
    assert not verify(doc).valid
    slow = certify_box(PAPER_TOML, SLOW_BOX, classes="prop41_ges").to_json()
    assert slow["conditions"]["prop41_ges"]["status"] == "certified" and slow["verdict"] == "certified"
    problem = problem_from_sources(PAPER_TOML, {})
    corner = {"alpha_d": Fraction(540), "k_d": Fraction(1, 10), "los_speed": Fraction(5, 10**5)}
    refutation = prop41.refutation(build_system(problem_at_point(problem, corner), "derived"))
    assert refutation is None  # the slow box's corner is not refuted, so a refutation stated there must fail
    slow["conditions"]["prop41_ges"] = {"status": "refuted", "summary": "forged",
                                        "refutation": {"point": {k: str(v) for k, v in corner.items()},
                                                       "sup_bound": "1", "g": "2"}}
    slow["verdict"] = "not_certified"  # consistent with the forged status: only the refutation is wrong
    slow["answers"] = answers_of(slow["conditions"])  # and so are the answers
    rows = verify(slow).checks
    assert [c.ok for c in rows if c.check == "prop41_ges"] == [False]
    assert all(c.ok for c in rows if c.check != "prop41_ges")

"""The saturated real loop over a box: global reach with one S_1, Y_q for every gain set."""

from __future__ import annotations

import random
from fractions import Fraction

import pytest
import sympy as sp

from lyapcheck.paper.boxes.saturated import certify_saturated_box, verify_saturated_box
from lyapcheck.paper.boxes.box import parse_box, problem_at_point
from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions.saturated import OMEGA_ROUNDING, global_reach, reach_push
from lyapcheck.paper.params import problem_from_sources
from symbolic._generated import integrator_rates, unsaturated_strip_sq, windup_bound_sq
from tests.conftest import PAPER_TOML

NEAR_PAPER = ["alpha_d=540..660", "k_d=0.1..0.2"]


def _sign_of(expr: sp.Expr) -> int:
    """+1 / -1 when ``expr`` (a rational function of positive symbols) is positive / negative for
    every positive value: numerator and denominator expand to polynomials whose coefficients all
    have one sign. 0 when this simple test cannot tell."""
    num, den = sp.fraction(sp.factor(sp.together(expr)))
    signs = []
    for part in (num, den):
        coefficients = sp.Poly(sp.expand(part), *sorted(part.free_symbols, key=str)).coeffs() if part.free_symbols \
            else [part]
        if all(c > 0 for c in coefficients):
            signs.append(1)
        elif all(c < 0 for c in coefficients):
            signs.append(-1)
        else:
            return 0
    return signs[0] * signs[1]


def test_every_quantity_of_the_reach_argument_is_monotone_in_every_parameter() -> None:
    """The covering argument of lyapcheck.paper.boxes.saturated, on the generated code of the derivation."""
    sigma0, k_d, delta, U, S1, w, alpha, e11_hat, omega = sp.symbols(
        "sigma0 k_d delta U S1 w alpha e11_hat omega", positive=True)
    s_star_sq = windup_bound_sq(sigma0, k_d, delta, U)
    assert [_sign_of(sp.diff(s_star_sq, x)) for x in (delta, U, k_d, sigma0)] == [1, 1, -1, -1]
    y_sat_sq = unsaturated_strip_sq(alpha, delta, e11_hat, omega)
    assert [_sign_of(sp.diff(y_sat_sq, x)) for x in (alpha, delta)] == [-1, -1]
    # push(Y_q) with Y_q = Delta + w (the box keeps Delta <= Y_q): increasing in every parameter
    Yq = sp.Symbol("Yq", positive=True)
    damping, forcing = integrator_rates(Yq, sigma0, k_d, delta, U)
    push = sigma0 * (damping * S1 + forcing)
    for x in (sigma0, k_d, U, delta):
        assert _sign_of(sp.diff(push, x).subs(Yq, delta + w)) == 1, x


@pytest.fixture(scope="module")
def problem():  # type: ignore[no-untyped-def]
    return problem_from_sources(PAPER_TOML, {})


def test_a_one_point_box_reproduces_the_point_argument(problem) -> None:  # type: ignore[no-untyped-def]
    result = certify_saturated_box(problem, parse_box(["alpha_d=600..600", "k_d=0.15..0.15"]))
    system = build_system(problem, "derived")
    y_sat_sq = unsaturated_strip_sq(problem.gains.alpha_d, system.delta, problem.swimmer.e11_hat,
                                    problem.actuation.omega_so * (1 - OMEGA_ROUNDING))
    point = global_reach(system, k_d=problem.gains.k_d, y_sat_sq=y_sat_sq, time_scale=-system.A[0][0])
    assert point is not None and result["status"] == "certified"
    reach = result["certificate"]["reach"]
    # the same argument; S_1 and Y_q are rounded differently (exact square roots here), by ~1e-6
    for key in ("S_1", "Y_q", "gamma"):
        assert abs(Fraction(reach[key]) / Fraction(point[key]) - 1) < Fraction(1, 10**5), key


def test_a_box_is_certified_and_every_interior_gain_set_meets_its_own_conditions(problem) -> None:  # type: ignore[no-untyped-def]
    box = parse_box(NEAR_PAPER)
    result = certify_saturated_box(problem, box)
    assert result["status"] == "certified", result["summary"]
    assert verify_saturated_box(problem, box, "derived", result)[0]
    reach = result["certificate"]["reach"]
    S1, Yq = Fraction(reach["S_1"]), Fraction(reach["Y_q"])
    rng = random.Random(11)
    for _ in range(6):
        point = {name: lo + Fraction(rng.randint(0, 1000), 1000) * (hi - lo) for name, lo, hi in box.bounds}
        p = problem_at_point(problem, point)
        system = build_system(p, "derived")
        y_sat_sq = unsaturated_strip_sq(p.gains.alpha_d, system.delta, p.swimmer.e11_hat,
                                        p.actuation.omega_so * (1 - OMEGA_ROUNDING))
        assert S1 * S1 > windup_bound_sq(system.sigma0, p.gains.k_d, system.delta, system.speed)
        assert system.delta <= Yq and Yq * Yq <= y_sat_sq
        gamma = -system.A[0][0] * Yq - reach_push(system, p.gains.k_d, S1, Yq)
        assert gamma >= Fraction(reach["gamma"]) > 0


def test_a_forged_margin_or_another_box_fails_and_a_wide_box_is_not_claimed(problem) -> None:  # type: ignore[no-untyped-def]
    box = parse_box(NEAR_PAPER)
    result = certify_saturated_box(problem, box)
    reach = result["certificate"]["reach"]
    forged = {**result, "certificate": {"reach": {**reach, "gamma": str(Fraction(reach["gamma"]) * 2)}}}
    assert not verify_saturated_box(problem, box, "derived", forged)[0]
    for key in ("windup_bound_s_m", "reach_set_y_half_width_m"):  # stated smaller than proved
        assert not verify_saturated_box(problem, box, "derived", {**result, key: result[key] / 10})[0], key
    low_s = {**result, "certificate": {"reach": {**reach, "S_1": "0.3"}}}
    assert not verify_saturated_box(problem, box, "derived", low_s)[0]
    wider = parse_box(["alpha_d=540..660", "k_d=0.05..0.2"])  # a smaller k_d winds the integrator up further
    assert not verify_saturated_box(problem, wider, "derived", result)[0]
    wide = certify_saturated_box(problem, parse_box(["alpha_d=150..2400", "k_d=0.05..3.2"]))
    assert wide["status"] == "not_certified" and float(Fraction(wide["certificate"]["reach"]["gamma"])) < 0
    printed = certify_saturated_box(problem, box, "printed")
    assert printed["status"] == "not_applicable"
    # corners beyond the double range: an answer, not an overflow (Y_sat < Delta, or a push of 1e300)
    for extreme in (["alpha_d=1e-6..1e6"], ["k_d=1e-300..1e300"], ["los_speed=1e-300 m/s..1e300 m/s"]):
        far = certify_saturated_box(problem, parse_box(extreme))
        assert far["status"] == "not_certified", far["summary"]

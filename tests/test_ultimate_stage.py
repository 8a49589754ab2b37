"""ultimate_bound's ellipsoid stage in Q = P^-1: the exact inverse, and the line search's candidates."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from lyapcheck import exact
from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions import scaling, ultimate
from lyapcheck.paper.params import Problem


def test_p_from_q_is_the_exact_inverse_in_the_original_coordinates() -> None:
    """Q = kappa^2 T Q~ T^T (T = diag(1, beta)) and P = Q^-1, with no rounding beyond Q~'s."""
    sc = scaling.Scaling(beta=Fraction(7, 3), time=Fraction(5))
    kappa = Fraction(3, 1000)
    q_scaled = np.array([[2.5, -0.75], [-0.75, 4.0]])
    P = ultimate.p_from_q(sc, kappa, q_scaled)
    assert P is not None
    T = ((Fraction(1), Fraction(0)), (Fraction(0), sc.beta))
    Qt = exact.scale(kappa * kappa, exact.rational_matrix(q_scaled))
    Q = exact.matmul(exact.matmul(T, Qt), exact.transpose(T))
    assert exact.matmul(P, Q) == exact.identity(2)
    assert ultimate.p_from_q(sc, kappa, np.array([[1.0, 2.0], [2.0, 4.0]])) is None  # singular


@pytest.mark.parametrize("best_is_accurate", [True, False])
def test_the_line_search_checks_the_best_solve_then_the_best_optimal_one(best_is_accurate: bool) -> None:
    """A convex Q11(lambda) with its minimum near lambda = 0.01; the solves below lambda = 0.003 end
    "inaccurate" and, when the minimum is among them, the best "optimal" solve comes second."""
    centre = 0.01 if best_is_accurate else 0.001
    calls: list[float] = []

    def attempt(lam: float) -> ultimate.Candidate:
        calls.append(lam)
        value = 1.0 + np.log(lam / centre) ** 2
        return value, lam, np.eye(2) * value, lam >= 0.003

    def best_of(lams: list[float]) -> float:
        """The smallest Q11, and among values within LINE_SEARCH_TIE of it the smallest lambda."""
        low = min(1.0 + np.log(lam / centre) ** 2 for lam in lams)
        return min(lam for lam in lams if 1.0 + np.log(lam / centre) ** 2 <= low * (1 + ultimate.LINE_SEARCH_TIE))

    candidates = ultimate.line_search(attempt)
    assert len(calls) == len(ultimate.LAMBDA_GRID) + 2 * ultimate.LAMBDA_REFINE_STEPS
    assert candidates[0][1] == best_of(calls)
    if best_is_accurate:
        assert len(candidates) == 1 and candidates[0][3]
    else:
        assert len(candidates) == 2 and not candidates[0][3] and candidates[1][3]
        assert candidates[1][1] == best_of([lam for lam in calls if lam >= 0.003])


def test_the_line_search_steps_do_not_follow_the_last_bits_of_a_solve() -> None:
    """Issue 24: values that differ by less than LINE_SEARCH_TIE (as two platforms' optima of one
    program do) are equal to the search, so noise at 1e-9 relative takes the same steps and ends
    on the same lambda."""
    rng = np.random.default_rng(2)
    ends = set()
    for _ in range(5):
        def attempt(lam: float) -> ultimate.Candidate:
            # a minimum flat within 1e-7 over a factor 3 of lambda, plus noise of the solver's size
            value = (1.0 + 1e-7 * np.tanh(np.log(lam / 0.01) ** 2)) * (1 + 1e-9 * rng.standard_normal())
            return value, lam, np.eye(2) * value, True
        ends.add(ultimate.line_search(attempt)[0][1])
    assert len(ends) == 1


def test_stages_found_in_q_pass_the_exact_check_in_p_at_the_test_gains(easy_problem: Problem) -> None:
    """The first stage at EASY_GAINS, found in Q, passes the unchanged exact check in P, and its bound
    is the one the snapshot records (0.0864 mm; the P-form found 0.120 mm here, 0.092 mm elsewhere)."""
    system = build_system(easy_problem, "derived")
    result = ultimate.run(system)
    assert result.status == "certified" and result.numbers["ellipsoid_stages"] >= 1
    assert ultimate.verify(system, result.certificate)[0]
    assert result.numbers["eps_bound_m"] < 0.9e-4

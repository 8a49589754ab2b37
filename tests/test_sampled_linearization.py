"""The sampled-data loop's linearization (issue 44, item 2): exp(A T) + Gamma(T) B K decided in ball
arithmetic, against a floating-point reference of the critical period."""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np
import pytest
from scipy.linalg import expm

from lyapcheck.models.classes import sampled

# the upright pendulum theta'' = 9.81 sin(theta) - 0.1 theta' + u, linearized, under u = -30 theta - 5 omega
A = [[F(0), F(1)], [F(981, 100), F(-1, 10)]]
B = [[F(0)], [F(1)]]
K = [[F(-30), F(-5)]]


def _radius(period: float) -> float:
    M = np.zeros((3, 3))
    M[:2, :2] = np.array(A, dtype=float) * period
    M[:2, 2:] = np.array(B, dtype=float) * period
    E = expm(M)
    return float(max(abs(np.linalg.eigvals(E[:2, :2] + E[:2, 2:] @ np.array(K, dtype=float)))))


def _critical_period() -> float:
    lo, hi = 0.01, 1.0
    for _ in range(50):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _radius(mid) < 1 else (lo, mid)
    return lo


def test_stable_and_unstable_periods_are_decided_and_verified() -> None:
    for period, expected in ((F(1, 100), "certified"), (F(1, 5), "certified"), (F(1, 2), "refuted")):
        result = sampled.decide(A, B, K, period)
        assert result.status == expected, period
        data = result.certificate if expected == "certified" else result.refutation
        assert data is not None and data["method"] == sampled.METHOD
        assert sampled.verify(A, B, K, period, expected, data)[0]
        # the other verdict, or the same one at another period, does not verify
        other = "refuted" if expected == "certified" else "certified"
        assert not sampled.verify(A, B, K, period, other, data)[0]
        assert not sampled.verify(A, B, K, period + F(1, 1000), expected, data)[0]


def test_the_decision_brackets_the_true_critical_period() -> None:
    critical = _critical_period()  # about 0.380 s
    below = F(round(critical * 0.999, 6)).limit_denominator(10**6)
    above = F(round(critical * 1.001, 6)).limit_denominator(10**6)
    assert sampled.decide(A, B, K, below).status == "certified"
    assert sampled.decide(A, B, K, above).status == "refuted"


def test_tampered_matrices_fail_verification() -> None:
    result = sampled.decide(A, B, K, F(1, 10))
    data = dict(result.certificate or {})
    assert not sampled.verify(A, B, [[F(-31), F(-5)]], F(1, 10), "certified", data)[0]
    data["precision_bits"] = 10**6
    assert not sampled.verify(A, B, K, F(1, 10), "certified", data)[0]


def test_an_eigenvalue_on_the_unit_circle_stays_inconclusive() -> None:
    # a double integrator with no feedback: exp(A T) has the double eigenvalue 1 for every T
    zero = [[F(0), F(1)], [F(0), F(0)]]
    result = sampled.decide(zero, [[F(0)], [F(1)]], [[F(0), F(0)]], F(1, 10))
    assert result.status == "inconclusive"
    assert not result.certificate and not result.refutation


def test_without_an_input_the_map_is_exp_AT() -> None:
    hurwitz = [[F(-1), F(2)], [F(0), F(-3)]]
    assert sampled.decide(hurwitz, [], [], F(7, 3)).status == "certified"
    assert sampled.decide([[F(1, 5)]], [], [], F(1, 10)).status == "refuted"


def test_a_non_positive_period_is_refused() -> None:
    with pytest.raises(ValueError):
        sampled.decide(A, B, K, F(0))


def test_the_sentence_is_the_claims_one_made_from_the_status_and_the_period_alone() -> None:
    from lyapcheck.models.classes.claims import summary

    for period, status in ((F(1, 3), "certified"), (F(1, 2), "refuted")):
        c = sampled.decide(A, B, K, period).to_json()
        assert c["status"] == status
        assert summary("linearization", c) == c["summary"]  # what certify printed, verify and the report re-make
        assert "period 1/3 s" in c["summary"] if period == F(1, 3) else "period 0.5 s" in c["summary"]
        data = c["certificate" if status == "certified" else "refutation"]
        moved = {**c, ("certificate" if status == "certified" else "refutation"): {**data, "period": "1/4"}}
        assert summary("linearization", moved) != c["summary"]  # the sentence follows the stated period
        with pytest.raises(ValueError):  # a malformed period: verify reports a failed check
            summary("linearization", {**c, ("certificate" if status == "certified" else "refutation"):
                                      {**data, "period": "a while"}})

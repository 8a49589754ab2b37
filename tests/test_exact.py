"""Exact arithmetic: the judge of every certified / refuted verdict."""

from __future__ import annotations

import math
from fractions import Fraction as Q

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lyapcheck import exact

small = st.fractions(min_value=-50, max_value=50, max_denominator=40)


@settings(max_examples=300, derandomize=True)
@given(small, small, st.fractions(min_value=0, max_value=50, max_denominator=40))
def test_sign_of_a_plus_b_sqrt_q_matches_high_precision(a: Q, b: Q, q: Q) -> None:
    from decimal import Decimal, localcontext

    with localcontext(prec=80):  # the process-wide context stays as other tests expect it
        value = Decimal(a.numerator) / Decimal(a.denominator) + Decimal(b.numerator) / Decimal(b.denominator) * (
            Decimal(q.numerator) / Decimal(q.denominator)).sqrt()
    expected = (value > 0) - (value < 0)
    if abs(value) > Decimal("1e-60"):
        assert exact.sign_a_plus_b_sqrt(a, b, q) == expected


@settings(max_examples=200, derandomize=True)
@given(small, small, small, small, small, st.fractions(min_value=0, max_value=30, max_denominator=20))
def test_min_eigenvalue_comparison_matches_numpy(m11: Q, m12: Q, m22: Q, a: Q, b: Q, q: Q) -> None:
    m = exact.matrix([[m11, m12], [m12, m22]])
    lam_min = float(np.linalg.eigvalsh(np.array(exact.to_float(m))).min())
    r = float(a) + float(b) * math.sqrt(float(q))
    if abs(lam_min - r) > 1e-9 * (1 + abs(r)):
        assert exact.min_eig_exceeds_2x2(m, a, b, q) == (lam_min > r)


def test_sylvester_and_determinant() -> None:
    assert exact.is_positive_definite(exact.matrix([[2, 1], [1, 2]]))
    assert not exact.is_positive_definite(exact.matrix([[1, 2], [2, 1]]))
    assert not exact.is_positive_definite(exact.matrix([[1, 0], [1, 1]]))  # not symmetric
    m = exact.matrix([[1, 2, 3], [4, 5, 6], [7, 8, 10]])
    assert exact.det(m) == Q(-3)


def test_sqrt_upper_is_an_upper_bound_and_tight() -> None:
    for q in (Q(2), Q(1, 3), Q(10**12 + 7, 10**6)):
        r = exact.sqrt_upper(q)
        assert r * r >= q
        assert float(r) - math.sqrt(float(q)) < 1e-12 * (1 + math.sqrt(float(q)))


def test_negative_real_eigenvalue_detection() -> None:
    assert exact.has_negative_real_eigenvalue_2x2(exact.matrix([[-1, 0], [0, 2]]))
    assert not exact.has_negative_real_eigenvalue_2x2(exact.matrix([[0, -1], [1, 0]]))  # +-i
    assert not exact.has_negative_real_eigenvalue_2x2(exact.matrix([[1, 0], [0, 2]]))
    assert exact.has_negative_real_eigenvalue_2x2(exact.matrix([[-1, 0], [0, -2]]))


_entries = st.fractions(min_value=-1000, max_value=1000, max_denominator=10**6)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.integers(min_value=1, max_value=6).flatmap(lambda n: st.lists(_entries, min_size=n * n, max_size=n * n)),
       st.fractions(min_value=-2, max_value=2, max_denominator=10**12))
def test_the_float_screen_never_rejects_a_positive_definite_matrix(flat: list[Q], shift: Q) -> None:
    """surely_not_positive_definite lets the searches skip exact checks: it must never say so of a
    matrix the exact check accepts, including ones shifted to within rounding of singular."""
    n = math.isqrt(len(flat))
    a = [[flat[i * n + j] for j in range(n)] for i in range(n)]
    gram = [[sum(a[k][i] * a[k][j] for k in range(n)) for j in range(n)] for i in range(n)]  # A^T A >= 0
    m = exact.matrix([[gram[i][j] + (shift if i == j else 0) for j in range(n)] for i in range(n)])
    if exact.surely_not_positive_definite(m):
        assert not exact.is_positive_definite_ldl(m)


def test_the_float_screen_sees_a_clear_negative_eigenvalue_and_leaves_close_calls_to_the_exact_check() -> None:
    assert exact.surely_not_positive_definite(exact.matrix([[1, 2], [2, 1]]))  # eigenvalues 3, -1
    assert not exact.surely_not_positive_definite(exact.matrix([[2, 1], [1, 2]]))
    # eigenvalue -1e-20 next to 1: not positive definite, but far below float resolution
    close = exact.matrix([[1, 0], [0, Q(-1, 10**20)]])
    assert not exact.is_positive_definite_ldl(close) and not exact.surely_not_positive_definite(close)
    assert not exact.surely_not_positive_definite(exact.matrix([[1, 2], [3, 1]]))  # not symmetric: exact decides


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.integers(min_value=2, max_value=7).flatmap(
    lambda n: st.tuples(st.just(n), st.lists(_entries, min_size=n * n, max_size=n * n),
                        st.lists(st.booleans(), min_size=n, max_size=n), st.permutations(range(n)),
                        st.fractions(min_value=-1, max_value=2, max_denominator=8))))
def test_the_block_by_block_check_decides_as_the_whole_elimination(case: tuple) -> None:  # type: ignore[type-arg]
    """is_positive_definite_ldl checks each diagonal block (up to a permutation) on its own; it must
    decide exactly what the elimination of the whole matrix decides, on matrices made block
    diagonal by zeroing the entries between two index classes, then permuted. The diagonal shift
    (a fraction of the smallest diagonal entry) makes both answers common."""
    n, flat, side, order, t = case
    a = np.array(flat, dtype=object).reshape(n, n)
    m = a @ a.T
    for i in range(n):
        for j in range(n):
            if side[i] != side[j]:
                m[i, j] = Q(0)
    shift = t * min(m[i, i] for i in range(n))
    m = (m - np.diag([shift] * n))[np.ix_(order, order)]
    rational = tuple(tuple(Q(v) for v in row) for row in m)
    blocks = exact.diagonal_blocks(rational)
    assert sorted(i for b in blocks for i in b) == list(range(n))
    assert exact.is_positive_definite_ldl(rational) == exact.leading_minors_positive(rational)


def test_the_block_by_block_check_sees_a_failing_block() -> None:
    """An indefinite block among definite ones, interleaved by a permutation, is found."""
    m = exact.matrix([[2, 0, 1, 0], [0, 1, 0, 3], [1, 0, 2, 0], [0, 3, 0, 1]])  # blocks {0, 2} and {1, 3}
    assert sorted(map(sorted, exact.diagonal_blocks(m))) == [[0, 2], [1, 3]]
    assert not exact.is_positive_definite_ldl(m)
    assert exact.is_positive_definite_ldl(exact.matrix([[2, 0, 1, 0], [0, 4, 0, 3], [1, 0, 2, 0], [0, 3, 0, 4]]))

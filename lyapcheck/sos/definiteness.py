"""Exact positive definiteness of symmetric rational matrices, at the sizes SOS certificates bring.

Three exact tests, cheapest first; each decides in integer arithmetic, none trusts a float:

1. **Blocks.** A matrix that is block diagonal up to a permutation (a sign-symmetric Gram matrix)
   is positive definite iff each diagonal block is; each block is decided on its own.
2. **Small blocks** (at most :data:`BAREISS_MAX` rows): fraction-free (Bareiss) elimination on
   the integer matrix ``D M`` (:func:`lyapcheck.exact.leading_minors_positive`); its k-th pivot is
   the k-th leading principal minor (times ``D^k``), so all pivots > 0 is Sylvester's criterion.
   Decides both ways.
3. **Large blocks**: a congruence. From a floating-point Cholesky factor ``M ~ L L^T`` we take
   ``X``, the inverse of ``L``'s unit-diagonal part rounded to a dyadic grid (so ``X`` is an exact
   unit lower triangular rational matrix, hence invertible), and form ``B = X M X^T`` exactly
   with FLINT's integer matrix product. By Sylvester's law of inertia ``M > 0`` iff ``B > 0``,
   and ``B`` is nearly diagonal, so a strictly diagonally dominant ``B`` with a positive diagonal
   (Gershgorin, exact) proves ``M > 0``. This is only sufficient; when it does not apply, the
   characteristic polynomial decides: a real symmetric matrix (all eigenvalues real) is positive
   definite iff the coefficients of ``det(t I - M)`` strictly alternate in sign (Descartes).

Before them, two cheaper sufficient tests (exact, O(n^2) integer operations; a False from them only
means "not shown", and the tests above then decide):

0. **Diagonal dominance**: a symmetric matrix with a positive diagonal and ``m_ii > sum_(j != i)
   |m_ij|`` on every row is positive definite (Gershgorin). The Gram matrices of a DSOS program
   (:attr:`lyapcheck.sos.structure.Gram.cone` ``"dd"``) are of this kind after rounding.
   **Scaled diagonal dominance** (the H-matrix test): a positive diagonal ``D`` with ``D m D``
   strictly diagonally dominant proves ``m > 0`` (a congruence). ``D``'s entries come from the
   comparison matrix ``C`` (``C_ii = m_ii``, ``C_ij = -|m_ij|``): when ``m`` is SDD, ``C`` is a
   nonsingular M-matrix and ``d = C^-1 1 > 0`` gives ``C d = 1 > 0``; ``d`` is solved in floats,
   rounded to a dyadic grid, and only the exact integer inequalities ``m_ii d_i > sum_j |m_ij| d_j``
   decide. A symmetric matrix with a positive diagonal is SDD (a sum of 2x2 PSD matrices, one per
   pair of rows) exactly when such a ``D`` exists for its non-strict version: the Gram matrices of
   an SDSOS program (``"sdd"``).

Measured on this machine (random SPD matrices with 15-digit entries, condition up to 1e10):
Python-integer Bareiss 1.1 s at 80 rows; FLINT's characteristic polynomial 0.11 s at 80 rows and
3.4 s at 200; the congruence 0.05 s at 80 rows and 0.23 s at 200. The pure-Python LDL^T of
:func:`lyapcheck.exact.ldl_pivots` stays as the independent second opinion in the tests.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Final, Sequence

from lyapcheck.exact import diagonal_blocks, integer_matrix, is_symmetric, leading_minors_positive

#: blocks up to this size are decided by Bareiss elimination in Python integers (fast enough)
BAREISS_MAX: Final = 24
#: bits of the dyadic grid the congruence's unit lower triangular factor is rounded to
CONGRUENCE_BITS: Final = 40
#: bits of the dyadic grid the H-matrix test's scaling ``d`` is rounded to (relative to its largest entry)
SCALING_BITS: Final = 40
#: above this size the characteristic polynomial fallback is not attempted (minutes of FLINT time);
#: a matrix the congruence cannot show definite is then reported as not shown positive definite
CHARPOLY_MAX: Final = 220

Matrix = Sequence[Sequence[Fraction]]


def _congruence_positive_definite(m: Matrix) -> bool | None:
    """True when the exact congruence ``X m X^T`` is strictly diagonally dominant with a positive
    diagonal (so ``m > 0``); None when that test does not apply (decide otherwise)."""
    import flint
    import numpy as np

    n = len(m)
    a = np.array([[float(x) for x in row] for row in m])
    if not np.all(np.isfinite(a)):
        return None
    try:
        chol = np.linalg.cholesky(a)
    except np.linalg.LinAlgError:
        return None
    unit = chol / np.diag(chol)
    # X = unit^-1 by forward substitution (unit lower triangular), in floats; then exact dyadic
    x = np.linalg.solve(unit, np.eye(n))
    scale = 2 ** CONGRUENCE_BITS
    xi = np.rint(np.tril(x, -1) * scale)
    if not np.all(np.isfinite(xi)):
        return None
    rows = [[int(v) for v in row] for row in xi]
    for i in range(n):
        rows[i][i] = scale  # exactly unit diagonal: X is invertible whatever the rounding did
    X = flint.fmpz_mat(rows)
    M = flint.fmpz_mat(integer_matrix(m))
    B = X * M * X.transpose()
    entries = [[int(v) for v in row] for row in B.tolist()]
    for i in range(n):
        row = entries[i]
        off = sum(abs(v) for j, v in enumerate(row) if j != i)
        if row[i] <= off:
            return None
    return True


def diagonally_dominant(m: Matrix) -> bool:
    """Exact: every diagonal entry is > 0 and > the sum of the absolute values of its row's other
    entries (so the symmetric ``m`` is positive definite). False means "not shown", never "not
    positive definite"."""
    return scaled_diagonally_dominant(m, [1] * len(m))


def scaled_diagonally_dominant(m: Matrix, scaling: Sequence[int] | None = None) -> bool:
    """Exact: ``m_ii d_i > sum_(j != i) |m_ij| d_j`` for every row, with ``d > 0`` the given integer
    ``scaling`` or, by default, the rounded solution of ``C d = 1`` (``C`` the comparison matrix,
    see the module docstring). Then ``D m D`` is strictly diagonally dominant with a positive
    diagonal, so the symmetric ``m`` is positive definite. False means "not shown", never "not
    positive definite"."""
    n = len(m)
    if n == 0:
        return True
    a = integer_matrix(m)
    if any(a[i][i] <= 0 for i in range(n)):
        return False
    d = list(scaling) if scaling is not None else _comparison_scaling(m)
    if d is None or len(d) != n or any(x <= 0 for x in d):
        return False
    for i, row in enumerate(a):
        off = 0
        for j, v in enumerate(row):
            if v and j != i:
                off += abs(v) * d[j]
        if row[i] * d[i] <= off:
            return False
    return True


def _comparison_scaling(m: Matrix) -> list[int] | None:
    """``d = C^-1 1`` for the comparison matrix ``C`` of ``m`` (floats, scaled by the diagonal for a
    well-conditioned solve), rounded to positive integers on a grid of :data:`SCALING_BITS` bits; None
    when the solve fails or some ``d_i`` is not positive (``m`` is then not an H-matrix, as far as
    floats can tell)."""
    import numpy as np

    M = np.array([[float(v) for v in row] for row in m])
    diag = np.diag(M).copy()
    if not np.all(np.isfinite(M)) or np.any(diag <= 0):
        return None
    # C' = S C S with S = diag(m_ii)^-1/2 has a unit diagonal; d = S d' with C' d' = S 1
    s = 1.0 / np.sqrt(diag)
    C = -np.abs(M) * s[:, None] * s[None, :]
    np.fill_diagonal(C, 1.0)
    if not np.all(np.isfinite(C)):
        return None
    try:
        d = s * np.linalg.solve(C, s)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(d)) or np.any(d <= 0):
        return None
    d = np.ldexp(d / d.max(), SCALING_BITS)
    out = [int(v) for v in np.rint(d)]
    return out if all(v > 0 for v in out) else None


def _charpoly_positive_definite(m: Matrix) -> bool:
    """Exact, for a symmetric ``m``: the characteristic polynomial's coefficients alternate strictly."""
    import flint

    n = len(m)
    coeffs = [int(c) for c in flint.fmpz_mat(integer_matrix(m)).charpoly().coeffs()]
    coeffs += [0] * (n + 1 - len(coeffs))
    # det(tI - M) = sum c_k t^k; all n roots real and positive iff (-1)^(n-k) c_k > 0 for every k
    return all((c > 0) if (n - k) % 2 == 0 else (c < 0) for k, c in enumerate(coeffs))


def is_positive_definite(m: Matrix) -> bool:
    """Exact positive definiteness of a symmetric rational matrix (False if not symmetric).

    A False for a block above :data:`CHARPOLY_MAX` rows may mean "not shown" rather than "not
    positive definite" (the congruence did not apply and the characteristic polynomial is not
    attempted): callers treat False as "no certificate", never as a refutation.
    """
    if not is_symmetric(m):
        return False
    if len(m) == 0:
        return True
    for idx in diagonal_blocks(m):
        block = [[_rational(m[i][j]) for j in idx] for i in idx]
        if not _block_positive_definite(block):
            return False
    return True


def _rational(x: Fraction | int) -> Fraction:
    return x if isinstance(x, Fraction) else Fraction(x)


def _block_positive_definite(block: list[list[Fraction]]) -> bool:
    n = len(block)
    if diagonally_dominant(block):
        return True
    if n <= BAREISS_MAX:
        return leading_minors_positive(block)
    if any(block[i][i] <= 0 for i in range(n)):
        return False
    if scaled_diagonally_dominant(block):
        return True
    shown = _congruence_positive_definite(block)
    if shown:
        return True
    if _negative_direction(block):
        return False
    if n > CHARPOLY_MAX:
        return False
    return _charpoly_positive_definite(block)


def _negative_direction(m: list[list[Fraction]]) -> bool:
    """True when a rounded eigenvector ``v`` of the smallest float eigenvalue gives ``v^T m v < 0``
    exactly: a quick, exact proof that ``m`` is not positive definite."""
    import numpy as np

    a = np.array([[float(x) for x in row] for row in m])
    if not np.all(np.isfinite(a)):
        return False
    values, vectors = np.linalg.eigh(a)
    if not values[0] < 0:
        return False
    v = vectors[:, 0] / np.max(np.abs(vectors[:, 0]))
    return proves_not_positive_semidefinite(m, [Fraction(round(float(x) * 2**30), 2**30) for x in v])


def is_positive_semidefinite(m: Matrix) -> bool:
    """Exact positive semidefiniteness of a symmetric rational matrix (False if not symmetric).

    Symmetric elimination with diagonal pivoting: a positive diagonal entry is eliminated (a Schur
    complement keeps semidefiniteness both ways); a negative one proves indefiniteness; when every
    remaining diagonal entry is 0 the rest must be exactly 0 (a semidefinite matrix with a zero
    diagonal entry has a zero row). Blocks are decided one by one.
    """
    if not is_symmetric(m):
        return False
    for idx in diagonal_blocks(m):
        work = [[_rational(m[i][j]) for j in idx] for i in idx]
        if not _semidefinite_block(work):
            return False
    return True


def _semidefinite_block(a: list[list[Fraction]]) -> bool:
    live = list(range(len(a)))
    while live:
        pivot = next((k for k in live if a[k][k] > 0), None)
        if pivot is None:
            return all(a[i][j] == 0 for i in live for j in live)
        if any(a[k][k] < 0 for k in live):
            return False
        live.remove(pivot)
        p = a[pivot][pivot]
        row = a[pivot]
        for i in live:
            f = a[i][pivot] / p
            if f:
                ai = a[i]
                for j in live:
                    ai[j] -= f * row[j]
    return True


def proves_not_positive_semidefinite(m: Matrix, v: Sequence[Fraction]) -> bool:
    """Exact: ``v^T m v < 0``, i.e. ``v`` proves that ``m`` is not positive semidefinite."""
    total = Fraction(0)
    for i, row in enumerate(m):
        if v[i]:
            total += v[i] * sum((row[j] * v[j] for j in range(len(v)) if v[j]), Fraction(0))
    return total < 0

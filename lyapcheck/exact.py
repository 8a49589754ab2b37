"""Exact rational linear algebra for certificate checks.

Every ``certified`` and every ``refuted`` verdict is decided here, in
:class:`fractions.Fraction` arithmetic, never by a floating-point comparison. Matrices are
tuples of tuples of Fractions.
"""

from __future__ import annotations

import math
import re
from decimal import ROUND_CEILING, ROUND_HALF_EVEN, Context, Decimal, localcontext
from fractions import Fraction
from typing import Any, Iterable, Mapping, Sequence

Matrix = tuple[tuple[Fraction, ...], ...]

#: Python's default decimal context (28 digits), fixed here: see sqrt_upper
_GUESS_CONTEXT = Context(prec=28, rounding=ROUND_HALF_EVEN)


def to_rational(x: float, digits: int = 15) -> Fraction:
    """Round a float to `digits` significant decimal digits, as an exact Fraction."""
    if not math.isfinite(x):
        raise ValueError(f"cannot round a non-finite number to a rational: {x}")
    if x == 0.0:  # the same value without the decimal round trip (zero blocks of sparse certificates)
        return Fraction(0)
    return Fraction(Decimal(f"{x:.{digits - 1}e}"))


#: a whole text that :class:`~fractions.Fraction` reads as a decimal with an exponent (``2.5e+3``,
#: `` -1E-7 ``); group 1 is the exponent. A hash such as ``"3e5a..."`` or a sentence does not match
_DECIMAL_WITH_EXPONENT = re.compile(r"\s*[+-]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE]([+-]?[0-9_]+)\s*")


def _oversized(text: str) -> bool:
    """``text`` is a decimal whose exponent is beyond :data:`lyapcheck.tolerances.MAX_READ_EXPONENT`
    (decided on its digits, before any number is built from them)."""
    from lyapcheck.tolerances import MAX_READ_EXPONENT

    found = _DECIMAL_WITH_EXPONENT.fullmatch(text)
    digits = found.group(1).lstrip("+-").replace("_", "").lstrip("0") if found is not None else ""
    return len(digits) > len(str(MAX_READ_EXPONENT)) or (bool(digits) and int(digits) > MAX_READ_EXPONENT)


def read_rational(value: Any, key: str = "a number") -> Fraction:
    """A number read from a document (a certificate, a store, a spec) as an exact rational.

    Parameters
    ----------
    value
        A JSON integer, a finite float (read as the decimal it prints as: ``0.1`` is 1/10, as
        ``Fraction(str(value))``), a :class:`~fractions.Fraction`, or a text that
        :class:`~fractions.Fraction` reads (``"3"``, ``"-7/2"``, ``"0.125"``, ``"1e-7"``).
    key
        What the number is, for the error message.

    Raises
    ------
    ValueError
        Naming ``key``: a boolean, a non-finite float, a text that is not a number, or a decimal
        exponent beyond :data:`lyapcheck.tolerances.MAX_READ_EXPONENT` (its exact value would take
        minutes to build: it is refused before it is built).
    """
    from lyapcheck.tolerances import MAX_READ_EXPONENT

    if isinstance(value, bool):
        raise ValueError(f"{key}: {value!r} is not a number")
    if isinstance(value, (int, Fraction)):
        return Fraction(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{key}: {value!r} is not a finite number")
        value = str(value)  # the decimal it prints as (0.1 is 1/10), as the JSON text wrote it
    if not isinstance(value, str):
        raise ValueError(f"{key}: {type(value).__name__} is not a number")
    if _oversized(value):
        raise ValueError(f"{key}: the exponent of {value[:40]!r} is beyond +-{MAX_READ_EXPONENT}")
    try:
        return Fraction(value)
    except (ValueError, ZeroDivisionError) as exc:
        raise ValueError(f"{key}: {value[:40]!r} is not a number ({exc})") from None


def oversized_number(tree: Any, path: str = "") -> str | None:
    """Where a document (parsed JSON) writes a number whose decimal exponent is beyond
    :data:`lyapcheck.tolerances.MAX_READ_EXPONENT` (``"1e999999999"``), or None.

    ``verify`` calls it on a whole document before it reads any number of it, so that no reader,
    :func:`read_rational` or a plain :class:`~fractions.Fraction`, ever builds such a value: a
    forged certificate is refused in milliseconds instead of stalling the check for minutes.
    A text is a number when :class:`~fractions.Fraction` would read the whole of it; a model's text
    is not one (the model-file reader refuses such numbers itself), nor is a hash or a sentence.
    """
    stack: list[tuple[Any, str]] = [(tree, path)]
    while stack:
        node, where = stack.pop()
        if isinstance(node, dict):
            stack.extend((v, f"{where}.{k}" if where else str(k)) for k, v in node.items())
        elif isinstance(node, list):
            stack.extend((v, f"{where}[{i}]") for i, v in enumerate(node))
        elif isinstance(node, str) and _oversized(node):
            return where or "the document"
    return None


def refuse_oversized_numbers(doc: Any) -> None:
    """A document that writes a number with a decimal exponent beyond
    :data:`lyapcheck.tolerances.MAX_READ_EXPONENT` is malformed (one line naming where), before any of
    its numbers is read (:func:`lyapcheck.exact.oversized_number`)."""
    from lyapcheck.errors import CertificateError
    from lyapcheck.tolerances import MAX_READ_EXPONENT

    where = oversized_number(doc)
    if where is not None:
        raise CertificateError(f"certificate is malformed: {where} writes a number with a decimal exponent beyond "
                               f"+-{MAX_READ_EXPONENT}")


def matrix(rows: Iterable[Iterable[int | str | Fraction]]) -> Matrix:
    return tuple(tuple(Fraction(v) for v in row) for row in rows)


def rational_matrix(values: Any, digits: int = 15) -> Matrix:
    """Round a 2-D float array (numpy or nested sequences) entrywise to exact rationals."""
    return tuple(tuple(to_rational(float(v), digits) for v in row) for row in values)


def symmetrize(m: Matrix) -> Matrix:
    """``(m + m^T) / 2``, exactly (an entry equal to its mirror is kept as it is: the same value)."""
    n = len(m)
    return tuple(tuple(m[i][j] if m[i][j] == m[j][i] else (m[i][j] + m[j][i]) / 2 for j in range(n))
                 for i in range(n))


def transpose(m: Matrix) -> Matrix:
    return tuple(zip(*m))


def matmul(a: Matrix, b: Matrix) -> Matrix:
    bt = transpose(b)
    return tuple(tuple(sum((x * y for x, y in zip(row, col)), Fraction(0)) for col in bt) for row in a)


def add(a: Matrix, b: Matrix) -> Matrix:
    return tuple(tuple(x + y for x, y in zip(ra, rb)) for ra, rb in zip(a, b))


def scale(c: Fraction, a: Matrix) -> Matrix:
    return tuple(tuple(c * x for x in row) for row in a)


def identity(n: int) -> Matrix:
    return tuple(tuple(Fraction(int(i == j)) for j in range(n)) for i in range(n))


def block(rows: Sequence[Sequence[Matrix]]) -> Matrix:
    """Assemble a block matrix from blocks of compatible shapes."""
    out: list[tuple[Fraction, ...]] = []
    for block_row in rows:
        height = len(block_row[0])
        for i in range(height):
            out.append(tuple(x for blk in block_row for x in blk[i]))
    return tuple(out)


def lyapunov_form(a: Matrix, p: Matrix) -> Matrix:
    """``A^T P + P A``."""
    return add(matmul(transpose(a), p), matmul(p, a))


def det(m: Matrix) -> Fraction:
    """Determinant by fraction-exact Gaussian elimination."""
    n = len(m)
    work = [list(row) for row in m]
    result = Fraction(1)
    for col in range(n):
        pivot = next((r for r in range(col, n) if work[r][col] != 0), None)
        if pivot is None:
            return Fraction(0)
        if pivot != col:
            work[col], work[pivot] = work[pivot], work[col]
            result = -result
        result *= work[col][col]
        for r in range(col + 1, n):
            factor = work[r][col] / work[col][col]
            if factor:
                for c in range(col, n):
                    work[r][c] -= factor * work[col][c]
    return result


#: bits after the binary point of the dyadic rationals the ball-arithmetic proofs round their grid
#: corners and levels to
DYADIC_BITS = 20


def dyadic_floor(x: Fraction, bits: int = DYADIC_BITS) -> Fraction:
    """The largest multiple of ``2**-bits`` at most ``x``."""
    scale = 2 ** bits
    return Fraction(math.floor(x * scale), scale)


def dyadic_ceil(x: Fraction, bits: int = DYADIC_BITS) -> Fraction:
    """The smallest multiple of ``2**-bits`` at least ``x``."""
    scale = 2 ** bits
    return Fraction(math.ceil(x * scale), scale)


def float_above(x: Fraction) -> float:
    """The least float at least ``x`` (``float`` of a Fraction is correctly rounded: one step at most)."""
    f = float(x)
    return math.nextafter(f, math.inf) if Fraction(f) < x else f


def float_below(x: Fraction) -> float:
    """The largest float at most ``x``."""
    f = float(x)
    return math.nextafter(f, -math.inf) if Fraction(f) > x else f


def quadratic_matrix(terms: Mapping[tuple[int, ...], Fraction], n: int) -> list[list[Fraction]]:
    """The symmetric ``P`` with ``z^T P z`` the terms of degree 2 in the first ``n`` variables alone
    (``terms``: exponents to coefficient; every other term is left out)."""
    P = [[Fraction(0)] * n for _ in range(n)]
    for m, c in terms.items():
        if sum(m) != 2 or any(m[n:]):
            continue
        i, j = (k for k in range(n) for _ in range(m[k]))
        if i == j:
            P[i][i] += c
        else:
            P[i][j] += c / 2
            P[j][i] += c / 2
    return P


def inverse(m: Sequence[Sequence[Fraction]]) -> list[list[Fraction]]:
    """The exact inverse of an invertible square matrix (Gauss-Jordan elimination with row
    pivoting, in rationals; for the small matrices of scalings and quadratic forms)."""
    n = len(m)
    a = [list(row) + [Fraction(int(i == j)) for j in range(n)] for i, row in enumerate(m)]
    for c in range(n):
        pivot = next(r for r in range(c, n) if a[r][c] != 0)
        a[c], a[pivot] = a[pivot], a[c]
        p = a[c][c]
        a[c] = [x / p for x in a[c]]
        for r in range(n):
            if r != c and a[r][c]:
                f = a[r][c]
                a[r] = [x - f * y for x, y in zip(a[r], a[c])]
    return [row[n:] for row in a]


def solve(m: Matrix, b: Sequence[Fraction]) -> list[Fraction]:
    """``x`` with ``m x = b`` for a square, invertible ``m`` (fraction-exact Gaussian elimination);
    ValueError when ``m`` is singular."""
    n = len(m)
    work = [list(row) + [b[i]] for i, row in enumerate(m)]
    for col in range(n):
        pivot = next((r for r in range(col, n) if work[r][col] != 0), None)
        if pivot is None:
            raise ValueError("the matrix is singular")
        work[col], work[pivot] = work[pivot], work[col]
        head = work[col]
        for r in range(col + 1, n):
            factor = work[r][col] / head[col]
            if factor:
                row = work[r]
                for c in range(col, n + 1):
                    row[c] -= factor * head[c]
    x = [Fraction(0)] * n
    for i in range(n - 1, -1, -1):
        row = work[i]
        x[i] = (row[n] - sum((row[j] * x[j] for j in range(i + 1, n)), Fraction(0))) / row[i]
    return x


def least_squares(rows: Sequence[Sequence[Fraction | int]], rhs: Sequence[Fraction | int]) -> list[Fraction]:
    """The exact minimizer of ``|A x - b|^2`` (``A``'s rows ``rows``, full column rank), from the
    normal equations ``A^T A x = A^T b`` solved exactly. Why not a floating-point solver: the
    answer is the same on every platform (a floating-point one differs in its last bits between
    BLAS kernels), and rounding it to integers, as the scalings do, then never depends on them.
    ValueError when ``A`` does not have full column rank."""
    cols = len(rows[0]) if rows else 0
    normal = [[Fraction(0)] * cols for _ in range(cols)]
    right = [Fraction(0)] * cols
    for row, value in zip(rows, rhs):
        nonzero = [(j, Fraction(a)) for j, a in enumerate(row) if a]
        for j, a in nonzero:
            right[j] += a * value
            line = normal[j]
            for k, c in nonzero:
                line[k] += a * c
    return solve(tuple(tuple(r) for r in normal), right)


def is_symmetric(m: Sequence[Sequence[Any]]) -> bool:
    """Square (every row as long as the matrix) and equal to its transpose."""
    n = len(m)
    return all(len(row) == n for row in m) and all(m[i][j] == m[j][i] for i in range(n) for j in range(i + 1, n))


def is_positive_definite(m: Matrix) -> bool:
    """Sylvester's criterion: a symmetric matrix is PD iff all leading minors are > 0."""
    return is_symmetric(m) and leading_minors_positive(m)


def ldl(m: Sequence[Sequence[Fraction]]) -> tuple[list[list[Fraction]], list[Fraction]] | None:
    """The exact symmetric elimination ``M = L D L^T`` (``L`` unit lower triangular, ``D`` the pivots),
    or None if a pivot is zero."""
    n = len(m)
    L = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    D: list[Fraction] = []
    for j in range(n):
        pivot = Fraction(m[j][j]) - sum((L[j][k] ** 2 * D[k] for k in range(j)), Fraction(0))
        if pivot == 0:
            return None
        D.append(pivot)
        for i in range(j + 1, n):
            L[i][j] = (Fraction(m[i][j]) - sum((L[i][k] * L[j][k] * D[k] for k in range(j)), Fraction(0))) / pivot
    return L, D


def ldl_pivots(m: Matrix) -> list[Fraction] | None:
    """Pivots of the exact symmetric elimination ``M = L D L^T`` (None if a pivot is zero).

    A symmetric matrix is positive definite iff every pivot is positive; this costs
    O(n^3) exact operations instead of the n determinants of Sylvester's criterion.
    """
    found = ldl(m)
    return None if found is None else found[1]


def integer_matrix(m: Sequence[Sequence[Fraction | int]]) -> list[list[int]]:
    """``D M`` in Python integers, ``D > 0`` the least common denominator of the entries."""
    rows = [[Fraction(x) for x in row] for row in m]
    den = math.lcm(*(x.denominator for row in rows for x in row)) if rows else 1
    return [[x.numerator * (den // x.denominator) for x in row] for row in rows]


def leading_minors_positive(m: Sequence[Sequence[Fraction | int]]) -> bool:
    """Exact: every leading principal minor of the symmetric ``m`` is > 0 (positive definiteness).

    Fraction-free (Bareiss) elimination on ``D m`` in Python integers: the k-th pivot is the
    k-th leading principal minor of ``D m`` (``D^k`` times that of ``m``, the same sign), and
    every division is exact. It decides exactly what :func:`ldl_pivots` and Sylvester's
    criterion decide (``LDL^T`` pivot ``k`` is the ratio of minors ``k`` and ``k - 1``), without
    a gcd after every operation. The elimination keeps the trailing block symmetric, so only
    its upper triangle is updated.
    """
    a = integer_matrix(m)
    n = len(a)
    prev = 1
    for k in range(n):
        pivot = a[k][k]
        if pivot <= 0:
            return False
        row_k = a[k]
        for i in range(k + 1, n):
            row_i = a[i]
            f = row_i[k]
            for j in range(i, n):
                row_i[j] = (row_i[j] * pivot - f * row_k[j]) // prev
            for j in range(k + 1, i):  # the lower part mirrors the upper (symmetric)
                row_i[j] = a[j][i]
        prev = pivot
    return True


def diagonal_blocks(m: Sequence[Sequence[Any]]) -> list[list[int]]:
    """The index sets of the diagonal blocks of a symmetric ``m`` up to a permutation: the
    connected components of the graph with an edge ``i - j`` wherever ``m[i][j] != 0``."""
    n = len(m)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if m[i][j] != 0:
                parent[root(i)] = root(j)
    blocks: dict[int, list[int]] = {}
    for i in range(n):
        blocks.setdefault(root(i), []).append(i)
    return list(blocks.values())


def is_positive_definite_ldl(m: Matrix) -> bool:
    """Exact positive definiteness of a symmetric rational matrix (see :func:`leading_minors_positive`).

    A matrix that is block diagonal up to a permutation (e.g. a Gram matrix of a sign-symmetric
    certificate: even monomials against odd ones are exactly zero) is positive definite if and
    only if each of its diagonal blocks is, so each block is checked on its own (a 12 x 12 and a
    7 x 7 elimination cost about a third of a 19 x 19 one).
    """
    if not is_symmetric(m):
        return False
    blocks = diagonal_blocks(m)
    if len(blocks) == 1:
        return leading_minors_positive(m)
    return all(leading_minors_positive(tuple(tuple(m[i][j] for j in idx) for i in idx)) for idx in blocks)


def surely_not_positive_definite(m: Matrix) -> bool:
    """True only if the symmetric rational ``m`` is certainly not positive definite: a float screen
    that lets a search skip an exact check bound to fail. It never shows definiteness.

    ``m`` rounded to floats is ``m + E`` with ``|E_ij| <= 2^-53 |m_ij|``, and ``eigvalsh`` is
    backward stable, so each computed eigenvalue is within about ``n 2^-52 ||m||`` (below
    ``1e-13 ||m||`` for the sizes here) of an exact one. An eigenvalue computed below
    ``-SCREEN_MARGIN ||m||`` (four orders of magnitude beyond that) therefore means an exact
    eigenvalue below zero, and :func:`is_positive_definite_ldl` would return False. Anything
    else, including a float overflow or a non-symmetric ``m``, returns False (check exactly).
    """
    import numpy as np

    from lyapcheck.tolerances import SCREEN_MARGIN

    if not is_symmetric(m):
        return False
    try:
        values = np.linalg.eigvalsh(np.array(to_float(m), dtype=np.float64))
    except (OverflowError, np.linalg.LinAlgError):
        return False
    if not np.all(np.isfinite(values)):
        return False
    return bool(values[0] < -SCREEN_MARGIN * float(np.abs(values).max()))


def is_negative_definite(m: Matrix) -> bool:
    return is_positive_definite(scale(Fraction(-1), m))


def sign_a_plus_b_sqrt(a: Fraction, b: Fraction, q: Fraction) -> int:
    """Exact sign of ``a + b*sqrt(q)`` for ``q >= 0`` (isolate, then square with signs)."""
    if q < 0:
        raise ValueError("q must be non-negative")
    sa = (a > 0) - (a < 0)
    sb = (b > 0) - (b < 0)
    if q == 0 or sb == 0:
        return sa
    if sa == 0 or sa == sb:
        return sb
    # opposite signs: compare a^2 with b^2 q
    diff = a * a - b * b * q
    if diff == 0:
        return 0
    return sa if diff > 0 else sb


def min_eig_exceeds_2x2(m: Matrix, a: Fraction, b: Fraction, q: Fraction) -> bool:
    """Exactly decide ``lambda_min(M) > a + b sqrt(q)`` for a symmetric 2x2 rational M.

    ``lambda_min(M) > r`` iff ``M - r I`` is positive definite iff ``m11 - r > 0`` and
    ``det(M - r I) = r^2 - tr(M) r + det(M) > 0``. With ``r = a + b sqrt(q)`` both are of the
    form ``X + Y sqrt(q)``, whose signs :func:`sign_a_plus_b_sqrt` decides exactly.
    """
    if not is_symmetric(m) or len(m) != 2:
        raise ValueError("expected a symmetric 2x2 matrix")
    m11, m22, m12 = m[0][0], m[1][1], m[0][1]
    first = sign_a_plus_b_sqrt(m11 - a, -b, q)
    tr, dt = m11 + m22, m11 * m22 - m12 * m12
    # r^2 = a^2 + b^2 q + 2ab sqrt(q)
    x = a * a + b * b * q - tr * a + dt
    y = 2 * a * b - tr * b
    second = sign_a_plus_b_sqrt(x, y, q)
    return first > 0 and second > 0


def exact_decimal(x: Fraction) -> str:
    """``x`` written as a decimal with no rounding (``5/4`` -> ``"1.25"``); ValueError when its
    denominator has a prime factor other than 2 and 5 (no finite decimal exists)."""
    q, k = x.denominator, 0
    while q % 10 == 0:
        q //= 10
        k += 1
    while q % 2 == 0:
        q //= 2
        k += 1
    while q % 5 == 0:
        q //= 5
        k += 1
    if q != 1:
        raise ValueError(f"{x} has no finite decimal expansion")
    scaled = x * 10 ** k
    assert scaled.denominator == 1
    digits = str(abs(scaled.numerator)).rjust(k + 1, "0")
    text = digits[:len(digits) - k] + ("." + digits[len(digits) - k:] if k else "")
    return ("-" if x < 0 else "") + text


def sqrt_upper(q: Fraction, digits: int = 30) -> Fraction:
    """A rational ``r >= sqrt(q)``, checked exactly (``r*r >= q``)."""
    if q < 0:
        raise ValueError("q must be non-negative")
    if q == 0:
        return Fraction(0)
    # the first guess in Python's default decimal context, whatever the caller's context is (a
    # changed global precision made the certified bound depend on what ran before)
    with localcontext(_GUESS_CONTEXT):
        guess = Fraction(Decimal(q.numerator).sqrt() / Decimal(q.denominator).sqrt()) if digits else Fraction(0)
    step = guess / 10**digits + Fraction(1, 10**digits)
    # r = guess + k step with the least k >= 0 such that r^2 >= q (what stepping up one step at a
    # time finds, in hundreds of big-rational steps): k estimated in 80-digit decimals, then
    # settled exactly, so the result is the same rational
    if guess * guess >= q:
        return guess
    with localcontext() as ctx:
        ctx.prec = 80

        def dec(x: Fraction) -> Decimal:
            return Decimal(x.numerator) / Decimal(x.denominator)

        k = max(int(((dec(q).sqrt() - dec(guess)) / dec(step)).to_integral_value(rounding=ROUND_CEILING)), 1)
    while k > 1 and (guess + (k - 1) * step) ** 2 >= q:
        k -= 1
    while (guess + k * step) ** 2 < q:
        k += 1
    return guess + k * step


def sqrt_lower(q: Fraction, digits: int = 30) -> Fraction:
    """A rational ``r <= sqrt(q)``, exact: ``q / sqrt_upper(q)`` (``sqrt(q) = q / sqrt(q)``, and a
    larger divisor gives a smaller quotient)."""
    if q < 0:
        raise ValueError("q must be non-negative")
    return Fraction(0) if q == 0 else q / sqrt_upper(q, digits)


def floor_digits(x: Fraction, digits: int) -> Fraction:
    """The largest decimal with ``digits`` significant digits that is ``<= x`` (exact; ``x > 0``): a
    certified lower bound written short."""
    if x <= 0:
        raise ValueError("x must be positive")
    exponent = math.floor(math.log10(x.numerator) - math.log10(x.denominator)) - digits + 1
    quantum = Fraction(10) ** exponent
    return math.floor(x / quantum) * quantum


def has_negative_real_eigenvalue_2x2(m: Matrix) -> bool:
    """Exact: does the real 2x2 matrix M have a real eigenvalue < 0?"""
    tr = m[0][0] + m[1][1]
    dt = m[0][0] * m[1][1] - m[0][1] * m[1][0]
    disc = tr * tr - 4 * dt
    if disc < 0:
        return False
    if dt < 0:
        return True  # real roots of opposite signs
    return tr < 0  # roots of equal sign (or one zero): negative iff their sum is


def inverse_2x2(m: Matrix) -> Matrix:
    d = m[0][0] * m[1][1] - m[0][1] * m[1][0]
    if d == 0:
        raise ZeroDivisionError("singular matrix")
    return ((m[1][1] / d, -m[0][1] / d), (-m[1][0] / d, m[0][0] / d))


def is_hurwitz_2x2(m: Matrix) -> bool:
    """Exact: both eigenvalues in the open left half-plane iff trace < 0 and det > 0."""
    return (m[0][0] + m[1][1]) < 0 and (m[0][0] * m[1][1] - m[0][1] * m[1][0]) > 0


def to_json(m: Matrix) -> list[list[str]]:
    return [[str(x) for x in row] for row in m]


def from_json(rows: Sequence[Sequence[str]]) -> Matrix:
    return tuple(tuple(Fraction(x) for x in row) for row in rows)


def to_float(m: Matrix) -> list[list[float]]:
    return [[float(x) for x in row] for row in m]

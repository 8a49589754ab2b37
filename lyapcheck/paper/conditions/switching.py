"""``switched_ges``: GES under *arbitrary* variation of ``rho`` in its sector, decided exactly.

The argument (a valid proof, stated here and in reports):

Every sector class (``sector_ges``, ``prop41_*``) uses of ``rho(x)`` only that
``0 < rho(x) <= rho_sup``. A proof of that kind therefore also proves GES of the linear
differential inclusion ``x_dot = (A + rho(t) B) x`` for *every* measurable
``rho(t) in (0, rho_sup]``, in particular for a periodic switching between two admissible values
``r_0, r_1``. Write ``A_i = A + r_i B`` and ``M = expm(A_0 t_0) expm(A_1 t_1)`` (``A_1`` for
``t_1`` seconds, then ``A_0`` for ``t_0`` seconds). Along that switching ``x(k T) = M^k x(0)``
with ``T = t_0 + t_1``; if the spectral radius ``rho(M) > 1`` some trajectory grows like
``rho(M)^k``, so the inclusion is not stable and *no* Lyapunov function, of any form, that only
uses the sector bound can prove GES. (This does not show the actual closed loop unstable: there
``rho`` is a function of the state and cannot be switched at will.)

Exact proof of ``rho(M) > 1``. For a real 2x2 ``M`` with trace ``T`` and determinant ``D`` both
eigenvalues lie in the closed unit disc iff ``|D| <= 1`` and ``|T| <= 1 + D`` (Schur-Cohn / Jury
for ``z^2 - T z + D``), so ``rho(M) > 1`` iff ``|D| > 1`` or ``|T| > 1 + D``. ``T`` and ``D`` are
enclosed rigorously: rational ``t_i``; an exact similarity ``diag(1, beta)`` with ``beta`` a power of
two (trace and determinant are invariant) to balance the off-diagonal entries; for each ``i``,
``Y = A_i t_i / 2^s``, the Taylor polynomial of order ``N`` evaluated by Horner's rule in interval
arithmetic, plus the remainder ``||Y||^(N+1) / (N+1)! / (1 - ||Y||/(N+2))`` (infinity norm, which
bounds every entry) on every entry, then ``s`` interval squarings. Every interval end point is a
dyadic rational rounded *outward* to ``p`` significant bits, so the denominators stay small and
every enclosure is rigorous. The criterion is then checked on the enclosures of ``T`` and ``D``
in :class:`fractions.Fraction` arithmetic. A vertex that is not Hurwitz (exact trace/determinant
test) refutes GES directly, with ``rho`` held constant.

Exact certificate (the ``certified`` verdict): a common quadratic Lyapunov function for
``A + 0 B`` and ``A + rho_sup B``, checked exactly as in ``sector_ges`` (which see); by convexity
it decays for every ``rho(t) in [0, rho_sup]``. Shorten and Narendra's 2x2 test tells when no
such function exists; the inclusion may then still be stable (a non-quadratic Lyapunov
function), and if the search finds no growing switching either, the verdict is ``not_certified``.

Search. For planar pairs that are not stable under arbitrary switching, the worst-case
switching law is generically periodic and bang-bang, switching where ``A_0 x`` and ``A_1 x``
are collinear (Boscain 2002; Margaliot 2006), so two dwell times per period suffice. The search
maximises the growth rate ``ln rho(M) / (t_0 + t_1)`` over a log-spaced grid of dwell times (in
a time unit set by the balanced matrices, so it works at any scale of the gains) and refines the
best points by shrinking local grids. Closed-form 2x2 exponentials keep it in plain numpy. The
search only proposes ``(t_0, t_1)``; the verdict is the exact check.
"""

from __future__ import annotations

import math
import time
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Sequence

from lyapcheck import exact
from lyapcheck import tolerances as tol
from lyapcheck.paper import claims
from lyapcheck.paper.claims import ARGUMENT_SWITCHING, ARGUMENT_VERTEX
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.errors import CertificateError, InvalidParameter, SolverError
from lyapcheck.exact import read_rational

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    FloatArray = NDArray[np.float64]

Interval = tuple[Fraction, Fraction]
IntervalMatrix = tuple[tuple[Interval, ...], ...]

NAME = "switched_ges"
ARGUMENT_CQLF = "common_quadratic_lyapunov"

#: the low end of the switching, as a fraction of ``rho_sup``: ``rho = 0`` itself is not in the
#: sector ``(0, rho_sup]``, so the refutation switches to a small admissible value instead
RHO_LO_FRACTION = Fraction(1, 2**20)

# --- search (floating point; steers only) --------------------------------------------------
#: log-spaced dwell times per vertex, in the scaled time unit (largest balanced entry = 1): from
#: ``TAU_MIN`` up to ``SLOW_SPAN`` time constants of the vertex's slowest eigenvalue, within
#: ``[TAU_MAX_FLOOR, TAU_MAX_CAP]``; ``GRID_PER_DECADE`` points a decade, within the point limits
TAU_MIN = 1e-3
SLOW_SPAN = 8.0
TAU_MAX_FLOOR = 8.0
TAU_MAX_CAP = 1e14
GRID_PER_DECADE = 10
GRID_POINTS_MIN = 40
GRID_POINTS_MAX = 120
#: an unstable vertex is never integrated past ``exp(MAX_EXPONENT)``, which avoids overflow
MAX_EXPONENT = 50.0
#: local refinement: starts, rounds, and the factor the local grid shrinks by each round
REFINE_STARTS = 4
REFINE_ROUNDS = 18
REFINE_SHRINK = 0.4
REFINE_SIDE = 9
#: significant digits tried, fewest first, when rounding dwell times to rationals; the
#: shortest rounding that keeps half of the growth margin is used (a readable certificate)
TIME_DIGITS = (3, 4, 6, 9, 12)

# --- exact enclosure -----------------------------------------------------------------------
#: scaling and squaring brings ``||A t / 2^s||_inf`` to at most this
SCALE_TARGET = Fraction(1, 2)
#: the stored growth lower bound is rounded down to this many bits (readability)
BOUND_BITS = 40
#: limits on certificate fields, so that a hostile file cannot make the verifier run for ever
MAX_TAYLOR_ORDER = 400
MAX_SQUARINGS = 4000
MAX_BITS = 8192
MAX_NUMBER_BITS = 20000


# =========================================================================================
# exact interval arithmetic (Fractions only)
# =========================================================================================


def _round_down(x: Fraction, bits: int) -> Fraction:
    """The largest dyadic rational with ``bits`` significant bits that is ``<= x``."""
    n, d = x.numerator, x.denominator
    if n == 0:
        return x
    shift = bits - (abs(n).bit_length() - d.bit_length())
    if shift >= 0:
        return Fraction((n << shift) // d, 1 << shift)  # // floors, also for n < 0
    return Fraction((n // (d << -shift)) << -shift)


def _round_up(x: Fraction, bits: int) -> Fraction:
    return -_round_down(-x, bits)


def _outward(lo: Fraction, hi: Fraction, bits: int) -> Interval:
    return _round_down(lo, bits), _round_up(hi, bits)


def _imul(a: Interval, b: Interval) -> Interval:
    products = (a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1])
    return min(products), max(products)


def _imatmul(a: IntervalMatrix, b: IntervalMatrix, bits: int) -> IntervalMatrix:
    """Enclosure of ``{X Y : X in a, Y in b}``; each entry summed exactly, then rounded once."""
    n, m = len(b), len(b[0])
    rows = []
    for row in a:
        out = []
        for j in range(m):
            lo = hi = Fraction(0)
            for k in range(n):
                p_lo, p_hi = _imul(row[k], b[k][j])
                lo += p_lo
                hi += p_hi
            out.append(_outward(lo, hi, bits))
        rows.append(tuple(out))
    return tuple(rows)


def _norm_inf(m: exact.Matrix) -> Fraction:
    return max(sum((abs(x) for x in row), Fraction(0)) for row in m)


def _taylor_remainder(nu: Fraction, order: int) -> Fraction:
    """``nu^(N+1)/(N+1)! / (1 - nu/(N+2))`` bounds ``||sum_{k>N} Y^k/k!||`` when ``||Y|| = nu < N+2``."""
    return nu ** (order + 1) / math.factorial(order + 1) / (1 - nu / (order + 2))


def expm_parameters(a: exact.Matrix, t: Fraction, bits: int) -> tuple[int, int]:
    """Taylor order ``N`` and squarings ``s`` for :func:`expm_enclosure` at ``bits`` bits.

    ``s`` is the least with ``||A t||_inf / 2^s <= SCALE_TARGET``; ``N`` the least whose remainder
    bound is below ``2^-bits`` (the entries of ``expm(Y)`` are of order one).
    """
    nu = _norm_inf(a) * abs(t)
    squarings = 0
    while nu > SCALE_TARGET * 2**squarings:
        squarings += 1
    theta = nu / 2**squarings
    target = Fraction(1, 2**bits)
    order = 1
    while order < MAX_TAYLOR_ORDER and _taylor_remainder(theta, order) > target:
        order += 1
    return order, squarings


def expm_enclosure(a: exact.Matrix, t: Fraction, order: int, squarings: int, bits: int) -> IntervalMatrix:
    """An interval matrix that rigorously contains ``expm(A t)`` (scaling, Taylor, squaring).

    Parameters
    ----------
    a, t
        Exact rational matrix and time.
    order, squarings
        Taylor order ``N`` and number ``s`` of squarings; any values are rigorous as long as
        ``||A t||_inf / 2^s < N + 2`` (else ``ValueError``); :func:`expm_parameters` picks them.
    bits
        Significant bits kept by the outward rounding of every interval end point.
    """
    n = len(a)
    y = exact.scale(Fraction(t, 2**squarings), a)
    nu = _round_up(_norm_inf(y), 64)  # a simpler number >= ||Y||; the bound grows with nu
    if nu >= order + 2:
        raise ValueError(f"the Taylor remainder bound needs ||Y||_inf < N + 2 = {order + 2}; got {float(nu):.4g}")
    radius = _round_up(_taylor_remainder(nu, order), bits)
    one, zero = Fraction(1), Fraction(0)
    h: IntervalMatrix = tuple(tuple((one, one) if i == j else (zero, zero) for j in range(n)) for i in range(n))
    # Horner: H <- I + Y H / k for k = N..1 gives the Taylor polynomial of order N
    for k in range(order, 0, -1):
        rows = []
        for i in range(n):
            out = []
            for j in range(n):
                lo = hi = Fraction(0)
                for m in range(n):
                    c = y[i][m]
                    if c >= 0:
                        lo += c * h[m][j][0]
                        hi += c * h[m][j][1]
                    else:
                        lo += c * h[m][j][1]
                        hi += c * h[m][j][0]
                base = one if i == j else zero
                out.append(_outward(base + lo / k, base + hi / k, bits))
            rows.append(tuple(out))
        h = tuple(rows)
    e: IntervalMatrix = tuple(tuple(_outward(lo - radius, hi + radius, bits) for lo, hi in row) for row in h)
    for _ in range(squarings):
        e = _imatmul(e, e, bits)
    return e


def _abs_lower(iv: Interval) -> Fraction:
    """The least ``|x|`` over the interval."""
    if iv[0] > 0:
        return iv[0]
    if iv[1] < 0:
        return -iv[1]
    return Fraction(0)


def schur_cohn_margin(trace: Interval, det: Interval) -> Fraction:
    """A lower bound of ``max(|T| - 1 - D, |D| - 1)`` over the box ``trace x det``.

    For a real 2x2 matrix, ``rho(M) > 1`` iff ``|D| > 1`` or ``|T| > 1 + D``, so a positive
    value proves ``rho(M) > 1`` for every matrix whose trace and determinant lie in the box.
    """
    return max(_abs_lower(trace) - 1 - det[1], _abs_lower(det) - 1)


def spectral_radius_exceeds_one(trace: Interval, det: Interval) -> bool:
    """Exact: does every real 2x2 matrix with trace in ``trace`` and det in ``det`` have ``rho > 1``?

    With point intervals this is an exact decision (true iff ``rho(M) > 1``).
    """
    return schur_cohn_margin(trace, det) > 0


def spectral_radius_exceeds_one_2x2(m: exact.Matrix) -> bool:
    """Exact decision of ``rho(M) > 1`` for a rational 2x2 matrix (Schur-Cohn / Jury)."""
    t = m[0][0] + m[1][1]
    d = m[0][0] * m[1][1] - m[0][1] * m[1][0]
    return spectral_radius_exceeds_one((t, t), (d, d))


def _sqrt_down(q: Fraction, bits: int) -> Fraction:
    """A rational ``r <= sqrt(q)`` (``q >= 0``), within ``2^-bits``."""
    scaled = (q.numerator << (2 * bits)) // q.denominator
    return Fraction(math.isqrt(scaled), 1 << bits)


def growth_lower_bound(trace: Interval, det: Interval, bits: int = BOUND_BITS) -> Fraction:
    """A proven lower bound of ``rho(M)`` over the box ``trace x det`` (2x2, real).

    ``rho >= sqrt(|D|)`` and ``rho >= |T| / 2`` always; if ``T^2 - 4 D > 0`` on the whole box the
    eigenvalues are real and ``rho = (|T| + sqrt(T^2 - 4 D)) / 2``, increasing in ``|T|`` and
    decreasing in ``D``.
    """
    abs_t = _abs_lower(trace)
    bound = max(_sqrt_down(_abs_lower(det), bits + 8), abs_t / 2)
    disc = abs_t * abs_t - 4 * det[1]
    if disc > 0:
        bound = max(bound, (abs_t + _sqrt_down(disc, bits + 8)) / 2)
    return _round_down(bound, bits) if bound > 0 else Fraction(0)


def _balance(vertices: Sequence[exact.Matrix]) -> Fraction:
    """A power of two ``beta`` with ``|a12| beta ~ |a21| / beta`` over both vertices.

    A power of two brings no new prime factors into the denominators of ``D^-1 A D``.
    """
    a12 = sum((abs(v[0][1]) for v in vertices), Fraction(0))
    a21 = sum((abs(v[1][0]) for v in vertices), Fraction(0))
    if a12 == 0 or a21 == 0:
        return Fraction(1)
    log2_ratio = (math.log2(a21.numerator) - math.log2(a21.denominator)
                  - math.log2(a12.numerator) + math.log2(a12.denominator))
    return Fraction(2) ** round(log2_ratio / 2)


def _similar(a: exact.Matrix, beta: Fraction) -> exact.Matrix:
    """``diag(1, beta)^-1 A diag(1, beta)``, exactly."""
    return ((a[0][0], a[0][1] * beta), (a[1][0] / beta, a[1][1]))


def _trace_det(vertices: Sequence[exact.Matrix], times: Sequence[Fraction], beta: Fraction,
               orders: Sequence[int], squarings: Sequence[int], bits: int) -> tuple[Interval, Interval]:
    """Enclosures of trace and determinant of ``expm(A_0 t_0) expm(A_1 t_1)``."""
    encl = [expm_enclosure(_similar(v, beta), t, n, s, bits)
            for v, t, n, s in zip(vertices, times, orders, squarings)]
    m = _imatmul(encl[0], encl[1], bits)
    trace = _outward(m[0][0][0] + m[1][1][0], m[0][0][1] + m[1][1][1], bits)
    diag = _imul(m[0][0], m[1][1])
    off = _imul(m[0][1], m[1][0])
    det = _outward(diag[0] - off[1], diag[1] - off[0], bits)
    return trace, det


def _check_vertices(vertices: Sequence[exact.Matrix]) -> list[exact.Matrix]:
    """Two real 2x2 rational matrices, or ``InvalidParameter``."""
    ok = (len(vertices) == 2 and all(len(v) == 2 and all(len(r) == 2 for r in v) for v in vertices))
    if not ok:
        raise InvalidParameter("vertices", "two 2x2 rational matrices", vertices)
    return [tuple(tuple(Fraction(x) for x in row) for row in v) for v in vertices]


def certify_unstable_switching(vertices: Sequence[exact.Matrix], t0: Fraction, t1: Fraction,
                               bits_tried: Sequence[int] = tol.SWITCHING_ENCLOSURE_BITS) -> dict[str, Any] | None:
    """Exact proof that ``rho(expm(A_0 t_0) expm(A_1 t_1)) > 1``, as a JSON-able certificate.

    Parameters
    ----------
    vertices
        ``[A_0, A_1]``, exact 2x2 matrices.
    t0, t1
        Rational dwell times (``>= 0``, not both zero).
    bits_tried
        Enclosure precisions tried in turn; the first that proves the criterion is kept.

    Returns
    -------
    dict or None
        The certificate (keys: see :func:`verify_unstable_switching`), or None when no
        precision proves ``rho > 1`` (it may be ``<= 1``).
    """
    verts = _check_vertices(vertices)
    t0, t1 = Fraction(t0), Fraction(t1)
    if t0 < 0 or t1 < 0 or t0 + t1 == 0:
        raise InvalidParameter("t0, t1", "non-negative dwell times, not both zero", (str(t0), str(t1)))
    beta = _balance(verts)
    balanced = [_similar(v, beta) for v in verts]
    for bits in bits_tried:
        params = [expm_parameters(b, t, bits) for b, t in zip(balanced, (t0, t1))]
        orders, squarings = [p[0] for p in params], [p[1] for p in params]
        trace, det = _trace_det(verts, (t0, t1), beta, orders, squarings, bits)
        if not spectral_radius_exceeds_one(trace, det):
            continue
        criterion = "|T| > 1 + D" if _abs_lower(trace) - 1 - det[1] > 0 else "|D| > 1"
        bound = growth_lower_bound(trace, det)
        return {
            "argument": ARGUMENT_SWITCHING,
            "vertices": [exact.to_json(v) for v in verts],
            "t0": str(t0), "t1": str(t1),
            "balance": str(beta),
            "taylor_order": orders, "squarings": squarings, "precision_bits": bits,
            "trace": [str(trace[0]), str(trace[1])], "det": [str(det[0]), str(det[1])],
            "criterion": criterion,
            "growth_lower_bound": str(bound),
            "statement": _statement(bound, t0, t1, criterion),
        }
    return None


def _statement(bound: Fraction, t0: Fraction, t1: Fraction, criterion: str) -> str:
    """What a periodic-switching certificate states (``verify`` regenerates it)."""
    return (f"rho(expm(A0 t0) expm(A1 t1)) >= {float(bound):.6g} > 1 with t0 = {float(t0):.6g}, "
            f"t1 = {float(t1):.6g} ({criterion} on rigorous enclosures of T and D)")


def growth_upper_bound(trace: Interval, det: Interval) -> float:
    """An upper bound (in floating point) on the spectral radius of any real 2x2 matrix whose trace
    and determinant lie in the intervals: the roots of ``z^2 - T z + D`` have modulus at most
    ``(|T| + sqrt(T^2 + 4 |D|)) / 2``. ``verify`` holds the search's estimate of the growth to it."""
    t = float(max(abs(trace[0]), abs(trace[1])))
    d = float(max(abs(det[0]), abs(det[1])))
    return (t + math.sqrt(t * t + 4 * d)) / 2


def _fraction_field(cert: dict[str, Any], key: str) -> Fraction:
    value = read_rational(cert[key])
    if value.numerator.bit_length() > MAX_NUMBER_BITS or value.denominator.bit_length() > MAX_NUMBER_BITS:
        raise ValueError(f"'{key}' has more than {MAX_NUMBER_BITS} bits")
    return value


def _int_pair(cert: dict[str, Any], key: str, upper: int) -> list[int]:
    values = cert[key]
    if (not isinstance(values, list) or len(values) != 2
            or not all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= upper for v in values)):
        raise ValueError(f"'{key}' must be two integers in [0, {upper}]; got {values!r}")
    return values


def _interval_field(cert: dict[str, Any], key: str) -> Interval:
    lo, hi = (read_rational(x) for x in cert[key])
    if lo > hi:
        raise ValueError(f"'{key}' is an empty interval")
    return lo, hi


def verify_unstable_switching(vertices: Sequence[exact.Matrix], certificate: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a :func:`certify_unstable_switching` certificate from scratch, in Fractions only.

    Certificate keys: ``argument`` (``"periodic_switching_2x2"``), ``vertices`` (``[A_0, A_1]``
    as rational strings), ``t0``, ``t1`` (rational strings, seconds of the system), ``balance``
    (``beta`` of the similarity ``diag(1, beta)``), ``taylor_order`` and ``squarings`` (one per
    vertex), ``precision_bits``, ``trace`` and ``det`` (stated enclosures ``[lo, hi]`` of ``T`` and
    ``D`` of ``M = expm(A_0 t_0) expm(A_1 t_1)``), ``criterion``, ``growth_lower_bound``,
    ``statement``.

    The enclosures are recomputed; the stated ones must contain them, the Schur-Cohn criterion
    must hold on the stated ones and they must imply the stated growth bound.

    Returns
    -------
    (ok, why)
        ``ok`` is true only if every check passed.

    Raises
    ------
    CertificateError
        If a field is missing or not of the expected form.
    """
    try:
        verts = _check_vertices(vertices)
        if certificate["argument"] != ARGUMENT_SWITCHING:
            raise ValueError(f"argument is {certificate['argument']!r}, not {ARGUMENT_SWITCHING!r}")
        stated_vertices = [exact.from_json(v) for v in certificate["vertices"]]
        t0, t1 = _fraction_field(certificate, "t0"), _fraction_field(certificate, "t1")
        beta = _fraction_field(certificate, "balance")
        orders = _int_pair(certificate, "taylor_order", MAX_TAYLOR_ORDER)
        squarings = _int_pair(certificate, "squarings", MAX_SQUARINGS)
        bits = certificate["precision_bits"]
        if not isinstance(bits, int) or isinstance(bits, bool) or not 8 <= bits <= MAX_BITS:
            raise ValueError(f"'precision_bits' must be an integer in [8, {MAX_BITS}]; got {bits!r}")
        trace = _interval_field(certificate, "trace")
        det = _interval_field(certificate, "det")
        claimed = _fraction_field(certificate, "growth_lower_bound")
    except (KeyError, TypeError, ValueError, ZeroDivisionError, IndexError, AttributeError) as exc:
        raise CertificateError(f"switched_ges certificate is malformed: {exc}") from None
    if stated_vertices != verts:
        return False, "the certificate's vertex matrices are not the system's"
    if t0 < 0 or t1 < 0 or t0 + t1 == 0:
        return False, "dwell times must be non-negative and not both zero"
    if beta <= 0:
        return False, "the balancing factor must be positive"
    try:
        fresh_t, fresh_d = _trace_det(verts, (t0, t1), beta, orders, squarings, bits)
    except ValueError as exc:  # the remainder bound does not apply at these parameters
        return False, str(exc)
    if not (trace[0] <= fresh_t[0] and fresh_t[1] <= trace[1] and det[0] <= fresh_d[0] and fresh_d[1] <= det[1]):
        return False, "the stated enclosures of trace and determinant do not contain the recomputed ones"
    if not spectral_radius_exceeds_one(trace, det):
        return False, "the Schur-Cohn criterion (|D| > 1 or |T| > 1 + D) does not hold on the enclosures"
    bound = growth_lower_bound(trace, det)
    if claimed > bound:
        return False, f"the stated growth bound {float(claimed):.6g} exceeds what the enclosures prove ({float(bound):.6g})"
    criterion = "|T| > 1 + D" if _abs_lower(trace) - 1 - det[1] > 0 else "|D| > 1"
    stated = _statement(claimed, t0, t1, criterion)
    if certificate.get("criterion") != criterion or certificate.get("statement") != stated:
        return False, f"the stated criterion or statement is not the enclosures'; they give: {stated!r}"
    return True, (f"rho(expm(A0 t0) expm(A1 t1)) >= {float(claimed):.6g} > 1 proven exactly "
                  f"(t0 = {float(t0):.6g}, t1 = {float(t1):.6g}; {criterion} on the enclosures of T and D)")


# =========================================================================================
# numerical search (numpy only, imported lazily: the exact checks above never need it)
# =========================================================================================


def _float_matrices(vertices: Sequence[exact.Matrix], beta: Fraction) -> tuple[list[FloatArray], float]:
    """Balanced vertices divided by their largest entry, and that entry (the time scale)."""
    import numpy as np

    try:
        mats = [np.array(exact.to_float(_similar(v, beta)), dtype=float) for v in vertices]
    except OverflowError:
        raise SolverError("a vertex entry is too large for floating point; the switching search cannot run") from None
    scale = max(float(np.abs(m).max()) for m in mats)
    if not math.isfinite(scale):
        raise SolverError("non-finite vertex entries; the switching search cannot run")
    if scale == 0:
        return mats, 0.0
    return [m / scale for m in mats], scale


def _expm2(a: FloatArray, tau: FloatArray) -> FloatArray:
    """``expm(a tau)`` for a real 2x2 ``a`` at every entry of ``tau``, shape ``tau.shape + (2, 2)``.

    ``a = m I + N`` with ``N^2 = q I``, so ``expm(a tau) = e^(m tau) (c I + s N)`` with cosh/sinh
    (``q > 0``) or cos/sin (``q < 0``); the exponentials are combined before evaluation so
    that a stiff stable matrix does not overflow in ``cosh``.
    """
    import numpy as np

    m = 0.5 * (a[0, 0] + a[1, 1])
    n = a - m * np.eye(2)
    q = 0.25 * (a[0, 0] - a[1, 1]) ** 2 + a[0, 1] * a[1, 0]
    if q > 0:
        r = math.sqrt(q)
        rt = r * tau
        small = rt < 1
        rs = np.where(small, rt, 0.0)
        sinhc = np.where(rs > 0, np.sinh(rs) / np.where(rs > 0, rs, 1.0), 1.0)
        grow = np.exp(np.where(small, 0.0, (m + r) * tau))
        decay = np.exp(np.where(small, 0.0, (m - r) * tau))
        em = np.exp(np.where(small, m * tau, 0.0))
        c = np.where(small, em * np.cosh(rs), 0.5 * (grow + decay))
        s = np.where(small, em * tau * sinhc, (grow - decay) / (2 * r))
    elif q < 0:
        w = math.sqrt(-q)
        em = np.exp(m * tau)
        c = em * np.cos(w * tau)
        s = em * np.sin(w * tau) / w
    else:
        c = np.exp(m * tau)
        s = c * tau
    result: FloatArray = c[..., None, None] * np.eye(2) + s[..., None, None] * n
    return result


def _log_radius(mats: list[FloatArray], tau0: FloatArray, tau1: FloatArray) -> FloatArray:
    """``ln rho(expm(A_0 tau0) expm(A_1 tau1))`` (broadcast).

    The eigenvalues of ``M`` are ``T/2 +- sqrt(q)`` with ``q = ((m11 - m22)/2)^2 + m12 m21``, taken from
    the entries: the textbook ``T^2/4 - D`` cancels near ``M = I`` and would put an error of
    ``sqrt(eps) ~ 1e-8`` on ``rho`` at short dwell times, a spurious "growth". The determinant
    is exact, ``exp(tr A_0 tau0 + tr A_1 tau1)``, for the complex case ``rho = sqrt(D)``.
    """
    import numpy as np

    m = np.einsum("...ab,...bc->...ac", _expm2(mats[0], tau0), _expm2(mats[1], tau1))
    half_trace = 0.5 * (m[..., 0, 0] + m[..., 1, 1])
    q = 0.25 * (m[..., 0, 0] - m[..., 1, 1]) ** 2 + m[..., 0, 1] * m[..., 1, 0]
    log_det = np.trace(mats[0]) * tau0 + np.trace(mats[1]) * tau1
    with np.errstate(divide="ignore"):
        real = np.log(np.abs(half_trace) + np.sqrt(np.maximum(q, 0.0)))
    out: FloatArray = np.where(q >= 0, real, 0.5 * log_det)
    return out


def _rate(mats: list[FloatArray], tau0: FloatArray, tau1: FloatArray) -> FloatArray:
    """Growth rate ``ln rho(M) / (tau0 + tau1)`` (scaled units); ``-inf`` where undefined."""
    import numpy as np

    tau0, tau1 = np.broadcast_arrays(tau0, tau1)
    period = tau0 + tau1
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        value = _log_radius(mats, tau0, tau1) / np.where(period > 0, period, 1.0)
    out: FloatArray = np.where((period > 0) & np.isfinite(value), value, -np.inf)
    return out


def _eigen_summary(a: FloatArray) -> tuple[list[float], float]:
    """Eigenvalue moduli and the largest real part of a real 2x2 matrix (closed form)."""
    m = 0.5 * (a[0, 0] + a[1, 1])
    q = 0.25 * (a[0, 0] - a[1, 1]) ** 2 + a[0, 1] * a[1, 0]
    if q >= 0:
        r = math.sqrt(q)
        return [abs(m + r), abs(m - r)], m + r
    modulus = math.sqrt(m * m - q)
    return [modulus, modulus], m


def _dwell_ranges(mats: list[FloatArray]) -> list[float]:
    """Longest dwell searched per vertex (scaled units).

    Each vertex gets its own range: when the two vertices' rates are far apart (badly scaled
    gains give 1e12), the worst switching dwells on each vertex for its own time constants.
    """
    out = []
    for a in mats:
        moduli, re_max = _eigen_summary(a)
        slow = min((x for x in moduli if x > 0), default=0.0)
        tau_max = min(max(SLOW_SPAN / slow, TAU_MAX_FLOOR), TAU_MAX_CAP) if slow > 0 else TAU_MAX_CAP
        # an unstable vertex: stop before exp() overflows (the growth is found long before)
        out.append(min(tau_max, MAX_EXPONENT / re_max) if re_max > 0 else tau_max)
    return out


def _grid(tau_max: float) -> FloatArray:
    """Zero and log-spaced dwell times up to ``tau_max``."""
    import numpy as np

    points = int(np.clip(GRID_PER_DECADE * math.log10(tau_max / TAU_MIN), GRID_POINTS_MIN, GRID_POINTS_MAX))
    out: FloatArray = np.concatenate(([0.0], np.geomspace(TAU_MIN, tau_max, points)))
    return out


def _zoom(mats: list[FloatArray], start: tuple[float, float], steps: tuple[float, float],
          bounds: list[tuple[float, float]]) -> tuple[float, float, float, int]:
    """Maximise the growth rate around ``start`` (log dwell times) on shrinking local grids."""
    import numpy as np

    offsets = np.linspace(-1.0, 1.0, REFINE_SIDE)
    u = np.array(start, dtype=float)
    h = np.array(steps, dtype=float)
    best = float(_rate(mats, np.exp(u[0:1]), np.exp(u[1:2]))[0])
    evaluations = 1
    for _ in range(REFINE_ROUNDS):
        u0 = np.clip(u[0] + h[0] * offsets, *bounds[0])[:, None]
        u1 = np.clip(u[1] + h[1] * offsets, *bounds[1])[None, :]
        values = _rate(mats, np.exp(u0), np.exp(u1))
        evaluations += values.size
        i, j = np.unravel_index(int(np.argmax(values)), values.shape)
        if values[i, j] > best:
            best = float(values[i, j])
            u = np.array([u0[i, 0], u1[0, j]])
        h *= REFINE_SHRINK
    return float(u[0]), float(u[1]), best, evaluations


def find_unstable_switching(vertices: Sequence[exact.Matrix]) -> dict[str, Any] | None:
    """Numerical search for dwell times with ``rho(expm(A_0 t_0) expm(A_1 t_1)) > 1``.

    Parameters
    ----------
    vertices
        ``[A_0, A_1]``, exact 2x2 matrices (time unit: that of the system, seconds).

    Returns
    -------
    dict or None
        ``t0``, ``t1`` (floats), ``t0_exact``, ``t1_exact`` (short rational strings, the
        values to prove), ``growth_per_period`` (``rho(M)`` at the rational times, float),
        ``growth_rate`` (``ln rho / (t0 + t1)``, per time unit), ``time_scale`` (the rate that
        normalises time in the search), ``evaluations``, ``seconds``; None when no switching
        with ``rho(M) > 1 + SWITCHING_MIN_GROWTH`` was found. Nothing here is a proof.

    Raises
    ------
    SolverError
        If the vertices cannot be represented in floating point.
    """
    import numpy as np

    started = time.perf_counter()
    verts = _check_vertices(vertices)
    beta = _balance(verts)
    mats, scale = _float_matrices(verts, beta)
    if scale == 0:
        return None  # x_dot = 0: nothing grows
    # overflow and 0 * inf only occur at points that are masked as -inf anyway
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        return _search(mats, scale, started)


def _search(mats: list[FloatArray], scale: float, started: float) -> dict[str, Any] | None:
    """The body of :func:`find_unstable_switching`, on balanced, time-scaled float matrices."""
    import numpy as np

    tau_max = _dwell_ranges(mats)
    grids = [_grid(t_max) for t_max in tau_max]
    values = _rate(mats, grids[0][:, None], grids[1][None, :])
    evaluations = values.size
    if not np.isfinite(values).any():
        raise SolverError("the switching search produced no finite growth rate")
    # refine from the best grid points that lie apart (distinct peaks, not one peak's shoulders)
    starts: list[tuple[int, int]] = []
    for flat in np.argsort(values, axis=None)[::-1]:
        i, j = (int(k) for k in np.unravel_index(int(flat), values.shape))
        if not np.isfinite(values[i, j]) or len(starts) == REFINE_STARTS:
            break
        if all(max(abs(i - a), abs(j - b)) > 2 for a, b in starts):
            starts.append((i, j))
    best = (-np.inf, 0.0, 0.0)
    bounds = [(math.log(TAU_MIN) - 3.0, math.log(t_max)) for t_max in tau_max]
    steps = tuple(math.log(grid[2] / grid[1]) for grid in grids)
    for i, j in starts:
        tau0, tau1, value = float(grids[0][i]), float(grids[1][j]), float(values[i, j])
        if tau0 > 0 and tau1 > 0:
            u0, u1, value, count = _zoom(mats, (math.log(tau0), math.log(tau1)), (steps[0], steps[1]), bounds)
            evaluations += count
            tau0, tau1 = math.exp(u0), math.exp(u1)
        if value > best[0]:
            best = (value, tau0, tau1)
    rate, tau0, tau1 = best
    min_log_growth = math.log1p(tol.SWITCHING_MIN_GROWTH)
    if not rate > 0 or rate * (tau0 + tau1) <= min_log_growth:
        return None
    # the shortest rational dwell times that keep half of the numerical growth margin
    target = max(0.5 * rate * (tau0 + tau1), min_log_growth)
    for digits in TIME_DIGITS:
        r0 = exact.to_rational(tau0 / scale, digits)
        r1 = exact.to_rational(tau1 / scale, digits)
        log_growth = float(_log_radius(mats, np.array(float(r0) * scale), np.array(float(r1) * scale)))
        if r0 + r1 > 0 and log_growth > target:
            period = float(r0 + r1)
            return {"t0": float(r0), "t1": float(r1), "t0_exact": str(r0), "t1_exact": str(r1),
                    "growth_per_period": math.exp(log_growth), "growth_rate": log_growth / period,
                    "time_scale": scale, "evaluations": int(evaluations),
                    "seconds": time.perf_counter() - started}
    return None


# =========================================================================================
# the condition class
# =========================================================================================


def _find_common_quadratic(vertices: list[exact.Matrix]) -> tuple[exact.Matrix, Fraction] | None:
    """Search ``P > 0`` with ``A_i^T P + P A_i < 0`` at both vertices, checked exactly.

    ``P~ = [[1, b], [b, b^2 + e^z]]`` (positive definite for all ``b, z``) in the balanced,
    time-scaled coordinates; the worst normalised vertex eigenvalue is minimised over ``(b, z)``
    on a grid refined by shrinking local grids. Returns ``(P, decay rate)`` or None.
    """
    import numpy as np

    from lyapcheck.paper.conditions import sector

    beta = _balance(vertices)
    mats, scale = _float_matrices(vertices, beta)
    if scale == 0:
        return None

    def margin(b: FloatArray, z: FloatArray) -> FloatArray:
        b, z = np.broadcast_arrays(b, z)
        p11, p12, p22 = np.ones_like(b), b, b * b + np.exp(z)
        worst = np.full(b.shape, -np.inf)
        for a in mats:
            # L = A^T P + P A, entrywise
            l11 = 2 * (a[0, 0] * p11 + a[1, 0] * p12)
            l22 = 2 * (a[0, 1] * p12 + a[1, 1] * p22)
            l12 = a[0, 0] * p12 + a[1, 0] * p22 + p11 * a[0, 1] + p12 * a[1, 1]
            lam = 0.5 * (l11 + l22) + np.sqrt(0.25 * (l11 - l22) ** 2 + l12 * l12)
            worst = np.maximum(worst, lam)
        p_max = 0.5 * (p11 + p22) + np.sqrt(0.25 * (p11 - p22) ** 2 + p12 * p12)
        out: FloatArray = -worst / p_max
        return out

    bs, zs = np.linspace(-4.0, 4.0, 33), np.linspace(-8.0, 8.0, 33)
    with np.errstate(over="ignore", invalid="ignore"):
        values = np.nan_to_num(margin(bs[:, None], zs[None, :]), nan=-np.inf)
        i, j = np.unravel_index(int(np.argmax(values)), values.shape)
        b, z, best = float(bs[i]), float(zs[j]), float(values[i, j])
        h = np.array([bs[1] - bs[0], zs[1] - zs[0]])
        offsets = np.linspace(-1.0, 1.0, REFINE_SIDE)
        for _ in range(REFINE_ROUNDS):
            cand = np.nan_to_num(margin((b + h[0] * offsets)[:, None], (z + h[1] * offsets)[None, :]), nan=-np.inf)
            k, m = np.unravel_index(int(np.argmax(cand)), cand.shape)
            if cand[k, m] > best:
                b, z, best = b + h[0] * offsets[k], z + h[1] * offsets[m], float(cand[k, m])
            h *= REFINE_SHRINK
    if not best > 0:
        return None
    bq = exact.to_rational(b, 10)
    cq = bq * bq + exact.to_rational(math.exp(z), 10)
    # P = D^-1 P~ D^-1 for x~ = D^-1 x, D = diag(1, beta)
    p = ((Fraction(1), bq / beta), (bq / beta, cq / (beta * beta)))
    # x^T (A^T P + P A) x = scale x~^T L~ x~ <= -scale best lambda_max(P~) |x~|^2 <= -scale best V,
    # so V decays with 2 mu = scale best; 10 % is left for the rounding to rationals
    rate = exact.to_rational(0.45 * scale * best, 4)
    for _ in range(30):
        if sector.exact_check(vertices, p, rate)[0]:
            return p, rate
        rate /= 2
    return (p, Fraction(0)) if sector.exact_check(vertices, p, Fraction(0))[0] else None


def verify(system: System, certificate: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a ``switched_ges`` refutation or certificate against ``system``, exactly.

    Raises
    ------
    CertificateError
        If a field is missing or not of the expected form.
    """
    try:
        argument = certificate["argument"]
        if argument == ARGUMENT_SWITCHING:
            rhos = [read_rational(r) for r in certificate["rho"]]
            if len(rhos) != 2:
                raise ValueError("'rho' must hold two values")
        elif argument == ARGUMENT_VERTEX:
            rhos = [read_rational(certificate["rho"])]
        elif argument == ARGUMENT_CQLF:
            rho_lo = read_rational(certificate["rho_lo"])
            p = exact.from_json(certificate["P"])
            rate = read_rational(certificate["decay_rate"])
        else:
            raise ValueError(f"unknown argument {argument!r}")
    except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
        raise CertificateError(f"switched_ges certificate is malformed: {exc}") from None
    if argument == ARGUMENT_CQLF:
        from lyapcheck.paper.conditions import sector

        if rho_lo > 0:
            return False, "the Lyapunov inequalities must hold down to rho = 0 to cover the sector (0, rho_sup]"
        return sector.exact_check([system.vertex(rho_lo), system.vertex(system.rho_sup)], p, rate)
    if not all(0 < r <= system.rho_sup for r in rhos):
        return False, "a switching value of rho lies outside the sector (0, rho_sup]"
    if argument == ARGUMENT_VERTEX:
        vertex = system.vertex(rhos[0])
        if exact.is_hurwitz_2x2(vertex):
            return False, "the stated vertex is Hurwitz"
        try:
            stated = exact.from_json(certificate["vertex"])
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            raise CertificateError(f"switched_ges certificate is malformed: {exc}") from None
        if stated != vertex or certificate.get("statement") != claims.vertex_not_hurwitz(rhos[0], vertex):
            return False, "the stated vertex matrix or statement is not that of A + rho B at the stated rho"
        return True, f"A + rho B at rho = {float(rhos[0]):.6g} is not Hurwitz (exact trace/determinant test)"
    return verify_unstable_switching([system.vertex(r) for r in rhos], certificate)


def _vertex_refutation(rho: Fraction, vertex: exact.Matrix, numbers: dict[str, Any]) -> ConditionResult:
    refutation = {"argument": ARGUMENT_VERTEX, "rho": str(rho), "vertex": exact.to_json(vertex),
                  "statement": claims.vertex_not_hurwitz(rho, vertex)}
    return claims.decided(ConditionResult(NAME, "refuted", "", numbers=numbers, refutation=refutation))


def run(system: System) -> ConditionResult:
    """GES of ``x_dot = (A + rho(t) B) x`` for every ``rho(t) in (0, rho_sup]``: refute or certify.

    ``refuted``: an exactly proven exponentially growing switching (or a non-Hurwitz vertex);
    ``certified``: an exactly checked common quadratic Lyapunov function on ``[0, rho_sup]``;
    ``not_certified``: neither was found; ``inconclusive``: numerical trouble, or a growing
    switching that the exact enclosure could not confirm.
    """
    started = time.perf_counter()
    rho_lo = system.rho_sup * RHO_LO_FRACTION
    rhos = (rho_lo, system.rho_sup)
    vertices = [system.vertex(r) for r in rhos]
    numbers: dict[str, Any] = {"rho_switch": [str(r) for r in rhos]}
    for r, v in zip(rhos, vertices):
        if not exact.is_hurwitz_2x2(v):
            return _vertex_refutation(r, v, numbers)
    try:
        found = find_unstable_switching(vertices)
    except SolverError as exc:
        return ConditionResult(NAME, "inconclusive", f"switching search failed: {exc}; nothing proved",
                               numbers=numbers)
    solver: dict[str, Any] = {"method": "log grid + shrinking local grids over (t0, t1)"}
    if found is not None:
        solver.update(evaluations=found["evaluations"], search_seconds=found["seconds"])
        t0, t1 = Fraction(found["t0_exact"]), Fraction(found["t1_exact"])
        cert = certify_unstable_switching(vertices, t0, t1)
        numbers.update(growth_per_period=found["growth_per_period"], t0_s=float(t0), t1_s=float(t1),
                       period_s=float(t0 + t1), growth_rate_per_s=found["growth_rate"])
        if cert is None:
            solver["seconds"] = time.perf_counter() - started
            return ConditionResult(NAME, "inconclusive",
                                   f"a switching with growth {found['growth_per_period']:.6g} per period was found "
                                   "numerically, but the exact enclosure could not confirm rho > 1; nothing proved",
                                   numbers=numbers, solver=solver)
        refutation = {**cert, "rho": [str(r) for r in rhos]}
        ok, why = verify(system, refutation)
        solver["seconds"] = time.perf_counter() - started
        if not ok:  # pragma: no cover - a fresh certificate failing its own re-check is a bug
            return ConditionResult(NAME, "inconclusive", f"exact re-check failed: {why}", numbers=numbers,
                                   solver=solver)
        numbers["growth_per_period_lower_bound"] = float(Fraction(cert["growth_lower_bound"]))
        return claims.decided(ConditionResult(NAME, "refuted", "", numbers=numbers, refutation=refutation,
                                              solver=solver))
    closed = [system.vertex(Fraction(0)), system.vertex(system.rho_sup)]
    from lyapcheck.paper.conditions import sector

    no_quadratic = sector.refutation(closed)
    found_p = None if no_quadratic is not None else _find_common_quadratic(closed)
    solver["seconds"] = time.perf_counter() - started
    if found_p is not None:
        p, rate = found_p
        ok, why = sector.exact_check(closed, p, rate)
        if ok:
            numbers["decay_rate_per_s"] = float(rate)
            certificate = {"argument": ARGUMENT_CQLF, "P": exact.to_json(p), "decay_rate": str(rate), "rho_lo": "0"}
            return claims.decided(ConditionResult(NAME, "certified", "", numbers=numbers, certificate=certificate,
                                                  solver=solver))
    why_not = ("no common quadratic Lyapunov function exists (Shorten-Narendra), "
               if no_quadratic is not None else "no common quadratic Lyapunov function was found, ")
    return ConditionResult(NAME, "not_certified",
                           f"no exponentially growing periodic switching of rho was found and {why_not}"
                           "so stability under arbitrary variation of rho is undecided; nothing proved",
                           numbers=numbers, solver=solver)

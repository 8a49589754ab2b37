"""``V' < 0`` on a cell of an ellipsoid's coordinates from an exact polynomial model of ``V'`` in them
(issue 42): the shell test of :mod:`lyapcheck.models.engines.ellipsoid_cells` on loops of sines and cosines.

Ball arithmetic through the loop's expression loses the correlations of the ellipsoid's tilted
coordinates: ``z = M y`` with ``M`` of condition number about 200 for an LQR robot's ``P``, and every
enclosure of the field's derivatives over a cell comes out hundreds of times wider than their variation
over it. Here the change of variables is made once, exactly, on polynomials instead:

1. **The model.** The states' flows are ``f_i = N_i / D_i`` in the recasting (states and the auxiliaries
   ``s = sin(u)``, ``c = cos(u)``, each ``u`` a polynomial of the states vanishing at the equilibrium, in
   deviations). With ``D`` the product of the distinct denominators (each signed positive at the
   equilibrium), ``G = V' D = 2 sum_i (P z)_i N_i D / D_i`` is a polynomial of the states and the
   auxiliaries. Each auxiliary is replaced by its Taylor polynomial in ``u`` plus a remainder variable
   ``r`` (Lagrange: ``|sin u - T| <= |u|^(k+2) / (k+2)!`` for the odd degree ``k``, the same for ``cos u - 1``
   with the even one; every derivative of sin and cos is at most 1), and ``z`` by ``M y``, all in exact
   rationals: ``G(M y) = p(y) + q(y, r)`` exactly, every term of ``q`` holding an ``r``.
2. **Its error.** On the box ``|y_i| <= h_i`` around the ellipsoid, ``|u| <= U`` (the sum of ``|coefficient|
   h^alpha`` of ``u(M y)``) and ``|r| <= U^(k+2) / (k+2)!``; ``|q|`` and the terms of ``p`` above the degree
   kept (POLY_CELL_DEGREE) are bounded the same way, and so is the rounding of ``p``'s coefficients to
   floats: ``|G(M y) - p~(y)| <= error`` on the box, exactly, then rounded up. Each ``D_i`` is proved
   positive on the box by ball arithmetic on the true functions (the states' balls about the equilibrium,
   arb's sine and cosine of their arguments' balls, in the model file's own variables); otherwise the
   model is not made.
3. **A cell.** ``p~`` is expanded about the cell's centre ``m`` (``p~(m + t) = sum A_alpha t^alpha``, the
   Taylor shift one axis at a time, in floats) and bounded over ``|t_i| <= w_i``: ``A_0 + sum |A_alpha|
   w^alpha``, a term of even exponents counting only where ``A_alpha > 0``. The floating-point error of
   the shift is bounded by ``gamma_K`` times the same shift of ``|p~|`` with ``|m|`` (``gamma_K = K u / (1 -
   K u)``, ``u = 2^-53``, the bound on a sum of ``K`` products in any order, FMA or not), and the final sum's
   by another ``gamma``: where ``A_0`` plus all that plus ``error`` is below 0, ``G < 0``, so ``V' < 0``,
   on the cell. The expansion's first-order term is the gradient at the centre, exact up to rounding: the
   bound's spread is the polynomial's own variation over the cell, not that of enclosures.
   **The cell's own error.** Where the box's ``error`` fails a cell, the error is bounded again on the cell's
   own box ``|y_i| <= b_i`` (``b_i`` the larger ``|end|`` of its side; the error's terms have coefficients
   ``>= 0``, so their sum at ``b`` bounds them on the cell): the box's corners, where ``|y|`` is ``sqrt(n)``
   times the ellipsoid's radius, set ``error``, while a cell at the ellipsoid's boundary has most of its
   ``|y_i|`` small (the acrobot's design aimed at its simulated region, level 0.9: 0.037 on the box, 1e-12 to
   4e-6 on cells at the boundary). In floats (:func:`upper_sum`): each power and product on mantissas in
   ``[1/2, 1)`` (``frexp``), the exponents added exactly, so that nothing underflows before the last
   ``ldexp``; the result is rounded up by ``gamma`` of the operations and ``2^-1074`` per term.

4. **A ball about the equilibrium** (:func:`decreasing_ball`): ``G`` has no constant or linear term, so
   with its quadratic part at most ``-mu |y|^2`` and its other terms bounded by ``C_k |y|^k``, ``G < 0``
   on a shell ``inner <= |y| <= rho`` where the cells need not go.

The exact part (1) is made once per loop, ``P`` and ``M`` (a fraction of a second at 4 states) and kept
for the search's other levels; the error (2) is a polynomial evaluation per box. A cell costs 2n products
of a ``(degree + 1) x (degree + 1)`` matrix with the ``(degree + 1)^n`` floats, so the model is kept for
loops where that tensor has at most POLY_CELL_MAX_ENTRIES entries (4 states at degree 14).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final, Sequence

import flint
import numpy as np

from lyapcheck.exact import float_above
from lyapcheck.models.engines.interval_field import negative_definite
from lyapcheck.models.language.recast import RecastSystem
from lyapcheck.sos.polynomials import degree_in
from lyapcheck.tolerances import POLY_CELL_COS_DEGREE, POLY_CELL_DEGREE, POLY_CELL_MAX_ENTRIES, POLY_CELL_SIN_DEGREE

#: the unit roundoff of IEEE doubles (round to nearest)
UNIT_ROUNDOFF: Final = 2.0 ** -53
#: added to every floating-point upper bound, for products that underflow (their relative bound fails)
UNDERFLOW_FLOOR: Final = 2.0 ** -900
#: the share of the box's error that the smallest of its terms may make up together: they are bounded once
#: on the box, the others on each cell (:func:`local_error`)
LOCAL_ERROR_SHARE: Final = 1e-6

Cell = tuple[tuple[float, float], ...]


def gamma(k: int) -> float:
    """``gamma_k = k u / (1 - k u)`` rounded up (a float a little above it): the relative error bound of a
    sum of ``k`` products in floating point."""
    ku = k * UNIT_ROUNDOFF
    return ku / (1 - ku) * (1 + 1e-6)


@dataclass(frozen=True)
class ErrorTerms:
    """The model's error as a function of a box's bounds (module docstring, part 3, a cell's own error): the
    terms of ``q`` and of the dropped and rounded parts of ``p`` (exponents of ``y`` and ``r``, coefficients
    ``>= 0`` rounded up), and per auxiliary the terms of ``|u(M y)|``'s bound (exponents of ``y``,
    ``|coefficients|`` rounded up) and its remainder's degree."""

    exponents: np.ndarray
    coefficients: np.ndarray
    arguments: tuple[tuple[np.ndarray, np.ndarray, int], ...]


@dataclass(frozen=True)
class PolynomialModel:
    """``G(M y) = V' D`` (module docstring) within ``error`` of ``p~(y) = sum coefficients[alpha] y^alpha`` on
    the ellipsoid's box; ``degree``: the total degree kept."""

    coefficients: np.ndarray
    error: float
    degree: int
    #: the exponents whose every entry is even (``t^alpha >= 0``), the shape of ``coefficients``
    even: np.ndarray
    #: ``|coefficients|``, each exponent's total degree, and :func:`_binomials` of the degree (made once)
    magnitudes: np.ndarray
    order: np.ndarray
    binomials: tuple[np.ndarray, np.ndarray]
    #: the error on a smaller box (a cell's, :func:`local_error`): the terms it sums, the others' bound on
    #: the model's box and that box's half-widths
    error_terms: ErrorTerms
    error_floor: float
    half: tuple[float, ...]


def _abs_bound(p: Any, bounds: Sequence[Fraction]) -> Fraction:
    """``sum |c| b^alpha`` over the terms of ``p`` (an fmpq_mpoly): an upper bound of ``|p|`` where each
    variable ``v_j`` has ``|v_j| <= bounds[j]`` (exact)."""
    total = Fraction(0)
    for exps, c in zip(p.monoms(), p.coeffs()):
        term = abs(Fraction(int(c.p), int(c.q)))
        for e, b in zip(exps, bounds):
            if e:
                term *= b ** int(e)
        total += term
    return total


def _taylor(function: str, u: Any, ctx: Any, order: int) -> Any:
    """The Taylor polynomial of ``sin(u)`` or ``cos(u) - 1`` (the auxiliary's deviation) of degree ``order``
    (odd for sin, even for cos), composed with ``u``; its remainder is :func:`_remainder`."""
    total = ctx.from_dict({})
    first = 1 if function == "sin" else 2
    assert order % 2 == first % 2, "sin's Taylor degree is odd, cos's even"
    power = u ** first
    for k in range(first, order + 1, 2):
        # sin u = u - u^3/3! + ...; cos u - 1 = -u^2/2! + u^4/4! - ...
        sign = (-1) ** ((k - 1) // 2) if function == "sin" else (-1) ** (k // 2)
        total += power * flint.fmpq(sign, math.factorial(k))
        power = power * u * u
    return total


def _order(function: str) -> int:
    return POLY_CELL_SIN_DEGREE if function == "sin" else POLY_CELL_COS_DEGREE


def _remainder(function: str, bound: Fraction) -> Fraction:
    """The Lagrange bound of :func:`_taylor`'s remainder where ``|u| <= bound``: ``bound^(k+2) / (k+2)!``, the
    next term's degree (the Taylor polynomial of degree ``k + 1`` is the same; every derivative of sin and cos
    is at most 1 in absolute value)."""
    nxt = _order(function) + 2
    return bound ** nxt / math.factorial(nxt)


@dataclass(frozen=True)
class _Exact:
    """The part of the model that does not depend on the box (exact): ``G(M y)`` with each auxiliary
    replaced by its Taylor polynomial plus ``r_k``, term by term (``y``'s exponents, ``r``'s, coefficient),
    each auxiliary's function and argument ``u(M y)``, and the distinct denominators (signed positive at
    the equilibrium, in the recasting's ring)."""

    #: the terms kept (``y``'s exponents, of total degree at most the model's, no ``r``), their floats
    kept: dict[tuple[int, ...], float]
    #: ``sum |c| y^alpha r^beta`` over the other terms, and ``sum |c - float(c)| y^alpha`` over the kept ones
    #: (fmpq_mpolys in ``y`` and ``r``: evaluated at a box's bounds, the model's error there)
    dropped: Any
    rounding: Any
    arguments: list[tuple[str, Any]]
    denominators: list[Any]
    #: ``dropped + rounding`` and the arguments' bounds as floats, for a cell's own error
    error_terms: ErrorTerms


#: the last few exact parts made (the same ``P`` and ``M`` serve every level of a search)
_MADE: dict[tuple[Any, ...], "_Exact | str"] = {}
_MADE_KEEP: Final = 4


def _exact(system: RecastSystem, P: Sequence[Sequence[Fraction]], M: Sequence[Sequence[float]],
           degree: int) -> _Exact | str:
    # (the loop by its content, never by id: a freed system's id may be reused by another)
    loop = (system.ring.names, tuple(str(r.numerator) + "/" + str(r.denominator) for r in system.field),
            tuple(sorted(system.definitions().items())), tuple(sorted(system.values.items())))
    key = (loop, tuple(Fraction(x) for row in P for x in row), tuple(x for row in M for x in row), degree)
    if key not in _MADE:
        if len(_MADE) >= _MADE_KEEP:
            _MADE.pop(next(iter(_MADE)))
        _MADE[key] = _make_exact(system, P, M, degree)
    return _MADE[key]


def refusal(system: RecastSystem, degree: int = POLY_CELL_DEGREE) -> str | None:
    """Why the loop gets no polynomial model (one line), or None: its auxiliaries must be sines and cosines of
    polynomials of the states (their arguments' vanishing at the equilibrium is checked when the model is
    made), and its dense tensor within POLY_CELL_MAX_ENTRIES."""
    if (degree + 1) ** system.n > POLY_CELL_MAX_ENTRIES:
        return f"a polynomial model of degree {degree} in {system.n} states is too large (POLY_CELL_MAX_ENTRIES)"
    ring = system.ring
    for a in system.auxiliaries:
        if a.function not in ("sin", "cos") or a.argument is None or not a.smooth:
            return f"the auxiliary {a.name} = {a.definition} is not a sine or cosine of the states"
        if any(degree_in(ring, a.argument, [name]) > 0 for name in ring.names if name not in system.states):
            return f"the auxiliary {a.name} = {a.definition} has an argument beyond the states"
    return None


def _make_exact(system: RecastSystem, P: Sequence[Sequence[Fraction]], M: Sequence[Sequence[float]],
                degree: int) -> _Exact | str:
    n = system.n
    ring = system.ring
    if (why := refusal(system, degree)) is not None:
        return why
    ynames = tuple(f"y{i}" for i in range(n))
    rnames = tuple(f"r{k}" for k in range(len(system.auxiliaries)))
    ctx = flint.fmpq_mpoly_ctx.get(ynames + rnames, "lex")
    gens = ctx.gens()
    ys, rs = gens[:n], gens[n:]
    Mq = [[Fraction(x) for x in row] for row in M]
    z = [sum((ys[j] * _fmpq(Mq[i][j]) for j in range(n) if Mq[i][j]), ctx.from_dict({})) for i in range(n)]
    images: list[Any] = list(z)
    arguments = []
    for k, a in enumerate(system.auxiliaries):
        assert a.argument is not None
        u = system.shift(a.argument).compose(*(z + [ctx.from_dict({})] * (len(ring.names) - n)), ctx=ctx)
        if any(all(e == 0 for e in m) for m in u.monoms()):
            return f"the auxiliary {a.name} = {a.definition}: its argument does not vanish at the equilibrium"
        arguments.append((a.function, u))
        images.append(_taylor(a.function, u, ctx, _order(a.function)) + rs[k])
    # V' D = 2 sum_i (P z)_i N_i / D_i times D, the product of the distinct non-constant denominators, each
    # signed positive at the equilibrium (all variables 0; proved positive on the box by polynomial_model)
    flows = [(system.shift(r.numerator), system.shift(r.denominator)) for r in system.field]
    zero = [Fraction(0)] * len(ring.names)
    distinct: list[Any] = []
    for _, den in flows:
        if den.is_constant() or any(den == d or den == -d for d in distinct):
            continue
        distinct.append(den if ring.evaluate(den, zero) > 0 else -den)
    composed = [d.compose(*images, ctx=ctx) for d in distinct]
    total = ctx.from_dict({})
    for i, (num, den) in enumerate(flows):
        Pz = sum((z[j] * _fmpq(Fraction(P[i][j])) for j in range(n) if P[i][j]), ctx.from_dict({}))
        term = num.compose(*images, ctx=ctx)
        if den.is_constant():
            term = term * _fmpq(1 / ring.evaluate(den, zero))
            own = -1
        else:
            own = next(k for k, d in enumerate(distinct) if den == d or den == -d)
            if den == -distinct[own]:
                term = -term
        for k, dy in enumerate(composed):
            if k != own:
                term = term * dy
        total += 2 * Pz * term
    kept: dict[tuple[int, ...], float] = {}
    dropped: dict[tuple[int, ...], Any] = {}
    rounding: dict[tuple[int, ...], Any] = {}
    for raw, c in zip(total.monoms(), total.coeffs()):
        exps = tuple(int(e) for e in raw)
        if any(exps[n:]) or sum(exps[:n]) > degree:
            dropped[exps] = abs(c)
            continue
        cf = float(Fraction(int(c.p), int(c.q)))  # (correctly rounded)
        kept[exps[:n]] = cf
        if Fraction(cf) != Fraction(int(c.p), int(c.q)):
            rounding[exps] = abs(c - _fmpq(Fraction(cf)))
    errors = {**dropped, **rounding}  # (disjoint: a rounded term is kept, a dropped one is not)
    error_terms = ErrorTerms(_exponent_array(errors.keys(), n + len(rnames)),
                             np.array([float_above(_fraction(c)) for c in errors.values()]),
                             tuple((_exponent_array([tuple(int(e) for e in m)[:n] for m in u.monoms()], n),
                                    np.array([float_above(abs(_fraction(c))) for c in u.coeffs()]),
                                    _order(function) + 2) for function, u in arguments))
    return _Exact(kept, ctx.from_dict(dropped), ctx.from_dict(rounding), arguments, distinct, error_terms)


def _fraction(c: Any) -> Fraction:
    return Fraction(int(c.p), int(c.q))


def _exponent_array(exponents: Any, width: int) -> np.ndarray:
    rows = [tuple(int(e) for e in m) for m in exponents]
    return np.array(rows, dtype=np.int64).reshape(len(rows), width)


def upper_sum(exponents: np.ndarray, coefficients: np.ndarray, bounds: Sequence[float]) -> float:
    """An upper bound of ``sum_t c_t prod_v b_v^(e_tv)`` (every ``c_t``, ``b_v >= 0``; floats, exact as
    given), computed in floats (module docstring, part 3): each factor split by ``frexp`` into a mantissa in
    ``[1/2, 1)`` and an integer exponent, the mantissas' powers and products rounded ``gamma``-wise (none
    below ``2^-(e + n + 1)``: nothing underflows), the exponents summed exactly, each term rebuilt by
    ``ldexp`` (exact, or within ``2^-1074`` where it underflows), then summed. ``inf`` where it overflows."""
    if len(coefficients) == 0:
        return 0.0
    m = len(bounds)
    top = int(exponents.max(initial=0))
    mant, expo = np.frexp(np.asarray(bounds, dtype=np.float64))
    table = np.cumprod(np.concatenate([np.ones((m, 1)), np.repeat(mant[:, None], top, axis=1)], axis=1), axis=1)
    cm, ce = np.frexp(coefficients)
    rows = np.arange(m)
    mantissas = cm * np.prod(table[rows, exponents], axis=1)
    exps = ce + exponents @ expo
    with np.errstate(over="ignore", under="ignore"):
        total = float(np.sum(np.ldexp(mantissas, exps)))
    if not math.isfinite(total):
        return math.inf
    # each term: at most top * m roundings in the powers and m + 1 in the products; the sum: len - 1
    operations = top * m + m + 1 + len(coefficients)
    slack = len(coefficients) * 2.0 ** -1074  # (an ldexp into the subnormals: at most one unit there)
    return float(np.nextafter((total + slack) * (1 + 2 * gamma(operations)), math.inf))


def _bounds(terms: ErrorTerms, ybounds: Sequence[float]) -> list[float]:
    """``|y_i| <= ybounds_i`` and, from them, each auxiliary's ``|r| <= U^(k+2)/(k+2)!`` (``|u| <= U``), rounded
    up: the values the error's terms are summed at."""
    bounds = list(ybounds)
    for exponents, coefficients, power in terms.arguments:
        # a few terms each, in floats rounded up by gamma of their operations (the powers by repeated
        # multiplication, every operand >= 0), and an underflow floor: U, then U^(k+2) / (k+2)!
        rows = exponents.tolist()
        U = 0.0
        for row, c in zip(rows, coefficients.tolist()):
            term = c
            for x, e in zip(ybounds, row):
                for _ in range(e):
                    term *= x
            U += term
        U = _rounded_up(U, sum(sum(row) + 1 for row in rows) + len(rows))
        r = float_above(Fraction(1, math.factorial(power)))
        for _ in range(power):
            r *= U
        bounds.append(_rounded_up(r, power))
    return bounds


def _rounded_up(x: float, operations: int) -> float:
    """Above the exact value of a computation on numbers ``>= 0`` that gave ``x`` after at most ``operations``
    roundings (``gamma``; one more for this product, and UNDERFLOW_FLOOR for an underflow)."""
    return float(np.nextafter(x * (1 + 2 * gamma(operations + 1)), math.inf)) + UNDERFLOW_FLOOR


def _split_terms(terms: ErrorTerms, half: Sequence[float], error: float) -> tuple[ErrorTerms, float]:
    """The error's terms a cell sums (:func:`local_error`) and the bound on the box ``|y_i| <= half_i`` of the
    others, the smallest there whose sum is within LOCAL_ERROR_SHARE of ``error`` (a bound for every cell of
    the box: each term grows with the bounds): at the acrobot's level 0.9, 2,700 of 38,700 terms are summed."""
    bounds = _bounds(terms, half)
    with np.errstate(all="ignore"):  # (an estimate, floats: it only splits the terms; inf sorts last)
        values = terms.coefficients * np.prod(np.asarray(bounds)[None, :] ** terms.exponents, axis=1)
    order = np.argsort(values, kind="stable")
    small = order[:int(np.searchsorted(np.cumsum(values[order]), LOCAL_ERROR_SHARE * error, side="right"))]
    big = np.setdiff1d(np.arange(len(values)), small)
    floor = upper_sum(terms.exponents[small], terms.coefficients[small], bounds)
    return ErrorTerms(terms.exponents[big], terms.coefficients[big], terms.arguments), floor


def local_error(model: "PolynomialModel", cell: Cell) -> float:
    """The model's error on the cell's own box ``|y_i| <= max(|a_i|, |b_i|)`` (module docstring, part 3), the
    cell within the model's box: each auxiliary's ``|u| <= U`` and ``|r| <= U^(k+2)/(k+2)!`` there, the
    error's larger terms at those bounds and the others' bound on the box (:func:`_split_terms`), all rounded
    up (:func:`upper_sum`)."""
    bounds = [max(abs(a), abs(b)) for a, b in cell]
    if any(b > h for b, h in zip(bounds, model.half)):
        return math.inf  # (beyond the model's box neither the floor nor the denominators' sign holds)
    terms = model.error_terms
    own = upper_sum(terms.exponents, terms.coefficients, _bounds(terms, bounds))
    return float(np.nextafter(own + model.error_floor, math.inf))


def polynomial_model(system: RecastSystem, P: Sequence[Sequence[Fraction]], M: Sequence[Sequence[float]],
                     half: Sequence[Fraction], degree: int = POLY_CELL_DEGREE) -> PolynomialModel | str:
    """The model of the module docstring for ``V = z^T P z`` on ``system`` (a nominal loop: no bounded
    constants), ``z = M y`` (``M`` floats, exact dyadics), on the box ``|y_i| <= half_i``; or why none (one
    line): an auxiliary other than the sine or cosine of a polynomial of the states that vanishes at the
    equilibrium, a denominator not proved positive on the box, or a model too large."""
    n = system.n
    exact = _exact(system, P, M, degree)
    if isinstance(exact, str):
        return exact
    ring = system.ring
    Mq = [[Fraction(x) for x in row] for row in M]
    ybounds = [Fraction(h) for h in half]
    rbounds = [_remainder(function, _abs_bound(u, ybounds + [Fraction(0)] * len(exact.arguments)))
               for function, u in exact.arguments]
    # the denominators' signs, from the true functions: every variable of the recasting over the box in balls,
    # the states x_eq + M y and each auxiliary the sine or cosine of its argument's ball, in the model file's
    # own (unshifted) variables, where cos^2 <= 1 is not lost to the dependency of c - 1 and (c - 1)^2
    box_values = [flint.arb(_fmpq(system.values[s])) + flint.arb(0, float_above(
        sum((abs(Mq[i][j]) * ybounds[j] for j in range(n)), Fraction(0)))) for i, s in enumerate(system.states)]
    for a in system.auxiliaries:
        assert a.argument is not None
        arg = _evaluate_balls(a.argument, box_values + [flint.arb(0)] * (len(ring.names) - n))
        box_values.append(_function_ball(a.function, arg))
    if not all(_evaluate_balls(system.unshift(d), box_values) > 0 for d in exact.denominators):
        return "a denominator of the flows is not proved positive on the ellipsoid's box"
    at = [_fmpq(b) for b in ybounds + rbounds]
    error = exact.dropped(*at) + exact.rounding(*at)  # (exact: every coefficient and bound is >= 0)
    shape = (degree + 1,) * n
    coefficients = np.zeros(shape)
    for exps, cf in exact.kept.items():
        coefficients[exps] = cf
    error = Fraction(int(error.p), int(error.q))
    even = np.all(np.indices(shape) % 2 == 0, axis=0)
    box = tuple(float_above(Fraction(h)) for h in half)  # (the cells' ellipsoid box: dyadics, exact)
    terms, floor = _split_terms(exact.error_terms, box, float(error))
    return PolynomialModel(coefficients, float_above(error), degree, even, np.abs(coefficients),
                           np.indices(shape).sum(axis=0), _binomials(degree), terms, floor, box)


def decreasing_ball(system: RecastSystem, P: Sequence[Sequence[Fraction]], M: Sequence[Sequence[float]],
                    inner: Fraction, largest: Fraction) -> Fraction:
    """A radius ``rho <= largest`` with ``G(M y) < 0`` wherever ``inner <= |y| <= rho`` (Euclidean), or 0
    where none is found: the ball about the equilibrium that the cells need not cover once ``|y| < inner``
    is proved by other means. With ``p~``'s quadratic part at most ``-mu |y|^2`` (``-H - mu I`` positive
    semidefinite, exact), ``C_k`` the sum of ``|c_alpha|`` over its terms of degree ``k`` (``|y^alpha| <=
    |y|^k``) and ``e`` the model's error on the box ``|y_i| <= rho``: ``G <= r^2 h(r) + e`` at ``|y| = r``,
    ``h(r) = -mu + sum_k C_k r^(k-2)`` increasing, so ``h(rho) < 0`` and ``inner^2 h(rho) + e < 0`` give
    ``G < 0`` on the whole shell (``r^2 h(r) <= r^2 h(rho) <= inner^2 h(rho)``). Exact rationals throughout."""
    from lyapcheck.sos.definiteness import is_positive_definite

    n = system.n
    if inner <= 0 or largest <= inner:
        return Fraction(0)
    first = polynomial_model(system, P, M, [largest] * n)
    if isinstance(first, str):
        return Fraction(0)
    C = first.coefficients
    order = np.indices(C.shape).sum(axis=0)
    if np.any(C[order <= 1] != 0):
        return Fraction(0)  # (V' D has no constant or linear term where the equilibrium is one; a guard)
    H = [[Fraction(0)] * n for _ in range(n)]
    for i in range(n):
        for j in range(n):
            e = [0] * n
            e[i] += 1
            e[j] += 1
            H[i][j] = Fraction(float(C[tuple(e)])) / (1 if i == j else 2)
    top = float(np.linalg.eigvalsh(np.array([[float(x) for x in row] for row in H]))[-1])
    if not top < 0:
        return Fraction(0)
    mu = Fraction(-top * (1 - 1e-6))
    if not is_positive_definite([[-H[i][j] - (mu if i == j else 0) for j in range(n)] for i in range(n)]):
        return Fraction(0)
    sums = {k: sum((Fraction(float(x)) for x in np.abs(C[order == k]) if x), Fraction(0))
            for k in range(3, first.degree + 1)}

    def h(r: Fraction) -> Fraction:
        return -mu + sum((c * r ** (k - 2) for k, c in sums.items()), Fraction(0))

    rho = largest
    while rho > inner and not h(rho) < 0:
        rho = rho * 3 / 4
    for _ in range(8):  # (the model's error shrinks with the box: a few smaller radii are tried)
        if rho <= inner:
            return Fraction(0)
        model = polynomial_model(system, P, M, [rho] * n)
        if not isinstance(model, str) and inner * inner * h(rho) + Fraction(model.error) < 0:
            return rho
        rho = rho * 3 / 4
    return Fraction(0)


def _function_ball(function: str, arg: Any) -> Any:
    """A ball holding ``sin(u)``, or ``cos(u)``, for every ``u`` in the ball ``arg``. On a ball about 0 within
    ``[-pi, pi]`` cos is even and decreasing in ``|u|``: ``[cos(m), 1]`` (``m`` the ball's largest ``|u|``),
    where arb's cos of the ball would be centred at 1, twice as wide; beyond it, ``[-1, 1]`` at most."""
    if function == "sin":
        value = arg.sin()
        return value if value.rad() < 1 else flint.arb(0, 1)
    m = abs(arg).upper()
    if arg.contains(0) and m < flint.arb.pi():
        return flint.arb(m).cos().union(flint.arb(1))
    value = arg.cos()
    return value if value.rad() < 1 else flint.arb(0, 1)


def _evaluate_balls(p: Any, values: Sequence[Any]) -> Any:
    """``p`` (an fmpq_mpoly) at balls, term by term: a ball holding its value wherever each variable lies in
    its ball."""
    total = flint.arb(0)
    for exps, c in zip(p.monoms(), p.coeffs()):
        term = flint.arb(flint.fmpq(c))
        for e, v in zip(exps, values):
            if e:
                term *= _power(v, int(e))
        total += term
    return total


def _power(v: Any, e: int) -> Any:
    """A ball holding ``x^e`` for every ``x`` in the ball ``v`` (``e >= 1``): the hull of the endpoints' powers
    (``x^e`` is monotone for odd ``e`` and in ``|x|`` for even ``e``, with 0 where the ball holds it). arb's
    own power of a ball holding 0 is not finite."""
    lo, hi = v.lower(), v.upper()

    def point(x: Any) -> Any:
        out = flint.arb(1)
        for _ in range(e):
            out *= x
        return out

    hull = point(lo).union(point(hi))
    if e % 2 == 0 and v.contains(0):
        hull = hull.union(flint.arb(0))
    return hull


def _fmpq(x: Fraction) -> Any:
    return flint.fmpq(x.numerator, x.denominator)


def _powers(x: float, degree: int) -> np.ndarray:
    """``x^0, ..., x^degree`` by repeated multiplication (``x^e`` within ``gamma_e`` of the exact power)."""
    out = np.empty(degree + 1)
    out[0] = 1.0
    out[1:] = x
    return np.cumprod(out)


def _binomials(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """``binom(j, i)`` (exact floats, ``j >= i``; 0 elsewhere) and ``j - i`` (clipped at 0)."""
    B = np.array([[math.comb(j, i) if j >= i else 0 for j in range(degree + 1)] for i in range(degree + 1)],
                 dtype=float)
    gap = np.clip(np.subtract.outer(np.arange(degree + 1), np.arange(degree + 1)).T, 0, None)
    return B, gap


def cell_bound(model: PolynomialModel, cell: Cell) -> "CellBound":
    """The bounds of :class:`CellBound` on the cell, exactly (module docstring, part 3): ``centre`` the computed
    value of ``p~`` at the cell's centre, ``spread`` every spread and error bound, ``error`` the errors alone,
    rounded up."""
    n = model.coefficients.ndim
    D = model.degree
    order = model.order
    binomials, gap = model.binomials
    A = model.coefficients
    B = model.magnitudes
    # the shift along each axis in turn: the axis contracted is the first; the result's axes rotate so
    # that after n steps they are back in order
    for a, b in cell:
        S = binomials * _powers((a + b) / 2, D)[gap]  # S[i, j] = binom(j, i) m^(j - i)
        A = (S @ A.reshape(D + 1, -1)).reshape(A.shape)
        B = (np.abs(S) @ B.reshape(D + 1, -1)).reshape(B.shape)
        A = np.moveaxis(A, 0, -1)
        B = np.moveaxis(B, 0, -1)
    # the exact shift differs from A by at most gamma_K times the exact shift of |p~| with |S|, which B
    # (computed alike, every term >= 0) holds within the same factor: each of the n stages adds the
    # rounding of the powers and products in S and of a sum of D + 1 products (twice that, for B's own)
    shift_error = 2 * gamma(n * (2 * D + 4))
    R = np.ones(())
    for a, b in cell:
        R = np.multiply.outer(R, _powers((b - a) / 2, D))  # (the radii are exact: the cells are dyadic)
    spread = np.where(model.even, np.maximum(A, 0.0), np.abs(A))
    origin = (0,) * n
    centre = float(A[origin])
    spread[origin] = 0.0  # (its error stays: B's constant term)
    errors = shift_error * B
    # the quadratic part t^T H t: where every matrix of its enclosure (each coefficient within its error) is
    # negative definite, it is <= 0 on the whole cell and adds nothing (the Taylor form's concavity; its cross
    # terms would otherwise each add |A_alpha| w^alpha)
    H = [[flint.arb(0)] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            alpha = tuple(int(k == i) + int(k == j) for k in range(n))
            value = flint.arb(float(A[alpha]), float(errors[alpha]) * (1 + 4 * UNIT_ROUNDOFF) + UNDERFLOW_FLOOR)
            H[i][j] = H[j][i] = value if i == j else value / 2
    if negative_definite(H):
        quadratic = order == 2
        spread[quadratic] = 0.0
        errors = np.where(quadratic, 0.0, errors)
    terms = (spread + errors) * R
    # the powers of the radii (n D products), the products above, and the sum of every term
    total = float(np.sum(terms)) * (1 + gamma(terms.size + n * D + 4)) + UNDERFLOW_FLOOR
    error = model.error
    if (total + error) * (1 + 4 * UNIT_ROUNDOFF) + UNDERFLOW_FLOOR >= -centre > total:
        # the cell's own error, only where the box's alone fails the cell (a cell its spread fails gains nothing)
        error = min(error, local_error(model, cell))
    at_centre = (shift_error * float(B[origin]) + error) * (1 + 4 * UNIT_ROUNDOFF) + UNDERFLOW_FLOOR
    return CellBound(centre, (total + error) * (1 + 4 * UNIT_ROUNDOFF) + UNDERFLOW_FLOOR, at_centre, terms)


@dataclass(frozen=True)
class CellBound:
    """What :func:`cell_bound` proved of a cell: ``centre - error <= G(M m) <= centre + error`` at its centre
    ``m``, ``G(M y) <= centre + spread`` on it; ``terms``, each exponent's share of the spread (floats)."""

    centre: float
    spread: float
    error: float
    terms: np.ndarray

    @property
    def negative(self) -> bool:
        """``G < 0``, so ``V' < 0``, on the cell (compared exactly: ``spread < -centre``)."""
        return self.spread < -self.centre

    def weights(self, cell: Cell) -> list[float]:
        """Each side's share of the spread per unit of its width (floats: they only choose the side a failing
        cell is cut across): the sum over the exponents of ``terms * alpha_k / w_k``."""
        shares = [float(np.tensordot(self.terms, np.arange(self.terms.shape[k]), axes=([k], [0])).sum())
                  for k in range(self.terms.ndim)]
        return [x / max((b - a) / 2, 1e-300) for x, (a, b) in zip(shares, cell)]


__all__ = ["PolynomialModel", "ErrorTerms", "refusal", "polynomial_model", "decreasing_ball", "cell_bound",
           "CellBound", "gamma", "local_error", "upper_sum"]

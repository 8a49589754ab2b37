"""Exact multivariate polynomials over the rationals (FLINT), and their views for the solver.

Every polynomial of the engine is a :class:`flint.fmpq_mpoly` in a :class:`Ring`: the ring knows
its variable names and converts between FLINT's numbers and :class:`fractions.Fraction` (the two
do not compare equal to each other: ``fmpq(1, 3) != Fraction(1, 3)``, so conversions happen only
here). Exponent tuples follow the ring's variable order. Floating-point views (coefficients as
doubles) are what the numerical search is built from; the exact checks never read them.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Iterable, Mapping, Sequence

import flint

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

Monomial = tuple[int, ...]
Poly = Any  # flint.fmpq_mpoly (FLINT's type stubs are not typed)


def to_fraction(c: Any) -> Fraction:
    """A FLINT rational (or an int) as a :class:`Fraction`."""
    if isinstance(c, Fraction):
        return c
    if isinstance(c, int):
        return Fraction(c)
    return Fraction(int(c.p), int(c.q))


def to_fmpq(c: Fraction | int | Any) -> Any:
    """A rational as FLINT's ``fmpq``."""
    if isinstance(c, Fraction):
        return flint.fmpq(c.numerator, c.denominator)
    if isinstance(c, int):
        return flint.fmpq(c)
    return c


@lru_cache(maxsize=None)
def _context(names: tuple[str, ...]) -> Any:
    return flint.fmpq_mpoly_ctx.get(names, "lex")


@dataclass(frozen=True)
class Ring:
    """Polynomials with rational coefficients in the variables ``names`` (in this order)."""

    names: tuple[str, ...]

    @property
    def ctx(self) -> Any:
        return _context(self.names)

    @property
    def nvars(self) -> int:
        return len(self.names)

    def gens(self) -> tuple[Poly, ...]:
        return tuple(self.ctx.gens()) if self.names else ()

    def gen(self, name: str) -> Poly:
        return self.gens()[self.names.index(name)]

    def zero(self) -> Poly:
        return self.ctx.from_dict({})

    def constant(self, c: Fraction | int) -> Poly:
        return self.ctx.constant(to_fmpq(c))

    def monomial(self, m: Monomial, c: Fraction | int = 1) -> Poly:
        return self.ctx.from_dict({tuple(m): to_fmpq(c)})

    def from_terms(self, terms: Mapping[Monomial, Fraction | int]) -> Poly:
        return self.ctx.from_dict({tuple(m): to_fmpq(c) for m, c in terms.items() if c != 0})

    def terms(self, p: Poly) -> dict[Monomial, Fraction]:
        """``{exponents: coefficient}`` with exact Fractions (zero terms absent)."""
        return {tuple(int(e) for e in m): to_fraction(c) for m, c in zip(p.monoms(), p.coeffs())}

    def float_terms(self, p: Poly) -> dict[Monomial, float]:
        return {tuple(int(e) for e in m): float(to_fraction(c)) for m, c in zip(p.monoms(), p.coeffs())}

    def support(self, p: Poly) -> list[Monomial]:
        return [tuple(int(e) for e in m) for m in p.monoms()]

    def embed(self, p: Poly, other: "Ring") -> Poly:
        """``p`` (a polynomial of this ring) in ``other``, whose variables include all of ours."""
        where = [other.names.index(n) for n in self.names]
        out: dict[Monomial, Any] = {}
        for m, c in zip(p.monoms(), p.coeffs()):
            e = [0] * other.nvars
            for i, k in zip(where, m):
                e[i] = int(k)
            out[tuple(e)] = c
        return other.ctx.from_dict(out)

    def restrict(self, p: Poly, other: "Ring") -> Poly:
        """``p`` in ``other`` (a ring with a subset of our variables); p must not use the others."""
        keep = [self.names.index(n) for n in other.names]
        dropped = [i for i in range(self.nvars) if i not in keep]
        out: dict[Monomial, Any] = {}
        for m, c in zip(p.monoms(), p.coeffs()):
            if any(int(m[i]) for i in dropped):
                raise ValueError(f"the polynomial {p} uses a variable that {other.names} does not have")
            out[tuple(int(m[i]) for i in keep)] = c
        return other.ctx.from_dict(out)

    def substitute(self, p: Poly, values: Mapping[str, Fraction]) -> Poly:
        """Set some variables to exact values (the polynomial stays in this ring)."""
        if not values:
            return p
        return p.subs({name: to_fmpq(v) for name, v in values.items()})

    def compose(self, p: Poly, images: Sequence[Poly]) -> Poly:
        """``p(images[0], images[1], ...)``: a change of variables (one image per variable)."""
        return p.compose(*images) if self.names else p

    def evaluate(self, p: Poly, point: Sequence[Fraction]) -> Fraction:
        """``p`` at an exact point."""
        total = Fraction(0)
        for m, c in zip(p.monoms(), p.coeffs()):
            term = to_fraction(c)
            for x, k in zip(point, m):
                if k:
                    term *= x ** int(k)
            total += term
        return total


def total_degree(p: Poly) -> int:
    """The total degree (0 for a constant, -1 for the zero polynomial)."""
    return -1 if p.is_zero() else int(p.total_degree())


def degree_in(ring: Ring, p: Poly, variables: Iterable[str]) -> int:
    """The largest total degree of a term of ``p`` in the given variables only."""
    idx = [ring.names.index(v) for v in variables]
    return max((sum(int(m[i]) for i in idx) for m in p.monoms()), default=-1)


def gram_form(ring: Ring, basis: Sequence[Monomial], Q: Sequence[Sequence[Fraction]]) -> Poly:
    """``z^T Q z`` for the monomial vector ``z = basis`` (exact)."""
    acc: dict[Monomial, Fraction] = {}
    for i, row in enumerate(Q):
        bi = basis[i]
        for j, q in enumerate(row):
            if q:
                m = tuple(a + b for a, b in zip(bi, basis[j]))
                acc[m] = acc.get(m, Fraction(0)) + q
    return ring.from_terms(acc)


def monomials(nvars: int, dmin: int, dmax: int) -> list[Monomial]:
    """All monomials of total degree ``dmin..dmax`` in ``nvars`` variables, degree by degree, the
    first variable's power descending (the order of :func:`lyapcheck.paper.poly.monomials`)."""
    def of_degree(d: int, n: int) -> list[Monomial]:
        if n == 0:
            return [()] if d == 0 else []
        if n == 1:
            return [(d,)]
        return [(i, *rest) for i in range(d, -1, -1) for rest in of_degree(d - i, n - 1)]

    return [m for d in range(max(dmin, 0), dmax + 1) for m in of_degree(d, nvars)]


MonomialPlan = tuple[int, tuple[tuple[int, "np.ndarray", "np.ndarray", "np.ndarray"], ...]]


def monomial_plan(exponents: "np.ndarray") -> MonomialPlan:
    """What :func:`monomial_values` does per variable, worked out once for an exponent matrix: the
    monomials in which the variable has exponent 1 (a product), and those with a higher one (a power)."""
    import numpy as np

    steps = []
    for k in range(exponents.shape[1]):
        column = exponents[:, k]
        ones, higher = np.flatnonzero(column == 1), np.flatnonzero(column > 1)
        if ones.size or higher.size:
            steps.append((k, ones, higher, column[higher][None, :]))
    return exponents.shape[0], tuple(steps)


def monomial_values(x: "np.ndarray", plan: "MonomialPlan | np.ndarray") -> "np.ndarray":
    """Every monomial ``x^e`` (rows of an exponent matrix, one column per variable of ``x``, or its
    :func:`monomial_plan`) at every row of ``x``: ``(rows, monomials)``, floating point. Exponent 1
    multiplies, higher ones power, 0 skips: the simulations evaluate the same few monomials tens of
    thousands of times, and ``np.prod(x ** e)`` over all of them was most of a stiff model's
    falsification."""
    import numpy as np

    if not isinstance(plan, tuple):
        plan = monomial_plan(plan)
    count, steps = plan
    out = np.ones((x.shape[0], count))
    for k, ones, higher, powers in steps:
        if ones.size:
            out[:, ones] *= x[:, k:k + 1]
        if higher.size:
            out[:, higher] *= x[:, k:k + 1] ** powers
    return out

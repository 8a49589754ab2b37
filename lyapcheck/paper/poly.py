"""Sparse polynomials, exact or floating: just what the SOS classes need.

A polynomial is a dict ``{(i, j, ...): c}`` from exponent tuples to coefficients, e.g.
``{(i, j): c}`` for ``sum c * y**i * r**j``; coefficients are :class:`fractions.Fraction` for
exact work or floats for building the numerical program. All exponent tuples of one
polynomial have the same length (the number of variables).
"""

from __future__ import annotations

from typing import Any, Iterable

Monomial = tuple[int, ...]
Poly = dict[Monomial, Any]


def monomials(dmin: int, dmax: int, nvars: int = 2) -> list[Monomial]:
    """All monomials of total degree ``dmin..dmax``, degree by degree, first variable's power descending."""
    def of_degree(d: int, n: int) -> list[Monomial]:
        if n == 1:
            return [(d,)]
        return [(i, *rest) for i in range(d, -1, -1) for rest in of_degree(d - i, n - 1)]

    return [m for d in range(dmin, dmax + 1) for m in of_degree(d, nvars)]


def add(*polys: Poly) -> Poly:
    out: Poly = {}
    for p in polys:
        for m, c in p.items():
            out[m] = out.get(m, 0) + c
    return {m: c for m, c in out.items() if c != 0}


def scale(c: Any, p: Poly) -> Poly:
    return {m: c * v for m, v in p.items() if c * v != 0}


def mul(p: Poly, q: Poly) -> Poly:
    out: Poly = {}
    for m1, c1 in p.items():
        for m2, c2 in q.items():
            m = tuple(a + b for a, b in zip(m1, m2))
            out[m] = out.get(m, 0) + c1 * c2
    return {m: c for m, c in out.items() if c != 0}


def deriv(p: Poly, var: int) -> Poly:
    out: Poly = {}
    for m, c in p.items():
        if m[var] > 0:
            mm = tuple(e - 1 if k == var else e for k, e in enumerate(m))
            out[mm] = out.get(mm, 0) + c * m[var]
    return out


def monomial(m: Monomial) -> Poly:
    return {m: 1}


def gram_form(basis: list[Monomial], Q: Iterable[Iterable[Any]]) -> Poly:
    """``z^T Q z`` for the monomial vector ``z = basis``."""
    out: Poly = {}
    for i, row in enumerate(Q):
        for j, c in enumerate(row):
            m = tuple(a + b for a, b in zip(basis[i], basis[j]))
            out[m] = out.get(m, 0) + c
    return {m: c for m, c in out.items() if c != 0}


def gram_classes(basis: list[Monomial]) -> dict[Monomial, list[tuple[int, int]]]:
    """For each monomial, the Gram entries (i, j) whose product ``z_i z_j`` is that monomial."""
    classes: dict[Monomial, list[tuple[int, int]]] = {}
    for i, a in enumerate(basis):
        for j, b in enumerate(basis):
            classes.setdefault(tuple(x + y for x, y in zip(a, b)), []).append((i, j))
    return classes


def embed(p: Poly, nvars: int) -> Poly:
    """The same polynomial in more variables (the new ones with exponent 0)."""
    return {tuple(m) + (0,) * (nvars - len(m)): c for m, c in p.items()}

"""Sparse polynomials in two variables, exact or floating: just what the SOS class needs.

A polynomial is a dict ``{(i, j): c}`` meaning ``sum c * y**i * r**j``; coefficients are
:class:`fractions.Fraction` for exact work or floats for building the numerical program.
"""

from __future__ import annotations

from typing import Any, Iterable

Monomial = tuple[int, int]
Poly = dict[Monomial, Any]


def monomials(dmin: int, dmax: int) -> list[Monomial]:
    """All monomials of total degree ``dmin..dmax``, degree by degree, y-power descending."""
    return [(i, d - i) for d in range(dmin, dmax + 1) for i in range(d, -1, -1)]


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
    for (i1, j1), c1 in p.items():
        for (i2, j2), c2 in q.items():
            m = (i1 + i2, j1 + j2)
            out[m] = out.get(m, 0) + c1 * c2
    return {m: c for m, c in out.items() if c != 0}


def deriv(p: Poly, var: int) -> Poly:
    out: Poly = {}
    for m, c in p.items():
        if m[var] > 0:
            mm = (m[0] - 1, m[1]) if var == 0 else (m[0], m[1] - 1)
            out[mm] = out.get(mm, 0) + c * m[var]
    return out


def monomial(m: Monomial) -> Poly:
    return {m: 1}


def gram_form(basis: list[Monomial], Q: Iterable[Iterable[Any]]) -> Poly:
    """``z^T Q z`` for the monomial vector ``z = basis``."""
    out: Poly = {}
    for i, row in enumerate(Q):
        for j, c in enumerate(row):
            m = (basis[i][0] + basis[j][0], basis[i][1] + basis[j][1])
            out[m] = out.get(m, 0) + c
    return {m: c for m, c in out.items() if c != 0}


def gram_classes(basis: list[Monomial]) -> dict[Monomial, list[tuple[int, int]]]:
    """For each monomial, the Gram entries (i, j) whose product ``z_i z_j`` is that monomial."""
    classes: dict[Monomial, list[tuple[int, int]]] = {}
    for i, a in enumerate(basis):
        for j, b in enumerate(basis):
            classes.setdefault((a[0] + b[0], a[1] + b[1]), []).append((i, j))
    return classes

"""Denominators proved positive everywhere, exactly: ``p - c = sigma`` with ``c > 0``, ``sigma`` SOS.

A rational field is multiplied through by its denominators only after each is proved positive
(or negative, whose sign then moves to the numerator) for every state: certificate kind
Positivity of :mod:`lyapcheck.sos.certificates`. The search scales the denominator's variables
first (the same least-squares powers of two as the field, :mod:`lyapcheck.models.loop.field`), so a
denominator such as ``(eps + sigma0 s)^2 + Delta^2`` with ``Delta = 7.5e-4`` is handled as it
comes; the certificate is stored in those coordinates with the scaling, and checked exactly.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any, Sequence

from lyapcheck.models.engines import store
from lyapcheck.models.engines.search import (Budget, ParameterValues, Search, box_multipliers, box_multipliers_from_json,
                                     box_multipliers_of, multiplier_grams, multiplier_variable, one, param)
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, check_positivity
from lyapcheck.sos.polynomials import Poly, Ring, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term


def _variable_scales(ring: Ring, p: Poly) -> list[Fraction]:
    """Powers of two ``s_i`` that bring ``p(s * z)``'s coefficients near each other (least squares)."""
    import numpy as np

    terms = ring.float_terms(p)
    n = ring.nvars
    rows, rhs = [], []
    for m, c in terms.items():
        rows.append(list(m) + [-1.0])
        rhs.append(-math.log2(abs(c)))
    for i in range(n):
        rows.append([1e-3 * (k == i) for k in range(n)] + [0.0])
        rhs.append(0.0)
    x, *_ = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)
    return [Fraction(2) ** int(round(v)) for v in x[:n]]


def positivity_structure(ring: Ring, p: Poly, free: int | None = None) -> Structure | None:
    """``p - c - sum_j r_j (1 - u_j^2) = sigma``: the ring's variables from index ``free`` on are a
    box's normalized parameters (none by default)."""
    n = ring.nvars
    free = n if free is None else free
    support = set(ring.support(p)) | {tuple([0] * n)}
    generators = bases.sign_symmetries(n, [(ring.support(p), None)])
    # only the parameters p depends on get a multiplier: p > 0 for every value of the others is p > 0
    # (a multiplier on an absent parameter only adds monomials that the rounding must cancel exactly)
    present = [j for j in range(free, n) if any(m[j] for m in ring.support(p))]
    box_grams, box_terms = box_multipliers(n, free, support, with_states=False, generators=generators,
                                           box_vars=present, margin=False)  # its objective is c, not the margin
    for g in box_grams:
        j = multiplier_variable(g.name)
        sq = {tuple(2 * int(k == j) for k in range(n)), tuple([0] * n)}
        support |= {tuple(a + b + c for a, b, c in zip(x, y, s)) for x in g.basis for y in g.basis for s in sq}
    basis = bases.sos_basis(n, support)
    if not basis:
        return None
    blocks = bases.character_blocks(basis, generators)
    terms = (Term(one(ring, -1), "c"), *box_terms, Term(one(ring, -1), "sigma"))
    return Structure(nvars=n, grams=(Gram("sigma", tuple(basis), tuple(map(tuple, blocks)), margin=False), *box_grams),
                     scalars=(Scalar("c", "zero"),),
                     identities=(Identity("positivity", terms, param("p", ring.support(p) + [tuple([0] * n)]),
                                          "sigma"),),
                     objective=("max", "c"))


def prove_positive(ring: Ring, p: Poly, budget: Budget, free: int | None = None) -> dict[str, Any] | None:
    """An exact certificate that ``p > 0`` everywhere (in scaled variables, with the scales), or
    None; the ring's variables from index ``free`` on are a box's normalized parameters, where
    ``p > 0`` is proved for ``u`` in ``[-1, 1]`` only (and they keep scale 1)."""
    if p.is_constant():
        c = ring.evaluate(p, [Fraction(0)] * ring.nvars)
        return {"kind": "constant", "value": str(c)} if c > 0 else None
    free = ring.nvars if free is None else free
    problem = {"ring": list(ring.names), "p": store.polynomial_json(ring, p), "free": free} if store.enabled() else None
    key = store.problem_key("positivity", problem) if problem is not None else None
    stored = recall_certificate(ring, p, free, key) if key is not None else None
    if stored is not None:
        return stored
    found = _search_positive(ring, p, budget, free)
    if found is not None and key is not None:
        store.keep(key, {"certificate": found})
    return found


def recall_certificate(ring: Ring, p: Poly, free: int, key: str) -> dict[str, Any] | None:
    """The certificate stored under ``key`` (:mod:`lyapcheck.models.engines.store`) when it passes
    :func:`check_certificate` on ``p`` now; None otherwise."""
    entry = store.recall(key)
    cert = entry.get("certificate") if entry is not None else None
    if not isinstance(cert, dict) or cert.get("kind") != "sos":
        return None
    try:
        ok, _ = check_certificate(ring, p, cert, free)
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return None
    return cert if ok else None


def _search_positive(ring: Ring, p: Poly, budget: Budget, free: int) -> dict[str, Any] | None:
    """:func:`prove_positive`'s search (one solve, its rounding and the exact check)."""
    scales = [s if k < free else Fraction(1) for k, s in enumerate(_variable_scales(ring, p))]
    gens = ring.gens()
    scaled = ring.compose(p, [g * to_fmpq(s) for g, s in zip(gens, scales)])
    peak = max(abs(c) for c in ring.terms(scaled).values())
    norm = Fraction(2) ** math.floor(math.log2(peak))
    scaled = scaled * to_fmpq(1 / norm)
    structure = positivity_structure(ring, scaled, free)
    if structure is None:
        return None
    values = ParameterValues()
    values.set_poly(ring, "p", scaled, structure.identities[0].constant.support)  # type: ignore[union-attr]
    search = Search(ring, budget)
    solution = search.solve(structure, values)
    c_max = solution.scalars.get("c", 0.0)
    if not solution.usable or not c_max > 0:
        return None
    from lyapcheck.sos.rounding import project, round_scalar, rounded_point

    # the largest c makes sigma's constant entry 0; half of it leaves room for the rounding
    rounded = rounded_point(solution)
    rounded.scalars["c"] = round_scalar(c_max / 2)
    point = project(ring, structure, rounded, values.exact)
    if point is None:
        return None
    sigma = GramPoly.of(structure.gram("sigma").basis, point.grams["sigma"])
    c = point.scalars["c"]
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_positivity(ring, scaled, c, sigma, box)
    if not ok:
        return None
    out: dict[str, Any] = {"kind": "sos", "scales": [str(s) for s in scales], "normalization": str(norm),
                           "c": str(c), "gram_sigma": sigma.to_json()}
    if box:
        out["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in box]
    return out


def prove_positive_on_box(ring: Ring, p: Poly, budget: Budget) -> dict[str, Any] | None:
    """``p > 0`` for every point of ``[-1, 1]^k`` (every variable of ``ring`` a box parameter)."""
    return prove_positive(ring, p, budget, free=0)


def check_certificate(ring: Ring, p: Poly, cert: dict[str, Any], free: int | None = None) -> tuple[bool, str]:
    """Re-check a positivity certificate of ``p`` exactly (``free``: as in :func:`prove_positive`)."""
    free = ring.nvars if free is None else free
    if cert.get("kind") == "constant":
        c = ring.evaluate(p, [Fraction(0)] * ring.nvars)
        ok = p.is_constant() and c > 0 and Fraction(cert["value"]) == c
        return ok, "a positive constant" if ok else "not the positive constant stated"
    scales = [Fraction(s) for s in cert["scales"]]
    norm = Fraction(cert["normalization"])
    if len(scales) != ring.nvars or any(s <= 0 for s in scales) or norm <= 0:
        return False, "the scales and the normalization must be positive, one scale per variable"
    gens = ring.gens()
    scaled = ring.compose(p, [g * to_fmpq(s) for g, s in zip(gens, scales)]) * to_fmpq(1 / norm)
    sigma = GramPoly.from_json(cert["gram_sigma"], ring.nvars)
    box = box_multipliers_from_json(cert.get("box_multipliers", []), ring.nvars)
    if any(not (free <= j < ring.nvars) or scales[j] != 1 for j, _ in box):
        return False, "a box multiplier on a variable that is not a box parameter, or a scaled box parameter"
    return check_positivity(ring, scaled, Fraction(cert["c"]), sigma, box)


def prove_denominators(ring: Ring, denominators: Sequence[Poly], budget: Budget, free: int | None = None
                       ) -> tuple[list[int], list[dict[str, Any]], Poly | None]:
    """For each distinct denominator: its sign (+1 / -1) and certificate; or the first one that
    could not be proved of one sign (the third value; then the signs are incomplete)."""
    signs: list[int] = []
    certs: list[dict[str, Any]] = []
    for d in denominators:
        cert = prove_positive(ring, d, budget, free)
        sign = 1
        if cert is None:
            cert = prove_positive(ring, -d, budget, free)
            sign = -1
        if cert is None:
            return signs, certs, d
        signs.append(sign)
        certs.append({**cert, "sign": sign})
    return signs, certs, None

"""``sos_bound``: a global ultimate bound on each output under bounded disturbances.

Certificate (kinds Dissipation and OutputBound of :mod:`lyapcheck.sos.certificates`), in scaled
coordinates, in the ring of the states ``z`` and the disturbances ``d``:

    -grad V . g(z, d) - lam (V - 1) D - sum_k tau_k (b_k^2 - d_k^2) = sigma_D,
    V - y^2 + B - 1 = sigma_E,

with ``V = z_V^T Q_V z_V`` over the monomials of degree 0 to ``k`` of the states (``Q_V > 0``:
``V >= lambda (1 + |z|^2)``, radially unbounded), ``tau_k``, ``sigma_D``, ``sigma_E`` sums of
squares with positive definite Gram matrices, ``lam > 0``. For every ``|d_k| <= b_k``,
``V' = grad V . g / D <= -lam (V - 1)``, so ``V(t) <= 1 + (V(0) - 1) exp(-lam t)``: solutions exist
for all time (``V`` bounds ``|z|``) and ``limsup V <= 1`` from every start. With the second
identity ``y^2 <= V + B - 1``, hence ``limsup |y| <= sqrt(B)`` for every disturbance within its
bounds and every initial state.

The search, per output: minimize ``B`` for each decay rate of :data:`LAMBDA_GRID` (scaled time),
``V`` of degree 2, then 4 where the field allows; every candidate is decided by the exact check,
and the smallest certified ``B`` is the bound. The bound in declared units is
``s_y sqrt(B)`` rounded up exactly (:func:`lyapcheck.exact.sqrt_upper`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

from lyapcheck.models.field import ScaledField, unscale_polynomial
from lyapcheck.models.lyapunov import terms_json
from lyapcheck.models.search import BudgetExhausted, ParameterValues, Search, one, param
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, check_dissipation, check_output_bound
from lyapcheck.sos.polynomials import Monomial, Poly, monomials, to_fmpq
from lyapcheck.sos.program import Gram, Identity, Scalar, Structure, Term

#: decay rates ``lam`` of the dissipation inequality tried, in scaled time
LAMBDA_GRID: Final = (0.05, 0.2, 0.6, 1.5, 4.0)
#: degrees of V tried, in turn
BOUND_DEGREES: Final = (2, 4)
#: the smallest eigenvalue every Gram matrix keeps in the search (scaled coordinates), so that the
#: rounded solution passes the exact positive-definiteness checks
BOUND_FLOOR: Final = 1e-7
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120


def _symmetry(scaled: ScaledField, y: Poly) -> list[tuple[int, ...]]:
    ring = scaled.ring
    odd = [(ring.support(gi), i) for i, gi in enumerate(scaled.g)] + [(ring.support(scaled.D), None)]
    return bases.sign_symmetries(ring.nvars, odd, [ring.support(y)])


def bound_structure(scaled: ScaledField, y: Poly, degree: int) -> Structure | None:
    ring = scaled.ring
    n, m = scaled.n, scaled.m
    nv = ring.nvars
    generators = _symmetry(scaled, y)
    z_v = [tuple(list(a) + [0] * m) for a in monomials(n, 0, degree // 2)]
    v_blocks = bases.character_blocks(z_v, generators)
    v_products = {tuple(a + b for a, b in zip(z_v[i], z_v[j])) for idx in v_blocks for i in idx for j in idx}
    z_tau = monomials(nv, 0, max(degree // 2 - 1, 0))
    tau_blocks = bases.character_blocks(z_tau, generators)
    tau_products = {tuple(a + b for a, b in zip(z_tau[i], z_tau[j])) for idx in tau_blocks for i in idx for j in idx}
    target: set[Monomial] = set()
    for i, gi in enumerate(scaled.g):
        derived = {q[:i] + (q[i] - 1,) + q[i + 1:] for q in v_products if q[i] > 0}
        target |= {tuple(a + b for a, b in zip(q, s)) for q in derived for s in ring.support(gi)}
    d_support = set(ring.support(scaled.D))
    target |= {tuple(a + b for a, b in zip(q, s)) for q in v_products for s in d_support} | d_support
    for k in range(m):
        sq = tuple(2 * int(j == n + k) for j in range(nv))
        target |= {tuple(a + b for a, b in zip(q, s)) for q in tau_products for s in (sq, tuple([0] * nv))}
    z_d = bases.sos_basis(nv, target)
    e_target = set(v_products) | set(ring.support(y * y)) | {tuple([0] * nv)}
    z_e = bases.sos_basis(nv, e_target)
    if not z_d or not z_e or max(len(z_d), len(z_e), len(z_v)) > MAX_GRAM_ROWS:
        return None
    d_blocks = bases.character_blocks(z_d, generators)
    e_blocks = bases.character_blocks(z_e, generators)
    grams = [Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)), margin="floor")]
    grams += [Gram(f"tau{k}", tuple(z_tau), tuple(map(tuple, tau_blocks)), margin="floor") for k in range(m)]
    grams += [Gram("sigD", tuple(z_d), tuple(map(tuple, d_blocks)), margin="floor"),
              Gram("sigE", tuple(z_e), tuple(map(tuple, e_blocks)), margin="floor")]
    terms_d = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in enumerate(scaled.g)]
    terms_d.append(Term(param("lamD", d_support), "V"))
    for k in range(m):
        sq = tuple(2 * int(j == n + k) for j in range(nv))
        terms_d.append(Term(param(f"b{k}", [sq, tuple([0] * nv)]), f"tau{k}"))
    terms_d.append(Term(one(ring, -1), "sigD"))
    terms_e = (Term(one(ring, 1), "V"), Term(one(ring, 1), "B"), Term(one(ring, -1), "sigE"))
    return Structure(nvars=nv, grams=tuple(grams), scalars=(Scalar("B"),),
                     identities=(Identity("dissipation", tuple(terms_d), param("lamD0", d_support), "sigD"),
                                 Identity("output", terms_e, param("E0", set(ring.support(y * y)) | {tuple([0] * nv)}),
                                          "sigE")),
                     objective=("min", "B"))


def bound_values(scaled: ScaledField, structure: Structure, y: Poly, lam: Fraction) -> ParameterValues:
    ring = scaled.ring
    n = scaled.n
    values = ParameterValues()
    for i, gi in enumerate(scaled.g):
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    d_support = ring.support(scaled.D)
    values.set_poly(ring, "lamD", scaled.D * to_fmpq(-lam), d_support)
    values.set_poly(ring, "lamD0", scaled.D * to_fmpq(lam), d_support)
    gens = ring.gens()
    for k, b in enumerate(scaled.bounds):
        d = gens[n + k]
        values.set_poly(ring, f"b{k}", d * d - ring.constant(b * b), [tuple(2 * int(j == n + k) for j in range(ring.nvars)),
                                                                     tuple([0] * ring.nvars)])
    values.set_poly(ring, "E0", -(y * y) - ring.constant(1), list(set(ring.support(y * y)) | {tuple([0] * ring.nvars)}))
    values.set_scalar("floor", BOUND_FLOOR)
    return values


def attempt(scaled: ScaledField, structure: Structure, y: Poly, lam: Fraction, search: Search) -> dict[str, Any] | None:
    values = bound_values(scaled, structure, y, lam)
    solution = search.solve(structure, values)
    if not solution.usable:
        return None
    point = search.exact(structure, solution, values)
    if point is None:
        return None
    ring = scaled.ring
    grams = {g.name: GramPoly.of(g.basis, point.grams[g.name]) for g in structure.grams}
    taus = [grams[f"tau{k}"] for k in range(scaled.m)]
    B = point.scalars["B"]
    ok, _ = check_dissipation(ring, scaled.g, scaled.D, scaled.bounds, grams["V"], lam, taus, grams["sigD"])
    if not ok:
        return None
    ok, _ = check_output_bound(ring, grams["V"], y, B, grams["sigE"])
    if not ok:
        return None
    return {"V": grams["V"], "taus": taus, "sigD": grams["sigD"], "sigE": grams["sigE"], "B": B, "lam": lam}


def best_bound(scaled: ScaledField, y: Poly, search: Search) -> tuple[dict[str, Any] | None, list[str]]:
    best: dict[str, Any] | None = None
    tried: list[str] = []
    for degree in BOUND_DEGREES:
        structure = bound_structure(scaled, y, degree)
        if structure is None:
            tried.append(f"degree {degree}: too large")
            continue
        for lam in LAMBDA_GRID:
            found = attempt(scaled, structure, y, Fraction(lam).limit_denominator(1000), search)
            if found is not None and (best is None or found["B"] < best["B"]):
                best = {**found, "degree": degree}
        tried.append(f"degree {degree}: {'found' if best is not None else 'none'}")
    return best, tried


def run(scaled: ScaledField, search: Search) -> ConditionResult:
    """Every output's certified ``limsup`` (declared units), one certificate each."""
    from lyapcheck import exact

    if scaled.m == 0:
        return ConditionResult("sos_bound", "not_applicable", "the model has no [disturbances]: there is no "
                                                              "disturbance to bound the outputs under")
    bounds: dict[str, float] = {}
    certs: dict[str, Any] = {}
    missing: list[str] = []
    try:
        for (name, y), s_y in zip(scaled.outputs.items(), scaled.scaling.outputs):
            found, tried = best_bound(scaled, y, search)
            if found is None:
                missing.append(f"{name} ({'; '.join(tried)})")
                continue
            bound = exact.sqrt_upper(found["B"], 12) * s_y
            bounds[name] = float(bound)
            certs[name] = {"degree": found["degree"], "lam_scaled": str(found["lam"]), "B_scaled": str(found["B"]),
                           "bound": str(bound), "gram_V": found["V"].to_json(),
                           "gram_tau": [t.to_json() for t in found["taus"]], "gram_sigma_D": found["sigD"].to_json(),
                           "gram_sigma_E": found["sigE"].to_json(),
                           "V": terms_json(scaled.ring, unscale_polynomial(scaled.ring, found["V"].poly(scaled.ring),
                                                                           scaled.scaling, scaled.n))}
    except BudgetExhausted as exc:
        return ConditionResult("sos_bound", "inconclusive", f"{exc}; bounds found so far: {bounds}",
                               numbers={"reason": str(exc), "bounds": bounds}, solver={"solves": search.log})
    if not bounds:
        return ConditionResult("sos_bound", "not_certified", "no dissipation certificate was found for any output: "
                                                             + "; ".join(missing), solver={"solves": search.log})
    text = ", ".join(f"limsup |{k}| <= {v:.4g}" for k, v in bounds.items())
    summary = f"for every disturbance within its bounds and every start: {text} (checked exactly)"
    if missing:
        summary += f"; no bound for {', '.join(missing)}"
    return ConditionResult("sos_bound", "certified", summary, numbers={"bounds": bounds},
                           certificate={"outputs": certs}, solver={"solves": search.log})

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

The ``y`` bounded is the output's deviation from its value at the equilibrium (the disturbances at 0),
``y - y_eq`` (:func:`output_deviation`): the shifted field's output keeps ``y_eq`` as its constant
term, and a bound on ``|h|`` for a gap whose equilibrium is 30 m would say nothing. The claim states
``bounds_reference`` (each ``y_eq``, SI) and, with ``[units]``, ``bounds_unit`` (:func:`bound_figures`).

The search, per output: minimize ``B`` for each decay rate of :data:`LAMBDA_GRID` (scaled time),
``V`` of degree 2, then 4 where the field allows; every candidate is decided by the exact check,
and the smallest certified ``B`` is the bound. The bound in declared units is
``s_y sqrt(B)`` rounded up exactly (:func:`lyapcheck.exact.sqrt_upper`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.engines import reasons
from lyapcheck.models.loop.field import ScaledField, unscale_polynomial
from lyapcheck.models.classes.lyapunov import TARGET_LIMIT, affordable, face_probe, terms_json
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (BudgetExhausted, ParameterValues, Search, box_multipliers, box_multipliers_of,
                                     box_support, exact_grams, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import check_dissipation, check_output_bound
from lyapcheck.sos.polynomials import Monomial, Poly, monomials, to_fmpq
from lyapcheck.sos.program import Gram, Identity, Scalar, Solution, Structure, Term

if TYPE_CHECKING:
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.recast import RecastModel

#: decay rates ``lam`` of the dissipation inequality tried, in scaled time
LAMBDA_GRID: Final = (0.05, 0.2, 0.6, 1.5, 4.0)
#: factors around the best grid rate tried next (a geometric refinement of lam)
LAMBDA_REFINE: Final = (0.5, 0.7, 1.4, 2.0)
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


def bound_structure(scaled: ScaledField, y: Poly, degree: int,
                    drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | None:
    """The program for ``V`` of this degree; ``drop``: (Gram, monomial) pairs left out of the
    bases of ``V`` and the remainders (facial reduction, :func:`lyapcheck.models.classes.lyapunov.vanishing_monomials`)."""
    ring = scaled.ring
    n, m = scaled.n, scaled.m
    nv = ring.nvars
    generators = _symmetry(scaled, y)
    z_v = [q for q in (tuple(list(a) + [0] * (nv - n)) for a in monomials(n, 0, degree // 2))  # V of the states alone
           if ("V", q) not in drop]
    if not bases.has_pure_powers(z_v, range(n)):
        return None  # the face the solver found keeps no pure power of some state: no strict V there
    v_blocks = bases.character_blocks(z_v, generators)
    v_products = {tuple(a + b for a, b in zip(z_v[i], z_v[j])) for idx in v_blocks for i in idx for j in idx}
    target: set[Monomial] = set()
    for i, gi in enumerate(scaled.g):
        derived = {q[:i] + (q[i] - 1,) + q[i + 1:] for q in v_products if q[i] > 0}
        target |= {tuple(a + b for a, b in zip(q, s)) for q in derived for s in ring.support(gi)}
    d_support = set(ring.support(scaled.D))
    target |= {tuple(a + b for a, b in zip(q, s)) for q in v_products for s in d_support} | d_support
    # tau_k (b_k^2 - d_k^2) must reach the flow's degree: the disturbance enters it, times D
    top = max((sum(q) for q in target), default=2)
    # tau_k depends on the states (and a box's parameters), not on the disturbances: a d in its basis
    # would bring -tau_dd d^4, which no sum of squares can balance
    z_tau = [q for q in monomials(nv, 0, max((top - 1) // 2, 0)) if not any(q[n:n + m])]
    tau_blocks = bases.character_blocks(z_tau, generators)
    tau_products = {tuple(a + b for a, b in zip(z_tau[i], z_tau[j])) for idx in tau_blocks for i in idx for j in idx}
    for k in range(m):
        sq = tuple(2 * int(j == n + k) for j in range(nv))
        target |= {tuple(a + b for a, b in zip(q, s)) for q in tau_products for s in (sq, tuple([0] * nv))}
    box_vars = list(range(n + m, nv))
    d_box_grams, d_box_terms = box_multipliers(nv, n, target, with_states=False, generators=generators, prefix="rD",
                                               box_vars=box_vars, margin="floor")
    target |= box_support(d_box_grams, nv)
    if len(target) > TARGET_LIMIT:
        return None
    z_d = [q for q in bases.sos_basis(nv, target) if ("sigD", q) not in drop]
    e_target = set(v_products) | set(ring.support(y * y)) | {tuple([0] * nv)}
    e_box_grams, e_box_terms = box_multipliers(nv, n, e_target, with_states=False, generators=generators, prefix="rE",
                                               box_vars=[j for j in box_vars if any(q[j] for q in ring.support(y))],
                                               margin="floor")
    e_target |= box_support(e_box_grams, nv)
    z_e = [q for q in bases.sos_basis(nv, e_target) if ("sigE", q) not in drop]
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
    terms_d.append(Term(param("lamD", d_support), "v0"))  # V's free constant: -lam v0 D
    for k in range(m):
        sq = tuple(2 * int(j == n + k) for j in range(nv))
        terms_d.append(Term(param(f"b{k}", [sq, tuple([0] * nv)]), f"tau{k}"))
    terms_d.extend(d_box_terms)
    terms_d.append(Term(one(ring, -1), "sigD"))
    terms_e = (Term(one(ring, 1), "V"), Term(one(ring, 1), "v0"), Term(one(ring, 1), "B"), *e_box_terms,
               Term(one(ring, -1), "sigE"))
    grams += d_box_grams + e_box_grams
    return affordable(Structure(nvars=nv, grams=tuple(grams), scalars=(Scalar("B"), Scalar("v0")),
                     identities=(Identity("dissipation", tuple(terms_d), param("lamD0", d_support), "sigD"),
                                 Identity("output", terms_e, param("E0", set(ring.support(y * y)) | {tuple([0] * nv)}),
                                          "sigE")),
                     objective=("min", "B")))


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
    return attempt_with_solution(scaled, structure, y, lam, search)[0]


def attempt_with_solution(scaled: ScaledField, structure: Structure, y: Poly, lam: Fraction, search: Search
                          ) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at decay rate ``lam``; the exact certificate if it passes (and the solve)."""
    point, solution = search.solve_exact(structure, bound_values(scaled, structure, y, lam))
    if point is None:
        return None, solution
    ring = scaled.ring
    grams = exact_grams(structure, point)
    taus = [grams[f"tau{k}"] for k in range(scaled.m)]
    B, v0 = point.scalars["B"], point.scalars["v0"]
    box_d = box_multipliers_of(point.grams, multiplier_grams(structure, "rD"))
    box_e = box_multipliers_of(point.grams, multiplier_grams(structure, "rE"))
    ok, _ = check_dissipation(ring, scaled.g, scaled.D, scaled.bounds, grams["V"], lam, taus, grams["sigD"], box_d, v0)
    if not ok:
        return None, solution
    ok, _ = check_output_bound(ring, grams["V"], y, B, grams["sigE"], box_e, v0)
    if not ok:
        return None, solution
    return {"V": grams["V"], "v0": v0, "taus": taus, "sigD": grams["sigD"], "sigE": grams["sigE"], "B": B,
            "lam": lam, "box_D": box_d, "box_E": box_e}, solution


def best_bound(scaled: ScaledField, y: Poly, search: Search) -> tuple[dict[str, Any] | None, list[str]]:
    """The smallest certified ``B`` over the degrees and decay rates (module docstring), with
    facial reduction of the remainders where a solve shows vanishing diagonal entries, and a
    geometric refinement of ``lam`` around the best one found on :data:`LAMBDA_GRID`."""
    from lyapcheck.models.classes.lyapunov import FACIAL_ROUNDS, vanishing_monomials

    best: dict[str, Any] | None = None
    tried: list[str] = []
    for degree in searched_degrees(BOUND_DEGREES):
        full = bound_structure(scaled, y, degree)
        if full is None:
            tried.append(f"degree {degree}: " + size_limit(None, "a program above the size limits", None,
                                                           "MAX_GRAM_ROWS, TARGET_LIMIT, BLOCK_COST_LIMIT"))
            continue
        found_here: list[tuple[Fraction, Fraction]] = []
        # the full program first at every rate, then its facial reductions in turn: each found by a
        # probe (:func:`face_probe`) once per degree, when a rate fails on every program so far. The
        # floor on every Gram matrix makes a program whose V must be singular over the full basis
        # infeasible, and its solution says nothing of the face (the margin variable is unused)
        chain: list[tuple[Structure, frozenset[tuple[str, Monomial]]]] = [(full, frozenset())]
        exhausted = False
        outcomes: dict[str, int] = {}  # why each solve gave no certificate, counted

        def try_lam(lam: Fraction) -> dict[str, Any] | None:
            nonlocal exhausted
            for i in range(FACIAL_ROUNDS + 1):
                if i == len(chain):
                    if exhausted:
                        return None
                    structure, drop = chain[-1]
                    probe = face_probe(structure, "V")
                    values = bound_values(scaled, structure, y, lam)
                    values.floats = {k: v for k, v in values.floats.items() if k in probe.parameters()}
                    solution = search.solve(probe, values)
                    vanishing = frozenset((name, q) for name in ("V", "sigD", "sigE")
                                          for q in vanishing_monomials(structure.gram(name), solution))
                    reduced = bound_structure(scaled, y, degree, drop | vanishing) if vanishing else None
                    if reduced is None:
                        exhausted = True
                        return None
                    chain.append((reduced, drop | vanishing))
                found, solution = attempt_with_solution(scaled, chain[i][0], y, lam, search)
                if found is not None:
                    return found
                why = why_none(solution)
                outcomes[why] = outcomes.get(why, 0) + 1
            return None

        for lam in (Fraction(x).limit_denominator(1000) for x in LAMBDA_GRID):
            found = try_lam(lam)
            if found is not None:
                found_here.append((found["B"], lam))
                if best is None or found["B"] < best["B"]:
                    best = {**found, "degree": degree}
        if found_here:
            _, lam0 = min(found_here)
            for factor in LAMBDA_REFINE:
                lam = (lam0 * Fraction(factor).limit_denominator(1000)).limit_denominator(10**6)
                found = try_lam(lam)
                if found is not None and best is not None and found["B"] < best["B"]:
                    best = {**found, "degree": degree}
        if found_here:
            tried.append(f"degree {degree}: found")
        else:
            tried.append(f"degree {degree}: none at the rates lam = {', '.join(f'{x:g}' for x in LAMBDA_GRID)} "
                         f"(scaled time), on the full basis and {len(chain) - 1} facial reduction(s): "
                         + ", ".join(f"{why} ({count})" for why, count in outcomes.items()))
    return best, tried


def output_deviation(scaled: ScaledField, name: str) -> tuple[Poly, Fraction | None]:
    """The output ``name`` whose ``limsup |.|`` the class proves, in scaled coordinates, and its
    reference point in declared units: ``y~ - y~(0)`` and ``y_eq = s_y y~(0)``, the output at the
    equilibrium with the disturbances at 0 (the shifted coordinates put the equilibrium at 0). Where
    that value depends on a box's parameters (it is not one number), the output itself and None."""
    ring = scaled.ring
    y = scaled.outputs[name]
    s_y = scaled.scaling.outputs[list(scaled.outputs).index(name)]
    moving = scaled.n + scaled.m  # the states and the disturbances; a box's parameters come after
    zero = tuple([0] * ring.nvars)
    fixed = {m: c for m, c in ring.terms(y).items() if not any(m[:moving])}
    if any(m != zero for m in fixed):
        return y, None
    y_eq = fixed.get(zero, Fraction(0))
    return y - ring.constant(y_eq), y_eq * s_y


def output_units(model: "Model | RecastModel") -> dict[str, str]:
    """Each output's unit (an SI unit text, ``''`` when dimensionless) where the model declares
    ``[units]``, else ``{}``: a state's as declared, an expression's its dimension's SI unit, found by
    the dimension check of :mod:`lyapcheck.models.language.dimensions` (which the model passed on loading)
    from the states' units and the parameters' values as the file gives them (a ``--set`` has the
    file's dimension, checked on loading)."""
    import tomllib

    from lyapcheck.models.language import dimensions as dims
    from lyapcheck.units import parse_si_with_dimension

    if not model.units:
        return {}
    table = dims.read_units(model.units, model.states)
    names = {s: dims.Named("state", table.dimension(s), table.states[s][0], bool(table.states[s][0]))
             for s in model.states}
    for key, value in tomllib.loads(model.text).get("parameters", {}).items():
        quantity = parse_si_with_dimension(key, value)
        names[key] = dims.Named("parameter", quantity.dimension, str(value), bool(quantity.unit))
    out: dict[str, str] = {}
    for name, text in model.output_text.items():
        written = text.strip()
        out[name] = table.states[written][0] if written in table.states else \
            dims.check_output(name, written, names).si_unit()
    return out


def bound_figures(scaled: ScaledField, names: Sequence[str]) -> dict[str, Any]:
    """What a claim on the outputs ``names`` states beside its bounds: ``bounds_reference`` (each
    output's value at the equilibrium, SI; None where it depends on a box's parameters, and the
    bound is then on the output itself) and, with ``[units]``, ``bounds_unit``. ``verify`` re-makes
    them from the model and compares."""
    references = {}
    for name in names:
        _, y_eq = output_deviation(scaled, name)
        references[name] = float(y_eq) if y_eq is not None else None
    out: dict[str, Any] = {"bounds_reference": references}
    units = output_units(scaled.cleared.shifted.model)
    if units:
        out["bounds_unit"] = {name: units[name] for name in names}
    return out


def run(scaled: ScaledField, search: Search) -> ConditionResult:
    """Every output's certified ``limsup`` (declared units), one certificate each."""
    from lyapcheck import exact

    if scaled.m == 0:
        return ConditionResult("sos_bound", "not_applicable", "the model has no [disturbances]: there is no "
                                                              "disturbance to bound the outputs under")
    bounds: dict[str, float] = {}
    certs: dict[str, Any] = {}
    missing: list[str] = []
    detail: list[str] = []  # what each output's search met (numbers["detail"])
    try:
        for name, s_y in zip(scaled.outputs, scaled.scaling.outputs):
            y, _ = output_deviation(scaled, name)
            found, tried = best_bound(scaled, y, search)
            if found is None:
                missing.append(f"{name} ({'; '.join(tried)})")
                detail.extend(f"{name}: {line}" for line in tried)
                continue
            bound = exact.sqrt_upper(found["B"], 12) * s_y
            bounds[name] = float(bound)
            certs[name] = {"degree": found["degree"], "lam_scaled": str(found["lam"]), "B_scaled": str(found["B"]),
                           "bound": str(bound), "gram_V": found["V"].to_json(), "V_constant": str(found["v0"]),
                           "gram_tau": [t.to_json() for t in found["taus"]], "gram_sigma_D": found["sigD"].to_json(),
                           "gram_sigma_E": found["sigE"].to_json(),
                           "V": terms_json(scaled.ring, unscale_polynomial(
                               scaled.ring, found["V"].poly(scaled.ring) + scaled.ring.constant(found["v0"]),
                               scaled.scaling, scaled.n))}
            if found["box_D"] or found["box_E"]:
                certs[name]["box_multipliers_D"] = [{"variable": j, "gram": r.to_json()} for j, r in found["box_D"]]
                certs[name]["box_multipliers_E"] = [{"variable": j, "gram": r.to_json()} for j, r in found["box_E"]]
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a bound on every output", search.budget.seconds,
                                   [str(exc), f"bounds found so far: {bounds}", *detail])
        return ConditionResult("sos_bound", "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "bounds": bounds}),
                               solver={"solves": search.log})
    if not bounds:
        none = reasons.not_found("storage function that bounds an output", BOUND_DEGREES, detail,
                                 ("degree", "disturbances", "time"))
        return ConditionResult("sos_bound", "not_certified", none.summary, numbers=none.numbers(),
                               solver={"solves": search.log})
    from lyapcheck.models.classes.claims import summary

    numbers = {"bounds": bounds, **bound_figures(scaled, list(bounds))}
    text = summary("sos_bound", {"status": "certified", **numbers}, list(scaled.outputs)) or ""
    return ConditionResult("sos_bound", "certified", text, numbers=numbers,
                           certificate={"outputs": certs}, solver={"solves": search.log})

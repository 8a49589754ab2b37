"""``barrier``: no trajectory from the initial set ever enters the unsafe set, found by SOS and checked exactly.

The certificate (kind Barrier of :mod:`lyapcheck.sos.certificates`), in the scaled coordinates of
:mod:`lyapcheck.models.loop.field`, with the disturbances that enter the field as box coordinates
``d = b u``, ``u in [-1, 1]`` (:func:`~lyapcheck.models.loop.field.state_field`, robust), and each set a
union of pieces ``{p_1 >= 0, ..., p_m >= 0}`` (:mod:`lyapcheck.models.language.sets`, mapped to the scaled
coordinates):

    -B - sum_i s_i h_i = r_I                         each initial piece   (B <= 0 there)
    B - 1 - sum_j t_j h_j = r_U                      each unsafe piece    (B >= 1 there)
    -grad B . g + lam B D - sum_k r_k (1 - u_k^2) = r_D                   (B' <= lam B everywhere)

with every ``s``, ``t``, ``r`` a sum of squares, and ``h`` each inequality of the piece and each
product of two of them (:func:`~lyapcheck.sos.certificates.piece_generators`). ``B`` is a free
polynomial of the states (its coefficients are the program's free scalars). The margin of 1 between the sets makes every
condition non-strict, so the exact check needs positive semidefinite Gram matrices only; the search
still maximizes the smallest Gram eigenvalue, which gives the rounding room.

The search: ``B`` of degree 2, then 4, then 6, each at the rates :data:`LAMBDAS` (scaled time), the
first certificate that passes the exact check is the answer. The property is ``safety``: for every
start in the initial set and every disturbance within its bounds (time-varying ones included: ``B``
does not depend on ``d``), the state never enters the unsafe set.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.engines import reasons
from lyapcheck.models.classes.claims import BARRIER_SENTENCE
from lyapcheck.models.loop.field import ScaledField, StateField
from lyapcheck.models.classes.lyapunov import BLOCK_COST_LIMIT, TARGET_LIMIT, affordable, on_remainder_faces
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (BudgetExhausted, ParameterValues, Search, box_multipliers, box_multipliers_of,
                                     box_support, exact_grams, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, check_barrier, piece_generators
from lyapcheck.sos.polynomials import Monomial, Poly, monomials, to_fmpq
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Solution, Structure, Term, full_blocks

#: degrees of B tried, in turn
BARRIER_DEGREES: Final = (2, 4, 6)
#: rates lam of B' <= lam B tried at each degree (scaled time); any real rate is sound
LAMBDAS: Final = (Fraction(-1, 4), Fraction(0), Fraction(1), Fraction(-1), Fraction(1, 4))
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120

Pieces = Sequence[Sequence[Poly]]


def _b_basis(field: StateField, degree: int) -> list[Monomial]:
    """B's monomials: every monomial of the states of degree 0..``degree`` (no box coordinate)."""
    nv = field.ring.nvars
    return [tuple(list(m) + [0] * (nv - field.n)) for m in monomials(field.n, 0, degree)]


def _products(basis: Sequence[Monomial]) -> set[Monomial]:
    return {tuple(a + b for a, b in zip(x, y)) for x in basis for y in basis}


def _shift(support: Sequence[Monomial], by: Sequence[Monomial]) -> set[Monomial]:
    return {tuple(a + b for a, b in zip(x, y)) for x in support for y in by}


def _multiplier_basis(field: StateField, b_degree: int, p: Poly) -> list[Monomial]:
    """An S-procedure multiplier's basis: the state monomials up to half of ``deg B - deg p`` (at
    least the constant), so that ``s p`` stays within B's degree."""
    nv = field.ring.nvars
    half = max(0, (b_degree - max(sum(m) for m in field.ring.support(p))) // 2)
    return [tuple(list(m) + [0] * (nv - field.n)) for m in monomials(field.n, 0, half)]


def set_identities(field: StateField, b_basis: Sequence[Monomial], degree: int, initial: Pieces, unsafe: Pieces,
                   grams: list[Gram], drop: frozenset[tuple[str, Monomial]] = frozenset()) -> list[Identity] | str:
    """The identities on the sets, for a free polynomial with coefficients ``b0, b1, ...`` over
    ``b_basis``: ``-B - sum s h = R`` on each initial piece and ``B - 1 - sum t h = R`` on each
    unsafe piece (their multipliers and remainders appended to ``grams``), or why not (a size limit)."""
    ring = field.ring
    nv = ring.nvars
    zero = tuple([0] * nv)
    identities: list[Identity] = []
    for kind, pieces, sign, constant in (("I", initial, -1, 0), ("U", unsafe, 1, -1)):
        for k, piece in enumerate(pieces):
            terms = [Term(Coefficients.literal({m: sign}), f"b{i}") for i, m in enumerate(b_basis)]
            target = set(b_basis)
            for j, p in enumerate(piece_generators(list(piece))):
                basis = _multiplier_basis(field, degree, p)
                name = f"s{kind}{k}_{j}"
                grams.append(Gram(name, tuple(basis), full_blocks(basis)))
                terms.append(Term(param(f"p{kind}{k}_{j}", ring.support(p)), name))
                target |= _shift(ring.support(p), list(_products(basis)))
            name = f"R{kind}{k}"
            remainder_basis = [m for m in bases.sos_basis(nv, target | {zero}) if (name, m) not in drop]
            if len(remainder_basis) > MAX_GRAM_ROWS:
                return size_limit(len(remainder_basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS,
                                  "MAX_GRAM_ROWS")
            grams.append(Gram(name, tuple(remainder_basis), full_blocks(remainder_basis)))
            terms.append(Term(one(ring, -1), name))
            const = Coefficients.literal({zero: constant}) if constant else None
            identities.append(Identity(f"{kind}{k}", tuple(terms), const, name))
    return identities


def set_values(field: StateField, values: ParameterValues, initial: Pieces, unsafe: Pieces) -> None:
    """The parameters of :func:`set_identities`: each generator of each piece, negated."""
    ring = field.ring
    for kind, pieces in (("I", initial), ("U", unsafe)):
        for k, piece in enumerate(pieces):
            for j, p in enumerate(piece_generators(list(piece))):
                values.set_poly(ring, f"p{kind}{k}_{j}", -p, ring.support(p))


def set_certificates(structure: Structure, grams: dict[str, GramPoly], initial: Pieces, unsafe: Pieces
                     ) -> tuple[list[Any], list[Any]]:
    """The exact multipliers and remainders of :func:`set_identities`, per piece."""
    initial_certs = [([grams[f"sI{k}_{j}"] for j in range(len(piece_generators(list(piece))))], grams[f"RI{k}"])
                     for k, piece in enumerate(initial)]
    unsafe_certs = [([grams[f"sU{k}_{j}"] for j in range(len(piece_generators(list(piece))))], grams[f"RU{k}"])
                    for k, piece in enumerate(unsafe)]
    return initial_certs, unsafe_certs


def barrier_structure(field: StateField, initial: Pieces, unsafe: Pieces, degree: int,
                      drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``B`` of this degree, or why there is none (a size limit, named). ``drop``:
    (remainder, monomial) pairs left out of the remainders' bases (facial reduction)."""
    ring = field.ring
    nv = ring.nvars
    zero = tuple([0] * nv)
    b_basis = _b_basis(field, degree)
    scalars = tuple(Scalar(f"b{k}") for k in range(len(b_basis)))
    grams: list[Gram] = []
    on_sets = set_identities(field, b_basis, degree, initial, unsafe, grams, drop)
    if isinstance(on_sets, str):
        return on_sets
    identities = list(on_sets)
    # the decrease: each coefficient b_m multiplies -grad(z^m) . g + lam z^m D (a parameter per m)
    terms = []
    target: set[Monomial] = set()
    for i, m in enumerate(b_basis):
        support = _decrease_support(field, m)
        if not support:
            continue
        terms.append(Term(param(f"dB{i}", support), f"b{i}"))
        target |= set(support)
    box_grams, box_terms = box_multipliers(nv, field.n, target, with_states=False)
    target |= box_support(box_grams, nv)
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    decrease_basis = [m for m in bases.sos_basis(nv, target | {zero}) if ("RD", m) not in drop]
    if len(decrease_basis) > MAX_GRAM_ROWS:
        return size_limit(len(decrease_basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
    grams.append(Gram("RD", tuple(decrease_basis), full_blocks(decrease_basis)))
    grams.extend(box_grams)
    terms.extend(box_terms)
    terms.append(Term(one(ring, -1), "RD"))
    identities.append(Identity("decrease", tuple(terms), None, "RD"))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=scalars, identities=tuple(identities),
                          objective=("max_margin",))
    if affordable(structure) is None:
        return size_limit(f"{structure.cost():.1e}", "work units of the program", f"{BLOCK_COST_LIMIT:.1e}",
                          "BLOCK_COST_LIMIT")
    return structure


def _decrease_poly(field: StateField, m: Monomial, lam: Fraction) -> Poly:
    """``-grad(z^m) . g + lam z^m D``: the decrease identity's coefficient of B's monomial ``m``
    (``lam = 0``: reach_avoid's ``-grad(z^m) . g``)."""
    ring = field.ring
    zm = ring.from_terms({m: 1})
    total = zm * field.D * to_fmpq(lam)
    for i, gi in enumerate(field.g):
        total -= zm.derivative(i) * gi
    return total


def _decrease_support(field: StateField, m: Monomial, with_rate: bool = True) -> list[Monomial]:
    """The generic support of :func:`_decrease_poly` (every rate: ``lam = 1`` stands for all;
    ``with_rate`` False: ``lam = 0``)."""
    ring = field.ring
    out: set[Monomial] = set()
    for i, gi in enumerate(field.g):
        if m[i] > 0:
            d = m[:i] + (m[i] - 1,) + m[i + 1:]
            out |= _shift(ring.support(gi), [d])
    if with_rate:
        out |= _shift(ring.support(field.D), [m])
    return sorted(out)


def barrier_values(field: StateField, degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction) -> ParameterValues:
    """The program's parameters: each set inequality (negated, as the identity subtracts ``s p``) and
    each of B's monomials' decrease coefficient at rate ``lam``."""
    ring = field.ring
    values = ParameterValues()
    set_values(field, values, initial, unsafe)
    for i, m in enumerate(_b_basis(field, degree)):
        support = _decrease_support(field, m)
        if support:
            values.set_poly(ring, f"dB{i}", _decrease_poly(field, m, lam), support)
    return values


def attempt(field: StateField, structure: Structure, degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction,
            search: Search) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at rate ``lam``; the exact certificate if it passes the exact check."""
    point, solution = search.solve_exact(structure, barrier_values(field, degree, initial, unsafe, lam))
    if point is None:
        return None, solution
    ring = field.ring
    B = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(_b_basis(field, degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_barrier(ring, field.g, field.D, B, lam, initial, initial_certs, unsafe, unsafe_certs,
                          grams["RD"], box)
    if not ok:
        return None, solution
    return {"B": B, "lam": lam, "initial": initial_certs, "unsafe": unsafe_certs, "decrease": grams["RD"],
            "box": box, "margin": solution.scalars.get("t", 0.0)}, solution


def search_barrier(field: StateField, initial: Pieces, unsafe: Pieces, search: Search
                   ) -> tuple[dict[str, Any] | None, list[str]]:
    """The first certificate over :data:`BARRIER_DEGREES` and :data:`LAMBDAS`, and what was tried."""
    tried: list[str] = []
    for degree in searched_degrees(BARRIER_DEGREES):
        full = barrier_structure(field, initial, unsafe, degree)
        if isinstance(full, str):
            tried.append(f"degree {degree}: {full}")
            continue
        outcomes: dict[str, int] = {}
        for lam in LAMBDAS:
            # (the lambdas run within this iteration: degree and lam are this iteration's)
            found, solution = on_remainder_faces(
                full, lambda drop: barrier_structure(field, initial, unsafe, degree, drop),
                lambda structure: attempt(field, structure, degree, initial, unsafe, lam, search), search)
            if found is not None:
                found["degree"] = degree
                tried.append(f"degree {degree}: found at lam = {lam}")
                return found, tried
            why = why_none(solution)
            outcomes[why] = outcomes.get(why, 0) + 1
        tried.append(f"degree {degree}: none at lam = {', '.join(str(x) for x in LAMBDAS)} (scaled time): "
                     + ", ".join(f"{why} ({count})" for why, count in outcomes.items()))
    return None, tried




def scaled_pieces(scaled: ScaledField, field: StateField, pieces: Pieces) -> list[list[Poly]]:
    """A set's pieces, polynomials in the declared states (the model's state ring), in the scaled
    coordinates of ``field``: ``x = x_eq + S z`` substituted exactly (the sets do not depend on the
    disturbances or a box's parameters)."""
    from lyapcheck.models.loop.field import linear_images

    model = scaled.cleared.shifted.model
    full = model.state_ring
    images = linear_images(full, model.n, scaled.scaling.matrix())
    images = [im + to_fmpq(e) for im, e in zip(images[:model.n], model.equilibrium)] + images[model.n:]
    index = {name: k for k, name in enumerate(full.names)}
    target = field.ring

    def moved(p: Poly) -> Poly:  # the state ring's polynomial in the field's ring (by name)
        q = full.compose(p, images)
        terms = {}
        for m, c in full.terms(q).items():
            if any(e and full.names[k] not in target.names for k, e in enumerate(m)):
                raise ValueError("a set depends on a variable of the field's ring only by name: a disturbance")
            terms[tuple(m[index[name]] if name in index else 0 for name in target.names)] = c
        return target.from_terms(terms)

    return [[moved(p) for p in piece] for piece in pieces]


def certificate_json(scaled: ScaledField, field: StateField, found: dict[str, Any]) -> dict[str, Any]:
    """The exact certificate: ``B`` in the declared (shifted) states (``terms``, as every model
    certificate's polynomials), its rate, and every Gram matrix in the scaled coordinates."""
    from lyapcheck.models.classes.lyapunov import stated_v

    def piece(cert: Any) -> dict[str, Any]:
        multipliers, remainder = cert
        return {"multipliers": [s.to_json() for s in multipliers], "remainder": remainder.to_json()}

    out: dict[str, Any] = {"kind": "barrier", "degree": found["degree"], "lambda_scaled": str(found["lam"]),
                           "B": stated_v(scaled, field, found["B"]),
                           "B_scaled": {"terms": [[str(c), list(m)]
                                                  for m, c in sorted(field.ring.terms(found["B"]).items())]},
                           "initial": [piece(c) for c in found["initial"]],
                           "unsafe": [piece(c) for c in found["unsafe"]],
                           "gram_decrease": found["decrease"].to_json()}
    if found["box"]:
        out["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in found["box"]]
    return out


def run(scaled: ScaledField, search: Search) -> ConditionResult:
    """The ``barrier`` class on the model's ``[sets]`` (``initial`` and ``unsafe``), for every
    disturbance within its bounds (the robust field: each disturbance that enters is a box
    coordinate, so ``B`` serves every disturbance signal)."""
    from lyapcheck.models.loop.field import state_field

    model = scaled.cleared.shifted.model
    field = state_field(scaled, robust=True)
    initial = scaled_pieces(scaled, field, model.sets["initial"])
    unsafe = scaled_pieces(scaled, field, model.sets["unsafe"])
    try:
        found, tried = search_barrier(field, initial, unsafe, search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a barrier", search.budget.seconds, str(exc))
        return ConditionResult("barrier", "inconclusive", late.summary, numbers=late.numbers({"reason": str(exc)}),
                               solver={"solves": search.log}, property="safety")
    trial = _falsification(model)
    if found is None:
        if trial is not None and trial.entry is not None:
            entry = trial.entry.describe(list(model.states), list(model.disturbances), model.units)
            return ConditionResult("barrier", "counterexample",
                                   f"a simulated trajectory from the initial set enters the unsafe set: {entry} "
                                   "(simulation, reproducible from its start and disturbance)",
                                   numbers={"tried": tried, "falsification": trial.to_dict(),
                                            "detail": [f"no barrier was found: {line}" for line in tried]},
                                   refutation={"kind": "trajectory", **trial.entry.to_dict()},
                                   solver={"solves": search.log}, property="safety")
        none = reasons.not_found("barrier", BARRIER_DEGREES, tried, ("degree", "sets", "time"))
        numbers: dict[str, Any] = none.numbers({"tried": tried})
        if trial is not None:
            numbers["falsification"] = trial.to_dict()
        return ConditionResult("barrier", "not_certified", none.summary, numbers=numbers, solver={"solves": search.log},
                               property="safety")
    T = scaled.scaling.time
    numbers = {"degree": found["degree"], "lambda_per_s": float(found["lam"] / T),
               "relative_margin": found["margin"]}
    if trial is not None:
        numbers["falsification"] = trial.to_dict()
        numbers["closest_approach"] = trial.closest_approach
        if trial.entered:  # a trajectory into a set proved unreachable: the proof or the simulation is wrong
            numbers["soundness_violation"] = True
    return ConditionResult("barrier", "certified", SUMMARY, numbers=numbers,
                           certificate=certificate_json(scaled, field, found), solver={"solves": search.log},
                           property="safety")


#: starts simulated from the initial set beside every barrier search; half as many above
#: FALSIFICATION_FEW_ABOVE states (the 8-state HighOrd8's 100 starts took 1.9 s, three times its proof)
FALSIFICATION_SAMPLES: Final = 100
FALSIFICATION_FEW_ABOVE: Final = 3


def _falsification(model: Any) -> Any:
    """Simulation beside the proof (:mod:`lyapcheck.models.classes.falsify`): the closest approach of
    trajectories from the initial set to the unsafe set, under every disturbance scenario; None
    when the simulation itself cannot run (a set whose inside no sampling finds)."""
    from lyapcheck.models.classes.falsify import falsify
    from lyapcheck.models.language.sets import margin

    try:
        samples = FALSIFICATION_SAMPLES if model.n <= FALSIFICATION_FEW_ABOVE else FALSIFICATION_SAMPLES // 2
        return falsify(model, model.sets["initial"], model.sets["unsafe"], margin, samples=samples)
    except ValueError:
        return None


#: what a certified barrier states (lyapcheck.models.classes.claims, which verify regenerates it from)
SUMMARY: Final = BARRIER_SENTENCE

__all__ = ["BARRIER_DEGREES", "LAMBDAS", "SUMMARY", "barrier_structure", "search_barrier", "attempt", "run",
           "scaled_pieces", "certificate_json"]

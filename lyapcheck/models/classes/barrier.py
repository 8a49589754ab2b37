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

One implementation for both kinds of loop: the program reads a
:class:`~lyapcheck.models.classes.bounds.BoundField` (:func:`as_barrier_field`), of which a polynomial
loop's robust field is the case without relations (its programs and certificates are the ones this class
has always built). A loop with functions (:func:`run_functions`; section "loops with functions" below)
is the same program on its recasting, every identity also carrying the recasting's relations'
multipliers; its certificate (kind :data:`KIND`) stores each identity's proof by relation index and
:func:`check_on_relations` re-checks it. ``[sets]`` are read on both kinds, and over a box of parameters.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Iterator, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.engines import reasons
from lyapcheck.models.classes.claims import BARRIER_RELATIONS_KIND, BARRIER_SENTENCE, RECAST_BARRIER_KIND
from lyapcheck.models.loop.field import ScaledField, StateField
from lyapcheck.models.classes.lyapunov import TARGET_LIMIT, on_remainder_faces, within_cost
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (BudgetExhausted, ParameterValues, Search, box_multipliers, box_multipliers_of,
                                     box_support, exact_grams, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, check_barrier, piece_generators
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Solution, Structure, Term, full_blocks

if TYPE_CHECKING:
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, Relation
    from lyapcheck.results import Property

#: degrees of B tried, in turn
BARRIER_DEGREES: Final = (2, 4, 6)
#: rates lam of B' <= lam B tried at each degree (scaled time); any real rate is sound
LAMBDAS: Final = (Fraction(-1, 4), Fraction(0), Fraction(1), Fraction(-1), Fraction(1, 4))
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120

Pieces = Sequence[Sequence[Poly]]


def as_barrier_field(field: "StateField | BoundField") -> "BoundField":
    """What the barrier's program reads of a loop (:class:`~lyapcheck.models.classes.bounds.BoundField`):
    a polynomial loop's robust field is the case without relations (B over the states, which move as
    ``g / D``, the disturbances' box coordinates after them); a loop with functions' view
    (:func:`relations_field`) is passed through."""
    from lyapcheck.models.classes.bounds import BoundField

    if isinstance(field, BoundField):
        return field
    n, nv = field.n, field.ring.nvars
    return BoundField(field.ring, n, tuple(range(n)), tuple(range(n)), tuple(enumerate(field.g)), field.D, (), (),
                      tuple(range(n, nv)))


def _b_basis(field: "StateField | BoundField", degree: int) -> list[Monomial]:
    """B's monomials: every monomial of B's variables (the states on a polynomial loop) of degree
    0..``degree`` (no box coordinate)."""
    from lyapcheck.models.classes.bounds import _embed

    view = as_barrier_field(field)
    nv = view.ring.nvars
    return [_embed(m, view.v_vars, nv) for m in monomials(len(view.v_vars), 0, degree)]


def _products(basis: Sequence[Monomial]) -> set[Monomial]:
    return {tuple(a + b for a, b in zip(x, y)) for x in basis for y in basis}


def _shift(support: Sequence[Monomial], by: Sequence[Monomial]) -> set[Monomial]:
    return {tuple(a + b for a, b in zip(x, y)) for x in support for y in by}


def _multiplier_basis(field: "StateField | BoundField", b_degree: int, p: Poly) -> list[Monomial]:
    """An S-procedure multiplier's basis: the monomials of B's variables up to half of ``deg B - deg p``
    (at least the constant), so that ``s p`` stays within B's degree."""
    half = max(0, (b_degree - max(sum(m) for m in field.ring.support(p))) // 2)
    return _b_basis(field, half)


def set_identities(field: "StateField | BoundField", b_basis: Sequence[Monomial], degree: int, initial: Pieces,
                   unsafe: Pieces, grams: list[Gram], drop: frozenset[tuple[str, Monomial]] = frozenset(),
                   scalars: list[Scalar] | None = None) -> list[Identity] | str:
    """The identities on the sets, for a free polynomial with coefficients ``b0, b1, ...`` over
    ``b_basis``: ``-B - sum s h = R`` on each initial piece and ``B - 1 - sum t h = R`` on each
    unsafe piece (their multipliers and remainders appended to ``grams``), or why not (a size limit).
    On a loop with functions each identity also subtracts its relations' multipliers
    (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`, their free scalars appended to
    ``scalars``); a polynomial loop has none."""
    from lyapcheck.models.classes.bounds import relation_multipliers

    view = as_barrier_field(field)
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
            if view.relations:
                rel_grams, rel_scalars, rel_terms, added = relation_multipliers(view, f"{kind}{k}", target, (),
                                                                                margin=True)
                grams.extend(rel_grams)
                terms.extend(rel_terms)
                target |= added
                if scalars is not None:
                    scalars.extend(rel_scalars)
            name = f"R{kind}{k}"
            remainder_basis = [m for m in bases.sos_basis(nv, target | {zero})
                               if (name, m) not in drop and view.allowed(m)]
            if len(remainder_basis) > MAX_GRAM_ROWS:
                return size_limit(len(remainder_basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS,
                                  "MAX_GRAM_ROWS")
            grams.append(Gram(name, tuple(remainder_basis), full_blocks(remainder_basis)))
            terms.append(Term(one(ring, -1), name))
            const = Coefficients.literal({zero: constant}) if constant else None
            identities.append(Identity(f"{kind}{k}", tuple(terms), const, name))
    return identities


def set_values(field: "StateField | BoundField", values: ParameterValues, initial: Pieces, unsafe: Pieces) -> None:
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


def barrier_structure(field: "StateField | BoundField", initial: Pieces, unsafe: Pieces, degree: int,
                      drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``B`` of this degree, or why there is none (a size limit, named). ``drop``:
    (remainder, monomial) pairs left out of the remainders' bases (facial reduction). On a loop with
    functions (a view with relations, :func:`relations_field`) every identity also carries its
    relations' multipliers; a polynomial loop's program is the one this class has always built."""
    from lyapcheck.models.classes.bounds import relation_multipliers

    view = as_barrier_field(field)
    ring = field.ring
    nv = ring.nvars
    b_basis = _b_basis(view, degree)
    scalars = [Scalar(f"b{k}") for k in range(len(b_basis))]
    grams: list[Gram] = []
    on_sets = set_identities(view, b_basis, degree, initial, unsafe, grams, drop, scalars)
    if isinstance(on_sets, str):
        return on_sets
    identities = list(on_sets)
    # the decrease: each coefficient b_m multiplies -grad(z^m) . g + lam z^m D (a parameter per m)
    terms = []
    target: set[Monomial] = set()
    for i, m in enumerate(b_basis):
        support = _decrease_support(view, m)
        if not support:
            continue
        terms.append(Term(param(f"dB{i}", support), f"b{i}"))
        target |= set(support)
    box_grams, box_terms = box_multipliers(nv, view.n, target, with_states=False, box_vars=view.box_vars)
    target |= box_support(box_grams, nv)
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(view, "D", target, (), margin=True)
    target |= added
    decrease_basis = remainder_basis(nv, target, "RD", drop, view.allowed)
    if isinstance(decrease_basis, str):
        return decrease_basis
    grams.append(Gram("RD", tuple(decrease_basis), full_blocks(decrease_basis)))
    grams.extend(box_grams)
    terms.extend(box_terms)
    grams.extend(rel_grams)
    terms.extend(rel_terms)
    scalars.extend(rel_scalars)
    terms.append(Term(one(ring, -1), "RD"))
    identities.append(Identity("decrease", tuple(terms), None, "RD"))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=tuple(scalars), identities=tuple(identities),
                          objective=("max_margin",))
    return within_cost(structure)


def remainder_basis(nv: int, target: set[Monomial], name: str, drop: frozenset[tuple[str, Monomial]],
                    allowed: Callable[[Monomial], bool] = lambda m: True, max_rows: int = MAX_GRAM_ROWS
                    ) -> list[Monomial] | str:
    """The basis of the remainder ``name`` of one identity whose other terms span ``target`` (its constant term
    besides): the Newton basis less what facial reduction dropped (``drop``) and what ``allowed`` refuses; or
    the size limit the identity (:data:`~lyapcheck.models.classes.lyapunov.TARGET_LIMIT`) or the basis
    (``max_rows``, the class's ``MAX_GRAM_ROWS``) passes."""
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    basis = [m for m in bases.sos_basis(nv, target | {tuple([0] * nv)}) if (name, m) not in drop and allowed(m)]
    if len(basis) > max_rows:
        return size_limit(len(basis), "monomials per sum-of-squares matrix", max_rows, "MAX_GRAM_ROWS")
    return basis


def _decrease_poly(field: "StateField | BoundField", m: Monomial, lam: Fraction) -> Poly:
    """``-grad(z^m) . g + lam z^m D``: the decrease identity's coefficient of B's monomial ``m``
    (``lam = 0``: reach_avoid's ``-grad(z^m) . g``); on a loop with functions ``g`` is the flows' ``N``
    and ``D`` their common denominator."""
    view = as_barrier_field(field)
    ring = view.ring
    zm = ring.from_terms({m: 1})
    total = zm * view.W * to_fmpq(lam)
    for i, gi in view.flows:
        total -= zm.derivative(i) * gi
    return total


def _decrease_support(field: "StateField | BoundField", m: Monomial, with_rate: bool = True) -> list[Monomial]:
    """The generic support of :func:`_decrease_poly` (every rate: ``lam = 1`` stands for all;
    ``with_rate`` False: ``lam = 0``)."""
    view = as_barrier_field(field)
    ring = view.ring
    out: set[Monomial] = set()
    for i, gi in view.flows:
        if m[i] > 0:
            d = m[:i] + (m[i] - 1,) + m[i + 1:]
            out |= _shift(ring.support(gi), [d])
    if with_rate:
        out |= _shift(ring.support(view.W), [m])
    return sorted(out)


def barrier_values(field: "StateField | BoundField", degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction
                   ) -> ParameterValues:
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


def attempt(field: "StateField | BoundField", structure: Structure, degree: int, initial: Pieces, unsafe: Pieces,
            lam: Fraction, search: Search) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at rate ``lam``; the exact certificate if it passes the exact check (a polynomial loop's
    :func:`~lyapcheck.sos.certificates.check_barrier`, a loop with functions' :func:`check_on_relations`)."""
    view = as_barrier_field(field)
    values = barrier_values(field, degree, initial, unsafe, lam)
    if view.relations:  # (a multiplier a facial reduction left out takes its parameter with it)
        kept = structure.parameters()
        values.floats = {k: v for k, v in values.floats.items() if k in kept}
        values.exact = {k: v for k, v in values.exact.items() if k in kept}
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    ring = field.ring
    B = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(_b_basis(view, degree))})
    if view.relations:
        proofs = relation_proofs(view, structure, point, initial, unsafe)
        ok, _ = check_on_relations(view, B, lam, initial, unsafe, proofs)
        if not ok:
            return None, solution
        return {"B": B, "lam": lam, "proofs": proofs, "margin": solution.scalars.get("t", 0.0)}, solution
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_barrier(ring, [gi for _, gi in view.flows], view.W, B, lam, initial, initial_certs, unsafe,
                          unsafe_certs, grams["RD"], box)
    if not ok:
        return None, solution
    return {"B": B, "lam": lam, "initial": initial_certs, "unsafe": unsafe_certs, "decrease": grams["RD"],
            "box": box, "margin": solution.scalars.get("t", 0.0)}, solution


def on_zero_faces(structure: Structure, attempt: Any, search: Search) -> tuple[Any, Solution]:
    """A loop with functions: solve ``structure`` and, while its exact check refuses a point on a face of the
    cone (a Gram row whose diagonal the solver left at 0: a relation's multiplier as well as a remainder,
    :func:`~lyapcheck.models.engines.recast_sos.zero_face`), that face left out and solved again, at most
    :data:`~lyapcheck.models.engines.recast_sos.FACE_ROUNDS` times (the relational classes' facial
    reduction). What ``attempt`` found (None when nothing passed) and the last solve."""
    from typing import cast

    from lyapcheck.models.engines.recast_sos import FACE_ROUNDS, zero_face

    for _ in range(FACE_ROUNDS + 1):
        search.budget.check()
        found, solution = attempt(structure)
        if found is not None or not solution.usable:
            return found, solution
        # (zero_face reads a program's Gram matrices alone, their names and bases, which a structure has too)
        face = zero_face(cast(Any, structure), solution.grams)
        smaller = without_face(structure, face) if face else None
        if smaller is None:
            break
        structure = smaller
    return None, solution


def without_face(structure: Structure, face: set[tuple[str, Monomial]]) -> Structure | None:
    """``structure`` with the (Gram, monomial) pairs of ``face`` left out of the Gram bases; a multiplier
    left with no row is left out with its term (it is 0), as the relational classes' programs leave it out
    (None when a remainder would keep no row)."""
    from dataclasses import replace

    remainders = {i.remainder for i in structure.identities}
    grams = []
    gone: set[str] = set()
    for g in structure.grams:
        keep = [k for k, q in enumerate(g.basis) if (g.name, q) not in face]
        if not keep:
            if g.name in remainders:
                return None
            gone.add(g.name)
            continue
        new = {k: j for j, k in enumerate(keep)}
        blocks = tuple(b for b in (tuple(new[k] for k in block if k in new) for block in g.blocks) if b)
        grams.append(replace(g, basis=tuple(g.basis[k] for k in keep), blocks=blocks))
    identities = tuple(replace(i, terms=tuple(t for t in i.terms if t.decision not in gone))
                       for i in structure.identities)
    return replace(structure, grams=tuple(grams), identities=identities)


#: a choice of B searched: its degree, the program's view of the loop for it, and its label in what was tried
Choice = tuple[int, "BoundField", str]


def search_barrier(field: "StateField | BoundField", initial: Pieces, unsafe: Pieces, search: Search,
                   choices: Sequence[Choice] | None = None) -> tuple[dict[str, Any] | None, list[str]]:
    """The first certificate over :data:`BARRIER_DEGREES` and :data:`LAMBDAS`, and what was tried.

    ``choices``: B's degrees and variables in turn (a loop with functions: :func:`relation_choices`, B in the
    states, then with the smooth auxiliaries, rates per second, each rate with a budget of
    :data:`~lyapcheck.tolerances.TEMPLATE_SOLVES` solves); by default B in the states of each degree
    (a polynomial loop, rates in scaled time). The found certificate says its ``degree`` and ``choice``."""
    from lyapcheck import tolerances
    from lyapcheck.models.engines.search import SolvesSpent

    if choices is None:
        view = as_barrier_field(field)
        choices = [(degree, view, f"degree {degree}") for degree in searched_degrees(BARRIER_DEGREES)]
    tried: list[str] = []
    for index, (degree, view, label) in enumerate(choices):
        full = barrier_structure(view, initial, unsafe, degree)
        if isinstance(full, str):
            tried.append(f"{label}: {full}")
            continue
        outcomes: dict[str, int] = {}
        for lam in LAMBDAS:
            # a loop with functions: each rate (its faces together) gets a budget of solves, a count
            solver = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES") \
                if view.relations else search
            try:
                # (the lambdas run within this iteration: degree, view and lam are this iteration's)
                if view.relations:
                    found, solution = on_zero_faces(
                        full, lambda structure: attempt(view, structure, degree, initial, unsafe, lam, solver), solver)
                else:
                    found, solution = on_remainder_faces(
                        full, lambda drop: barrier_structure(view, initial, unsafe, degree, drop),
                        lambda structure: attempt(view, structure, degree, initial, unsafe, lam, solver), solver)
            except SolvesSpent as exc:
                outcomes[str(exc)] = outcomes.get(str(exc), 0) + 1
                continue
            if found is not None:
                found["degree"] = degree
                found["choice"] = index
                tried.append(f"{label}: found at lam = {lam}")
                return found, tried
            why = why_none(solution)
            outcomes[why] = outcomes.get(why, 0) + 1
        time_unit = "per second" if view.relations else "scaled time"
        tried.append(f"{label}: none at lam = {', '.join(str(x) for x in LAMBDAS)} ({time_unit}): "
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
    # the program lives in the robust field's ring, which drops every disturbance with bound 0 or that
    # does not enter (the scaled ring the caller's search was made for keeps them all)
    search = search.over(field.ring)
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
    certificate = certificate_json(scaled, field, found)
    # the figure is B's own degree in the states (what verify re-derives from the stated B): the search's
    # degree is only its bound, and rounding may leave B's top terms 0 (fossil-barr1: degree 3 at degree 4)
    degree = max((sum(e[:scaled.n]) for _, e in certificate["B"]["terms"]), default=0)
    numbers = {"degree": degree, "lambda_per_s": float(found["lam"] / T), "relative_margin": found["margin"]}
    if trial is not None:
        numbers["falsification"] = trial.to_dict()
        numbers["closest_approach"] = trial.closest_approach
        if trial.entered:  # a trajectory into a set proved unreachable: the proof or the simulation is wrong
            numbers["soundness_violation"] = True
    return ConditionResult("barrier", "certified", SUMMARY, numbers=numbers,
                           certificate=certificate, solver={"solves": search.log}, property="safety")


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


# -- loops with functions ---------------------------------------------------------------------------------
#
# The same program on the recasting (:mod:`lyapcheck.models.language.recast`), unscaled: ``B`` is a
# polynomial in the deviations of the states and of the smooth auxiliaries (as a recast Lyapunov
# function, :meth:`~lyapcheck.models.classes.recast_classes.Loop.v_variables`), each identity also
# subtracts its relations' multipliers (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`: a
# free one per equality, a sum of squares per inequality), and a set's inequalities (polynomials in the
# states, shifted to deviations) with their pairwise products are the pieces' S-procedure terms, as on a
# polynomial loop:
#
#     -B >= 0           on the relations and each initial piece        (B <= 0 on the initial set)
#     B - 1 >= 0        on the relations and each unsafe piece         (B >= 1 on the unsafe set)
#     lam B D - grad B . N >= 0   on the relations                     (B' <= lam B everywhere)
#
# with ``x' = N / D`` and ``D > 0`` proved on the relations. Every point ``(x, a(x))`` of the true loop
# lies in the relations' set, so along a trajectory ``b(t) = B(x(t), a(x(t)))`` has ``b' <= lam b``: from
# ``b(0) <= 0``, ``b(t) <= 0 < 1`` for ever, and the unsafe set (``B >= 1`` there) is never entered. The
# angles are ordinary states here (a set may bound an angle itself: no claim modulo 2 pi). The loop is the
# nominal one (every disturbance at 0: its claim says ``(d = 0)``). Each identity's proof is stored by
# relation index (:class:`~lyapcheck.models.engines.recast_sos.ConditionCertificate`; a set's generators
# follow the loop's relations) and re-checked by :func:`check_on_relations`.
#
# Beside the proof, the true loop (each function evaluated by numpy,
# :class:`~lyapcheck.models.engines.recast_numeric.FloatLoop`) is simulated from the initial set
# (:func:`lyapcheck.models.classes.falsify.falsify`): a trajectory that enters the unsafe set is a
# ``counterexample`` (no proof is then searched: none can exist), and one beside a certificate a
# soundness alarm.

#: the certificate kind of a loop with functions' barrier (``verify`` dispatches on it)
KIND: Final = BARRIER_RELATIONS_KIND
#: the kind the relational route wrote before it was merged into this class (issue 41): refused, with
#: the advice to certify again
OLD_KIND: Final = RECAST_BARRIER_KIND
OLD_FORMAT: Final = ("a certificate of an older format (kind recast_barrier, written before barrier had one "
                     "implementation for every loop): run lyapcheck certify again to get one that verify checks")
#: degrees of B tried on a loop with functions, in turn
RECAST_BARRIER_DEGREES: Final = (2, 4)
#: the owner of a set's relation (:attr:`lyapcheck.models.language.recast.Relation.owner`)
SET_OWNER: Final = "set"


def flat_loop(loop: "Loop") -> "Loop":
    """The loop with its angles as ordinary states (their relations with their sine and cosine kept)
    and its proved square-root bounds: a set may bound an angle, so no claim is modulo 2 pi."""
    from lyapcheck.models.classes.recast_classes import base_loop, with_root_bounds

    if not loop.angles:
        return loop
    return with_root_bounds(base_loop(loop.system, cylinder=False, fixed=loop.fixed), dict(loop.root_bounds),
                            loop.root_constants)


def state_relation(loop: "Loop", state_ring: Ring, p: Poly, why: str) -> "Relation":
    """``p >= 0`` for ``p`` a polynomial of the model's state ring, as a relation of the loop's ring in
    the deviations."""
    from lyapcheck.models.language.recast import Relation

    ring = loop.ring
    n = loop.n_states  # (a box's parameters, bounded constants of the loop, follow the states: no set names one)
    terms = {}
    for m, c in state_ring.terms(p).items():
        if any(m[n:]):
            raise ValueError("a set's inequality uses a variable that is not a state")
        terms[tuple(m[:n]) + (0,) * (ring.nvars - n)] = c
    return Relation("ge", loop.system.shift(ring.from_terms(terms)), why, SET_OWNER)


def relation_pieces(loop: "Loop", state_ring: Ring, pieces: Pieces, what: str) -> list[list[Poly]]:
    """A set's pieces, polynomials of the model's state ring, in the loop's ring in the deviations (the
    program's pieces on a loop with functions, as :func:`scaled_pieces` on a polynomial loop)."""
    return [[state_relation(loop, state_ring, p, f"{what} piece {k}").poly for p in piece]
            for k, piece in enumerate(pieces)]


def piece_relations(loop: "Loop", state_ring: Ring, pieces: Pieces, what: str) -> list[list["Relation"]]:
    """Each piece's generators (its inequalities and their pairwise products), polynomials of the
    model's state ring, as relations ``p >= 0`` of the loop's ring in the deviations."""
    return [[state_relation(loop, state_ring, p, f"{what} piece {k}, generator {j}")
             for j, p in enumerate(piece_generators(list(piece)))] for k, piece in enumerate(pieces)]


def _generator_relations(view: "BoundField", piece: Sequence[Poly], what: str) -> list["Relation"]:
    from lyapcheck.models.language.recast import Relation

    return [Relation("ge", p, f"{what}, generator {j}", SET_OWNER) for j, p in enumerate(piece_generators(list(piece)))]


def relations_field(loop: "Loop", names: Sequence[str], N: dict[str, Poly], D: Poly) -> "BoundField":
    """The program's view of a loop with functions for ``B`` over the variables ``names``, which move as
    ``N / D`` (``D > 0`` proved apart): the decrease's weight is ``D`` (``lam B D - grad B . N``), and every
    relation of the recasting gets a multiplier in every identity."""
    from lyapcheck.models.classes.bounds import BoundField

    ring = loop.ring
    index = {name: i for i, name in enumerate(ring.names)}
    v_vars = tuple(index[name] for name in names)
    return BoundField(ring, len(loop.states()), v_vars, tuple(loop.coordinates()),
                      tuple((index[name], N[name]) for name in names), D, (), (), (), (), tuple(loop.relations), (),
                      tuple(range(len(loop.relations))), loop.unused() | loop.roots(), loop.square_free())


def decrease_of(view: "BoundField", B: Poly, lam: Fraction) -> Poly:
    """``lam B D - grad B . N`` (ValueError when ``B`` uses a variable without a flow in the view: its term
    would be missing from B', so nothing may be proved with it)."""
    ring = view.ring
    moving = {i for i, _ in view.flows}
    if any(m[i] for m in ring.support(B) for i in range(ring.nvars) if i not in moving):
        raise ValueError("B uses a variable whose flow is not in the derivative")
    total = B * view.W * to_fmpq(lam)
    for i, gi in view.flows:
        total -= B.derivative(i) * gi
    return total


def conditions(view: "BoundField", B: Poly, lam: Fraction, initial: Pieces, unsafe: Pieces,
               decrease: Poly | None = None) -> list[tuple[str, Poly, list["Relation"]]]:
    """Each identity's name, its ``F >= 0`` and the relations it is proved on (the recasting's, then a
    piece's generators). ``decrease``: the step condition's ``F`` in place of ``B'``'s (a discrete-time
    map's ``lam B - B(F)``, :mod:`lyapcheck.models.classes.map_relations_safety`)."""
    ring = view.ring
    out = [(f"I{k}", -B, list(view.relations) + _generator_relations(view, piece, f"initial piece {k}"))
           for k, piece in enumerate(initial)]
    out += [(f"U{k}", B - ring.constant(1), list(view.relations) + _generator_relations(view, piece,
                                                                                       f"unsafe piece {k}"))
            for k, piece in enumerate(unsafe)]
    out.append(("D", decrease_of(view, B, lam) if decrease is None else decrease, list(view.relations)))
    return out


def relation_proofs(view: "BoundField", structure: Structure, point: Any, initial: Pieces, unsafe: Pieces
                    ) -> dict[str, "ConditionCertificate"]:
    """Each identity's multipliers of a solved program on a loop with functions, by relation index (the
    recasting's relations' by :func:`~lyapcheck.models.classes.bounds.relation_certificates`, then a
    piece's generators' S-procedure multipliers) with its remainder, by identity name (:func:`conditions`)."""
    from lyapcheck.models.classes.bounds import relation_certificates

    pieces = [(f"I{k}", p) for k, p in enumerate(initial)] + [(f"U{k}", p) for k, p in enumerate(unsafe)]
    names = [name for name, _ in pieces] + ["D"]
    proofs = dict(zip(names, relation_certificates(view, structure, point, [(name, f"R{name}") for name in names])))
    add_piece_multipliers(proofs, pieces, view, structure, point)
    return proofs


def add_piece_multipliers(proofs: dict[str, "ConditionCertificate"], pieces: Sequence[tuple[str, Any]],
                          view: "BoundField", structure: Structure, point: Any) -> None:
    """Each set piece's S-procedure multipliers (Grams ``s<identity>_<j>``, one per generator of the
    piece) into its identity's proof, after the recasting's relations (the barrier's and the
    reach-avoid's identities on a loop with functions)."""
    by_name = {g.name: g for g in structure.grams}
    for name, piece in pieces:
        for j in range(len(piece_generators(list(piece)))):
            gram = f"s{name}_{j}"
            if gram in by_name:  # (a multiplier a facial reduction left out is 0)
                proofs[name].taus[len(view.relations) + j] = GramPoly.of(by_name[gram].basis, point.grams[gram])


def check_on_relations(view: "BoundField", B: Poly, lam: Fraction, initial: Pieces, unsafe: Pieces,
                       proofs: dict[str, "ConditionCertificate"], decrease: Poly | None = None
                       ) -> tuple[bool, str]:
    """Exactly, on a loop with functions: each identity of :func:`conditions` on its relations
    (:func:`~lyapcheck.models.engines.recast_sos.check_condition`), with no region multiplier
    (``decrease``: as :func:`conditions`)."""
    from lyapcheck.models.engines.recast_sos import check_condition

    for name, F, relations in conditions(view, B, lam, initial, unsafe, decrease):
        proof = proofs[name]
        if proof.rho is not None:
            return False, f"{name}: a barrier's identity takes no region multiplier"
        ok, why = check_condition(view.ring, F, relations, proof)
        if not ok:
            what = {"I": "B <= 0 on the initial set", "U": "B >= 1 on the unsafe set"}.get(name[0], "B' <= lambda B")
            return False, f"{what}: {why}"
    return True, ("B <= 0 on the initial set, B >= 1 on the unsafe set and B' <= lambda B on the recasting's "
                  "relations, exactly")


@dataclass
class Template:
    """A polynomial's template (a barrier's B, a reach-avoid's V): its degree, its monomials, its
    label in what was tried, and the flows ``N / D`` of its variables with the proofs of ``D > 0``."""

    degree: int
    basis: list[Monomial]
    label: str
    N: dict[str, Poly]
    D: Poly
    dens: list[Any]


def templates(loop: "Loop", degrees: Sequence[int], search: Search, tried: list[str]) -> Iterator[Template]:
    """The templates of each degree, in the states first, then with the smooth auxiliaries, whose
    denominator is proved positive (a template whose denominator is not is said in ``tried``)."""
    from lyapcheck.models.classes.recast_classes import common_denominator, prove_denominators
    from lyapcheck.models.language.recast import written_poly

    ring = loop.ring
    all_vars = loop.v_variables()
    coordinates = loop.coordinates()
    sets_of = [coordinates] if len(all_vars) == len(coordinates) else [coordinates, all_vars]
    for dv in searched_degrees(degrees):
        for v_vars in sets_of:
            basis = [m for m in monomials(ring.nvars, 0, dv) if all(m[i] == 0 for i in range(ring.nvars)
                                                                   if i not in v_vars)]
            names = [ring.names[i] for i in v_vars]
            label = f"degree {dv} in {', '.join(names)}"
            N, D, distinct = common_denominator(loop, names)
            dens, failed = prove_denominators(loop, distinct, search)
            if failed is not None:
                tried.append(f"{label}: the denominator {written_poly(ring, failed)} was not proved positive")
                continue
            yield Template(dv, basis, label, N, D, dens)


def relation_choices(loop: "Loop", search: Search, tried: list[str]
                     ) -> tuple[list[Choice], list[Template]]:
    """B's choices on a loop with functions (:func:`templates` of :data:`RECAST_BARRIER_DEGREES`: B in the
    states, then with the smooth auxiliaries, each whose denominator is proved positive), as
    :func:`search_barrier` takes them, and their templates (the denominators' proofs)."""
    ring = loop.ring
    chosen = list(templates(loop, RECAST_BARRIER_DEGREES, search, tried))
    choices = []
    for t in chosen:
        names = [ring.names[i] for i in range(ring.nvars) if any(m[i] for m in t.basis)]
        choices.append((t.degree, relations_field(loop, names, t.N, t.D), t.label))
    return choices, chosen


def certificate_functions(loop: "Loop", found: dict[str, Any], template: Template) -> dict[str, Any]:
    """The exact certificate on a loop with functions: B in the deviations (``shift``), written with the
    functions too, its rate and degree, and every proof (the recasting's, each set piece's, the decrease's)."""
    ring = loop.ring
    proofs = found["proofs"]
    initial = sorted((k for k in proofs if k.startswith("I")), key=lambda k: int(k[1:]))
    unsafe = sorted((k for k in proofs if k.startswith("U")), key=lambda k: int(k[1:]))
    return {**polynomial_json(loop, KIND, "B", found["B"]), "lambda_per_s": str(found["lam"]),
            **recasting_json(loop, template.D, template.dens),
            "initial": [proofs[k].to_json(ring) for k in initial], "unsafe": [proofs[k].to_json(ring) for k in unsafe],
            "decrease": proofs["D"].to_json(ring)}


def polynomial_json(loop: "Loop", kind: str, letter: str, P: Poly) -> dict[str, Any]:
    """A certificate's head: its kind, the recasting's variables, auxiliaries and shift, and its
    polynomial (``B``, ``V``) in the deviations, written with the functions too, with its degree."""
    from lyapcheck.models.classes.recast_classes import v_text
    from lyapcheck.models.engines.recast_sos import poly_to_json

    system = loop.system
    ring = loop.ring
    return {"kind": kind, "variables": list(ring.names), "auxiliaries": system.definitions(),
            "shift": {k: str(v) for k, v in system.values.items()},
            letter: poly_to_json(ring, P), f"{letter}_text": v_text(system, P), "degree": b_degree(ring, P)}


def recasting_json(loop: "Loop", D: Poly, dens: list[Any]) -> dict[str, Any]:
    """The field's denominator and the recasting's proofs (square roots' bounds, ``D > 0``)."""
    from lyapcheck.models.classes.recast_classes import root_proofs_json
    from lyapcheck.models.engines.recast_sos import poly_to_json

    ring = loop.ring
    return {"denominator": poly_to_json(ring, D),
            "recasting": {"roots": root_proofs_json(loop),
                          "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                                           for d, c, cert in dens]}}


def b_degree(ring: Ring, B: Poly) -> int:
    """B's total degree (the ``degree`` figure)."""
    return max((sum(m) for m in ring.support(B)), default=0)


def true_field(model: "RecastModel") -> Any:
    """The true loop's field as :func:`falsification` simulates it (each function evaluated by numpy, the
    disturbances at 0: the nominal loop), unstopped: ``verify`` replays a counterexample with it
    (:func:`lyapcheck.models.classes.falsify.replay`, which stops a trajectory at the goal itself)."""
    from lyapcheck.models.engines.recast_numeric import TrueField

    return TrueField(model.system)


def falsification(model: "RecastModel", stop: Any = None) -> Any:
    """The closest approach of trajectories of the true loop from the initial set to the unsafe set
    (disturbances at 0), each watched until it reaches ``stop`` when given (before it, the true loop's
    trajectory exactly); None when the simulation cannot run (no inside point of a set found)."""
    from lyapcheck.models.classes.falsify import default_horizon, falsify
    from lyapcheck.models.language.sets import margin

    samples = FALSIFICATION_SAMPLES if model.n <= FALSIFICATION_FEW_ABOVE else FALSIFICATION_SAMPLES // 2
    # the horizon is the true loop's (stopped at a goal around the equilibrium, its Jacobian there is 0)
    horizon = None if stop is None else default_horizon(model, evaluate=true_field(model))  # type: ignore[arg-type]
    try:  # (with stop, falsify holds the field at 0 in the goal: a trajectory is watched until it gets there)
        return falsify(model, model.sets["initial"], model.sets["unsafe"], margin,  # type: ignore[arg-type]
                       samples=samples, disturbed=False, evaluate=true_field(model), horizon=horizon, stop=stop)
    except ValueError:
        return None


def counterexample(model: "RecastModel", trial: Any, name: str, prop: "Property", when: str = "") -> ConditionResult:
    """``counterexample``: a simulated trajectory of the true loop from the initial set enters the
    unsafe set (``when``: words on when, as " before it reaches the goal"), reproducible from its start."""
    entry = trial.entry.describe(list(model.states), [], getattr(model, "units", None) or None)
    return ConditionResult(name, "counterexample",
                           f"a simulated trajectory of the true loop from the initial set enters the unsafe set{when}: "
                           f"{entry} (simulation, reproducible from its start)",
                           numbers={"falsification": trial.to_dict()},
                           refutation={"kind": "trajectory", **trial.entry.to_dict()}, property=prop)


def not_smooth_note(loop: "Loop", function: str, condition: str) -> str | None:
    """Why a low degree often cannot: the ``function`` (B, V) may not use the loop's non-smooth
    functions (sat, abs, ...), yet ``condition`` must hold on the whole state space through their
    relations alone; None when the loop has none."""
    rough = sorted({a.function for a in loop.system.auxiliaries if not a.smooth and a.function})
    if not rough:
        return None
    return (f"{function} may not use {', '.join(rough)} (not smooth): {condition} must then hold on the whole "
            "state space through their relations alone")


def run_functions(model: "RecastModel", loop: "Loop", budget: "Budget", box: "ModelBox | None" = None
                  ) -> ConditionResult:
    """The ``barrier`` class on a loop with functions (the section's comment above). With ``box``, ``loop``
    is the loop with the box's parameters as bounded constants
    (:func:`lyapcheck.models.classes.recast_regions.boxed_loop`, ``model`` read at the box's centre): one B for
    every value of the box."""
    if box is not None and sets_use_box(model, box):
        return ConditionResult("barrier", "not_applicable", SETS_USE_BOX)
    trial, at = box_falsification(model, box) if box is not None else (falsification(model), None)
    if trial is not None and trial.entry is not None:
        return at_point(counterexample(model, trial, "barrier", "safety"), at)
    flat = flat_loop(loop)
    initial = relation_pieces(flat, model.state_ring, model.sets["initial"], "initial")
    unsafe = relation_pieces(flat, model.state_ring, model.sets["unsafe"], "unsafe")
    search = Search(flat.ring, budget)
    tried: list[str] = []
    try:
        choices, chosen = relation_choices(flat, search, tried)
        if choices:
            found, lines = search_barrier(choices[0][1], initial, unsafe, search, choices)
            tried.extend(lines)
        else:
            found = None
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a barrier", budget.seconds, str(exc))
        numbers = late.numbers({"reason": str(exc)})
        if trial is not None:
            numbers["falsification"] = trial.to_dict()
        return ConditionResult("barrier", "inconclusive", late.summary, numbers=numbers, property="safety")
    if found is None:
        rough = not_smooth_note(flat, "B", "B' <= lambda B")
        if rough:
            tried.append(rough)
        none = reasons.not_found("barrier", searched_degrees(RECAST_BARRIER_DEGREES), tried,
                                 ("degree", "sets", "time"))
        numbers = none.numbers({"tried": tried})
        if trial is not None:
            numbers["falsification"] = trial.to_dict()
        return ConditionResult("barrier", "not_certified", none.summary, numbers=numbers,
                               solver={"solves": search.log}, property="safety")
    numbers = {"degree": b_degree(flat.ring, found["B"]), "lambda_per_s": float(found["lam"])}
    if trial is not None:
        numbers["falsification"] = trial.to_dict()
        numbers["closest_approach"] = trial.closest_approach
    return ConditionResult("barrier", "certified", BARRIER_SENTENCE, numbers=numbers,
                           certificate=certificate_functions(flat, found, chosen[found["choice"]]),
                           solver={"solves": search.log}, property="safety")


# -- a loop with functions over a box of parameters --------------------------------------------------------
#
# Over a box the search runs on the loop recast with the box's parameters as bounded constants (each a
# variable without a flow, ``h^2 - dp^2 >= 0`` among the relations): every point ``(x, a(x), p)`` of the
# true loop at a parameter value ``p`` of the box lies in the relations' set, and ``p`` stays put along a
# trajectory, so each identity proved there holds at every value of the box, and one B (or V, which
# uses none of the parameters) serves them all. The sets are read at the model's values: a set that
# names a box parameter is refused.

#: why a safety class over a box refuses sets that name a box parameter (the polynomial loops' words,
#: :func:`lyapcheck.models.surfaces.certify.certify_model`)
SETS_USE_BOX: Final = ("over a box the sets may not depend on a parameter of the box (they are read at the model's "
                       "values)")
#: the most corners of a box simulated after its centre (a box of up to 3 parameters has them all)
BOX_CORNERS: Final = 8


def sets_use_box(model: "RecastModel", box: "ModelBox") -> bool:
    """Some ``[sets]`` inequality names a parameter of ``box`` (the sets are read again from their
    text with the parameters as symbols: :attr:`RecastModel.sets` has them at the model's values)."""
    from lyapcheck.models.language.sets import forms_name, parse_set

    ring = Ring(tuple(model.states) + tuple(model.disturbances) + tuple(model.parameters))
    forms = {key: parse_set(model.source, key, [list(piece) for piece in text], ring, model.states,
                            tuple(model.disturbances))[1] for key, text in model.set_text.items()}
    return forms_name(ring, forms, set(box.names))


#: a point of a box where the true loop is simulated: the loop there, what a claim about it says first,
#: and the box's parameters there (exact decimals)
BoxPoint = tuple["RecastModel", str, dict[str, str]]


def box_points(model: "RecastModel", box: "ModelBox") -> Iterator[BoxPoint]:
    """The true loop at points of the box (:data:`BoxPoint`): its centre (``model``), then up to
    :data:`BOX_CORNERS` corners, each read again from the model text with the box's parameters there
    (a corner that has no finite decimal, or where the model cannot be read, is left out: these
    points only look for a counterexample)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.classes.claims import box_prefix
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    yield model, box_prefix(box, "counterexample"), {name: exact_decimal(box.center(name)) for name in box.names}
    for corner in box.corners()[:BOX_CORNERS]:
        try:
            values = {name: exact_decimal(v) for name, v in corner.items()}
            there = parse_any_model(model.text, model.source, {**model.overrides, **values})
        except (ValueError, ModelFileError):
            continue
        if isinstance(there, RecastModel):
            where = ", ".join(f"{name} = {text}" for name, text in values.items())
            yield there, f"at a corner of the box ({where}), so not for every value of the box: ", values


def box_falsification(model: "RecastModel", box: "ModelBox", goal: bool = False) -> tuple[Any, BoxPoint | None]:
    """:func:`falsification` at the points of :func:`box_points` (``goal``: each trajectory watched until
    it reaches the goal), until one enters the unsafe set: that trial and its point; else the
    centre's trial (None when it cannot run) and None."""
    first = None
    for k, point in enumerate(box_points(model, box)):
        there = point[0]
        trial = falsification(there, stop=there.sets["goal"] if goal else None)
        if trial is not None and trial.entry is not None:
            return trial, point
        if k == 0:
            first = trial
    return first, None


def at_point(result: ConditionResult, point: BoxPoint | None) -> ConditionResult:
    """A counterexample found at a point of a box says which point first, and its refutation gives the
    box's parameters there (``parameters``: it is reproduced at them); ``point`` None: not over a box."""
    if point is not None:
        _, words, values = point
        result.summary = words + result.summary
        if result.refutation is not None:
            result.refutation["parameters"] = dict(values)
    return result


# -- verify on a loop with functions ---------------------------------------------------------------------

def check_polynomial(loop: "Loop", cert: dict[str, Any], letter: str, what: str
                     ) -> tuple[Poly, dict[str, Poly], Poly] | str:
    """A certificate's polynomial (``B``, ``V``; :func:`polynomial_json`) and the field it is proved
    on: its variables allowed, its text and degree as stated, the denominators' proofs re-checked;
    the polynomial, the flows ``N`` and the denominator ``D``, or why not (``what``: its class's words)."""
    from lyapcheck.models.classes.recast_classes import (check_denominator_proofs, common_denominator, v_names,
                                                         v_text)
    from lyapcheck.models.engines.recast_sos import poly_from_json
    from lyapcheck.sos.polynomials import degree_in

    ring = loop.ring
    P = poly_from_json(ring, cert[letter], letter)
    allowed = {ring.names[i] for i in loop.v_variables()}
    if any(degree_in(ring, P, [n]) > 0 for n in ring.names if n not in allowed):
        return f"{letter} uses a variable {what} may not (a root, or a non-smooth function)"
    if cert.get(f"{letter}_text") != v_text(loop.system, P):
        return f"{letter}_text is not {letter} written with the functions"
    if cert.get("degree") != b_degree(ring, P):
        return f"the stated degree is not {letter}'s"
    ok, why, N = check_denominator_proofs(loop, v_names(loop, P), cert["recasting"]["denominators"])
    if not ok:
        return why
    _, D, _ = common_denominator(loop, v_names(loop, P))
    if poly_from_json(ring, cert["denominator"], "denominator") != D:
        return "the stated denominator is not the field's"
    return P, N, D


def check(model: "RecastModel", proved: "Loop", c: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a loop with functions' barrier exactly from the certificate and the model text
    (:func:`check_on_relations`): ``proved`` is the loop with the certificate's square-root bounds already
    re-checked; the sets are the model's. A certificate written before the merge (:data:`OLD_KIND`) is
    refused in one line."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.recast_classes import v_names
    from lyapcheck.models.engines.recast_sos import ConditionCertificate

    cert = c["certificate"]
    if cert.get("kind") == OLD_KIND:
        return False, OLD_FORMAT
    if cert.get("kind") != KIND:
        return False, f"a barrier's certificate kind must be {KIND!r}, not {cert.get('kind')!r}"
    if c.get("property") != "safety":
        return False, "a barrier certificate proves safety"
    if "initial" not in model.sets or "unsafe" not in model.sets:
        return False, "the model has no [sets] initial and unsafe for a barrier"
    loop = flat_loop(proved)
    ring = loop.ring
    head = check_polynomial(loop, cert, "B", "a barrier")
    if isinstance(head, str):
        return False, head
    B, N, D = head
    lam = read_rational(cert["lambda_per_s"])
    view = relations_field(loop, v_names(loop, B), N, D)
    initial = relation_pieces(loop, model.state_ring, model.sets["initial"], "initial")
    unsafe = relation_pieces(loop, model.state_ring, model.sets["unsafe"], "unsafe")
    if len(cert["initial"]) != len(initial) or len(cert["unsafe"]) != len(unsafe):
        return False, "one proof per piece of the initial and of the unsafe set is needed"
    names = [name for name, _, _ in conditions(view, B, lam, initial, unsafe)]
    stored = list(cert["initial"]) + list(cert["unsafe"]) + [cert["decrease"]]
    sizes = [len(relations) for _, _, relations in conditions(view, B, lam, initial, unsafe)]
    proofs = {name: ConditionCertificate.from_json(ring, data, size) for name, data, size in zip(names, stored, sizes)}
    return check_on_relations(view, B, lam, initial, unsafe, proofs)


#: what a certified barrier states (lyapcheck.models.classes.claims, which verify regenerates it from)
SUMMARY: Final = BARRIER_SENTENCE

__all__ = ["BARRIER_DEGREES", "LAMBDAS", "SUMMARY", "barrier_structure", "search_barrier", "attempt", "run",
           "scaled_pieces", "certificate_json", "as_barrier_field", "KIND", "OLD_KIND", "OLD_FORMAT",
           "RECAST_BARRIER_DEGREES", "run_functions", "check", "check_on_relations", "relations_field",
           "relation_pieces", "relation_proofs", "add_piece_multipliers", "conditions", "certificate_functions", "falsification", "flat_loop",
           "piece_relations", "state_relation", "not_smooth_note", "Template", "templates", "polynomial_json",
           "recasting_json", "check_polynomial", "counterexample", "SETS_USE_BOX", "BOX_CORNERS", "sets_use_box",
           "box_points", "box_falsification", "at_point", "BoxPoint", "true_field"]

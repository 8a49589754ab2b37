"""``barrier`` on a polynomial discrete-time map: no iterate of a start in the initial set is ever in the
unsafe set, found by SOS and checked exactly; or an iterate that is, proved in rationals and balls.

The map is the model's, shifted to its fixed point (``e+ = F(e)``, ``F(0) = 0``,
:func:`~lyapcheck.models.loop.discrete.shifted_map`); the ``[sets]`` are written in the user's states,
so each set polynomial ``p(x)`` is moved to ``p(x_eq + e)`` (:func:`map_sets`), exactly. Everything below
is in the shifted states ``e`` (no scaling: a map's iterates are compared with the sets directly).

The certificate (kind :data:`KIND`), with ``B`` a free polynomial of the states of degree ``d``:

    -B - sum_i s_i h_i = r_I                         each initial piece   (B <= 0 there)
    B - 1 - sum_j t_j h_j = r_U                      each unsafe piece    (B >= 1 there)
    lam B - B(F) = r_S                               everywhere           (the step condition)

with every ``s``, ``t``, ``r`` a sum of squares (exact positive semidefinite Gram matrices), ``h`` each
inequality of the piece and each product of two
(:func:`~lyapcheck.sos.certificates.piece_generators`) and ``lam >= 0`` a fixed rational.

Why it proves safety, for every step: the step condition gives ``B(F(e)) <= lam B(e)`` for every ``e``;
where ``B(e) <= 0`` and ``lam >= 0`` the right side is ``<= 0``, so ``{B <= 0}`` is forward invariant
(any ``lam >= 0`` is sound; ``lam <= 1`` is the usual choice, the search also tries 2). A start in
the initial set has ``B <= 0``, hence so does every iterate ``e_k``, ``k = 0, 1, 2, ...``, while
``B >= 1`` on the unsafe set: no iterate is ever in it. The step condition is asked of the whole state
space (a constant multiplier): a map whose iterates grow faster than ``B`` does at infinity needs a
``B`` that is negative far out, which a degree-4 ``B`` may be.

The search: ``B`` of degree 2, then 4 (:data:`BARRIER_DEGREES`), each at the rates :data:`LAMBDAS`,
the first certificate that passes :func:`check_discrete_barrier` is the answer (cvxpy/Clarabel, rounded to
rationals by :mod:`lyapcheck.sos.rounding`, the remainders' facial reduction of the continuous class).

Before it, the falsification (:func:`falsify_map`): the map iterated in floating point from starts
sampled in the initial set; an iterate that enters the unsafe set is re-derived exactly
(:func:`check_iterate`): its start rounded to a short rational and checked to be in the initial set in
rationals, its iterates computed in ball arithmetic (python-flint ``arb``, :data:`ITERATE_BITS` bits,
every rounding enclosed), and every inequality of an unsafe piece proved ``>= 0`` on the ball. That is a
proof that the property fails: the class is ``refuted`` with the start and the step (kind
:data:`REFUTATION_KIND`), which ``verify`` re-derives from the model text.

``reach_avoid`` (:func:`run_reach_avoid`): a ``V`` that falls by ``eps`` at every step outside the goal and is
bounded below, with the same sets' identities and the same falsification (an unsafe iterate before any in
the goal); its figure ``reach_steps_bound`` is a number of steps (the section "reach_avoid" below).

Over a box of parameters (``certify --box``) the ring holds the states, then the box's parameters normalized to
``u in [-1, 1]`` (:func:`~lyapcheck.models.classes.discrete_lyapunov.map_polynomials`; the fixed point checked
not to move). ``B`` (``V``) stays a polynomial of the states alone, one for every value of the box, and the step
identity (each goal identity) subtracts the S-procedure terms ``sum_j r_j(e, u) (1 - u_j^2)``, every ``r_j`` a
sum of squares (``box_multipliers``): on the box each term is ``>= 0``, so ``B(F(e, u)) <= lam B(e)``
(``V(F(e, u)) <= V(e) - eps`` outside the goal) for every state and every value, and the arguments above hold
along the iterates at any value of the box (even one that changes from step to step). The sets' identities
are the point's (the sets may not name a parameter of the box: certify says so). The falsification runs at
the box's corners and centre (:mod:`lyapcheck.models.classes.discrete_safety_box`, which the classes' entries
run first and whose ``verify`` re-checks a refutation over a box; this module never imports it).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.models.classes.claims import (DISCRETE_BARRIER_KIND, DISCRETE_BARRIER_SENTENCE, DISCRETE_REACH_KIND,
                                             discrete_reach_sentence)
from lyapcheck.models.classes.discrete_lyapunov import NotAMap, compose, map_polynomials
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, box_multipliers, \
    box_multipliers_from_json, box_support, exact_grams, multiplier_grams, multiplier_variable, one, param, why_none
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import BoxMultipliers, GramPoly, PieceCertificate, box_terms, check_on_sets, \
    piece_generators
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term, full_blocks

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.loop.field import ShiftedField

#: the certificate kind (claims words it; verify dispatches on it)
KIND: Final = DISCRETE_BARRIER_KIND
#: the refutation kind: a start in the initial set with an iterate in the unsafe set
REFUTATION_KIND: Final = "discrete_iterate"
#: degrees of B tried, in turn
BARRIER_DEGREES: Final = (2, 4)
#: rates lam of B(F(e)) <= lam B(e) tried at each degree (any lam >= 0 is sound: module docstring)
LAMBDAS: Final = (Fraction(1), Fraction(1, 2), Fraction(0), Fraction(2))
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120
#: the falsification: starts sampled in the initial set, and iterations of the map from each
FALSIFY_STARTS: Final = 400
FALSIFY_STEPS: Final = 200
#: significant digits of a counterexample's start (rounded to a short rational before its exact check)
START_DIGITS: Final = 10
#: working precision (bits) of the ball arithmetic that re-derives a counterexample's iterates
ITERATE_BITS: Final = 256
#: the most steps a stated counterexample may have (verify refuses more: a bound on its work)
MAX_STEPS: Final = 10_000

Pieces = Sequence[Sequence[Poly]]


# -- the sets in the shifted states -------------------------------------------------------------------------

def map_sets(model: "Model", ring: Ring) -> dict[str, list[list[Poly]]]:
    """Each of the model's ``[sets]`` (polynomials of the declared states, :attr:`Model.state_ring`) moved
    to the map's shifted states: ``p(x_eq + e)``, in ``ring`` (the states alone), exactly."""
    from lyapcheck.sos.polynomials import to_fmpq

    full = model.state_ring
    gens = full.gens()
    images = [g + to_fmpq(e) for g, e in zip(gens[:model.n], model.equilibrium)] + list(gens[model.n:])
    # over a box the ring ends with the box's normalized parameters, which no set names (certify refuses sets
    # naming one): the sets are moved in the ring of the variables they share, then embedded
    shared = Ring(tuple(name for name in ring.names if name in full.names))
    return {key: [[embed(shared, full.restrict(full.compose(p, images), shared), ring) for p in piece]
                  for piece in pieces]
            for key, pieces in model.sets.items()}


def embed(src: Ring, p: Poly, dst: Ring) -> Poly:
    """``p`` of ``src`` in ``dst``, a ring holding every variable of ``src`` by name (at exponent 0 the others)."""
    if src.names == dst.names:
        return p
    index = [dst.names.index(name) for name in src.names]
    terms = {}
    for m, c in src.terms(p).items():
        out = [0] * dst.nvars
        for i, k in zip(index, m):
            out[i] = k
        terms[tuple(out)] = c
    return dst.from_terms(terms)


def state_basis(ring: Ring, n: int, degree: int) -> list[Monomial]:
    """The monomials of degree 0..``degree`` of the ``n`` states (the ring's first variables), embedded in the
    ring: a barrier's B (a reach-avoid V) is of the states alone, one for every value of a box."""
    pad = tuple([0] * (ring.nvars - n))
    return [tuple(m) + pad for m in monomials(n, 0, degree)]


# -- the certificate and its exact check ---------------------------------------------------------------------

@dataclass(frozen=True)
class DiscreteBarrier:
    """A certificate of kind :data:`KIND` (module docstring), exact."""

    B: Poly
    lam: Fraction
    initial: tuple[PieceCertificate, ...]
    unsafe: tuple[PieceCertificate, ...]
    step: GramPoly
    #: over a box: the step identity's multipliers ``(j, r_j)`` of ``1 - u_j^2`` (none at a point)
    box: BoxMultipliers = ()

    def to_json(self, ring: Ring) -> dict[str, Any]:
        from lyapcheck.models.classes.lyapunov import terms_json

        out = {"kind": KIND, "time": "discrete", "coordinates": "shifted", "degree": poly_degree(ring, self.B),
               "lambda": str(self.lam), "B": terms_json(ring, self.B),
               "initial": [piece_json(c) for c in self.initial], "unsafe": [piece_json(c) for c in self.unsafe],
               "gram_step": self.step.to_json()}
        if self.box:
            out["box_multipliers"] = multipliers_json(self.box)
        return out

    @classmethod
    def from_json(cls, ring: Ring, cert: Mapping[str, Any]) -> "DiscreteBarrier":
        from lyapcheck.exact import read_rational
        from lyapcheck.models.engines.recast_sos import poly_from_json

        n = ring.nvars

        return cls(poly_from_json(ring, cert["B"], "B"), read_rational(cert["lambda"], "lambda"),
                   tuple(piece_of(c, n) for c in cert["initial"]), tuple(piece_of(c, n) for c in cert["unsafe"]),
                   GramPoly.from_json(cert["gram_step"], n),
                   tuple(box_multipliers_from_json(cert.get("box_multipliers", []), n)))


def multipliers_json(box: BoxMultipliers) -> list[dict[str, Any]]:
    """A box's multipliers ``(j, r_j)`` as a certificate writes them (``variable``: the ring's index)."""
    return [{"variable": j, "gram": r.to_json()} for j, r in box]


def check_box_form(ring: Ring, n: int, p: Poly, name: str, box: BoxMultipliers) -> tuple[Poly | None, str]:
    """What a box asks of a map's safety certificate: ``p`` (B or V) of the ``n`` states alone (one for every
    value of the box) and each multiplier PSD on a box variable (the ring's variables after the states): the
    term ``sum_j r_j (1 - u_j^2)``, or None and why not."""
    if any(any(m[n:]) for m in ring.support(p)):
        return None, f"{name} must be a polynomial of the states alone (one {name} for every value of the box)"
    if any(not n <= j < ring.nvars for j, _ in box):
        return None, "a box multiplier names a variable that is not one of the box's parameters"
    boxed, why = box_terms(ring, box)
    if why is not None:
        return None, why
    return boxed, ""


def piece_json(cert: PieceCertificate) -> dict[str, Any]:
    """One set piece's certificate (its multipliers and remainder) as a certificate writes it."""
    multipliers, remainder = cert
    return {"multipliers": [s.to_json() for s in multipliers], "remainder": remainder.to_json()}


def piece_of(data: Mapping[str, Any], n: int) -> PieceCertificate:
    """A set piece's certificate read back (:func:`piece_json`), Gram matrices over ``n`` variables."""
    return ([GramPoly.from_json(s, n) for s in data["multipliers"]], GramPoly.from_json(data["remainder"], n))


def poly_degree(ring: Ring, p: Poly) -> int:
    return max([sum(m) for m in ring.support(p)] + [0])


def check_discrete_barrier(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, cert: DiscreteBarrier
                           ) -> tuple[bool, str]:
    """The three identities of the module docstring, exactly, with ``lam >= 0`` and every Gram matrix
    positive semidefinite: then no iterate of a start in ``initial`` is ever in ``unsafe``. Reads the
    certificate, the map and the sets alone."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    if cert.lam < 0:
        return False, "the rate lambda must be >= 0 (for {B <= 0} to be invariant)"
    boxed, box_why = check_box_form(ring, len(F), cert.B, "B", cert.box)
    if boxed is None:
        return False, box_why
    ok, why = check_on_sets(ring, cert.B, "B", [tuple(p) for p in initial], cert.initial,
                            [tuple(p) for p in unsafe], cert.unsafe)
    if not ok:
        return False, why
    if not is_positive_semidefinite(cert.step.Q):
        return False, "the step remainder is not positive semidefinite (exact)"
    if cert.B * ring.constant(cert.lam) - compose(ring, cert.B, F) - boxed != cert.step.poly(ring):
        return False, "the step identity lambda B - B(F) = r does not hold exactly" + (
            " (with the box's multipliers)" if cert.box else "")
    if ring.nvars > len(F):  # over a box: each r_j (1 - u_j^2) >= 0 there, so B(F(e, u)) <= lambda B(e) on it
        return True, (f"{why}, and lambda B - B(F) - sum_j r_j (1 - u_j^2) = r with r and every r_j sums of squares "
                      f"and lambda = {cert.lam} >= 0, exactly: B(F(e, u)) <= lambda B(e) for every state and every "
                      "value of the box, so {B <= 0} holds at every step (discrete-time map)")
    return True, (f"{why}, and lambda B - B(F) = r with r a sum of squares and lambda = {cert.lam} >= 0, exactly: "
                  "B(F(e)) <= lambda B(e) for every state, so {B <= 0} holds at every step (discrete-time map)")


# -- the program -------------------------------------------------------------------------------------------

def _step_support(ring: Ring, F: Sequence[Poly], m: Monomial) -> list[Monomial]:
    """The support of ``lam e^m - (e^m)(F)`` for every rate (``e^m`` and its image's monomials)."""
    return sorted(set(ring.support(compose(ring, ring.monomial(m), F))) | {m})


def _on_sets_program(ring: Ring, F: Sequence[Poly], degree: int, initial: Pieces, unsafe: Pieces,
                     drop: frozenset[tuple[str, Monomial]]
                     ) -> tuple[list[Monomial], list[Scalar], list[Gram], list[Identity]] | str:
    """What a map's barrier and reach_avoid programs share: a free polynomial of the states of this degree
    (:func:`state_basis`, its coefficients the scalars ``b0, b1, ...``) with the sets' identities of the
    continuous barrier (:func:`lyapcheck.models.classes.barrier.set_identities`, on the map's ring without
    disturbances or relations): the basis, the scalars, the Gram matrices so far and those identities, or why
    there are none."""
    from lyapcheck.models.classes.barrier import set_identities
    from lyapcheck.models.loop.field import StateField

    basis = state_basis(ring, len(F), degree)
    field = StateField(ring=ring, g=tuple(F), D=ring.constant(1))
    scalars = [Scalar(f"b{k}") for k in range(len(basis))]
    grams: list[Gram] = []
    on_sets = set_identities(field, basis, degree, initial, unsafe, grams, drop, scalars)
    if isinstance(on_sets, str):
        return on_sets
    return basis, scalars, grams, list(on_sets)


def _step_values(ring: Ring, F: Sequence[Poly], degree: int, initial: Pieces, unsafe: Pieces, prefix: str,
                 lam: Fraction) -> ParameterValues:
    """What a map's barrier and reach_avoid parameters share: the sets' inequalities (the continuous class's) and
    each monomial's step coefficient ``lam e^m - (e^m)(F)`` as ``<prefix><i>`` (barrier: ``sB`` at its rate;
    reach_avoid: ``sV`` at 1)."""
    from lyapcheck.models.classes.barrier import set_values
    from lyapcheck.models.loop.field import StateField
    from lyapcheck.sos.polynomials import to_fmpq

    values = ParameterValues()
    set_values(StateField(ring=ring, g=tuple(F), D=ring.constant(1)), values, initial, unsafe)
    for i, m in enumerate(state_basis(ring, len(F), degree)):
        zm = ring.monomial(m)
        values.set_poly(ring, f"{prefix}{i}", zm * to_fmpq(lam) - compose(ring, zm, F), _step_support(ring, F, m))
    return values


def _affordable_program(n: int, grams: Sequence[Gram], scalars: Sequence[Scalar], identities: Sequence[Identity]
                        ) -> Structure | str:
    """The program (margin maximised), or the size limit it exceeds (BLOCK_COST_LIMIT, named)."""
    from lyapcheck.models.classes.lyapunov import within_cost

    structure = Structure(nvars=n, grams=tuple(grams), scalars=tuple(scalars), identities=tuple(identities),
                          objective=("max_margin",))
    return within_cost(structure)


def barrier_structure(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, degree: int,
                      drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``B`` of this degree, or why there is none (a size limit, named). The sets'
    identities are the continuous barrier's (:func:`lyapcheck.models.classes.barrier.set_identities`, on
    the map's ring without disturbances or relations); the step identity is this module's."""
    from lyapcheck.models.classes.barrier import remainder_basis

    nv = ring.nvars
    zero = tuple([0] * nv)
    sets = _on_sets_program(ring, F, degree, initial, unsafe, drop)
    if isinstance(sets, str):
        return sets
    b_basis, scalars, grams, on_sets = sets
    terms = []
    target: set[Monomial] = set()
    for i, m in enumerate(b_basis):
        support = _step_support(ring, F, m)
        terms.append(Term(param(f"sB{i}", support), f"b{i}"))
        target |= set(support)
    # over a box: - sum_j r_j(e, u) (1 - u_j^2), the remainder's basis widened by what they add
    box_grams, box_terms_ = _box_multipliers(ring, len(F), target | {zero}, "RuS", drop)
    grams.extend(box_grams)
    terms.extend(box_terms_)
    target |= box_support(box_grams, nv)
    step_basis = remainder_basis(nv, target, "RS", drop, max_rows=MAX_GRAM_ROWS)
    if isinstance(step_basis, str):
        return step_basis
    grams.append(Gram("RS", tuple(step_basis), full_blocks(step_basis)))
    terms.append(Term(one(ring, -1), "RS"))
    return _affordable_program(nv, grams, scalars, [*on_sets, Identity("step", tuple(terms), None, "RS")])


def _box_multipliers(ring: Ring, n: int, target: set[Monomial], prefix: str,
                     drop: frozenset[tuple[str, Monomial]]) -> tuple[list[Gram], list[Term]]:
    """Over a box (the ring's variables after the ``n`` states), the S-procedure terms ``-r_j (1 - u_j^2)`` of
    one identity whose other terms span ``target`` (:func:`~lyapcheck.models.engines.search.box_multipliers`,
    named ``<prefix><j>``, ``R...`` so that facial reduction drops the rows a multiplier must leave at 0, as its
    constant term where the identity's other terms vanish at the origin for every ``u``), less the monomials
    facial reduction dropped; none at a point."""
    from dataclasses import replace

    if ring.nvars == n:
        return [], []
    grams, terms = box_multipliers(ring.nvars, n, target, with_states=False, prefix=prefix)
    kept = []
    for g in grams:
        basis = tuple(m for m in g.basis if (g.name, m) not in drop)
        if basis:
            kept.append(replace(g, basis=basis, blocks=full_blocks(basis)))
    names = {g.name for g in kept}
    return kept, [t for t in terms if t.decision in names]


def barrier_values(ring: Ring, F: Sequence[Poly], degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction
                   ) -> ParameterValues:
    """The program's parameters: the sets' inequalities (the continuous class's) and each of B's
    monomials' step coefficient ``lam e^m - (e^m)(F)`` (:func:`_step_values`)."""
    return _step_values(ring, F, degree, initial, unsafe, "sB", lam)


def attempt(ring: Ring, F: Sequence[Poly], structure: Structure, degree: int, initial: Pieces, unsafe: Pieces,
            lam: Fraction, search: Search) -> tuple[DiscreteBarrier | None, Any]:
    """One solve at rate ``lam``: the exact certificate when it passes :func:`check_discrete_barrier`."""
    from lyapcheck.models.classes.barrier import set_certificates

    values = barrier_values(ring, F, degree, initial, unsafe, lam)
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    B = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(state_basis(ring, len(F), degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    box = tuple((multiplier_variable(g.name), grams[g.name]) for g in multiplier_grams(structure, "RuS"))
    cert = DiscreteBarrier(B, lam, tuple(initial_certs), tuple(unsafe_certs), grams["RS"], box)
    if not check_discrete_barrier(ring, F, initial, unsafe, cert)[0]:
        return None, solution
    return cert, solution


def search_barrier(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, search: Search
                   ) -> tuple[DiscreteBarrier | None, list[str]]:
    """The first certificate over :data:`BARRIER_DEGREES` and :data:`LAMBDAS`, and what was tried."""
    from lyapcheck.degrees import searched_degrees
    from lyapcheck.models.classes.lyapunov import on_remainder_faces

    tried: list[str] = []
    for degree in searched_degrees(BARRIER_DEGREES):
        full = barrier_structure(ring, F, initial, unsafe, degree)
        if isinstance(full, str):
            tried.append(f"degree {degree}: {full}")
            continue
        outcomes: dict[str, int] = {}
        for lam in LAMBDAS:
            # (the lambdas run within this iteration: degree and lam are this iteration's)
            found, solution = on_remainder_faces(
                full, lambda drop: barrier_structure(ring, F, initial, unsafe, degree, drop),
                lambda structure: attempt(ring, F, structure, degree, initial, unsafe, lam, search), search)
            if found is not None:
                tried.append(f"degree {degree}: found at lambda = {lam}")
                return found, tried
            why = why_none(solution)
            outcomes[why] = outcomes.get(why, 0) + 1
        tried.append(f"degree {degree}: none at lambda = {', '.join(str(x) for x in LAMBDAS)}: "
                     + ", ".join(f"{why} ({count})" for why, count in outcomes.items()))
    return None, tried


# -- the falsification and its exact re-derivation -------------------------------------------------------------

def in_piece_exact(ring: Ring, piece: Sequence[Poly], point: Sequence[Fraction]) -> bool:
    values = dict(zip(ring.names, point))
    return all(ring.terms(ring.substitute(p, values)).get(tuple([0] * ring.nvars), Fraction(0)) >= 0 for p in piece)


def ball_value(ring: Ring, p: Poly, x: Sequence[Any]) -> Any:
    """``p`` at a vector of balls (flint ``arb``), every coefficient exact as an ``fmpq`` ball."""
    import flint

    total = flint.arb(0)
    for m, c in ring.terms(p).items():
        term = flint.arb(flint.fmpq(c.numerator, c.denominator))
        for xi, k in zip(x, m):
            if k:
                term *= xi ** k
        total += term
    return total


def _outside(ring: Ring, goal: Sequence[Poly], x: Sequence[Any]) -> bool:
    """Some inequality of the goal (one piece) is ``< 0`` on the whole ball ``x`` (proved)."""
    return any(ball_value(ring, q, x) < 0 for q in goal)  # (arb: True only when certain)


def check_iterate(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, start: Sequence[Fraction],
                  steps: int, goal: Sequence[Poly] | None = None) -> tuple[bool, str]:
    """Whether the start ``e_0`` (shifted states, exact) lies in the initial set (rationals) and its
    iterate ``e_steps`` in the unsafe set (ball arithmetic at :data:`ITERATE_BITS` bits: every inequality
    of one unsafe piece ``>= 0`` on the whole ball that encloses the iterate): a proof that the property
    fails. With ``goal`` (reach_avoid's one piece), every iterate before, ``e_0 .. e_(steps - 1)``, must
    also be proved outside the goal (some goal inequality ``< 0`` on its ball)."""
    import flint

    if not 1 <= steps <= MAX_STEPS:
        return False, f"the step count must be in [1, {MAX_STEPS}], not {steps}"
    if not any(in_piece_exact(ring, piece, start) for piece in initial):
        return False, "the start is not in the initial set (exact)"
    saved = flint.ctx.prec
    flint.ctx.prec = ITERATE_BITS
    try:
        x = [flint.arb(flint.fmpq(v.numerator, v.denominator)) for v in start]
        for k in range(steps):
            if goal is not None and not _outside(ring, goal, x):
                return False, f"iterate {k} of the start is not proved to lie outside the goal (ball arithmetic)"
            x = [ball_value(ring, fi, x) for fi in F]
        for k, piece in enumerate(unsafe):
            if all(ball_value(ring, p, x) >= 0 for p in piece):  # (arb: True only when certain)
                return True, (f"the start is in the initial set (exact) and its iterate {steps} lies in piece {k + 1} "
                              f"of the unsafe set (ball arithmetic, {ITERATE_BITS} bits)")
    finally:
        flint.ctx.prec = saved
    return False, f"iterate {steps} of the start is not proved to lie in the unsafe set (ball arithmetic)"


@dataclass(frozen=True)
class Counterexample:
    """A start (shifted states, exact) whose iterate ``steps`` is in the unsafe set, proved."""

    start: tuple[Fraction, ...]
    steps: int

    def to_json(self, model: "Model | RecastModel") -> dict[str, Any]:
        from lyapcheck.exact import exact_decimal

        def written(v: Fraction) -> str:  # a finite decimal where one exists (the start is rounded to digits)
            try:
                return exact_decimal(v)
            except ValueError:
                return str(v)

        x0 = {name: written(e + xe) for name, e, xe in zip(model.states, self.start, model.equilibrium)}
        return {"kind": REFUTATION_KIND, "time": "discrete", "start": x0, "steps": self.steps}


def falsify_map(model: "Model", ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces,
                goal: Sequence[Poly] | None = None) -> Counterexample | None:
    """Iterate the map (floating point) from starts sampled in the initial set; the first iterate that
    enters the unsafe set is re-derived exactly (:func:`check_iterate`), its start rounded to
    :data:`START_DIGITS` digits. None when no iterate is proved unsafe (or no start could be sampled).
    With ``goal`` (reach_avoid), a start is followed only until an iterate is in the goal."""
    import numpy as np

    from lyapcheck.exact import to_rational
    from lyapcheck.models.classes.falsify import sample_set
    from lyapcheck.models.engines.iteration import BoolArray, FloatArray, IntArray, iterate_map, stacked_map
    from lyapcheck.models.engines.numeric import NumericPoly
    from lyapcheck.models.language.sets import margin

    rng = np.random.default_rng(20261130)
    try:
        starts = sample_set(model, model.sets["initial"], margin, FALSIFY_STARTS, rng)[0]
    except ValueError:
        return None
    eq = np.array([float(v) for v in model.equilibrium])
    maps = [NumericPoly(ring, fi) for fi in F]
    goal_maps = [NumericPoly(ring, q) for q in goal] if goal is not None else []
    found: list[Counterexample] = []

    def stop(x: FloatArray) -> BoolArray:
        """A row that is not finite is done; so is one in the goal (reach_avoid holds for that start)."""
        done = ~np.all(np.isfinite(x), axis=1)
        if goal_maps:
            done |= np.all(np.stack([q(x) >= 0 for q in goal_maps], axis=1), axis=1)
        return done

    def unsafe_hit(step: int, rows: IntArray, x: FloatArray) -> bool:
        """Re-derive exactly each finite iterate found in the unsafe set; True at the first proved one."""
        hit = np.all(np.isfinite(x), axis=1) & (margin(model.sets["unsafe"], x + eq) >= 0)
        for k in rows[hit]:
            start = tuple(to_rational(float(v), START_DIGITS) - xe for v, xe in zip(starts[k], model.equilibrium))
            if check_iterate(ring, F, initial, unsafe, start, step, goal)[0]:
                found.append(Counterexample(start, step))
                return True
        return False

    iterate_map(stacked_map(maps), starts - eq, FALSIFY_STEPS, observe=unsafe_hit, stop=stop)
    return found[0] if found else None


# -- reach_avoid ---------------------------------------------------------------------------------------------
#
# The certificate (kind :data:`REACH_KIND`), with ``V`` a free polynomial of the states, a rational
# ``eps > 0`` and a rational ``C``, the goal one piece ``{q_1 >= 0, ..., q_m >= 0}``:
#
#     -V - sum_i s_i h_i = r_I                   each initial piece     (V <= 0 there)
#     V - 1 - sum_j t_j h_j = r_U                each unsafe piece      (V >= 1 there)
#     V - V(F) - eps + g_k q_k = r_k             each goal inequality   (V(F(e)) <= V(e) - eps where q_k(e) <= 0)
#     V + C = r_B                                everywhere             (V >= -C)
#
# every ``s, t, g, r`` a sum of squares. Why it proves reach-while-avoid, counted in steps: outside the
# goal some ``q_k < 0``, so each step from there lowers ``V`` by ``eps`` at least. A start has ``V(e_0) <= 0``;
# while ``e_0, ..., e_(k-1)`` are all outside the goal, ``V(e_k) <= V(e_0) - k eps <= 0``, so no iterate up to the
# first one in the goal is unsafe (``V >= 1`` there), and ``V >= -C`` gives ``k eps <= C``: some iterate
# ``e_k`` with ``k <= floor(C / eps)`` (the figure ``reach_steps_bound``, a number of steps, not a time) is in
# the goal. As in continuous time, the decrease is asked outside the goal everywhere (not only on
# ``{V <= 0}``: that would be bilinear), and staying in the goal afterwards is not claimed.

#: the certificate kind of a map's reach_avoid
REACH_KIND: Final = DISCRETE_REACH_KIND
#: degrees of V tried, in turn
REACH_DEGREES: Final = (2, 4)
#: why a map's reach_avoid does not take ``[sets] stay_in_goal = true``
STAY_NOT_TAKEN: Final = ("[sets] stay_in_goal = true is not taken on a discrete-time map yet (reach_avoid proves "
                         "reaching the goal there, not staying in it): remove it to decide reach_avoid on the map")


@dataclass(frozen=True)
class DiscreteReach:
    """A certificate of kind :data:`REACH_KIND` (the section's comment), exact."""

    V: Poly
    eps: Fraction
    C: Fraction
    initial: tuple[PieceCertificate, ...]
    unsafe: tuple[PieceCertificate, ...]
    goal: tuple[tuple[GramPoly, GramPoly], ...]
    below: GramPoly
    #: over a box: each goal identity's multipliers ``(j, r_j)`` of ``1 - u_j^2`` (none at a point)
    box: tuple[BoxMultipliers, ...] = ()

    def steps_bound(self) -> int:
        """``floor(C / eps)``: the goal is reached at a step at most this (0 when ``C < 0``: then no start
        has ``V <= 0``, the initial set is empty)."""
        return max(0, (self.C / self.eps).__floor__())

    def to_json(self, ring: Ring) -> dict[str, Any]:
        from lyapcheck.models.classes.lyapunov import terms_json

        return {"kind": REACH_KIND, "time": "discrete", "coordinates": "shifted", "degree": poly_degree(ring, self.V),
                "eps": str(self.eps), "C": str(self.C), "reach_steps_bound": self.steps_bound(),
                "V": terms_json(ring, self.V), "initial": [piece_json(c) for c in self.initial],
                "unsafe": [piece_json(c) for c in self.unsafe],
                "goal": [{"multiplier": g.to_json(), "remainder": r.to_json(),
                          **({"box_multipliers": multipliers_json(self.box[k])} if self.box else {})}
                         for k, (g, r) in enumerate(self.goal)],
                "gram_below": self.below.to_json()}

    @classmethod
    def from_json(cls, ring: Ring, cert: Mapping[str, Any]) -> "DiscreteReach":
        from lyapcheck.exact import read_rational
        from lyapcheck.models.engines.recast_sos import poly_from_json

        n = ring.nvars

        return cls(poly_from_json(ring, cert["V"], "V"), read_rational(cert["eps"], "eps"),
                   read_rational(cert["C"], "C"), tuple(piece_of(c, n) for c in cert["initial"]),
                   tuple(piece_of(c, n) for c in cert["unsafe"]),
                   tuple((GramPoly.from_json(g["multiplier"], n), GramPoly.from_json(g["remainder"], n))
                         for g in cert["goal"]),
                   GramPoly.from_json(cert["gram_below"], n),
                   tuple(tuple(box_multipliers_from_json(g["box_multipliers"], n)) for g in cert["goal"]
                         if "box_multipliers" in g))


def check_discrete_reach(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, goal: Sequence[Poly],
                         cert: DiscreteReach) -> tuple[bool, str]:
    """The identities of the section's comment, exactly, with ``eps > 0`` and every Gram matrix positive
    semidefinite: then every start in ``initial`` has an iterate in the goal at a step at most
    ``floor(C / eps)``, and no iterate before it is in ``unsafe``. Reads the certificate, the map and the
    sets alone."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    if cert.eps <= 0:
        return False, "the decrease per step eps must be > 0"
    ok, why = check_on_sets(ring, cert.V, "V", [tuple(p) for p in initial], cert.initial,
                            [tuple(p) for p in unsafe], cert.unsafe)
    if not ok:
        return False, why
    if len(cert.goal) != len(goal) or len(cert.box) not in (0, len(goal)):
        return False, "one proof per inequality of the goal is needed"
    step = cert.V - compose(ring, cert.V, F) - ring.constant(cert.eps)
    for k, (q, (g, r)) in enumerate(zip(goal, cert.goal)):
        if not is_positive_semidefinite(g.Q) or not is_positive_semidefinite(r.Q):
            return False, f"goal inequality {k + 1}: a Gram matrix is not positive semidefinite (exact)"
        # over a box each r_j (1 - u_j^2) >= 0 on it: V(F(e, u)) <= V(e) - eps outside the goal, every u
        boxed, box_why = check_box_form(ring, len(F), cert.V, "V", cert.box[k] if cert.box else ())
        if boxed is None:
            return False, box_why
        if step + g.poly(ring) * q - boxed != r.poly(ring):
            return False, f"goal inequality {k + 1}: V - V(F) - eps + g q = r does not hold exactly" + (
                " (with the box's multipliers)" if cert.box else "")
    if not is_positive_semidefinite(cert.below.Q) or cert.V + ring.constant(cert.C) != cert.below.poly(ring):
        return False, "V + C = r (V bounded below) does not hold exactly with r a sum of squares"
    every = " for every value of the box" if ring.nvars > len(F) else ""
    return True, (f"{why}, V(F(e)) <= V(e) - eps outside the goal{every} (eps = {cert.eps} > 0) and V >= -C "
                  f"(C = {cert.C}), exactly: the goal is reached within {cert.steps_bound()} steps, no iterate unsafe "
                  "before (discrete-time map)")


def reach_structure(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, goal: Sequence[Poly],
                    degree: int, drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``V`` of this degree (the sets' identities the barrier's; the goal's and the bound
    below this section's), or why there is none (a size limit, named)."""
    from lyapcheck.models.classes.barrier import remainder_basis
    from lyapcheck.models.engines.search import literal

    n = ring.nvars
    zero = tuple([0] * n)
    sets = _on_sets_program(ring, F, degree, initial, unsafe, drop)
    if isinstance(sets, str):
        return sets
    v_basis, scalars, grams, identities = sets
    step_support: set[Monomial] = set()
    for m in v_basis:
        step_support |= set(_step_support(ring, F, m))
    top = max(sum(m) for m in step_support)
    for k, q in enumerate(goal):
        half = max(0, (top - poly_degree(ring, q) + 1) // 2)
        g_basis = state_basis(ring, len(F), half)
        products = {tuple(a + b for a, b in zip(x, y)) for x in g_basis for y in g_basis}
        target = step_support | {zero} | {tuple(a + b for a, b in zip(x, y)) for x in products
                                          for y in ring.support(q)}
        # over a box: - sum_j r_j(e, u) (1 - u_j^2) in this goal identity, the remainder widened by what it adds
        box_grams, box_terms_ = _box_multipliers(ring, len(F), target, f"RuG{k}v", drop)
        target |= box_support(box_grams, n)
        basis = remainder_basis(n, target, f"RG{k}", drop, max_rows=MAX_GRAM_ROWS)
        if isinstance(basis, str):
            return basis
        # (the multiplier is named R... too: the facial reduction of on_remainder_faces then also drops the rows
        # the top degree forces to 0 in it, as where F's growth leaves V's top form no room)
        g_basis = [m for m in g_basis if (f"Rg{k}", m) not in drop]
        if not g_basis:
            return "the goal's multiplier has no row left"
        grams += [Gram(f"Rg{k}", tuple(g_basis), full_blocks(g_basis)), Gram(f"RG{k}", tuple(basis), full_blocks(basis)),
                  *box_grams]
        terms = [Term(param(f"sV{i}", _step_support(ring, F, m)), f"b{i}") for i, m in enumerate(v_basis)]
        terms += [Term(one(ring, -1), "eps"), Term(param(f"q{k}", ring.support(q)), f"Rg{k}"), *box_terms_,
                  Term(one(ring, -1), f"RG{k}")]
        identities.append(Identity(f"G{k}", tuple(terms), None, f"RG{k}"))
    below = [m for m in bases.sos_basis(n, set(v_basis) | {zero}) if ("RB", m) not in drop]
    grams.append(Gram("RB", tuple(below), full_blocks(below)))
    terms = [Term(literal(ring, {m: 1}), f"b{i}") for i, m in enumerate(v_basis)]
    terms += [Term(one(ring), "C"), Term(one(ring, -1), "RB")]
    identities.append(Identity("below", tuple(terms), None, "RB"))
    scalars += [Scalar("eps", lower="margin"), Scalar("C")]
    return _affordable_program(n, grams, scalars, identities)


def goal_box(structure: Structure, grams: Mapping[str, GramPoly], ring: Ring, n: int, goals: int
             ) -> tuple[BoxMultipliers, ...]:
    """Each goal identity's exact box multipliers ``(j, r_j)`` of a solved :func:`reach_structure` (none at a
    point: the ring has only the ``n`` states)."""
    if ring.nvars == n:
        return ()
    return tuple(tuple((multiplier_variable(g.name), grams[g.name]) for g in multiplier_grams(structure, f"RuG{k}v"))
                 for k in range(goals))


def reach_values(ring: Ring, F: Sequence[Poly], degree: int, initial: Pieces, unsafe: Pieces, goal: Sequence[Poly]
                 ) -> ParameterValues:
    """The program's parameters: the sets' inequalities, each of V's monomials' step coefficient
    ``e^m - (e^m)(F)`` (:func:`_step_values` at 1) and each goal inequality."""
    values = _step_values(ring, F, degree, initial, unsafe, "sV", Fraction(1))
    for k, q in enumerate(goal):
        values.set_poly(ring, f"q{k}", q, ring.support(q))
    return values


def attempt_reach(ring: Ring, F: Sequence[Poly], structure: Structure, degree: int, initial: Pieces, unsafe: Pieces,
                  goal: Sequence[Poly], search: Search) -> tuple[DiscreteReach | None, Any]:
    """One solve: the exact certificate when it passes :func:`check_discrete_reach`."""
    from lyapcheck.models.classes.barrier import set_certificates

    values = reach_values(ring, F, degree, initial, unsafe, goal)
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    V = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(state_basis(ring, len(F), degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    cert = DiscreteReach(V, point.scalars["eps"], point.scalars["C"], tuple(initial_certs), tuple(unsafe_certs),
                         tuple((grams[f"Rg{k}"], grams[f"RG{k}"]) for k in range(len(goal))), grams["RB"],
                         goal_box(structure, grams, ring, len(F), len(goal)))
    if not check_discrete_reach(ring, F, initial, unsafe, goal, cert)[0]:
        return None, solution
    return cert, solution


def search_reach(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, goal: Sequence[Poly],
                 search: Search) -> tuple[DiscreteReach | None, list[str]]:
    """The first certificate over :data:`REACH_DEGREES`, its steps bound tightened (:func:`tighten_reach`),
    and what was tried."""
    from lyapcheck.degrees import searched_degrees
    from lyapcheck.models.classes.lyapunov import on_remainder_faces

    tried: list[str] = []
    for degree in searched_degrees(REACH_DEGREES):
        full = reach_structure(ring, F, initial, unsafe, goal, degree)
        if isinstance(full, str):
            tried.append(f"degree {degree}: {full}")
            continue
        solved: list[Structure] = []  # the structure (after facial reduction) whose certificate passed

        def attempt(structure: Structure) -> tuple[DiscreteReach | None, Any]:
            found, solution = attempt_reach(ring, F, structure, degree, initial, unsafe, goal, search)
            if found is not None:
                solved.append(structure)
            return found, solution

        found, solution = on_remainder_faces(
            full, lambda drop: reach_structure(ring, F, initial, unsafe, goal, degree, drop), attempt, search)
        if found is not None:
            tighter = tighten_reach(ring, F, solved[-1], degree, initial, unsafe, goal, found, search)
            tried.append(f"degree {degree}: found" + ("" if tighter is found else
                                                      f", its steps bound {found.steps_bound()} tightened to "
                                                      f"{tighter.steps_bound()}"))
            return tighter, tried
        tried.append(f"degree {degree}: {why_none(solution)}")
    return None, tried


# -- a tighter steps bound ---------------------------------------------------------------------------------------
#
# The search above maximises the programme's margin; ``C`` is free in it, so the solver leaves it wherever its
# interior point lies (``floor(C / eps)`` thousands of steps where the iterates take about fifteen). A second
# solve of the same structure (the same bases, after the same facial reduction) fixes ``eps`` to a rational
# ``E`` (the goal identities' constant) and minimises ``C``, every Gram matrix kept above a floor so that the
# rounded point passes the exact check. Scaling ``(V, C, eps)`` by ``s >= 1`` keeps every identity (``V >= s``
# on the unsafe set is still ``>= 1``), so the smallest ``C / E`` does not grow with ``E``: ``E`` starts at the
# found ``eps`` and is multiplied by REACH_TIGHTEN_GROWTH while the bound falls, at most REACH_TIGHTEN_SOLVES
# solves. Every tighter certificate is decided by :func:`check_discrete_reach`; one that fails it, or the time
# limit, leaves the certificate found so far (the looser one at worst) standing.

def tightened_structure(structure: Structure) -> Structure:
    """``structure`` (a :func:`reach_structure`) with ``eps`` fixed to the parameter ``eps_fixed`` (each goal
    identity's constant, ``-E``), every Gram matrix above the parameter ``floor`` and ``C`` minimised."""
    from dataclasses import replace

    zero = tuple([0] * structure.nvars)
    identities = []
    for ident in structure.identities:
        if any(t.decision == "eps" for t in ident.terms):
            ident = replace(ident, terms=tuple(t for t in ident.terms if t.decision != "eps"),
                            constant=param("eps_fixed", [zero]))
        identities.append(ident)
    return replace(structure, grams=tuple(replace(g, margin="floor") for g in structure.grams),
                   scalars=tuple(sc for sc in structure.scalars if sc.name != "eps"), identities=tuple(identities),
                   objective=("min", "C"))


def attempt_tighter(ring: Ring, F: Sequence[Poly], structure: Structure, degree: int, initial: Pieces,
                    unsafe: Pieces, goal: Sequence[Poly], eps: Fraction, search: Search) -> DiscreteReach | None:
    """One solve of :func:`tightened_structure` at ``eps``: the exact certificate when it passes
    :func:`check_discrete_reach`, else None."""
    from lyapcheck import tolerances as tol
    from lyapcheck.models.classes.barrier import set_certificates

    values = reach_values(ring, F, degree, initial, unsafe, goal)
    values.set_poly(ring, "eps_fixed", ring.constant(-eps), [tuple([0] * ring.nvars)])
    values.set_scalar("floor", tol.REACH_TIGHTEN_FLOOR * float(eps))
    point, _ = search.solve_exact(structure, values)
    if point is None:
        return None
    V = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(state_basis(ring, len(F), degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    cert = DiscreteReach(V, eps, point.scalars["C"], tuple(initial_certs), tuple(unsafe_certs),
                         tuple((grams[f"Rg{k}"], grams[f"RG{k}"]) for k in range(len(goal))), grams["RB"],
                         goal_box(structure, grams, ring, len(F), len(goal)))
    return cert if check_discrete_reach(ring, F, initial, unsafe, goal, cert)[0] else None


def tighten_reach(ring: Ring, F: Sequence[Poly], structure: Structure, degree: int, initial: Pieces,
                  unsafe: Pieces, goal: Sequence[Poly], found: DiscreteReach, search: Search) -> DiscreteReach:
    """The certificate with the smallest steps bound among ``found`` and the tighter solves (the section's
    comment); ``found`` itself when none is smaller."""
    from lyapcheck import tolerances as tol

    tight = tightened_structure(structure)
    best, eps = found, found.eps
    try:
        for _ in range(tol.REACH_TIGHTEN_SOLVES):
            search.budget.check()
            cert = attempt_tighter(ring, F, tight, degree, initial, unsafe, goal, eps, search)
            if cert is None or cert.steps_bound() >= best.steps_bound():
                break
            best, eps = cert, eps * tol.REACH_TIGHTEN_GROWTH
    except BudgetExhausted:
        pass  # the time limit ends the tightening, never the proof: the best certificate so far stands
    return best


# -- the classes ------------------------------------------------------------------------------------------------

def no_sets(name: str, model: "Model | RecastModel") -> ConditionResult | None:
    """``not_applicable`` with the continuous safety classes' sentence when the model lacks the class's sets
    (:data:`~lyapcheck.models.language.sets.CLASS_SETS`); None when it has them."""
    from lyapcheck.models.language.sets import CLASS_SETS

    needed = CLASS_SETS[name]
    if all(model.sets.get(k) for k in needed):
        return None
    return ConditionResult(name, "not_applicable", f"the model's [sets] needs {', '.join(repr(k) for k in needed[:-1])} "
                                                   f"and {needed[-1]!r} (docs/model-files.md, [sets])")


def refuted_result(name: str, model: "Model | RecastModel", found: Counterexample, when: str = "") -> ConditionResult:
    """``refuted`` with the proved counterexample (``when``: reach_avoid's words on the goal)."""
    data = found.to_json(model)
    where = ", ".join(f"{k} = {v}" for k, v in data["start"].items())
    return ConditionResult(name, "refuted",
                           f"refuted: the start ({where}) is in the initial set and its iterate {found.steps} is in the "
                           f"unsafe set{when} (the start checked in rationals, the iterates in ball arithmetic)",
                           numbers={"steps_to_unsafe": found.steps, "time": "discrete"}, refutation=data,
                           property="safety" if name == "barrier" else "reach_avoid")


def run_barrier(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """``barrier`` on the map (module docstring): the falsification first (``refuted`` with an iterate
    proved unsafe), then the search for ``B``; ``certified`` only after :func:`check_discrete_barrier`."""
    ruled = no_sets("barrier", model)
    if ruled is not None:
        return ruled
    try:
        ring, F = map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult("barrier", "not_applicable", f"not a polynomial map: {exc}")
    sets = map_sets(model, ring)
    initial, unsafe = sets["initial"], sets["unsafe"]
    refuted = _falsified("barrier", model, shifted, ring, F, initial, unsafe)
    if refuted is not None:
        return refuted
    search = Search(ring, budget)
    try:
        cert, tried = search_barrier(ring, F, initial, unsafe, search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a barrier of the discrete-time map", budget.seconds, str(exc))
        return ConditionResult("barrier", "inconclusive", late.summary, solver={"solves": search.log},
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}), property="safety")
    if cert is None:
        from lyapcheck.degrees import searched_degrees

        none = reasons.not_found("barrier", searched_degrees(BARRIER_DEGREES), tried, ("degree", "sets", "time"))
        return ConditionResult("barrier", "not_certified", none.summary, solver={"solves": search.log},
                               numbers=none.numbers({"tried": tried, "time": "discrete"}), property="safety")
    return ConditionResult("barrier", "certified", DISCRETE_BARRIER_SENTENCE,
                           numbers={"degree": poly_degree(ring, cert.B), "lambda": float(cert.lam),
                                    "time": "discrete"},
                           certificate=_stated_box(cert.to_json(ring), shifted), solver={"solves": search.log},
                           property="safety")


def _falsified(name: str, model: "Model", shifted: "ShiftedField", ring: Ring, F: Sequence[Poly],
               initial: Pieces, unsafe: Pieces, goal: Sequence[Poly] | None = None) -> ConditionResult | None:
    """``refuted`` with an unsafe iterate proved (:func:`falsify_map`), or None. Over a box, None: the box's
    refutation (at its corners and centre) is :func:`lyapcheck.models.classes.discrete_safety_box.refute`, which
    the class's entry runs first (:mod:`lyapcheck.models.classes.runs_discrete`)."""
    if shifted.box is not None:
        return None
    found_cx = falsify_map(model, ring, F, initial, unsafe, goal)
    if found_cx is None:
        return None
    return refuted_result(name, model, found_cx, "" if goal is None else " before any iterate is in the goal")


def _stated_box(cert: dict[str, Any], shifted: "ShiftedField") -> dict[str, Any]:
    """A certificate over a box states it (``parameter_box``, exact bounds; verify compares the document's)."""
    if shifted.box is not None:
        cert["parameter_box"] = shifted.box.to_json()
    return cert


def run_reach_avoid(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """``reach_avoid`` on the map (the section above): the falsification first (``refuted`` with an iterate
    proved unsafe before any is in the goal), then the search for ``V``; ``certified`` only after
    :func:`check_discrete_reach`, with the steps bound ``floor(C / eps)``."""
    from lyapcheck.models.classes.reach_avoid import goal_of_one_piece

    ruled = no_sets("reach_avoid", model)
    if ruled is not None:
        return ruled
    if model.stay_in_goal:
        return ConditionResult("reach_avoid", "not_applicable", STAY_NOT_TAKEN, property="reach_avoid")
    one_piece = goal_of_one_piece(model.sets["goal"])
    if one_piece is not None:
        return one_piece
    try:
        ring, F = map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult("reach_avoid", "not_applicable", f"not a polynomial map: {exc}")
    sets = map_sets(model, ring)
    initial, unsafe, goal = sets["initial"], sets["unsafe"], sets["goal"][0]
    refuted = _falsified("reach_avoid", model, shifted, ring, F, initial, unsafe, goal)
    if refuted is not None:
        return refuted
    search = Search(ring, budget)
    try:
        cert, tried = search_reach(ring, F, initial, unsafe, goal, search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a reach-avoid certificate of the discrete-time map", budget.seconds, str(exc))
        return ConditionResult("reach_avoid", "inconclusive", late.summary, solver={"solves": search.log},
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}), property="reach_avoid")
    if cert is None:
        from lyapcheck.degrees import searched_degrees

        none = reasons.not_found("reach-avoid certificate", searched_degrees(REACH_DEGREES), tried,
                                 ("degree", "sets", "time"))
        return ConditionResult("reach_avoid", "not_certified", none.summary, solver={"solves": search.log},
                               numbers=none.numbers({"tried": tried, "time": "discrete"}), property="reach_avoid")
    return ConditionResult("reach_avoid", "certified", discrete_reach_sentence(cert.steps_bound()),
                           numbers={"degree": poly_degree(ring, cert.V), "reach_steps_bound": cert.steps_bound(),
                                    "time": "discrete"},
                           certificate=_stated_box(cert.to_json(ring), shifted), solver={"solves": search.log},
                           property="reach_avoid")


# -- verify ---------------------------------------------------------------------------------------------------

def verify(shifted: "ShiftedField", name: str, c: Mapping[str, Any], model: "Model") -> tuple[bool, str]:
    """Re-check a map's ``barrier`` or ``reach_avoid`` from its JSON and the model text alone, without a
    solver: a certified one's identities exactly (:func:`check_discrete_barrier`,
    :func:`check_discrete_reach`; the sets re-read from the model) and its stated figures; a refuted one's
    start and iterate (:func:`check_iterate`)."""
    from lyapcheck.models.language.sets import CLASS_SETS

    prop = {"barrier": "safety", "reach_avoid": "reach_avoid"}.get(name)
    if prop is None:
        return False, f"{name} has no discrete-time safety check"
    if c.get("property") != prop:
        return False, f"a {name} claim is about {prop}, not {c.get('property')}"
    if not all(model.sets.get(k) for k in CLASS_SETS[name]):
        return False, f"the model has no [sets] {', '.join(CLASS_SETS[name])} for {name}"
    if name == "reach_avoid" and (model.stay_in_goal or len(model.sets["goal"]) != 1):
        return False, "a map's reach_avoid takes a goal of one piece and no stay_in_goal"
    try:
        ring, F = map_polynomials(shifted)
        sets = map_sets(model, ring)
        goal = sets["goal"][0] if name == "reach_avoid" else None
        if c.get("status") == "refuted":
            if shifted.box is not None:  # (re-derived at its value of the box: discrete_safety_box.verify)
                return False, "a refutation over a box is re-checked at its value of the box, not here"
            return _verify_refutation(model, ring, F, sets, c, goal)
        cert = c["certificate"]
        kind = KIND if name == "barrier" else REACH_KIND
        if cert.get("kind") != kind or cert.get("time") != "discrete":
            return False, f"not a {name} certificate of a discrete-time map (kind {cert.get('kind')!r})"
        if cert.get("parameter_box") != (shifted.box.to_json() if shifted.box is not None else None):
            return False, "the certificate's parameter_box is not the document's box"
        found: DiscreteBarrier | DiscreteReach
        if goal is None:
            found = barrier = DiscreteBarrier.from_json(ring, cert)
            ok, why = check_discrete_barrier(ring, F, sets["initial"], sets["unsafe"], barrier)
        else:
            found = reach = DiscreteReach.from_json(ring, cert)
            ok, why = check_discrete_reach(ring, F, sets["initial"], sets["unsafe"], goal, reach)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError, NotAMap) as exc:
        return False, f"malformed certificate: {exc}"
    if not ok:
        return False, why
    poly = found.B if isinstance(found, DiscreteBarrier) else found.V
    if cert.get("degree") != poly_degree(ring, poly) or c.get("degree") != cert.get("degree"):
        return False, "the stated degree is not the certificate's polynomial's"
    if isinstance(found, DiscreteBarrier):
        if cert.get("lambda") != str(found.lam) or c.get("lambda") != float(found.lam):
            return False, "the stated lambda is not the certificate's"
    elif cert.get("reach_steps_bound") != found.steps_bound() or c.get("reach_steps_bound") != found.steps_bound():
        return False, "the stated reach_steps_bound is not floor(C / eps)"
    return True, why


def _verify_refutation(model: "Model", ring: Ring, F: Sequence[Poly], sets: Mapping[str, Pieces],
                       c: Mapping[str, Any], goal: Sequence[Poly] | None) -> tuple[bool, str]:
    return verify_refutation(model, c, lambda start, steps: check_iterate(ring, F, sets["initial"], sets["unsafe"],
                                                                        start, steps, goal))


def verify_refutation(model: "Model | RecastModel", c: Mapping[str, Any],
                      check_at: Callable[[list[Fraction], int], tuple[bool, str]]) -> tuple[bool, str]:
    """A refuted claim's start and step count read from its JSON (the start in the user's states, moved to
    the shifted states) and re-derived by ``check_at(start, steps)`` (:func:`check_iterate` on a polynomial
    map; a map with functions' own, :mod:`lyapcheck.models.classes.map_relations_safety`)."""
    from lyapcheck.exact import read_rational

    data = c["refutation"]
    if data.get("kind") != REFUTATION_KIND:
        return False, f"not an iterate refutation of a discrete-time map (kind {data.get('kind')!r})"
    steps = data["steps"]
    if isinstance(steps, bool) or not isinstance(steps, int):
        return False, "the step count must be an integer"
    if set(data["start"]) != set(model.states):
        return False, "the start must give one value per state"
    start = [read_rational(data["start"][s], f"start.{s}") - xe for s, xe in zip(model.states, model.equilibrium)]
    if c.get("steps_to_unsafe") != steps:
        return False, "the stated steps_to_unsafe is not the refutation's"
    return check_at(start, steps)


__all__ = ["KIND", "REFUTATION_KIND", "BARRIER_DEGREES", "LAMBDAS", "DiscreteBarrier", "Counterexample",
           "map_sets", "check_discrete_barrier", "barrier_structure", "barrier_values", "search_barrier",
           "check_iterate", "falsify_map", "no_sets", "in_piece_exact", "ball_value", "refuted_result",
           "verify_refutation", "run_barrier", "run_reach_avoid", "verify", "REACH_KIND", "REACH_DEGREES",
           "DiscreteReach", "check_discrete_reach", "reach_structure", "reach_values", "search_reach",
           "tightened_structure", "tighten_reach", "STAY_NOT_TAKEN"]

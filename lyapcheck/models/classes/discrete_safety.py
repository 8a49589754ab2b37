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

``reach_avoid`` is not decided on a map yet (:func:`run_reach_avoid` says so).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.models.classes.claims import DISCRETE_BARRIER_KIND, DISCRETE_BARRIER_SENTENCE
from lyapcheck.models.classes.discrete_lyapunov import NotAMap, compose, map_polynomials
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, exact_grams, one, \
    param, why_none
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, PieceCertificate, check_on_sets, piece_generators
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term, full_blocks

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
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
    return {key: [[full.restrict(full.compose(p, images), ring) for p in piece] for piece in pieces]
            for key, pieces in model.sets.items()}


# -- the certificate and its exact check ---------------------------------------------------------------------

@dataclass(frozen=True)
class DiscreteBarrier:
    """A certificate of kind :data:`KIND` (module docstring), exact."""

    B: Poly
    lam: Fraction
    initial: tuple[PieceCertificate, ...]
    unsafe: tuple[PieceCertificate, ...]
    step: GramPoly

    def to_json(self, ring: Ring) -> dict[str, Any]:
        from lyapcheck.models.classes.lyapunov import terms_json

        def piece(cert: PieceCertificate) -> dict[str, Any]:
            multipliers, remainder = cert
            return {"multipliers": [s.to_json() for s in multipliers], "remainder": remainder.to_json()}

        return {"kind": KIND, "time": "discrete", "coordinates": "shifted", "degree": poly_degree(ring, self.B),
                "lambda": str(self.lam), "B": terms_json(ring, self.B),
                "initial": [piece(c) for c in self.initial], "unsafe": [piece(c) for c in self.unsafe],
                "gram_step": self.step.to_json()}

    @classmethod
    def from_json(cls, ring: Ring, cert: Mapping[str, Any]) -> "DiscreteBarrier":
        from lyapcheck.exact import read_rational
        from lyapcheck.models.engines.recast_sos import poly_from_json

        n = ring.nvars

        def piece(data: Mapping[str, Any]) -> PieceCertificate:
            return ([GramPoly.from_json(s, n) for s in data["multipliers"]], GramPoly.from_json(data["remainder"], n))

        return cls(poly_from_json(ring, cert["B"], "B"), read_rational(cert["lambda"], "lambda"),
                   tuple(piece(c) for c in cert["initial"]), tuple(piece(c) for c in cert["unsafe"]),
                   GramPoly.from_json(cert["gram_step"], n))


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
    ok, why = check_on_sets(ring, cert.B, "B", [tuple(p) for p in initial], cert.initial,
                            [tuple(p) for p in unsafe], cert.unsafe)
    if not ok:
        return False, why
    if not is_positive_semidefinite(cert.step.Q):
        return False, "the step remainder is not positive semidefinite (exact)"
    if cert.B * ring.constant(cert.lam) - compose(ring, cert.B, F) != cert.step.poly(ring):
        return False, "the step identity lambda B - B(F) = r does not hold exactly"
    return True, (f"{why}, and lambda B - B(F) = r with r a sum of squares and lambda = {cert.lam} >= 0, exactly: "
                  "B(F(e)) <= lambda B(e) for every state, so {B <= 0} holds at every step (discrete-time map)")


# -- the program -------------------------------------------------------------------------------------------

def _step_support(ring: Ring, F: Sequence[Poly], m: Monomial) -> list[Monomial]:
    """The support of ``lam e^m - (e^m)(F)`` for every rate (``e^m`` and its image's monomials)."""
    return sorted(set(ring.support(compose(ring, ring.monomial(m), F))) | {m})


def barrier_structure(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, degree: int,
                      drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``B`` of this degree, or why there is none (a size limit, named). The sets'
    identities are the continuous barrier's (:func:`lyapcheck.models.classes.barrier.set_identities`, on
    the map's ring without disturbances or relations); the step identity is this module's."""
    from lyapcheck.models.classes.barrier import set_identities
    from lyapcheck.models.classes.lyapunov import BLOCK_COST_LIMIT, TARGET_LIMIT, affordable
    from lyapcheck.models.engines.reasons import size_limit
    from lyapcheck.models.loop.field import StateField

    n = ring.nvars
    zero = tuple([0] * n)
    field = StateField(ring=ring, g=tuple(F), D=ring.constant(1))
    b_basis = monomials(n, 0, degree)
    scalars = [Scalar(f"b{k}") for k in range(len(b_basis))]
    grams: list[Gram] = []
    on_sets = set_identities(field, b_basis, degree, initial, unsafe, grams, drop, scalars)
    if isinstance(on_sets, str):
        return on_sets
    terms = []
    target: set[Monomial] = set()
    for i, m in enumerate(b_basis):
        support = _step_support(ring, F, m)
        terms.append(Term(param(f"sB{i}", support), f"b{i}"))
        target |= set(support)
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    step_basis = [m for m in bases.sos_basis(n, target | {zero}) if ("RS", m) not in drop]
    if len(step_basis) > MAX_GRAM_ROWS:
        return size_limit(len(step_basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
    grams.append(Gram("RS", tuple(step_basis), full_blocks(step_basis)))
    terms.append(Term(one(ring, -1), "RS"))
    identities = [*on_sets, Identity("step", tuple(terms), None, "RS")]
    structure = Structure(nvars=n, grams=tuple(grams), scalars=tuple(scalars), identities=tuple(identities),
                          objective=("max_margin",))
    if affordable(structure) is None:
        return size_limit(f"{structure.cost():.1e}", "work units of the program", f"{BLOCK_COST_LIMIT:.1e}",
                          "BLOCK_COST_LIMIT")
    return structure


def barrier_values(ring: Ring, F: Sequence[Poly], degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction
                   ) -> ParameterValues:
    """The program's parameters: the sets' inequalities (the continuous class's) and each of B's
    monomials' step coefficient ``lam e^m - (e^m)(F)``."""
    from lyapcheck.models.classes.barrier import set_values
    from lyapcheck.models.loop.field import StateField
    from lyapcheck.sos.polynomials import to_fmpq

    values = ParameterValues()
    set_values(StateField(ring=ring, g=tuple(F), D=ring.constant(1)), values, initial, unsafe)
    for i, m in enumerate(monomials(ring.nvars, 0, degree)):
        zm = ring.monomial(m)
        values.set_poly(ring, f"sB{i}", zm * to_fmpq(lam) - compose(ring, zm, F), _step_support(ring, F, m))
    return values


def attempt(ring: Ring, F: Sequence[Poly], structure: Structure, degree: int, initial: Pieces, unsafe: Pieces,
            lam: Fraction, search: Search) -> tuple[DiscreteBarrier | None, Any]:
    """One solve at rate ``lam``: the exact certificate when it passes :func:`check_discrete_barrier`."""
    from lyapcheck.models.classes.barrier import set_certificates

    values = barrier_values(ring, F, degree, initial, unsafe, lam)
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    B = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(monomials(ring.nvars, 0, degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    cert = DiscreteBarrier(B, lam, tuple(initial_certs), tuple(unsafe_certs), grams["RS"])
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

def _in_piece_exact(ring: Ring, piece: Sequence[Poly], point: Sequence[Fraction]) -> bool:
    values = dict(zip(ring.names, point))
    return all(ring.terms(ring.substitute(p, values)).get(tuple([0] * ring.nvars), Fraction(0)) >= 0 for p in piece)


def _ball_value(ring: Ring, p: Poly, x: Sequence[Any]) -> Any:
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


def check_iterate(ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces, start: Sequence[Fraction],
                  steps: int) -> tuple[bool, str]:
    """Whether the start ``e_0`` (shifted states, exact) lies in the initial set (rationals) and its
    iterate ``e_steps`` in the unsafe set (ball arithmetic at :data:`ITERATE_BITS` bits: every inequality
    of one unsafe piece ``>= 0`` on the whole ball that encloses the iterate): a proof that the property
    fails."""
    import flint

    if not 1 <= steps <= MAX_STEPS:
        return False, f"the step count must be in [1, {MAX_STEPS}], not {steps}"
    if not any(_in_piece_exact(ring, piece, start) for piece in initial):
        return False, "the start is not in the initial set (exact)"
    saved = flint.ctx.prec
    flint.ctx.prec = ITERATE_BITS
    try:
        x = [flint.arb(flint.fmpq(v.numerator, v.denominator)) for v in start]
        for _ in range(steps):
            x = [_ball_value(ring, fi, x) for fi in F]
        for k, piece in enumerate(unsafe):
            if all(_ball_value(ring, p, x) >= 0 for p in piece):  # (arb: True only when certain)
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

    def to_json(self, model: "Model") -> dict[str, Any]:
        from lyapcheck.exact import exact_decimal

        def written(v: Fraction) -> str:  # a finite decimal where one exists (the start is rounded to digits)
            try:
                return exact_decimal(v)
            except ValueError:
                return str(v)

        x0 = {name: written(e + xe) for name, e, xe in zip(model.states, self.start, model.equilibrium)}
        return {"kind": REFUTATION_KIND, "time": "discrete", "start": x0, "steps": self.steps}


def falsify_map(model: "Model", ring: Ring, F: Sequence[Poly], initial: Pieces, unsafe: Pieces
                ) -> Counterexample | None:
    """Iterate the map (floating point) from starts sampled in the initial set; the first iterate that
    enters the unsafe set is re-derived exactly (:func:`check_iterate`), its start rounded to
    :data:`START_DIGITS` digits. None when no iterate is proved unsafe (or no start could be sampled)."""
    import numpy as np

    from lyapcheck.exact import to_rational
    from lyapcheck.models.classes.falsify import sample_set
    from lyapcheck.models.engines.numeric import NumericPoly
    from lyapcheck.models.language.sets import margin

    rng = np.random.default_rng(20261130)
    try:
        starts = sample_set(model, model.sets["initial"], margin, FALSIFY_STARTS, rng)[0]  # type: ignore[arg-type]
    except ValueError:
        return None
    eq = np.array([float(v) for v in model.equilibrium])
    maps = [NumericPoly(ring, fi) for fi in F]
    x = starts - eq
    alive = np.all(np.isfinite(x), axis=1)
    with np.errstate(all="ignore"):
        for step in range(1, FALSIFY_STEPS + 1):
            x = np.stack([f(x) for f in maps], axis=1)
            alive &= np.all(np.isfinite(x), axis=1)
            hit = alive & (margin(model.sets["unsafe"], x + eq) >= 0)
            for k in np.flatnonzero(hit):
                start = tuple(to_rational(float(v), START_DIGITS) - xe
                              for v, xe in zip(starts[k], model.equilibrium))
                if check_iterate(ring, F, initial, unsafe, start, step)[0]:
                    return Counterexample(start, step)
            if not alive.any():
                break
    return None


# -- the classes ------------------------------------------------------------------------------------------------

def _no_sets(name: str, model: "Model") -> ConditionResult | None:
    """``not_applicable`` with the continuous safety classes' sentence when the model lacks the class's sets
    (:data:`~lyapcheck.models.language.sets.CLASS_SETS`); None when it has them."""
    from lyapcheck.models.language.sets import CLASS_SETS

    needed = CLASS_SETS[name]
    if all(model.sets.get(k) for k in needed):
        return None
    return ConditionResult(name, "not_applicable", f"the model's [sets] needs {', '.join(repr(k) for k in needed[:-1])} "
                                                   f"and {needed[-1]!r} (docs/model-files.md, [sets])")


def run_barrier(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """``barrier`` on the map (module docstring): the falsification first (``refuted`` with an iterate
    proved unsafe), then the search for ``B``; ``certified`` only after :func:`check_discrete_barrier`."""
    ruled = _no_sets("barrier", model)
    if ruled is not None:
        return ruled
    try:
        ring, F = map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult("barrier", "not_applicable", f"not a polynomial map: {exc}")
    sets = map_sets(model, ring)
    initial, unsafe = sets["initial"], sets["unsafe"]
    found_cx = falsify_map(model, ring, F, initial, unsafe)
    if found_cx is not None:
        data = found_cx.to_json(model)
        where = ", ".join(f"{k} = {v}" for k, v in data["start"].items())
        return ConditionResult("barrier", "refuted",
                               f"refuted: the start ({where}) is in the initial set and its iterate {found_cx.steps} "
                               "is in the unsafe set (the start checked in rationals, the iterates in ball arithmetic)",
                               numbers={"steps_to_unsafe": found_cx.steps, "time": "discrete"}, refutation=data,
                               property="safety")
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
                           certificate=cert.to_json(ring), solver={"solves": search.log}, property="safety")


def run_reach_avoid(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """``reach_avoid`` on a map: not decided yet (no discrete-time condition is implemented); the
    registry keeps its ``discrete`` flag False, so a map's run never calls this."""
    from lyapcheck.models.classes.registry import DISCRETE
    from lyapcheck.models.loop.discrete import not_decided

    return ConditionResult("reach_avoid", "not_applicable", not_decided("reach_avoid", DISCRETE))


# -- verify ---------------------------------------------------------------------------------------------------

def verify(shifted: "ShiftedField", name: str, c: Mapping[str, Any], model: "Model") -> tuple[bool, str]:
    """Re-check a map's ``barrier`` from its JSON and the model text alone, without a solver: a certified
    one's identities exactly (:func:`check_discrete_barrier`, the sets re-read from the model), its stated
    figures and property; a refuted one's start and iterate (:func:`check_iterate`)."""
    if name != "barrier":
        return False, f"{name} has no discrete-time check"
    if c.get("property") != "safety":
        return False, f"a barrier proves or refutes safety, not {c.get('property')}"
    if not model.sets.get("initial") or not model.sets.get("unsafe"):
        return False, "the model has no [sets] initial and unsafe for a barrier"
    try:
        ring, F = map_polynomials(shifted)
        sets = map_sets(model, ring)
        if c.get("status") == "refuted":
            return _verify_refutation(model, ring, F, sets, c)
        cert = c["certificate"]
        if cert.get("kind") != KIND or cert.get("time") != "discrete":
            return False, f"not a barrier certificate of a discrete-time map (kind {cert.get('kind')!r})"
        found = DiscreteBarrier.from_json(ring, cert)
        ok, why = check_discrete_barrier(ring, F, sets["initial"], sets["unsafe"], found)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError, NotAMap) as exc:
        return False, f"malformed certificate: {exc}"
    if not ok:
        return False, why
    if cert.get("degree") != poly_degree(ring, found.B) or c.get("degree") != cert.get("degree"):
        return False, "the stated degree is not B's"
    if cert.get("lambda") != str(found.lam) or c.get("lambda") != float(found.lam):
        return False, "the stated lambda is not the certificate's"
    return True, why


def _verify_refutation(model: "Model", ring: Ring, F: Sequence[Poly], sets: Mapping[str, Pieces],
                       c: Mapping[str, Any]) -> tuple[bool, str]:
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
    return check_iterate(ring, F, sets["initial"], sets["unsafe"], start, steps)


__all__ = ["KIND", "REFUTATION_KIND", "BARRIER_DEGREES", "LAMBDAS", "DiscreteBarrier", "Counterexample",
           "map_sets", "check_discrete_barrier", "barrier_structure", "barrier_values", "search_barrier",
           "check_iterate", "falsify_map", "run_barrier", "run_reach_avoid", "verify"]

"""``barrier`` on a loop with functions: no trajectory of the true loop from the initial set enters the unsafe set.

The polynomial barrier (:mod:`lyapcheck.models.classes.barrier`) on the recasting (:mod:`lyapcheck.models.language.recast`):
``B`` is a polynomial in the deviations of the states and of the smooth auxiliaries (as a recast
Lyapunov function, :meth:`~lyapcheck.models.classes.recast_classes.Loop.v_variables`), and each condition
is proved on the set of the recasting's relations (:mod:`lyapcheck.models.engines.recast_sos`), with a
set's inequalities (polynomials in the states, shifted to deviations) and their pairwise products
(:func:`~lyapcheck.sos.certificates.piece_generators`) as further relations ``p >= 0``:

    -B >= 0           on the relations and each initial piece        (B <= 0 on the initial set)
    B - 1 >= 0        on the relations and each unsafe piece         (B >= 1 on the unsafe set)
    lam B D - grad B . N >= 0   on the relations                     (B' <= lam B everywhere)

with ``x' = N / D`` and ``D > 0`` proved on the relations (as the recast sos_gas does). Every point
``(x, a(x))`` of the true loop lies in the relations' set, so along a trajectory ``b(t) =
B(x(t), a(x(t)))`` has ``b' <= lam b``: from ``b(0) <= 0``, ``b(t) <= 0 < 1`` for ever, and the unsafe
set (``B >= 1`` there) is never entered. The angles are ordinary states here (a set may bound an
angle itself: no claim modulo 2 pi). The loop is the nominal one (every disturbance at 0: its claim
says ``(d = 0)``).

Beside the proof, the true loop (each function evaluated by numpy,
:class:`~lyapcheck.models.engines.recast_numeric.FloatLoop`) is simulated from the initial set
(:func:`lyapcheck.models.classes.falsify.falsify`): a trajectory that enters the unsafe set is a
``counterexample`` (no proof is then searched: none can exist), and one beside a certificate a
soundness alarm.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final, Iterator, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.engines import reasons
from lyapcheck.models.classes.barrier import FALSIFICATION_FEW_ABOVE, FALSIFICATION_SAMPLES, LAMBDAS
from lyapcheck.models.classes.claims import BARRIER_SENTENCE, RECAST_BARRIER_KIND
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.language.recast import RecastModel, Relation, written_poly
from lyapcheck.models.classes.recast_classes import (Loop, _set, base_loop, common_denominator, lie, prove_denominators,
                                             root_proofs_json, v_names, v_text, with_root_bounds)
from lyapcheck.models.engines.recast_sos import (ConditionCertificate, ConditionProgram, check_condition, known_values,
                                         poly_from_json, poly_to_json, solve_on_faces)
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, SolvesSpent
from lyapcheck.results import ConditionResult, Property
from lyapcheck.sos.certificates import piece_generators
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, degree_in, monomials, to_fmpq
from lyapcheck.exact import read_rational

#: the certificate's kind (``verify`` dispatches on it)
KIND: Final = RECAST_BARRIER_KIND
#: degrees of B tried, in turn
RECAST_BARRIER_DEGREES: Final = (2, 4)
#: the owner of a set's relation (:attr:`lyapcheck.models.language.recast.Relation.owner`)
SET_OWNER: Final = "set"


def flat_loop(loop: Loop) -> Loop:
    """The loop with its angles as ordinary states (their relations with their sine and cosine kept)
    and its proved square-root bounds: a set may bound an angle, so no claim is modulo 2 pi."""
    if not loop.angles:
        return loop
    return with_root_bounds(base_loop(loop.system, cylinder=False, fixed=loop.fixed), dict(loop.root_bounds),
                            loop.root_constants)


def piece_relations(loop: Loop, state_ring: Ring, pieces: Sequence[Sequence[Poly]], what: str
                    ) -> list[list[Relation]]:
    """Each piece's generators (its inequalities and their pairwise products), polynomials of the
    model's state ring, as relations ``p >= 0`` of the loop's ring in the deviations."""
    return [[state_relation(loop, state_ring, p, f"{what} piece {k}, generator {j}")
             for j, p in enumerate(piece_generators(list(piece)))] for k, piece in enumerate(pieces)]


def state_relation(loop: Loop, state_ring: Ring, p: Poly, why: str) -> Relation:
    """``p >= 0`` for ``p`` a polynomial of the model's state ring, as a relation of the loop's ring in
    the deviations."""
    ring = loop.ring
    n = loop.n_states  # (a box's parameters, bounded constants of the loop, follow the states: no set names one)
    terms = {}
    for m, c in state_ring.terms(p).items():
        if any(m[n:]):
            raise ValueError("a set's inequality uses a variable that is not a state")
        terms[tuple(m[:n]) + (0,) * (ring.nvars - n)] = c
    return Relation("ge", loop.system.shift(ring.from_terms(terms)), why, SET_OWNER)


@dataclass
class Found:
    """A barrier that passed the exact check: ``B`` (deviations), its rate, degree and proofs."""

    B: Poly
    lam: Fraction
    degree: int
    initial: list[ConditionCertificate]
    unsafe: list[ConditionCertificate]
    decrease: ConditionCertificate


def conditions(loop: Loop, B: Poly, lam: Fraction, N: dict[str, Poly], D: Poly, initial: list[list[Relation]],
               unsafe: list[list[Relation]]) -> list[tuple[str, Poly, list[Relation]]]:
    """Each identity's name, its ``F >= 0`` and the relations it is proved on (module docstring)."""
    ring = loop.ring
    out = [(f"I{k}", -B, loop.relations + rels) for k, rels in enumerate(initial)]
    out += [(f"U{k}", B - ring.constant(1), loop.relations + rels) for k, rels in enumerate(unsafe)]
    out.append(("D", B * D * to_fmpq(lam) - lie(loop, B, N), list(loop.relations)))
    return out


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


def templates(loop: Loop, degrees: Sequence[int], search: Search, tried: list[str]) -> Iterator[Template]:
    """The templates of each degree, in the states first, then with the smooth auxiliaries, whose
    denominator is proved positive (a template whose denominator is not is said in ``tried``)."""
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


def search_barrier(loop: Loop, initial: list[list[Relation]], unsafe: list[list[Relation]], budget: Budget
                   ) -> tuple[tuple[Found, Poly, list[Any]] | None, list[str], Any]:
    """The first barrier over :data:`RECAST_BARRIER_DEGREES` (B in the states first, then with the
    smooth auxiliaries) and the rates :data:`~lyapcheck.models.classes.barrier.LAMBDAS` (per second) that
    passes the exact check; with its denominator ``D`` and the proofs of ``D > 0``; what was tried."""
    from lyapcheck import tolerances

    ring = loop.ring
    search = Search(ring, budget)
    tried: list[str] = []
    zero = tuple([0] * ring.nvars)
    for template in templates(loop, RECAST_BARRIER_DEGREES, search, tried):
        dv, basis, label, N, D, dens = (template.degree, template.basis, template.label, template.N, template.D,
                                        template.dens)
        for lam in LAMBDAS:
            # each rate (its faces together) gets a budget of solves: a count, the same on any machine
            capped = search.within(tolerances.TEMPLATE_SOLVES, "per template",
                                   "lyapcheck.tolerances.TEMPLATE_SOLVES")
            monos = [ring.monomial(m) for m in basis]
            shapes = conditions(loop, ring.zero(), lam, N, D, initial, unsafe)  # names and relations

            def terms_of(name: str, lam: Fraction = lam) -> list[tuple[str, Poly]]:
                if name.startswith("I"):
                    return [(f"b{k}", -p) for k, p in enumerate(monos)]
                if name.startswith("U"):
                    return [(f"b{k}", p) for k, p in enumerate(monos)]
                return [(f"b{k}", p * D * to_fmpq(lam) - lie(loop, p, N)) for k, p in enumerate(monos)]

            def build(drop: frozenset[tuple[str, Monomial]], lam: Fraction = lam) -> ConditionProgram | str:
                program = ConditionProgram(ring, loop.relations, drop, loop.unused(), roots=loop.roots(),
                                           square_free=loop.square_free())
                for k in range(len(basis)):
                    program.free(f"b{k}")
                for name, _, relations in shapes:
                    program.relations = relations  # each identity's own: a set's inequalities only where they hold
                    free = terms_of(name)
                    top = max((sum(m) for _, p in free for m in ring.support(p)), default=dv)
                    why = program.condition(name, [zero], free, top, vanishing=False)
                    if why is not None:
                        return why
                return program

            values = ParameterValues()
            for name, _, _ in shapes:
                known = ring.constant(-1) if name.startswith("U") else ring.zero()
                _set(values, *known_values(ring, name, known, [zero]))

            def accept(program: ConditionProgram, point: Any, lam: Fraction = lam) -> Found | None:
                B = sum((ring.monomial(m, point.scalars[f"b{k}"]) for k, m in enumerate(basis)), ring.zero())
                certs = {}
                for name, F, relations in conditions(loop, B, lam, N, D, initial, unsafe):
                    cert = program.certificate(name, point)
                    if not check_condition(ring, F, relations, cert)[0]:
                        return None
                    certs[name] = cert
                return Found(B, lam, dv, [certs[f"I{k}"] for k in range(len(initial))],
                             [certs[f"U{k}"] for k in range(len(unsafe))], certs["D"])

            try:
                found, why = solve_on_faces(capped, build, values, accept)
            except SolvesSpent as exc:
                tried.append(f"{label}, lambda = {lam} per second: {exc}")
                continue
            if found is not None:
                tried.append(f"{label}: found at lambda = {lam} per second")
                return (found, D, dens), tried, search
            tried.append(f"{label}, lambda = {lam} per second: {why}")
            if "size" in why or "rows" in why:
                break
    return None, tried, search


def certificate_json(loop: Loop, found: Found, D: Poly, dens: list[Any]) -> dict[str, Any]:
    """The exact certificate: B in the deviations (``shift``), written with the functions too, its
    rate and degree, and every proof (the recasting's, each set piece's, the decrease's)."""
    ring = loop.ring
    return {**polynomial_json(loop, KIND, "B", found.B), "lambda_per_s": str(found.lam),
            **recasting_json(loop, D, dens),
            "initial": [c.to_json(ring) for c in found.initial], "unsafe": [c.to_json(ring) for c in found.unsafe],
            "decrease": found.decrease.to_json(ring)}


def polynomial_json(loop: Loop, kind: str, letter: str, P: Poly) -> dict[str, Any]:
    """A certificate's head: its kind, the recasting's variables, auxiliaries and shift, and its
    polynomial (``B``, ``V``) in the deviations, written with the functions too, with its degree."""
    system = loop.system
    ring = loop.ring
    return {"kind": kind, "variables": list(ring.names), "auxiliaries": system.definitions(),
            "shift": {k: str(v) for k, v in system.values.items()},
            letter: poly_to_json(ring, P), f"{letter}_text": v_text(system, P), "degree": b_degree(ring, P)}


def recasting_json(loop: Loop, D: Poly, dens: list[Any]) -> dict[str, Any]:
    """The field's denominator and the recasting's proofs (square roots' bounds, ``D > 0``)."""
    ring = loop.ring
    return {"denominator": poly_to_json(ring, D),
            "recasting": {"roots": root_proofs_json(loop),
                          "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                                           for d, c, cert in dens]}}


def b_degree(ring: Ring, B: Poly) -> int:
    """B's total degree (the ``degree`` figure)."""
    return max((sum(m) for m in ring.support(B)), default=0)


# -- falsification on the true loop -------------------------------------------------------------------

def true_field(model: RecastModel) -> Any:
    """The true loop's field as :func:`falsification` simulates it (each function evaluated by numpy, the
    disturbances at 0: the nominal loop), unstopped: ``verify`` replays a counterexample with it
    (:func:`lyapcheck.models.classes.falsify.replay`, which stops a trajectory at the goal itself)."""
    from lyapcheck.models.engines.recast_numeric import TrueField

    return TrueField(model.system)


def falsification(model: RecastModel, stop: Any = None) -> Any:
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


def counterexample(model: RecastModel, trial: Any, name: str, prop: Property, when: str = "") -> ConditionResult:
    """``counterexample``: a simulated trajectory of the true loop from the initial set enters the
    unsafe set (``when``: words on when, as " before it reaches the goal"), reproducible from its start."""
    entry = trial.entry.describe(list(model.states), [], getattr(model, "units", None) or None)
    return ConditionResult(name, "counterexample",
                           f"a simulated trajectory of the true loop from the initial set enters the unsafe set{when}: "
                           f"{entry} (simulation, reproducible from its start)",
                           numbers={"falsification": trial.to_dict()},
                           refutation={"kind": "trajectory", **trial.entry.to_dict()}, property=prop)


def not_smooth_note(loop: Loop, function: str, condition: str) -> str | None:
    """Why a low degree often cannot: the ``function`` (B, V) may not use the loop's non-smooth
    functions (sat, abs, ...), yet ``condition`` must hold on the whole state space through their
    relations alone; None when the loop has none."""
    rough = sorted({a.function for a in loop.system.auxiliaries if not a.smooth and a.function})
    if not rough:
        return None
    return (f"{function} may not use {', '.join(rough)} (not smooth): {condition} must then hold on the whole "
            "state space through their relations alone")


# -- the class ----------------------------------------------------------------------------------------

def run(model: RecastModel, loop: Loop, budget: Budget, box: ModelBox | None = None) -> ConditionResult:
    """The ``barrier`` class on a loop with functions (module docstring). With ``box``, ``loop`` is the
    loop with the box's parameters as bounded constants (:func:`lyapcheck.models.surfaces.recast_run.boxed_loop`,
    ``model`` read at the box's centre): one B for every value of the box (:func:`over_box`)."""
    if box is not None and sets_use_box(model, box):
        return ConditionResult("barrier", "not_applicable", SETS_USE_BOX)
    trial, at = box_falsification(model, box) if box is not None else (falsification(model), None)
    if trial is not None and trial.entry is not None:
        return at_point(counterexample(model, trial, "barrier", "safety"), at)
    flat = flat_loop(loop)
    initial = piece_relations(flat, model.state_ring, model.sets["initial"], "initial")
    unsafe = piece_relations(flat, model.state_ring, model.sets["unsafe"], "unsafe")
    try:
        result, tried, search = search_barrier(flat, initial, unsafe, budget)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a barrier", budget.seconds, str(exc))
        numbers = late.numbers({"reason": str(exc)})
        if trial is not None:
            numbers["falsification"] = trial.to_dict()
        return ConditionResult("barrier", "inconclusive", late.summary, numbers=numbers, property="safety")
    if result is None:
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
    found, D, dens = result
    numbers = {"degree": b_degree(flat.ring, found.B), "lambda_per_s": float(found.lam)}
    if trial is not None:
        numbers["falsification"] = trial.to_dict()
        numbers["closest_approach"] = trial.closest_approach
    return ConditionResult("barrier", "certified", BARRIER_SENTENCE, numbers=numbers,
                           certificate=certificate_json(flat, found, D, dens), solver={"solves": search.log},
                           property="safety")


# -- over a box of parameters -------------------------------------------------------------------------
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


def sets_use_box(model: RecastModel, box: ModelBox) -> bool:
    """Some ``[sets]`` inequality names a parameter of ``box`` (the sets are read again from their
    text with the parameters as symbols: :attr:`RecastModel.sets` has them at the model's values)."""
    from lyapcheck.models.language.sets import forms_name, parse_set

    ring = Ring(tuple(model.states) + tuple(model.disturbances) + tuple(model.parameters))
    forms = {key: parse_set(model.source, key, [list(piece) for piece in text], ring, model.states,
                            tuple(model.disturbances))[1] for key, text in model.set_text.items()}
    return forms_name(ring, forms, set(box.names))


#: a point of a box where the true loop is simulated: the loop there, what a claim about it says first,
#: and the box's parameters there (exact decimals)
BoxPoint = tuple[RecastModel, str, dict[str, str]]


def box_points(model: RecastModel, box: ModelBox) -> Iterator[BoxPoint]:
    """The true loop at points of the box (:data:`BoxPoint`): its centre (``model``), then up to
    :data:`BOX_CORNERS` corners, each read again from the model text with the box's parameters there
    (a corner that has no finite decimal, or where the model cannot be read, is left out: these
    points only look for a counterexample)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.classes.claims import box_prefix

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


def box_falsification(model: RecastModel, box: ModelBox, goal: bool = False) -> tuple[Any, BoxPoint | None]:
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


# -- verify -------------------------------------------------------------------------------------------

def check_polynomial(loop: Loop, cert: dict[str, Any], letter: str, what: str
                     ) -> tuple[Poly, dict[str, Poly], Poly] | str:
    """A certificate's polynomial (``B``, ``V``; :func:`polynomial_json`) and the field it is proved
    on: its variables allowed, its text and degree as stated, the denominators' proofs re-checked;
    the polynomial, the flows ``N`` and the denominator ``D``, or why not (``what``: its class's words)."""
    from lyapcheck.models.classes.recast_classes import check_denominator_proofs

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


def check(model: RecastModel, proved: Loop, c: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a recast barrier exactly from the certificate and the model text: ``proved`` is the
    loop with the certificate's square-root bounds already re-checked; the sets are the model's."""
    cert = c["certificate"]
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
    initial = piece_relations(loop, model.state_ring, model.sets["initial"], "initial")
    unsafe = piece_relations(loop, model.state_ring, model.sets["unsafe"], "unsafe")
    stored = list(cert["initial"]) + list(cert["unsafe"]) + [cert["decrease"]]
    if len(cert["initial"]) != len(initial) or len(cert["unsafe"]) != len(unsafe):
        return False, "one proof per piece of the initial and of the unsafe set is needed"
    for (name, F, relations), data in zip(conditions(loop, B, lam, N, D, initial, unsafe), stored):
        proof = ConditionCertificate.from_json(ring, data, len(relations))
        if proof.rho is not None:
            return False, f"{name}: a barrier's identity takes no region multiplier"
        ok, why = check_condition(ring, F, relations, proof)
        if not ok:
            what = {"I": "B <= 0 on the initial set", "U": "B >= 1 on the unsafe set"}.get(name[0], "B' <= lambda B")
            return False, f"{what}: {why}"
    return True, ("B <= 0 on the initial set, B >= 1 on the unsafe set and B' <= lambda B on the recasting's "
                  "relations, exactly")


__all__ = ["KIND", "RECAST_BARRIER_DEGREES", "run", "check", "certificate_json", "falsification", "flat_loop",
           "piece_relations", "state_relation", "not_smooth_note", "Template", "templates", "polynomial_json",
           "recasting_json", "check_polynomial", "counterexample", "SETS_USE_BOX", "BOX_CORNERS", "sets_use_box",
           "box_points", "box_falsification", "at_point", "BoxPoint", "true_field"]

"""``sos_bound`` on a loop with functions: a global ultimate bound on each output, for every
disturbance signal within its bounds, proved exactly on the recasting's relations.

The loop is recast with its disturbances as variables (:attr:`lyapcheck.models.language.recast.RecastModel.robust`),
and ``|d_k| <= b_k`` enters as the relation ``b_k^2 - d_k^2 >= 0``. With the flows of ``V``'s
variables ``N / D`` (``D > 0`` proved, :func:`~lyapcheck.models.classes.recast_classes.prove_denominators`),
the certificate of one output ``y`` is three identities of the form
:func:`~lyapcheck.models.engines.recast_sos.check_condition` checks, each with its multipliers:

    V - eps |dx|^2 >= 0                      (positivity; radially unbounded in the states),
    -grad V . N - lam (V - 1) >= 0            (dissipation: D V' <= -lam (V - 1)),
    V - y^2 + B - 1 >= 0                      (the output under V),

all on the set the recasting's relations and the disturbance bounds describe, which every state of
the true loop under every admissible disturbance lies in. ``y`` is the output's deviation from its
value at the equilibrium, ``y - y_eq`` (:meth:`BoundLoop.output`): the claim is ``limsup |y - y_eq|
<= sqrt(B)``, and states ``y_eq`` as ``bounds_reference`` (:func:`bound_claim`).

Why ``limsup |y| <= sqrt(B)`` follows, from every start: where ``V > 1``, ``V' <= -lam (V - 1) / D
< 0``, so ``V(t) <= max(V(x0), 1)`` and the trajectory stays in ``{V <= max(V(x0), 1)}``, which is
bounded in the states by the positivity (the auxiliaries are functions of the states, so they and
``D`` are bounded there too, ``D <= D_max``). Solutions therefore exist for all time, and
``V' <= -(lam / D_max) (V - 1)`` whenever ``V > 1``, so ``limsup V <= 1``; the third identity gives
``y^2 <= V + B - 1``, hence ``limsup y^2 <= B``. Dividing by ``D`` (not multiplying the decay by it,
as the polynomial class does) lets a loop whose field grows slower than linearly, ILOS in course form
with its ``1/sqrt(Delta^2 + e^2)``, carry a quadratic ``V``.

``V`` uses the states (not an angle: there its sine and cosine) and the smooth auxiliaries that do not
depend on a disturbance: the recasting gives an auxiliary of ``d`` the flow of a constant ``d``, which
a disturbance *signal* does not have. Over a box of parameters (each a bounded constant like a
disturbance, :func:`bound_loop`), ``V`` is common to the box first, then affine in its parameters:
a parameter is constant in time, so ``V(x, p)`` serves each value, and the argument above holds for
each value apart.

The search, per output: ``V`` of degree 2, then 4 (in the states, then with the auxiliaries, then
affine in a box's parameters), at each decay rate of :data:`LAMBDA_GRID`; first
``B`` minimized (the remainders only positive semidefinite), then the program solved again with ``B``
raised by :data:`B_SLACK` and the Gram margins maximized, so that the rounded point passes the exact
check. The smallest certified ``B`` is the output's; the printed bound is ``sqrt(B)`` rounded up
exactly (:func:`lyapcheck.exact.sqrt_upper`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final, Mapping

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.engines import reasons
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.language.recast import RecastModel, written_poly
from lyapcheck.models.classes.recast_classes import (Loop, _set, base_loop, check_denominator_proofs, check_root_proofs,
                                             common_denominator, lie, prove_denominators, prove_root_bounds,
                                             root_proofs_json, state_square, v_text)
from lyapcheck.models.engines.recast_sos import (ConditionCertificate, ConditionProgram, check_condition, known_values,
                                         poly_from_json, poly_to_json, solve_on_faces)
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, why_none
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Monomial, Poly, degree_in, monomials, to_fmpq
from lyapcheck.exact import read_rational

#: decay rates ``lam`` of the dissipation inequality tried (1/s: the loop is not scaled)
LAMBDA_GRID: Final = (Fraction(1, 20), Fraction(1, 5), Fraction(3, 5), Fraction(3, 2), Fraction(4))
#: degrees of V tried, in turn
BOUND_DEGREES: Final = (2, 4)
#: why an output that uses an angle gets no bound
ANGLE_OUTPUT: Final = "it uses an angle, which the loop takes modulo 2 pi: no bound is sought"
#: ``V >= eps |dx|^2``: the positivity margin (radial unboundedness in the states)
POSITIVITY_EPSILON: Final = Fraction(1, 10**4)
#: the minimized ``B`` is raised by this factor (and :data:`B_FLOOR`) before the margin-maximizing
#: solve whose rounded point the exact check decides
B_SLACK: Final = Fraction(11, 10)
#: ... plus this, so that a minimized ``B`` of 0 (an output the disturbance cannot move) leaves room
B_FLOOR: Final = Fraction(1, 10**6)
#: digits of the printed bound ``sqrt(B)`` rounded up
BOUND_DIGITS: Final = 12
#: the certificate's kind
KIND: Final = "recast_bound"


@dataclass
class BoundLoop:
    """The loop with its disturbances (and a box's parameters) as bounded constants
    (:attr:`~lyapcheck.models.classes.recast_classes.Loop.fixed`, each with its relation), and what ``V`` may use."""

    loop: Loop
    #: the model's disturbances and bounds ``|d| <= b``
    disturbances: dict[str, Fraction]
    #: a box's parameters among the loop's constants: constant in time, so ``V`` may depend on them
    #: (the recasting's flows hold for a constant), unlike a disturbance
    box_names: tuple[str, ...] = ()

    @property
    def ring(self) -> Any:
        return self.loop.ring

    @property
    def v_vars(self) -> list[int]:
        """The variables ``V`` may use: no disturbance, box parameter or auxiliary of one (the
        recasting's flow of such an auxiliary holds for a constant only, and a disturbance varies)."""
        return self.loop.v_variables()

    @property
    def states(self) -> tuple[str, ...]:
        return self.loop.states()

    @property
    def parameters(self) -> tuple[int, ...]:
        """The indices of the box's parameters."""
        return tuple(self.ring.names.index(n) for n in self.box_names)

    def with_loop(self, loop: Loop) -> "BoundLoop":
        return BoundLoop(loop, self.disturbances, self.box_names)

    def names(self) -> list[str]:
        return [self.ring.names[i] for i in self.v_vars]

    def state_square(self) -> Poly:
        """``|dx|^2`` over the model's states (not the constants); an angle's is ``s^2 + (c - 1)^2``."""
        return state_square(self.loop)

    def output(self, y: Poly, state_ring: Any) -> Poly:
        """An output (over the states' ring) as the class bounds it: its deviation from its value at
        the equilibrium, ``y - y_eq`` (:func:`output_reference`), in this ring's deviations (where
        ``y_eq`` is the constant term)."""
        ring = self.ring
        n = len(state_ring.names)
        embedded = ring.from_terms({tuple(list(m) + [0] * (ring.nvars - n)): c for m, c in state_ring.terms(y).items()})
        shifted = self.loop.system.shift(embedded)
        return shifted - ring.constant(ring.terms(shifted).get(tuple([0] * ring.nvars), Fraction(0)))


def bound_loop(model: RecastModel, box: ModelBox | None = None) -> BoundLoop | str:
    """The loop ``sos_bound`` works on (before its square roots' bounds), or why there is none: the
    disturbances, and the box's parameters, as bounded constants."""
    from lyapcheck.models.language.recast import recast_with_constants

    if box is None:
        system = model.robust
    else:
        system = recast_with_constants(model, {**{d: Fraction(0) for d in model.disturbances},
                                               **{name: box.center(name) for name in box.names}})
    if system is None:
        return ("the recasting could not keep the disturbances as variables (a disturbance inside a function "
                "whose exact value at the equilibrium is needed)")
    fixed = {**model.disturbances, **({name: box.half(name) for name in box.names} if box is not None else {})}
    return BoundLoop(base_loop(system, fixed=fixed), dict(model.disturbances), box.names if box is not None else ())


def output_reference(model: RecastModel, name: str) -> Fraction:
    """The output's value at the equilibrium (SI), the point its bound is relative to: the outputs
    are polynomials in the states alone, so the disturbances do not enter it."""
    from lyapcheck.sos.polynomials import Ring

    return Ring(model.states).evaluate(model.outputs[name], list(model.equilibrium))


def bound_claim(model: RecastModel, bounds: Mapping[str, float | Fraction]) -> dict[str, Any]:
    """The claim of certified ``bounds`` as its condition states it: the bounds and their reference
    points (``bounds_reference``, each output at the equilibrium) and, with ``[units]``, each output's
    unit (``bounds_unit``, as a polynomial loop's: :func:`lyapcheck.models.classes.bounds.output_units`).
    Certify writes it and its sentence (:func:`bound_sentence`); ``verify`` re-makes both from the
    model and compares."""
    from lyapcheck.models.classes.bounds import output_units

    claim: dict[str, Any] = {"status": "certified", "bounds": dict(bounds),
                             "bounds_reference": {name: float(output_reference(model, name)) for name in bounds}}
    units = output_units(model)
    if units:
        claim["bounds_unit"] = {name: units[name] for name in bounds}
    return claim


def bound_sentence(model: RecastModel, bounds: Mapping[str, float | Fraction]) -> str:
    """The sentence of certified ``bounds`` (:func:`lyapcheck.models.classes.claims.summary` of
    :func:`bound_claim`): ``limsup |y - 1.5| <= 0.2``."""
    from lyapcheck.models.classes.claims import summary

    return summary("sos_bound", bound_claim(model, bounds), list(model.outputs)) or ""


@dataclass(frozen=True)
class Template:
    """The form of ``V`` tried: its degree and variables, with the flows ``N / D`` of those variables
    and the proofs that ``D``'s factors are positive (the same for every output and rate)."""

    degree: int
    variables: tuple[int, ...]
    N: dict[str, Poly]
    denominators: tuple[tuple[Poly, Fraction, ConditionCertificate], ...]
    #: a box's parameters V is affine in (each monomial of ``degree`` in the variables times 1 or one
    #: of them): one V per value of the box, ``V(x, p)``
    parameters: tuple[int, ...] = ()

    def basis(self, ring: Any) -> list[Monomial]:
        # from degree 0: a constant in V lets {V <= 1} be any sublevel set of V's other terms, so that
        # B < 1 (a bound below 1) is possible at all
        plain = [m for m in monomials(ring.nvars, 0, self.degree)
                 if all(m[i] == 0 for i in range(ring.nvars) if i not in self.variables)]
        return plain + [tuple(e + int(i == p) for i, e in enumerate(m)) for p in self.parameters for m in plain]

    def label(self, ring: Any) -> str:
        names = ", ".join(ring.names[i] for i in self.variables)
        affine = f", affine in {', '.join(ring.names[i] for i in self.parameters)}" if self.parameters else ""
        return f"degree {self.degree} in {names}{affine}"


def templates(bl: BoundLoop, search: Search) -> tuple[list[Template], list[str]]:
    """Per degree of :data:`BOUND_DEGREES`: ``V`` in the states alone (cheaper, and its denominator
    has lower degree), then in the states and the auxiliaries ``V`` may use; where a loop has an angle,
    the second only (an angle enters through its sine and cosine). Each with its denominators proved
    positive, or left out and said why."""
    ring = bl.ring
    coordinates = tuple(i for i in bl.v_vars if ring.names[i] in bl.states)
    choices = [tuple(bl.v_vars)] if bl.loop.angles else \
        list(dict.fromkeys(v for v in (coordinates, tuple(bl.v_vars)) if v))
    out: list[Template] = []
    skipped: list[str] = []
    proved: dict[tuple[int, ...], tuple[dict[str, Poly], tuple[Any, ...]] | None] = {}
    for variables in choices:
        N, _, distinct = common_denominator(bl.loop, [ring.names[i] for i in variables])
        dens, failed = prove_denominators(bl.loop, distinct, search)
        if failed is not None:
            skipped.append(f"V in {', '.join(ring.names[i] for i in variables)}: the denominator "
                           f"{written_poly(ring, failed)} was not proved positive with the disturbances acting")
            proved[variables] = None
        else:
            proved[variables] = (N, tuple(dens))
    for degree in searched_degrees(BOUND_DEGREES):
        for variables in choices:
            made = proved[variables]
            if made is not None:
                out.append(Template(degree, variables, made[0], made[1]))
        for variables in choices:  # then V(x, p), one per value of a box (its parameters' flow is 0: no new
            made = proved[variables]  # denominator)
            if made is not None and bl.parameters:
                N, _, _ = common_denominator(bl.loop, [ring.names[i] for i in variables + bl.parameters])
                out.append(Template(degree, variables, N, made[1], bl.parameters))
    return out, skipped


def _program(bl: BoundLoop, t: Template, y: Poly, lam: Fraction, B: Fraction | None,
             drop: frozenset[tuple[str, Monomial]]) -> ConditionProgram | str:
    """The three conditions (module docstring); ``B`` None: free and minimized."""
    ring = bl.ring
    loop = bl.loop
    zero = tuple([0] * ring.nvars)
    basis = t.basis(ring)
    program = ConditionProgram(ring, loop.relations, drop, loop.unused(), margin=B is not None, roots=loop.roots(),
                               square_free=loop.square_free())
    for k in range(len(basis)):
        program.free(f"v{k}")
    pos_terms = [(f"v{k}", ring.monomial(m)) for k, m in enumerate(basis)]
    dis_terms = [(f"v{k}", -lie(loop, ring.monomial(m), t.N) - ring.monomial(m) * to_fmpq(lam))
                 for k, m in enumerate(basis)]
    top = max((sum(mm) for _, p in dis_terms for mm in ring.support(p)), default=2)
    out_terms = list(pos_terms)
    if B is None:
        program.free("B")
        out_terms.append(("B", ring.constant(1)))
    l2 = bl.state_square()
    y2 = y * y
    why = program.condition("P", ring.support(l2), pos_terms, max(t.degree, 2), vanishing=False) or \
        program.condition("E", [zero], dis_terms, top, vanishing=False) or \
        program.condition("O", sorted(set(ring.support(y2)) | {zero}), out_terms,
                          max(t.degree, max((sum(m) for m in ring.support(y2)), default=0)), vanishing=False)
    if why is not None:
        return why
    if B is None:
        program.minimize([("B", 1.0)])
    return program


def _values(bl: BoundLoop, y: Poly, lam: Fraction, B: Fraction | None) -> ParameterValues:
    ring = bl.ring
    zero = tuple([0] * ring.nvars)
    l2 = bl.state_square()
    values = ParameterValues()
    _set(values, *known_values(ring, "P", -l2 * to_fmpq(POSITIVITY_EPSILON), ring.support(l2)))
    _set(values, *known_values(ring, "E", ring.constant(lam), [zero]))
    known_o = -(y * y) - ring.constant(1) + ring.constant(B if B is not None else 0)
    _set(values, *known_values(ring, "O", known_o, sorted(set(ring.support(y * y)) | {zero})))
    return values


@dataclass
class Found:
    """One output's certified bound."""

    template: Template
    V: Poly
    lam: Fraction
    B: Fraction
    positivity: ConditionCertificate
    dissipation: ConditionCertificate
    output: ConditionCertificate


def conditions(bl: BoundLoop, V: Poly, N: dict[str, Poly], y: Poly, lam: Fraction, B: Fraction) -> dict[str, Poly]:
    """The three polynomials proved non-negative on the relations (module docstring)."""
    ring = bl.ring
    return {"positivity": V - bl.state_square() * to_fmpq(POSITIVITY_EPSILON),
            "dissipation": -lie(bl.loop, V, N) - (V - ring.constant(1)) * to_fmpq(lam),
            "output": V - y * y + ring.constant(B - 1)}


def _attempt(bl: BoundLoop, t: Template, y: Poly, lam: Fraction, search: Search) -> tuple[Found | None, str]:
    """One decay rate: ``B`` minimized, then the certificate at ``B`` raised (module docstring)."""
    ring = bl.ring
    first = _program(bl, t, y, lam, None, frozenset())
    if isinstance(first, str):
        return None, first
    solution = search.solve(first.structure(), _values(bl, y, lam, None))
    if not solution.usable:
        return None, why_none(solution)
    low = max(float(solution.scalars["B"]), 0.0)
    B = (Fraction(low).limit_denominator(10**6) * B_SLACK + B_FLOOR).limit_denominator(10**9)
    basis = t.basis(ring)

    def build(drop: frozenset[tuple[str, Monomial]]) -> ConditionProgram | str:
        return _program(bl, t, y, lam, B, drop)

    def accept(program: ConditionProgram, point: Any) -> Found | None:
        V = sum((ring.monomial(m, point.scalars[f"v{k}"]) for k, m in enumerate(basis)), ring.zero())
        certs = {key: program.certificate(key, point) for key in ("P", "E", "O")}
        polys = conditions(bl, V, t.N, y, lam, B)
        for key, name in (("P", "positivity"), ("E", "dissipation"), ("O", "output")):
            if not check_condition(ring, polys[name], bl.loop.relations, certs[key])[0]:
                return None
        return Found(t, V, lam, B, certs["P"], certs["E"], certs["O"])

    return solve_on_faces(search, build, _values(bl, y, lam, B), accept)


def best_bound(bl: BoundLoop, forms: list[Template], y: Poly, search: Search) -> tuple[Found | None, list[str]]:
    """The smallest certified ``B`` over the templates of the lowest degree that gives one, at every
    rate of :data:`LAMBDA_GRID`, and what was tried."""
    ring = bl.ring
    best: Found | None = None
    tried: list[str] = []
    for t in forms:
        if best is not None and best.template.degree < t.degree:
            break  # the next degree costs far more; the bound of this one is kept
        outcomes: dict[str, int] = {}
        for lam in LAMBDA_GRID:
            found, why = _attempt(bl, t, y, lam, search)
            if found is None:
                outcomes[why] = outcomes.get(why, 0) + 1
                if "rows" in why:  # a size limit: every rate of this template is as large
                    break
            elif best is None or found.B < best.B:
                best = found
        label = t.label(ring)
        tried.append(f"{label}: " + ("found" if not outcomes else "none at some rates of lam = "
                                     f"{', '.join(str(x) for x in LAMBDA_GRID)} 1/s (" +
                                     ", ".join(f"{why} ({count})" for why, count in outcomes.items()) + ")"))
    return best, tried


def sos_bound(model: RecastModel, budget: Budget, box: ModelBox | None = None) -> ConditionResult:
    """Every output's certified ``limsup`` for every disturbance within its bounds (module docstring);
    with ``box``, for every parameter value of it as well (each a bounded constant)."""
    from lyapcheck import exact
    from lyapcheck.sos.polynomials import Ring

    if not model.disturbances:
        return ConditionResult("sos_bound", "not_applicable", "the model has no [disturbances]: add one (name = "
                                                              "bound) to bound its outputs")
    made = bound_loop(model, box)
    if isinstance(made, str):
        return ConditionResult("sos_bound", "not_applicable", made)
    search = Search(made.ring, budget)
    bounds: dict[str, float] = {}
    certs: dict[str, Any] = {}
    missing: list[str] = []
    detail: list[str] = []  # what each output's search met, a line each (numbers["detail"])
    try:
        loop, unproved = prove_root_bounds(made.loop, search)
        if unproved:
            why = reasons.reason(f"the square root '{unproved[0]}' has an argument not proved non-negative with the "
                                 "disturbances acting", ("disturbances",))
            return ConditionResult("sos_bound", "not_certified", why.summary, numbers=why.numbers(),
                                   solver={"solves": search.log})
        bl = made.with_loop(loop)
        forms, skipped = templates(bl, search)
        state_ring = Ring(model.states)
        for name, y0 in model.outputs.items():
            if any(degree_in(state_ring, y0, [a]) > 0 for a in loop.angles):
                missing.append(f"{name} ({ANGLE_OUTPUT})")
                continue
            y = bl.output(y0, state_ring)
            found, tried = best_bound(bl, forms, y, search)
            if found is None:
                missing.append(f"{name} ({'; '.join(skipped + tried) or 'no form of V could be built'})")
                detail.extend(f"{name}: {line}" for line in skipped + tried)
                continue
            bound = exact.sqrt_upper(found.B, BOUND_DIGITS)
            bounds[name] = float(bound)
            certs[name] = output_json(bl, found, y, bound)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a bound on every output", budget.seconds,
                                   [str(exc), f"bounds found so far: {bounds}", *missing])
        return ConditionResult("sos_bound", "inconclusive", late.summary, numbers=late.numbers({"reason": str(exc)}),
                               solver={"solves": search.log})
    if not bounds:
        none = (reasons.reason("no bound was sought: every output uses an angle, which the loop takes modulo 2 pi",
                               ("outputs",), missing) if all(ANGLE_OUTPUT in m for m in missing) else
                reasons.not_found("storage function that bounds an output", BOUND_DEGREES, detail or missing,
                                  ("degree", "disturbances", "time")))
        return ConditionResult("sos_bound", "not_certified", none.summary,
                               numbers=none.numbers({"reason": "; ".join(missing)}), solver={"solves": search.log})
    ring = bl.ring
    system = loop.system
    certificate = {"kind": KIND, "variables": list(ring.names), "auxiliaries": system.definitions(),
                   "angles": list(loop.angles), "shift": {k: str(v) for k, v in system.values.items()},
                   "disturbances": {d: str(b) for d, b in bl.disturbances.items()},
                   **({"parameter_box": box.to_json()} if box is not None else {}),
                   "positivity_epsilon": str(POSITIVITY_EPSILON),
                   "recasting": {"roots": root_proofs_json(loop)}, "outputs": certs}
    claim = bound_claim(model, bounds)
    result = ConditionResult("sos_bound", "certified", bound_sentence(model, bounds),
                             numbers={k: v for k, v in claim.items() if k != "status"}, certificate=certificate,
                             solver={"solves": search.log})
    result.disturbances = "all"
    return result


def output_json(bl: BoundLoop, found: Found, y: Poly, bound: Fraction) -> dict[str, Any]:
    ring = bl.ring
    t = found.template
    return {"y": poly_to_json(ring, y), "v_variables": [ring.names[i] for i in t.variables + t.parameters],
            "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                             for d, c, cert in t.denominators],
            "V": poly_to_json(ring, found.V), "V_text": v_text(bl.loop.system, found.V),
            "degree": t.degree, "lam": str(found.lam), "B": str(found.B), "bound": str(bound),
            "positivity": found.positivity.to_json(ring), "dissipation": found.dissipation.to_json(ring),
            "output": found.output.to_json(ring)}


# -- verify -------------------------------------------------------------------------------------------

def check_bound(model: RecastModel, c: Mapping[str, Any], box: ModelBox | None = None,
                summary_of: Any = None) -> tuple[bool, str]:
    """Re-check a ``sos_bound`` certificate of a loop with functions exactly (module docstring);
    ``box``: the document's box of parameters; ``summary_of``: the sentence the bounds print (default
    :func:`lyapcheck.models.classes.claims.summary`'s)."""
    from lyapcheck.sos.polynomials import Ring

    cert = c["certificate"]
    if cert.get("kind") != KIND:
        return False, "not a bound certificate of a loop with functions"
    if cert.get("parameter_box") != (box.to_json() if box is not None else None):
        return False, "the certificate's parameter box is not the document's"
    made = bound_loop(model, box)
    if isinstance(made, str):
        return False, made
    system = made.loop.system
    ring = made.ring
    if cert.get("variables") != list(ring.names) or cert.get("auxiliaries") != system.definitions() or \
            cert.get("shift") != {k: str(v) for k, v in system.values.items()} or \
            cert.get("disturbances") != {d: str(b) for d, b in made.disturbances.items()} or \
            cert.get("angles") != list(made.loop.angles):
        return False, "variables, auxiliaries, shift, disturbances or angles differ from the model text's recasting"
    if read_rational(cert["positivity_epsilon"]) != POSITIVITY_EPSILON:
        return False, "positivity_epsilon is not the class's"
    loop, why = check_root_proofs(made.loop, cert["recasting"]["roots"])
    if loop is None:
        return False, why
    bl = made.with_loop(loop)
    state_ring = Ring(model.states)
    outputs = cert["outputs"]
    if not isinstance(outputs, dict) or not set(outputs) <= set(model.outputs):
        return False, "a bound is stated for an output the model does not have"
    bounds: dict[str, float] = {}
    allowed = set(bl.names()) | set(bl.box_names)  # a box's parameter is constant: V may depend on it
    for name, item in outputs.items():
        y = bl.output(model.outputs[name], state_ring)
        if poly_from_json(ring, item["y"], "y") != y:
            return False, f"{name}: the stated output is not the model's"
        names = item["v_variables"]
        if not isinstance(names, list) or not set(names) <= allowed or len(set(names)) != len(names):
            return False, (f"{name}: V's variables must be ones it may use (no disturbance, auxiliary of a "
                           "disturbance or box parameter, angle)")
        V = poly_from_json(ring, item["V"], "V")
        if any(degree_in(ring, V, [n]) > 0 for n in ring.names if n not in names):
            return False, f"{name}: V uses a variable not among its v_variables"
        ok, why, N = check_denominator_proofs(loop, names, item["denominators"])
        if not ok:
            return False, f"{name}: {why}"
        if item.get("V_text") != v_text(system, V):
            return False, f"{name}: V_text is not V written with the functions"
        lam, B, bound = (read_rational(item[k]) for k in ("lam", "B", "bound"))
        if lam <= 0 or B < 0 or bound < 0 or bound * bound < B:
            return False, f"{name}: lam must be > 0 and bound^2 >= B >= 0"
        polys = conditions(bl, V, N, y, lam, B)
        for key in ("positivity", "dissipation", "output"):
            proof = ConditionCertificate.from_json(ring, item[key], len(loop.relations))
            ok, why = check_condition(ring, polys[key], loop.relations, proof)
            if not ok:
                return False, f"{name}, {key}: {why}"
        bounds[name] = float(bound)
    claim = bound_claim(model, bounds)
    if any(c.get(k) != v for k, v in claim.items() if k != "status") or ("bounds_unit" in c) != ("bounds_unit" in claim):
        return False, ("the stated bounds, their reference points (bounds_reference) or their units (bounds_unit) are "
                       "not the certificate's")
    expected = bound_sentence(model, bounds)
    if c.get("summary") != (summary_of(expected) if summary_of is not None else expected):
        return False, "the printed sentence is not the one the certificate supports"
    return True, ("positivity, dissipation D V' <= -lam (V - 1) and y^2 <= V + B - 1 on the recasting's relations "
                  "with every disturbance within its bounds, exactly")


__all__ = ["sos_bound", "check_bound", "bound_loop", "bound_claim", "bound_sentence", "output_reference", "BoundLoop",
           "LAMBDA_GRID", "BOUND_DEGREES", "KIND"]

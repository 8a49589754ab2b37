"""``sos_bound`` on a polynomial discrete-time map: an ultimate bound on each output under bounded
disturbances, found by SOS and checked exactly.

The map is the model's, shifted to its fixed point with the disturbances at 0
(:func:`~lyapcheck.models.loop.discrete.shifted_map`): ``e+ = F(e, d)``, ``F(0, 0) = 0``, in the shifted
states ``e`` (no scaling). Each disturbance is written ``d_k = b_k u_k`` with ``u_k`` in ``[-1, 1]``
(``b_k`` its ``[disturbances]`` bound), so the ring's variables after the states are the ``u_k``.

Over a box of parameters (``certify --box``) the box's normalized parameters follow the disturbances in the
ring, each in ``[-1, 1]`` too, and get the same S-procedure multipliers: ``V`` stays of the states alone, so one
certificate holds for every parameter value of the box. (A parameter is constant along an orbit while a
disturbance may change every step; the identities hold for every ``u`` of the box at each step, so they cover
the constant case, at the cost of the conservatism that is.) The output's reference ``y_eq`` is its value at the
fixed point with the disturbances at 0 and the parameters at the box's centre.

The certificate (kind :data:`KIND`), per output ``y`` (its deviation ``y - y_eq`` from its value at the
fixed point, as the continuous class states it), with ``V`` a free polynomial of the states of degree
``k``, ``lam`` a fixed rational in ``[0, 1)`` and ``B >= 0`` a rational:

    (1 - lam) + lam V(e) - V(F(e, b u)) - sum_k r_k (1 - u_k^2) = sigma_D       (the step)
    B + V(e) - 1 - y(e, b u)^2 - sum_k q_k (1 - u_k^2) = sigma_E               (the output)

every ``r_k``, ``q_k`` a sum of squares in ``(e, u)`` (exact positive semidefinite Gram matrices, the
S-procedure on ``1 - u_k^2 >= 0`` as :func:`~lyapcheck.models.engines.search.box_multipliers` builds it) and
``sigma_D``, ``sigma_E`` with exact positive definite Gram matrices.

Why it bounds every iterate: for every state and every ``|d_k| <= b_k`` the step identity gives
``V(F(e, d)) - 1 <= lam (V(e) - 1)``. Along any disturbance sequence within its bounds, by induction
(``lam >= 0`` keeps the sign of an inequality), ``V(e_k) - 1 <= lam^k (V(e_0) - 1)``: ``{V <= 1}`` is
invariant, and from any start ``limsup_k V(e_k) <= 1`` (``lam < 1``). The output identity gives
``y^2 <= B + (V - 1)`` everywhere (and ``y^2 <= B`` on ``{V <= 1}``), so ``limsup_k |y_k| <= sqrt(B)``: every
iterate eventually stays within any margin above ``sqrt(B)``, and within ``sqrt(B)`` itself from a start in
``{V <= 1}``. A map is defined everywhere, so nothing else is needed: ``V`` need not be nonnegative, nor
radially unbounded (the bound needs the two identities only, with ``lam`` in ``[0, 1)``). The output identity
is the continuous class's ``y^2 <= B^2`` on ``{V <= 1}`` with the S-procedure multiplier of ``1 - V`` fixed
to 1: no generality is lost, since ``s V + (1 - s)`` satisfies the step identity whenever ``V`` does
(``s >= 0``) and moves ``V - 1`` to ``s (V - 1)``; and a constant multiplier keeps the limsup argument valid
off ``{V <= 1}``, which a polynomial multiplier would not (it may be unbounded there).

The search: ``V`` of degree 2, then 4 (:data:`BOUND_DEGREES`), at each rate of :data:`LAMBDAS`; per
output, ``B`` is minimized by cvxpy/Clarabel, rounded to rationals (:mod:`lyapcheck.sos.rounding`) and
checked exactly (:func:`check_map_bound`); the smallest certified ``B`` of the first degree that gives one
is kept. The figure is ``bounds`` ``{output: sqrt(B) rounded up}`` (:func:`lyapcheck.exact.sqrt_upper`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.models.classes.claims import DISCRETE_BOUND_KIND, summary
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import (Budget, BudgetExhausted, ParameterValues, Search, box_multipliers,
                                             box_multipliers_from_json, box_multipliers_of, box_support, exact_grams,
                                             literal, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, box_terms
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.loop.field import ShiftedField
    from lyapcheck.sos.rounding import ExactPoint

#: the kind of the certificate (``verify`` and the sentence read it)
KIND: Final = DISCRETE_BOUND_KIND
#: the rates ``lam`` of the step identity tried, in turn (any rational in [0, 1) is sound)
LAMBDAS: Final = (Fraction(1, 2), Fraction(3, 4), Fraction(9, 10), Fraction(1, 4), Fraction(19, 20))
#: degrees of ``V`` tried, in turn: ``V(F)`` has degree ``deg V * deg F``
BOUND_DEGREES: Final = (2, 4)
#: the smallest eigenvalue every Gram matrix keeps in the search, so that the rounded point passes the
#: exact positive-definiteness checks (the continuous class's floor)
BOUND_FLOOR: Final = 1e-7
#: significant digits of the bound ``sqrt(B)`` rounded up
BOUND_DIGITS: Final = 12
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120


class DisturbedMap:
    """The map ``e+ = F(e, b u)`` in the ring of the states and the normalized disturbances ``u`` (then a box's
    normalized parameters, if the map has one)."""

    def __init__(self, shifted: "ShiftedField") -> None:
        from lyapcheck.models.classes.discrete_lyapunov import NotAMap

        model = shifted.model
        self.ring: Ring = shifted.ring
        self.n: int = shifted.n
        self.names: list[str] = list(model.disturbances)
        if list(self.ring.names[self.n:]) != self.names + list(shifted.box_names):
            raise NotAMap("the map's ring does not list its disturbances after its states (then a box's parameters)")
        self.bounds: tuple[Fraction, ...] = tuple(Fraction(b) for b in model.disturbances.values())
        gens = self.ring.gens()
        # d_k = b_k u_k: the ring's variable n + k is read as u_k from here on (a box's parameters, already
        # normalized, stay as they are)
        self.images: list[Poly] = list(gens[:self.n]) + [gens[self.n + k] * to_fmpq(b)
                                                         for k, b in enumerate(self.bounds)] \
            + list(gens[self.n + len(self.bounds):])
        F = []
        for name, num, den in zip(self.ring.names, shifted.numerators, shifted.denominators):
            if not den.is_constant():
                raise NotAMap(f"the next value of {name} has a denominator depending on the states (a polynomial "
                              "map is needed)")
            F.append(self.ring.compose(num * (1 / den.leading_coefficient()), self.images))
        self.F: tuple[Poly, ...] = tuple(F)
        self.outputs: dict[str, Poly] = {k: self.ring.compose(y, self.images) for k, y in shifted.outputs.items()}

    @property
    def nvars(self) -> int:
        return self.ring.nvars

    def after_step(self, p: Poly) -> Poly:
        """``p(F(e, b u))`` for a polynomial ``p`` of the states."""
        return self.ring.compose(p, list(self.F) + list(self.ring.gens()[self.n:]))

    def output(self, name: str) -> tuple[Poly, Fraction]:
        """The output's deviation ``y - y_eq`` and ``y_eq`` (its value at the fixed point, disturbances at 0)."""
        y = self.outputs[name]
        y_eq = self.ring.evaluate(y, [Fraction(0)] * self.nvars)
        return y - self.ring.constant(y_eq), y_eq


# -- the exact check -----------------------------------------------------------------------------------

def bound_preconditions(ring: Ring, n: int, V: Poly, lam: Fraction, B: Fraction) -> str | None:
    """What the bound's argument asks of its figures before any identity (every map's, with functions or not):
    ``0 <= lam < 1``, ``B >= 0`` and ``V`` of the ring's first ``n`` variables (the states) alone; why not,
    else None."""
    if not 0 <= lam < 1:
        return "the rate lam must satisfy 0 <= lam < 1"
    if B < 0:
        return "B must be >= 0"
    if any(any(m[n:]) for m in ring.support(V)):
        return "V may depend on the states only"
    return None


def check_map_bound(dm: DisturbedMap, y: Poly, V: Poly, lam: Fraction, B: Fraction, sigma_D: GramPoly,
                    sigma_E: GramPoly, box_D: Sequence[tuple[int, GramPoly]], box_E: Sequence[tuple[int, GramPoly]]
                    ) -> tuple[bool, str]:
    """The two identities of the module docstring, exactly: then ``limsup |y_k| <= sqrt(B)`` along every
    disturbance sequence within its bounds, from every start (for every parameter value of a box)."""
    ring, n = dm.ring, dm.n
    why_not = bound_preconditions(ring, n, V, lam, B)
    if why_not is not None:
        return False, why_not
    if any(not n <= j < ring.nvars for j, _ in (*box_D, *box_E)):
        return False, "a multiplier names a variable that is no disturbance (nor a parameter of the box)"
    if not sigma_D.positive_definite() or not sigma_E.positive_definite():
        return False, "Q_sigma_D or Q_sigma_E is not positive definite (exact)"
    boxed_D, why = box_terms(ring, box_D)
    if why is not None:
        return False, why
    boxed_E, why = box_terms(ring, box_E)
    if why is not None:
        return False, why
    one_ = ring.constant(1)
    if one_ * to_fmpq(1 - lam) + V * to_fmpq(lam) - dm.after_step(V) - boxed_D != sigma_D.poly(ring):
        return False, "the identity (1 - lam) + lam V - V(F) - sum r_k (1 - u_k^2) = sigma_D does not hold exactly"
    if ring.constant(B - 1) + V - y * y - boxed_E != sigma_E.poly(ring):
        return False, "the identity B + V - 1 - y^2 - sum q_k (1 - u_k^2) = sigma_E does not hold exactly"
    return True, "(1 - lam) + lam V - V(F) and B + V - 1 - y^2 are sums of squares on the disturbances' box, exactly"


# -- the program ---------------------------------------------------------------------------------------

def _c(k: int) -> str:
    return f"c{k}"


def _without(grams: Sequence[Gram], drop: frozenset[tuple[str, Monomial]]) -> list[Gram]:
    """The multipliers' Grams with the monomials of ``drop`` left out of their bases (one block each)."""
    from dataclasses import replace

    out = []
    for g in grams:
        basis = tuple(q for q in g.basis if (g.name, q) not in drop)
        if basis:
            out.append(replace(g, basis=basis, blocks=(tuple(range(len(basis))),)))
    return out


def state_monomials(ring: Ring, n: int, degree: int) -> list[Monomial]:
    """The monomials of ``V``: of the ring's first ``n`` variables (the states), degree 0 to ``degree``, in the
    whole ring's exponents."""
    pad = tuple([0] * (ring.nvars - n))
    return [tuple(m) + pad for m in monomials(n, 0, degree)]


def bound_structure(ring: Ring, y: Poly, alphas: Sequence[Monomial], steps: Sequence[set[Monomial]],
                    z_d: Sequence[Monomial], z_e: Sequence[Monomial], step_grams: Sequence[Gram] = (),
                    step_terms: Sequence[Term] = (), output_grams: Sequence[Gram] = (),
                    output_terms: Sequence[Term] = (), scalars: Sequence[Scalar] = ()) -> Structure | str:
    """The bound's program, whatever the map's constraints are (a polynomial map's disturbance box, a map with
    functions' relations): the step identity ``(1 - lam) + lam V - V(F) - (step terms) = sigma_D`` (``V``'s
    coefficient ``c_k`` on ``alphas[k]``, its parameter ``p_k`` of support ``steps[k]``, :func:`step_values`)
    and the output identity ``B + V - 1 - y^2 - (output terms) = sigma_E``, ``B`` minimized; ``sigma_D``,
    ``sigma_E`` on the bases ``z_d``, ``z_e``. The constraints' multipliers come as Grams, terms and scalars;
    why there is no program when a size limit is passed."""
    from lyapcheck.models.classes.lyapunov import within_cost
    from lyapcheck.models.engines.reasons import size_limit

    if not z_d or not z_e or max(len(z_d), len(z_e)) > MAX_GRAM_ROWS:
        return size_limit(max(len(z_d), len(z_e)), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS,
                          "MAX_GRAM_ROWS")
    zero = tuple([0] * ring.nvars)
    terms_d = [Term(param(f"p{k}", s), _c(k)) for k, s in enumerate(steps)]
    terms_d += [*step_terms, Term(one(ring, -1), "sigD")]
    terms_e = [Term(literal(ring, {a: 1}), _c(k)) for k, a in enumerate(alphas)]
    terms_e += [Term(one(ring, 1), "B"), *output_terms, Term(one(ring, -1), "sigE")]
    grams = [Gram("sigD", tuple(z_d), (tuple(range(len(z_d))),), margin="floor"),
             Gram("sigE", tuple(z_e), (tuple(range(len(z_e))),), margin="floor"), *step_grams, *output_grams]
    structure = Structure(
        nvars=ring.nvars, grams=tuple(grams),
        scalars=(Scalar("B"), *(Scalar(_c(k)) for k in range(len(alphas))), *scalars),
        identities=(Identity("step", tuple(terms_d), param("lam0", [zero]), "sigD"),
                    Identity("output", tuple(terms_e), literal(ring, ring.terms(-(y * y) - ring.constant(1))),
                             "sigE")),
        objective=("min", "B"))
    return within_cost(structure)


def bound_program(dm: DisturbedMap, y: Poly, degree: int, drop: frozenset[tuple[str, Monomial]] = frozenset()
                  ) -> tuple[Structure, list[Monomial]] | str:
    """The program for a ``V`` of this degree (its coefficients ``c_k``, one per monomial of degree 0 to
    ``degree`` of the states, the monomials returned with it), or why there is none (a size limit).
    ``drop``: (Gram, monomial) pairs the remainders' bases leave out (facial reduction)."""
    from lyapcheck.models.classes.lyapunov import TARGET_LIMIT
    from lyapcheck.models.engines.reasons import size_limit

    ring, n, nv = dm.ring, dm.n, dm.nvars
    zero = tuple([0] * nv)
    alphas = state_monomials(ring, n, degree)
    steps = [set(ring.support(dm.after_step(ring.monomial(a)))) | {a} for a in alphas]
    target: set[Monomial] = set().union(*steps) | {zero}
    u_vars = list(range(n, nv))
    d_grams, d_terms = box_multipliers(nv, n, target, with_states=False, prefix="rD", box_vars=u_vars,
                                       margin="floor")
    d_grams = _without(d_grams, drop)
    d_terms = [t for t in d_terms if any(g.name == t.decision for g in d_grams)]
    target |= box_support(d_grams, nv)
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    e_target = set(alphas) | set(ring.support(y * y)) | {zero}
    e_grams, e_terms = box_multipliers(nv, n, e_target, with_states=False, prefix="rE",
                                       box_vars=[j for j in u_vars if any(m[j] for m in ring.support(y))],
                                       margin="floor")
    e_grams = _without(e_grams, drop)
    e_terms = [t for t in e_terms if any(g.name == t.decision for g in e_grams)]
    e_target |= box_support(e_grams, nv)
    z_d = [q for q in bases.sos_basis(nv, target) if ("sigD", q) not in drop]
    z_e = [q for q in bases.sos_basis(nv, e_target) if ("sigE", q) not in drop]
    structure = bound_structure(ring, y, alphas, steps, z_d, z_e, d_grams, d_terms, e_grams, e_terms)
    if isinstance(structure, str):
        return structure
    return structure, alphas


def step_values(ring: Ring, alphas: Sequence[Monomial], lam: Fraction, after_step: Callable[[Poly], Poly]
                ) -> ParameterValues:
    """The parameters of :func:`bound_structure` at rate ``lam``: ``p_k = lam e^a_k - e^a_k(F)`` (``after_step``
    the map's composition), ``lam0 = 1 - lam`` and the Gram floor."""
    values = ParameterValues()
    for k, a in enumerate(alphas):
        e_a = ring.monomial(a)
        after = after_step(e_a)
        values.set_poly(ring, f"p{k}", e_a * to_fmpq(lam) - after, set(ring.support(after)) | {tuple(a)})
    values.set_poly(ring, "lam0", ring.constant(1 - lam), [tuple([0] * ring.nvars)])
    values.set_scalar("floor", BOUND_FLOOR)
    return values


def bound_values(dm: DisturbedMap, alphas: Sequence[Monomial], lam: Fraction) -> ParameterValues:
    return step_values(dm.ring, alphas, lam, dm.after_step)


def solve_bound(ring: Ring, structure: Structure, alphas: Sequence[Monomial], values: ParameterValues,
                search: Search) -> tuple[ExactPoint, dict[str, Any], Poly, Fraction] | str:
    """One solve of :func:`bound_structure`'s program, rounded: the exact point, its Grams, ``V`` and ``B`` (for
    the caller's exact check), or why there is no point."""
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return why_none(solution)
    V = ring.from_terms({a: point.scalars[_c(k)] for k, a in enumerate(alphas)})
    return point, exact_grams(structure, point), V, point.scalars["B"]


def attempt(dm: DisturbedMap, y: Poly, structure: Structure, alphas: Sequence[Monomial], lam: Fraction,
            search: Search) -> tuple[dict[str, Any] | None, str]:
    """One solve at rate ``lam``: the exact certificate if it passes :func:`check_map_bound`, else why not."""
    solved = solve_bound(dm.ring, structure, alphas, bound_values(dm, alphas, lam), search)
    if isinstance(solved, str):
        return None, solved
    point, grams, V, B = solved
    box_D = box_multipliers_of(point.grams, multiplier_grams(structure, "rD"))
    box_E = box_multipliers_of(point.grams, multiplier_grams(structure, "rE"))
    ok, why = check_map_bound(dm, y, V, lam, B, grams["sigD"], grams["sigE"], box_D, box_E)
    if not ok:
        return None, f"the rounded point failed the exact check ({why})"
    return {"V": V, "lam": lam, "B": B, "sigD": grams["sigD"], "sigE": grams["sigE"], "box_D": box_D,
            "box_E": box_E}, "found"


def best_bound(dm: DisturbedMap, y: Poly, search: Search, degrees: Sequence[int] | None = None
               ) -> tuple[dict[str, Any] | None, list[str]]:
    """The smallest certified ``B`` over :data:`LAMBDAS`, at the first degree of ``degrees`` that gives
    one (:data:`BOUND_DEGREES` under ``--degree``'s ceiling by default), and what each degree met. Where every program so far fails at a rate, a probe (the continuous
    classes' :func:`~lyapcheck.models.classes.lyapunov.face_probe`) names the remainders' basis monomials
    that must vanish, and the program without them is tried next (facial reduction, at most
    :data:`~lyapcheck.models.classes.lyapunov.FACIAL_ROUNDS` rounds per degree): the floor on every Gram
    matrix makes a program whose remainder must be singular over the full basis infeasible."""
    from lyapcheck.models.classes.lyapunov import FACIAL_ROUNDS, face_probe, vanishing_monomials

    from lyapcheck.degrees import searched_degrees

    tried: list[str] = []
    for degree in searched_degrees(BOUND_DEGREES) if degrees is None else degrees:
        search.budget.check()
        built = bound_program(dm, y, degree)
        if isinstance(built, str):
            tried.append(f"degree {degree}: {built}")
            continue
        chain: list[tuple[tuple[Structure, list[Monomial]], frozenset[tuple[str, Monomial]]]] = [(built, frozenset())]
        best: dict[str, Any] | None = None
        whys: list[str] = []
        for lam in LAMBDAS:
            found, why = None, "none"
            for i in range(FACIAL_ROUNDS + 1):
                if i == len(chain):
                    (structure, alphas), drop = chain[-1]
                    probe = face_probe(structure, "sigE")
                    values = bound_values(dm, alphas, lam)
                    values.floats = {k: v for k, v in values.floats.items() if k in probe.parameters()}
                    solution = search.solve(probe, values)
                    vanishing = frozenset((g.name, q) for g in structure.grams
                                          for q in vanishing_monomials(g, solution))
                    reduced = bound_program(dm, y, degree, drop | vanishing) if vanishing else None
                    if reduced is None or isinstance(reduced, str):
                        break
                    chain.append((reduced, drop | vanishing))
                (structure, alphas), _ = chain[i]
                found, why = attempt(dm, y, structure, alphas, lam, search)
                if found is not None:
                    break
            if found is None:
                whys.append(f"lam {lam}: {why}")
            elif best is None or found["B"] < best["B"]:
                best = found
        if best is not None:
            best["degree"] = degree
            tried.append(f"degree {degree}: found")
            return best, tried
        tried.append(f"degree {degree}: none at any rate ({'; '.join(whys)})")
    return None, tried


# -- the class -----------------------------------------------------------------------------------------

def _poly_json(ring: Ring, p: Poly) -> dict[str, Any]:
    from lyapcheck.models.classes.lyapunov import terms_json

    return terms_json(ring, p)


def bound_figures(model: "Model", dm: DisturbedMap, names: Sequence[str]) -> dict[str, Any]:
    """``bounds_reference`` (each output at the fixed point, SI) and, with ``[units]``, ``bounds_unit``: what
    the claim states beside its bounds, as the continuous class states them; ``verify`` re-makes them."""
    from lyapcheck.models.classes.bounds import output_units

    out: dict[str, Any] = {"bounds_reference": {k: float(dm.output(k)[1]) for k in names}}
    units = output_units(model)
    if units:
        out["bounds_unit"] = {k: units[k] for k in names}
    return out


def run(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """Every output's certified ``limsup`` over the steps, one certificate each."""
    from lyapcheck import exact
    from lyapcheck.models.classes.discrete_lyapunov import NotAMap

    if not model.disturbances:
        return ConditionResult("sos_bound", "not_applicable", reasons.NO_DISTURBANCES)
    try:
        dm = DisturbedMap(shifted)
    except NotAMap as exc:
        return ConditionResult("sos_bound", "not_applicable", f"not a polynomial map: {exc}")
    search = Search(dm.ring, budget)
    bounds: dict[str, float] = {}
    certs: dict[str, Any] = {}
    detail: list[str] = []
    try:
        for name in dm.outputs:
            y, _ = dm.output(name)
            found, tried = best_bound(dm, y, search)
            if found is None:
                detail.extend(f"{name}: {line}" for line in tried)
                continue
            bound = exact.sqrt_upper(found["B"], BOUND_DIGITS)
            bounds[name] = float(bound)
            certs[name] = {"degree": found["degree"], "lam": str(found["lam"]), "B": str(found["B"]),
                           "bound": str(bound), "V": _poly_json(dm.ring, found["V"]),
                           "gram_sigma_D": found["sigD"].to_json(), "gram_sigma_E": found["sigE"].to_json(),
                           "box_multipliers_D": [{"variable": j, "gram": r.to_json()} for j, r in found["box_D"]],
                           "box_multipliers_E": [{"variable": j, "gram": r.to_json()} for j, r in found["box_E"]]}
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a bound on every output", search.budget.seconds,
                                   [str(exc), f"bounds found so far: {bounds}", *detail])
        return ConditionResult("sos_bound", "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "bounds": bounds, "time": "discrete"}),
                               solver={"solves": search.log})
    if not bounds:
        none = reasons.not_found("storage function V with V(F) <= lam V + 1 - lam that bounds an output",
                                 BOUND_DEGREES, detail, ("degree", "disturbances"))
        return ConditionResult("sos_bound", "not_certified", none.summary,
                               numbers=none.numbers({"tried": detail, "time": "discrete"}),
                               solver={"solves": search.log})
    # (an output without a bound is named by the sentence: "no bound for ...")
    numbers: dict[str, Any] = {"bounds": bounds, **bound_figures(model, dm, list(bounds)), "time": "discrete"}
    certificate = {"kind": KIND, "time": "discrete", "outputs": certs}
    text = summary("sos_bound", {"status": "certified", **numbers, "certificate": certificate},
                   list(dm.outputs)) or ""
    return ConditionResult("sos_bound", "certified", text, numbers=numbers, certificate=certificate,
                           solver={"solves": search.log}, disturbances="all")


# -- verify --------------------------------------------------------------------------------------------

def _at_least(stated: Any, proved: Fraction) -> bool:
    """A stated float bound is no smaller than the proved one (up to its printing: 12 digits)."""
    return stated is not None and Fraction(float(stated)) >= proved - abs(proved) / 10**12


def stated_bound_wrong(out: str, data: Mapping[str, Any], B: Fraction, stated: Mapping[str, Any]) -> str | None:
    """What is wrong with an output's stated bound, its identities checked (every map's ``verify``): the
    certificate's ``bound`` below ``sqrt(B)``, or the stated figure below that bound; None when nothing is."""
    bound = Fraction(data["bound"])
    if bound < 0 or bound * bound < B:
        return f"output {out}: the stated bound {data['bound']} is below sqrt(B)"
    if not _at_least(stated.get(out), bound):
        return f"output {out}: the stated figure is below the certified bound"
    return None


def stated_claim_wrong(c: Mapping[str, Any], figures: Mapping[str, Any]) -> str | None:
    """What is wrong with a map's bound claim beside its certificate (every map's ``verify``): its reference
    points or units not ``figures`` (the model's, re-made), or its disturbances not ``all``; None when
    nothing is."""
    if any(c.get(key) != figures.get(key) for key in ("bounds_reference", "bounds_unit")):
        return "the bounds' reference points (bounds_reference) or units (bounds_unit) are not the model's"
    if c.get("disturbances") != "all":
        return "a map's sos_bound covers every disturbance sequence within its bounds ('all')"
    return None


def verify(shifted: "ShiftedField", c: Mapping[str, Any], model: "Model") -> tuple[bool, str]:
    """Re-check a certified ``sos_bound`` of a map from its JSON and the map re-derived from the model text,
    without a solver: each output's two identities, its bound ``>= sqrt(B)``, the stated figures (at least
    the certified bound), the reference points and units. The sentence is checked by verify's summaries."""
    from lyapcheck.models.engines.recast_sos import poly_from_json

    try:
        cert = c["certificate"]
        if cert.get("kind") != KIND or cert.get("time") != "discrete":
            return False, f"not a certificate of a discrete-time map's bound (kind {cert.get('kind')!r})"
        dm = DisturbedMap(shifted)
        stated = c.get("bounds")
        if not isinstance(stated, dict) or set(stated) != set(cert["outputs"]) or not stated:
            return False, "the stated bounds are not the certificate's outputs"
        nv = dm.nvars
        for out, data in cert["outputs"].items():
            if out not in dm.outputs:
                return False, f"no output named {out}"
            y, _ = dm.output(out)
            V = poly_from_json(dm.ring, data["V"], "V")
            lam, B = Fraction(data["lam"]), Fraction(data["B"])
            ok, why = check_map_bound(dm, y, V, lam, B, GramPoly.from_json(data["gram_sigma_D"], nv),
                                      GramPoly.from_json(data["gram_sigma_E"], nv),
                                      box_multipliers_from_json(data.get("box_multipliers_D", []), nv),
                                      box_multipliers_from_json(data.get("box_multipliers_E", []), nv))
            if not ok:
                return False, f"output {out}: {why}"
            why_not = stated_bound_wrong(out, data, B, stated)
            if why_not is not None:
                return False, why_not
        figures = bound_figures(model, dm, list(cert["outputs"]))
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:
        return False, f"malformed certificate: {exc}"
    why_not = stated_claim_wrong(c, figures)
    if why_not is not None:
        return False, why_not
    return True, "every output's step and output identities hold exactly on the disturbances' box"


__all__ = ["KIND", "LAMBDAS", "BOUND_DEGREES", "DisturbedMap", "bound_preconditions", "check_map_bound", "stated_bound_wrong", "stated_claim_wrong", "state_monomials", "bound_structure",
           "step_values", "solve_bound", "bound_program", "best_bound", "run", "verify"]

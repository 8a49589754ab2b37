"""``sos_bound``: a global ultimate bound on each output under bounded disturbances, on every loop.

One formulation for both kinds of loop (:class:`BoundField` is what the program reads of either). On a
polynomial or rational loop (kinds Dissipation and OutputBound of :mod:`lyapcheck.sos.certificates`),
in scaled coordinates, in the ring of the states ``z`` and the disturbances ``d``:

    -grad V . g(z, d) - lam (V - 1) D - sum_k tau_k (b_k^2 - d_k^2) = sigma_D,
    V - y^2 + B - 1 = sigma_E,

with ``V = z_V^T Q_V z_V`` over the monomials of degree 0 to ``k`` of the states (``Q_V > 0``:
``V >= lambda (1 + |z|^2)``, radially unbounded), ``tau_k``, ``sigma_D``, ``sigma_E`` sums of
squares with positive definite Gram matrices, ``lam > 0``. For every ``|d_k| <= b_k``,
``V' = grad V . g / D <= -lam (V - 1)``, so ``V(t) <= 1 + (V(0) - 1) exp(-lam t)``: solutions exist
for all time (``V`` bounds ``|z|``) and ``limsup V <= 1`` from every start. With the second
identity ``y^2 <= V + B - 1``, hence ``limsup |y| <= sqrt(B)`` for every disturbance within its
bounds and every initial state.

A loop with functions is the same program with the recasting's relations (:mod:`lyapcheck.models.engines.recast_sos`;
kind :data:`KIND`), unscaled: the loop is recast with its disturbances (and a box's parameters) as bounded
constants, ``V`` is a Gram form over the states (an angle through its sine and cosine) and the smooth
auxiliaries that do not depend on a disturbance, and each identity carries ``- sum_i lambda_i h_i``
(``lambda_i`` free, per equality relation) and ``- sum_j tau_j g_j`` (``tau_j`` sums of squares, per inequality;
a disturbance's ``tau_k`` is its relation's). Its flows are ``N / D`` with every factor of ``D`` proved
positive apart (:func:`~lyapcheck.models.classes.recast_classes.prove_denominators`), and the decay is
not multiplied by ``D`` (:attr:`BoundField.W` is 1): ``D V' <= -lam (V - 1)``. Where ``V > 1``, ``V`` falls,
so a trajectory stays in ``{V <= max(V(x0), 1)}``, bounded in the states (``Q_V > 0``), where the auxiliaries
and ``D`` are bounded too (``D <= D_max``): then ``V' <= -(lam / D_max) (V - 1)`` and again ``limsup V <= 1``.
Dividing by ``D`` lets a loop whose field grows slower than linearly (ILOS in course form, with its
``1/sqrt(Delta^2 + e^2)``) carry a quadratic ``V``; multiplied, its decay would outgrow the field. A
polynomial loop is the case without relations: its program is the one this class has always built.

The ``y`` bounded is the output's deviation from its value at the equilibrium (the disturbances at 0),
``y - y_eq`` (:func:`output_deviation`): the shifted field's output keeps ``y_eq`` as its constant
term, and a bound on ``|h|`` for a gap whose equilibrium is 30 m would say nothing. The claim states
``bounds_reference`` (each ``y_eq``, SI) and, with ``[units]``, ``bounds_unit`` (:func:`bound_figures`,
:func:`bound_claim`). An output that uses an angle gets no bound (the loop lives on a circle in it).

The search, per output: minimize ``B`` for each decay rate of :data:`LAMBDA_GRID` (scaled time on a
polynomial loop, 1/s on a loop with functions), then around the best one (:data:`LAMBDA_REFINE`),
``V`` of degree 2, then 4 where the field allows, with facial reduction; every candidate is decided by
the exact check, and the smallest certified ``B`` is the bound. On a loop with functions, where the
minimizing point fails the check, ``B`` is raised by :data:`B_SLACK` and the Gram margins maximized
(:func:`_attempt_on_relations`), and ``V``'s variables (:func:`variable_choices`) and degrees are tried in
turn, cheapest first: the first that gives a bound is kept (a richer ``V`` costs far more there, with the
auxiliaries and bounded constants in its programs).
The bound in declared units is ``s_y sqrt(B)`` rounded up exactly (:func:`lyapcheck.exact.sqrt_upper`;
``s_y = 1`` on a loop with functions).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence, cast

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
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, degree_in, monomials, to_fmpq
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Solution, Structure, Term

if TYPE_CHECKING:
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, Relation
    from lyapcheck.sos.certificates import GramPoly

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
#: a loop with functions: where the point of the minimized ``B`` fails the exact check, ``B`` is raised by
#: this factor (and :data:`B_FLOOR`) and the Gram margins are maximized (:func:`_attempt_on_relations`)
B_SLACK: Final = Fraction(11, 10)
#: ... plus this, so that a minimized ``B`` of 0 (an output the disturbance cannot move) leaves room
B_FLOOR: Final = Fraction(1, 10**6)


@dataclass(frozen=True)
class BoundField:
    """What the program of ``sos_bound`` reads of a loop, of either kind: a polynomial or rational loop
    (:meth:`of_scaled`: its scaled states, disturbances and a box's normalized parameters) or a loop with
    functions (:meth:`BoundLoop.field`: the recasting's states, auxiliaries and bounded constants, with
    the relations that tie them). A polynomial loop is the case with no relations: its program is the
    one this class has always built, term for term."""

    ring: Ring
    #: the number of variables :func:`~lyapcheck.models.engines.search.box_multipliers` counts as states
    n: int
    #: the variables ``V`` is a polynomial in (its Gram basis's monomials)
    v_vars: tuple[int, ...]
    #: the variables whose pure powers ``V``'s basis must hold (``V`` radially unbounded in them)
    coordinates: tuple[int, ...]
    #: ``(variable, g)``: each variable of ``V`` moves as ``g / D_field`` (``D_field > 0``)
    flows: tuple[tuple[int, Poly], ...]
    #: the weight of the decay, ``-lam (V - 1) W``: a polynomial loop's denominator ``D`` (so that
    #: ``V' <= -lam (V - 1)``); 1 on a loop with functions, whose denominators are proved positive apart
    #: and bounded on every bounded set, so that ``V' <= -lam (V - 1) / D`` (module docstring)
    W: Poly
    #: the disturbances' variables and bounds ``|d_k| <= b_k``
    disturbances: tuple[int, ...]
    bounds: tuple[Fraction, ...]
    #: a box's normalized parameters ``u`` in ``[-1, 1]`` (a polynomial loop over a box)
    box_vars: tuple[int, ...] = ()
    #: a loop with functions over a box: the parameters ``V``'s basis holds each monomial of the states also
    #: times (``V(x, p)``, one ``V`` per value of the box: a parameter is constant, its flow 0)
    v_params: tuple[int, ...] = ()
    #: a loop with functions: every relation of the recasting (indices as its certificate names them),
    #: the index of each disturbance's ``b_k^2 - d_k^2 >= 0`` among them (the multiplier ``tau_k``), and
    #: the others, which get multipliers of their own (free on an equality, a sum of squares on an inequality)
    relations: tuple[Relation, ...] = ()
    disturbance_relations: tuple[int, ...] = ()
    multiplied: tuple[int, ...] = ()
    #: variables no multiplier's basis uses (an angle: its sine and cosine stand for it), and those no
    #: basis holds squared (a square root ``r``, a cosine: a relation reduces their squares)
    unused: frozenset[int] = frozenset()
    square_free: frozenset[int] = frozenset()

    @classmethod
    def of_scaled(cls, scaled: ScaledField) -> "BoundField":
        n, m, nv = scaled.n, scaled.m, scaled.ring.nvars
        return cls(scaled.ring, n, tuple(range(n)), tuple(range(n)), tuple(enumerate(scaled.g)), scaled.D,
                   tuple(range(n, n + m)), tuple(scaled.bounds), tuple(range(n + m, nv)))

    def allowed(self, q: Monomial) -> bool:
        """A multiplier's or remainder's basis may hold ``q`` (always on a polynomial loop)."""
        return not any(q[i] for i in self.unused) and not any(q[i] >= 2 for i in self.square_free)


def as_bound_field(field: "ScaledField | BoundField") -> BoundField:
    return field if isinstance(field, BoundField) else BoundField.of_scaled(field)


def _symmetry(field: BoundField, y: Poly) -> list[tuple[int, ...]]:
    ring = field.ring
    odd = [(ring.support(gi), i) for i, gi in field.flows] + [(ring.support(field.W), None)]
    odd += [(ring.support(field.relations[j].poly), None) for j in field.multiplied]  # each relation invariant
    return bases.sign_symmetries(ring.nvars, odd, [ring.support(y)])


def _embed(a: Monomial, variables: Sequence[int], nv: int) -> Monomial:
    out = [0] * nv
    for e, i in zip(a, variables):
        out[i] = e
    return tuple(out)


def relation_multipliers(field: BoundField, name: str, target: set[Monomial], generators: Sequence[Sequence[int]],
                         margin: bool | str = "floor") -> tuple[list[Gram], list[Scalar], list[Term], set[Monomial]]:
    """The S-procedure terms of a loop with functions' relations in identity ``name`` (``D`` or ``E``):
    ``- lambda_i h_i`` (``lambda_i`` free, its coefficients the scalars ``L<name>_<i>_<k>``) per equality
    and ``- tau_j g_j`` (``tau_j`` the Gram ``T<name>_<j>``) per inequality, of the degree the identity's
    other terms reach (the relations of :attr:`BoundField.multiplied`; none on a polynomial loop), and the
    monomials they add. (:class:`~lyapcheck.models.engines.recast_sos.ConditionProgram` builds the same terms
    for the relational classes, with their own naming and margins.) ``margin``: the ``tau_j``'s, as
    :class:`~lyapcheck.sos.program.Gram`'s (a floor parameter here; the program's margin variable in a
    program that maximizes it, as ``barrier``'s)."""
    ring = field.ring
    nv = ring.nvars
    top = max((sum(q) for q in target), default=2)
    top += top % 2
    grams: list[Gram] = []
    scalars: list[Scalar] = []
    terms: list[Term] = []
    added: set[Monomial] = set()
    for i in field.multiplied:
        rel = field.relations[i]
        d = max((sum(q) for q in ring.support(rel.poly)), default=0)
        if rel.kind == "eq":
            for k, q in enumerate(q for q in monomials(nv, 0, max(top - d, 0)) if field.allowed(q)):
                scalar = f"L{name}_{i}_{k}"
                scalars.append(Scalar(scalar))
                product = ring.monomial(q) * rel.poly
                terms.append(Term(Coefficients.literal(ring.terms(-product)), scalar))
                added |= set(ring.support(product))
        else:
            if top - d < 0:
                continue
            basis = [q for q in monomials(nv, 0, (top - d) // 2) if field.allowed(q)]
            gname = f"T{name}_{i}"
            grams.append(Gram(gname, tuple(basis), tuple(map(tuple, bases.character_blocks(basis, generators))),
                              margin=margin))
            terms.append(Term(Coefficients.literal(ring.terms(-rel.poly)), gname))
            added |= {tuple(a + b + c for a, b, c in zip(x, z, w)) for x in basis for z in basis
                      for w in ring.support(rel.poly)}
    return grams, scalars, terms, added


def bound_structure(field: "ScaledField | BoundField", y: Poly, degree: int,
                    drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | None:
    """The program for ``V`` of this degree; ``drop``: (Gram, monomial) pairs left out of the
    bases of ``V`` and the remainders (facial reduction, :func:`lyapcheck.models.classes.lyapunov.vanishing_monomials`)."""
    field = as_bound_field(field)
    ring = field.ring
    n = field.n
    m = len(field.disturbances)
    nv = ring.nvars
    generators = _symmetry(field, y)
    plain = [_embed(a, field.v_vars, nv) for a in monomials(len(field.v_vars), 0, degree // 2)]
    plain += [tuple(e + int(i == p) for i, e in enumerate(q)) for p in field.v_params for q in plain]
    z_v = [q for q in plain if ("V", q) not in drop]
    if not bases.has_pure_powers(z_v, field.coordinates):
        return None  # the face the solver found keeps no pure power of some state: no strict V there
    v_blocks = bases.character_blocks(z_v, generators)
    v_products = {tuple(a + b for a, b in zip(z_v[i], z_v[j])) for idx in v_blocks for i in idx for j in idx}
    target: set[Monomial] = set()
    for i, gi in field.flows:
        derived = {q[:i] + (q[i] - 1,) + q[i + 1:] for q in v_products if q[i] > 0}
        target |= {tuple(a + b for a, b in zip(q, s)) for q in derived for s in ring.support(gi)}
    d_support = set(ring.support(field.W))
    target |= {tuple(a + b for a, b in zip(q, s)) for q in v_products for s in d_support} | d_support
    # tau_k (b_k^2 - d_k^2) must reach the flow's degree: the disturbance enters it, times D
    top = max((sum(q) for q in target), default=2)
    # tau_k depends on the states (and a box's parameters), not on the disturbances: a d in its basis
    # would bring -tau_dd d^4, which no sum of squares can balance
    z_tau = [q for q in monomials(nv, 0, max((top - 1) // 2, 0))
             if not any(q[j] for j in field.disturbances) and field.allowed(q)]
    tau_blocks = bases.character_blocks(z_tau, generators)
    tau_products = {tuple(a + b for a, b in zip(z_tau[i], z_tau[j])) for idx in tau_blocks for i in idx for j in idx}
    for k in range(m):
        sq = tuple(2 * int(j == field.disturbances[k]) for j in range(nv))
        target |= {tuple(a + b for a, b in zip(q, s)) for q in tau_products for s in (sq, tuple([0] * nv))}
    box_vars = list(field.box_vars)
    d_box_grams, d_box_terms = box_multipliers(nv, n, target, with_states=False, generators=generators, prefix="rD",
                                               box_vars=box_vars, margin="floor")
    target |= box_support(d_box_grams, nv)
    d_rel_grams, d_rel_scalars, d_rel_terms, added = relation_multipliers(field, "D", target, generators)
    target |= added
    if len(target) > TARGET_LIMIT:
        return None
    z_d = [q for q in bases.sos_basis(nv, target) if ("sigD", q) not in drop and field.allowed(q)]
    e_target = set(v_products) | set(ring.support(y * y)) | {tuple([0] * nv)}
    e_box_grams, e_box_terms = box_multipliers(nv, n, e_target, with_states=False, generators=generators, prefix="rE",
                                               box_vars=[j for j in box_vars if any(q[j] for q in ring.support(y))],
                                               margin="floor")
    e_target |= box_support(e_box_grams, nv)
    e_rel_grams, e_rel_scalars, e_rel_terms, added = relation_multipliers(field, "E", e_target, generators)
    e_target |= added
    z_e = [q for q in bases.sos_basis(nv, e_target) if ("sigE", q) not in drop and field.allowed(q)]
    if not z_d or not z_e or max(len(z_d), len(z_e), len(z_v)) > MAX_GRAM_ROWS:
        return None
    d_blocks = bases.character_blocks(z_d, generators)
    e_blocks = bases.character_blocks(z_e, generators)
    grams = [Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)), margin="floor")]
    grams += [Gram(f"tau{k}", tuple(z_tau), tuple(map(tuple, tau_blocks)), margin="floor") for k in range(m)]
    grams += [Gram("sigD", tuple(z_d), tuple(map(tuple, d_blocks)), margin="floor"),
              Gram("sigE", tuple(z_e), tuple(map(tuple, e_blocks)), margin="floor")]
    terms_d = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in field.flows]
    terms_d.append(Term(param("lamD", d_support), "V"))
    terms_d.append(Term(param("lamD", d_support), "v0"))  # V's free constant: -lam v0 D
    for k in range(m):
        sq = tuple(2 * int(j == field.disturbances[k]) for j in range(nv))
        terms_d.append(Term(param(f"b{k}", [sq, tuple([0] * nv)]), f"tau{k}"))
    terms_d.extend(d_box_terms)
    terms_d.extend(d_rel_terms)
    terms_d.append(Term(one(ring, -1), "sigD"))
    terms_e = (Term(one(ring, 1), "V"), Term(one(ring, 1), "v0"), Term(one(ring, 1), "B"), *e_box_terms,
               *e_rel_terms, Term(one(ring, -1), "sigE"))
    grams += d_box_grams + e_box_grams + d_rel_grams + e_rel_grams
    return affordable(Structure(nvars=nv, grams=tuple(grams),
                                scalars=(Scalar("B"), Scalar("v0"), *d_rel_scalars, *e_rel_scalars),
                     identities=(Identity("dissipation", tuple(terms_d), param("lamD0", d_support), "sigD"),
                                 Identity("output", terms_e, param("E0", set(ring.support(y * y)) | {tuple([0] * nv)}),
                                          "sigE")),
                     objective=("min", "B")))


def bound_values(field: "ScaledField | BoundField", structure: Structure, y: Poly, lam: Fraction) -> ParameterValues:
    field = as_bound_field(field)
    ring = field.ring
    values = ParameterValues()
    for i, gi in field.flows:
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    d_support = ring.support(field.W)
    values.set_poly(ring, "lamD", field.W * to_fmpq(-lam), d_support)
    values.set_poly(ring, "lamD0", field.W * to_fmpq(lam), d_support)
    gens = ring.gens()
    for k, b in enumerate(field.bounds):
        j = field.disturbances[k]
        d = gens[j]
        values.set_poly(ring, f"b{k}", d * d - ring.constant(b * b), [tuple(2 * int(i == j) for i in range(ring.nvars)),
                                                                     tuple([0] * ring.nvars)])
    values.set_poly(ring, "E0", -(y * y) - ring.constant(1), list(set(ring.support(y * y)) | {tuple([0] * ring.nvars)}))
    values.set_scalar("floor", BOUND_FLOOR)
    return values


def attempt(scaled: "ScaledField | BoundField", structure: Structure, y: Poly, lam: Fraction, search: Search
            ) -> dict[str, Any] | None:
    return attempt_with_solution(scaled, structure, y, lam, search)[0]


def attempt_with_solution(field: "ScaledField | BoundField", structure: Structure, y: Poly, lam: Fraction,
                          search: Search, faces: dict[Structure, frozenset[tuple[str, Monomial]]] | None = None
                          ) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at decay rate ``lam``; the exact certificate if it passes (and the solve). ``faces``: on a
    loop with functions, the face each program's margin solve was reduced to at an earlier rate (read and
    kept, :func:`_attempt_on_relations`)."""
    field = as_bound_field(field)
    point, solution = search.solve_exact(structure, bound_values(field, structure, y, lam))
    if point is None:
        return None, solution
    ring = field.ring
    grams = exact_grams(structure, point)
    taus = [grams[f"tau{k}"] for k in range(len(field.bounds))]
    B, v0 = point.scalars["B"], point.scalars["v0"]
    if field.relations:  # a loop with functions: the identities on the recasting's relations
        return _attempt_on_relations(field, structure, y, lam, search, point, solution, {} if faces is None else faces)
    g = [gi for _, gi in field.flows]
    box_d = box_multipliers_of(point.grams, multiplier_grams(structure, "rD"))
    box_e = box_multipliers_of(point.grams, multiplier_grams(structure, "rE"))
    ok, _ = check_dissipation(ring, g, field.W, field.bounds, grams["V"], lam, taus, grams["sigD"], box_d, v0)
    if not ok:
        return None, solution
    ok, _ = check_output_bound(ring, grams["V"], y, B, grams["sigE"], box_e, v0)
    if not ok:
        return None, solution
    return {"V": grams["V"], "v0": v0, "taus": taus, "sigD": grams["sigD"], "sigE": grams["sigE"], "B": B,
            "lam": lam, "box_D": box_d, "box_E": box_e}, solution


def _on_relations(field: BoundField, structure: Structure, y: Poly, lam: Fraction, point: Any, B: Fraction
                  ) -> dict[str, Any] | None:
    """The certificate of an exact point on a loop with functions, if it passes the exact check."""
    grams = exact_grams(structure, point)
    v0 = point.scalars["v0"]
    dissipation, output = relation_certificates(field, structure, point)
    ok, _ = check_on_relations(field, grams["V"], v0, lam, B, y, dissipation, output)
    if not ok:
        return None
    return {"V": grams["V"], "v0": v0, "B": B, "lam": lam, "dissipation": dissipation, "output": output}


def _attempt_on_relations(field: BoundField, structure: Structure, y: Poly, lam: Fraction, search: Search,
                          point: Any, solution: Solution, faces: dict[Structure, frozenset[tuple[str, Monomial]]]
                          ) -> tuple[dict[str, Any] | None, Solution]:
    """The minimized ``B``'s point, if it passes; else, as the relational route has always done (its
    relations leave a minimizing point on the boundary, where rounding fails), ``B`` raised by
    :data:`B_SLACK` (and :data:`B_FLOOR`) and fixed, and every Gram matrix's margin maximized: an interior
    point, which the exact check decides. The face that solve is reduced to depends on the program's terms,
    not on the rate: kept in ``faces``, it is where the next rate's margin solve starts (fewer solves)."""
    from dataclasses import replace

    from lyapcheck.models.engines.recast_sos import FACE_ROUNDS, zero_face

    found = _on_relations(field, structure, y, lam, point, point.scalars["B"])
    if found is not None or not solution.usable:
        return found, solution
    low = max(float(solution.scalars["B"]), 0.0)
    B = (Fraction(low).limit_denominator(10**6) * B_SLACK + B_FLOOR).limit_denominator(10**9)
    fixed = replace(structure, grams=tuple(replace(g, margin=True) for g in structure.grams),
                    scalars=tuple(s for s in structure.scalars if s.name != "B"),
                    identities=tuple(replace(i, terms=tuple(t for t in i.terms if t.decision != "B"))
                                     for i in structure.identities), objective=("max_margin",))
    values = bound_values(field, fixed, y, lam)
    zero = tuple([0] * field.ring.nvars)
    values.set_poly(field.ring, "E0", -(y * y) + field.ring.constant(B - 1),
                    list(set(field.ring.support(y * y)) | {zero}))
    del values.floats["floor"]
    known = faces.get(structure, frozenset())
    face_so_far: frozenset[tuple[str, Monomial]] = frozenset()
    if known and (reduced := _without(fixed, set(known))) is not None:
        fixed, face_so_far = reduced, known
    # a point on a face of the cone (a monomial whose diagonal the identity forces to 0, which the generic
    # Newton polytope of the relations' products cannot see) has no margin: drop the face, solve again
    for _ in range(FACE_ROUNDS + 1):
        point, solution = search.solve_exact(fixed, values)
        if point is not None:
            found = _on_relations(field, fixed, y, lam, point, B)
            if found is not None:
                faces[structure] = face_so_far
                return found, solution
        # (zero_face reads a program's Gram matrices alone, their names and bases, which a structure has too)
        face = zero_face(cast(Any, fixed), solution.grams) if solution.usable else set()
        smaller = _without(fixed, face) if face else None
        if smaller is None:
            return None, solution
        fixed, face_so_far = smaller, face_so_far | frozenset(face)
    return None, solution


def _without(structure: Structure, face: set[tuple[str, Monomial]]) -> Structure | None:
    """``structure`` with the (Gram, monomial) pairs of ``face`` left out of the Gram bases (None when a
    Gram matrix would keep no row)."""
    from dataclasses import replace

    grams = []
    for g in structure.grams:
        keep = [k for k, q in enumerate(g.basis) if (g.name, q) not in face]
        if not keep:
            return None
        new = {k: j for j, k in enumerate(keep)}
        blocks = tuple(b for b in (tuple(new[k] for k in block if k in new) for block in g.blocks) if b)
        grams.append(replace(g, basis=tuple(g.basis[k] for k in keep), blocks=blocks))
    return replace(structure, grams=tuple(grams))


def best_bound(scaled: "ScaledField | BoundField", y: Poly, search: Search, degrees: Sequence[int] | None = None
               ) -> tuple[dict[str, Any] | None, list[str]]:
    """The smallest certified ``B`` over the degrees (``degrees``, default :data:`BOUND_DEGREES`) and decay
    rates (module docstring), with
    facial reduction of the remainders where a solve shows vanishing diagonal entries, and a
    geometric refinement of ``lam`` around the best one found on :data:`LAMBDA_GRID`."""
    from lyapcheck.models.classes.lyapunov import FACIAL_ROUNDS, vanishing_monomials

    scaled = as_bound_field(scaled)
    faces: dict[Structure, frozenset[tuple[str, Monomial]]] = {}  # (a loop with functions' margin solves)
    best: dict[str, Any] | None = None
    tried: list[str] = []
    for degree in searched_degrees(BOUND_DEGREES) if degrees is None else degrees:
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
                found, solution = attempt_with_solution(scaled, chain[i][0], y, lam, search, faces)
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
                         f"({'1/s' if scaled.relations else 'scaled time'}), on the full basis and "
                         f"{len(chain) - 1} facial reduction(s): "
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
            found, tried = best_bound(BoundField.of_scaled(scaled), y, search)
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


# -- loops with functions ---------------------------------------------------------------------------------

#: why an output that uses an angle gets no bound
ANGLE_OUTPUT: Final = "it uses an angle, which the loop takes modulo 2 pi: no bound is sought"
#: digits of the printed bound ``sqrt(B)`` rounded up (a loop with functions is not scaled)
BOUND_DIGITS: Final = 12
#: the kind of a loop with functions' certificate (its identities on the recasting's relations)
KIND: Final = "sos_bound_relations"
#: the kind the relational route wrote before it was merged into this class (issue 41): refused, with
#: the advice to certify again
OLD_KIND: Final = "recast_bound"
OLD_FORMAT: Final = ("a certificate of an older format (kind recast_bound, written before sos_bound had one "
                     "implementation for every loop): run lyapcheck certify again to get one that verify checks")


@dataclass
class BoundLoop:
    """A loop with functions with its disturbances (and a box's parameters) as bounded constants
    (:attr:`~lyapcheck.models.classes.recast_classes.Loop.fixed`, each with its relation), and what ``V`` may use."""

    loop: "Loop"
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
    def parameters(self) -> tuple[int, ...]:
        """The indices of the box's parameters."""
        return tuple(self.ring.names.index(n) for n in self.box_names)

    def with_loop(self, loop: "Loop") -> "BoundLoop":
        return BoundLoop(loop, self.disturbances, self.box_names)

    def names(self) -> list[str]:
        return [self.ring.names[i] for i in self.v_vars]

    def output(self, y: Poly, state_ring: Any) -> Poly:
        """An output (over the states' ring) as the class bounds it: its deviation from its value at
        the equilibrium, ``y - y_eq`` (:func:`output_reference`), in this ring's deviations (where
        ``y_eq`` is the constant term)."""
        ring = self.ring
        n = len(state_ring.names)
        embedded = ring.from_terms({tuple(list(m) + [0] * (ring.nvars - n)): c for m, c in state_ring.terms(y).items()})
        shifted = self.loop.system.shift(embedded)
        return shifted - ring.constant(ring.terms(shifted).get(tuple([0] * ring.nvars), Fraction(0)))

    def field(self, names: Sequence[str], N: Mapping[str, Poly]) -> BoundField:
        """The program's view of this loop for ``V`` over the variables ``names``, which move as ``N / D``."""
        from lyapcheck.models.classes.recast_classes import CONSTANT

        ring = self.ring
        loop = self.loop
        index = {name: i for i, name in enumerate(ring.names)}
        d_rel = [next(j for j, r in enumerate(loop.relations)
                      if r.owner == CONSTANT and degree_in(ring, r.poly, [d]) > 0) for d in self.disturbances]  # each disturbance's b^2 - d^2 >= 0 (base_loop)
        coordinates = tuple(ring.names.index(s) for s in loop.states() if s not in loop.angles)
        flows = tuple((index[name], N[name]) for name in names if not N[name].is_zero())
        moving = tuple(index[name] for name in names if name not in self.box_names)
        return BoundField(ring, len(loop.states()), moving, coordinates, flows,
                          ring.constant(1), tuple(index[d] for d in self.disturbances),
                          tuple(self.disturbances.values()), (), tuple(index[name] for name in names
                                                                        if name in self.box_names),
                          tuple(loop.relations), tuple(d_rel),
                          tuple(j for j in range(len(loop.relations)) if j not in d_rel),
                          loop.unused() | loop.roots(), loop.square_free())


def bound_loop(model: "RecastModel", box: "ModelBox | None" = None) -> BoundLoop | str:
    """The loop ``sos_bound`` works on (before its square roots' bounds), or why there is none: the
    disturbances, and the box's parameters, as bounded constants."""
    from lyapcheck.models.classes.recast_classes import base_loop
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


def output_reference(model: "RecastModel", name: str) -> Fraction:
    """The output's value at the equilibrium (SI), the point its bound is relative to: the outputs
    are polynomials in the states alone, so the disturbances do not enter it."""
    return Ring(model.states).evaluate(model.outputs[name], list(model.equilibrium))


def bound_claim(model: "RecastModel", bounds: Mapping[str, float | Fraction]) -> dict[str, Any]:
    """The claim of certified ``bounds`` on a loop with functions as its condition states it: the bounds
    and their reference points (``bounds_reference``, each output at the equilibrium) and, with
    ``[units]``, each output's unit (``bounds_unit``, :func:`output_units`): the figures a polynomial
    loop's claim states (:func:`bound_figures`). Certify writes it and its sentence (:func:`bound_sentence`);
    ``verify`` re-makes both from the model and compares."""
    claim: dict[str, Any] = {"status": "certified", "bounds": dict(bounds),
                             "bounds_reference": {name: float(output_reference(model, name)) for name in bounds}}
    units = output_units(model)
    if units:
        claim["bounds_unit"] = {name: units[name] for name in bounds}
    return claim


def bound_sentence(model: "RecastModel", bounds: Mapping[str, float | Fraction]) -> str:
    """The sentence of certified ``bounds`` (:func:`lyapcheck.models.classes.claims.summary` of
    :func:`bound_claim`): ``limsup |y - 1.5| <= 0.2``."""
    from lyapcheck.models.classes.claims import summary

    return summary("sos_bound", bound_claim(model, bounds), list(model.outputs)) or ""


def relation_certificates(field: BoundField, structure: Structure, point: Any,
                          identities: Sequence[tuple[str, str]] = (("D", "sigD"), ("E", "sigE"))
                          ) -> tuple["ConditionCertificate", ...]:
    """The two identities' multipliers of a solved program on a loop with functions, by relation index:
    each disturbance's ``tau_k``, every other relation's multiplier, and the remainder. ``identities``:
    each identity's name (as :func:`relation_multipliers` was given it) and its remainder's (``barrier``'s
    identities: ``("I0", "RI0")``, ...)."""
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.sos.certificates import GramPoly

    ring = field.ring
    by_name = {g.name: g for g in structure.grams}

    def of(name: str, sigma: str) -> ConditionCertificate:
        identity = next(i for i in structure.identities if i.remainder == sigma)
        lambdas: dict[int, Poly] = {}
        taus: dict[int, GramPoly] = {}
        for term in identity.terms:
            if term.decision.startswith(f"L{name}_"):  # the term -q h_i of a free multiplier's monomial q
                i = int(term.decision.split("_")[1])
                product = ring.from_terms(dict(zip(term.coefficients.support, term.coefficients.values)))
                q = -product / field.relations[i].poly  # exact: the term is built as -q h_i
                lambdas[i] = lambdas.get(i, ring.zero()) + q * to_fmpq(point.scalars[term.decision])
            elif term.decision.startswith(f"T{name}_"):
                taus[int(term.decision.split("_")[1])] = GramPoly.of(by_name[term.decision].basis,
                                                                   point.grams[term.decision])
        if name == "D":
            for k, j in enumerate(field.disturbance_relations):
                taus[j] = GramPoly.of(by_name[f"tau{k}"].basis, point.grams[f"tau{k}"])
        return ConditionCertificate(lambdas, taus, GramPoly.of(by_name[sigma].basis, point.grams[sigma]))

    return tuple(of(name, sigma) for name, sigma in identities)


def check_on_relations(field: BoundField, V: "GramPoly", v0: Fraction, lam: Fraction, B: Fraction, y: Poly,
                       dissipation: "ConditionCertificate", output: "ConditionCertificate") -> tuple[bool, str]:
    """Exactly, on a loop with functions: ``V = z^T Q z + v0`` over ``V``'s variables with ``Q > 0`` and a
    pure power of every coordinate (non-angle state) in its basis, ``lam > 0``, and the two identities
    (module docstring) on the recasting's relations
    (:func:`~lyapcheck.models.engines.recast_sos.check_condition`)."""
    from lyapcheck.models.engines.recast_sos import check_condition

    ring = field.ring
    if lam <= 0:
        return False, "the rate lam must be > 0"
    if not V.basis or any(q[i] for q in V.basis for i in range(ring.nvars) if i not in field.v_vars + field.v_params):
        return False, "V's basis may hold V's variables only"
    if not bases.has_pure_powers(V.basis, field.coordinates):
        return False, "V's basis must hold a pure power of every state (so that V is radially unbounded)"
    if not V.positive_definite():
        return False, "Q_V is not positive definite (exact)"
    v = V.poly(ring) + ring.constant(v0)
    flow = ring.zero()
    for i, gi in field.flows:
        flow += v.derivative(i) * gi
    ok, why = check_condition(ring, -flow - (v - ring.constant(1)) * field.W * to_fmpq(lam), field.relations,
                              dissipation)
    if not ok:
        return False, f"dissipation: {why}"
    ok, why = check_condition(ring, v - y * y + ring.constant(B - 1), field.relations, output)
    if not ok:
        return False, f"output: {why}"
    return True, ("Q_V > 0, the dissipation D V' <= -lam (V - 1) and y^2 <= V + B - 1 on the recasting's relations "
                  "with every disturbance within its bounds, exactly")


def variable_choices(bl: BoundLoop) -> list[tuple[int, ...]]:
    """The variables ``V`` is tried over, in turn: the states alone (cheaper, and their denominator has
    lower degree), then with the auxiliaries ``V`` may use; where a loop has an angle, the second only
    (an angle enters through its sine and cosine); over a box, each then with its parameters (``V(x, p)``,
    one per value of the box: a parameter is constant)."""
    ring = bl.ring
    coordinates = tuple(i for i in bl.v_vars if ring.names[i] in bl.loop.states())
    choices = [tuple(bl.v_vars)] if bl.loop.angles else \
        list(dict.fromkeys(v for v in (coordinates, tuple(bl.v_vars)) if v))
    return choices + [c + bl.parameters for c in choices if bl.parameters]


def functions_fields(bl: BoundLoop, search: Search) -> tuple[list[tuple[BoundField, list[Any]]], list[str]]:
    """Per choice of ``V``'s variables (:func:`variable_choices`), the program's view with the flows
    ``N / D`` of those variables and the proofs that ``D``'s factors are positive; a choice whose
    denominator is not proved positive is left out and said why."""
    from lyapcheck.models.classes.recast_classes import common_denominator, prove_denominators
    from lyapcheck.models.language.recast import written_poly

    ring = bl.ring
    out: list[tuple[BoundField, list[Any]]] = []
    skipped: list[str] = []
    proved: dict[tuple[int, ...], list[Any] | None] = {}
    for variables in variable_choices(bl):
        names = [ring.names[i] for i in variables]
        N, _, distinct = common_denominator(bl.loop, names)
        plain = tuple(i for i in variables if i not in bl.parameters)  # a parameter's flow is 0: no new denominator
        if plain not in proved:
            dens, failed = prove_denominators(bl.loop, distinct, search)
            proved[plain] = None if failed is not None else dens
            if failed is not None:
                skipped.append(f"V in {', '.join(names)}: the denominator {written_poly(ring, failed)} was not "
                               "proved positive with the disturbances acting")
        if proved[plain] is not None:
            out.append((bl.field(names, N), list(proved[plain] or [])))
    return out, skipped


def run_functions(model: "RecastModel", budget: "Budget", box: "ModelBox | None" = None) -> ConditionResult:
    """The class on a loop with functions: every output's certified ``limsup`` for every disturbance
    within its bounds (module docstring); with ``box``, for every parameter value of it as well (each a
    bounded constant)."""
    from lyapcheck import exact
    from lyapcheck.models.classes.recast_classes import prove_root_bounds, root_proofs_json

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
        fields, skipped = functions_fields(bl, search)
        state_ring = Ring(model.states)
        for name, y0 in model.outputs.items():
            if any(degree_in(state_ring, y0, [a]) > 0 for a in loop.angles):
                missing.append(f"{name} ({ANGLE_OUTPUT})")
                continue
            y = bl.output(y0, state_ring)
            best: tuple[dict[str, Any], BoundField, list[Any]] | None = None
            tried: list[str] = []
            for degree in searched_degrees(BOUND_DEGREES):
                if best is not None:
                    break  # the next degree costs far more: the bound of this one is kept
                for field, dens in fields:
                    found, lines = best_bound(field, y, search, (degree,))
                    label = ", ".join(bl.ring.names[i] for i in field.v_vars + field.v_params)
                    tried.extend(f"V in {label}, {line}" for line in lines)
                    if found is not None:  # the next variables cost more (more rows, another denominator)
                        best = (found, field, dens)
                        break
            if best is None:
                missing.append(f"{name} ({'; '.join(skipped + tried) or 'no form of V could be built'})")
                detail.extend(f"{name}: {line}" for line in skipped + tried)
                continue
            found, field, dens = best
            bound = exact.sqrt_upper(found["B"], BOUND_DIGITS)
            bounds[name] = float(bound)
            certs[name] = output_json(bl, field, dens, found, y, bound)
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
                   "recasting": {"roots": root_proofs_json(loop)}, "outputs": certs}
    claim = bound_claim(model, bounds)
    result = ConditionResult("sos_bound", "certified", bound_sentence(model, bounds),
                             numbers={k: v for k, v in claim.items() if k != "status"}, certificate=certificate,
                             solver={"solves": search.log})
    result.disturbances = "all"
    return result


def output_json(bl: BoundLoop, field: BoundField, dens: Sequence[Any], found: Mapping[str, Any], y: Poly,
                bound: Fraction) -> dict[str, Any]:
    """One output's certificate on a loop with functions: ``V`` (its Gram matrix and constant, and as a
    polynomial with its text in the functions), the flows' denominators with their proofs, ``lam``, ``B``,
    the bound and the two identities' multipliers by relation index."""
    from lyapcheck.models.classes.recast_classes import v_text
    from lyapcheck.models.engines.recast_sos import poly_to_json

    ring = bl.ring
    V = found["V"].poly(ring) + ring.constant(found["v0"])
    return {"y": poly_to_json(ring, y), "v_variables": [ring.names[i] for i in field.v_vars + field.v_params],
            "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                             for d, c, cert in dens],
            "gram_V": found["V"].to_json(), "V_constant": str(found["v0"]),
            "V": poly_to_json(ring, V), "V_text": v_text(bl.loop.system, V),
            "degree": found["degree"], "lam": str(found["lam"]), "B": str(found["B"]), "bound": str(bound),
            "dissipation": found["dissipation"].to_json(ring), "output": found["output"].to_json(ring)}


def check_functions(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None" = None,
                    summary_of: Any = None) -> tuple[bool, str]:
    """Re-check a ``sos_bound`` certificate of a loop with functions exactly (module docstring);
    ``box``: the document's box of parameters; ``summary_of``: the sentence the bounds print (default
    :func:`lyapcheck.models.classes.claims.summary`'s). A certificate of the relational route written
    before the merge (:data:`OLD_KIND`) is refused in one line."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.recast_classes import check_denominator_proofs, check_root_proofs, v_text
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, poly_from_json
    from lyapcheck.sos.certificates import GramPoly

    cert = c["certificate"]
    if cert.get("kind") == OLD_KIND:
        return False, OLD_FORMAT
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
        ok, why, N = check_denominator_proofs(loop, names, item["denominators"])
        if not ok:
            return False, f"{name}: {why}"
        field = bl.field(names, N)
        gram = GramPoly.from_json(item["gram_V"], ring.nvars)
        v0, lam, B, bound = (read_rational(item[k]) for k in ("V_constant", "lam", "B", "bound"))
        V = gram.poly(ring) + ring.constant(v0)
        if poly_from_json(ring, item["V"], "V") != V or item.get("V_text") != v_text(system, V):
            return False, f"{name}: V or V_text is not the Gram matrix's polynomial"
        if B < 0 or bound < 0 or bound * bound < B:
            return False, f"{name}: bound^2 >= B >= 0 is needed"
        dissipation = ConditionCertificate.from_json(ring, item["dissipation"], len(loop.relations))
        output = ConditionCertificate.from_json(ring, item["output"], len(loop.relations))
        ok, why = check_on_relations(field, gram, v0, lam, B, y, dissipation, output)
        if not ok:
            return False, f"{name}, {why}"
        bounds[name] = float(bound)
    claim = bound_claim(model, bounds)
    if any(c.get(k) != v for k, v in claim.items() if k != "status") or ("bounds_unit" in c) != ("bounds_unit" in claim):
        return False, ("the stated bounds, their reference points (bounds_reference) or their units (bounds_unit) are "
                       "not the certificate's")
    expected = bound_sentence(model, bounds)
    if c.get("summary") != (summary_of(expected) if summary_of is not None else expected):
        return False, "the printed sentence is not the one the certificate supports"
    return True, ("Q_V > 0, dissipation D V' <= -lam (V - 1) and y^2 <= V + B - 1 on the recasting's relations "
                  "with every disturbance within its bounds, exactly")

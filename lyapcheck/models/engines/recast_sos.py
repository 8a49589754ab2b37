"""Sum-of-squares conditions on a recast loop, with the recasting's relations as S-procedure terms.

A recast loop (:mod:`lyapcheck.models.language.recast`) lives on the set

    S = { (z, a) : h_i(z, a) = 0,  g_j(z, a) >= 0 }

of the states' deviations ``z`` and the auxiliaries' deviations ``a`` (the constant roots ``rt2``,
``rt3`` unshifted). Every point of the true loop, ``(z, a(z))``, lies in ``S``. A condition
"``F >= 0`` on S" is proved by the exact polynomial identity (Putinar's form, as in
Papachristodoulou & Prajna 2005, Section 3)

    F - sum_i lambda_i h_i - sum_j tau_j g_j = sigma                          (*)

with ``lambda_i`` free polynomials, ``tau_j`` and ``sigma`` sums of squares, given as Gram
matrices that are exactly positive semidefinite. :func:`check_condition` checks (*) exactly from
the certificate alone; :class:`ConditionProgram` builds the SOS program that finds it.

Multiplier bases keep every term of (*) vanishing to second order at the origin (the equilibrium):
a ``tau_j`` has a constant only when ``g_j`` itself vanishes to second order there, and the
remainder ``sigma`` has no constant. Positivity is thus relative to the equilibrium, as a Lyapunov
function's is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Mapping, Sequence, TypeVar

from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.language.recast import Relation
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.definiteness import is_positive_semidefinite
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Structure, Term, full_blocks
from lyapcheck.exact import read_rational

T = TypeVar("T")

#: the largest Gram basis a condition builds (rows); above it the condition is not attempted
MAX_RECAST_GRAM_ROWS = 60


def poly_to_json(ring: Ring, p: Poly) -> dict[str, Any]:
    """The contract's exact form ``{"terms": [[coefficient, [exponents]], ...]}``."""
    return {"terms": [[str(c), list(m)] for m, c in sorted(ring.terms(p).items())]}


def poly_from_json(ring: Ring, data: Any, key: str) -> Poly:
    """A polynomial from :func:`poly_to_json`'s form (ValueError naming ``key`` otherwise)."""
    from lyapcheck.sos.certificates import exponent

    if not isinstance(data, Mapping) or not isinstance(data.get("terms"), list):
        raise ValueError(f"{key}: must be a table with a list 'terms'")
    out: dict[Monomial, Fraction] = {}
    for term in data["terms"]:
        if not isinstance(term, list) or len(term) != 2 or not isinstance(term[1], list) or \
                len(term[1]) != ring.nvars:
            raise ValueError(f"{key}: a term must be [coefficient, [{ring.nvars} exponents]]")
        m = tuple(exponent(e, key) for e in term[1])
        out[m] = out.get(m, Fraction(0)) + read_rational(term[0])
    return ring.from_terms(out)


def mdeg(m: Monomial, roots: frozenset[int]) -> int:
    return sum(e for i, e in enumerate(m) if i not in roots)


def order_at_origin(ring: Ring, p: Poly, roots: frozenset[int] = frozenset()) -> int:
    """The smallest degree of a term of ``p`` in the deviations (a large number for 0). ``roots``:
    the constant roots' variables (``rt2``, ``rt3``), constants rather than deviations, which count
    for no degree (a monomial ``rt3 x`` does not vanish faster than ``x``)."""
    return min((mdeg(m, roots) for m in ring.support(p)), default=10 ** 6)


def degree(ring: Ring, p: Poly, roots: frozenset[int] = frozenset()) -> int:
    """The degree of ``p`` in the deviations (the roots not counted)."""
    return max((mdeg(m, roots) for m in ring.support(p)), default=0)


# -- the exact check ------------------------------------------------------------------------------

@dataclass(frozen=True)
class ConditionCertificate:
    """The multipliers of one identity (*): ``lambda_i`` by relation index, ``tau_j`` by relation
    index, the remainder ``sigma``, and (a region's condition) ``rho`` times ``(V - level)``."""

    lambdas: dict[int, Poly]
    taus: dict[int, GramPoly]
    sigma: GramPoly
    rho: GramPoly | None = None

    def to_json(self, ring: Ring) -> dict[str, Any]:
        out: dict[str, Any] = {"lambdas": {str(i): poly_to_json(ring, p) for i, p in sorted(self.lambdas.items())},
                               "taus": {str(j): g.to_json() for j, g in sorted(self.taus.items())},
                               "sigma": self.sigma.to_json()}
        if self.rho is not None:
            out["rho"] = self.rho.to_json()
        return out

    @classmethod
    def from_json(cls, ring: Ring, data: Any, relations: int) -> "ConditionCertificate":
        if not isinstance(data, Mapping):
            raise ValueError("a condition's certificate must be a table")

        def index(key: str) -> int:
            if not key.isdigit() or int(key) >= relations:
                raise ValueError(f"relation index {key!r} is not one of the {relations} relations")
            return int(key)

        lambdas = {index(k): poly_from_json(ring, v, f"lambdas.{k}") for k, v in dict(data.get("lambdas", {})).items()}
        taus = {index(k): GramPoly.from_json(v, ring.nvars) for k, v in dict(data.get("taus", {})).items()}
        rho = GramPoly.from_json(data["rho"], ring.nvars) if data.get("rho") is not None else None
        return cls(lambdas, taus, GramPoly.from_json(data["sigma"], ring.nvars), rho)


def check_condition(ring: Ring, F: Poly, relations: Sequence[Relation], cert: ConditionCertificate,
                    region: Poly | None = None) -> tuple[bool, str]:
    """Exactly: (*) holds with ``F`` (minus ``rho * region`` when a region's ``V - level`` is given:
    then ``F >= 0`` is proved where ``V <= level``), every ``tau``, ``rho`` and ``sigma``
    positive semidefinite, and each ``lambda`` on an equality, each ``tau`` on an inequality."""
    for i in cert.lambdas:
        if relations[i].kind != "eq":
            return False, f"relation {i} ({relations[i].why}) is an inequality: it takes a sum of squares, not a free multiplier"
    for j in cert.taus:
        if relations[j].kind != "ge":
            return False, f"relation {j} ({relations[j].why}) is an equality"
    grams = [("sigma", cert.sigma)] + [(f"tau{j}", g) for j, g in cert.taus.items()]
    if cert.rho is not None:
        if region is None:
            return False, "a multiplier rho without a region"
        grams.append(("rho", cert.rho))
    for name, g in grams:
        if not is_positive_semidefinite([list(r) for r in g.Q]):
            return False, f"{name} is not positive semidefinite"
    total = F - cert.sigma.poly(ring)
    for i, lam in cert.lambdas.items():
        total -= lam * relations[i].poly
    for j, tau in cert.taus.items():
        total -= tau.poly(ring) * relations[j].poly
    if cert.rho is not None and region is not None:
        total += cert.rho.poly(ring) * region  # F - rho (level - V) ... = F + rho (V - level)
    if not total.is_zero():
        return False, "the polynomial identity does not hold exactly"
    return True, "the identity holds exactly and every multiplier is a sum of squares"


# -- the program --------------------------------------------------------------------------------------

@dataclass
class ConditionProgram:
    """Identities (*) sharing free scalars (a Lyapunov function's coefficients), built into one
    :class:`~lyapcheck.sos.structure.Structure` whose known parts are parameters."""

    ring: Ring
    relations: Sequence[Relation]
    #: (Gram name, monomial) pairs left out of the bases: the zero face a previous solve found
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    #: variables no multiplier uses (an angle, which appears in no identity)
    unused: frozenset[int] = frozenset()
    #: the remainders' Gram matrices at least the margin (maximized); False: only PSD (a program
    #: with another objective, :meth:`minimize`)
    margin: bool = True
    #: the constant roots' variables (:func:`order_at_origin`)
    roots: frozenset[int] = frozenset()
    #: variables no basis monomial has squared: square roots ``r``, whose ``r^2 = q`` (an equality
    #: relation) makes every ``r^2`` of a basis redundant modulo it; kept, the redundancy puts a
    #: kernel into the remainder that no monomial face removes (``r^2 - q`` has a zero on a whole
    #: variety), and the margin is then 0
    square_free: frozenset[int] = frozenset()
    grams: list[Gram] = field(default_factory=list)
    scalars: list[Scalar] = field(default_factory=list)
    identities: list[Identity] = field(default_factory=list)
    #: per identity: its name, the relation multipliers' names (lambda scalars per relation, tau Grams)
    layout: dict[str, dict[str, Any]] = field(default_factory=dict)

    def free(self, name: str) -> None:
        self.scalars.append(Scalar(name))

    def condition(self, name: str, known_support: Sequence[Monomial], free_terms: Sequence[tuple[str, Poly]],
                  top_degree: int, region_support: Sequence[Monomial] | None = None, vanishing: bool = True
                  ) -> str | None:
        """Add ``known + sum_k c_k p_k - sum lambda h - sum tau g [- rho (level - V)] = sigma``.

        ``known`` is the parameter ``K_<name>`` over ``known_support``; ``free_terms`` are
        ``(scalar, p_k)``; ``region_support`` the support of ``V - level`` (the parameter
        ``W_<name>``) when the condition holds on a sublevel set only. ``vanishing``: every term
        vanishes to second order at the origin (a Lyapunov condition); else the multipliers and the
        remainder have constants too. Returns why not (a size)."""
        ring = self.ring
        nv = ring.nvars
        terms: list[Term] = []
        target: set[Monomial] = set(known_support)
        for scalar, p in free_terms:
            if p.is_zero():
                continue
            terms.append(Term(Coefficients.literal(ring.terms(p)), scalar))
            target |= set(ring.support(p))
        roots = self.roots
        top = max(top_degree, max((mdeg(m, roots) for m in target), default=0))
        top += top % 2
        lambdas: dict[int, list[tuple[str, Monomial]]] = {}
        taus: dict[int, str] = {}
        for i, rel in enumerate(self.relations):
            d = degree(ring, rel.poly, roots)
            if rel.kind == "eq":
                names = []
                for k, m in enumerate(self._monomials(0, top - d)):
                    sname = f"L{name}_{i}_{k}"
                    self.scalars.append(Scalar(sname))
                    mono = ring.monomial(m)
                    terms.append(Term(Coefficients.literal(ring.terms(-(mono * rel.poly))), sname))
                    names.append((sname, m))
                    target |= set(ring.support(mono * rel.poly))
                lambdas[i] = names
            else:
                half = (top - d) // 2
                if half < 0:
                    continue
                lowest = 0 if order_at_origin(ring, rel.poly, roots) >= 2 or not vanishing else 1
                gname = f"T{name}_{i}"
                basis = [m for m in self._monomials(lowest, half) if (gname, m) not in self.drop]
                if not basis:
                    continue
                self.grams.append(Gram(gname, tuple(basis), full_blocks(basis), margin=self.margin))
                terms.append(Term(Coefficients.literal(ring.terms(-rel.poly)), gname))
                taus[i] = gname
                target |= {tuple(a + b + c for a, b, c in zip(x, y, z)) for x in basis for y in basis
                           for z in ring.support(rel.poly)}
        rho_name = None
        if region_support is not None:
            half = max((mdeg(m, roots) for m in target), default=2) // 2 - \
                max((mdeg(m, roots) for m in region_support), default=0) // 2
            basis = self._monomials(1 if vanishing else 0, max(half, 1))
            rho_name = f"P{name}"
            self.grams.append(Gram(rho_name, tuple(basis), full_blocks(basis), margin=self.margin))
            terms.append(Term(Coefficients.parameter(f"W_{name}", sorted(region_support)), rho_name))
            target |= {tuple(a + b + c for a, b, c in zip(x, y, z)) for x in basis for y in basis
                       for z in region_support}
        rname = f"S{name}"
        if roots:  # a basis over Q(sqrt 2, sqrt 3): each monomial of the deviations times 1 and each root
            remainder = [m for m in self._monomials(1 if vanishing else 0, top // 2) if (rname, m) not in self.drop]
        else:
            remainder = [m for m in bases.sos_basis(nv, target | {tuple([0] * nv)})
                         if (sum(m) >= 1 or not vanishing) and (rname, m) not in self.drop
                         and not any(m[i] for i in self.unused) and not any(m[i] >= 2 for i in self.square_free)]
        if len(remainder) > MAX_RECAST_GRAM_ROWS:
            return size_limit(len(remainder), "rows of one sum-of-squares matrix", MAX_RECAST_GRAM_ROWS,
                              "MAX_RECAST_GRAM_ROWS")  # "rows": the searches stop a template's rates on it
        self.grams.append(Gram(rname, tuple(remainder), full_blocks(remainder), margin=self.margin))
        terms.append(Term(Coefficients.literal({tuple([0] * nv): -1}), rname))
        self.identities.append(Identity(name, tuple(terms), Coefficients.parameter(f"K_{name}", sorted(known_support)),
                                        rname))
        self.layout[name] = {"lambdas": lambdas, "taus": taus, "sigma": rname, "rho": rho_name}
        return None

    def _monomials(self, low: int, high: int) -> list[Monomial]:
        """The monomials of degree ``low..high`` in the deviations (no unused variable), each also
        times every product of distinct roots (their powers are reduced by ``rt^2 = k``)."""
        roots = sorted(self.roots)
        plain = [m for m in monomials(self.ring.nvars, low, high)
                 if not any(m[i] for i in self.unused) and not any(m[i] for i in roots)
                 and not any(m[i] >= 2 for i in self.square_free)]
        out = list(plain)
        for k in range(1, len(roots) + 1):
            from itertools import combinations

            for chosen in combinations(roots, k):
                out += [tuple(e + (1 if i in chosen else 0) for i, e in enumerate(m)) for m in plain]
        return out

    #: the objective: ("max_margin",) or ("min", "objective") after :meth:`minimize`
    objective: tuple[str, ...] = ("max_margin",)

    def minimize(self, weights: Sequence[tuple[str, float]]) -> None:
        """Minimize ``sum_k w_k c_k`` over the free scalars (``objective >= sum``, a 1x1 remainder)."""
        nv = self.ring.nvars
        zero = tuple([0] * nv)
        self.scalars.append(Scalar("objective"))
        terms = [Term(Coefficients.literal({zero: 1}), "objective")]
        terms += [Term(Coefficients.literal({zero: -Fraction(w)}), name) for name, w in weights if w]
        self.grams.append(Gram("Sobjective", (zero,), full_blocks([zero]), margin=False))
        terms.append(Term(Coefficients.literal({zero: -1}), "Sobjective"))
        self.identities.append(Identity("objective", tuple(terms), None, "Sobjective"))
        self.objective = ("min", "objective")

    def structure(self) -> Structure:
        return Structure(nvars=self.ring.nvars, grams=tuple(self.grams), scalars=tuple(self.scalars),
                         identities=tuple(self.identities), objective=self.objective)

    def certificate(self, name: str, point: Any) -> ConditionCertificate:
        """The exact multipliers of identity ``name`` from an exact point of the program."""
        ring = self.ring
        lay = self.layout[name]
        by_name = {g.name: g for g in self.grams}
        lambdas = {i: sum((ring.monomial(m, point.scalars[sname]) for sname, m in names), ring.zero())
                   for i, names in lay["lambdas"].items()}
        taus = {j: GramPoly.of(by_name[g].basis, point.grams[g]) for j, g in lay["taus"].items()}
        sigma = GramPoly.of(by_name[lay["sigma"]].basis, point.grams[lay["sigma"]])
        rho = GramPoly.of(by_name[lay["rho"]].basis, point.grams[lay["rho"]]) if lay["rho"] else None
        return ConditionCertificate(lambdas, taus, sigma, rho)


def known_values(ring: Ring, name: str, known: Poly, support: Sequence[Monomial]) -> tuple[str, list[Fraction]]:
    """The parameter ``K_<name>``'s exact values: ``known``'s coefficients over ``support``."""
    terms = ring.terms(known)
    extra = [m for m in terms if m not in set(support)]
    if extra:
        raise ValueError(f"{name}: the known part has monomials outside its support: {extra[:3]}")
    return f"K_{name}", [terms.get(tuple(m), Fraction(0)) for m in sorted(support)]


#: a Gram row whose diagonal entry is below this (relative to the largest) is on the zero face
FACE_TOLERANCE = 1e-7
#: rounds of facial reduction (drop the zero face, re-solve) after an exact check fails
FACE_ROUNDS = 3


def zero_face(program: ConditionProgram, grams: Mapping[str, Any]) -> set[tuple[str, Monomial]]:
    """The basis monomials whose diagonal entries the solver left at (numerical) zero: the face the
    solution lies on, which a re-solve without them can enter the interior of."""
    out: set[tuple[str, Monomial]] = set()
    for g in program.grams:
        Q = grams.get(g.name)
        if Q is None or not len(g.basis):
            continue
        diag = [float(Q[i][i]) for i in range(len(g.basis))]
        top = max(max(diag), 1e-300)
        out |= {(g.name, g.basis[i]) for i, d in enumerate(diag) if d <= FACE_TOLERANCE * max(top, 1.0)}
    return out


def solve_on_faces(search: Any, build: Callable[[frozenset[tuple[str, Monomial]]], "ConditionProgram | str"],
                   values: Any, accept: Callable[[ConditionProgram, Any], T | None]) -> tuple[T | None, str]:
    """Solve, round and ``accept`` (an exact check); when the check refuses a point that lies on a
    face, drop that face and solve again (at most :data:`FACE_ROUNDS` times). Returns what
    ``accept`` gave, or None and why."""
    from lyapcheck.models.engines.search import why_none

    drop: frozenset[tuple[str, Monomial]] = frozenset()
    why = "nothing was solved"
    for _ in range(FACE_ROUNDS + 1):
        program = build(drop)
        if isinstance(program, str):
            return None, program
        point, solution = search.solve_exact(program.structure(), values)
        if point is not None:
            out = accept(program, point)
            if out is not None:
                return out, ""
        why = why_none(solution)
        if not solution.usable:
            return None, why
        face = zero_face(program, solution.grams) - drop
        if not face:
            return None, why
        drop = drop | face
    return None, why

"""``roa`` and ``candidate`` on a discrete-time map: a sublevel set ``{V <= c}`` proved to be a region of
attraction of ``e+ = F(e)`` (the equilibrium shifted to 0, ``F(0) = 0``, ``F`` polynomial), exactly.

The certificate (kind :data:`KIND`), in the declared shifted states:

    V(e) - V(F(e)) - eps m(e) - s(e) (c - V(e)) = sigma(e),

with ``V = z_V^T Q_V z_V``, ``Q_V > 0`` and a pure power of every state in ``z_V`` (positive definite,
radially unbounded: :func:`~lyapcheck.sos.certificates.check_positive_definite_v`), ``c > 0``, ``eps > 0``,
``s = z_s^T Q_s z_s`` and ``sigma = z^T Q_sigma z`` with ``Q_s, Q_sigma >= 0`` (exact), and the margin
``m(e) = sum_i e_i^(2 k_i)``, ``e_i^(k_i)`` the lowest pure power of ``e_i`` in ``z_V`` (``|e|^2`` for a
quadratic ``V``; :func:`margin_polynomial`, re-derived from ``V`` by ``verify``).

Why ``{V <= c}`` is a region of attraction of the map. On the set ``s >= 0`` and ``c - V >= 0``, so
``V(F(e)) <= V(e) - eps m(e)``: ``V`` strictly decreases along the map away from 0. Forward invariance:
``e_k`` in the set gives ``V(e_(k+1)) <= V(e_k) <= c``, so every iterate of a start in the set stays in it.
Convergence: summing the decrease, ``eps sum_(k<K) m(e_k) <= V(e_0) - V(e_K) <= V(e_0) <= c`` (``V >= 0``)
for every ``K``, so ``m(e_k) -> 0``, hence every ``|e_(k,i)| -> 0``: ``e_k -> 0``. And the fixed point is
stable: ``V`` is positive definite, so its small sublevel sets (invariant by the same argument) are small
neighbourhoods of 0. (No LaSalle argument is needed: the margin ``eps m`` gives the decrease a rate.)

``V``: for ``roa``, the linearization's quadratic ``V = e^T P e`` with ``A^T P A - P = -I`` (``A`` the
Jacobian of ``F`` at 0; the exact Stein solution of
:func:`~lyapcheck.models.classes.discrete_linearization.stein_solution`, scaled to a largest entry of 1 and
rounded to short rationals, then ``P > 0`` checked exactly), as the continuous ``roa`` starts from the
linearization's ``V``; for ``candidate``, the user's ``V`` (``--candidate``), shown positive definite by
:func:`~lyapcheck.models.classes.regions.gram_of`.

The level (:func:`largest_level`): for a fixed ``V`` the identity is linear in ``(s, eps, sigma)`` for each
``c``. One attempt solves it at one ``c`` (the rounding, correction and projection of
:mod:`lyapcheck.sos.rounding` through :meth:`~lyapcheck.models.engines.search.Search.exact`) and keeps the
level only when :func:`check_discrete_sublevel` passes; the levels tried are those of the monotone search
:func:`~lyapcheck.models.classes.level_search.largest_proved_level` from a sampled estimate of the largest
level (``min V`` over sampled ``e`` with ``V(F(e)) >= V(e)``): growth, halvings and bisections, each a
count, so that the outcome is the same on any machine, and a proved level is never lost.

As in continuous time, ``roa`` is ``not_applicable`` once ``quadratic`` or ``sos_gas`` certified GAS, and the
model's ``[domain]`` is where the certified set is compared with the simulated region of attraction (the
map iterated from a grid of starts: ``roa_share``); the set itself is not confined to the domain. Its size
in the user's terms is :mod:`lyapcheck.models.classes.region_size`'s (``size``: the largest ball, the reach
along each axis), attached by the runner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.models.classes.claims import discrete_region_sentence
from lyapcheck.models.classes.discrete_lyapunov import NotAMap, compose, map_degree, map_polynomials
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import EXACT_TRY_MARGIN, Budget, BudgetExhausted, ParameterValues, Search, \
    box_multipliers, box_multipliers_from_json, box_multipliers_of, box_support, literal, multiplier_grams, one, param
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import BoxMultipliers, GramPoly, box_terms, check_positive_definite_v
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from lyapcheck.models.classes.contexts import Candidate
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.loop.field import ShiftedField

#: the certificate kind (``verify`` dispatches on it; :mod:`lyapcheck.models.classes.claims` words it)
KIND: Final = "discrete_sublevel"
#: the level search (:func:`~lyapcheck.models.classes.level_search.largest_proved_level`), in counts:
#: levels tried upwards from a proved first level (each the last times LEVEL_GROWTH), ...
LEVEL_GROWTH: Final = Fraction(4)
LEVEL_GROWTH_STEPS: Final = 10
#: ... levels tried downwards from a failed first one (each half the last): 2^-16 of the estimate
LEVEL_HALVINGS: Final = 16
#: ... and halvings of the bracket between the largest proved and the smallest failed level
LEVEL_BISECTIONS: Final = 10
#: significant digits of a level as tried (rounded down: short certificates)
LEVEL_DIGITS: Final = 8
#: significant digits of the entries of the linearization's P (scaled to a largest entry of 1)
P_DIGITS: Final = 12
#: sampled directions and radii of the level estimate (min V where V(F) >= V)
ESTIMATE_DIRECTIONS: Final = 2000
ESTIMATE_RADII: Final = 200
#: the sampled ball's radius without a [domain] (with one: this many of its largest half-widths)
ESTIMATE_RADIUS: Final = 4.0
#: iterations of the map from each start of the [domain]'s grid (the simulated region of attraction) and the
#: distance to the fixed point, in the domain's largest half-width, below which a start counts as converged
ITERATIONS: Final = 500
CONVERGED_RADIUS: Final = 1e-6
#: a start whose iterate exceeds this times the domain's largest half-width counts as diverged
ESCAPE_RADIUS: Final = 1e6
#: a simulated iterate of a start in the set with V above the level times (1 + this) left the set: a
#: soundness alarm (floating-point slack only: the certificate proves V(e_k) <= level)
LEFT_SET_SLACK: Final = 1e-9
#: over a box, the multiplier ``s`` may carry the box's parameters up to this degree (as the continuous
#: classes' :data:`lyapcheck.models.classes.regions.MULTIPLIER_PARAM_DEGREE`: the set is common, the
#: decrease it needs is not)
BOX_MULTIPLIER_PARAM_DEGREE: Final = 1


# -- the certificate and its exact check --------------------------------------------------------------

def margin_polynomial(ring: Ring, V: GramPoly, n: int | None = None) -> Poly:
    """``m(e) = sum_i e_i^(2 k_i)``, ``e_i^(k_i)`` the lowest pure power of ``e_i`` in ``V``'s basis, over the
    ``n`` states (the ring's first variables; by default all of them, a box's parameters after them)
    (ValueError when a state has none: such a ``V`` is not positive definite either)."""
    n = ring.nvars if n is None else n
    m = ring.zero()
    for i in range(n):
        powers = [b[i] for b in V.basis if b[i] > 0 and sum(b) == b[i]]
        if not powers:
            raise ValueError(f"V's basis holds no pure power of {ring.names[i]}")
        m += ring.monomial(tuple(2 * min(powers) if k == i else 0 for k in range(ring.nvars)))
    return m


@dataclass(frozen=True)
class DiscreteSublevel:
    """A certificate of kind :data:`KIND` (module docstring), exact; over a box, with the S-procedure
    multipliers ``r_j`` of ``1 - u_j^2`` (``box``; the box itself is the document's)."""

    V: GramPoly
    level: Fraction
    eps: Fraction
    s: GramPoly
    sigma: GramPoly
    box: BoxMultipliers = ()

    def to_json(self, ring: Ring) -> dict[str, Any]:
        from lyapcheck.models.classes.lyapunov import terms_json

        out: dict[str, Any] = {"kind": KIND, "time": "discrete", "V": terms_json(ring, self.V.poly(ring)),
                               "level": str(self.level), "eps": str(self.eps), "gram_V": self.V.to_json(),
                               "gram_s": self.s.to_json(), "gram_sigma": self.sigma.to_json()}
        if self.box:
            out["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in self.box]
        return out

    @classmethod
    def from_json(cls, cert: Mapping[str, Any], nv: int) -> "DiscreteSublevel":
        return cls(GramPoly.from_json(cert["gram_V"], nv), Fraction(cert["level"]), Fraction(cert["eps"]),
                   GramPoly.from_json(cert["gram_s"], nv), GramPoly.from_json(cert["gram_sigma"], nv),
                   tuple(box_multipliers_from_json(cert.get("box_multipliers", []), nv)))


def check_discrete_sublevel(ring: Ring, F: Sequence[Poly], cert: DiscreteSublevel) -> tuple[bool, str]:
    """``V - V(F) - eps m - s (c - V) - sum_j r_j (1 - u_j^2) = sigma`` exactly, with ``c > 0``, ``eps > 0``,
    ``V`` positive definite, radially unbounded and of the states alone, ``Q_s, Q_sigma >= 0``, each ``r_j``
    PSD on a box variable (none at a point): then ``{V <= c}`` is a forward-invariant region of attraction
    of the map for every parameter value of the box (module docstring: on the box ``1 - u_j^2 >= 0``).
    Reads the certificate and the map alone."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n = len(F)
    if cert.level <= 0:
        return False, "the level c must be > 0"
    if cert.eps <= 0:
        return False, "the margin eps must be > 0"
    ok, why = check_positive_definite_v(cert.V, n)
    if not ok:
        return False, why
    if not is_positive_semidefinite(cert.s.Q) or not is_positive_semidefinite(cert.sigma.Q):
        return False, "Q_s or Q_sigma is not positive semidefinite (exact)"
    if any(any(m[n:]) for m in cert.V.basis):
        return False, "V must be a polynomial of the states alone (one set for every value of the box)"
    if any(not n <= j < ring.nvars for j, _ in cert.box):
        return False, "a box multiplier names a variable that is not one of the box's parameters"
    boxed, box_why = box_terms(ring, cert.box)
    if box_why is not None:
        return False, box_why
    v = cert.V.poly(ring)
    lhs = v - compose(ring, v, F) - margin_polynomial(ring, cert.V, n) * to_fmpq(cert.eps) \
        - cert.s.poly(ring) * (ring.constant(cert.level) - v) - boxed
    if lhs != cert.sigma.poly(ring):
        return False, ("the identity V - V(F) - eps m - s (c - V) = sigma does not hold exactly"
                       + (" (with the box's multipliers)" if cert.box else ""))
    if cert.box:
        return True, ("Q_V > 0, Q_s >= 0, Q_sigma >= 0, the box's multipliers PSD, eps > 0 and V - V(F) - eps m - "
                      "s (c - V) - sum r_j (1 - u_j^2) = sigma, exactly: V(F(e, u)) <= V(e) - eps m(e) on {V <= c} "
                      "for every value of the box (discrete-time map)")
    return True, ("Q_V > 0, Q_s >= 0, Q_sigma >= 0, eps > 0 and V - V(F) - eps m - s (c - V) = sigma, exactly: "
                  "V(F(e)) <= V(e) - eps m(e) on {V <= c} (discrete-time map)")


# -- the level program ----------------------------------------------------------------------------------

def level_symmetry(ring: Ring, F: Sequence[Poly], V: Poly) -> list[tuple[int, ...]]:
    """The sign changes ``S`` with ``F(S e) = S F(e)`` and ``V(S e) = V(e)`` (the margin is invariant under
    every one): the program is invariant, so ``s`` and ``sigma`` may be too."""
    return bases.sign_symmetries(ring.nvars, [(ring.support(fi), i) for i, fi in enumerate(F)]
                                 + [(ring.support(V), None)])


def multiplier_half_degree(ring: Ring, F: Sequence[Poly], V: Poly) -> int:
    """``s`` of degree ``2k``: ``deg(s V) >= deg V(F) = deg V deg F``, and ``k >= 1``."""
    dv = max(sum(m) for m in ring.support(V))
    return max(1, math.ceil(dv * (map_degree(ring, F) - 1) / 2))


def level_program(ring: Ring, F: Sequence[Poly], V: GramPoly, generators: Sequence[Sequence[int]],
                  drop: frozenset[Monomial] = frozenset()) -> Structure | str:
    """The level step's program for a fixed ``V`` (the level ``c`` a parameter), or why there is none (a
    size limit of the continuous classes, named): ``s (V - c) - eps m - sigma + (V - V(F)) = 0``, maximizing
    the margin ``t`` with ``Q_s, Q_sigma >= t I`` and ``eps >= t``. ``drop``: monomials ``sigma``'s basis
    leaves out (facial reduction)."""
    from lyapcheck.models.classes.lyapunov import CANDIDATE_LIMIT, MAX_GRAM_ROWS, TARGET_LIMIT, within_cost
    from lyapcheck.models.engines.reasons import size_limit

    nv, n = ring.nvars, len(F)
    zero = tuple([0] * nv)
    v = V.poly(ring)
    decrease = v - compose(ring, v, F)
    ks = multiplier_half_degree(ring, F, v)
    dv = max(sum(m) for m in ring.support(v))
    pd = BOX_MULTIPLIER_PARAM_DEGREE if nv > n else 0  # over a box, s may depend on the box's parameters
    if bases.candidate_count(nv, max(dv * map_degree(ring, F), 2 * ks + dv) + 2 * pd) > CANDIDATE_LIMIT:
        return size_limit(bases.candidate_count(nv, 2 * ks + dv + 2 * pd), "candidate monomials", CANDIDATE_LIMIT,
                          "CANDIDATE_LIMIT")
    # (at a point nv == n and pd == 0: the monomials of degree 1 to ks of the states, as ever)
    z_s = [m for m in monomials(nv, 1, ks + pd) if 1 <= sum(m[:n]) <= ks and sum(m[n:]) <= pd]
    s_blocks = bases.character_blocks(z_s, generators)
    v_support = set(ring.support(v)) | {zero}
    margin = margin_polynomial(ring, V, n)
    s_products = {tuple(a + b for a, b in zip(z_s[i], z_s[j])) for idx in s_blocks for i in idx for j in idx}
    target = set(ring.support(decrease)) | set(ring.support(margin)) \
        | {tuple(a + b for a, b in zip(m, q)) for m in s_products for q in v_support}
    # over a box: - sum_j r_j (1 - u_j^2), the multipliers' bases matched to the identity's other terms
    box_grams, box_terms_ = box_multipliers(nv, n, target, with_states=True, generators=generators)
    target |= box_support(box_grams, nv)
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    z_sigma = [m for m in bases.sos_basis(nv, target) if m not in drop]
    if not z_sigma:
        return "no strict certificate of this form exists (sigma's basis is empty)"
    if max(len(z_sigma), len(z_s)) > MAX_GRAM_ROWS:
        return size_limit(max(len(z_sigma), len(z_s)), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS,
                          "MAX_GRAM_ROWS")
    sigma_blocks = bases.character_blocks(z_sigma, generators)
    terms = (Term(param("Vc", v_support), "s"), Term(literal(ring, {m: -c for m, c in ring.terms(margin).items()}),
                                                     "eps"),
             *box_terms_, Term(one(ring, -1), "sigma"))
    structure = Structure(nvars=nv, grams=(Gram("s", tuple(z_s), tuple(map(tuple, s_blocks))),
                                           Gram("sigma", tuple(z_sigma), tuple(map(tuple, sigma_blocks))), *box_grams),
                          scalars=(Scalar("eps", lower="margin"),),
                          identities=(Identity(KIND, terms, param("DV", ring.support(decrease) or [zero]), "sigma"),),
                          objective=("max_margin",))
    return within_cost(structure)


def level_values(ring: Ring, F: Sequence[Poly], V: GramPoly, structure: Structure, level: Fraction
                 ) -> ParameterValues:
    v = V.poly(ring)
    ident = structure.identities[0]
    values = ParameterValues()
    values.set_poly(ring, "DV", v - compose(ring, v, F), ident.constant.support)  # type: ignore[union-attr]
    values.set_poly(ring, "Vc", v - ring.constant(level), ident.terms[0].coefficients.support)
    return values


class LevelProgram:
    """The level attempts of one ``V`` on one map: one program (rebuilt without the monomials a solve shows
    vanishing, at most :data:`~lyapcheck.models.classes.lyapunov.FACIAL_ROUNDS` times in all), one solve and
    one exact check per attempt."""

    def __init__(self, ring: Ring, F: Sequence[Poly], V: GramPoly, search: Search) -> None:
        self.ring, self.F, self.V, self.search = ring, tuple(F), V, search
        self.generators = level_symmetry(ring, F, V.poly(ring))
        self.drop: frozenset[Monomial] = frozenset()
        self.rounds = 0
        self.built = level_program(ring, F, V, self.generators)

    def attempt(self, level: Fraction) -> DiscreteSublevel | None:
        """The exact certificate at ``level``, or None."""
        from lyapcheck.models.classes.lyapunov import FACIAL_ROUNDS, vanishing_monomials

        while isinstance(self.built, Structure):
            structure = self.built
            self.search.budget.check()
            values = level_values(self.ring, self.F, self.V, structure, level)
            solution = self.search.solve(structure, values)
            if solution.usable and solution.scalars.get("t", -1.0) >= -EXACT_TRY_MARGIN:
                point = self.search.exact(structure, solution, values)
                if point is not None:
                    cert = DiscreteSublevel(self.V, level, point.scalars["eps"],
                                            GramPoly.of(structure.gram("s").basis, point.grams["s"]),
                                            GramPoly.of(structure.gram("sigma").basis, point.grams["sigma"]),
                                            tuple(box_multipliers_of(point.grams, multiplier_grams(structure))))
                    if check_discrete_sublevel(self.ring, self.F, cert)[0]:
                        return cert
            vanishing = vanishing_monomials(structure.gram("sigma"), solution)
            if not vanishing or self.rounds >= FACIAL_ROUNDS:
                return None
            reduced = level_program(self.ring, self.F, self.V, self.generators, self.drop | vanishing)
            if isinstance(reduced, str):
                return None
            self.drop, self.built, self.rounds = self.drop | vanishing, reduced, self.rounds + 1
        return None


def largest_level(ring: Ring, F: Sequence[Poly], V: GramPoly, search: Search, first: Fraction
                  ) -> tuple[DiscreteSublevel | None, str]:
    """The largest proved level of ``V`` (the monotone search from ``first``) and what ended the search
    early ("" when its counts did), or None and why none was proved."""
    from lyapcheck.exact import floor_digits
    from lyapcheck.models.classes.level_search import largest_proved_level

    program = LevelProgram(ring, F, V, search)
    if isinstance(program.built, str):
        return None, program.built
    found = largest_proved_level(program.attempt, floor_digits(first, LEVEL_DIGITS), growth=LEVEL_GROWTH,
                                 growth_steps=LEVEL_GROWTH_STEPS, halvings=LEVEL_HALVINGS,
                                 bisections=LEVEL_BISECTIONS, rounded=lambda x: floor_digits(x, LEVEL_DIGITS))
    if found.proof is None:
        tried = ", ".join(f"{float(c):.6g}" for c, _ in found.tried)
        return None, f"no level of V passed the exact check (levels tried: {tried})"
    return found.proof, found.stopped


# -- sampling: the level's first estimate and the simulated region of attraction -------------------------

def level_estimate(ring: Ring, F: Sequence[Poly], V: Poly, radius: float) -> tuple[float, bool]:
    """``min V`` over sampled ``e`` (a ball of ``radius``) where ``V(F(e)) >= V(e)``, ``e != 0``: a numerical
    upper bound of the largest provable level, and True; where no sample has it, ``max V`` over the
    samples and False (the search then grows the level from there). Over a box, the samples are taken at
    its centre and its corners (:func:`lyapcheck.models.classes.regions.box_samples`): the set is common."""
    import numpy as np

    from lyapcheck.models.classes.regions import box_samples
    from lyapcheck.models.engines.numeric import NumericPoly

    n = len(F)
    rng = np.random.default_rng(20261129)
    directions = rng.normal(size=(ESTIMATE_DIRECTIONS, n))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = np.linspace(radius / ESTIMATE_RADII, radius, ESTIMATE_RADII)
    states = (directions[:, None, :] * radii[None, :, None]).reshape(-1, n)
    points = np.vstack([np.hstack([states, np.tile(u, (states.shape[0], 1))]) for u in box_samples(ring.nvars - n)])
    v_num = NumericPoly(ring, V)
    dv_num = NumericPoly(ring, compose(ring, V, F) - V)
    with np.errstate(all="ignore"):
        v, dv = v_num(points), dv_num(points)
    rising = np.isfinite(dv) & (dv >= 0)
    if np.any(rising):
        return float(np.min(v[rising])), True
    return float(np.max(v[np.isfinite(v)])), False


def simulated_region(ring: Ring, F: Sequence[Poly], starts: "np.ndarray", half: float) -> "np.ndarray":
    """Which starts (shifted states, rows) converge to 0 under :data:`ITERATIONS` iterations of the map
    (within :data:`CONVERGED_RADIUS` times ``half``, the domain's largest half-width; one beyond
    :data:`ESCAPE_RADIUS` times it, or not finite, diverged)."""
    import numpy as np

    from lyapcheck.models.engines.iteration import iterate_map, stacked_map
    from lyapcheck.models.engines.numeric import NumericPoly

    f = stacked_map([NumericPoly(ring, fi) for fi in F])
    x, alive = iterate_map(f, starts, ITERATIONS, escape=ESCAPE_RADIUS * half)
    return alive & np.all(np.abs(np.where(alive[:, None], x, 0.0)) <= CONVERGED_RADIUS * half, axis=1)


def left_set(ring: Ring, F: Sequence[Poly], V: Poly, level: float, starts: "np.ndarray") -> int:
    """How many of ``starts`` (in the set) have an iterate, within :data:`ITERATIONS`, with ``V`` above the
    level (beyond :data:`LEFT_SET_SLACK`): 0 unless the certificate is wrong (a soundness alarm)."""
    import numpy as np

    from lyapcheck.models.engines.iteration import iterate_map, stacked_map
    from lyapcheck.models.engines.numeric import NumericPoly

    v_num = NumericPoly(ring, V)
    out = np.zeros(len(starts), dtype=bool)

    def above(k: int, rows: "np.ndarray", x: "np.ndarray") -> None:
        out[rows] |= ~(v_num(x) <= level * (1 + LEFT_SET_SLACK))

    # every row every step (no escape box): a row that runs away counts from its first iterate above the level
    iterate_map(stacked_map([NumericPoly(ring, fi) for fi in F]), starts, ITERATIONS, observe=above)
    return int(np.sum(out))


# -- the classes ----------------------------------------------------------------------------------------

def stein_v(ring: Ring, F: Sequence[Poly]) -> GramPoly | None:
    """The linearization's ``V = e^T P e`` (module docstring), or None when ``A^T P A - P = -I`` has no
    solution or its rounded ``P`` is not positive definite (exact)."""
    from lyapcheck.exact import to_rational
    from lyapcheck.models.classes.discrete_linearization import stein_solution
    from lyapcheck.sos.definiteness import is_positive_definite

    n = ring.nvars
    A = [[ring.terms(fi).get(tuple(int(k == j) for k in range(n)), Fraction(0)) for j in range(n)] for fi in F]
    P = stein_solution([[Fraction(x) for x in row] for row in A])
    if P is None:
        return None
    scale = max(abs(x) for row in P for x in row)
    P = [[to_rational(float(x / scale), P_DIGITS) for x in row] for row in P]
    if not is_positive_definite(P):
        return None
    basis = [tuple(int(k == i) for k in range(n)) for i in range(n)]
    return GramPoly.of(basis, P)


def at_centre(ring: Ring, F: Sequence[Poly]) -> tuple[Ring, tuple[Poly, ...]]:
    """The map at the box's centre (``u = 0``) in the ring of the states alone; the map itself at a point."""
    n = len(F)
    if ring.nvars == n:
        return ring, tuple(F)
    states = Ring(ring.names[:n])
    centre = {name: Fraction(0) for name in ring.names[n:]}
    return states, tuple(ring.restrict(ring.substitute(fi, centre), states) for fi in F)


def on_box(V: GramPoly, nv: int) -> GramPoly:
    """A ``V`` of the states alone (its basis over the states) in the ring of the states and a box's
    parameters (the basis padded with exponents 0: one ``V`` for every value of the box)."""
    pad = nv - len(V.basis[0])
    return V if pad == 0 else GramPoly.of([tuple(b) + (0,) * pad for b in V.basis], V.Q)


def on_states(V: GramPoly, n: int) -> GramPoly:
    """The inverse of :func:`on_box`: a ``V`` of the states alone with its basis over the ``n`` states."""
    if any(any(b[n:]) for b in V.basis):
        raise ValueError("V depends on the box's parameters")
    return GramPoly.of([tuple(b[:n]) for b in V.basis], V.Q)


def _ring_map(shifted: "ShiftedField", name: str) -> tuple[Ring, tuple[Poly, ...]] | ConditionResult:
    try:
        return map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult(name, "not_applicable", f"not a polynomial map: {exc}")


def _radius(model: "Model") -> float:
    """The sampled ball's radius (shifted states): :data:`ESTIMATE_RADIUS` times the domain's largest
    half-width about the fixed point, or :data:`ESTIMATE_RADIUS` without a domain."""
    return ESTIMATE_RADIUS * _half_width(model)


def _half_width(model: "Model") -> float:
    if not model.domain:
        return 1.0
    return max(max(abs(float(model.domain[s][0] - e)), abs(float(model.domain[s][1] - e)))
               for s, e in zip(model.states, model.equilibrium))


def region(name: str, model: "Model", ring: Ring, F: Sequence[Poly], V: GramPoly, budget: Budget,
           what: str) -> ConditionResult:
    """The largest proved level of ``V`` as the class's result: certified with its set, the simulated
    figures over the ``[domain]`` (estimates), or not_certified / inconclusive with the reason."""
    search = Search(ring, budget)
    v = V.poly(ring)
    estimate, bounded = level_estimate(ring, F, v, _radius(model))
    numbers: dict[str, Any] = {}
    if bounded:
        numbers["level_supremum_estimate"] = estimate
    first = Fraction(estimate) if estimate > 0 else Fraction(1)
    try:
        cert, stopped = largest_level(ring, F, V, search, first)
    except BudgetExhausted as exc:
        late = reasons.out_of_time(f"a region of attraction of the discrete-time map ({what})", budget.seconds,
                                   str(exc), ("time",))
        return ConditionResult(name, "inconclusive", late.summary, property="ROA", solver={"solves": search.log},
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}))
    if cert is None:
        steps = ("other_candidate", "time") if name == "candidate" else ("candidate", "time")
        none = reasons.reason(f"no region of attraction of the discrete-time map was proved: no level set of "
                              f"{what} could be proved to shrink along the map", steps, stopped)
        return ConditionResult(name, "not_certified", none.summary, property="ROA", solver={"solves": search.log},
                               numbers=none.numbers({**numbers, "time": "discrete"}))
    numbers = {"level": float(cert.level), "degree": 2 * max(sum(m) for m in V.basis), **numbers}
    if bounded:
        numbers["level_ratio_to_estimate"] = float(cert.level) / estimate
    numbers.update(_simulated(model, ring, F, cert))
    result = ConditionResult(name, "certified", discrete_region_sentence(name, float(cert.level)), numbers=numbers,
                             certificate=cert.to_json(ring), solver={"solves": search.log}, property="ROA")
    if stopped:
        result.solver["stopped"] = stopped
    return result


def _simulated(model: "Model", ring: Ring, F: Sequence[Poly], cert: DiscreteSublevel) -> dict[str, Any]:
    """The certified set against the map iterated from a grid of the ``[domain]`` (nothing without one):
    ``roa_share`` and ``simulated_roa_share_of_domain`` as in continuous time, and a soundness alarm where a
    start in the set leaves it."""
    if not model.domain:
        return {}
    import numpy as np

    from lyapcheck.models.classes.field_regions import roa_starts
    from lyapcheck.models.engines.numeric import NumericPoly

    # over a box, the map at its centre (an estimate; the certificate holds for every value)
    ring, F = at_centre(ring, F)
    eq = np.array([float(x) for x in model.equilibrium])
    starts = roa_starts(model) - eq
    converged = simulated_region(ring, F, starts, _half_width(model))
    v = on_states(cert.V, ring.nvars).poly(ring)
    inside = NumericPoly(ring, v)(starts) <= float(cert.level)
    out: dict[str, Any] = {"simulated_starts": int(len(starts)),
                           "simulated_roa_share_of_domain": float(np.mean(converged))}
    if converged.any():
        out["roa_share"] = float(np.mean(inside[converged]))
    left = left_set(ring, F, v, float(cert.level), starts[inside]) if inside.any() else 0
    if left:
        out["starts_left_set"] = left
        out["soundness_violation"] = True
    return out


def box_stein_v(ring: Ring, F: Sequence[Poly], budget: Budget) -> GramPoly | None:
    """Over a box: a quadratic ``V`` whose decrease along the Jacobian map ``A(u) e`` is proved for every
    value of the box (the certificate of ``linearization`` over a box,
    :func:`lyapcheck.models.classes.discrete_lyapunov.run_linearization_box`'s program), or None. The centre's
    Stein ``V`` need not decrease at the box's corners; this one does, near the fixed point."""
    from lyapcheck.models.classes.discrete_lyapunov import jacobian_map, search_degree

    found, _ = search_degree(ring, jacobian_map(ring, F), 2, Search(ring, budget))
    return None if found is None else found["V"]


def run_roa(model: "Model", shifted: "ShiftedField", budget: Budget) -> ConditionResult:
    """``roa`` on the map: the largest proved level of the linearization's quadratic ``V`` (over a box, one
    common to the box's Jacobians, :func:`box_stein_v`, and one level for every value of the box)."""
    found = _ring_map(shifted, "roa")
    if isinstance(found, ConditionResult):
        return found
    ring, F = found
    if ring.nvars > len(F):
        try:
            V = box_stein_v(ring, F, budget)
        except BudgetExhausted as exc:
            late = reasons.out_of_time("a quadratic V common to the box's Jacobians", budget.seconds, str(exc),
                                       ("time",))
            return ConditionResult("roa", "inconclusive", late.summary, property="ROA",
                                   numbers=late.numbers({"reason": str(exc), "time": "discrete"}))
        if V is None:
            why = reasons.reason("no P > 0 with A(p)^T P A(p) - P < 0 for every p of the box was found (see "
                                 "linearization), so no quadratic V common to the box starts the search",
                                 ("candidate",), "a narrower box, or certify a point with --set NAME=VALUE")
            return ConditionResult("roa", "not_certified", why.summary, numbers=why.numbers({"time": "discrete"}),
                                   property="ROA")
        return region("roa", model, ring, F, V, budget, "the quadratic V common to the box's linearizations")
    V = stein_v(ring, F)
    if V is None:
        why = reasons.reason("A^T P A - P = -I has no positive definite solution P for the map's Jacobian A at the "
                             "fixed point (not every eigenvalue has modulus < 1), so no quadratic V starts the search "
                             "(see linearization)", ("candidate",))
        return ConditionResult("roa", "not_certified", why.summary, numbers=why.numbers({"time": "discrete"}),
                               property="ROA")
    return region("roa", model, ring, F, V, budget, "the linearization's quadratic V")


def run_candidate(model: "Model", shifted: "ShiftedField", cand: "Candidate", budget: Budget) -> ConditionResult:
    """``candidate`` on the map: the user's ``V`` (shifted to the fixed point), shown positive definite, then
    its largest proved level."""
    from lyapcheck.models.classes.regions import gram_of
    from lyapcheck.models.loop.field import StateField

    found = _ring_map(shifted, "candidate")
    if isinstance(found, ConditionResult):
        return found
    ring, F = found
    full = model.state_ring
    gens = full.gens()
    images = [g + to_fmpq(e) for g, e in zip(gens[:model.n], model.equilibrium)] + list(gens[model.n:])
    # V is of the states alone (over a box, one V for every value: a parameter in the text is the model's value,
    # parse_candidate), shown positive definite in their ring, then read in the map's
    states, F_states = at_centre(ring, F)
    v = full.restrict(full.compose(cand.poly, images), states)
    shown = gram_of(StateField(ring=states, g=F_states, D=states.constant(1)), v, Search(states, budget))
    V = None if shown is None else on_box(shown, ring.nvars)
    if V is None:
        why = reasons.reason("the candidate V could not be proved positive definite and radially unbounded",
                             ("other_candidate",), "no positive definite Gram matrix over its reduced basis with a "
                             "pure power of every state")
        return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers({"time": "discrete"}),
                               property="ROA")
    return region("candidate", model, ring, F, V, budget, "the candidate V")


# -- verify ---------------------------------------------------------------------------------------------

def verify(shifted: "ShiftedField", name: str, c: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a certified ``roa`` or ``candidate`` of a map from its JSON and the map alone, without a
    solver: the identity and the signs exactly (:func:`check_discrete_sublevel`), the stated ``V`` the Gram
    ``V``, the stated level at most the certified one, the property and the sentence. Over a box the map is
    re-derived with the box's coordinates (``shifted``), so a box widened after the fact fails the identity."""
    if c.get("status") != "certified":
        return True, f"status {c.get('status')}: no certificate to check"
    try:
        cert = c["certificate"]
        if cert.get("kind") != KIND or cert.get("time") != "discrete":
            return False, f"not a region certificate of a discrete-time map (kind {cert.get('kind')!r})"
        ring, F = map_polynomials(shifted)
        found = DiscreteSublevel.from_json(cert, ring.nvars)
        stated = c["level"]
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, NotAMap) as exc:
        return False, f"malformed certificate: {exc}"
    if found.box and shifted.box is None:
        return False, "box multipliers in the certificate of a map without a box"
    try:
        ok, why = check_discrete_sublevel(ring, F, found)
    except ValueError as exc:
        return False, str(exc)
    if not ok:
        return False, why
    from lyapcheck.models.classes.lyapunov import terms_json

    if terms_json(ring, found.V.poly(ring)) != cert.get("V"):
        return False, "the stated V is not the certificate's Gram V"
    if isinstance(stated, bool) or not isinstance(stated, (int, float)) or stated > float(found.level):
        return False, "the stated level exceeds the certified one"
    if c.get("property") != "ROA":
        return False, f"a {KIND} certificate proves a region of attraction (ROA), not {c.get('property')}"
    return True, why


__all__ = ["KIND", "DiscreteSublevel", "margin_polynomial", "check_discrete_sublevel", "level_program",
           "largest_level", "level_estimate", "simulated_region", "stein_v", "box_stein_v", "at_centre", "on_box",
           "on_states", "run_roa", "run_candidate", "verify"]

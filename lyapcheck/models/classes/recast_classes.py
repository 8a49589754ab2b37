"""The classes on a recast (non-polynomial) loop: ``linearization`` (``quadratic`` and ``sos_gas``:
:mod:`lyapcheck.models.classes.lyapunov_relations`; ``roa`` and ``candidate``'s sublevel sets:
:mod:`lyapcheck.models.classes.regions`), on this module's loop and proofs.

Coordinates: the deviations from the equilibrium of the states and of every non-constant
auxiliary (:meth:`lyapcheck.models.language.recast.RecastSystem.shift`); the constant roots stay. A
Lyapunov function ``V`` is a polynomial in the states and the smooth auxiliaries. Each condition is
proved on the set ``S`` of the recasting's relations (:mod:`lyapcheck.models.engines.recast_sos`), which
holds every point ``(z, a(z))`` of the true loop:

- positivity ``V - eps |z|^2 >= 0`` on S (so ``V(z, a(z)) >= eps |z|^2``: positive definite and
  radially unbounded in the **states**, whatever the auxiliaries do);
- decrease ``-grad V . N - eps |z|^2 >= 0`` on S, with ``x' = N / D`` and ``D > 0`` proved on S
  (each distinct factor of the denominators, :func:`prove_denominators`);
- for a region, the decrease only where ``V <= level`` (a multiplier ``rho`` times ``V - level``).

Then ``roa`` proves that every trajectory of the true loop starting where ``V(x, a(x)) <= level`` (a bounded set, by the
positivity) converges to the equilibrium. A loop that enters only through ``sin`` and ``cos`` of an
angle has its other equilibria (``k pi``) in every such set's complement: no global claim can be
proved (none is false-certified: the identities would have to hold at those points too).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.models.engines import reasons
from lyapcheck.models.language.expressions import Rational
from lyapcheck.models.language.recast import RecastSystem, Relation, written_poly
from lyapcheck.models.engines.recast_sos import (ConditionCertificate, ConditionProgram, check_condition, known_values,
                                         poly_from_json, poly_to_json, solve_on_faces)
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, degree_in, to_fmpq
from lyapcheck.exact import read_rational

if TYPE_CHECKING:
    from lyapcheck.models.language.parameter_box import ModelBox

#: the margin eps of positivity and decrease (times |z|^2), tried in turn
EPSILONS: Final = (Fraction(1, 100), Fraction(1, 10000))


# -- the loop in deviations -------------------------------------------------------------------------

@dataclass
class Loop:
    """The recast loop in deviations, with its relations (the system's, shifted, then the proved
    lower bounds ``r - c >= 0`` of square roots) and what proved them."""

    system: RecastSystem
    relations: list[Relation]
    #: per square root with a proved lower bound: (c, its proof on the system's relations)
    root_bounds: dict[str, tuple[Fraction, ConditionCertificate]] = field(default_factory=dict)
    #: the angle states (:func:`angle_states`), each with its (sine, cosine) names: the loop lives
    #: on a cylinder and every claim is modulo 2 pi in them
    angles: dict[str, tuple[str, str]] = field(default_factory=dict)
    #: the system's last "states" that are bounded constants, not states: a box's parameters and
    #: disturbances, recast as variables without a flow (:func:`lyapcheck.models.language.recast.recast_with_constants`),
    #: each with the half-width of its interval around its value; a Lyapunov function never uses
    #: them nor an auxiliary of them (its recast flow is that of a constant)
    fixed: dict[str, Fraction] = field(default_factory=dict)
    #: the square roots whose bound's proof also used the bounded constants' relations (a root of
    #: a box's parameter, ``sqrt(Delta^2 + e^2) >= Delta_lo``); the others' proofs hold for any value
    root_constants: frozenset[str] = frozenset()

    @property
    def ring(self) -> Ring:
        return self.system.ring

    @property
    def n(self) -> int:
        return self.system.n

    @property
    def n_states(self) -> int:
        """The number of true states (the system's first ones; :attr:`fixed` follow them)."""
        return self.system.n - len(self.fixed)

    def states(self) -> tuple[str, ...]:
        """The true states (not the bounded constants of :attr:`fixed`)."""
        return self.system.states[:self.n_states]

    def of_fixed(self) -> set[str]:
        """The bounded constants and every auxiliary whose argument uses one (directly or through another)."""
        ring = self.ring
        moved = set(self.fixed)
        for a in self.system.auxiliaries:
            if a.argument is not None and any(degree_in(ring, a.argument, [n]) > 0 for n in moved):
                moved.add(a.name)
        return moved

    def v_variables(self) -> list[int]:
        """The indices of the variables V may use: the states (not the angles) and the smooth auxiliaries,
        none of :meth:`of_fixed`."""
        moved = self.of_fixed() if self.fixed else set()
        names = [n for n in self.states() + self.system.smooth() if n not in self.angles and n not in moved]
        return [self.ring.names.index(n) for n in names]

    def roots(self) -> frozenset[int]:
        """The constant roots' indices (``rt2``, ``rt3``)."""
        return frozenset(self.ring.names.index(n) for n in self.system.roots())

    def unused(self) -> frozenset[int]:
        """The angles' indices: they appear in no identity (their sine and cosine do)."""
        return frozenset(self.ring.names.index(a) for a in self.angles)

    def square_free(self) -> frozenset[int]:
        """The variables whose squares a relation reduces
        (:attr:`~lyapcheck.models.engines.recast_sos.ConditionProgram.square_free`): each square root
        (``r^2 = q``) and each angle's cosine (``c^2 = 1 - s^2``)."""
        roots = {a.name for a in self.system.auxiliaries if a.function == "sqrt" and a.smooth and a.radicand is None}
        cosines = {cosine for _, cosine in self.angles.values()}
        return frozenset(self.ring.names.index(n) for n in roots | cosines)

    def coordinates(self) -> list[int]:
        """The states V may use: every state but the angles (an angle enters through its sine and cosine)."""
        return [i for i, s in enumerate(self.states()) if s not in self.angles]

    def flow(self, name: str) -> Rational:
        """A state's or smooth auxiliary's flow, shifted."""
        s = self.system
        r = s.field[s.states.index(name)] if name in s.states else s.flows[name]
        return Rational(self.ring, s.shift(r.numerator), s.shift(r.denominator)).normalized()


#: the owner of a bounded constant's relation (:attr:`Loop.fixed`); a square root's bound is proved
#: without it first, then with it (:func:`prove_root_bounds`, :attr:`Loop.root_constants`)
CONSTANT: Final = "constant"


def base_loop(system: RecastSystem, cylinder: bool = True, fixed: Mapping[str, Fraction] | None = None) -> Loop:
    """The loop in deviations with the system's relations; ``cylinder``: its angles
    (:func:`angle_states`) taken modulo 2 pi (their relations with the angle itself left out);
    ``fixed``: the last "states" that are bounded constants (:attr:`Loop.fixed`), each with its
    relation ``h^2 - dv^2 >= 0`` (``v`` within ``h`` of its value)."""
    fixed = dict(fixed or {})
    angles = {a: sc for a, sc in angle_states(system).items() if a not in fixed} if cylinder else {}
    ring = system.ring
    relations = [Relation(r.kind, system.shift(r.poly), r.why, r.owner) for r in system.relations
                 if not any(degree_in(ring, r.poly, [a]) > 0 for a in angles)]
    for name, h in fixed.items():
        centre = system.values[name]
        g = ring.gen(name)
        why = f"|{name}| <= {h}" if centre == 0 else f"{name} in [{centre - h}, {centre + h}]"
        relations.append(Relation("ge", ring.constant(h * h) - g * g, why, CONSTANT))
    return Loop(system, relations, angles=angles, fixed=fixed)


def for_v(loop: Loop, V: Poly) -> Loop:
    """The loop a given V is proved on: on the cylinder, unless V uses an angle itself (a user's
    candidate may): then the angle is a state like any other, with every relation that ties it to
    its sine and cosine, and the claim is not modulo 2 pi."""
    ring = loop.ring
    if not any(degree_in(ring, V, [a]) > 0 for a in loop.angles):
        return loop
    return with_root_bounds(base_loop(loop.system, cylinder=False, fixed=loop.fixed), dict(loop.root_bounds),
                            loop.root_constants)


def angle_states(system: RecastSystem) -> dict[str, tuple[str, str]]:
    """The states that enter the loop only through the sine and cosine of themselves (a pendulum's
    angle): nowhere in the field, the flows, or another function's argument. The loop is then
    periodic in them; its certificates use the sine and cosine instead, and prove what holds on the
    cylinder (convergence modulo 2 pi)."""
    ring = system.ring
    out: dict[str, tuple[str, str]] = {}
    for theta in system.states:
        pair = [a for a in system.auxiliaries if a.function in ("sin", "cos") and a.argument is not None
                and a.argument == ring.gen(theta)]
        if len(pair) != 2 or not all(a.smooth for a in pair):
            continue
        others = [a for a in system.auxiliaries if a.argument is not None and a not in pair]
        polys = [r.numerator for r in system.field] + [r.denominator for r in system.field] + \
            [r.numerator for r in system.flows.values()] + [r.denominator for r in system.flows.values()] + \
            [a.argument for a in others if a.argument is not None]
        if any(degree_in(ring, p, [theta]) > 0 for p in polys):
            continue
        sine = next(a.name for a in pair if a.function == "sin")
        cosine = next(a.name for a in pair if a.function == "cos")
        out[theta] = (sine, cosine)
    return out


def with_root_bounds(loop: Loop, bounds: dict[str, tuple[Fraction, ConditionCertificate]],
                     constants: frozenset[str] = frozenset()) -> Loop:
    """The loop with ``r - c >= 0`` for every proved square root bound (in the auxiliaries' order);
    ``constants``: the roots whose proofs used the bounded constants' relations."""
    relations = list(loop.relations)
    for a in loop.system.auxiliaries:
        if a.name in bounds:
            c = bounds[a.name][0]
            relations.append(Relation("ge", loop.system.shift(loop.ring.gen(a.name)) - to_fmpq(c),
                                      f"{a.name} >= {c} (sqrt of an argument proved >= {c * c})", "derived"))
    return Loop(loop.system, relations, dict(bounds), dict(loop.angles), dict(loop.fixed),
                frozenset(n for n in constants if n in bounds))


def common_denominator(loop: Loop, names: Sequence[str]) -> tuple[dict[str, Poly], Poly, list[Poly]]:
    """``N`` and ``D`` with each flow ``= N / D``: ``D`` the least common multiple of the
    denominators, as the product of its irreducible factors (each signed to be positive at the
    equilibrium, so that proving each positive proves ``D`` positive), and those factors."""
    flows = {n: loop.flow(n) for n in names}
    lcm = loop.ring.constant(1)
    for r in flows.values():
        if not r.denominator.is_constant():
            lcm = lcm * r.denominator / lcm.gcd(r.denominator)
    D = loop.ring.constant(1)
    distinct: list[Poly] = []
    for factor, power in lcm.factor()[1]:
        if factor.is_constant():
            continue
        factor = factor * (1 / factor.leading_coefficient())
        if _at_origin_sign(loop, factor) < 0:
            factor = -factor
        distinct.append(factor)
        D = D * factor ** int(power)
    N = {}
    for n, r in flows.items():
        if r.denominator.is_constant():
            N[n] = r.numerator * D * (1 / r.denominator.leading_coefficient())
        else:
            N[n] = r.numerator * (D / r.denominator)  # exact: D is a multiple of every denominator
        assert N[n] * r.denominator == r.numerator * D, "N / D is not the flow"  # the identity, exactly
    return N, D, distinct


# -- single proofs: F >= 0 on S -----------------------------------------------------------------------

def prove_nonnegative(loop: Loop, F: Poly, search: Search, name: str) -> ConditionCertificate | None:
    """An exact certificate of ``F >= 0`` on the loop's relations, or None."""
    ring = loop.ring
    support = ring.support(F) or [tuple([0] * ring.nvars)]
    vanishing = _at_origin(loop, F) == 0  # then no term of the identity has a constant (nor a root alone)

    def build(drop: frozenset[tuple[str, Monomial]]) -> ConditionProgram | str:
        program = ConditionProgram(ring, loop.relations, drop, loop.unused(), roots=loop.roots())
        return program.condition(name, support, [], max(sum(m) for m in support), vanishing=vanishing) or program

    def accept(program: ConditionProgram, point: Any) -> ConditionCertificate | None:
        cert = program.certificate(name, point)
        return cert if check_condition(ring, F, loop.relations, cert)[0] else None

    values = ParameterValues()
    _set(values, *known_values(ring, name, F, support))
    return solve_on_faces(search, build, values, accept)[0]


def _set(values: ParameterValues, key: str, exact: list[Fraction]) -> None:
    import numpy as np

    values.exact[key] = exact
    values.floats[key] = np.array([float(c) for c in exact])


def base_loop_of(loop: Loop) -> Loop:
    """The loop with the system's relations only (no derived bound)."""
    return Loop(loop.system, [r for r in loop.relations if r.owner != "derived"], angles=dict(loop.angles),
                fixed=dict(loop.fixed))


def _restricted(loop: Loop, owners: set[str], bounds: dict[str, tuple[Fraction, "ConditionCertificate"]]) -> Loop:
    """The relations of the auxiliaries (or :data:`CONSTANT`) in ``owners`` only, with the bounds proved
    for them."""
    kept = Loop(loop.system, [r for r in loop.relations if r.owner in owners], angles=dict(loop.angles),
                fixed=dict(loop.fixed))
    return with_root_bounds(kept, {k: v for k, v in bounds.items() if k in owners and v[0] > 0})


def root_loop(base: Loop, name: str, bounds: dict[str, tuple[Fraction, "ConditionCertificate"]],
              constants: bool = False) -> Loop:
    """What the proof of square root ``name``'s bound may use: the relations of the auxiliaries
    made before it, and their proved bounds (its own relation r^2 = q presupposes q >= 0); with
    ``constants``, the bounded constants' relations too (a box's parameter inside the root)."""
    names = [a.name for a in base.system.auxiliaries]
    before = set(names[:names.index(name)])
    return _restricted(base_loop_of(base), before | ({CONSTANT} if constants else set()), bounds)


def prove_root_bounds(loop: Loop, search: Search) -> tuple[Loop, list[str]]:
    """Prove each square root's argument ``q >= c^2`` with ``c = r(eq)/2 > 0`` (so ``r >= c``), or
    ``q >= 0`` when ``r(eq) = 0``. Returns the loop with the bounds, and the roots whose argument
    could not be proved non-negative (the file is then refused)."""
    system = loop.system
    base = loop
    bounds: dict[str, tuple[Fraction, ConditionCertificate]] = {}
    constants: set[str] = set()
    unproved: list[str] = []
    # first without the bounded constants' relations (a proof for any value of them; their multipliers
    # only add a face to the program), then with them where the loop has any
    with_constants = (False, True) if loop.fixed else (False,)
    for a in system.auxiliaries:
        if a.function != "sqrt" or a.argument is None:
            continue
        q = system.shift(a.argument)
        assert a.value is not None
        c = a.value / 2
        targets = ([(c, q - to_fmpq(c * c), f"root_{a.name}")] if c > 0 else []) + \
            [(Fraction(0), q, f"nonneg_{a.name}")]
        found = _first_root_proof(base, a.name, bounds, targets, with_constants, search)
        if found is None:
            unproved.append(a.written_as or a.definition)
            continue
        bound, uses, cert = found
        bounds[a.name] = (bound, cert)
        if uses:
            constants.add(a.name)
    return with_root_bounds(base, {k: v for k, v in bounds.items() if v[0] > 0}, frozenset(constants)), unproved


def _first_root_proof(base: Loop, name: str, bounds: dict[str, tuple[Fraction, ConditionCertificate]],
                      targets: Sequence[tuple[Fraction, Poly, str]], with_constants: Sequence[bool], search: Search
                      ) -> tuple[Fraction, bool, ConditionCertificate] | None:
    """The first of ``targets`` (bound, polynomial to prove >= 0, label) proved for root ``name``,
    without the bounded constants' relations first, then with them: its bound, whether it used them,
    and the proof; None when none is proved."""
    for bound, F, label in targets:
        for uses in with_constants:
            cert = prove_nonnegative(root_loop(base, name, bounds, uses), F, search, label)
            if cert is not None:
                return bound, uses, cert
    return None


def root_proofs_json(loop: Loop) -> dict[str, Any]:
    return {name: {"bound": str(c), "proof": cert.to_json(loop.ring), **({"constants": True} if name in
                                                                         loop.root_constants else {})}
            for name, (c, cert) in loop.root_bounds.items()}


def check_root_proofs(base: Loop, data: Any) -> tuple[Loop | None, str]:
    """Re-check stored square-root bounds on the base relations; the loop with them, or why not."""
    if not isinstance(data, dict):
        return None, "recasting.roots must be a table"
    bounds: dict[str, tuple[Fraction, ConditionCertificate]] = {}
    constants: set[str] = set()
    for name, item in data.items():
        aux = next((a for a in base.system.auxiliaries if a.name == name and a.function == "sqrt"), None)
        if aux is None or aux.argument is None:
            return None, f"recasting.roots: {name!r} is not a square root of the loop"
        c = read_rational(item["bound"])
        if c <= 0:
            return None, f"recasting.roots.{name}: the bound must be > 0"
        if item.get("constants", False) not in (True, False):
            return None, f"recasting.roots.{name}: constants must be true or false"
        before = root_loop(base, name, bounds, bool(item.get("constants", False)))
        if item.get("constants"):
            constants.add(name)
        cert = ConditionCertificate.from_json(base.ring, item["proof"], len(before.relations))
        F = base.system.shift(aux.argument) - to_fmpq(c * c)
        ok, why = check_condition(base.ring, F, before.relations, cert)
        if not ok:
            return None, f"recasting.roots.{name}: {why}"
        bounds[name] = (c, cert)
    return with_root_bounds(base, bounds, frozenset(constants)), "every square root's lower bound is proved exactly"


def prove_denominators(loop: Loop, distinct: Sequence[Poly], search: Search
                       ) -> tuple[list[tuple[Poly, Fraction, ConditionCertificate]], Poly | None]:
    """For each distinct denominator ``d``: ``d - c >= 0`` on S with ``c = d(0)/4 > 0`` (exact);
    returns the proofs, and the first denominator that failed (None when all passed)."""
    ring = loop.ring
    out: list[tuple[Poly, Fraction, ConditionCertificate]] = []
    for k, d in enumerate(distinct):
        at0 = _at_origin(loop, d)
        if at0 is None or at0 <= 0:
            return out, d
        c = at0 / 4  # well inside d's bound at the equilibrium: an interior point for the solver
        cert = prove_nonnegative(loop, d - to_fmpq(c), search, f"den{k}")
        if cert is None:
            return out, d
        out.append((d, c, cert))
    del ring
    return out, None


def check_denominator_proofs(loop: Loop, names: Sequence[str], stored: Any) -> tuple[bool, str, dict[str, Poly]]:
    """Re-check stored denominator proofs (:func:`prove_denominators`) for the flows of ``names``
    exactly: every distinct factor of the common denominator stored, with ``d - c >= 0``, ``c > 0``,
    proved on the loop's relations. Returns whether they hold, why not, and the numerators ``N``."""
    ring = loop.ring
    N, _, distinct = common_denominator(loop, names)
    if not isinstance(stored, list) or len(stored) != len(distinct):
        return False, "one positivity proof per denominator of the field is needed", N
    for d, item in zip(distinct, stored):
        if poly_from_json(ring, item["poly"], "denominator") != d:
            return False, "a stored denominator is not the field's", N
        bound = read_rational(item["bound"])
        if bound <= 0:
            return False, "a denominator's bound must be > 0", N
        proof = ConditionCertificate.from_json(ring, item["proof"], len(loop.relations))
        ok, why = check_condition(ring, d - to_fmpq(bound), loop.relations, proof)
        if not ok:
            return False, f"denominator {item['poly']}: {why}", N
    return True, "", N


def _at_origin_sign(loop: Loop, p: Poly) -> int:
    v = _at_origin(loop, p)
    return 0 if v is None else (v > 0) - (v < 0)


def _at_origin(loop: Loop, p: Poly) -> Fraction | None:
    """``p`` at the equilibrium (every deviation 0), when that is rational (roots reduced)."""
    ring = loop.ring
    zero = {n: Fraction(0) for n in ring.names if n in loop.system.values}
    value = loop.system.reduce(ring.substitute(p, zero))
    if not value.is_constant():
        return None
    return Fraction(0) if value.is_zero() else Fraction(str(value.leading_coefficient()))


# -- Lyapunov conditions ------------------------------------------------------------------------------

def lie(loop: Loop, V: Poly, N: dict[str, Poly]) -> Poly:
    """``grad V . N`` (ValueError when V uses a variable without a flow in ``N``: its term would be
    missing from V', so nothing may be proved with it)."""
    ring = loop.ring
    moving = [n for n in ring.names if degree_in(ring, V, [n]) > 0 and n not in N]
    if moving:
        raise ValueError(f"V uses {moving[0]}, whose flow is not in the derivative")
    total = ring.zero()
    for name, n in N.items():
        i = ring.names.index(name)
        if degree_in(ring, V, [name]) > 0:
            total += V.derivative(i) * n
    return total


def state_square(loop: Loop) -> Poly:
    """``|z|^2`` over the states; an angle's ``theta^2`` is ``sin^2 + (cos - 1)^2`` (zero exactly at
    the angle's equilibrium modulo 2 pi)."""
    ring = loop.ring
    total = ring.zero()
    for s in loop.states():
        if s in loop.angles:
            sine, cosine = loop.angles[s]
            total += ring.gen(sine) ** 2 + ring.gen(cosine) ** 2  # deviations: c - 1
        else:
            total += ring.gen(s) * ring.gen(s)
    return total


def v_names(loop: Loop, V: Poly) -> list[str]:
    """The variables whose flows ``V'`` needs (V's variables; the states but the angles always, for a
    stable order)."""
    ring = loop.ring
    return [s for s in loop.states() if s not in loop.angles] + \
        [n for n in loop.system.smooth() if degree_in(ring, V, [n]) > 0]


@dataclass
class Proved:
    """A certified V: its certificate's parts (JSON) and figures."""

    certificate: dict[str, Any]
    numbers: dict[str, Any]


def certificate_head(loop: Loop, V: Poly, eps: Fraction, D: Poly, dens: Sequence[tuple[Poly, Fraction,
                                                                                    ConditionCertificate]]
                     ) -> dict[str, Any]:
    system = loop.system
    ring = loop.ring
    return {"kind": "recast", "variables": list(ring.names), "auxiliaries": system.definitions(),
            "angles": list(loop.angles),
            "shift": {k: str(v) for k, v in system.values.items()},
            "V": poly_to_json(ring, V), "V_text": v_text(system, V), "epsilon": str(eps),
            "denominator": poly_to_json(ring, D),
            "recasting": {"roots": root_proofs_json(loop),
                          "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                                           for d, c, cert in dens]}}


def v_text(system: RecastSystem, V: Poly) -> str:
    """V written with the functions: each deviation ``v - value`` spelled out in the model's language."""
    ring = system.ring
    text = written_poly(ring, V)
    names = sorted(ring.names, key=len, reverse=True)
    table = {}
    for n in names:
        aux = next((a for a in system.auxiliaries if a.name == n), None)
        base = aux.definition if aux is not None else n
        value = system.values.get(n)
        table[n] = f"({base} - {value})" if value else base
    import re

    return re.sub(r"\b(" + "|".join(map(re.escape, names)) + r")\b", lambda m: table[m.group(1)], text)


def _dyadic(x: Fraction, bits: int = 12) -> Fraction:
    """``x`` rounded to ``bits`` significant bits (short certificates)."""
    if x <= 0:
        return x
    import math

    e = math.floor(math.log2(x))
    step = Fraction(2) ** (e - bits)
    return (x // step) * step


def quadratic_candidate(loop: Loop, J: list[list[Fraction]]) -> Poly | None:
    """``z^T P z`` with ``J^T P + P J = -I`` (exact), when ``P > 0``."""
    from lyapcheck.models.classes.linearization import lyapunov_solution
    from lyapcheck.sos.definiteness import is_positive_definite

    P = lyapunov_solution(J)
    if P is None or not is_positive_definite(P):
        return None
    ring = loop.ring
    z = [ring.gen(s) for s in loop.system.states]
    square = {}
    for i, s in enumerate(loop.system.states):
        if s in loop.angles:  # on the cylinder: theta -> sin theta, theta^2 -> 2 (1 - cos theta)
            sine, cosine = loop.angles[s]
            z[i] = ring.gen(sine)
            square[i] = -2 * ring.gen(cosine)
    return sum((square[i] * to_fmpq(P[i][i]) if i == j and i in square else z[i] * z[j] * to_fmpq(P[i][j])
                for i in range(loop.n) for j in range(loop.n)), ring.zero())


# -- the linearization ------------------------------------------------------------------------------

#: the functions smooth where the recasting evaluates them, with their slope there (their arguments are 0 at
#: the equilibrium; sqrt's slope is 1 / (2 sqrt(u0)), read from the auxiliary's value)
_SLOPE_AT_0: Final = {"sin": Fraction(1), "cos": Fraction(0), "exp": Fraction(1), "atan": Fraction(1),
                      "tanh": Fraction(1)}
#: why an exact first-order part has no rational entry, by what is asked for (the Jacobian; the kinks' form)
_IRRATIONAL: Final = {False: "the Jacobian has an irrational entry (sqrt 2 or sqrt 3); its stability is not decided "
                             "exactly here",
                      True: "the first-order part has an irrational entry (sqrt 2 or sqrt 3); it is not decided "
                            "exactly here"}


@dataclass(frozen=True)
class FirstOrder:
    """The chain rule's walk through the auxiliaries at the equilibrium: each variable's linear form in
    ``w = (e, phi)`` (``e`` the states' deviations, ``phi`` one coordinate per kink asked for), the kinks
    met (each auxiliary with its argument's form), and the field's rows (divided by their denominators'
    values). With no kink asked for, ``w = e`` and the rows are the Jacobian."""

    forms: dict[str, list[Fraction]]
    kinks: list[tuple[Any, list[Fraction]]]
    rows: list[list[Fraction]]


def first_order(loop: Loop, kinks: Sequence[str] = (), field_rows: bool = True) -> FirstOrder | str:
    """The one chain-rule walk behind :func:`jacobian`, :func:`gradient_at_equilibrium` and the kinks'
    linearization (:func:`lyapcheck.models.classes.piecewise_linearization.derive`): every variable's
    linear form, ``kinks`` (auxiliary names, at their kink at the equilibrium) each given a coordinate of
    its own; or why there is none (a kink not asked for, sqrt at 0, an irrational entry, a denominator
    0 at the equilibrium). ``field_rows`` False: the forms only."""
    system = loop.system
    n = loop.n
    width = n + len(kinks)
    zero = [Fraction(0)] * width
    forms: dict[str, list[Fraction]] = {s: [Fraction(int(i == j)) for j in range(width)]
                                        for i, s in enumerate(system.states)}
    met: list[tuple[Any, list[Fraction]]] = []
    irrational = _IRRATIONAL[bool(kinks)]
    for a in system.auxiliaries:
        if a.argument is None:  # a constant root
            forms[a.name] = list(zero)
            continue
        du = _linear_form(loop, system.shift(a.argument), forms, width, irrational)
        if isinstance(du, str):
            return du
        u0 = Fraction(0) if a.value is None else _argument_value(system, a)
        f = a.function
        if f in _SLOPE_AT_0:
            forms[a.name] = [_SLOPE_AT_0[f] * d for d in du]
        elif f == "sqrt":
            if not a.value:
                return f"{a.written_as}: sqrt is not differentiable where its argument is 0"
            forms[a.name] = [d / (2 * a.value) for d in du]
        elif f == "abs" and u0 != 0:
            forms[a.name] = [(1 if u0 > 0 else -1) * d for d in du]
        elif f == "sat" and abs(u0) != a.limit:
            assert a.limit is not None
            forms[a.name] = list(du) if abs(u0) < a.limit else list(zero)
        elif f in ("abs", "sat") and a.name in kinks:  # a kink at the equilibrium: a coordinate of its own
            index = n + len(met)
            met.append((a, du))
            forms[a.name] = [Fraction(int(j == index)) for j in range(width)]
        elif f == "abs":
            return f"{a.written_as}: abs is not differentiable where its argument is 0 (the equilibrium)"
        elif f == "sat":
            return f"{a.written_as}: sat is not differentiable at its corner (the equilibrium)"
        else:  # pragma: no cover - every function of the recasting is above
            return f"{a.written_as}: no derivative"
    rows: list[list[Fraction]] = []
    for r in system.field if field_rows else ():
        d0 = _at_origin(loop, system.shift(r.denominator))
        if d0 is None or d0 == 0:
            return "a denominator of the field is irrational or 0 at the equilibrium"
        row = _linear_form(loop, system.shift(r.numerator), forms, width, irrational)
        if isinstance(row, str):
            return row
        rows.append([x / d0 for x in row])
    return FirstOrder(forms, met, rows)


def jacobian(loop: Loop) -> list[list[Fraction]] | str:
    """The exact Jacobian of the true field at the equilibrium (chain rule through the
    auxiliaries, :func:`first_order` with no kink), or why there is none (a non-differentiable function
    there, or an irrational entry)."""
    walked = first_order(loop)
    return walked if isinstance(walked, str) else walked.rows


def gradient_at_equilibrium(loop: Loop, p: Poly) -> list[Fraction] | str:
    """The exact gradient in the states, at the equilibrium, of ``p`` (a polynomial in the
    deviations of the states and auxiliaries), by the chain rule; or why there is none."""
    grads = variable_gradients(loop)
    return grads if isinstance(grads, str) else _linear_form(loop, p, grads, loop.n, _IRRATIONAL[False])


def variable_gradients(loop: Loop) -> dict[str, list[Fraction]] | str:
    """Each state's and auxiliary's gradient in the states at the equilibrium (exact), or why not."""
    walked = first_order(loop, field_rows=False)
    return walked if isinstance(walked, str) else walked.forms


def _argument_value(system: RecastSystem, a: Any) -> Fraction:
    ring = system.ring
    point = [system.values.get(n, Fraction(0)) for n in ring.names]
    return ring.evaluate(a.argument, point)


def _linear_form(loop: Loop, p: Poly, forms: Mapping[str, list[Fraction]], width: int, irrational: str
                 ) -> list[Fraction] | str:
    """The linear form of ``p`` (a polynomial in the deviations, 0 at the equilibrium): its partials there
    times each variable's form (``irrational``: the reason when a partial is not rational)."""
    ring = loop.ring
    out = [Fraction(0)] * width
    for i, name in enumerate(ring.names):
        if degree_in(ring, p, [name]) <= 0:
            continue
        if name in forms and not any(forms[name]):
            continue  # the variable does not move to first order (cos at 0): its partial does not matter
        partial = _at_origin(loop, p.derivative(i))
        if partial is None:
            return irrational
        if partial == 0:
            continue
        if name not in forms:
            return f"{name}: no derivative"  # pragma: no cover
        out = [o + partial * g for o, g in zip(out, forms[name])]
    return out


def linearization(loop: Loop) -> ConditionResult:
    from lyapcheck.models.classes.linearization import decide

    J = jacobian(loop)
    if isinstance(J, str):  # (a kink at the equilibrium: lyapcheck.models.classes.piecewise_linearization then)
        return ConditionResult("linearization", "not_applicable", J, property="LES")
    return decide(J)


# -- the linearization over a box of parameters (issue 45, item 1) ------------------------------------

def jacobian_over_box(loop: Loop) -> tuple[list[list[Poly]], Ring] | str:
    """``J(u)``: the exact Jacobian of the true field at the equilibrium for every value of a box, as
    polynomials in the box's normalized parameters ``u`` (``theta = c + h u``, ``u`` in ``[-1, 1]``; the
    ring returned, in the box's order), on ``loop`` recast with the box's parameters as bounded
    constants (:attr:`Loop.fixed`); or why there is none, one line.

    The chain rule of :func:`jacobian`, with each auxiliary's value and derivative at the equilibrium
    as polynomials in ``u`` where they are exact for every value of the box: ``sin``, ``atan``, ``tanh``
    (0, slope 1), ``cos`` (1, slope 0) and ``exp`` (1, slope 1) of an argument that is 0 there for every
    value; ``sqrt`` of an argument whose value there does not depend on the parameters; ``abs`` of an
    argument of one strict sign on the whole box, and ``sat`` of one strictly inside (slope 1) or
    strictly beyond (slope 0) its limits on the whole box, both proved by exact Bernstein coefficients
    (:mod:`~lyapcheck.models.engines.bernstein`). Every right-hand side must be 0 at the equilibrium
    for every value (as a polynomial in ``u``, exactly), and its denominator there a nonzero constant."""
    from lyapcheck.models.engines.bernstein import positive_on_box

    system = loop.system
    ring = loop.ring
    box_ring = Ring(tuple(loop.fixed))
    unit = tuple((Fraction(-1), Fraction(1)) for _ in loop.fixed)
    states = loop.states()
    n = loop.n_states
    zero, one = ring.zero(), ring.constant(1)
    # each variable at the equilibrium, a polynomial in u (a parameter's own variable stands for its u)
    images: dict[str, Poly] = {s: ring.constant(system.values[s]) for s in states}
    images.update({p: ring.gen(p) * to_fmpq(h) + to_fmpq(system.values[p]) for p, h in loop.fixed.items()})
    grads: dict[str, list[Poly]] = {s: [one if i == j else zero for j in range(n)] for i, s in enumerate(states)}
    grads.update({p: [zero] * n for p in loop.fixed})

    def at_equilibrium(p: Poly) -> Poly:
        return system.reduce(ring.compose(p, [images.get(name, ring.gen(name)) for name in ring.names]))

    def in_u(p: Poly) -> Poly | None:
        """``p`` in the box's ring, or None when it is not rational there (a constant root remains)."""
        return ring.restrict(p, box_ring) if all(degree_in(ring, p, [r]) <= 0 for r in system.roots()) else None

    def positive(p: Poly) -> bool:
        q = in_u(p)
        return q is not None and positive_on_box(box_ring.terms(q), unit).proved

    def gradient(p: Poly) -> list[Poly]:
        out = [zero] * n
        for i, name in enumerate(ring.names):
            if degree_in(ring, p, [name]) <= 0 or not any(not g.is_zero() for g in grads[name]):
                continue  # (a variable that does not move to first order: its partial does not matter)
            partial = at_equilibrium(p.derivative(i))
            out = [system.reduce(o + partial * g) for o, g in zip(out, grads[name])]
        return out

    for a in system.auxiliaries:
        if a.argument is None:  # a constant root
            grads[a.name] = [zero] * n
            continue
        u0 = at_equilibrium(a.argument)
        du = gradient(a.argument)
        where = f"{a.written_as or a.definition}: its argument at the equilibrium"
        f = a.function
        if f in ("sin", "cos", "exp", "atan", "tanh"):
            if not u0.is_zero():
                return (f"{where} is not 0 for every value of the box (sin, cos, exp, atan and tanh have exact values "
                        "and slopes only at 0)")
            value, factor = (one, zero if f == "cos" else one) if f in ("cos", "exp") else (zero, one)
        elif f == "sqrt":
            assert a.value is not None
            if any(degree_in(ring, u0, [p]) > 0 for p in loop.fixed):
                return (f"{where} depends on the box's parameters (the square root's value and slope there are not "
                        "polynomial in them)")
            if not a.value:
                return f"{a.written_as}: sqrt is not differentiable where its argument is 0 (the equilibrium)"
            value, factor = ring.constant(a.value), ring.constant(1 / (2 * a.value))
        elif f == "abs":
            if positive(u0):
                value, factor = u0, one
            elif positive(-u0):
                value, factor = -u0, -one
            else:
                return (f"{where} is not proved of one strict sign on the whole box (abs is neither polynomial nor "
                        "differentiable across 0)")
        elif f == "sat":
            assert a.limit is not None
            L = to_fmpq(a.limit)
            if positive(u0 + L) and positive(L - u0):
                value, factor = u0, one
            elif positive(u0 - L):  # saturated on the whole box: constant near the equilibrium
                value, factor = ring.constant(a.limit), zero
            elif positive(-u0 - L):
                value, factor = ring.constant(-a.limit), zero
            else:
                return (f"{where} is not proved strictly inside (or strictly beyond) the limits +-{a.limit} for every "
                        "value of the box (sat is neither polynomial nor differentiable across its corners)")
        else:  # pragma: no cover - every function is above
            return f"{a.written_as}: no derivative"
        images[a.name] = value
        grads[a.name] = [system.reduce(factor * d) for d in du]
    J: list[list[Poly]] = []
    for s, r in zip(states, system.field):
        if not at_equilibrium(r.numerator).is_zero():
            return (f"{s}' at the equilibrium is not 0 for every value of the box as a polynomial in its parameters "
                    "(the equilibrium moves with them)")
        d0 = in_u(at_equilibrium(r.denominator))
        if d0 is None or not d0.is_constant() or d0.is_zero():
            return (f"the denominator of {s}' at the equilibrium is not a nonzero rational constant over the box (the "
                    "Jacobian is not polynomial in the parameters)")
        row = [in_u(x) for x in gradient(r.numerator)]
        if any(x is None for x in row):
            return "the Jacobian has an irrational entry (sqrt 2 or sqrt 3); its stability is not decided exactly here"
        J.append([x * (1 / d0.leading_coefficient()) for x in row if x is not None])
    return J, box_ring


def linearization_over_box(loop: Loop, box: ModelBox) -> ConditionResult:
    """``linearization`` for every value of ``box`` on ``loop`` recast with its parameters as bounded
    constants: :func:`jacobian_over_box` decided by the polynomial loops' box test
    (:func:`lyapcheck.models.classes.linearization.decide_over_box`), or ``not_applicable`` with why."""
    from lyapcheck.models.classes.linearization import decide_over_box

    assert tuple(loop.fixed) == box.names, "the boxed loop's constants are the box's parameters, in its order"
    built = jacobian_over_box(loop)
    if isinstance(built, str):
        return ConditionResult("linearization", "not_applicable", f"over this box: {built}", property="LES")
    J, ring = built
    return decide_over_box(J, ring, box)


# -- another equilibrium: no global claim -------------------------------------------------------------

def other_equilibrium(loop: Loop) -> dict[str, str] | None:
    """An equilibrium of the true loop other than the stated one (modulo 2 pi), found exactly: each
    angle at ``k pi/12`` (its sine and cosine exact in Q(sqrt 2, sqrt 3)), every other state at its
    equilibrium value; the point as ``{"theta": "k/12*pi", ...}``, or None. Such a point refutes
    global asymptotic stability (a trajectory starting there stays there)."""
    for angle in loop.angles:
        for k in range(1, 24):
            point = {angle: f"{Fraction(k, 12)}*pi"}
            if _is_equilibrium(loop, {angle: k}):
                return point
    return None


def _is_equilibrium(loop: Loop, angles_at: dict[str, int]) -> bool:
    """Whether every right-hand side is exactly 0 with the angles at ``k pi/12`` (the rest at the
    equilibrium); False when a value cannot be written exactly here."""
    from lyapcheck.models.language.recast import exact_cos_sin

    system = loop.system
    ring = loop.ring
    roots = {k: ring.gen(n) for n, k in system.roots().items()}
    images: dict[str, Poly] = {n: ring.constant(v) for n, v in system.values.items()}
    for angle, k in angles_at.items():
        sine, cosine = loop.angles[angle]
        for name, value in zip((cosine, sine), exact_cos_sin(k)):
            p = ring.constant(value.get(1, Fraction(0)))
            for radicand, coefficient in value.items():
                if radicand == 1 or not coefficient:
                    continue
                if any(r not in roots for r in ((2, 3) if radicand == 6 else (radicand,))):
                    return False  # an irrational value the loop has no root variable for
                term = ring.constant(coefficient)
                for r in ((2, 3) if radicand == 6 else (radicand,)):
                    term = term * roots[r]
                p += term
            images[name] = p
    for a in system.auxiliaries:  # any other function must take an exactly known value there
        if a.name in images or a.argument is None:
            continue
        u = system.reduce(ring.compose(a.argument, [images.get(n, ring.gen(n)) for n in ring.names]))
        if not u.is_constant():
            return False
        at = Fraction(0) if u.is_zero() else Fraction(str(u.leading_coefficient()))
        if a.function == "abs":
            images[a.name] = ring.constant(abs(at))
        elif a.function == "sat" and a.limit is not None:
            images[a.name] = ring.constant(max(-a.limit, min(a.limit, at)))
        elif a.function in ("sin", "atan", "tanh") and at == 0:
            images[a.name] = ring.constant(0)
        elif a.function in ("cos", "exp") and at == 0:
            images[a.name] = ring.constant(1)
        else:
            return False
    full = [images.get(n, ring.gen(n)) for n in ring.names]
    for rhs in system.field:
        if not system.reduce(ring.compose(rhs.numerator, full)).is_zero():
            return False
        if system.reduce(ring.compose(rhs.denominator, full)).is_zero():
            return False
    return True


def refute_global(loop: Loop, name: str, prop: str = "GAS") -> ConditionResult | None:
    """``refuted`` with the other equilibrium as the refutation, when there is one (exact)."""
    point = other_equilibrium(loop)
    if point is None:
        return None
    return ConditionResult(name, "refuted", refutation_sentence(point), property=prop,  # type: ignore[arg-type]
                           refutation={"kind": "equilibrium", "point": point})


def refutation_sentence(point: dict[str, str]) -> str:
    """What another equilibrium refutes, from the point alone (``verify`` re-makes it and compares)."""
    where = ", ".join(f"{k} = {v}" for k, v in point.items())
    return (f"not globally asymptotically stable: the loop has another equilibrium at {where} (the other states at "
            "their equilibrium; checked exactly, its sine and cosine in Q(sqrt 2, sqrt 3))")


def check_refutation(loop: Loop, data: Any) -> tuple[bool, str]:
    """Re-check a stored other equilibrium exactly."""
    if not isinstance(data, dict) or data.get("kind") != "equilibrium" or not isinstance(data.get("point"), dict):
        return False, "a refutation must name another equilibrium"
    at: dict[str, int] = {}
    for angle, text in data["point"].items():
        if angle not in loop.angles or not isinstance(text, str) or not text.endswith("*pi"):
            return False, f"{angle!r} is not an angle of the loop at k*pi"
        k = Fraction(text[:-3]) * 12
        if k.denominator != 1 or k % 24 == 0:
            return False, f"{angle} must be at a multiple of pi/12 other than 0 (modulo 2 pi)"
        at[angle] = int(k) % 24
    if not at or not _is_equilibrium(loop, at):
        return False, "the stated point is not an equilibrium of the loop"
    return True, "another equilibrium, exactly: no global asymptotic stability"

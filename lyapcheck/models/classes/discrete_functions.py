"""Discrete-time maps with functions (``[model] time = "discrete"`` with ``sin``, ``tanh``, ``[networks]``, ...;
issue 44, item 1): ``linearization``, ``roa`` and ``candidate``.

The map ``x+ = F(x)`` is read by the recasting of continuous loops, applied to its displacement
``F(x) - x`` (:meth:`lyapcheck.models.language.modelfile._Reader.recast_map`): the recasting's exact check
that every right-hand side is 0 at the equilibrium is the fixed-point check ``F(x_eq) = x_eq``, each
function's value exact there. In deviations ``e = x - x_eq`` the map is ``e+ = e + d(e)`` with
``d(e) = F(x_eq + e) - x_eq - e``.

``linearization``: the exact Jacobian of ``d`` at the fixed point by the chain rule through the
auxiliaries (:func:`lyapcheck.models.classes.recast_classes.jacobian`, the continuous loops' own), plus the
identity, then the exact Schur decision of :func:`lyapcheck.models.classes.discrete_linearization.decide`
(spectral radius < 1 certified, > 1 refuted). A function not differentiable at the fixed point:
``not_applicable`` naming it.

``roa``: ``V(e) = e^T P e`` with ``P`` a short dyadic rounding of the solution of ``A^T P A - P = -I``
(``A`` the exact Jacobian), ``P > 0`` checked exactly, and ``g(e) = V(e + d(e)) - V(e) < 0`` on
``E = {V <= c}`` except at the fixed point, proved by ball arithmetic on the true map (every function and
the network in outward-rounded ``arb`` balls, :class:`~lyapcheck.models.engines.interval_field.BallLoop`)
on the cells of :func:`~lyapcheck.models.engines.ellipsoid_cells.prove_ellipsoid`, with this module's
geometry (:class:`MapGeometry`: ``g`` and its derivatives instead of a Lie derivative). ``g(0) = 0`` and
``grad g(0) = 0`` (the fixed point), so the Hessian-zone argument of that module holds unchanged.

Why ``E`` is then a region of attraction: for ``e`` in ``E``, ``V(F(e)) <= V(e) <= c`` (``g <= 0``), so
``F(E)`` lies in ``E`` (forward invariance) and ``V`` is non-increasing along every orbit from ``E``. ``g``
is continuous and ``< 0`` on the compact ``E`` minus any open ball ``B_r`` around the fixed point, so there
``g <= -m_r < 0``: an orbit that stayed outside ``B_r`` would decrease ``V`` by ``m_r`` at each step
without bound, which ``V >= 0`` forbids; and once in the sublevel set ``{V <= min_{E \\ B_r} V}`` (inside
``B_r`` for small sublevels) it stays there. Hence ``V(e_k) -> 0`` and ``e_k -> 0`` for every start in ``E``:
asymptotic stability with ``E`` inside the region of attraction.

The level is the largest one proved by a monotone search
(:func:`~lyapcheck.models.classes.level_search.largest_proved_level`: growth by a factor, then bisections)
within cell budgets (counts, :data:`~lyapcheck.tolerances.BALL_LEVEL_CELLS` per attempt,
:data:`~lyapcheck.tolerances.BALL_LEVEL_TOTAL_CELLS` in all). The certificate (kind
``discrete_interval``) states ``P`` and the level; :func:`verify_roa` repeats the proof, cell for cell.

``candidate`` (:func:`candidate`): the user's ``--candidate`` V, which must be a quadratic form
``e^T P e`` in the state deviations (its ``P`` read exactly; a V with any other term is ``not_applicable``,
a ``P`` not positive definite ``not_certified``), proved by the same route as ``roa`` with that ``P`` (no
rounding): its largest proved level. Its certificate is the ``roa`` kind with ``"V_from": "candidate"``;
:func:`verify_candidate` checks that the stated ``P`` is the candidate's, then proves the level again.

Over a box of parameters (``--box``): :mod:`lyapcheck.models.classes.discrete_functions_box`.

``quadratic`` and ``sos_gas`` on such a map: :mod:`lyapcheck.models.classes.map_relations` (a V of the states
on the recasting's relations); a linearization at a kink of the fixed point:
:mod:`lyapcheck.models.classes.piecewise_linearization`; every other class is ``not_applicable`` (one line:
:data:`NOT_YET`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

import flint

from lyapcheck import tolerances
from lyapcheck.models.classes.claims import DISCRETE_INTERVAL_KIND, discrete_interval_sentence
from lyapcheck.models.engines.ellipsoid_cells import Cell, Whitening, _Geometry
from lyapcheck.models.engines.interval_field import BallLoop, Jet, ball
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.recast import RecastModel

#: the certificate kind of ``roa`` on a map with functions
KIND: Final = DISCRETE_INTERVAL_KIND
#: the reason of every class without a ``run_map_functions`` entry (lyapcheck.models.classes.registry: the
#: classes a map with functions takes, MAP_FUNCTIONS) on such a map
NOT_YET: Final = ('not taken yet on a discrete-time map with functions ([model] time = "discrete" with sin, tanh, '
                  "[networks], ...): the classes taken are linearization, quadratic, sos_gas, roa, candidate, "
                  "sos_bound, barrier and reach_avoid")
#: significant bits of a level tried
LEVEL_BITS: Final = 12
#: the first level tried: the ellipsoid this wide (in its widest state) ...
MAP_FIRST_EXTENT: Final = Fraction(1, 2)
#: ... and, if not proved, a quarter of it at most this many times
MAP_LOCAL_STEPS: Final = 12


def exact_jacobian(model: "RecastModel") -> list[list[Fraction]] | str:
    """``A = I + Jd`` at the fixed point (exact), or why there is none (a function not differentiable
    there, named; an irrational entry)."""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian

    J = jacobian(base_loop(model.system, cylinder=False))
    if isinstance(J, str):
        return J
    return [[x + (1 if i == j else 0) for j, x in enumerate(row)] for i, row in enumerate(J)]


def linearization(model: "RecastModel") -> ConditionResult:
    """The map's linearization decided exactly (module docstring)."""
    from lyapcheck.models.classes import discrete_linearization

    A = exact_jacobian(model)
    if isinstance(A, str):
        return ConditionResult("linearization", "not_applicable", f"the map's Jacobian at the fixed point: {A}",
                               property="LES")
    return discrete_linearization.decide(A)


def verify_linearization(model: "RecastModel", status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """A map's linearization re-derived: the exact Jacobian again, then the discrete-time test."""
    from lyapcheck.models.classes import discrete_linearization

    A = exact_jacobian(model)
    if isinstance(A, str):
        return False, f"the map's Jacobian is not exact here: {A}"
    return discrete_linearization.verify_matrix(A, status, data)


class MapDifference:
    """``g(z) = V(z + d(z)) - V(z)`` for ``V = z^T P z`` on balls (the interface
    :func:`~lyapcheck.models.engines.ellipsoid_cells.prove_ellipsoid` asks of a Lie derivative)."""

    def __init__(self, loop: BallLoop, P: list[list[Fraction]]) -> None:
        self.loop = loop
        self.n = loop.n
        self.P = [[ball(x) for x in row] for row in P]

    def quadratic(self, z: list[Any]) -> Any:
        n = self.n
        total: Any = flint.arb(0)
        for i in range(n):
            total = z[i] * (self.P[i][i] * z[i]) + total
            for j in range(i + 1, n):
                total = (z[i] * z[j]) * (2 * self.P[i][j]) + total
        return total

    def __call__(self, z: list[Any]) -> Any:
        d = self.loop.field(z)
        return self.quadratic([zi + di for zi, di in zip(z, d)]) - self.quadratic(z)


class MapGeometry(_Geometry):
    """The cells of :mod:`~lyapcheck.models.engines.ellipsoid_cells` with ``g = V(F(z)) - V(z)``: ``g`` is
    carried as a :class:`~lyapcheck.models.engines.interval_field.Jet` of the cell's own coordinates ``y``
    (``z = M y``, ``M`` exact), so its gradient and Hessian come out in ``y`` by the chain rule. ``V(z)`` is
    ``y^T Q y`` (``Q = M^T P M``, exact), ``V(F(z))`` the quadratic form of ``P`` on the map's image."""

    factored = False  # (g is a difference along a map, not a Lie derivative: the factored test does not apply)

    def __init__(self, w: Whitening, P: list[list[Fraction]], diff: MapDifference) -> None:
        super().__init__(w, P, diff)  # type: ignore[arg-type]
        self.diff = diff

    def _g(self, ys: list[Any], order: int) -> Jet | None:
        n = self.n
        Y = [Jet.variable(y, i, n, order) for i, y in enumerate(ys)]
        Z = [sum((Y[j].scaled(self.M[i][j]) for j in range(n)), Jet.constant(flint.arb(0), n, order))
             for i in range(n)]
        D = self.loop.field(Z)
        D = [di if isinstance(di, Jet) else Jet.constant(di, n, order) for di in D]
        if any(di.grad is None or (order >= 2 and di.hess is None) for di in D):
            return None
        image = [zi + di for zi, di in zip(Z, D)]
        q_old = Jet.constant(flint.arb(0), n, order)
        for i in range(n):
            q_old = q_old + (Y[i] * Y[i]).scaled(self.Q[i][i])
            for j in range(i + 1, n):
                q_old = q_old + (Y[i] * Y[j]).scaled(2 * self.Q[i][j])
        q_new = Jet.constant(flint.arb(0), n, order)
        P = self.diff.P
        for i in range(n):
            q_new = q_new + (image[i] * image[i]).scaled(P[i][i])
            for j in range(i + 1, n):
                q_new = q_new + (image[i] * image[j]).scaled(2 * P[i][j])
        return q_new - q_old

    def hessian_y(self, lie: Any, cell: Cell) -> list[list[Any]] | None:
        g = self._g([flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell], 2)
        if g is None or g.hess is None:
            return None
        H = g.hess
        if not all(h.is_finite() for row in H for h in row):
            return None
        return H

    def at_centre(self, lie: Any, cell: Cell) -> tuple[Any, list[Any] | None]:
        ys = [flint.arb((a + b) / 2) for a, b in cell]
        g = self._g(ys, 1)
        if g is None or g.grad is None:
            return self.diff(self.z_of(ys)), None
        return g.value, g.grad


def rounded_p(A: list[list[Fraction]]) -> list[list[Fraction]] | None:
    """``P`` of ``A^T P A - P = -I`` rounded to :data:`~lyapcheck.tolerances.P_BITS` significant bits (symmetric), or None."""
    from lyapcheck.models.classes.discrete_linearization import stein_solution
    from lyapcheck.models.engines.ellipsoid_cells import _short

    P = stein_solution(A)
    if P is None:
        return None
    n = len(P)
    return [[_short(P[min(i, j)][max(i, j)], tolerances.P_BITS) for j in range(n)] for i in range(n)]


def prove_level(model: "RecastModel", P: list[list[Fraction]], level: Fraction, cells: int,
                loop: BallLoop | None = None) -> Any:
    """``g < 0`` on ``{e^T P e <= level}`` but at the fixed point (deterministic; at most ``cells`` cells).
    ``loop``: the true map in balls (default the model's at its parameters; over a box, the map with the
    box's parameters as balls, :func:`lyapcheck.models.classes.discrete_functions_box.boxed_map`)."""
    from lyapcheck.exact import inverse
    from lyapcheck.models.engines.ellipsoid_cells import prove_ellipsoid

    diff = MapDifference(BallLoop(model.system) if loop is None else loop, P)
    diagonal = [inverse(P)[i][i] for i in range(len(P))]
    return prove_ellipsoid(diff, P, diagonal, level, [], None, cells,  # type: ignore[arg-type]
                           geometry=lambda w: MapGeometry(w, P, diff))


def _v_terms(P: list[list[Fraction]], states: tuple[str, ...], equilibrium: tuple[Fraction, ...]) -> str:
    parts = []
    names = [s if x == 0 else f"({s} - {x})" for s, x in zip(states, equilibrium)]
    for i in range(len(P)):
        for j in range(i, len(P)):
            c = P[i][j] * (1 if i == j else 2)
            if c:
                parts.append(f"{c}*{names[i]}*{names[j]}" if i != j else f"{c}*{names[i]}**2")
    return " + ".join(parts)


def area(P: list[list[Fraction]], level: Fraction) -> float | None:
    """The area of ``{e^T P e <= level}`` for 2 states: ``pi level / sqrt(det P)``; None otherwise."""
    import math

    if len(P) != 2:
        return None
    det = P[0][0] * P[1][1] - P[0][1] * P[1][0]
    return math.pi * float(level) / math.sqrt(float(det))


class Found:
    """A level search's outcome: the level proved and its proof's cells, the cells spent, the levels tried."""

    def __init__(self, level: Fraction, cells: int, spent: int, tried: list[tuple[Fraction, bool]]) -> None:
        self.level, self.cells, self.spent, self.tried = level, cells, spent, tried

    def numbers(self) -> dict[str, Any]:
        """The figures a certified region states."""
        return {"level": float(self.level), "cells": self.cells, "cells_spent": self.spent,
                "tried": [f"level {float(lv):.6g}: {'proved' if ok else 'not proved'}" for lv, ok in self.tried]}


def prove_on_all(model: "RecastModel", P: list[list[Fraction]], level: Fraction, cells: int,
                 loops: Sequence[BallLoop | None]) -> tuple[bool, int, str]:
    """:func:`prove_level` on each of ``loops`` (the parts of a box; ``[None]``: the model's map), within
    ``cells`` cells in all: (proved on every one, cells examined, why not)."""
    used = 0
    for loop in loops:
        proof = prove_level(model, P, level, max(cells - used, 0), loop)
        used += proof.cells
        if not proof.ok:
            return False, used, proof.why
    return True, used, ""


def level_search(model: "RecastModel", P: list[list[Fraction]], budget: "Budget", name: str,
                 loops: Sequence[BallLoop | None] = (None,)) -> Found | ConditionResult:
    """The largest level of ``{e^T P e <= level}`` proved (``P`` positive definite, exact) on every one of
    ``loops`` (default the model's map), within the cell budgets (module docstring), or ``name``'s
    inconclusive or not_certified result saying why."""
    from lyapcheck.exact import inverse
    from lyapcheck.models.classes.level_search import largest_proved_level
    from lyapcheck.models.classes.recast_classes import _dyadic
    from lyapcheck.models.engines.search import BudgetExhausted

    widest = max(inverse(P)[i][i] for i in range(len(P)))
    spent = [0]
    total, each = tolerances.BALL_LEVEL_TOTAL_CELLS, tolerances.BALL_LEVEL_CELLS

    def attempt(level: Fraction) -> tuple[Fraction, int] | None:
        left = total - spent[0]
        if left <= 0:
            raise BudgetExhausted(f"the search's {total} cells were spent (lyapcheck.tolerances.BALL_LEVEL_TOTAL_CELLS)")
        if budget.left() <= 0:
            raise BudgetExhausted(budget.reached())
        ok, cells, _ = prove_on_all(model, P, level, min(each, left), loops)
        spent[0] += cells
        return (level, cells) if ok else None

    first = _dyadic(MAP_FIRST_EXTENT ** 2 / widest, LEVEL_BITS)
    try:
        for _ in range(MAP_LOCAL_STEPS):
            if attempt(first) is not None:
                break
            first = _dyadic(first / 4, LEVEL_BITS)
        found = largest_proved_level(attempt, first, growth=tolerances.MAP_LEVEL_GROWTH,
                                     growth_steps=tolerances.MAP_LEVEL_GROWTH_STEPS,
                                     halvings=0, bisections=tolerances.MAP_LEVEL_BISECTIONS,
                                     rounded=lambda x: _dyadic(x, LEVEL_BITS))
    except BudgetExhausted as exc:
        return ConditionResult(name, "inconclusive", f"ball arithmetic on the true map: {exc}", property="ROA")
    if found.proof is None or found.level is None:
        return ConditionResult(name, "not_certified", "ball arithmetic on the true map: V(F(e)) < V(e) was not "
                               f"proved on the smallest ellipsoid tried (level {float(first):.3g})", property="ROA")
    level, cells = found.proof
    return Found(level, cells, spent[0], list(found.tried))


def region_certificate(model: "RecastModel", P: list[list[Fraction]], found: Found) -> dict[str, Any]:
    """The ``discrete_interval`` certificate of a proved level."""
    return {"kind": KIND, "method": "ball arithmetic on the true map (python-flint arb), cells of the ellipsoid",
            "time": "discrete", "variables": list(model.states),
            "P": [[str(x) for x in row] for row in P], "level": str(found.level), "cells": found.cells,
            "V_text": _v_terms(P, model.states, model.equilibrium)}


def certified_region(name: str, P: list[list[Fraction]], found: Found, certificate: dict[str, Any],
                     summary: str) -> ConditionResult:
    """A proved level's result (``roa`` or ``candidate``, at a point or over a box): its figures and, where
    the level set's area is known, that area beside them."""
    numbers = found.numbers()
    size = area(P, found.level)
    if size is not None:
        numbers["area"] = size
    return ConditionResult(name, "certified", summary, property="ROA", certificate=certificate, numbers=numbers)


def roa(model: "RecastModel", budget: "Budget") -> ConditionResult:
    """The largest sublevel set of the linearization's ``V`` proved a region of attraction (module docstring)."""
    from lyapcheck.sos.definiteness import is_positive_definite

    A = exact_jacobian(model)
    if isinstance(A, str):
        return ConditionResult("roa", "not_applicable", f"the map's Jacobian at the fixed point: {A}", property="ROA")
    P = rounded_p(A)
    if P is None or not is_positive_definite(P):
        return ConditionResult("roa", "not_certified", "the discrete Lyapunov equation A^T P A - P = -I of the exact "
                               "Jacobian has no positive definite solution (rounded): no quadratic V to start from",
                               property="ROA")
    found = level_search(model, P, budget, "roa")
    if isinstance(found, ConditionResult):
        return found
    return certified_region("roa", P, found, region_certificate(model, P, found),
                            discrete_interval_sentence("roa", found.level, over_box=False))


def candidate_matrix(model: "RecastModel") -> list[list[Fraction]] | str:
    """``P`` of the user's ``V = e^T P e`` (exact), or why the candidate is not such a form."""
    from lyapcheck.models.engines.interval_region import quadratic_form

    V = model.candidate_v
    if V is None:
        return "no candidate was given (--candidate)"
    P = quadratic_form(model.system.ring, V, len(model.states))
    if P is None:
        return ("the candidate is not a quadratic form e^T P e in the state deviations (a term of another degree, or "
                "a function of the states): on a map with functions the candidate class proves the sublevel sets of "
                "a quadratic V only, by ball arithmetic on the true map")
    return P


def candidate_p(model: "RecastModel") -> list[list[Fraction]] | ConditionResult:
    """``P`` of the user's ``V = e^T P e``, positive definite (checked exactly), or the candidate's result saying
    why it is not such a form (``not_applicable``) or not definite (``not_certified``): at a point and over a
    box alike."""
    from lyapcheck.sos.definiteness import is_positive_definite

    P = candidate_matrix(model)
    if isinstance(P, str):
        return ConditionResult("candidate", "not_applicable", P, property="ROA")
    if not is_positive_definite(P):
        return ConditionResult("candidate", "not_certified", "the candidate V = e^T P e has P not positive definite "
                               "(checked exactly): its sublevel sets are no bounded neighbourhoods of the fixed "
                               "point, so none is a region of attraction", property="ROA")
    return P


def candidate(model: "RecastModel", budget: "Budget") -> ConditionResult:
    """The user's quadratic ``V``: its largest level proved a region of attraction (module docstring)."""
    P = candidate_p(model)
    if isinstance(P, ConditionResult):
        return P
    found = level_search(model, P, budget, "candidate")
    if isinstance(found, ConditionResult):
        return found
    cert = {**region_certificate(model, P, found), "V_from": "candidate"}
    return certified_region("candidate", P, found, cert,
                            discrete_interval_sentence("candidate", found.level, over_box=False))


def verify_roa(model: "RecastModel", c: dict[str, Any], loops: Sequence[BallLoop | None] = (None,)
               ) -> tuple[bool, str]:
    """A ``discrete_interval`` region re-proved from its certificate: ``P`` symmetric and positive definite
    (exact), then the same cells at the stated level (at most :data:`~lyapcheck.tolerances.BALL_LEVEL_CELLS`);
    ``loops``: over a box, the map with each part of the box's parameters as balls."""
    from lyapcheck.sos.definiteness import is_positive_definite

    cert = c.get("certificate")
    if not isinstance(cert, dict) or cert.get("kind") != KIND:
        return False, f"a certified roa on a map with functions states a certificate of kind '{KIND}'"
    n = len(model.states)
    P = [[Fraction(str(x)) for x in row] for row in cert["P"]]
    level = Fraction(str(cert["level"]))
    if len(P) != n or any(len(row) != n for row in P) or any(P[i][j] != P[j][i] for i in range(n) for j in range(n)):
        return False, "P must be a symmetric matrix over the states"
    if not level > 0 or not is_positive_definite(P):
        return False, "P must be positive definite and the level > 0 (checked exactly)"
    ok, cells, why = prove_on_all(model, P, level, tolerances.BALL_LEVEL_CELLS, loops)
    if not ok:
        return False, f"V(F(e)) < V(e) is not proved on {{V <= {cert['level']}}}: {why}"
    return True, f"V(F(e)) < V(e) proved again on {{V <= {cert['level']}}} by ball arithmetic ({cells} cells)"


def verify_candidate(model: "RecastModel", c: dict[str, Any]) -> tuple[bool, str]:
    """A certified ``candidate``: its certificate says the V is the user's (``"V_from": "candidate"``), its
    ``P`` is the candidate's as the model text and the document's candidate give it (exactly), and the
    level is proved again (:func:`verify_roa`)."""
    cert = c.get("certificate")
    if not isinstance(cert, dict) or cert.get("V_from") != "candidate":
        return False, "a certified candidate on a map with functions states the user's V (\"V_from\": \"candidate\")"
    P = candidate_matrix(model)
    if isinstance(P, str):
        return False, f"the document's candidate: {P}"
    stated = [[Fraction(str(x)) for x in row] for row in cert["P"]]
    if stated != P:
        return False, "the stated P is not the candidate's (V = e^T P e of the document's candidate text)"
    return verify_roa(model, c)


__all__ = ["KIND", "NOT_YET", "exact_jacobian", "linearization", "verify_linearization", "MapDifference",
           "MapGeometry", "Found", "prove_on_all", "level_search", "region_certificate", "roa", "verify_roa",
           "certified_region", "candidate_matrix", "candidate_p", "candidate", "verify_candidate", "area"]

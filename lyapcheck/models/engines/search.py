"""What every generic class's search shares: its time budget, its solver log, and the way from a
polynomial's coefficients to a program's parameters and back to an exact point.

A class's work is bounded by counts that are the same on any machine and under any load: each
solve by the solver's iterations (:data:`~lyapcheck.tolerances.SOLVER_MAX_ITER`), and a step of a
search by its budget of solves (:class:`SolveLimit`, :meth:`Search.within`; a step that spends it
raises :class:`SolvesSpent`, and its class says so in its reason). The wall-time budget
(:class:`Budget`) is only a safety net: every solve gets at most the class's time left (Clarabel's
own time limit, far above a normal solve), and a search that runs out raises
:class:`BudgetExhausted`, which the class reports as ``inconclusive`` naming the limit. The budget
is checked before and after each program is built, each solve, and between the steps of each exact
rounding (:func:`lyapcheck.sos.rounding.exact_point`'s ``checkpoint``), so that a class ends within
its limit plus the longest single step (one solve, capped by its time limit, or one rounding step).

A search that has several forms to try (``sos_gas`` on a network) may order them by what they will
cost against the budget: :func:`estimated_seconds` of a program (from its size, with the rates of
:mod:`lyapcheck.tolerances`) against the budget less the estimates of the work already done
(:meth:`Budget.fits`), never against the clock, so that the order is the same under load.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Iterable, Mapping, Sequence

from lyapcheck import tolerances as tol
from lyapcheck.sos.polynomials import Monomial, Poly, Ring
from lyapcheck.sos.structure import Coefficients, Structure

if TYPE_CHECKING:  # pragma: no cover
    # numpy, the solver and the rounding are imported by the first solve: a run whose certificates
    # all come from the store (lyapcheck.models.engines.store) re-checks them exactly without any of them
    import numpy as np

    from lyapcheck.sos.program import Gram, Solution, Term
    from lyapcheck.sos.rounding import ExactPoint


#: a solve whose margin (smallest Gram eigenvalue, scaled coordinates) is above minus this is handed
#: to the exact check: on a degenerate face the solver's margin is 0 give or take 1e-12, and the
#: rounded, projected point may still be exactly feasible (the check decides, never the margin)
EXACT_TRY_MARGIN = 1e-9


class BudgetExhausted(Exception):
    """A class's search reached its time limit (the safety net), or one of its steps spent its
    budget of solves (:class:`SolvesSpent`)."""


@dataclass
class SolveLimit:
    """A budget of solves for one step of a search (a template, the V-s iteration, the enlarging
    rounds): ``solves`` at most, ``per`` the step in a reason's words (``per template``), and
    ``limit_name`` the constant that sets it. A count, so that a loaded machine does the same
    work and gets the same outcome as an idle one."""

    solves: int
    per: str
    limit_name: str
    used: int = 0

    def words(self) -> str:
        """``the search's budget of 12 solves per template was spent`` (a reason's words)."""
        return f"the search's budget of {self.solves} solve{'s' if self.solves != 1 else ''} {self.per} was spent"


class SolvesSpent(BudgetExhausted):
    """A step of a search spent its budget of solves (:class:`SolveLimit`); its message is the
    limit's words and the constant's name."""

    def __init__(self, limit: SolveLimit) -> None:
        self.limit = limit
        super().__init__(f"{limit.words()} ({limit.limit_name})")


def _now() -> float:
    """The clock of :class:`Budget` (one name, so that a test can show that no outcome depends on it)."""
    return time.perf_counter()


@dataclass
class Budget:
    """A wall-time limit for one class (``limit_name`` names the constant, for the message).

    A safety net, not a decider: every step whose outcome a test or a documented figure depends
    on bounds its work by counts (cells, iterations, solves: the ball-arithmetic route's
    :data:`~lyapcheck.tolerances.INTERVAL_ATTEMPT_CELLS`, the solves of :class:`SolveLimit`), so
    that a loaded machine gets the same outcome; reaching this limit makes the class inconclusive
    with a reason that names it as the safety net."""

    seconds: float
    limit_name: str
    start: float = field(default_factory=lambda: _now())
    #: the estimated seconds (:func:`estimated_seconds`) of the solves and roundings done so far: the
    #: run's work on a deterministic clock (:meth:`fits`)
    estimated: float = 0.0

    def left(self) -> float:
        return self.seconds - (_now() - self.start)

    def record(self, estimated: float) -> None:
        """One solve (or rounding) done, at its estimated seconds (for :meth:`fits`)."""
        self.estimated += estimated

    def fits(self, estimate: float, reserve: float = 0.0) -> bool:
        """Whether work estimated at ``estimate`` seconds, with ``reserve`` seconds kept for work that
        must follow it, fits in the budget less the estimates of the work already done. Estimates
        only, never the clock: the order a search takes from it is the same on a loaded machine
        (issue 40: work decides outcomes, the clock only guards), and the time limit stays the
        safety net."""
        return estimate + reserve <= self.seconds - self.estimated

    def reached(self) -> str:
        """The detail line of this limit reached (it names the limit as the safety net it is)."""
        return f"time limit of {self.seconds:g} s reached (a safety net: {self.limit_name})"

    def check(self) -> None:
        if self.left() <= 0:
            raise BudgetExhausted(self.reached())


@dataclass
class Search:
    """One class's search: the ring of its polynomials, its budget, its log of solves and the
    budgets of solves of the steps it is in (:meth:`within`)."""

    ring: Ring
    budget: Budget
    log: list[dict[str, Any]] = field(default_factory=list)
    limits: tuple[SolveLimit, ...] = ()

    def within(self, solves: int, per: str, limit_name: str) -> "Search":
        """This search (same ring, budget and log) inside a step with a budget of ``solves`` solves
        (:class:`SolveLimit`): a solve past it raises :class:`SolvesSpent`."""
        return Search(self.ring, self.budget, self.log, (*self.limits, SolveLimit(solves, per, limit_name)))

    def over(self, ring: Ring) -> "Search":
        """This search (same budget, log and budgets of solves) for programs whose polynomials live in
        ``ring``: a class that builds its own view of the loop (a robust field keeps only the
        disturbances with a bound > 0 that enter it) rounds its points in that view's ring."""
        return Search(ring, self.budget, self.log, self.limits)

    def solve(self, structure: Structure, values: "ParameterValues") -> Solution:
        from lyapcheck.sos.program import SOSProgram

        for limit in self.limits:
            if limit.used >= limit.solves:
                raise SolvesSpent(limit)
        self.budget.check()
        program = SOSProgram.of(structure)
        self.budget.check()
        for limit in self.limits:
            limit.used += 1
        # the class's time left is the solver's limit: a safety net far above a normal solve, whose
        # length SOLVER_MAX_ITER bounds (a count of iterations)
        solution = program.solve(values.floats, time_limit=max(self.budget.left(), 0.05))
        # the solve's share of the estimate (the rounding's is recorded by exact): the run's work so far
        self.budget.record(estimated_seconds(structure) / 2)
        entry = solution.report.to_json()
        entry["program"] = structure.key()
        if "t" in solution.scalars:
            entry["margin"] = solution.scalars["t"]
        self.log.append(entry)
        return solution

    def exact(self, structure: Structure, solution: Solution, values: "ParameterValues") -> ExactPoint | None:
        from lyapcheck.sos.rounding import exact_point

        if not solution.usable:
            return None
        # the budget is checked between the rounding's steps: a large program's rounding takes as
        # long as its solve, and must not carry the class past its time limit
        point = exact_point(self.ring, structure, solution, values.exact, checkpoint=self.budget.check)
        self.budget.record(estimated_seconds(structure) / 2)
        return point

    def solve_exact(self, structure: Structure, values: "ParameterValues", *, near_only: bool = False
                    ) -> tuple[ExactPoint | None, Solution]:
        """One solve and, when the solver returned a point, its exact rounding (None when there is
        none): what every class's attempt does before its exact check. ``near_only``: round only a point
        whose margin ``t`` is not below ``-EXACT_TRY_MARGIN`` (a program without ``t`` counts as near):
        a clearly infeasible point is not worth the rounding."""
        solution = self.solve(structure, values)
        if near_only and solution.scalars.get("t", 0.0) < -EXACT_TRY_MARGIN:
            return None, solution
        return self.exact(structure, solution, values), solution


def exact_grams(structure: Structure, point: ExactPoint) -> dict[str, Any]:
    """Every Gram matrix of an exact point, as :class:`~lyapcheck.sos.certificates.GramPoly` by name."""
    from lyapcheck.sos.certificates import GramPoly

    return {g.name: GramPoly.of(g.basis, point.grams[g.name]) for g in structure.grams}


def estimated_seconds(structure: Structure) -> float:
    """The estimated seconds of one solve of ``structure`` and its exact rounding on an idle core:
    :data:`~lyapcheck.tolerances.ESTIMATE_SOLVE_FLOOR_S` plus its semidefinite work units
    (:meth:`~lyapcheck.sos.structure.Structure.cost`) at :data:`~lyapcheck.tolerances.PSD_WORK_PER_SECOND`
    and its cone decisions (:meth:`~lyapcheck.sos.structure.Structure.cone_size`) at
    :data:`~lyapcheck.tolerances.CONE_DECISIONS_PER_SECOND`. An estimate, for ordering a search's
    forms against its time (:meth:`Budget.fits`); never part of a decision about a certificate."""
    return (tol.ESTIMATE_SOLVE_FLOOR_S + structure.cost() / tol.PSD_WORK_PER_SECOND
            + structure.cone_size() / tol.CONE_DECISIONS_PER_SECOND)


def why_none(solution: Solution) -> str:
    """Why a solve gave no certificate, in the words of the not-certified reasons: the solver proved
    the program infeasible, returned no point, or its point failed the exact check."""
    if solution.report.outcome == "infeasible":
        return "the solver proved the program infeasible"
    if solution.usable:
        return "the exact check refused the solver's point"
    return f"the solver returned no point ({solution.report.raw_status})"


@dataclass
class ParameterValues:
    """Every parameter of a program, as floats (for the solver) and exactly (for the rounding)."""

    floats: dict[str, np.ndarray] = field(default_factory=dict)
    exact: dict[str, list[Fraction]] = field(default_factory=dict)

    def set_poly(self, ring: Ring, name: str, p: Poly, support: Iterable[Monomial]) -> None:
        """Parameter ``name`` = ``p``'s coefficients over ``support`` in :func:`canonical` order (the
        order :func:`param` declares)."""
        import numpy as np

        support = canonical(support)
        terms = ring.terms(p)
        unknown = [m for m in terms if m not in set(support)]
        if unknown:
            raise ValueError(f"parameter {name}: the polynomial has monomials outside its support: {unknown[:3]}")
        exact = [terms.get(tuple(m), Fraction(0)) for m in support]
        self.exact[name] = exact
        self.floats[name] = np.array([float(c) for c in exact])

    def set_matrix(self, name: str, M: np.ndarray) -> None:
        import numpy as np

        self.floats[name] = np.asarray(M, dtype=np.float64)

    def set_scalar(self, name: str, value: float) -> None:
        import numpy as np

        self.floats[name] = np.asarray(float(value), dtype=np.float64)


def canonical(support: Iterable[Monomial]) -> list[Monomial]:
    """A support's one order: sorted, without repeats."""
    return sorted(set(tuple(m) for m in support))


def param(name: str, support: Iterable[Monomial]) -> Coefficients:
    """Coefficients given by parameter ``name``, one entry per monomial of ``support`` (canonical order)."""
    return Coefficients.parameter(name, canonical(support))


def literal(ring: Ring, terms: Mapping[Monomial, Fraction | int]) -> Coefficients:
    return Coefficients.literal(terms)


def one(ring: Ring, c: int | Fraction = 1) -> Coefficients:
    """The constant polynomial ``c`` as literal coefficients."""
    return Coefficients.literal({tuple([0] * ring.nvars): c})


def support_of(ring: Ring, *polys: Poly) -> list[Monomial]:
    out: set[Monomial] = set()
    for p in polys:
        out |= set(ring.support(p))
    return sorted(out)


def poly_times_support(ring: Ring, p_support: Sequence[Monomial], q_support: Sequence[Monomial]) -> set[Monomial]:
    return {tuple(a + b for a, b in zip(m1, m2)) for m1 in p_support for m2 in q_support}


def box_multipliers(nvars: int, n_states: int, target: Iterable[Monomial], with_states: bool,
                    generators: Sequence[Sequence[int]] = (), prefix: str = "r",
                    box_vars: Sequence[int] | None = None, margin: bool | str = True
                    ) -> tuple[list["Gram"], list["Term"]]:
    """The S-procedure terms of a box: for each box variable ``u_j`` (by default the ring's variables
    after the first ``n_states``), a Gram ``r_j`` and the term ``-r_j (1 - u_j^2)``.

    ``r_j``'s basis matches the identity's other terms (``target``, their generic support): half
    its degree in the states, and half its degree in the box's parameters less one (the
    multiplier's ``u_j^2`` adds two), so that ``r_j (1 - u_j^2)`` produces no monomial the other
    terms cannot balance. With ``with_states`` every basis monomial holds a state (``r_j`` vanishes
    at ``z = 0``, as an identity whose other terms vanish there needs). Empty lists when the ring
    has no box variables. ``margin`` as :class:`~lyapcheck.sos.program.Gram`'s: the program's margin
    variable (a program that maximizes it), or a floor parameter (a program with another objective,
    where the margin variable is free and would let the multipliers go indefinite).
    """
    from lyapcheck.sos import bases
    from lyapcheck.sos.polynomials import monomials
    from lyapcheck.sos.program import Gram, Term

    box_vars = list(range(n_states, nvars)) if box_vars is None else list(box_vars)
    if not box_vars:
        return [], []
    support = list(target)
    state_half = max((sum(m[:n_states]) for m in support), default=2) // 2
    param_half = max(max((sum(m[n_states:]) for m in support), default=0) - 2, 0) // 2
    candidates = [m for m in monomials(nvars, 0, state_half + param_half)
                  if sum(m[:n_states]) <= state_half and sum(m[n_states:]) <= param_half
                  and (not with_states or sum(m[:n_states]) >= 1)]
    # r_j (1 - u_j^2) subtracts z^(2a): keep a only where the other terms' Newton polytope holds 2a
    # (else that entry is forced to 0, and no margin is possible); the z^(2a) u_j^2 it adds is what
    # the multiplier is for (it balances the terms odd in u_j)
    basis = [m for m, inside in zip(candidates, bases.inside_half_polytope(candidates, support)) if inside]
    if not basis:
        return [], []
    blocks = tuple(map(tuple, bases.character_blocks(basis, generators)))
    grams, terms = [], []
    for j in box_vars:
        name = f"{prefix}{j}"
        sq = tuple(2 * int(k == j) for k in range(nvars))
        grams.append(Gram(name, tuple(basis), blocks, margin=margin))
        terms.append(Term(Coefficients.literal({tuple([0] * nvars): -1, sq: 1}), name))
    return grams, terms


def multiplier_variable(name: str) -> int:
    """The box variable a multiplier Gram is named after (``r3``, ``rD3`` -> 3)."""
    digits = name[len(name.rstrip("0123456789")):]
    return int(digits)


def multiplier_grams(structure: Structure, prefix: str = "r") -> list["Gram"]:
    """The structure's box multipliers of one identity (named ``<prefix><variable>``)."""
    return [g for g in structure.grams if g.name.startswith(prefix) and g.name[len(prefix):].isdigit()]


def box_multipliers_of(point_grams: Mapping[str, Any], grams: Sequence["Gram"]) -> list[tuple[int, Any]]:
    """The exact multipliers ``(variable, Gram)`` of a solved box program."""
    from lyapcheck.sos.certificates import GramPoly

    return [(multiplier_variable(g.name), GramPoly.of(g.basis, point_grams[g.name])) for g in grams]


def box_multipliers_from_json(data: Sequence[Mapping[str, Any]], nvars: int) -> list[tuple[int, Any]]:
    from lyapcheck.sos.certificates import GramPoly

    from lyapcheck.sos.certificates import exponent

    return [(exponent(item["variable"], "box_multipliers.variable", nvars), GramPoly.from_json(item["gram"], nvars))
            for item in data]


def box_support(box_grams: Sequence["Gram"], nv: int) -> set[Monomial]:
    """The monomials the box's multiplier terms ``r_j (1 - u_j^2)`` can produce."""
    out: set[Monomial] = set()
    for g in box_grams:
        j = multiplier_variable(g.name)
        shifts = (tuple([0] * nv), tuple(2 * int(k == j) for k in range(nv)))
        products = {tuple(a + b for a, b in zip(g.basis[i], g.basis[k])) for idx in g.blocks for i in idx for k in idx}
        out |= {tuple(a + b for a, b in zip(m, s)) for m in products for s in shifts}
    return out

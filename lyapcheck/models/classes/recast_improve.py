"""Enlarging a recast loop's region of attraction beyond the linearization's quadratic ``V``.

The V-s iteration (Jarvis-Wloszek et al., "Some controls applications of sum of squares
programming", CDC 2003; Topcu, Packard & Seiler, Automatica 2008), alternating two convex steps:

1. **level step** (exact, :func:`lyapcheck.models.classes.recast_classes.certify_region`): for a fixed
   ``V``, the largest level ``b`` with ``-V' - eps l - rho (b - V) >= 0`` on the recasting's set, and
   its multiplier ``rho``;
2. **V step** (numerical only): with ``rho`` fixed and ``V`` scaled to level 1, a new ``V`` that
   keeps ``V - eps l >= 0`` and ``-V' - eps l - rho (1 - V) >= 0`` and is as small as it can be on
   sample states whose simulated trajectories of the true loop converge (a linear objective: their
   mean ``V``), so that ``{V <= 1}`` grows towards the simulated region of attraction.

The V step's answer is only a candidate: its coefficients are rounded to short rationals and the
level step certifies it exactly, from scratch, like any other ``V``. Nothing here decides anything.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from lyapcheck import tolerances
from lyapcheck.degrees import searched_degrees
from lyapcheck.sos.polynomials import Monomial, Poly, monomials, to_fmpq

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.recast_classes import Loop, Region
    from lyapcheck.models.engines.search import Budget

#: V-s iterations at most (each a level step and a V step)
VS_ITERATIONS: Final = 4
#: degrees of the improved V, in turn
VS_DEGREES: Final = (2, 4)
#: sample states for the V step's objective (those that converge in simulation)
VS_SAMPLES: Final = 200
#: the V step's margin of the decrease (times |z|^2): the level step's smallest (a larger one
#: shrinks the set the V step can find, 63 % -> 40 % of the pendulum's box)
VS_MARGIN: Final = Fraction(1, 10000)
#: the V step's margin of positivity: twice the level step's largest, room for the rounding
VS_POSITIVITY_MARGIN: Final = Fraction(1, 50)
#: how long each sample is simulated (the loop's time unit)
VS_HORIZON_S: Final = 25.0
#: bits kept of the V step's coefficients (short certificates; the level step decides)
VS_ROUND_BITS: Final = 20
#: a step that adds less than this share of the converging samples ends the iteration at its degree
VS_MIN_GAIN: Final = 0.01
# The iteration's work is counted, not timed (the same regions on any machine): a V step is one
# solve (its length bounded by SOLVER_MAX_ITER), a level step at most
# lyapcheck.tolerances.VS_LEVEL_SOLVES solves, the whole iteration at most VS_SOLVES.


def target_samples(loop: "Loop", box: tuple[np.ndarray, np.ndarray], rng: np.random.Generator) -> np.ndarray:
    """Deviations in the box whose simulated trajectories of the true loop converge (modulo 2 pi in
    the angles): the region the V step pulls ``{V <= 1}`` towards."""
    from lyapcheck.models.engines.recast_numeric import converges_modulo

    lo, hi = box
    Z = lo + (hi - lo) * rng.random((VS_SAMPLES * 3, loop.n))
    eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
    ok = converges_modulo(loop.system, Z + eq, tuple(loop.angles), horizon=VS_HORIZON_S)
    return Z[ok][:VS_SAMPLES]


def improved_regions(loop: "Loop", first: "Region", budget: "Budget", box: tuple[np.ndarray, np.ndarray]
                     ) -> tuple[list["Region"], list[str]]:
    """Regions from the V-s iteration started at ``first`` (each certified exactly by the level
    step), and what was tried."""
    from lyapcheck.models.classes.recast_classes import certify_region
    from lyapcheck.models.engines.recast_numeric import v_values
    from lyapcheck.models.engines.search import BudgetExhausted, Search

    samples = target_samples(loop, box, np.random.default_rng(1))
    tried: list[str] = []
    if len(samples) == 0:
        return [], ["the V-s iteration: no sample of the box converges in simulation"]
    out: list["Region"] = []
    # the whole iteration's budget of solves: what is left of the class's work goes to the exact
    # checks of the regions found, whatever the machine's speed
    search = Search(loop.ring, budget).within(tolerances.VS_SOLVES, "for the V-s iteration",
                                              "lyapcheck.tolerances.VS_SOLVES")

    def covered(r: "Region") -> float:
        """The share of the converging samples inside a region (the iteration's progress)."""
        return float(np.mean(v_values(loop.system, r.V, samples) <= float(r.level)))

    best, best_share = first, covered(first)
    for degree in searched_degrees(VS_DEGREES):
        region = best
        for k in range(VS_ITERATIONS):
            label = f"the V-s iteration (degree {degree}, step {k + 1})"
            try:
                outside = samples[v_values(loop.system, region.V, samples) > float(region.level)]
                V = v_step(loop, region.V * to_fmpq(1 / region.level), region.rho, degree,
                           outside if len(outside) else samples, search)
                if isinstance(V, str):
                    tried.append(f"{label}: {V}")
                    break
                # each level step gets a budget of solves (a count: the same steps on any machine)
                level_search = search.within(tolerances.VS_LEVEL_SOLVES, "per level step",
                                             "lyapcheck.tolerances.VS_LEVEL_SOLVES")
                found = certify_region(loop, V, level_search, label, start=Fraction(1, 2))
            except BudgetExhausted as exc:  # a budget of solves spent, or the class's time limit (the safety net)
                tried.append(f"{label}: {exc}")
                return out, tried
            if isinstance(found, str):
                tried.append(f"{label}: {found}")
                break
            share = covered(found)
            stopped = f" (the largest proved when {found.stopped})" if found.stopped else ""
            tried.append(f"{label}: level {float(found.level):.6g}{stopped}, {100 * share:.1f} % of the converging "
                         "samples")
            out.append(found)
            region = found
            if share < best_share + VS_MIN_GAIN:  # no longer growing: the next degree, from the best set
                break
            best, best_share = found, share
    return out, tried


def v_step(loop: "Loop", V_scaled: Poly, rho: Poly, degree: int, samples: np.ndarray, search: Any) -> Poly | str:
    """One V step (see the module docstring): a new V of ``degree`` in the loop's V variables, or why none."""
    from lyapcheck.models.classes.recast_classes import common_denominator, lie, state_square
    from lyapcheck.models.engines.recast_numeric import variable_values, poly_values
    from lyapcheck.models.engines.recast_sos import ConditionProgram, known_values
    from lyapcheck.models.engines.search import ParameterValues
    from lyapcheck.models.classes.recast_classes import _set

    ring = loop.ring
    v_vars = loop.v_variables()
    basis: list[Monomial] = [m for m in monomials(ring.nvars, 1, degree)
                             if all(m[i] == 0 for i in range(ring.nvars) if i not in v_vars)]
    names = [ring.names[i] for i in v_vars]
    N, D, _ = common_denominator(loop, names)
    eps = VS_MARGIN
    l2 = state_square(loop)
    # the objective's weights: each basis monomial's mean over the samples (deviations)
    system = loop.system
    eq = np.array([float(system.values[s]) for s in system.states])
    cols = variable_values(system, samples + eq)
    shifted = {n: v - float(system.values[n]) if n in system.values else v for n, v in cols.items()}
    weights = [float(np.mean(poly_values(ring, ring.monomial(m), shifted, len(samples)))) for m in basis]
    program = ConditionProgram(ring, loop.relations, frozenset(), loop.unused(), margin=False, roots=loop.roots())
    for k in range(len(basis)):
        program.free(f"v{k}")
    pos_terms = [(f"v{k}", ring.monomial(m)) for k, m in enumerate(basis)]
    dec_terms = [(f"v{k}", -lie(loop, ring.monomial(m), N) + rho * ring.monomial(m)) for k, m in enumerate(basis)]
    top = max((sum(mm) for _, p in dec_terms for mm in ring.support(p)), default=2)
    known_dec = -l2 * to_fmpq(eps) - rho
    # the new set contains the old one: 1 - V >= s (1 - V_old) (the iteration never shrinks it)
    zero = tuple([0] * ring.nvars)
    contain_terms = [(f"v{k}", -ring.monomial(m)) for k, m in enumerate(basis)]
    old_support = sorted(set(ring.support(V_scaled)) | {zero})
    why = program.condition("P", ring.support(l2), pos_terms, degree) or \
        program.condition("D", ring.support(known_dec), dec_terms, top) or \
        program.condition("C", [zero], contain_terms, degree, region_support=old_support, vanishing=False)
    if why is not None:
        return f"the V step was not built: {why}"
    program.minimize([(f"v{k}", w) for k, w in enumerate(weights)])
    values = ParameterValues()
    # positivity with the level step's largest margin, so that the rounded V passes its exact check there
    _set(values, *known_values(ring, "P", -l2 * to_fmpq(VS_POSITIVITY_MARGIN), ring.support(l2)))
    _set(values, *known_values(ring, "D", known_dec, ring.support(known_dec)))
    _set(values, *known_values(ring, "C", ring.constant(1), [zero]))
    old_terms = ring.terms(V_scaled - 1)
    _set(values, "W_C", [old_terms.get(m, Fraction(0)) for m in old_support])
    solution = search.solve(program.structure(), values)
    if not solution.usable:
        from lyapcheck.models.engines.search import why_none

        return f"the V step found no V ({why_none(solution)})"
    from lyapcheck.sos.rounding import round_scalar

    V = ring.zero()
    peak = max(abs(solution.scalars[f"v{k}"]) for k in range(len(basis)))
    for k, m in enumerate(basis):
        value = solution.scalars[f"v{k}"]
        c = round_scalar(value, VS_ROUND_BITS) if abs(value) > 1e-9 * peak else 0
        if c:
            V += ring.monomial(m, c)
    del D
    return V if not V.is_zero() else "the V step gave V = 0"


__all__ = ["improved_regions", "v_step", "target_samples"]

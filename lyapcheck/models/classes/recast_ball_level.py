"""The largest level of a quadratic ``V = z^T P z`` (the LQR cost-to-go, a Lyapunov equation's ``P``)
proved on the true loop by ball arithmetic, at any number of states.

The first level is the exact local argument: the Hessian of ``V'`` is negative definite on a box
``N = prod [-r_i, r_i]`` around the equilibrium shaped like the ellipsoid's bounding box (ball
arithmetic, one enclosure of the whole box: :func:`~lyapcheck.models.engines.interval_region.local_box`),
and ``level (P^-1)_ii <= r_i^2`` for every state (rational arithmetic) puts the whole ellipsoid
``{V <= level}`` inside ``N``. A strict
local Lyapunov function (``V' `` with a negative definite Hessian at the equilibrium, as the
linearization's ``P`` has) always gets that level, however many states the loop has. Larger levels
are the same claim over a larger box, whose faces are proved exactly (``level (P^-1)_ii < c^2``)
and whose cells outside ``N`` are bisected (each attempt within :data:`~lyapcheck.tolerances.BALL_LEVEL_CELLS`
cells, the whole search within :data:`~lyapcheck.tolerances.BALL_LEVEL_TOTAL_CELLS`, from 4 states
:data:`~lyapcheck.tolerances.ELLIPSOID_LEVEL_TOTAL_CELLS`);
:func:`~lyapcheck.models.classes.level_search.largest_proved_level` keeps the largest level proved. The certificate is the ball-arithmetic route's (``kind`` "interval", ``"boundary": "exact"``):
``verify`` runs the same proof again.

From 4 states (issue 42) the decrease is proved on cells of the ellipsoid's own coordinates
(:mod:`lyapcheck.models.engines.ellipsoid_cells`), where an attempt costs about the same cells at any
level: the search then starts at JUMP_SHARE of the level at which sampling first sees ``V' >= 0``
(:func:`sampled_jump`; it only proposes, the proof decides), doubles it once proved and bisects, and
where that first attempt fails grows from the local level as below 4 states (:func:`jumped_search`). That
first attempt has fewer cells (:data:`~lyapcheck.tolerances.ELLIPSOID_JUMP_CELLS`), so that a sampled level
too large for the cells leaves the growth more of them; an attempt that fails at a point proved in the set
where ``V' >= 0`` lowers the top of the search's bracket to ``V`` there.
Its budgets count cells of the cart-pole's cost (:func:`cell_cost`).
"""

from __future__ import annotations

import time
from fractions import Fraction
from typing import Any, Final

from lyapcheck import tolerances
from lyapcheck.models.classes.recast_classes import Loop
from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Poly

#: levels tried upwards from the local one (each the last times BALL_LEVEL_GROWTH), then halvings of
#: the bracket between the largest proved and the smallest failed level
BALL_LEVEL_GROWTH: Final = Fraction(4)
BALL_LEVEL_GROWTH_STEPS: Final = 8
BALL_LEVEL_BISECTIONS: Final = 4
#: each state's side of the box is the ellipsoid's extent times this (room for the exact faces)
BALL_LEVEL_BOX_ROOM: Final = Fraction(9, 8)
#: the first level tried for the local one has an ellipsoid this wide in its widest state; each next
#: is a quarter of the last (the ellipsoid half as wide), at most BALL_LEVEL_LOCAL_STEPS of them
BALL_LEVEL_FIRST_EXTENT: Final = 4
BALL_LEVEL_LOCAL_STEPS: Final = 40
#: significant bits of a level tried
LEVEL_BITS: Final = 12
#: over a box the local level is the centre's, which a corner may not share: levels below it tried, each
#: half the last (at a point the local level is proved without a cell, so none are needed)
BALL_LEVEL_BOX_HALVINGS: Final = 4


def ball_level(loop: Loop, V: Poly, budget: Budget, name: str, v_from: str, robust: Any = None
               ) -> ConditionResult | str:
    """``name``'s region ``{V <= level}`` for a positive definite quadratic form ``V`` over the states,
    proved by ball arithmetic (module docstring), or why there is none (one line). With ``robust`` (a
    :class:`~lyapcheck.models.classes.recast_interval.Robust` holding a box of parameters; ``loop`` its
    centre) every level is proved for every value of the box (the local level is the centre's, a first
    level to try), and the certificate states the box."""
    from lyapcheck.models.classes.claims import interval_sentence
    from lyapcheck.models.classes.level_search import LevelSteps, largest_proved_level
    from lyapcheck.models.classes.recast_classes import _dyadic
    from lyapcheck.models.classes.recast_interval import METHOD, certificate, prove
    from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
    from lyapcheck.models.engines.interval_region import (IntervalClaim, dyadic_ceil, inside_local_box,
                                                          inverse_diagonal, local_box, quadratic_form)

    n = loop.n
    P = quadratic_form(loop.ring, V, n)
    diagonal = None if P is None else inverse_diagonal(P)
    if diagonal is None:
        return f"{METHOD} at any number of states takes V a positive definite quadratic form in the states"

    def claim_at(level: Fraction) -> IntervalClaim:
        # each side the ellipsoid's extent with room: a dyadic above sqrt(level (P^-1)_ii) 9/8
        half = [dyadic_ceil(Fraction(float(level * d) ** 0.5) * BALL_LEVEL_BOX_ROOM) for d in diagonal]
        return IntervalClaim(V, level, tuple(-h for h in half), tuple(half), exact_boundary=True)

    # the first level: the largest (down from an ellipsoid 4 wide, by quarters) whose ellipsoid lies in the local
    # box N of its own claim, as the prover finds it: that claim is then proved without a cell
    lie = LieDerivative(BallLoop(loop.system), loop.ring, V)
    first = _dyadic(Fraction(BALL_LEVEL_FIRST_EXTENT ** 2) / max(diagonal), LEVEL_BITS)
    for _ in range(BALL_LEVEL_LOCAL_STEPS):
        claim = claim_at(first)
        radii = local_box(lie, claim.lo, claim.hi)
        if radii is not None and inside_local_box(loop.ring, claim, n, radii):
            break
        first = _dyadic(first / 4, LEVEL_BITS)
    else:
        return "the Hessian of V' is not proved negative definite on any box around the equilibrium"

    spent = [0]  # the cells of every attempt so far: the search stops at BALL_LEVEL_TOTAL_CELLS (a count)
    scale = cell_cost(lie.loop, P)  # from 4 states, the budgets are in cells of the cart-pole's cost
    whole = tolerances.BALL_LEVEL_TOTAL_CELLS if loop.n < ELLIPSOID_JUMP_STATES else \
        tolerances.ELLIPSOID_LEVEL_TOTAL_CELLS
    total, each = int(whole / scale), int(tolerances.BALL_LEVEL_CELLS / scale)
    scaled = "" if scale == 1 else f", over {float(scale):.3g} for this loop's cost of a cell"

    refuted: dict[Fraction, Fraction] = {}  # a failed level -> V at a point of its set proved to have V' >= 0

    def attempt(level: Fraction, cap: int | None = None) -> tuple[IntervalClaim, Any] | None:
        left = total - spent[0]
        if left <= 0:
            raise BudgetExhausted(f"the search's {total} cells were spent (lyapcheck.tolerances."
                                  f"{'BALL_LEVEL' if loop.n < ELLIPSOID_JUMP_STATES else 'ELLIPSOID_LEVEL'}"
                                  f"_TOTAL_CELLS{scaled})")
        if budget.left() <= 0:
            raise BudgetExhausted(budget.reached())
        claim = claim_at(level)
        cells, cells_name = (each, "BALL_LEVEL_CELLS") if cap is None or cap >= each else (cap, "ELLIPSOID_JUMP_CELLS")
        proof = prove(loop, claim, deadline=time.perf_counter() + budget.left(), robust=robust, cells=min(cells, left),
                      cells_name=f"lyapcheck.tolerances.{cells_name}{scaled}")
        spent[0] += proof.cells + proof.boundary_cells
        if not proof.ok and proof.counterexample_v is not None:
            refuted[level] = Fraction(proof.counterexample_v)
        return (claim, proof) if proof.ok else None

    # (over a box the jump's search takes the centre's local level as proved: it grows from there instead)
    jump = None if P is None or robust is not None else sampled_jump(loop, P, first)
    try:
        if jump is None:
            found = largest_proved_level(attempt, first, growth=BALL_LEVEL_GROWTH,
                                         growth_steps=BALL_LEVEL_GROWTH_STEPS,
                                         halvings=0 if robust is None else BALL_LEVEL_BOX_HALVINGS,
                                         bisections=BALL_LEVEL_BISECTIONS, rounded=lambda x: _dyadic(x, LEVEL_BITS),
                                         steps=LevelSteps(failed_at=lambda c: refuted.get(c, c)))
        else:
            found = jumped_search(attempt, first, _dyadic(jump, LEVEL_BITS), lambda x: _dyadic(x, LEVEL_BITS),
                                  failed_at=lambda c: refuted.get(c, c),
                                  jump_cells=int(tolerances.ELLIPSOID_JUMP_CELLS / scale))
    except BudgetExhausted as exc:
        return f"{METHOD}: {exc}"
    if found.proof is None or found.level is None:
        return f"{METHOD}: the local level {float(first):.3g} (the ellipsoid in the box of smallest half-width " \
               f"{min(radii)} where the Hessian of V' is negative definite) was not proved"
    claim, proof = found.proof
    cert = certificate(loop, claim, proof)
    if robust is not None:
        robust.stamp(cert)
    tried = [f"level {float(level):.6g}: {'proved' if ok else 'not proved'}" for level, ok in found.tried]
    if found.stopped:
        tried.append(f"stopped: {found.stopped}")
    return ConditionResult(name, "certified", interval_sentence(cert), property="ROA", certificate=cert,
                           numbers={"level": float(claim.level), "V_from": v_from, "cells": proof.cells,
                                    "boundary_cells": proof.boundary_cells, "proof_seconds": proof.seconds,
                                    "local_level": float(first), "tried": tried})


#: from ELLIPSOID_JUMP_STATES states (where each attempt's cells cost about the same at any level) the
#: search starts at this share of the level sampling sees V' < 0 up to, rather than growing from the
#: local level by BALL_LEVEL_GROWTH (each level proved on the way would cost a whole attempt)
ELLIPSOID_JUMP_STATES: Final = 4
JUMP_SHARE: Final = Fraction(1, 2)
#: sampled directions (in the ellipsoid's coordinates, a fixed seed) and radii along each, out to 4^JUMP_RANGE
#: times the local level (the acrobot's local level is about 1e-8 of its sampled one: 4^12 fell short)
JUMP_DIRECTIONS: Final = 4000
JUMP_RADII: Final = 64
JUMP_RANGE: Final = 18
#: bisections of the bracket above a proved sampled level
JUMP_BISECTIONS: Final = 3


#: the cost of a cell of the cart-pole (robot-cart-pole-lqr.toml) in CELL_COST's units: the budgets of
#: BALL_LEVEL_CELLS and BALL_LEVEL_TOTAL_CELLS are in cells of this cost from ELLIPSOID_JUMP_STATES states
REFERENCE_CELL_COST: Final = 3712


def cell_cost(loop: Any, P: list[list[Fraction]] | None = None) -> Fraction:
    """How many of the reference's cells one cell of this loop counts for, from ELLIPSOID_JUMP_STATES
    states (1 below): the terms' factors of the field's polynomials (its numerators, denominators and
    auxiliaries' arguments, each function 4) times ``n^3`` (a Hessian's entries, and the products of
    ``n x n`` matrices), over REFERENCE_CELL_COST, at least 1. A count from the model alone, so that the
    budget decides the same way on any machine: a cell of the 4-state acrobot or of the 6-state planar
    quadrotor takes about 2.5 times the cart-pole's time. Where the cells try the polynomial model first
    (:func:`~lyapcheck.models.engines.ellipsoid_cells.uses_model`, with V's matrix ``P``), 1: most cells then
    end at the model, whose cost is about the cart-pole's cell at any such loop."""
    from lyapcheck.models.engines.ellipsoid_cells import uses_model

    n = loop.n
    if n < ELLIPSOID_JUMP_STATES or (P is not None and uses_model(loop, P)):
        return Fraction(1)
    polys = list(loop.numerators) + [d for d in loop.denominators if d is not None] + \
        [a[3] for a in loop.auxiliaries if a[3] is not None]
    ops = sum(1 + sum(k for _, k in factors) for p in polys for _, factors in p.terms) + 4 * len(loop.auxiliaries)
    return max(Fraction(1), Fraction(ops * n ** 3, REFERENCE_CELL_COST))


def sampled_jump(loop: Loop, P: list[list[Fraction]], first: Fraction) -> Fraction | None:
    """Where the level search of a quadratic ``V = z^T P z`` starts from ELLIPSOID_JUMP_STATES states:
    JUMP_SHARE of the smallest ``V`` at which a sample (floats, a fixed seed: it only proposes a level,
    the proof decides) has ``V' >= 0``, or the largest ``V`` sampled when none has; None below those
    states, or when that is not above the local level ``first``."""
    import numpy as np

    from lyapcheck.models.engines.ellipsoid_cells import whitening
    from lyapcheck.models.engines.recast_numeric import field_values

    n = loop.n
    if n < ELLIPSOID_JUMP_STATES:
        return None
    w = whitening(P, Fraction(1))
    if w is None:
        return None
    M = np.array(w.M)
    Pf = np.array([[float(x) for x in row] for row in P])
    eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
    U = np.random.default_rng(0).normal(size=(JUMP_DIRECTIONS, n))
    U /= np.linalg.norm(U, axis=1)[:, None]
    top = float(first) * 4.0 ** JUMP_RANGE  # the largest level sampled, a factor 4^JUMP_RANGE above the local one
    radii = np.sqrt(np.geomspace(float(first), top, JUMP_RADII))
    bad = top
    with np.errstate(all="ignore"):
        for r in radii:
            Z = (U * r) @ M.T
            F = field_values(loop.system, Z + eq)
            g = 2 * np.einsum("ij,jk,ik->i", Z, Pf, F)
            V = np.einsum("ij,jk,ik->i", Z, Pf, Z)
            hit = ~(g < 0)
            if hit.any():
                bad = float(np.min(V[hit]))
                break
    level = Fraction(bad) * JUMP_SHARE
    return level if level > first else None


def jumped_search(attempt: Any, first: Fraction, start: Fraction, rounded: Any, failed_at: Any = None,
                  jump_cells: int | None = None) -> Any:
    """The level search from the sampled level ``start``: the local level ``first`` (proved without a
    cell), then ``start`` (within ``jump_cells`` cells, :data:`~lyapcheck.tolerances.ELLIPSOID_JUMP_CELLS`:
    ``attempt(level, cap)``) and, proved, its double and JUMP_BISECTIONS bisections; failed, the search of
    fewer states (growing from ``first`` by BALL_LEVEL_GROWTH) with the cells left. The largest proved
    level is kept (:func:`~lyapcheck.models.classes.level_search.largest_proved_level`): none is lost.
    ``failed_at``: a failed level's smaller level known to fail (a proved point where ``V' >= 0``), the
    top of the bracket then (:class:`~lyapcheck.models.classes.level_search.LevelSteps`).

    Growing from the local level, not bisecting (in log scale) between it and a failed ``start``: at the
    acrobot's and the pendubot's shaped V (issue 42) the attempts fail by their cells, whose count grows with
    the level beyond the Hessian zone (about 1.5 times per factor 4), while those below it cost a cell or a
    few hundred; the bracket's middle there (the geometric mean, 1e-5 to 1e-4 of ``start``) then spends the
    rest on one failure, where the growth proves each level up to the last one the cells reach."""
    from lyapcheck.models.classes.level_search import LevelSteps, largest_proved_level

    steps = LevelSteps(failed_at=failed_at)

    def jump_attempt(level: Fraction) -> Any:
        return attempt(level, jump_cells) if level == start and jump_cells is not None else attempt(level)

    local = largest_proved_level(attempt, first, growth=Fraction(1), growth_steps=1, halvings=0, bisections=0)
    try:
        found = largest_proved_level(jump_attempt, start, growth=Fraction(2), growth_steps=2, halvings=0,
                                     bisections=JUMP_BISECTIONS, rounded=rounded, steps=steps)
    except BudgetExhausted as exc:  # (the class's time, before anything above the local level was proved)
        local.stopped = str(exc)
        return local
    tried = local.tried + found.tried
    if found.level is None and not found.stopped:
        try:
            found = largest_proved_level(attempt, first, growth=BALL_LEVEL_GROWTH,
                                         growth_steps=BALL_LEVEL_GROWTH_STEPS, halvings=0,
                                         bisections=BALL_LEVEL_BISECTIONS, rounded=rounded, steps=steps)
            tried += found.tried[1:]  # (the local level again: proved without a cell)
        except BudgetExhausted as exc:  # (the local level is proved: only a spent search raises here)
            local.stopped = str(exc)
    best = found if found.level is not None and local.level is not None and found.level > local.level else local
    best.tried = tried
    return best


def state_quadratic(loop: Loop, J: list[list[Fraction]]) -> Poly | None:
    """``z^T P z`` over the states themselves (an angle too: the claim is then in the states, not modulo
    2 pi) with ``J^T P + P J = -I`` (exact), when ``P > 0``; None otherwise."""
    from lyapcheck.models.classes.linearization import lyapunov_solution
    from lyapcheck.sos.definiteness import is_positive_definite
    from lyapcheck.sos.polynomials import to_fmpq

    P = lyapunov_solution(J)
    if P is None or not is_positive_definite(P):
        return None
    ring = loop.ring
    z = [ring.gen(s) for s in loop.system.states]
    return sum((z[i] * z[j] * to_fmpq(P[i][j]) for i in range(loop.n) for j in range(loop.n)), ring.zero())


__all__ = ["ball_level", "state_quadratic"]

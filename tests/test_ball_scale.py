"""Ball arithmetic at 4 to 6 states (issue 42, items 1 and 2): the enclosures of the ellipsoid's cells
contain the true values (sampled), and the 4-state cart-pole's LQR cost-to-go gets a larger level
than the box cells gave, within the same fixed count of cells."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import flint
import numpy as np
import pytest

from lyapcheck.models.classes import recast_classes as rc
from lyapcheck.models.engines import ellipsoid_cells as ec
from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
from lyapcheck.models.engines.interval_region import quadratic_form
from lyapcheck.models.language.modelfile import load_any_model

CARTPOLE = Path(__file__).parent / "data" / "cartpole-lqr.toml"


def cartpole() -> tuple[Any, Any, LieDerivative, list[list[Fraction]]]:
    from lyapcheck.models.classes import recast_regions

    model: Any = load_any_model(CARTPOLE, candidate=CARTPOLE.read_text().splitlines()[5].lstrip("# "))
    loop = rc.for_v(recast_regions.proved_loop(model, 60), model.candidate_v)
    V = model.candidate_v
    P = quadratic_form(loop.ring, V, loop.n)
    assert P is not None
    return loop, V, LieDerivative(BallLoop(loop.system), loop.ring, V), P


def point_jet(lie: LieDerivative, z: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """``g``, its gradient and Hessian in ``z`` at a point (balls of radius 0: tight)."""
    jet = lie.jet([flint.arb(float(x)) for x in z], 2)
    assert jet.grad is not None and jet.hess is not None
    return (float(jet.value.mid()), np.array([float(x.mid()) for x in jet.grad]),
            np.array([[float(h.mid()) for h in row] for row in jet.hess]))


def contains(b: Any, x: float, slack: float = 1e-9) -> bool:
    """``x`` (a float computed at a point) lies in the ball ``b``, up to the float's own rounding."""
    return float(b.lower()) - slack * (1 + abs(x)) <= x <= float(b.upper()) + slack * (1 + abs(x))


def test_the_enclosures_of_a_cell_contain_sampled_values_of_v_dot_its_gradient_and_hessian() -> None:
    _, _, lie, P = cartpole()
    w = ec.whitening(P, Fraction(1, 10))
    assert w is not None
    geo = ec._Geometry(w, P, lie)
    M = np.array(w.M)
    rng = np.random.default_rng(7)
    n = geo.n
    for _ in range(12):
        centre = rng.uniform(-0.3, 0.3, n)
        r = rng.uniform(0.002, 0.05)
        cell = tuple((float(c - r), float(c + r)) for c in centre)
        H = geo.hessian_y(lie, cell)
        assert H is not None
        value, grad = geo.at_centre(lie, cell)
        assert grad is not None
        g_m, dg_m, _ = point_jet(lie, M @ centre)
        assert contains(value, g_m)
        for i, gi in enumerate(M.T @ dg_m):  # the gradient in y is M^T times the gradient in z
            assert contains(grad[i], gi)
        upper = geo.taylor_upper(value, grad, H, cell)
        q = geo.quadratic(cell)
        for _ in range(20):
            y = centre + rng.uniform(-r, r, n)
            g, _, Hz = point_jet(lie, M @ y)
            assert contains(upper, g)  # Taylor's theorem with the Hessian enclosed over the cell
            Hy = M.T @ Hz @ M
            for i in range(n):
                for j in range(n):
                    assert contains(H[i][j], Hy[i, j])
            assert contains(q, float(y @ np.array(w.Q, dtype=float) @ y))


def test_the_whitened_box_holds_the_ellipsoid_exactly() -> None:
    _, _, _, P = cartpole()
    level = Fraction(3, 1000)
    w = ec.whitening(P, level)
    assert w is not None
    from lyapcheck.exact import inverse

    Qinv = inverse(w.Q)
    assert all(level * Qinv[i][i] <= h * h for i, h in enumerate(w.half))
    # and Q is M^T P M exactly
    Mq = [[Fraction(x) for x in row] for row in w.M]
    n = len(P)
    assert all(w.Q[i][j] == sum(Mq[k][i] * P[k][l] * Mq[l][j] for k in range(n) for l in range(n))
               for i in range(n) for j in range(n))


def test_a_preconditioned_hessian_test_refuses_an_indefinite_enclosure() -> None:
    H = [[flint.arb(-1), flint.arb(0, 0.1)], [flint.arb(0, 0.1), flint.arb(-2)]]
    assert ec.negative_definite_preconditioned(H)
    H[1][1] = flint.arb(0.5)
    assert not ec.negative_definite_preconditioned(H)
    H = [[flint.arb(-1), flint.arb(0, 2)], [flint.arb(0, 2), flint.arb(-1)]]  # contains [[-1, 2], [2, -1]]
    assert not ec.negative_definite_preconditioned(H)


def test_a_false_claim_is_refused_with_a_point_where_v_does_not_decrease() -> None:
    from lyapcheck.models.engines.interval_region import (IntervalClaim, dyadic_ceil, inverse_diagonal,
                                                          prove_region)

    loop, V, _, P = cartpole()
    level = Fraction(100)  # far beyond the region of attraction: V' >= 0 somewhere in the ellipsoid
    diagonal = inverse_diagonal(P)
    assert diagonal is not None
    half = [dyadic_ceil(Fraction(float(level * d) ** 0.5) * Fraction(9, 8)) for d in diagonal]
    claim = IntervalClaim(V, level, tuple(-h for h in half), tuple(half), exact_boundary=True)
    proof = prove_region(loop.system, claim, cell_budget=5_000)
    assert not proof.ok and "V' >= 0" in proof.why
    assert proof.counterexample_v is not None and proof.counterexample_v <= level


@pytest.mark.slow
def test_the_cartpole_cost_to_go_gets_a_larger_level_than_the_box_cells_within_the_same_cells(monkeypatch: Any
                                                                                              ) -> None:
    """The same search (:func:`ball_level`) with the same fixed count of cells, once with the box's
    cells of 1 to 3 states, once with the ellipsoid's: the ellipsoid's proves a larger level, and
    ``verify`` re-checks it."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.classes.recast_ball_level import ball_level
    from lyapcheck.models.classes.recast_interval import check_interval
    from lyapcheck.models.engines import interval_region
    from lyapcheck.models.engines.search import Budget

    from lyapcheck.models.classes import recast_ball_level

    loop, V, _, _ = cartpole()
    monkeypatch.setattr(tolerances, "BALL_LEVEL_CELLS", 4_000)
    monkeypatch.setattr(tolerances, "BALL_LEVEL_TOTAL_CELLS", 8_000)
    monkeypatch.setattr(tolerances, "ELLIPSOID_LEVEL_TOTAL_CELLS", 8_000)
    levels = {}
    result: Any = None
    for states in (5, 4):  # 5: the box's cells and the search from the local level at 4 states (as before
        # issue 42); 4: the ellipsoid's cells and the search from the sampled level
        monkeypatch.setattr(interval_region, "ELLIPSOID_MIN_STATES", states)
        monkeypatch.setattr(recast_ball_level, "ELLIPSOID_JUMP_STATES", states)
        result = ball_level(loop, V, Budget(600, "test"), "candidate", "the LQR cost-to-go")
        assert not isinstance(result, str), result
        levels[states] = result.numbers["level"]
    assert levels[4] > 4 * levels[5], levels
    ok, why = check_interval(loop, {"certificate": result.certificate, "level": result.numbers["level"],
                                    "summary": covered(None, result.summary)})
    assert ok, why


def test_trimming_a_cell_keeps_every_point_of_the_ellipsoid_and_cuts_what_lies_outside() -> None:
    _, _, lie, P = cartpole()
    level = Fraction(1, 20)
    w = ec.whitening(P, level)
    assert w is not None
    geo = ec._Geometry(w, P, lie)
    Q = np.array(w.Q, dtype=float)
    c = flint.arb(float(level))
    rng = np.random.default_rng(3)
    trimmed = 0
    for _ in range(40):
        u = rng.normal(size=4)
        centre = u / np.linalg.norm(u) * float(level) ** 0.5  # on the boundary of E (Q near the identity)
        r = 2.0 ** -int(rng.integers(3, 7))
        cell = tuple((float(x - r), float(x + r)) for x in centre)
        cut = ec._trim(geo, cell, c)
        assert all(a <= a2 <= b2 <= b for (a, b), (a2, b2) in zip(cell, cut))
        trimmed += cut != cell
        for _ in range(200):
            y = centre + rng.uniform(-r, r, 4)
            if y @ Q @ y <= float(level) * (1 - 1e-9):
                assert all(a2 <= yi <= b2 for yi, (a2, b2) in zip(y, cut))
    assert trimmed >= 10  # cells across the boundary lose slabs


def test_the_pieces_of_a_cell_tile_it_and_are_cut_where_the_weights_are() -> None:
    cell = ((-0.5, 0.5), (0.0, 0.25), (1.0, 2.0))
    pieces = ec._pieces(cell, [1e-3] * 3, [1.0, 0.0, 10.0], margin=1e-6)
    assert pieces is not None and len(pieces) == 2 ** ec.MAX_PIECES_HALVINGS
    volume = sum(np.prod([b - a for a, b in p]) for p in pieces)
    assert volume == pytest.approx(np.prod([b - a for a, b in cell]))
    assert all(a >= lo and b <= hi for p in pieces for (a, b), (lo, hi) in zip(p, cell))
    assert all(p[0] == cell[0] and p[1] == cell[1] for p in pieces)  # the heavy side takes both halvings
    assert sorted(p[2] for p in pieces) == [(1.0, 1.25), (1.25, 1.5), (1.5, 1.75), (1.75, 2.0)]
    # a margin the first halving already meets: two pieces, as a split
    assert len(ec._pieces(cell, [1e-3] * 3, [1.0, 0.0, 10.0], margin=100.0) or ()) == 2
    assert ec._pieces(cell, [10.0] * 3, [1.0, 1.0, 1.0], margin=1e-6) is None  # every side at the finest

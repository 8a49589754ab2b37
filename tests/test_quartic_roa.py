"""The region of attraction of a V of degree above 2 proved by ball arithmetic on cells of its quadratic
part's whitened coordinates (issue 42, :mod:`lyapcheck.models.engines.quartic_cells`): a 2-state
damped pendulum gets a quartic V's level within a small count of cells, a level at which V' > 0
somewhere in the set is never proved, and the enclosures of the cart-pole's cells contain sampled values."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import flint
import numpy as np

from lyapcheck.models.engines import quartic_cells as qc
from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
from lyapcheck.models.language.modelfile import load_any_model

PENDULUM = """
[model]
name = "damped pendulum"
states = ["th", "w"]

[dynamics]
th = "w"
w = "-sin(th) - w"
"""

#: J = [[0, 1], [-1, -1]], J^T P + P J = -I gives P = [[3/2, 1/2], [1/2, 1]]; plus a quartic term
QUARTIC = {(2, 0): Fraction(3, 2), (1, 1): Fraction(1), (0, 2): Fraction(1), (4, 0): Fraction(1, 100)}
#: a small count of cells (the test's work budget: the outcome does not depend on the machine)
BUDGET = 4000


def pendulum(tmp_path: Path, terms: dict[tuple[int, int], Fraction]) -> tuple[Any, Any, Any]:
    path = tmp_path / "pendulum.toml"
    path.write_text(PENDULUM)
    model: Any = load_any_model(path)
    system = model.system
    ring = system.ring
    V = ring.from_terms({m + (0,) * (ring.nvars - 2): c for m, c in terms.items()})
    return system, ring, V


def proof(tmp_path: Path, terms: dict[tuple[int, int], Fraction], level: Fraction, box_level: Fraction) -> qc.QuarticProof:
    system, ring, V = pendulum(tmp_path, terms)
    return qc.prove_sublevel(LieDerivative(BallLoop(system), ring, V), ring, V, level, box_level, BUDGET)


def test_a_quartic_v_of_the_damped_pendulum_is_proved_on_its_sublevel_set_within_a_small_budget(tmp_path: Path) -> None:
    found = proof(tmp_path, QUARTIC, Fraction(1), Fraction(2))
    assert found.ok, found.why
    assert 0 < found.face_cells and found.cells + found.face_cells <= BUDGET
    again = proof(tmp_path, QUARTIC, Fraction(1), Fraction(2))  # deterministic: verify repeats it cell for cell
    assert (again.ok, again.face_cells, again.cells) == (True, found.face_cells, found.cells)


def test_a_level_where_v_dot_is_positive_in_the_set_is_never_proved(tmp_path: Path) -> None:
    # at th = 4 (beyond pi, where sin(th) < 0 pushes away), w = 0: V' = 2 (3/2 th + ... ) w + ... > 0
    system, ring, V = pendulum(tmp_path, QUARTIC)
    lie = LieDerivative(BallLoop(system), ring, V)
    point = [flint.arb(4), flint.arb(0)]
    assert lie(point) > 0  # V' > 0 there, exactly (ball arithmetic)
    v_there = float(lie.value_of_v(point).mid())
    found = qc.prove_sublevel(lie, ring, V, Fraction(2) * Fraction(v_there).limit_denominator(100),
                              Fraction(4) * Fraction(v_there).limit_denominator(100), BUDGET)
    assert not found.ok and found.counterexample_v is not None  # refuted at a proved point, not by the budget


def test_a_v_whose_quadratic_part_is_not_positive_definite_is_refused(tmp_path: Path) -> None:
    found = proof(tmp_path, {(2, 0): Fraction(1), (0, 2): Fraction(-1), (4, 0): Fraction(1)}, Fraction(1),
                  Fraction(2))
    assert not found.ok and "positive definite" in found.why


def test_the_cells_enclosures_of_a_quartic_v_contain_sampled_values(tmp_path: Path) -> None:
    from lyapcheck.models.engines.ellipsoid_cells import whitening

    system, ring, V = pendulum(tmp_path, QUARTIC)
    lie = LieDerivative(BallLoop(system), ring, V)
    parts = qc.split_quadratic(ring, V, 2)
    assert not isinstance(parts, str)
    P, R = parts
    w = whitening(P, Fraction(2))
    assert w is not None
    geo = qc.QuarticGeometry(w, P, lie, ring, R)
    M = np.array(w.M)
    rng = np.random.default_rng(3)
    for _ in range(20):
        centre = rng.uniform(-0.8, 0.8, 2)
        r = rng.uniform(0.01, 0.2)
        cell = tuple((float(c - r), float(c + r)) for c in centre)
        value, grad = geo.at_centre(lie, cell)
        H = geo.hessian_y(lie, cell)
        assert grad is not None and H is not None
        upper = geo.taylor_upper(value, grad, H, cell)
        enclosure = geo.v_upper(cell)
        for _ in range(20):
            y = centre + rng.uniform(-r, r, 2)
            z = [flint.arb(float(x)) for x in M @ y]
            g = float(lie(z).mid())
            v = float(lie.value_of_v(z).mid())
            assert float(upper.lower()) - 1e-9 <= g <= float(upper.upper()) + 1e-9
            assert float(enclosure.lower()) - 1e-9 <= v <= float(enclosure.upper()) + 1e-9
        if geo.v_above(cell, flint.arb(0)):  # V > 0 proved on the cell: every sampled V is > 0 there
            assert all(float(lie.value_of_v([flint.arb(float(x)) for x in M @ (centre + rng.uniform(-r, r, 2))])
                             .mid()) > 0 for _ in range(10))


def test_a_spent_budget_is_named_as_the_caller_set_it(tmp_path: Path) -> None:
    """The ellipsoid engine serves callers with different budgets: the reason names the one the quartic
    proof's caller set, never another caller's constant."""
    system, ring, V = pendulum(tmp_path, QUARTIC)
    lie = LieDerivative(BallLoop(system), ring, V)
    found = qc.prove_sublevel(lie, ring, V, Fraction(1), Fraction(2), 60, budget_name="the test's BUDGET")
    assert not found.ok and found.face_cells < 60
    assert "the test's BUDGET, less the faces'" in found.why and "BALL_LEVEL_CELLS" not in found.why

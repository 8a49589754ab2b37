"""The factored cell test of the ellipsoid cells (issue 42): ``V' = z^T (Abar^T P + P Abar) z`` with
``Abar(z) = int_0^1 J(t z) dt``. On a linear loop ``Abar = A`` exactly, so the test passes exactly when
``A^T P + P A`` is negative definite; on a nonlinear loop its enclosure contains the sampled matrix; across
a kink it never passes."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import flint
import numpy as np

from lyapcheck.models.engines import ellipsoid_cells as ec
from lyapcheck.models.engines.interval_field import Jet, apply


class _Loop:
    """A loop given by a Python function of jets (``z -> f(z)``): what the geometry asks of a loop."""

    def __init__(self, f: Any, n: int) -> None:
        self.f = f
        self.n = n

    def field(self, z: list[Any]) -> list[Any]:
        return self.f(z)


class _Lie:
    def __init__(self, loop: _Loop) -> None:
        self.loop = loop


def linear(A: list[list[float]]) -> Any:
    def f(z: list[Any]) -> list[Any]:
        return [sum((z[j] * flint.arb(A[i][j]) for j in range(len(z))), flint.arb(0) * z[0]) for i in range(len(z))]
    return f


def geometry(f: Any, P: list[list[Fraction]], level: Fraction = Fraction(1)) -> Any:
    w = ec.whitening(P, level)
    assert w is not None
    return ec._Geometry(w, P, _Lie(_Loop(f, len(P))))  # type: ignore[arg-type]


def cells(geo: Any) -> list[ec.Cell]:
    """A cell holding the equilibrium, one beside it, one far out, and a thin one (in ``y``)."""
    h = [float(x) for x in geo.widths]
    return [tuple((-x / 8, x / 16) for x in h), tuple((x / 64, x / 32) for x in h),
            tuple((x / 4, x / 2) for x in h), tuple((-x / 2, -x / 2 + x / 1024) for x in h)]


P2 = [[Fraction(3, 2), Fraction(1, 4)], [Fraction(1, 4), Fraction(1)]]


def test_on_a_linear_loop_the_test_passes_on_every_cell_when_a_t_p_plus_p_a_is_negative_definite() -> None:
    A = [[-1.0, 1.0], [-1.0, -1.0]]
    Pf = np.array(P2, dtype=float)
    assert np.linalg.eigvalsh(np.array(A).T @ Pf + Pf @ np.array(A))[-1] < 0
    geo = geometry(linear(A), P2)
    assert all(geo.factored_negative(cell) for cell in cells(geo))


def test_on_a_linear_loop_the_test_fails_on_every_cell_when_a_t_p_plus_p_a_is_not() -> None:
    A = [[-1.0, 5.0], [-0.2, -0.5]]  # stable (trace < 0, det > 0) but A^T P + P A indefinite for this P
    Pf = np.array(P2, dtype=float)
    assert np.all(np.linalg.eigvals(np.array(A)).real < 0)
    assert np.linalg.eigvalsh(np.array(A).T @ Pf + Pf @ np.array(A))[-1] > 0
    geo = geometry(linear(A), P2)
    assert not any(geo.factored_negative(cell) for cell in cells(geo))


def test_a_cell_across_a_kink_never_passes_and_one_beside_it_may() -> None:
    def f(z: list[Any]) -> list[Any]:  # -z0 - |z0| / 4 + z1, -z0 - z1: V' < 0 for P = I, but a kink at z0 = 0
        return [-z[0] - apply("abs", z[0]) * flint.arb(0.25) + z[1], -z[0] - z[1]]

    P = [[Fraction(1), Fraction(0)], [Fraction(0), Fraction(1)]]
    geo = geometry(f, P)
    across = ((-0.25, 0.25), (0.1, 0.2))
    assert not geo.factored_negative(across)
    # beside a kink through the equilibrium the segments t z, t in [0, 1], reach it at t = 0: the slab
    # [0, 1/K] touches the kink, so the test does not pass there either
    beside = ((0.1, 0.2), (0.1, 0.2))
    assert not geo.factored_negative(beside)
    assert geo.factored_y(beside) is None


def test_a_geometry_of_another_v_turns_the_test_off() -> None:
    from lyapcheck.models.classes.discrete_functions import MapGeometry
    from lyapcheck.models.engines.quartic_cells import QuarticGeometry

    assert ec._Geometry.factored and not QuarticGeometry.factored and not MapGeometry.factored


def test_the_enclosure_holds_the_sampled_matrix_on_a_nonlinear_loop() -> None:
    def f(z: list[Any]) -> list[Any]:  # a damped pendulum-like loop with a sine and a product
        return [z[1], apply("sin", z[0]) * flint.arb(-2.0) - z[1] - z[0] * z[1] * flint.arb(0.5)]

    def numeric_jacobian(z: np.ndarray) -> np.ndarray:
        return np.array([[0.0, 1.0], [-2 * np.cos(z[0]) - 0.5 * z[1], -1.0 - 0.5 * z[0]]])

    geo = geometry(f, P2)
    M = np.array([[float(x.mid()) for x in row] for row in geo.M])  # (exact: M's entries are floats)
    Pf = np.array(P2, dtype=float)
    rng = np.random.default_rng(3)
    for cell in cells(geo):
        N = geo.factored_y(cell)
        assert N is not None
        for _ in range(10):
            y = np.array([rng.uniform(a, b) for a, b in cell])
            z = M @ y
            ts = (np.arange(400) + 0.5) / 400
            Abar = sum(numeric_jacobian(t * z) for t in ts) / len(ts)
            exact = 2 * M.T @ (Abar.T @ Pf + Pf @ Abar) @ M
            for i in range(2):
                for j in range(2):
                    slack = 1e-4 * (1 + abs(exact[i, j]))
                    assert float(N[i][j].lower()) - slack <= exact[i, j] <= float(N[i][j].upper()) + slack

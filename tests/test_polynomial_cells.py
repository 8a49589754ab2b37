"""The polynomial model of V' in an ellipsoid's coordinates (lyapcheck.models.engines.polynomial_cells,
issue 42): its value within its stated error of V' times the flows' denominator computed independently
(benchmarks/robot_lqr.py's sympy field of the acrobot, not lyapcheck's), its cell bounds above every sampled
value of that true product, and loops it does not take refused in one line."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from lyapcheck.models.classes.recast_classes import base_loop
from lyapcheck.models.classes.shaped_quadratic import rational_form
from lyapcheck.models.engines import polynomial_cells as pc
from lyapcheck.models.engines.ellipsoid_cells import whitening
from lyapcheck.models.language.modelfile import load_any_model
from tests.conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
ACROBOT = ROOT / "examples" / "models" / "robot-acrobot-lqr.toml"


@pytest.fixture(scope="module")
def acrobot() -> dict:
    """The acrobot's loop, an LQR-like quadratic V (the linearization's Lyapunov matrix for Q = I, exact
    enough: any positive definite P is a valid test), the ellipsoid's coordinates at level 1/2, the model,
    and the true ``V' D`` as a numpy function of ``y`` (``D = I1 I2 + m2 l1^2 I2 - (m2 l1 lc2 cos q2)^2``,
    the denominator the model file writes)."""
    import scipy.linalg

    loop = base_loop(load_any_model(ACROBOT).system)
    z, f = benchmark_module("robot_lqr").closed_loop("robot-acrobot-lqr")
    J = np.array(sp.Matrix(f).jacobian(z).subs({s: 0 for s in z}).evalf(), dtype=float)
    Pf = scipy.linalg.solve_continuous_lyapunov(J.T, -np.eye(4))
    P = rational_form(Pf)
    assert P is not None
    w = whitening(P, Fraction(1, 2))
    assert w is not None
    model = pc.polynomial_model(loop.system, P, w.M, w.half)
    assert not isinstance(model, str), model
    rhs = sp.lambdify(z, f, "numpy")
    M = np.array(w.M)
    Pq = np.array([[float(x) for x in row] for row in P])

    def true_g(Y: np.ndarray) -> np.ndarray:
        Z = Y @ M.T
        F = np.stack([np.broadcast_to(np.asarray(c, dtype=float), Z.shape[:1]) for c in rhs(*Z.T)], axis=1)
        D = 0.333 * 1.33 + 1.33 - np.cos(Z[:, 1]) ** 2
        return 2 * np.sum((Z @ Pq) * F, axis=1) * D

    return {"loop": loop, "P": P, "w": w, "model": model, "true_g": true_g,
            "half": np.array([float(h) for h in w.half])}


def p_tilde(model: pc.PolynomialModel, Y: np.ndarray) -> np.ndarray:
    """The model's float polynomial at the rows of ``Y``, term by term."""
    out = np.zeros(len(Y))
    for idx in np.argwhere(model.coefficients != 0):
        out += model.coefficients[tuple(idx)] * np.prod(Y ** idx, axis=1)
    return out


def random_cell(rng: np.random.Generator, half: np.ndarray, reach: float, sizes: tuple[float, float]
                ) -> tuple[np.ndarray, np.ndarray, tuple[tuple[float, float], ...]]:
    """A cell centred within ``reach`` of the box ``|y_i| <= half_i``, its half-widths ``half`` times 10 to a
    power uniform in ``sizes``: its centre, its radii and the cell."""
    centre = (rng.random(4) * 2 - 1) * half * reach
    radius = half * 10 ** rng.uniform(*sizes, size=4)
    return centre, radius, tuple((float(c - r), float(c + r)) for c, r in zip(centre, radius))


def test_the_model_is_v_dot_times_the_denominator_within_its_error(acrobot) -> None:
    rng = np.random.default_rng(0)
    Y = (rng.random((3000, 4)) * 2 - 1) * acrobot["half"]
    truth = acrobot["true_g"](Y)
    gap = np.abs(p_tilde(acrobot["model"], Y) - truth)
    # (the float evaluations of both sides add about 1e-12 relative)
    assert np.all(gap <= acrobot["model"].error + 1e-9 * (1 + np.abs(truth)))
    assert acrobot["model"].error < 1e-2  # (a useful model: far below V' D's size on the set's shell)


def test_a_cell_bound_is_above_every_sampled_true_value(acrobot) -> None:
    """Random cells of many sizes, anywhere in the box: the true V' D at 100 points of each (corners
    included) never exceeds the bound, and the centre's value lies within the stated error of it."""
    model, true_g, half = acrobot["model"], acrobot["true_g"], acrobot["half"]
    rng = np.random.default_rng(1)
    proved = 0
    for _ in range(200):
        centre, radius, cell = random_cell(rng, half, 0.9, (-4, -0.3))
        bound = pc.cell_bound(model, cell)
        corners = np.array([[c + (r if (k >> j) & 1 else -r) for j, (c, r) in enumerate(zip(centre, radius))]
                            for k in range(16)])
        points = np.vstack([corners, centre + (rng.random((84, 4)) * 2 - 1) * radius])
        assert np.all(true_g(points) <= bound.centre + bound.spread + 1e-9), cell
        mid = true_g(np.array([[(a + b) / 2 for a, b in cell]]))[0]
        assert abs(mid - bound.centre) <= bound.error + 1e-9 * (1 + abs(mid))
        proved += bound.negative
    assert proved > 100  # (the bound is tight enough to prove most cells of this size away from 0)


def test_a_cell_holding_a_point_where_v_dot_is_positive_is_never_proved(acrobot) -> None:
    """On a box large enough to hold points where V' D > 0 (found by sampling the model), every cell around
    such a point is refused at every size."""
    loop, P = acrobot["loop"], acrobot["P"]
    rng = np.random.default_rng(2)
    for level in (2, 8, 32):
        w = whitening(P, Fraction(level))
        model = pc.polynomial_model(loop.system, P, w.M, w.half)
        assert not isinstance(model, str), model
        half = np.array([float(h) for h in w.half])
        Y = (rng.random((4000, 4)) * 2 - 1) * half
        values = p_tilde(model, Y)
        if (values > model.error).any():
            break
    else:
        pytest.fail("no point with V' D > 0 sampled")
    for y in Y[values > model.error][:20]:
        for r in (1e-1, 1e-3, 1e-6):
            cell = tuple((float(c - r), float(c + r)) for c in y)
            assert not pc.cell_bound(model, cell).negative


def test_the_decreasing_ball_holds_on_samples(acrobot) -> None:
    loop, P, w = acrobot["loop"], acrobot["P"], acrobot["w"]
    inner = Fraction(1, 1000)
    rho = pc.decreasing_ball(loop.system, P, w.M, inner, max(Fraction(h) for h in w.half))
    assert rho > inner
    rng = np.random.default_rng(4)
    U = rng.normal(size=(5000, 4))
    U /= np.linalg.norm(U, axis=1)[:, None]
    radii = float(inner) + (float(rho) - float(inner)) * rng.random((5000, 1))
    assert np.all(acrobot["true_g"](U * radii) < 0)


LOOP = """[model]
states = ["x", "v", "a", "b"]
[parameters]
k = {k}
[dynamics]
x = "v"
v = "({top}) / (cos(x) - k)"
a = "-a + b"
b = "-b"
"""


@pytest.mark.parametrize("top, k, why", [
    ("-sin(x) - v", "0.5", "denominator"),        # cos(x) - 1/2 vanishes at x = pi/3, inside the box
    ("-sat(x, 1) - v", "-2", "sat"),             # not a sine or cosine
])
def test_loops_the_model_does_not_take_are_refused_in_one_line(top: str, k: str, why: str, tmp_path: Path) -> None:
    path = tmp_path / "loop.toml"
    path.write_text(LOOP.format(top=top, k=k))
    model = load_any_model(path)
    loop = base_loop(model.system)
    P = [[Fraction(int(i == j)) for j in range(4)] for i in range(4)]
    found = pc.polynomial_model(loop.system, P, [[float(i == j) for j in range(4)] for i in range(4)],
                                [Fraction(2)] * 4)
    assert isinstance(found, str) and why in found and "\n" not in found


def test_a_large_model_is_refused_before_it_is_made() -> None:
    model = load_any_model(ROOT / "examples" / "models" / "robot-planar-quadrotor-lqr.toml")
    assert "too large" in (pc.refusal(model.system) or "")


def test_upper_sum_is_above_the_exact_sum_even_where_terms_underflow() -> None:
    """``upper_sum`` against the sum in exact rationals: never below it, within a few units of rounding of it
    where nothing underflows; tiny bounds (terms far below 2^-1022) give a bound of at most a few subnormals
    above the exact sum, and an overflow gives inf, never a finite number below the truth."""
    rng = np.random.default_rng(4)
    for scale in (1.0, 1e-3, 1e-40, 1e3):
        for _ in range(20):
            E = rng.integers(0, 12, size=(300, 6))
            c = rng.random(300) * 10.0 ** rng.integers(-8, 8, size=300)
            b = list(rng.random(6) * scale)
            exact = sum(Fraction(float(ci)) * np.prod([Fraction(x) ** int(e) for x, e in zip(b, row)])
                        for ci, row in zip(c, E))
            got = pc.upper_sum(E, c, b)
            assert Fraction(got) >= exact
            if scale >= 1e-3:
                assert got <= float(exact) * (1 + 1e-9) + 1e-300
    assert pc.upper_sum(np.array([[400]]), np.array([1.0]), [10.0]) == np.inf


def test_a_cells_own_error_is_above_the_exact_error_there(acrobot) -> None:
    """``local_error`` against the model's exact error terms summed in rationals at the cell's bounds (each
    remainder from its argument's exact bound there): never below, and far below the box's error for small
    cells away from the box's corners (the point of it)."""
    loop, P = acrobot["loop"], acrobot["P"]
    w = whitening(P, Fraction(4))
    model = pc.polynomial_model(loop.system, P, w.M, w.half)
    assert not isinstance(model, str), model
    exact = pc._exact(loop.system, P, w.M, model.degree)
    assert not isinstance(exact, str)
    half = np.array([float(h) for h in w.half])
    rng = np.random.default_rng(5)
    smaller = 0
    for _ in range(30):
        _, _, cell = random_cell(rng, half, 0.6, (-4, -1.5))
        b = [Fraction(max(abs(lo), abs(hi))) for lo, hi in cell]
        rb = [pc._remainder(f, pc._abs_bound(u, b + [Fraction(0)] * len(exact.arguments)))
              for f, u in exact.arguments]
        at = [pc._fmpq(x) for x in b + rb]
        truth = exact.dropped(*at) + exact.rounding(*at)
        local = pc.local_error(model, cell)
        assert Fraction(local) >= Fraction(int(truth.p), int(truth.q))
        smaller += local < model.error / 100
    assert smaller >= 20
    beyond = tuple((float(h) * 0.5, float(h) * 1.01) for h in half)  # (past the model's box: no bound there)
    assert pc.local_error(model, beyond) == np.inf
    # and a cell's bound, with its own error where the box's fails it, stays above the true V' D
    true_g = acrobot["true_g"]
    for _ in range(100):
        centre, radius, cell = random_cell(rng, half, 0.6, (-3, -1))
        bound = pc.cell_bound(model, cell)
        points = centre + (rng.random((50, 4)) * 2 - 1) * radius
        assert np.all(true_g(points) <= bound.centre + bound.spread + 1e-9), cell


@pytest.mark.slow
def test_the_cells_the_model_alone_splits_still_prove_and_refuse(acrobot, monkeypatch) -> None:
    """With the ball tests' trial at 0 (``ellipsoid_cells.BALL_AFTER_MODEL_TRIAL``: from the first cell the model
    fails, only every 8th gets the ball tests, the others are split by the model's own weights) a small level of
    the acrobot's V (condition number about 73,000: the model runs) is still proved, and a level holding points
    where the model has V' D > 0 is still refused."""
    from lyapcheck.models.engines import ellipsoid_cells as ec
    from lyapcheck.models.classes import recast_regions
    from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
    from lyapcheck.models.engines.interval_region import inverse_diagonal

    monkeypatch.setattr(ec, "BALL_AFTER_MODEL_TRIAL", 0)
    loop, P = acrobot["loop"], acrobot["P"]
    lie = LieDerivative(BallLoop(loop.system), loop.ring, recast_regions.state_form(loop, P))
    assert ec.uses_model(lie.loop, P)
    proof = ec.prove_ellipsoid(lie, P, inverse_diagonal(P), Fraction(1, 1000), [], 20000, 20000)
    assert proof.ok, proof.why
    refused = ec.prove_ellipsoid(lie, P, inverse_diagonal(P), Fraction(32), [], 20000, 20000)
    assert not refused.ok

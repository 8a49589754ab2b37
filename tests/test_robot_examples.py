"""The robot examples of issue 42 (``examples/models/robot-*.toml``): each file parses, its
``linearization`` is certified (LES), the closed-loop Jacobian lyapcheck proves it on is exactly
``A - B K`` of an independent sympy derivation of the open-loop robot (``benchmarks/robot_lqr.py``),
and the gains the files write are ``control.lqr``'s on that linearization to the digits written.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
import sympy as sp

from lyapcheck import certify
from tests.conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"
ROBOTS = ["robot-cart-pole-lqr", "robot-acrobot-lqr", "robot-pendubot-lqr", "robot-planar-quadrotor-lqr",
          "robot-pendulum-sat-pd"]
LQR = ["robot-cart-pole-lqr", "robot-acrobot-lqr", "robot-pendubot-lqr", "robot-planar-quadrotor-lqr"]


def robot_lqr() -> ModuleType:
    """benchmarks/robot_lqr.py as a module."""
    return benchmark_module("robot_lqr")


def half_unit(value: float) -> float:
    """Half a unit of the last significant digit of ``value`` as written (shortest repr)."""
    digits = format(value, ".15g").lstrip("-").replace(".", "").lstrip("0")
    return 10.0 ** (np.floor(np.log10(abs(value))) - len(digits) + 1) / 2


def linearization_of(stem: str) -> dict[str, Any]:
    result = certify(model=str(MODELS / f"{stem}.toml"), classes=["linearization"])
    return result.to_dict()["conditions"]["linearization"]


@pytest.mark.parametrize("stem", ROBOTS)
def test_robot_example_is_locally_exponentially_stable(stem: str) -> None:
    condition = linearization_of(stem)
    assert condition["status"] == "certified", condition["summary"]
    assert condition["property"] == "LES"


@pytest.mark.parametrize("stem", LQR)
def test_closed_loop_jacobian_is_a_minus_bk(stem: str) -> None:
    """The file's [dynamics] linearize to A - B K exactly, A and B from the sympy derivation."""
    A, B = robot_lqr().linearization(stem)
    K = robot_lqr().file_gain(stem)
    expected = (A - B * K).applyfunc(sp.nsimplify)
    got = linearization_of(stem)["certificate"]["jacobian"]
    assert [[Fraction(x) for x in row] for row in got] == [
        [Fraction(int(sp.numer(x)), int(sp.denom(x))) for x in row] for row in expected.tolist()]


@pytest.mark.parametrize("stem", LQR)
def test_file_gain_is_lqr_to_the_digits_written(stem: str) -> None:
    """Each written gain is control.lqr's rounded to its significant digits: within half a unit of
    its last digit (the rounding), not closer to any other number of that many digits."""
    K, _ = robot_lqr().lqr(stem)
    written = robot_lqr().file_parameters(stem)
    names = robot_lqr().PLANTS[stem].gains
    for i, row in enumerate(names):
        for j, name in enumerate(row):
            value = float(written[name])
            assert abs(K[i, j] - value) <= half_unit(value) * (1 + 1e-9), (name, K[i, j], value)


def test_cart_pole_gain_is_lqr_of_its_own_linearization() -> None:
    """The cart-pole's K: the closed loop's own Jacobian (lyapcheck's, exact) is A - B K, and the
    A of its derivation with the file's B gives control.lqr's K back to the 6 digits written."""
    import control

    stem = "robot-cart-pole-lqr"
    A, B = robot_lqr().linearization(stem)
    J = np.array([[float(Fraction(x)) for x in row] for row in linearization_of(stem)["certificate"]["jacobian"]])
    Bf = np.array(B, dtype=float)
    K_file = np.array(robot_lqr().file_gain(stem), dtype=float)
    A_from_file = J + Bf @ K_file  # the open loop recovered from the file's closed loop
    K, _, _ = control.lqr(A_from_file, Bf, np.diag([10, 1, 10, 1]), np.eye(1))
    tolerance = np.vectorize(half_unit)(K_file) * (1 + 1e-9)
    assert np.all(np.abs(K - K_file) <= tolerance), (K, K_file)


def test_taylor_model_for_drake_starts_with_the_closed_loop_jacobian() -> None:
    """The cubic Taylor model bench_robot_roa gives Drake: its linear terms are lyapcheck's exact closed-loop
    Jacobian, it has no constant or quadratic term (the cart-pole's field is odd in the states), and it agrees
    with the true field near the equilibrium to third order (error ~ |z|^5 there, odd field)."""
    stem = "robot-cart-pole-lqr"
    terms = robot_lqr().taylor_terms(stem)
    J = [[float(Fraction(x)) for x in row] for row in linearization_of(stem)["certificate"]["jacobian"]]
    for i, row in enumerate(terms):
        assert all(sum(e) in (1, 3) for _, e in row), row
        linear = {e.index(1): c for c, e in row if sum(e) == 1}
        assert [linear.get(j, 0.0) for j in range(4)] == pytest.approx(J[i], rel=1e-9, abs=1e-12)
    z, f = robot_lqr().closed_loop(stem)
    point = {zi: sp.Rational(1, 100) * (k + 1) for k, zi in enumerate(z)}
    for fi, row in zip(f, terms):
        taylor = sum(c * np.prod([float(point[zi]) ** e for zi, e in zip(z, ex)]) for c, ex in row)
        assert abs(float(fi.subs(point)) - taylor) < 1e-6


def converging(stem: str, starts: np.ndarray, horizon: float = 30.0, step: float = 0.01) -> np.ndarray:
    """Which ``starts`` (deviations, rows) converge on the true closed loop: RK4 on robot_lqr's sympy field
    (independent of lyapcheck), ending within 1e-3 of the equilibrium."""
    z, f = robot_lqr().closed_loop(stem)
    rhs = sp.lambdify(z, f, "numpy")

    def field(X: np.ndarray) -> np.ndarray:
        return np.stack([np.broadcast_to(np.asarray(c, dtype=float), X.shape[:1]) for c in rhs(*X.T)], axis=1)

    X = starts.copy()
    with np.errstate(all="ignore"):
        for _ in range(int(horizon / step)):
            k1 = field(X)
            k2 = field(X + step / 2 * k1)
            k3 = field(X + step / 2 * k2)
            k4 = field(X + step * k3)
            X = X + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return np.all(np.isfinite(X), axis=1) & (np.linalg.norm(X, axis=1) < 1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("stem", LQR)
def test_every_start_in_the_certified_roa_converges(stem: str) -> None:
    """roa's certified set (at 4 to 6 states the shaped quadratic V or the linearization's, issue 42): 300
    starts drawn in it (uniform in the ellipsoid {V <= level} of the states, the set's own box kept), each
    simulated independently of lyapcheck, all converge."""
    condition = certify(model=str(MODELS / f"{stem}.toml"), classes=["linearization", "roa"]).to_dict()[
        "conditions"]["roa"]
    assert condition["status"] == "certified", condition["summary"]
    cert = condition["certificate"]
    n = len(robot_lqr().PLANTS[stem].states)
    P = np.zeros((n, n))
    for coefficient, exponents in cert["V"]["terms"]:
        if any(exponents[n:]):
            pytest.skip("the certified V involves more than the states (the SOS route's): not an ellipsoid")
        i, j = [k for k, e in enumerate(exponents[:n]) for _ in range(e)]
        P[i, j] += float(Fraction(coefficient)) / (1 if i == j else 2)
        P[j, i] = P[i, j]
    level = float(Fraction(cert["level"]))
    rng = np.random.default_rng(3)
    U = rng.normal(size=(300, n))
    U /= np.linalg.norm(U, axis=1)[:, None]
    Y = U * rng.random((300, 1)) ** (1 / n) * np.sqrt(level)
    starts = Y @ np.linalg.cholesky(np.linalg.inv(P)).T  # z' P z = |y|^2 <= level
    assert np.all(np.sum((starts @ P) * starts, axis=1) <= level * (1 + 1e-9))
    ok = converging(stem, starts)
    assert ok.all(), starts[~ok][:3]

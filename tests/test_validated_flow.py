"""The validated integrator of the true loop (lyapcheck.models.engines.validated_flow): every enclosure holds the
exact states reached from every start of the box, and is tight enough to be of use.

The exact flows come from outside lyapcheck: a linear loop's from scipy's matrix exponential, a pendulum's and a
saturated loop's from numpy's RK4 with a step far finer than the integrator's (tests.recast_loops.rk4).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from scipy.linalg import expm

from lyapcheck.models.engines.validated_flow import LipschitzLoop, flow_into, split, start, step
from lyapcheck.models.engines.interval_field import ball
from lyapcheck.models.language.modelfile import parse_any_model
from tests.recast_loops import PENDULUM, rk4

LINEAR = """
[model]
name = "a linear loop"
states = ["x", "v"]
[dynamics]
x = "v"
v = "-2*x - 3*v"
"""

SATURATED = """
[model]
name = "double integrator, saturated feedback"
states = ["x", "v"]
[dynamics]
x = "v"
v = "sat(-x - 2*v, 1)"
"""


def loop_of(text: str) -> LipschitzLoop:
    from lyapcheck.models.surfaces.ball_roa import as_recast

    model = parse_any_model(text, "m.toml")
    if not hasattr(model, "system"):
        model = as_recast(model)
    return LipschitzLoop(model.system)


def box_points(lo: list[Fraction], hi: list[Fraction], count: int = 200) -> np.ndarray:
    """The box's corners and random points of it."""
    a, b = np.array([float(x) for x in lo]), np.array([float(x) for x in hi])
    corners = np.array([[a[0], a[1]], [a[0], b[1]], [b[0], a[1]], [b[0], b[1]]])
    return np.vstack([corners, a + (b - a) * np.random.default_rng(0).random((count, 2))])


def holds(enclosure: list, X: np.ndarray) -> bool:
    return all(bool(e.lower() <= X[:, i].min() + 1e-12) and bool(e.upper() >= X[:, i].max() - 1e-12)
               for i, e in enumerate(enclosure))


def test_the_linear_loops_enclosures_hold_its_exact_flow_and_stay_tight() -> None:
    loop = loop_of(LINEAR)
    A = np.array([[0.0, 1.0], [-2.0, -3.0]])
    lo, hi = [Fraction(1), Fraction(-1, 2)], [Fraction(5, 4), Fraction(-1, 4)]
    X0 = box_points(lo, hi)
    h = Fraction(1, 32)
    s = start(lo, hi)
    for k in range(1, 161):
        nxt = step(loop, s, ball(h))
        assert nxt is not None
        s = nxt
        if k % 20:
            continue
        exact = X0 @ expm(A * float(k * h)).T
        enclosure = s.enclosure()
        assert holds(enclosure, exact), k
        # tight: each radius at most 1.5 times the exact image's half-width (the image of a box is a
        # parallelogram, its hull is what a box can hold) plus a small absolute slack
        for i, e in enumerate(enclosure):
            half = (exact[:, i].max() - exact[:, i].min()) / 2
            assert float(e.rad()) <= 1.5 * half + 1e-6, (k, i, float(e.rad()), half)


@pytest.mark.parametrize("text, field, lo, hi", [
    (PENDULUM, lambda X: np.stack([X[:, 1], -np.sin(X[:, 0]) - X[:, 1]], axis=1),
     [Fraction(1), Fraction(0)], [Fraction(11, 10), Fraction(1, 10)]),
    # crosses the saturation's kink on its way in
    (SATURATED, lambda X: np.stack([X[:, 1], np.clip(-X[:, 0] - 2 * X[:, 1], -1, 1)], axis=1),
     [Fraction(3), Fraction(0)], [Fraction(31, 10), Fraction(1, 10)]),
])
def test_a_nonlinear_loops_enclosures_hold_its_trajectories(text: str, field, lo, hi) -> None:
    loop = loop_of(text)
    X = box_points(lo, hi)
    h = Fraction(1, 32)
    s = start(lo, hi)
    crossed = False
    for k in range(1, 193):
        nxt = step(loop, s, ball(h))
        assert nxt is not None, k
        s = nxt
        X = rk4(field, X, float(h), step=float(h) / 16)
        assert holds(s.enclosure(), X), k
        crossed |= text is SATURATED and bool(np.any(np.abs(-X[:, 0] - 2 * X[:, 1]) < 1))
    widths = [float(e.rad()) for e in s.enclosure()]
    assert max(widths) < 0.05  # converging: the enclosure has not blown up (it started at half-width 0.05)
    assert crossed or text is not SATURATED


def test_a_split_set_is_covered_by_its_two_halves() -> None:
    s = start([Fraction(0), Fraction(0)], [Fraction(1), Fraction(1, 3)])
    s = step(loop_of(PENDULUM), s, ball(Fraction(1, 8)))
    assert s is not None
    a, b = split(s)
    whole = s.enclosure()
    # every point of c + Q r is in one half: sampled along the split coordinate
    rng = np.random.default_rng(1)
    import flint

    for _ in range(200):
        t = [float(x.lower()) + (float(x.upper()) - float(x.lower())) * rng.random() for x in s.r]
        point = [c + sum(s.Q[i, j] * flint.arb(t[j]) for j in range(2)) for i, c in enumerate(s.c)]
        assert any(all(e.contains(p) for e, p in zip(half.enclosure(), point)) for half in (a, b))
    # each half is about half as wide along the widest coordinate, and no wider elsewhere (up to rounding)
    k = max(range(2), key=lambda i: float(s.r[i].rad()))
    for half in (a, b):
        assert float(half.r[k].rad()) <= float(s.r[k].rad()) / 2 * (1 + 1e-7)  # (radii are rounded up to 30 bits)
        assert float(half.r[1 - k].rad()) <= float(s.r[1 - k].rad()) * (1 + 1e-7) + 1e-12
        assert all(float(e.rad()) <= float(w.rad()) * (1 + 1e-7) + 1e-12 for w, e in zip(whole, half.enclosure()))


def test_flow_into_proves_a_box_that_enters_a_ball_and_not_one_that_cannot() -> None:
    loop = loop_of(PENDULUM)

    def near(X: list) -> bool:
        return all(bool(abs(x) < ball(Fraction(1, 10))) for x in X)

    good = flow_into(loop, [Fraction(1), Fraction(0)], [Fraction(11, 10), Fraction(1, 10)], Fraction(1, 32), near,
                     max_steps=800, max_radius=10.0)
    assert good.steps is not None and 0 < good.steps <= 800
    # the exact flow agrees: every sampled start is within 0.1 of the equilibrium at the stated time
    X = rk4(lambda Y: np.stack([Y[:, 1], -np.sin(Y[:, 0]) - Y[:, 1]], axis=1),
            box_points([Fraction(1), Fraction(0)], [Fraction(11, 10), Fraction(1, 10)]), good.steps / 32, 1 / 512)
    assert np.all(np.abs(X) < 0.1)
    # too short a horizon: not proved, and said so
    short = flow_into(loop, [Fraction(1), Fraction(0)], [Fraction(11, 10), Fraction(1, 10)], Fraction(1, 32), near,
                      max_steps=good.steps - 1, max_radius=10.0)
    assert short.steps is None and "after" in short.why
    # the lossless pendulum never enters: the horizon ends it
    lossless = loop_of(PENDULUM.replace("- b*omega", ""))
    never = flow_into(lossless, [Fraction(1), Fraction(0)], [Fraction(11, 10), Fraction(1, 10)], Fraction(1, 32), near,
                      max_steps=200, max_radius=10.0)
    assert never.steps is None

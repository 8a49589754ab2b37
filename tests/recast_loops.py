"""Loops with functions that several test modules use, and the independent integrator they check
certified sets with (numpy's own functions, a fixed-step RK4: nothing of lyapcheck's)."""

from __future__ import annotations

import numpy as np


ILOS = """
[model]
name = "ILOS course form"
states = ["y", "yi"]
[parameters]
U = 1
Delta = 2
kappa = "0.5"
[dynamics]
y = "-U*(y + kappa*yi)/sqrt(Delta**2 + (y + kappa*yi)**2)"
yi = "U*y/sqrt(Delta**2 + (y + kappa*yi)**2)"
"""


PENDULUM = """
[model]
name = "damped pendulum"
states = ["theta", "omega"]
[parameters]
b = 1
[dynamics]
theta = "omega"
omega = "-sin(theta) - b*omega"
[domain]
theta = [-3.14159, 3.14159]
omega = [-4, 4]
"""


SPRING = """
[model]
name = "a spring with a sine term"
states = ["x1", "x2"]
[dynamics]
x1 = "x2"
x2 = "-sin(x1) - x1 - x2"
"""


UNSTABLE = """
[model]
name = "x'' = sin(x) - x'"
states = ["x", "v"]
[dynamics]
x = "v"
v = "sin(x) - v"
"""


def rk4(f, X: np.ndarray, horizon: float, step: float = 0.02) -> np.ndarray:
    for _ in range(int(horizon / step)):
        k1 = f(X)
        k2 = f(X + step / 2 * k1)
        k3 = f(X + step / 2 * k2)
        k4 = f(X + step * k3)
        X = X + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return X


def pendulum_field(X: np.ndarray) -> np.ndarray:
    return np.stack([X[:, 1], -np.sin(X[:, 0]) - X[:, 1]], axis=1)


#: a pendulum without friction: its energy is conserved, so no trajectory converges
LOSSLESS = """
[model]
name = "lossless pendulum"
states = ["theta", "omega"]
[dynamics]
theta = "omega"
omega = "-sin(theta)"
"""

#: two first-order units coupled through sin and tanh: no denominator, and a quadratic V (GES)
COUPLED = """
[model]
name = "two first-order units coupled through sin and tanh"
states = ["x1", "x2"]
[dynamics]
x1 = "-x1 + sin(x2)/2"
x2 = "-x2 + tanh(x1)/2"
"""

"""The open-loop linearizations and LQR gains behind the ``examples/models/robot-*-lqr.toml`` loops.

Each example's file closes its robot with ``u = -K z`` (``z`` the deviation from the upright or
hover equilibrium) and writes ``K`` rounded in ``[parameters]``. This module derives, with sympy and
independently of lyapcheck, each robot's open-loop equations of motion as written in the file's
comments, their exact Jacobians ``A = df/dz``, ``B = df/du`` at the equilibrium (the parameters
read exactly from the model file's ``[parameters]``), and ``K``, ``S`` from ``control.lqr(A, B, Q, R)``.

Used by ``benchmarks/bench_robot_roa.py`` (the LQR cost-to-go ``z' S z`` as ``--candidate``) and by
``tests/test_robot_examples.py`` (the file's ``K`` is ``control.lqr``'s to the digits written, and
lyapcheck's exact closed-loop Jacobian is ``A - B K``).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import sympy as sp

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"


@dataclass(frozen=True)
class Plant:
    """An open-loop robot: states, inputs, its field ``f(z, u)`` (sympy), Q, R, and the gain names."""

    states: tuple[str, ...]
    inputs: tuple[str, ...]
    field: Callable[[dict[str, sp.Expr], dict[str, sp.Symbol], dict[str, sp.Symbol]], list[sp.Expr]]
    Q: tuple[float, ...]  # the diagonal of Q
    R: tuple[float, ...]  # the diagonal of R
    #: the [parameters] holding K, row by row (input by input), in the order of ``states``
    gains: tuple[tuple[str, ...], ...]


def _cart_pole(p: dict[str, sp.Expr], z: dict[str, sp.Symbol], u: dict[str, sp.Symbol]) -> list[sp.Expr]:
    # Tedrake, Underactuated Robotics, Ch. 3 (cart-pole), with theta = pi + phi (upright phi = 0)
    mc, mp, l, g = p["mc"], p["mp"], p["l"], p["g"]
    phi, v, w, f = z["phi"], z["v"], z["w"], u["f"]
    den = mc + mp * sp.sin(phi) ** 2
    xdd = (f - mp * l * sp.sin(phi) * w**2 + mp * g * sp.sin(phi) * sp.cos(phi)) / den
    phidd = (f * sp.cos(phi) - mp * l * w**2 * sp.sin(phi) * sp.cos(phi) + (mc + mp) * g * sp.sin(phi)) / (l * den)
    return [v, xdd, w, phidd]


def _two_link(actuated: int) -> Callable[..., list[sp.Expr]]:
    """Tedrake's acrobot manipulator equations (Ch. 3), q1 = pi + p1, torque on joint ``actuated``."""

    def field(p: dict[str, sp.Expr], z: dict[str, sp.Symbol], u: dict[str, sp.Symbol]) -> list[sp.Expr]:
        m1, m2, l1, lc1, lc2, I1, I2, g = (p[k] for k in ("m1", "m2", "l1", "lc1", "lc2", "I1", "I2", "g"))
        p1, q2, w1, w2, tau = z["p1"], z["q2"], z["w1"], z["w2"], u["tau"]
        q1 = sp.pi + p1
        c2 = sp.cos(q2)
        M = sp.Matrix([[I1 + I2 + m2 * l1**2 + 2 * m2 * l1 * lc2 * c2, I2 + m2 * l1 * lc2 * c2],
                       [I2 + m2 * l1 * lc2 * c2, I2]])
        C = sp.Matrix([[-2 * m2 * l1 * lc2 * sp.sin(q2) * w2, -m2 * l1 * lc2 * sp.sin(q2) * w2],
                       [m2 * l1 * lc2 * sp.sin(q2) * w1, 0]])
        tau_g = sp.Matrix([-m1 * g * lc1 * sp.sin(q1) - m2 * g * (l1 * sp.sin(q1) + lc2 * sp.sin(q1 + q2)),
                           -m2 * g * lc2 * sp.sin(q1 + q2)])
        Bu = sp.Matrix([tau if actuated == 1 else 0, tau if actuated == 2 else 0])
        qdd = M.LUsolve(tau_g + Bu - C * sp.Matrix([w1, w2]))
        return [w1, w2, qdd[0], qdd[1]]

    return field


def _planar_quadrotor(p: dict[str, sp.Expr], z: dict[str, sp.Symbol], u: dict[str, sp.Symbol]) -> list[sp.Expr]:
    # Tedrake, Underactuated Robotics, Ch. 3 (planar quadrotor); u_i = m g/2 + d_i
    m, r, J, g = p["m"], p["r"], p["J"], p["g"]
    th, d1, d2 = z["th"], u["d1"], u["d2"]
    thrust = m * g + d1 + d2
    return [z["vx"], z["vy"], z["w"], -thrust * sp.sin(th) / m, thrust * sp.cos(th) / m - g, r * (d1 - d2) / J]


PLANTS: dict[str, Plant] = {
    "robot-cart-pole-lqr": Plant(("x", "v", "phi", "w"), ("f",), _cart_pole, (10, 1, 10, 1), (1,),
                                 (("k1", "k2", "k3", "k4"),)),
    "robot-acrobot-lqr": Plant(("p1", "q2", "w1", "w2"), ("tau",), _two_link(2), (10, 10, 1, 1), (1,),
                               (("k1", "k2", "k3", "k4"),)),
    "robot-pendubot-lqr": Plant(("p1", "q2", "w1", "w2"), ("tau",), _two_link(1), (10, 10, 1, 1), (1,),
                                (("k1", "k2", "k3", "k4"),)),
    "robot-planar-quadrotor-lqr": Plant(("x", "y", "th", "vx", "vy", "w"), ("d1", "d2"), _planar_quadrotor,
                                        (10, 10, 10, 1, 1, 0.1), (1, 1),
                                        (("a1", "a2", "a3", "a4", "a5", "a6"), ("b1", "b2", "b3", "b4", "b5", "b6"))),
}


def file_parameters(stem: str) -> dict[str, sp.Rational]:
    """The model file's ``[parameters]``, each read exactly from its decimal text."""
    data = tomllib.loads((MODELS / f"{stem}.toml").read_text(encoding="utf-8"))
    return {k: sp.Rational(str(v)) for k, v in data.get("parameters", {}).items()}


def linearization(stem: str) -> tuple[sp.Matrix, sp.Matrix]:
    """The exact open-loop ``A``, ``B`` at the equilibrium (``z = 0``, ``u = 0``), parameters from the file."""
    plant = PLANTS[stem]
    params = file_parameters(stem)
    z = {s: sp.Symbol(s) for s in plant.states}
    u = {s: sp.Symbol(s) for s in plant.inputs}
    f = sp.Matrix(plant.field(params, z, u))
    at = {**{s: 0 for s in z.values()}, **{s: 0 for s in u.values()}}
    A = f.jacobian(list(z.values())).subs(at).applyfunc(sp.nsimplify)
    B = f.jacobian(list(u.values())).subs(at).applyfunc(sp.nsimplify)
    return A, B


def lqr(stem: str) -> tuple[np.ndarray, np.ndarray]:
    """``K``, ``S`` of ``control.lqr`` on the exact linearization (in floating point)."""
    import control

    plant = PLANTS[stem]
    A, B = linearization(stem)
    K, S, _ = control.lqr(np.array(A, dtype=float), np.array(B, dtype=float), np.diag(plant.Q), np.diag(plant.R))
    return np.asarray(K), np.asarray(S)


def file_gain(stem: str) -> sp.Matrix:
    """The ``K`` the model file writes in its ``[parameters]``, exactly."""
    params = file_parameters(stem)
    return sp.Matrix([[params[k] for k in row] for row in PLANTS[stem].gains])


def cost_to_go(stem: str, digits: int = 6) -> str:
    """``z' S z`` with ``control.lqr``'s ``S`` rounded to ``digits`` significant digits, as a model expression."""
    _, S = lqr(stem)
    names = PLANTS[stem].states
    terms = []
    for i, a in enumerate(names):
        for j in range(i, len(names)):
            c = S[i, j] * (1 if i == j else 2)
            if c != 0:
                terms.append(f"{c:.{digits}g}*{a}**2" if i == j else f"{c:.{digits}g}*{a}*{names[j]}")
    return " + ".join(terms).replace("+ -", "- ")


def closed_loop(stem: str) -> tuple[list[sp.Symbol], list[sp.Expr]]:
    """The states and the true closed-loop field ``f(z, -K z)`` with the file's ``K`` and parameters (exact)."""
    plant = PLANTS[stem]
    params = file_parameters(stem)
    z = {s: sp.Symbol(s) for s in plant.states}
    K = file_gain(stem)
    u_values = -K * sp.Matrix(list(z.values()))
    u = {s: sp.Symbol(s) for s in plant.inputs}
    f = plant.field(params, z, u)
    return list(z.values()), [fi.subs({u[s]: u_values[k] for k, s in enumerate(plant.inputs)}) for fi in f]


def taylor_terms(stem: str, order: int = 3) -> list[list[tuple[float, list[int]]]]:
    """The closed loop's Taylor polynomial of degree ``order`` at the equilibrium, per state, as
    ``[(coefficient, exponents), ...]`` (the model Drake's comparison of issue 42 analyses: Drake's
    region of attraction needs a polynomial field)."""
    z, f = closed_loop(stem)
    t = sp.Symbol("t")
    out = []
    for fi in f:
        scaled = fi.subs({zi: t * zi for zi in z}, simultaneous=True)
        poly = sp.series(scaled, t, 0, order + 1).removeO().subs(t, 1)
        terms = sp.Poly(sp.expand(poly), *z).terms()
        out.append([(float(c), list(m)) for m, c in terms if c != 0])
    return out

"""The cross-track error dynamics in the structured form the certificate code consumes.

    x_dot = A x + rho(x) B x + E w,      x = (eps, s),   w = d_perp  (|w| <= d*)

with the state-dependent coefficient ``rho(x) = U Delta / ((eps + sigma0 s)^2 + Delta^2)``
(eqs. ``eq:xCrossdyn``, ``eq:xCrossdyn2``). ``rho`` takes every value of the half-open
interval ``(0, U/Delta]``: the supremum is attained on the line ``eps + sigma0 s = 0`` and the
infimum is approached as ``|x| -> inf``.

Two versions are exported:

* ``derived`` (default): produced by :mod:`symbolic.ilos` from the model; ``A`` has the
  factor ``kappa = e11 alpha_d / e11_hat`` and the disturbance enters with gain 1;
* ``printed``: eqs. ``eq:xCrossdyn``/``eq:xCrossdyn2`` exactly as in the paper (no ``e11``,
  disturbance gain ``alpha_d``), so that the paper's claims can be checked on its own terms.

Numeric values are produced with :func:`evaluate` from exact rationals, so the exact checks in
:mod:`lyapcheck` see the same matrices as the solver.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Callable, Literal, Mapping

import sympy as sp

from symbolic import symbols as S
from symbolic.ilos import derive

DynamicsName = Literal["derived", "printed"]
DYNAMICS: tuple[DynamicsName, ...] = ("derived", "printed")

#: the symbols a numeric evaluation needs, by parameter name used in lyapcheck.paper.params
PARAMETER_SYMBOLS: dict[str, sp.Symbol] = {
    "alpha_d": S.alpha_d, "sigma0": S.sigma0, "k_d": S.k_d, "delta_los": S.Delta,
    "los_speed": S.U, "e11": S.e11, "e11_hat": S.e11_hat,
}


@dataclass(frozen=True)
class ErrorDynamics:
    """Symbolic structured closed loop (see module docstring)."""

    name: DynamicsName
    A: sp.Matrix
    B: sp.Matrix
    E: sp.Matrix
    rho: sp.Expr
    rho_sup: sp.Expr
    state: tuple[sp.Symbol, sp.Symbol]

    def rhs(self, w: sp.Expr = sp.Integer(0)) -> sp.Matrix:
        """The full right-hand side ``A x + rho(x) B x + E w``."""
        x = sp.Matrix(self.state)
        return self.A * x + self.rho * self.B * x + self.E * w


@lru_cache(maxsize=2)
def error_dynamics(name: DynamicsName = "derived") -> ErrorDynamics:
    """The structured error dynamics, derived from the model or as printed."""
    x = sp.Matrix([S.eps, S.s])
    B = sp.Matrix([[0, 0], [1, 0]])
    rho = S.U * S.Delta / ((S.eps + S.sigma0 * S.s) ** 2 + S.Delta**2)
    if name == "derived":
        D = derive()
        eps_dot = D.eps_dot
        rhs0 = sp.Matrix([eps_dot.subs(S.d_perp, 0), D.s_dot])
        A = rhs0.subs(S.U, 0).jacobian(x)
        E = sp.Matrix([sp.diff(eps_dot, S.d_perp), 0])
        # guard the structure: the derived rhs must be exactly A x + rho B x + E d_perp
        residual = sp.simplify(sp.Matrix([eps_dot, D.s_dot]) - (A * x + rho * B * x + E * S.d_perp))
        if residual != sp.zeros(2, 1):  # pragma: no cover - a failure here is a derivation bug
            raise RuntimeError(f"derived error dynamics do not have the structured form: {residual}")
    elif name == "printed":
        A = -S.alpha_d * sp.Matrix([[1, S.sigma0], [0, S.k_d / S.alpha_d]])
        E = sp.Matrix([S.alpha_d, 0])
        rho = rho.subs(S.U, 1)
    else:
        raise ValueError(f"dynamics must be one of {DYNAMICS}, got {name!r}")
    return ErrorDynamics(name=name, A=A, B=B, E=E, rho=rho, rho_sup=rho.subs({S.eps: 0, S.s: 0}),
                         state=(S.eps, S.s))


@dataclass(frozen=True)
class NumericDynamics:
    """Exact rational instance of :class:`ErrorDynamics` at one parameter point."""

    name: DynamicsName
    A: tuple[tuple[Fraction, Fraction], tuple[Fraction, Fraction]]
    B: tuple[tuple[Fraction, Fraction], tuple[Fraction, Fraction]]
    E: tuple[Fraction, Fraction]
    rho_sup: Fraction
    sigma0: Fraction
    delta: Fraction
    speed: Fraction


def _frac(expr: sp.Expr) -> Fraction:
    value = sp.nsimplify(expr) if expr.has(sp.Float) else expr
    if not value.is_Rational:
        raise ValueError(f"expected a rational value, got {value}")
    return Fraction(int(value.p), int(value.q))


def evaluate(name: DynamicsName, values: Mapping[str, Fraction]) -> NumericDynamics:
    """Substitute exact parameter values (keys of :data:`PARAMETER_SYMBOLS`)."""
    dyn = error_dynamics(name)
    subs = {PARAMETER_SYMBOLS[k]: sp.Rational(v.numerator, v.denominator) for k, v in values.items()
            if k in PARAMETER_SYMBOLS}
    A = dyn.A.xreplace(subs)
    B = dyn.B.xreplace(subs)
    E = dyn.E.xreplace(subs)
    speed = subs.get(S.U, sp.Integer(1)) if name == "derived" else sp.Integer(1)
    return NumericDynamics(
        name=name,
        A=((_frac(A[0, 0]), _frac(A[0, 1])), (_frac(A[1, 0]), _frac(A[1, 1]))),
        B=((_frac(B[0, 0]), _frac(B[0, 1])), (_frac(B[1, 0]), _frac(B[1, 1]))),
        E=(_frac(E[0]), _frac(E[1])),
        rho_sup=_frac(dyn.rho_sup.xreplace(subs)),
        sigma0=Fraction(values["sigma0"]),
        delta=Fraction(values["delta_los"]),
        speed=_frac(speed),
    )


@lru_cache(maxsize=4)
def guidance_functions(name: DynamicsName = "derived") -> tuple[Callable[..., object], Callable[..., object]]:
    """Numpy callables ``v_d(eps, s, alpha_d, sigma0, delta, theta_r)`` and
    ``s_dot(eps, s, sigma0, k_d, delta, U)`` for the simulator (eqs. ``eq:los2``).

    ``v_d`` returns the two components in the world frame. For ``printed`` the speed ``U`` is
    ignored (the paper's equation, read in SI, has ``U = 1``).
    """
    D = derive()
    args_v = (S.eps, S.s, S.alpha_d, S.sigma0, S.Delta, S.theta_r)
    v_d = sp.lambdify(args_v, [D.v_d[0], D.v_d[1]], modules="numpy")
    s_expr = D.s_dot if name == "derived" else D.s_dot.subs(S.U, 1)
    s_dot = sp.lambdify((S.eps, S.s, S.sigma0, S.k_d, S.Delta, S.U), s_expr, modules="numpy")
    return v_d, s_dot

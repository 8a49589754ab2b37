"""The ODS quadratic program of Section 4.2 (subsec:ods): derivations, claims and numerics.

The paper turns the pointwise-optimal decision strategy into a trust-region subproblem
(TRS): eq:permissible2 -> eq:tempODS -> eq:ODS with the data of eq:ODS2, characterises its
solution by eq:TRSiff2, and gives the solution in eq:rawSol / eq:algSol, then eq:solFinal
for Q = I / (Omega_0 e11^2). This module

* derives each of those equations with sympy and encodes the printed form next to it as a
  :class:`~symbolic.ledger.Claim` (:func:`claims`);
* settles Proposition prop:TRSsol's claim that u* is absolutely continuous *if and only if*
  q1 = q2, by an exact argument plus a high-precision numerical path
  (:func:`continuity_evidence`);
* turns the derived forms into numpy callables (``sympy.lambdify``), so that the numeric
  controller has no second, hand-copied formula: :func:`ods_gradient`, :func:`ods_control`
  (eq:solFinal, with the step-out bound enforced exactly in floating point),
  :func:`trs_solve_diag` (eq:rawSol + eq:algSol with a bracketing root finder) and
  :func:`trs_solve_cvxpy` (an independent conic reference, cvxpy + Clarabel).

Findings (see the claims for the one-sentence explanations): the printed G_mu of eq:ODS2
has the wrong sign; the quartic eq:tempn2 has wrong linear and constant coefficients;
eq:temp44 and eq:temp55 drop the minus sign of eq:temp11; eq:tempn5 and the "only if" of
prop:TRSsol are false (the TRS minimiser is Lipschitz in G_mu for every q1, q2 > 0).

This module must not import :mod:`lyapcheck` (layering): errors are raised as the builtin
``ValueError`` / ``RuntimeError`` with the toolkit's one message template.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Callable, Final, Literal

import mpmath
import numpy as np
import numpy.typing as npt
import sympy as sp

from symbolic import symbols as S
from symbolic.ledger import Claim, Verdict

if TYPE_CHECKING:  # pragma: no cover - typing only; cvxpy is imported lazily
    import cvxpy

__all__ = [
    "ContinuityEvidence",
    "Form",
    "claims",
    "continuity_evidence",
    "derived_quadratic",
    "gradient_expr",
    "ods_control",
    "ods_gradient",
    "quartic_coefficients",
    "trs_solve_cvxpy",
    "trs_solve_diag",
    "unconstrained_minimiser_expr",
]

FloatArray = npt.NDArray[np.float64]
Form = Literal["derived", "printed"]
_FORMS: Final = ("derived", "printed")

#: Clarabel accuracy for the reference solve. Tighter than its defaults (1e-8) because the
#: reference is compared with closed forms; it is a reference, never a certificate.
CVXPY_TOL: Final = 1e-10

#: Working precision (decimal digits) of the high-precision secular-equation solves used as
#: evidence for the continuity claim.
EVIDENCE_DPS: Final = 40

# ---------------------------------------------------------------------------------------
# Symbols local to this section (shared ones come from symbolic.symbols).
u_x, u_z = sp.symbols("u_x u_z", real=True)
w_x, w_z = sp.symbols("w_x w_z", real=True)
vd_x, vd_z = sp.symbols("v^d_x v^d_z", real=True)
Q11, Q12, Q22 = sp.symbols("Q_11 Q_12 Q_22", real=True)
a11, a12, a22 = sp.symbols("a_11 a_12 a_22", real=True)
G1, G2 = sp.symbols("G_1mu G_2mu", real=True)
#: substitution variables of eq:tempn1
lam_t = sp.Symbol("tilde{lambda}", positive=True)
Om_t = sp.Symbol("tilde{Omega}", real=True)
#: lambda + 1/Omega_0 in eq:tempAlg2 (positive because lambda* >= 0)
_shift = sp.Symbol("x", positive=True)

_U = sp.Matrix([u_x, u_z])
_W = sp.Matrix([w_x, w_z])
_D = sp.Matrix([S.d_x, S.d_z])
_VD = sp.Matrix([vd_x, vd_z])
_Q = sp.Matrix([[Q11, Q12], [Q12, Q22]])
_G = sp.Matrix([G1, G2])
_I2 = sp.eye(2)
_NORM_G = sp.sqrt(G1**2 + G2**2)
#: Q = I / (Omega_0 e11^2), the choice of eq:solFinal
_Q_ISO = {Q11: 1 / (S.Omega_0 * S.e11**2), Q12: sp.Integer(0), Q22: 1 / (S.Omega_0 * S.e11**2)}


def _quad(x: sp.Matrix, M: sp.Matrix) -> sp.Expr:
    return sp.expand((x.T * M * x)[0, 0])


def _a_diag() -> sp.Matrix:
    """A_mu = e11^2 diag(q1, q2) (eq:ODS2 with the diagonal Q of prop:TRSsol)."""
    return S.e11**2 * sp.diag(S.q1, S.q2)


# ---------------------------------------------------------------------------------------
# Derivations (cached: the ledger is rebuilt often and must stay fast).


@lru_cache(maxsize=None)
def derived_quadratic() -> tuple[sp.Matrix, sp.Matrix, sp.Expr]:
    """Expand eq:tempODS into the QP form of eq:ODS.

    Returns
    -------
    A, G, c
        With J the objective of eq:tempODS, ``J/2 = 1/2 u^T A u + G^T u + c`` (eq:ODS2):
        ``A`` is the Hessian of J/2, ``G`` its gradient at u = 0, ``c`` its value there.
        Q is a general symmetric matrix (Q_11, Q_12, Q_22).
    """
    r = S.e11 * _U + _D - _VD
    half = _quad(r, _Q) / 2
    A = sp.hessian(half, (u_x, u_z))
    at0 = {u_x: 0, u_z: 0}
    G = sp.Matrix([sp.factor(sp.diff(half, x).subs(at0)) for x in (u_x, u_z)])
    c = sp.expand(half.subs(at0))
    return A, G, c


def _printed_ods2() -> tuple[sp.Matrix, sp.Matrix]:
    """A_mu and G_mu exactly as printed in eq:ODS2."""
    A = S.e11**2 * _Q
    G = (-A / S.e11) * (_D - _VD)
    return A, G


@lru_cache(maxsize=None)
def gradient_expr(form: Form) -> sp.Matrix:
    """G_mu for Q = I/(Omega_0 e11^2) (eq:ODS2, eq:solFinal), derived or as printed."""
    _check_form(form)
    G = derived_quadratic()[1] if form == "derived" else _printed_ods2()[1]
    return G.subs(_Q_ISO).applyfunc(sp.cancel)


@lru_cache(maxsize=None)
def unconstrained_minimiser_expr(form: Form) -> sp.Matrix:
    """-A_mu^{-1} G_mu for a general Q, with A_mu, G_mu derived or as printed (eq:ODS2).

    The derived one is the feedforward law eq:tmp1 / eq:nomCont, (v^d - d_mu)/e11.
    """
    _check_form(form)
    A, G = (derived_quadratic()[:2]) if form == "derived" else _printed_ods2()
    return (-A.LUsolve(G)).applyfunc(sp.cancel)


def _kkt_solution(A: sp.Matrix, lam: sp.Expr) -> sp.Matrix:
    """Solve eq:TRSiff2 (b), (A + lam I) u = -G, for u (the derived eq:temp11)."""
    sol = sp.solve(list((A + lam * _I2) * _U + _G), [u_x, u_z], dict=True)
    if len(sol) != 1:
        raise RuntimeError(f"Expected a unique solution of eq:TRSiff2 (b); got {sol!r} instead.")
    return sp.Matrix([sp.factor(sol[0][u_x]), sp.factor(sol[0][u_z])])


@lru_cache(maxsize=None)
def _u_of_lambda() -> sp.Matrix:
    """u(lambda) for A_mu = e11^2 diag(q1, q2), from eq:TRSiff2 (b)."""
    return _kkt_solution(_a_diag(), S.lam)


@lru_cache(maxsize=None)
def _secular_derived() -> sp.Expr:
    """|u(lambda)|^2 - Omega_SO^2 with u(lambda) from eq:TRSiff2 (b): the derived eq:algSol."""
    u = _u_of_lambda()
    return u[0] ** 2 + u[1] ** 2 - S.Omega_SO**2


@lru_cache(maxsize=None)
def quartic_coefficients(form: Form) -> tuple[sp.Expr, ...]:
    """Coefficients (highest degree first, monic) of the quartic eq:tempn2 in tilde-lambda.

    The derived one clears the denominators of eq:algSol after the substitution eq:tempn1
    (lambda = tilde-lambda - Omega_1, Omega_2 = Omega_1 + tilde-Omega) and divides by
    Omega_SO^2.
    """
    _check_form(form)
    if form == "printed":
        n2 = G1**2 + G2**2
        return (
            sp.Integer(1), 2 * Om_t, -(n2 / S.Omega_SO**2 - Om_t**2), -2 * Om_t * G1**2, -(Om_t**2),
        )
    omega1 = S.q1 * S.e11**2
    # eq:tempn1 maps e11^2 q1 + lambda -> tilde-lambda and e11^2 q2 + lambda -> tilde-lambda + tilde-Omega
    sec = _secular_derived().subs(S.lam, lam_t - omega1)
    sec = sec.subs(S.q2, (Om_t + omega1) / S.e11**2)
    num, _den = sp.fraction(sp.together(sec))
    poly = sp.Poly(sp.expand(num), lam_t)
    lead = poly.LC()
    return tuple(sp.cancel(c / lead) for c in poly.all_coeffs())


@lru_cache(maxsize=None)
def _solfinal_derived() -> tuple[sp.Matrix, sp.Matrix, sp.Expr, sp.Expr]:
    """Branches of eq:solFinal derived from eq:TRSiff2 with A_mu = I/Omega_0.

    Returns the interior branch (lambda* = 0), the boundary branch (lambda* from eq:tempAlg),
    the switching threshold on |G_mu|, and lambda* on the boundary.
    """
    A = _a_diag().subs({S.q1: 1 / (S.Omega_0 * S.e11**2), S.q2: 1 / (S.Omega_0 * S.e11**2)})
    interior = _kkt_solution(A, sp.Integer(0))
    # eq:tempAlg: |G|^2 = (lambda + 1/Omega_0)^2 Omega_SO^2, solved for x = lambda + 1/Omega_0 > 0
    roots = sp.solve(sp.Eq(_NORM_G**2, _shift**2 * S.Omega_SO**2), _shift)
    if len(roots) != 1:
        raise RuntimeError(f"Expected one positive root of eq:tempAlg; got {roots!r} instead.")
    lam_star = roots[0] - 1 / S.Omega_0
    boundary = _kkt_solution(A, lam_star).applyfunc(sp.simplify)
    # interior branch feasible iff |u|^2 <= Omega_SO^2; |u| = Omega_0 |G| is linear in |G|
    g = sp.Symbol("g", positive=True)
    u_norm_sq = sp.simplify(_quad(interior, _I2).subs(G2, 0).subs(G1, g))
    thr = sp.solve(sp.Eq(u_norm_sq, S.Omega_SO**2), g)
    if len(thr) != 1:
        raise RuntimeError(f"Expected one threshold on |G_mu|; got {thr!r} instead.")
    return interior, boundary, thr[0], lam_star


# ---------------------------------------------------------------------------------------
# Claims.


def _check_ods() -> Verdict:
    A, G, c = derived_quadratic()
    r = S.e11 * _U + _D - _VD
    residual = sp.expand(_quad(r, _Q) / 2 - (_quad(_U, A) / 2 + (G.T * _U)[0, 0] + c))
    # |u| <= Omega_SO  <=>  u^T u <= Omega_SO^2 because both sides are non-negative
    ok = residual == 0
    return Verdict(
        status="holds" if ok else "discrepancy",
        printed="min 1/2 u^T A_mu u + G_mu^T u  s.t.  u^T u <= Omega_SO^2",
        derived=f"J/2 = 1/2 u^T A u + G^T u + c with A = {sp.sstr(A.tolist())}, G = {sp.sstr(G.tolist())}",
        explanation=(
            "Half the objective of eq:tempODS minus its u-independent part is exactly the QP "
            "objective of eq:ODS and u^T u <= Omega_SO^2 is |u| <= Omega_SO squared, so the two "
            "problems have the same minimiser, with A_mu and G_mu as derived (the printed sign of "
            "G_mu is flagged under eq:ODS2)."
            if ok else "The expansion of eq:tempODS is not of the form of eq:ODS."
        ),
    )


def _check_trsiff2() -> Verdict:
    A = sp.Matrix([[a11, a12], [a12, a22]])
    lam = S.lam

    def f(x: sp.Matrix, g: sp.Matrix) -> sp.Expr:
        return _quad(x, A) / 2 + sp.expand((g.T * x)[0, 0])

    # (b) is stationarity of the Lagrangian f(u) + lam/2 (u^T u - Omega_SO^2)
    lagr = f(_U, _G) + lam / 2 * (_quad(_U, _I2) - S.Omega_SO**2)
    grad = sp.Matrix([sp.diff(lagr, x) for x in (u_x, u_z)])
    stationarity_ok = all(sp.expand(e) == 0 for e in grad - ((A + lam * _I2) * _U + _G))
    # sufficiency: with G = -(A + lam I) u (condition (b)),
    # f(w) - f(u) = 1/2 (w-u)^T (A + lam I) (w-u) + lam/2 (|u|^2 - |w|^2),
    # which is >= 0 for feasible w under (c), (d) and lam >= 0.
    g_b = -(A + lam * _I2) * _U
    ident = f(_W, g_b) - f(_U, g_b) - (
        _quad(_W - _U, A + lam * _I2) / 2 + lam / 2 * (_quad(_U, _I2) - _quad(_W, _I2))
    )
    sufficiency_ok = sp.expand(ident) == 0
    # (d) is automatic when A_mu = e11^2 diag(q1, q2) with q1, q2 > 0: the TRS is convex
    eig = (_a_diag() + lam * _I2).eigenvals()
    convex_ok = all(bool(ev.is_positive) for ev in eig)
    ok = stationarity_ok and sufficiency_ok and convex_ok
    return Verdict(
        status="holds" if ok else ("discrepancy" if not stationarity_ok else "unverifiable"),
        printed="|u*| <= Omega_SO, (A_mu + lambda* I) u* = -G_mu, lambda*(Omega_SO - |u*|) = 0, A_mu + lambda* I >= 0",
        derived=(
            "grad_u [f + lambda/2 (u^T u - Omega_SO^2)] = (A + lambda I) u + G; "
            "f(w) - f(u) = 1/2 (w-u)^T (A + lambda I)(w-u) + lambda/2 (|u|^2 - |w|^2); "
            f"eig(A_mu + lambda I) = {sp.sstr(list(eig))} > 0"
        ),
        explanation=(
            "Condition (b) is the stationarity of the Lagrangian and the exact identity "
            "f(w) - f(u) = 1/2 (w-u)^T(A+lambda I)(w-u) + lambda/2(|u|^2-|w|^2) makes (a)-(d) "
            "sufficient, Slater's point u = 0 makes them necessary, and since A_mu = e11^2 Q is "
            "positive definite the TRS is convex and (d) holds automatically for every lambda* >= 0."
            if ok else "The KKT system printed does not match the derived one."
        ),
    )


def _check_tempn5() -> Verdict:
    interior, boundary, thr, lam_star = _solfinal_derived()
    phi = sp.Symbol("phi", real=True)
    on_switch = {G1: thr * sp.cos(phi), G2: thr * sp.sin(phi)}
    gap = (interior.subs(on_switch) - boundary.subs(on_switch)).applyfunc(sp.simplify)
    continuous_at_switch = all(e == 0 for e in gap)
    # a saturated point, |G_mu| = 2 Omega_SO / Omega_0: lambda* = 1/Omega_0 > 0
    lam_sat = sp.simplify(lam_star.subs({G1: 2 * thr, G2: 0}))
    ok = continuous_at_switch and bool(lam_sat.is_positive)
    return Verdict(
        status="discrepancy" if ok else "unverifiable",
        printed="u* continuous everywhere iff tilde-lambda_0 = Omega_1 (eq:tempn4) iff lambda* = 0 (eq:tempn5)",
        derived=(
            f"eq:solFinal branches agree on |G_mu| = {sp.sstr(thr)} (difference {sp.sstr(gap.tolist())}) "
            f"but lambda* = {sp.sstr(lam_star)} (= {sp.sstr(lam_sat)} at |G_mu| = 2 Omega_SO/Omega_0)"
        ),
        explanation=(
            "Continuity does not require lambda* = 0: eq:solFinal itself is continuous (its branches "
            "agree exactly on |G_mu| = Omega_SO/Omega_0) while its saturated branch has "
            "lambda* = |G_mu|/Omega_SO - 1/Omega_0 > 0, and lambda* = 0 at every p would mean the "
            "step-out constraint is never active, so eq:tempn4/eq:tempn5 are false."
            if ok else "Could not establish the continuity of eq:solFinal at the switch."
        ),
    )


@dataclass(frozen=True)
class ContinuityEvidence:
    """Numerical evidence for the continuity of the TRS minimiser with q1 != q2.

    Attributes
    ----------
    q1, q2, e11, omega_so
        The instance (A_mu = e11^2 diag(q1, q2)).
    n_points
        Samples along each path G_mu(t) = G_a + t (G_b - G_a), t in [0, 1].
    lipschitz_observed
        Max over consecutive samples of |u(t_k+1) - u(t_k)| / |G(t_k+1) - G(t_k)|.
    lipschitz_bound
        1 / lambda_min(A_mu), the proven Lipschitz constant.
    switch_quotient
        |u(t* + delta) - u(t* - delta)| / |G(t* + delta) - G(t* - delta)| across the exact
        saturation crossing t* (delta = 1e-25).
    max_secular_residual
        Largest |Omega_SO - |u|| / Omega_SO over saturated samples (high precision).
    saturated_fraction
        Share of samples where the constraint is active (lambda* > 0).
    """

    q1: float
    q2: float
    e11: float
    omega_so: float
    n_points: int
    lipschitz_observed: float
    lipschitz_bound: float
    switch_quotient: float
    max_secular_residual: float
    saturated_fraction: float


def _mp_trs_diag(g: tuple[Any, Any], a: tuple[Any, Any], omega: Any) -> tuple[tuple[Any, Any], Any]:
    """Solve the diagonal TRS in mpmath: eq:rawSol with eq:algSol by a bracketing root finder."""
    u0 = (-g[0] / a[0], -g[1] / a[1])
    if mpmath.hypot(*u0) <= omega:
        return u0, mpmath.mpf(0)
    norm_g = mpmath.hypot(*g)
    lo = max(mpmath.mpf(0), norm_g / omega - max(a))
    hi = norm_g / omega - min(a)

    def secular(lam: Any) -> Any:
        return (g[0] / (a[0] + lam)) ** 2 + (g[1] / (a[1] + lam)) ** 2 - omega**2

    if secular(lo) <= 0:
        lam = lo
    elif secular(hi) >= 0:
        lam = hi
    else:
        lam = mpmath.findroot(secular, (lo, hi), solver="anderson")
    return (-g[0] / (a[0] + lam), -g[1] / (a[1] + lam)), lam


@lru_cache(maxsize=None)
def continuity_evidence(n_points: int = 241) -> ContinuityEvidence:
    """Sample G_mu along paths crossing the saturation boundary with q1 != q2.

    The minimiser is solved to :data:`EVIDENCE_DPS` digits; difference quotients are compared
    with the bound 1/lambda_min(A_mu) proven in :func:`_check_continuity`.
    """
    with mpmath.workdps(EVIDENCE_DPS):
        q1, q2, e11, omega = mpmath.mpf(1), mpmath.mpf(4), mpmath.mpf("0.5"), mpmath.mpf(1)
        a = (e11**2 * q1, e11**2 * q2)
        bound = 1 / min(a)
        # two paths: from inside to outside, one nearly along the soft axis (quotient close
        # to the bound), one oblique (boundary solution not parallel to G_mu)
        paths = [
            ((mpmath.mpf("0.05"), mpmath.mpf("0.2")), (mpmath.mpf("1.5"), mpmath.mpf("0.3"))),
            ((mpmath.mpf("-0.1"), mpmath.mpf("0.3")), (mpmath.mpf("0.8"), mpmath.mpf("-3.5"))),
        ]
        worst = mpmath.mpf(0)
        switch_worst = mpmath.mpf(0)
        residual = mpmath.mpf(0)
        saturated = 0
        for ga, gb in paths:
            dg = (gb[0] - ga[0], gb[1] - ga[1])

            def at(t: Any) -> tuple[Any, Any]:
                return (ga[0] + t * dg[0], ga[1] + t * dg[1])  # noqa: B023 - used in-loop only

            prev_u: tuple[Any, Any] | None = None
            prev_g: tuple[Any, Any] | None = None
            for k in range(n_points):
                g = at(mpmath.mpf(k) / (n_points - 1))
                u, lam = _mp_trs_diag(g, a, omega)
                if lam > 0:
                    saturated += 1
                    residual = max(residual, abs(mpmath.hypot(*u) - omega) / omega)
                if prev_u is not None and prev_g is not None:
                    q = mpmath.hypot(u[0] - prev_u[0], u[1] - prev_u[1]) / mpmath.hypot(
                        g[0] - prev_g[0], g[1] - prev_g[1]
                    )
                    worst = max(worst, q)
                prev_u, prev_g = u, g
            # exact crossing: |A^{-1} G(t)|^2 = Omega^2 is a quadratic in t
            c2 = (dg[0] / a[0]) ** 2 + (dg[1] / a[1]) ** 2
            c1 = 2 * (ga[0] * dg[0] / a[0] ** 2 + ga[1] * dg[1] / a[1] ** 2)
            c0 = (ga[0] / a[0]) ** 2 + (ga[1] / a[1]) ** 2 - omega**2
            t_star = (-c1 + mpmath.sqrt(c1**2 - 4 * c2 * c0)) / (2 * c2)
            delta = mpmath.mpf("1e-25")
            u_minus, _ = _mp_trs_diag(at(t_star - delta), a, omega)
            u_plus, lam_plus = _mp_trs_diag(at(t_star + delta), a, omega)
            if not lam_plus > 0:
                raise RuntimeError("The evidence path did not cross into saturation.")
            jump = mpmath.hypot(u_plus[0] - u_minus[0], u_plus[1] - u_minus[1])
            switch_worst = max(switch_worst, jump / (2 * delta * mpmath.hypot(*dg)))
        return ContinuityEvidence(
            q1=float(q1), q2=float(q2), e11=float(e11), omega_so=float(omega), n_points=n_points,
            lipschitz_observed=float(worst), lipschitz_bound=float(bound),
            switch_quotient=float(switch_worst), max_secular_residual=float(residual),
            saturated_fraction=saturated / (len(paths) * n_points),
        )


def _check_continuity() -> Verdict:
    # Exact part: for minimisers u1, u2 of f_i(u) = 1/2 u^T A u + G_i^T u over the ball, the
    # first-order conditions (A u1 + G1).(u2 - u1) >= 0 and (A u2 + G2).(u1 - u2) >= 0 add to
    # an expression that the identity below rewrites, giving
    # lambda_min |u1 - u2|^2 <= (u1-u2)^T A (u1-u2) <= -(G1-G2).(u1-u2) <= |G1-G2| |u1-u2|.
    A = sp.Matrix([[a11, a12], [a12, a22]])
    h1, h2 = sp.symbols("h_1 h_2", real=True)
    H = sp.Matrix([h1, h2])
    vi_sum = ((A * _U + _G).T * (_W - _U))[0, 0] + ((A * _W + H).T * (_U - _W))[0, 0]
    rhs = -_quad(_U - _W, A) - ((_G - H).T * (_U - _W))[0, 0]
    identity_ok = sp.expand(vi_sum - rhs) == 0
    # uniqueness of lambda*: eq:algSol's left side is strictly decreasing in lambda >= 0
    dsec = sp.diff(_secular_derived(), S.lam)
    expected = -2 * sum(
        (g**2 / (S.e11**2 * q + S.lam) ** 3 for g, q in ((G1, S.q1), (G2, S.q2))), sp.Integer(0)
    )
    monotone_ok = sp.simplify(dsec - expected) == 0
    ev = continuity_evidence()
    numeric_ok = (
        ev.lipschitz_observed <= ev.lipschitz_bound * (1 + 1e-12)
        and ev.switch_quotient <= ev.lipschitz_bound * (1 + 1e-12)
        and ev.max_secular_residual < 1e-30
        and 0 < ev.saturated_fraction < 1
    )
    ok = identity_ok and monotone_ok and numeric_ok
    return Verdict(
        status="discrepancy" if ok else "unverifiable",
        printed="u*(p) absolutely continuous if and only if q1 = q2 = 1/(Omega_0 e11^2)",
        derived=(
            "for every q1, q2 > 0: |u*(G) - u*(G')| <= |G - G'| / lambda_min(A_mu); "
            f"path with q1={ev.q1:g}, q2={ev.q2:g}, e11={ev.e11:g}, Omega_SO={ev.omega_so:g} "
            f"({ev.saturated_fraction:.0%} saturated): max difference quotient "
            f"{ev.lipschitz_observed:.12g} <= bound {ev.lipschitz_bound:.12g}, "
            f"quotient across the saturation switch {ev.switch_quotient:.12g}"
        ),
        explanation=(
            "The 'only if' is false: for any q1, q2 > 0 the TRS is strictly convex, its minimiser "
            "is unique and 1/lambda_min(A_mu)-Lipschitz in G_mu (exact variational-inequality "
            "identity), hence absolutely continuous in p, and a 40-digit path with q1 != q2 crossing "
            f"saturation gives difference quotients <= {ev.lipschitz_observed:.6g} against the "
            f"bound {ev.lipschitz_bound:.6g}; only the 'if' direction holds."
            if ok else "The exact argument or the numerical evidence for continuity did not go through."
        ),
    )


@lru_cache(maxsize=None)
def claims() -> list[Claim]:
    """Every checkable equation of Section 4.2 (subsec:ods), printed vs derived."""
    A_d, G_d, _c = derived_quadratic()
    A_p, G_p = _printed_ods2()
    A = _a_diag()
    u_lam = _u_of_lambda()
    interior_d, boundary_d, thr_d, lam_star_d = _solfinal_derived()
    omega0_inv = 1 / S.Omega_0
    # A_mu = I/Omega_0 (q1 = q2 = 1/(Omega_0 e11^2)) for the proof's last steps
    u_iso = u_lam.subs({S.q1: 1 / (S.Omega_0 * S.e11**2), S.q2: 1 / (S.Omega_0 * S.e11**2)})
    obj_perm = _quad(_VD - (_D + S.e11 * _U), _Q)  # eq:permissible2 with v = d_mu + e11 u
    obj_temp = _quad(S.e11 * _U + _D - _VD, _Q)
    omega1 = S.q1 * S.e11**2

    return [
        Claim(
            label="eq:tempODS",
            title="ODS over velocities (eq:permissible2) as a problem in u",
            printed=obj_temp,
            derived=obj_perm,
            holds_text=(
                "Substituting v = d_mu + e11 u (eq:permissible, a bijection since e11 != 0, with "
                "|u| <= Omega_SO) into eq:permissible2 gives the objective of eq:tempODS."
            ),
        ),
        Claim(label="eq:ODS", title="eq:tempODS as the QP (1/2 u^T A u + G^T u)", check=_check_ods),
        Claim(
            label="eq:ODS2",
            title="A_mu and G_mu of the QP",
            printed=sp.Matrix([A_p[0, 0], A_p[0, 1], A_p[1, 1], G_p[0], G_p[1]]),
            derived=sp.Matrix([A_d[0, 0], A_d[0, 1], A_d[1, 1], G_d[0], G_d[1]]),
            holds_text="A_mu and G_mu as printed match the expansion of eq:tempODS.",
            discrepancy_text=(
                "The printed G_mu has the wrong sign: expanding eq:tempODS gives "
                "G_mu = +(A_mu/e11)(d_mu - v^d), whose unconstrained minimiser -A_mu^{-1} G_mu = "
                "(v^d - d_mu)/e11 is the feedforward law eq:tmp1/eq:nomCont, whereas the printed "
                "sign gives (d_mu - v^d)/e11, i.e. steers against the reference field (A_mu = e11^2 Q "
                "is correct)."
            ),
        ),
        Claim(label="eq:TRSiff2", title="KKT conditions of the TRS", check=_check_trsiff2),
        Claim(
            label="eq:rawSol",
            title="TRS solution, interior and boundary branches",
            printed=sp.Matrix([*(-A.inv() * _G), *(-(A + S.lam * _I2).inv() * _G)]),
            derived=sp.Matrix([*_kkt_solution(A, sp.Integer(0)), *u_lam]),
            holds_text=(
                "Both branches solve eq:TRSiff2 (b) with lambda* = 0 and lambda* > 0; the branch test "
                "is implicit in u*, the computable one being |A_mu^{-1} G_mu| < Omega_SO (then "
                "lambda* = 0 is feasible)."
            ),
        ),
        Claim(
            label="eq:temp22",
            title="|u*|^2 as a quadratic form in G_mu",
            printed=sp.expand((_G.T * ((A + S.lam * _I2) ** -2) * _G)[0, 0]),
            derived=u_lam[0] ** 2 + u_lam[1] ** 2,
            holds_text="With u* from eq:temp11 and A_mu symmetric, u*^T u* = G^T (A_mu + lambda I)^{-2} G.",
        ),
        Claim(
            label="eq:temp33",
            title="(A_mu + lambda I)^{-1} G_mu componentwise",
            printed=sp.Matrix([G1 / (S.e11**2 * S.q1 + S.lam), G2 / (S.e11**2 * S.q2 + S.lam)]),
            derived=-u_lam,
            holds_text="(A_mu + lambda I)^{-1} is diagonal with entries 1/(e11^2 q_i + lambda).",
        ),
        Claim(
            label="eq:algSol",
            title="secular equation for lambda*",
            printed=(
                G1**2 / (S.e11**2 * S.q1 + S.lam) ** 2 + G2**2 / (S.e11**2 * S.q2 + S.lam) ** 2
                - S.Omega_SO**2
            ),
            derived=_secular_derived(),
            holds_text=(
                "|u(lambda)|^2 = Omega_SO^2 with u from eq:TRSiff2 (b) is the printed equation; its "
                "left side is strictly decreasing in lambda >= 0, so the non-negative root is unique."
            ),
        ),
        Claim(
            label="eq:tempn2",
            title="quartic in tilde-lambda after eq:tempn1 (coefficients, monic)",
            printed=sp.Matrix(quartic_coefficients("printed")),
            derived=sp.Matrix(quartic_coefficients("derived")),
            holds_text="The quartic's coefficients match the cleared secular equation.",
            discrepancy_text=(
                "Clearing denominators in eq:algSol gives linear coefficient "
                "-2 tilde-Omega G_1mu^2/Omega_SO^2 and constant term -tilde-Omega^2 G_1mu^2/Omega_SO^2, "
                "so the printed quartic drops the factor 1/Omega_SO^2 from its linear term and "
                "G_1mu^2/Omega_SO^2 from its constant term (it is not even dimensionally homogeneous); "
                "the leading, cubic and quadratic coefficients are right."
            ),
        ),
        Claim(
            label="eq:tempn3",
            title="TRS solution in the variables of eq:tempn1",
            printed=sp.Matrix([
                -G1 / omega1, -G2 / (S.q2 * S.e11**2), -G1 / lam_t, -G2 / (lam_t + Om_t),
            ]),
            derived=sp.Matrix([
                *_kkt_solution(A, sp.Integer(0)),
                *u_lam.subs(S.lam, lam_t - omega1).subs(S.q2, (Om_t + omega1) / S.e11**2),
            ]),
            holds_text="eq:rawSol rewritten with tilde-lambda = lambda* + Omega_1 and tilde-Omega = Omega_2 - Omega_1.",
        ),
        Claim(label="eq:tempn5", title="continuity iff lambda* = 0 (with eq:tempn4)", check=_check_tempn5),
        Claim(
            label="eq:tempAlg",
            title="secular equation for A_mu = I/Omega_0",
            printed=G1**2 + G2**2 - (S.lam + omega0_inv) ** 2 * S.Omega_SO**2,
            derived=sp.cancel(
                (u_iso[0] ** 2 + u_iso[1] ** 2 - S.Omega_SO**2) * (S.lam + omega0_inv) ** 2
            ),
            holds_text="With q1 = q2 = 1/(Omega_0 e11^2), eq:algSol times (lambda + 1/Omega_0)^2 is the printed equation.",
        ),
        Claim(
            label="eq:tempAlg2",
            title="lambda* for A_mu = I/Omega_0",
            printed=_NORM_G / S.Omega_SO - omega0_inv,
            derived=lam_star_d,
            holds_text=(
                "The root of eq:tempAlg with lambda* + 1/Omega_0 > 0 is |G_mu|/Omega_SO - 1/Omega_0, "
                "which is positive whenever the constraint is active, contradicting the proof's "
                "'lambda* = 0' (see eq:tempn5)."
            ),
        ),
        Claim(
            label="eq:temp44",
            title="boundary solution for A_mu = I/Omega_0",
            printed=sp.Matrix([G1 / (omega0_inv + S.lam), G2 / (omega0_inv + S.lam)]),
            derived=u_iso,
            discrepancy_text=(
                "eq:temp44 writes u* = +(A_mu + lambda* I)^{-1} G_mu, dropping the minus sign that "
                "eq:TRSiff2 (b) and eq:temp11 give, so its components have the wrong sign."
            ),
        ),
        Claim(
            label="eq:temp55",
            title="saturated solution Omega_SO G_mu / |G_mu|",
            printed=S.Omega_SO / _NORM_G * _G,
            derived=boundary_d,
            discrepancy_text=(
                "With lambda* + 1/Omega_0 = |G_mu|/Omega_SO from eq:tempAlg2, eq:temp11 gives "
                "u* = -Omega_SO G_mu/|G_mu|, so the printed +Omega_SO G_mu/|G_mu| has the wrong sign "
                "(eq:solFinal has the right one)."
            ),
        ),
        Claim(
            label="eq:solFinal",
            title="closed-form ODS control for Q = I/(Omega_0 e11^2)",
            printed=sp.Matrix([
                -S.Omega_0 * G1, -S.Omega_0 * G2,
                -S.Omega_SO * G1 / _NORM_G, -S.Omega_SO * G2 / _NORM_G,
                S.Omega_SO / S.Omega_0,
            ]),
            derived=sp.Matrix([*interior_d, *boundary_d, thr_d]),
            holds_text=(
                "With A_mu = I/Omega_0, lambda* = 0 gives -Omega_0 G_mu, feasible iff "
                "|G_mu| <= Omega_SO/Omega_0, and otherwise lambda* = |G_mu|/Omega_SO - 1/Omega_0 >= 0 "
                "gives -Omega_SO G_mu/|G_mu|; the two branches agree on the switch."
            ),
        ),
        Claim(label="prop:TRSsol", title="u* absolutely continuous iff q1 = q2", check=_check_continuity),
    ]


# ---------------------------------------------------------------------------------------
# Numerics: lambdified from the derivations above.


def _check_form(form: str) -> None:
    if form not in _FORMS:
        raise ValueError(f"The 'form' parameter must be one of {_FORMS}. Got {form!r} instead.")


def _positive(name: str, value: npt.ArrayLike) -> FloatArray:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)) or not np.all(arr > 0):
        raise ValueError(f"The '{name}' parameter must be finite and in (0, inf). Got {value!r} instead.")
    return arr


def _vectors(name: str, value: npt.ArrayLike) -> FloatArray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim < 1 or arr.shape[-1] != 2:
        raise ValueError(
            f"The '{name}' parameter must be an array of shape (..., 2). Got shape {arr.shape} instead."
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"The '{name}' parameter must be finite. Got {value!r} instead.")
    return arr


@lru_cache(maxsize=None)
def _gradient_callables(form: Form) -> tuple[Callable[..., Any], Callable[..., Any]]:
    G = gradient_expr(form)
    args = (vd_x, vd_z, S.d_x, S.d_z, S.e11, S.Omega_0)
    return (sp.lambdify(args, G[0], modules="numpy"), sp.lambdify(args, G[1], modules="numpy"))


@lru_cache(maxsize=None)
def _solfinal_callables() -> tuple[Callable[..., Any], Callable[..., Any], Callable[..., Any]]:
    """Interior branch, saturated branch and threshold of the derived eq:solFinal."""
    interior, boundary, thr, _lam = _solfinal_derived()
    args = (G1, G2, S.Omega_0, S.Omega_SO)

    def vec(expr: sp.Matrix) -> Callable[..., Any]:
        fx = sp.lambdify(args, expr[0], modules="numpy")
        fz = sp.lambdify(args, expr[1], modules="numpy")
        return lambda *a: (fx(*a), fz(*a))

    return vec(interior), vec(boundary), sp.lambdify(args, thr, modules="numpy")


@lru_cache(maxsize=None)
def _u_of_lambda_callable() -> Callable[..., Any]:
    u = _u_of_lambda()
    args = (G1, G2, S.q1, S.q2, S.e11, S.lam)
    fx = sp.lambdify(args, u[0], modules="math")
    fz = sp.lambdify(args, u[1], modules="math")
    return lambda *a: (fx(*a), fz(*a))


def ods_gradient(
    v_d: npt.ArrayLike,
    d_hat: npt.ArrayLike,
    e11_hat: npt.ArrayLike,
    omega_0: npt.ArrayLike,
    form: Form = "derived",
) -> FloatArray:
    """G_mu of eq:ODS2 for Q = I/(Omega_0 e11_hat^2), so that A_mu = I/Omega_0.

    Parameters
    ----------
    v_d
        Reference velocity eq:los, shape (..., 2), m/s.
    d_hat
        Disturbance estimate (eq:nomCont), shape (..., 2), m/s.
    e11_hat
        Estimate of e11 (eq:e11), positive, m (per rad); broadcast over the leading axes.
    omega_0
        Omega_0 > 0 of eq:solFinal (1/Omega_0 = e11^2 q), broadcast over the leading axes.
    form
        ``"derived"``: the sign obtained by expanding eq:tempODS (the default, used by the
        controller); ``"printed"``: eq:ODS2 as printed, which has the opposite sign.

    Returns
    -------
    numpy.ndarray
        G_mu with shape (..., 2): ``(d_hat - v_d)/(Omega_0 e11_hat)`` for the derived form.
    """
    _check_form(form)
    v = _vectors("v_d", v_d)
    d = _vectors("d_hat", d_hat)
    e = _positive("e11_hat", e11_hat)
    w0 = _positive("omega_0", omega_0)
    return _gradient(v, d, e, w0, form)


def _gradient(v: FloatArray, d: FloatArray, e: FloatArray, w0: FloatArray, form: Form) -> FloatArray:
    """:func:`ods_gradient` on validated arrays (shared with :class:`BatchODS`)."""
    try:
        parts = np.broadcast_arrays(v[..., 0], v[..., 1], d[..., 0], d[..., 1], e, w0)
    except ValueError as exc:
        raise ValueError(
            "The 'v_d', 'd_hat', 'e11_hat' and 'omega_0' parameters must broadcast over the "
            f"leading axes. Got shapes {v.shape}, {d.shape}, {e.shape}, {w0.shape} instead."
        ) from exc
    fx, fz = _gradient_callables(form)
    with np.errstate(over="ignore", under="ignore"):
        G = np.stack(np.broadcast_arrays(fx(*parts), fz(*parts)), axis=-1).astype(np.float64)
    if not np.all(np.isfinite(G)):
        raise ValueError(
            "The 'e11_hat' and 'omega_0' parameters must keep G_mu finite. "
            "Got values for which (d_hat - v_d)/(Omega_0 e11_hat) overflows instead."
        )
    return G


def _exceeds(u: FloatArray, radius: FloatArray) -> npt.NDArray[np.bool_]:
    """|u| > radius under both common ways of computing |u| (hypot and the naive sqrt)."""
    with np.errstate(over="ignore", under="ignore"):
        by_hypot = np.hypot(u[..., 0], u[..., 1]) > radius
        naive = np.sqrt(u[..., 0] * u[..., 0] + u[..., 1] * u[..., 1])
    # the naive norm may overflow for radii near the float maximum; only hypot counts there
    by_naive = np.isfinite(naive) & (naive > radius)
    return np.asarray(by_hypot | by_naive)


def _clip_to_ball(u: FloatArray, radius: FloatArray, *, copy: bool = True) -> FloatArray:
    """Shrink the rows of u that exceed ``radius`` by rounding, until |u| <= radius exactly.

    Each pass scales by (radius/|u|)(1 - 2^(k-52)): k = 0 is a one-ulp backoff, and k grows
    so that the loop terminates even for subnormal entries, where one-ulp factors round back.
    ``copy=False`` shrinks a float64 array the caller owns in place.
    """
    if copy:
        u = np.array(u, dtype=np.float64, copy=True)
    if radius.shape != u.shape[:-1]:
        radius = np.broadcast_to(radius, u.shape[:-1])
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        # the common case, decided cheaply: |u|^2 below radius^2 (1 - 1e-12) in floating point,
        # with radius^2 a normal finite number, means |u| < radius exactly (the rounding of each
        # side, underflow included, is far below the 1e-12 margin), so neither hypot nor the naive
        # norm can exceed it; anything else (overflow, NaN, tiny radii) goes the long way
        limit = (radius * radius) * (1.0 - 1e-12)
        inside = ((u[..., 0] * u[..., 0] + u[..., 1] * u[..., 1] <= limit) & (limit >= np.finfo(np.float64).tiny)
                  & (limit < np.inf))
    if inside.all():
        return u
    for k in range(53):
        over = _exceeds(u, radius)
        if not over.any():
            return u
        rows = u[over]
        with np.errstate(over="ignore", under="ignore"):
            factor = np.minimum(radius[over] / np.hypot(rows[:, 0], rows[:, 1]), 1.0) * (1.0 - 2.0 ** (k - 52))
        u[over] = rows * factor[:, None]
    if np.any(_exceeds(u, radius)):
        raise RuntimeError("Could not enforce |u| <= omega_so in floating point.")
    return u


def ods_control(
    v_d: npt.ArrayLike,
    d_hat: npt.ArrayLike,
    e11_hat: npt.ArrayLike,
    omega_0: npt.ArrayLike,
    omega_so: npt.ArrayLike,
    form: Form = "derived",
) -> FloatArray:
    """The ODS angular-velocity command of eq:solFinal; see :func:`ods_control_and_gradient`."""
    return ods_control_and_gradient(v_d, d_hat, e11_hat, omega_0, omega_so, form)[0]


def ods_control_and_gradient(
    v_d: npt.ArrayLike,
    d_hat: npt.ArrayLike,
    e11_hat: npt.ArrayLike,
    omega_0: npt.ArrayLike,
    omega_so: npt.ArrayLike,
    form: Form = "derived",
) -> tuple[FloatArray, FloatArray]:
    """The ODS angular-velocity command of eq:solFinal, |u| <= omega_so exactly, and the G_mu it
    came from (the simulator needs both at every step: G_mu places the saturation's kink).

    ``u = -Omega_0 G_mu`` if ``|G_mu| < Omega_SO/Omega_0``, else ``-Omega_SO G_mu/|G_mu|``,
    with G_mu from :func:`ods_gradient` and both branches lambdified from the derivation.

    Parameters
    ----------
    v_d, d_hat, e11_hat, omega_0, form
        As in :func:`ods_gradient`.
    omega_so
        Step-out frequency Omega_SO of eq:ineq, rad/s, positive; broadcast over leading axes.

    Returns
    -------
    tuple of numpy.ndarray
        u with shape (..., 2), rad/s. Every row satisfies ``hypot(u) <= omega_so`` and
        ``sqrt(u_x^2 + u_z^2) <= omega_so`` in floating point (rounding overshoot is removed).
        With the derived form and no saturation this is eq:nomCont, (v_d - d_hat)/e11_hat.
        Then G_mu, exactly :func:`ods_gradient`'s value.
    """
    G = ods_gradient(v_d, d_hat, e11_hat, omega_0, form)
    return _control(G, _positive("omega_0", omega_0), _positive("omega_so", omega_so)), G


def _control(G: FloatArray, omega_0: FloatArray, omega_so: FloatArray) -> FloatArray:
    """The command of eq:solFinal from G_mu and validated rates (shared with :class:`BatchODS`).

    The simulator calls this at every stage of every step, mostly on a handful of rows, so the
    numpy calls are what costs: the saturated branch is evaluated only when some row saturates,
    and the result is built in place. Every entry is the same floating-point expression either way.
    """
    w0 = omega_0 if omega_0.shape == G.shape[:-1] else np.broadcast_to(omega_0, G.shape[:-1])
    om = omega_so if omega_so.shape == G.shape[:-1] else np.broadcast_to(omega_so, G.shape[:-1])
    interior, boundary, threshold = _solfinal_callables()
    gx, gz = G[..., 0], G[..., 1]
    u = np.empty(G.shape)
    with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
        saturated = np.hypot(gx, gz) >= threshold(gx, gz, w0, om)
        ux_i, uz_i = interior(gx, gz, w0, om)
        if saturated.any():
            # the saturated branch is homogeneous of degree 0 in G_mu: rescale so that |G| ~ 1
            # (no overflow in |G|, no underflow to 0/0)
            scale = np.maximum(np.abs(gx), np.abs(gz))
            safe = np.where(scale > 0, scale, 1.0)
            ux_b, uz_b = boundary(gx / safe, gz / safe, w0, om)
            sat_ok = saturated & (scale > 0)
            u[..., 0] = np.where(sat_ok, ux_b, np.where(saturated, 0.0, ux_i))
            u[..., 1] = np.where(sat_ok, uz_b, np.where(saturated, 0.0, uz_i))
        else:
            u[..., 0] = ux_i
            u[..., 1] = uz_i
    return _clip_to_ball(u, om, copy=False)


class BatchODS:
    """:func:`ods_control_and_gradient` for a batch whose constant inputs are validated once.

    The simulator evaluates the command at every stage of every step with the same ``d_hat``,
    ``e11_hat``, ``Omega_0``, ``Omega_SO`` and form; validating them at each call was a sixth of
    a sweep's simulation time. A call takes the reference ``v_d`` (finite rows: the caller's
    contract, as the simulator's ``_on_finite_rows`` ensures) and the rows of the batch it
    belongs to, and returns what :func:`ods_control_and_gradient` returns, bit for bit
    (``tests/test_ods.py``).
    """

    def __init__(self, d_hat: npt.ArrayLike, e11_hat: npt.ArrayLike, omega_0: npt.ArrayLike,
                 omega_so: npt.ArrayLike, form: Form = "derived") -> None:
        _check_form(form)
        self.form: Form = form
        self.d_hat = _vectors("d_hat", d_hat)
        self.e11_hat = _positive("e11_hat", e11_hat)
        self.omega_0 = _positive("omega_0", omega_0)
        self.omega_so = _positive("omega_so", omega_so)

    def __call__(self, v_d: FloatArray, rows: Any = slice(None)) -> tuple[FloatArray, FloatArray]:
        v = np.asarray(v_d, dtype=np.float64)
        d, e, w0 = self.d_hat[rows], self.e11_hat[rows], self.omega_0[rows]
        if v.ndim == 2 and d.shape == v.shape and e.shape == w0.shape == v.shape[:1]:
            G = self._gradient_rows(v, d, e, w0)
        else:
            G = _gradient(v, d, e, w0, self.form)
        return _control(G, w0, self.omega_so[rows]), G

    def _gradient_rows(self, v: FloatArray, d: FloatArray, e: FloatArray, w0: FloatArray) -> FloatArray:
        """:func:`_gradient` on ``(n, 2)`` rows whose shapes already match: the same lambdified
        expressions, without the broadcasting and stacking that cost more than they compute."""
        fx, fz = _gradient_callables(self.form)
        parts = (v[:, 0], v[:, 1], d[:, 0], d[:, 1], e, w0)
        G = np.empty(v.shape)
        with np.errstate(over="ignore", under="ignore"):
            G[:, 0] = fx(*parts)
            G[:, 1] = fz(*parts)
        if not np.isfinite(G).all():
            raise ValueError(
                "The 'e11_hat' and 'omega_0' parameters must keep G_mu finite. "
                "Got values for which (d_hat - v_d)/(Omega_0 e11_hat) overflows instead."
            )
        return G


def trs_solve_diag(
    G: npt.ArrayLike, q1: float, q2: float, e11: float, omega_so: float
) -> FloatArray:
    """Solve the TRS eq:ODS for Q = diag(q1, q2) by eq:rawSol and the secular eq:algSol.

    The root lambda* >= 0 of eq:algSol is bracketed in
    ``[max(0, |G|/Omega_SO - max_i a_i), |G|/Omega_SO - min_i a_i]`` (a_i = e11^2 q_i) and
    found by :func:`scipy.optimize.brentq` on ``|u(lambda)|/Omega_SO - 1``, with u(lambda)
    lambdified from eq:TRSiff2 (b).

    Parameters
    ----------
    G
        G_mu, shape (2,) or (..., 2).
    q1, q2
        Diagonal of Q, positive.
    e11
        e11 of eq:e11, positive.
    omega_so
        Step-out frequency, rad/s, positive.

    Returns
    -------
    numpy.ndarray
        u*, same shape as G, with |u*| <= omega_so exactly.
    """
    from scipy.optimize import brentq  # scipy.optimize is heavy to import; only solves need it

    g_all = _vectors("G", G)
    for name, value in (("q1", q1), ("q2", q2), ("e11", e11), ("omega_so", omega_so)):
        if np.ndim(value) != 0:
            raise ValueError(f"The '{name}' parameter must be a scalar. Got shape {np.shape(value)} instead.")
    q1f, q2f = float(_positive("q1", q1)), float(_positive("q2", q2))
    ef, om = float(_positive("e11", e11)), float(_positive("omega_so", omega_so))
    a = (ef * ef * q1f, ef * ef * q2f)
    u_of = _u_of_lambda_callable()
    out = np.empty_like(g_all)
    for idx in np.ndindex(g_all.shape[:-1]):
        gx, gz = float(g_all[idx][0]), float(g_all[idx][1])
        ux, uz = u_of(gx, gz, q1f, q2f, ef, 0.0)
        if np.hypot(ux, uz) > om:

            def h(lam: float, gx: float = gx, gz: float = gz) -> float:
                vx, vy = u_of(gx, gz, q1f, q2f, ef, lam)
                return float(np.hypot(vx, vy) / om - 1.0)

            norm_g = float(np.hypot(gx, gz))
            lo, hi = max(0.0, norm_g / om - max(a)), norm_g / om - min(a)
            # in exact arithmetic h(lo) >= 0 >= h(hi); rounding can spoil it at the ends
            if h(lo) <= 0:
                lam = lo
            elif h(hi) >= 0:
                lam = hi
            else:
                lam = float(brentq(h, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500))
            ux, uz = u_of(gx, gz, q1f, q2f, ef, lam)
        out[idx] = (ux, uz)
    return _clip_to_ball(out, np.asarray(om))


@lru_cache(maxsize=1)
def _trs_problem() -> tuple[cvxpy.Problem, cvxpy.Variable, cvxpy.Parameter, cvxpy.Parameter, cvxpy.Parameter]:
    """eq:ODS as a DPP second-order cone program, built once and re-solved via parameters.

    1/2 u^T A u is written 1/2 |L^T u|^2 with A = L L^T (Cholesky), so that the parametrised
    problem stays DPP (a quadratic form with a matrix parameter is not).
    """
    import cvxpy as cp

    u = cp.Variable(2, name="u")
    lt = cp.Parameter((2, 2), name="L_T")
    g = cp.Parameter(2, name="G_mu")
    radius = cp.Parameter(nonneg=True, name="Omega_SO")
    problem = cp.Problem(
        cp.Minimize(0.5 * cp.sum_squares(lt @ u) + g @ u), [cp.norm(u, 2) <= radius]
    )
    return problem, u, lt, g, radius


def trs_solve_cvxpy(G: npt.ArrayLike, A_mu: npt.ArrayLike, omega_so: float) -> FloatArray:
    """Reference solution of the QP eq:ODS as an SOCP, solved by Clarabel.

    Parameters
    ----------
    G
        G_mu, shape (2,).
    A_mu
        Symmetric positive definite (2, 2) matrix.
    omega_so
        Radius Omega_SO > 0.

    Returns
    -------
    numpy.ndarray
        u*, shape (2,), accurate to about :data:`CVXPY_TOL` (no exact-bound guarantee).

    Raises
    ------
    RuntimeError
        If Clarabel's status is anything but ``optimal`` (``optimal_inaccurate`` included).
    """
    import cvxpy as cp

    g = _vectors("G", G)
    if g.shape != (2,):
        raise ValueError(f"The 'G' parameter must have shape (2,). Got shape {g.shape} instead.")
    A = np.asarray(A_mu, dtype=np.float64)
    if A.shape != (2, 2) or not np.all(np.isfinite(A)) or not np.allclose(A, A.T, rtol=0, atol=0):
        raise ValueError(f"The 'A_mu' parameter must be a finite symmetric (2, 2) matrix. Got {A_mu!r} instead.")
    try:
        L = np.linalg.cholesky(A)
    except np.linalg.LinAlgError as exc:
        raise ValueError(f"The 'A_mu' parameter must be positive definite. Got {A_mu!r} instead.") from exc
    om = float(_positive("omega_so", omega_so))
    problem, u, lt, gp, radius = _trs_problem()
    lt.value, gp.value, radius.value = L.T, g, om
    problem.solve(
        solver=cp.CLARABEL, tol_gap_abs=CVXPY_TOL, tol_gap_rel=CVXPY_TOL, tol_feas=CVXPY_TOL
    )
    if problem.status != cp.OPTIMAL or u.value is None:
        raise RuntimeError(f"Clarabel did not solve eq:ODS: status {problem.status!r}, expected 'optimal'.")
    return np.asarray(u.value, dtype=np.float64)

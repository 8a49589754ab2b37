"""``saturated_loop``: what the certified polynomial V proves for the loop users run.

The ODS law of eq. ``eq:solFinal`` is unsaturated exactly when ``|v_d - d_hat| / e11_hat <
Omega_SO``. With ``d_hat = 0`` (Remark rem:Estimates) and ``|v_d| = alpha_d sqrt(Delta^2 + y^2)``
(``y = eps + sigma0 s``, eq. ``eq:los2``), that is the strip

    |y| < Y_sat,   Y_sat^2 = (e11_hat Omega_SO / alpha_d)^2 - Delta^2.

Inside the strip the saturated loop IS the nominal error dynamics of ``sos_gas``.

What is proved (each step exact, with ``V`` from ``sos_gas``, in its scaled coordinates):

1. Invariance (no disturbance). ``V >= l (y^2 + r^2)`` with an exact ``l <= lambda_min(Q_V)``. The
   level ``c = l * Ysat^2 * (1 - 1e-6)`` gives ``{V <= c}`` inside the strip; there ``V' <= -mu V``.
   Hence every trajectory of the saturated loop that starts in ``{V <= c}`` never saturates and
   converges to the path exponentially. A larger level comes from the S-procedure
   ``V - c - sigma (y^2 - Y^2) = SOS`` (:func:`certified_level`): its largest ``c`` is found first,
   where the Gram matrix is singular (so whether a rounded solution there passes the exact check
   would be decided by the solver's last bits); the level used is that ``c`` backed off by
   :data:`LEVEL_BACK_OFF` and rounded down to :data:`LEVEL_DIGITS` significant digits, a point of a
   fixed grid, where the Gram matrices are solved again for the largest margin before the check.
2. With a disturbance ``|d_perp| <= d*`` (scaled ``k_d = |E_0| d* / (Delta |a11|)``): on
   ``{V <= v}``, ``|y|, |r| <= R = sqrt(v/l)`` and ``|dV/dy| <= G(R)`` (sum of ``|coefficient| R^degree``),
   so ``V' <= -R h(R)`` with the concave ``h(R) = mu l R - k_d (g1 + g2 R + g3 R^2)``. If ``h > 0`` at
   ``R_lo`` and at ``R_hi >= Ysat``, ``{V <= c}`` is invariant and every trajectory from it ends in
   ``{V <= l R_lo^2}``: ``limsup |eps| <= sqrt(2) Delta R_lo``.
3. Reaching from anywhere (:func:`global_reach`; assumption: H1/H2 hold under saturation, i.e.
   the swimmer keeps ``p_dot = e11 u + d`` with ``u`` radially saturated at ``Omega_SO``). In the
   physical coordinates ``y = eps + sigma0 s``:

   ``eps' = -phi(y) + E_0 d``,  ``s' = -(k_d + sigma0 U Delta / q) s + U Delta y / q``,  ``q = y^2 + Delta^2``,

   with ``phi(y) = t_s y`` in the strip (``t_s = alpha_d e11 / e11_hat``) and ``e11 Omega_SO y /
   sqrt(q)`` outside; ``|phi|`` grows with ``|y|`` and ``|phi(y)| >= t_s Y`` for ``|y| >= Y`` whenever
   ``Y <= Y_sat`` (at the strip's edge the two laws agree). The s-dynamics do not depend on the
   controller.

   a. Wind-up. ``d|s|/dt <= -(1/q) [(k_d q + sigma0 U Delta) |s| - U Delta |y|]
      <= -k_d (|s| - S*)`` with ``S* = max_y U Delta |y| / (k_d q + sigma0 U Delta)
      = U Delta / (2 sqrt(k_d^2 Delta^2 + k_d sigma0 U Delta))``: the damping that the integrator
      gets near the path (``sigma0 U / Delta``) caps it far below the box ``U / (2 k_d)`` of
      ``ultimate_bound``. So for a rational ``S_1 > S*`` (checked by squaring), ``|s| <= S_1`` is
      reached in finite time and never left.
   b. Pull. For ``|s| <= S_1`` and ``|y| >= Y_q`` (a rational ``Delta <= Y_q <= Y_sat``, checked by
      squaring; ``|y| / q`` and ``1 / q`` decrease for ``|y| >= Delta``):
      ``sign(y) y' <= -t_s Y_q + |E_0| d* + sigma0 k_d S_1 + sigma0 U Delta Y_q / q_q
      + sigma0^2 U Delta S_1 / q_q = -gamma``. When ``gamma > 0`` (exact), ``|y|`` falls at rate
      ``>= gamma`` until ``|y| <= Y_q``, and the set ``K = {|y| <= Y_q, |s| <= S_1}`` is entered in
      finite time and never left.
   c. Inside ``K`` the loop is unsaturated: it IS the error dynamics of the other classes from the
      entry time on, so every conclusion they prove from ANY initial condition (``sos_gas``:
      convergence with ``d = 0``; ``sos_bound``: ``limsup |eps|`` under ``|d| <= d*``) holds for
      the real, saturated loop from ANY initial condition.

   The real loop is never GES, whatever the gains: ``|eps'| <= e11 Omega_SO + |E_0| d*`` bounds the
   speed, so from ``|eps(0)| = E`` the error needs time ``>= E / (2 e11 Omega_SO)`` to halve,
   while ``k |x0| exp(-lambda t)`` would halve it in a time independent of ``E``.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import poly
from lyapcheck.paper import claims
from lyapcheck.paper.claims import OMEGA_ROUNDING
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.paper.conditions.sos import bases, scaled_dynamics
from symbolic._generated import integrator_rates, unsaturated_strip_sq, windup_bound_sq

SQRT2_UPPER = Fraction(141422, 100000)
#: the S-procedure level (step 1 of the module docstring): the solver's largest c, backed off by
#: this fraction and rounded down to LEVEL_DIGITS significant digits (a fixed grid, so every
#: platform checks the same level unless the solvers' c straddle a grid point: then one step)
LEVEL_BACK_OFF = 1e-3
LEVEL_DIGITS = 4


def build_level_program(cp: Any, deg_v: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """max c s.t. V - c - sigma (y^2 - Y^2) = z_p^T Q_p z_p, sigma = z_s^T S z_s, Q_p, S >= 1e-9 I (DPP; compiled once)."""
    c = cp.Variable(name="c")
    S, Qp, y_sq, v, cons = _level_identity(cp, deg_v, c)
    ns, n_p = S.shape[0], Qp.shape[0]
    cons += [S >> 1e-9 * np.eye(ns), Qp >> 1e-9 * np.eye(n_p)]
    params = {"Y_sq": y_sq, **{_param_name(m): p for m, p in v.items()}}
    return cp.Problem(cp.Maximize(c), cons), params, {"S": S, "Q_p": Qp, "c": c}


def build_level_margin_program(cp: Any, deg_v: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """max t s.t. V - c - sigma (y^2 - Y^2) = z_p^T Q_p z_p, Q_p, S >= t I at a given level ``c``
    (DPP; compiled once): the Gram matrices with the largest margin, for the exact check."""
    c = cp.Parameter(nonneg=True, name="c")
    t = cp.Variable(name="t")
    S, Qp, y_sq, v, cons = _level_identity(cp, deg_v, c)
    ns, n_p = S.shape[0], Qp.shape[0]
    cons += [S >> t * np.eye(ns), Qp >> t * np.eye(n_p)]
    params = {"c": c, "Y_sq": y_sq, **{_param_name(m): p for m, p in v.items()}}
    return cp.Problem(cp.Maximize(t), cons), params, {"S": S, "Q_p": Qp, "t": t}


def _level_identity(cp: Any, deg_v: int, c: Any) -> tuple[Any, Any, Any, dict[poly.Monomial, Any], list[Any]]:
    """``S``, ``Q_p``, the parameters ``Y_sq`` and ``v_m`` (V's coefficients) and the coefficient
    identity ``V - c - sigma (y^2 - Y^2) = z_p^T Q_p z_p``, monomial by monomial."""
    z_s, z_p = level_bases(deg_v)
    S = cp.Variable((len(z_s), len(z_s)), symmetric=True, name="S")
    Qp = cp.Variable((len(z_p), len(z_p)), symmetric=True, name="Q_p")
    y_sq = cp.Parameter(nonneg=True, name="Y_sq")
    v = {m: cp.Parameter(name=_param_name(m)) for m in poly.monomials(0, deg_v)}
    classes = poly.gram_classes(z_p)
    s_classes = poly.gram_classes(z_s)
    cons = []
    for m, vm in v.items():
        lhs = sum(Qp[i, j] for i, j in classes.get(m, [])) if m in classes else 0
        # sigma * y^2 contributes S entries of monomial (m - (2, 0)); sigma * (-Y^2) those of m
        shifted = (m[0] - 2, m[1])
        times_y2 = sum(S[i, j] for i, j in s_classes.get(shifted, [])) if shifted in s_classes else 0
        plain = sum(S[i, j] for i, j in s_classes.get(m, [])) if m in s_classes else 0
        rhs = vm - (c if m == (0, 0) else 0) - times_y2 + y_sq * plain
        cons.append(lhs == rhs)
    return S, Qp, y_sq, v, cons


def _param_name(m: poly.Monomial) -> str:
    return f"v_{m[0]}_{m[1]}"


def level_bases(deg_v: int) -> tuple[list[poly.Monomial], list[poly.Monomial]]:
    """Monomial vectors of the multiplier ``sigma`` and of the level's Gram form."""
    half = deg_v // 2
    return poly.monomials(0, half - 1), poly.monomials(0, half)


def level_residual(V: poly.Poly, c: Fraction, S: exact.Matrix, z_s: list[poly.Monomial], Y_sq: Fraction) -> poly.Poly:
    """``V - c - sigma (y^2 - Y^2)`` exactly."""
    sigma = poly.gram_form(z_s, S)
    shifted = poly.mul(sigma, {(2, 0): Fraction(1), (0, 0): -Y_sq})
    return poly.add(V, {(0, 0): -c}, poly.scale(Fraction(-1), shifted))


def check_level(V: poly.Poly, deg_v: int, level: dict[str, Any], Y_sq: Fraction) -> tuple[bool, str]:
    """Exact: S > 0, Q_p > 0 and V - c - sigma (y^2 - Y^2) = z_p^T Q_p z_p, so V > c wherever |y| >= Y."""
    prog_z_s, prog_z_p = level_bases(deg_v)
    S, Qp, c = exact.from_json(level["S"]), exact.from_json(level["Q_p"]), Fraction(level["c"])
    if not (exact.is_positive_definite_ldl(S) and exact.is_positive_definite_ldl(Qp)):
        return False, "multiplier or Gram matrix of the level certificate is not positive definite"
    if level_residual(V, c, S, prog_z_s, Y_sq) != poly.gram_form(prog_z_p, Qp):
        return False, "the level identity does not hold exactly"
    return True, "V > c wherever |y| >= Y_sat (exact S-procedure)"


def certified_level(V: poly.Poly, deg_v: int, Y_sq: Fraction, floor: Fraction = Fraction(0)) -> dict[str, Any] | None:
    """A level ``c > floor`` on the grid of :data:`LEVEL_DIGITS` digits, near the largest with
    ``{V <= c}`` inside the strip (module docstring, step 1), checked exactly; None if there is none.

    The first solve finds the largest ``c`` (an "inaccurate" one too: it only proposes); the second
    solves the Gram matrices at the grid level with the largest margin ``t``, and that solution is
    mapped back, rounded, projected onto the identity and checked exactly. Both solves run in
    coordinates ``(y, r) = L (u, v)`` with ``L ~ Y`` and ``V`` divided by ``N``, its largest
    coefficient there (:func:`_level_scales`): the strip is ``|u| < ~1`` and every number of the
    program of order one (unscaled, a wide strip, as at ``Y = 88`` with ``V ~ y^4``, put the level
    near 1e7 and the Gram entries from 1e-9 to 1e7, and the solver stopped with an error on some
    platforms only). ``floor``: a level already proved (no second solve below it).
    """
    from lyapcheck.paper.conditions import compiled
    from lyapcheck.paper.conditions.rounding import floor_to_digits
    from lyapcheck.paper.conditions.sos import project_gram

    L, N = _level_scales(V, Y_sq)
    V_s = {m: Fraction(a) * L ** sum(m) / N for m, a in V.items()}
    values = {"Y_sq": float(Y_sq / L**2), **{_param_name(m): float(V_s.get(m, 0)) for m in poly.monomials(0, deg_v)}}
    largest = compiled.load(f"level_{deg_v}").solve(values)
    if largest.report.outcome not in ("optimal", "inaccurate") or largest.values is None:
        return None
    c_max = float(largest.values["c"]) * (1 - LEVEL_BACK_OFF) * float(N)
    if not (math.isfinite(c_max) and c_max > 0):
        return None
    c = floor_to_digits(c_max, LEVEL_DIGITS)
    if c <= floor:
        return None
    solved = compiled.load(f"level_margin_{deg_v}").solve({**values, "c": float(c / N)})
    v = solved.values
    if solved.report.outcome not in ("optimal", "inaccurate") or v is None or not v["t"] > 0:
        return None
    z_s, z_p = level_bases(deg_v)
    # back to (y, r): sigma(y, r) = N / L^2 sigma_s(y / L, r / L), z_p^T Q_p z_p = N (z_p^T Q_p,s z_p)(y / L, r / L)
    S = _unscaled(exact.symmetrize(exact.rational_matrix(v["S"])), z_s, L, N / L**2)
    Qp_s = _unscaled(exact.symmetrize(exact.rational_matrix(v["Q_p"])), z_p, L, N)
    Qp = project_gram(z_p, Qp_s, level_residual(V, c, S, z_s, Y_sq))
    if Qp is None:
        return None
    level = {"c": str(c), "S": exact.to_json(S), "Q_p": exact.to_json(Qp)}
    return level if check_level(V, deg_v, level, Y_sq)[0] else None


def _level_scales(V: poly.Poly, Y_sq: Fraction) -> tuple[Fraction, Fraction]:
    """Rationals ``L ~ sqrt(Y_sq)`` and ``N``, the largest coefficient of ``V(L u, L v)`` (3 digits each)."""
    L = exact.to_rational(math.sqrt(float(Y_sq)), 3)
    largest = max((abs(float(Fraction(a) * L ** sum(m))) for m, a in V.items()), default=1.0)
    return L, exact.to_rational(largest, 3) if largest > 0 else Fraction(1)


def _unscaled(Q: exact.Matrix, basis: list[poly.Monomial], L: Fraction, factor: Fraction) -> exact.Matrix:
    """The Gram matrix over ``basis`` in ``(y, r)`` of ``factor * (z^T Q z)(y / L, r / L)`` (exact congruence)."""
    d = [L ** -sum(m) for m in basis]
    return tuple(tuple(factor * d[i] * Q[i][j] * d[j] for j in range(len(basis))) for i in range(len(basis)))


def lambda_min_lower(Q: exact.Matrix) -> Fraction | None:
    lam = float(np.linalg.eigvalsh(np.array(exact.to_float(Q))).min())
    if lam <= 0:
        return None
    ell = exact.to_rational(lam * 0.99, 6)
    n = len(Q)
    for _ in range(40):
        shifted = tuple(tuple(Q[i][j] - (ell if i == j else 0) for j in range(n)) for i in range(n))
        if exact.is_positive_definite_ldl(shifted):
            return ell
        ell /= 2
    return None


def gradient_bound_coefficients(V: poly.Poly) -> list[Fraction]:
    """``[g0, g1, g2, ...]`` with ``|dV/dy| <= sum g_k R^k`` whenever ``|y|, |r| <= R``."""
    dv = poly.deriv(V, 0)
    coeffs: list[Fraction] = [Fraction(0)] * (max((sum(m) for m in dv), default=0) + 1)
    for m, c in dv.items():
        coeffs[sum(m)] += abs(Fraction(c))
    return coeffs


def h_value(R: Fraction, mu: Fraction, ell: Fraction, kd: Fraction, g: list[Fraction]) -> Fraction:
    """``h(R) = mu l R - kd * sum_{k>=1} g_k R^{k-1}`` (``g_0 = 0``: V has no linear term)."""
    return mu * ell * R - kd * sum((gk * R ** (k - 1) for k, gk in enumerate(g) if k >= 1), Fraction(0))


def reach_push(system: System, k_d: Fraction, S1: Fraction, Yq: Fraction) -> Fraction:
    """Largest push away from the strip for ``|y| >= Y_q``, ``|s| <= S_1``: ``|E_0| d* + sigma0
    (damping(Y_q) S_1 + forcing(Y_q))`` with the integrator's rates from the derivation (both
    decrease in ``|y|`` for ``|y| >= Delta``)."""
    damping, forcing = integrator_rates(Yq, system.sigma0, k_d, system.delta, system.speed)
    return abs(system.E[0]) * system.d_max + system.sigma0 * (damping * S1 + forcing)


def global_reach(system: System, *, k_d: Fraction, y_sat_sq: Fraction, time_scale: Fraction) -> dict[str, str] | None:
    """Step 3 of the module docstring: rationals ``S_1 > S*``, ``Delta <= Y_q <= Y_sat`` and the
    margin ``gamma`` (exact; reach is proved when ``gamma > 0``). None if ``Y_sat < Delta``."""
    delta = system.delta
    if y_sat_sq < delta**2:
        return None
    s_star_sq = windup_bound_sq(system.sigma0, k_d, delta, system.speed)
    S1 = exact.to_rational(math.sqrt(float(s_star_sq)) * (1 + 1e-6), 8)
    while S1 * S1 <= s_star_sq:
        S1 *= 1 + Fraction(1, 10**6)
    Yq = exact.to_rational(math.sqrt(float(y_sat_sq)) * (1 - 1e-9), 8)
    while Yq * Yq > y_sat_sq:
        Yq *= 1 - Fraction(1, 10**9)
    if Yq < delta:
        return None
    pull = time_scale * Yq
    push = reach_push(system, k_d, S1, Yq)
    return {"S_star_sq": str(s_star_sq), "S_1": str(S1), "Y_q": str(Yq), "pull": str(pull), "push": str(push),
            "gamma": str(pull - push)}


def run(system: System, sos_result: ConditionResult, *, alpha_d: Fraction, e11: Fraction, e11_hat: Fraction,
        omega_so: Fraction, k_d: Fraction) -> ConditionResult:
    if system.dynamics != "derived":
        return ConditionResult("saturated_loop", "not_certified",
                               "not applicable: the printed error dynamics are not the plant's (see ledger eq:los3)")
    if sos_result.status != "certified":
        return ConditionResult("saturated_loop", "not_certified",
                               "needs a certified polynomial V (sos_gas), which was not found")
    dyn = scaled_dynamics(system)
    assert dyn is not None  # sos_gas was certified on the same structure
    cert = sos_result.certificate
    QV = exact.from_json(cert["Q_V"])
    mu = Fraction(cert["mu_scaled"])
    z_v, _ = bases(int(cert["degree"]))
    V = poly.gram_form(z_v, QV)
    ell = lambda_min_lower(QV)
    omega_lo = omega_so * (1 - OMEGA_ROUNDING)
    y_sat_sq = unsaturated_strip_sq(alpha_d, system.delta, e11_hat, omega_lo)
    if ell is None or y_sat_sq <= 0:
        return ConditionResult("saturated_loop", "not_certified",
                               "the ODS law saturates everywhere (Omega_SO e11_hat <= alpha_d Delta) or V's bound failed")
    Y_sq = y_sat_sq / system.delta**2  # scaled strip half-width, squared
    # level from V >= l (y^2 + r^2) (always valid), improved by the exact S-procedure when it passes
    c = ell * Y_sq * (1 - Fraction(1, 10**6))
    level = certified_level(V, int(cert["degree"]), Y_sq, floor=c)
    if level is not None:
        c = Fraction(level["c"])
    data: dict[str, Any] = {"lambda_min_lower": str(ell), "strip_half_width_sq_scaled": str(Y_sq), "level_c": str(c),
                            "level_certificate": level}
    numbers: dict[str, Any] = {
        "strip_half_width_m": math.sqrt(float(y_sat_sq)),
        "invariant_eps_radius_m_at_s0": None,
        "ultimate_eps_bound_m": None,
        "global_reach": None,
    }
    # an inner estimate: with s = 0 (r = 0), |V(y, 0)| <= sum_k |a_k| Y0^k for |y| <= Y0
    on_axis = [abs(Fraction(v)) for m, v in V.items() if m[1] == 0]
    degs = [m[0] for m in V if m[1] == 0]

    def axis_bound(y0: Fraction) -> Fraction:
        return sum((a * y0**d for a, d in zip(on_axis, degs)), Fraction(0))

    lo_y, hi_y = Fraction(0), exact.sqrt_upper(Y_sq)
    for _ in range(40):
        mid = (lo_y + hi_y) / 2
        lo_y, hi_y = (mid, hi_y) if axis_bound(mid) <= c else (lo_y, mid)
    y0 = Fraction(math.floor(float(lo_y) * 10**6), 10**6)  # rounded down: still inside
    if axis_bound(y0) > c:  # pragma: no cover - y0 <= lo_y, which satisfies it
        y0 = Fraction(0)
    numbers["invariant_eps_radius_m_at_s0"] = float(y0 * system.delta)
    data["axis_radius_scaled"] = str(y0)
    # with disturbance
    kd = abs(system.E[0]) * system.d_max / (system.delta * dyn.time_scale)
    g = gradient_bound_coefficients(V)
    R_hi = exact.sqrt_upper(Y_sq)
    if system.d_max > 0:
        a = float(kd * g[3]) if len(g) > 3 else 0.0
        bcoef = float(kd * g[2]) - float(mu * ell) if len(g) > 2 else -float(mu * ell)
        c0 = float(kd * g[1]) if len(g) > 1 else 0.0
        disc = bcoef * bcoef - 4 * a * c0
        ok_bound = False
        if a > 0 and disc > 0 and bcoef < 0:
            R_lo = exact.to_rational((-bcoef - math.sqrt(disc)) / (2 * a) * 1.001, 6)
            if h_value(R_lo, mu, ell, kd, g) > 0 and h_value(R_hi, mu, ell, kd, g) > 0 and R_lo < R_hi:
                ok_bound = True
                eps_bound = SQRT2_UPPER * system.delta * R_lo
                numbers["ultimate_eps_bound_m"] = float(eps_bound)
                data.update({"R_lo": str(R_lo), "R_hi": str(R_hi), "kd_scaled": str(kd),
                             "eps_bound": str(eps_bound)})
        if not ok_bound:
            data["disturbance"] = "not proved"

    # global reach (module docstring, step 3)
    reach = global_reach(system, k_d=k_d, y_sat_sq=y_sat_sq, time_scale=dyn.time_scale)
    proved = reach is not None and Fraction(reach["gamma"]) > 0
    numbers["global_reach"] = "proved" if proved else "not_proved"
    numbers["not_ges"] = claims.not_ges(e11 * omega_so + abs(system.E[0]) * system.d_max)
    if reach is not None:
        data["reach"] = reach
        numbers["windup_bound_s_m"] = float(Fraction(reach["S_1"]))
        numbers["reach_set_y_half_width_m"] = float(Fraction(reach["Y_q"]))
        numbers["reach_margin_m_per_s"] = float(Fraction(reach["gamma"]))
        numbers["reach_condition"] = claims.reach_condition(reach)
    return claims.decided(ConditionResult("saturated_loop", "certified", "", numbers=numbers, certificate=data),
                          {"delta_los": system.delta, "d_max": system.d_max, "e11": e11, "omega_so": omega_so})


def verify(system: System, sos_cert: dict[str, Any], cert: dict[str, Any], *, alpha_d: Fraction,
           e11_hat: Fraction, omega_so: Fraction, k_d: Fraction | None = None) -> tuple[bool, str]:
    """Exact re-check of the invariance part (the level inside the strip) and the axis radius."""
    from lyapcheck.paper.conditions.sos import stored_degree_and_bases

    deg_v, why = stored_degree_and_bases(sos_cert)
    if why is not None:
        return False, f"the V of sos_gas: {why}"
    z_v, _ = bases(deg_v)
    V = poly.gram_form(z_v, exact.from_json(sos_cert["Q_V"]))
    Y_sq = unsaturated_strip_sq(alpha_d, system.delta, e11_hat, omega_so * (1 - OMEGA_ROUNDING)) / system.delta**2
    if Fraction(cert["strip_half_width_sq_scaled"]) != Y_sq:
        return False, "stored strip width does not follow from the inputs"
    c = Fraction(cert["level_c"])
    ell = Fraction(cert["lambda_min_lower"])
    QV = exact.from_json(sos_cert["Q_V"])
    n = len(QV)
    if not exact.is_positive_definite_ldl(tuple(tuple(QV[i][j] - (ell if i == j else 0) for j in range(n)) for i in range(n))):
        return False, "lambda_min lower bound of Q_V fails"
    if c > ell * Y_sq:
        level = cert.get("level_certificate")
        if level is None or Fraction(level["c"]) != c:
            return False, "level c exceeds what lambda_min proves and has no S-procedure certificate"
        ok, why = check_level(V, deg_v, level, Y_sq)
        if not ok:
            return False, why
    y0 = Fraction(cert["axis_radius_scaled"])
    axis = sum((abs(Fraction(v)) * y0 ** m[0] for m, v in V.items() if m[1] == 0), Fraction(0))
    if axis > c:
        return False, "the stated axis radius is not inside {V <= c}"
    if "R_lo" in cert:  # step 2: the bound under the disturbance, from the concave h
        dyn = scaled_dynamics(system)
        if dyn is None:
            return False, "the dynamics do not have the structure this class needs"
        kd = abs(system.E[0]) * system.d_max / (system.delta * dyn.time_scale)
        g = gradient_bound_coefficients(V)
        mu = Fraction(sos_cert["mu_scaled"])
        R_lo, R_hi = Fraction(cert["R_lo"]), Fraction(cert["R_hi"])
        if not (Fraction(cert["kd_scaled"]) == kd and 0 < R_lo < R_hi and R_hi * R_hi >= Y_sq
                and h_value(R_lo, mu, ell, kd, g) > 0 and h_value(R_hi, mu, ell, kd, g) > 0):
            return False, "the disturbance step (h(R_lo) > 0, h(R_hi) > 0, R_hi >= Y) does not hold"
        if Fraction(cert["eps_bound"]) < SQRT2_UPPER * system.delta * R_lo:
            return False, "the stated eps bound under d* is below sqrt(2) Delta R_lo"
    if "reach" in cert and k_d is not None:
        ok, why = verify_reach(system, cert["reach"], k_d=k_d, alpha_d=alpha_d, e11_hat=e11_hat, omega_so=omega_so)
        if not ok:
            return False, why
        return True, "{V <= c} lies in the unsaturated strip and contains the stated starts; " + why
    return True, "{V <= c} lies in the unsaturated strip and contains the stated starts, exactly"


def verify_reach(system: System, reach: dict[str, str], *, k_d: Fraction, alpha_d: Fraction, e11_hat: Fraction,
                 omega_so: Fraction) -> tuple[bool, str]:
    """Re-check step 3 from the inputs: ``S_1 > S*``, ``Delta <= Y_q <= Y_sat`` and ``gamma``."""
    delta = system.delta
    S1, Yq, gamma = Fraction(reach["S_1"]), Fraction(reach["Y_q"]), Fraction(reach["gamma"])
    y_sat_sq = unsaturated_strip_sq(alpha_d, delta, e11_hat, omega_so * (1 - OMEGA_ROUNDING))
    if not S1 * S1 > windup_bound_sq(system.sigma0, k_d, delta, system.speed):
        return False, "the wind-up bound S_1 is not above S*"
    if not (delta <= Yq and Yq * Yq <= y_sat_sq):
        return False, "Y_q is not between Delta and the strip's half-width"
    if gamma != -system.A[0][0] * Yq - reach_push(system, k_d, S1, Yq):
        return False, "the stated reach margin does not follow from the inputs"
    fresh = {"S_star_sq": windup_bound_sq(system.sigma0, k_d, delta, system.speed), "pull": -system.A[0][0] * Yq,
             "push": reach_push(system, k_d, S1, Yq)}
    if any(key in reach and Fraction(reach[key]) != value for key, value in fresh.items()):
        return False, "the stated S_star_sq, pull or push does not follow from the inputs"
    return True, (f"global reach re-checked: margin {float(gamma):.4g} m/s" if gamma > 0
                  else "global reach not proved (margin <= 0), as stated")

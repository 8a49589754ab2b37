"""A global ultimate bound on ``|eps|`` from a polynomial certificate (a stage of ``ultimate_bound``).

In the scaled coordinates of :mod:`lyapcheck.paper.conditions.sos` a disturbance ``|d_perp| <= d*``
adds ``w`` to ``y'`` with ``|w| <= k = |E_0| d* / (Delta |a11|)``. Exact rational certificates:

* ``V = z^T Q_V z`` over ``z = (1, y, r, y^2, y r, r^2)`` with ``Q_V - delta diag(0,0,0,1,1,1) > 0``
  (so ``V >= delta (y^4 + y^2 r^2 + r^4)``: radially unbounded);
* dissipation, in ``(y, r, w)``: ``-grad V . g - q (dV/dy) w - lam (V - 1) - tau (k^2 - w^2) = z_D^T Q_D z_D``
  with ``tau = z_T^T T z_T`` and ``Q_D, T > 0``;
* output: ``V - (y - r)^2 + (B - 1) = z_E^T Q_E z_E`` with ``Q_E > 0``.

For conditioning the certificate is written with ``r = beta r~`` and time divided by ``omega``
(exact rationals; the argument is unchanged in those coordinates). ``omega`` is near ``sqrt(b)``,
the ILOS oscillation frequency in scaled time.

Conditioning of the search. With ``beta = sqrt(b)`` (the linear oscillation's balance) the optimal
``V`` is dominated by ``r~^4`` (Gram entries from 1e-4 to 2e4 at the paper's gains): Clarabel
stopped at its 200-iteration cap with ``B`` still creeping down, so the figure was wherever the
solver stopped. The search therefore tries, per decay rate, the coordinates of
:data:`SEARCH_SCALES`: ``beta`` a fraction of ``sqrt(b)``, and the disturbance written as
``w = kappa w~`` with ``|w~| <= k / kappa`` (``kappa`` near ``k``), which keeps ``T`` and ``Q_D`` of
order one. There a solve converges in 20-40 iterations. The multipliers found in ``w~`` are
mapped back exactly (``Q_D[i][j] / kappa^(d_i + d_j)`` and ``T[i][j] / kappa^(d_i + d_j + 2)``
with ``d`` the degree in ``w``: the identity in ``w~`` is the identity in ``w`` after the
substitution), so the certificate and its check do not know about ``kappa``.

Symmetry. The field is odd and ``q`` even, so the search runs over Gram matrices that are block
diagonal by monomial parity (:func:`build_parity_program`; the argument is in
:mod:`lyapcheck.paper.conditions.sos`): the same optimum from PSD blocks of at most 12 x 12 instead of
19 x 19, a solve in about a quarter of the time. The certificate's matrices are the full ones,
zero between the blocks, and the exact check is unchanged.

Proof. Wherever ``V >= 1`` and ``|w| <= k``: ``q V' = grad V . g + q (dV/dy) w <= -lam (V - 1) <= 0``.
If ``V >= 1 + delta`` held for ever, the trajectory would stay in the compact set
``{1 + delta <= V <= V(t0)}``, where ``q`` is bounded, so ``V' <= -lam delta / q_max`` would drive
``V`` below ``1 + delta``, a contradiction; and ``V = 1 + delta`` cannot be crossed upwards. So
``limsup V <= 1`` from EVERY initial condition, and by the output certificate
``(y - r)^2 <= V + B - 1``, hence ``limsup |eps| = Delta limsup |y - r| <= Delta sqrt(B)``.
This speaks of the error dynamics (unsaturated ODS law), as Proposition 4.1 does.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import poly
from lyapcheck import tolerances as tol
from lyapcheck.paper.conditions.base import System
from lyapcheck.sos.definiteness import is_positive_definite
from lyapcheck.sos.sdp import CompiledProgram
from lyapcheck.paper.conditions.sos import (ScaledDynamics, assemble_parity_blocks, is_sign_symmetric, parity, parity_blocks,
                                      parity_gram, project_gram, scaled_dynamics)

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.results import ConditionResult

#: strictness margins of the numerical search, so the exact checks survive rounding
ETA = 1e-7
TOP_DELTA = Fraction(1, 10**4)
#: decay rates tried (balanced time); each costs one solve of ~0.1 s (see SEARCH_SCALES)
LAMBDA_GRID = (0.03, 0.3, 1.0)
#: the bound stated at a decay rate: the solver's smallest B raised by this fraction and rounded
#: up to BOUND_DIGITS significant digits (a fixed grid: two platforms state the same bound unless
#: their smallest B straddle a grid point, one step apart then); where the smallest B's own
#: solution fails the exact check, the Gram matrices are solved again at that level (see run)
BOUND_BACK_OFF = 1e-3
BOUND_DIGITS = 4
#: coordinates of the search, tried in this order for each decay rate until a solution passes the
#: exact check: (``beta`` over ``sqrt(b)``, floor of ``kappa``; ``kappa = k / omega`` clipped to
#: [floor, 1]). Chosen on 102 points of the shipped sweeps: the first alone certified 16 points
#: that ``beta = sqrt(b)`` did not but missed 3 it did; with the second as a fallback none was
#: missed. ``benchmarks/bench_sos_bound.py`` measures the search against the one before.
SEARCH_SCALES: Final = ((Fraction(1, 10), 0.1), (Fraction(1, 20), 0.03))

Z_V = poly.monomials(0, 2)
Z_E = poly.monomials(0, 2)
Z_T = poly.monomials(0, 2, 3)
#: r^3 is left out: the top-degree part of the dissipation form vanishes to second order on y = 0
Z_D = [m for m in poly.monomials(0, 3, 3) if m != (0, 3, 0)]
TOP = [i for i, m in enumerate(Z_V) if sum(m) == 2]


def balanced_fields(dyn: ScaledDynamics, beta: Fraction, omega: Fraction) -> tuple[poly.Poly, poly.Poly, poly.Poly]:
    """The field in ``(y, r~)`` with ``r = beta r~`` and time divided by ``omega`` (exact)."""
    g_y, g_r, q = dyn.fields()

    def sub(p: poly.Poly) -> poly.Poly:
        return {m: c * beta ** m[1] for m, c in p.items()}

    return poly.scale(1 / omega, sub(g_y)), poly.scale(1 / (beta * omega), sub(g_r)), sub(q)


def dissipation(V: poly.Poly, tau: poly.Poly, fields: tuple[poly.Poly, poly.Poly, poly.Poly], k: Any, lam: Any) -> poly.Poly:
    """``-grad V . g - q (dV/dy) w - lam (V - 1) - tau (k^2 - w^2)`` in (y, r~, w)."""
    g_y, g_r, q = (poly.embed(p, 3) for p in fields)
    V3 = poly.embed(V, 3)
    flow = poly.add(poly.mul(poly.deriv(V3, 0), g_y), poly.mul(poly.deriv(V3, 1), g_r))
    push = poly.mul(poly.mul(q, poly.deriv(V3, 0)), {(0, 0, 1): 1})
    level = poly.scale(lam, poly.add(V3, {(0, 0, 0): -1}))
    s_proc = poly.mul(tau, {(0, 0, 0): k * k, (0, 0, 2): -1})
    return poly.add(poly.scale(-1, flow), poly.scale(-1, push), poly.scale(-1, level), poly.scale(-1, s_proc))


def output_form(V: poly.Poly, B: Any, beta: Any) -> poly.Poly:
    """``V - (y - beta r~)^2 + (B - 1)``."""
    return poly.add(V, {(2, 0): -1, (1, 1): 2 * beta, (0, 2): -beta * beta}, {(0, 0): B - 1})


MONOS_D = poly.monomials(0, 6, 3)
#: the dissipation identity's monomials that a sign-symmetric certificate must match (the odd
#: ones hold by symmetry)
EVEN_MONOS_D: Final = [m for m in MONOS_D if parity(m) == 0]


def _param_name(m: poly.Monomial) -> str:
    return "C_" + "_".join(str(e) for e in m)


def value_tables() -> dict[poly.Monomial, np.ndarray]:
    """``L_m``: the coefficient of monomial ``m`` (in ``(y, r~, w)``) of ``V`` is ``<L_m, Q_V>``."""
    n = len(Z_V)
    tables = {m: np.zeros((n, n)) for m in MONOS_D}
    for m2, entries in poly.gram_classes(Z_V).items():
        for i, j in entries:
            tables[(*m2, 0)][i, j] += 1.0
    return tables


def dissipation_constraints(QD: Any, QV: Any, T: Any, C: Mapping[poly.Monomial, Any], lam: Any, k2: Any,
                            cp: Any, monomials: Sequence[poly.Monomial] = MONOS_D) -> list[Any]:
    """``z_D^T Q_D z_D == -grad V . g - q (dV/dy) w - lam (V - 1) - tau (k^2 - w^2)``, monomial by
    monomial; the dynamics enter through ``C[m]`` (``<C_m, Q_V>`` is the flow's part of monomial
    ``m``, a Parameter or an array). Shared with the box version (:mod:`lyapcheck.paper.boxes.bounds`).
    ``monomials``: those whose coefficient identity is imposed (all by default)."""
    d_classes, t_classes = poly.gram_classes(Z_D), poly.gram_classes(Z_T)
    Lv = value_tables()
    cons = []
    for m in monomials:
        lhs = sum(QD[i, j] for i, j in d_classes.get(m, [])) if m in d_classes else 0
        rhs = cp.sum(cp.multiply(C[m], QV)) - lam * cp.sum(cp.multiply(Lv[m], QV))
        if m == (0, 0, 0):
            rhs = rhs + lam
        # - tau (k^2 - w^2): tau coefficient of m times -k^2, and of m - (0,0,2) times +1
        if m in t_classes:
            rhs = rhs - k2 * sum(T[i, j] for i, j in t_classes[m])
        shifted = (m[0], m[1], m[2] - 2)
        if shifted in t_classes:
            rhs = rhs + sum(T[i, j] for i, j in t_classes[shifted])
        cons.append(lhs == rhs)
    return cons


def output_constraints(QE: Any, QV: Any, B: Any, beta: Any, beta2: Any) -> list[Any]:
    """``z_E^T Q_E z_E == V - (y - beta r~)^2 + (B - 1)``, monomial by monomial."""
    e_classes, v_classes = poly.gram_classes(Z_E), poly.gram_classes(Z_V)
    cons = []
    for m in poly.monomials(0, 4):
        lhs = sum(QE[i, j] for i, j in e_classes.get(m, [])) if m in e_classes else 0
        v_part = sum(QV[i, j] for i, j in v_classes.get(m, [])) if m in v_classes else 0
        # -(y - beta r~)^2 written out monomial by monomial
        extra: Any = {(2, 0): -1.0, (1, 1): 2.0 * beta, (0, 2): -beta2}.get((m[0], m[1]), 0.0)
        const = (B - 1) if m == (0, 0) else 0
        cons.append(lhs == v_part + extra + const)
    return cons


def top_shift() -> np.ndarray:
    """``delta diag(0, 0, 0, 1, 1, 1)``: ``Q_V`` minus it must stay positive definite."""
    top = np.zeros((len(Z_V), len(Z_V)))
    for i in TOP:
        top[i, i] = float(TOP_DELTA)
    return top


def build_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """The three certificates of the module docstring at given scales and lambda, ``B`` minimised
    (DPP; compiled once)."""
    return _build_full(cp, fixed=False)


def build_fixed_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """:func:`build_program` at a given bound ``B`` (a parameter), a feasibility program: the
    solver stops near the centre of the feasible set, away from the singular Gram matrices of the
    smallest ``B`` (:func:`run` uses it when the smallest ``B``'s solution fails the exact check)."""
    return _build_full(cp, fixed=True)


def _build_full(cp: Any, fixed: bool) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    QV = cp.Variable((len(Z_V), len(Z_V)), symmetric=True)
    T = cp.Variable((len(Z_T), len(Z_T)), symmetric=True)
    QD = cp.Variable((len(Z_D), len(Z_D)), symmetric=True)
    QE = cp.Variable((len(Z_E), len(Z_E)), symmetric=True)
    B = cp.Parameter(nonneg=True) if fixed else cp.Variable()
    lam = cp.Parameter(nonneg=True)
    k2 = cp.Parameter(nonneg=True)
    beta = cp.Parameter(nonneg=True)
    beta2 = cp.Parameter(nonneg=True)
    # coefficient of monomial m of -grad V . g - q dV/dy w is <C_m, Q_V>: tables built per solve
    C = {m: cp.Parameter((len(Z_V), len(Z_V))) for m in MONOS_D}
    cons = [QV - top_shift() >> ETA * np.eye(len(Z_V)), T >> ETA * np.eye(len(Z_T)),
            QD >> ETA * np.eye(len(Z_D)), QE >> ETA * np.eye(len(Z_E))]
    cons += dissipation_constraints(QD, QV, T, C, lam, k2, cp)
    cons += output_constraints(QE, QV, B, beta, beta2)
    params = {"lambda": lam, "k2": k2, "beta": beta, "beta2": beta2, **{_param_name(m): C[m] for m in MONOS_D}}
    variables = {"Q_V": QV, "T": T, "Q_D": QD, "Q_E": QE}
    if fixed:
        return cp.Problem(cp.Minimize(0), cons), {**params, "B": B}, variables
    return cp.Problem(cp.Minimize(B), cons), params, {**variables, "B": B}


#: the Gram matrices of a certificate: (variable name, basis)
GRAMS: Final = (("Q_V", Z_V), ("T", Z_T), ("Q_D", Z_D), ("Q_E", Z_E))


def build_parity_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """:func:`build_program` restricted to sign-symmetric certificates: every Gram matrix block
    diagonal, even monomials against even, odd against odd (DPP; compiled once).

    It loses nothing when the fields are odd and ``q`` even (:func:`~lyapcheck.paper.conditions.sos.is_sign_symmetric`,
    true of the derived ILOS dynamics; the argument is in :mod:`lyapcheck.paper.conditions.sos`, "sign
    symmetry"): every identity here, the S-procedure term ``tau (k^2 - w^2)`` and the output
    ``(y - beta r~)^2`` included, is invariant under ``(y, r~, w) -> -(y, r~, w)``. The solver
    reaches the full program's optimum (whose off-diagonal blocks come out at 1e-15; at the
    paper's gains B agrees to 8 digits) from PSD blocks of at most 12 x 12 instead of 19 x 19, in
    a quarter of the time. The exact check is the full one, on the full matrices (zero off the
    blocks).
    """
    return _build_parity(cp, fixed=False)


def build_parity_fixed_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """:func:`build_parity_program` at a given ``B`` (as :func:`build_fixed_program`)."""
    return _build_parity(cp, fixed=True)


def _build_parity(cp: Any, fixed: bool) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    cons: list[Any] = []
    variables: dict[str, Any] = {}
    QV, T, QD, QE = (positive_parity_gram(cp, basis, name, cons, variables) for name, basis in GRAMS)
    B = cp.Parameter(nonneg=True) if fixed else cp.Variable()
    lam = cp.Parameter(nonneg=True)
    k2 = cp.Parameter(nonneg=True)
    beta = cp.Parameter(nonneg=True)
    beta2 = cp.Parameter(nonneg=True)
    C = {m: cp.Parameter((len(Z_V), len(Z_V))) for m in EVEN_MONOS_D}
    cons += dissipation_constraints(QD, QV, T, C, lam, k2, cp, monomials=EVEN_MONOS_D)
    cons += even_output_constraints(QE, QV, B, beta, beta2)
    params = {"lambda": lam, "k2": k2, "beta": beta, "beta2": beta2, **{_param_name(m): C[m] for m in EVEN_MONOS_D}}
    if fixed:
        return cp.Problem(cp.Minimize(0), cons), {**params, "B": B}, variables
    return cp.Problem(cp.Minimize(B), cons), params, {**variables, "B": B}


def positive_parity_gram(cp: Any, basis: Sequence[poly.Monomial], name: str, cons: list[Any],
                         variables: dict[str, Any]) -> Any:
    """A Gram matrix block diagonal by parity (:func:`~lyapcheck.paper.conditions.sos.parity_gram`) with
    each block ``>= ETA I`` (``Q_V`` minus :func:`top_shift`) appended to ``cons`` and the block
    variables added to ``variables``; returns the full matrix expression. Shared with the box
    program (:mod:`lyapcheck.paper.boxes.bounds`)."""
    full, blocks = parity_gram(cp, basis, name)
    shift = top_shift() if name == "Q_V" else np.zeros((len(basis), len(basis)))
    for idx, X in zip(parity_blocks(basis), blocks.values()):
        cons.append(X - shift[np.ix_(idx, idx)] >> ETA * np.eye(len(idx)))
    variables.update(blocks)
    return full


def even_output_constraints(QE: Any, QV: Any, B: Any, beta: Any, beta2: Any) -> list[Any]:
    """:func:`output_constraints` of the even monomials (the others hold by symmetry)."""
    return [c for m, c in zip(poly.monomials(0, 4), output_constraints(QE, QV, B, beta, beta2)) if parity(m) == 0]


def dynamics_data(fields: tuple[poly.Poly, poly.Poly, poly.Poly], beta: Fraction) -> dict[str, Any]:
    """Parameter values for the dynamics: the scales and the tables ``C_m`` (floats)."""
    g_y, g_r, q = (poly.embed({m: float(c) for m, c in p.items()}, 3) for p in fields)
    n = len(Z_V)
    mats = {m: np.zeros((n, n)) for m in MONOS_D}
    for i in range(n):
        for j in range(n):
            zz = poly.embed(poly.monomial(tuple(a + b for a, b in zip(Z_V[i], Z_V[j]))), 3)
            flow = poly.add(poly.mul(poly.deriv(zz, 0), g_y), poly.mul(poly.deriv(zz, 1), g_r))
            push = poly.mul(poly.mul(q, poly.deriv(zz, 0)), {(0, 0, 1): 1.0})
            for m, c in poly.add(poly.scale(-1.0, flow), poly.scale(-1.0, push)).items():
                mats[m][i, j] += c
    return {"beta": float(beta), "beta2": float(beta * beta), **{_param_name(m): mats[m] for m in MONOS_D}}


def program(parity_reduced: bool = False, fixed: bool = False) -> CompiledProgram:
    """The compiled search: the full program or the sign-symmetric one (:func:`build_parity_program`),
    minimising ``B`` or, with ``fixed``, at a given ``B`` (:func:`build_fixed_program`)."""
    from lyapcheck.paper.conditions import compiled

    return compiled.load("sos_bound" + ("_parity" if parity_reduced else "") + ("_fixed" if fixed else ""))


def scales(dyn: ScaledDynamics) -> tuple[Fraction, Fraction]:
    """Rational ``beta = omega ~ sqrt(b)``: balances the ILOS oscillation (frequency ~ sqrt(b))."""
    root = exact.to_rational(float(np.sqrt(float(dyn.b))), 4) if dyn.b > 0 else Fraction(1)
    return max(root, Fraction(1)), max(root, Fraction(1))


def top_shifted(QV: exact.Matrix) -> exact.Matrix:
    """``Q_V - delta diag(0, 0, 0, 1, 1, 1)`` (exact): positive definite makes ``V`` radially unbounded."""
    return tuple(tuple(QV[i][j] - (TOP_DELTA if i == j and i in TOP else 0) for j in range(len(QV)))
                 for i in range(len(QV)))


def check(dyn: ScaledDynamics, k: Fraction, cert: dict[str, Any]) -> tuple[bool, str]:
    """Exact re-check of a bound certificate (see module docstring)."""
    QV, T, QD, QE = (exact.from_json(cert[key]) for key in ("Q_V", "T", "Q_D", "Q_E"))
    lam, B = Fraction(cert["lambda"]), Fraction(cert["B"])
    beta, omega = Fraction(cert["beta"]), Fraction(cert["omega"])
    if beta <= 0 or omega <= 0:
        return False, "scales must be positive"
    shifted = top_shifted(QV)
    if lam <= 0 or not all(is_positive_definite(m) for m in (shifted, T, QD, QE)):
        return False, "a Gram matrix or multiplier of the bound certificate is not positive definite"
    V = poly.gram_form(Z_V, QV)
    tau = poly.gram_form(Z_T, T)
    fields = balanced_fields(dyn, beta, omega)
    if dissipation(V, tau, fields, k / omega, lam) != poly.gram_form(Z_D, QD):
        return False, "the dissipation identity does not hold exactly"
    if output_form(V, B, beta) != poly.gram_form(Z_E, QE):
        return False, "the output identity does not hold exactly"
    return True, "ok"


#: one point of :data:`SEARCH_SCALES`: (``beta / sqrt(b)``, floor of ``kappa``, or None for ``kappa = 1``)
SearchScale = tuple[Fraction, float | None]


def coordinates_at(root: Fraction, k: Fraction, scale: SearchScale) -> tuple[Fraction, Fraction, Fraction]:
    """``(beta, omega, kappa)`` of one search scale (module docstring, "Conditioning") around the
    rational ``root ~ sqrt(b)``, for the disturbance scale ``k`` (the largest, over a box)."""
    factor, kappa_floor = scale
    if kappa_floor is None:
        return root * factor, root, Fraction(1)
    return root * factor, root, exact.to_rational(min(max(float(k / root), kappa_floor), 1.0), 6)


def search_coordinates(dyn: ScaledDynamics, k: Fraction, scale: SearchScale) -> tuple[Fraction, Fraction, Fraction]:
    """:func:`coordinates_at` around this point's ``sqrt(b)`` (:func:`scales`)."""
    return coordinates_at(scales(dyn)[0], k, scale)


def search_fields(fields: tuple[poly.Poly, poly.Poly, poly.Poly], kappa: Fraction) -> tuple[poly.Poly, poly.Poly, poly.Poly]:
    """The fields with ``w = kappa w~``: the push ``q (dV/dy) w`` is ``(kappa q) (dV/dy) w~`` (exact)."""
    g_y, g_r, q = fields
    return g_y, g_r, poly.scale(kappa, q)


def unscaled(Q: exact.Matrix, basis: list[poly.Monomial], kappa: Fraction, extra: int) -> exact.Matrix:
    """A Gram matrix over ``basis`` in ``w`` from one found in ``w~ = w / kappa``: entry ``(i, j)``
    divided by ``kappa^(d_i + d_j + extra)``, ``d`` the degree in ``w`` (exact)."""
    return tuple(tuple(Q[i][j] / kappa ** (basis[i][2] + basis[j][2] + extra) for j in range(len(basis)))
                 for i in range(len(basis)))


@dataclass(frozen=True)
class RoundedSolution:
    """A solver's solution rounded to exact matrices (search coordinates) whose identities hold."""

    lam: Fraction
    B: Fraction
    QV: exact.Matrix
    T: exact.Matrix
    QE: exact.Matrix
    QDs: tuple[exact.Matrix, ...]


def round_solution(v: Mapping[str, Any], QD_values: Sequence[Any], lam: float, beta: Fraction,
                   blocks: Sequence[tuple[tuple[poly.Poly, poly.Poly, poly.Poly], Fraction]],
                   bound: Fraction | None = None) -> RoundedSolution | None:
    """Round ``B`` up (or take ``bound``, the level a margin solve was given), ``Q_V`` and ``T`` to
    rationals, and project ``Q_E`` and each dissipation Gram
    matrix (one per block: its search fields and disturbance scale) onto its identity, exactly.

    None if an identity is not representable, or if the float screen shows a Gram matrix
    indefinite (the exact check would then fail; the unscaling to ``w`` is a congruence, which
    keeps definiteness). Shared by the point search and the box search (:mod:`lyapcheck.paper.boxes.bounds`).
    """
    lam_q = exact.to_rational(lam, 6)
    B = bound if bound is not None else exact.to_rational(float(v["B"]) * (1 + 1e-6) + 1e-9, 9)
    QV = exact.symmetrize(exact.rational_matrix(v["Q_V"]))
    T = exact.symmetrize(exact.rational_matrix(v["T"]))
    V, tau = poly.gram_form(Z_V, QV), poly.gram_form(Z_T, T)
    QE = project_gram(Z_E, exact.symmetrize(exact.rational_matrix(v["Q_E"])), output_form(V, B, beta))
    QDs = [project_gram(Z_D, exact.symmetrize(exact.rational_matrix(QD)), dissipation(V, tau, fields, k, lam_q))
           for QD, (fields, k) in zip(QD_values, blocks)]
    if QE is None or any(QD is None for QD in QDs):
        return None
    grams = tuple(QD for QD in QDs if QD is not None)
    if any(exact.surely_not_positive_definite(m) for m in (top_shifted(QV), T, QE, *grams)):
        return None
    return RoundedSolution(lam_q, B, QV, T, QE, grams)


def _certificate(dyn: ScaledDynamics, k: Fraction, v: Mapping[str, Any], lam: float,
                 coords: tuple[Fraction, Fraction, Fraction], bound: Fraction | None = None) -> dict[str, Any] | None:
    """Round a solution found in ``coords`` (at the level ``bound``, for a margin solve) to an
    exact certificate in ``w``; None unless it checks."""
    beta, omega, kappa = coords
    fields = search_fields(balanced_fields(dyn, beta, omega), kappa)
    r = round_solution(v, [v["Q_D"]], lam, beta, [(fields, k / omega / kappa)], bound)
    if r is None:
        return None
    cert = {"lambda": str(r.lam), "B": str(r.B), "beta": str(beta), "omega": str(omega),
            "Q_V": exact.to_json(r.QV), "T": exact.to_json(unscaled(r.T, Z_T, kappa, 2)),
            "Q_D": exact.to_json(unscaled(r.QDs[0], Z_D, kappa, 0)), "Q_E": exact.to_json(r.QE), "k_scaled": str(k)}
    return cert if check(dyn, k, cert)[0] else None


def run(system: System, search: tuple[SearchScale, ...] = SEARCH_SCALES,
        max_iter: int = tol.SOS_BOUND_MAX_ITER) -> dict[str, Any] | None:
    """Search and exactly check the bound; returns the best certificate (with ``eps_bound``) or None.

    For each decay rate of :data:`LAMBDA_GRID` the coordinates of ``search`` are tried in order
    until one gives a certificate, with the sign-symmetric program (:func:`build_parity_program`)
    when the field allows it. In each, the smallest ``B`` is solved for and its solution rounded
    and checked exactly. That solution lies where Gram matrices are singular, and where Clarabel
    stops short of the optimum ("inaccurate") whether it passes depends on where it stopped, so on
    the platform's last bits; when it fails, the Gram matrices are solved again at the level
    ``B1 (1 + BOUND_BACK_OFF)`` rounded up to :data:`BOUND_DIGITS` digits (:func:`build_fixed_program`:
    the solver then stops near the centre of that set), sign-symmetric and then full. The bound
    stated for a rate is that grid level whichever of the two passed (a certificate with a smaller
    ``B`` proves it too), so platforms that pass by different routes state the same bound; the
    result is the best over the rates (the first of equal ones). The first coordinates' solves run
    side by side in threads (Clarabel releases the GIL) while this thread checks the finished
    ones; every solve is independent of the others (no warm start), so the result does not depend
    on their timing.
    """
    from concurrent.futures import ThreadPoolExecutor

    from lyapcheck.paper.conditions.rounding import ceil_to_digits

    dyn = scaled_dynamics(system)
    if dyn is None or system.d_max <= 0:
        return None
    k = abs(system.E[0]) * system.d_max / (system.delta * dyn.time_scale)
    # the field's symmetry does not depend on the coordinates (scalings keep each monomial's parity)
    symmetric = is_sign_symmetric(dyn.fields())
    data: dict[SearchScale, tuple[tuple[Fraction, Fraction, Fraction], dict[str, Any]]] = {}

    def prepared(scale: SearchScale, reduced: bool, fixed: bool = False) -> tuple[tuple[Fraction, Fraction, Fraction],
                                                                                  dict[str, Any]]:
        if scale not in data:
            coords = search_coordinates(dyn, k, scale)
            beta, omega, kappa = coords
            data[scale] = coords, {**dynamics_data(search_fields(balanced_fields(dyn, beta, omega), kappa), beta),
                                   "k2": float((k / omega / kappa) ** 2)}
        coords, values = data[scale]
        if reduced:  # the odd monomials' tables belong to identities the reduced program leaves out
            params = program(parity_reduced=True, fixed=fixed).data.params
            values = {name: v for name, v in values.items() if name in params}
        return coords, values

    def solve(scale: SearchScale, lam: float) -> Any:
        return program(parity_reduced=symmetric).solve({**prepared(scale, symmetric)[1], "lambda": lam},
                                                       max_iter=max_iter)

    def rounded(values: Any, reduced: bool, lam: float, scale: SearchScale, bound: Fraction | None = None
                ) -> dict[str, Any] | None:
        full = assemble_parity_blocks(values, GRAMS) if reduced else values
        return _certificate(dyn, k, full, lam, prepared(scale, reduced)[0], bound)

    def at_level(scale: SearchScale, reduced: bool, lam: float, level: Fraction) -> dict[str, Any] | None:
        solved = program(parity_reduced=reduced, fixed=True).solve(
            {**prepared(scale, reduced, fixed=True)[1], "lambda": lam, "B": float(level)}, max_iter=max_iter)
        if solved.report.outcome not in ("optimal", "inaccurate") or solved.values is None:
            return None
        return rounded(solved.values, reduced, lam, scale, level)

    def attempt(solved: Any, scale: SearchScale, lam: float) -> tuple[Fraction, dict[str, Any]] | None:
        """(the bound stated at ``lam``, a certificate proving it) from a smallest-B solve, or None."""
        b = solved.report.objective
        # an inaccurate solution is still a candidate: the exact check is the judge
        if solved.report.outcome not in ("optimal", "inaccurate") or solved.values is None or b is None \
                or not (math.isfinite(b) and b > 0):
            return None
        level = ceil_to_digits(float(b) * (1 + BOUND_BACK_OFF), BOUND_DIGITS)
        cert = rounded(solved.values, symmetric, lam, scale)
        for reduced in ((True, False) if symmetric else (False,)):
            if cert is not None:
                break
            cert = at_level(scale, reduced, lam, level)
        return None if cert is None else (max(level, Fraction(cert["B"])), cert)

    for scale in search:
        prepared(scale, symmetric)  # once, before the threads use them
        prepared(scale, symmetric, fixed=True)
    found: dict[float, tuple[Fraction, dict[str, Any]]] = {}
    with ThreadPoolExecutor(max_workers=min(len(LAMBDA_GRID), os.cpu_count() or 1)) as pool:
        first = [pool.submit(solve, search[0], lam) for lam in LAMBDA_GRID]
        for lam, pending in zip(LAMBDA_GRID, first):
            result = attempt(pending.result(), search[0], lam)
            for scale in search[1:]:
                if result is not None:
                    break
                result = attempt(solve(scale, lam), scale, lam)
            if result is not None:
                found[lam] = result
    if not found:
        return None
    lam = min(found, key=lambda x: (found[x][0], LAMBDA_GRID.index(x)))
    level, cert = found[lam]
    return {**cert, "eps_bound": str(system.delta * exact.sqrt_upper(level))}


def run_class(system: System) -> "ConditionResult":
    """The ``sos_bound`` condition class (see module docstring)."""
    from lyapcheck.results import ConditionResult

    if system.d_max <= 0:
        return ConditionResult("sos_bound", "not_certified", "d* = 0: nothing to bound (see sos_gas for convergence)")
    cert = run(system)
    if cert is None:
        return ConditionResult("sos_bound", "not_certified",
                               "no polynomial dissipation certificate was found; this is not a proof that the bound fails")
    from lyapcheck.paper import claims

    bound = Fraction(cert["eps_bound"])
    return claims.decided(ConditionResult(
        "sos_bound", "certified", "",
        numbers={"eps_bound_m": float(bound), "eps_bound_exact": str(bound), "d_max_m_per_s": float(system.d_max)},
        certificate=cert))


def verify(system: System, cert: dict[str, Any]) -> tuple[bool, str]:
    dyn = scaled_dynamics(system)
    if dyn is None:
        return False, "the dynamics do not have the structure this stage needs"
    k = abs(system.E[0]) * system.d_max / (system.delta * dyn.time_scale)
    if Fraction(cert["k_scaled"]) != k:
        return False, "the stored disturbance scale does not match the system"
    ok, why = check(dyn, k, cert)
    if not ok:
        return False, why
    if Fraction(cert["eps_bound"]) < system.delta * exact.sqrt_upper(Fraction(cert["B"])):
        return False, "the stated eps bound is below Delta sqrt(B)"
    return True, "ok"

"""``sector_ges`` at sweep speed: a shorter rational certificate and a well-conditioned decay rate.

The program is :func:`lyapcheck.paper.conditions.sector.program`, compiled once and solved by Clarabel
directly (:mod:`lyapcheck.paper.conditions.compiled`; before issue 11 this module built that direct
path for itself, now every class has it). What stays here is the sweep's cheaper route to the
same verdict: the solver's ``P`` is rounded to :data:`RATIONAL_DIGITS` significant digits, and
the decay rate handed to the exact check is computed as a generalised eigenvalue problem in the
scaled coordinates (the condition ``A^T P + P A + 2 mu P < 0`` is invariant under the congruence
of :mod:`lyapcheck.paper.conditions.scaling`), which is well conditioned, so the first exact check
usually passes; :func:`lyapcheck.paper.conditions.sector.certify_polytope` bounds the rate through
eigenvalues in the original coordinates instead and may halve it many times.

Nothing about the verdict changes: :func:`lyapcheck.paper.conditions.sector.exact_check` decides every
``certified``; :func:`lyapcheck.paper.conditions.sector.refutation` decides every ``refuted``.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper.conditions import scaling, sector
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult

#: the rate handed to the exact check is this fraction of the floating-point optimum; halved
#: on failure at most this many times (as in sector.certify_polytope)
_RATE_BACKOFF: Final = 0.999
_RATE_HALVINGS: Final = 30
#: significant digits of the rounded certificate (see certify)
RATIONAL_DIGITS: Final = 10


def _rate_upper(a_scaled: Sequence[np.ndarray], P_scaled: np.ndarray, time_scale: float) -> float:
    """Largest ``mu`` with ``A_i^T P + P A_i + 2 mu P < 0`` at every vertex, in floating point.

    In the scaled coordinates (``A = T A~ T^-1 s``, ``P = T^-T P~ T^-1``) the condition reads
    ``s (A~^T P~ + P~ A~) + 2 mu P~ < 0``: ``mu = s lambda_min(Q~, P~) / 2`` with
    ``Q~ = -(A~^T P~ + P~ A~)``, the smaller root of ``det(Q~ - lambda P~) = 0`` (2x2, closed form,
    well conditioned). Only a candidate: the exact check decides.
    """
    p00, p01, p11 = float(P_scaled[0, 0]), float(P_scaled[0, 1]), float(P_scaled[1, 1])
    det_p = p00 * p11 - p01 * p01
    if not (p00 > 0 and det_p > 0):
        return -math.inf
    best = math.inf
    for a in a_scaled:
        q = -(a.T @ P_scaled + P_scaled @ a)
        q00, q01, q11 = float(q[0, 0]), 0.5 * float(q[0, 1] + q[1, 0]), float(q[1, 1])
        b = q00 * p11 + q11 * p00 - 2 * q01 * p01
        c = q00 * q11 - q01 * q01
        root = math.sqrt(max(b * b - 4 * det_p * c, 0.0))
        best = min(best, (b - root) / (2 * det_p) * time_scale / 2)
    return best


def certify(system: System, rho_lo: Fraction = Fraction(0)) -> ConditionResult:
    """``sector_ges`` for one point through the sweep's route (same statuses as ``sector.run``)."""
    vertices = [system.vertex(rho_lo), system.vertex(system.rho_sup)]
    sc = scaling.choose(vertices)
    scaled = [sc.matrix_to_scaled(v) for v in vertices]
    solved = sector.program().solve({"A_lo": scaled[0], "A_hi": scaled[1]})
    report, values = solved.report, solved.values
    optimal = report.outcome == "optimal" and values is not None
    margin = float(values["m"]) if optimal and values is not None else None
    numbers: dict[str, Any] = {"relative_margin": margin, "rho_interval": [str(rho_lo), str(system.rho_sup)]}
    if optimal and values is not None and margin is not None and margin > 0:
        # 10 significant digits (sector.certify_polytope keeps 15): the solver's P has a relative
        # margin far above 1e-10, and shorter rationals make the exact check cheaper
        P_tilde = exact.symmetrize(exact.rational_matrix(values["P"], RATIONAL_DIGITS))
        P = sc.p_from_scaled(P_tilde)
        mu = _rate_upper(scaled, np.array(exact.to_float(P_tilde)), float(sc.time))
        if math.isfinite(mu) and mu > 0:
            rate = exact.to_rational(mu * _RATE_BACKOFF, 6)
            for _ in range(_RATE_HALVINGS):
                ok, why = sector.exact_check(vertices, P, rate)  # also checks P > 0
                if ok:
                    return sector.certified_result(P, rate, rho_lo, why, numbers, report.to_json())
                rate /= 2
    return sector.uncertified_result(vertices, numbers, report.outcome, margin, report.to_json())

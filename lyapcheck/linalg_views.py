"""Linear-algebra views with python-control: the paper's own recipe, and poles.

* Poles of ``A`` (the vertex ``rho = 0``, the far field) and of the linearisation at the
  equilibrium ``A + rho_sup B`` (``rho(0) = rho_sup``), with exact Hurwitz checks.
* "Choose Gamma, solve for P": ``P`` from ``A^T P + P A = -Gamma`` with ``control.lyap`` for
  ``Gamma = I``, then the exact check of eq. ``eq:stabCond`` on that ``P`` (rounded to rationals).
  This is a cross-check of the SDP, not a certificate search: the SDP optimises over all ``P``.

python-control costs about two seconds to import, so these views are opt-in
(``certify --linear-views``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.conditions.base import System


def linear_views(system: System) -> dict[str, Any]:
    import control

    from lyapcheck.conditions import prop41

    out: dict[str, Any] = {}
    for label, mat in (("A", system.A), ("linearisation_at_0", system.vertex(system.rho_sup))):
        poles = control.ss(np.array(exact.to_float(mat)), np.zeros((2, 1)), np.eye(2), np.zeros((2, 1))).poles()
        out[label] = {"poles": [[float(p.real), float(p.imag)] for p in poles],
                      "hurwitz_exact": exact.is_hurwitz_2x2(mat)}
    A = np.array(exact.to_float(system.A))
    P = control.lyap(A.T, np.eye(2))  # solves A^T P + P A + I = 0
    residual = float(np.abs(A.T @ P + P @ A + np.eye(2)).max())
    P_q = exact.symmetrize(exact.rational_matrix(P))
    ok, why = prop41.exact_check(system, P_q, iss=False)
    out["lyap_gamma_identity"] = {"P": exact.to_json(P_q), "residual": residual,
                                  "satisfies_stabcond_exactly": ok, "detail": why}
    return out

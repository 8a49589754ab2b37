"""Linear-algebra views with python-control: the paper's own recipe, and poles.

* Poles of ``A`` (the vertex ``rho = 0``, the far field) and of the linearisation at the
  equilibrium ``A + rho_sup B`` (``rho(0) = rho_sup``), with exact Hurwitz checks.
* "Choose Gamma, solve for P": ``P`` from ``A^T P + P A = -Gamma`` with ``control.lyap`` for
  ``Gamma = I``, then the exact check of eq. ``eq:stabCond`` on that ``P`` (rounded to rationals).
  This is a cross-check of the SDP, not a certificate search: the SDP optimises over all ``P``.

The floating-point parts are views, not verdicts: at extreme (valid) scales a matrix entry can
lie beyond the double range, or the solver can lose every digit. Such a view then reads
``{"computed": false, "reason": "..."}`` instead of numbers, and the exact Hurwitz checks (on
rationals, at any scale) are still given. A computed view says ``"computed": true``.

python-control costs about two seconds to import, so these views are opt-in
(``certify --linear-views``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.paper.conditions.base import System
from lyapcheck.errors import LyapcheckError


class _NotComputed(LyapcheckError):
    """A floating-point view cannot be computed at this scale; the message says why."""


def _to_floats(mat: exact.Matrix, name: str) -> np.ndarray:
    """``mat`` as a float array, or :class:`_NotComputed` when an entry is beyond the double range."""
    try:
        return np.array(exact.to_float(mat), dtype=float)
    except OverflowError:
        # Fraction.__float__ raises rather than returning inf: the exact value is too large
        raise _NotComputed(f"{name} has an entry beyond the largest double (1.8e308); "
                           "not representable in floating point") from None


def _finite(values: np.ndarray, what: str) -> np.ndarray:
    if not np.all(np.isfinite(values)):
        raise _NotComputed(f"{what} is not finite in double precision at this scale")
    return values


def _not_computed(exc: Exception) -> dict[str, Any]:
    return {"computed": False, "reason": str(exc)}


def _poles_view(mat: exact.Matrix, name: str) -> dict[str, Any]:
    """Poles of ``mat`` with python-control, beside the exact Hurwitz check (valid at any scale)."""
    import control

    view: dict[str, Any]
    try:
        A = _to_floats(mat, name)
        # python-control / LAPACK may overflow inside eig at extreme scales: checked below
        with np.errstate(all="ignore"):
            poles = control.ss(A, np.zeros((2, 1)), np.eye(2), np.zeros((2, 1))).poles()
        _finite(np.asarray(poles), f"the poles of {name}")
        view = {"computed": True, "poles": [[float(p.real), float(p.imag)] for p in poles]}
    except _NotComputed as exc:
        view = _not_computed(exc)
    except (np.linalg.LinAlgError, ValueError, ArithmeticError) as exc:
        view = _not_computed(_NotComputed(f"python-control could not compute the poles of {name}: {exc}"))
    view["hurwitz_exact"] = exact.is_hurwitz_2x2(mat)
    return view


def _lyap_view(system: System) -> dict[str, Any]:
    """``P`` from ``A^T P + P A = -I`` (python-control), then the exact eq. ``eq:stabCond`` check."""
    import control

    from lyapcheck.paper.conditions import prop41

    try:
        A = _to_floats(system.A, "A")
        with np.errstate(all="ignore"):
            P = _finite(np.asarray(control.lyap(A.T, np.eye(2))), "P (control.lyap)")  # A^T P + P A + I = 0
            residual = float(_finite(np.abs(A.T @ P + P @ A + np.eye(2)), "the Lyapunov residual").max())
    except _NotComputed as exc:
        return _not_computed(exc)
    except (np.linalg.LinAlgError, ValueError, ArithmeticError) as exc:
        return _not_computed(_NotComputed(f"control.lyap failed: {exc}"))
    P_q = exact.symmetrize(exact.rational_matrix(P))
    ok, why = prop41.exact_check(system, P_q, iss=False)
    return {"computed": True, "P": exact.to_json(P_q), "residual": residual,
            "satisfies_stabcond_exactly": ok, "detail": why}


def linear_views(system: System) -> dict[str, Any]:
    """The python-control views of ``system`` (see the module docstring).

    Parameters
    ----------
    system
        The error dynamics at one gain set.

    Returns
    -------
    dict
        ``A`` and ``linearisation_at_0`` (poles and ``hurwitz_exact``) and ``lyap_gamma_identity``
        (``P``, ``residual``, the exact check). A view that floating point cannot give at this
        scale is ``{"computed": False, "reason": ...}`` (the exact Hurwitz check is still given).
    """
    return {"A": _poles_view(system.A, "A"),
            "linearisation_at_0": _poles_view(system.vertex(system.rho_sup), "A + rho_sup B"),
            "lyap_gamma_identity": _lyap_view(system)}

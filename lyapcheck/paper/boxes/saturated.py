"""The saturated real loop for every gain set of a box: global reach of the unsaturated set.

At one gain set (:func:`lyapcheck.paper.conditions.saturated.global_reach`, step 3 of that module's
docstring) the real loop, with the ODS law saturated at the step-out frequency and any
``|d_perp| <= d*``, enters ``K = {|eps + sigma0 s| <= Y_q, |s| <= S_1}`` in finite time and never
leaves it, when the rationals ``S_1``, ``Y_q`` satisfy

    S_1^2 > S*^2,   Delta <= Y_q,   Y_q^2 <= Y_sat^2,   gamma = |a11| Y_q - push(S_1, Y_q) > 0,

``push = |E_0| d* + sigma0 (damping(Y_q) S_1 + forcing(Y_q))`` (all from the derivation,
:mod:`symbolic.ilos`). Inside ``K`` the loop is unsaturated, so it is the error dynamics.

Over a box the same ``S_1`` and ``Y_q`` serve every gain set, because each quantity is monotone
in every parameter (``tests/test_box_saturated.py`` checks each sign on the derivation):

* ``S*^2 = Delta U^2 / (4 k_d (Delta k_d + U sigma0))`` increases with ``Delta`` and ``U`` and
  decreases with ``k_d`` and ``sigma0``; ``Y_sat^2 = (e11_hat Omega_SO / alpha_d)^2 - Delta^2``
  decreases with ``alpha_d`` and ``Delta``;
* ``|a11|`` is a monomial (the pull ``|a11| Y_q`` is smallest at a corner);
* ``push`` increases with ``sigma0``, ``k_d`` and ``U``, and with ``Delta`` while
  ``Delta <= Y_q`` (``Delta/(Y_q^2 + Delta^2)`` rises up to ``Delta = Y_q``), which the box's
  ``Delta_max <= Y_q`` guarantees.

A function monotone in each coordinate separately takes its extremes over a box at corners. So
with ``S_1^2 > max S*^2``, ``Delta_max <= Y_q``, ``Y_q^2 <= min Y_sat^2`` (all over corners) and
``min_corners |a11| Y_q - max_corners push > 0``, every gain set of the box satisfies its own
point conditions with these ``S_1``, ``Y_q``. Then whatever the box classes ``sos_gas`` and
``sos_bound`` prove for the error dynamics from ANY start holds for the real loop at every gain
set of the box (:func:`real_loop_bound` states the conjunction with ``sos_bound``).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Mapping

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.claims import OMEGA_ROUNDING, figure_text
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system


#: digits of the exact square roots, and the relative margin that keeps S_1 > S* and Y_q < Y_sat strict
ROOT_DIGITS = 12
SQRT_MARGIN = Fraction(1, 10**9)


def _float(x: Fraction) -> float | None:
    """``x`` as a double, or None beyond the double range (a box's corners can combine extreme
    gains into figures no double holds; the exact values stay in the certificate)."""
    try:
        return float(x)
    except OverflowError:
        return None


def _corner_data(problem: Problem, box: ParameterBox, dynamics: str) -> list[dict[str, Any]] | str:
    """Per corner: the system, its k_d, alpha_d and Y_sat^2; or why the class does not apply."""
    from symbolic._generated import unsaturated_strip_sq

    if dynamics != "derived":
        return "not applicable: the printed error dynamics are not the plant's (see ledger eq:los3)"
    omega = problem.actuation.omega_so
    if omega is None or problem.d_max is None:
        return "needs the step-out frequency and d* (--omega-so and --d-max, or the TOML keys)"
    rows = []
    for p in corner_problems(problem, box):
        system = build_system(p, dynamics)
        if not (system.A[1][0] == 0 and system.A[0][0] < 0):
            return "the dynamics at some corner do not have the structure this class needs"
        rows.append({"system": system, "k_d": p.gains.k_d,
                     "y_sat_sq": unsaturated_strip_sq(p.gains.alpha_d, system.delta, p.swimmer.e11_hat,
                                                      omega * (1 - OMEGA_ROUNDING))})
    return rows


def _windup_max(rows: list[dict[str, Any]]) -> Fraction:
    from symbolic._generated import windup_bound_sq

    return max(windup_bound_sq(r["system"].sigma0, r["k_d"], r["system"].delta, r["system"].speed) for r in rows)


def _margin(rows: list[dict[str, Any]], S1: Fraction, Yq: Fraction) -> tuple[Fraction, Fraction]:
    """``(min pull, max push)`` over the corners for the common ``S_1``, ``Y_q``."""
    from lyapcheck.paper.conditions.saturated import reach_push

    pull = min(-r["system"].A[0][0] * Yq for r in rows)
    push = max(reach_push(r["system"], r["k_d"], S1, Yq) for r in rows)
    return pull, push


def certify_saturated_box(problem: Problem, box: ParameterBox, dynamics: str = "derived") -> dict[str, Any]:
    """Global reach of the unsaturated set for every gain set of ``box`` (module docstring)."""
    rows = _corner_data(problem, box, dynamics)
    if isinstance(rows, str):
        status = "not_applicable" if rows.startswith(("needs", "not applicable")) else "not_certified"
        return {"status": status, "property": "invariant_set", "summary": rows}
    y_sat_sq = min(r["y_sat_sq"] for r in rows)
    delta_max = max(r["system"].delta for r in rows)
    if y_sat_sq < delta_max**2:
        return {"status": "not_certified", "property": "invariant_set", "box": box.to_json(),
                "summary": f"at some gain set of the box ({box.describe()}) the ODS law saturates inside |y| < Delta "
                           "(Omega_SO e11_hat <= alpha_d Delta sqrt(2)); this argument needs Y_sat >= Delta"}
    # exact square roots (the corners' values may lie beyond the double range): S_1 just above
    # sqrt(S*^2) and Y_q just below sqrt(Y_sat^2), since q / sqrt_upper(q) <= sqrt(q)
    s_star_sq = _windup_max(rows)
    S1 = exact.sqrt_upper(s_star_sq, ROOT_DIGITS) * (1 + SQRT_MARGIN)
    Yq = y_sat_sq / exact.sqrt_upper(y_sat_sq, ROOT_DIGITS) * (1 - SQRT_MARGIN)
    if Yq < delta_max:
        return {"status": "not_certified", "property": "invariant_set", "box": box.to_json(),
                "summary": f"at some gain set of the box ({box.describe()}) the ODS law saturates inside |y| < Delta "
                           "(Omega_SO e11_hat <= alpha_d Delta sqrt(2)); this argument needs Y_sat >= Delta"}
    pull, push = _margin(rows, S1, Yq)
    gamma = pull - push
    reach = {"S_star_sq_max": str(s_star_sq), "S_1": str(S1), "Y_q": str(Yq), "delta_max": str(delta_max),
             "pull_min": str(pull), "push_max": str(push), "gamma": str(gamma)}
    numbers = {"windup_bound_s_m": _float(S1), "reach_set_y_half_width_m": _float(Yq),
               "reach_margin_m_per_s": _float(gamma)}
    if gamma <= 0:
        return {"status": "not_certified", "property": "invariant_set", "box": box.to_json(), **numbers,
                "summary": f"global reach is not proved for the box ({box.describe()}): the weakest pull "
                           f"{figure_text(pull)} m/s does not beat the strongest push {figure_text(push)} m/s over its "
                           "corners (a smaller box may succeed; this is not a proof that reach fails)",
                "certificate": {"reach": reach}}
    return claims.decided_box("saturated_loop", {"status": "certified", "property": "invariant_set",
                                                 "box": box.to_json(), **numbers, "summary": "",
                                                 "certificate": {"reach": reach}}, box)


def verify_saturated_box(problem: Problem, box: ParameterBox, dynamics: str,
                         result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive the corner extremes from the box and re-check every inequality exactly (no solver)."""
    rows = _corner_data(problem, box, dynamics)
    if isinstance(rows, str):
        return False, rows
    reach = result["certificate"]["reach"]
    S1, Yq, gamma = Fraction(reach["S_1"]), Fraction(reach["Y_q"]), Fraction(reach["gamma"])
    if not S1 * S1 > _windup_max(rows):
        return False, "the wind-up bound S_1 is not above S* at every corner"
    if not (max(r["system"].delta for r in rows) <= Yq and Yq * Yq <= min(r["y_sat_sq"] for r in rows)):
        return False, "Y_q is not between Delta_max and the narrowest strip's half-width"
    pull, push = _margin(rows, S1, Yq)
    if gamma != pull - push or gamma <= 0:
        return False, "the stated reach margin does not follow from the box, or is not positive"
    stated = result.get("reach_margin_m_per_s")
    if stated is not None and not Fraction(stated) <= gamma * (1 + Fraction(1, 10**12)):
        return False, "the stated reach margin exceeds the certified one"
    for key, proved in (("windup_bound_s_m", S1), ("reach_set_y_half_width_m", Yq)):  # bounds: not smaller
        if result.get(key) is not None and not Fraction(result[key]) >= proved * (1 - Fraction(1, 10**12)):
            return False, f"the stated {key} is below the certificate's"
    return True, f"global reach re-checked over the box's corners: margin {figure_text(gamma)} m/s"


def real_loop_bound(results: dict[str, dict[str, Any]]) -> None:
    """With reach over the box and a certified ``sos_bound`` box, the real loop's ``limsup |eps|`` at
    every gain set of the box is at most the bound (their conjunction; both are re-checked by verify)."""
    sat, bound = results.get("saturated_loop"), results.get("sos_bound")
    if sat is None or bound is None or sat["status"] != "certified" or bound["status"] != "certified":
        return
    sat["real_loop_limsup_eps_m"] = bound["eps_bound_m"]
    sat["summary"] += claims.real_loop_clause(bound["eps_bound_m"], box=True)

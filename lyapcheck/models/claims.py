"""The sentence each decided class of a model file prints, made from its checked figures alone.

A certificate's ``summary`` is what a reader believes, so it must never say more than the figures
beside it, which ``verify`` re-checks against the exact certificate. This module is the one place
that writes those sentences: :func:`lyapcheck.models.certify.certify_model` sets each ``certified``
or ``refuted`` condition's summary with :func:`summary`, and
:func:`lyapcheck.models.certificate.verify_document` regenerates it from the figures it has just
re-checked and fails where the file's text differs (an edited summary, ``limsup |y| <= 0.1`` where
0.52 was proved, is caught there). Reports print the regenerated text.

The disturbances (DESIGN.md, "Disturbances in claims"): a claim proved with every disturbance
held at 0 says ``(d = 0)``; a stability claim proved for every disturbance signal within its bounds
says so. ``not_certified``, ``inconclusive`` and ``not_applicable`` conditions claim nothing; their
text is a reason, not a summary of figures, and is left as the class wrote it.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Mapping, Sequence

#: what a ``certified`` sublevel set of each class is called in its sentence
SET_NAMES = {"roa": "region of attraction", "candidate": "the user's V"}
#: the prefix of a claim by the disturbances it covers (a stability class of a disturbed model)
DISTURBANCE_PREFIX = {"zero": "(d = 0) ", "all": "for every disturbance signal within its bounds: "}
#: said of a nominal claim whose robust form was tried and not found
ROBUST_NOT_FOUND = "; with the declared disturbances acting, no certificate of this class was found"
#: what a certified ``barrier`` states (:mod:`lyapcheck.models.barrier`)
BARRIER_SENTENCE = ("safety: no trajectory that starts in the initial set ever enters the unsafe set (B <= 0 on the "
                    "initial set, B >= 1 on the unsafe set, B' <= lambda B everywhere; checked exactly)")


def covered(coverage: str | None, text: str) -> str:
    """A claim's sentence with the disturbances it covers in front (``(d = 0) ...``), as for a
    loop with functions, which is certified with its disturbances at 0."""
    return DISTURBANCE_PREFIX.get(coverage, "") + text if coverage is not None else text


def summary(name: str, condition: Mapping[str, Any], outputs: Sequence[str] = (),
            box: Mapping[str, Sequence[Any]] | None = None) -> str | None:
    """The sentence of a ``certified`` or ``refuted`` condition (its JSON form), or None for the
    other statuses. ``outputs``: the model's output names (``sos_bound`` names those it did not
    bound); ``box``: the document's box of parameters (``{"mu": ["4/5", "6/5"]}``), which a claim
    over it names first. Raises KeyError, TypeError or ValueError on figures of the wrong form
    (verify reports them as a failed check)."""
    status = condition.get("status")
    if status not in ("certified", "refuted"):
        return None
    if name == "linearization":
        text = _linearization(status, condition)
    elif status != "certified":
        return None
    elif name == "sos_bound":
        text = _bounds(condition, outputs)
    elif name == "barrier":
        text = BARRIER_SENTENCE
    elif name == "reach_avoid":
        text = (f"reach-avoid: every trajectory that starts in the initial set reaches the goal within "
                f"{_number(condition, 'reach_time_bound_s'):.4g} s without entering the unsafe set before (V <= 0 on "
                "the initial set, V >= 1 on the unsafe set, V' <= -eps outside the goal, V bounded below; checked "
                "exactly)")
        if "stay" in (condition.get("certificate") or {}):
            text += ("; and it stays in the goal afterwards (it reaches {W <= 0}, a set inside the goal that no "
                     "trajectory leaves: W' <= mu W; checked exactly)")
    else:
        text = _stability(name, condition)
    disturbances = condition.get("disturbances")
    if name != "sos_bound" and disturbances is not None:
        text = DISTURBANCE_PREFIX[disturbances] + text
    if "robust_attempt" in condition:
        text += ROBUST_NOT_FOUND
    if box:
        text = f"for every {box_words(box)}: {text}"
    return text


def box_words(box: Mapping[str, Sequence[Any]]) -> str:
    """``mu in [0.8, 1.2] and k in [1, 2]``: a box of parameters (exact bounds as in a certificate's
    ``box``) as a reader reads it (:meth:`~lyapcheck.models.parameter_box.ModelBox.describe`)."""
    from lyapcheck.models.parameter_box import ModelBox

    return ModelBox.from_json({name: [str(lo), str(hi)] for name, (lo, hi) in box.items()}).describe(" and ")


def _number(condition: Mapping[str, Any], key: str) -> float:
    value = condition[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"figure '{key}' must be a number, got {value!r}")
    return float(value)


def _linearization(status: str, condition: Mapping[str, Any]) -> str:
    data = condition.get("certificate" if status == "certified" else "refutation") or {}
    method = data.get("method")
    if status == "certified" and method == "lyapunov_equation":
        return ("the Jacobian at the equilibrium is Hurwitz (J^T P + P J = -I with P > 0, exact): locally "
                "exponentially stable")
    if status == "certified" and method == "routh_hurwitz":
        return "the Jacobian is Hurwitz (every Hurwitz determinant > 0, exact): locally exponentially stable"
    if status == "refuted" and method == "lyapunov_inertia":
        return ("the Jacobian has an eigenvalue with positive real part (J^T P + P J = -I with P not positive "
                "definite, exact; inertia theorem): the equilibrium is unstable")
    if status == "refuted" and method == "root_isolation":
        return (f"the Jacobian has an eigenvalue with positive real part (rigorous enclosure {data['root']}): the "
                "equilibrium is unstable")
    raise ValueError(f"unknown linearization method {method!r} for status {status!r}")


def _stability(name: str, condition: Mapping[str, Any]) -> str:
    cert = condition.get("certificate") or {}
    kind = cert.get("kind")
    if kind in ("sublevel", "quadratic_ball"):
        what = SET_NAMES.get(name, name)
        level = _number(condition, "level")
        ball = (f"; it holds the ball |x - x_eq| <= {_number(condition, 'ball_radius'):.4g}"
                if "ball_radius" in condition else "")
        return f"{what}: every start in {{V <= {level:.6g}}} converges to the equilibrium (checked exactly){ball}"
    if kind != "lyapunov":
        raise ValueError(f"unknown certificate kind {kind!r}")
    if condition.get("property") == "GES":
        return (f"GES: |x(t)| <= {_number(condition, 'k'):.4g} |x0| exp(-{_number(condition, 'decay_rate_per_s'):.4g} "
                "t) from every start (a quadratic V with V' <= -mu V, checked exactly)")
    rate = _number(condition, "decay_rate_V_per_s")
    if name == "candidate":
        tail = f", V' <= -{rate:.4g} V" if rate > 0 else ""
        return f"GAS: V' < 0 away from the equilibrium everywhere{tail} (checked exactly)"
    degree = condition["degree"]
    if isinstance(degree, bool) or not isinstance(degree, int):
        raise TypeError(f"figure 'degree' must be an integer, got {degree!r}")
    tail = f", and V' <= -{rate:.4g} V (V decays exponentially from every start)" if rate > 0 else ""
    what = "a quadratic V" if degree == 2 else f"a polynomial V of degree {degree}"
    return f"GAS: {what} with V' < 0 away from the equilibrium{tail} (checked exactly)"


def _bounds(condition: Mapping[str, Any], outputs: Sequence[str]) -> str:
    bounds = condition["bounds"]
    if not isinstance(bounds, dict):
        raise TypeError("figure 'bounds' must be a table of outputs")
    text = ", ".join(f"limsup |{k}| <= {_number(bounds, k):.4g}" for k in bounds)
    out = f"for every disturbance within its bounds and every start: {text} (checked exactly)"
    missing = [k for k in outputs if k not in bounds]
    if missing:
        out += f"; no bound for {', '.join(missing)}"
    return out


# -- V as a reader sees it ------------------------------------------------------------------------

#: significant digits of a coefficient in ``V_text`` and in the table's short form of V
V_DIGITS = 6
#: the table's short form of V shows this many terms, then how many more there are
V_SHORT_TERMS = 6


def v_text(terms: Mapping[str, Any], variables: Sequence[str], shifts: Mapping[str, Any] | None = None,
           limit: int | None = None) -> str:
    """``V`` (the contract's exact ``{"terms": [[coefficient, [exponents]], ...]}``, in ``z = x -
    x_eq``) as a readable polynomial in the declared names: coefficients to :data:`V_DIGITS`
    significant digits, each state with a non-zero equilibrium value written ``(x1 - 1.5)``; with
    ``limit``, only the first terms (by degree) and how many more. The exact V is ``terms``."""

    shifts = shifts or {}
    rows = []
    for coefficient, exponents in terms["terms"]:
        if len(exponents) != len(variables):
            raise ValueError(f"V: a term has {len(exponents)} exponents for {len(variables)} variables")
        rows.append((Fraction(coefficient), exponents))
    parts = []
    for k, (c, exponents) in enumerate(rows):
        if limit is not None and k == limit and len(rows) > limit + 1:  # one term more is shown, not counted
            parts.append(f"+ ... ({len(rows) - limit} more terms)")
            break
        factors = []
        for name, e in zip(variables, exponents):
            if e == 0:
                continue
            shift = Fraction(str(shifts.get(name, 0)))
            base = name if shift == 0 else f"({name} {'-' if shift > 0 else '+'} {float(abs(shift)):.{V_DIGITS}g})"
            factors.append(base if e == 1 else f"{base}**{e}")
        magnitude = f"{float(abs(c)):.{V_DIGITS}g}"
        body = "*".join(factors) if magnitude == "1" and factors else "*".join([magnitude] + factors)
        sign = "-" if c < 0 else "+"
        parts.append(body if not parts and sign == "+" else f"{sign} {body}" if parts else f"-{body}")
    return " ".join(parts) if parts else "0"


def v_expression(terms: Mapping[str, Any], variables: Sequence[str], shifts: Mapping[str, Any] | None = None) -> Any:
    """``V`` exactly, as a sympy expression in the declared names (``x - x_eq`` where the
    equilibrium is not 0); the numbers are the certificate's rationals."""
    import sympy as sp

    shifts = shifts or {}
    def rational(value: Any) -> Any:  # through Fraction's own reader: no text reaches sympy's parser
        exact = Fraction(str(value))
        return sp.Rational(exact.numerator, exact.denominator)

    symbols = [sp.Symbol(name) - rational(shifts.get(name, 0)) for name in variables]
    total = sp.Integer(0)
    for coefficient, exponents in terms["terms"]:
        term = rational(coefficient)
        for base, e in zip(symbols, exponents):
            term *= base ** int(e)
        total += term
    return total


__all__ = ["summary", "box_words", "v_text", "v_expression", "SET_NAMES", "DISTURBANCE_PREFIX"]

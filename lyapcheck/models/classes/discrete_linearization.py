"""``linearization`` of a discrete-time map: the spectral radius of its Jacobian, decided exactly (LES).

``A`` is the Jacobian of the shifted map ``e+ = f(x_eq + e) - x_eq`` at 0 (exact rationals:
:func:`lyapcheck.models.classes.linearization.jacobian` of
:func:`lyapcheck.models.loop.discrete.shifted_map`). Then, in this order:

1. **Stein (discrete Lyapunov) equation** ``A^T P A - P = -I``, solved exactly (FLINT). ``P > 0``
   (exact) proves every eigenvalue of ``A`` of modulus < 1, so the fixed point is locally exponentially
   stable (``certified``). A solution ``P`` that is not positive definite proves an eigenvalue of modulus
   > 1 (``refuted``): with ``V = e^T P e``, ``V(A e) - V(e) = -|e|^2``, so from an ``e`` with
   ``V(e) <= 0`` (or ``V(Ae) < 0`` on P's kernel) ``V`` decreases geometrically to minus infinity along the
   iterates and they grow without bound.
2. When the equation is singular (``lambda_i lambda_j = 1`` for some eigenvalues: one on the unit circle, or
   a pair ``lambda, 1/lambda``), the characteristic polynomial ``p(z)`` decides through its bilinear
   (Cayley) transform ``q(s) = (1 - s)^n p((1 + s)/(1 - s))``, which maps the open unit disc onto the open
   left half-plane and, when ``p(-1) != 0``, keeps the degree: every Hurwitz determinant of ``q`` > 0
   (exact) certifies; a rigorous root enclosure of ``q`` with real part > 0 is an eigenvalue of modulus
   > 1 and refutes; a root of ``q`` on the imaginary axis (exact) is an eigenvalue on the unit circle, and
   ``p(-1) = 0`` is the eigenvalue -1: critical, ``not_certified`` (after ``p``'s other roots are tried
   for modulus > 1), as the continuous-time critical case.

Every certificate and refutation carries ``"time": "discrete"``: verify re-derives it with this test
only on a map, and a continuous-time one never verifies against a map (nor this one against a field).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.models.classes.linearization import (Matrix, _fmpq_mat, characteristic_polynomial,
                                                    hurwitz_determinants, imaginary_axis_roots, jacobian,
                                                    right_half_plane_root)
from lyapcheck.models.loop.field import ShiftedField
from lyapcheck.results import ConditionResult
from lyapcheck.sos.definiteness import is_positive_definite
from lyapcheck.sos.polynomials import to_fraction

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox

#: the key and value every discrete-time linearization certificate carries
TIME_KEY: Final = "time"
TIME_VALUE: Final = "discrete"

CERTIFIED_STEIN: Final = ("every eigenvalue of the map's Jacobian at the fixed point has modulus < 1 (A^T P A - P = -I "
                          "with P > 0, exact): the discrete-time map is locally exponentially stable there")
CERTIFIED_CAYLEY: Final = ("every eigenvalue of the map's Jacobian at the fixed point has modulus < 1 (its "
                           "characteristic polynomial's bilinear transform is Hurwitz: every Hurwitz determinant > 0, "
                           "exact): the discrete-time map is locally exponentially stable there")
REFUTED_STEIN: Final = ("the map's Jacobian at the fixed point has an eigenvalue of modulus > 1 (A^T P A - P = -I with P "
                        "not positive definite, exact): the discrete-time map's fixed point is unstable")


def refuted_root(root: str) -> str:
    """The sentence of a refutation by a root enclosure of the bilinear transform."""
    return (f"the map's Jacobian at the fixed point has an eigenvalue of modulus > 1 (its bilinear transform s = "
            f"(z - 1)/(z + 1) has the rigorous enclosure {root}, real part > 0): the discrete-time map's fixed "
            "point is unstable")


def stein_solution(A: Matrix) -> Matrix | None:
    """The exact ``P = P^T`` with ``A^T P A - P = -I``, or None when that is singular."""
    n = len(A)
    pairs = [(i, j) for i in range(n) for j in range(i, n)]
    index = {p: k for k, p in enumerate(pairs)}
    rows, rhs = [], []
    for a in range(n):
        for b in range(a, n):
            # (A^T P A - P)_{ab} = sum_{k,l} A_ka P_kl A_lb - P_ab
            row = [Fraction(0)] * len(pairs)
            for k in range(n):
                if A[k][a] == 0:
                    continue
                for m in range(n):
                    if A[m][b] != 0:
                        row[index[(min(k, m), max(k, m))]] += A[k][a] * A[m][b]
            row[index[(a, b)]] -= 1
            rows.append(row)
            rhs.append([Fraction(-1 if a == b else 0)])
    try:
        x = _fmpq_mat(rows).solve(_fmpq_mat(rhs))
    except (ZeroDivisionError, ValueError):
        return None
    P = [[Fraction(0)] * n for _ in range(n)]
    for (i, j), k in index.items():
        P[i][j] = P[j][i] = to_fraction(x[k, 0])
    return P


def stein_residual_ok(A: Matrix, P: Matrix) -> bool:
    """``A^T P A - P = -I`` exactly (and ``P`` symmetric, of ``A``'s size)."""
    n = len(A)
    if len(P) != n or any(len(row) != n for row in P) or any(P[i][j] != P[j][i] for i in range(n) for j in range(n)):
        return False
    PA = [[sum((P[k][m] * A[m][b] for m in range(n)), Fraction(0)) for b in range(n)] for k in range(n)]
    return all(sum((A[k][a] * PA[k][b] for k in range(n)), Fraction(0)) - P[a][b] == (-1 if a == b else 0)
               for a in range(n) for b in range(n))


def _poly_mul(a: Sequence[Fraction], b: Sequence[Fraction]) -> list[Fraction]:
    out = [Fraction(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return out


def cayley(p: Sequence[Fraction]) -> list[Fraction]:
    """``q(s) = (1 - s)^n p((1 + s)/(1 - s))`` for ``p`` of degree ``n`` (lowest degree first, exact)."""
    n = len(p) - 1
    q = [Fraction(0)] * (n + 1)
    for k, c in enumerate(p):
        term = [Fraction(1)]
        for _ in range(k):
            term = _poly_mul(term, [Fraction(1), Fraction(1)])
        for _ in range(n - k):
            term = _poly_mul(term, [Fraction(1), Fraction(-1)])
        for i, t in enumerate(term):
            q[i] += c * t
    return q


def _monic(q: Sequence[Fraction]) -> list[Fraction]:
    while len(q) > 1 and q[-1] == 0:
        q = q[:-1]
    return [c / q[-1] for c in q]


def _without_minus_one(p: Sequence[Fraction]) -> list[Fraction]:
    """``p`` divided by ``(z + 1)`` as often as it divides (exact)."""
    p = list(p)
    while len(p) > 1 and sum(c * (-1) ** k for k, c in enumerate(p)) == 0:
        # p = (z + 1) b: p_n = b_(n-1) and p_k = b_(k-1) + b_k, from the top down
        n = len(p) - 1
        b = [Fraction(0)] * (n + 1)
        for k in range(n, 0, -1):
            b[k - 1] = p[k] - b[k]
        p = b[:n]
    return p


def run(shifted: ShiftedField) -> ConditionResult:
    """Decide the map's linearization (see the module docstring); ``shifted`` is the shifted map."""
    return decide(jacobian(shifted))


def decide(A: Matrix) -> ConditionResult:
    """Decide whether every eigenvalue of the exact ``A`` has modulus < 1, one has modulus > 1, or neither."""
    n = len(A)
    cert: dict[str, Any] = {TIME_KEY: TIME_VALUE, "jacobian": [[str(x) for x in row] for row in A]}
    numbers: dict[str, Any] = {}
    try:
        import numpy as np

        numbers["spectral_radius_estimate"] = float(np.max(np.abs(np.linalg.eigvals(
            np.array([[float(x) for x in row] for row in A])))))
    except (ValueError, OverflowError, ArithmeticError):
        pass
    P = stein_solution(A)
    if P is not None:
        cert["P"] = [[str(x) for x in row] for row in P]
        if is_positive_definite(P):
            cert["method"] = "stein_equation"
            return ConditionResult("linearization", "certified", CERTIFIED_STEIN, numbers=numbers, certificate=cert)
        cert["method"] = "stein_unbounded"
        return ConditionResult("linearization", "refuted", REFUTED_STEIN, numbers=numbers, refutation=cert)
    p = characteristic_polynomial(A)
    cert["characteristic_polynomial"] = [str(c) for c in p]
    rest = _without_minus_one(p)
    q = _monic(cayley(rest))
    if len(rest) == len(p) and all(h > 0 for h in hurwitz_determinants(q)):
        cert["method"] = "cayley_hurwitz"
        return ConditionResult("linearization", "certified", CERTIFIED_CAYLEY, numbers=numbers, certificate=cert)
    root = right_half_plane_root(q) if len(q) > 1 else None
    if root is not None:
        cert["method"] = "cayley_root_isolation"
        cert["root"] = root
        return ConditionResult("linearization", "refuted", refuted_root(root), numbers=numbers, refutation=cert)
    from lyapcheck.models.engines import reasons

    if len(rest) < len(p) or (len(q) > 1 and imaginary_axis_roots(q)):
        where = "-1" if len(rest) < len(p) else "on the unit circle"
        why = reasons.reason(f"critical case: the map's Jacobian has an eigenvalue {where} (exact) and none of modulus "
                             "> 1, so the linearization decides nothing", ())
        return ConditionResult("linearization", "not_certified", why.summary,
                               numbers=why.numbers({**numbers, "reason": "critical"}), certificate=cert)
    why = reasons.reason(f"the eigenvalues of the {n}x{n} Jacobian of the map could not be located exactly",
                         (), "no root enclosure was conclusive")
    return ConditionResult("linearization", "inconclusive", why.summary, numbers=why.numbers(numbers))


# -- over a box of parameters: an unstable corner (or centre) refutes the box's claim ------------------------

#: the method of a map's refutation over a box: a value of the box (a corner or the centre) whose Jacobian is
#: proved unstable by :func:`decide` (the same word as the continuous loops' box refutation)
BOX_POINT_METHOD: Final = "box_point"


#: the method of a map with functions' refutation at a value of a box (its ``at_point``): Routh's first column of
#: the bilinear transform of the ball Jacobian's characteristic polynomial changes sign
#: (:func:`lyapcheck.models.classes.discrete_functions_box.unstable_at`)
BALL_ROUTH_METHOD: Final = "ball_cayley_routh"
REFUTED_BALL_ROUTH: Final = ("the map's Jacobian at the fixed point has an eigenvalue of modulus > 1 (Routh's array of "
                             "its characteristic polynomial's bilinear transform changes sign, in ball arithmetic): "
                             "the discrete-time map's fixed point is unstable")


def box_points(box: "ModelBox") -> list[dict[str, Fraction]]:
    """The values of ``box`` decided one by one: its corners (where a gain is most extreme: an unstable value
    of a box is most often at one), then its centre."""
    return [*box.corners(), {name: box.center(name) for name in box.names}]


def box_point_sentence(point: dict[str, Fraction], at: str) -> str:
    """The claim of a refutation at ``point`` of the box (``at``: the point decision's sentence)."""
    from lyapcheck.models.classes.linearization import lower_first, point_words

    return f"at {point_words(point)}, a value of the box, {lower_first(at)}"


def refute_over_box(jacobian_at: Callable[[dict[str, Fraction]], Matrix], box: "ModelBox") -> ConditionResult | None:
    """``refuted`` for the whole box when the exact Jacobian at one of :func:`box_points` (``jacobian_at``
    of a parameter point) has an eigenvalue of modulus > 1 (:func:`decide`: one value of the box where the
    fixed point is unstable makes a claim for every value false), naming that value; None when none is
    (a corner or centre that is stable or critical proves nothing about the rest of the box)."""
    for point in box_points(box):
        at = decide(jacobian_at(point))
        if at.status == "refuted":
            data = {TIME_KEY: TIME_VALUE, "method": BOX_POINT_METHOD, "point": {k: str(v) for k, v in point.items()},
                    "at_point": at.refutation}
            return ConditionResult("linearization", "refuted", box_point_sentence(point, at.summary),
                                   numbers=at.numbers, refutation=data)
    return None


def stated_box_point(data: Mapping[str, Any], box: "ModelBox") -> dict[str, Fraction] | str:
    """The value of the box a refutation states (its ``point``: every parameter named, each exact and within
    its interval), or why it is not one: what every map's refutation at a value of a box is re-checked from."""
    try:
        point = {str(k): Fraction(v) for k, v in (data.get("point") or {}).items()}
    except (TypeError, ValueError, ZeroDivisionError) as exc:
        return f"malformed point: {exc}"
    if set(point) != set(box.names):
        return "the stated point does not name every parameter of the box"
    for name, value in point.items():
        lo, hi = box.interval(name)
        if not lo <= value <= hi:
            return f"the stated {name} = {value} is not in the box [{lo}, {hi}]"
    return point


def verify_box_point(jacobian_at: Callable[[dict[str, Fraction]], Matrix], box: "ModelBox", data: dict[str, Any]
                     ) -> tuple[bool, str]:
    """Re-check a refutation of :func:`refute_over_box`: the stated point in the box (every parameter named,
    exact bounds) and the point refutation again on the Jacobian the map gives there."""
    if not is_discrete_certificate(data) or data.get("method") != BOX_POINT_METHOD:
        return False, f"not a map's refutation at a value of the box (method {data.get('method')!r})"
    point = stated_box_point(data, box)
    if isinstance(point, str):
        return False, point
    at = data.get("at_point")
    if not isinstance(at, dict):
        return False, "the refutation at the point is missing"
    ok, why = verify_matrix(jacobian_at(point), "refuted", at)
    return (True, f"at a value of the box: {why}") if ok else (False, f"at the stated point: {why}")


def is_discrete_certificate(data: Any) -> bool:
    """A linearization certificate or refutation of a map (it says ``"time": "discrete"``)."""
    return isinstance(data, dict) and data.get(TIME_KEY) == TIME_VALUE


def verify(shifted: ShiftedField, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a map's ``linearization`` certificate or refutation exactly against the shifted map."""
    return verify_matrix(jacobian(shifted), status, data)


def verify_matrix(A: Matrix, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a map's ``linearization`` certificate or refutation of the exact Jacobian ``A``."""
    if not is_discrete_certificate(data):
        return False, 'the certificate is not a discrete-time one ("time": "discrete"), and the model is a map'
    if data.get("jacobian") != [[str(x) for x in row] for row in A]:
        return False, "the stored Jacobian differs from the map's"
    method = data.get("method")
    if method in ("stein_equation", "stein_unbounded"):
        P = [[Fraction(x) for x in row] for row in data["P"]]
        if not stein_residual_ok(A, P):
            return False, "A^T P A - P = -I does not hold exactly"
        if status == "certified" and method == "stein_equation":
            return (True, "A^T P A - P = -I with P > 0, exactly") if is_positive_definite(P) else \
                (False, "P is not positive definite")
        if status == "refuted" and method == "stein_unbounded":
            return (True, "A^T P A - P = -I with P not positive definite, exactly") if not is_positive_definite(P) \
                else (False, "P is positive definite: every eigenvalue has modulus < 1")
    p = characteristic_polynomial(A)
    rest = _without_minus_one(p)
    q = _monic(cayley(rest))
    if method == "cayley_hurwitz" and status == "certified":
        return (True, "the bilinear transform's Hurwitz determinants are all > 0, exactly") \
            if len(rest) == len(p) and all(h > 0 for h in hurwitz_determinants(q)) else \
            (False, "a Hurwitz determinant of the bilinear transform is not > 0")
    if method == "cayley_root_isolation" and status == "refuted":
        return (True, "a rigorous root enclosure of the bilinear transform with real part > 0") \
            if len(q) > 1 and right_half_plane_root(q) else (False, "no root enclosure with real part > 0")
    return False, f"unknown method {method!r} for status {status!r}"


def sentence(status: str, data: dict[str, Any]) -> str:
    """The claim of a decided map linearization (its certificate's or refutation's ``method``)."""
    method = data.get("method")
    if status == "certified" and method == "stein_equation":
        return CERTIFIED_STEIN
    if status == "certified" and method == "cayley_hurwitz":
        return CERTIFIED_CAYLEY
    if status == "refuted" and method == "stein_unbounded":
        return REFUTED_STEIN
    if status == "refuted" and method == "cayley_root_isolation":
        return refuted_root(str(data["root"]))
    if status == "refuted" and method == BALL_ROUTH_METHOD:  # a map with functions' value of a box, in balls
        return REFUTED_BALL_ROUTH
    if status == "refuted" and method == BOX_POINT_METHOD:  # over a box: the value, then the point's own words
        point = {str(k): Fraction(v) for k, v in data["point"].items()}
        return box_point_sentence(point, sentence("refuted", data["at_point"]))
    raise ValueError(f"unknown discrete-time linearization method {method!r} for status {status!r}")


__all__ = ["stein_solution", "stein_residual_ok", "cayley", "run", "decide", "verify", "verify_matrix", "sentence",
           "is_discrete_certificate", "TIME_KEY", "TIME_VALUE", "BOX_POINT_METHOD", "box_points", "box_point_sentence",
           "refute_over_box", "verify_box_point", "BALL_ROUTH_METHOD", "REFUTED_BALL_ROUTH"]

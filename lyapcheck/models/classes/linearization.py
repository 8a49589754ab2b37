"""``linearization``: the Jacobian at the equilibrium, decided exactly (property LES).

``J = d(N_i / D_i)/dz_j`` at ``z = 0`` with the disturbances 0; since ``N_i(0) = 0`` it is
``(dN_i/dz_j)(0) / D_i(0)``, exact rationals. Then, in this order:

1. **Lyapunov equation** ``J^T P + P J = -I``, solved exactly (FLINT). When it has a unique
   solution: ``P > 0`` (exact) proves ``J`` Hurwitz, so the equilibrium is locally exponentially
   stable (``certified``). If ``P`` is not positive definite, the inertia theorem
   (Ostrowski-Schneider: ``J^T H + H J > 0`` with ``H = -P`` gives ``In(J) = In(H)``) says ``J``
   has as many eigenvalues with positive real part as ``P`` has negative ones, at least one: the
   equilibrium is unstable (``refuted``, Lyapunov's indirect method).
2. When the equation is singular (``lambda_i + lambda_j = 0`` for some eigenvalues: a zero or
   imaginary eigenvalue, or a pair ``+-lambda``), the characteristic polynomial ``p`` decides:
   Routh-Hurwitz (all Hurwitz determinants > 0, exact) certifies; an isolating root enclosure
   (FLINT/Arb, rigorous interval arithmetic) whose real part is > 0 refutes; otherwise the roots on
   the imaginary axis are found exactly (``gcd(Re p(i w), Im p(i w))`` has a real root) and the
   case is critical: ``not_certified``, the linearization decides nothing.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Sequence

from lyapcheck.models.loop.field import ShiftedField
from lyapcheck.results import ConditionResult
from lyapcheck.sos.definiteness import is_positive_definite
from lyapcheck.sos.polynomials import to_fraction

if TYPE_CHECKING:
    from lyapcheck.models.language.parameter_box import ModelBox

Matrix = list[list[Fraction]]


def jacobian(shifted: ShiftedField) -> Matrix:
    """``J`` at the equilibrium (disturbances 0), exactly."""
    ring = shifted.ring
    n = shifted.n
    origin = [Fraction(0)] * ring.nvars
    J = []
    for num, den in zip(shifted.numerators, shifted.denominators):
        d0 = ring.evaluate(den, origin)
        J.append([ring.evaluate(num.derivative(j), origin) / d0 for j in range(n)])
    return J


def _fmpq_mat(rows: Sequence[Sequence[Fraction]]) -> Any:
    import flint

    return flint.fmpq_mat([[flint.fmpq(x.numerator, x.denominator) for x in row] for row in rows])


def lyapunov_solution(J: Matrix) -> Matrix | None:
    """The exact ``P = P^T`` with ``J^T P + P J = -I``, or None when that is singular."""
    import flint

    n = len(J)
    pairs = [(i, j) for i in range(n) for j in range(i, n)]
    index: dict[tuple[int, ...], int] = {p: k for k, p in enumerate(pairs)}
    rows, rhs = [], []
    for a in range(n):
        for b in range(a, n):
            # (J^T P + P J)_{ab} = sum_k J_ka P_kb + P_ak J_kb
            row = [Fraction(0)] * len(pairs)
            for k in range(n):
                row[index[tuple(sorted((k, b)))]] += J[k][a]
                row[index[tuple(sorted((a, k)))]] += J[k][b]
            rows.append(row)
            rhs.append([Fraction(-1 if a == b else 0)])
    A = _fmpq_mat(rows)
    try:
        x = A.solve(_fmpq_mat(rhs))
    except (ZeroDivisionError, ValueError):
        return None
    P = [[Fraction(0)] * n for _ in range(n)]
    for (i, j), k in index.items():
        P[i][j] = P[j][i] = to_fraction(x[k, 0])
    del flint
    return P


def lyapunov_residual_ok(J: Matrix, P: Matrix) -> bool:
    n = len(J)
    for a in range(n):
        for b in range(n):
            value = sum((J[k][a] * P[k][b] + P[a][k] * J[k][b] for k in range(n)), Fraction(0))
            if value != (-1 if a == b else 0):
                return False
    return True


def characteristic_polynomial(J: Matrix) -> list[Fraction]:
    """Coefficients of ``det(s I - J)``, lowest degree first (exact)."""
    return [to_fraction(c) for c in _fmpq_mat(J).charpoly().coeffs()]


def hurwitz_matrix(coeffs: Sequence[Any], zero: Any) -> list[list[Any]]:
    """The Hurwitz matrix of the monic ``p(s) = sum c_k s^k`` (``c`` lowest degree first, numbers or
    polynomials; ``zero`` the zero of their kind): entry ``(i, j)`` is ``a_(2j - i)`` (1-based) with
    ``p = a_0 s^n + a_1 s^(n-1) + ... + a_n``, 0 outside ``0..n``."""
    n = len(coeffs) - 1
    a = [coeffs[n - k] for k in range(n + 1)]

    def entry(i: int, j: int) -> Any:
        k = 2 * (j + 1) - (i + 1)
        return a[k] if 0 <= k <= n else zero

    return [[entry(i, j) for j in range(n)] for i in range(n)]


def hurwitz_determinants(coeffs: Sequence[Fraction]) -> list[Fraction]:
    """The Hurwitz determinants of the monic ``p(s) = sum c_k s^k`` (all > 0 iff Hurwitz)."""
    from lyapcheck import exact

    H = hurwitz_matrix(coeffs, Fraction(0))
    return [exact.det(tuple(tuple(row[:k]) for row in H[:k])) for k in range(1, len(H) + 1)]


#: the relative precision of :func:`local_rate`'s bisection, in bits
LOCAL_RATE_BITS = 20


def local_rate(J: Matrix, bits: int = LOCAL_RATE_BITS) -> Fraction | None:
    """A proved local exponential rate of the exact Jacobian ``J``: the largest ``r`` found, by
    bisection to ``2**-bits`` of its upper bound, with ``J + r I`` Hurwitz (every Hurwitz
    determinant of its characteristic polynomial > 0, exact), so that every eigenvalue of ``J`` has
    real part ``< -r`` and, near the equilibrium, solutions decay like ``exp(-r t)``; None when ``J``
    itself is not Hurwitz. The upper bound is ``-trace(J)/n`` (the eigenvalues' mean real part), which
    the largest real part is at least."""
    n = len(J)

    def hurwitz_at(r: Fraction) -> bool:
        shifted = [[J[i][j] + (r if i == j else 0) for j in range(n)] for i in range(n)]
        return all(h > 0 for h in hurwitz_determinants(characteristic_polynomial(shifted)))

    if n == 0 or not hurwitz_at(Fraction(0)):
        return None
    high = -sum((J[i][i] for i in range(n)), Fraction(0)) / n
    low = Fraction(0)
    step = high / 2 ** bits
    while high - low > step:
        mid = (low + high) / 2
        low, high = (mid, high) if hurwitz_at(mid) else (low, mid)
    return low


def right_half_plane_root(coeffs: Sequence[Fraction]) -> str | None:
    """A root enclosure with real part certainly > 0 (FLINT/Arb, rigorous), as text, or None."""
    import flint

    poly = flint.fmpq_poly([flint.fmpq(c.numerator, c.denominator) for c in coeffs])
    roots: Any = poly.complex_roots()  # (acb, multiplicity) pairs at run time, whatever the stubs say
    for root, multiplicity in roots:
        if root.real > 0:
            return f"{root} (multiplicity {multiplicity})"
    return None


def imaginary_axis_roots(coeffs: Sequence[Fraction]) -> bool:
    """Exactly: ``p`` has a root on the imaginary axis (``gcd(Re p(i w), Im p(i w))`` has a real root)."""
    import flint

    re, im = [Fraction(0)] * len(coeffs), [Fraction(0)] * len(coeffs)
    for k, c in enumerate(coeffs):  # (i w)^k = i^k w^k
        unit = k % 4
        if unit == 0:
            re[k] += c
        elif unit == 1:
            im[k] += c
        elif unit == 2:
            re[k] -= c
        else:
            im[k] -= c
    R = flint.fmpq_poly([flint.fmpq(c.numerator, c.denominator) for c in re])
    I_ = flint.fmpq_poly([flint.fmpq(c.numerator, c.denominator) for c in im])
    G = R.gcd(I_) if not I_.is_zero() else R
    if G.degree() < 1:
        return False
    # Arb isolates the roots of an integer polynomial and gives the real ones an exactly zero
    # imaginary part (arb_fmpz_poly_complex_roots)
    roots: Any = G.numer().complex_roots()
    return any(root.imag.is_zero() for root, _ in roots)


def run(shifted: ShiftedField) -> ConditionResult:
    """Decide the linearization (see the module docstring)."""
    return decide(jacobian(shifted))


def decide(J: Matrix) -> ConditionResult:
    """Decide whether the exact Jacobian ``J`` is Hurwitz, unstable or critical (the module docstring)."""
    n = len(J)
    cert: dict[str, Any] = {"jacobian": [[str(x) for x in row] for row in J]}
    numbers: dict[str, Any] = {}
    try:
        import numpy as np

        eig = np.linalg.eigvals(np.array([[float(x) for x in row] for row in J]))
        numbers["max_real_part_estimate"] = float(np.max(eig.real))
    except (ValueError, OverflowError, ArithmeticError):
        pass
    P = lyapunov_solution(J)
    if P is not None:
        cert["P"] = [[str(x) for x in row] for row in P]
        if is_positive_definite(P):
            cert["method"] = "lyapunov_equation"
            return ConditionResult("linearization", "certified",
                                   "the Jacobian at the equilibrium is Hurwitz (J^T P + P J = -I with P > 0, exact): "
                                   "locally exponentially stable", numbers=numbers, certificate=cert)
        cert["method"] = "lyapunov_inertia"
        return ConditionResult("linearization", "refuted",
                               "the Jacobian has an eigenvalue with positive real part (J^T P + P J = -I with P not "
                               "positive definite, exact; inertia theorem): the equilibrium is unstable",
                               numbers=numbers, refutation=cert)
    coeffs = characteristic_polynomial(J)
    cert["characteristic_polynomial"] = [str(c) for c in coeffs]
    if all(h > 0 for h in hurwitz_determinants(coeffs)):
        cert["method"] = "routh_hurwitz"
        return ConditionResult("linearization", "certified",
                               "the Jacobian is Hurwitz (every Hurwitz determinant > 0, exact): locally exponentially "
                               "stable", numbers=numbers, certificate=cert)
    root = right_half_plane_root(coeffs)
    if root is not None:
        cert["method"] = "root_isolation"
        cert["root"] = root
        return ConditionResult("linearization", "refuted",
                               f"the Jacobian has an eigenvalue with positive real part (rigorous enclosure {root}): "
                               "the equilibrium is unstable", numbers=numbers, refutation=cert)
    from lyapcheck.models.engines import reasons

    if imaginary_axis_roots(coeffs):
        why = reasons.reason("critical case: the Jacobian has eigenvalues on the imaginary axis (exact) and none with "
                             "positive real part, so the linearization decides nothing", ("search", "candidate"))
        return ConditionResult("linearization", "not_certified", why.summary,
                               numbers=why.numbers({**numbers, "reason": "critical"}), certificate=cert)
    why = reasons.reason(f"the eigenvalues of the {n}x{n} Jacobian could not be located exactly",
                         ("search", "candidate"), "no root enclosure was conclusive")
    return ConditionResult("linearization", "inconclusive", why.summary, numbers=why.numbers(numbers))


def verify(shifted: ShiftedField, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a ``linearization`` certificate or refutation exactly."""
    return verify_jacobian(jacobian(shifted), status, data)


def verify_jacobian(J: Matrix, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a ``linearization`` certificate or refutation of the exact Jacobian ``J``."""
    if data.get("jacobian") != [[str(x) for x in row] for row in J]:
        return False, "the stored Jacobian differs from the model's"
    method = data.get("method")
    if method in ("lyapunov_equation", "lyapunov_inertia"):
        P = [[Fraction(x) for x in row] for row in data["P"]]
        if len(P) != len(J) or not lyapunov_residual_ok(J, P):
            return False, "J^T P + P J = -I does not hold exactly"
        if status == "certified":
            return (True, "J^T P + P J = -I with P > 0, exactly") if is_positive_definite(P) else \
                (False, "P is not positive definite")
        if status == "refuted":
            # P is nonsingular by the inertia theorem; that P is not positive definite is the claim
            return (True, "J^T P + P J = -I with P not positive definite, exactly") if not is_positive_definite(P) \
                else (False, "P is positive definite: J is Hurwitz, not unstable")
    coeffs = characteristic_polynomial(J)
    if method == "routh_hurwitz" and status == "certified":
        return (True, "every Hurwitz determinant > 0, exactly") if all(h > 0 for h in hurwitz_determinants(coeffs)) \
            else (False, "a Hurwitz determinant is not > 0")
    if method == "root_isolation" and status == "refuted":
        return (True, "a rigorous root enclosure with real part > 0") if right_half_plane_root(coeffs) else \
            (False, "no root enclosure with real part > 0")
    return False, f"unknown method {method!r} for status {status!r}"


# -- over a box of parameters: the Jacobian for every value of the box (issue 45, item 1) -----------

#: the method of a box certificate: every Hurwitz condition positive on the box (Bernstein, exact)
BOX_METHOD = "box_hurwitz"
#: the method of a box refutation: a point of the box where the Jacobian is proved unstable
BOX_POINT_METHOD = "box_point"


def jacobian_over_box(shifted: ShiftedField) -> tuple[list[list[Any]], Any] | str:
    """``J(u)`` at the equilibrium as polynomials in the box's normalized parameters ``u`` (the ring of
    :attr:`ShiftedField.box_names`), with that ring; or why not (a denominator at the equilibrium
    that depends on the parameters: the Jacobian is then rational in them)."""
    from lyapcheck.sos.polynomials import Ring

    ring = shifted.ring
    n = shifted.n
    box_ring = Ring(shifted.box_names)
    at_equilibrium = {name: Fraction(0) for name in ring.names[:n]}
    J = []
    for i, (num, den) in enumerate(zip(shifted.numerators, shifted.denominators)):
        d0 = ring.restrict(ring.substitute(den, at_equilibrium), box_ring)
        if not d0.is_constant() or d0.is_zero():
            return (f"the denominator of {shifted.model.states[i]}' at the equilibrium depends on the box's "
                    "parameters (the Jacobian is rational in them)")
        scale = 1 / d0.leading_coefficient()
        J.append([ring.restrict(ring.substitute(num.derivative(j), at_equilibrium), box_ring) * scale
                  for j in range(n)])
    return J, box_ring


def characteristic_polynomial_of(M: Sequence[Sequence[Any]], ring: Any) -> list[Any]:
    """``det(s I - M)`` of a matrix of polynomials, lowest degree first (Faddeev-LeVerrier: exact, one
    matrix product per degree; the divisions are by integers)."""
    import flint

    n = len(M)
    zero = ring.zero()
    coeffs: list[Any] = [zero] * (n + 1)
    coeffs[n] = ring.constant(1)
    W = [[zero] * n for _ in range(n)]  # M_0 = 0
    for k in range(1, n + 1):
        # M_k = M M_(k-1) + c_(n-k+1) I ;  c_(n-k) = -tr(M M_k) / k
        W = [[sum((M[i][t] * W[t][j] for t in range(n)), zero) + (coeffs[n - k + 1] if i == j else zero)
              for j in range(n)] for i in range(n)]
        trace = sum((sum((M[i][t] * W[t][i] for t in range(n)), zero) for i in range(n)), zero)
        coeffs[n - k] = trace * flint.fmpq(-1, k)
    return coeffs


def hurwitz_conditions(coeffs: Sequence[Any], ring: Any) -> list[tuple[str, Any]]:
    """The polynomials that are all positive exactly where the monic ``p(s) = sum c_k s^k`` is Hurwitz:
    the Hurwitz determinants ``Delta_1 .. Delta_(n-1)`` and ``a_n = c_0`` (``Delta_n = a_n
    Delta_(n-1)``), each named."""
    n = len(coeffs) - 1
    H = hurwitz_matrix(coeffs, ring.zero())
    out = []
    for k in range(1, n):
        leading = [row[:k] for row in H[:k]]
        det = characteristic_polynomial_of(leading, ring)[0] * (-1) ** k  # det M = (-1)^k det(0 I - M)
        out.append((f"Delta_{k}", det))
    out.append((f"a_{n}", coeffs[0]))
    return out


def _u_box(m: int) -> tuple[tuple[Fraction, Fraction], ...]:
    return tuple((Fraction(-1), Fraction(1)) for _ in range(m))


def run_over_box(shifted: ShiftedField) -> ConditionResult:
    """``linearization`` for every parameter value of ``shifted``'s box (:func:`decide_over_box`), or
    ``not_certified`` where ``J(u)`` is not polynomial in the parameters."""
    from lyapcheck.models.engines import reasons

    assert shifted.box is not None
    built = jacobian_over_box(shifted)
    if isinstance(built, str):
        why = reasons.reason(built, ("box",))
        return ConditionResult("linearization", "not_certified", why.summary, numbers=why.numbers())
    J, ring = built
    return decide_over_box(J, ring, shifted.box)


def decide_over_box(J: Sequence[Sequence[Any]], ring: Any, box: "ModelBox") -> ConditionResult:
    """Decide the Jacobian ``J(u)`` of every value of ``box`` (polynomials in its normalized parameters
    ``u``, the variables of ``ring`` in the box's order, ``theta = c + h u``), whatever kind of loop it
    comes from: ``certified`` when every Hurwitz condition of ``J(u)`` is proved positive on the box
    (:mod:`~lyapcheck.models.engines.bernstein`, exact), ``refuted`` when a point of the box has an
    unstable Jacobian (proved exactly there: no claim can hold for every value of the box), else
    ``not_certified`` naming the condition."""
    from lyapcheck.models.engines import bernstein, reasons

    conditions = hurwitz_conditions(characteristic_polynomial_of(J, ring), ring)
    u_box = _u_box(ring.nvars)
    examined = 0
    for name, q in conditions:
        found = bernstein.positive_on_box(ring.terms(q), u_box)
        examined += found.boxes
        if found.proved:
            continue
        if found.witness is not None:
            point = _parameter_point(box, found.witness)
            at = decide(_jacobian_at(J, ring, found.witness))
            if at.status == "refuted":
                data = {"method": BOX_POINT_METHOD, "point": {k: str(v) for k, v in point.items()},
                        "at_point": at.refutation}
                return ConditionResult("linearization", "refuted",
                                       f"at {point_words(point)}, a value of the box, {lower_first(at.summary)}",
                                       numbers=at.numbers, refutation=data)
            where = f"it is <= 0 at {point_words(point)}, where the linearization is {at.status}"
        else:
            where = f"not proved within {bernstein.MAX_BOXES} sub-boxes"
        why = reasons.reason(f"the Hurwitz condition {name} > 0 was not proved on the whole box ({where})",
                             ("box",))
        return ConditionResult("linearization", "not_certified", why.summary, numbers=why.numbers())
    cert = {"method": BOX_METHOD, "conditions": [name for name, _ in conditions], "sub_boxes": examined,
            "jacobian": [[_poly_json(ring, p) for p in row] for row in J]}
    return ConditionResult("linearization", "certified", BOX_SENTENCE, certificate=cert)


def rate_over_box(data: dict[str, Any], names: Sequence[str], rate: Fraction) -> bool:
    """Whether every eigenvalue of the stored ``J(u)`` (a certified box linearization's ``"jacobian"``,
    polynomials in the box's normalized parameters ``names``) has real part ``< -rate`` for every value of
    the box: ``J(u) + rate I`` Hurwitz there, by the same exact Bernstein test as :func:`decide_over_box`.
    The local decay rate over a box (``tune --objective local_decay_rate``'s neighbourhood); the caller
    has checked that the stored ``J(u)`` is the model's (:func:`verify_jacobian_over_box`)."""
    from lyapcheck.models.engines import bernstein
    from lyapcheck.sos.polynomials import Ring

    if data.get("method") != BOX_METHOD or not isinstance(data.get("jacobian"), list):
        return False
    ring = Ring(tuple(names))
    J = [[ring.from_terms({tuple(int(k) for k in m): Fraction(str(c)) for c, m in p}) for p in row]
         for row in data["jacobian"]]
    shifted = [[p + ring.constant(rate) if i == j else p for j, p in enumerate(row)] for i, row in enumerate(J)]
    conditions = hurwitz_conditions(characteristic_polynomial_of(shifted, ring), ring)
    return all(bernstein.positive_on_box(ring.terms(q), _u_box(ring.nvars)).proved for _, q in conditions)


#: what a certified box linearization states (the box's words come first: lyapcheck.models.classes.claims)
BOX_SENTENCE = ("the Jacobian at the equilibrium is Hurwitz (every Hurwitz determinant > 0 on the whole box, by "
                "exact Bernstein coefficients): locally exponentially stable")


def _poly_json(ring: Any, p: Any) -> list[list[Any]]:
    return [[str(c), list(m)] for m, c in sorted(ring.terms(p).items())]


def _jacobian_at(J: Sequence[Sequence[Any]], ring: Any, u: Sequence[Fraction]) -> Matrix:
    return [[ring.evaluate(p, list(u)) for p in row] for row in J]


def _parameter_point(box: "ModelBox", u: Sequence[Fraction]) -> dict[str, Fraction]:
    """The parameter values of normalized ``u`` (``theta = c + h u``)."""
    return {name: box.center(name) + box.half(name) * x for name, x in zip(box.names, u)}


def point_words(point: dict[str, Fraction]) -> str:
    """``k = 1, ki = 2``: a parameter point as a sentence names it."""
    return ", ".join(f"{k} = {float(v):.6g}" for k, v in point.items())


def lower_first(text: str) -> str:
    """A sentence that follows a comma."""
    return text[:1].lower() + text[1:]


def verify_over_box(shifted: ShiftedField, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a box linearization of a polynomial or rational loop (:func:`verify_jacobian_over_box`)."""
    built = jacobian_over_box(shifted)
    if isinstance(built, str):
        return False, built
    J, ring = built
    assert shifted.box is not None
    return verify_jacobian_over_box(J, ring, shifted.box, status, data)


def verify_jacobian_over_box(J: Sequence[Sequence[Any]], ring: Any, box: "ModelBox", status: str,
                             data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a box linearization of the Jacobian ``J(u)`` the model gives (:func:`decide_over_box`'s
    arguments): a certificate by running the same exact proof again (deterministic), a refutation by the
    exact point check at the stated point of the box."""
    if status == "certified":
        if data.get("method") != BOX_METHOD:
            return False, f"a box linearization's method must be {BOX_METHOD!r}"
        if data.get("jacobian") != [[_poly_json(ring, p) for p in row] for row in J]:
            return False, "the stored Jacobian over the box differs from the model's"
        again = decide_over_box(J, ring, box)
        return (True, "every Hurwitz condition > 0 on the box (Bernstein coefficients), exactly") \
            if again.status == "certified" else (False, "the Hurwitz conditions are not proved on the box")
    if status == "refuted" and data.get("method") == BOX_POINT_METHOD:
        point = {k: Fraction(v) for k, v in (data.get("point") or {}).items()}
        if set(point) != set(box.names):
            return False, "the stated point does not name every parameter of the box"
        if any(not box.interval(k)[0] <= v <= box.interval(k)[1] for k, v in point.items()):
            return False, "the stated point is not in the box"
        u = [(point[k] - box.center(k)) / box.half(k) for k in box.names]
        return verify_jacobian(_jacobian_at(J, ring, u), "refuted", data.get("at_point") or {})
    return False, f"unknown method {data.get('method')!r} for status {status!r} over a box"

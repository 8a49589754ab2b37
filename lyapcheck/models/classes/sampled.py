"""``linearization`` of a sampled-data loop: a continuous plant under a digital controller with a
zero-order hold (issue 44, item 2; DESIGN.md, "Sampled data").

The plant ``x' = f(x, u)`` runs between sampling instants with ``u`` held at ``k(x(t_k))``. Over one
period ``T`` the loop is the map ``x(t_k) -> x(t_k + T)``, whose Jacobian at the equilibrium is

    ``A_T = exp(A T) + (integral_0^T exp(A s) ds) B K``,

with ``A = df/dx``, ``B = df/du`` and ``K = dk/dx`` there (exact rationals). Both blocks are read off
one exponential, ``exp(T [[A, B], [0, 0]]) = [[exp(A T), Gamma], [0, I]]``, computed in ball
arithmetic (Arb, through python-flint): every entry of the true ``A_T`` lies in its ball.

**Deciding |eigenvalues| < 1 for every matrix of the balls.** The characteristic polynomial ``p`` of
the ball matrix (Arb's enclosure of the true one's coefficients) is mapped by the Cayley transform
``z = (1 + s)/(1 - s)`` to ``q(s) = (1 - s)^n p((1 + s)/(1 - s))``: a root of ``p`` inside the unit
disk is a root of ``q`` in the open left half-plane, outside it one in the open right half-plane,
and ``q`` has degree ``n`` exactly when ``p(-1) != 0``. Routh's array of ``q`` is then computed in
balls. When no ball of its first column contains 0, the number of sign changes along it is the
number of right half-plane roots of every polynomial of the balls (Routh's theorem, regular case):

- no sign change: every eigenvalue of the true ``A_T`` has modulus < 1, so the sampled-data loop is
  locally exponentially stable at the sampling instants, and between them (the flow over one period
  is Lipschitz near the equilibrium): ``certified``;
- a sign change: ``A_T`` has an eigenvalue of modulus > 1, so the equilibrium of the sampled-data
  loop is unstable (Lyapunov's indirect method for maps): ``refuted``.

A ball containing 0 is retried at a higher precision, up to :data:`MAX_PRECISION_BITS`; an
eigenvalue on the unit circle (the critical period itself) stays ``inconclusive``, as it must.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Sequence

from lyapcheck.models.classes.claims import SAMPLED_METHOD, sampled_linearization_sentence, seconds_text
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Ring

if TYPE_CHECKING:
    from lyapcheck.models.language.sampling import SampledModel

Matrix = Sequence[Sequence[Fraction]]

#: the first working precision of the ball arithmetic, in bits
FIRST_PRECISION_BITS = 64
#: the last: beyond it a ball of Routh's first column that still contains 0 leaves the case undecided
MAX_PRECISION_BITS = 1024
#: the certificate's method (claims words its sentence)
METHOD = SAMPLED_METHOD


def _arb_matrix(rows: Matrix) -> Any:
    import flint

    return flint.arb_mat([[flint.arb(flint.fmpq(x.numerator, x.denominator)) for x in row] for row in rows])


def sampled_jacobian(A: Matrix, B: Matrix, K: Matrix, period: Fraction) -> Any:
    """``exp(A T) + Gamma(T) B K`` as an Arb ball matrix at the current working precision
    (module docstring); ``A`` is ``n x n``, ``B`` ``n x m``, ``K`` ``m x n``."""
    import flint

    n, m = len(A), len(B[0]) if B else 0
    augmented = [[Fraction(0)] * (n + m) for _ in range(n + m)]
    for i in range(n):
        for j in range(n):
            augmented[i][j] = A[i][j] * period
        for j in range(m):
            augmented[i][n + j] = B[i][j] * period
    E = _arb_matrix(augmented).exp()
    Phi = flint.arb_mat([[E[i, j] for j in range(n)] for i in range(n)])
    if m == 0:
        return Phi
    Gamma = flint.arb_mat([[E[i, n + j] for j in range(m)] for i in range(n)])
    return Phi + Gamma * _arb_matrix(K)


def cayley_routh_column(M: Any) -> list[Any]:
    """The first column of Routh's array of ``q(s) = (1 - s)^n p((1 + s)/(1 - s))``, ``p`` the
    characteristic polynomial of the ball matrix ``M``, in balls (``q``'s leading coefficient first,
    made positive where its sign is known)."""
    import flint

    n = M.nrows()
    p = M.charpoly().coeffs()  # lowest degree first, monic
    plus, minus = flint.arb_poly([1, 1]), flint.arb_poly([1, -1])
    q = flint.arb_poly([0])
    for k, c in enumerate(p):
        q += c * plus ** k * minus ** (n - k)
    a = list(reversed(q.coeffs()))  # highest degree first
    a += [flint.arb(0)] * (n + 1 - len(a))
    if a[0] < 0:
        a = [-c for c in a]
    rows = [a[0::2], a[1::2]]
    width = len(rows[0])
    rows = [r + [flint.arb(0)] * (width + 1 - len(r)) for r in rows]
    column = [rows[0][0], rows[1][0]][: n + 1]
    while len(column) < n + 1:
        upper, lower = rows[-2], rows[-1]
        pivot = lower[0]
        if pivot.contains(0):
            return column  # undecided at this precision: the caller sees a ball containing 0
        row = [(pivot * upper[j + 1] - upper[0] * lower[j + 1]) / pivot for j in range(width)] + [flint.arb(0)]
        rows.append(row)
        column.append(row[0])
    return column


def _sign_changes(column: Sequence[Any]) -> int | None:
    """Sign changes along the column, or None when a ball contains 0."""
    if any(c.contains(0) for c in column):
        return None
    signs = [c > 0 for c in column]
    return sum(1 for a, b in zip(signs, signs[1:]) if a != b)


def _decide_at(A: Matrix, B: Matrix, K: Matrix, period: Fraction, bits: int) -> tuple[int | None, list[Any]]:
    import flint

    saved = flint.ctx.prec
    flint.ctx.prec = bits
    try:
        column = cayley_routh_column(sampled_jacobian(A, B, K, period))
        changes = _sign_changes(column) if len(column) == len(A) + 1 else None
    finally:
        flint.ctx.prec = saved
    return changes, column


def _spectral_radius_estimate(A: Matrix, B: Matrix, K: Matrix, period: Fraction) -> float | None:
    """A floating-point estimate of ``A_T``'s spectral radius, shown beside the proof, never used by it."""
    import numpy as np
    from scipy.linalg import expm

    try:
        n, m = len(A), len(B[0]) if B else 0
        M = np.zeros((n + m, n + m))
        M[:n, :n] = np.array(A, dtype=float) * float(period)
        if m:
            M[:n, n:] = np.array(B, dtype=float) * float(period)
        E = expm(M)
        AT = E[:n, :n] + (E[:n, n:] @ np.array(K, dtype=float) if m else 0.0)
        return float(np.max(np.abs(np.linalg.eigvals(AT))))
    except (ValueError, OverflowError, ArithmeticError, np.linalg.LinAlgError):
        return None


def _data(A: Matrix, B: Matrix, K: Matrix, period: Fraction) -> dict[str, Any]:
    def text(rows: Matrix) -> list[list[str]]:
        return [[str(x) for x in row] for row in rows]

    return {"method": METHOD, "period": str(period), "A": text(A), "B": text(B), "K": text(K)}


def decide(A: Matrix, B: Matrix, K: Matrix, period: Fraction) -> ConditionResult:
    """Decide the sampled-data linearization at ``period`` seconds (module docstring)."""
    if period <= 0:
        raise ValueError("the sampling period must be > 0")
    numbers: dict[str, Any] = {"period_s": float(period)}
    estimate = _spectral_radius_estimate(A, B, K, period)
    if estimate is not None:
        numbers["spectral_radius_estimate"] = estimate
    bits = FIRST_PRECISION_BITS
    while True:
        changes, column = _decide_at(A, B, K, period, bits)
        if changes is not None or bits >= MAX_PRECISION_BITS:
            break
        bits *= 2
    data = {**_data(A, B, K, period), "precision_bits": bits, "routh_first_column": [str(c) for c in column]}
    at = seconds_text(period)
    if changes == 0:  # (the sentence is the claims module's, from the status and the period alone)
        return ConditionResult("linearization", "certified", sampled_linearization_sentence("certified", period),
                               numbers=numbers, certificate=data)
    if changes is not None:
        return ConditionResult("linearization", "refuted", sampled_linearization_sentence("refuted", period),
                               numbers=numbers, refutation=data)
    return ConditionResult(
        "linearization", "inconclusive",
        f"at period {at} s the Jacobian over one period could not be placed inside or outside the unit circle "
        f"at {MAX_PRECISION_BITS} bits (an eigenvalue on or near the unit circle: a critical period); try a "
        "slightly different period", numbers={**numbers, "reason": "critical"})


def verify(A: Matrix, B: Matrix, K: Matrix, period: Fraction, status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-derive a sampled-data ``linearization`` answer from the model's exact ``A, B, K`` and period."""
    if data.get("method") != METHOD:
        return False, f"unknown method {data.get('method')!r}"
    expected = _data(A, B, K, period)
    for key in ("period", "A", "B", "K"):
        if data.get(key) != expected[key]:
            return False, f"the stored {key} differs from the model's"
    bits = data.get("precision_bits")
    if not isinstance(bits, int) or not FIRST_PRECISION_BITS <= bits <= MAX_PRECISION_BITS:
        return False, f"precision_bits must be an integer in {FIRST_PRECISION_BITS}..{MAX_PRECISION_BITS}"
    changes, _ = _decide_at(A, B, K, period, bits)
    if status == "certified":
        return (True, "no sign change in Routh's first column, in ball arithmetic") if changes == 0 else \
            (False, "Routh's first column is not of one sign")
    if status == "refuted":
        return (True, f"{changes} sign change(s) in Routh's first column, in ball arithmetic") if changes else \
            (False, "Routh's first column shows no eigenvalue of modulus > 1")
    return False, f"status {status!r} is not checked"


def linear_parts(model: "SampledModel") -> tuple[list[list[Fraction]], list[list[Fraction]], list[list[Fraction]]] | str:
    """``A = df/dx``, ``B = df/du`` and ``K = dk/dx`` at the equilibrium, exactly, or why there are
    none (a function of the plant not differentiable there, an irrational entry)."""
    from lyapcheck.models.language.modelfile import Model

    n, m = model.n, len(model.controls)
    if isinstance(model.plant, Model):
        from lyapcheck.models.classes.linearization import jacobian
        from lyapcheck.models.loop.field import shifted_field

        J: Any = jacobian(shifted_field(model.plant))
    else:
        from lyapcheck.models.classes.recast_classes import base_loop
        from lyapcheck.models.classes.recast_classes import jacobian as true_jacobian

        J = true_jacobian(base_loop(model.plant.system))
        if isinstance(J, str):
            return J
    if model.controller_system is not None:
        gain = control_gain(model)
        if isinstance(gain, str):
            return gain
        return [row[:n] for row in J[:n]], [row[n:n + m] for row in J[:n]], gain
    ring = Ring(model.states)
    point = list(model.equilibrium)
    K = []
    for u in model.controls:
        law = model.controller[u]
        d0 = ring.evaluate(law.denominator, point)
        n0 = ring.evaluate(law.numerator, point)
        K.append([(ring.evaluate(law.numerator.derivative(j), point) * d0
                   - n0 * ring.evaluate(law.denominator.derivative(j), point)) / (d0 * d0) for j in range(n)])
    return [row[:n] for row in J[:n]], [row[n:n + m] for row in J[:n]], K


def control_gain(model: "SampledModel") -> list[list[Fraction]] | str:
    """``K = dk/dx`` at the equilibrium, exactly, for laws with functions
    (:attr:`~lyapcheck.models.language.sampling.SampledModel.controller_system`): the chain rule through
    the laws' auxiliaries (:func:`~lyapcheck.models.classes.recast_classes.gradient_at_equilibrium`, as a
    continuous loop's Jacobian) and the quotient rule; or why there is none (a function not
    differentiable there, ``abs`` at 0 or ``sat`` at its corner, or an irrational entry), naming it."""
    from lyapcheck.models.classes.recast_classes import base_loop, gradient_at_equilibrium
    from lyapcheck.models.language.recast import value_at_equilibrium

    system = model.controller_system
    if system is None:
        raise ValueError("control_gain takes laws with functions (controller_system)")
    loop = base_loop(system, cylinder=False)
    K = []
    for u in model.controls:
        law = model.controller[u]
        n0, d0 = value_at_equilibrium(system, law.numerator), value_at_equilibrium(system, law.denominator)
        if n0 is None or not d0:  # (refused when the file was read)
            return f"[controller] {u}: its value at the equilibrium is not an exact rational"  # pragma: no cover
        dn = gradient_at_equilibrium(loop, system.shift(law.numerator))
        dd = gradient_at_equilibrium(loop, system.shift(law.denominator))
        if isinstance(dn, str) or isinstance(dd, str):
            return f"[controller] {u}: {dn if isinstance(dn, str) else dd}"
        K.append([(a * d0 - n0 * b) / (d0 * d0) for a, b in zip(dn, dd)])
    return K


def linearization(model: "SampledModel") -> ConditionResult:
    """The sampled-data linearization at the model's period (:func:`decide`), or ``not_applicable`` naming
    why it cannot be formed: the controller's gain (a law with a function not differentiable at the
    equilibrium, ``abs`` at 0) or the plant's Jacobian (the same in the plant)."""
    if model.controller_system is not None:  # a law with functions: its gain may not exist (abs at 0)
        gain = control_gain(model)
        if isinstance(gain, str):
            return ConditionResult("linearization", "not_applicable", "the controller's gain K = dk/dx at the "
                                   f"equilibrium cannot be formed exactly: {gain}", property="LES")
    parts = linear_parts(model)
    if isinstance(parts, str):
        # not_applicable, as a continuous loop's linearization for the same reason (recast_classes.linearization):
        # the test needs the Jacobian, so the class does not apply; nothing was left undecided by a search
        return ConditionResult("linearization", "not_applicable",
                               f"the plant's Jacobian at the equilibrium cannot be formed exactly: {parts}",
                               property="LES")
    A, B, K = parts
    return decide(A, B, K, model.period)


def verify_linearization(model: "SampledModel", status: str, data: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a ``linearization`` certificate or refutation (:func:`verify`) on ``A``, ``B``, ``K`` and the
    period re-derived from the model."""
    parts = linear_parts(model)
    if isinstance(parts, str):
        return False, "no exact Jacobian"
    return verify(*parts, model.period, status, data)


def spectral_radius_estimate(model: "SampledModel") -> float | None:
    """A floating-point estimate of the spectral radius of ``model``'s Jacobian over one period at its
    period (``simulate`` takes its default horizon from it); None when the Jacobian cannot be formed.
    Never a proof: :func:`decide` is."""
    parts = linear_parts(model)
    if isinstance(parts, str):
        return None
    A, B, K = parts
    return _spectral_radius_estimate(A, B, K, model.period)


__all__ = ["control_gain", "linear_parts", "linearization", "verify_linearization", "spectral_radius_estimate", "FIRST_PRECISION_BITS", "MAX_PRECISION_BITS", "METHOD", "cayley_routh_column", "decide",
           "sampled_jacobian", "verify"]

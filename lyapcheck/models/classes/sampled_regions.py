"""``roa`` of a sampled-data loop on its true nonlinear flow (issue 44, item 2; DESIGN.md, "Sampled data").

The loop is the map ``x(t_k) -> x(t_k + T) = Phi_T(x(t_k))``: the plant ``x' = f(x, u)`` (with its
functions: ``sin``, ``sat``, networks, ...) flowing for one period with ``u`` held at ``k(x(t_k))``. With
``e = x - x_eq``, ``v = u - u_eq`` and the linear parts ``A = df/dx``, ``B = df/du``, ``K = dk/dx`` at the
equilibrium (exact, :func:`lyapcheck.models.classes.sampled.linear_parts`):

    ``Phi_T(x) = x_eq + A_T e + R(e)``,  ``A_T = exp(A T) + Gamma B K``,  ``Gamma = int_0^T exp(A s) ds``,

and the proof bounds ``|R(e)| <= L2 |e|^2`` on the ball ``|e| <= r``, every step in ball arithmetic (Arb,
python-flint) on the model's own field (:class:`lyapcheck.models.engines.interval_field.Jet`: value,
gradient and Hessian enclosures over a box):

1. the held control: ``|v| <= Lk |e|`` and ``|k(x) - u_eq - K e| <= Lq |e|^2`` (``Lk`` the sup of
   ``|dk/dx|_F`` and ``Lq`` half the sup of the Hessians' Frobenius norms over ``[-r, r]^n``);
2. an a priori enclosure of the flow over one period: on the box ``|e_i| <= rho``, ``|v_j| <= Lk r`` the
   field grows at most as ``|f| <= Lx |e| + Lu |v|`` (its Jacobian blocks' sup norms), so by Gronwall
   ``|e(t)| <= Ce |e(0)|`` with ``Ce = exp(Lx T) (1 + Lu Lk T)`` for ``0 <= t <= T`` as long as the path is
   in the box, and ``Ce r < rho`` keeps it there (a continuation argument). Once the path is known to stay
   in the box, ``Ce`` is tightened by step 3's variation of constants (the linear loop's own growth
   ``sup |exp(A t) + Gamma(t) K|`` plus the remainder's), and the Hessians are then taken over a smaller box
   around the ball ``Ce r`` by a bootstrap (a bound below the assumed one on every ``[0, t]`` where the
   assumed one held: that set of times is open and closed);
3. the variation of constants ``e(T) = exp(A T) e0 + Gamma v + int_0^T exp(A (T - s)) h(s) ds`` with
   ``h = f - A e - B v`` bounded equation by equation by its Hessian blocks over that box
   (``|h_i| <= eta_i |e0|^2``, ``eta_i = (a_i Ce^2 + 2 b_i Ce Lk + c_i Lk^2) / 2``) and ``exp(A s)`` enclosed
   for every ``s`` in ``[0, T]`` by one ball matrix: ``|R| <= L2 |e|^2`` with
   ``L2 = |Gamma| Lq + T sum_i |col_i exp(A s)| eta_i``, column by column, so that a nonlinearity entering
   one equation pays only its column; ``W`` and ``LP`` are the same after ``A_T^T P`` and after ``L^T``
   (``P = L L^T``, a ball Cholesky factor);
4. ``V(e) = e^T P e`` with a rational ``P`` (the discrete Lyapunov equation solved in floats at the ball
   centre of ``A_T`` and rounded), ``P - A_T^T P A_T >= lambda_Q I`` proved for every matrix of ``A_T``'s balls
   (the centre's exact positive-definiteness test after a Gershgorin bound of the radii), and
   ``V(Phi_T(x)) - V(x) = -e^T (P - A_T^T P A_T) e + 2 e^T A_T^T P R + R^T P R
   <= -(lambda_Q - 2 W r - LP^2 r^2) |e|^2``; the bracket is proved > 0 exactly (every figure an upper
   bound, a rational);
5. the level ``c = lambda_P r^2`` with ``P - lambda_P I >= 0`` proved exactly: ``{V <= c}`` lies in the ball,
   so every start of it at a sampling instant stays in it and converges to the equilibrium, and between
   two instants ``|x(t) - x_eq| <= Ce |x(t_k) - x_eq|`` (the inter-sample excursion, step 2).

``r`` is the largest radius of a doubling-then-bisection search that passes (each try a handful of jet
evaluations over one box). ``verify`` re-derives ``A, B, K``, the period and ``A_T`` from the model text and
runs steps 1 to 5 again with the certificate's ``P``, ``r``, ``rho`` and proved lower bounds: a raised level,
another ``P`` or a smaller stated remainder fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Sequence

import flint

from lyapcheck import tolerances as tol
from lyapcheck.models.classes.claims import SAMPLED_REGION_KIND
from lyapcheck.models.engines.interval_field import Jet, apply, ball
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.sampling import SampledModel

Matrix = list[list[Fraction]]
#: the certificate's kind (claims words its sentence) and method
KIND = SAMPLED_REGION_KIND
METHOD = "sampled_flow_remainder"


def _exact(x: Any) -> Fraction:
    mantissa, exponent = x.man_exp()
    return Fraction(int(mantissa)) * Fraction(2) ** int(exponent)


def upper(x: Any) -> Fraction:
    """An exact upper bound of a finite ball, rounded up to :data:`~lyapcheck.tolerances.SAMPLED_FIGURE_BITS`
    significant bits (a short dyadic a reader can print; ValueError on an infinite ball)."""
    if not x.is_finite():
        raise ValueError("an unbounded enclosure")
    q = _exact(x.upper())
    if q <= 0:
        return q if q == 0 else -_round_down(-q)
    e = tol.SAMPLED_FIGURE_BITS - (q.numerator.bit_length() - q.denominator.bit_length())
    scale = Fraction(2) ** e
    return Fraction(math.ceil(q * scale)) / scale


def _round_down(q: Fraction) -> Fraction:
    e = tol.SAMPLED_FIGURE_BITS - (q.numerator.bit_length() - q.denominator.bit_length())
    scale = Fraction(2) ** e
    return Fraction(math.floor(q * scale)) / scale


def _dyadic(x: float, bits: int) -> Fraction:
    """``x`` rounded to ``bits`` significant bits, exactly (the same on every machine)."""
    if x == 0 or not math.isfinite(x):
        return Fraction(0)
    e = bits - math.frexp(x)[1]
    return Fraction(round(x * 2.0 ** e)) / Fraction(2) ** e if e >= 0 else Fraction(round(x * 2.0 ** e)) * 2 ** -e


def _frobenius(rows: Sequence[Sequence[Any]]) -> Any:
    """An upper bound of the spectral norm of every matrix of the balls (its Frobenius norm, from each
    entry's largest modulus)."""
    total = flint.arb(0)
    for row in rows:
        for x in row:
            m = abs(x).upper()
            total += m * m
    return total.sqrt()


# -- the true plant and controller as jets over a box ---------------------------------------------------

class TrueLoop:
    """The plant ``f(x_eq + e, u_eq + v)`` (its first ``n`` right-hand sides, as jets in ``(e, v)``) and the
    controller ``k(x_eq + e)`` (as jets in ``e``), each enclosed over a box by ball arithmetic on the model's
    own expressions (no relation of a recasting is used)."""

    def __init__(self, model: "SampledModel") -> None:
        from lyapcheck.models.engines.interval_field import BallLoop, CompiledPoly
        from lyapcheck.models.language.modelfile import Model
        from lyapcheck.sos.polynomials import Ring

        self.n, self.m = model.n, len(model.controls)
        plant = model.plant
        if isinstance(plant, Model):
            from lyapcheck.models.loop.field import shifted_field

            shifted = shifted_field(plant)
            pairs = [(CompiledPoly(shifted.ring, N), None if D == shifted.ring.constant(1) else
                      CompiledPoly(shifted.ring, D)) for N, D in zip(shifted.numerators, shifted.denominators)]

            def field(z: list[Any]) -> list[Any]:
                zero = flint.arb(0)
                out = []
                for N, D in pairs[:self.n]:
                    value = N(z, zero)
                    out.append(value if D is None else apply("reciprocal", D(z, zero)) * value)
                return out

            self._field: Callable[[list[Any]], list[Any]] = field
        else:
            self._field = BallLoop(plant.system).field
        laws = [model.controller[u] for u in model.controls]
        self._variables: Callable[[Sequence[Any]], list[Any]]
        if model.controller_system is None:
            ring = Ring(model.states)
            x_eq = [ball(q) for q in model.equilibrium]

            def variables(e: Sequence[Any]) -> list[Any]:
                return [c + ei for c, ei in zip(x_eq, e)]

            self._variables = variables
        else:
            ring = model.controller_system.ring
            self._variables = BallLoop(model.controller_system).variables
        self._laws = [(CompiledPoly(ring, r.numerator), CompiledPoly(ring, r.denominator)) for r in laws]

    def plant(self, e: Sequence[Any], v: Sequence[Any]) -> list[Jet]:
        """The first ``n`` right-hand sides as order-2 jets in ``(e, v)`` over the balls."""
        k = self.n + self.m
        z = [Jet.variable(b, i, k, 2) for i, b in enumerate(list(e) + list(v))]
        return [f if isinstance(f, Jet) else Jet.constant(f, k, 2) for f in self._field(z)[:self.n]]

    def controller(self, e: Sequence[Any]) -> list[Jet]:
        """Each law as an order-2 jet in ``e`` over the balls."""
        z = [Jet.variable(b, i, self.n, 2) for i, b in enumerate(e)]
        values = self._variables(z)
        zero = flint.arb(0)
        out = []
        for N, D in self._laws:
            num, den = N(values, zero), D(values, zero)
            den = den if isinstance(den, Jet) else Jet.constant(den, self.n, 2)
            law = apply("reciprocal", den) * num
            out.append(law if isinstance(law, Jet) else Jet.constant(law, self.n, 2))
        return out


# -- steps 1 to 3: the remainder over one period ---------------------------------------------------------

@dataclass(frozen=True)
class FlowBounds:
    """Step 1 to 4's figures on the ball ``|e| <= r``, each an exact upper bound (module docstring): ``L2``
    bounds ``|R(e)| / |e|^2``, ``W`` bounds ``|A_T^T P R(e)| / |e|^2`` (the cross term of V's decrease) and
    ``LP`` bounds ``|L^T R(e)| / |e|^2`` with ``P = L L^T`` (so ``R^T P R <= LP^2 |e|^4``)."""

    Lk: Fraction
    Lq: Fraction
    Lx: Fraction
    Lu: Fraction
    Ce: Fraction
    L2: Fraction
    W: Fraction
    LP: Fraction
    rho: Fraction

    def to_json(self) -> dict[str, str]:
        return {k: str(getattr(self, k)) for k in FLOW_FIGURES}


#: the flow's figures a certificate states, in order
FLOW_FIGURES = ("Lk", "Lq", "Lx", "Lu", "Ce", "L2", "W", "LP", "rho")


@dataclass(frozen=True)
class Weights:
    """The linear parts' norms the remainder is weighed by (upper bounds, balls): ``|Gamma|``, each column
    of ``exp(A s)`` over ``0 <= s <= T``, and the same after ``X = A_T^T P`` (for ``W``) and after ``L^T``
    (``P = L L^T``, for ``LP``)."""

    gamma: Any
    columns: tuple[Any, ...]
    x_gamma: Any
    x_columns: tuple[Any, ...]
    l_gamma: Any
    l_columns: tuple[Any, ...]
    #: ``sup |exp(A t) + Gamma(t) K|`` and ``sup |Gamma(t)|`` over ``[0, T]`` (the linear excursion)
    mu: Any
    gamma_t: Any


def _cholesky(P: list[list[Any]]) -> list[list[Any]] | None:
    """``L`` lower triangular with ``P = L L^T``, in balls (every symmetric matrix of the balls has its
    factor in ``L``'s balls), or None when a pivot is not proved > 0."""
    n = len(P)
    L = [[flint.arb(0)] * n for _ in range(n)]
    for j in range(n):
        d = P[j][j] - sum((L[j][k] * L[j][k] for k in range(j)), flint.arb(0))
        if not d > 0:
            return None
        L[j][j] = d.sqrt()
        for i in range(j + 1, n):
            L[i][j] = (P[i][j] - sum((L[i][k] * L[j][k] for k in range(j)), flint.arb(0))) / L[j][j]
    return L


def weights(parts: LinearParts, P: Matrix) -> Weights | None:
    """:class:`Weights` of ``P``; None when ``P``'s Cholesky factor is not proved."""
    AT, gamma, E = parts.AT, parts.gamma, parts.E
    n = len(P)
    Pb = [[ball(x) for x in row] for row in P]
    X = [[sum((AT[k][i] * Pb[k][j] for k in range(n)), flint.arb(0)) for j in range(n)] for i in range(n)]
    L = _cholesky(Pb)
    if L is None:
        return None
    LT = [[L[j][i] for j in range(n)] for i in range(n)]

    def times(L: list[list[Any]], R: list[list[Any]]) -> list[list[Any]]:
        return [[sum((L[i][k] * R[k][j] for k in range(len(R))), flint.arb(0)) for j in range(len(R[0]))]
                for i in range(len(L))] if R and R[0] else [[] for _ in L]

    def columns(M: list[list[Any]]) -> tuple[Any, ...]:
        return tuple(_frobenius([[row[j]] for row in M]) for j in range(n))

    return Weights(_frobenius(gamma), columns(E), _frobenius(times(X, gamma)), columns(times(X, E)),
                   _frobenius(times(LT, gamma)), columns(times(LT, E)), _spectral(parts.growth),
                   _frobenius(parts.gamma_t))


def _derivatives(jets: Sequence[Jet], what: str) -> tuple[list[list[Any]], list[list[list[Any]]]] | str:
    grads, hessians = [], []
    for j in jets:
        if j.grad is None or j.hess is None or not all(g.is_finite() for g in j.grad) or \
                not all(h.is_finite() for row in j.hess for h in row):
            return f"{what} is not twice differentiable with bounded derivatives on the box (a kink or a pole)"
        grads.append(j.grad)
        hessians.append(j.hess)
    return grads, hessians


def flow_bounds(loop: TrueLoop, period: Fraction, w: Weights, r: Fraction, rho: Fraction | None
                ) -> FlowBounds | str:
    """Steps 1 to 3 on ``|e| <= r`` and the cross term ``W``; ``rho``: the a priori box's half-width (None:
    found by :data:`~lyapcheck.tolerances.SAMPLED_APRIORI_TRIES` enlargements); or why not.

    With ``|h_i(s)| <= eta_i |e0|^2`` (each right-hand side's Hessian blocks over the a priori box) and
    ``R = Gamma q(e0) + int_0^T exp(A (T - s)) h(s) ds``: ``|R| <= |Gamma| Lq |e0|^2 + T sum_i |exp(A s)_i|
    eta_i |e0|^2`` column by column (a plant whose nonlinearity enters one equation pays only that column),
    and the same after ``A_T^T P`` for ``W``."""
    n, m = loop.n, loop.m
    T = ball(period)
    half = flint.arb(1) / 2
    box_r = [flint.arb(0, ball(r)) for _ in range(n)]
    control = _derivatives(loop.controller(box_r), "the controller")
    if isinstance(control, str):
        return control
    grads, hessians = control
    Lk = _frobenius(grads)
    Lq = half * flint.arb(sum((_frobenius(H) ** 2 for H in hessians), flint.arb(0))).sqrt()
    v_half = upper(Lk * ball(r))
    current = rho if rho is not None else r * tol.SAMPLED_APRIORI_START
    for _ in range(1 if rho is not None else tol.SAMPLED_APRIORI_TRIES):
        e_box = [flint.arb(0, ball(current)) for _ in range(n)]
        v_box = [flint.arb(0, ball(v_half)) for _ in range(m)]
        plant = _derivatives(loop.plant(e_box, v_box), "the plant")
        if isinstance(plant, str):
            return plant
        pg, ph = plant
        Lx = _frobenius([g[:n] for g in pg])
        Lu = _frobenius([g[n:] for g in pg])
        Ce = (Lx * T).exp() * (1 + Lu * Lk * T)
        if upper(Ce * ball(r)) < current:
            blocks = [(_frobenius([row[:n] for row in H[:n]]), _frobenius([row[n:] for row in H[:n]]),
                       _frobenius([row[n:] for row in H[n:]])) for H in ph]

            def etas(C: Any) -> list[Any]:
                return [half * (a * C * C + 2 * b * C * Lk + c * Lk * Lk) for a, b, c in blocks]

            eta = etas(Ce)
            for _ in range(tol.SAMPLED_EXCURSION_PASSES):
                # the excursion again by the variation of constants, now that the path is known to stay in
                # the box: |e(t)| <= (mu + (|Gamma(t)| Lq + T sum_i |exp(A s)_i| eta_i) r) |e0|, mu the linear
                # loop's own growth over the period (near 1 for a short period, where Gronwall's is not)
                again = w.mu + (w.gamma_t * Lq + T * sum((col * e for col, e in zip(w.columns, eta)),
                                                         flint.arb(0))) * ball(r)
                if not again.upper() < Ce.upper():
                    break
                Ce = again
                eta = etas(Ce)
            # a smaller box around the excursion just proved, by a bootstrap: with the Hessians over the box
            # |e_i| <= C r (C a little above Ce), a bound C' < C by the variation of constants holds on every
            # [0, t] where |e| <= C |e0| held, so that set of times is open and closed: all of [0, T]
            C = Ce * tol.SAMPLED_BOOTSTRAP_SLACK
            inner = _dyadic(float(upper(C * ball(r))) * tol.SAMPLED_BOOTSTRAP_SLACK, 20)
            if inner < current:
                e_inner = [flint.arb(0, ball(inner)) for _ in range(n)]
                tight = _derivatives(loop.plant(e_inner, v_box), "the plant")
                if not isinstance(tight, str) and upper(C * ball(r)) < inner:
                    inner_blocks = [(_frobenius([row[:n] for row in H[:n]]), _frobenius([row[n:] for row in H[:n]]),
                                     _frobenius([row[n:] for row in H[n:]])) for H in tight[1]]
                    inner_eta = [half * (a * C * C + 2 * b * C * Lk + c * Lk * Lk) for a, b, c in inner_blocks]
                    again = w.mu + (w.gamma_t * Lq + T * sum((col * e for col, e in zip(w.columns, inner_eta)),
                                                             flint.arb(0))) * ball(r)
                    if again.upper() < C.lower() and again.upper() < Ce.upper():
                        Ce = again
                        eta = [half * (a * Ce * Ce + 2 * b * Ce * Lk + c * Lk * Lk) for a, b, c in inner_blocks]
            L2 = w.gamma * Lq + T * sum((col * e for col, e in zip(w.columns, eta)), flint.arb(0))
            W = w.x_gamma * Lq + T * sum((col * e for col, e in zip(w.x_columns, eta)), flint.arb(0))
            LP = w.l_gamma * Lq + T * sum((col * e for col, e in zip(w.l_columns, eta)), flint.arb(0))
            return FlowBounds(upper(Lk), upper(Lq), upper(Lx), upper(Lu), upper(Ce), upper(L2), upper(W), upper(LP),
                              current)
        if rho is not None:
            break
        # (the flow may leave the box: enlarge it past the excursion found, a dyadic so the figure stays short)
        current = _dyadic(float(upper(Ce * ball(r))) * tol.SAMPLED_APRIORI_GROWTH, 20)
    return (f"the flow over one period from |e| <= {float(r):.3g} could not be enclosed: the field grows too fast on "
            "the boxes tried (Gronwall)")


# -- step 4 and 5: V, its decrease and the level ----------------------------------------------------------

@dataclass(frozen=True)
class LinearParts:
    """The linear loop over one period, in balls at the current precision: ``A_T``, ``Gamma`` (its input
    block, ``int_0^T exp(A s) ds B``), and for every ``t`` in ``[0, T]`` at once (the exponential of the
    matrix times the ball ``[0, T]``): ``exp(A t)``, ``Gamma(t)`` and the linear loop's state map
    ``exp(A t) + Gamma(t) K``."""

    AT: list[list[Any]]
    gamma: list[list[Any]]
    E: list[list[Any]]
    gamma_t: list[list[Any]]
    growth: list[list[Any]]


def sampled_parts(A: Matrix, B: Matrix, K: Matrix, period: Fraction) -> LinearParts:
    """:class:`LinearParts` (``A_T`` as :func:`lyapcheck.models.classes.sampled.sampled_jacobian` makes it)."""
    from lyapcheck.models.classes.sampled import sampled_jacobian

    n, m = len(A), len(B[0]) if B else 0
    AT = sampled_jacobian(A, B, K, period)
    aug = [[Fraction(0)] * (n + m) for _ in range(n + m)]
    for i in range(n):
        for j in range(n):
            aug[i][j] = A[i][j]
        for j in range(m):
            aug[i][n + j] = B[i][j]
    M = flint.arb_mat([[ball(x) for x in row] for row in aug])
    E = (M * ball(period)).exp()
    within = (M * flint.arb(ball(period) / 2, ball(period) / 2)).exp()
    Kb = [[ball(x) for x in row] for row in K]
    gamma_t = [[within[i, n + j] for j in range(m)] for i in range(n)]
    growth = [[within[i, j] + sum((gamma_t[i][k] * Kb[k][j] for k in range(m)), flint.arb(0)) for j in range(n)]
              for i in range(n)]
    return LinearParts([[AT[i, j] for j in range(n)] for i in range(n)], [[E[i, n + j] for j in range(m)]
                                                                           for i in range(n)],
                       [[within[i, j] for j in range(n)] for i in range(n)], gamma_t, growth)


def _spectral(M: list[list[Any]]) -> Any:
    """An upper bound of the spectral norm of every matrix of the balls: the smaller of the Frobenius norm
    and the square root of a Gershgorin bound of ``M^T M`` (tight for a matrix near the identity)."""
    n = len(M[0]) if M else 0
    gram = [[sum((M[k][i] * M[k][j] for k in range(len(M))), flint.arb(0)) for j in range(n)] for i in range(n)]
    gershgorin = max((sum((abs(x).upper() for x in row), flint.arb(0)) for row in gram), default=flint.arb(0))
    frobenius = _frobenius(M)
    root = gershgorin.sqrt()
    return root if root < frobenius else frobenius


def stein_margin(P: Matrix, AT: list[list[Any]], lam: Fraction) -> bool:
    """``P - A^T P A - lam I`` positive definite for every matrix ``A`` of the balls ``AT``: the centre's exact
    test after subtracting the radii's Gershgorin bound (every symmetric matrix of the balls is the centre
    plus a perturbation of spectral norm at most its largest absolute row sum of radii). A map with functions'
    test over a box is this one with ``lam = 0``
    (:func:`lyapcheck.models.classes.discrete_functions_box.stein_margin_proved`)."""
    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    Pb = [[ball(x) for x in row] for row in P]
    PA = [[sum((Pb[k][l] * AT[l][j] for l in range(n)), flint.arb(0)) for j in range(n)] for k in range(n)]
    C = [[Fraction(0)] * n for _ in range(n)]
    R = [[Fraction(0)] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            x = Pb[i][j] - sum((AT[k][i] * PA[k][j] for k in range(n)), flint.arb(0))
            if not x.is_finite():
                return False
            lo, hi = _exact(x.lower()), _exact(x.upper())
            C[i][j] = C[j][i] = (lo + hi) / 2
            R[i][j] = R[j][i] = (hi - lo) / 2
    radius = max(sum(row) for row in R)
    return is_positive_definite([[C[i][j] - (radius + lam if i == j else 0) for j in range(n)] for i in range(n)])


def _lower_eigen(P: Matrix, test: Callable[[Fraction], bool], estimate: float) -> Fraction | None:
    """The largest of a few rational fractions of ``estimate`` that ``test`` proves, or None."""
    for share in tol.SAMPLED_EIGEN_SHARES:
        lam = _dyadic(estimate * share, 24)
        if lam > 0 and test(lam):
            return lam
    return None


@dataclass(frozen=True)
class Decrease:
    """What step 4 needs of ``P`` besides the flow: ``lambda_Q``, proved."""

    lambda_Q: Fraction

    def margin(self, flow: FlowBounds, r: Fraction) -> Fraction:
        """``lambda_Q - 2 W r - LP^2 r^2``: > 0 proves V's decrease on ``0 < |e| <= r``, as
        ``V(Phi_T(x)) - V(x) = -e^T (P - A_T^T P A_T) e + 2 e^T A_T^T P R + R^T P R``."""
        return self.lambda_Q - 2 * flow.W * r - flow.LP ** 2 * r * r


def decrease_of(P: Matrix, AT: list[list[Any]], lambda_Q: Fraction) -> Decrease | str:
    """Step 4's figures of ``P``, ``lambda_Q`` proved; or why not."""
    if not stein_margin(P, AT, lambda_Q):
        return "P - A_T^T P A_T >= lambda_Q I is not proved for the balls of A_T"
    return Decrease(lambda_Q)


def level_of(P: Matrix, lambda_P: Fraction, r: Fraction) -> Fraction | None:
    """``c = lambda_P r^2`` when ``P - lambda_P I >= 0`` is proved exactly (then ``{V <= c}`` is inside
    ``|e| <= r``), else None."""
    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    if not lambda_P > 0 or not is_positive_definite([[P[i][j] - (lambda_P if i == j else 0) for j in range(n)]
                                                     for i in range(n)]):
        return None
    return lambda_P * r * r


def _float_p(AT: list[list[Any]]) -> tuple[Matrix, float, float] | None:
    """``P`` of ``A^T P A - P = -I`` at the balls' centres, rounded to
    :data:`~lyapcheck.tolerances.P_BITS` bits, and floating-point estimates of the least eigenvalues of ``P``
    and of ``P - A^T P A`` (proposals: every figure used is proved); None when the centre is not Schur."""
    import numpy as np
    from scipy.linalg import solve_discrete_lyapunov

    n = len(AT)
    M = np.array([[float(AT[i][j].mid()) for j in range(n)] for i in range(n)])
    if not np.all(np.isfinite(M)) or np.max(np.abs(np.linalg.eigvals(M))) >= 1:
        return None
    X = solve_discrete_lyapunov(M.T, np.eye(n))
    P = [[_dyadic(float(X[min(i, j), max(i, j)]), tol.P_BITS) for j in range(n)] for i in range(n)]
    Pf = np.array(P, dtype=float)
    return P, float(np.min(np.linalg.eigvalsh(Pf))), float(np.min(np.linalg.eigvalsh(Pf - M.T @ Pf @ M)))


# -- the class --------------------------------------------------------------------------------------------

def _with_precision(bits: int, run: Callable[[], Any]) -> Any:
    saved = flint.ctx.prec
    flint.ctx.prec = bits
    try:
        return run()
    finally:
        flint.ctx.prec = saved


def _linear(model: "SampledModel") -> tuple[Matrix, Matrix, Matrix] | str:
    from lyapcheck.models.classes.sampled import control_gain, linear_parts

    if model.controller_system is not None:
        gain = control_gain(model)
        if isinstance(gain, str):
            return f"the controller's gain K = dk/dx at the equilibrium cannot be formed exactly: {gain}"
    parts = linear_parts(model)
    if isinstance(parts, str):
        return f"the plant's Jacobian at the equilibrium cannot be formed exactly: {parts}"
    return parts


@dataclass(frozen=True)
class Found:
    """A proved region: ``P``, its proved eigenvalue bounds, the radius, the flow's figures and the level."""

    P: Matrix
    lambda_P: Fraction
    decrease: Decrease
    r: Fraction
    flow: FlowBounds
    level: Fraction


def search(model: "SampledModel", parts: tuple[Matrix, Matrix, Matrix], budget: "Budget | None" = None
           ) -> Found | str:
    """Steps 1 to 5 with the largest radius found (module docstring), at
    :data:`~lyapcheck.tolerances.SAMPLED_REGION_BITS`; or why none. Its work is bounded by counts (the
    radii tried); ``budget``, the class's safety net, is checked before each radius."""
    A, B, K = parts
    period = model.period

    def run() -> Found | str:
        linear = sampled_parts(A, B, K, period)
        AT = linear.AT
        proposal = _float_p(AT)
        if proposal is None:
            return ("the Jacobian over one period is not Schur at its ball centre (see linearization): no quadratic V "
                    "decreases along the sampled loop near the equilibrium")
        P, eig_P, eig_Q = proposal
        lambda_P = _lower_eigen(P, lambda lam: level_of(P, lam, Fraction(1)) is not None, eig_P)
        lambda_Q = _lower_eigen(P, lambda lam: stein_margin(P, AT, lam), eig_Q)
        if lambda_P is None or lambda_Q is None:
            return "P from the discrete Lyapunov equation could not be proved positive definite with a decrease margin"
        decrease = decrease_of(P, AT, lambda_Q)
        if isinstance(decrease, str):  # pragma: no cover - lambda_Q was just proved
            return decrease
        loop = TrueLoop(model)
        w = weights(linear, P)
        if w is None:  # pragma: no cover - P - lambda_P I >= 0 was proved above
            return "P's Cholesky factor is not proved in ball arithmetic"

        def attempt(r: Fraction) -> FlowBounds | None:
            if budget is not None:
                budget.check()
            flow = flow_bounds(loop, period, w, r, None)
            return flow if isinstance(flow, FlowBounds) and decrease.margin(flow, r) > 0 else None

        r = tol.SAMPLED_RADIUS_START
        best: tuple[Fraction, FlowBounds] | None = None
        low, high = Fraction(0), None
        for _ in range(tol.SAMPLED_RADIUS_DOUBLINGS):
            flow = attempt(r)
            if flow is None:
                high = r
                break
            best, low = (r, flow), r
            r *= 2
        if high is None and best is None:  # pragma: no cover - the loop runs at least once
            return "no radius tried"
        if best is None:  # shrink to the first radius that passes
            for _ in range(tol.SAMPLED_RADIUS_DOUBLINGS):
                r /= 2
                flow = attempt(r)
                if flow is not None:
                    best, low = (r, flow), r
                    high = 2 * r
                    break
            if best is None:
                why = flow_bounds(loop, period, w, r, None)
                return ("no ball around the equilibrium was proved: " + why if isinstance(why, str) else
                        "no ball around the equilibrium was proved: the remainder of the flow over one period is "
                        f"too large for V's decrease margin even at |e| <= {float(r):.3g}")
        if high is not None:
            for _ in range(tol.SAMPLED_RADIUS_BISECTIONS):
                mid = (low + high) / 2
                flow = attempt(mid)
                if flow is None:
                    high = mid
                else:
                    best, low = (mid, flow), mid
        r, flow = best
        level = level_of(P, lambda_P, r)
        assert level is not None  # (lambda_P was proved above)
        return Found(P, lambda_P, decrease, r, flow, level)

    result: Found | str = _with_precision(tol.SAMPLED_REGION_BITS, run)
    return result


def _data(model: "SampledModel", parts: tuple[Matrix, Matrix, Matrix], found: Found) -> dict[str, Any]:
    from lyapcheck.models.classes.sampled import _data as linear_data

    return {**linear_data(*parts, model.period), "kind": KIND, "method": METHOD,
            "precision_bits": tol.SAMPLED_REGION_BITS,
            "P": [[str(x) for x in row] for row in found.P], "states": list(model.states),
            "equilibrium": [str(x) for x in model.equilibrium],
            "lambda_P": str(found.lambda_P), "lambda_Q": str(found.decrease.lambda_Q),
            "radius": str(found.r), "level": str(found.level), "flow": found.flow.to_json()}


#: the figures a ``roa`` condition of a sampled-data loop states (:func:`verify` compares each)
FIGURES = ("level", "ball_radius", "intersample_factor", "remainder_L2", "a_priori_radius", "period_s")


def _numbers(model: "SampledModel", found: Found) -> dict[str, Any]:
    return {"level": float(found.level), "ball_radius": float(found.r), "intersample_factor": float(found.flow.Ce),
            "remainder_L2": float(found.flow.L2), "a_priori_radius": float(found.flow.rho),
            "period_s": float(model.period)}


def roa(model: "SampledModel", budget: "Budget | None" = None) -> ConditionResult:
    """The sampled-data loop's region of attraction (module docstring): ``certified`` once steps 1 to 5
    passed, else ``not_certified`` (or ``not_applicable`` without an exact Jacobian) saying why."""
    from lyapcheck.models.classes.claims import sampled_region_sentence

    parts = _linear(model)
    if isinstance(parts, str):
        return ConditionResult("roa", "not_applicable", parts, property="ROA")
    found = search(model, parts, budget)
    if isinstance(found, str):
        return ConditionResult("roa", "not_certified", found, property="ROA")
    data = _data(model, parts, found)
    return ConditionResult("roa", "certified", sampled_region_sentence(model.period, data),
                           numbers=_numbers(model, found), certificate=data, property="ROA")


def verify(model: "SampledModel", c: dict[str, Any]) -> tuple[bool, str]:
    """Re-derive a sampled-data ``roa`` certificate from the model text (module docstring): the linear parts,
    ``A_T`` in balls, ``P``'s proved eigenvalue bounds, the flow's bounds on the stated ball and a priori box
    (none may be smaller than the stated ones), the decrease and the level; then the figures."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.sampled import _data as linear_data

    if c.get("status") != "certified":
        return False, f"a {c.get('status')} roa claim on a sampled-data loop that no check re-derives"
    data = c.get("certificate") or {}
    if data.get("kind") != KIND or data.get("method") != METHOD:
        return False, f"unknown certificate kind {data.get('kind')!r} / method {data.get('method')!r}"
    parts = _linear(model)
    if isinstance(parts, str):
        return False, parts
    expected = linear_data(*parts, model.period)
    for key in ("period", "A", "B", "K"):
        if data.get(key) != expected[key]:
            return False, f"the stated {key} differs from the model's"
    if data.get("states") != list(model.states) or data.get("equilibrium") != [str(x) for x in model.equilibrium]:
        return False, "the stated states or equilibrium differ from the model's"
    bits = data.get("precision_bits")
    if not isinstance(bits, int) or isinstance(bits, bool) or not 53 <= bits <= tol.SAMPLED_REGION_MAX_BITS:
        return False, f"precision_bits must be an integer in 53..{tol.SAMPLED_REGION_MAX_BITS}"
    n = model.n
    P = [[read_rational(x, "P") for x in row] for row in data["P"]]
    if len(P) != n or any(len(row) != n for row in P) or any(P[i][j] != P[j][i] for i in range(n) for j in range(n)):
        return False, f"P must be a symmetric {n} x {n} matrix"
    lambda_P, lambda_Q = read_rational(data["lambda_P"], "lambda_P"), read_rational(data["lambda_Q"], "lambda_Q")
    r, level = read_rational(data["radius"], "radius"), read_rational(data["level"], "level")
    stated = {k: read_rational(v, k) for k, v in data["flow"].items()}
    if not r > 0 or not lambda_Q > 0:
        return False, "the radius and lambda_Q must be > 0"

    if set(stated) != set(FLOW_FIGURES):
        return False, "the flow figures must be " + ", ".join(FLOW_FIGURES)
    claimed = FlowBounds(**stated)

    def run() -> Decrease | str:
        linear = sampled_parts(*parts, model.period)
        decrease = decrease_of(P, linear.AT, lambda_Q)
        if isinstance(decrease, str):
            return decrease
        if level_of(P, lambda_P, r) is None:
            return "P - lambda_P I >= 0 is not proved"
        if not level <= lambda_P * r * r:
            return f"the level {level} exceeds lambda_P r^2 = {lambda_P * r * r}: {{V <= level}} may leave the ball"
        w = weights(linear, P)
        if w is None:
            return "P's Cholesky factor is not proved in ball arithmetic"
        flow = flow_bounds(TrueLoop(model), model.period, w, r, claimed.rho)
        if isinstance(flow, str):
            return flow
        smaller = [k for k in FLOW_FIGURES if k != "rho" and getattr(claimed, k) < getattr(flow, k)]
        if smaller:
            return f"the stated flow figure(s) {', '.join(smaller)} are below the bounds re-derived"
        if not decrease.margin(claimed, r) > 0:
            return "V's decrease margin is not > 0 on the stated ball"
        return decrease

    decrease = _with_precision(bits, run)
    if isinstance(decrease, str):
        return False, decrease
    why = ("V(Phi_T(x)) < V(x) on {V <= level} re-derived in ball arithmetic on the true flow over one period "
           f"(|R(e)| <= {float(claimed.L2):.4g} |e|^2 on |e| <= {float(r):.4g}); between samples |x(t) - x_eq| <= "
           f"{float(claimed.Ce):.4g} |x(t_k) - x_eq|")
    numbers = _numbers(model, Found(P, lambda_P, decrease, r, claimed, level))
    for key in numbers:
        if c.get(key) != numbers[key]:
            return False, f"the figure {key} = {c.get(key)!r} is not the certificate's ({numbers[key]!r})"
    return True, why


__all__ = ["KIND", "METHOD", "FIGURES", "FLOW_FIGURES", "LinearParts", "Weights", "weights", "FlowBounds", "Decrease", "Found", "TrueLoop", "flow_bounds", "sampled_parts",
           "stein_margin", "decrease_of", "level_of", "search", "roa", "verify", "upper"]

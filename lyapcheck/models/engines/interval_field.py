"""The true loop (with its functions) in rigorous ball arithmetic, with first and second derivatives.

A closed loop with ``sin``, ``sqrt``, ``sat``, ... is evaluated over a box of states with
python-flint's ``arb`` balls: every value computed encloses the exact value at every point of the
box (outward rounding included), so ``g < 0`` for a ball ``g`` proves the inequality at every point.
Derivatives are carried forward by :class:`Jet` (value, gradient, Hessian, each a ball) through the
chain rule, with each function's exact first and second derivatives; where a function is not
differentiable on the ball (``abs`` or ``sat`` across a kink, ``sqrt`` of a ball reaching 0) the
derivatives are dropped, and whatever needed them is simply not proved.

The loop is read from its recasting (:class:`lyapcheck.models.language.recast.RecastSystem`): the states,
then each auxiliary computed from its argument (a polynomial in the states and earlier auxiliaries)
by its function, then each state's right-hand side (a ratio of polynomials in all of them). This
is the model's own field, not the recast polynomial one: no relation is used.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Sequence, Union

import flint

from lyapcheck.models.language.recast import RecastSystem
from lyapcheck.sos.polynomials import Poly, Ring

Ball = Any  # flint.arb
Number = Union["Jet", Any]


def ball(q: Fraction | int) -> Ball:
    """``q`` as a ball (exact when ``q`` is dyadic, else the tightest ball at 53 bits)."""
    q = Fraction(q)
    return flint.arb(flint.fmpq(q.numerator, q.denominator))


class Jet:
    """A function of the states on a box: enclosures of its value, gradient and Hessian there.

    ``grad`` is ``None`` when the function is not known to be differentiable on the box, ``hess``
    when not twice; both are dropped by any operation with a jet that lacks them.
    """

    __slots__ = ("value", "grad", "hess")

    def __init__(self, value: Ball, grad: list[Ball] | None = None, hess: list[list[Ball]] | None = None) -> None:
        self.value = value
        self.grad = grad
        self.hess = hess if grad is not None else None

    @staticmethod
    def variable(value: Ball, index: int, n: int, order: int) -> "Jet":
        zero = flint.arb(0)
        grad = [flint.arb(1) if i == index else zero for i in range(n)] if order >= 1 else None
        hess = [[zero] * n for _ in range(n)] if order >= 2 else None
        return Jet(value, grad, hess)

    @staticmethod
    def constant(value: Ball, n: int, order: int) -> "Jet":
        zero = flint.arb(0)
        return Jet(value, [zero] * n if order >= 1 else None, [[zero] * n for _ in range(n)] if order >= 2 else None)

    def __add__(self, other: Number) -> "Jet":
        if not isinstance(other, Jet):
            return Jet(self.value + other, self.grad, self.hess)
        grad = [a + b for a, b in zip(self.grad, other.grad)] if self.grad is not None and other.grad is not None \
            else None
        hess = [[a + b for a, b in zip(r, s)] for r, s in zip(self.hess, other.hess)] \
            if self.hess is not None and other.hess is not None else None
        return Jet(self.value + other.value, grad, hess)

    __radd__ = __add__

    def __neg__(self) -> "Jet":
        return self.scaled(flint.arb(-1))

    def __sub__(self, other: Number) -> "Jet":
        return self + (-other)

    def __rsub__(self, other: Number) -> "Jet":
        return (-self) + other

    def scaled(self, c: Ball) -> "Jet":
        return Jet(self.value * c, None if self.grad is None else [c * a for a in self.grad],
                   None if self.hess is None else [[c * a for a in r] for r in self.hess])

    def __mul__(self, other: Number) -> "Jet":
        if not isinstance(other, Jet):
            return self.scaled(other)
        a, b = self, other
        grad = hess = None
        if a.grad is not None and b.grad is not None:
            grad = [a.value * gb + b.value * ga for ga, gb in zip(a.grad, b.grad)]
            if a.hess is not None and b.hess is not None:
                n = len(grad)
                hess = [[a.value * b.hess[i][j] + b.value * a.hess[i][j] + a.grad[i] * b.grad[j] + a.grad[j] * b.grad[i]
                         for j in range(n)] for i in range(n)]
        return Jet(a.value * b.value, grad, hess)

    __rmul__ = __mul__

    def composed(self, f: Ball, df: Ball | None, d2f: Ball | None) -> "Jet":
        """``phi(self)`` given ``phi``, ``phi'`` and ``phi''`` at the value (``None``: not differentiable)."""
        if df is None or self.grad is None:
            return Jet(f)
        grad = [df * g for g in self.grad]
        hess = None
        if d2f is not None and self.hess is not None:
            n = len(grad)
            hess = [[df * self.hess[i][j] + d2f * self.grad[i] * self.grad[j] for j in range(n)] for i in range(n)]
        return Jet(f, grad, hess)


def apply(function: str, u: Number, limit: Fraction | None = None) -> Number:
    """``function(u)`` for a ball or a jet, with the derivatives where they exist on the whole ball."""
    x = u.value if isinstance(u, Jet) else u
    one = flint.arb(1)
    df: Ball | None
    d2f: Ball | None
    if function == "sin":
        s, c = x.sin(), x.cos()
        f, df, d2f = s, c, -s
    elif function == "cos":
        s, c = x.sin(), x.cos()
        f, df, d2f = c, -s, -c
    elif function == "exp":
        f = x.exp()
        df = d2f = f
    elif function == "sqrt":
        f = x.sqrt()
        df = d2f = None
        if x > 0:
            df = one / (2 * f)
            d2f = -one / (4 * f * f * f)
    elif function == "atan":
        f = x.atan()
        w = one / (one + x * x)
        df, d2f = w, -2 * x * w * w
    elif function == "tanh":
        f = x.tanh()
        df = one - f * f
        d2f = -2 * f * df
    elif function == "abs":
        f = abs(x)
        df, d2f = (one, flint.arb(0)) if x > 0 else (-one, flint.arb(0)) if x < 0 else (None, None)
    elif function == "sat":
        assert limit is not None
        L = ball(limit)
        f = x.min(L).max(-L)
        df, d2f = (one, flint.arb(0)) if (x < L and x > -L) else \
            (flint.arb(0), flint.arb(0)) if (x > L or x < -L) else (None, None)
    elif function == "reciprocal":
        f = one / x
        df, d2f = -f * f, 2 * f * f * f
    else:  # pragma: no cover - the recaster makes no other auxiliary
        raise ValueError(f"no ball version of {function}")
    if not isinstance(u, Jet):
        return f
    return u.composed(f, df, d2f)


class CompiledPoly:
    """A polynomial of a ring ready to be evaluated on balls or jets (its coefficients as balls)."""

    def __init__(self, ring: Ring, p: Poly) -> None:
        self.terms = [(ball(c), [(i, k) for i, k in enumerate(m) if k]) for m, c in ring.terms(p).items()]
        self.degrees = [0] * ring.nvars
        for _, factors in self.terms:
            for i, k in factors:
                self.degrees[i] = max(self.degrees[i], k)

    def __call__(self, values: Sequence[Number | None], zero: Number) -> Number:
        powers: dict[int, list[Number]] = {}
        for i, d in enumerate(self.degrees):
            if d:
                x = values[i]
                assert x is not None
                row = [x]
                for _ in range(d - 1):
                    row.append(row[-1] * x)
                powers[i] = row
        total = zero
        for c, factors in self.terms:
            term: Number = c
            for i, k in factors:
                term = powers[i][k - 1] * term
            total = term + total
        return total


class BallLoop:
    """The true loop of a recast system, evaluated on balls or jets of the state deviations.

    ``fixed``: balls for the system's last states, which are not states of the loop but its
    disturbances, recast as states without a flow (:attr:`lyapcheck.models.language.recast.RecastModel.robust`);
    every value then holds for every disturbance value in those balls. ``n`` is the loop's own states.
    """

    def __init__(self, system: RecastSystem, fixed: Sequence[Ball] = ()) -> None:
        self.system = system
        ring = system.ring
        self.n = system.n - len(fixed)
        self.fixed = list(fixed)
        self.equilibrium = [ball(system.values[s]) for s in system.states[:self.n]]
        self.auxiliaries = [(a.function, a.limit, a.radicand,
                             None if a.argument is None else CompiledPoly(ring, a.argument))
                            for a in system.auxiliaries]
        own = system.field[:self.n]
        self.numerators = [CompiledPoly(ring, r.numerator) for r in own]
        self.denominators = [None if (r.denominator.is_constant() and r.denominator == ring.constant(1))
                             else CompiledPoly(ring, r.denominator) for r in own]

    def variables(self, z: Sequence[Number]) -> list[Number]:
        """Every variable of the recasting at the state deviations ``z``: ``x = x_eq + z``, the
        disturbances' balls, then the auxiliaries."""
        values: list[Number] = [e + zi for e, zi in zip(self.equilibrium, z)] + list(self.fixed)
        zero = flint.arb(0)
        for function, limit, radicand, argument in self.auxiliaries:
            if argument is None:  # a constant root
                values.append(flint.arb(radicand).sqrt())
                continue
            values.append(apply(function, argument(values, zero), limit))
        return values

    def field(self, z: Sequence[Number]) -> list[Number]:
        """``x'`` at ``x_eq + z``."""
        values = self.variables(z)
        zero = flint.arb(0)
        out: list[Number] = []
        for num, den in zip(self.numerators, self.denominators):
            f = num(values, zero)
            if den is not None:
                f = apply("reciprocal", den(values, zero)) * f
            out.append(f)
        return out


class _PolynomialBank:
    """Polynomials in the state deviations evaluated together: their monomials' values at a point
    are computed once and one ball matrix product gives every polynomial (python-flint's arb_mat)."""

    def __init__(self, ring: Ring, n: int, polys: Sequence[Poly]) -> None:
        monomials = sorted({m[:n] for p in polys for m in ring.terms(p)}, key=lambda m: (sum(m), m))
        where = {m: k for k, m in enumerate(monomials)}
        self.monomials = monomials
        self.degrees = [max((m[i] for m in monomials), default=0) for i in range(n)]
        rows = [[flint.arb(0)] * len(monomials) for _ in polys]
        for r, p in enumerate(polys):
            for m, c in ring.terms(p).items():
                if any(m[n:]):
                    raise ValueError("a V over the states only is evaluated here")
                rows[r][where[m[:n]]] = ball(c)
        self.matrix = flint.arb_mat(rows) if rows and monomials else None
        self.count = len(polys)

    def __call__(self, z: Sequence[Ball]) -> list[Ball]:
        if self.matrix is None:
            return [flint.arb(0)] * self.count
        powers = []
        for zi, d in zip(z, self.degrees):
            row = [flint.arb(1)]
            for _ in range(d):
                row.append(row[-1] * zi)
            powers.append(row)
        column = []
        for m in self.monomials:
            v = powers[0][m[0]]
            for i in range(1, len(m)):
                if m[i]:
                    v = v * powers[i][m[i]]
            column.append([v])
        out = self.matrix * flint.arb_mat(column)
        return [out[r, 0] for r in range(self.count)]


class LieDerivative:
    """``g(z) = grad V(z) . f(x_eq + z)`` for a ``V`` over the state deviations, on balls, or as a
    :class:`Jet`: ``V``'s partial derivatives up to the third are exact polynomials evaluated on the
    balls, and only the field is carried as a jet (far fewer operations than a jet of ``V`` itself)."""

    def __init__(self, loop: BallLoop, ring: Ring, V: Poly) -> None:
        self.loop = loop
        n = self.n = loop.n
        first = [V.derivative(i) for i in range(n)]
        second = [[first[i].derivative(j) for j in range(n)] for i in range(n)]
        third = [[[second[i][j].derivative(k) for k in range(n)] for j in range(n)] for i in range(n)]
        self.v = _PolynomialBank(ring, n, [V])
        self.first = _PolynomialBank(ring, n, first)
        self.upto_second = _PolynomialBank(ring, n, first + [p for row in second for p in row])
        self.upto_third = _PolynomialBank(ring, n, first + [p for row in second for p in row]
                                          + [p for plane in third for row in plane for p in row])

    def value_of_v(self, z: Sequence[Ball]) -> Ball:
        return self.v(z)[0]

    def gradient_of_v(self, z: Sequence[Ball]) -> list[Ball]:
        return self.first(z)

    def __call__(self, z: Sequence[Ball]) -> Ball:
        f = self.loop.field(z)
        total = flint.arb(0)
        for d, fi in zip(self.first(z), f):
            total = d * fi + total
        return total

    def jet(self, z: Sequence[Ball], order: int) -> Jet:
        """``g`` with its gradient (``order`` 1) and Hessian (2) enclosed over the balls ``z``."""
        n = self.n
        f = [fi if isinstance(fi, Jet) else Jet.constant(fi, n, order)  # a constant right-hand side
             for fi in self.loop.field([Jet.variable(zi, i, n, order) for i, zi in enumerate(z)])]
        values = (self.upto_third if order >= 2 else self.upto_second)(z)
        p = values[:n]
        dp = [values[n + i * n: n + (i + 1) * n] for i in range(n)]
        zero = flint.arb(0)
        value = zero
        for pi, fi in zip(p, f):
            value = value + pi * fi.value
        grads = [fi.grad for fi in f]
        if any(g is None for g in grads):
            return Jet(value)
        fg: list[list[Ball]] = [g for g in grads if g is not None]
        grad = []
        for k in range(n):
            t = zero
            for i in range(n):
                t = t + dp[i][k] * f[i].value + p[i] * fg[i][k]
            grad.append(t)
        hessians = [fi.hess for fi in f]
        if order < 2 or any(h is None for h in hessians):
            return Jet(value, grad)
        fh: list[list[list[Ball]]] = [h for h in hessians if h is not None]
        base = n + n * n
        hess = [[zero] * n for _ in range(n)]
        for k in range(n):
            for m in range(k, n):
                t = zero
                for i in range(n):
                    t = (t + values[base + (i * n + k) * n + m] * f[i].value + dp[i][k] * fg[i][m]
                         + dp[i][m] * fg[i][k] + p[i] * fh[i][k][m])
                hess[k][m] = hess[m][k] = t
        return Jet(value, grad, hess)


class RecastLieDerivative:
    """``g`` for a ``V`` over the states and the smooth auxiliaries (``1 - cos(theta) + omega^2/2``):
    ``V' = G / D`` with ``G = grad V . N`` from the recasting's flows ``N / D`` (computed exactly by
    the caller), evaluated on the true variables ``(x, a(x))`` carried as jets of the states, so the
    chain rule through each function is the jets' own."""

    def __init__(self, loop: BallLoop, ring: Ring, V: Poly, G: Poly, D: Poly) -> None:
        self.loop = loop
        self.n = loop.n
        self.V = CompiledPoly(ring, V)
        self.G = CompiledPoly(ring, G)
        self.D = None if D == ring.constant(1) else CompiledPoly(ring, D)
        values = loop.system.values
        self.shift = [ball(values[name]) if name in values else None for name in ring.names]

    def _deviations(self, z: Sequence[Number]) -> list[Number]:
        out = []
        for v, s in zip(self.loop.variables(z), self.shift):
            out.append(v if s is None else v - s)
        return out

    def _ratio(self, dev: list[Number]) -> Number:
        zero = flint.arb(0)
        g = self.G(dev, zero)
        return g if self.D is None else apply("reciprocal", self.D(dev, zero)) * g

    def value_of_v(self, z: Sequence[Ball]) -> Ball:
        return self.V(self._deviations(z), flint.arb(0))

    def gradient_of_v(self, z: Sequence[Ball]) -> list[Ball]:
        v = self.V(self._deviations([Jet.variable(zi, i, self.n, 1) for i, zi in enumerate(z)]), flint.arb(0))
        if not isinstance(v, Jet):
            return [flint.arb(0)] * self.n
        return v.grad if v.grad is not None else [flint.arb(0, float("inf"))] * self.n

    def __call__(self, z: Sequence[Ball]) -> Ball:
        return self._ratio(self._deviations(z))

    def jet(self, z: Sequence[Ball], order: int) -> Jet:
        g = self._ratio(self._deviations([Jet.variable(zi, i, self.n, order) for i, zi in enumerate(z)]))
        return g if isinstance(g, Jet) else Jet.constant(g, self.n, order)


def negative_definite(H: list[list[Ball]]) -> bool:
    """Every symmetric matrix whose lower triangle lies in the balls of ``H`` is negative definite:
    the Cholesky factorization of ``-H`` in ball arithmetic succeeds with every pivot > 0."""
    n = len(H)
    A = [[-H[i][j] for j in range(n)] for i in range(n)]
    L = [[flint.arb(0)] * n for _ in range(n)]
    for j in range(n):
        s = A[j][j]
        for k in range(j):
            s = s - L[j][k] * L[j][k]
        if not s > 0:
            return False
        L[j][j] = s.sqrt()
        for i in range(j + 1, n):
            t = A[i][j]
            for k in range(j):
                t = t - L[i][k] * L[j][k]
            L[i][j] = t / L[j][j]
    return True


__all__ = ["Jet", "apply", "ball", "BallLoop", "CompiledPoly", "LieDerivative", "RecastLieDerivative",
           "negative_definite"]

"""``V' < 0`` on an ellipsoid ``{z^T P z <= level}`` of a loop with any number of states, by ball
arithmetic on cells of the ellipsoid's own coordinates (issue 42, item 1).

The exact-boundary claim of :mod:`lyapcheck.models.engines.interval_region` (``V = z^T P z`` positive
definite, its faces proved exactly) needs ``g = V' < 0`` on the ellipsoid ``E = {z^T P z <= level}``
except at the equilibrium. Bisecting the box around ``E`` in the states' own axes (the route of 1 to 3
states) spends nearly all of its cells outside a thin, tilted ``E`` (an LQR cost-to-go's ``P`` has a
condition number in the thousands) and bounds ``g`` by plain intervals. Here instead:

1. **Coordinates.** ``z = M y`` with ``M`` a float (so exactly dyadic) approximation of ``L^-T``
   (``P = L L^T``), and ``Q = M^T P M`` computed exactly in rationals: ``E`` is ``{y^T Q y <= level}``, a
   near-ball, inside the box ``|y_i| <= h_i`` with ``level (Q^-1)_ii <= h_i^2`` (exact). Any ``M`` works:
   nothing rests on it being close to ``L^-T``. Cells are boxes in ``y``; a cell whose lower bound of
   ``y^T Q y`` (ball arithmetic) exceeds ``level`` is outside ``E`` and dropped; a cell is split across
   its widest side, which in ``y`` is the widest in the ellipsoid's metric.
2. **The Hessian zone, exactly.** ``g(0) = 0`` and ``grad g(0) = 0`` (exact, as for the local box), so
   ``g(z) = int_0^1 (1 - t) z^T H(t z) z dt``. Cells are taken in increasing order of their lower
   bound of ``y^T Q y``; each gets an enclosure of the Hessian ``H`` of ``g`` over it and a Cholesky
   test of ``C^T H C`` (``C`` a float preconditioner: ``C^T H C`` negative definite for every matrix of
   the enclosure forces ``C`` invertible and ``H`` negative definite). At the first cell that fails at
   the finest width of this phase (HESSIAN_ZONE_MIN_WIDTH), ``level_1`` is the least lower bound of
   ``y^T Q y`` over it and the cells not taken yet: every point of ``E_1 = {y^T Q y < level_1}`` lies in
   a cell where ``H`` is negative definite, ``E_1`` is convex and contains the equilibrium, so ``g < 0``
   on ``E_1`` except at the equilibrium (when no cell fails, ``E_1`` is ``E`` itself). A cell whose
   image lies in the local box ``N`` (the same argument, proved before) needs nothing either.
3. **The shell, by Taylor forms.** Every other cell that meets ``E`` gets
   ``g(m) + grad g(m) . t + t^T H t / 2`` (``m`` its centre, ``|t_i| <= r_i``, ``H`` enclosed over the
   cell or over an ancestor, which contains it: Taylor's theorem with the Lagrange remainder), in
   ``y``; where ``H`` is proved negative definite, ``t^T H t <= 0`` and ``g(m) + grad g(m) . t`` bounds
   ``g``. A cell that fails is split across the side whose width adds most to the bound (where the
   margin is thin), not merely the widest. A centre with ``g >= 0`` proved inside ``E`` ends the
   proof: the claim is false at this level. Three economies (issue 42), none of which a claim rests on:
   a cell meeting the boundary of ``E`` first loses its outer slabs proved outside ``E`` (:func:`_trim`);
   a cell whose bound fails already at first order (``g(m) + grad g(m) . t``, which no Hessian lowers)
   gets no Hessian of its own and is cut at once into the pieces its halvings would reach
   (:func:`_pieces`, at most 4); and the innermost and outermost cells go by turns, with an attempt
   given up near the finest width where ``V'`` is too close to 0 for it (:func:`_at_the_bottom`), so
   that a level too large fails within a few thousand cells. The cells examined by an attempt that succeeds do not
   depend on the order.
4. **The factored test**, on a shell cell whose Taylor form fails (before it is split). ``f(0) = 0``, so
   ``f(z) = Abar(z) z`` with ``Abar(z) = int_0^1 J(t z) dt`` and ``g(z) = z^T (Abar^T P + P Abar) z``
   exactly: where every symmetric matrix of an enclosure of ``M^T (Abar^T P + P Abar) M`` over the cell is
   negative definite, ``g < 0`` on the cell except at the equilibrium, whatever its position (cells holding
   the equilibrium included), a claim on the cell alone. ``t`` is cut into K slabs (1 for a cell holding the
   equilibrium, about its distance over its width elsewhere, FACTORED_MAX_SLABS at most); on each,
   ``int_slab J(t z) dt`` lies in ``J(t_m z) / K`` plus ``[-1, 1] rad(G) / (4 K^2)``, ``G`` the derivative in
   ``t`` of ``J(t z)`` enclosed over the slab (the midpoint form: ``int (t - t_m) dt = 0``; without second
   derivatives on the slab, ``J`` enclosed over it). A field with no first derivative on a slab (a kink, a
   pole) fails the test. A geometry of another ``V`` or another ``g`` turns it off (``factored``).

5. **The polynomial model** (:mod:`lyapcheck.models.engines.polynomial_cells`) comes first on a shell cell
   where the loop is a nominal one whose functions are sines and cosines of the states and ``P`` is
   ill-conditioned (condition number at least POLY_CELL_MIN_CONDITION): ``V'`` times the flows' positive
   denominator is an exact polynomial in ``y`` within a proved error on the ellipsoid's box, bounded on a
   cell by its expansion about the cell's centre (its quadratic part dropped where proved negative
   definite). No enclosure of the field over the cell enters, so the tilted coordinates cost nothing: the
   acrobot's shaped V aimed at the box (condition number 48,000) is proved at level 1.0 in about 7,000
   cells, where the ball-arithmetic tests stopped below 0.001. A cell it fails goes on to the tests of
   parts 3 and 4 (the cart-pole's LQR ``z'Sz``, condition number 48,500: 6,500 cells at level 0.387 with
   both, 19,000 with the model alone, 12,000 without it). The model also proves a ball ``inner <= |y| <= rho`` about the
   equilibrium (:func:`~lyapcheck.models.engines.polynomial_cells.decreasing_ball`, ``|y| < inner`` inside
   ``N``'s or ``E_1``'s ellipsoid), whose cells the zone's phase and the shell skip; a cell whose centre has
   ``V' > 0`` proved by the model ends the attempt. Where the ball tests prove none of the first
   BALL_AFTER_MODEL_TRIAL cells the model failed, only every BALL_AFTER_MODEL_EVERY-th such cell gets them
   (all again after one they prove); the others are split across the side whose width adds most to the
   model's bound. A choice of work only: every cell is still proved by one test or split. On a
   well-conditioned ``P`` (the cart-pole's shaped one, 584) parts 3 and 4 alone cost less.

The enclosures keep the ellipsoid's correlations: ``grad V = 2 P z`` is enclosed as ``2 W y`` with
``W = P M`` exact, never as ``P`` times the ball enclosure of ``M`` times a cell (whose corners lie far
outside the tilted cell: for an LQR ``P`` that box product is hundreds of times too wide), and the
matrix products group the exact factors first (``M^T P = W^T``). Only the field's own derivatives are
enclosed over the box around ``M`` times the cell (the chain rule in ball arithmetic, each function's
exact derivatives, :class:`~lyapcheck.models.engines.interval_field.Jet`).

The cells are deterministic (the same claim gives the same cells), so ``verify`` repeats the proof
cell for cell from the certificate alone. The work is bounded by a count of cells.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

import flint
import numpy as np

from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative, ball, negative_definite
from lyapcheck.models.engines.polynomial_cells import (PolynomialModel, cell_bound, decreasing_ball, polynomial_model,
                                                      refusal)
from lyapcheck.tolerances import FACTORED_MAX_SLABS, FACTORED_REACH, POLY_CELL_MIN_CONDITION

#: the finest split of the Hessian zone's phase: a cell whose Hessian is not proved negative definite
#: is split while its widest side is above this fraction of the ellipsoid's box (then it bounds the zone)
HESSIAN_ZONE_MIN_WIDTH: Final = Fraction(1, 8)
#: the finest split of the shell's phase, as a fraction of the ellipsoid's box in each coordinate
SHELL_MIN_WIDTH: Final = Fraction(1, 2 ** 12)
#: the outer slabs a shell cell that meets the boundary of ``{V <= level}`` loses before its Taylor form:
#: on each side the outer half, quarter, ... of the cell, down to 2^-TRIM_DEPTH of it, the largest proved
#: outside the set (one enclosure of V each, far cheaper than the field's)
TRIM_DEPTH: Final = 3
#: the most halvings by which a shell cell failing at first order is cut at once (2^this pieces)
MAX_PIECES_HALVINGS: Final = 2
#: a shell cell within 2^this of the finest width whose first-order bound fails even at the finest width
#: around its centre ends the attempt (V' too close to 0 there for the finest cells)
BOTTOM_HALVINGS: Final = 3
#: where the polynomial model runs (part 5), the ball tests of parts 3 and 4 on the cells it fails: once the first
#: BALL_AFTER_MODEL_TRIAL such cells gave them none, only every BALL_AFTER_MODEL_EVERY-th gets them, until one
#: proves a cell (then all again). On the acrobot's shaped V they proved none of 2,486 (level 0.56) to 4,970
#: (0.985) and took half the time; on the cart-pole's z'Sz 2 to 15 % of 1,000 to 7,000, the first 500 of level
#: 0.68 none (stopping them for good there: level 0.58 instead of 0.68)
BALL_AFTER_MODEL_TRIAL: Final = 500
BALL_AFTER_MODEL_EVERY: Final = 8

Cell = tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class Whitening:
    """``z = M y`` and ``Q = M^T P M`` (exact), the box ``|y_i| <= half_i`` around ``{y^T Q y <= level}``."""

    M: list[list[float]]
    Q: list[list[Fraction]]
    half: list[Fraction]


@dataclass
class EllipsoidProof:
    """What :func:`prove_ellipsoid` established: ``ok`` or why not, the cells it took, the level of the
    Hessian zone (``level_1``), and ``V`` at a point of ``E`` where ``g >= 0`` was proved (or None)."""

    ok: bool
    why: str
    cells: int
    hessian_level: Fraction | None
    counterexample_v: float | None = None


#: significant bits of each entry of M (a short dyadic: M y of a dyadic cell corner is then exact in arb)
M_BITS: Final = 24


def _short(x: Fraction, bits: int = M_BITS) -> Fraction:
    """``x`` rounded to ``bits`` significant bits (a dyadic; exact integer arithmetic, the same everywhere)."""
    if x == 0:
        return x
    e = bits - (abs(x.numerator).bit_length() - x.denominator.bit_length())
    return Fraction(round(x * Fraction(2) ** e)) / Fraction(2) ** e


def _inverse_root(P: list[list[Fraction]]) -> list[list[Fraction]] | None:
    """A dyadic ``M`` near ``L^-T D^-1/2`` for ``P = L D L^T`` (unit triangular ``L``, computed exactly),
    so that ``M^T P M`` is near the identity; None when a pivot is not > 0. Rationals and integer square
    roots only, so that ``verify`` on any machine gets the same ``M`` (hence the same cells)."""
    from math import isqrt

    from lyapcheck.exact import inverse, ldl

    n = len(P)
    found = ldl(P)
    if found is None or any(d <= 0 for d in found[1]):
        return None
    L, D = found
    inv = inverse(L)  # L^-1, unit lower triangular
    scale = 2 ** 60
    root = [Fraction(isqrt(int(scale * scale / d)), scale) for d in D]  # about 1 / sqrt(D_j)
    return [[_short(inv[j][i] * root[j]) for j in range(n)] for i in range(n)]  # M_ij = (L^-T)_ij root_j


def whitening(P: list[list[Fraction]], level: Fraction) -> Whitening | None:
    """The coordinates of the module docstring (part 1) for a positive definite ``P``, or None."""
    from lyapcheck.exact import inverse
    from lyapcheck.exact import dyadic_ceil
    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    Mq = _inverse_root(P)
    if Mq is None:
        return None
    Q = [[sum((Mq[k][i] * P[k][l] * Mq[l][j] for k in range(n) for l in range(n)), Fraction(0))
          for j in range(n)] for i in range(n)]
    if not is_positive_definite(Q):
        return None
    Qinv = inverse(Q)
    half = []
    for i in range(n):
        h = dyadic_ceil(Fraction(float(level * Qinv[i][i]) ** 0.5 * 1.001), 16)
        while h * h < level * Qinv[i][i]:  # exact: the ellipsoid's extent along y_i is at most h
            h *= 2
        half.append(h)
    return Whitening([[float(x) for x in row] for row in Mq], Q, half)


class _Geometry:
    """Cells of ``y`` and what ball arithmetic says of them: ``z = M y``, ``y^T Q y``, ``g`` and its
    derivatives in ``y``.

    ``g = grad V . f = 2 (W y) . f(M y)`` with ``W = P M`` (exact): ``grad V`` is enclosed from ``y`` itself,
    not from the ball enclosure of ``M`` times a cell (whose corners lie far outside the tilted cell:
    ``P`` times that box is hundreds of times too wide for an LQR ``P``), and the products of matrices
    are taken with the exact ones grouped first (``M^T P`` is ``W^T``, small, where ``|M^T| |P|`` is not)."""

    def __init__(self, w: Whitening, P: list[list[Fraction]], lie: LieDerivative) -> None:
        self.n = n = len(w.half)
        self.loop = lie.loop
        Mq = [[Fraction(x) for x in row] for row in w.M]
        W = [[sum((P[i][k] * Mq[k][j] for k in range(n)), Fraction(0)) for j in range(n)] for i in range(n)]
        self.M = [[flint.arb(x) for x in row] for row in w.M]  # exact (floats)
        self.Mmat = flint.arb_mat(self.M)
        self.Mt = self.Mmat.transpose()
        self.W2 = [[ball(2 * x) for x in row] for row in W]  # grad V = 2 W y
        self.W2t = flint.arb_mat(self.W2).transpose()
        self.P2 = [[ball(2 * x) for x in row] for row in P]  # the Hessian of V
        self.Q = [[ball(x) for x in row] for row in w.Q]
        self.widths = [2 * float(h) for h in w.half]

    def z_of(self, y: list[Any]) -> list[Any]:
        return [sum((self.M[i][j] * y[j] for j in range(self.n)), flint.arb(0)) for i in range(self.n)]

    def quadratic(self, cell: Cell) -> Any:
        """An enclosure of ``y^T Q y`` over the cell (squares enclosed as squares, not as products)."""
        n = self.n
        total = flint.arb(0)
        for i, (a, b) in enumerate(cell):
            near = 0.0 if a <= 0 <= b else min(abs(a), abs(b))
            far = max(abs(a), abs(b))
            square = (flint.arb(near) * flint.arb(near)).union(flint.arb(far) * flint.arb(far))
            total += self.Q[i][i] * square
        ys = [flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell]
        for i in range(n):
            for j in range(i + 1, n):
                total += 2 * self.Q[i][j] * ys[i] * ys[j]
        return total

    def _field(self, ys: list[Any], order: int) -> tuple[list[Any], list[Any]] | None:
        """``grad V`` and the field as jets in ``z`` (up to ``order``) over the balls ``ys`` of ``y``, or None
        where the field is not differentiable that often on them."""
        from lyapcheck.models.engines.interval_field import Jet

        n = self.n
        Z = self.z_of(ys)
        f = [fi if isinstance(fi, Jet) else Jet.constant(fi, n, order)
             for fi in self.loop.field([Jet.variable(zi, i, n, order) for i, zi in enumerate(Z)])]
        if any(fi.grad is None or (order >= 2 and fi.hess is None) for fi in f):
            return None
        p = [sum((self.W2[i][j] * ys[j] for j in range(n)), flint.arb(0)) for i in range(n)]
        return p, f

    def hessian_y(self, lie: LieDerivative, cell: Cell) -> list[list[Any]] | None:
        """The Hessian of ``g`` in ``y`` enclosed over the cell, or None: ``M^T (P Jf + Jf^T P) M``
        ``+ M^T (sum_i p_i Hf_i) M`` with ``p = 2 W y`` (``Jf``, ``Hf_i``: the field's derivatives in ``z``
        over the ball enclosure of ``M`` times the cell)."""
        n = self.n
        got = self._field([flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell], 2)
        if got is None:
            return None
        p, f = got
        J = flint.arb_mat([fi.grad for fi in f])  # J[i, k] = d f_i / d z_k
        A = self.W2t * J * self.Mmat  # M^T (2 P) Jf M, with M^T 2P = 2 W^T exact
        S = [[sum((p[i] * f[i].hess[k][m] for i in range(n)), flint.arb(0)) for m in range(n)] for k in range(n)]
        B = self.Mt * flint.arb_mat(S) * self.Mmat
        H = [[A[i, j] + A[j, i] + B[i, j] for j in range(n)] for i in range(n)]
        if not all(h.is_finite() for row in H for h in row):
            return None
        return H

    #: ``g`` is the Lie derivative of ``V = z^T P z`` along the loop's field, the premise of
    #: :meth:`factored_negative`; a geometry with another ``V`` or another ``g`` turns the test off
    factored: bool = True

    def slabs(self, cell: Cell) -> int:
        """How many slabs of ``t`` the factored test of the cell takes: 1 for a cell holding the
        equilibrium (``t C`` lies in ``C`` for every ``t`` in [0, 1]), else about its distance from the
        equilibrium over its width (so that a slab's hull ``[a, b] C`` is not much wider than the cell), a
        power of 2 up to FACTORED_MAX_SLABS (floats of the dyadic cell: the same on every machine)."""
        if all(a <= 0 <= b for a, b in cell):
            return 1
        distance = max(max(-a, b) for a, b in cell)
        width = max(b - a for a, b in cell)
        k = 1
        while k < FACTORED_MAX_SLABS and k * width < distance:
            k *= 2
        return k

    def _jets(self, zs: list[Any], order: int) -> list[Any] | None:
        """The field as jets in ``z`` (up to ``order``) over the balls ``zs``, or None where it has no first
        derivatives there (the second are None where it has none)."""
        from lyapcheck.models.engines.interval_field import Jet

        n = self.n
        f = [fi if isinstance(fi, Jet) else Jet.constant(fi, n, order)
             for fi in self.loop.field([Jet.variable(zi, i, n, order) for i, zi in enumerate(zs)])]
        return None if any(fi.grad is None for fi in f) else f

    def factored_y(self, cell: Cell) -> list[list[Any]] | None:
        """An enclosure of ``2 M^T (Abar^T P + P Abar) M`` over the cell, ``Abar(z) = int_0^1 Jf(t z) dt``
        (module docstring, part 4), or None where the field is not differentiable on a slab. ``t`` in
        [0, 1] is cut into slabs [k/K, (k+1)/K]; over a slab ``t z`` (``z`` in the cell's z-box) lies in the
        box whose sides are the hulls of the four products of the slab's and the side's ends (``t z`` is
        bilinear), and ``int_slab Jf(t z) dt`` in the midpoint form over it; ``Abar`` is the sum."""
        n = self.n
        K = self.slabs(cell)
        # the z-box of the cell first, then t times it: M (t y) = t (M y), and t times the z-box keeps the
        # cancellations of M y that a y-box of the products t y_i would lose
        Z = [(zi.lower(), zi.upper()) for zi in self.z_of([flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell])]
        zc = [lo.union(hi) for lo, hi in Z]  # the cell's z-box as balls
        total: Any = None
        for k in range(K):
            ta, tb = flint.arb(k) / K, flint.arb(k + 1) / K  # exact: K is a power of 2
            tm = (ta + tb) / 2
            slab = [(ta * lo).union(tb * lo).union(ta * hi).union(tb * hi) for lo, hi in Z]
            f2 = self._jets(slab, 2)
            if f2 is None:
                return None  # a kink or a pole on this slab: the cell is not proved by this test
            if all(fi.hess is not None for fi in f2):
                # the midpoint form: J(t z) = J(tm z) + (t - tm) G with G = d/dt J(s z) at some s of the slab
                # (entry by entry), G_ik = sum_l (d2 f_i / dz_k dz_l) z_l enclosed over the slab; since
                # int (t - tm) dt = 0, int_slab J(t z) dt lies in J(tm z) / K + [-1, 1] rad(G) / (4 K^2)
                fm = self._jets([tm * zi for zi in zc], 1)
                if fm is None:
                    return None
                spread = flint.arb(1) / (4 * K * K)
                unit = flint.arb(0, 1)  # [-1, 1]
                J = flint.arb_mat([[fm[i].grad[m] / K + _deviation(sum(
                    (f2[i].hess[m][l] * zc[l] for l in range(n)), flint.arb(0))) * unit * spread
                    for m in range(n)] for i in range(n)])
            else:  # first derivatives only (a field twice differentiable nowhere on the slab): J over the slab
                J = flint.arb_mat([[g / K for g in fi.grad] for fi in f2])
            total = J if total is None else total + J
        X = self.W2t * total * self.Mmat  # M^T (2 P) Abar M, with M^T 2P = 2 W^T exact
        N = [[X[i, j] + X[j, i] for j in range(n)] for i in range(n)]
        if not all(x.is_finite() for row in N for x in row):
            return None
        return N

    def factored_negative(self, cell: Cell) -> bool:
        """``g < 0`` on the cell except at the equilibrium, by ``g(z) = z^T (Abar^T P + P Abar) z``
        (``f(0) = 0``, so ``f(z) = Abar(z) z``): every symmetric matrix of :meth:`factored_y`'s enclosure is
        proved negative definite. Needs first derivatives of the field only, and holds down to the
        equilibrium, cells holding it included."""
        if not self.factored:
            return False
        N = self.factored_y(cell)
        return N is not None and negative_definite_preconditioned(N)

    def at_centre(self, lie: LieDerivative, cell: Cell) -> tuple[Any, list[Any] | None]:
        """``g`` and its gradient in ``y`` at the cell's centre: ``2 W^T f + M^T Jf^T p``."""
        n = self.n
        ys = [flint.arb((a + b) / 2) for a, b in cell]
        got = self._field(ys, 1)
        if got is None:
            return lie.jet(self.z_of(ys), 0).value, None
        p, f = got
        value = sum((p[i] * f[i].value for i in range(n)), flint.arb(0))
        F = flint.arb_mat([[fi.value] for fi in f])
        Jtp = flint.arb_mat([[sum((f[i].grad[k] * p[i] for i in range(n)), flint.arb(0))] for k in range(n)])
        gy = self.W2t * F + self.Mt * Jtp
        return value, [gy[i, 0] for i in range(n)]

    def v_upper(self, cell: Cell) -> Any:
        """An enclosure of ``V`` over the cell (here ``y^T Q y``)."""
        return self.quadratic(cell)

    def outside(self, q: Any, cell: Cell, c: Any) -> bool:
        """The cell lies outside ``{V <= level}`` (``q``: ``y^T Q y`` enclosed over it, ``c``: the level)."""
        return bool(q > c)

    def zone_outside(self, q: Any, c: Any) -> bool:
        """The Hessian zone's phase may leave the cell out: it lies outside the convex ``{y^T Q y <= level}``."""
        return bool(q > c)

    def negative(self, value: Any, grad: list[Any], H: tuple[list[list[Any]], bool], cell: Cell) -> bool:
        """``g < 0`` on the cell by the Taylor form with ``H`` (enclosed over the cell or an ancestor); when
        ``H`` is proved negative definite, also by ``g(m) + grad . t`` (``t^T H t <= 0``)."""
        if self.taylor_upper(value, grad, H[0], cell) < 0:
            return True
        return H[1] and self.first_order_negative(value, grad, cell)

    def first_order_negative(self, value: Any, grad: list[Any], cell: Cell) -> bool:
        """``g(m) + grad g(m) . t < 0`` for every ``|t_i| <= r_i``: ``g < 0`` on the cell where ``g`` is
        concave there, and otherwise the least a Taylor form's bound can be (its Hessian's terms' enclosures
        contain 0, so they never lower it)."""
        zero = flint.arb(0)
        total = value
        for gi, (a, b) in zip(grad, cell):
            r = flint.arb((b - a) / 2)
            total = total + gi * zero.union(r).union(-r)
        return bool(total < 0)

    def taylor_upper(self, value: Any, grad: list[Any], H: list[list[Any]], cell: Cell) -> Any:
        """An enclosure of ``g`` over the cell, ``g(m) + grad . t + t^T H t / 2`` with ``|t_i| <= r_i``."""
        radii = [flint.arb((b - a) / 2) for a, b in cell]  # exact: dyadic
        zero = flint.arb(0)
        total = value
        for i, gi in enumerate(grad):
            total = total + gi * zero.union(radii[i]).union(-radii[i])
            total = total + H[i][i] * zero.union(radii[i] * radii[i] / 2)
            for j in range(i + 1, self.n):
                p = radii[i] * radii[j]
                total = total + H[i][j] * p.union(-p)
        return total


def uses_model(loop: Any, P: list[list[Fraction]]) -> bool:
    """Whether the cells of ``V = z^T P z`` on the loop (a :class:`BallLoop`) try the polynomial model first
    (module docstring, part 5): a nominal loop whose functions are sines and cosines of the states, a model of
    the allowed size (:func:`~lyapcheck.models.engines.polynomial_cells.refusal`), and ``P`` of condition
    number at least POLY_CELL_MIN_CONDITION. (The model itself may still be refused at a level, where a
    denominator is not proved positive on the ellipsoid's box: the other tests then run.)"""
    return isinstance(loop, BallLoop) and not loop.fixed and loop.n == loop.system.n and \
        refusal(loop.system) is None and _condition(P) >= POLY_CELL_MIN_CONDITION


def _polynomial_model(lie: LieDerivative, P: list[list[Fraction]], w: Whitening) -> PolynomialModel | None:
    """The polynomial model of ``V'`` in the ellipsoid's coordinates (module docstring, part 5), or None where
    it is refused on this ellipsoid's box."""
    found = polynomial_model(lie.loop.system, P, w.M, w.half)
    return None if isinstance(found, str) else found


def _condition(P: list[list[Fraction]]) -> float:
    """``P``'s condition number (floats: it only chooses the tests, :data:`POLY_CELL_MIN_CONDITION`)."""
    eig = np.linalg.eigvalsh(np.array([[float(x) for x in row] for row in P]))
    return float(eig[-1] / eig[0]) if eig[0] > 0 else math.inf


def _model_ball(model: PolynomialModel, lie: LieDerivative, P: list[list[Fraction]], w: Whitening,
                floor: Fraction) -> Fraction:
    """A level ``c`` with ``V' < 0`` on ``{y^T Q y <= c}`` except at the equilibrium, from the model's
    decreasing ball (:func:`decreasing_ball`) about the ball ``|y|^2 < floor / lambda_max(Q)`` inside
    ``{y^T Q y < floor}`` (proved already: ``E_1`` or ``N``'s ellipsoid), or 0. ``{y^T Q y <= c}`` lies in
    ``|y| <= rho`` for ``c = lambda_min(Q) rho^2``; both eigenvalue bounds are proved exactly."""
    from math import isqrt

    from lyapcheck.sos.definiteness import is_positive_definite

    if floor <= 0:
        return Fraction(0)
    n = len(w.Q)
    eig = np.linalg.eigvalsh(np.array([[float(x) for x in row] for row in w.Q]))
    low, high = Fraction(float(eig[0]) * (1 - 1e-9)), Fraction(float(eig[-1]) * (1 + 1e-9))
    if not (low > 0 and is_positive_definite([[w.Q[i][j] - (low if i == j else 0) for j in range(n)] for i in range(n)])
            and is_positive_definite([[(high if i == j else 0) - w.Q[i][j] for j in range(n)] for i in range(n)])):
        return Fraction(0)
    scale = 2 ** 40
    # inner^2 <= floor / high (strictly below: E_1 is open), rho^2 >= the ellipsoid's own extent
    inner = Fraction(isqrt(int(floor / high * (1 - Fraction(1, 2 ** 20)) * scale * scale)), scale)
    largest = max(Fraction(h) for h in w.half)
    rho = decreasing_ball(lie.loop.system, P, w.M, inner, largest)
    return low * rho * rho


def _deviation(g: Any) -> Any:
    """A ball holding ``x - mid(g)`` for every ``x`` in the ball ``g`` (``mid(g)`` exact)."""
    return g - flint.arb(g.mid())


def _inverse_cholesky_transpose(S: list[list[float]]) -> list[list[float]] | None:
    """``L^-T`` for the Cholesky factor ``L`` of ``S`` (``S = L L^T``), in Python floats, None when ``S``
    is not numerically positive definite. Written out rather than numpy's LAPACK on purpose: Python's
    float operations and ``math.sqrt`` are correctly rounded, so every machine gets the same ``C`` and
    ``verify`` repeats a proof cell for cell (LAPACK's blocking and FMA use vary with the machine).
    The proof holds for any ``C``: this only chooses a good one."""
    n = len(S)
    L = [[0.0] * n for _ in range(n)]
    for j in range(n):
        d = S[j][j] - sum(L[j][k] * L[j][k] for k in range(j))
        if not d > 0 or not math.isfinite(d):
            return None
        L[j][j] = math.sqrt(d)
        for i in range(j + 1, n):
            L[i][j] = (S[i][j] - sum(L[i][k] * L[j][k] for k in range(j))) / L[j][j]
    inv = [[0.0] * n for _ in range(n)]  # L^-1, lower triangular, by forward substitution
    for c in range(n):
        for i in range(c, n):
            inv[i][c] = ((1.0 if i == c else 0.0) - sum(L[i][k] * inv[k][c] for k in range(c, i))) / L[i][i]
    if not all(math.isfinite(x) for row in inv for x in row):
        return None
    return [[inv[j][i] for j in range(n)] for i in range(n)]


def negative_definite_preconditioned(H: list[list[Any]]) -> bool:
    """Every symmetric matrix in the enclosure ``H`` is negative definite: the Cholesky test of ``C^T H C``
    with ``C = L^-T`` for the float Cholesky factor ``L`` of ``-mid(H)`` (any ``C``: ``C^T H C`` negative
    definite implies ``C`` invertible, so ``H`` negative definite)."""
    n = len(H)
    mid = [[-(float(H[i][j].mid()) + float(H[j][i].mid())) / 2 for j in range(n)] for i in range(n)]
    C = _inverse_cholesky_transpose(mid)
    if C is None:
        return False
    Cm = flint.arb_mat(C)
    A = Cm.transpose() * flint.arb_mat(H) * Cm
    return negative_definite([[A[i, j] for j in range(n)] for i in range(n)])


def _split(cell: Cell, min_width: list[float], weights: list[float] | None = None) -> tuple[Cell, Cell] | None:
    """The two halves across the widest side (in ``y``, the ellipsoid's metric), or with ``weights``
    across the side of the largest weight times width (what that side adds to the Taylor form's
    bound: the side where the margin is thinnest); None when every side is at the finest width."""
    sides = [i for i in range(len(cell)) if cell[i][1] - cell[i][0] > min_width[i]]
    if not sides:
        return None
    k = max(sides, key=lambda i: (cell[i][1] - cell[i][0]) * (1.0 if weights is None else weights[i]))
    a, b = cell[k]
    m = (a + b) / 2
    return cell[:k] + ((a, m),) + cell[k + 1:], cell[:k] + ((m, b),) + cell[k + 1:]


def _pieces(cell: Cell, min_width: list[float], weights: list[float], margin: float) -> tuple[Cell, ...] | None:
    """A cell whose Taylor form fails already at first order cut at once into the pieces its halvings would
    reach: the side of the largest weight times width halved (as :func:`_split`) until the spread
    ``sum_i weight_i r_i`` falls below ``margin`` (``-g`` at the centre, floats: an estimate that only
    chooses the cuts) or MAX_PIECES_HALVINGS halvings are made; the pieces between are never examined.
    None when every side is at the finest width."""
    widths = [b - a for a, b in cell]
    cuts = [0] * len(cell)
    for _ in range(MAX_PIECES_HALVINGS):
        sides = [i for i in range(len(cell)) if widths[i] > min_width[i]]
        if not sides or (sum(cuts) > 0 and sum(w * x / 2 for w, x in zip(weights, widths)) < margin):
            break
        k = max(sides, key=lambda i: widths[i] * weights[i])
        widths[k] /= 2
        cuts[k] += 1
    if not any(cuts):
        return None
    pieces: list[Cell] = [()]
    for (a, b), k in zip(cell, cuts):
        step = (b - a) / 2 ** k
        pieces = [p + ((a + j * step, b if j == 2 ** k - 1 else a + (j + 1) * step),) for p in pieces
                  for j in range(2 ** k)]
    return tuple(pieces)


def _at_the_bottom(cell: Cell, min_width: list[float], value: Any, grad: list[Any]) -> bool:
    """Every side of the cell is within 2^BOTTOM_HALVINGS of the finest width, ``g(m) < 0`` and the first
    order spread ``sum_i |g_i| w_i / 2`` over a cell of the finest widths ``w`` around ``m`` is at least
    ``-g(m)`` (floats: an estimate that only decides when an attempt gives up)."""
    margin = -float(value.mid())
    return margin > 0 and all(b - a <= w * 2 ** BOTTOM_HALVINGS for (a, b), w in zip(cell, min_width)) and \
        sum(abs(float(gi.mid())) * w / 2 for gi, w in zip(grad, min_width)) >= margin


def _trim(geo: Any, cell: Cell, c: Any) -> Cell:
    """The cell less its outer slabs proved outside ``{V <= level}`` (``c``: the level), side by side, from
    the end farther from the equilibrium: the largest of the outer half, quarter, ... (TRIM_DEPTH) of the
    side whose slab ``geo.outside`` proves outside the set. The slabs hold no point of the set, so ``g < 0``
    on the rest of the cell is the claim on the whole cell, and a Taylor form over the smaller cell is
    tighter (its corners no longer reach far outside the set, where ``g`` is largest). The cuts are at
    the cell's own dyadic points: the same cells on every machine."""
    for i in range(len(cell)):
        a, b = cell[i]
        upper = abs(b) >= abs(a)
        for k in range(1, TRIM_DEPTH + 1):
            w = (b - a) / 2 ** k
            piece = cell[:i] + (((b - w, b) if upper else (a, a + w)),) + cell[i + 1:]
            if geo.outside(geo.quadratic(piece), piece, c):
                cell = cell[:i] + (((a, b - w) if upper else (a + w, b)),) + cell[i + 1:]
                break
    return cell


def _weights(grad: list[Any], H: list[list[Any]] | None, cell: Cell) -> list[float]:
    """Each side's share of the Taylor form's spread per unit of its width: ``|g_i| + sum_j |H_ij| r_j``
    (``|g_i|`` alone without ``H``; floats: they only choose the side to split, the proof never rests on
    them)."""
    radii = [(b - a) / 2 for a, b in cell]
    return [abs(float(gi.mid())) + float(gi.rad()) + (0.0 if H is None else sum(
        (abs(float(h.mid())) + float(h.rad())) * r for h, r in zip(H[i], radii))) for i, gi in enumerate(grad)]


def _where(cell: Cell) -> str:
    """A cell in the ellipsoid's coordinates, for a reason given in one line."""
    return ", ".join(f"y{i} in [{a:.6g}, {b:.6g}]" for i, (a, b) in enumerate(cell))


def prove_ellipsoid(lie: LieDerivative, P: list[list[Fraction]], diagonal: list[Fraction], level: Fraction,
                    local: list[Fraction], cell_budget: int | None, cell_limit: int, deadline: float | None = None,
                    stopped: str = "stopped at the deadline", geometry: Any = None,
                    box_level: Fraction | None = None, budget_name: str | None = None) -> EllipsoidProof:
    """``g < 0`` on ``{z^T P z <= level}`` except at the equilibrium (module docstring); deterministic.
    ``local``: the half-widths of the local box ``N`` around the equilibrium on which the Hessian of ``g``
    is proved negative definite (:func:`~lyapcheck.models.engines.interval_region.local_box`; empty:
    none), so ``g < 0`` on ``N`` but at the equilibrium: a cell whose image lies in ``N`` needs nothing
    more. ``cell_budget`` (a search's work budget) and ``cell_limit`` (``verify``'s) bound the cells.
    ``diagonal``: the diagonal of ``P^-1`` (exact); ``stopped``: the reason given when ``deadline`` passes.
    ``geometry`` (a function of the :class:`Whitening` giving a :class:`_Geometry`) and ``box_level`` (the
    cells' box is that of ``{y^T Q y <= box_level}``): a ``V`` whose quadratic part is ``z^T P z``, with
    its own test of a cell outside ``{V <= level}`` (:mod:`lyapcheck.models.engines.quartic_cells`)."""
    # {z^T P z <= inner} lies in N: max {z_i : z^T P z <= c} = sqrt(c (P^-1)_ii)
    inner = min((x * x / d for x, d in zip(local, diagonal)), default=Fraction(0)) if diagonal else Fraction(0)
    N = [ball(x) for x in local]

    w = whitening(P, level if box_level is None else box_level)
    if w is None:
        return EllipsoidProof(False, "V's matrix is not proved positive definite in the ellipsoid's coordinates",
                              0, None)
    geo = _Geometry(w, P, lie) if geometry is None else geometry(w)
    n = geo.n
    model = _polynomial_model(lie, P, w) if geo.factored and uses_model(lie.loop, P) and type(lie) is LieDerivative \
        else None
    c = ball(level)
    box: Cell = tuple((-float(h), float(h)) for h in w.half)
    count = 0
    limit = cell_limit if cell_budget is None else min(cell_budget, cell_limit)

    def over() -> str | None:
        if count > limit:
            if cell_budget is None or cell_budget > cell_limit:
                return f"more than {cell_limit} cells"
            return f"more than the attempt's {cell_budget} cells" + (f" ({budget_name})" if budget_name else "")
        if deadline is not None and count % 64 == 0 and time.perf_counter() > deadline:
            return stopped
        return None

    def in_local_box(cell: Cell) -> bool:
        return bool(N) and all(abs(zi) <= r for zi, r in zip(geo.z_of([flint.arb((a + b) / 2, (b - a) / 2)
                                                                          for a, b in cell]), N))

    def counterexample(cell: Cell, value: Any = None) -> EllipsoidProof | None:
        """The end of the proof when ``g >= 0`` is proved at the cell's centre, a point of ``E`` other
        than the equilibrium (``value``: ``g`` there, when already enclosed)."""
        if all(a + b == 0 for a, b in cell):
            return None
        if value is None:
            value = lie(geo.z_of([flint.arb((a + b) / 2) for a, b in cell]))
        if not value >= 0:
            return None
        centre = geo.v_upper(tuple(((a + b) / 2, (a + b) / 2) for a, b in cell))
        if not centre <= c:
            return None
        return EllipsoidProof(False, f"V' >= 0 at a point where V = {float(centre.mid()):.6g} <= level (proved): "
                              "V does not decrease on the whole set at this level", count, level_1,
                              float(centre.mid()))

    # the polynomial model's ball (part 5), where N's ellipsoid gives its inner radius: V' < 0 on it but at the
    # equilibrium, so the Hessian zone's phase and the shell skip the cells inside it
    early = ball(_model_ball(model, lie, P, w, inner)) if model is not None and inner > 0 else None
    # phase 2: the Hessian zone, cells in increasing order of their lower bound of y^T Q y
    zone_width = [x * float(HESSIAN_ZONE_MIN_WIDTH) for x in geo.widths]
    shell_width = [x * float(SHELL_MIN_WIDTH) for x in geo.widths]
    order = 0  # ties broken by the order of creation: deterministic
    heap: list[tuple[float, int, Cell]] = [(0.0, order, box)]
    lows: dict[Cell, Any] = {box: geo.quadratic(box)}
    zone: list[tuple[Cell, Any, list[list[Any]]]] = []  # (cell, y^T Q y over it, H over it)
    pending: list[tuple[Cell, tuple[list[list[Any]], bool] | None]] = []  # (cell, (H, H proved < 0))
    level_1: Fraction | None = None  # None: the zone is all of E
    while heap:
        _, _, cell = heapq.heappop(heap)
        q = lows.pop(cell)
        if geo.zone_outside(q, c):
            continue  # outside E
        if in_local_box(cell) or (early is not None and bool(q <= early)):
            continue  # the Hessian is negative definite on all of N (so at each point of this cell), or the
            # model's ball holds the cell
        count += 1
        if (why := over()) is not None:
            return EllipsoidProof(False, why, count, None)
        if (refuted := counterexample(cell)) is not None:
            return refuted
        H = geo.hessian_y(lie, cell)
        if H is not None and negative_definite_preconditioned(H):
            zone.append((cell, q, H))
            continue
        # near the equilibrium (a cell wider than its distance from it) down to the shell's finest width:
        # there the Hessian is negative definite on small enough cells, and the zone must reach beyond N
        near = max(b - a for a, b in cell) > max(float(q.lower()), 0.0) ** 0.5
        halves: tuple[Cell, ...] | None = _split(cell, shell_width if near else zone_width)
        if halves is not None:
            for half in halves:
                lows[half] = geo.quadratic(half)
                order += 1
                heapq.heappush(heap, (float(lows[half].lower()), order, half))
            continue
        # the zone ends here: E_1 = {y^T Q y < level_1}, level_1 a dyadic at most the lower bound of y^T Q y
        # over this cell and every cell not taken yet (so E_1 meets none of them)
        pending.append((cell, None if H is None else (H, False)))
        pending.extend((rest, None) for _, _, rest in sorted(heap))
        lowest = min([q.lower()] + [lows[rest].lower() for _, _, rest in heap])
        level_1 = Fraction(max(float(lowest.mid()) - 2 * float(lowest.rad()), 0.0))
        while level_1 > 0 and not ball(level_1) < lowest:  # (a ball's lower bound is itself a small ball)
            level_1 = Fraction(float(level_1) * (1 - 2 ** -30))
        break
    c1 = None if level_1 is None else ball(level_1)
    c0 = ball(inner)  # {y^T Q y <= inner} lies in N
    # the polynomial model's ball (part 5): V' < 0 on inner <= |y| <= rho, inner within E_1 or N's ellipsoid
    cp = early if early is not None or model is None or level_1 is None else \
        ball(_model_ball(model, lie, P, w, max(level_1, inner)))

    def inside(q: Any, cell: Cell) -> bool:
        """The cell (``y^T Q y`` enclosed over it by ``q``) lies in ``E_1``, in ``N``, or in the model's ball."""
        return c1 is None or bool(q < c1) or bool(q <= c0) or (cp is not None and bool(q <= cp)) or \
            in_local_box(cell)

    for cell, q, H in zone:
        if inside(q, cell):
            continue  # g < 0 by the Hessian
        pending.append((cell, (H, True)))
    # phase 3: the shell, by Taylor forms; depth first, in a fixed order: the innermost and the outermost cells
    # by turns (the same cells in any order, but a level too large fails near the equilibrium or near the
    # boundary, and the attempt then ends sooner)
    far = [float(geo.quadratic(cell).upper()) for cell, _ in pending]
    ranked = [pending[k] for k in sorted(range(len(pending)), key=lambda k: (far[k], k))]
    failed = balls_tried = balls_proved = 0  # (cells the model failed, the ball tests on them: BALL_AFTER_MODEL_TRIAL)
    turns = [ranked[k // 2] if k % 2 == 0 else ranked[-1 - k // 2] for k in range(len(ranked))]
    stack = list(reversed(turns))
    while stack:
        cell, H = stack.pop()
        q = geo.quadratic(cell)
        if geo.outside(q, cell, c) or inside(q, cell):
            continue  # outside E, or inside E_1 or N's ellipsoid
        if not q <= c:  # the cell meets the boundary of E: only its part in E needs g < 0
            cell = _trim(geo, cell, c)
        count += 1
        if (why := over()) is not None:
            return EllipsoidProof(False, why, count, level_1)
        if model is not None:  # part 5: the polynomial model first, where the loop has one
            bound = cell_bound(model, cell)
            if bound.negative:
                continue
            if bound.centre - bound.error > 0:  # V' D > 0, so V' > 0, at the centre: a counterexample in E
                refuted = counterexample(cell, flint.arb(bound.centre, bound.error))
                if refuted is not None:
                    return refuted
            failed += 1
            if balls_tried >= BALL_AFTER_MODEL_TRIAL and balls_proved == 0 and failed % BALL_AFTER_MODEL_EVERY:
                # the ball tests prove nothing the model does not here: the cell is split across the side whose
                # width adds most to the model's bound
                halves = _split(cell, shell_width, bound.weights(cell))
                if halves is None:
                    return EllipsoidProof(False, f"V' < 0 is not proved at {_where(cell)} (the ellipsoid's "
                                          "coordinates, at the finest cells of the polynomial model)", count, level_1)
                stack.extend((half, H) for half in reversed(halves))
                continue
            balls_tried += 1
        value, grad = geo.at_centre(lie, cell)
        if (refuted := counterexample(cell, value)) is not None:
            return refuted
        if grad is not None and H is not None and geo.negative(value, grad, H, cell):
            balls_proved += model is not None
            continue
        # the cell's own Hessian only where it can help: when g(m) + grad g(m) . t already reaches 0 on the
        # cell, no Hessian makes the Taylor form negative (its terms' enclosures all contain 0), and the
        # halves keep the ancestor's (which contains them)
        hopeless = grad is not None and not geo.first_order_negative(value, grad, cell)
        own_H = geo.hessian_y(lie, cell) if grad is not None and not hopeless else None
        own = None if own_H is None else (own_H, negative_definite_preconditioned(own_H))
        if grad is not None and own is not None and geo.negative(value, grad, own, cell):
            balls_proved += model is not None
            continue
        # the factored test (module docstring, part 4) where the Taylor form failed: no cost on the cells the
        # Taylor form proves, and it holds where V' ~ |z|^2 is too small for a Taylor form's spread
        if float(q.upper()) <= FACTORED_REACH * float(level) and geo.factored_negative(cell):
            balls_proved += model is not None
            continue
        inherited = own if own is not None else H
        weights = None if grad is None else _weights(grad, None if inherited is None else inherited[0], cell)
        if hopeless and grad is not None and _at_the_bottom(cell, shell_width, value, grad):
            # near the finest width, g(m) + grad g(m) . t reaches 0 even over a cell of the finest width around
            # m: V' is too close to 0 here for the finest cells (an estimate: giving up is never unsound), so the
            # attempt ends now rather than after every cell down to that width
            return EllipsoidProof(False, f"V' < 0 is not proved at {_where(cell)} (the ellipsoid's coordinates: V' is "
                                  f"{float(value.mid()):.3g} at the centre, too close to 0 for the finest cells)",
                                  count, level_1)
        if hopeless and weights is not None and float(value.mid()) < 0:
            halves = _pieces(cell, shell_width, weights, -float(value.mid()))
        else:
            halves = _split(cell, shell_width, weights)
        if halves is None:
            return EllipsoidProof(False, f"V' < 0 is not proved at {_where(cell)} (the ellipsoid's coordinates, at the "
                                  "finest cells)", count, level_1)
        stack.extend((half, inherited) for half in reversed(halves))
    return EllipsoidProof(True, "proved", count, level_1)


__all__ = ["EllipsoidProof", "Whitening", "whitening", "prove_ellipsoid", "negative_definite_preconditioned",
           "uses_model"]

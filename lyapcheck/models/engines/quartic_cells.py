"""``V' < 0`` on a sublevel set ``{V <= level}`` of a polynomial ``V`` of degree above 2 (a quartic fitted
to simulations) at any number of states, by ball arithmetic on cells of the whitened coordinates of
``V``'s quadratic part (issue 42: a quadratic ``V`` covers at most a few per cent of the cart-pole's
simulated region of attraction).

``V = z^T P z + R(z)`` with ``P`` positive definite (exact) and ``R`` of degree 3 or more. The cells are
those of :mod:`lyapcheck.models.engines.ellipsoid_cells` (``z = M y``, ``Q = M^T P M``), over the box
``Y = prod [-h_i, h_i]`` of ``{y^T Q y <= box_level}``. The claim: every trajectory from
``Omega = {z = M y : y in Y, V(z) <= level}`` converges to the equilibrium. Its proof:

1. **The boundary.** ``V > level`` on every face of ``Y`` (the faces bisected, ``V`` enclosed over each
   piece): ``Omega`` is compact, and invariant as long as ``V`` does not increase in it.
2. **The decrease.** :func:`~lyapcheck.models.engines.ellipsoid_cells.prove_ellipsoid` with this module's
   geometry: a cell is dropped only where ``V``'s lower bound over it exceeds ``level`` (in the shell's
   phase; the Hessian zone's phase drops none, so that its convex ``E_1`` lies in cells where the Hessian
   of ``g = V'`` is proved negative definite); ``g``, its gradient and Hessian are those of the quadratic
   part (the ellipsoid engine's enclosures, which keep its correlations) plus those of ``R' = grad R . f``
   enclosed over the ball enclosure of ``M`` times the cell (:class:`~lyapcheck.models.engines.interval_field.LieDerivative`
   of ``R``). ``g(0) = 0`` and ``grad g(0) = 0`` (``V`` has no constant or linear term, ``f(x_eq) = 0``),
   and the Hessian of ``g`` at 0 is the quadratic part's, so the Hessian zone argument is the ellipsoid
   engine's.

Every enclosure is python-flint's ``arb`` (outward rounded); floats only choose cells. The cells are
deterministic, so a ``verify`` repeats the proof from ``(V, level, box_level)`` alone; the work is a count
of cells.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

import flint

from lyapcheck.models.engines.ellipsoid_cells import Cell, EllipsoidProof, Whitening, _Geometry, prove_ellipsoid
from lyapcheck.models.engines.interval_field import LieDerivative, ball
from lyapcheck.sos.polynomials import Poly, Ring

#: the finest piece of a face of ``Y`` in the boundary's bisection, as a fraction of the box's width
FACE_MIN_WIDTH: Final = Fraction(1, 2 ** 10)


def split_quadratic(ring: Ring, V: Poly, n: int) -> tuple[list[list[Fraction]], Poly] | str:
    """``(P, R)`` with ``V = z^T P z + R``, ``R`` of degree 3 or more (exact), or why not (one line): ``V``
    must be over the first ``n`` variables, without constant or linear terms."""
    from lyapcheck.models.engines.interval_region import quadratic_form

    quadratic: dict[tuple[int, ...], Any] = {}
    rest: dict[tuple[int, ...], Any] = {}
    for m, c in ring.terms(V).items():
        if any(m[n:]):
            return "V must be a polynomial in the state deviations alone"
        if sum(m) < 2:
            return "V must have no constant or linear term"
        (quadratic if sum(m) == 2 else rest)[m] = c
    P = quadratic_form(ring, ring.from_terms(quadratic), n)
    if P is None:
        return "V has no quadratic part"
    return P, ring.from_terms(rest)


class QuarticGeometry(_Geometry):
    """The ellipsoid engine's cells for ``V = z^T P z + R``: its enclosures of the quadratic part's ``g``
    plus those of ``grad R . f`` (module docstring, part 2)."""

    factored = False  # (V is not z^T P z: the factored test of the quadratic part alone proves nothing of V)

    def __init__(self, w: Whitening, P: list[list[Fraction]], lie: LieDerivative, ring: Ring, R: Poly) -> None:
        from lyapcheck.models.engines.interval_field import _PolynomialBank
        from lyapcheck.sos.polynomials import to_fmpq

        super().__init__(w, P, lie)
        self.rest = LieDerivative(lie.loop, ring, R)
        # V in y exactly (z = M y, M dyadic): its enclosures over a cell then keep the cell's shape, where
        # V over the ball enclosure of M times the cell (a box far wider than the tilted cell) does not
        n = self.n
        gens = ring.gens()
        images = [sum((gens[j] * to_fmpq(Fraction(w.M[i][j])) for j in range(n)), ring.zero()) if i < n else gens[i]
                  for i in range(ring.nvars)]
        Ry = ring.compose(R, images)
        self.r_bank = _PolynomialBank(ring, n, [Ry])
        self.r_grad_bank = _PolynomialBank(ring, n, [Ry.derivative(i) for i in range(n)])

    def v_above(self, cell: Cell, c: Any) -> bool:
        """``V > c`` on the cell: ``y^T Q y`` (squares as squares, :meth:`quadratic`) plus ``R(M y)``
        (exact in ``y``) by its natural enclosure, else by the mean-value form ``R(m) + grad R(cell) . t``."""
        balls = [flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell]
        q = self.quadratic(cell)
        if q + self.r_bank(balls)[0] > c:
            return True
        zero = flint.arb(0)
        total = q + self.r_bank([flint.arb((a + b) / 2) for a, b in cell])[0]
        for gi, (a, b) in zip(self.r_grad_bank(balls), cell):
            r = flint.arb((b - a) / 2)
            total = total + gi * zero.union(r).union(-r)
        return bool(total > c)

    def _z(self, cell: Cell) -> list[Any]:
        return self.z_of([flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell])

    def v_upper(self, cell: Cell) -> Any:
        return self.quadratic(cell) + self.r_bank([flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell])[0]

    def outside(self, q: Any, cell: Cell, c: Any) -> bool:
        return self.v_above(cell, c)

    def zone_outside(self, q: Any, c: Any) -> bool:
        return False  # (E_1 must lie in cells whose Hessian is proved: none is left out)

    def hessian_y(self, lie: Any, cell: Cell) -> list[list[Any]] | None:
        H = super().hessian_y(lie, cell)
        if H is None:
            return None
        jet = self.rest.jet(self._z(cell), 2)
        if jet.hess is None:
            return None
        B = self.Mt * flint.arb_mat(jet.hess) * self.Mmat
        out = [[H[i][j] + B[i, j] for j in range(self.n)] for i in range(self.n)]
        return out if all(h.is_finite() for row in out for h in row) else None

    def at_centre(self, lie: Any, cell: Cell) -> tuple[Any, list[Any] | None]:
        value, grad = super().at_centre(lie, cell)
        if grad is None:
            return value, None  # (the whole V's g, from ``lie``: the field has no derivative there)
        jet = self.rest.jet(self.z_of([flint.arb((a + b) / 2) for a, b in cell]), 1)
        if jet.grad is None:
            return value + jet.value, None
        gy = self.Mt * flint.arb_mat([[x] for x in jet.grad])
        return value + jet.value, [grad[i] + gy[i, 0] for i in range(self.n)]


@dataclass
class QuarticProof:
    """What :func:`prove_sublevel` established: ``ok`` or why not, the cells of the faces and of the
    decrease, and the seconds it took (a figure, never a decision)."""

    ok: bool
    why: str
    face_cells: int
    cells: int
    seconds: float
    counterexample_v: float | None = None


def faces_above(geo: QuarticGeometry, c: Any, half: list[Fraction], limit: int) -> tuple[bool, str, int]:
    """Part 1: ``V > level`` on every face of ``Y`` (bisected in a fixed order, at most ``limit`` pieces)."""
    n = geo.n
    count = 0
    for i in range(n):
        for side in (-float(half[i]), float(half[i])):
            stack: list[Cell] = [tuple((side, side) if k == i else (-float(half[k]), float(half[k]))
                                       for k in range(n))]
            while stack:
                piece = stack.pop()
                count += 1
                if count > limit:
                    return False, f"V > level is not proved on the box's faces within {limit} pieces", count
                if geo.v_above(piece, c):
                    continue
                sides = [k for k in range(n) if k != i and
                         piece[k][1] - piece[k][0] > geo.widths[k] * float(FACE_MIN_WIDTH)]
                if not sides:
                    where = ", ".join(f"y{k} in [{a:.6g}, {b:.6g}]" for k, (a, b) in enumerate(piece))
                    return False, f"V > level is not proved on the box's face at {where}", count
                k = max(sides, key=lambda s: piece[s][1] - piece[s][0])
                a, b = piece[k]
                m = (a + b) / 2
                stack.append(piece[:k] + ((m, b),) + piece[k + 1:])
                stack.append(piece[:k] + ((a, m),) + piece[k + 1:])
    return True, "proved", count


def prove_sublevel(lie: LieDerivative, ring: Ring, V: Poly, level: Fraction, box_level: Fraction,
                   cell_budget: int, deadline: float | None = None, stopped: str = "stopped at the deadline",
                   budget_name: str = "the caller's cell_budget") -> QuarticProof:
    """The module's claim for ``(V, level, box_level)`` (``lie``: ``V'`` on the loop's true field),
    deterministic, within ``cell_budget`` cells (the faces' pieces and the decrease's cells together);
    ``budget_name``: what set ``cell_budget`` (named when the decrease's cells spend it)."""
    from lyapcheck.models.engines.ellipsoid_cells import whitening
    from lyapcheck.models.engines.interval_region import inverse_diagonal, local_box

    start = time.perf_counter()
    n = lie.n

    def failed(why: str, faces: int = 0, cells: int = 0, v: float | None = None) -> QuarticProof:
        return QuarticProof(False, why, faces, cells, time.perf_counter() - start, v)

    if level <= 0 or box_level <= 0:
        return failed("the level and the box's level must be > 0")
    parts = split_quadratic(ring, V, n)
    if isinstance(parts, str):
        return failed(parts)
    P, R = parts
    diagonal = inverse_diagonal(P)
    w = None if diagonal is None else whitening(P, box_level)
    if diagonal is None or w is None:
        return failed("V's quadratic part is not proved positive definite")
    geo = QuarticGeometry(w, P, lie, ring, R)
    c = ball(level)
    ok, why, faces = faces_above(geo, c, w.half, cell_budget)
    if not ok:
        return failed(why, faces)
    # the local box N (the Hessian of g negative definite on it) within the z-box around M Y (exact bounds)
    Mq = [[Fraction(x) for x in row] for row in w.M]
    zhalf = [sum((abs(Mq[i][j]) * w.half[j] for j in range(n)), Fraction(0)) for i in range(n)]
    from lyapcheck.exact import dyadic_ceil

    zhalf = [dyadic_ceil(h) for h in zhalf]
    radii = local_box(lie, tuple(-h for h in zhalf), tuple(zhalf)) or []
    found: EllipsoidProof = prove_ellipsoid(lie, P, diagonal, level, radii, cell_budget - faces, cell_budget,
                                            deadline, stopped, geometry=lambda ww: QuarticGeometry(ww, P, lie, ring, R),
                                            box_level=box_level,
                                            budget_name=f"{budget_name}, less the faces' {faces} cells")
    return QuarticProof(found.ok, found.why, faces, found.cells, time.perf_counter() - start,
                        found.counterexample_v)


__all__ = ["QuarticGeometry", "QuarticProof", "faces_above", "prove_sublevel", "split_quadratic"]

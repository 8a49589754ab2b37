"""The system data the paper's condition classes act on, and which of them prove stability."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from typing import Any, Sequence

from lyapcheck.paper import poly
from lyapcheck.exact import Matrix

#: classes whose exact pass proves stability of the error dynamics (the verdict "certified")
STABILITY_CLASSES = ("prop41_ges", "prop41_iss", "sector_ges", "switched_ges", "sos_gas", "ges")


@dataclass(frozen=True)
class System:
    """``x_dot = A x + rho(x) B x + E w``, ``rho in (0, rho_sup]``, ``|w| <= d_max`` (exact)."""

    dynamics: str
    A: Matrix
    B: Matrix
    E: tuple[Fraction, Fraction]
    rho_sup: Fraction
    sigma0: Fraction
    delta: Fraction
    speed: Fraction
    d_max: Fraction

    def vertex(self, rho: Fraction) -> Matrix:
        return tuple(tuple(a + rho * b for a, b in zip(ra, rb)) for ra, rb in zip(self.A, self.B))


# -- the sos and ges classes' scaled loop, and the sector class's polytope over a box ---------------
# (here, below the classes and their sentences in lyapcheck.paper.claims, so that each can import them)

@dataclass(frozen=True)
class ScaledDynamics:
    time_scale: Fraction
    c: Fraction
    a: Fraction
    b: Fraction

    def fields(self) -> tuple[poly.Poly, poly.Poly, poly.Poly]:
        """Exact polynomial field ``(g_y, g_r)`` (cleared of ``q``) and ``q``, in (y, r)."""
        q: poly.Poly = {(2, 0): Fraction(1), (0, 0): Fraction(1)}
        e: poly.Poly = {(1, 0): Fraction(1), (0, 1): Fraction(-1)}
        e_dot = poly.add(poly.scale(Fraction(-1), e), {(0, 1): self.c})
        r_dot_linear: poly.Poly = {(0, 1): -self.a}
        g_r = poly.add(poly.mul(r_dot_linear, q), poly.scale(self.b, e))
        g_y = poly.add(poly.mul(e_dot, q), g_r)
        return g_y, g_r, q


def scaled_dynamics(system: System) -> ScaledDynamics | None:
    a = system.A
    if not (a[1][0] == 0 and a[0][0] < 0 and a[1][1] < 0 and system.sigma0 > 0
            and system.B == ((0, 0), (1, 0))):
        return None
    ts = -a[0][0]
    return ScaledDynamics(time_scale=ts, c=a[0][1] / (system.sigma0 * ts), a=-a[1][1] / ts,
                          b=system.sigma0 * system.speed / (system.delta * ts))


def sector_polytope(vertices: Sequence[Any]) -> list[Any]:
    """The matrices ``[[-1, c], [r, -a]]`` at the corners of ``c, a`` ranges and ``r in {0, b_max}``.

    In scaled coordinates the sector system is ``x' = [[-1, c], [r, -a]] x`` with ``0 < r <= b``
    (:mod:`lyapcheck.paper.conditions.sector` in the coordinates of :mod:`lyapcheck.paper.conditions.ges`), and
    over the box ``c``, ``a``, ``b`` range over the intervals spanned by the ``(c, a, b)`` hull. The
    matrix is affine in ``(c, a, r)``, so every matrix of every gain set in the box lies in the
    convex hull of these, and a quadratic form decreasing at them decreases at every one.
    """
    from lyapcheck import exact

    cs = sorted({v.c for v in vertices})
    as_ = sorted({v.a for v in vertices})
    b_max = max(v.b for v in vertices)
    out = []
    for c in (cs[0], cs[-1]):
        for a in (as_[0], as_[-1]):
            for r in (Fraction(0), b_max):
                m = exact.matrix([[-1, c], [r, -a]])
                if m not in out:
                    out.append(m)
    return out

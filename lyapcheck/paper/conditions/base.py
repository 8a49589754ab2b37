"""The system data the paper's condition classes act on, and which of them prove stability."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

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

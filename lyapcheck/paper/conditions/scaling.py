"""State and time scaling so that the LMI data span few orders of magnitude.

With the paper's physical values the entries of ``A + rho B`` range from 1e-4 to 1e3. The
certificate search uses ``x = T x~`` with ``T = diag(1, beta)`` (``beta`` a rational that balances
the coupling ``a12`` against ``rho_sup``) and divides the vertex matrices by a common scale
``s`` (a change of time unit). Both maps are exact, so a certificate found in the scaled
coordinates is mapped back exactly (``P = T^-T P~ T^-1``) and checked in the original ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from lyapcheck import exact


@dataclass(frozen=True)
class Scaling:
    beta: Fraction
    time: Fraction

    def matrix_to_scaled(self, a: exact.Matrix) -> np.ndarray:
        """``T^-1 A T / s`` as floats."""
        b, s = float(self.beta), float(self.time)
        return np.array([[float(a[0][0]) / s, float(a[0][1]) * b / s],
                         [float(a[1][0]) / (b * s), float(a[1][1]) / s]])

    def vector_to_scaled(self, v: tuple[Fraction, Fraction]) -> np.ndarray:
        b, s = float(self.beta), float(self.time)
        return np.array([float(v[0]) / s, float(v[1]) / (b * s)])

    def p_from_scaled(self, p_scaled: exact.Matrix) -> exact.Matrix:
        """``P = T^-T P~ T^-1`` exactly."""
        inv = Fraction(1) / self.beta
        return ((p_scaled[0][0], p_scaled[0][1] * inv), (p_scaled[1][0] * inv, p_scaled[1][1] * inv * inv))


def choose(vertices: list[exact.Matrix]) -> Scaling:
    a12 = max(abs(float(v[0][1])) for v in vertices)
    a21 = max(abs(float(v[1][0])) for v in vertices)
    beta = math.sqrt(a21 / a12) if a12 > 0 and a21 > 0 else 1.0
    beta_q = exact.to_rational(beta, 6)
    sc = Scaling(beta_q, Fraction(1))
    size = max(np.abs(sc.matrix_to_scaled(v)).max() for v in vertices)
    return Scaling(beta_q, exact.to_rational(size, 6))

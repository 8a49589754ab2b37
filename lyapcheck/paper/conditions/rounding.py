"""Deterministic rounding of a search's floating-point answer onto fixed rational grids.

A figure that a search reads off a solver (a level, a bound) differs in its last digits from one
floating-point platform to another. Rounded down (or up) to a few significant digits it is a
point of a fixed grid, the same on every platform unless the two answers straddle a grid point;
then they differ by one step, ``10^(1 - digits)`` relative at most. Which way to round is the
caller's: always the way that keeps the certified statement true (a level inside what the solver
found, a bound above it), and the exact check decides.
"""

from __future__ import annotations

import math
from fractions import Fraction


def _step(x: float, digits: int) -> Fraction:
    """The grid step at ``x`` (``x > 0``): one unit of its ``digits``-th significant digit."""
    exponent = math.floor(math.log10(x)) - digits + 1
    step = Fraction(10) ** exponent
    # log10 of a double may land one off at an exact power of ten: keep digits digits
    while x / step >= 10**digits:
        step *= 10
    while x / step < 10 ** (digits - 1):
        step /= 10
    return step


def floor_to_digits(x: float, digits: int) -> Fraction:
    """The largest rational with ``digits`` significant decimal digits that is ``<= x`` (``x > 0``)."""
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"The 'x' parameter must be a positive finite float. Got {x!r} instead.")
    step = _step(x, digits)
    return math.floor(Fraction(x) / step) * step


def ceil_to_digits(x: float, digits: int) -> Fraction:
    """The smallest rational with ``digits`` significant decimal digits that is ``>= x`` (``x > 0``)."""
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"The 'x' parameter must be a positive finite float. Got {x!r} instead.")
    step = _step(x, digits)
    return math.ceil(Fraction(x) / step) * step

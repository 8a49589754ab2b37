"""The decay-rate search shared by ``ges`` and its box form: a geometric bisection whose every
step is decided by an exact check, never by a solver's status (issue 24).

``proved(mu)`` returns an exactly checked certificate at the rate ``mu`` or None. The search tries
``low`` first and, if that fails, ``floor`` (a slow branch below ``low``); from the first rate
proved it bisects geometrically towards ``high`` (or ``low``) for ``steps`` steps and keeps the
certificate of the largest rate proved. The steps are fixed numbers, so two platforms whose
exact checks agree take the same steps.
"""

from __future__ import annotations

import math
from typing import Callable, TypeVar

Found = TypeVar("Found")


def largest_proved_rate(proved: Callable[[float], Found | None], *, low: float, high: float, floor: float,
                        steps: int) -> Found | None:
    """The certificate of the largest rate proved on the bisection's path (module docstring)."""
    found = proved(low)
    lo, hi = low, high
    if found is None:
        found = proved(floor)
        lo, hi = floor, low
    if found is None:
        return None
    for _ in range(steps):
        mid = math.sqrt(lo * hi)
        better = proved(mid)
        if better is not None:
            lo, found = mid, better
        else:
            hi = mid
    return found

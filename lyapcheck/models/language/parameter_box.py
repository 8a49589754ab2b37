"""A box of a model's parameters: closed intervals, exact, in the model's order (pure data), and the one way a
box or an interval is written in a message (:func:`interval_ends`, :func:`box_text`).

Its own module so that the modules that take a box (:mod:`lyapcheck.models.loop.field`,
:mod:`lyapcheck.models.surfaces.certify`) need not import :mod:`lyapcheck.models.loop.boxes`, which parses and
checks boxes with them.

An interval is written with :data:`SHORT_DIGITS` significant digits, and more where its two ends would then read the
same (a split box narrower than that, ``k in [1, 1]``): each end gets as many as it takes for the two texts to
differ, up to a double's 17, then the exact rational (two values closer than a double tells apart). The paper's
boxes, the sweeps' notes and the reports' tables print parameter boxes through it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Final, Iterable, Iterator, Mapping, Sequence

#: significant digits of an interval's ends in a message, where they tell the two ends apart (:func:`interval_ends`)
SHORT_DIGITS: Final = 6
#: the most significant digits of a double's shortest text: two different doubles differ within these
DOUBLE_DIGITS: Final = 17

#: an end of an interval: exact, or a float read back from a store
End = Fraction | float | int

#: a random point of a box (:meth:`ModelBox.points`): the uniform fraction of each interval on a grid
#: of this many steps, and a log-uniform value to this many significant digits (its exact decimal is
#: then short: a point is read again from the model text as ``--set NAME=VALUE``)
POINT_STEPS: Final = 10**6
POINT_DIGITS: Final = 7


@dataclass(frozen=True)
class ModelBox:
    """Closed intervals of some of a model's parameters (exact SI), in the model's order."""

    bounds: tuple[tuple[str, Fraction, Fraction], ...]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _, _ in self.bounds)

    def interval(self, name: str) -> tuple[Fraction, Fraction]:
        for n, lo, hi in self.bounds:
            if n == name:
                return lo, hi
        raise KeyError(name)

    def center(self, name: str) -> Fraction:
        lo, hi = self.interval(name)
        return (lo + hi) / 2

    def half(self, name: str) -> Fraction:
        lo, hi = self.interval(name)
        return (hi - lo) / 2

    def to_json(self) -> dict[str, list[str]]:
        return {name: [str(lo), str(hi)] for name, lo, hi in self.bounds}

    @classmethod
    def from_json(cls, data: Mapping[str, Sequence[str]]) -> "ModelBox":
        return cls(tuple((name, Fraction(lo), Fraction(hi)) for name, (lo, hi) in data.items()))

    def corners(self) -> list[dict[str, Fraction]]:
        import itertools

        return [dict(zip(self.names, values)) for values in itertools.product(*((lo, hi) for _, lo, hi in self.bounds))]

    def points(self, count: int, seed: int) -> list[dict[str, Fraction]]:
        """``count`` points of the box, uniform in each parameter (log-uniform where the range is
        positive and spans more than a factor of 10), from a generator seeded by ``seed`` alone.
        Each value is a short exact decimal (the uniform fraction on a grid of ``POINT_STEPS``, a
        log-uniform value to ``POINT_DIGITS`` significant digits): a point is read again from the
        model text as ``--set NAME=VALUE``, and a float's exact binary value written out has dozens of
        digits where an edge such as 0.8 is not dyadic."""
        import numpy as np

        rng = np.random.default_rng(seed)
        out = []
        for _ in range(count):
            point = {}
            for name, lo, hi in self.bounds:
                u = float(rng.random())
                if lo > 0 and hi / lo > 10:
                    value = Fraction(f"{math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))):.{POINT_DIGITS}g}")
                else:
                    value = lo + (hi - lo) * Fraction(round(u * POINT_STEPS), POINT_STEPS)
                point[name] = min(max(value, lo), hi)
            out.append(point)
        return out

    def split(self) -> tuple["ModelBox", "ModelBox"]:
        """Halve the widest interval (relative to its centre's magnitude where that is non-zero)."""
        def width(b: tuple[str, Fraction, Fraction]) -> float:
            _, lo, hi = b
            scale = max(abs(lo), abs(hi))
            return float((hi - lo) / scale) if scale else float(hi - lo)

        i = max(range(len(self.bounds)), key=lambda k: width(self.bounds[k]))
        name, lo, hi = self.bounds[i]
        mid = (lo + hi) / 2
        left = self.bounds[:i] + ((name, lo, mid),) + self.bounds[i + 1:]
        right = self.bounds[:i] + ((name, mid, hi),) + self.bounds[i + 1:]
        return ModelBox(left), ModelBox(right)

    def describe(self, separator: str = ", ") -> str:
        """``mu in [0.8, 1.2], k in [1, 2]``: each bound to 6 significant digits, more where the two ends of an
        interval would read the same (:func:`box_text`)."""
        return box_text(self.bounds, separator)

    def __iter__(self) -> Iterator[tuple[str, Fraction, Fraction]]:
        return iter(self.bounds)


def interval_ends(lo: End, hi: End, digits: int = SHORT_DIGITS) -> tuple[str, str]:
    """The two ends of ``[lo, hi]`` as text: ``digits`` significant digits each (``%g``), more where the two would
    read the same although the ends differ, up to :data:`DOUBLE_DIGITS`; two ends that no double tells apart are
    written as exact rationals ``p/q``. Equal ends, and an end that is not finite, are written as given."""
    a, b = float(lo), float(hi)
    short = f"{a:.{digits}g}", f"{b:.{digits}g}"
    if lo == hi or not (math.isfinite(a) and math.isfinite(b)) or short[0] != short[1]:
        return short
    for more in range(digits + 1, DOUBLE_DIGITS + 1):
        texts = f"{a:.{more}g}", f"{b:.{more}g}"
        if texts[0] != texts[1]:
            return texts
    # (the two ends round to one double: only their exact values differ)
    return str(Fraction(lo)), str(Fraction(hi))


def box_text(bounds: Iterable[tuple[str, End, End]], separator: str = ", ", digits: int = SHORT_DIGITS) -> str:
    """``k in [1.00002, 1.00003], mu in [0.8, 1.2]``: each ``(name, lo, hi)`` as :func:`interval_ends` writes it."""
    return separator.join(f"{name} in [{a}, {b}]" for name, lo, hi in bounds for a, b in [interval_ends(lo, hi, digits)])


"""A box of a model's parameters: closed intervals, exact, in the model's order (pure data).

Its own module so that the modules that take a box (:mod:`lyapcheck.models.loop.field`,
:mod:`lyapcheck.models.surfaces.certify`) need not import :mod:`lyapcheck.models.loop.boxes`, which parses and
checks boxes with them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Final, Iterator, Mapping, Sequence

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
        """``mu in [0.8, 1.2], k in [1, 2]``: each bound to 6 significant digits."""
        return separator.join(f"{name} in [{float(lo):.6g}, {float(hi):.6g}]" for name, lo, hi in self.bounds)

    def __iter__(self) -> Iterator[tuple[str, Fraction, Fraction]]:
        return iter(self.bounds)

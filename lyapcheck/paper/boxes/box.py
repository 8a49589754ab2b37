"""A box of gains: closed intervals of some of the paper's parameters, the others fixed.

What every box class shares: the box itself (:class:`ParameterBox`, parsed from
``--box "alpha_d=540..660"``), the problems at its corners, and the ``(c, a, b)`` hull of the
scaled error dynamics over it (:func:`scaled_hull`; why corners cover a box is in
:mod:`lyapcheck.paper.boxes.quadratic`). The classes live in the sibling modules; the dispatch
over them in :mod:`lyapcheck.paper.boxes.classes`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.errors import InvalidParameter
from lyapcheck.paper.params import FIELD_BY_KEY, Problem, validate_field
from lyapcheck.paper.conditions.base import ScaledDynamics, scaled_dynamics
from lyapcheck.paper.system import build_system


#: parameters a box may span -> the key of the FIELDS table
BOX_FIELDS: dict[str, str] = {
    "alpha_d": "gains.alpha_d", "sigma0": "gains.sigma0", "k_d": "gains.k_d", "delta_los": "gains.delta_los",
    "los_speed": "gains.los_speed", "e11": "swimmer.e11",
}


@dataclass(frozen=True)
class ParameterBox:
    """Closed intervals ``[lo, hi]`` (SI, exact) of some gain parameters; the others are fixed."""

    bounds: tuple[tuple[str, Fraction, Fraction], ...]

    def to_json(self) -> dict[str, list[str]]:
        return {name: [str(lo), str(hi)] for name, lo, hi in self.bounds}

    @classmethod
    def from_json(cls, data: Mapping[str, Sequence[str]]) -> "ParameterBox":
        return cls(tuple((name, Fraction(lo), Fraction(hi)) for name, (lo, hi) in data.items()))

    def corners(self) -> list[dict[str, Fraction]]:
        return [dict(zip((n for n, _, _ in self.bounds), values))
                for values in itertools.product(*((lo, hi) for _, lo, hi in self.bounds))]

    def split(self) -> tuple["ParameterBox", "ParameterBox"]:
        """Halve the widest interval (relative width, the parameters span decades)."""
        widest = max(range(len(self.bounds)), key=lambda i: self.bounds[i][2] / self.bounds[i][1])
        name, lo, hi = self.bounds[widest]
        mid = (lo + hi) / 2
        left = self.bounds[:widest] + ((name, lo, mid),) + self.bounds[widest + 1:]
        right = self.bounds[:widest] + ((name, mid, hi),) + self.bounds[widest + 1:]
        return ParameterBox(left), ParameterBox(right)

    def relative_width(self) -> float:
        return max(float(hi / lo) - 1 for _, lo, hi in self.bounds)

    def describe(self) -> str:
        """``alpha_d in [540, 660], ...`` (SI), as every parameter box is written
        (:func:`lyapcheck.models.language.parameter_box.box_text`: the ends of a narrow interval told apart)."""
        from lyapcheck.models.language.parameter_box import box_text

        return box_text(self.bounds)


def parse_box(specs: Sequence[str]) -> ParameterBox:
    """``["alpha_d=540..660", "delta_los=0.5 mm..1 mm"]`` -> :class:`ParameterBox` (one-line errors)."""
    bounds: list[tuple[str, Fraction, Fraction]] = []
    for spec in specs:
        name, sep, interval = spec.partition("=")
        name = name.strip()
        if not sep or ".." not in interval:
            raise InvalidParameter("box", "NAME=LO..HI, e.g. 'alpha_d=540..660'", spec)
        if name not in BOX_FIELDS:
            raise InvalidParameter("box", f"a parameter among {', '.join(BOX_FIELDS)}", name)
        if any(name == b[0] for b in bounds):
            raise InvalidParameter(name, "given once in --box", spec)
        lo_text, _, hi_text = interval.partition("..")
        field = FIELD_BY_KEY[BOX_FIELDS[name]]
        lo, hi = validate_field(field, lo_text.strip()), validate_field(field, hi_text.strip())
        if lo > hi:
            raise InvalidParameter(name, f"an interval with low <= high (box '{spec}')", interval)
        bounds.append((name, lo, hi))
    if not bounds:
        raise InvalidParameter("box", "at least one NAME=LO..HI", "")
    return ParameterBox(tuple(bounds))


def problem_at_point(problem: Problem, point: Mapping[str, Fraction]) -> Problem:
    """``problem`` with the parameters of ``point`` (names of :data:`BOX_FIELDS`) set."""
    from dataclasses import replace

    gains = {k: v for k, v in point.items() if k != "e11"}
    p = problem.with_gains(**gains) if gains else problem
    if "e11" in point:
        p = replace(p, swimmer=replace(p.swimmer, e11=point["e11"]))
    return p


def corner_problems(problem: Problem, box: ParameterBox) -> list[Problem]:
    """The problem at every corner of the box (the other parameters as in ``problem``)."""
    return [problem_at_point(problem, corner) for corner in box.corners()]


def stored_hull(problem: Problem, box: ParameterBox, dynamics: str,
                cert: Mapping[str, Any]) -> tuple[list[Any], Fraction] | str:
    """The ``(c, a, b)`` hull re-derived from the box, or why the certificate's stored copy differs."""
    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return "the dynamics at some corner do not have the structure this class needs"
    vertices, ts_min = hull
    stored = {tuple(Fraction(x) for x in v) for v in cert["vertices"]}
    if stored != {(v.c, v.a, v.b) for v in vertices} or Fraction(cert["time_scale_min"]) != ts_min:
        return "the stored (c, a, b) vertices or min |a11| do not match the box"
    return hull


def scaled_hull(problem: Problem, box: ParameterBox, dynamics: str) -> tuple[list[Any], Fraction] | None:
    """Vertices of the ``(c, a, b)`` box over the parameter box, and ``min |a11|`` (exact)."""

    points = []
    for p in corner_problems(problem, box):
        dyn = scaled_dynamics(build_system(p, dynamics))
        if dyn is None:
            return None
        points.append(dyn)
    ranges = [(min(getattr(d, k) for d in points), max(getattr(d, k) for d in points)) for k in ("c", "a", "b")]
    vertices = [ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b) for c, a, b in itertools.product(*ranges)]
    unique = list({(v.c, v.a, v.b): v for v in vertices}.values())
    return unique, min(d.time_scale for d in points)


def sample_points(box: ParameterBox, count: int, seed: Sequence[int]) -> list[dict[str, Fraction]]:
    """``count`` points of ``box``, log-uniform in each parameter (the gains span decades),
    from a generator seeded by ``seed`` alone (so a box's points do not depend on run order)."""
    import numpy as np

    rng = np.random.default_rng(list(seed))
    out = []
    for _ in range(count):
        point = {}
        for name, lo, hi in box.bounds:
            u = float(rng.random())
            value = Fraction(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))) if lo > 0 else lo
            point[name] = min(max(value, lo), hi)  # rounding of exp/log must not leave the box
        out.append(point)
    return out

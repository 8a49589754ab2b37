"""Boxes of a model's parameters: ``--box "mu=0.8..1.2"``, one certificate for every value in it.

In the certificates a box parameter ``theta_i in [lo_i, hi_i]`` is written ``c_i + h_i u_i`` with
``c_i`` the centre, ``h_i`` the half-width and ``u_i in [-1, 1]`` (exact rationals); the box
enters every identity through multipliers ``s_i (1 - u_i^2)`` with ``s_i`` a sum of squares
(the S-procedure: ``1 - u_i^2 >= 0`` exactly on the box), so each identity holds for every
parameter value of the box. A certificate's polynomials may depend on ``u`` (a parameter-dependent
``V``, the standard robust-SOS construction; a common ``V`` is its degree-0 case). A box widened
after the fact changes ``c`` and ``h``, so the identities no longer hold and ``verify`` fails.

A box is checked when it is given: its names are the model's parameters, each range non-empty
(``lo < hi``), the equilibrium is one for every value in the box (exactly: the right-hand sides at
the equilibrium vanish identically in the box's parameters), and the model is defined on the whole
box (every denominator at the equilibrium is proved non-zero on it). Bad boxes are one-line exit-2
errors naming the field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Iterator, Mapping, Sequence

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.modelfile import Model


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
        positive and spans more than a factor of 10), from a generator seeded by ``seed`` alone."""
        import numpy as np

        rng = np.random.default_rng(seed)
        out = []
        for _ in range(count):
            point = {}
            for name, lo, hi in self.bounds:
                u = float(rng.random())
                if lo > 0 and hi / lo > 10:
                    value = Fraction(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))
                else:
                    value = lo + (hi - lo) * Fraction(u)
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

    def describe(self) -> str:
        return ", ".join(f"{name} in [{float(lo):.6g}, {float(hi):.6g}]" for name, lo, hi in self.bounds)

    def __iter__(self) -> Iterator[tuple[str, Fraction, Fraction]]:
        return iter(self.bounds)


def parse_model_box(model: Model, specs: Sequence[str] | Mapping[str, Any]) -> ModelBox:
    """``["mu=0.8..1.2", "d=0.05 mm/s..0.1 mm/s"]`` (or ``{"mu": (0.8, 1.2)}``) for ``model``,
    validated (see the module docstring)."""
    from lyapcheck.units import parse_si_quantity

    items: list[tuple[str, Any, Any, str]] = []
    if isinstance(specs, Mapping):
        for name, value in specs.items():
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise InvalidParameter("box", "NAME: (lo, hi)", f"{name}: {value!r}")
            items.append((str(name), value[0], value[1], f"{name}={value[0]}..{value[1]}"))
    else:
        for spec in specs:
            name, sep, interval = str(spec).partition("=")
            if not sep or ".." not in interval:
                raise InvalidParameter("box", "NAME=LO..HI, e.g. 'mu=0.8..1.2'", spec)
            lo_text, _, hi_text = interval.partition("..")
            items.append((name.strip(), lo_text.strip(), hi_text.strip(), str(spec)))
    if not items:
        raise InvalidParameter("box", "at least one NAME=LO..HI", "")
    given: dict[str, tuple[Fraction, Fraction]] = {}
    for name, lo_text, hi_text, spec in items:
        if name not in model.parameters:
            known = ", ".join(model.parameters) or "none"
            raise ModelFileError(model.source, f"--box {name}", f"no parameter named '{name}' (parameters: {known})")
        if name in given:
            raise ModelFileError(model.source, f"--box {name}", "given twice")
        try:
            lo, hi = parse_si_quantity(name, lo_text), parse_si_quantity(name, hi_text)
        except InvalidParameter as exc:
            raise ModelFileError(model.source, f"--box {name}", f"must be LO..HI with numbers or unit strings, "
                                                                f"got {exc.got!r}") from None
        if not lo < hi:
            raise ModelFileError(model.source, f"--box {name}", f"an empty range: lo must be below hi, got '{spec}'")
        given[name] = (lo, hi)
    box = ModelBox(tuple((name, *given[name]) for name in model.parameters if name in given))
    check_box(model, box)
    return box


def check_box(model: Model, box: ModelBox) -> None:
    """The equilibrium is one for every parameter of the box, and the model is defined there."""
    from lyapcheck.models.field import shifted_field
    from lyapcheck.sos.polynomials import Ring

    shifted = shifted_field(model, box=box)
    ring = shifted.ring
    n = model.n
    where = f"--box {', '.join(box.names)}"
    origin = {name: Fraction(0) for name in ring.names[:n]} | {d: Fraction(0) for d in model.disturbances}
    u_ring = Ring(box.names)
    for s, num, den in zip(model.states, shifted.numerators, shifted.denominators):
        if not ring.substitute(num, origin).is_zero():
            raise ModelFileError(model.source, where, f"the equilibrium moves with the box's parameters: {s}' is not 0 "
                                                      "there for every value of the box (checked exactly)")
        den_eq = ring.restrict(ring.substitute(den, origin), u_ring)
        if not _nonzero_on_box(u_ring, den_eq):
            raise ModelFileError(model.source, where, f"the model is not defined on the whole box: the denominator of "
                                                      f"{s} at the equilibrium, {str(den_eq).replace('^', '**')} in the "
                                                      "normalized parameters u in [-1, 1], could not be proved non-zero "
                                                      "there")


def _nonzero_on_box(ring: Any, p: Any) -> bool:
    """Exactly: ``p(u) != 0`` for every ``u`` in ``[-1, 1]^k``. A constant is decided at once; one
    variable by isolating the real roots (Arb, rigorous); more by a sign proof (an SOS certificate
    of ``+-p - c`` on the box), else refused."""
    if p.is_constant():
        return not p.is_zero()
    k = ring.nvars
    used = [i for i in range(k) if any(m[i] for m in p.monoms())]
    if len(used) == 1:
        import flint

        i = used[0]
        coeffs: dict[int, Any] = {}
        for m, c in zip(p.monoms(), p.coeffs()):
            coeffs[int(m[i])] = c
        uni = flint.fmpq_poly([coeffs.get(e, 0) for e in range(max(coeffs) + 1)])
        roots: Any = uni.numer().complex_roots()
        for root, _ in roots:
            if root.imag.is_zero() and not (root.real > 1 or root.real < -1):
                return False  # a real root in [-1, 1] (or too close to its ends to say): refused
        return True
    from lyapcheck.models.positivity import prove_positive_on_box
    from lyapcheck.models.search import Budget

    budget = Budget(30.0, "lyapcheck.models.boxes: a box's definedness proof")
    return prove_positive_on_box(ring, p, budget) is not None or prove_positive_on_box(ring, -p, budget) is not None

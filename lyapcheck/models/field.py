"""A model's field at fixed parameters, made ready for the classes: shifted, cleared, scaled.

Steps, each exact:

1. **Shift** the equilibrium to 0: ``x = x_eq + z``.
2. **Clear the denominators.** ``z_i' = N_i(z, d) / D_i(z)``. Each distinct non-constant
   denominator must be proved positive everywhere (:func:`prove_positive`: ``D_j - c = sigma``
   with ``c > 0`` and ``sigma`` a sum of squares, checked exactly; or the same for ``-D_j``, whose
   sign then moves into the numerator). With ``D = prod_j D_j > 0`` the polynomial field is
   ``g_i = N_i D / D_i`` and ``z' = g(z, d) / D(z)``: a Lyapunov inequality on ``grad V . g``
   is one on ``V'`` times ``D > 0``.
3. **Scale** (:func:`choose_scaling`): ``z = S z~`` (``S`` diagonal), ``d = S_d d~``, time
   ``t = T tau``, and ``D = c_D D~``, all powers of two (exact, and exactly invertible), chosen so
   that the scaled coefficients are of order one: the least-squares fit of their base-2
   logarithms to 0. States of 1e-4 m and gains of 600 are thus handled as they come; the user
   never rescales. With a ``[domain]`` the state scales are its half-widths instead (the region
   the classes are asked about becomes the unit box). The scaled field is

       dz~_i/dtau = g~_i(z~, d~) / D~(z~),  g~_i = T / (s_i c_D) g_i(S z~, S_d d~),  D~ = D(S z~) / c_D,

   an exact change of coordinates: a certificate in ``z~`` is one in ``z``. Certificates store
   the scaling, and ``verify`` redoes it from the model text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.models.modelfile import Model, field_at
from lyapcheck.sos.polynomials import Poly, Ring, to_fmpq


@dataclass(frozen=True)
class Scaling:
    """``z = S z~``, ``d = S_d d~``, ``t = T tau``, ``D = c_D D~``, outputs ``y = s_y y~`` (exact, > 0)."""

    states: tuple[Fraction, ...]
    disturbances: tuple[Fraction, ...]
    time: Fraction
    denominator: Fraction
    outputs: tuple[Fraction, ...]

    def to_json(self) -> dict[str, Any]:
        return {"states": [str(s) for s in self.states], "disturbances": [str(s) for s in self.disturbances],
                "time": str(self.time), "denominator": str(self.denominator),
                "outputs": [str(s) for s in self.outputs]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "Scaling":
        return cls(states=tuple(Fraction(s) for s in data["states"]),
                   disturbances=tuple(Fraction(s) for s in data["disturbances"]),
                   time=Fraction(data["time"]), denominator=Fraction(data["denominator"]),
                   outputs=tuple(Fraction(s) for s in data["outputs"]))

    def positive(self) -> bool:
        return all(x > 0 for x in (*self.states, *self.disturbances, self.time, self.denominator, *self.outputs))


@dataclass(frozen=True)
class ShiftedField:
    """``z' = N_i(z, d) / D_i(z)`` with ``z = x - x_eq`` (before clearing): exact, in :attr:`ring`."""

    model: Model
    ring: Ring
    numerators: tuple[Poly, ...]
    denominators: tuple[Poly, ...]
    outputs: dict[str, Poly]

    @property
    def n(self) -> int:
        return self.model.n

    def distinct_denominators(self) -> list[Poly]:
        """The distinct non-constant denominators (each up to a positive constant factor)."""
        out: list[Poly] = []
        for d in self.denominators:
            if d.is_constant():
                continue
            if not any(_same_up_to_constant(d, e) for e in out):
                out.append(d)
        return out


def _same_up_to_constant(a: Poly, b: Poly) -> bool:
    if len(a) != len(b) or a.monoms() != b.monoms():
        return False
    ratio = a.coeffs()[0] / b.coeffs()[0]
    return a == b * ratio


def shifted_field(model: Model, parameters: Mapping[str, Fraction] | None = None) -> ShiftedField:
    """Step 1: the field at ``parameters`` (default: the model's) with the equilibrium moved to 0."""
    ring = model.state_ring
    rhs = field_at(model, parameters)
    gens = ring.gens()
    images = [g + to_fmpq(c) for g, c in zip(gens[:model.n], model.equilibrium)] + list(gens[model.n:])

    def shift(p: Poly) -> Poly:
        return ring.compose(p, images) if any(model.equilibrium) else p

    nums, dens = [], []
    for r in rhs:
        num, den = shift(r.numerator), shift(r.denominator)
        if den.is_constant():
            num, den = num * (1 / den.leading_coefficient()), ring.constant(1)
        nums.append(num)
        dens.append(den)
    values = model.parameters if parameters is None else parameters
    outputs = {}
    for name, expr in model.outputs.items():
        num = model.ring.restrict(model.ring.substitute(expr.numerator, values), ring)
        den = model.ring.restrict(model.ring.substitute(expr.denominator, values), ring)
        outputs[name] = shift(num) * (1 / den.leading_coefficient())
    return ShiftedField(model=model, ring=ring, numerators=tuple(nums), denominators=tuple(dens), outputs=outputs)


@dataclass(frozen=True)
class ClearedField:
    """Step 2: ``z' = g(z, d) / D(z)`` with ``D > 0`` proved (``D = 1`` for a polynomial field)."""

    shifted: ShiftedField
    g: tuple[Poly, ...]
    D: Poly
    positivity: tuple[dict[str, Any], ...] = field(default_factory=tuple)

    @property
    def ring(self) -> Ring:
        return self.shifted.ring

    @property
    def n(self) -> int:
        return self.shifted.n


def clear(shifted: ShiftedField, signs: Sequence[int]) -> ClearedField:
    """``g_i = N_i D / D_i`` with ``D = prod(sign_j D_j)`` over the distinct denominators (``signs``
    from :func:`prove_positive`, +1 or -1 each)."""
    ring = shifted.ring
    distinct = shifted.distinct_denominators()
    D = ring.constant(1)
    for d, s in zip(distinct, signs):
        D = D * (d * s)
    g = []
    for num, den in zip(shifted.numerators, shifted.denominators):
        if den.is_constant():
            g.append(num * D)
            continue
        j = next(k for k, e in enumerate(distinct) if _same_up_to_constant(den, e))
        factor = distinct[j].leading_coefficient() / den.leading_coefficient()  # den = distinct_j / factor
        rest = ring.constant(1)
        for k, (d, s) in enumerate(zip(distinct, signs)):
            if k != j:
                rest = rest * (d * s)
        # N / den = N * factor / distinct_j = N * factor * s_j * rest / D
        g.append(num * factor * signs[j] * rest)
    return ClearedField(shifted=shifted, g=tuple(g), D=D)


# -- scaling ----------------------------------------------------------------------------------------

def _pow2(x: float) -> Fraction:
    return Fraction(2) ** int(round(x))


def choose_scaling(cleared: ClearedField, domain: Mapping[str, tuple[Fraction, Fraction]] | None = None) -> Scaling:
    """Powers of two that bring the field's coefficients near 1 (see the module docstring)."""
    import numpy as np

    model = cleared.shifted.model
    n, m = model.n, len(model.disturbances)
    ring = cleared.ring
    bounds = list(model.disturbances.values())
    dist_log = [math.log2(float(b)) if b > 0 else 0.0 for b in bounds]
    fixed_states: list[float | None] = [None] * n
    if domain:
        for i, (name, eq) in enumerate(zip(model.states, model.equilibrium)):
            lo, hi = domain[name]
            half = max(abs(float(lo - eq)), abs(float(hi - eq)))
            if half > 0:
                fixed_states[i] = math.log2(half)
    # unknowns: u_0..u_{n-1} (states), tau (time), delta (denominator)
    rows, rhs = [], []

    def add(row: list[float], value: float, weight: float = 1.0) -> None:
        rows.append([weight * r for r in row])
        rhs.append(weight * value)

    for i, gi in enumerate(cleared.g):
        for mono, c in ring.float_terms(gi).items():
            row = [0.0] * (n + 2)
            for k in range(n):
                row[k] += mono[k]
            row[i] -= 1.0
            row[n] = 1.0
            row[n + 1] = -1.0
            value = -math.log2(abs(c)) - sum(mono[n + k] * dist_log[k] for k in range(m))
            add(row, value)
    for mono, c in ring.float_terms(cleared.D).items():
        row = [0.0] * (n + 2)
        for k in range(n):
            row[k] += mono[k]
        row[n + 1] = -1.0
        add(row, -math.log2(abs(c)))
    for k, fixed in enumerate(fixed_states):
        row = [0.0] * (n + 2)
        row[k] = 1.0
        if fixed is not None:
            add(row, fixed, weight=1e3)
        else:
            add(row, 0.0, weight=1e-3)  # a gentle pull to 1 where the field does not decide
    row = [0.0] * (n + 2)
    row[n] = 1.0
    add(row, 0.0, weight=1e-3)
    A, b = np.array(rows), np.array(rhs)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    states = tuple(_pow2(v) for v in x[:n])
    time = _pow2(x[n])
    denominator = _pow2(x[n + 1]) if not cleared.D.is_constant() else Fraction(1)
    disturbances = tuple(_pow2(v) if bounds[k] > 0 else Fraction(1) for k, v in enumerate(dist_log))
    outputs = []
    for y in cleared.shifted.outputs.values():
        logs = [math.log2(abs(c)) + sum(mono[k] * x[k] for k in range(n)) for mono, c in ring.float_terms(y).items()]
        outputs.append(_pow2(max(logs)) if logs else Fraction(1))
    return Scaling(states=states, disturbances=disturbances, time=time, denominator=denominator,
                   outputs=tuple(outputs))


@dataclass(frozen=True)
class ScaledField:
    """Step 3: ``dz~/dtau = g~(z~, d~) / D~(z~)``, ``|d~_k| <= bounds[k]``, outputs ``y~``."""

    cleared: ClearedField
    scaling: Scaling
    g: tuple[Poly, ...]
    D: Poly
    bounds: tuple[Fraction, ...]
    outputs: dict[str, Poly]

    @property
    def ring(self) -> Ring:
        return self.cleared.ring

    @property
    def n(self) -> int:
        return self.cleared.n

    @property
    def m(self) -> int:
        return len(self.bounds)

    @property
    def states(self) -> tuple[str, ...]:
        return self.cleared.shifted.model.states


def apply_scaling(cleared: ClearedField, scaling: Scaling) -> ScaledField:
    """The exact scaled field (see the module docstring)."""
    ring = cleared.ring
    n = cleared.n
    model = cleared.shifted.model
    gens = ring.gens()
    images = ([g * to_fmpq(s) for g, s in zip(gens[:n], scaling.states)]
              + [g * to_fmpq(s) for g, s in zip(gens[n:], scaling.disturbances)])
    g = tuple(ring.compose(gi, images) * to_fmpq(scaling.time / (s * scaling.denominator))
              for gi, s in zip(cleared.g, scaling.states))
    D = ring.compose(cleared.D, images) * to_fmpq(1 / scaling.denominator)
    bounds = tuple(b / s for b, s in zip(model.disturbances.values(), scaling.disturbances))
    outputs = {name: ring.compose(y, images) * to_fmpq(1 / s)
               for (name, y), s in zip(cleared.shifted.outputs.items(), scaling.outputs)}
    return ScaledField(cleared=cleared, scaling=scaling, g=g, D=D, bounds=bounds, outputs=outputs)


def unscale_polynomial(ring: Ring, p: Poly, scaling: Scaling, n: int) -> Poly:
    """``p(S^-1 z)``: a polynomial in the scaled states as one in the (shifted) declared states."""
    gens = ring.gens()
    images = [g * to_fmpq(1 / s) for g, s in zip(gens[:n], scaling.states)] + list(gens[n:])
    return ring.compose(p, images)


@dataclass(frozen=True)
class StateField:
    """The scaled field with the disturbances set to 0, in the ring of the states alone: what the
    stability classes (``quadratic``, ``sos_gas``, ``roa``, ``candidate``) work on."""

    ring: Ring
    g: tuple[Poly, ...]
    D: Poly

    @property
    def n(self) -> int:
        return len(self.g)


def state_field(scaled: ScaledField) -> StateField:
    ring = Ring(scaled.states)
    full = scaled.ring
    zero = {name: Fraction(0) for name in full.names[scaled.n:]}
    g = tuple(full.restrict(full.substitute(gi, zero), ring) for gi in scaled.g)
    return StateField(ring=ring, g=g, D=full.restrict(scaled.D, ring))

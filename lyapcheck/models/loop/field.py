"""A model's field at fixed parameters, made ready for the classes: shifted, cleared, scaled.

Steps, each exact:

1. **Shift** the equilibrium to 0: ``x = x_eq + z``.
2. **Clear the denominators.** ``z_i' = N_i(z, d) / D_i(z)``. Each distinct non-constant
   denominator must be proved positive everywhere (:func:`prove_positive`: ``D_j - c = sigma``
   with ``c > 0`` and ``sigma`` a sum of squares, checked exactly; or the same for ``-D_j``, whose
   sign then moves into the numerator). With ``D = prod_j D_j > 0`` the polynomial field is
   ``g_i = N_i D / D_i`` and ``z' = g(z, d) / D(z)``: a Lyapunov inequality on ``grad V . g``
   is one on ``V'`` times ``D > 0``.
3. **Scale** (:func:`choose_scaling`): ``z = A z~`` with ``A = N^-1 S`` (``S`` diagonal; ``N``
   the identity unless a denominator depends on the states through a linear form, which then
   becomes a coordinate: :func:`adapted_transform`), ``d = S_d d~``, time
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
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from lyapcheck.exact import inverse, quadratic_matrix
from lyapcheck.models.language.expressions import Rational
from lyapcheck.models.language.modelfile import Model, field_at
from lyapcheck.sos.polynomials import Poly, Ring, to_fmpq

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox


@dataclass(frozen=True)
class Scaling:
    """The coordinates the classes work in: ``z = x - x_eq = A w~`` with ``A = N^-1 S``,
    ``d = S_d d~``, ``t = T tau``, ``D = c_D D~``, outputs ``y = s_y y~`` (exact; the diagonal
    factors > 0, ``N`` unit upper... any invertible rational matrix; identity unless a denominator
    depends on a linear form, see :func:`adapted_transform`)."""

    states: tuple[Fraction, ...]
    disturbances: tuple[Fraction, ...]
    time: Fraction
    denominator: Fraction
    outputs: tuple[Fraction, ...]
    #: ``w = N z``: rows of N (None: the identity)
    transform: tuple[tuple[Fraction, ...], ...] | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"states": [str(s) for s in self.states],
                               "disturbances": [str(s) for s in self.disturbances],
                               "time": str(self.time), "denominator": str(self.denominator),
                               "outputs": [str(s) for s in self.outputs]}
        if self.transform is not None:
            out["transform"] = [[str(x) for x in row] for row in self.transform]
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "Scaling":
        transform = data.get("transform")
        return cls(states=tuple(Fraction(s) for s in data["states"]),
                   disturbances=tuple(Fraction(s) for s in data["disturbances"]),
                   time=Fraction(data["time"]), denominator=Fraction(data["denominator"]),
                   outputs=tuple(Fraction(s) for s in data["outputs"]),
                   transform=None if transform is None else tuple(tuple(Fraction(x) for x in row)
                                                                  for row in transform))

    def positive(self) -> bool:
        """The diagonal factors are > 0 and the transform (if any) is square and invertible."""
        if not all(x > 0 for x in (*self.states, *self.disturbances, self.time, self.denominator, *self.outputs)):
            return False
        if self.transform is None:
            return True
        n = len(self.states)
        if len(self.transform) != n or any(len(row) != n for row in self.transform):
            return False
        from lyapcheck import exact

        return exact.det(self.transform) != 0

    def matrix(self) -> list[list[Fraction]]:
        """``A`` with ``z = A w~``: ``N^-1 S``."""
        n = len(self.states)
        inv = inverse(self.transform) if self.transform is not None else _identity(n)
        return [[inv[i][j] * self.states[j] for j in range(n)] for i in range(n)]

    def inverse_matrix(self) -> list[list[Fraction]]:
        """``A^-1`` with ``w~ = A^-1 z``: ``S^-1 N``."""
        n = len(self.states)
        N = [list(row) for row in self.transform] if self.transform is not None else _identity(n)
        return [[N[i][j] / self.states[i] for j in range(n)] for i in range(n)]

    def to_scaled(self, z: Any) -> Any:
        """Float points ``z = x - x_eq`` (rows) in the scaled coordinates ``w~``."""
        import numpy as np

        Ainv = np.array([[float(x) for x in row] for row in self.inverse_matrix()])
        return np.asarray(z, dtype=np.float64) @ Ainv.T


def _identity(n: int) -> list[list[Fraction]]:
    return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]


def linear_images(ring: Ring, n: int, matrix: Sequence[Sequence[Fraction]]) -> list[Poly]:
    """The images ``v_i = sum_j M_ij u_j`` of the first ``n`` variables (the others unchanged)."""
    gens = ring.gens()
    images = []
    for i in range(n):
        p = ring.zero()
        for j in range(n):
            if matrix[i][j]:
                p += gens[j] * to_fmpq(matrix[i][j])
        images.append(p)
    return images + list(gens[n:])


@dataclass(frozen=True)
class ShiftedField:
    """``z' = N_i(z, d) / D_i(z)`` with ``z = x - x_eq`` (before clearing): exact, in :attr:`ring`."""

    model: Model
    ring: Ring
    numerators: tuple[Poly, ...]
    denominators: tuple[Poly, ...]
    outputs: dict[str, Poly]
    #: the box of parameters the ring's last variables range over (normalized to [-1, 1]), if any
    box: "ModelBox | None" = None

    @property
    def n(self) -> int:
        return self.model.n

    @property
    def box_names(self) -> tuple[str, ...]:
        return self.box.names if self.box is not None else ()

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


def shifted_field(model: Model, parameters: Mapping[str, Fraction] | None = None,
                  box: "ModelBox | None" = None) -> ShiftedField:
    """Step 1: the field at ``parameters`` (default: the model's) with the equilibrium moved to 0.

    With a ``box``, its parameters stay variables of the ring, normalized: a box parameter
    ``theta_i in [lo_i, hi_i]`` is ``c_i + h_i u_i`` with ``u_i in [-1, 1]`` (the ring's variable of
    the parameter's name is ``u_i``), and the others take their values.
    """
    values = dict(model.parameters if parameters is None else parameters)
    if box is None:
        ring = model.state_ring
        rhs = field_at(model, values)
        outputs_src = {name: _at(model, expr, values, ring) for name, expr in model.outputs.items()}
    else:
        ring = Ring(model.state_ring.names + box.names)
        fixed = {k: v for k, v in values.items() if k not in box.names}
        rhs = tuple(_boxed(model, r, fixed, box, ring) for r in model.dynamics)
        outputs_src = {name: _boxed(model, expr, fixed, box, ring) for name, expr in model.outputs.items()}
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
    outputs = {}
    for name, r in outputs_src.items():
        if not r.denominator.is_constant():
            raise ValueError(f"output {name} has a denominator depending on a box parameter; not supported")
        outputs[name] = shift(r.numerator) * (1 / r.denominator.leading_coefficient())
    return ShiftedField(model=model, ring=ring, numerators=tuple(nums), denominators=tuple(dens), outputs=outputs,
                        box=box)


def _at(model: Model, expr: Rational, values: Mapping[str, Fraction], ring: Ring) -> Rational:
    num = model.ring.restrict(model.ring.substitute(expr.numerator, values), ring)
    den = model.ring.restrict(model.ring.substitute(expr.denominator, values), ring)
    return Rational(ring, num, den)


def _boxed(model: Model, expr: Rational, fixed: Mapping[str, Fraction], box: "ModelBox", ring: Ring) -> Rational:
    """``expr`` with the fixed parameters set and each box parameter ``c + h u`` (exact)."""
    full = model.ring
    images = []
    for name, g in zip(full.names, full.gens()):
        if name in box.names:
            images.append(g * to_fmpq(box.half(name)) + to_fmpq(box.center(name)))
        else:
            images.append(g)
    num = full.restrict(full.compose(full.substitute(expr.numerator, fixed), images), ring)
    den = full.restrict(full.compose(full.substitute(expr.denominator, fixed), images), ring)
    return Rational(ring, num, den).normalized()


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

def _pow2(x: float | Fraction) -> Fraction:
    return Fraction(2) ** int(round(x))


def adapted_transform(cleared: ClearedField) -> tuple[tuple[Fraction, ...], ...] | None:
    """``N`` (``w = N z``) that makes a linear form a coordinate where a denominator depends on the
    states through it: a denominator whose quadratic part is ``c l(z)^2`` (rank one, exact) gets
    ``w_k = l(z) / l_k`` for a pivot state ``k``. The paper's ``(eps + sigma0 s)^2 + Delta^2`` thus
    becomes ``w_eps^2 + Delta^2``: in ``z`` no monomial basis shows that the remainder's top-degree
    part vanishes on the line ``eps + sigma0 s = 0`` (its Gram matrix cannot be positive definite),
    in ``w`` the Newton polytope does. None when no denominator has such a form."""
    shifted = cleared.shifted
    ring = shifted.ring
    n = shifted.n
    rows = _identity(n)
    used: set[int] = set()
    for den in shifted.distinct_denominators():
        quad = {m: c for m, c in ring.terms(den).items() if sum(m) == 2 and not any(m[n:])}
        if not quad:
            continue
        Q = quadratic_matrix(quad, n)
        k = next((i for i in range(n) if Q[i][i] != 0 and i not in used), None)
        if k is None:
            continue
        row = Q[k]
        if all(Q[i][j] * Q[k][k] == Q[i][k] * Q[k][j] for i in range(n) for j in range(n)):  # rank one
            if sum(1 for x in row if x) < 2:
                continue  # already a coordinate
            rows[k] = [x / row[k] for x in row]
            used.add(k)
    if not used:
        return None
    from lyapcheck import exact

    if exact.det(tuple(tuple(r) for r in rows)) == 0:
        return None
    return tuple(tuple(r) for r in rows)


def choose_scaling(cleared: ClearedField, domain: Mapping[str, tuple[Fraction, Fraction]] | None = None) -> Scaling:
    """An adapted linear transform (:func:`adapted_transform`), then powers of two that bring the
    field's coefficients near 1 (see the module docstring): the least-squares fit of their logarithms,
    solved exactly (:func:`lyapcheck.exact.least_squares`), so that the same field gets the same
    scaling on every platform."""
    from lyapcheck import exact

    model = cleared.shifted.model
    n, m = model.n, len(model.disturbances)
    ring = cleared.ring
    transform = adapted_transform(cleared)
    if transform is not None:
        images = linear_images(ring, n, inverse(transform))
        g_w = [sum((ring.compose(gj, images) * to_fmpq(transform[i][j]) for j, gj in enumerate(cleared.g)
                    if transform[i][j]), ring.zero()) for i in range(n)]
        D_w = ring.compose(cleared.D, images)
        outputs_w = [ring.compose(y, images) for y in cleared.shifted.outputs.values()]
        domain = None  # a box in z is not a box in w
    else:
        g_w, D_w, outputs_w = list(cleared.g), cleared.D, list(cleared.shifted.outputs.values())
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
    rows: list[list[Fraction]] = []
    rhs: list[Fraction] = []
    strong, gentle = Fraction(1000), Fraction(1, 1000)

    def add(row: list[float], value: float, weight: Fraction = Fraction(1)) -> None:
        rows.append([weight * Fraction(r) for r in row])
        rhs.append(weight * Fraction(value))

    for i, gi in enumerate(g_w):
        for mono, c in ring.float_terms(gi).items():
            if any(mono[n + k] for k in range(m) if bounds[k] == 0):
                continue  # a disturbance of bound 0 is identically 0 (apply_scaling): its terms are not there
            row = [0.0] * (n + 2)
            for k in range(n):
                row[k] += mono[k]
            row[i] -= 1.0
            row[n] = 1.0
            row[n + 1] = -1.0
            value = -math.log2(abs(c)) - sum(mono[n + k] * dist_log[k] for k in range(m))
            add(row, value)
    for mono, c in ring.float_terms(D_w).items():
        row = [0.0] * (n + 2)
        for k in range(n):
            row[k] += mono[k]
        row[n + 1] = -1.0
        add(row, -math.log2(abs(c)))
    for k, fixed in enumerate(fixed_states):
        row = [0.0] * (n + 2)
        row[k] = 1.0
        if fixed is not None:
            add(row, fixed, weight=strong)
        else:
            add(row, 0.0, weight=gentle)  # a gentle pull to 1 where the field does not decide
    row = [0.0] * (n + 2)
    row[n] = 1.0
    add(row, 0.0, weight=gentle)
    x = exact.least_squares(rows, rhs)
    states = tuple(_pow2(v) for v in x[:n])
    time = _pow2(x[n])
    denominator = _pow2(x[n + 1]) if not D_w.is_constant() else Fraction(1)
    disturbances = tuple(_pow2(v) if bounds[k] > 0 else Fraction(1) for k, v in enumerate(dist_log))
    outputs = []
    for y in outputs_w:  # sized by its deviation: sos_bound bounds |y - y_eq| (lyapcheck.models.classes.bounds)
        logs = [math.log2(abs(c)) + sum(mono[k] * float(x[k]) for k in range(n))
                for mono, c in ring.float_terms(y).items() if any(mono)]
        outputs.append(_pow2(max(logs)) if logs else Fraction(1))
    return Scaling(states=states, disturbances=disturbances, time=time, denominator=denominator,
                   outputs=tuple(outputs), transform=transform)


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
    """The exact field in the scaled coordinates: ``g~ = (T / c_D) A^-1 g(A w~, S_d d~)``,
    ``D~ = D(A w~) / c_D``, ``y~ = y(A w~) / s_y`` (see :class:`Scaling`). A disturbance of bound 0 is
    identically 0 and set to 0 there (its variable stays in the ring, in no polynomial)."""
    ring = cleared.ring
    n = cleared.n
    model = cleared.shifted.model
    A = scaling.matrix()
    Ainv = scaling.inverse_matrix()
    gens = ring.gens()
    m = len(scaling.disturbances)
    # a disturbance of bound 0 is identically 0: its image is 0, so that no class, and no check of its
    # certificate, carries a variable that only a multiplier of |d| <= 0 could hold (ill-posed programs)
    images = (linear_images(ring, n, A)[:n]
              + [g * to_fmpq(s) if b > 0 else ring.zero()
                 for g, s, b in zip(gens[n:n + m], scaling.disturbances, model.disturbances.values())]
              + list(gens[n + m:]))
    composed = [ring.compose(gi, images) for gi in cleared.g]
    factor = to_fmpq(scaling.time / scaling.denominator)
    g = tuple(sum((composed[j] * to_fmpq(Ainv[i][j]) for j in range(n) if Ainv[i][j]), ring.zero()) * factor
              for i in range(n))
    D = ring.compose(cleared.D, images) * to_fmpq(1 / scaling.denominator)
    bounds = tuple(b / s for b, s in zip(model.disturbances.values(), scaling.disturbances))
    outputs = {name: ring.compose(y, images) * to_fmpq(1 / s)
               for (name, y), s in zip(cleared.shifted.outputs.items(), scaling.outputs)}
    return ScaledField(cleared=cleared, scaling=scaling, g=g, D=D, bounds=bounds, outputs=outputs)


def unscale_polynomial(ring: Ring, p: Poly, scaling: Scaling, n: int, box: "ModelBox | None" = None) -> Poly:
    """``p(A^-1 z)``: a polynomial in the scaled states as one in the (shifted) declared states; with
    a box, its normalized parameters ``u`` become the declared ones, ``u = (theta - c) / h``."""
    images = linear_images(ring, n, scaling.inverse_matrix())
    if box is not None:
        for k, name in enumerate(ring.names):
            if name in box.names:
                images[k] = (images[k] - to_fmpq(box.center(name))) * to_fmpq(1 / box.half(name))
    return ring.compose(p, images)


def declared_quadratic(scaling: Scaling, P_scaled: Sequence[Sequence[Fraction]]) -> list[list[Fraction]]:
    """``P`` of ``V = z^T P z`` from ``V = w~^T P~ w~``: ``A^-T P~ A^-1``."""
    Ainv = scaling.inverse_matrix()
    n = len(Ainv)
    tmp = [[sum((P_scaled[i][k] * Ainv[k][j] for k in range(n)), Fraction(0)) for j in range(n)] for i in range(n)]
    return [[sum((Ainv[k][i] * tmp[k][j] for k in range(n)), Fraction(0)) for j in range(n)] for i in range(n)]


@dataclass(frozen=True)
class StateField:
    """The scaled field as the stability classes (``quadratic``, ``sos_gas``, ``roa``, ``candidate``)
    see it: in the ring of the states, then (robust form) the disturbances that enter it, each
    normalized to ``u in [-1, 1]``, then a box's parameters (normalized the same way). Every variable
    after the states is a box coordinate of :func:`lyapcheck.models.engines.search.box_multipliers`; a ``V``
    that depends on none of the first :attr:`disturbances` of them is a common Lyapunov function for
    every disturbance signal within its bounds."""

    ring: Ring
    g: tuple[Poly, ...]
    D: Poly
    #: how many disturbances follow the states in the ring (0: disturbances set to 0, the nominal loop)
    disturbances: int = 0

    @property
    def n(self) -> int:
        return len(self.g)

    @property
    def p(self) -> int:
        """How many box coordinates (disturbances, then a box's parameters) follow the states."""
        return self.ring.nvars - len(self.g)

    @property
    def claim_ring(self) -> Ring:
        """The ring a certificate's ``V`` is stated in: the states and a box's parameters (a ``V``
        never depends on a disturbance)."""
        if not self.disturbances:
            return self.ring
        names = self.ring.names
        return Ring(names[:self.n] + names[self.n + self.disturbances:])


def active_disturbances(scaled: ScaledField) -> list[int]:
    """The disturbances (indices) with a bound > 0 that enter the field's right-hand side or its
    denominator: the ones a robust claim has to cover."""
    return entering(scaled.ring, scaled.n, (*scaled.g, scaled.D), scaled.bounds)


def entering(ring: Ring, n: int, polys: Sequence[Poly], bounds: Sequence[Fraction]) -> list[int]:
    """The disturbances (indices; the ring's variables after the ``n`` states) with a bound > 0
    that occur in one of ``polys``."""
    used = set()
    for p in polys:
        for m in ring.support(p):
            used |= {k for k in range(len(bounds)) if m[n + k]}
    return [k for k in sorted(used) if bounds[k] > 0]


def disturbances_vanish(scaled: ScaledField) -> bool:
    """Whether every disturbance leaves the equilibrium in place: ``g(0, d) = 0`` for every ``d``
    (they enter multiplied by the states, as in ``x' = -x + d x``). Then a stability property can
    hold for every disturbance signal (:func:`state_field` with ``robust=True``); otherwise a
    disturbance moves the equilibrium and only an ultimate bound can speak of it (``sos_bound``)."""
    ring = scaled.ring
    zero = {name: Fraction(0) for name in ring.names[:scaled.n]}
    return all(ring.substitute(gi, zero) == ring.zero() for gi in scaled.g)


def state_field(scaled: ScaledField, robust: bool = False) -> StateField:
    """The field the stability classes work on. Nominal (``robust=False``): the disturbances set
    to 0, the ring keeps the states and the box's parameters (if any). Robust: each disturbance of
    :func:`active_disturbances` stays, as ``d~_k = b_k u_k`` with ``u_k in [-1, 1]`` (``b_k`` its
    scaled bound), the others set to 0; sound only where :func:`disturbances_vanish` (the caller
    checks)."""
    box_names = scaled.cleared.shifted.box_names
    full = scaled.ring
    n = scaled.n
    kept = active_disturbances(scaled) if robust else []
    kept_names = tuple(full.names[n + k] for k in kept)
    ring = Ring(scaled.states + kept_names + box_names)
    zero = {name: Fraction(0) for name in full.names[n:] if name not in box_names and name not in kept_names}
    gens = full.gens()
    images = list(gens)
    for k in kept:
        images[n + k] = gens[n + k] * to_fmpq(scaled.bounds[k])

    def restricted(p: Poly) -> Poly:
        p = full.substitute(p, zero)
        if kept:
            p = full.compose(p, images)
        return full.restrict(p, ring)

    return StateField(ring=ring, g=tuple(restricted(gi) for gi in scaled.g), D=restricted(scaled.D),
                      disturbances=len(kept))


def robust_field(scaled: ScaledField) -> StateField | None:
    """The field with every disturbance a box coordinate (:func:`state_field`, robust), where a
    robust stability claim can exist: the model has disturbances that enter the field, and they
    vanish at the equilibrium. None otherwise (no disturbance enters: the nominal claim covers them
    all; or one moves the equilibrium: only ``sos_bound`` can speak of it)."""
    if not active_disturbances(scaled) or not disturbances_vanish(scaled):
        return None
    return state_field(scaled, robust=True)

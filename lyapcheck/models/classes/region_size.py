"""The size of a certified region ``{V <= level}`` in the user's terms: the largest ball and the reach along each axis.

A certified ``roa`` or ``candidate`` states its set as ``{x : V(x - x_eq) <= level}`` (a loop with
functions: ``V(x - x_eq, a(x) - a(x_eq))``, each auxiliary at its definition; a ball-arithmetic
region also within its ``box``). Two figures say how large it is, in the declared states (SI,
unscaled), each a lower bound proved in rational arithmetic from ``V`` and ``level`` alone:

* ``ball_radius``: a radius ``r`` such that the ball ``|x - x_eq| <= r`` lies in the set. ``V`` is
  bounded above on the ball by a polynomial ``B(r)`` with non-negative coefficients: the quadratic
  part in the states ``z^T P z`` by ``mu r^2``, with ``mu`` a rational whose ``mu I - P`` is proved
  positive semidefinite exactly (:func:`lyapcheck.sos.definiteness.is_positive_semidefinite`), and
  every other term ``c_a z^a`` by ``|c_a| peak_a r^|a|`` (the triangle inequality), where
  ``peak_a >= prod (a_i / |a|)^(a_i / 2)``, the largest ``|z^a|`` on the unit sphere. ``r`` is
  the root of ``B(r) = level`` (``B`` increases), bracketed exactly (:mod:`lyapcheck.roots`); for a
  quadratic V it is ``sqrt(level / mu)`` rounded down.
* ``axis_extents``: for each state ``x_i`` an ``a_i`` such that the segment ``{x_eq + t e_i : |t| <= a_i}``
  lies in the set: the first positive root of ``level - V(t e_i)`` and of ``level - V(-t e_i)``,
  isolated exactly (Sturm); on a polynomial V this is exact up to the rounding down. It is the set's
  *reach* along the axis through the equilibrium, not its projection on the axis (the set may reach
  farther in ``x_i`` away from that line).

An auxiliary of a loop with functions enters through a bound on its deviation: for
``f(u)`` with ``f`` one of :data:`LIPSCHITZ_ONE` and ``u`` affine in the states (and earlier such
auxiliaries), ``|f(u) - f(u_eq)| <= |u - u_eq| <= w . |x - x_eq|``; for ``sin``/``cos`` at an
equilibrium where its slope is 0 (``cos`` at value +-1, ``sin`` at +-1) also
``<= (w . |x - x_eq|)^2 / 2``. Each figure is computed with the first-order bounds and with the
second-order ones where they exist, and the larger proved figure kept (both are sound). A ``V``
using any other auxiliary, or a box's parameter, gets no figures, and the certificate says why.

Figures are rounded down to :data:`SIZE_DIGITS` significant digits. ``verify`` re-derives them with
:func:`region_size` from the certificate's ``V``, ``level`` and ``ball_mu`` (``mu`` is re-checked,
not re-searched: a float eigenvalue may differ in its last bit elsewhere) and refuses any difference.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Final, Mapping, Sequence

from lyapcheck.exact import floor_digits, quadratic_matrix, read_rational, sqrt_lower, sqrt_upper
from lyapcheck.roots import Univariate, evaluate, first_positive_root, trim

#: the classes whose certified set's size is stated
SIZED_CLASSES: Final = ("roa", "candidate")
#: significant digits a size figure is rounded down to
SIZE_DIGITS: Final = 10
#: functions whose deviation is at most their argument's (Lipschitz constant 1)
LIPSCHITZ_ONE: Final = frozenset({"sin", "cos", "tanh", "atan", "sat", "abs"})
#: digits of the upper bound of a monomial's peak on the unit sphere (the ball's bound of V)
PEAK_DIGITS: Final = 12
#: tries of a float guess of ``mu`` (lyapcheck.tolerances.SIZE_MU_ROOM) before Gershgorin's bound
MU_TRIES: Final = 8

Monomial = tuple[int, ...]


@dataclass(frozen=True)
class DeviationBound:
    """``|a(x) - a(x_eq)| <= factor (weights . |x - x_eq|)^power`` for an auxiliary ``a``."""

    weights: tuple[Fraction, ...]
    power: int = 1
    factor: Fraction = Fraction(1)


@dataclass(frozen=True)
class Extra:
    """A variable of ``V`` after the states: an auxiliary with its deviation bounds (first-order,
    then second-order where one exists), or a variable with none (``bounds`` empty: why in ``what``)."""

    name: str
    what: str
    bounds: tuple[DeviationBound, ...] = ()


@dataclass
class RegionSize:
    """The exact figures (None / empty when left out; ``omitted`` then says why)."""

    ball_radius: Fraction | None = None
    ball_mu: Fraction | None = None
    axis_extents: dict[str, Fraction] = field(default_factory=dict)
    unbounded_axes: list[str] = field(default_factory=list)
    method: str = ""
    omitted: str = ""

    def to_json(self) -> dict[str, Any]:
        """The certificate's ``size`` table (exact rationals as text)."""
        out: dict[str, Any] = {}
        if self.ball_radius is not None:
            out["ball_radius"] = str(self.ball_radius)
        if self.ball_mu is not None:
            out["ball_mu"] = str(self.ball_mu)
        if self.axis_extents:
            out["axis_extents"] = {s: str(a) for s, a in self.axis_extents.items()}
        if self.unbounded_axes:
            out["unbounded_axes"] = list(self.unbounded_axes)
        out["method"] = self.method
        if self.omitted:
            out["omitted"] = self.omitted
        return out

    def figures(self) -> dict[str, Any]:
        """The condition's ``size`` figure (floats of the exact figures), empty when none."""
        out: dict[str, Any] = {}
        if self.ball_radius is not None:
            out["ball_radius"] = float(self.ball_radius)
        if self.axis_extents:
            out["axis_extents"] = {s: float(a) for s, a in self.axis_extents.items()}
        return out


# -- the auxiliaries' bounds ----------------------------------------------------------------------

def auxiliary_extras(system: Any) -> list[Extra]:
    """One :class:`Extra` per auxiliary of a recast loop (:class:`~lyapcheck.models.language.recast.RecastSystem`),
    in the ring's order after the states."""
    n = system.n
    ring = system.ring
    first: dict[str, tuple[Fraction, ...]] = {s: tuple(Fraction(int(i == k)) for i in range(n))
                                              for k, s in enumerate(system.states)}
    out = []
    for aux in system.auxiliaries:
        weights = _affine_weights(ring, aux.argument, first, n) if aux.argument is not None else None
        if aux.function not in LIPSCHITZ_ONE or weights is None or aux.value is None:
            out.append(Extra(aux.name, aux.definition))
            continue
        first[aux.name] = weights
        bounds = [DeviationBound(weights)]
        if aux.function in ("sin", "cos") and abs(aux.value) == 1:  # its slope is 0 at the equilibrium
            bounds.append(DeviationBound(weights, 2, Fraction(1, 2)))
        out.append(Extra(aux.name, aux.definition, tuple(bounds)))
    return out


def _affine_weights(ring: Any, argument: Any, first: Mapping[str, tuple[Fraction, ...]], n: int
                    ) -> tuple[Fraction, ...] | None:
    """``w`` with ``|u(x) - u(x_eq)| <= w . |x - x_eq|`` for an affine argument ``u`` of states and
    bounded auxiliaries, or None."""
    total = [Fraction(0)] * n
    for m, c in ring.terms(argument).items():
        degree = sum(m)
        if degree == 0:
            continue
        if degree > 1:
            return None
        name = ring.names[m.index(1)]
        if name not in first:
            return None
        total = [t + abs(Fraction(c)) * w for t, w in zip(total, first[name])]
    return tuple(total)


def extras_of(variables: Sequence[str], states: Sequence[str], system: Any = None) -> list[Extra]:
    """The :class:`Extra` of each of ``V``'s variables after the states (``variables``: all of them,
    states first): an auxiliary of ``system`` (a recast loop) with its bounds; any other (a box's
    parameter) with none. The bounds come from the model, never from the certificate."""
    n = len(states)
    if list(variables[:n]) != list(states):
        raise ValueError("V's variables must begin with the states, in their order")
    known = {e.name: e for e in auxiliary_extras(system)} if system is not None else {}
    return [known.get(v, Extra(v, v)) for v in variables[n:]]


# -- the figures ----------------------------------------------------------------------------------

def read_terms(data: Any, nvars: int) -> dict[Monomial, Fraction]:
    """A stated polynomial's terms (``{"terms": [[c, [e, ...]], ...]}``), ``nvars`` exponents each."""
    from lyapcheck.sos.certificates import exponent

    if not isinstance(data, Mapping) or not isinstance(data.get("terms"), list):
        raise ValueError("V must be a table with a list 'terms'")
    out: dict[Monomial, Fraction] = {}
    for term in data["terms"]:
        if not isinstance(term, list) or len(term) != 2 or not isinstance(term[1], list) or len(term[1]) != nvars:
            raise ValueError(f"V: a term must be [coefficient, [{nvars} exponents]]")
        m = tuple(exponent(e, "V.terms") for e in term[1])
        out[m] = out.get(m, Fraction(0)) + read_rational(term[0])
    return {m: c for m, c in out.items() if c != 0}


def region_size(V: Mapping[Monomial, Fraction], level: Fraction, states: Sequence[str], extras: Sequence[Extra] = (),
                box: Mapping[str, tuple[Fraction, Fraction]] | None = None, mu: Fraction | None = None
                ) -> RegionSize:
    """The size figures of ``{V <= level}`` (within ``box``, deviations, where given): ``V`` over the
    states then ``extras``, in deviations from the equilibrium. ``mu``: the stated bound of the
    quadratic part's largest eigenvalue (``verify``), re-checked exactly (ValueError when it fails);
    None: found here."""
    n = len(states)
    used = {j for m in V for j in range(n, len(m)) if m[j]}
    blind = [extras[j - n] for j in sorted(used) if not extras[j - n].bounds]
    if blind:
        why = ", ".join(e.what for e in blind)
        return RegionSize(method="", omitted=f"V uses {why}, whose deviation from the equilibrium has no bound here")
    if V.get(tuple([0] * (n + len(extras))), Fraction(0)) >= level or level <= 0:
        return RegionSize(omitted="the equilibrium is not inside {V <= level}")
    variants = _variants(extras)
    P = _quadratic_part(V, n)
    if P is not None:
        mu = _checked_mu(P, mu) if mu is not None else _find_mu(P)
    elif mu is not None:
        raise ValueError("ball_mu is stated, but V has no quadratic part in the states")
    out = RegionSize(ball_mu=mu)
    radii = [r for r in (_ball(V, level, n, variant, P, mu) for variant in variants) if r is not None]
    out.ball_radius = max(radii) if radii else None
    for i, s in enumerate(states):
        reaches = [_axis(V, level, n, i, variant) for variant in variants]
        # (each variant is sound, so the largest reach holds; None: a variant holds the whole line)
        reach = None if any(r is None for r in reaches) else max(r for r in reaches if r is not None)
        if box is not None and s in box:
            lo, hi = box[s]
            side = max(min(-lo, hi), Fraction(0))
            reach = side if reach is None or side < reach else reach
        if reach is None:
            out.unbounded_axes.append(s)
        else:
            out.axis_extents[s] = floor_digits(reach, SIZE_DIGITS) if reach > 0 else Fraction(0)
    if box is not None and out.ball_radius is not None:
        side = min(min(-lo, hi) for lo, hi in box.values())
        out.ball_radius = max(min(out.ball_radius, side), Fraction(0))
    if out.ball_radius is not None and out.ball_radius > 0:
        out.ball_radius = floor_digits(out.ball_radius, SIZE_DIGITS)
    out.method = _method(V, n, P is not None, bool(used), box is not None)
    return out


def _method(V: Mapping[Monomial, Fraction], n: int, quadratic_part: bool, auxiliaries: bool, boxed: bool) -> str:
    quadratic = all(sum(m) == 2 for m in V) and not auxiliaries
    ball = ("ball: r^2 = level / mu, mu I - P proved positive semidefinite exactly" if quadratic else
            "ball: the largest r with B(r) <= level, B bounding V on |x - x_eq| <= r"
            + (" (mu r^2 for its quadratic part, mu I - P proved positive semidefinite exactly; " if quadratic_part
               else " (") + "|c| r^|a| prod (a_i/|a|)^(a_i/2) for every other term" + ("; each auxiliary by its deviation bound" if auxiliaries
                                                               else "") + ")")
    axes = ("axes: the first root of level - V(t e_i) on each side, isolated exactly"
            + ("; an auxiliary's term bounded by its deviation bound" if auxiliaries else ""))
    return f"{ball}; {axes}" + ("; both within the certificate's box" if boxed else "") + \
        f"; rounded down to {SIZE_DIGITS} significant digits"


def _variants(extras: Sequence[Extra]) -> list[list[DeviationBound | None]]:
    """The first-order bounds of every extra, then (where any has one) its second-order ones."""
    first = [e.bounds[0] if e.bounds else None for e in extras]
    second = [e.bounds[-1] if e.bounds else None for e in extras]
    return [first] if second == first else [first, second]


def _quadratic_part(V: Mapping[Monomial, Fraction], n: int) -> list[list[Fraction]] | None:
    """``P`` of the terms of degree 2 in the states alone (None when there are none)."""
    if not any(sum(m) == 2 and not any(m[n:]) for m in V):
        return None
    return quadratic_matrix(V, n)


def _checked_mu(P: list[list[Fraction]], mu: Fraction) -> Fraction:
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n = len(P)
    if mu < 0 or not is_positive_semidefinite([[(mu if i == j else 0) - P[i][j] for j in range(n)] for i in range(n)]):
        raise ValueError(f"ball_mu = {mu}: mu I - P is not positive semidefinite (or mu < 0)")
    return mu


def _find_mu(P: list[list[Fraction]]) -> Fraction:
    """A short rational ``mu >= max(lambda_max(P), 0)``, proved (a float guess widened until the exact
    check passes; Gershgorin's bound, always valid, as the last resort)."""
    import numpy as np

    from lyapcheck.exact import to_rational
    from lyapcheck.tolerances import SIZE_MU_ROOM

    top = max(float(np.max(np.linalg.eigvalsh(np.array([[float(x) for x in row] for row in P])))), 0.0)
    for k in range(MU_TRIES):  # (12 digits keep mu short; each try widens the room a thousandfold)
        guess = to_rational(top * (1 + SIZE_MU_ROOM * 1000 ** k), 12)
        try:
            return _checked_mu(P, guess)
        except ValueError:
            continue
    return _checked_mu(P, max(max(sum((abs(x) for x in row), Fraction(0)) for row in P), Fraction(0)))


def _term_bound(m: Monomial, n: int, scale: Sequence[Fraction], variant: Sequence[DeviationBound | None]
                ) -> tuple[Fraction, int]:
    """``(k, d)`` with ``|z^m| <= k t^d`` where each state's deviation is at most ``scale[i] t``."""
    k, d = Fraction(1), 0
    for i in range(n):
        if m[i]:
            k *= scale[i] ** m[i]
            d += m[i]
    for j, e in enumerate(m[n:]):
        if e:
            b = variant[j]
            assert b is not None
            weight = sum((w * s for w, s in zip(b.weights, scale)), Fraction(0))
            k *= (b.factor * weight ** b.power) ** e
            d += b.power * e
    return k, d


def _add(poly: Univariate, degree: int, c: Fraction) -> None:
    while len(poly) <= degree:
        poly.append(Fraction(0))
    poly[degree] += c


def _sphere_peak(a: Sequence[int]) -> Fraction:
    """A rational upper bound of ``max |x^a|`` on the unit sphere: ``prod (a_i / |a|)^(a_i / 2)``
    (Lagrange: the maximum is at ``x_i^2 = a_i / |a|``), so ``|x^a| <= peak r^|a|`` on the ball; 1
    for ``|a| = 0``."""
    d = sum(a)
    if d == 0:
        return Fraction(1)
    q = Fraction(1)
    for e in a:
        q *= Fraction(e, d) ** e
    return sqrt_upper(q, PEAK_DIGITS)


def _ball(V: Mapping[Monomial, Fraction], level: Fraction, n: int, variant: Sequence[DeviationBound | None],
          P: list[list[Fraction]] | None, mu: Fraction | None) -> Fraction | None:
    """The largest ``r`` (exact lower bound) with ``B(r) <= level``, for this variant of the bounds."""
    B: Univariate = []
    if P is not None:
        assert mu is not None
        _add(B, 2, mu)
    # a bound of an auxiliary in the ball: w . |x - x_eq| <= |w| r, |w| rounded up
    norms = [Fraction(1)] * n
    unit_variant = [None if b is None else DeviationBound((sqrt_upper(sum((w * w for w in b.weights), Fraction(0))),)
                                                          + (Fraction(0),) * (n - 1), b.power, b.factor)
                    for b in variant]
    for m, c in V.items():
        if P is not None and sum(m) == 2 and not any(m[n:]):
            continue
        k, d = _term_bound(m, n, norms, unit_variant)
        _add(B, d, abs(c) * k * _sphere_peak(m[:n]))
    B = trim(B)
    if len(B) <= 1:
        return None  # (V constant: no ball bounds it)
    if len(B) == 3 and B[0] == 0 and B[1] == 0:
        return sqrt_lower(level / B[2])
    root = first_positive_root([B[0] - level, *B[1:]])
    return None if root is None else root[0]


def _axis(V: Mapping[Monomial, Fraction], level: Fraction, n: int, i: int, variant: Sequence[DeviationBound | None]
          ) -> Fraction | None:
    """The reach along ``e_i`` (exact lower bound; None: the whole line lies in the set)."""
    exact: Univariate = []
    bound: Univariate = []
    scale = [Fraction(int(k == i)) for k in range(n)]
    for m, c in V.items():
        if any(m[k] for k in range(n) if k != i):
            continue  # another state's deviation is 0 on the axis
        k, d = _term_bound(m, n, scale, variant)
        if k == 0:
            continue  # an auxiliary that does not depend on x_i: its deviation is 0 on the axis
        if any(m[n:]):
            _add(bound, d, abs(c) * k)
        else:
            _add(exact, d, c)
    reaches = []
    for sign in (1, -1):
        q = [Fraction(0)] * max(len(exact), len(bound), 1)
        for d, c in enumerate(exact):
            q[d] += c * sign ** d
        for d, c in enumerate(bound):
            q[d] += c
        q[0] -= level
        root = first_positive_root(q) if len(trim(q)) > 1 else None
        if root is not None:
            reaches.append(root[0])
    return min(reaches) if reaches else None


# -- a certified condition's size -----------------------------------------------------------------

def condition_size(certificate: Mapping[str, Any], states: Sequence[str], extras: Sequence[Extra],
                   mu: Fraction | None = None) -> RegionSize:
    """The figures of a certified ``roa`` / ``candidate`` from its certificate: ``V`` over the
    states then ``extras``, its ``level``, and a ball-arithmetic region's ``box``."""
    n = len(states)
    V = read_terms(certificate["V"], n + len(extras))
    level = read_rational(certificate["level"], "level")
    box = certificate.get("box") if certificate.get("kind") == "interval" else None
    corners = None
    if box is not None:
        if not isinstance(box, Mapping) or list(box) != list(states):
            raise ValueError("box: one interval per state, in the states' order")
        corners = {s: (read_rational(box[s][0]), read_rational(box[s][1])) for s in states}
    return region_size(V, level, states, extras, corners, mu)


def state_units(units: Mapping[str, str] | None, states: Sequence[str]) -> dict[str, str] | None:
    """Each state's unit as ``[units]`` writes it (``''``: dimensionless), None without ``[units]``."""
    if not units:
        return None
    return {s: "" if str(units.get(s, "")).strip() in ("", "1") else str(units[s]).strip() for s in states}


def attach(result: Any, states: Sequence[str], extras: Sequence[Extra], units: Mapping[str, str] | None) -> None:
    """Write a certified region's size into its result: ``certificate.size`` (exact, with the states'
    units where ``[units]`` gives them) and the figure ``size`` (floats)."""
    size = condition_size(result.certificate, states, extras)
    data = size.to_json()
    table = state_units(units, states)
    if table is not None:
        data["units"] = table
    result.certificate["size"] = data
    figures = size.figures()
    if figures:
        result.numbers["size"] = figures


def check_size(c: Mapping[str, Any], states: Sequence[str], extras: Sequence[Extra],
               units: Mapping[str, str] | None) -> tuple[bool, str]:
    """``verify`` of a certified region's size: re-derived from its certificate (``ball_mu``
    re-checked), equal to the certificate's ``size`` and to the condition's figure ``size``."""
    cert = c["certificate"]
    stated = cert.get("size")
    if stated is None:
        if "size" in c:
            return False, "a size figure is stated without the certificate's size table"
        return True, "no size figures stated"
    if not isinstance(stated, Mapping):
        return False, "the certificate's size must be a table"
    mu = read_rational(stated["ball_mu"], "size.ball_mu") if "ball_mu" in stated else None
    try:
        size = condition_size(cert, states, extras, mu)
    except ValueError as exc:
        return False, f"the size: {exc}"
    expected = size.to_json()
    table = state_units(units, states)
    if table is not None:
        expected["units"] = table
    for key in sorted(set(expected) | set(stated)):
        if stated.get(key) != expected.get(key):
            return False, (f"the size's {key} {stated.get(key)!r} is not the one V and the level give "
                           f"({expected.get(key)!r})")
    figures = size.figures()
    if c.get("size", {}) != figures:
        return False, f"the stated size figures {c.get('size')!r} are not the certificate's ({figures!r})"
    return True, "the largest ball and the axis extents are re-derived exactly from V and the level"


def check_size_rows(model: Any, conditions: Mapping[str, Any], rows: list[tuple[str, bool, str]],
                    variables: Sequence[str] | None = None, system: Any = None) -> None:
    """``verify``'s row for each certified region whose certificate states its size, named by its
    class (a failed row demotes the class): :func:`check_size`. ``variables``: V's variables as the
    model gives them (None: the certificate's, each auxiliary's bound taken from ``system``, the
    model's recasting, never from the certificate)."""
    for name, c in conditions.items():
        if name not in SIZED_CLASSES or not isinstance(c, Mapping) or c.get("status") != "certified" or \
                not isinstance(c.get("certificate"), Mapping) or ("size" not in c and "size" not in c["certificate"]):
            continue
        try:
            names = variables if variables is not None else c["certificate"]["variables"]
            ok, why = check_size(c, model.states, extras_of(names, model.states, system), model.units)
        except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError) as exc:
            ok, why = False, f"the size is malformed: {type(exc).__name__}: {str(exc)[:200]}"
        rows.append((name, ok, why if ok else f"{name}: {why}"))


__all__ = ["DeviationBound", "Extra", "LIPSCHITZ_ONE", "RegionSize", "SIZED_CLASSES", "SIZE_DIGITS", "attach",
           "auxiliary_extras", "extras_of", "check_size", "check_size_rows", "condition_size", "read_terms",
           "region_size", "state_units"]

"""Non-polynomial closed loops, recast exactly into polynomial ones with auxiliary variables.

A model file's ``[dynamics]`` may use ``sin cos exp sqrt atan tanh abs min max sat`` and the
constant ``pi`` (DESIGN.md, "Model files"; docs/model-files.md). Each distinct function
application becomes an **auxiliary variable**, with the exact relations it satisfies
(Papachristodoulou & Prajna, "On the construction of Lyapunov functions using the sum of squares
decomposition", CDC 2002; "Analysis of non-polynomial systems using the sum of squares
decomposition", 2005). Every relation below is an identity or a proved inequality, true for every
real argument; leaving one out only weakens what can be proved, adding a false one would be a
soundness bug (tests/test_recast.py checks each at many points and symbolically):

==========  =====================================  ==========================================
function    flow along the trajectories             relations (for every real ``u``)
==========  =====================================  ==========================================
sin, cos    ``s' = c u'``, ``c' = -s u'``           ``s^2 + c^2 = 1``; ``u^2 - s^2 >= 0``;
            (one pair per argument)                 ``u^2/2 - (1 - c) >= 0``;
                                                    ``u s - u^2 + u^4/6 >= 0``;
                                                    ``1 - u^2/2 + u^4/24 - c >= 0``
exp         ``e' = e u'``                            ``e >= 0``; ``e - 1 - u >= 0``;
                                                    ``1 - e (1 - u) >= 0``
sqrt(q)     ``r' = q' / (2 r)`` (when ``q >= c^2``   ``r^2 = q``; ``r >= 0``; ``r - c >= 0``
            with ``c > 0`` is proved)               (with the proved ``c``)
atan        ``a' = u' / (1 + u^2)``                  ``a u >= 0``; ``u^2 - a^2 >= 0``;
                                                    ``1.571^2 - a^2 >= 0`` (``pi/2 < 1.571``);
                                                    ``u a - u^2 + u^4/3 >= 0``
tanh        ``t' = (1 - t^2) u'``                    ``1 - t^2 >= 0``; ``t u >= 0``; ``t (u - t) >= 0``;
                                                    ``u t - u^2 + u^4/3 >= 0``
abs         none (not differentiable)               ``b^2 = u^2``; ``b >= 0``
sat(u, L)   none (not differentiable)               ``(u - q)(L^2 - q^2) = 0``; ``L^2 - q^2 >= 0``;
                                                    ``q (u - q) >= 0`` (these three hold for
                                                    ``q = clip(u, -L, L)`` and for no other ``q``)
==========  =====================================  ==========================================

``min(a, b) = (a + b - |a - b|)/2`` and ``max(a, b) = (a + b + |a - b|)/2``. An auxiliary with a
flow is **smooth**: a Lyapunov function may use it. The others (``abs``, ``sat``, and any function
of them) are **algebraic**: they enter the field and its relations only; the piecewise structure
of a saturation is carried by its relations, whose S-procedure multipliers split the state space
into its regions with one ``V`` (the three zones users otherwise write by hand).

Exactness: ``sin(u0 + k pi/12)`` is expanded by the angle-addition formula with the exact
``cos(k pi/12)`` and ``sin(k pi/12)`` in ``Q(sqrt 2, sqrt 3)``; those two square roots are constant
auxiliaries ``rt2``, ``rt3`` with ``rt2^2 = 2``, ``rt2 >= 0`` (and the same for 3), never floats.
An argument's value at the equilibrium must make the auxiliary's value rational (``sin(0)``,
``exp(0)``, ``sqrt`` of a rational square), else the file is refused naming the call: a
transcendental value (``sin(1)``) cannot be written exactly.

Everything here is exact and solver-free. The SOS proofs that a ``sqrt``'s argument is
non-negative (and its lower bound), and that each denominator of the field is positive on the
relations' set, are found by :func:`lyapcheck.models.classes.recast_classes.prove_root_bounds` and
:func:`~lyapcheck.models.classes.recast_classes.prove_denominators`, stored in certificates and re-checked
exactly by ``verify``.

While an expression is built, the auxiliaries and ``pi`` are variables named ``#k#`` and ``#pi#``:
no name a user can write (a model file's names are identifiers), so no state can be mistaken for
one, and a definition's text is made by replacing those markers, never a substring of a name.
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.errors import ModelFileError
from lyapcheck.models.language.expressions import (FUNCTIONS, ExpressionError, Rational, first_function_use, parse_with_divisors,
                                          uses_functions, written_tree)
from lyapcheck.sos.polynomials import Poly, Ring, degree_in, to_fmpq, to_fraction

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.networks import Network

#: an upper bound of pi/2 = 1.5707963...: |atan u| < pi/2 < 1.571
ATAN_RANGE: Final = Fraction(1571, 1000)
#: the letter each function's auxiliaries are named with (s1, c1, e1, ...)
PREFIX: Final = {"sin": "s", "cos": "c", "exp": "e", "sqrt": "r", "atan": "a", "tanh": "t", "abs": "b", "sat": "q"}
#: the constant square roots the angle-addition formula may need
ROOTS: Final = (2, 3)
#: the variable standing for pi while an expression is built (no model-file name can be this)
PI_MARK: Final = "#pi#"


class RecastError(ExpressionError):
    """A function application that cannot be recast exactly (one line, naming it)."""


@dataclass(frozen=True)
class Auxiliary:
    """One auxiliary variable: ``name = function(argument)``, written in the model-file language
    over the states (``definition``), its value at the equilibrium (``None`` for the constants
    ``rt2``, ``rt3``, which are not shifted) and whether it is smooth (has a flow)."""

    name: str
    function: str
    definition: str
    argument: Poly | None
    value: Fraction | None
    smooth: bool
    #: the call as the user wrote it (the first one, for messages)
    written_as: str = ""
    #: sat's limit L (> 0)
    limit: Fraction | None = None
    #: a constant root's radicand (2 or 3: the auxiliary is sqrt of it, not shifted); None otherwise
    radicand: int | None = None


@dataclass(frozen=True)
class Relation:
    """``poly = 0`` (``kind`` "eq") or ``poly >= 0`` ("ge") on every point of the recast loop."""

    kind: str
    poly: Poly
    why: str
    #: the auxiliary whose relation it is (its index while building, its name after): a proof that
    #: a square root's argument is non-negative may use only the relations of earlier auxiliaries,
    #: never its own (r^2 = q holds for a real r only where q >= 0 already)
    owner: str = ""


@dataclass
class Recaster:
    """Turns function applications into auxiliaries while the builder walks an expression
    (:class:`lyapcheck.models.language.expressions.FunctionCalls`). Variables live in a ring with spare
    slots (``slots``), renamed to their final names by :meth:`system`."""

    states: tuple[str, ...]
    equilibrium: tuple[Fraction, ...]
    slots: int
    ring: Ring = field(init=False)
    auxiliaries: list[Auxiliary] = field(default_factory=list)
    #: the argument each auxiliary was made for, by (function, numerator text)
    made: dict[tuple[str, str], int] = field(default_factory=dict)
    #: a smooth auxiliary's flow is ``factor * u'``: its factor and its argument, by index
    #: (the flows themselves need the whole field: :meth:`flows`)
    chain: dict[int, tuple[Rational, Poly]] = field(default_factory=dict)
    relations: list[Relation] = field(default_factory=list)

    def __post_init__(self) -> None:
        names = self.states + tuple(self._slot(k) for k in range(self.slots)) + (PI_MARK,)
        self.ring = Ring(names)

    # -- the builder's hooks -------------------------------------------------------------------------
    def check_call(self, name: str, arity: int, text: str) -> None:
        if name not in FUNCTIONS:
            known = ", ".join(FUNCTIONS)
            raise ExpressionError(f"unknown function '{name}' in '{text}' (functions: {known}; and the constant pi)")
        if arity != FUNCTIONS[name]:
            want = FUNCTIONS[name]
            raise ExpressionError(f"'{name}' takes {want} argument{'s' if want > 1 else ''}, got {arity} in '{text}'")

    def pi(self) -> Rational:
        return Rational.polynomial(self.ring, self.ring.gen(PI_MARK))

    def apply(self, name: str, args: list[Rational], text: str) -> Rational:
        args = [a.normalized() for a in args]
        if name in ("min", "max"):
            a, b = args
            half = Rational.polynomial(self.ring, self.ring.constant(Fraction(1, 2)))
            sign = -1 if name == "min" else 1
            absolute = self.apply("abs", [a - b], text)
            if sign < 0:
                absolute = -absolute
            return half * (a + b + absolute)
        if name == "sat":
            return self._sat(args[0], args[1], text)
        u = args[0]
        if name in ("sin", "cos"):
            return self._trig(name, u, text)
        self._no_pi(u, name, text)
        num = self._polynomial_argument(u, name, text)
        if num.is_constant():
            return self._constant(name, to_fraction(num.leading_coefficient()) if not num.is_zero() else Fraction(0),
                                  text)
        return self._variable(self._auxiliary(name, num, text))

    # -- each function ----------------------------------------------------------------------------
    def _variable(self, index: int) -> Rational:
        return Rational.polynomial(self.ring, self.ring.gen(self._slot(index)))

    def _slot(self, index: int) -> str:
        return f"#{index}#"

    def _no_pi(self, u: Rational, name: str, text: str) -> None:
        if degree_in(self.ring, u.numerator, [PI_MARK]) > 0 or degree_in(self.ring, u.denominator, [PI_MARK]) > 0:
            raise RecastError(f"'{text}': pi may appear only in an argument of sin or cos, as a multiple of pi/12 "
                              "added to the rest")

    def _polynomial_argument(self, u: Rational, name: str, text: str) -> Poly:
        if not u.denominator.is_constant():
            raise RecastError(f"'{text}': the argument of {name} divides by a non-constant expression; write it as "
                              "a polynomial in the states and functions (only constant divisors inside a function)")
        return u.numerator * (1 / u.denominator.leading_coefficient())

    def _trig(self, name: str, u: Rational, text: str) -> Rational:
        if degree_in(self.ring, u.denominator, [PI_MARK]) > 0:
            raise RecastError(f"'{text}': pi may not appear in a divisor")
        num = self._polynomial_argument(u, name, text)
        k = Fraction(0)
        if degree_in(self.ring, num, [PI_MARK]) > 0:
            pi_index = self.ring.names.index(PI_MARK)
            rest_terms, pi_terms = {}, {}
            for m, c in self.ring.terms(num).items():
                if m[pi_index] == 0:
                    rest_terms[m] = c
                elif m[pi_index] == 1 and sum(m) == 1:
                    pi_terms[m] = c
                else:
                    raise RecastError(f"'{text}': pi must enter the argument as a constant multiple k*pi added "
                                      "to the rest")
            k = next(iter(pi_terms.values()))
            num = self.ring.from_terms(rest_terms)
        if (12 * k).denominator != 1:
            raise RecastError(f"'{text}': the multiple of pi in the argument is {k}*pi; only multiples of pi/12 "
                              "have exact sines and cosines here")
        ck, sk = exact_cos_sin(int(12 * k) % 24)
        cos_k, sin_k = self._root_poly(ck), self._root_poly(sk)
        if num.is_constant():
            if not num.is_zero():
                raise RecastError(f"'{text}': {name} of the constant {to_fraction(num.leading_coefficient())} "
                                  "(plus any multiple of pi) is transcendental and cannot be written exactly")
            value = sin_k if name == "sin" else cos_k
            return Rational.polynomial(self.ring, value)
        s_index = self._auxiliary("sin", num, text)
        s = self.ring.gen(self._slot(s_index))
        c = self.ring.gen(self._slot(s_index + 1))
        # sin(u0 + a) = sin u0 cos a + cos u0 sin a;  cos(u0 + a) = cos u0 cos a - sin u0 sin a
        out = s * cos_k + c * sin_k if name == "sin" else c * cos_k - s * sin_k
        return Rational.polynomial(self.ring, out)

    def _root_poly(self, value: Mapping[int, Fraction]) -> Poly:
        """``a + b sqrt2 + c sqrt3 + d sqrt6`` (a mapping {1: a, 2: b, 3: c, 6: d}) in the ring."""
        out = self.ring.constant(value.get(1, Fraction(0)))
        for radicand, coefficient in value.items():
            if radicand == 1 or coefficient == 0:
                continue
            p = self.ring.constant(coefficient)
            for root in ((2, 3) if radicand == 6 else (radicand,)):
                p = p * self.ring.gen(self._slot(self._root(root)))
            out = out + p
        return out

    def _root(self, radicand: int) -> int:
        key = ("root", str(radicand))
        if key in self.made:
            return self.made[key]
        index = self._new(Auxiliary(f"rt{radicand}", "sqrt", f"sqrt({radicand})", None, None, True,
                                    radicand=radicand))
        self.made[key] = index
        x = self.ring.gen(self._slot(index))
        self.chain[index] = (Rational.polynomial(self.ring, self.ring.zero()), self.ring.zero())
        self.relations += [Relation(r.kind, r.poly, r.why, str(index)) for r in root_relations(x, radicand)]
        return index

    def _constant(self, name: str, value: Fraction, text: str) -> Rational:
        ring = self.ring
        if name == "sqrt":
            if value < 0:
                raise RecastError(f"'{text}': sqrt of the negative constant {value}")
            root = _rational_sqrt(value)
            if root is not None:
                return Rational.polynomial(ring, ring.constant(root))
            for radicand in (2, 3, 6):
                r = _rational_sqrt(value / radicand)
                if r is not None:
                    return Rational.polynomial(ring, self._root_poly({radicand: r}))
            raise RecastError(f"'{text}': sqrt({value}) is exact here only for a rational square times 1, 2, 3 or 6")
        if name in ("exp", "atan", "tanh"):
            if value != 0:
                raise RecastError(f"'{text}': {name}({value}) is transcendental and cannot be written exactly")
            return Rational.polynomial(ring, ring.constant(1 if name == "exp" else 0))
        if name == "abs":
            return Rational.polynomial(ring, ring.constant(abs(value)))
        raise RecastError(f"'{text}': {name} of a constant")  # pragma: no cover - every function is above

    def _sat(self, u: Rational, limit: Rational, text: str) -> Rational:
        if not limit.is_polynomial() or not limit.numerator.is_constant():
            raise RecastError(f"'{text}': the limit of sat must be a positive constant (a number or parameters), "
                              "got an expression of the states")
        L = to_fraction(limit.numerator.leading_coefficient()) if not limit.numerator.is_zero() else Fraction(0)
        if L <= 0:
            raise RecastError(f"'{text}': the limit of sat must be > 0, got {L}")
        self._no_pi(u, "sat", text)
        num = self._polynomial_argument(u, "sat", text)
        if num.is_constant():
            value = to_fraction(num.leading_coefficient()) if not num.is_zero() else Fraction(0)
            return Rational.polynomial(self.ring, self.ring.constant(max(-L, min(L, value))))
        index = self._auxiliary("sat", num, text, limit=L)
        return self._variable(index)

    def _auxiliary(self, function: str, u: Poly, text: str, limit: Fraction | None = None) -> int:
        """The auxiliary of ``function(u)`` (for sin, the index of the pair's sine; its cosine is
        the next): made once per distinct argument, with its flow and relations."""
        key = (function, f"{u}|{limit}")
        if key in self.made:
            return self.made[key]
        ring = self.ring
        first_relation = len(self.relations)
        smooth = function not in ("abs", "sat") and not self._uses_algebraic(u)
        definition = f"{function}({self.written(u)}" + (f", {limit}" if limit is not None else "") + ")"
        index = self._new(Auxiliary("", function, definition, u, None, smooth, text, limit))
        self.made[key] = index
        x = ring.gen(self._slot(index))
        c: Poly | None = None
        if function == "sin":
            cos_index = self._new(Auxiliary("", "cos", f"cos({self.written(u)})", u, None, smooth, text))
            c = ring.gen(self._slot(cos_index))
        self.relations += function_relations(ring, function, x, u, cosine=c, limit=limit)
        if smooth and function == "sin":
            assert c is not None
            self.chain[index] = (Rational.polynomial(ring, c), u)
            self.chain[cos_index] = (-Rational.polynomial(ring, x), u)
        elif smooth and function == "exp":
            self.chain[index] = (Rational.polynomial(ring, x), u)
        elif smooth and function == "sqrt":  # r' = q'/(2 r): usable where 2 r > 0 is proved (a class proves its denominators)
            self.chain[index] = (Rational(ring, ring.constant(1), 2 * x), u)
        elif smooth and function == "atan":
            self.chain[index] = (Rational(ring, ring.constant(1), 1 + u * u), u)
        elif smooth and function == "tanh":
            self.chain[index] = (Rational.polynomial(ring, 1 - x * x), u)
        self.relations[first_relation:] = [Relation(r.kind, r.poly, r.why, str(index))
                                           for r in self.relations[first_relation:]]
        return index

    def _uses_algebraic(self, u: Poly) -> bool:
        return any(not a.smooth and degree_in(self.ring, u, [self._slot(i)]) > 0
                   for i, a in enumerate(self.auxiliaries))

    def _new(self, aux: Auxiliary) -> int:
        if len(self.auxiliaries) >= self.slots:
            raise RecastError("too many function applications")  # pragma: no cover - slots are counted first
        self.auxiliaries.append(aux)
        return len(self.auxiliaries) - 1

    # -- exact calculus -----------------------------------------------------------------------------
    def flows(self, rhs: Sequence[Rational]) -> dict[int, Rational]:
        """Every smooth auxiliary's flow ``factor * grad u . (x', a')``, given the states' right-hand
        sides (an argument uses only states and earlier auxiliaries, so one pass in order)."""
        ring = self.ring
        out: dict[int, Rational] = {}
        speeds: dict[str, Rational] = {s: r for s, r in zip(self.states, rhs)}
        for index in range(len(self.auxiliaries)):
            if index not in self.chain:
                continue
            factor, u = self.chain[index]
            du = Rational.polynomial(ring, ring.zero())
            for k, name in enumerate(ring.names):
                if degree_in(ring, u, [name]) <= 0:
                    continue
                if name not in speeds:
                    raise RecastError(f"'{self.auxiliaries[index].definition}': its argument uses a function "
                                      "without a flow")  # pragma: no cover - smooth arguments use smooth ones
                du = du + Rational.polynomial(ring, u.derivative(k)) * speeds[name]
            out[index] = (factor * du).normalized()
            speeds[self._slot(index)] = out[index]
        return out

    def written(self, p: Poly) -> str:
        """``p`` in the model-file language over the states, each auxiliary by its definition."""
        text = str(p).replace("^", "**")
        for i in range(len(self.auxiliaries)):
            text = text.replace(self._slot(i), _parenthesized(self.auxiliaries[i].definition))
        return text


def root_relations(x: Poly, radicand: int) -> list[Relation]:
    """The relations of the constant root ``x = sqrt(radicand)`` (``rt2``, ``rt3``)."""
    return [Relation("eq", x * x - radicand, f"rt{radicand}^2 = {radicand}"),
            Relation("ge", x, f"rt{radicand} >= 0")]


def function_relations(ring: Ring, function: str, x: Poly, u: Poly, cosine: Poly | None = None,
                       limit: Fraction | None = None) -> list[Relation]:
    """The relations (the module docstring's table) of ``x = function(u)`` in ``ring`` (no owner set):
    ``cosine`` is a sine's pair, ``limit`` a saturation's ``L``. The one place they are written: the recaster
    calls it while it builds a loop, and a map's classes
    (:mod:`lyapcheck.models.classes.map_relations`) call it again on the finished system, whose relations a
    map's recasting does not derive."""
    if function == "sin":
        assert cosine is not None
        c = cosine
        u2 = u * u
        return [Relation("eq", x * x + c * c - 1, "sin^2 + cos^2 = 1"),
                Relation("ge", u2 - x * x, "|sin u| <= |u|"),
                Relation("ge", u2 * to_fmpq(Fraction(1, 2)) - 1 + c, "1 - cos u <= u^2/2"),
                Relation("ge", u * x - u2 + u2 * u2 * to_fmpq(Fraction(1, 6)),
                         "u sin u >= u^2 - u^4/6 (Taylor, alternating)"),
                Relation("ge", 1 - u2 * to_fmpq(Fraction(1, 2)) + u2 * u2 * to_fmpq(Fraction(1, 24)) - c,
                         "cos u <= 1 - u^2/2 + u^4/24 (Taylor, alternating)")]
    if function == "exp":
        return [Relation("ge", x, "exp u >= 0"), Relation("ge", x - 1 - u, "exp u >= 1 + u"),
                Relation("ge", 1 - x * (1 - u), "exp(u) (1 - u) <= 1")]
    if function == "sqrt":
        return [Relation("eq", x * x - u, "r^2 = q"), Relation("ge", x, "r >= 0")]
    if function == "atan":
        return [Relation("ge", x * u, "atan(u) u >= 0"), Relation("ge", u * u - x * x, "|atan u| <= |u|"),
                Relation("ge", ring.constant(ATAN_RANGE ** 2) - x * x, "|atan u| < pi/2 < 1.571"),
                Relation("ge", u * x - u * u + u * u * u * u * to_fmpq(Fraction(1, 3)),
                         "u atan u >= u^2 - u^4/3 (Taylor, alternating)")]
    if function == "tanh":
        return [Relation("ge", 1 - x * x, "|tanh u| <= 1"), Relation("ge", x * u, "tanh(u) u >= 0"),
                Relation("ge", x * (u - x), "tanh(u) (u - tanh u) >= 0"),
                Relation("ge", u * x - u * u + u * u * u * u * to_fmpq(Fraction(1, 3)),
                         "u tanh u >= u^2 - u^4/3 (Taylor: tanh u >= u - u^3/3 for u >= 0)")]
    if function == "abs":
        return [Relation("eq", x * x - u * u, "|u|^2 = u^2"), Relation("ge", x, "|u| >= 0")]
    if function == "sat":
        assert limit is not None
        L2 = to_fmpq(limit * limit)
        return [Relation("eq", (u - x) * (L2 - x * x), "sat(u) = u unless |sat(u)| = L"),
                Relation("ge", L2 - x * x, "|sat(u)| <= L"),
                Relation("ge", x * (u - x), "sat(u) (u - sat(u)) >= 0")]
    return []


def _parenthesized(definition: str) -> str:
    """A definition as a factor of a longer text (parentheses unless it is one call or name)."""
    return f"({definition})" if " " in definition else definition


def _rational_sqrt(q: Fraction) -> Fraction | None:
    if q < 0:
        return None
    a, b = math.isqrt(q.numerator), math.isqrt(q.denominator)
    return Fraction(a, b) if a * a == q.numerator and b * b == q.denominator else None


def exact_cos_sin(k: int) -> tuple[dict[int, Fraction], dict[int, Fraction]]:
    """``cos(k pi/12)`` and ``sin(k pi/12)`` exactly, as ``{1: a, 2: b, 3: c, 6: d}`` meaning
    ``a + b sqrt2 + c sqrt3 + d sqrt6``: from ``cos(pi/12) = (sqrt6 + sqrt2)/4``,
    ``sin(pi/12) = (sqrt6 - sqrt2)/4`` by repeated angle addition in ``Q(sqrt2, sqrt3)``."""
    c: dict[int, Fraction] = {1: Fraction(1)}
    s: dict[int, Fraction] = {}
    c1 = {6: Fraction(1, 4), 2: Fraction(1, 4)}
    s1 = {6: Fraction(1, 4), 2: Fraction(-1, 4)}
    for _ in range(k % 24):
        c, s = _sub(_mul(c, c1), _mul(s, s1)), _add(_mul(s, c1), _mul(c, s1))
    return c, s


def _mul(a: Mapping[int, Fraction], b: Mapping[int, Fraction]) -> dict[int, Fraction]:
    out: dict[int, Fraction] = {}
    for i, x in a.items():
        for j, y in b.items():
            g = math.gcd(i, j)
            # sqrt(i) sqrt(j) = g sqrt(i j / g^2) for squarefree i, j in {1, 2, 3, 6}
            r = i * j // (g * g)
            out[r] = out.get(r, Fraction(0)) + x * y * g
    return {k: v for k, v in out.items() if v}


def _add(a: Mapping[int, Fraction], b: Mapping[int, Fraction]) -> dict[int, Fraction]:
    out = dict(a)
    for k, v in b.items():
        out[k] = out.get(k, Fraction(0)) + v
    return {k: v for k, v in out.items() if v}


def _sub(a: Mapping[int, Fraction], b: Mapping[int, Fraction]) -> dict[int, Fraction]:
    return _add(a, {k: -v for k, v in b.items()})


# -- the recast system --------------------------------------------------------------------------------

@dataclass(frozen=True)
class RecastSystem:
    """A model's loop, recast: polynomial (rational) in the states and the auxiliaries.

    ``ring`` has the states, then the auxiliaries in the order they were made (an argument uses only
    states and earlier auxiliaries). ``field`` are the states' right-hand sides, ``flows`` the smooth
    auxiliaries' (by name), ``relations`` everything the auxiliaries satisfy, and ``values`` the
    equilibrium of every state and non-constant auxiliary (the classes work in ``v - value``).
    """

    ring: Ring
    states: tuple[str, ...]
    auxiliaries: tuple[Auxiliary, ...]
    field: tuple[Rational, ...]
    flows: dict[str, Rational]
    relations: tuple[Relation, ...]
    values: dict[str, Fraction]

    @property
    def n(self) -> int:
        return len(self.states)

    @property
    def names(self) -> tuple[str, ...]:
        return self.ring.names

    def definitions(self) -> dict[str, str]:
        """``certificate.auxiliaries``: each auxiliary's name and definition in the model-file language."""
        return {a.name: a.definition for a in self.auxiliaries}

    def smooth(self) -> tuple[str, ...]:
        """The auxiliaries a Lyapunov function may use (those with a flow, not the constant roots)."""
        return tuple(a.name for a in self.auxiliaries if a.smooth and a.value is not None)

    def roots(self) -> dict[str, int]:
        """The constant roots' names and radicands (``{"rt3": 3}``)."""
        return {a.name: a.radicand for a in self.auxiliaries if a.radicand is not None}

    def shift(self, p: Poly) -> Poly:
        """``p`` in the deviations ``v - value`` (the constant roots stay as they are)."""
        images = [self.ring.gen(n) + to_fmpq(self.values[n]) if n in self.values else self.ring.gen(n) for n in self.names]
        return self.ring.compose(p, images)

    def unshift(self, p: Poly) -> Poly:
        images = [self.ring.gen(n) - to_fmpq(self.values[n]) if n in self.values else self.ring.gen(n) for n in self.names]
        return self.ring.compose(p, images)

    def reduce(self, p: Poly) -> Poly:
        """``p`` with every ``rtk^2`` replaced by ``k`` (its normal form modulo the root relations)."""
        roots = {self.names.index(a.name): a.radicand for a in self.auxiliaries if a.radicand is not None}
        if not roots:
            return p
        out: dict[tuple[int, ...], Fraction] = {}
        for m, c in self.ring.terms(p).items():
            e = list(m)
            for i, k in roots.items():
                c *= Fraction(k) ** (e[i] // 2)
                e[i] %= 2
            out[tuple(e)] = out.get(tuple(e), Fraction(0)) + c
        return self.ring.from_terms({m: c for m, c in out.items() if c})

    def to_json(self) -> dict[str, Any]:
        return {"variables": list(self.names), "auxiliaries": self.definitions(),
                "flows": {name: written(self.ring, r) for name, r in self.flows.items()},
                "relations": [{"kind": r.kind, "poly": written_poly(self.ring, r.poly), "why": r.why}
                              for r in self.relations],
                "values": {k: str(v) for k, v in self.values.items()}}


def written_poly(ring: Ring, p: Poly) -> str:
    return str(p).replace("^", "**") if not p.is_zero() else "0"


def written(ring: Ring, r: Rational) -> str:
    num = written_poly(ring, r.numerator)
    if r.denominator.is_constant() and r.denominator == ring.constant(1):
        return num
    return f"({num})/({written_poly(ring, r.denominator)})"


def count_calls(texts: Sequence[str]) -> int:
    """An upper bound of the auxiliaries the texts can make (two per call, two roots)."""
    total = 0
    for text in texts:
        tree = written_tree(str(text))
        if tree is not None:  # else the builder says what is wrong
            total += sum(isinstance(node, ast.Call) for node in ast.walk(tree))
    return 2 * total + len(ROOTS) + 2


def _parse_recast(source: str, key: str, text: str, recaster: Recaster, states: tuple[str, ...],
                  constants: Mapping[str, Fraction], defined: Mapping[str, Rational]) -> Rational:
    """One right-hand side or law, read with its calls recast by ``recaster``; a one-line
    :class:`~lyapcheck.errors.ModelFileError` at ``key`` on anything refused, ``pi`` outside an argument of
    ``sin``/``cos`` included (it would be a transcendental coefficient)."""
    try:
        r, _ = parse_with_divisors(text, recaster.ring, calls=recaster, names=states, constants=constants,
                                   defined=defined)
    except ExpressionError as exc:
        raise ModelFileError(source, key, str(exc)) from None
    if degree_in(recaster.ring, r.numerator, [PI_MARK]) > 0 or degree_in(recaster.ring, r.denominator, [PI_MARK]) > 0:
        raise ModelFileError(source, key, "pi may appear only in an argument of sin or cos (as k*pi/12 added to "
                                          "the rest); elsewhere it would be a transcendental coefficient")
    return r


def recast_dynamics(source: str, states: tuple[str, ...], texts: Mapping[str, object],
                    constants: Mapping[str, Fraction], equilibrium: Sequence[Fraction],
                    candidate: str | None = None, networks: Sequence["Network"] = (), for_map: bool = False
                    ) -> tuple[RecastSystem, Poly | None]:
    """Parse each state's right-hand side with the functions recast (one-line
    :class:`~lyapcheck.errors.ModelFileError` naming the key on anything refused); with a
    ``candidate`` V (``--candidate``, the same language), its functions are recast too and it is
    returned as a polynomial in the recast ring's deviations (0 at the equilibrium). ``networks``
    (``[networks.NAME]``, :mod:`lyapcheck.models.language.networks`) are lowered first, their neurons the
    first auxiliaries, and their outputs are names the texts may use. ``for_map`` (a map's displacement
    ``F(x) - x``, which is no field): neither the auxiliaries' flows nor their relations are derived (both
    empty: a map's classes evaluate the true map and differentiate it at its fixed point, and moving a
    2 x 32 network's relations to the final ring alone takes minutes)."""
    slots = count_calls([str(t) for t in texts.values()] + ([candidate] if candidate is not None else []))
    slots += 2 * sum(n.neurons for n in networks)
    recaster = Recaster(states, tuple(equilibrium), slots)
    defined = network_outputs(source, recaster, networks)
    rhs: list[Rational] = []
    for s in states:
        key = f"[dynamics] {s}"
        text = texts[s]
        if not isinstance(text, (str, int, float)) or isinstance(text, bool):
            raise ModelFileError(source, key, f"must be an expression in a string, got {text!r}")
        rhs.append(_parse_recast(source, key, str(text), recaster, states, constants, defined))
    extra: list[Rational] = []
    if candidate is not None:
        try:
            v, _ = parse_with_divisors(str(candidate), recaster.ring, calls=recaster, names=states, constants=constants,
                                       defined=defined)
        except ExpressionError as exc:
            raise ModelFileError(source, "--candidate", str(exc)) from None
        if not v.is_polynomial():
            raise ModelFileError(source, "--candidate", "must be polynomial in the states and functions (no division "
                                                        "by an expression of the states)")
        extra.append(v)
    try:
        flows = recaster.flows(rhs) if not for_map else {}
    except ExpressionError as exc:  # pragma: no cover - defensive
        raise ModelFileError(source, "[dynamics]", str(exc)) from None
    if for_map:
        recaster.relations.clear()
    system, moved = _finish(source, recaster, rhs, flows, equilibrium, extra)
    if not moved:
        return system, None
    V = system.shift(moved[0].numerator)
    if any(degree_in(system.ring, V, [a.name]) > 0 for a in system.auxiliaries if not a.smooth or a.value is None):
        raise ModelFileError(source, "--candidate", "may use the states and smooth functions of them (sin, cos, exp, "
                                                    "sqrt, atan, tanh), not abs, min, max, sat or irrational constants")
    at0 = system.reduce(system.ring.substitute(V, {n: Fraction(0) for n in system.values}))
    if not at0.is_zero():
        raise ModelFileError(source, "--candidate", f"must be 0 at the equilibrium, got {written_poly(system.ring, at0)} "
                                                    "there")
    return system, V


def network_outputs(source: str, recaster: Recaster, networks: Sequence["Network"]) -> dict[str, Rational]:
    """Every network's outputs as expressions of the recaster's ring (its neurons made auxiliaries), after
    checking that each network's value at the equilibrium is exact
    (:func:`lyapcheck.models.language.networks.outputs_at`)."""
    from lyapcheck.models.language.networks import lower, outputs_at

    point = dict(zip(recaster.states, recaster.equilibrium))
    defined: dict[str, Rational] = {}
    for network in networks:
        outputs_at(source, network, point)
        try:
            defined.update(lower(network, recaster.ring, recaster))
        except ExpressionError as exc:  # pragma: no cover - an affine argument of tanh or max is always taken
            raise ModelFileError(source, network.key, str(exc)) from None
    return defined


def _finish(source: str, recaster: Recaster, rhs: Sequence[Rational], flows: Mapping[int, Rational],
            equilibrium: Sequence[Fraction], extra: Sequence[Rational] = ()) -> tuple[RecastSystem, list[Rational]]:
    """Name the auxiliaries, move everything to the final ring, and compute the equilibrium values."""
    states = recaster.states
    auxes = recaster.auxiliaries
    counters: dict[str, int] = {}
    names: list[str] = []
    taken = set(states)
    for a in auxes:
        if a.value is None and a.argument is None and a.name:  # a constant root: rt2, rt3
            name = a.name
        else:
            prefix = PREFIX[a.function]
            if a.function == "cos":  # the cosine shares its sine's number
                name = prefix + names[-1][1:]
            else:
                counters[prefix] = counters.get(prefix, 0) + 1
                name = f"{prefix}{counters[prefix]}"
        while name in taken:
            name += "_"
        taken.add(name)
        names.append(name)
    ring = Ring(states + tuple(names))
    old = recaster.ring
    where = list(range(len(states))) + [len(states) + i for i in range(len(names))]

    def move(p: Poly) -> Poly:
        out: dict[tuple[int, ...], Any] = {}
        for m, c in zip(p.monoms(), p.coeffs()):
            e = [0] * ring.nvars
            for k in range(len(states) + len(names)):
                e[where[k]] = int(m[k])
            if any(int(m[k]) for k in range(len(states) + len(names), old.nvars)):
                raise ValueError("a polynomial uses a slot that was never made")  # pragma: no cover
            out[tuple(e)] = c
        return ring.ctx.from_dict(out)

    def move_rational(r: Rational) -> Rational:
        return Rational(ring, move(r.numerator), move(r.denominator)).normalized()

    # definitions again, now that every name is known: in the states only (nested calls by their text)
    defined: list[Auxiliary] = []
    values: dict[str, Fraction] = {s: v for s, v in zip(states, equilibrium)}
    for a, name in zip(auxes, names):
        value: Fraction | None = None
        if a.argument is not None:
            u = move(a.argument)
            point = [values.get(n) for n in ring.names]
            used = [n for n in ring.names if degree_in(ring, u, [n]) > 0]
            if any(values.get(n) is None for n in used):
                raise ModelFileError(source, "[dynamics]", f"'{a.written_as}': its argument uses an irrational "
                                                           "constant; write it without one")
            at = ring.evaluate(u, [p if p is not None else Fraction(0) for p in point])
            value = _value_at(source, a, at)
            values[name] = value
        defined.append(Auxiliary(name, a.function, a.definition, move(a.argument) if a.argument is not None else None,
                                 value, a.smooth, a.written_as, a.limit, a.radicand))
    # definitions written over the states: replace slot names by the final names' definitions
    final: list[Auxiliary] = []
    for a, name in zip(defined, names):
        definition = a.definition
        for i in range(len(names)):
            definition = definition.replace(f"#{i}#", _parenthesized(defined[i].definition))
        final.append(Auxiliary(a.name, a.function, definition, a.argument, a.value, a.smooth, a.written_as, a.limit,
                               a.radicand))
    relations = tuple(Relation(r.kind, move(r.poly), r.why, names[int(r.owner)]) for r in recaster.relations)
    field_rhs = tuple(move_rational(r) for r in rhs)
    flow_map = {names[i]: move_rational(f) for i, f in flows.items()}
    system = RecastSystem(ring=ring, states=states, auxiliaries=tuple(final), field=field_rhs, flows=flow_map,
                          relations=relations, values=values)
    _check_equilibrium(source, system)
    return system, [move_rational(r) for r in extra]


def _value_at(source: str, a: Auxiliary, u: Fraction) -> Fraction:
    """The auxiliary's exact value at the equilibrium, where its argument is ``u`` (rational)."""
    f = a.function
    where = f"'{a.written_as}'"
    if f in ("sin", "cos", "exp", "atan", "tanh"):
        if u != 0:
            raise ModelFileError(source, "[dynamics]", f"{where}: its argument is {u} at the equilibrium, where "
                                 f"{f} is transcendental; only an argument 0 there (plus k*pi/12 for sin and cos) "
                                 "is exact (shift the state or the angle)")
        return Fraction(1) if f in ("cos", "exp") else Fraction(0)
    if f == "sqrt":
        root = _rational_sqrt(u)
        if u < 0:
            raise ModelFileError(source, "[dynamics]", f"{where}: sqrt of {u} < 0 at the equilibrium")
        if root is None:
            raise ModelFileError(source, "[dynamics]", f"{where}: its argument is {u} at the equilibrium, whose "
                                 "square root is irrational; only a rational square there is exact")
        return root
    if f == "abs":
        return abs(u)
    if f == "sat":
        assert a.limit is not None
        return max(-a.limit, min(a.limit, u))
    raise ModelFileError(source, "[dynamics]", f"{where}: unknown function")  # pragma: no cover


def _check_equilibrium(source: str, system: RecastSystem) -> None:
    """Each right-hand side is 0 at the equilibrium, exactly (the root relations reduced)."""
    ring = system.ring
    point = {n: v for n, v in system.values.items()}
    for s, r in zip(system.states, system.field):
        num = ring.substitute(r.numerator, point)
        den = ring.substitute(r.denominator, point)
        num, den = system.reduce(num), system.reduce(den)
        if den.is_zero():
            raise ModelFileError(source, f"[dynamics] {s}", "its denominator is 0 at the equilibrium")
        if not num.is_zero():
            raise ModelFileError(source, "[equilibrium]", f"is not an equilibrium: {s}' = "
                                 f"{written_poly(ring, num)} there, not 0 (checked exactly)")


def stays_put(system: RecastSystem, constants: Sequence[str]) -> bool:
    """Whether ``f(x_eq, c) = 0`` for every value of ``constants`` (variables of ``system`` without a flow:
    a box's parameters, disturbances), proved exactly by substitution, or False where this cannot show it.

    Every other state is set to its equilibrium value; then an auxiliary whose argument has become a
    number is its value at the equilibrium, and one whose argument has become the same polynomial as an
    earlier auxiliary's of the same function is that auxiliary (``sin(x + p)`` is ``sin(p)`` at ``x =
    0``). Each is an identity for every value of the constants, so a right-hand side whose numerator is
    then 0 (the root relations reduced), over a non-zero number, is 0 for every one of them. Ball
    arithmetic, evaluating ``sin(p) - sin(p)`` on an interval of ``p``, cannot show this."""
    ring = system.ring
    images: dict[str, Poly] = {s: ring.constant(system.values[s]) for s in system.states if s not in constants}
    seen: dict[tuple[Any, ...], Poly] = {}

    def substituted(p: Poly) -> Poly:
        return system.reduce(ring.compose(p, [images.get(n, ring.gen(n)) for n in ring.names]))

    for a in system.auxiliaries:
        if a.argument is None or a.name not in system.values:  # (a constant root: a number already)
            continue
        argument = substituted(a.argument)
        if argument.is_constant():  # (the same number as at the equilibrium, so the same value)
            images[a.name] = ring.constant(system.values[a.name])
            continue
        key = (a.function, a.limit, a.radicand, tuple(sorted(ring.terms(argument).items())))
        images[a.name] = seen.setdefault(key, ring.gen(a.name))
    for r in system.field:
        den = substituted(r.denominator)
        if not substituted(r.numerator).is_zero() or not den.is_constant() or den.is_zero():
            return False
    return True


@dataclass(frozen=True)
class RecastModel:
    """A model file whose loop uses functions: what :func:`lyapcheck.models.language.modelfile.parse_any_model`
    reads (the parameters are set to their values; the loop is :attr:`system`)."""

    source: str
    text: str
    name: str
    origin: str
    states: tuple[str, ...]
    parameters: dict[str, Fraction]
    equilibrium: tuple[Fraction, ...]
    domain: dict[str, tuple[Fraction, Fraction]] | None
    system: RecastSystem
    overrides: dict[str, str] = field(default_factory=dict)
    #: ``--candidate`` as a polynomial in the recast ring's deviations (its functions recast with the loop's)
    candidate_v: Poly | None = None
    #: the declared disturbances and their bounds ``|d| <= b``; :attr:`system` is the loop with each
    #: at 0, and every claim about it says ``(d = 0)``
    disturbances: dict[str, Fraction] = field(default_factory=dict)
    #: with disturbances: the loop recast with them as the last states (without a flow), for claims
    #: that hold for every disturbance value (None: no disturbances, or one the recasting cannot keep)
    robust: RecastSystem | None = None
    #: the outputs ``sos_bound`` bounds, polynomials over the states (``Ring(states)``); default each state
    outputs: dict[str, Poly] = field(default_factory=dict)
    #: the outputs' texts as written (``[outputs]``; default each state's name)
    output_text: dict[str, str] = field(default_factory=dict)
    #: ``[sets]`` ``initial`` and ``unsafe`` (lyapcheck.models.language.sets: polynomials of :attr:`state_ring`,
    #: parameters set) and their strings as written, for the barrier class
    sets: dict[str, Any] = field(default_factory=dict)
    set_text: dict[str, Any] = field(default_factory=dict)
    #: the ``[units]`` table as written (empty when the model declares none): the right-hand sides
    #: were dimension-checked as written, before the recasting (lyapcheck.models.language.dimensions)
    units: dict[str, str] = field(default_factory=dict)
    #: ``[networks.NAME]`` as read (lyapcheck.models.language.networks): every recasting of the loop lowers them
    networks: tuple["Network", ...] = ()
    #: ``[model] time``: ``"discrete"`` for a map, whose :attr:`system` is then the recast displacement
    #: ``F(x) - x`` (lyapcheck.models.language.modelfile, ``recast_map``), never a field
    time: str = "continuous"

    @property
    def state_ring(self) -> Ring:
        """The states and the disturbances (the ring of :attr:`sets`, as a polynomial model's)."""
        return Ring(self.states + tuple(self.disturbances))

    @property
    def sha256(self) -> str:
        import hashlib

        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def n(self) -> int:
        return len(self.states)

    def to_toml(self) -> str:
        """The model file's text as read: a file with it gives this model (``overrides`` aside)."""
        return self.text

    def key_of(self, call: str) -> str:
        """The key of the first right-hand side whose text has ``call`` (``[dynamics] x2``), for messages."""
        compact = call.replace(" ", "")
        for state, text in self.dynamics_text.items():
            if compact in text.replace(" ", ""):
                return f"[dynamics] {state}"
        return "[dynamics]"

    @property
    def dynamics_text(self) -> dict[str, str]:
        """The right-hand sides as the file writes them (read again from :attr:`text`)."""
        import tomllib

        table = tomllib.loads(self.text)["dynamics"]
        return {s: str(table[s]) for s in self.states}


def recast_with_constants(model: RecastModel, constants: Mapping[str, Fraction]) -> RecastSystem:
    """The model's loop recast again with some of its parameters and disturbances as variables
    without a flow, after the states, each at the value given (a box's centre; 0 for a disturbance):
    the others keep their values (a disturbance not named is 0). Raises
    :class:`~lyapcheck.errors.ModelFileError` (one line) where the recasting cannot keep one of them
    a variable (a function of it whose value at the equilibrium is not exact)."""
    names = tuple(constants)
    params: dict[str, Fraction] = {k: v for k, v in model.parameters.items() if k not in constants}
    params.update({d: Fraction(0) for d in model.disturbances if d not in constants})
    texts: dict[str, object] = {**model.dynamics_text, **{n: "0" for n in names}}
    system, _ = recast_dynamics(model.source, model.states + names, texts, params,
                                tuple(model.equilibrium) + tuple(constants[n] for n in names),
                                networks=model.networks)
    return system


def recast_laws(source: str, section: str, states: tuple[str, ...], laws: Mapping[str, object],
                constants: Mapping[str, Fraction], equilibrium: Sequence[Fraction],
                networks: Sequence["Network"] = ()) -> tuple[RecastSystem, dict[str, Rational]]:
    """Laws that use functions (a sampled-data file's ``[controller]``,
    :mod:`lyapcheck.models.language.sampling`), recast by the same builder as a loop's right-hand sides:
    the system over the states, each frozen (``x' = 0``: only its auxiliaries, their relations and
    their exact values at the equilibrium matter), and each law a rational function of its ring (states,
    then auxiliaries; not shifted). One-line :class:`~lyapcheck.errors.ModelFileError` naming
    ``[section] NAME`` on anything refused, a transcendental value at the equilibrium included
    (``tanh(1)``: refused as in ``[dynamics]``). ``networks`` are lowered first, as
    :func:`recast_dynamics` lowers them (their neurons the first auxiliaries), and their outputs are
    names the laws may use."""
    texts = {name: str(text) for name, text in laws.items()}
    slots = count_calls(list(texts.values())) + 2 * sum(n.neurons for n in networks)
    recaster = Recaster(states, tuple(equilibrium), slots)
    defined = network_outputs(source, recaster, networks)
    parsed: list[Rational] = []
    for name, text in texts.items():
        parsed.append(_parse_recast(source, f"[{section}] {name}", text, recaster, states, constants, defined))
    frozen = [Rational.polynomial(recaster.ring, recaster.ring.zero()) for _ in states]
    try:
        system, moved = _finish(source, recaster, frozen, recaster.flows(frozen), equilibrium, parsed)
    except ModelFileError as exc:  # keyed [dynamics] there: the law whose text has the call instead
        message = str(exc).removeprefix(f"{exc.source}: {exc.key}: ")
        compact = message.split("'")[1].replace(" ", "") if message.count("'") >= 2 else ""
        key = next((f"[{section}] {name}" for name, text in texts.items() if compact and compact in text.replace(" ", "")),
                   f"[{section}]")
        raise ModelFileError(source, key, message) from None
    return system, dict(zip(texts, moved))


def value_at_equilibrium(system: RecastSystem, p: Poly) -> Fraction | None:
    """``p`` (over ``system.ring``, not shifted) at the equilibrium, exactly: every state and auxiliary
    at its value, the constant roots reduced; None when the value is irrational (a root remains)."""
    at = system.reduce(system.ring.substitute(p, {name: v for name, v in system.values.items()}))
    if not at.is_constant():
        return None
    return to_fraction(at.leading_coefficient()) if not at.is_zero() else Fraction(0)

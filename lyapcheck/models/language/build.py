"""Build a model in Python: sympy expressions, or a python-control plant closed with a gain.

A notebook needs no TOML file. :func:`from_sympy` takes sympy objects (Symbols for the states,
parameters and disturbances; sympy expressions for the right-hand sides), prints each expression
into the model-file language (:mod:`lyapcheck.models.language.expressions`) with a small printer over
sympy's expression tree, writes the model file's text and reads that text with the project's own
parser (:func:`lyapcheck.models.language.modelfile.parse_any_model`). The model is therefore exactly what
a file with that text gives, and ``model.to_toml()`` (its :attr:`text`) is that file: a
certificate carries the text and its SHA-256 as for any file.

Nothing here parses a string as an expression: an expression given as a ``str`` is refused
(:class:`InvalidParameter`), so no user text reaches ``sympify``. Strings are taken only where a
model file takes data: a name, a quantity with a unit (``"0.75 mm"``, read by the file's unit
parser).

The printer emits only what the language takes: numbers as exact rationals (``p/q``), ``+ - * /``,
``**`` with a non-negative integer exponent, ``sqrt`` (sympy's ``x**(1/2)``), the functions
``sin cos exp atan tanh abs min max`` and ``pi``. Anything else (a symbol not declared, a
non-integer power other than a half-integer, an unsupported function, a number that is not
finite) is an :class:`InvalidParameter` naming the argument and the sub-expression.

Floats are read by their shortest decimal repr (``0.1`` is ``1/10``, as the language reads the
decimal ``0.1``), the number a user typed, not its binary neighbour. A sympy ``Float`` is taken
only when its value is a double (the default 53-bit precision); give other values as
``sympy.Rational``.

:func:`from_control` closes a python-control ``StateSpace`` ``x' = A x + B u`` with ``u = -K (x -
x_eq)``: ``x' = (A - B K)(x - x_eq) + A x_eq``, each entry exact from the matrices' decimal reprs.
:func:`close_loop` closes a sympy plant ``x' = f(x, u)`` with a law ``u = k(x)`` (or a gain) by
substitution. A ``NonlinearIOSystem`` holds Python callables that cannot be read exactly and is
refused.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal
from fractions import Fraction
from numbers import Integral, Real
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.errors import InvalidParameter
from lyapcheck.models.language.sets import SET_KEYS, STAY_KEY

if TYPE_CHECKING:  # pragma: no cover
    import sympy as sp

    from lyapcheck.models.language.modelfile import Model as FileModel
    from lyapcheck.models.language.recast import RecastModel

#: the language's functions by sympy class name (sqrt is sympy's ``Pow(x, 1/2)``, handled apart)
_FUNCTIONS: Final = {"sin": "sin", "cos": "cos", "exp": "exp", "atan": "atan", "tanh": "tanh", "Abs": "abs",
                     "Min": "min", "Max": "max"}
#: what the language takes, for messages
_LANGUAGE: Final = ("numbers, the declared names, + - * /, ** with a non-negative integer, sqrt, sin cos exp atan "
                    "tanh abs min max, pi")
#: the longest sub-expression quoted in a message
_QUOTE: Final = 80
_BARE_KEY: Final = re.compile(r"[A-Za-z0-9_-]+")

# precedences of printed text: a sub-text is parenthesized where its context binds tighter
_ADD, _MUL, _NEG, _POW, _ATOM = 1, 2, 3, 4, 5


def _sympy() -> Any:
    import sympy

    return sympy


def _quoted(expr: object) -> str:
    text = " ".join(str(expr).split())
    return text if len(text) <= _QUOTE else text[:_QUOTE - 3] + "..."


def exact_number(field: str, value: object) -> Fraction:
    """``value`` exactly: an int, a Fraction, a sympy Integer or Rational, or a float (or a sympy
    Float that is a double) read by its decimal repr (``0.1`` is ``1/10``)."""
    sp = _sympy()
    if isinstance(value, bool) or value is None or isinstance(value, str):
        raise InvalidParameter(field, "a number (int, float, Fraction or a sympy number)", value)
    if isinstance(value, sp.Basic):
        if value.is_Integer or value.is_Rational:
            return Fraction(int(value.p), int(value.q))
        if value.is_Float:
            return _float_fraction(field, _double(field, value))
        raise InvalidParameter(field, "a number (int, float, Fraction or a sympy number)", _quoted(value))
    if isinstance(value, Fraction):
        return value
    if isinstance(value, Integral):  # int, numpy integers
        return Fraction(int(value))
    if isinstance(value, Real):  # float, numpy floating
        return _float_fraction(field, float(value))
    raise InvalidParameter(field, "a number (int, float, Fraction or a sympy number)", type(value).__name__)


def _double(field: str, value: Any) -> float:
    """A sympy Float's value as a double, refused when it is not one exactly (another precision)."""
    as_float = float(value)
    exact = _sympy().Rational(value) if math.isfinite(as_float) else None  # the Float's binary value, exactly
    if exact is None or Fraction(as_float) != Fraction(int(exact.p), int(exact.q)):
        raise InvalidParameter(field, "a sympy Float of double precision (give other values as sympy.Rational)",
                               _quoted(value))
    return as_float


def _float_fraction(field: str, value: float) -> Fraction:
    if not math.isfinite(value):
        raise InvalidParameter(field, "a finite number", value)
    # the decimal the user typed (repr is the shortest decimal that reads back as this double), as
    # the model language reads a decimal literal: 0.1 is 1/10
    return Fraction(Decimal(repr(value)))


def _decimal_text(field: str, value: Fraction) -> str:
    """A terminating decimal's exact text (``1/4`` is ``0.25``); a model file's quantities are
    decimals, so another rational is refused."""
    q, twos, fives = value.denominator, 0, 0
    while q % 2 == 0:
        q, twos = q // 2, twos + 1
    while q % 5 == 0:
        q, fives = q // 5, fives + 1
    if q != 1:
        raise InvalidParameter(field, "a number with a terminating decimal expansion (a model file's quantities are "
                                      "decimals; write a fraction such as 1/3 into the expressions instead)",
                               f"{value.numerator}/{value.denominator}")
    if value.denominator == 1:
        return str(value.numerator)
    places = max(twos, fives)
    digits = abs(value.numerator) * 10 ** places // value.denominator
    text = str(digits).rjust(places + 1, "0")
    return ("-" if value < 0 else "") + text[:-places] + "." + text[-places:]


def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in text:
        if ch in ('"', "\\"):
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _key(name: str) -> str:
    return name if _BARE_KEY.fullmatch(name) else _toml_string(name)


class _Printer:
    """sympy expression -> model-language text, over the declared names only."""

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        self.sp = _sympy()

    def text(self, field: str, expr: object) -> str:
        self.field = field
        return self.print(self.expression(field, expr))[0]

    def expression(self, field: str, expr: object) -> Any:
        """``expr`` as a sympy expression: a sympy one, or a Python number read exactly; a string is
        refused (no text is ever parsed here)."""
        sp = self.sp
        if isinstance(expr, str):
            raise InvalidParameter(field, "a sympy expression, not a string (strings are never parsed: build the "
                                          "expression from sympy.Symbol objects)", _quoted(expr))
        if isinstance(expr, sp.Basic):
            return expr
        number = exact_number(field, expr)
        return sp.Rational(number.numerator, number.denominator)

    def refuse(self, sub: Any, why: str) -> InvalidParameter:
        return InvalidParameter(self.field, f"an expression of the model language ({_LANGUAGE}); {why}", _quoted(sub))

    def wrap(self, printed: tuple[str, int], at_least: int) -> str:
        text, prec = printed
        return text if prec >= at_least else f"({text})"

    def print(self, e: Any) -> tuple[str, int]:
        sp = self.sp
        if isinstance(e, sp.Symbol):
            if e.name not in self.names:
                raise self.refuse(e, f"the symbol '{e.name}' is not declared (declared: "
                                     f"{', '.join(self.names) or 'none'})")
            return e.name, _ATOM
        if e is sp.pi:
            return "pi", _ATOM
        if e is sp.E:
            return "exp(1)", _ATOM
        if e.is_Number:
            return self.number(e)
        if e.is_Add:
            return self.add(e)
        if e.is_Mul:
            return self.mul(e)
        if e.is_Pow:
            return self.power(e)
        name = type(e).__name__
        if name in _FUNCTIONS and e.func is getattr(sp, name):  # sympy's own class, not a look-alike
            args = [self.print(a)[0] for a in e.args]
            if name in ("Min", "Max"):  # the language's min and max take two arguments: nest the rest
                text = args[-1]
                for a in reversed(args[:-1]):
                    text = f"{_FUNCTIONS[name]}({a}, {text})"
                return text, _ATOM
            if len(args) != 1:
                raise self.refuse(e, f"{_FUNCTIONS[name]} takes one argument")
            return f"{_FUNCTIONS[name]}({args[0]})", _ATOM
        if isinstance(e, sp.Function):
            raise self.refuse(e, f"the function '{name}' is not one the language takes")
        raise self.refuse(e, f"'{name}' is not part of the language")

    def number(self, e: Any) -> tuple[str, int]:
        if e.is_Integer:
            return str(int(e)), _ATOM if e >= 0 else _NEG
        if e.is_Rational:
            text = f"{abs(int(e.p))}/{int(e.q)}"
            return (text, _MUL) if e > 0 else ("-" + text, _NEG)
        if e.is_Float:
            text = repr(_double(self.field, e))
            return text, _NEG if text.startswith("-") else _ATOM
        raise self.refuse(e, "the number is not finite and real")

    def add(self, e: Any) -> tuple[str, int]:
        parts: list[str] = []
        for term in e.as_ordered_terms():
            coefficient = term.as_coeff_Mul()[0]
            if coefficient.is_negative:
                parts.append((" - " if parts else "-") + self.wrap(self.print(-term), _MUL))
            else:
                parts.append((" + " if parts else "") + self.wrap(self.print(term), _MUL))
        return "".join(parts), _ADD

    def mul(self, e: Any) -> tuple[str, int]:
        sp = self.sp
        coefficient = e.as_coeff_Mul()[0]
        if coefficient.is_negative:
            # -a*b reads as (-a)*b in Python, the same number
            return "-" + self.wrap(self.print(-e), _MUL), _NEG
        numerator: list[str] = []
        denominator: list[str] = []
        for f in e.as_ordered_factors():
            if f.is_Rational and not f.is_Integer and f.q % 10 == 0:  # a decimal's digits (K = 2.414...)
                numerator.append(_decimal_text(self.field, Fraction(int(f.p), int(f.q))))
            elif f.is_Rational and not f.is_Integer:
                if f.p != 1:
                    numerator.append(str(int(f.p)))
                denominator.append(str(int(f.q)))
            elif f.is_Pow and f.exp.is_Rational and f.exp.is_negative:
                inverse = f.base if f.exp == -1 else sp.Pow(f.base, -f.exp, evaluate=False)
                denominator.append(self.wrap(self.print(inverse), _POW))
            else:
                numerator.append(self.wrap(self.print(f), _POW))
        text = "*".join(numerator) or "1"
        if denominator:
            below = denominator[0] if len(denominator) == 1 else "(" + "*".join(denominator) + ")"
            return f"{text}/{below}", _MUL
        return text, _MUL if len(numerator) > 1 else _POW

    def power(self, e: Any) -> tuple[str, int]:
        sp = self.sp
        base, exponent = e.args
        if exponent.is_Integer:
            k = int(exponent)
            if k < 0:
                inverse = base if k == -1 else sp.Pow(base, -k, evaluate=False)
                return "1/" + self.wrap(self.print(inverse), _POW), _MUL
            return f"{self.wrap(self.print(base), _ATOM)}**{k}", _POW
        if exponent.is_Rational and exponent.q == 2:  # a half-integer power: sqrt(b)**k
            root, k = f"sqrt({self.print(base)[0]})", abs(int(exponent.p))
            text = root if k == 1 else f"{root}**{k}"
            return ("1/" + text, _MUL) if exponent.is_negative else (text, _POW)
        raise self.refuse(e, f"the exponent {_quoted(exponent)} is not an integer (nor a half-integer: sqrt)")


def expression_text(field: str, expr: object, names: Sequence[str]) -> str:
    """``expr`` (a sympy expression or a number) in the model language, over ``names`` only;
    :class:`InvalidParameter` at ``field`` for anything outside it (a string among them)."""
    return _Printer(names).text(field, expr)


def _symbols(field: str, values: object, plural: str) -> tuple[Any, ...]:
    """A sequence of distinct sympy Symbols."""
    sp = _sympy()
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, sp.MatrixBase)):
        raise InvalidParameter(field, f"a sequence of sympy Symbols ({plural})", _quoted(values))
    out = tuple(values)
    for i, s in enumerate(out):
        if not isinstance(s, sp.Symbol):
            raise InvalidParameter(f"{field}[{i}]", "a sympy Symbol", _quoted(s))
    names = [s.name for s in out]
    twice = next((n for n in names if names.count(n) > 1), None)
    if twice is not None:
        raise InvalidParameter(field, "distinct symbols", f"'{twice}' twice")
    return out


def _name_of(field: str, key: object) -> str:
    """A mapping's key: a sympy Symbol or its name."""
    sp = _sympy()
    if isinstance(key, sp.Symbol):
        return str(key.name)
    if isinstance(key, str):
        return key
    raise InvalidParameter(field, "keys that are sympy Symbols (or their names)", _quoted(key))


def _mapping(field: str, values: object) -> Mapping[Any, Any]:
    if values is None:
        return {}
    if not isinstance(values, Mapping):
        raise InvalidParameter(field, "a mapping", type(values).__name__)
    return values


def _quantity(field: str, value: object) -> str:
    """A quantity as TOML: an exact decimal, or a string with a unit for the file's unit parser."""
    if isinstance(value, str):
        return _toml_string(value)  # data for the unit parser, e.g. "0.75 mm"
    text = _decimal_text(field, exact_number(field, value))
    return text if "." not in text else _toml_string(text)  # quoted: read as an exact decimal


def _by_state(field: str, values: object, states: Sequence[str]) -> list[tuple[str, object]]:
    """``{state: value}`` (or one value per state, in order) as pairs."""
    sp = _sympy()
    if isinstance(values, Mapping):
        pairs = [(_name_of(field, k), v) for k, v in values.items()]
    elif isinstance(values, (Sequence, sp.MatrixBase)) and not isinstance(values, (str, bytes)):
        items = list(values)
        if len(items) != len(states):
            raise InvalidParameter(field, f"one entry per state ({len(states)})", len(items))
        pairs = list(zip(states, items))
    else:
        raise InvalidParameter(field, "a mapping from the states, or one entry per state", _quoted(values))
    return pairs


def from_sympy(states: Sequence["sp.Symbol"], rhs: Sequence[object] | Mapping[Any, object], *,
               parameters: Mapping[Any, object] | None = None, disturbances: Mapping[Any, object] | None = None,
               equilibrium: Mapping[Any, object] | Sequence[object] | None = None,
               outputs: Mapping[str, object] | None = None,
               domain: Mapping[Any, tuple[object, object]] | None = None,
               sets: Mapping[str, object] | None = None, name: str = "model built with sympy",
               origin: str = "", time: str = "continuous") -> "FileModel | RecastModel":
    """A model from sympy expressions, read as the model file :meth:`Model.to_toml` returns.

    Parameters
    ----------
    states
        The states, sympy Symbols, in the order of the state vector.
    rhs
        Each state's time derivative: a sympy expression (or a number), one per state in order, or a
        mapping from the state symbols. A string is refused: nothing is parsed from text.
    parameters, disturbances
        ``{Symbol: value}``: each parameter's value and each disturbance's bound ``|d| <= b``, a
        number (a float by its decimal repr: ``0.1`` is ``1/10``; a Fraction or sympy Rational with
        a terminating decimal expansion) or a string with a unit (``"0.75 mm"``).
    equilibrium
        ``{Symbol: value}`` or one value per state (default: the origin); checked exactly.
    outputs
        ``{name: expression}``, polynomial in the states (default: each state).
    domain
        ``{Symbol: (lo, hi)}`` over every state.
    sets
        ``{"initial" | "unsafe" | "goal": inequalities}``: a sympy relational (``x**2 + y**2 <= 1``),
        a list of them (all hold) or a list of lists (a union); ``"stay_in_goal": True``.
    name, origin
        ``[model] name`` and ``source``.
    time
        ``[model] time``: ``"continuous"`` (``rhs`` are time derivatives) or ``"discrete"`` (``rhs`` are
        each state's next value, a map).

    Returns
    -------
    Model or RecastModel
        A :class:`~lyapcheck.models.language.modelfile.Model` (polynomial or rational loop) or, when the
        right-hand sides use functions or pi, a :class:`~lyapcheck.models.language.recast.RecastModel`;
        both are what :func:`lyapcheck.certify`, ``verify`` and ``simulate`` take.

    Raises
    ------
    InvalidParameter
        An argument of the wrong type, an expression outside the language (naming the argument and
        the sub-expression), a string where an expression is expected, an inexact number.
    ModelFileError
        The text breaks a model-file rule the parser checks (an exponent above 12, a name that is
        not an identifier, an equilibrium that is not one): ``<from_sympy>: KEY: what``.
    """
    return _parse(model_text(states, rhs, parameters=parameters, disturbances=disturbances, equilibrium=equilibrium,
                             outputs=outputs, domain=domain, sets=sets, name=name, origin=origin, time=time),
                  "<from_sympy>")


def _time_line(time: object) -> list[str]:
    """``[model] time``'s line: none for the default (a continuous model's text is as before)."""
    from lyapcheck.models.language.modelfile import TIME_KINDS

    if not isinstance(time, str) or time not in TIME_KINDS:
        raise InvalidParameter("time", "one of " + ", ".join(f'"{k}"' for k in TIME_KINDS), _quoted(time))
    return [] if time == TIME_KINDS[0] else [f"time = {_toml_string(time)}"]


def model_text(states: Sequence["sp.Symbol"], rhs: Sequence[object] | Mapping[Any, object], *,
               parameters: Mapping[Any, object] | None = None, disturbances: Mapping[Any, object] | None = None,
               equilibrium: Mapping[Any, object] | Sequence[object] | None = None,
               outputs: Mapping[str, object] | None = None,
               domain: Mapping[Any, tuple[object, object]] | None = None,
               sets: Mapping[str, object] | None = None, name: str = "model built with sympy",
               origin: str = "", time: str = "continuous") -> str:
    """The model file's text for :func:`from_sympy`'s arguments (not yet validated by the parser)."""
    sp = _sympy()
    symbols = _symbols("states", states, "the states")
    state_names = [s.name for s in symbols]
    params = _mapping("parameters", parameters)
    dists = _mapping("disturbances", disturbances)
    param_names = [_name_of("parameters", k) for k in params]
    dist_names = [_name_of("disturbances", k) for k in dists]
    printer = _Printer(state_names + dist_names + param_names)
    for label, text in (("name", name), ("origin", origin)):
        if not isinstance(text, str):
            raise InvalidParameter(label, "a string", type(text).__name__)

    lines = ["[model]", f"name = {_toml_string(name)}",
             "states = [" + ", ".join(_toml_string(s) for s in state_names) + "]"]
    if origin:
        lines.append(f"source = {_toml_string(origin)}")
    lines += _time_line(time)
    for section, table in (("parameters", params), ("disturbances", dists)):
        if table:
            lines += ["", f"[{section}]"]
            for key, value in table.items():
                label = _name_of(section, key)
                lines.append(f"{_key(label)} = {_quantity(f'{section}[{label}]', value)}")

    if isinstance(rhs, Mapping):
        given = {_name_of("rhs", k): v for k, v in rhs.items()}
        extra = [k for k in given if k not in state_names]
        if extra:
            raise InvalidParameter("rhs", f"a mapping from the states ({', '.join(state_names)})", extra[0])
        missing = [s for s in state_names if s not in given]
        if missing:
            raise InvalidParameter("rhs", f"an expression for every state (no entry for '{missing[0]}')", "")
        right = [given[s] for s in state_names]
    elif isinstance(rhs, (Sequence, sp.MatrixBase)) and not isinstance(rhs, (str, bytes)):
        right = list(rhs)
        if len(right) != len(state_names):
            raise InvalidParameter("rhs", f"one expression per state ({len(state_names)})", len(right))
    else:
        raise InvalidParameter("rhs", "a sequence of sympy expressions, one per state, or a mapping from the states",
                               _quoted(rhs))
    lines += ["", "[dynamics]"]
    for s, expr in zip(state_names, right):
        lines.append(f"{_key(s)} = {_toml_string(printer.text(f'rhs[{s}]', expr))}")

    if equilibrium is not None:
        lines += ["", "[equilibrium]"]
        for key, value in _by_state("equilibrium", equilibrium, state_names):
            lines.append(f"{_key(key)} = {_quantity(f'equilibrium[{key}]', value)}")
    if outputs:
        lines += ["", "[outputs]"]
        for key, expr in _mapping("outputs", outputs).items():
            if not isinstance(key, str):
                raise InvalidParameter("outputs", "a mapping from output names (strings)", _quoted(key))
            lines.append(f"{_key(key)} = {_toml_string(printer.text(f'outputs[{key}]', expr))}")
    if domain is not None:
        lines += ["", "[domain]"]
        for key, value in _by_state("domain", domain, state_names):
            field = f"domain[{key}]"
            if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, sp.Tuple)) or len(value) != 2:
                raise InvalidParameter(field, "(lo, hi)", _quoted(value))
            lines.append(f"{_key(key)} = [{_quantity(field, value[0])}, {_quantity(field, value[1])}]")
    if sets:
        lines += ["", "[sets]"]
        for key, value in _mapping("sets", sets).items():
            if key == STAY_KEY:
                if not isinstance(value, bool):
                    raise InvalidParameter(f"sets[{key}]", "True or False", value)
                lines.append(f"{key} = {'true' if value else 'false'}")
                continue
            if key not in SET_KEYS:
                raise InvalidParameter("sets", f"keys among {', '.join(SET_KEYS)}, {STAY_KEY}", key)
            lines.append(f"{key} = {_set_text(printer, f'sets[{key}]', value)}")
    return "\n".join(lines) + "\n"


def _set_text(printer: _Printer, field: str, value: object) -> str:
    """A set as TOML: a relational, a list of them (all hold) or a list of lists (a union)."""
    sp = _sympy()

    def inequality(where: str, rel: object) -> str:
        if not isinstance(rel, (sp.LessThan, sp.GreaterThan, sp.StrictLessThan, sp.StrictGreaterThan)):
            raise InvalidParameter(where, "a sympy inequality (<=, >=, <, > between expressions; a string is "
                                          "never parsed)", _quoted(rel))
        left, right = (printer.text(where, side) for side in (rel.lhs, rel.rhs))
        return _toml_string(f"{left} {rel.rel_op} {right}")

    items: list[Any] = [value] if not isinstance(value, (list, tuple)) else list(value)
    if items and all(isinstance(v, (list, tuple)) for v in items):
        pieces = ["[" + ", ".join(inequality(f"{field}[{i}][{j}]", r) for j, r in enumerate(piece)) + "]"
                  for i, piece in enumerate(items)]
        return "[" + ", ".join(pieces) + "]"
    return "[" + ", ".join(inequality(f"{field}[{i}]", r) for i, r in enumerate(items)) + "]"


def _parse(text: str, source: str) -> "FileModel | RecastModel":
    from lyapcheck.models.language.modelfile import parse_any_model

    return parse_any_model(text, source)


def close_loop(states: Sequence["sp.Symbol"], inputs: Sequence["sp.Symbol"],
               rhs: Sequence[object] | Mapping[Any, object], *, law: Sequence[object] | Mapping[Any, object] | None
               = None, gain: object = None, **model: Any) -> "FileModel | RecastModel":
    """A sympy plant ``x' = f(x, u)`` closed with a law ``u = k(x)``, by substitution.

    Parameters
    ----------
    states, inputs
        sympy Symbols: the plant's states and inputs.
    rhs
        ``f(x, u)``, one sympy expression per state (or a mapping from the states).
    law
        ``u = k(x)``: one sympy expression per input (or a mapping from the inputs), in the states
        (and parameters); not with ``gain``.
    gain
        A matrix ``K`` (inputs x states, e.g. ``control.lqr``'s): the law ``u = -K (x - x_eq)``, with
        ``x_eq`` the ``equilibrium`` (default the origin); each entry read exactly (a float by its
        decimal repr). For a non-zero input at the equilibrium, give ``law``.
    **model
        :func:`from_sympy`'s keywords (``parameters``, ``equilibrium``, ``domain``, ...).
    """
    sp = _sympy()
    xs = _symbols("states", states, "the plant's states")
    us = _symbols("inputs", inputs, "the plant's inputs")
    if (law is None) == (gain is None):
        raise InvalidParameter("law", "given, or a gain (one of law and gain)", "both" if law is not None else "none")
    if gain is not None:
        K = _matrix("gain", gain, len(us), len(xs))
        eq = dict(_by_state("equilibrium", model["equilibrium"], [x.name for x in xs])) \
            if model.get("equilibrium") is not None else {}
        # u = -K (x - x_eq) is exact in SI: the equilibrium's values are numbers here (no unit strings)
        offsets = [x - _rational(sp, exact_number(f"equilibrium[{x.name}]", eq[x.name])) if x.name in eq else x
                   for x in xs]
        laws = [-sum((_rational(sp, K[i][j]) * offsets[j] for j in range(len(xs))), sp.Integer(0))
                for i in range(len(us))]
    else:
        printer = _Printer([])
        if isinstance(law, Mapping):
            given = {_name_of("law", k): v for k, v in law.items()}
            missing = [u.name for u in us if u.name not in given]
            if missing or len(given) != len(us):
                raise InvalidParameter("law", f"one expression per input ({', '.join(u.name for u in us)})",
                                       ", ".join(given))
            laws = [printer.expression(f"law[{u.name}]", given[u.name]) for u in us]
        elif isinstance(law, (Sequence, sp.MatrixBase)) and not isinstance(law, (str, bytes)):
            items = list(law)
            if len(items) != len(us):
                raise InvalidParameter("law", f"one expression per input ({len(us)})", len(items))
            laws = [printer.expression(f"law[{u.name}]", v) for u, v in zip(us, items)]
        else:
            raise InvalidParameter("law", "a sequence of sympy expressions, one per input, or a mapping from the "
                                          "inputs", _quoted(law))
        for u, k in zip(us, laws):
            inside = sorted(v.name for v in k.free_symbols & set(us))
            if inside:
                raise InvalidParameter(f"law[{u.name}]", "an expression in the states, not in the inputs",
                                       _quoted(k))
    printer = _Printer([])
    if isinstance(rhs, Mapping):
        plant = {k: printer.expression(f"rhs[{_name_of('rhs', k)}]", v) for k, v in rhs.items()}
        closed: Sequence[object] | Mapping[Any, object] = {k: v.xreplace(dict(zip(us, laws))) for k, v in plant.items()}
    elif isinstance(rhs, (Sequence, sp.MatrixBase)) and not isinstance(rhs, (str, bytes)):
        closed = [printer.expression(f"rhs[{i}]", v).xreplace(dict(zip(us, laws))) for i, v in enumerate(rhs)]
    else:
        raise InvalidParameter("rhs", "a sequence of sympy expressions, one per state, or a mapping from the states",
                               _quoted(rhs))
    return from_sympy(xs, closed, **model)


def _rational(sp: Any, value: Fraction) -> Any:
    return sp.Rational(value.numerator, value.denominator)


def _matrix(field: str, value: object, rows: int, cols: int) -> list[list[Fraction]]:
    """A rows x cols matrix (numpy array, nested lists, sympy Matrix), each entry exact."""
    import numpy as np

    sp = _sympy()
    if isinstance(value, sp.MatrixBase):
        entries = [[value[i, j] for j in range(value.cols)] for i in range(value.rows)]
    else:
        try:
            array = np.asarray(value, dtype=object)
        except (TypeError, ValueError):
            raise InvalidParameter(field, "a matrix", type(value).__name__) from None
        if array.ndim == 1 and rows == 1:
            array = array.reshape(1, -1)
        if array.ndim != 2:
            raise InvalidParameter(field, f"a {rows} x {cols} matrix", f"an array of shape {array.shape}")
        entries = array.tolist()
    shape = (len(entries), len(entries[0]) if entries else 0)
    if shape != (rows, cols):
        raise InvalidParameter(field, f"a {rows} x {cols} matrix", f"{shape[0]} x {shape[1]}")
    return [[exact_number(f"{field}[{i}, {j}]", v) for j, v in enumerate(row)] for i, row in enumerate(entries)]


def from_control(system: object, gain: object, *, equilibrium: Sequence[object] | Mapping[Any, object] | None = None,
                 states: Sequence["sp.Symbol"] | None = None, **model: Any) -> "FileModel | RecastModel":
    """A python-control ``StateSpace`` ``x' = A x + B u`` closed with ``u = -K (x - x_eq)``.

    The loop is ``x' = (A - B K)(x - x_eq) + A x_eq``, each entry exact: the matrices' floats are
    read by their decimal reprs (``0.1`` is ``1/10``), so ``A - B K`` is computed in rationals. A
    discrete-time system (``dt`` set) gives the map ``x+ = (A - B K)(x - x_eq) + A x_eq`` (``[model] time =
    "discrete"``; its sampling period plays no part in the map).

    Parameters
    ----------
    system
        A ``control.StateSpace``, continuous-time or discrete-time. A ``NonlinearIOSystem`` (Python
        callables, which cannot be read exactly) is refused: give its sympy plant to :func:`close_loop`.
    gain
        ``K``, inputs x states (``control.lqr``'s first result).
    equilibrium
        ``x_eq`` (default the origin): one number per state or ``{Symbol: value}``.
    states
        sympy Symbols naming the states (default: the system's state labels when they are names,
        else ``x1 ... xn``).
    **model
        :func:`from_sympy`'s other keywords (``outputs``, ``domain``, ``sets``, ``name``).
    """
    import control

    sp = _sympy()
    if not isinstance(system, control.StateSpace):
        if isinstance(system, control.NonlinearIOSystem):
            raise InvalidParameter("system", "a control.StateSpace (a NonlinearIOSystem holds Python functions that "
                                             "cannot be read exactly: give the sympy plant to close_loop instead)",
                                   type(system).__name__)
        raise InvalidParameter("system", "a control.StateSpace (convert a transfer function with control.ss)",
                               type(system).__name__)
    time = "discrete" if system.isdtime(strict=True) else "continuous"
    if model.get("time", time) != time:  # the system says which time it is in
        raise InvalidParameter("time", f'"{time}", the system\'s (dt = {system.dt})', model["time"])
    model["time"] = time
    n, m = system.nstates, system.ninputs
    A, B, K = _matrix("system.A", system.A, n, n), _matrix("system.B", system.B, n, m), _matrix("gain", gain, m, n)
    if states is None:
        labels = list(getattr(system, "state_labels", []))
        names = labels if len(labels) == n and all(str(s).isidentifier() for s in labels) \
            else [f"x{i + 1}" for i in range(n)]
        xs = tuple(sp.Symbol(str(s)) for s in names)
    else:
        xs = _symbols("states", states, "the system's states")
        if len(xs) != n:
            raise InvalidParameter("states", f"one symbol per state of the system ({n})", len(xs))
    x_eq = [Fraction(0)] * n
    if equilibrium is not None:
        given = dict(_by_state("equilibrium", equilibrium, [x.name for x in xs]))
        for i, x in enumerate(xs):
            if x.name in given:
                x_eq[i] = exact_number(f"equilibrium[{x.name}]", given[x.name])
    closed = [[A[i][j] - sum((B[i][k] * K[k][j] for k in range(m)), Fraction(0)) for j in range(n)]
              for i in range(n)]
    offset = [sum((A[i][j] * x_eq[j] for j in range(n)), Fraction(0)) for i in range(n)]
    rhs = [sum((_rational(sp, closed[i][j]) * (xs[j] - _rational(sp, x_eq[j])) for j in range(n)), sp.Integer(0))
           + _rational(sp, offset[i]) for i in range(n)]
    if equilibrium is not None:
        model["equilibrium"] = x_eq
    model.setdefault("name", "python-control loop closed with u = -K (x - x_eq)")
    return from_sympy(xs, rhs, **model)


class _ModelKind(type):
    """``isinstance(m, Model)`` for a model of either kind: a polynomial or rational loop
    (:class:`lyapcheck.models.language.modelfile.Model`) or a loop with functions
    (:class:`lyapcheck.models.language.recast.RecastModel`)."""

    def __instancecheck__(cls, instance: object) -> bool:
        from lyapcheck.models.language.modelfile import Model as FileModel
        from lyapcheck.models.language.recast import RecastModel

        return isinstance(instance, (FileModel, RecastModel))


class Model(metaclass=_ModelKind):
    """``lyapcheck.Model``: the ways to build a model in Python, and the type of what they return.

    A model is read from a model file's text in every case (``to_toml()`` gives it back); this class
    is not instantiated itself: ``isinstance(m, Model)`` holds for a polynomial or rational loop
    (:class:`lyapcheck.models.language.modelfile.Model`) and for a loop with functions
    (:class:`lyapcheck.models.language.recast.RecastModel`), both of which ``certify``, ``verify`` and
    ``simulate`` take.
    """

    from_sympy = staticmethod(from_sympy)
    from_control = staticmethod(from_control)
    close_loop = staticmethod(close_loop)

    @staticmethod
    def from_toml(text: str, source: str = "<from_toml>") -> "FileModel | RecastModel":
        """A model file's text, as a file with it is read (``model.to_toml()`` round-trips)."""
        if not isinstance(text, str):
            raise InvalidParameter("text", "a model file's text (a string)", type(text).__name__)
        return _parse(text, source)

    def __new__(cls, *args: object, **kwargs: object) -> "Model":
        raise TypeError("lyapcheck.Model is not instantiated: build a model with Model.from_sympy, "
                        "Model.from_control or close_loop, or read one with Model.from_toml")

"""The ``[units]`` table of a model file, and the dimension check of its expressions.

A model that declares ``[units]`` (a unit per state, default dimensionless; ``time``, default and
only ``s``) has every right-hand side checked, term by term as written
(docs/model-files-units.md):

- a state has the dimension of its unit; a parameter or a disturbance that of the unit of its value
  or bound (``k = "2 1/s^2"``, ``d = "0.1 mm/s"``); a plain number is dimensionless;
- ``x'`` has the dimension of ``x`` per time, and so must every term of its right-hand side;
- every term of a sum (``+``, ``-``) has the sum's dimension: where it is known from outside (the
  right-hand side, or a sum whose co-factors fix it, as in ``-(k*x + c*v)/m``) each term is compared
  with it; otherwise (a sum in a denominator, an output) with the sum's first term;
- ``*`` and ``/`` multiply and divide dimensions, ``** k`` raises to the ``k``-th power, a unary sign
  changes nothing;
- a literal number is dimensionless (``-x + 1`` with ``x`` in m is a mismatch), except the literal 0,
  which fits any dimension;
- in a loop with functions (lyapcheck.models.language.recast): ``sin cos exp tanh atan`` take a dimensionless
  argument and give a dimensionless result; ``sqrt(q)`` has half the dimension of ``q`` (a dimension
  with an odd power has no square root and is refused); ``abs(u)`` has the dimension of ``u``;
  ``min(a, b)``, ``max(a, b)`` and ``sat(u, limit)`` need their two arguments of one dimension and
  have it; ``pi`` is dimensionless.

Outputs are checked for consistency only (the terms of each sum agree): nothing declares an
output's unit, and its bound is in the unit its expression has.

The walker reads the expression with :func:`ast.parse` (a tree, nothing evaluated), after
:mod:`lyapcheck.models.language.expressions` has accepted the text, and visits only that language's nodes
(``BinOp`` with ``+ - * / **``, ``UnaryOp``, ``Constant``, ``Name``, and ``Call`` of the functions of
:data:`~lyapcheck.models.language.expressions.FUNCTIONS`). Anything else, or a name the model does not
declare, raises :class:`OutsideLanguage`: a loop with functions is dimension-checked before it is
recast, and its parser (which runs in the recasting) then says what is wrong in its own words.
Values are untouched: a model file is SI inside with or without ``[units]``, which is why
``[units]`` takes SI units only.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from fractions import Fraction
from typing import Final, Literal, Mapping, Sequence

from lyapcheck.errors import InvalidParameter
from lyapcheck.models.language.expressions import (FUNCTIONS, MAX_EXPRESSION_LENGTH, ExpressionError, parse_quietly,
                                          refuse_deep_nesting)
from lyapcheck.units import DIMENSIONLESS, Dimension, SIQuantity, model_unit, parse_si_with_dimension

#: the table's key for the time unit
TIME_KEY: Final = "time"
#: the dimension of time, the only one the ``time`` key accepts
TIME: Final = Dimension.of({"[time]": 1})
#: the functions whose argument must be dimensionless, and whose value is
_DIMENSIONLESS_FUNCTIONS: Final = ("sin", "cos", "exp", "tanh", "atan")
#: the functions whose two arguments must have one dimension, which is the value's
_AGREEING_FUNCTIONS: Final = ("min", "max", "sat")
#: the constant of the language (dimensionless), a name no model may declare in a loop with functions
_PI: Final = "pi"
#: the deepest tree the walker visits (the expression parser's MAX_DEPTH is 60, and a parenthesis
#: costs the walker at most two levels)
_MAX_WALK_DEPTH: Final = 200


class DimensionError(ValueError):
    """A ``[units]`` entry, a quantity or a term whose dimension is wrong: ``key`` names where
    (``[dynamics] v``) and the message says what was found and what was expected, in one line."""

    def __init__(self, key: str, message: str) -> None:
        self.key = key
        self.message = message
        super().__init__(f"{key}: {message}")


class OutsideLanguage(DimensionError):
    """A text outside the expression language (a node, a function or a name the model does not
    have): its parser says what is wrong, in one line; the dimension check stands aside for it."""


@dataclass(frozen=True)
class Named:
    """A name of the model with its dimension, and how the file gives it (for messages)."""

    kind: Literal["state", "parameter", "disturbance"]
    dimension: Dimension
    #: a state's unit ('' when dimensionless); a parameter's value or a disturbance's bound as written
    given: str
    #: whether the value or bound has a unit (a state: whether [units] lists it)
    has_unit: bool

    def describe(self, name: str) -> str:
        if self.kind == "state":
            return f"{name} is in {self.given}" if self.has_unit else f"{name} is dimensionless (not in [units])"
        shown = f"{name} =" if self.kind == "parameter" else f"|{name}| <="
        if self.has_unit:
            return f"{shown} '{self.given}'"
        return f"{shown} {self.given} is a plain number (dimensionless)"


@dataclass(frozen=True)
class UnitTable:
    """``[units]`` as read: each state's unit text ('' when not listed) and dimension, and the time's."""

    states: dict[str, tuple[str, Dimension]]
    time: str

    def dimension(self, state: str) -> Dimension:
        return self.states[state][1]


def read_units(table: Mapping[str, object], states: Sequence[str], other_names: Sequence[str] = ()) -> UnitTable:
    """Read ``[units]``: a unit per state (SI, exactly: factor 1 to SI base units) and ``time = "s"``.

    ``other_names`` are the parameters and disturbances, named in the message when a key is one of
    them (their unit comes from their value).
    """
    if TIME_KEY in table and TIME_KEY in states:
        raise DimensionError(f"[units] {TIME_KEY}", f"is ambiguous: a state is named '{TIME_KEY}', and the key is the "
                                                    "time unit (rename the state to give it a unit)")
    units: dict[str, tuple[str, Dimension]] = {s: ("", DIMENSIONLESS) for s in states}
    time = "s"
    for key, value in table.items():
        where = f"[units] {key}"
        if key != TIME_KEY and key not in states:
            why = (" (a parameter or a disturbance takes its unit from its value, e.g. k = \"2 1/s^2\")"
                   if key in other_names else "")
            raise DimensionError(where, f"no state named '{key}' (keys: the states {', '.join(states)}, and "
                                        f"'{TIME_KEY}'){why}")
        if not isinstance(value, str):
            raise DimensionError(where, f"must be a unit in a string, such as \"m\" or \"m/s\", got {value!r}")
        text = value.strip()
        if text in ("", "1"):
            factor, dimension = Fraction(1), DIMENSIONLESS
        else:
            try:
                factor, dimension = model_unit(key, text, value)
            except InvalidParameter as exc:
                raise DimensionError(where, f"must be {exc.expected.replace('a number with a unit', 'a unit')}, "
                                            f"got {value!r}") from None
        si = dimension.si_unit() or "1"
        if key == TIME_KEY:
            if dimension != TIME or factor != 1:
                raise DimensionError(where, f"must be 's' (the default), got {value!r}: a model file is SI inside "
                                            "and its field is integrated in seconds (a rate '0.5 1/min' is read "
                                            "as 1/120 1/s)")
            time = text
            continue
        if factor != 1:
            raise DimensionError(where, f"must be an SI unit, got {value!r} ({factor} {si}): a model file is SI "
                                        f"inside (its values, [equilibrium] and [domain] are read in SI), so write "
                                        f"'{si}' and give quantities with their own units (\"0.75 mm\")")
        units[key] = (text if text != "1" else "", dimension)
    return UnitTable(units, time)


def check_dynamics(state: str, text: str, units: UnitTable, names: Mapping[str, Named]) -> None:
    """Every term of ``state``'s right-hand side has the dimension of ``state`` per time (else
    :class:`DimensionError` at ``[dynamics] state``, naming the term and both dimensions)."""
    unit, dimension = units.states[state]
    expected = dimension / TIME
    why = f"the dimension of {state}' ({state} in {unit}, per {units.time})" if unit else \
        f"the dimension of {state}' ({state} dimensionless, per {units.time})"
    _Walker(text, names, closed=True).check(f"[dynamics] {state}", expected, why)


def check_map(state: str, text: str, units: UnitTable, names: Mapping[str, Named]) -> None:
    """A discrete-time map's right-hand side is ``state``'s next value: every term has the dimension
    of ``state`` itself, not per time (else :class:`DimensionError` at ``[dynamics] state``)."""
    unit, dimension = units.states[state]
    why = f"the dimension of {state}+ ({state} in {unit}: a map gives the next value)" if unit else \
        f"the dimension of {state}+ ({state} dimensionless: a map gives the next value)"
    _Walker(text, names, closed=True).check(f"[dynamics] {state}", dimension, why)


def check_output(name: str, text: str, names: Mapping[str, Named]) -> Dimension:
    """An output's terms agree in every sum (nothing declares its unit); its dimension."""
    return _Walker(text, names).check(f"[outputs] {name}", None, "")


def check_inequality(key: str, text: str, names: Mapping[str, Named]) -> None:
    """A ``[sets]`` inequality (``A <= B``, or a chain): each side agrees with itself, as an output,
    and the sides of each comparison have one dimension (a side that is the literal 0 fits any)."""
    from lyapcheck.models.language.sets import split_inequality

    for left, op, right in split_inequality(text):
        found = []
        for side in (left, right):
            walker = _Walker(side, names)
            found.append((walker.check(key, None, ""), _is_zero(parse_quietly(walker.text).body)))
        (dl, zl), (dr, zr) = found
        if zl or zr or dl == dr:
            continue
        message = (f"the sides of '{left} {op} {right}' differ in dimension: '{left}' has {dl}, '{right}' has {dr}")
        if dl == DIMENSIONLESS or dr == DIMENSIONLESS:
            bare = left if dl == DIMENSIONLESS else right
            message += (f"; '{bare}' is dimensionless: give a constant with a unit as a parameter "
                        "(e.g. x0 = \"1 m\")")
        raise DimensionError(key, message)


def check_value(key: str, value: object, expected: Dimension, what: str) -> None:
    """A quantity given with a unit (``[equilibrium]``, ``[domain]``, ``--set``) has the dimension
    ``expected`` (``what`` says whose it is); a plain number is read in SI and passes."""
    if not isinstance(value, str):
        return
    quantity = parse_si_with_dimension(key, value)
    if quantity.unit and quantity.dimension != expected:
        raise DimensionError(key, f"'{value}' has dimension {quantity.dimension}, but {what} has {expected} "
                                  "([units] is declared; a plain number is read in SI)")


class _Mismatch(Exception):
    """A term whose dimension is not the one expected; ``said``, when given, is the message's
    opening instead of "the term ... has dimension ..., expected ..." (a function's argument)."""

    def __init__(self, term: ast.AST, found: Dimension, expected: Dimension, why: str, said: str = "") -> None:
        super().__init__()
        self.term, self.found, self.expected, self.why, self.said = term, found, expected, why, said


class _Walker:
    """The dimension of an expression's tree, top down where the expected dimension is known."""

    def __init__(self, text: str, names: Mapping[str, Named], closed: bool = False) -> None:
        self.text = str(text).strip()
        self.source = self.text.encode("utf-8")
        self.names = names
        #: every name must be one of ``names`` (a right-hand side: else :class:`OutsideLanguage`);
        #: elsewhere a name not given (an output's disturbance times 0) is dimensionless
        self.closed = closed

    def check(self, key: str, expected: Dimension | None, why: str) -> Dimension:
        # on a polynomial loop the expression parser accepted the text first; a loop with functions
        # is checked before its recasting parses it, so what the parser refuses stands aside here
        # (OutsideLanguage), checked by the same limits before ast.parse recurses through it
        if len(self.text) > MAX_EXPRESSION_LENGTH:
            raise OutsideLanguage(key, "the expression is too long")
        try:
            refuse_deep_nesting(self.text)
            tree = parse_quietly(self.text)
        except (ExpressionError, SyntaxError, ValueError, RecursionError, MemoryError):
            raise OutsideLanguage(key, "not a valid expression") from None
        try:
            return self.walk(tree.body, expected, why, 0)
        except _Mismatch as exc:
            raise DimensionError(key, self.message(exc)) from None
        except OutsideLanguage as exc:
            raise OutsideLanguage(key, exc.message) from None

    def message(self, exc: _Mismatch) -> str:
        term = self.segment(exc.term)
        text = exc.said or f"the term '{term}' has dimension {exc.found}, expected {exc.expected}, {exc.why}"
        callees = _callees(exc.term)
        used = list(dict.fromkeys(n.id for n in ast.walk(exc.term) if isinstance(n, ast.Name) and n not in callees))
        described = [self.names[n].describe(n) for n in used if n in self.names]
        if described:
            text += "; " + ", ".join(described)
        if not used and not exc.found.exponents:
            text += "; a number is dimensionless: give a constant with a unit as a parameter (e.g. x0 = \"1 m\")"
        return text

    def segment(self, node: ast.AST) -> str:
        start, end = getattr(node, "col_offset", None), getattr(node, "end_col_offset", None)
        text = self.source[start:end].decode("utf-8") if start is not None and end is not None else "?"
        return text if len(text) <= 60 else text[:60] + "..."

    def walk(self, node: ast.AST, expected: Dimension | None, why: str, depth: int) -> Dimension:
        if depth > _MAX_WALK_DEPTH:  # the parser's MAX_DEPTH refuses it (first, on a polynomial loop)
            raise OutsideLanguage("expression", "nested too deeply")
        if _is_zero(node):
            return expected if expected is not None else DIMENSIONLESS
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            return self.walk(node.operand, expected, why, depth + 1)
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, (ast.Add, ast.Sub)):
                return self.sum(node, expected, why, depth)
            if isinstance(node.op, (ast.Mult, ast.Div)):
                return self.product(node, expected, why, depth)
            if isinstance(node.op, ast.Pow):
                return self.power(node, expected, why, depth)
        if isinstance(node, ast.Name):
            named = self.names.get(node.id)
            if named is None and self.closed and node.id != _PI:  # pi: the language's constant, a number
                raise OutsideLanguage("expression", f"unknown name '{node.id}'")
            return self.compare(node, named.dimension if named else DIMENSIONLESS, expected, why)
        if isinstance(node, ast.Constant) and _is_number(node):
            return self.compare(node, DIMENSIONLESS, expected, why)
        if isinstance(node, ast.Call):
            return self.call(node, expected, why, depth)
        # the expression parser refuses every other node (first, on a polynomial loop)
        raise OutsideLanguage("expression", f"'{self.segment(node)}' is not part of the language")

    def compare(self, node: ast.AST, found: Dimension, expected: Dimension | None, why: str) -> Dimension:
        if expected is not None and found != expected:
            raise _Mismatch(node, found, expected, why)
        return found

    def sum(self, node: ast.BinOp, expected: Dimension | None, why: str, depth: int) -> Dimension:
        terms: list[ast.AST] = []
        left: ast.AST = node
        while isinstance(left, ast.BinOp) and isinstance(left.op, (ast.Add, ast.Sub)):
            terms.append(left.right)
            left = left.left
        terms.append(left)
        terms.reverse()
        return self.agree(node, terms, expected, why, depth, "the first term")

    def agree(self, node: ast.AST, parts: Sequence[ast.AST], expected: Dimension | None, why: str, depth: int,
              first_is: str) -> Dimension:
        """``parts`` of ``node`` that have one dimension, ``node``'s (a sum's terms, the arguments of
        ``min``, ``max``, ``sat``): each compared with ``expected`` where it is known, else with the
        first part that is not the literal 0 (``first_is`` says what that part is, for messages)."""
        if expected is not None:
            for part in parts:
                self.walk(part, expected, why, depth + 1)
            return expected
        reference: Dimension | None = None
        first = ""
        for part in parts:
            if _is_zero(part):
                continue
            if reference is None:
                reference, first = self.walk(part, None, why, depth + 1), self.segment(part)
                continue
            self.walk(part, reference, f"that of '{first}', {first_is} of '{self.segment(node)}'", depth + 1)
        return reference if reference is not None else DIMENSIONLESS

    def call(self, node: ast.Call, expected: Dimension | None, why: str, depth: int) -> Dimension:
        """A function of the language (the module docstring's rules); anything else is
        :class:`OutsideLanguage` (its parser says why)."""
        name = node.func.id if isinstance(node.func, ast.Name) else ""
        if name not in FUNCTIONS or node.keywords or len(node.args) != FUNCTIONS[name]:
            raise OutsideLanguage("expression", f"'{self.segment(node)}' is not a function of the language")
        args = node.args
        if name in _DIMENSIONLESS_FUNCTIONS:
            found = self.fitting(args[0], DIMENSIONLESS, f"for the argument of '{self.segment(node)}' to be "
                                                         "dimensionless", depth)
            if found != DIMENSIONLESS:
                raise _Mismatch(args[0], found, DIMENSIONLESS, why, f"the argument of {self.segment(node)} must be "
                                                                    f"dimensionless, it has {found}")
            return self.compare(node, DIMENSIONLESS, expected, why)
        if name == "sqrt":
            # where the root's dimension is known, its argument's (the square) is, and a sum there is
            # compared term by term with it
            if expected is not None:
                square = self.fitting(args[0], expected ** 2, f"for '{self.segment(node)}' to have {expected}", depth)
            else:
                square = self.walk(args[0], None, why, depth + 1)
            odd = [(base, power) for base, power in square.exponents if power % 2]
            if odd:
                base, power = odd[0]
                raise _Mismatch(args[0], square, square, why, f"the argument of {self.segment(node)} has dimension "
                                                              f"{square}, which has no square root: the power of "
                                                              f"{base} is odd ({power}); sqrt takes a dimensionless "
                                                              "argument or one whose powers are even (an area)")
            return self.compare(node, square ** Fraction(1, 2), expected, why)
        if name == "abs":
            return self.walk(args[0], expected, why, depth + 1)
        if name not in _AGREEING_FUNCTIONS:  # pragma: no cover - a function without a rule here
            raise OutsideLanguage("expression", f"'{self.segment(node)}' has no dimension rule")
        # min, max, sat: two arguments of one dimension, the value's; where that is known from outside
        # and the arguments agree with each other but not with it, the whole call is the term named
        try:
            return self.agree(node, args, expected, why, depth, "the first argument")
        except _Mismatch as outer:
            if expected is None:
                raise
            try:
                found = self.agree(node, args, None, why, depth, "the first argument")
            except _Mismatch:
                raise outer from None
            raise _Mismatch(node, found, expected, why) from None

    def fitting(self, node: ast.AST, target: Dimension, why: str, depth: int) -> Dimension:
        """The dimension of ``node``, a function's argument that should have ``target``: where it
        agrees with itself but has another dimension, that dimension (the caller names the whole
        argument); where it does not agree with itself either, the first term that does not fit
        ``target`` is named (:class:`_Mismatch`)."""
        try:
            self.walk(node, target, why, depth + 1)
            return target
        except _Mismatch as outer:
            try:
                found = self.walk(node, None, why, depth + 1)
            except _Mismatch:
                raise outer from None
            if found == target:  # pragma: no cover - agreeing with itself and with target, it fitted
                raise outer from None
            return found

    def product(self, node: ast.BinOp, expected: Dimension | None, why: str, depth: int) -> Dimension:
        factors: list[tuple[ast.AST, int]] = []
        left: ast.AST = node
        while isinstance(left, ast.BinOp) and isinstance(left.op, (ast.Mult, ast.Div)):
            factors.append((left.right, -1 if isinstance(left.op, ast.Div) else 1))
            left = left.left
        factors.append((left, 1))
        factors.reverse()
        # the last factor that holds a sum takes the dimension the others leave for it, so that its
        # terms are compared with what they must be; the other factors are read bottom up
        sums = [i for i, (f, _) in enumerate(factors) if _holds_sum(f)]
        target = sums[-1] if expected is not None and sums else None
        rest = DIMENSIONLESS
        for i, (factor, sign) in enumerate(factors):
            if i != target:
                rest = rest * self.walk(factor, None, why, depth + 1) ** sign
        if target is None:
            return self.compare(node, rest, expected, why)
        assert expected is not None
        factor, sign = factors[target]
        self.within(node, factor, (expected / rest) ** sign, rest, sign, expected, why, depth)
        return expected

    def within(self, node: ast.AST, inner: ast.AST, target: Dimension, rest: Dimension, power: int,
               expected: Dimension, why: str, depth: int) -> None:
        """Check the sum ``inner`` of the term ``node`` (``node`` is ``rest * inner**power``) against the
        dimension ``target`` that ``expected`` leaves for it. Where the sum agrees with itself but not
        with ``target``, the fault is outside it (a co-factor's unit: ``U = 1`` in
        ``U*delta*eps/(eps**2 + delta**2)``), so the whole term is named; where it does not agree with
        itself either, its first term that does not fit ``target`` is."""
        try:
            self.walk(inner, target, f"for '{self.segment(node)}' to have {expected}", depth + 1)
        except _Mismatch as outer:
            try:
                found = self.walk(inner, None, why, depth + 1)
            except _Mismatch:
                raise outer from None
            raise _Mismatch(node, rest * found ** power, expected, why) from None

    def power(self, node: ast.BinOp, expected: Dimension | None, why: str, depth: int) -> Dimension:
        exponent = node.right.value if isinstance(node.right, ast.Constant) else None
        if not isinstance(exponent, int) or isinstance(exponent, bool):  # the parser's rule
            raise OutsideLanguage("expression", f"the exponent of '{self.segment(node)}' is not an integer")
        if expected is not None and exponent > 0 and _holds_sum(node.left):
            self.within(node, node.left, expected ** Fraction(1, exponent), DIMENSIONLESS, exponent, expected, why,
                        depth)
            return expected
        base = self.walk(node.left, None, why, depth + 1)
        return self.compare(node, base ** exponent, expected, why)


def named_table(units: UnitTable, quantities: Mapping[str, tuple[Literal["parameter", "disturbance"], SIQuantity]],
                given: Mapping[str, str]) -> dict[str, Named]:
    """Every name of a model with its dimension, for the walker: each state's from ``[units]``, each
    parameter's and disturbance's from the unit of its value as the file gives it (``given``)."""
    names: dict[str, Named] = {}
    for s, (unit, dimension) in units.states.items():
        names[s] = Named("state", dimension, unit, bool(unit))
    for key, (kind, quantity) in quantities.items():
        names[key] = Named(kind, quantity.dimension, given[key], bool(quantity.unit))
    return names


def infer_controls(dynamics: Mapping[str, str], units: UnitTable, names: Mapping[str, Named],
                   controls: Sequence[str]) -> dict[str, Dimension]:
    """The dimension each control of a sampled-data loop must have for the plant's right-hand sides to
    check (:func:`check_dynamics`), where the walker can tell: each control stands for an unknown base
    dimension of its own while the right-hand sides are walked, and where a term's dimension then differs
    from the one expected only through that unknown (``u`` where ``[length] / [time] ** 2`` is expected,
    or ``k*u**2``), the equation is solved for it. A control the right-hand sides do not determine is
    left out; a mismatch that does not involve a control is left to :func:`check_dynamics` (the plant's
    own check reports it)."""
    unknown = {u: Dimension.of({f"<{u}>": 1}) for u in controls}
    known: dict[str, Dimension] = {}
    trees = {}
    for state, text in dynamics.items():
        try:
            refuse_deep_nesting(text)
            trees[state] = parse_quietly(str(text).strip())
        except (ExpressionError, SyntaxError, ValueError, RecursionError, MemoryError):
            continue  # the parser says what is wrong
    for _ in range(len(controls) * max(1, len(trees)) + 1):  # each round fixes one control, or ends
        trial = {**names, **{u: Named("state", known.get(u, unknown[u]), "", True) for u in controls}}
        solved = None
        for state, tree in trees.items():
            expected = units.dimension(state) / TIME
            try:
                _Walker(str(dynamics[state]), trial, closed=True).walk(tree.body, expected, "", 0)
            except _Mismatch as exc:
                solved = _solve_for_control(exc.found, exc.expected, {u: d for u, d in unknown.items()
                                                                      if u not in known})
            except OutsideLanguage:
                continue
            if solved is not None:
                break
        if solved is None:
            break
        known[solved[0]] = solved[1]
    return known


def _solve_for_control(found: Dimension, expected: Dimension, unknown: Mapping[str, Dimension]
                       ) -> tuple[str, Dimension] | None:
    """The control whose unknown dimension makes ``found`` equal ``expected``, and that dimension: with
    ``e_f`` and ``e_e`` the unknown's exponents in each, ``D ** (e_f - e_e)`` is the rest of ``expected``
    over the rest of ``found``; None when no control's unknown alone explains the difference."""
    def without(d: Dimension, base: str) -> Dimension:
        return Dimension.of({k: e for k, e in d.exponents if k != base})

    for u, marker in unknown.items():
        base = marker.exponents[0][0]
        e_f, e_e = dict(found.exponents).get(base, Fraction(0)), dict(expected.exponents).get(base, Fraction(0))
        if e_f == e_e:
            continue
        solution = (without(expected, base) / without(found, base)) ** (1 / (e_f - e_e))
        if not any(k.startswith("<") for k, _ in solution.exponents):  # free of the other controls' unknowns
            return u, solution
    return None


def check_law(control: str, text: str, dimension: Dimension | None, why: str, names: Mapping[str, Named]) -> None:
    """A sampled-data loop's ``[controller]`` law: every term has ``dimension`` (the one the plant needs for
    the control, ``why`` says so) where it is known, else the law agrees with itself (each sum's terms,
    each function's argument dimensionless), as an output (else :class:`DimensionError` at
    ``[controller] control``)."""
    _Walker(text, names, closed=True).check(f"[controller] {control}", dimension, why)


def _is_zero(node: ast.AST) -> bool:
    """The literal 0 (``0``, ``0.0``, ``-0``): a term that fits any dimension."""
    while isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return (isinstance(node, ast.Constant) and isinstance(node.value, (int, float))
            and not isinstance(node.value, bool) and node.value == 0)


def _is_number(node: ast.Constant) -> bool:
    return isinstance(node.value, (int, float)) and not isinstance(node.value, bool)


def _callees(node: ast.AST) -> list[ast.AST]:
    """The names of the functions called in ``node`` (``sin`` in ``sin(x)``): not names of the model."""
    return [n.func for n in ast.walk(node) if isinstance(n, ast.Call)]


def _holds_sum(node: ast.AST) -> bool:
    """Whether ``node`` is a sum, under signs and powers (``-(a + b)``, ``(a + b)**2``)."""
    while True:
        if isinstance(node, ast.UnaryOp):
            node = node.operand
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            node = node.left
        else:
            return isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub))


__all__ = ["DimensionError", "OutsideLanguage", "Named", "UnitTable", "read_units", "check_dynamics", "check_map", "check_output", "check_value",
           "TIME_KEY", "check_law", "infer_controls", "named_table"]

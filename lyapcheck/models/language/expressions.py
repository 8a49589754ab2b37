"""The expression language of model files: a whitelist over Python's ``ast``, built into exact
rational functions.

A user's string is data, never code. It is parsed by :func:`ast.parse` (which builds a tree and
runs nothing), and the tree is walked by :func:`_build`, which accepts exactly the contract's
small language (DESIGN.md, "Model files"):

- numbers: integer, decimal and exponent literals, read exactly from their source text
  (``0.1`` is ``1/10``, not its binary neighbour);
- the names the file declares (states, parameters, disturbances);
- ``+ - * /``, unary ``-`` and ``+``, parentheses;
- ``**`` with a non-negative integer literal exponent of at most :data:`MAX_EXPONENT`.

Everything else is refused with one line that says what was found and what to write instead: a
function call where none is taken (see below), ``^`` (write ``**``), a non-integer, negative or
huge exponent, an unknown name, a non-finite number. Nothing reaches ``eval``, ``exec``,
``sympify`` or ``parse_expr``.

In ``[dynamics]`` (and ``--candidate`` of such a loop) the language also has the functions of
:data:`FUNCTIONS` and the constant ``pi``: the builder hands each call to a
:class:`FunctionCalls` (:class:`lyapcheck.models.language.recast.Recaster`), which returns it as a new
variable of the ring, an auxiliary with its exact relations. :func:`uses_functions` tells which
texts need that (a scan of the tree, nothing evaluated).

The result is a :class:`Rational`: numerator and denominator polynomials with exact rational
coefficients in all the file's names. Sizes are bounded while the tree is built (degree, number
of terms), so an expression like ``(x1 + ... + x12)**12`` is refused before it is expanded: a
power is multiplied out one factor at a time and refused at the first product beyond
:data:`MAX_TERMS`, as the same factors written out with ``*`` would be.

Nothing here walks the tree by recursion deeper than :data:`MAX_DEPTH` levels of real nesting: a
long sum or product (``a + b + c + ...``, which Python parses as a tree as deep as it is long) is
folded in a loop, and messages quote what the user wrote by its position in the text instead of
re-printing a subtree (``ast.unparse`` recurses, and a chain like ``x1**x1**...`` or
``x1.a.a.a...`` of a thousand links would exceed Python's recursion limit).
"""

from __future__ import annotations

import ast
import math
import warnings
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from typing import Final, Mapping, Protocol, Sequence

from lyapcheck.sos.polynomials import Poly, Ring, total_degree

#: the largest exponent literal after ``**``
MAX_EXPONENT: Final = 12
#: the largest total degree of a numerator or a denominator, in all the file's names
MAX_TOTAL_DEGREE: Final = 12
#: the most terms a numerator or denominator may have while it is built
MAX_TERMS: Final = 2000
#: the longest expression, in characters
MAX_EXPRESSION_LENGTH: Final = 4000
#: the deepest nesting of the expression's tree (parentheses, unary signs, powers; the terms of one
#: sum or the factors of one product are one level, however many there are)
MAX_DEPTH: Final = 60
#: a number's magnitude must be finite as a double, and a non-zero one at least the smallest normal
NUMBER_RANGE: Final = "finite as a double (magnitude at most 1.8e308) and, if not 0, at least 2.2e-308"

#: functions users write, and what to do instead (every call is refused; these get a hint)
_RECAST_HINT: Final = ("here the expression must be polynomial or rational in the states; functions are taken in "
                       "[dynamics], which lyapcheck then recasts exactly (docs/model-files.md, 'Loops with functions')")


#: the functions of the language and their number of arguments
FUNCTIONS: Final = {"sin": 1, "cos": 1, "exp": 1, "sqrt": 1, "atan": 1, "tanh": 1, "abs": 1, "min": 2, "max": 2,
                    "sat": 2}


class ExpressionError(ValueError):
    """An expression outside the language; the message says what and what to write instead."""


class FunctionCalls(Protocol):
    """What the builder hands function calls and ``pi`` to (:class:`lyapcheck.models.language.recast.Recaster`)."""

    def check_call(self, name: str, arity: int, text: str) -> None: ...

    def apply(self, name: str, args: list["Rational"], text: str) -> "Rational": ...

    def pi(self) -> "Rational": ...


@dataclass(frozen=True)
class Rational:
    """``numerator / denominator``: exact polynomials in one :class:`Ring` (denominator non-zero)."""

    ring: Ring
    numerator: Poly
    denominator: Poly

    @classmethod
    def polynomial(cls, ring: Ring, p: Poly) -> "Rational":
        return cls(ring, p, ring.constant(1))

    def is_polynomial(self) -> bool:
        return self.denominator.is_constant()

    def normalized(self) -> "Rational":
        """Common factors cancelled and a constant denominator folded into the numerator."""
        num, den = self.numerator, self.denominator
        if num.is_zero():
            return Rational(self.ring, num, self.ring.constant(1))
        g = num.gcd(den)
        if not g.is_constant():
            num, den = num / g, den / g
        if den.is_constant():
            c = den.leading_coefficient()
            return Rational(self.ring, num * (1 / c), self.ring.constant(1))
        # a positive leading coefficient, so that equal rational functions look alike
        lead = den.leading_coefficient()
        return Rational(self.ring, num * (1 / lead), den * (1 / lead))

    def __add__(self, other: "Rational") -> "Rational":
        if self.denominator == other.denominator:
            return Rational(self.ring, self.numerator + other.numerator, self.denominator)
        return Rational(self.ring, self.numerator * other.denominator + other.numerator * self.denominator,
                        self.denominator * other.denominator)

    def __neg__(self) -> "Rational":
        return Rational(self.ring, -self.numerator, self.denominator)

    def __sub__(self, other: "Rational") -> "Rational":
        return self + (-other)

    def __mul__(self, other: "Rational") -> "Rational":
        return Rational(self.ring, self.numerator * other.numerator, self.denominator * other.denominator)

    def divide(self, other: "Rational") -> "Rational":
        if other.numerator.is_zero():
            raise ExpressionError("division by zero")
        return Rational(self.ring, self.numerator * other.denominator, self.denominator * other.numerator)

    def power(self, k: int) -> "Rational":
        return Rational(self.ring, self.numerator ** k, self.denominator ** k)


def parse_expression(text: str, ring: Ring) -> Rational:
    """The exact rational function of ``text`` (see :func:`parse_with_divisors`)."""
    return parse_with_divisors(text, ring)[0]


def parse_with_divisors(text: str, ring: Ring, *, calls: "FunctionCalls | None" = None,
                        names: Sequence[str] | None = None, constants: Mapping[str, Fraction] | None = None,
                        defined: Mapping[str, Rational] | None = None) -> tuple[Rational, tuple[Poly, ...]]:
    """The exact rational function of ``text``, over ``ring`` (whose names are the declared ones),
    and every non-constant divisor as written (the numerator of each ``/``'s right operand, before
    any common factor is cancelled: ``-x**2/x`` gives ``-x`` and the divisor ``x``).

    With ``calls`` (:mod:`lyapcheck.models.language.recast`), a function call of the non-polynomial language
    and the constant ``pi`` are handed to it, which returns each as a rational function of new
    variables of ``ring`` (its auxiliaries); ``names`` are then the names the user may write (the
    ring has more) and ``constants`` the names read as exact numbers (parameters at their values).
    ``defined`` are names that stand for expressions already built in ``ring`` (a network's outputs:
    :mod:`lyapcheck.models.language.networks`).

    Raises
    ------
    ExpressionError
        Anything outside the language, or beyond the size limits; the message is one line.
    """
    if not isinstance(text, str):
        raise ExpressionError(f"an expression must be a string, got {type(text).__name__} {text!r}")
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise ExpressionError(f"the expression has {len(text)} characters; the limit is {MAX_EXPRESSION_LENGTH} "
                              "(MAX_EXPRESSION_LENGTH)")
    if not text.strip():
        raise ExpressionError("the expression is empty")
    if "\n" in text.strip() or ";" in text:
        raise ExpressionError("an expression is one line, without ';'")
    refuse_deep_nesting(text)
    try:
        tree = parse_quietly(text.strip())
    except SyntaxError as exc:
        raise ExpressionError(f"not a valid expression ({exc.msg}{_where(exc.offset)})") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError("not a valid expression (too deeply nested)") from None
    builder = _Builder(text.strip(), ring, calls, names, constants, defined)
    try:
        result = builder.build(tree.body, 0)
    except RecursionError:  # a backstop only: the builder's own depth limit comes first
        raise ExpressionError(f"the expression is nested too deeply (the limit is {MAX_DEPTH}, MAX_DEPTH)") from None
    return result.normalized(), tuple(builder.divisors)


def refuse_deep_nesting(text: str) -> None:
    """Refuse parentheses nested deeper than :data:`MAX_DEPTH` before :func:`ast.parse` (which
    recurses) sees them."""
    depth = 0
    for ch in text:
        depth += ch == "("
        depth -= ch == ")"
        if depth > MAX_DEPTH:
            raise ExpressionError(f"parentheses nested deeper than {MAX_DEPTH} (MAX_DEPTH)")


def parse_quietly(text: str) -> ast.Expression:
    """``ast.parse(text, mode="eval")`` without Python's warnings: its tokenizer warns about some texts
    outside the language ("1if x1 else 2": invalid decimal literal) by printing to stderr, a second
    line beside the one-line error the builder gives for every such text anyway."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ast.parse(text, mode="eval")


def _where(offset: int | None) -> str:
    return f" at character {offset}" if offset else ""


class _Builder:
    """Walks a parsed tree, accepting only the contract's nodes (see the module docstring)."""

    def __init__(self, source: str, ring: Ring, calls: "FunctionCalls | None" = None,
                 names: Sequence[str] | None = None, constants: Mapping[str, Fraction] | None = None,
                 defined: Mapping[str, Rational] | None = None) -> None:
        self.source = source
        self.ring = ring
        self.calls = calls
        self.names = tuple(ring.names if names is None else names)
        self.constants = dict(constants or {})
        self.defined = dict(defined or {})
        # node positions are UTF-8 byte offsets; on one line they slice these bytes directly
        # (ast.get_source_segment splits the whole text on every call: a second for 1000 numbers)
        self.source_bytes = source.encode("utf-8")
        #: every non-constant divisor as written (its numerator), before any cancellation: where one
        #: is 0 the expression is undefined, even if a common factor cancels it ("-x**2/x")
        self.divisors: list[Poly] = []

    def build(self, node: ast.AST, depth: int) -> Rational:
        if depth > MAX_DEPTH:
            raise ExpressionError(f"the expression is nested deeper than {MAX_DEPTH} (MAX_DEPTH)")
        if isinstance(node, ast.Constant):
            return Rational.polynomial(self.ring, self.ring.constant(self._number(node)))
        if isinstance(node, ast.Name):
            if node.id in self.constants:
                return Rational.polynomial(self.ring, self.ring.constant(self.constants[node.id]))
            if node.id in self.defined:
                return self.defined[node.id]
            if self.calls is not None and node.id == "pi" and node.id not in self.names:
                return self.calls.pi()
            if node.id not in self.names:
                raise ExpressionError(self._unknown_name(node.id))
            return Rational.polynomial(self.ring, self.ring.gen(node.id))
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return -self.build(node.operand, depth + 1)
            if isinstance(node.op, ast.UAdd):
                return self.build(node.operand, depth + 1)
            raise ExpressionError(f"the operator '{_OPERATOR_TEXT.get(type(node.op), type(node.op).__name__)}' "
                                  "is not part of the language (use + - * / **)")
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, _CHAIN_OPERATORS):
                return self._chain(node, depth)
            return self._binary(node, depth)
        if isinstance(node, ast.Attribute) or isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            raise ExpressionError(self._attribute(node))
        if isinstance(node, ast.Call):
            name = node.func.id if isinstance(node.func, ast.Name) else self._text(node.func)
            if self.calls is not None and isinstance(node.func, ast.Name):
                if node.keywords:
                    raise ExpressionError(f"'{self._text(node)}': a function takes positional arguments only")
                self.calls.check_call(name, len(node.args), self._text(node))
                args = [self.build(a, depth + 1) for a in node.args]
                return self._checked(self.calls.apply(name, args, self._text(node)), node)
            raise ExpressionError(f"function call '{name}(...)' is not allowed: {_RECAST_HINT}")
        raise ExpressionError(f"'{self._text(node)}' is not part of the language (numbers, declared names, "
                              "+ - * /, ** with a non-negative integer, parentheses)")

    def _unknown_name(self, name: str) -> str:
        """The message for a name that is not declared: what it is, and what to write instead.

        Without a :class:`FunctionCalls` the text is in a section that takes no functions (or a
        polynomial ``[dynamics]``, where ``pi`` never reaches here: it makes the loop one with
        functions), so ``pi`` is refused as a constant that only [dynamics] takes."""
        declared = ", ".join(self.names) or "none"
        if name == "t":
            return (f"unknown name 't' (declared names: {declared}): time is not a name of the model; the loop must "
                    "be autonomous (for a time dependence, make time a state t with [dynamics] t = \"1\")")
        if name == "pi" and self.calls is None:
            return ("the constant 'pi' is not allowed here: the expression must be polynomial or rational in the "
                    "states (pi is taken in [dynamics], in an argument of sin or cos)")
        return f"unknown name '{name}' (declared names: {declared}; a constant is declared in [parameters])"

    def _attribute(self, node: ast.Attribute | ast.Call) -> str:
        """The message for ``math.sin(x)``, ``np.pi``, ``x.real``: attribute access is not part of
        the language; a known function or ``pi`` is written without its module."""
        attribute = node if isinstance(node, ast.Attribute) else node.func
        assert isinstance(attribute, ast.Attribute)  # the caller's test; narrows the type
        prefix = self._text(attribute.value)
        said = f"'{self._text(node)}': attribute access ('{prefix}.') is not part of the language"
        if isinstance(node, ast.Call):
            said = "function call " + said
            if self.calls is None:  # a call reaches here only outside [dynamics] (calls make a loop recast)
                return f"{said}, and {_RECAST_HINT}"
        if attribute.attr in FUNCTIONS or attribute.attr == "pi":
            whole, value = self._segment(node), self._segment(attribute.value)
            bare = whole[len(value):].lstrip().lstrip(".").lstrip() if whole and value and \
                whole.startswith(value) else attribute.attr + ("(...)" if isinstance(node, ast.Call) else "")
            return f"{said}: write '{_short(' '.join(bare.split()))}'"
        if isinstance(node, ast.Call):
            return f"{said} (functions: {', '.join(FUNCTIONS)}; and the constant pi)"
        return said

    def _text(self, node: ast.AST) -> str:
        """What the user wrote for ``node``, on one line and shortened: read from the source by
        position (``ast.unparse`` would recurse through a subtree of any depth)."""
        return _short(" ".join((self._segment(node) or type(node).__name__).split()))

    def _segment(self, node: ast.AST) -> str | None:
        """The source text of ``node``, exactly."""
        if getattr(node, "lineno", None) == 1 and getattr(node, "end_lineno", None) == 1:
            return self.source_bytes[node.col_offset:node.end_col_offset].decode("utf-8")  # type: ignore[attr-defined]
        return ast.get_source_segment(self.source, node)

    def _number(self, node: ast.Constant) -> Fraction:
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ExpressionError(f"'{self._text(node)}' is not a number of the language")
        if isinstance(value, int):
            number = Fraction(value)
        else:
            if not math.isfinite(value):
                raise ExpressionError(f"the number '{self._text(node)}' is not finite "
                                      f"(numbers must be {NUMBER_RANGE})")
            # exactly as written (0.1 is 1/10), read as a Decimal first: Fraction("1e-9999999") builds
            # 10**9999999 (seconds; "0e999999999" would take hours), so a decimal exponent beyond any
            # double's is refused before any power of ten is built
            try:
                decimal = Decimal(self._segment(node) or repr(value))
            except InvalidOperation:
                decimal = Decimal(repr(value))
            if decimal.is_zero():
                return Fraction(0)
            if abs(decimal.adjusted()) > _MAX_DECIMAL_EXPONENT:
                raise ExpressionError(f"the number '{self._text(node)}' is out of range "
                                      f"(numbers must be {NUMBER_RANGE})")
            number = Fraction(decimal)
        if number and not (2.2250738585072014e-308 <= abs(number) <= 1.7976931348623157e308):
            raise ExpressionError(f"the number '{self._text(node)}' is out of range "
                                  f"(numbers must be {NUMBER_RANGE})")
        return number

    def _binary(self, node: ast.BinOp, depth: int) -> Rational:
        """``**``, and the operators outside the language (``+ - * /`` are :meth:`_chain`'s)."""
        op = node.op
        if isinstance(op, ast.BitXor):
            raise ExpressionError(f"'^' in '{self._text(node)}' is not a power: write '**' "
                                  f"(e.g. {self._text(node.left)}**{self._text(node.right)})")
        if isinstance(op, ast.Pow):
            base = self.build(node.left, depth + 1)
            k = self._exponent(node.right)
            limit = MAX_TOTAL_DEGREE
            if (total_degree(base.numerator) * k > limit or total_degree(base.denominator) * k > limit):
                raise ExpressionError(f"'{self._text(node)}' has total degree above {limit} (MAX_TOTAL_DEGREE)")
            return self._checked(self._power(base, k, node), node)
        raise ExpressionError(f"the operator '{_OPERATOR_TEXT.get(type(op), type(op).__name__)}' is not part "
                              "of the language (use + - * / **)")

    def _chain(self, node: ast.BinOp, depth: int) -> Rational:
        """``a + b - c * d / e ...``: Python parses it as a tree leaning left, one level per operator,
        so a polynomial of 70 terms would be 70 levels deep. Its left spine is walked in a loop and
        folded in the order Python would evaluate it: every operand is one level below the chain."""
        spine: list[ast.BinOp] = []
        left: ast.expr = node
        while isinstance(left, ast.BinOp) and isinstance(left.op, _CHAIN_OPERATORS):
            spine.append(left)
            left = left.left
        result = self.build(left, depth + 1)
        for step in reversed(spine):
            right = self.build(step.right, depth + 1)
            if isinstance(step.op, ast.Add):
                result = self._checked(result + right, step)
            elif isinstance(step.op, ast.Sub):
                result = self._checked(result - right, step)
            elif isinstance(step.op, ast.Mult):
                result = self._checked(result * right, step)
            else:
                if right.numerator.is_zero():
                    raise ExpressionError(f"division by zero in '{self._text(step)}'")
                if not right.numerator.is_constant():
                    self.divisors.append(right.numerator)
                result = self._checked(result.divide(right), step)
        return result

    def _power(self, base: Rational, k: int, node: ast.AST) -> Rational:
        """``base**k``, one factor at a time, each product's size checked: ``(x1 + ... + x12)**12``
        (1,352,078 terms) is refused at its fifth power (4,368 terms) within microseconds, instead of
        after a second or more of expansion. The same factors written out with ``*`` meet the same
        limit at the same product."""
        result = Rational.polynomial(self.ring, self.ring.constant(1))
        for _ in range(k):
            result = Rational(self.ring, result.numerator * base.numerator, result.denominator * base.denominator)
            self._check_terms(result, node)
        return result

    def _exponent(self, node: ast.AST) -> int:
        text = self._text(node)
        if isinstance(node, ast.Constant) and isinstance(node.value, int) and not isinstance(node.value, bool):
            k = int(node.value)
            if k > MAX_EXPONENT:
                raise ExpressionError(f"the exponent {k} is above the limit {MAX_EXPONENT} (MAX_EXPONENT)")
            return k
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            raise ExpressionError(f"the exponent '{text}' is negative: write a division (1/x**k) instead")
        if isinstance(node, ast.Constant) and isinstance(node.value, float):
            raise ExpressionError(f"the exponent '{text}' is not an integer: the field must be polynomial or "
                                  "rational in the states")
        raise ExpressionError(f"the exponent '{text}' must be a non-negative integer literal (at most {MAX_EXPONENT})")

    def _checked(self, r: Rational, node: ast.AST) -> Rational:
        """Cancel common factors now and then, and refuse sizes beyond the limits."""
        if len(r.denominator) > 1 and not r.denominator.is_constant() and \
                (len(r.numerator) > 50 or len(r.denominator) > 50):
            r = r.normalized()
        for part in (r.numerator, r.denominator):
            if total_degree(part) > MAX_TOTAL_DEGREE:
                r = r.normalized()
                if total_degree(r.numerator) > MAX_TOTAL_DEGREE or total_degree(r.denominator) > MAX_TOTAL_DEGREE:
                    raise ExpressionError(f"'{self._text(node)}' has total degree above {MAX_TOTAL_DEGREE} "
                                          "(MAX_TOTAL_DEGREE)")
            self._check_terms(r, node)
        return r

    def _check_terms(self, r: Rational, node: ast.AST) -> None:
        if len(r.numerator) > MAX_TERMS or len(r.denominator) > MAX_TERMS:
            raise ExpressionError(f"'{self._text(node)}' expands to more than {MAX_TERMS} terms (MAX_TERMS)")


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


#: the operators of one left-leaning chain (:meth:`_Builder._chain`)
_CHAIN_OPERATORS: Final = (ast.Add, ast.Sub, ast.Mult, ast.Div)

#: the largest decimal exponent (of the leading digit) a literal may have: beyond every double's
_MAX_DECIMAL_EXPONENT: Final = 309

_OPERATOR_TEXT: Final[dict[type, str]] = {
    ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<", ast.RShift: ">>", ast.BitOr: "|",
    ast.BitAnd: "&", ast.BitXor: "^", ast.Invert: "~", ast.Not: "not",
}


# -- which texts use functions (a loop to recast: lyapcheck.models.language.recast) ------------------------------

def written_tree(text: object) -> ast.AST | None:
    """``text``'s tree, or None (the builder says what is wrong with it)."""
    if not isinstance(text, str):
        return None
    try:
        return parse_quietly(text.strip())
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return None


def _function_use(tree: ast.AST | None) -> str | None:
    """The first call (``'sin(...)'``) or ``'pi'`` in a tree, or None."""
    for node in ast.walk(tree) if tree is not None else ():
        if isinstance(node, ast.Call):
            return f"'{node.func.id if isinstance(node.func, ast.Name) else 'a function'}(...)'"
        if isinstance(node, ast.Name) and node.id == "pi":
            return "the constant 'pi'"
    return None


def uses_functions(texts: Sequence[object]) -> bool:
    """Whether any text calls a function or names ``pi`` (a non-polynomial loop)."""
    return any(_function_use(written_tree(text)) is not None for text in texts)


def first_function_use(dynamics: Mapping[str, object]) -> tuple[str, str]:
    """The key (``[dynamics] x1``) and the call (``'sin(...)'``) of the first right-hand side that
    uses a function or ``pi``."""
    for state, text in dynamics.items():
        use = _function_use(written_tree(text))
        if use is not None:
            return f"[dynamics] {state}", use
    return "[dynamics]", "a function"

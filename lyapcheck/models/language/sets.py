"""Sets of states in model files: the ``[sets]`` table (``initial``, ``unsafe``, ``goal``).

A set is written as inequalities over the states (docs/model-files.md, "[sets]")::

    initial = ["(x - 1.5)**2 + y**2 <= 0.25"]                    # one piece: every inequality holds
    unsafe = [["(x + 1)**2 + (y + 1)**2 <= 0.16"],                # a list of pieces: their union
              ["0.4 <= x", "x <= 0.6", "0.1 <= y", "y <= 0.5"]]

Each string is one comparison, ``A <= B`` or ``A >= B``, or a chain ``a <= x <= b`` (two
inequalities). ``<`` and ``>`` are read as ``<=`` and ``>=``: a set is always its closure, the
conservative reading for every use (a certificate that ``B > 0`` on the closed unsafe set, or
``B <= 0`` on the closed initial set, covers the open one). The string is split with
:func:`ast.parse` (a tree, nothing runs) at its top-level comparison, and each side, read back as
the text the user wrote (:func:`ast.get_source_segment`), goes through the expression language
(:func:`lyapcheck.models.language.expressions.parse_expression`): no string reaches an evaluator.

``A <= B`` is stored as the polynomial ``p = B - A`` with ``p >= 0``. A set is polynomial in the
states (no state in a denominator), uses no disturbance, and may use parameters: :data:`SetForms`
keep them as symbols (in the model's ring), and :func:`evaluate_set` substitutes values, giving a
:data:`StateSet` of polynomials in :attr:`Model.state_ring` (the declared, unshifted states, every
disturbance's exponent 0). Every error is one line naming ``[sets] KEY`` (:class:`ModelFileError`).
"""

from __future__ import annotations

import ast
from fractions import Fraction
from typing import TYPE_CHECKING, Final, Mapping, Protocol, Sequence

from lyapcheck.errors import ModelFileError
from lyapcheck.models.language.expressions import (MAX_EXPRESSION_LENGTH, ExpressionError, Rational, parse_expression,
                                          parse_quietly, refuse_deep_nesting)
from lyapcheck.sos.polynomials import MonomialPlan, Poly, Ring, degree_in, monomial_plan, monomial_values

if TYPE_CHECKING:  # pragma: no cover - numpy is imported where a set is evaluated, not to read a model
    import numpy as np

#: the keys of ``[sets]``
SET_KEYS: Final = ("initial", "unsafe", "goal")
#: the one key of ``[sets]`` that is not a set: ``stay_in_goal = true`` (reach_avoid then also proves
#: that the state stays in the goal once there)
STAY_KEY: Final = "stay_in_goal"
#: the sets each class of sets needs (a class given a model without one of them is refused)
CLASS_SETS: Final[dict[str, tuple[str, ...]]] = {"barrier": ("initial", "unsafe"),
                                                 "reach_avoid": ("initial", "unsafe", "goal")}
#: the most pieces of one set (a union), and the most inequalities of one piece
MAX_SET_PIECES: Final = 16
MAX_PIECE_INEQUALITIES: Final = 32

#: one piece: every polynomial ``p >= 0`` (an intersection), in ``Model.state_ring``
SetPiece = tuple[Poly, ...]
#: a set: the union of its pieces
StateSet = tuple[SetPiece, ...]
#: each piece's strings as written (a chain ``a <= x <= b`` is one string and two polynomials)
SetText = tuple[tuple[str, ...], ...]
#: each piece's ``p = B - A`` with the parameters as symbols, in ``Model.ring`` (polynomial in the states)
SetForms = tuple[tuple[Rational, ...], ...]

#: what a set's value may be, for messages
ACCEPTED: Final = ('a list of inequalities (one piece, all hold), e.g. ["x**2 + y**2 <= 1"], or a list of such '
                   'lists (a union of pieces), e.g. [["x <= 0"], ["x >= 1"]]')

class ModelSets(Protocol):
    """What the functions of a whole model read: a :class:`lyapcheck.models.language.modelfile.Model` is one
    (a protocol, so that this module, which the model file parser imports, does not import it)."""

    @property
    def source(self) -> str: ...
    @property
    def parameters(self) -> dict[str, Fraction]: ...
    @property
    def ring(self) -> Ring: ...
    @property
    def state_ring(self) -> Ring: ...
    @property
    def sets(self) -> dict[str, StateSet]: ...
    @property
    def set_text(self) -> dict[str, SetText]: ...
    @property
    def set_forms(self) -> dict[str, SetForms]: ...


_COMPARISONS: Final[dict[type, str]] = {ast.LtE: "<=", ast.GtE: ">=", ast.Lt: "<", ast.Gt: ">"}
_REFUSED: Final[dict[type, str]] = {ast.Eq: "==", ast.NotEq: "!=", ast.In: "in", ast.NotIn: "not in",
                                    ast.Is: "is", ast.IsNot: "is not"}


def split_inequality(text: str) -> tuple[tuple[str, str, str], ...]:
    """``(left, operator, right)`` texts of each comparison of ``text``, as written (a chain
    ``a <= x <= b`` gives two). Only the top level is read; the sides are not checked here.

    Raises
    ------
    ExpressionError
        ``text`` is not one comparison with ``<=``, ``>=``, ``<`` or ``>`` (one line).
    """
    if not isinstance(text, str):
        raise ExpressionError(f"an inequality must be a string, got {type(text).__name__} {text!r}")
    source = text.strip()
    if not source:
        raise ExpressionError("the inequality is empty")
    if len(source) > MAX_EXPRESSION_LENGTH:
        raise ExpressionError(f"the inequality has {len(source)} characters; the limit is {MAX_EXPRESSION_LENGTH} "
                              "(MAX_EXPRESSION_LENGTH)")
    if "\n" in source or "\r" in source or ";" in source:
        raise ExpressionError("an inequality is one line, without ';'")
    refuse_deep_nesting(source)
    try:
        tree = parse_quietly(source)
    except SyntaxError as exc:
        where = f" at character {exc.offset}" if exc.offset else ""
        raise ExpressionError(f"not a valid inequality ({exc.msg}{where})") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError("not a valid inequality (too deeply nested)") from None
    node = tree.body
    if isinstance(node, ast.BoolOp):
        word = "and" if isinstance(node.op, ast.And) else "or"
        raise ExpressionError(f"'{word}' is not part of a set: the strings of one list all hold (an intersection), "
                              "and a list of such lists is their union")
    if not isinstance(node, ast.Compare):
        raise ExpressionError("not an inequality: write 'A <= B', 'A >= B' or 'a <= x <= b'")
    for op in node.ops:
        if type(op) not in _COMPARISONS:
            shown = _REFUSED.get(type(op), type(op).__name__)
            hint = ("; an equality A == B is the two strings 'A <= B' and 'A >= B' of one piece"
                    if isinstance(op, ast.Eq) else "")
            raise ExpressionError(f"'{shown}' is not an inequality: a set is written with <= or >= (< and > are "
                                  f"read as <= and >=){hint}")
    sides = [node.left, *node.comparators]
    texts = [ast.get_source_segment(source, side) or "" for side in sides]
    return tuple((texts[i], _COMPARISONS[type(op)], texts[i + 1]) for i, op in enumerate(node.ops))


def parse_set(source: str, key: str, value: object, ring: Ring, states: Sequence[str],
              disturbances: Sequence[str]) -> tuple[SetText, SetForms]:
    """One ``[sets]`` value: its pieces' strings and their forms ``p >= 0`` in ``ring`` (the model's:
    states, disturbances, parameters), parameters still symbols. ``key`` is ``initial``,
    ``unsafe`` or ``goal``; errors are one-line :class:`ModelFileError` at ``[sets] KEY``."""
    where = f"[sets] {key}"
    pieces = _pieces(source, where, value)
    forms = []
    for piece in pieces:
        piece_forms: list[Rational] = []
        for text in piece:
            try:
                for left, op, right in split_inequality(text):
                    a, b = parse_expression(left, ring), parse_expression(right, ring)
                    if op in (">=", ">"):  # A >= B is B <= A
                        a, b = b, a
                    piece_forms.append(_form(source, where, text, a, b, ring, states, disturbances))
            except ExpressionError as exc:
                raise _error(source, where, f"in {_quoted(text)}: {exc}") from None
        if len(piece_forms) > MAX_PIECE_INEQUALITIES:
            raise _error(source, where, f"a piece has {len(piece_forms)} inequalities; the limit is "
                                        f"{MAX_PIECE_INEQUALITIES} (MAX_PIECE_INEQUALITIES)")
        forms.append(tuple(piece_forms))
    return pieces, tuple(forms)


def evaluate_set(source: str, key: str, forms: SetForms, ring: Ring, parameters: Mapping[str, Fraction],
                 state_ring: Ring) -> StateSet:
    """The set at these parameter values: each ``p`` in ``state_ring`` (one-line error, naming the
    parameters, where a denominator in the parameters alone is 0 at them)."""
    out = []
    for piece in forms:
        polys = []
        for form in piece:
            num = ring.substitute(form.numerator, parameters)
            den = ring.substitute(form.denominator, parameters)
            if den.is_zero():
                used = [p for p in parameters if p in ring.names and degree_in(ring, form.denominator, [p]) > 0]
                at = ", ".join(f"{p} = {parameters[p]}" for p in used)
                raise _error(source, f"[sets] {key}", f"division by zero: a denominator is 0 with {at} "
                                                      "(the parameters' values)")
            polys.append(ring.restrict(num * (1 / den.leading_coefficient()), state_ring))
        out.append(tuple(polys))
    return tuple(out)


def evaluate_sets(model: ModelSets, parameters: Mapping[str, Fraction] | None = None) -> dict[str, StateSet]:
    """Every set of ``model`` at ``parameters`` (default: the model's values)."""
    values = model.parameters if parameters is None else parameters
    return {key: evaluate_set(model.source, key, forms, model.ring, values, model.state_ring)
            for key, forms in model.set_forms.items()}


def require_sets(model: ModelSets, name: str) -> None:
    """Refuse (one line, at ``[sets]``) a class of sets (:data:`CLASS_SETS`) whose sets the model
    does not give."""
    needed = CLASS_SETS.get(name, ())
    missing = [k for k in needed if k not in model.sets]
    if missing:
        given = ", ".join(model.sets) or "none"
        raise _error(model.source, "[sets]", f"the class {name} needs the sets {_and(needed)}; "
                                             f"{_and(missing)} {'is' if len(missing) == 1 else 'are'} missing "
                                             f"(the file gives: {given})")


def contains(state_set: StateSet, point: Sequence[float]) -> bool:
    """Whether ``point`` (one value per state, in the declared order, SI) is in the set, in floating
    point: for falsification and simulation, never a proof."""
    import numpy as np

    return bool(margin(state_set, np.asarray(point, dtype=float).reshape(1, -1))[0] >= 0)


def margin(state_set: StateSet, points: np.ndarray) -> np.ndarray:
    """For each row of ``points`` (``(m, n)``, or one point ``(n,)``), the largest over the pieces
    of the smallest ``p(x)`` over the piece's inequalities: ``>= 0`` exactly in the set (floating
    point); how far inside, or outside, in the units of the polynomials. An empty set: ``-inf``."""
    import numpy as np

    x = np.atleast_2d(np.asarray(points, dtype=float))
    out = np.full(x.shape[0], -np.inf)
    for piece in state_set:
        inner = np.full(x.shape[0], np.inf)
        for p in piece:
            inner = np.minimum(inner, _values(p, x))
        out = np.maximum(out, inner)
    return out


def to_json(texts: SetText) -> list[list[str]]:
    """A set as a certificate records it: each piece's strings, as written (always a union)."""
    return [list(piece) for piece in texts]


def sets_json(model: ModelSets) -> dict[str, list[list[str]]]:
    """Every set of ``model`` as :func:`to_json` writes it, by key."""
    return {key: to_json(texts) for key, texts in model.set_text.items()}


# -- the pieces of a value ---------------------------------------------------------------------------------
def _pieces(source: str, where: str, value: object) -> SetText:
    def refuse(got: str) -> ModelFileError:
        return _error(source, where, f"must be {ACCEPTED}; got {got}")

    if isinstance(value, str):
        raise refuse(f"the string {_quoted(value)} (write it in a list: [{_quoted(value, chr(34))}])")
    if not isinstance(value, list):
        raise refuse(_described(value))
    if not value:
        raise refuse("an empty list")
    if all(isinstance(v, str) for v in value):
        pieces: list[list[object]] = [list(value)]
    elif all(isinstance(v, list) for v in value):
        pieces = list(value)
    else:
        odd = next(v for v in value if not isinstance(v, str))
        if any(isinstance(v, list) for v in value) and any(isinstance(v, str) for v in value):
            raise refuse("strings and lists mixed (a union is a list whose every entry is a list of strings)")
        raise refuse(f"a list holding {_described(odd)}")
    if len(pieces) > MAX_SET_PIECES:
        raise _error(source, where, f"has {len(pieces)} pieces; the limit is {MAX_SET_PIECES} (MAX_SET_PIECES)")
    out = []
    for i, piece in enumerate(pieces, start=1):
        if not piece:
            raise refuse(f"an empty list as piece {i}")
        odd_items = [v for v in piece if not isinstance(v, str)]
        if odd_items:
            raise refuse(f"piece {i} holding {_described(odd_items[0])}")
        out.append(tuple(str(v) for v in piece))
    return tuple(out)


def _form(source: str, where: str, text: str, a: Rational, b: Rational, ring: Ring, states: Sequence[str],
          disturbances: Sequence[str]) -> Rational:
    """``B - A`` of ``A <= B`` (``A >= B`` comes here as ``B <= A``), checked: polynomial in the states, no disturbance, some state."""
    for side in (a, b):
        used = [d for d in disturbances if degree_in(ring, side.numerator, [d]) > 0
                or degree_in(ring, side.denominator, [d]) > 0]
        if used:
            raise _error(source, where, f"in {_quoted(text)}: the disturbance '{used[0]}' may not appear (a set is "
                                        "over the states)")
        if degree_in(ring, side.denominator, states) > 0:
            raise _error(source, where, f"in {_quoted(text)}: a set must be polynomial in the states (no state in "
                                        "a denominator; multiply the inequality out)")
    form = (b - a).normalized()
    if degree_in(ring, form.numerator, states) <= 0:
        raise _error(source, where, f"in {_quoted(text)}: the inequality involves no state (it is true or false "
                                    "everywhere)")
    return form


#: each polynomial's exponents and float coefficients, by id (the polynomial kept, so the id is its
#: own): falsification evaluates the same few polynomials thousands of times
_ARRAYS: dict[int, tuple[Poly, np.ndarray, np.ndarray, dict[int, MonomialPlan]]] = {}


def _plan(p: Poly, n: int) -> MonomialPlan:
    """The :func:`~lyapcheck.sos.polynomials.monomial_plan` of ``p``'s exponents over the first ``n``
    variables (cached with its arrays)."""
    exponents, _ = _arrays(p)
    plans = _ARRAYS[id(p)][3]
    if n not in plans:
        plans[n] = monomial_plan(exponents[:, :n])
    return plans[n]


def _arrays(p: Poly) -> tuple[np.ndarray, np.ndarray]:
    import numpy as np

    hit = _ARRAYS.get(id(p))
    if hit is not None and hit[0] is p:
        return hit[1], hit[2]
    monoms = [tuple(int(e) for e in m) for m in p.monoms()]
    coefficients = np.array([float(Fraction(int(c.p), int(c.q))) for c in p.coeffs()], dtype=float)
    exponents = np.array(monoms, dtype=np.int64).reshape(len(monoms), -1) if monoms else np.zeros((0, 0), np.int64)
    if len(_ARRAYS) > 4096:
        _ARRAYS.clear()
    _ARRAYS[id(p)] = (p, exponents, coefficients, {})
    return exponents, coefficients


def _values(p: Poly, x: np.ndarray) -> np.ndarray:
    """``p`` (a polynomial of a state ring: the states first, then the disturbances at exponent 0)
    at the rows of ``x``."""
    import numpy as np

    n = x.shape[1]
    exponents, coefficients = _arrays(p)
    if not coefficients.size:
        return np.zeros(x.shape[0])
    if exponents.shape[1] < n or exponents[:, n:].any():
        raise ValueError(f"a point has {n} coordinates; the set's polynomial {p} needs the states of its ring")
    plan = _plan(p, n)
    out = np.empty(x.shape[0])
    for start in range(0, x.shape[0], 4096):  # bounded memory: (rows, terms, states) at a time
        rows = x[start:start + 4096]
        out[start:start + 4096] = monomial_values(rows, plan) @ coefficients
    return out


def _quoted(text: str, quote: str = "'") -> str:
    shown = " ".join(text.split())
    shown = shown if len(shown) <= 60 else shown[:60] + "..."
    return f"{quote}{shown}{quote}"


def _described(value: object) -> str:
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    return f"{type(value).__name__} {value!r}"


def _and(names: Sequence[str]) -> str:
    return " and ".join(names) if len(names) <= 2 else ", ".join(names[:-1]) + " and " + names[-1]


def _error(source: str, key: str, message: str) -> ModelFileError:
    """The contract's one-line error (every character printable, as the model file parser's)."""
    def printable(text: str) -> str:
        return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text)

    return ModelFileError(printable(source), printable(key), printable(message))


def forms_name(ring: Ring, set_forms: Mapping[str, SetForms], names: set[str]) -> bool:
    """Some inequality of ``set_forms`` (``[sets]`` as parsed: key -> pieces -> forms over ``ring``)
    names one of ``names`` (a box's parameters: the sets are read at the model's values, so a class
    over the box would prove them at one value only)."""
    for forms in set_forms.values():
        for piece in forms:
            for form in piece:
                for p in (form.numerator, form.denominator):
                    for m in ring.support(p):
                        if any(e and ring.names[k] in names for k, e in enumerate(m)):
                            return True
    return False


__all__ = ["forms_name", "SET_KEYS", "STAY_KEY", "CLASS_SETS", "MAX_SET_PIECES", "MAX_PIECE_INEQUALITIES", "SetPiece", "StateSet", "SetText",
           "SetForms", "split_inequality", "parse_set", "evaluate_set", "evaluate_sets", "require_sets", "contains",
           "margin", "to_json", "sets_json"]


"""Mathematics for the reports: sympy and exact rationals -> Typst math -> SVG, offline.

The route (see ``reports/README.md``): a small sympy printer writes Typst math source, and the
Typst compiler shipped in the ``typst`` wheel (with its own math font, New Computer Modern
Math) typesets every equation of a report in one compile, one equation per page, as SVG. The
same SVGs are embedded in the HTML and, through WeasyPrint, in the PDF, so both show identical
mathematics and neither needs TeX, a browser or the network.

Nothing from an input file reaches Typst source as text: numbers are parsed into
:class:`fractions.Fraction` first, names are split into letters, digits and quoted strings.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Iterable, Sequence

import sympy as sp
from sympy.printing.conventions import split_super_sub
from sympy.printing.precedence import PRECEDENCE, precedence
from sympy.printing.printer import Printer

log = logging.getLogger(__name__)

#: text size of the typeset mathematics, pt (the report's body text is 12 pt on screen)
MATH_SIZE_PT = 12
#: widest equation wanted on an A4 page with the report's margins, pt
MAX_WIDTH_PT = 470.0

#: sympy's Greek names -> Typst symbol names (LaTeX's \epsilon is lunate, \varepsilon is not)
_GREEK = {name: name for name in (
    "alpha", "beta", "chi", "delta", "eta", "gamma", "iota", "kappa", "lambda", "mu", "nu", "omega",
    "omicron", "pi", "psi", "rho", "sigma", "tau", "theta", "upsilon", "xi", "zeta")}
_GREEK.update({name.capitalize(): name.capitalize() for name in list(_GREEK)})
_GREEK.update({"lamda": "lambda", "Lamda": "Lambda", "epsilon": "epsilon.alt", "varepsilon": "epsilon",
               "Epsilon": "Epsilon", "phi": "phi.alt", "varphi": "phi", "Phi": "Phi", "vartheta": "theta.alt",
               "varrho": "rho.alt", "varsigma": "sigma.alt", "varpi": "pi.alt", "varkappa": "kappa.alt"})
#: words of the paper's notation that have a symbol of their own (d_mu^perp, xi_par)
_WORDS = {"perp": "perp", "par": "parallel", "inf": "infinity"}
_ACCENTS = ("hat", "tilde", "bar", "dot", "ddot", "vec", "check", "breve", "overline")
_ACCENTED = re.compile(r"^\\?(" + "|".join(_ACCENTS) + r")\{([^{}]+)\}(.*)$")
_TOKEN = re.compile(r"[A-Za-z]+|\d+|[^A-Za-z\d]+")

#: sympy function name -> Typst operator (all predefined in Typst's math mode)
_FUNCTIONS = {
    "sin": "sin", "cos": "cos", "tan": "tan", "cot": "cot", "sec": "sec", "csc": "csc",
    "sinh": "sinh", "cosh": "cosh", "tanh": "tanh", "asin": "arcsin", "acos": "arccos", "atan": "arctan",
    "exp": "exp", "log": "ln", "Max": "max", "Min": "min", "det": "det",
}


def typst_string(text: str) -> str:
    """A Typst string literal (shown upright in math), safe for any text."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _token(tok: str) -> str:
    """One piece of a symbol name: Greek letter, letter, digits, known word or quoted text."""
    if tok in _GREEK:
        return _GREEK[tok]
    if tok in _WORDS:
        return _WORDS[tok]
    if tok.isdigit() and tok.isascii():
        return tok
    if len(tok) == 1 and tok.isascii() and tok.isalpha():
        return tok
    if tok == "*":
        return "*"
    pieces = _TOKEN.findall(tok)
    if len(pieces) > 1:  # "1mu" -> 1 mu
        return " ".join(_token(p) for p in pieces)
    return typst_string(tok)


def _script(parts: Sequence[str]) -> str:
    return "(" + ", ".join(_token(p) for p in parts) + ")"


def typst_symbol(name: str) -> str:
    """Typst source for a sympy symbol name (``Delta_LOS``, ``d_mu^perp``, ``\\hat{d}_x``, ``|f_d|``)."""
    if len(name) > 2 and name.startswith("|") and name.endswith("|"):
        return f"abs({typst_symbol(name[1:-1])})"
    accented = _ACCENTED.match(name)
    if accented:
        accent, inner, rest = accented.groups()
        base = f"{accent}({typst_symbol(inner)})"
        if not rest:
            return base
        _, sups, subs = split_super_sub("x" + rest)
    else:
        stem, sups, subs = split_super_sub(name)
        if not stem:
            return typst_string(name)
        base = _token(stem)
    out = base
    if subs:
        out += "_" + _script(subs)
    if sups:
        out += "^" + _script(sups)
    return out


def _rational(value: Fraction | sp.Rational) -> str:
    """``-(p)/(q)`` (Typst draws ``(p)/(q)`` as a fraction and drops the grouping parentheses)."""
    p, q = int(value.numerator), int(value.denominator)
    sign = "-" if p < 0 else ""
    if q == 1:
        return f"{sign}{abs(p)}"
    return f"{sign}({abs(p)})/({q})"


def typst_float(value: float, digits: int = 6) -> str:
    """A float in Typst math (``1.5 times 10^(-3)``)."""
    text = f"{value:.{digits}g}"
    if "e" in text:
        mant, exp = text.split("e")
        return f"{mant} times 10^({int(exp)})"
    if text in ("inf", "-inf"):
        return text.replace("inf", "infinity")
    if text == "nan":
        return typst_string("NaN")
    return text


#: spacing of matrix rows and columns (Typst's defaults let stacked fractions touch)
_GAPS = "row-gap: #0.55em, column-gap: #0.8em, "
#: a fraction in a matrix cell is set in display size when its source is at most this long
_DISPLAY_CELL_CHARS = 24


def _cell(text: str) -> str:
    """A matrix cell: short fractions in display size (Typst sets cells in the small inline
    size, hard to read for 1/10); long ones stay compact so that the matrix keeps its width."""
    return f"display({text})" if "/" in text and len(text) <= _DISPLAY_CELL_CHARS else text


class TypstPrinter(Printer):
    """sympy expression -> Typst math source.

    Only what the toolkit's expressions use is printed natively (sums, products, powers,
    rationals, symbols, elementary functions, matrices, relations); anything else falls back to
    its ``sstr`` form as a quoted string, so a new kind of expression degrades, never fails.
    """

    printmethod = "_typst"
    _default_settings: dict[str, Any] = {"order": None}

    def emptyPrinter(self, expr: Any) -> str:  # noqa: N802 (sympy's name)
        return typst_string(sp.sstr(expr))

    def parenthesize(self, expr: Any, level: int, strict: bool = False) -> str:
        text = self._print(expr)
        prec = precedence(expr)
        if prec < level or (strict and prec <= level):
            return f"({text})"
        return text

    # -- atoms ---------------------------------------------------------------------------------
    def _print_Symbol(self, expr: sp.Symbol) -> str:
        return typst_symbol(expr.name)

    def _print_Integer(self, expr: sp.Integer) -> str:
        return str(int(expr))

    def _print_Rational(self, expr: sp.Rational) -> str:
        return _rational(Fraction(int(expr.p), int(expr.q)))

    def _print_Float(self, expr: sp.Float) -> str:
        return typst_float(float(expr))

    def _print_Pi(self, expr: Any) -> str:
        return "pi"

    def _print_Exp1(self, expr: Any) -> str:
        return "e"

    def _print_ImaginaryUnit(self, expr: Any) -> str:
        return "i"

    def _print_Infinity(self, expr: Any) -> str:
        return "infinity"

    def _print_NegativeInfinity(self, expr: Any) -> str:
        return "-infinity"

    def _print_BooleanTrue(self, expr: Any) -> str:
        return typst_string("true")

    def _print_BooleanFalse(self, expr: Any) -> str:
        return typst_string("false")

    # -- operations ----------------------------------------------------------------------------
    def add_terms(self, expr: sp.Expr) -> list[str]:
        """Terms of a sum, each with its sign in front (``["a", "- b", "+ c"]``)."""
        out: list[str] = []
        for i, term in enumerate(self._as_ordered_terms(expr, order=self._settings["order"])):
            text = self._print(term)
            if precedence(term) < PRECEDENCE["Add"]:
                text = f"({text})"
            if text.startswith("-"):
                out.append(text if i == 0 else "- " + text[1:])
            else:
                out.append(text if i == 0 else "+ " + text)
        return out

    def _print_Add(self, expr: sp.Add) -> str:
        return " ".join(self.add_terms(expr))

    def _join_factors(self, factors: list[sp.Expr], alone: bool) -> str:
        if len(factors) == 1 and alone:
            return self._print(factors[0])
        texts: list[str] = []
        for f in factors:
            text = self.parenthesize(f, PRECEDENCE["Mul"], strict=False)
            if texts and text[:1].isdigit() and texts[-1][-1:].isdigit():
                texts.append("dot")  # 2 3 would read as 23
            texts.append(text)
        return " ".join(texts)

    def _print_Mul(self, expr: sp.Mul) -> str:
        coeff, rest = expr.as_coeff_Mul()
        sign = ""
        if coeff.is_number and coeff < 0:
            expr = sp.Mul(-coeff, rest, evaluate=False) if coeff != -1 else rest
            sign = "-"
        num: list[sp.Expr] = []
        den: list[sp.Expr] = []
        factors = expr.as_ordered_factors() if isinstance(expr, sp.Mul) else [expr]
        for item in factors:
            if item.is_commutative and item.is_Pow and item.exp.is_Rational and item.exp.is_negative:
                den.append(item.base if item.exp == -1 else sp.Pow(item.base, -item.exp, evaluate=False))
            elif item.is_Rational and not item.is_Integer:
                if item.p != 1:
                    num.append(sp.Integer(item.p))
                den.append(sp.Integer(item.q))
            else:
                num.append(item)
        if not num:
            num = [sp.Integer(1)]
        top = self._join_factors(num, alone=bool(den))
        if not den:
            return sign + top
        bottom = self._join_factors(den, alone=True)
        return f"{sign}({top})/({bottom})"

    def _print_Pow(self, expr: sp.Pow) -> str:
        base, exp = expr.base, expr.exp
        if exp is sp.S.Half:
            return f"sqrt({self._print(base)})"
        if exp.is_Rational and exp.is_negative:
            inverse = base if exp == -1 else sp.Pow(base, -exp, evaluate=False)
            return f"(1)/({self._print(inverse)})"
        if exp.is_Rational and exp.p == 1 and exp.q > 2:
            return f"root({exp.q}, {self._print(base)})"
        text = self._print(base)
        needs = precedence(base) < PRECEDENCE["Pow"] or (base.is_Rational and not base.is_Integer) or \
            (base.is_number and base.is_negative) or (base.is_Symbol and "^" in text) or base.is_Pow
        if needs:
            text = f"({text})"
        return f"{text}^({self._print(exp)})"

    def _print_Function(self, expr: Any) -> str:
        name = type(expr).__name__
        args = ", ".join(self._print(a) for a in expr.args)
        if name in _FUNCTIONS:
            return f"{_FUNCTIONS[name]}({args})"
        return f"op({typst_string(name)})({args})"

    def _print_Abs(self, expr: sp.Abs) -> str:
        return f"abs({self._print(expr.args[0])})"

    def _print_sign(self, expr: Any) -> str:
        return f"op({typst_string('sgn')})({self._print(expr.args[0])})"

    def _print_Relational(self, expr: Any) -> str:
        ops = {"==": "=", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
        rel = ops.get(expr.rel_op, typst_string(expr.rel_op))
        return f"{self._print(expr.lhs)} {rel} {self._print(expr.rhs)}"

    def _print_MatrixBase(self, expr: sp.MatrixBase) -> str:
        rows = [", ".join(_cell(self._print(expr[i, j])) for j in range(expr.cols)) for i in range(expr.rows)]
        if not rows or expr.cols == 0:
            return "[]"
        return f'mat(delim: "[", {_GAPS}' + "; ".join(rows) + ")"

    _print_ImmutableDenseMatrix = _print_MatrixBase
    _print_MutableDenseMatrix = _print_MatrixBase
    _print_ImmutableMatrix = _print_MatrixBase

    def _print_tuple(self, expr: tuple[Any, ...]) -> str:
        return "(" + ", ".join(self._print(a) for a in expr) + ")"

    _print_Tuple = _print_tuple
    _print_list = _print_tuple


_PRINTER = TypstPrinter()


def typst_math(expr: object) -> str:
    """Typst math source of a sympy object (one line)."""
    return _PRINTER.doprint(expr)


def _break_sum(terms: list[str], lead: str, budget: int) -> str:
    """Lines of at most ``budget`` source characters, aligned after ``lead`` (Typst ``&``, ``\\``).

    A continuation line starts with ``""`` so that its ``+``/``-`` keeps binary spacing.
    """
    lines: list[str] = []
    current = ""
    for term in terms:
        if current and len(current) + len(term) > budget:
            lines.append(current)
            current = ""
        current = f"{current} {term}".strip()
    lines.append(current)
    first = f"{lead} & {lines[0]}"
    return " \\\n".join([first] + [f'& quad "" {line}' for line in lines[1:]])


def _terms(expr: sp.Expr) -> list[str]:
    return _PRINTER.add_terms(expr) if isinstance(expr, sp.Add) else [_PRINTER.doprint(expr)]


def typst_broken(expr: object, budget: int) -> str | None:
    """The equation broken over lines of about ``budget`` source characters, or None if it cannot be.

    A sum is split between terms; a product with one long sum keeps its other factors in front
    of a bracket that spans the lines; a matrix is shown entry by entry (``(i, j) :``), since a
    matrix cell cannot break.
    """
    if isinstance(expr, sp.MatrixBase):
        blocks = []
        for i in range(expr.rows):
            for j in range(expr.cols):
                where = f"({i + 1})" if expr.cols == 1 else f"({i + 1}, {j + 1})"
                blocks.append(_break_sum(_terms(expr[i, j]), f"{typst_string(where)} :", budget))
        return " \\\n".join(blocks)
    if isinstance(expr, sp.Add):
        return _break_sum(_PRINTER.add_terms(expr), "", budget)
    if isinstance(expr, sp.Mul):
        sums = [f for f in expr.args if isinstance(f, sp.Add)]
        if len(sums) == 1:
            rest = sp.Mul(*[f for f in expr.args if f is not sums[0]], evaluate=False)
            front = _PRINTER.doprint(rest) if rest != 1 else ""
            if front == "-1":
                front = "-"
            body = _break_sum(_PRINTER.add_terms(sums[0]), f"{front} [", budget)
            return body + " ]"
    return None


# -- exact rational data from certificate documents --------------------------------------------------
def parse_fraction(text: object) -> Fraction | None:
    """A rational from a certificate entry (``"p/q"``, an integer or a float), else None."""
    if isinstance(text, bool):
        return None
    if isinstance(text, (int, Fraction)):
        return Fraction(text)
    if isinstance(text, float):
        return Fraction(text) if text == text and abs(text) != float("inf") else None
    if not isinstance(text, str) or len(text) > 400:
        return None
    try:
        return Fraction(text.strip())
    except (ValueError, ZeroDivisionError):
        return None


def parse_matrix(value: object) -> list[list[Fraction]] | None:
    """A rectangular matrix of rationals (list of rows of ``"p/q"`` strings), else None."""
    if not isinstance(value, list) or not value or not all(isinstance(r, list) and r for r in value):
        return None
    width = len(value[0])
    if any(len(r) != width for r in value) or len(value) > 12 or width > 12:
        return None
    rows = [[parse_fraction(x) for x in r] for r in value]
    if any(x is None for r in rows for x in r):
        return None
    return rows  # type: ignore[return-value]


def typst_rational_matrix(rows: Sequence[Sequence[Fraction]]) -> str:
    """``mat(delim: "[", ...)`` with exact fractions."""
    return f'mat(delim: "[", {_GAPS}' + "; ".join(", ".join(_cell(_rational(x)) for x in r) for r in rows) + ")"


def typst_rational(value: Fraction) -> str:
    return _rational(value)


# -- compilation ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Typeset:
    """One typeset equation: standalone SVG and its size in pt."""

    svg: bytes
    width_pt: float
    height_pt: float


_SIZE = re.compile(rb'width="([\d.]+)pt" height="([\d.]+)pt"')
_CACHE: dict[str, Typeset | None] = {}

_PREAMBLE = (
    "#set page(width: auto, height: auto, margin: (x: 1.5pt, y: 2.5pt), fill: none)\n"
    f"#set text(size: {MATH_SIZE_PT}pt)\n"
)


def _compile(sources: Sequence[str]) -> list[bytes]:
    import typst

    body = "\n#pagebreak()\n".join(f"$ {s} $" for s in sources)
    pages = typst.compile((_PREAMBLE + body).encode(), format="svg", ignore_system_fonts=True)
    return list(pages) if isinstance(pages, list) else [pages]


def _typeset(svg: bytes) -> Typeset:
    found = _SIZE.search(svg[:400])
    width, height = (float(found.group(1)), float(found.group(2))) if found else (0.0, 0.0)
    return Typeset(svg, width, height)


def render(sources: Iterable[str]) -> dict[str, Typeset | None]:
    """Typeset many equations at once (one Typst compile); None for a source Typst rejects.

    Results are cached for the process, so the HTML and the PDF of one report, or several
    reports in one run, typeset each equation once.
    """
    import typst

    sources = list(sources)
    wanted = [s for s in dict.fromkeys(sources) if s not in _CACHE]
    if wanted:
        try:
            pages = _compile(wanted)
        except typst.TypstError:
            pages = []
        if len(pages) == len(wanted):
            _CACHE.update({s: _typeset(p) for s, p in zip(wanted, pages)})
        else:
            # one bad equation fails the whole document: find it by compiling one at a time
            for s in wanted:
                try:
                    _CACHE[s] = _typeset(_compile([s])[0])
                except typst.TypstError as exc:
                    log.warning("Typst could not typeset %r: %s", s[:80], exc)
                    _CACHE[s] = None
    return {s: _CACHE[s] for s in sources}


@dataclass
class Equation:
    """An equation of a report: its Typst source, a plain-text alternative, and once typeset, the SVG."""

    source: str
    alt: str
    expr: object = None
    result: Typeset | None = None


class Equations:
    """Collects a report's equations, then typesets them all in two Typst compiles.

    The first compile sets each equation on one line; the ones wider than :data:`MAX_WIDTH_PT`
    are broken (:func:`typst_broken`) with a line length scaled from the measured width and
    compiled again.
    """

    def __init__(self) -> None:
        self.items: list[Equation] = []

    def sympy(self, expr: object, alt: str | None = None) -> Equation:
        """An equation from a sympy object (alt text: its ``sstr`` form)."""
        try:
            source = typst_math(expr)
        except Exception:  # noqa: BLE001 - a printer gap must not stop a report; shown as text
            log.warning("no Typst form for %r", expr, exc_info=True)
            source = typst_string(sp.sstr(expr))
        eq = Equation(source, alt if alt is not None else sp.sstr(expr), expr)
        self.items.append(eq)
        return eq

    def typst(self, source: str, alt: str) -> Equation:
        """An equation from Typst source built by this package (never from input text)."""
        eq = Equation(source, alt)
        self.items.append(eq)
        return eq

    def typeset(self) -> None:
        done = render(eq.source for eq in self.items)
        retry: dict[int, str] = {}
        for k, eq in enumerate(self.items):
            eq.result = done[eq.source]
            if eq.result is not None and eq.result.width_pt > MAX_WIDTH_PT and eq.expr is not None:
                budget = max(40, int(len(eq.source) * MAX_WIDTH_PT / eq.result.width_pt * 0.85))
                broken = typst_broken(eq.expr, budget)
                if broken is not None:
                    retry[k] = broken
        if retry:
            again = render(retry.values())
            for k, source in retry.items():
                if again[source] is not None:
                    self.items[k].source = source
                    self.items[k].result = again[source]


def versions() -> dict[str, str]:
    """Versions of the typesetting stack, for the reproducibility block."""
    from importlib import metadata

    out = {}
    for name in ("typst", "weasyprint", "matplotlib", "jinja2"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:  # pragma: no cover
            out[name] = "absent"
    return out

"""Exact polynomials of model certificates, for reading and for drawing.

A model certificate stores each Lyapunov or storage function as exact terms,
``{"terms": [["p/q", [e_1, ..., e_n]], ...]}``, in the declared states shifted so that the
equilibrium is 0 (DESIGN.md, "Model files (contract)"). This module turns those terms into

- a plain-text polynomial in the model-file expression language (``3/2*x1**2 - x1*x2``), exact,
  so that a reader can paste it back as ``lyapcheck certify --model FILE --candidate "..."``;
- Typst math source, exact, broken over aligned lines, truncated past :data:`MAX_TYPESET_TERMS`
  terms (the full polynomial stays in the plain text and in the certificate file);
- a float evaluator on a batch of points, with every coefficient converted from its exact value
  once (in the certificate's scaled coordinates, where the coefficients are of moderate size).

Nothing here evaluates text: coefficients are parsed by :class:`fractions.Fraction`, names come
from the validated model and reach Typst through :func:`reports.typeset.typst_symbol`.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final, Sequence

import numpy as np
import numpy.typing as npt

from reports.typeset import typst_rational, typst_symbol

FloatArray = npt.NDArray[np.float64]

#: the most terms typeset in a report (a degree-8 V in 2 states has 24; in 4 states, 165): past
#: this the equation shows the lowest-degree terms and says how many more the certificate holds
MAX_TYPESET_TERMS: Final = 40
#: the longest exact plain-text polynomial printed on the page, characters (the certificate file
#: keeps every term; a page of 100 kB of digits helps no reader)
MAX_PLAIN_CHARS: Final = 12_000
#: the widest line of a typeset polynomial, in "digit widths" (a digit of a fraction's numerator
#: is about 5 pt wide in the 12 pt math font, and the report's column holds about 470 pt): an
#: estimate that keeps lines within the column; a line still too wide scrolls in HTML and is
#: scaled down in the PDF
LINE_BUDGET: Final = 84
#: the most terms a polynomial may have to be read at all (a malformed or hostile file)
MAX_TERMS: Final = 20_000
#: the largest exponent accepted (the model language caps degrees far below this)
MAX_EXPONENT: Final = 64


@dataclass(frozen=True)
class ExactPolynomial:
    """A polynomial as exact ``(coefficient, exponents)`` terms, one exponent per variable.

    Terms are kept in reading order: by total degree, then with the first variable's power
    highest (``x1**2, x1*x2, x2**2``).
    """

    terms: tuple[tuple[Fraction, tuple[int, ...]], ...]
    nvars: int

    @classmethod
    def from_json(cls, data: Any, nvars: int) -> "ExactPolynomial":
        """Read ``{"terms": [["p/q", [e...]], ...]}``; exponents past ``nvars`` must be 0.

        A storage function of ``sos_bound`` lives in the ring of the states and the disturbances,
        so its exponent lists are longer than the state vector; its disturbance powers are 0
        (``V`` is a function of the state), and any that is not makes the data unreadable here.

        Raises
        ------
        ValueError
            When the data is not such a polynomial (named in the message).
        """
        if not isinstance(data, dict) or not isinstance(data.get("terms"), list):
            raise ValueError("a polynomial must be {'terms': [[coefficient, exponents], ...]}")
        raw = data["terms"]
        if len(raw) > MAX_TERMS:
            raise ValueError(f"a polynomial has {len(raw)} terms; the limit is {MAX_TERMS}")
        merged: dict[tuple[int, ...], Fraction] = {}
        for term in raw:
            if not isinstance(term, list) or len(term) != 2 or not isinstance(term[1], list):
                raise ValueError(f"a term must be [coefficient, exponents], got {str(term)[:80]}")
            coefficient = _fraction(term[0])
            exponents = term[1]
            if len(exponents) < nvars or not all(isinstance(e, int) and not isinstance(e, bool)
                                                 and 0 <= e <= MAX_EXPONENT for e in exponents):
                raise ValueError(f"a term needs {nvars} exponents in 0..{MAX_EXPONENT}, got {str(exponents)[:80]}")
            if any(exponents[nvars:]):
                raise ValueError("a term depends on a variable other than the states")
            key = tuple(exponents[:nvars])
            merged[key] = merged.get(key, Fraction(0)) + coefficient
        ordered = sorted(((c, m) for m, c in merged.items() if c != 0), key=lambda t: _order(t[1]))
        return cls(tuple(ordered), nvars)

    @property
    def degree(self) -> int:
        return max((sum(m) for _, m in self.terms), default=0)

    def scaled(self, scales: Sequence[Fraction]) -> "ExactPolynomial":
        """``p(S u)`` as a polynomial in ``u`` (``S = diag(scales)``), exactly."""
        out = []
        for c, m in self.terms:
            factor = Fraction(1)
            for s, e in zip(scales, m):
                factor *= s ** e
            out.append((c * factor, m))
        return ExactPolynomial(tuple(out), self.nvars)

    def evaluator(self) -> "FloatPolynomial":
        """The polynomial in floating point (each coefficient the float nearest its exact value)."""
        exps = np.array([m for _, m in self.terms], dtype=np.int64).reshape(-1, self.nvars)
        coefs = np.array([float(c) for c, _ in self.terms], dtype=np.float64)
        return FloatPolynomial(exps, coefs)

    # -- reading -----------------------------------------------------------------------------------
    def plain_text(self, names: Sequence[str], shifts: Sequence[Fraction]) -> str:
        """The polynomial in the model-file language, exact; ``x_i - shift_i`` where a shift is not 0."""
        if not self.terms:
            return "0"
        pieces = []
        for k, (c, m) in enumerate(self.terms):
            sign = "-" if c < 0 else "+"
            magnitude = abs(c)
            factors = [_plain_power(names[i], shifts[i], e) for i, e in enumerate(m) if e]
            if not factors:
                body = _plain_rational(magnitude)
            elif magnitude == 1:
                body = "*".join(factors)
            else:
                body = "*".join([_plain_rational(magnitude)] + factors)
            pieces.append((("-" if sign == "-" else "") if k == 0 else f" {sign} ") + body)
        return "".join(pieces)

    def typst(self, names: Sequence[str], shifts: Sequence[Fraction], lead: str,
              max_terms: int = MAX_TYPESET_TERMS) -> tuple[str, int]:
        """Typst math source ``lead = ...`` broken over aligned lines; (source, terms shown).

        ``lead`` is Typst source written by this package (e.g. ``V(x)``), never input text.
        Past ``max_terms`` terms the sum ends in ``+ dots.c`` and the caller says how many more.
        """
        shown = self.terms[:max_terms]
        symbols = [_typst_variable(names[i], shifts[i]) for i in range(self.nvars)]
        # a variable's width in digit widths: a letter and its subscript, or a whole (x - c)
        widths = [3 if shifts[i] == 0 else 4 + _digits(abs(shifts[i])) for i in range(self.nvars)]
        lines: list[list[str]] = [[]]
        width = 0
        for k, (c, m) in enumerate(shown):
            source, cost = _typst_term(c, m, symbols, widths, first=k == 0)
            if lines[-1] and width + cost > LINE_BUDGET:
                lines.append([])
                width = 0
            lines[-1].append(source)
            width += cost
        if not shown:
            lines[-1].append("0")
        if len(self.terms) > len(shown):
            lines[-1].append("+ dots.c")
        rows = [" ".join(line) for line in lines]
        # a continuation line starts with "" so that its leading + or - keeps binary spacing
        body = f"{lead} & = {rows[0]}" + "".join(f' \\\n& quad "" {row}' for row in rows[1:])
        return body, len(shown)


@dataclass(frozen=True)
class FloatPolynomial:
    """Exponents ``(terms, n)`` and float coefficients ``(terms,)``: evaluated at ``(..., n)`` points."""

    exponents: npt.NDArray[np.int64]
    coefficients: FloatArray

    def __call__(self, points: FloatArray) -> FloatArray:
        points = np.asarray(points, dtype=np.float64)
        out = np.zeros(points.shape[:-1])
        if not self.coefficients.size:
            return out
        top = int(self.exponents.max())
        # powers[e][..., i] = points[..., i] ** e, built by repeated products (exact for small e)
        powers = [np.ones_like(points)]
        for _ in range(top):
            powers.append(powers[-1] * points)
        for e, c in zip(self.exponents, self.coefficients):
            term = np.full(out.shape, c)
            for i, k in enumerate(e):
                if k:
                    term = term * powers[int(k)][..., i]
            out += term
        return out


def _fraction(value: object) -> Fraction:
    if isinstance(value, bool) or not isinstance(value, (str, int)):
        raise ValueError(f"a coefficient must be 'p/q' text or an integer, got {str(value)[:80]}")
    text = str(value)
    if len(text) > 4000:
        raise ValueError("a coefficient has more than 4000 characters")
    try:
        return Fraction(text)
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"a coefficient is not a rational: {text[:80]}") from None


def _order(m: tuple[int, ...]) -> tuple[int, tuple[int, ...]]:
    return sum(m), tuple(-e for e in m)


def _plain_rational(x: Fraction) -> str:
    return str(x.numerator) if x.denominator == 1 else f"{x.numerator}/{x.denominator}"


def _plain_power(name: str, shift: Fraction, e: int) -> str:
    base = name if shift == 0 else f"({name} {'-' if shift > 0 else '+'} {_plain_rational(abs(shift))})"
    return base if e == 1 else f"{base}**{e}"


def _typst_variable(name: str, shift: Fraction) -> str:
    symbol = typst_symbol(name)
    if shift == 0:
        return symbol
    return f"({symbol} {'-' if shift > 0 else '+'} {typst_rational(abs(shift))})"


def _digits(x: Fraction) -> int:
    """Width of an exact coefficient set as a fraction, in digit widths."""
    return max(len(str(x.numerator)), len(str(x.denominator))) + (1 if x.denominator != 1 else 0)


def _typst_term(c: Fraction, m: tuple[int, ...], symbols: Sequence[str], widths: Sequence[int],
                first: bool) -> tuple[str, int]:
    """One term's Typst source and its estimated width (digit widths)."""
    sign = "-" if c < 0 else "+"
    magnitude = abs(c)
    factors = []
    cost = 2
    for symbol, width, e in zip(symbols, widths, m):
        if e:
            factors.append(symbol if e == 1 else f"{symbol}^({e})")
            cost += width
    coefficient = "" if magnitude == 1 and factors else typst_rational(magnitude)
    if coefficient:
        cost += _digits(magnitude)
    body = " ".join(([coefficient] if coefficient else []) + factors)
    if first:
        return (f"-{body}" if sign == "-" else body), cost
    return f"{sign} {body}", cost

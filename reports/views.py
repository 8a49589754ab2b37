"""Generic views of certificate data: any JSON value becomes rows, exact matrices or groups.

A condition class the report does not know (``sos_gas``, ``saturated_loop``, ...) is shown
the same way as the known ones: its status, summary, scalar numbers, every rational matrix
typeset with its eigenvalues, and nested tables as sub-groups. Nothing here raises on an
unexpected key or type: what cannot be interpreted is shown as (escaped) text.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from reports.typeset import Equation, Equations, parse_fraction, parse_matrix, typst_float, typst_rational_matrix

#: a matrix is typeset exactly when its longest entry ("p/q") has at most this many characters,
#: and, beyond 3 columns, at most the second number: otherwise in decimals (the exact rationals
#: stay in the certificate file, where ``lyapcheck verify`` checks them)
EXACT_ENTRY_CHARS = 40
EXACT_ENTRY_CHARS_WIDE = 12
#: an exact scalar longer than this is not printed in full (same reason)
EXACT_SCALAR_CHARS = 80
#: nesting deeper than this is shown as JSON text
MAX_DEPTH = 6
#: significant digits of decimal approximations
DIGITS = 6


def as_dict(value: object) -> dict[str, Any]:
    """``value`` if it is a mapping, else an empty one: a malformed section of a document shows as empty."""
    return value if isinstance(value, dict) else {}


def as_fraction(value: object) -> Fraction | None:
    """An exact number stored as a string or an integer, or None for anything else (a bool, a float, a
    text that is not a fraction, or one longer than 4000 characters)."""
    if isinstance(value, bool) or not isinstance(value, (str, int)) or len(str(value)) > 4000:
        return None
    try:
        return Fraction(str(value))
    except (ValueError, ZeroDivisionError):
        return None


def as_number(value: object) -> float | None:
    """A finite JSON number as a float, or None (a bool is not a number here, nor an integer beyond
    the double range, which a hand-edited file may hold)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def fmt_float(x: float, digits: int = DIGITS) -> str:
    """A float for reading: ``digits`` significant digits, ``inf``/``NaN`` spelled out."""
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:.{digits}g}"


def fmt_fraction(x: Fraction) -> str:
    return fmt_float(float(x)) if x.denominator != 1 or abs(x.numerator) >= 10**12 else str(x.numerator)


@dataclass
class Item:
    """One entry of a view.

    ``kind`` is ``"scalar"`` (``text``, maybe ``exact``), ``"matrix"`` (``eq``, ``note``), ``"group"`` (``children``) or ``"text"`` (a long string, shown as a paragraph).
    """

    kind: str
    key: str
    text: str = ""
    exact: str = ""
    eq: Equation | None = None
    note: str = ""
    children: list["Item"] = field(default_factory=list)


def _is_scalar(value: object) -> bool:
    return value is None or isinstance(value, (bool, int, float, str))


def scalar_text(value: object) -> tuple[str, str]:
    """(display text, exact text) of a scalar JSON value."""
    if value is None:
        return "—", ""
    if isinstance(value, bool):
        return ("yes" if value else "no"), ""
    if isinstance(value, int):
        return str(value), ""
    if isinstance(value, float):
        return fmt_float(value), ""
    text = str(value)
    if "/" in text:
        frac = parse_fraction(text)
        if frac is not None:
            if len(text) > EXACT_SCALAR_CHARS:
                return f"≈ {fmt_float(float(frac))} (exact: a {len(text)}-character rational, in the certificate)", ""
            return f"≈ {fmt_float(float(frac))}", text
    return text, ""


def matrix_item(key: str, rows: list[list[Fraction]], eqs: Equations, raw: object) -> Item:
    """A rational matrix: typeset exactly (or in decimals when entries are very long) + eigenvalues."""
    values = np.array([[float(x) for x in r] for r in rows])
    alt = json.dumps(raw)
    longest = max(len(str(x)) for r in rows for x in r)
    exact = longest <= (EXACT_ENTRY_CHARS if len(rows[0]) <= 3 else EXACT_ENTRY_CHARS_WIDE)
    if exact:
        eq = eqs.typst(typst_rational_matrix(rows), alt if len(alt) <= 4000 else alt[:4000] + " ...")
    else:
        cells = "; ".join(", ".join(_float_cell(v) for v in r) for r in values)
        eq = eqs.typst(f'mat(delim: "[", row-gap: #0.55em, column-gap: #0.8em, {cells})',
                       json.dumps([[float(fmt_float(v)) for v in r] for r in values]))
    note = "" if exact else f"decimals shown; the exact rational entries (up to {longest} characters) are in the certificate. "
    if values.shape[0] == values.shape[1] and np.all(np.isfinite(values)):
        symmetric = all(rows[i][j] == rows[j][i] for i in range(len(rows)) for j in range(len(rows)))
        eig = np.linalg.eigvalsh(values) if symmetric else np.linalg.eigvals(values)
        note += "eigenvalues " + ", ".join(_complex_text(z) for z in eig)
        if symmetric:
            note += " (symmetric" + (", positive definite)" if np.all(eig > 0) else ")")
    return Item("matrix", key, eq=eq, note=note)


def _float_cell(v: float) -> str:
    return typst_float(v, DIGITS)


def _complex_text(z: complex | float) -> str:
    z = complex(z)
    if abs(z.imag) <= 1e-12 * max(1.0, abs(z.real)):
        return fmt_float(z.real)
    return f"{fmt_float(z.real)} {'+' if z.imag >= 0 else '-'} {fmt_float(abs(z.imag))} i"


def value_items(key: str, value: object, eqs: Equations, depth: int = 0) -> list[Item]:
    """Items for one (key, value) pair of a certificate (recursive, never raises)."""
    if depth > MAX_DEPTH:
        return [Item("text", key, text=json.dumps(value, default=str)[:2000])]
    if _is_scalar(value):
        text, exact = scalar_text(value)
        kind = "text" if isinstance(value, str) and len(value) > 80 and not exact else "scalar"
        return [Item(kind, key, text=text, exact=exact)]
    if isinstance(value, list):
        rows = parse_matrix(value)
        if rows is not None:
            return [matrix_item(key, rows, eqs, value)]
        if all(_is_scalar(v) for v in value):
            parts = [scalar_text(v) for v in value]
            exact = ", ".join(e or t for t, e in parts) if any(e for _, e in parts) else ""
            approx = any(t.startswith("≈ ") for t, _ in parts)
            text = ("≈ " if approx else "") + "[" + ", ".join(t.removeprefix("≈ ") for t, _ in parts) + "]"
            if len(exact) > EXACT_SCALAR_CHARS * 2:
                text, exact = text + " (exact rationals in the certificate)", ""
            return [Item("scalar", key, text=text, exact=f"[{exact}]" if exact else "")]
        children: list[Item] = []
        for i, v in enumerate(value):
            sub = f"{key} [{i + 1}]"
            if isinstance(v, dict):
                children.append(Item("group", sub, children=dict_items(v, eqs, depth + 1)))
            else:
                children.extend(value_items(sub, v, eqs, depth + 1))
        return [Item("group", key, children=children)]
    if isinstance(value, dict):
        return [Item("group", key, children=dict_items(value, eqs, depth + 1))]
    return [Item("text", key, text=str(value)[:2000])]


def dict_items(data: dict[str, Any], eqs: Equations, depth: int = 0) -> list[Item]:
    """Items of a mapping: scalars first (one table), then matrices, then sub-groups."""
    items: list[Item] = []
    for k, v in data.items():
        items.extend(value_items(str(k), v, eqs, depth))
    rank = {"scalar": 0, "text": 1, "matrix": 2, "group": 3}
    return sorted(items, key=lambda it: rank.get(it.kind, 4))

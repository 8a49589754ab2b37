"""The claims ledger: each checkable equation of the paper, as printed and as derived.

A :class:`Claim` holds the printed and the derived form of one equation (sympy expressions,
matrices or equalities written as ``lhs - rhs``). :func:`compare` decides its status:

* ``holds``: ``simplify(printed - derived)`` is zero, and exact spot checks at random
  rational points agree;
* ``discrepancy``: a spot check at some admissible point gives a non-zero difference
  (evaluated exactly, or with 50 digits when transcendental functions appear), so the two
  forms are different functions;
* ``unverifiable``: neither could be established (or the claim needs information the paper
  does not give, such as a figure).

Claims that are not identities (an implication, an eigenvalue fact) carry their own
``check`` callable returning a :class:`Verdict`; they are held to the same statuses.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Callable, Literal, Mapping, Sequence

import sympy as sp

Status = Literal["holds", "discrepancy", "unverifiable"]

#: spot checks: evaluations with transcendental parts use this many digits, and a difference
#: counts as non-zero above this fraction of the printed value's magnitude
SPOT_CHECK_DIGITS = 50
SPOT_CHECK_REL_TOL = sp.Float("1e-30", SPOT_CHECK_DIGITS)

#: default sampler: positive rationals with small numerators/denominators
SymbolSampler = Callable[[random.Random], sp.Rational]


def positive_rational(rng: random.Random) -> sp.Rational:
    return sp.Rational(rng.randint(1, 97), rng.randint(1, 41))


def real_rational(rng: random.Random) -> sp.Rational:
    return sp.Rational(rng.randint(-97, 97), rng.randint(1, 41))


@dataclass(frozen=True)
class Verdict:
    status: Status
    derived: str
    explanation: str
    printed: str | None = None


@dataclass(frozen=True)
class Claim:
    """One checkable statement of the paper.

    Parameters
    ----------
    label
        The paper's LaTeX label, exactly as in the source (``"eq:los3"``).
    title
        Short human name.
    printed, derived
        The two forms. Comparable objects: expressions or matrices of the same shape.
    holds_text, discrepancy_text
        One-sentence explanations for each outcome.
    check
        Custom decision for claims that are not identities; overrides the comparison.
    samplers
        Per-symbol samplers for spot checks (default: positive rationals for positive
        symbols, signed rationals otherwise).
    """

    label: str
    title: str
    printed: object = None
    derived: object = None
    holds_text: str = ""
    discrepancy_text: str = ""
    check: Callable[[], Verdict] | None = None
    samplers: Mapping[sp.Symbol, SymbolSampler] = field(default_factory=dict)


@dataclass(frozen=True)
class LedgerEntry:
    label: str
    title: str
    status: Status
    printed: str
    derived: str
    explanation: str

    def to_json(self) -> dict[str, str]:
        return {
            "label": self.label, "title": self.title, "status": self.status,
            "printed": self.printed, "derived": self.derived, "explanation": self.explanation,
        }


def _as_matrix(obj: object) -> sp.Matrix:
    if isinstance(obj, str):  # a claim is built in code; text would be evaluated by sympify
        raise TypeError("a claim's expression must be a sympy object, not text")
    if isinstance(obj, sp.MatrixBase):
        return sp.Matrix(obj)
    if isinstance(obj, sp.Equality):
        return sp.Matrix([obj.lhs - obj.rhs])
    return sp.Matrix([sp.sympify(obj)])


def _render(obj: object) -> str:
    if isinstance(obj, sp.MatrixBase):
        return sp.sstr(sp.Matrix(obj).tolist())
    return sp.sstr(obj)


def _spot_value(expr: sp.Expr, point: Mapping[sp.Symbol, sp.Expr]) -> sp.Expr | None:
    """Exact value where possible, 50-digit float otherwise; None if undefined."""
    try:
        value = sp.nsimplify(expr.xreplace(point)) if expr.has(sp.Float) else expr.xreplace(point)
        if value.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
            return None
        if value.is_Rational:
            return value
        return sp.N(value, SPOT_CHECK_DIGITS)
    except (ZeroDivisionError, TypeError, ValueError):
        return None


def _numeric_nonzero(value: sp.Expr, scale: sp.Expr) -> bool:
    if value.is_Rational:
        return value != 0
    return bool(abs(value) > SPOT_CHECK_REL_TOL * max(abs(sp.N(scale, SPOT_CHECK_DIGITS)), 1))


def _is_zero(expr: sp.Expr) -> bool:
    """Cheap simplifications first; full ``simplify`` only as the last resort."""
    for step in (sp.expand, sp.cancel, lambda e: sp.trigsimp(sp.expand_trig(e)), sp.simplify):
        expr = step(expr)
        if expr == 0:
            return True
    return False


def _spot_checks_find_nonzero(
    diff: sp.Matrix, printed: sp.Matrix, samplers: Mapping[sp.Symbol, SymbolSampler], seed: int, points: int
) -> bool:
    """True if the difference is non-zero at some admissible random rational point."""
    rng = random.Random(seed)
    free = sorted(diff.free_symbols | printed.free_symbols, key=lambda sym: sym.name)
    evaluated = 0
    for _ in range(points * 4):
        if evaluated >= points:
            break
        point = {}
        for sym in free:
            sampler = samplers.get(sym)
            if sampler is None:
                sampler = positive_rational if sym.is_positive else real_rational
            point[sym] = sampler(rng)
        values = []
        for d_entry, p_entry in zip(diff, printed):
            v = _spot_value(d_entry, point)
            if v is None:
                break
            scale = _spot_value(p_entry, point)
            values.append((v, scale if scale is not None else sp.Integer(1)))
        else:
            evaluated += 1
            if any(_numeric_nonzero(v, sc) for v, sc in values):
                return True
    return False


def compare(claim: Claim, *, seed: int = 20261121, points: int = 5) -> LedgerEntry:
    """Decide the status of one claim (see module docstring)."""
    if claim.check is not None:
        verdict = claim.check()
        printed = verdict.printed if verdict.printed is not None else _render(claim.printed)
        return LedgerEntry(claim.label, claim.title, verdict.status, printed, verdict.derived, verdict.explanation)

    printed, derived = _as_matrix(claim.printed), _as_matrix(claim.derived)
    if printed.shape != derived.shape:
        return LedgerEntry(
            claim.label, claim.title, "discrepancy", _render(claim.printed), _render(claim.derived),
            f"Shapes differ ({printed.shape} printed, {derived.shape} derived). " + claim.discrepancy_text,
        )
    diff = printed - derived
    decided_nonzero = _spot_checks_find_nonzero(diff, printed, claim.samplers, seed, points)
    # Simplification is only attempted when sampling found no difference: proving zero is
    # what needs it, and simplifying a non-zero trigonometric difference is slow.
    symbolic_zero = (not decided_nonzero) and all(_is_zero(entry) for entry in diff)

    if decided_nonzero:
        status: Status = "discrepancy"
        text = claim.discrepancy_text or "The printed and derived forms differ at a sampled point."
    elif symbolic_zero:
        status = "holds"
        text = claim.holds_text or "The printed form simplifies to the derived one."
    else:
        status = "unverifiable"
        text = "Neither simplification nor spot checks could decide this identity."
    return LedgerEntry(claim.label, claim.title, status, _render(claim.printed), _render(claim.derived), text)


def build_ledger(claims: Sequence[Claim]) -> list[LedgerEntry]:
    return [compare(claim) for claim in claims]

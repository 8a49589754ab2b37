"""``certify --maximize NAME=LO..HI`` (and ``--minimize``): the largest (smallest) value of one parameter
at which the certification still succeeds, with a proof at each step (issue 45, item 3).

A value *passes* when ``lyapcheck certify`` with it would exit 0: no question answered negatively,
some claim beyond doubt, every ``--require`` met (:func:`lyapcheck.answers.unmet_requirements`). Each
value tried is a whole certification, checked exactly as any other; nothing is interpolated. The
search:

1. the far end (``HI`` for ``--maximize``): if it passes, it is the answer, and nothing failed;
2. the near end (``LO``): if it fails too, no value was proved;
3. else bisection between the last value that passed and the first that failed, ``steps`` times.

The result states the proved value (with its certificate document) and the first value that failed,
with how it failed: ``refuted`` (a question answered negatively, exactly: an unstable linearization,
a counterexample) or ``not proved`` (not certified, inconclusive). Bisection assumes the property
is monotone in the parameter; both stated facts hold whether it is or not (each was decided at its
own value), only the gap between them may hide other changes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Final, Mapping

#: bisection steps after the two ends: the gap shrinks to (HI - LO) / 2^steps
DEFAULT_STEPS: Final = 6
#: the most steps accepted (each is a whole certification)
MAX_STEPS: Final = 30


@dataclass(frozen=True)
class Step:
    """One value tried: the value, whether it passed, the verdict and the failing answer's word."""

    value: Fraction
    passed: bool
    verdict: str
    outcome: str  # "proved", "refuted" or "not proved"
    seconds: float

    def value_text(self) -> str:
        return decimal(self.value)


@dataclass
class Extremum:
    """What the search found (``proved`` None: no value passed; ``failed`` None: the far end passed)."""

    parameter: str
    direction: str  # "max" or "min"
    low: Fraction
    high: Fraction
    steps: list[Step] = field(default_factory=list)
    proved: Fraction | None = None
    #: what ``certify_at`` returned with the proved value (the API's CertifyResult: its certificate)
    proved_result: Any = None
    failed: Step | None = None

    def to_json(self) -> dict[str, Any]:
        return {"parameter": self.parameter, "direction": self.direction,
                "range": [decimal(self.low), decimal(self.high)],
                "proved": None if self.proved is None else decimal(self.proved),
                "failed": None if self.failed is None else decimal(self.failed.value),
                "failed_outcome": None if self.failed is None else self.failed.outcome,
                "steps": [{"value": decimal(s.value), "passed": s.passed, "verdict": s.verdict,
                           "outcome": s.outcome, "seconds": round(s.seconds, 2)} for s in self.steps]}

    def proved_text(self) -> str:
        return "" if self.proved is None else decimal(self.proved)

    def document(self) -> dict[str, Any] | None:
        """The proved value's certificate document with the ``extremum`` table (None when no value was
        proved): what ``certify --maximize/--minimize --out`` writes, so that its report shows the search."""
        if self.proved_result is None:
            return None
        return {**self.proved_result.to_json(), "extremum": self.to_json()}

    @classmethod
    def from_json(cls, table: Mapping[str, Any]) -> "Extremum":
        """The search as its ``extremum`` table states it (:meth:`to_json`), for a report or a check;
        KeyError, TypeError or ValueError on a malformed table. ``proved_result`` is None."""
        if not isinstance(table, Mapping):
            raise TypeError(f"the table is {type(table).__name__}, not a table")
        low, high = (Fraction(str(x)) for x in table["range"])
        direction = str(table["direction"])
        if direction not in ("max", "min"):
            raise ValueError(f"direction {direction!r} is neither 'max' nor 'min'")
        found = cls(str(table["parameter"]), direction, low, high)
        for s in table["steps"]:
            if not isinstance(s, Mapping):
                raise TypeError(f"a value tried is {type(s).__name__}, not a table")
            found.steps.append(Step(Fraction(str(s["value"])), bool(s["passed"]), str(s["verdict"]),
                                    str(s["outcome"]), float(s.get("seconds") or 0.0)))
        if table.get("proved") is not None:
            found.proved = Fraction(str(table["proved"]))
        if table.get("failed") is not None:
            failed = Fraction(str(table["failed"]))
            found.failed = next((s for s in found.steps if s.value == failed and not s.passed),
                                Step(failed, False, "", str(table.get("failed_outcome")), 0.0))
        return found

    def sentence(self) -> str:
        """The answer in words."""
        word = "largest" if self.direction == "max" else "smallest"
        if self.proved is None:
            tried = self.failed.value if self.failed is not None else self.low
            return (f"{self.parameter}: no value was proved (the {'lower' if self.direction == 'max' else 'upper'} "
                    f"end {decimal(tried)} was {self.failed.outcome if self.failed else 'not proved'})")
        if self.failed is None:
            return f"{self.parameter}: proved at the end of the range, {decimal(self.proved)} (nothing failed)"
        return (f"{self.parameter}: the {word} value proved is {decimal(self.proved)}; {decimal(self.failed.value)} "
                f"was {self.failed.outcome}")


#: significant digits of the values tried (each is given to ``--set`` as this decimal text, exactly)
DIGITS: Final = 12


def decimal(x: Fraction) -> str:
    """``x`` as the decimal text ``--set`` is given; ValueError if that text is not ``x`` exactly (the
    value certified must be the value reported: :func:`midpoint` and :func:`parse_range` make only
    values with an exact text)."""
    text = str(x.numerator) if x.denominator == 1 else f"{float(x):.{DIGITS}g}"
    if Fraction(text) != x:
        raise ValueError(f"{x} has no exact decimal text of {DIGITS} digits")
    return text


def midpoint(low: Fraction, high: Fraction) -> Fraction:
    """The midpoint, rounded to a value with an exact decimal text (:func:`decimal`)."""
    return Fraction(f"{float((low + high) / 2):.{DIGITS}g}")


def parse_range(text: str, flag: str) -> tuple[str, Fraction, Fraction]:
    """``NAME=LO..HI`` with ``LO < HI`` (numbers in the file's units); a one-line error naming ``flag``."""
    from lyapcheck.errors import InvalidParameter

    name, sep, rest = text.partition("=")
    lo_text, dots, hi_text = rest.partition("..")
    try:
        if not sep or not dots or not name.strip():
            raise ValueError
        low, high = Fraction(lo_text.strip()), Fraction(hi_text.strip())
        decimal(low), decimal(high)  # (a fraction such as 1/3 has no exact decimal text: refused)
    except (ValueError, ZeroDivisionError):
        raise InvalidParameter(flag, "NAME=LO..HI with two numbers (in the model file's units), e.g. d=0..2",
                               text) from None
    if not low < high:
        raise InvalidParameter(flag, "NAME=LO..HI with LO < HI", text)
    return name.strip(), low, high


def search(parameter: str, low: Fraction, high: Fraction, direction: str,
           certify_at: Callable[[str], tuple[dict[str, Any], bool, Any]], steps: int = DEFAULT_STEPS,
           clock: Callable[[], float] | None = None) -> Extremum:
    """The bisection of the module docstring; ``certify_at(value_text)`` certifies at one value and
    returns the document, whether it passed, and what to keep of it if it is the answer."""
    import time

    tick = clock or time.perf_counter
    result = Extremum(parameter, direction, low, high)
    far, near = (high, low) if direction == "max" else (low, high)

    def attempt(value: Fraction) -> Step:
        start = tick()
        doc, passed, kept = certify_at(decimal(value))
        verdict = str(doc.get("verdict"))
        outcome = "proved" if passed else ("refuted" if verdict in NEGATIVE_VERDICTS else "not proved")
        step = Step(value, passed, verdict, outcome, tick() - start)
        result.steps.append(step)
        if passed:
            result.proved, result.proved_result = value, kept
        return step

    if attempt(far).passed:
        return result
    result.failed = result.steps[-1]
    if not attempt(near).passed:
        result.failed = result.steps[-1]
        return result
    good, bad = near, far
    for _ in range(steps):
        mid = midpoint(min(good, bad), max(good, bad))
        if mid in (good, bad):
            break  # the decimals cannot split the gap further
        step = attempt(mid)
        if step.passed:
            good = mid
        else:
            bad, result.failed = mid, step
    return result


#: verdicts that answer a question negatively, exactly (lyapcheck.answers)
NEGATIVE_VERDICTS: Final = ("unstable", "unsafe")


def check_steps(value: Any) -> int:
    """``--steps``: an integer in 0..MAX_STEPS (one-line error naming ``steps``)."""
    from lyapcheck.errors import InvalidParameter

    try:
        steps = int(value)
        if str(steps) != str(value).strip():
            raise ValueError
    except (TypeError, ValueError):
        raise InvalidParameter("steps", f"an integer in 0..{MAX_STEPS}", value) from None
    if not 0 <= steps <= MAX_STEPS:
        raise InvalidParameter("steps", f"an integer in 0..{MAX_STEPS}", value)
    return steps


def check_extremum(doc: Mapping[str, Any]) -> list[tuple[str, bool, str]]:
    """The rows ``verify`` adds for a document with an ``extremum`` table (``certify --maximize/--minimize
    --out``): the proved value is the certificate's own override of the parameter, the certificate is a
    success (its verdict one that exits 0; the certificate's claims are re-checked by ``verify`` itself),
    and the table's record is the bisection's: the proved value is the best value that passed and the
    stated failure the closest value that failed, beyond it. (Each other value tried was decided when it
    was tried; only the proved one is re-checked.)"""
    from lyapcheck.answers import OK_VERDICTS

    rows: list[tuple[str, bool, str]] = []
    try:
        found = Extremum.from_json(doc["extremum"])
        if found.proved is None:
            return [("extremum", False, "the table states no proved value, yet a certificate comes with it")]
        override = (doc.get("overrides") or {}).get(found.parameter)
        same = override is not None and Fraction(str(override)) == found.proved
        rows.append(("extremum", same, f"the proved value {decimal(found.proved)} is the certificate's "
                                       f"{found.parameter}" if same else
                     f"the proved value is not the certificate's {found.parameter} ({override!r})"))
        ok = doc.get("verdict") in OK_VERDICTS
        rows.append(("extremum", ok, f"the certificate at the proved value succeeds (verdict {doc.get('verdict')})"
                     if ok else f"the certificate at the proved value does not succeed (verdict {doc.get('verdict')})"))
        rows.append(record_row(found))
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:
        rows.append(("extremum", False, f"the table is malformed ({type(exc).__name__}: {exc})"))
    return rows


def record_row(found: Extremum) -> tuple[str, bool, str]:
    """Whether a stated search is the bisection's record: every value in the range, the proved value
    among those that passed and the best of them, the stated failure among those that failed, the
    closest to the proved value and beyond it (further in the search's direction)."""
    sign = 1 if found.direction == "max" else -1
    passed = [s.value for s in found.steps if s.passed]
    failed = [s.value for s in found.steps if not s.passed]
    problems = []
    if any(not found.low <= s.value <= found.high for s in found.steps):
        problems.append("a value tried lies outside the range")
    if found.proved is None:
        if passed:
            problems.append("values passed, yet the table states no proved value")
    elif found.proved not in passed or any(sign * (v - found.proved) > 0 for v in passed):
        problems.append("the proved value is not the best value that passed")
    if found.failed is not None:
        if found.failed.value not in failed or any(sign * (v - found.failed.value) < 0 for v in failed):
            problems.append("the stated failure is not the closest value that failed")
        elif found.proved is not None and sign * (found.failed.value - found.proved) <= 0:
            problems.append("the stated failure is not beyond the proved value")
    elif failed:
        problems.append("values failed, yet the table states no failure")
    if problems:
        return "extremum", False, "the search's record is inconsistent: " + "; ".join(problems)
    return "extremum", True, (f"the search's record is consistent: {len(found.steps)} values tried, the proved "
                              "value the best that passed" + ("" if found.failed is None else
                                                              ", the stated failure the closest beyond it"))


__all__ = ["check_extremum", "record_row", "DEFAULT_STEPS", "MAX_STEPS", "DIGITS", "Step", "Extremum", "decimal", "midpoint", "parse_range", "search",
           "check_steps", "NEGATIVE_VERDICTS"]

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
from typing import Any, Callable, Final

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


__all__ = ["DEFAULT_STEPS", "MAX_STEPS", "DIGITS", "Step", "Extremum", "decimal", "midpoint", "parse_range", "search",
           "check_steps", "NEGATIVE_VERDICTS"]

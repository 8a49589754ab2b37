"""The largest proved level of a fixed ``V``: one monotone search for every route that proves levels.

A route gives ``attempt(level)``: a proof that ``{V <= level}`` is a region of attraction (a
certificate that passed its exact check), or None where none was found at that level. The search
never loses a proved level:

- from the first level it grows (times ``growth``) while the attempts succeed, or halves while they
  fail, until it holds a proved level ``lo`` and a failed one ``hi``;
- then it bisects between them; a failure at a larger level only lowers ``hi``, never ``lo``; where a
  failure says that a smaller level fails too (a route's ``failed_at``: a point proved in the set where
  ``V' >= 0``, at ``V = v``, fails every level from ``v``), ``hi`` falls to that level at once;
- when the work runs out (:class:`~lyapcheck.models.engines.search.BudgetExhausted` from an attempt),
  the largest level proved so far is the answer (the exception only propagates when none was).

Halving from a failed first level is the same path the former bisection on ``(0, first]`` took, so a
level this search returns is never below the one that bisection returned with the same budget.

A route may take other steps (:class:`LevelSteps`): the polynomial loops' level program
(:func:`lyapcheck.models.classes.regions.largest_level`) goes down by quarters, bisects geometrically and
stops at a relative width or a count of solves; there an attempt is a level the solver finds feasible, and
the exact checks follow the search.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable, Generic, TypeVar

from lyapcheck.models.engines.search import BudgetExhausted

T = TypeVar("T")


@dataclass
class LevelSearch(Generic[T]):
    """The outcome of :func:`largest_proved_level`: the largest proved level and its proof (None
    when no level was proved), the smallest level that failed above it (None: none failed), and
    what stopped the search early (the budget's words, or "")."""

    level: Fraction | None
    proof: T | None
    failed: Fraction | None
    stopped: str = ""
    tried: list[tuple[Fraction, bool]] = field(default_factory=list)


@dataclass(frozen=True)
class LevelSteps:
    """Other steps for :func:`largest_proved_level` than its own (each None: the search's own): ``up``, the
    next level upwards from a proved one (own: ``rounded(level * growth)``); ``down``, the next level
    downwards from a failed one (own: ``rounded(level / 2)``); ``between``, the level tried in a bracket
    ``(lo, hi)`` (own: ``rounded((lo + hi) / 2)``); ``above``, the bracket's top where no level above the
    proved one failed (own: the next level upwards); ``more``, whether to try another level, asked before
    each one downwards and in the bracket (with the largest proved level, None before one, and the
    bracket's top; own: always, until ``halvings`` and ``bisections`` are spent); ``failed_at``, the
    smallest level known to fail once ``level`` failed (own: ``level``; never above it), which becomes the
    bracket's top. Only the order of the attempts rests on it: a level is reported only when proved."""

    up: Callable[[Fraction], Fraction] | None = None
    down: Callable[[Fraction], Fraction] | None = None
    between: Callable[[Fraction, Fraction], Fraction] | None = None
    above: Fraction | None = None
    more: Callable[[Fraction | None, Fraction | None], bool] | None = None
    failed_at: Callable[[Fraction], Fraction] | None = None


def largest_proved_level(attempt: Callable[[Fraction], T | None], first: Fraction, *, growth: Fraction,
                         growth_steps: int, halvings: int, bisections: int,
                         rounded: Callable[[Fraction], Fraction] = lambda x: x,
                         steps: LevelSteps | None = None) -> LevelSearch[T]:
    """The largest level ``attempt`` proves (module docstring). ``growth_steps``: levels tried upwards
    at most; ``halvings``: levels tried downwards from a failed first one at most; ``bisections``:
    halvings of the bracket between the proved and the failed level; ``rounded``: a level as tried
    (short numbers), never above its argument; ``steps``: other steps than these (:class:`LevelSteps`)."""
    out: LevelSearch[T] = LevelSearch(None, None, None)
    steps = LevelSteps() if steps is None else steps
    up = steps.up or (lambda c: rounded(c * growth))
    down = steps.down or (lambda c: rounded(c / 2))
    between = steps.between or (lambda lo, hi: rounded((lo + hi) / 2))
    more = steps.more or (lambda lo, hi: True)
    failed_at = steps.failed_at or (lambda c: c)

    def run(level: Fraction) -> bool:
        proof = attempt(level)
        out.tried.append((level, proof is not None))
        if proof is None:
            known = min(failed_at(level), level)
            if out.level is not None and known <= out.level:
                known = level  # (a smaller failing level than a proved one: a float's rounding, ignored)
            out.failed = known if out.failed is None else min(out.failed, known)
            return False
        if out.level is None or level > out.level:
            out.level, out.proof = level, proof
        return True

    try:
        level = first
        if run(level):
            for _ in range(growth_steps - 1):  # grow while it works
                level = up(level)
                if out.level is None or level <= out.level or not run(level):
                    break
        else:
            for _ in range(halvings):  # down from a failed first level: the first proved one
                level = down(level)
                if level <= 0 or not more(None, out.failed) or run(level):
                    break
        if out.level is not None:
            hi = out.failed if out.failed is not None and out.failed > out.level else \
                steps.above if steps.above is not None else up(out.level) if steps.up else out.level * growth
            for _ in range(bisections):
                if not more(out.level, hi):
                    break
                mid = between(out.level, hi)
                if not out.level < mid < hi:
                    break
                if not run(mid):
                    known = min(failed_at(mid), mid)
                    hi = known if known > out.level else mid
    except BudgetExhausted as exc:
        if out.level is None:
            raise
        out.stopped = str(exc)
    return out


__all__ = ["LevelSearch", "LevelSteps", "largest_proved_level"]

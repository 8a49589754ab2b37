"""The reason a ``not_certified`` or ``inconclusive`` class prints: one sentence a user can act on.

A class that found nothing says, in the user's words, what it tried and what to try next, naming
an option that exists (:data:`NEXT`, the one place that words them). What the search met on its
way (solver statuses, size limits by their constant's name, Gram rows, refusals of the exact check,
the rates tried) is the reason's ``detail``: the condition's JSON keeps it under
``numbers["detail"]`` and the terminal prints it with ``--verbose`` only.

A search that stops at a size limit writes its detail line with :func:`size_limit`, which both
names the constant (for the detail) and words the figure (for the summary): :func:`size_limits`
reads the lines back, so that the summary says "the problem is too large" where a higher degree
would not help.

=====================  ==============================================================================
builder                sentence
=====================  ==============================================================================
:func:`not_found`      no <thing> of degree 2, 4 or 6 was found; try ... (or: too large at degree d)
:func:`out_of_time`    the time limit of 60 s was reached while searching for <thing>; try more time ...
:func:`reason`         any other "what was tried" with its "what to try next"
=====================  ==============================================================================

The few ``not_applicable`` sentences that every kind of loop prints (:data:`NEEDS_CANDIDATE`,
:data:`NO_DISTURBANCES`) are worded here too, once.
"""

from __future__ import annotations

import re
from typing import Any, Final, Iterable, Mapping, NamedTuple, Sequence

from lyapcheck.degrees import MAX_DEGREE

#: what to try next, one phrase per option (``{degree}``: the degree the phrase suggests). Every
#: phrase names an option of ``lyapcheck certify`` or a table of the model file
NEXT: Final[Mapping[str, str]] = {
    "degree": "a higher degree (--degree {degree})",
    "smaller_degree": "a smaller degree (--degree {degree})",
    "sos_gas": "a V of higher degree (--classes sos_gas --degree {degree})",
    "domain": "a smaller [domain]",
    "candidate": 'a candidate V (--candidate "...")',
    "other_candidate": 'another candidate V (--candidate "...")',
    "time": "more time (--time-limit SECONDS)",
    "fewer": "fewer states or functions (each function adds an auxiliary variable)",
    "sets": "an initial set farther from the unsafe set",
    "goal": "a goal set that holds the equilibrium inside",
    "disturbances": "smaller bounds in [disturbances]",
    "box": "a narrower box (--box)",
    "search": "the classes that search a Lyapunov function (--classes sos_gas,roa)",
    "outputs": "an output in [outputs] that does not use an angle",
}

#: what each class searches for, in a sentence's words (a class not named: "a certificate")
SEARCHED_FOR: Final[Mapping[str, str]] = {
    "linearization": "the linearization's eigenvalues", "quadratic": "a quadratic Lyapunov function",
    "sos_gas": "a Lyapunov function", "roa": "a region of attraction", "candidate": "a proof with the candidate V",
    "barrier": "a barrier", "reach_avoid": "a reach-avoid function", "sos_bound": "a bound on every output",
}

#: a size-limit detail line as :func:`size_limit` writes it: the user's words, then the constant
SIZE_LIMIT: Final = re.compile(r"too large: (?P<words>[^;()]+?) \((?P<constant>[A-Z][A-Z_]*(?:, [A-Z][A-Z_]*)*)\)")
#: the degree a detail line speaks of (``degree 4: ...``, ``W of degree 2: ...``)
DEGREE: Final = re.compile(r"\bdegree (\d+)\b")
#: the degree words of the common degrees (others: "of degree 6")
DEGREE_WORDS: Final[Mapping[int, str]] = {2: "quadratic", 4: "quartic"}

#: why ``candidate`` asked for without ``--candidate`` is ``not_applicable`` (on every kind of loop)
NEEDS_CANDIDATE: Final = 'needs --candidate "EXPR" (the user\'s V); not run'
#: why ``sos_bound`` on a model without ``[disturbances]`` is ``not_applicable`` (on a loop and on a map)
NO_DISTURBANCES: Final = "the model has no [disturbances]: add one (name = bound) to bound its outputs"


class Reason(NamedTuple):
    """A class's reason: the sentence it prints and the technical detail kept in its JSON."""

    summary: str
    detail: list[str]

    def numbers(self, numbers: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """``numbers`` (a condition's figures) with this reason's ``detail`` added."""
        return {**(numbers or {}), "detail": list(self.detail)}


def size_limit(count: Any, unit: str, limit: Any, constant: str) -> str:
    """A size limit met, as a detail line: ``too large: 67 monomials per sum-of-squares matrix where
    the limit is 60 (MAX_RECAST_GRAM_ROWS)``. ``count`` and ``limit`` may be None where the search
    does not know them (``unit`` then says it all); ``constant`` may name several."""
    figure = f"{count} {unit}" if count is not None else unit
    where = f" where the limit is {limit}" if limit is not None else ""
    return f"too large: {figure}{where} ({constant})"


def size_limits(detail: Iterable[str]) -> list[tuple[int | None, str]]:
    """The size limits among detail lines: ``(degree or None, the user's words)`` each."""
    out = []
    for line in detail:
        found = SIZE_LIMIT.search(line)
        if found is not None:
            degree = DEGREE.search(line[:found.start()])
            out.append((int(degree.group(1)) if degree else None, found.group("words")))
    return out


def degrees_of(detail: Iterable[str]) -> list[int]:
    """The degrees detail lines speak of, in order, once each."""
    out: list[int] = []
    for line in detail:
        found = DEGREE.search(line)
        if found is not None and int(found.group(1)) not in out:
            out.append(int(found.group(1)))
    return out


def or_list(items: Sequence[str], word: str = "or") -> str:
    """``a, b or c``."""
    items = list(items)
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} {word} {items[-1]}"


def advice(steps: Sequence[str], degree: int | None = None) -> str:
    """``try a, b or c`` from keys of :data:`NEXT` (``degree``: the one a degree phrase names)."""
    return "try " + or_list([NEXT[k].format(degree=degree if degree is not None else "N") for k in steps])


def degree_words(thing: str, degrees: Sequence[int]) -> str:
    """``quadratic or quartic Lyapunov function``, ``barrier of degree 2, 4 or 6``."""
    degrees = sorted(set(degrees))
    if degrees and all(d in DEGREE_WORDS for d in degrees):
        return f"{or_list([DEGREE_WORDS[d] for d in degrees])} {thing}"
    return f"{thing} of degree {or_list([str(d) for d in degrees])}" if degrees else thing


def _detail(detail: str | Iterable[str]) -> list[str]:
    return [detail] if isinstance(detail, str) else [str(d) for d in detail]


def reason(tried: str, steps: Sequence[str], detail: str | Iterable[str] = (), degree: int | None = None) -> Reason:
    """``<tried>; try <steps>``: what was tried (the user's words) and what to try next."""
    return Reason(f"{tried}; {advice(steps, degree)}" if steps else tried, _detail(detail))


def not_found(thing: str, degrees: Sequence[int], detail: str | Iterable[str], steps: Sequence[str],
              this_class: str = "this class") -> Reason:
    """No ``thing`` of ``degrees`` (those the detail lines name, where they do: the search's own,
    under ``--degree``'s ceiling) was found: ``no quadratic or quartic Lyapunov function was found;
    try ...``. Where the detail shows a size limit at the first degree, the problem is too large
    (``the problem is too large for this class at degree 4: ...; try fewer states ...``); at a later
    degree, the degrees below were searched and a higher degree is not suggested."""
    lines = _detail(detail)
    degrees = degrees_of(lines) or list(degrees)
    limits = size_limits(lines)
    # a degree was searched when some line of it is not a size limit (over a box: one parameter degree)
    reached = degrees_of(line for line in lines if not SIZE_LIMIT.search(line))
    limited = [d for d, _ in limits if d is not None]
    searched = [d for d in degrees if d not in limited or d in reached]
    limits = [(d, words) for d, words in limits if d is None or d not in searched]
    top = max(degrees) if degrees else None
    if limits and not searched:
        at, words = limits[0]
        where = f" at degree {at}" if at is not None else ""
        smaller = ["smaller_degree"] if at is not None and at > 2 else []
        return reason(f"the problem is too large for {this_class}{where}: {words}", [*smaller, "fewer"], lines,
                      degree=(at - 2) if at is not None else None)
    if limits:
        at, words = limits[0]
        where = f"at degree {at} " if at is not None else ""
        rest = [k for k in steps if k not in ("degree", "sos_gas")] or ["fewer"]
        return reason(f"no {degree_words(thing, searched)} was found, and {where}the problem is too large for "
                      f"{this_class} ({words})", rest, lines)
    if top is not None and top + 2 > MAX_DEGREE:  # --degree refuses more: the other steps remain
        steps = [k for k in steps if k not in ("degree", "sos_gas")] or ["fewer"]
    return reason(f"no {degree_words(thing, degrees)} was found", steps, lines,
                  degree=top + 2 if top is not None else None)


def out_of_time(thing: str, seconds: float, detail: str | Iterable[str], steps: Sequence[str] = ("time",),
                hard_stop: float | None = None) -> Reason:
    """The time limit ended the search: ``the time limit of 60 s was reached while searching for a
    Lyapunov function (degree 2 searched, none found); try more time (--time-limit SECONDS)``;
    ``hard_stop``: the class ran past its limit and was stopped at that many seconds."""
    lines = _detail(detail)
    searched = degrees_of(line for line in lines if not SIZE_LIMIT.search(line))
    done = f" (none of degree {or_list([str(d) for d in searched])} was found before)" if searched else ""
    when = (f"the class ran past its time limit of {seconds:g} s and was stopped at {hard_stop:g} s"
            if hard_stop is not None else f"the time limit of {seconds:g} s was reached")
    return reason(f"{when} while searching for {thing}{done}", steps, lines)


def with_budget(found: Reason, spent: str) -> Reason:
    """``found`` with the budget of work that ended part of its search said in its sentence: ``no
    quartic Lyapunov function was found (the search's budget of 12 solves per template was spent);
    try ...`` (``spent``: :meth:`lyapcheck.models.engines.search.SolveLimit.words`). A count, the same on
    any machine: more time would not change it."""
    head, sep, tail = found.summary.partition("; try ")
    return Reason(f"{head} ({spent}){sep}{tail}", found.detail)


def searched_for(name: str) -> str:
    """What class ``name`` searches for (:data:`SEARCHED_FOR`)."""
    return SEARCHED_FOR.get(name, "a certificate")


def numerical_trouble(thing: str, detail: str | Iterable[str]) -> Reason:
    """The numerical search failed on an error it cannot recover from."""
    return reason(f"the numerical search for {thing} failed (numerical trouble)", ("domain", "smaller_degree"),
                  detail)


__all__ = ["NEXT", "SEARCHED_FOR", "NEEDS_CANDIDATE", "NO_DISTURBANCES", "Reason", "searched_for", "size_limit",
           "size_limits", "reason", "not_found", "out_of_time", "with_budget", "numerical_trouble", "advice",
           "degree_words"]

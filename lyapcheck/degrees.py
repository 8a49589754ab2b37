"""The largest polynomial degree a class searches (``certify --degree N``, ``certify(degree=N)``).

Each class that searches polynomial certificates has its own ladder of degrees (``sos_gas``: 2, 4,
6, 8; ``roa``: 4, 6, 8; ``barrier``: 2, 4, 6; ...), tried in turn, cheapest first. ``--degree N``
lays one ceiling over all of them: a ladder is cut at ``N``, or extended by even degrees up to ``N``
when ``N`` is above its top (a higher degree can prove more, at a cost that grows quickly with the
number of variables). A ladder that would be empty keeps its first rung: a class's smallest degree
is the least it can search.

The ceiling is a context variable, so that it holds for one ``certify`` call (and the threads it
starts) and no other.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import Final, Iterator, Sequence

from lyapcheck.errors import InvalidParameter

#: the largest ``--degree`` accepted: beyond it a Gram matrix of even two states outgrows the solver
MAX_DEGREE: Final = 16

_CEILING: ContextVar[int | None] = ContextVar("lyapcheck_degree_ceiling", default=None)


def searched_degrees(ladder: Sequence[int]) -> tuple[int, ...]:
    """``ladder`` under the current ceiling (module docstring)."""
    ceiling = _CEILING.get()
    if ceiling is None or not ladder:
        return tuple(ladder)
    cut = [d for d in ladder if d <= ceiling]
    top = max(ladder)
    step = 2 if all(d % 2 == 0 for d in ladder) else 1
    cut += list(range(top + step, ceiling + 1, step))
    return tuple(cut) if cut else (min(ladder),)


def check_degree(value: object) -> int | None:
    """A ``--degree`` as given (None: each class's own ladder); a one-line error naming ``degree``."""
    if value is None:
        return None
    try:
        n = int(str(value))
    except ValueError:
        n = -1
    if not 2 <= n <= MAX_DEGREE or str(n) != str(value).strip():
        raise InvalidParameter("degree", f"an integer from 2 to {MAX_DEGREE}", value)
    return n


@contextmanager
def degree_ceiling(value: int | None) -> Iterator[None]:
    """Lay ``value`` (see :func:`check_degree`) over every ladder for the duration of the block."""
    token = _CEILING.set(value)
    try:
        yield
    finally:
        _CEILING.reset(token)


__all__ = ["MAX_DEGREE", "searched_degrees", "check_degree", "degree_ceiling"]

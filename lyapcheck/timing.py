"""Wall-time limits of one condition class: a hard stop around work that overruns its budget.

Generic (the paper's classes and a model's share it): every class also bounds its own search with a
cooperative budget; this stop catches what runs past it (a solve, an exact check, a simulation).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Any, Iterator


class ClassTimeLimit(Exception):
    """A condition class ran past :data:`lyapcheck.tolerances.CLASS_TIME_LIMIT_S`."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise :class:`ClassTimeLimit` in this block after ``seconds`` (main thread, POSIX only).

    Elsewhere (sweep workers run in threads or processes with their own limits) the block runs
    unbounded; every class also bounds its own iterations and solver time.
    """
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return

    def expire(signum: int, frame: Any) -> None:
        raise ClassTimeLimit(f"time limit of {seconds:g} s reached")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


__all__ = ["ClassTimeLimit", "time_limit"]

"""Iterates of a discrete-time map ``x[k+1] = f(x[k])`` in floating point, every start a row of one batch.

One loop serves every caller that iterates a map: ``simulate`` of a map
(:func:`lyapcheck.models.surfaces.iterate.iterate`, which records every iterate), and the discrete
classes' simulated checks (:func:`lyapcheck.models.classes.discrete_regions.simulated_region`, which
keeps the last iterate, and :func:`~lyapcheck.models.classes.discrete_regions.left_set`, which watches
``V`` along every iterate), and the falsification of a map's safety classes
(:func:`lyapcheck.models.classes.discrete_safety.falsify_map`, which freezes a row once it is in the goal
and ends the iteration at the first proved counterexample). A row that leaves the escape box or stops
being finite is frozen there (its last iterate kept, the map no longer applied to it), so one diverging
row neither overflows nor costs the others; so is a row whose iterate meets the caller's ``stop``
predicate. Without an escape box or a ``stop`` every row is iterated every step.

Iterates are pictures and cross-checks, never evidence for a status.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
BoolArray = npt.NDArray[np.bool_]

#: ``f`` at ``(batch, n)`` states: the ``(batch, n)`` next states
MapFunction = Callable[[FloatArray], FloatArray]
#: ``observe(k, rows, x)``: the iterates ``x`` (``(len(rows), n)``) of ``rows`` after step ``k`` (1, 2, ...);
#: True ends the iteration after that step (None or False: go on)
Observer = Callable[[int, IntArray, FloatArray], bool | None]
#: ``stop(x)`` at ``(batch, n)`` iterates: the ``(batch,)`` rows to freeze there
StopPredicate = Callable[[FloatArray], BoolArray]


def iterate_map(f: MapFunction, starts: FloatArray, steps: int, *, center: FloatArray | None = None,
                escape: FloatArray | float | None = None, observe: Observer | None = None,
                stop: StopPredicate | None = None) -> tuple[FloatArray, BoolArray]:
    """Apply ``f`` ``steps`` times to every row of ``starts``.

    Parameters
    ----------
    f
        The map at a batch of states (floating point; an overflow or a pole gives a non-finite row).
    starts
        ``(k, n)`` first states (not changed).
    steps
        How many iterations.
    center, escape
        The escape box ``|x - center| <= escape`` (per state, or one number; ``center`` 0 when None): a
        row whose iterate leaves it, or is not finite, is frozen at that iterate and no longer iterated.
        None: no box, every row is iterated every step (a non-finite row stays non-finite).
    observe
        Called after every step with the rows just iterated and their new iterates (a frozen row's last
        iterate included, at the step it left or stopped); when it returns True no further step is taken.
    stop
        A row whose start or iterate meets it is frozen there, after ``observe`` has seen that iterate
        (a start that meets it is never iterated). None: no row is stopped.

    Returns
    -------
    tuple
        The last iterate of every row (its iterate when it left or stopped, for a frozen row) and which
        rows neither left nor stopped (all True without a box or a ``stop``).
    """
    x = np.array(starts, dtype=np.float64, copy=True)
    alive = np.ones(x.shape[0], dtype=bool)
    everyone = np.arange(x.shape[0])
    freezes = escape is not None or stop is not None
    with np.errstate(all="ignore"):  # an overflow or a pole: a non-finite iterate, frozen (or kept)
        if stop is not None:
            alive &= ~stop(x)
        for k in range(1, steps + 1):
            if not freezes:
                x = f(x)
                rows = everyone
            else:
                if not alive.any():
                    break
                rows = np.flatnonzero(alive)
                x[rows] = f(x[rows])
            if observe is not None and observe(k, rows, x[rows]):
                break
            if escape is not None:
                offset = x if center is None else x - center
                alive &= np.all(np.isfinite(x), axis=1) & np.all(np.abs(offset) <= escape, axis=1)
            if stop is not None:
                alive[rows] &= ~stop(x[rows])
    return x, alive


def stacked_map(evaluators: Sequence[Callable[[FloatArray], FloatArray]]) -> MapFunction:
    """The map whose ``i``-th component is ``evaluators[i]`` (each ``(batch, n) -> (batch,)``, such as a
    :class:`~lyapcheck.models.engines.numeric.NumericPoly`)."""
    def f(x: FloatArray) -> FloatArray:
        return np.stack([e(x) for e in evaluators], axis=1)

    return f


__all__ = ["MapFunction", "Observer", "StopPredicate", "iterate_map", "stacked_map"]

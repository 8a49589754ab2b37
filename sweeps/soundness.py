"""Soundness of certified answers against simulation: the flag and its tolerance.

A certified ultimate bound says ``limsup |eps| <= eps_bound`` for every disturbance with
``|d_perp| <= d*``; every disturbance scenario of a sweep respects that bound, and starts on
the path, inside every invariant set of the certificate, so its whole tail must stay inside
the bound. A stability certificate says the error dynamics converge. Hence:

* ``bound_violation``: some disturbance scenario's tail sup of ``|eps|`` exceeds
  ``eps_bound * (1 + BOUND_REL_TOL)``; the tolerance only absorbs the integrator's error (its
  contract is ``lyapcheck.tolerances.SIM_REL_TOL`` relative to the state scale, tighter than
  this), never a modelling slack;
* ``divergence_violation``: the simulation diverged or failed where a stability class is
  certified.

Either is a soundness violation. It must never happen; when it does the sweep says so loudly and
exits with code 1.
"""

from __future__ import annotations

from typing import Final

import numpy as np
import numpy.typing as npt

from sweeps.schema import STABILITY_CLASSES, STATUS_CODES

#: relative tolerance on a certified bound before a simulated excursion counts as a violation
BOUND_REL_TOL: Final = 1e-6
#: the worst-case disturbance search's time budget in a sweep (every target): below any refinement
#: round's cost, so only its deterministic screening round and final re-simulation run (about 8 s a
#: point). A figure then does not depend on the machine's speed, which resuming a sweep
#: byte-for-byte needs, and a violation it finds is reproducible
WORST_CASE_SCREENING_ONLY: Final = 1e-9

BoolArray = npt.NDArray[np.bool_]


def bound_violation(eps_bound: npt.NDArray[np.float64], sim_sups: list[npt.NDArray[np.float64]]) -> BoolArray:
    """Where a disturbance scenario's tail sup leaves the certified bound (NaN: no bound / no run)."""
    out = np.zeros(eps_bound.shape, dtype=bool)
    limit = eps_bound * (1.0 + BOUND_REL_TOL)
    for sup in sim_sups:
        with np.errstate(invalid="ignore"):
            out |= np.isfinite(eps_bound) & np.isfinite(sup) & (sup > limit)
    return out


def stability_certified(statuses: dict[str, npt.NDArray[np.int8]]) -> BoolArray:
    """Where at least one stability class of :data:`STABILITY_CLASSES` is certified."""
    first = next(iter(statuses.values()))
    out = np.zeros(first.shape, dtype=bool)
    for cls in STABILITY_CLASSES:
        if cls in statuses:
            out |= statuses[cls] == STATUS_CODES["certified"]
    return out


def violations(eps_bound: npt.NDArray[np.float64], sim_sups: list[npt.NDArray[np.float64]],
               diverged: BoolArray, statuses: dict[str, npt.NDArray[np.int8]]) -> BoolArray:
    """The ``soundness_violation`` flag (module docstring)."""
    return bound_violation(eps_bound, sim_sups) | (diverged & stability_certified(statuses))

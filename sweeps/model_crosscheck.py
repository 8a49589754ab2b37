"""The old path of the simulation cross-check of a model file's sweep: a re-export of
:mod:`sweeps.crosscheck`, where the one pipeline of every target keeps it (issue 29 item 6). Delete this
file once nothing imports its path (sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.crosscheck import (
    CrossCheck, WORST_CASE_SCREENING_ONLY, cross_check,
)

__all__ = ["CrossCheck", "WORST_CASE_SCREENING_ONLY", "cross_check"]

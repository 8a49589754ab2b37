"""The old path of the summary of the paper's box sweep: a re-export of :mod:`sweeps.summary`, where the
one pipeline of every target keeps it (issue 29 item 6). Delete this file once nothing imports its path
(sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.summary import (
    MAX_LISTED, BoxSummary, leaf_fractions, summarize_boxes, violation_count,
    summarize_box_arrays as summarize_arrays,
)

__all__ = ["BoxSummary", "MAX_LISTED", "leaf_fractions", "summarize_arrays", "summarize_boxes", "violation_count"]

"""The old path of the summary of a model file's sweep: a re-export of :mod:`sweeps.summary`, where the
one pipeline of every target keeps it (issue 29 item 6). Delete this file once nothing imports its path
(sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.summary import (
    LEAF_STATUSES, MAX_LISTED, ModelSweepSummary, cell_fractions, open_summary, stored_window, summarize_dataset,
    summarize_model_store, violation_count, summarize_model_arrays as summarize_arrays,
)

__all__ = ["LEAF_STATUSES", "MAX_LISTED", "ModelSweepSummary", "cell_fractions", "open_summary", "stored_window",
           "summarize_arrays", "summarize_dataset", "summarize_model_store", "violation_count"]

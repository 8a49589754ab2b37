"""The old path of the run of the paper's box sweep: a re-export of :mod:`sweeps.run`,
:mod:`sweeps.spec`, :mod:`sweeps.evaluate`, where the one pipeline of every target keeps it (issue 29
item 6). Delete this file once nothing imports its path (sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.run import (
    BoxSweepReport, run_boxes,
)
from sweeps.spec import (
    initial_boxes,
)
from sweeps.evaluate import (
    evaluate_boxes,
)

__all__ = ["BoxSweepReport", "evaluate_boxes", "initial_boxes", "run_boxes"]

"""The old path of the run of a model file's sweep: a re-export of :mod:`sweeps.run`,
:mod:`sweeps.spec`, where the one pipeline of every target keeps it (issue 29 item 6). Delete this file
once nothing imports its path (sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.run import (
    ModelSweepReport, run_model_sweep,
)
from sweeps.spec import (
    relative_width, split_cell as split,
)

__all__ = ["ModelSweepReport", "relative_width", "run_model_sweep", "split"]

"""The old path of the spec of a model file's sweep: a re-export of :mod:`sweeps.spec`,
:mod:`sweeps.targets`, where the one pipeline of every target keeps it (issue 29 item 6). Delete this
file once nothing imports its path (sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.spec import (
    ModelAxis, ModelSimulation, ModelSweepSpec, cached_model_spec, exact_decimal, initial_cells, load_model_spec,
    parse_model_spec, window_box, MODEL_POINT_CLASSES as POINT_CLASSES, MODEL_BOX_CLASSES as BOX_CLASSES,
)
from sweeps.targets import (
    load_any_spec, names_a_model,
)

__all__ = ["BOX_CLASSES", "ModelAxis", "ModelSimulation", "ModelSweepSpec", "POINT_CLASSES", "cached_model_spec",
           "exact_decimal", "initial_cells", "load_any_spec", "load_model_spec", "names_a_model",
           "parse_model_spec", "window_box"]

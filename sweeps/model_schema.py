"""The old path of the schema of a model file's sweep: a re-export of :mod:`sweeps.schema`, where the
one pipeline of every target keeps it (issue 29 item 6). Delete this file once nothing imports its path
(sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.schema import (
    BOXES_MODE, FIGURES, OUTPUT_FIGURES, POINTS_MODE, STRING, check_model_dataset, is_model_dataset, json_list,
    point_variables, MODEL_MODES as MODES, model_box_variables as box_variables,
)

__all__ = ["BOXES_MODE", "FIGURES", "MODES", "OUTPUT_FIGURES", "POINTS_MODE", "STRING", "box_variables",
           "check_model_dataset", "is_model_dataset", "json_list", "point_variables"]

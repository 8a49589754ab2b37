"""The old path of the store of a model file's sweep: a re-export of :mod:`sweeps.store`, where the one
pipeline of every target keeps it (issue 29 item 6). Delete this file once nothing imports its path
(sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.store import (
    ModelBoxStore, ModelPointStore, open_model_store,
)

__all__ = ["ModelBoxStore", "ModelPointStore", "open_model_store"]

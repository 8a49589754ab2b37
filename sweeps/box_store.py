"""The old path of the store of the paper's box sweep: a re-export of :mod:`sweeps.store`, where the one
pipeline of every target keeps it (issue 29 item 6). Delete this file once nothing imports its path
(sweeps/__init__.py lists the old paths).
"""

from __future__ import annotations

from sweeps.store import (
    BOX_CHUNK, BoxStore,
)

__all__ = ["BOX_CHUNK", "BoxStore"]

"""The store of a box sweep (``mode = "boxes"``): one row per box of the refinement tree.

A Zarr v3 group with one dimension, ``box``, preallocated to the spec's ``max_boxes`` rows
(:func:`sweeps.schema.box_variables`); attributes ``mode = "boxes"``, ``spec_toml``,
``versions``, ``paper_point`` and ``dims`` (the swept parameters, JSON). Row ``i`` is the box
with id ``i`` of :mod:`sweeps.boxes_run`, whose ids are a deterministic function of the spec and
of the statuses of earlier boxes, so a resumed sweep recomputes exactly the rows that are not
``done`` and ends byte-for-byte identical to an uninterrupted one.

The properties of :mod:`sweeps.store` carry over: atomic creation (staging directory, rename),
whole chunk files, data written before ``done``, the spec and package versions checked on
resume, and every array read once before resuming.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Final, Mapping

import numpy as np

from sweeps.schema import BOX_DIM, box_variables
from sweeps.spec import SweepSpec
from sweeps.store import block_regions, check_arrays_readable, open_or_build, paper_point, versions

#: rows per Zarr chunk (the main process rewrites a whole chunk to update some of its rows)
BOX_CHUNK: Final = 256


class BoxStore:
    """An open box store (module docstring)."""

    def __init__(self, path: Path, group: Any, spec: SweepSpec) -> None:
        assert spec.boxes is not None
        self.path = path
        self.group = group
        self.spec = spec
        self.capacity = spec.boxes.max_boxes
        self.variables = box_variables(spec.dims, spec.classes)

    @classmethod
    def open_or_create(cls, path: str | Path, spec: SweepSpec) -> "BoxStore":
        target = Path(path)
        group = open_or_build(target, spec, lambda staging: _build(staging, spec))
        store = cls(target, group, spec)
        regions = block_regions((store.capacity,), (BOX_CHUNK,))
        check_arrays_readable(group, target, {v.name: (store.capacity,) for v in store.variables}, regions)
        return store

    def read(self, name: str) -> np.ndarray:
        return np.asarray(self.group[name][...])

    def write_rows(self, rows: np.ndarray, values: Mapping[str, np.ndarray]) -> None:
        """Set ``values[name][j]`` at row ``rows[j]``, chunk by chunk: data first, ``done`` last.

        Each touched chunk is read, updated and written back whole, so every chunk file on disk
        is a consistent state of the sweep (zarr writes a chunk through a temporary file).
        """
        rows = np.asarray(rows, dtype=np.int64)
        if rows.size == 0:
            return
        names = [n for n in values if n != "done"] + (["done"] if "done" in values else [])
        for key in np.unique(rows // BOX_CHUNK):
            region = slice(int(key) * BOX_CHUNK, min((int(key) + 1) * BOX_CHUNK, self.capacity))
            mask = rows // BOX_CHUNK == key
            local = rows[mask] - region.start
            for name in names:
                block = np.asarray(self.group[name][region])
                block[local] = np.asarray(values[name])[mask]
                self.group[name][region] = block


def _build(path: Path, spec: SweepSpec) -> None:
    import zarr

    assert spec.boxes is not None
    group = zarr.open_group(str(path), mode="w", zarr_format=3)
    group.attrs.update({"mode": "boxes", "spec_toml": spec.text, "versions": json.dumps(versions(), sort_keys=True),
                        "paper_point": json.dumps(paper_point(), sort_keys=True), "dims": json.dumps(list(spec.dims)),
                        "classes": json.dumps(list(spec.classes)),
                        "axis_scales": json.dumps({a.name: a.scale for a in spec.axes})})
    n = spec.boxes.max_boxes
    for var in box_variables(spec.dims, spec.classes):
        group.create_array(var.name, shape=(n,), dtype=var.dtype, chunks=(min(BOX_CHUNK, n),),
                           dimension_names=[BOX_DIM], fill_value=var.fill,
                           attributes={"description": var.description})

"""The Zarr store of a model sweep: a grid of points or a table of boxes (:mod:`sweeps.model_schema`).

The properties of :mod:`sweeps.store`, through its own helpers:

* **Atomic creation** (:func:`sweeps.store.open_or_build`): the group is built in a staging
  directory and renamed into place.
* **Whole chunks, data before ``done``**: a unit's region (points) or the rows of a unit (boxes)
  are written chunk by chunk, each chunk read, updated and written back whole, ``done`` last.
* **Determinism**: no timestamp or path in the metadata; certificates are stored without their
  solver logs (wall times), so a resumed sweep ends byte-for-byte identical to an uninterrupted one.
* **Resume**: the spec text and the package versions are checked by ``open_or_build``, and here
  the model's SHA-256 (the model file may have changed since) and the layout; every array is read
  once before resuming (:func:`sweeps.store.check_arrays_readable`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, cast

import numpy as np

from lyapcheck.errors import InputFileError
from sweeps.box_store import BOX_CHUNK
from sweeps.model_schema import BOXES_MODE, POINTS_MODE, STRING, box_variables, point_variables
from sweeps.model_spec import ModelSweepSpec
from sweeps.schema import BOX_DIM, Variable
from sweeps.store import Region, block_regions, check_arrays_readable, chunk_shape, open_or_build, versions

if TYPE_CHECKING:  # pragma: no cover
    from sweeps.spec import SweepSpec


def _attrs(spec: ModelSweepSpec) -> dict[str, Any]:
    return {"mode": POINTS_MODE if spec.mode == "points" else BOXES_MODE, "spec_toml": spec.text,
            "model_toml": spec.model_text, "model_file": spec.model_file, "model_sha256": spec.model_sha256,
            "model_name": spec.model.name,
            "versions": json.dumps(versions(), sort_keys=True), "dims": json.dumps(list(spec.dims)),
            "classes": json.dumps(list(spec.classes)), "outputs": json.dumps(list(spec.outputs)),
            "axis_scales": json.dumps({a.name: a.scale for a in spec.axes})}


def _open(path: Path, spec: ModelSweepSpec, build: Any) -> Any:
    """``open_or_build`` (it reads only ``spec.text`` of the spec it is given), then this sweep's checks."""
    group = open_or_build(path, cast("SweepSpec", spec), build)
    attrs = dict(group.attrs)
    expected = _attrs(spec)["mode"]
    if attrs.get("mode") != expected:
        raise InputFileError(f"'{path}' is a store of another kind ({attrs.get('mode', 'a paper sweep')}); choose "
                             "another --out")
    if attrs.get("model_sha256") != spec.model_sha256:
        raise InputFileError(f"'{path}' was computed from another text of the model file {spec.model_file} (SHA-256 "
                             f"{str(attrs.get('model_sha256'))[:12]}..., now {spec.model_sha256[:12]}...); resuming "
                             "would mix two models: choose another --out")
    return group


def _create(group: Any, var: Variable, shape: tuple[int, ...], chunks: tuple[int, ...], dims: list[str]) -> None:
    group.create_array(var.name, shape=shape, dtype=var.dtype, chunks=chunks, dimension_names=dims,
                       fill_value=var.fill, attributes={"description": var.description})


def _as(values: Any, var: Variable) -> np.ndarray:
    if var.dtype == STRING:
        return np.asarray([str(v) for v in np.asarray(values, dtype=object).ravel()], dtype=STRING)
    return np.asarray(values, dtype=var.dtype)


class ModelPointStore:
    """A points store: every variable over the grid of the swept parameters."""

    def __init__(self, path: Path, group: Any, spec: ModelSweepSpec) -> None:
        self.path = path
        self.group = group
        self.spec = spec
        self.chunks = chunk_shape(spec.shape, spec.chunk_size)
        self.variables = point_variables(spec.classes, spec.outputs)

    @classmethod
    def open_or_create(cls, path: str | Path, spec: ModelSweepSpec) -> "ModelPointStore":
        target = Path(path)

        def build(staging: Path) -> None:
            import zarr

            group = zarr.open_group(str(staging), mode="w", zarr_format=3)
            group.attrs.update(_attrs(spec))
            for axis in spec.axes:
                coord = group.create_array(axis.name, shape=(axis.size,), dtype="float64", chunks=(axis.size,),
                                           dimension_names=[axis.name], fill_value=np.nan,
                                           attributes={"scale": axis.scale, "parameter": axis.name,
                                                       "units": "SI (as the model file reads its parameters)"})
                coord[:] = np.asarray(axis.values, dtype=np.float64)
            chunks = chunk_shape(spec.shape, spec.chunk_size)
            for var in point_variables(spec.classes, spec.outputs):
                _create(group, var, spec.shape, chunks, list(spec.dims))

        group = _open(target, spec, build)
        store = cls(target, group, spec)
        arrays: dict[str, tuple[int, ...]] = {axis.name: (axis.size,) for axis in spec.axes}
        arrays.update({var.name: spec.shape for var in store.variables})
        check_arrays_readable(group, target, arrays, block_regions(spec.shape, store.chunks))
        return store

    def read(self, name: str) -> np.ndarray:
        return np.asarray(self.group[name][...])

    def done(self) -> np.ndarray:
        return np.asarray(self.group["done"][...], dtype=bool)

    def write_region(self, region: Region, result: Mapping[str, Any]) -> None:
        """Write one unit's flat results (C order of ``region``); ``done`` last."""
        shape = tuple(s.stop - s.start for s in region)
        for var in self.variables:
            if var.name != "done":
                self.group[var.name][region] = _as(result[var.name], var).reshape(shape)
        self.group["done"][region] = np.asarray(result["done"], dtype=bool).reshape(shape)


class ModelBoxStore:
    """A boxes store: one row per box of the refinement tree, preallocated to ``max_boxes`` rows."""

    def __init__(self, path: Path, group: Any, spec: ModelSweepSpec) -> None:
        assert spec.boxes is not None
        self.path = path
        self.group = group
        self.spec = spec
        self.capacity = spec.boxes.max_boxes
        self.variables = box_variables(spec.dims, spec.classes, spec.outputs)
        self.by_name = {v.name: v for v in self.variables}

    @classmethod
    def open_or_create(cls, path: str | Path, spec: ModelSweepSpec) -> "ModelBoxStore":
        assert spec.boxes is not None
        target = Path(path)
        rows = spec.boxes.max_boxes

        def build(staging: Path) -> None:
            import zarr

            group = zarr.open_group(str(staging), mode="w", zarr_format=3)
            group.attrs.update(_attrs(spec))
            for var in box_variables(spec.dims, spec.classes, spec.outputs):
                _create(group, var, (rows,), (min(BOX_CHUNK, rows),), [BOX_DIM])

        group = _open(target, spec, build)
        store = cls(target, group, spec)
        check_arrays_readable(group, target, {v.name: (rows,) for v in store.variables},
                              block_regions((rows,), (BOX_CHUNK,)))
        return store

    def read(self, name: str) -> np.ndarray:
        return np.asarray(self.group[name][...])

    def write_rows(self, rows: np.ndarray, values: Mapping[str, Any]) -> None:
        """Set ``values[name][j]`` at row ``rows[j]``, chunk by chunk: data first, ``done`` last."""
        rows = np.asarray(rows, dtype=np.int64)
        if rows.size == 0:
            return
        names = [n for n in values if n != "done" and n in self.by_name] + (["done"] if "done" in values else [])
        for key in np.unique(rows // BOX_CHUNK):
            region = slice(int(key) * BOX_CHUNK, min((int(key) + 1) * BOX_CHUNK, self.capacity))
            mask = rows // BOX_CHUNK == key
            local = rows[mask] - region.start
            for name in names:
                var = self.by_name[name]
                block = np.asarray(self.group[name][region])
                block[local] = _as(values[name], var)[mask]
                self.group[name][region] = block


def open_model_store(path: str | Path, spec: ModelSweepSpec) -> ModelPointStore | ModelBoxStore:
    """The store of ``spec`` at ``path``: created, or opened to resume (module docstring)."""
    if spec.mode == "boxes":
        return ModelBoxStore.open_or_create(path, spec)
    return ModelPointStore.open_or_create(path, spec)


__all__ = ["ModelPointStore", "ModelBoxStore", "open_model_store"]

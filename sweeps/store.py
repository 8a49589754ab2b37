"""The results store of every target: a Zarr v3 group that xarray opens as the Dataset of :mod:`sweeps.schema`.

Two layouts, whatever the target: a grid of points (:class:`GridStore`: one dimension per swept
parameter, one Zarr chunk per unit of work) and a table of boxes (:class:`TreeStore`: one row per
box of the refinement tree, preallocated to ``max_boxes`` rows). A target's store is one of them
with its variables (:mod:`sweeps.schema`), its attributes and its checks on resume: the paper's
:class:`Store` (points) and :class:`BoxStore`, a model file's :class:`ModelPointStore` and
:class:`ModelBoxStore` (which also check the model's SHA-256 and the layout).

Writing goes through zarr directly (one region per unit of work, from the main process only);
reading for users goes through xarray (:func:`open_results`). Properties the sweep relies on:

* **Atomic creation.** The group (metadata, coordinates, attributes) is built in a sibling
  directory and renamed into place, so a store either does not exist or is complete.
* **Atomic chunks.** zarr's local store writes each chunk file through a temporary file and a
  rename; a killed process leaves whole chunks, never torn ones. Each unit's region is one Zarr
  chunk of every variable, written data first and ``done`` last: a unit whose ``done`` is
  set has all its data on disk.
* **Determinism.** Metadata holds no timestamp or path; chunk bytes depend only on the values,
  so a resumed sweep ends byte-for-byte identical to an uninterrupted one.
* **Resume.** Opening an existing store checks that it was made from the same spec text and the
  same package versions (otherwise the results would mix two sweeps), reads every array once
  (:func:`check_arrays_readable`) and then reads ``done``.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
from importlib import metadata
from pathlib import Path
from typing import Any, Callable, Final, Mapping, Self, Sequence

import numpy as np

from lyapcheck.errors import InputFileError
from sweeps.schema import (
    BOX_DIM, BOXES_MODE, POINTS_MODE, STRING, SWEEPABLE, VARIABLES, Variable, box_variables, model_box_variables,
    point_variables,
)
from sweeps.spec import ModelSweepSpec, SweepSpec

#: packages whose versions can change a sweep's numbers (stored, and checked on resume)
VERSIONED_PACKAGES: Final = ("lyapcheck", "numpy", "scipy", "sympy", "cvxpy", "clarabel", "zarr", "xarray")
#: recorded in ``versions`` but not checked on resume: another floating-point platform (numpy's
#: SIMD loops, the OpenBLAS kernel) gives the same statuses and figures within lyapcheck.tolerances,
#: so a sweep started on one machine may be finished on another (a Dask cluster mixes them anyway)
RESUME_IGNORES: Final = ("floating_point",)
#: units of the coordinates (SI), stored as the coordinate's "units" attribute
COORD_UNITS: Final = {"alpha_d": "1/s", "sigma0": "1", "k_d": "1/s", "delta_los": "m", "d_max": "m/s"}

Region = tuple[slice, ...]
#: rows per Zarr chunk of a box store (the main process rewrites a whole chunk to update some of its rows)
BOX_CHUNK: Final = 256


def versions() -> dict[str, str]:
    """Versions of Python and of :data:`VERSIONED_PACKAGES`, and the floating-point platform
    (:func:`lyapcheck.numerics.describe`, for information only: :data:`RESUME_IGNORES`)."""
    from lyapcheck import numerics

    out = {"python": platform.python_version(), "floating_point": numerics.describe()}
    for name in VERSIONED_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:  # pragma: no cover - all are dependencies
            out[name] = "not installed"
    return out


def paper_point() -> dict[str, float]:
    """The paper's gain set (and d*) in SI, keyed like the sweep dimensions."""
    from lyapcheck.paper.simulation.scenarios import paper_problem

    p = paper_problem()
    g = p.gains
    return {"alpha_d": float(g.alpha_d), "sigma0": float(g.sigma0), "k_d": float(g.k_d),
            "delta_los": float(g.delta_los), "d_max": float(p.disturbance_bound())}


def chunk_shape(shape: Sequence[int], chunk_size: int) -> tuple[int, ...]:
    """A block of at most ``chunk_size`` points, filled from the last dimension backwards."""
    out = [1] * len(shape)
    room = max(chunk_size, 1)
    for i in range(len(shape) - 1, -1, -1):
        out[i] = max(1, min(shape[i], room))
        room //= out[i]
        if room <= 1:
            break
    return tuple(out)


def block_regions(shape: Sequence[int], chunks: Sequence[int]) -> list[Region]:
    """Every Zarr chunk of the grid as a region, in C order (the order units are handed out)."""
    counts = [-(-n // c) for n, c in zip(shape, chunks)]
    regions = []
    for idx in np.ndindex(*counts):
        regions.append(tuple(slice(i * c, min((i + 1) * c, n)) for i, c, n in zip(idx, chunks, shape)))
    return regions


def open_or_build(target: Path, spec: Any, build: Callable[[Path], None]) -> Any:
    """The zarr group at ``target``, created by ``build`` in a staging directory and renamed into
    place when it does not exist; an existing one must hold ``spec`` and these package versions.
    Shared by every store of every target."""
    import zarr

    if not target.exists():
        staging = target.with_name(f".{target.name}.creating")
        if staging.exists():  # left by a run killed while creating: never visible as a store
            shutil.rmtree(staging)
        target.parent.mkdir(parents=True, exist_ok=True)
        build(staging)
        os.replace(staging, target)
    try:
        group = zarr.open_group(str(target), mode="r+", zarr_format=3)
        attrs = dict(group.attrs)
    except Exception as exc:  # zarr raises several types for a foreign or corrupt directory
        raise InputFileError(f"'{target}' exists and is not a sweep store ({type(exc).__name__}); "
                             "choose another --out") from None
    if attrs.get("spec_toml") != spec.text:
        raise InputFileError(f"'{target}' holds a sweep of a different spec; choose another --out or remove it")
    stored = json.loads(str(attrs.get("versions", "{}")))
    now = versions()
    changed = sorted(k for k in set(stored) | set(now) if stored.get(k) != now.get(k) and k not in RESUME_IGNORES)
    if changed:
        raise InputFileError(f"'{target}' was written with other package versions ({', '.join(changed)}); "
                             "resuming would mix results: choose another --out")
    return group


def check_arrays_readable(group: Any, path: Path, arrays: Mapping[str, tuple[int, ...]],
                          regions: Sequence[Region]) -> None:
    """Read every array of ``arrays`` (name -> expected shape) once, region by region.

    A store damaged on disk (a truncated or deleted chunk or metadata file) would otherwise be
    resumed silently: a missing chunk reads as its fill value (so ``done`` is false and the
    points are recomputed, which is fine), but a truncated one raises deep inside zarr in the
    middle of a run, and a damaged data chunk of a finished unit would stay in the results.
    Reading costs one pass over the store and memory of one region at a time. Arrays of one
    dimension are read whole (coordinates); the others region by region.
    """
    for name, expected in arrays.items():
        try:
            array = group[name]
            if tuple(array.shape) != tuple(expected):
                raise ValueError(f"shape {tuple(array.shape)}, expected {tuple(expected)}")
            for region in regions if len(expected) == len(regions[0]) else [(slice(None),)]:
                array[region]
        except Exception as exc:  # zarr and its codecs raise many types for damaged bytes
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputFileError(f"'{path}' is damaged and cannot be resumed: array '{name}' is unreadable "
                                 f"({detail[:120]}); remove it or choose another --out") from None


def _create(group: Any, var: Variable, shape: tuple[int, ...], chunks: tuple[int, ...], dims: list[str]) -> None:
    group.create_array(var.name, shape=shape, dtype=var.dtype, chunks=chunks, dimension_names=dims,
                       fill_value=var.fill, attributes={"description": var.description})


def _as(values: Any, var: Variable) -> np.ndarray:
    if var.dtype == STRING:
        return np.asarray([str(v) for v in np.asarray(values, dtype=object).ravel()], dtype=STRING)
    return np.asarray(values, dtype=var.dtype)


class _StoreLayout:
    """What both layouts share: the store's place, its group, its spec and its variables (which a
    target's store says), and how the group is opened."""

    def __init__(self, path: Path, group: Any, spec: Any) -> None:
        self.path = path
        self.group = group
        self.spec = spec
        self.variables = self.variables_of(spec)
        self.by_name = {v.name: v for v in self.variables}

    # -- what a target says -----------------------------------------------------------------------
    @classmethod
    def variables_of(cls, spec: Any) -> tuple[Variable, ...]:
        raise NotImplementedError

    @classmethod
    def attrs_of(cls, spec: Any) -> dict[str, Any]:
        raise NotImplementedError

    @classmethod
    def open_group(cls, target: Path, spec: Any, build: Callable[[Path], None]) -> Any:
        """The group, created or checked for resuming (:func:`open_or_build`)."""
        return open_or_build(target, spec, build)


class GridStore(_StoreLayout):
    """A grid of points: every variable over the swept parameters, one coordinate each (module
    docstring). A target's store says which variables, attributes and coordinate attributes."""

    def __init__(self, path: Path, group: Any, spec: Any) -> None:
        super().__init__(path, group, spec)
        self.chunks = chunk_shape(spec.shape, spec.chunk_size)

    @classmethod
    def coord_attributes(cls, axis: Any) -> dict[str, Any]:
        raise NotImplementedError

    # -- the layout -----------------------------------------------------------------------------
    @classmethod
    def open_or_create(cls, path: str | Path, spec: Any) -> Self:
        """Open ``path`` to resume, or create it; refuse a store made from another spec."""
        target = Path(path)

        def build(staging: Path) -> None:
            import zarr

            group = zarr.open_group(str(staging), mode="w", zarr_format=3)
            group.attrs.update(cls.attrs_of(spec))
            for axis in spec.axes:
                coord = group.create_array(axis.name, shape=(axis.size,), dtype="float64", chunks=(axis.size,),
                                           dimension_names=[axis.name], fill_value=np.nan,
                                           attributes=cls.coord_attributes(axis))
                coord[:] = np.asarray(axis.values, dtype=np.float64)
            chunks = chunk_shape(spec.shape, spec.chunk_size)
            for var in cls.variables_of(spec):
                _create(group, var, tuple(spec.shape), chunks, list(spec.dims))

        group = cls.open_group(target, spec, build)
        store = cls(target, group, spec)
        store.check_readable()
        return store

    def check_readable(self) -> None:
        """Read every array once before resuming (:func:`check_arrays_readable`)."""
        arrays: dict[str, tuple[int, ...]] = {axis.name: (axis.size,) for axis in self.spec.axes}
        arrays.update({var.name: tuple(self.spec.shape) for var in self.variables})
        check_arrays_readable(self.group, self.path, arrays, block_regions(self.spec.shape, self.chunks))

    def read(self, name: str) -> np.ndarray:
        return np.asarray(self.group[name][...])

    def done(self) -> np.ndarray:
        """The ``done`` flags of every point (a bool array of the grid's shape)."""
        return np.asarray(self.group["done"][...], dtype=bool)

    def region_done(self, region: Region) -> bool:
        return bool(np.all(self.group["done"][region]))

    def write_region(self, region: Region, result: Mapping[str, Any]) -> None:
        """Write one unit's flat results (C order of ``region``); ``done`` last."""
        shape = tuple(s.stop - s.start for s in region)
        for var in self.variables:
            if var.name != "done":
                self.group[var.name][region] = _as(result[var.name], var).reshape(shape)
        self.group["done"][region] = np.asarray(result["done"], dtype=bool).reshape(shape)

    def write_points(self, index: np.ndarray, result: Mapping[str, np.ndarray]) -> None:
        """Write scattered points (integer grid indices, shape ``(n, ndim)``), chunk by chunk.

        Each touched Zarr chunk is read, updated and written back whole (data first, ``done``
        last), so every chunk file on disk stays a consistent state of the sweep.
        """
        chunks = np.asarray(self.chunks)
        keys = index // chunks
        order = np.lexsort(keys.T[::-1])
        index, keys = index[order], keys[order]
        values = {name: np.asarray(arr)[order] for name, arr in result.items()}
        boundaries = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
        for rows in np.split(np.arange(len(index)), boundaries):
            if rows.size == 0:
                continue
            key = keys[rows[0]]
            region = tuple(slice(int(k * c), int(min((k + 1) * c, n)))
                           for k, c, n in zip(key, chunks, self.spec.shape))
            local = tuple((index[rows] - np.array([r.start for r in region])).T)
            for var in self.variables:
                if var.name == "done":
                    continue
                block = np.asarray(self.group[var.name][region])
                block[local] = values[var.name][rows]
                self.group[var.name][region] = block
            block = np.asarray(self.group["done"][region])
            block[local] = values["done"][rows]
            self.group["done"][region] = block


class TreeStore(_StoreLayout):
    """A table of boxes: one row per box of the refinement tree (:func:`sweeps.run.run_box_tree`),
    preallocated to the spec's ``max_boxes`` rows (module docstring)."""

    def __init__(self, path: Path, group: Any, spec: Any) -> None:
        assert spec.boxes is not None
        super().__init__(path, group, spec)
        self.capacity = spec.boxes.max_boxes

    @classmethod
    def open_or_create(cls, path: str | Path, spec: Any) -> Self:
        """Open ``path`` to resume, or create it; refuse a store made from another spec."""
        assert spec.boxes is not None
        target = Path(path)
        rows = spec.boxes.max_boxes

        def build(staging: Path) -> None:
            import zarr

            group = zarr.open_group(str(staging), mode="w", zarr_format=3)
            group.attrs.update(cls.attrs_of(spec))
            for var in cls.variables_of(spec):
                _create(group, var, (rows,), (min(BOX_CHUNK, rows),), [BOX_DIM])

        group = cls.open_group(target, spec, build)
        store = cls(target, group, spec)
        check_arrays_readable(group, target, {v.name: (rows,) for v in store.variables},
                              block_regions((rows,), (BOX_CHUNK,)))
        return store

    def read(self, name: str) -> np.ndarray:
        return np.asarray(self.group[name][...])

    def write_rows(self, rows: np.ndarray, values: Mapping[str, Any]) -> None:
        """Set ``values[name][j]`` at row ``rows[j]`` for every stored variable of ``values``, chunk
        by chunk: data first, ``done`` last.

        Each touched chunk is read, updated and written back whole, so every chunk file on disk
        is a consistent state of the sweep (zarr writes a chunk through a temporary file).
        """
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


# -- the paper's model ----------------------------------------------------------------------------
def _paper_attrs(spec: SweepSpec) -> dict[str, Any]:
    return {"spec_toml": spec.text, "versions": json.dumps(versions(), sort_keys=True),
            "paper_point": json.dumps(paper_point(), sort_keys=True)}


class Store(GridStore):
    """The paper's points store: every variable of :data:`sweeps.schema.VARIABLES` over the grid."""

    spec: SweepSpec

    @classmethod
    def variables_of(cls, spec: Any) -> tuple[Variable, ...]:
        return VARIABLES

    @classmethod
    def attrs_of(cls, spec: Any) -> dict[str, Any]:
        return _paper_attrs(spec)

    @classmethod
    def coord_attributes(cls, axis: Any) -> dict[str, Any]:
        return {"units": COORD_UNITS[axis.name], "scale": axis.scale, "parameter": SWEEPABLE[axis.name]}


class BoxStore(TreeStore):
    """The paper's box store (``mode = "boxes"``): :func:`sweeps.schema.box_variables`; attributes
    ``mode``, ``spec_toml``, ``versions``, ``paper_point``, ``dims``, ``classes`` and ``axis_scales``."""

    spec: SweepSpec

    @classmethod
    def variables_of(cls, spec: Any) -> tuple[Variable, ...]:
        return box_variables(spec.dims, spec.classes)

    @classmethod
    def attrs_of(cls, spec: Any) -> dict[str, Any]:
        return {"mode": "boxes", **_paper_attrs(spec), "dims": json.dumps(list(spec.dims)),
                "classes": json.dumps(list(spec.classes)),
                "axis_scales": json.dumps({a.name: a.scale for a in spec.axes})}


# -- a model file ---------------------------------------------------------------------------------
def _model_attrs(spec: ModelSweepSpec) -> dict[str, Any]:
    return {"mode": POINTS_MODE if spec.mode == "points" else BOXES_MODE, "spec_toml": spec.text,
            "model_toml": spec.model_text, "model_file": spec.model_file, "model_sha256": spec.model_sha256,
            "model_name": spec.model.name,
            "versions": json.dumps(versions(), sort_keys=True), "dims": json.dumps(list(spec.dims)),
            "classes": json.dumps(list(spec.classes)), "outputs": json.dumps(list(spec.outputs)),
            "axis_scales": json.dumps({a.name: a.scale for a in spec.axes})}


def _open_model_group(path: Path, spec: ModelSweepSpec, build: Callable[[Path], None]) -> Any:
    """:func:`open_or_build`, then a model sweep's checks: the layout, and the model's SHA-256 (the
    model file may have changed since; every certificate would then be of another model)."""
    group = open_or_build(path, spec, build)
    attrs = dict(group.attrs)
    expected = _model_attrs(spec)["mode"]
    if attrs.get("mode") != expected:
        raise InputFileError(f"'{path}' is a store of another kind ({attrs.get('mode', 'a paper sweep')}); choose "
                             "another --out")
    if attrs.get("model_sha256") != spec.model_sha256:
        raise InputFileError(f"'{path}' was computed from another text of the model file {spec.model_file} (SHA-256 "
                             f"{str(attrs.get('model_sha256'))[:12]}..., now {spec.model_sha256[:12]}...); resuming "
                             "would mix two models: choose another --out")
    return group


class _ModelFileStore(_StoreLayout):
    """What both layouts of a model file's store say alike: their attributes (:func:`_model_attrs`) and
    the checks of a store opened to resume (:func:`_open_model_group`)."""

    @classmethod
    def attrs_of(cls, spec: Any) -> dict[str, Any]:
        return _model_attrs(spec)

    @classmethod
    def open_group(cls, target: Path, spec: Any, build: Callable[[Path], None]) -> Any:
        return _open_model_group(target, spec, build)


class ModelPointStore(_ModelFileStore, GridStore):
    """A model file's points store (:func:`sweeps.schema.point_variables`). Certificates are stored
    without their solver logs (wall times), so a resumed sweep ends byte-for-byte identical."""

    spec: ModelSweepSpec

    @classmethod
    def variables_of(cls, spec: Any) -> tuple[Variable, ...]:
        return point_variables(spec.classes, spec.outputs, spec.discrete)

    @classmethod
    def coord_attributes(cls, axis: Any) -> dict[str, Any]:
        return {"scale": axis.scale, "parameter": axis.name, "units": "SI (as the model file reads its parameters)"}


class ModelBoxStore(_ModelFileStore, TreeStore):
    """A model file's boxes store (:func:`sweeps.schema.model_box_variables`)."""

    spec: ModelSweepSpec

    @classmethod
    def variables_of(cls, spec: Any) -> tuple[Variable, ...]:
        return model_box_variables(spec.dims, spec.classes, spec.outputs, spec.discrete)


def open_model_store(path: str | Path, spec: ModelSweepSpec) -> ModelPointStore | ModelBoxStore:
    """The store of ``spec`` at ``path``: created, or opened to resume."""
    if spec.mode == "boxes":
        return ModelBoxStore.open_or_create(path, spec)
    return ModelPointStore.open_or_create(path, spec)


def open_results(path: str | Path) -> Any:
    """The store as an ``xarray.Dataset`` (lazy, dask-backed).

    Zarr v3 has no consolidated metadata in its specification (zarr warns when asked for it), so
    the store has none and is opened without.
    """
    import xarray as xr

    target = Path(path)
    if not (target / "zarr.json").exists():
        raise InputFileError(f"'{target}' is not a sweep store (no zarr.json)")
    return xr.open_zarr(str(target), consolidated=False)

"""The results store: a Zarr v3 group that xarray opens as the Dataset of :mod:`sweeps.schema`.

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
  same package versions (otherwise the results would mix two sweeps) and then reads ``done``.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
from importlib import metadata
from pathlib import Path
from typing import Any, Callable, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import InputFileError
from sweeps.schema import SWEEPABLE, VARIABLES
from sweeps.spec import SweepSpec

#: packages whose versions can change a sweep's numbers (stored, and checked on resume)
VERSIONED_PACKAGES: Final = ("lyapcheck", "numpy", "scipy", "sympy", "cvxpy", "clarabel", "zarr", "xarray")
#: recorded in ``versions`` but not checked on resume: another floating-point platform (numpy's
#: SIMD loops, the OpenBLAS kernel) gives the same statuses and figures within lyapcheck.tolerances,
#: so a sweep started on one machine may be finished on another (a Dask cluster mixes them anyway)
RESUME_IGNORES: Final = ("floating_point",)
#: units of the coordinates (SI), stored as the coordinate's "units" attribute
COORD_UNITS: Final = {"alpha_d": "1/s", "sigma0": "1", "k_d": "1/s", "delta_los": "m", "d_max": "m/s"}

Region = tuple[slice, ...]


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
    from lyapcheck.simulation.scenarios import paper_problem

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


def _attrs(spec: SweepSpec) -> dict[str, Any]:
    return {"spec_toml": spec.text, "versions": json.dumps(versions(), sort_keys=True),
            "paper_point": json.dumps(paper_point(), sort_keys=True)}


def _build(path: Path, spec: SweepSpec) -> None:
    import zarr

    group = zarr.open_group(str(path), mode="w", zarr_format=3)
    group.attrs.update(_attrs(spec))
    dims = list(spec.dims)
    for axis in spec.axes:
        coord = group.create_array(axis.name, shape=(axis.size,), dtype="float64", chunks=(axis.size,),
                                   dimension_names=[axis.name], fill_value=np.nan,
                                   attributes={"units": COORD_UNITS[axis.name], "scale": axis.scale,
                                               "parameter": SWEEPABLE[axis.name]})
        coord[:] = np.asarray(axis.values, dtype=np.float64)
    chunks = chunk_shape(spec.shape, spec.chunk_size)
    for var in VARIABLES:
        group.create_array(var.name, shape=spec.shape, dtype=var.dtype, chunks=chunks, dimension_names=dims,
                           fill_value=var.fill, attributes={"description": var.description})


def open_or_build(target: Path, spec: SweepSpec, build: Callable[[Path], None]) -> Any:
    """The zarr group at ``target``, created by ``build`` in a staging directory and renamed into
    place when it does not exist; an existing one must hold ``spec`` and these package versions.
    Shared by the point store and the box store (:mod:`sweeps.box_store`)."""
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


class Store:
    """An open results store (see the module docstring)."""

    def __init__(self, path: Path, group: Any, spec: SweepSpec) -> None:
        self.path = path
        self.group = group
        self.spec = spec
        self.chunks = chunk_shape(spec.shape, spec.chunk_size)

    @classmethod
    def open_or_create(cls, path: str | Path, spec: SweepSpec) -> "Store":
        """Open ``path`` to resume, or create it; refuse a store made from another spec."""
        target = Path(path)
        group = open_or_build(target, spec, lambda staging: _build(staging, spec))
        store = cls(target, group, spec)
        store.check_readable()
        return store

    def check_readable(self) -> None:
        """Read every array once before resuming (:func:`check_arrays_readable`)."""
        arrays: dict[str, tuple[int, ...]] = {axis.name: (axis.size,) for axis in self.spec.axes}
        arrays.update({var.name: tuple(self.spec.shape) for var in VARIABLES})
        check_arrays_readable(self.group, self.path, arrays, block_regions(self.spec.shape, self.chunks))

    def done(self) -> np.ndarray:
        """The ``done`` flags of every point (a bool array of the grid's shape)."""
        return np.asarray(self.group["done"][...], dtype=bool)

    def region_done(self, region: Region) -> bool:
        return bool(np.all(self.group["done"][region]))

    def write_region(self, region: Region, result: Mapping[str, np.ndarray]) -> None:
        """Write one unit's flat results (C order of ``region``); ``done`` last."""
        shape = tuple(s.stop - s.start for s in region)
        for var in VARIABLES:
            if var.name != "done":
                self.group[var.name][region] = np.asarray(result[var.name], dtype=var.dtype).reshape(shape)
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
            for var in VARIABLES:
                if var.name == "done":
                    continue
                block = np.asarray(self.group[var.name][region])
                block[local] = values[var.name][rows]
                self.group[var.name][region] = block
            block = np.asarray(self.group["done"][region])
            block[local] = values["done"][rows]
            self.group["done"][region] = block


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

"""Export a sweep store to NetCDF or CSV.

NetCDF goes through xarray (``netCDF4`` or ``h5netcdf`` when installed, else SciPy's NetCDF-3
writer, which stores booleans as int8 with a ``dtype: bool`` attribute that xarray restores).
CSV has one row per computed point (``done``), the coordinates first, written block by block
along the first dimension so that memory does not grow with the grid.
"""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import numpy as np

from lyapcheck.errors import InvalidParameter
from sweeps.schema import VARIABLES
from sweeps.store import open_results

EXPORT_SUFFIXES = (".nc", ".csv")


def _netcdf_engine() -> str:
    for engine, module in (("netcdf4", "netCDF4"), ("h5netcdf", "h5netcdf")):
        if importlib.util.find_spec(module) is not None:
            return engine
    return "scipy"


def export(store_path: str | Path, target: str | Path) -> Path:
    """Write the store at ``store_path`` to ``target`` (``.nc`` or ``.csv``, by suffix)."""
    out = Path(target)
    suffix = out.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise InvalidParameter("export", "a file name ending in .nc or .csv", str(target))
    out.parent.mkdir(parents=True, exist_ok=True)
    ds = open_results(store_path)
    if suffix == ".nc":
        ds.load().to_netcdf(out, engine=_netcdf_engine())
        return out
    dims = list(ds.sizes)
    names = [v.name for v in VARIABLES]
    block = max(1, int(ds.chunks[dims[-1]][0])) if dims and ds.chunks else 1
    with out.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(dims + names)
        first = dims[0]
        for start in range(0, ds.sizes[first], block if len(dims) == 1 else 1):
            stop = min(start + (block if len(dims) == 1 else 1), ds.sizes[first])
            part = ds.isel({first: slice(start, stop)}).load()
            done = part["done"].values.ravel()
            if not done.any():
                continue
            mesh = np.meshgrid(*[part[d].values for d in dims], indexing="ij")
            cols = [m.ravel()[done] for m in mesh] + [part[n].values.ravel()[done] for n in names]
            for row in zip(*cols):
                writer.writerow([repr(float(x)) if isinstance(x, (float, np.floating)) else
                                 (int(x) if isinstance(x, (np.integer, np.bool_, bool)) else x) for x in row])
    return out

"""The store of a model sweep: variable names, dtypes, fill values and status codes.

The contract between :mod:`sweeps.model_store` (which writes) and :mod:`reports.model_sweep_page`
(which renders). Two layouts, told apart by the ``mode`` attribute:

* ``model_points``: one dimension per swept parameter, named after it, with its SI values as
  the coordinate; every variable below over those dimensions.
* ``model_boxes``: one dimension ``box`` (a row per box of the refinement tree), with the box's
  edges ``lo_<p>``, ``hi_<p>`` (SI), its ``level`` and ``parent``, and ``unstable_corners`` (how
  many of its corners have an exactly unstable equilibrium; -1 when no stability class was asked)
  besides the variables below.

Variables (``<c>`` a class of the sweep, ``<y>`` an output of the model):

* ``status`` int8: 1 certified (a class proved its property for the point, or for every point
  of the box), 2 refuted (the equilibrium is proved unstable, exactly, at the point or at a
  corner of the box: no stability class can hold there), 0 not certified, 3 split (boxes: halved
  further), -1 not computed;
* ``status_<c>`` int8: each class's own status (:data:`sweeps.schema.STATUS_CODES`: 0
  not_certified, 1 certified, 2 refuted, 3 inconclusive, 4 not_applicable; -1 not computed);
* the key figures, NaN where the class did not certify: ``quadratic_decay_rate_V_per_s``,
  ``quadratic_k`` and ``quadratic_decay_rate_per_s`` (GES: ``|x| <= k |x0| exp(-rate t)``),
  ``sos_gas_decay_rate_V_per_s``, ``roa_level`` and ``roa_ball_radius`` (the certified set
  ``{V <= level}`` and the largest ball in it, SI), ``sos_bound_<y>`` (the certified
  ``limsup |y|``, in the output's SI units);
* ``certificate`` (string): the certificate document (JSON, kind
  ``lyapcheck-model-certificate``, its ``solver`` logs left out) of every certified point or box,
  empty elsewhere: ``lyapcheck verify`` re-checks it exactly;
* ``note`` (string): why the status is what it is, in one line;
* the simulation cross-check (:mod:`sweeps.model_crosscheck`): ``cross_check_points`` (parameter
  points simulated), ``cross_check_trajectories``, ``cross_check_worst_rise`` (largest rise of a
  certified V along a trajectory, relative to V(0)), ``cross_check_worst_envelope`` (largest excess
  of V over its certified decay envelope), ``cross_check_ges_ratio`` (largest
  ``|x(t)| / (k |x0| exp(-rate t))``), ``cross_check_not_converged`` (trajectories not at the
  equilibrium by the end of the horizon: a figure, not a violation), and with ``sos_bound``
  ``sim_worst_<y>`` (the worst-case search's largest tail sup of ``|y|``) and ``tightness_<y>``
  (certified bound / that);
* ``soundness_violation`` bool and ``violation_detail`` (string): a simulated trajectory left a
  certified set, envelope or bound;
* ``done`` bool, written last.

Attributes: ``mode``, ``spec_toml`` (the spec as given), ``model_toml`` (the model file verbatim),
``model_file``, ``model_sha256``, ``versions``, ``dims``, ``classes``, ``outputs`` and
``axis_scales`` (JSON text).
"""

from __future__ import annotations

import json
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck.errors import InputFileError
from sweeps.schema import BOX_DIM, NOT_COMPUTED, Variable

POINTS_MODE: Final = "model_points"
BOXES_MODE: Final = "model_boxes"
MODES: Final = (POINTS_MODE, BOXES_MODE)
#: a variable-length UTF-8 string (zarr v3's vlen-utf8 codec)
STRING: Final = np.dtypes.StringDType()
#: the key figures of each class: (variable suffix, the class's number, description)
FIGURES: Final[dict[str, tuple[tuple[str, str, str], ...]]] = {
    "quadratic": (("decay_rate_V_per_s", "decay_rate_V_per_s", "certified decay rate of V: V' <= -rate V, 1/s"),
                  ("k", "k", "GES constant: |x(t)| <= k |x0| exp(-rate t)"),
                  ("decay_rate_per_s", "decay_rate_per_s", "GES decay rate of |x|, 1/s")),
    "sos_gas": (("decay_rate_V_per_s", "decay_rate_V_per_s", "certified decay rate of V: V' <= -rate V, 1/s"),),
    "roa": (("level", "level", "the certified region of attraction is {V <= level}"),
            ("ball_radius", "ball_radius", "largest ball |x - x_eq| <= r certified inside it, SI")),
}


def _figures(classes: Sequence[str], outputs: Sequence[str]) -> list[Variable]:
    f8 = np.dtype("float64")
    out = [Variable(f"{c}_{suffix}", f8, np.nan, f"{c}: {text} (NaN: not certified)")
           for c in classes for suffix, _, text in FIGURES.get(c, ())]
    if "sos_bound" in classes:
        out += [Variable(f"sos_bound_{y}", f8, np.nan, f"sos_bound: limsup |{y}| <= this, SI (NaN: not certified)")
                for y in outputs]
    return out


def _common(classes: Sequence[str], outputs: Sequence[str], what: str) -> list[Variable]:
    i8, i16, i32, f8, b1 = (np.dtype(t) for t in ("int8", "int16", "int32", "float64", "bool"))
    out = [Variable("status", i8, NOT_COMPUTED, "1 certified, 2 refuted (unstable, exactly), 0 not certified, "
                    "3 split, -1 not computed")]
    out += [Variable(f"status_{c}", i8, NOT_COMPUTED, f"{c} over the {what}: 0 not_certified, 1 certified, 2 refuted, "
                     "3 inconclusive, 4 not_applicable, -1 not computed") for c in classes]
    out += _figures(classes, outputs)
    out += [
        Variable("certificate", STRING, "", "the certificate document (JSON) of a certified " + what
                 + "; verify re-checks it"),
        Variable("note", STRING, "", "why the status is what it is"),
        Variable("cross_check_points", i16, 0, "parameter points simulated against the certificate"),
        Variable("cross_check_trajectories", i32, 0, "trajectories simulated"),
        Variable("cross_check_worst_rise", f8, np.nan, "largest rise of a certified V along a trajectory, of V(0)"),
        Variable("cross_check_worst_envelope", f8, np.nan, "largest excess of V over V(0) exp(-rate t), of V(0)"),
        Variable("cross_check_ges_ratio", f8, np.nan, "largest |x(t) - x_eq| / (k |x0 - x_eq| exp(-rate t))"),
        Variable("cross_check_not_converged", i32, 0, "trajectories not at the equilibrium by the horizon"),
    ]
    if "sos_bound" in classes:
        for y in outputs:
            out.append(Variable(f"sim_worst_{y}", f8, np.nan, f"worst-case search: largest tail sup of |{y}|, SI"))
            out.append(Variable(f"tightness_{y}", f8, np.nan, f"sos_bound_{y} / sim_worst_{y}"))
    out += [
        Variable("soundness_violation", b1, False, "a simulated trajectory left a certified set, envelope or bound"),
        Variable("violation_detail", STRING, "", "what the simulation contradicted"),
        Variable("done", b1, False, f"this {what} was computed and stored"),
    ]
    return out


def point_variables(classes: Sequence[str], outputs: Sequence[str]) -> tuple[Variable, ...]:
    """Every variable of a points store, in a fixed order (``done`` last)."""
    return tuple(_common(classes, outputs, "point"))


def box_variables(dims: Sequence[str], classes: Sequence[str], outputs: Sequence[str]) -> tuple[Variable, ...]:
    """Every variable of a boxes store: the box's edges and place in the tree, then the common ones."""
    f8, i16, i32 = np.dtype("float64"), np.dtype("int16"), np.dtype("int32")
    out: list[Variable] = []
    for d in dims:
        out.append(Variable(f"lo_{d}", f8, np.nan, f"lower edge of the box in {d} (SI)"))
        out.append(Variable(f"hi_{d}", f8, np.nan, f"upper edge of the box in {d} (SI)"))
    out += [Variable("level", i16, -1, "refinement depth (0: a cell of the axes' grid)"),
            Variable("parent", i32, -1, "row of the box this one is a half of (-1: none)"),
            Variable("unstable_corners", np.dtype("int8"), -1, "corners of the box where the equilibrium is proved "
                     "unstable (linearization refuted, exactly); -1 not checked")]
    return tuple(out + _common(classes, outputs, "box"))


def is_model_dataset(ds: Any) -> bool:
    """A model sweep's store (either layout)."""
    return str(getattr(ds, "attrs", {}).get("mode", "")) in MODES


def json_list(ds: Any, key: str) -> tuple[str, ...]:
    """A JSON list attribute as names (InputFileError naming it otherwise)."""
    try:
        value = json.loads(str(ds.attrs.get(key)))
    except (TypeError, ValueError):
        value = None
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputFileError(f"the model sweep store's '{key}' attribute is not a JSON list of names")
    return tuple(value)


def check_model_dataset(ds: Any, source: str) -> None:
    """Check a loaded model sweep store (an xarray Dataset) against this schema, before anything reads it."""
    def bad(what: str) -> InputFileError:
        return InputFileError(f"'{source}' is not a model sweep store this lyapcheck reads: {what}")

    try:
        dims, classes, outputs = (json_list(ds, k) for k in ("dims", "classes", "outputs"))
    except InputFileError as exc:
        raise bad(str(exc)) from None
    if not 1 <= len(dims) <= 3:
        raise bad(f"dims {list(dims)}, expected one to three parameters")
    for key in ("spec_toml", "model_toml", "model_sha256"):
        if not isinstance(ds.attrs.get(key), str):
            raise bad(f"no '{key}' attribute")
    if ds.attrs["mode"] == BOXES_MODE:
        if tuple(map(str, ds.dims)) != (BOX_DIM,):
            raise bad(f"dimensions {list(map(str, ds.dims))}, expected ['{BOX_DIM}']")
        variables = box_variables(dims, classes, outputs)
        expected: tuple[str, ...] = (BOX_DIM,)
    else:
        if set(map(str, ds.dims)) != set(dims):
            raise bad(f"dimensions {list(map(str, ds.dims))}, expected {list(dims)}")
        for d in dims:
            values = np.asarray(ds.coords[d].values) if d in ds.coords else np.zeros(0)
            if values.ndim != 1 or values.dtype.kind != "f" or not np.all(np.isfinite(values)) \
                    or np.any(np.diff(values) <= 0):
                raise bad(f"coordinate '{d}' is not a finite, strictly increasing list of numbers")
        variables, expected = point_variables(classes, outputs), dims
    for var in variables:
        if var.name not in ds.data_vars:
            raise bad(f"no variable '{var.name}'")
        data = ds[var.name]
        same = data.dtype == var.dtype or (var.dtype == STRING and data.dtype.kind in ("T", "U", "O"))
        if not same or tuple(map(str, data.dims)) != tuple(expected):
            raise bad(f"variable '{var.name}' is {data.dtype} over {list(map(str, data.dims))}, expected {var.dtype} "
                      f"over {list(expected)}")

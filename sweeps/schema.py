"""The sweep store's schema: variable names, dtypes, fill values and status codes.

This is the contract between :mod:`sweeps` (which writes a store) and ``reports`` (which
renders one). One place says what every variable means; nothing else hard-codes a name.

Layout (an xarray Dataset in a Zarr v3 store):

* dimensions: the swept parameter names, 1 to 3 of :data:`SWEEPABLE`, in the spec's order;
  one coordinate per dimension, in SI (``alpha_d`` and ``k_d`` in 1/s, ``delta_los`` in m,
  ``d_max`` in m/s, ``sigma0`` dimensionless);
* ``status_<class>`` int8 per condition class of :data:`CLASSES` (:data:`STATUS_CODES`;
  ``-1`` not computed; for ``stabcond2`` 1 holds, 0 fails);
* ``margin_<class>`` float64 (NaN when the class has no margin at that point, see
  :data:`MARGIN_SOURCE`);
* ``eps_bound_m`` certified ultimate bound on ``|eps|``: the smallest of those certified by
  ``ultimate_bound`` and ``sos_bound`` (NaN where none);
* ``sim_eps_sup_m`` simulated ultimate bound: the largest tail sup of ``|eps|`` over the
  disturbance scenarios (not over ``nominal``, the divergence probe), and
  ``sim_eps_sup_m_<scenario>`` per scenario of :data:`SCENARIOS`;
* ``ratio_certified_over_simulated`` = ``eps_bound_m / sim_eps_sup_m``;
* ``sim_diverged``, ``soundness_violation``, ``done`` (bool);
* attributes ``spec_toml`` (the spec as given), ``versions`` (JSON text) and
  ``paper_point`` (JSON text: the paper's gains in SI, keyed like the dimensions).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from lyapcheck.paper.conditions import base as _base
from lyapcheck.errors import InputFileError

#: parameters a sweep may vary, mapped to their key in :data:`lyapcheck.paper.params.FIELDS`
SWEEPABLE: Final[dict[str, str]] = {
    "alpha_d": "gains.alpha_d",
    "sigma0": "gains.sigma0",
    "k_d": "gains.k_d",
    "delta_los": "gains.delta_los",
    "d_max": "disturbance.d_max",
}

#: condition classes a sweep can run, in the order of :data:`lyapcheck.paper.certification.CONDITION_ORDER`
#: (a test keeps the two equal; spelled out here so that reading a store needs no solver import)
CLASSES: Final = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound",
                  "sos_gas", "ges", "saturated_loop", "sos_bound")
#: run when the spec does not say: lyapcheck.paper.certification.QUICK_CLASSES (the polynomial classes
#: sos_gas, ges, saturated_loop and sos_bound cost 0.1-3 s per point)
DEFAULT_CLASSES: Final = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound")
#: classes whose exact pass proves stability of the error dynamics (lyapcheck.paper.conditions.base)
STABILITY_CLASSES: Final = _base.STABILITY_CLASSES
#: classes that certify an ultimate bound on |eps| (numbers["eps_bound_m"]); eps_bound_m is the
#: smallest certified one
BOUND_CLASSES: Final = ("ultimate_bound", "sos_bound")

NOT_COMPUTED: Final = -1
STATUS_CODES: Final[dict[str, int]] = {
    "not_certified": 0, "certified": 1, "refuted": 2, "inconclusive": 3,
    "fails": 0, "holds": 1,  # stabcond2 is plain arithmetic
    "not_applicable": 4, "counterexample": 5,
}

#: where each class's margin comes from (``numbers`` key of its ConditionResult); stabcond2's
#: margin is ``1 - lhs`` (positive when it holds); None: the class has no margin
MARGIN_SOURCE: Final[dict[str, str | None]] = {
    "prop41_ges": "relative_margin", "prop41_iss": "relative_margin", "stabcond2": "lhs_value",
    "sector_ges": "relative_margin", "switched_ges": None, "ultimate_bound": None, "sos_gas": "relative_margin",
    "ges": None, "saturated_loop": None, "sos_bound": None,
}

#: simulation scenarios: ``nominal`` (no disturbance, started off the path) probes divergence;
#: the others are disturbance scenarios, all with ``|d_perp| <= d*``; ``worst_case`` (opt-in, about
#: 8 s a point) is the worst-case disturbance search of ``simulate --worst-case`` started on the
#: path, so that ``ratio_certified_over_simulated`` is the tightness ratio of the certified bound
SCENARIOS: Final = ("nominal", "constant", "weight", "adversarial", "worst_case")
DISTURBANCE_SCENARIOS: Final = ("constant", "weight", "adversarial", "worst_case")
#: run when the spec does not say
DEFAULT_SCENARIOS: Final = ("nominal", "constant", "weight", "adversarial")


@dataclass(frozen=True)
class Variable:
    """One data variable of the store."""

    name: str
    dtype: np.dtype
    fill: object
    description: str


def variables() -> tuple[Variable, ...]:
    """Every data variable, in a fixed order (coordinates excluded)."""
    i8, f8, b1 = np.dtype("int8"), np.dtype("float64"), np.dtype("bool")
    out: list[Variable] = []
    for c in CLASSES:
        out.append(Variable(f"status_{c}", i8, NOT_COMPUTED,
                            f"{c}: 0 not_certified, 1 certified, 2 refuted, 3 inconclusive, -1 not computed"
                            + (" (1 holds, 0 fails)" if c == "stabcond2" else "")))
    for c in CLASSES:
        out.append(Variable(f"margin_{c}", f8, np.nan, f"{c}: margin behind the status (NaN: none)"))
    out.append(Variable("eps_bound_m", f8, np.nan, "certified ultimate bound on |eps| (smallest certified), m"))
    out.append(Variable("sim_eps_sup_m", f8, np.nan,
                        "simulated ultimate bound: max over disturbance scenarios of the tail sup of |eps|, m"))
    for s in SCENARIOS:
        out.append(Variable(f"sim_eps_sup_m_{s}", f8, np.nan, f"tail sup of |eps| in scenario '{s}', m"))
    out.append(Variable("ratio_certified_over_simulated", f8, np.nan, "eps_bound_m / sim_eps_sup_m"))
    out.append(Variable("sim_diverged", b1, False, "a simulation diverged or failed"))
    out.append(Variable("soundness_violation", b1, False,
                        "simulation left a certified bound, or diverged where stability is certified"))
    out.append(Variable("done", b1, False, "this point was computed and stored"))
    return tuple(out)


VARIABLES: Final = variables()
VARIABLE_BY_NAME: Final = {v.name: v for v in VARIABLES}


def status_code(status: str) -> int:
    """The int8 code of a ConditionResult status."""
    return STATUS_CODES[status]


# -- box sweeps (mode = "boxes"): one row per box ---------------------------------------------------
#: status of a box: certified for every point, refuted at a point of it (exactly), split into two
#: halves (an inner node of the refinement tree), or not certified (a leaf: minimum width or budget).
#: A box's GES is never refuted (lyapcheck.paper.boxes.quadratic explains why no exact obstruction exists); the
#: code is kept for classes' own statuses (``status_sector_ges``: no common quadratic V)
BOX_STATUS_CODES: Final[dict[str, int]] = {"not_certified": 0, "certified": 1, "refuted": 2, "split": 3}
#: the dimension of a box store
BOX_DIM: Final = "box"


def box_variables(dims: tuple[str, ...], classes: tuple[str, ...] = ()) -> tuple[Variable, ...]:
    """Every variable of a box store over the swept parameters ``dims`` with box ``classes``.

    ``status`` is the box's: certified when one class certifies (the classes run cheapest first
    and stop at the first certificate with a GES envelope ``k``, rate, so later classes stay
    ``-1`` there; ``prop41_ges``'s has none, and the next classes run for one); ``status_<class>``
    is each class's own (``refuted`` there is that class's exact refutation, not of GES).
    """
    i8, i16, i32, f8, b1 = (np.dtype(t) for t in ("int8", "int16", "int32", "float64", "bool"))
    out = []
    for d in dims:
        out.append(Variable(f"lo_{d}", f8, np.nan, f"lower edge of the box in {d} (SI)"))
        out.append(Variable(f"hi_{d}", f8, np.nan, f"upper edge of the box in {d} (SI)"))
    out += [
        Variable("status", i8, NOT_COMPUTED, "0 not_certified, 1 certified, 2 refuted, 3 split, -1 not computed"),
        *(Variable(f"status_{c}", i8, NOT_COMPUTED, f"{c} over the box: 0 not_certified, 1 certified, 2 refuted, "
                   "-1 not computed") for c in classes),
        *((Variable("eps_bound_m", f8, np.nan, "sos_bound: limsup |eps| <= this for every gain set of the box, m"),
           Variable("sim_worst_eps_m", f8, np.nan, "largest worst-case-search tail sup of |eps| at the box's random "
                    "points, m"),
           Variable("tightness_ratio", f8, np.nan, "eps_bound_m / sim_worst_eps_m"))
          if "sos_bound" in classes else ()),
        Variable("level", i16, -1, "refinement depth (0: a cell of the axes' grid)"),
        Variable("parent", i32, -1, "row of the box this one is a half of (-1: none)"),
        Variable("k", f8, np.nan, "GES constant of the box's certificate: |x(t)| <= k |x0| exp(-rate t)"),
        Variable("decay_rate_per_s", f8, np.nan, "GES decay rate of the box's certificate, 1/s"),
        Variable("cross_check_runs", i16, 0, "random points of the box simulated against its envelope"),
        Variable("cross_check_worst_ratio", f8, np.nan,
                 "largest |x(t)| / (k |x0| exp(-rate t)) seen in those simulations (<= 1: inside)"),
        Variable("soundness_violation", b1, False, "a simulation left the certified envelope or bound"),
        Variable("done", b1, False, "this box was computed and stored"),
    ]
    return tuple(out)


def is_box_dataset(ds: Any) -> bool:
    """A box store (``mode = "boxes"``) rather than a grid of points."""
    return str(getattr(ds, "attrs", {}).get("mode", "points")) == "boxes"


def check_box_dataset(ds: Any, source: str) -> None:
    """:func:`check_dataset` for a box store: one dimension ``box``, the variables of
    :func:`box_variables` over the parameters named in the ``dims`` attribute."""
    import json

    def bad(what: str) -> InputFileError:
        return InputFileError(f"'{source}' is not a box sweep store this lyapcheck reads: {what}")

    try:
        dims = tuple(json.loads(str(ds.attrs.get("dims"))))
    except (TypeError, ValueError):
        raise bad("its 'dims' attribute is not a JSON list") from None
    if not 1 <= len(dims) <= 3 or any(d not in SWEEPABLE for d in dims):
        raise bad(f"dims {list(dims)}, expected one to three of {', '.join(SWEEPABLE)}")
    if tuple(map(str, ds.dims)) != (BOX_DIM,):
        raise bad(f"dimensions {list(map(str, ds.dims))}, expected ['{BOX_DIM}']")
    try:
        classes = tuple(json.loads(str(ds.attrs.get("classes", "[]"))))
    except (TypeError, ValueError):
        raise bad("its 'classes' attribute is not a JSON list") from None
    for var in box_variables(dims, tuple(map(str, classes))):
        if var.name not in ds.data_vars:
            raise bad(f"no variable '{var.name}'")
        data = ds[var.name]
        if data.dtype != var.dtype or tuple(map(str, data.dims)) != (BOX_DIM,):
            raise bad(f"variable '{var.name}' is {data.dtype} over {list(map(str, data.dims))}, expected {var.dtype}")


def check_dataset(ds: Any, source: str) -> None:
    """Check a loaded store (an xarray Dataset) against this schema, before anything reads it.

    The dimensions are 1 to 3 names of :data:`SWEEPABLE`, each with a finite, strictly
    increasing coordinate; every variable of :data:`VARIABLES` that is present has its dtype
    and the grid's dimensions (a store of an older version may lack the newer classes' variables),
    and ``done`` is present. Anything else is an :class:`~lyapcheck.errors.InputFileError`
    naming ``source`` and what is wrong (a truncated or edited store, or not a sweep at all).
    """
    if is_box_dataset(ds):
        check_box_dataset(ds, source)
        return

    def bad(what: str) -> InputFileError:
        return InputFileError(f"'{source}' is not a sweep store this lyapcheck reads: {what}")

    dims = tuple(str(d) for d in ds.dims)
    if not 1 <= len(dims) <= 3 or any(d not in SWEEPABLE for d in dims):
        raise bad(f"dimensions {list(dims)}, expected one to three of {', '.join(SWEEPABLE)}")
    for dim in dims:
        if dim not in ds.coords:
            raise bad(f"no coordinate '{dim}'")
        values = np.asarray(ds.coords[dim].values)
        if (values.ndim != 1 or values.dtype.kind != "f" or not np.all(np.isfinite(values))
                or np.any(np.diff(values) <= 0)):
            raise bad(f"coordinate '{dim}' is not a finite, strictly increasing list of numbers")
    if "done" not in ds.data_vars:
        raise bad("no 'done' variable")
    for var in VARIABLES:
        if var.name not in ds.data_vars:
            continue
        data = ds[var.name]
        if data.dtype != var.dtype or set(map(str, data.dims)) != set(dims):
            raise bad(f"variable '{var.name}' is {data.dtype} over {list(map(str, data.dims))}, expected {var.dtype} "
                      f"over {list(dims)}")

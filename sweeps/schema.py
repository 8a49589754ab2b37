"""The sweep store's schema: variable names, dtypes, fill values and status codes, of every target.

This is the contract between :mod:`sweeps` (which writes a store) and ``reports`` (which
renders one). One place says what every variable means; nothing else hard-codes a name. A
target's variables per class are derived from its class list (``status_<class>`` for every class,
and each class's figures from one per-class table: :data:`MARGIN_SOURCE` for the paper's model,
:data:`FIGURES` and :data:`OUTPUT_FIGURES` for a model file, read from each class's entry in
:data:`lyapcheck.models.classes.registry.CLASSES`), so a class added to a target's list has its variables
without a new module here.

The paper's model, points (an xarray Dataset in a Zarr v3 store):

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

The paper's model, boxes: :func:`box_variables` (one dimension ``box``, attribute ``mode = "boxes"``).

A model file (target ``model``). Two layouts, told apart by the ``mode`` attribute:

* ``model_points``: one dimension per swept parameter, named after it, with its SI values as
  the coordinate; every variable below over those dimensions.
* ``model_boxes``: one dimension ``box`` (a row per box of the refinement tree), with the box's
  edges ``lo_<p>``, ``hi_<p>`` (SI), its ``level`` and ``parent``, and ``unstable_corners`` (how
  many of its corners have an exactly unstable equilibrium; -1 when no stability class was asked)
  besides the variables below.

Variables (``<c>`` a class of the sweep, ``<y>`` an output of the model):

* ``status`` int8: 1 certified (a class proved its property for the point, or for every point
  of the box), 2 refuted (the equilibrium is proved unstable, exactly, at the point or at a
  corner of the box: no stability class can hold there; or a safety class is refuted by an unsafe trajectory
  proved at the point or at a value of the box, named in ``note``), 0 not certified, 3 split (boxes: halved
  further), -1 not computed;
* ``status_<c>`` int8: each class's own status (:data:`sweeps.schema.STATUS_CODES`: 0
  not_certified, 1 certified, 2 refuted, 3 inconclusive, 4 not_applicable; -1 not computed);
* the key figures, NaN where the class did not certify: ``quadratic_decay_rate_V_per_s``,
  ``quadratic_k`` and ``quadratic_decay_rate_per_s`` (GES: ``|x| <= k |x0| exp(-rate t)``),
  ``sos_gas_decay_rate_V_per_s``, ``roa_level`` and ``roa_ball_radius`` (the certified set
  ``{V <= level}`` and the largest ball in it, SI), ``sos_bound_<y>`` (the certified
  ``limsup |y|``, in the output's SI units); a discrete-time map's per step instead
  (:data:`MAP_FIGURES`: ``quadratic_decay_rate_V_per_step``, ``quadratic_k``,
  ``quadratic_contraction_per_step``, ``sos_gas_decay_rate_V_per_step``, ``reach_avoid_reach_steps_bound``);
* ``certificate`` (string): the certificate document (JSON, kind
  ``lyapcheck-model-certificate``, its ``solver`` logs left out) of every certified point or box,
  empty elsewhere: ``lyapcheck verify`` re-checks it exactly;
* ``note`` (string): why the status is what it is, in one line;
* the simulation cross-check (:mod:`sweeps.crosscheck`): ``cross_check_points`` (parameter
  points simulated), ``cross_check_trajectories``, ``cross_check_worst_rise`` (largest rise of a
  certified V along a trajectory, relative to V(0)), ``cross_check_worst_envelope`` (largest excess
  of V over its certified decay envelope), ``cross_check_ges_ratio`` (largest
  ``|x(t)| / (k |x0| exp(-rate t))``), ``cross_check_not_converged`` (trajectories not at the
  equilibrium by the end of the horizon: a figure, not a violation), with ``barrier`` or
  ``reach_avoid`` ``cross_check_unsafe_margin`` (the largest margin of the unsafe set reached, ``>= 0``
  inside, each inequality over the size of its terms there, in [-1, 1]: ``< 0`` none entered) and with
  ``reach_avoid`` ``cross_check_reach_ratio`` (the latest time before the goal over the certified
  bound), and with ``sos_bound``
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
from dataclasses import dataclass
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck.errors import InputFileError
from lyapcheck.models.classes import registry as model_classes
from lyapcheck.paper.conditions import base as _base

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


def edge_variables(dims: Sequence[str]) -> list[Variable]:
    """The edges of a box, ``lo_<d>`` and ``hi_<d>`` per swept parameter (SI): the first variables of
    every box store, whatever its target."""
    f8 = np.dtype("float64")
    out = []
    for d in dims:
        out.append(Variable(f"lo_{d}", f8, np.nan, f"lower edge of the box in {d} (SI)"))
        out.append(Variable(f"hi_{d}", f8, np.nan, f"upper edge of the box in {d} (SI)"))
    return out


def box_variables(dims: tuple[str, ...], classes: tuple[str, ...] = ()) -> tuple[Variable, ...]:
    """Every variable of a box store over the swept parameters ``dims`` with box ``classes``.

    ``status`` is the box's: certified when one class certifies (the classes run cheapest first
    and stop at the first certificate with a GES envelope ``k``, rate, so later classes stay
    ``-1`` there; ``prop41_ges``'s has none, and the next classes run for one); ``status_<class>``
    is each class's own (``refuted`` there is that class's exact refutation, not of GES).
    """
    i8, i16, i32, f8, b1 = (np.dtype(t) for t in ("int8", "int16", "int32", "float64", "bool"))
    out = edge_variables(dims)
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
    A store of another target or layout is checked by its own function (:func:`check_box_dataset`,
    :func:`check_model_dataset`), told apart by the ``mode`` attribute.
    """
    if is_model_dataset(ds):
        check_model_dataset(ds, source)
        return
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


# -- sweeps of a model file (target "model"): points or boxes, classes of lyapcheck.models ------------
POINTS_MODE: Final = "model_points"
BOXES_MODE: Final = "model_boxes"
MODEL_MODES: Final = (POINTS_MODE, BOXES_MODE)
#: a variable-length UTF-8 string (zarr v3's vlen-utf8 codec)
STRING: Final = np.dtypes.StringDType()
#: the per-class table of a model file's classes: the key figures of each, as (variable suffix, key of
#: the class's numbers, description), from each class's entry in :data:`lyapcheck.models.classes.registry.CLASSES`;
#: a class without figures has its ``status_<class>`` only
FIGURES: Final[dict[str, tuple[tuple[str, str, str], ...]]] = {
    c.name: c.figures for c in model_classes.CLASSES if c.figures}
#: classes with one figure per output of the model: (key of the class's numbers holding ``{output:
#: value}``, description); stored as ``<class>_<output>``
OUTPUT_FIGURES: Final[dict[str, tuple[str, str]]] = {
    c.name: c.output_figure for c in model_classes.CLASSES if c.output_figure is not None}
#: a discrete-time map's figures where they are not :data:`FIGURES`' (a map states its rates per step and
#: its reach bound in steps, under keys of their own: ``discrete_lyapunov``'s and ``discrete_safety``'s
#: numbers; its barrier's ``lambda`` is a factor per step of its certificate, not a figure), so that a
#: map's store has columns that say per step and a continuous loop's store is what it was
MAP_FIGURES: Final[dict[str, tuple[tuple[str, str, str], ...]]] = {
    "quadratic": (("decay_rate_V_per_step", "decay_rate_V_per_step",
                   "certified decrease of V per step: V(x_k+1) <= (1 - mu) V(x_k)"),
                  ("k", "k", "GES constant: |x_k - x_eq| <= k |x_0 - x_eq| r^k"),
                  ("contraction_per_step", "contraction_per_step", "GES contraction r of |x_k - x_eq| per step")),
    "sos_gas": (("decay_rate_V_per_step", "decay_rate_V_per_step",
                 "certified decrease of V per step: V(x_k+1) <= (1 - mu) V(x_k)"),),
    "barrier": (),
    "reach_avoid": (("reach_steps_bound", "reach_steps_bound", "the goal is reached within this many steps"),),
}


def class_figures(cls: str, discrete: bool = False) -> tuple[tuple[str, str, str], ...]:
    """The key figures of class ``cls`` as (variable suffix, key of its numbers, description): on a
    discrete-time map (``discrete``) :data:`MAP_FIGURES`' where it has the class, else :data:`FIGURES`'."""
    if discrete and cls in MAP_FIGURES:
        return MAP_FIGURES[cls]
    return tuple(FIGURES.get(cls, ()))


def is_map_store(ds: Any) -> bool:
    """Whether a model sweep store (loaded) is of a discrete-time map: its stored model text says
    ``[model] time = "discrete"`` (read by :mod:`tomllib` alone, never parsed as a model)."""
    import tomllib

    try:
        model = tomllib.loads(str(ds.attrs.get("model_toml", ""))).get("model")
    except tomllib.TOMLDecodeError:
        return False
    return isinstance(model, dict) and model.get("time") == "discrete"


def _figures(classes: Sequence[str], outputs: Sequence[str], discrete: bool = False) -> list[Variable]:
    f8 = np.dtype("float64")
    out = [Variable(f"{c}_{suffix}", f8, np.nan, f"{c}: {text} (NaN: not certified)")
           for c in classes for suffix, _, text in class_figures(c, discrete)]
    for c in classes:
        if c in OUTPUT_FIGURES:
            text = OUTPUT_FIGURES[c][1]
            out += [Variable(f"{c}_{y}", f8, np.nan, f"{c}: {text.format(y=y)} (NaN: not certified)") for y in outputs]
    return out


def _model_common(classes: Sequence[str], outputs: Sequence[str], what: str, discrete: bool = False) -> list[Variable]:
    i8, i16, i32, f8, b1 = (np.dtype(t) for t in ("int8", "int16", "int32", "float64", "bool"))
    out = [Variable("status", i8, NOT_COMPUTED, "1 certified, 2 refuted (unstable, or unsafe, exactly), 0 not certified, "
                    "3 split, -1 not computed")]
    out += [Variable(f"status_{c}", i8, NOT_COMPUTED, f"{c} over the {what}: 0 not_certified, 1 certified, 2 refuted, "
                     "3 inconclusive, 4 not_applicable, -1 not computed") for c in classes]
    out += _figures(classes, outputs, discrete)
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
        Variable("cross_check_unsafe_margin", f8, np.nan, "barrier, reach_avoid: largest unsafe-set margin reached "
                 "(>= 0 inside), each inequality over the size of its terms there"),
        Variable("cross_check_reach_ratio", f8, np.nan, "reach_avoid: latest time before the goal / certified bound"),
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


def point_variables(classes: Sequence[str], outputs: Sequence[str], discrete: bool = False) -> tuple[Variable, ...]:
    """Every variable of a points store, in a fixed order (``done`` last); ``discrete``: of a
    discrete-time map (its figures per step, :func:`class_figures`)."""
    return tuple(_model_common(classes, outputs, "point", discrete))


def model_box_variables(dims: Sequence[str], classes: Sequence[str], outputs: Sequence[str],
                        discrete: bool = False) -> tuple[Variable, ...]:
    """Every variable of a boxes store: the box's edges and place in the tree, then the common ones
    (``discrete``: of a discrete-time map, its figures per step, :func:`class_figures`)."""
    f8, i16, i32 = np.dtype("float64"), np.dtype("int16"), np.dtype("int32")
    out = edge_variables(dims)
    out += [Variable("level", i16, -1, "refinement depth (0: a cell of the axes' grid)"),
            Variable("parent", i32, -1, "row of the box this one is a half of (-1: none)"),
            Variable("unstable_corners", np.dtype("int8"), -1, "corners of the box where the equilibrium is proved "
                     "unstable (linearization refuted, exactly); -1 not checked")]
    return tuple(out + _model_common(classes, outputs, "box", discrete))


def is_model_dataset(ds: Any) -> bool:
    """A model sweep's store (either layout)."""
    return str(getattr(ds, "attrs", {}).get("mode", "")) in MODEL_MODES


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
        variables = model_box_variables(dims, classes, outputs, is_map_store(ds))
        expected: tuple[str, ...] = (BOX_DIM,)
    else:
        if set(map(str, ds.dims)) != set(dims):
            raise bad(f"dimensions {list(map(str, ds.dims))}, expected {list(dims)}")
        for d in dims:
            values = np.asarray(ds.coords[d].values) if d in ds.coords else np.zeros(0)
            if values.ndim != 1 or values.dtype.kind != "f" or not np.all(np.isfinite(values)) \
                    or np.any(np.diff(values) <= 0):
                raise bad(f"coordinate '{d}' is not a finite, strictly increasing list of numbers")
        variables, expected = point_variables(classes, outputs, is_map_store(ds)), dims
    for var in variables:
        if var.name not in ds.data_vars:
            raise bad(f"no variable '{var.name}'")
        data = ds[var.name]
        same = data.dtype == var.dtype or (var.dtype == STRING and data.dtype.kind in ("T", "U", "O"))
        if not same or tuple(map(str, data.dims)) != tuple(expected):
            raise bad(f"variable '{var.name}' is {data.dtype} over {list(map(str, data.dims))}, expected {var.dtype} "
                      f"over {list(expected)}")

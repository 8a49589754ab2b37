"""Sweep specs of every target: a TOML file read into a validated, immutable spec.

Which target a spec is for is decided by :func:`sweeps.targets.load_any_spec` (a ``[sweep]`` that
names a model file is for the model-file target, anything else for the paper's model). The parts
every target reads alike live here once: the axes (:func:`axis_values`), ``[sweep.boxes]``
(:func:`box_settings`), the small validators and the file reader.

The paper's model (:class:`SweepSpec`). A spec is a parameter file (the sections of
``examples/paper.toml``) without the swept parameters, plus a ``[sweep]`` and a ``[simulation]`` table::

    [sweep]
    classes = ["prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound"]
    chunk_size = 100              # points per unit of work (and per Zarr chunk)

    [[sweep.axes]]                # one to three axes
    name = "alpha_d"              # alpha_d, sigma0, k_d, delta_los or d_max
    start = 150                   # with units where the parameter has one ("0.2 mm")
    stop = 2400
    num = 17
    scale = "log"                 # "linear" (default) or "log"
    # values = [300, 600, 1200]   # instead of start/stop/num/scale

    [sweep.refine]                # optional: quadtree refinement on a 2-D sweep (mode "points")
    class = "sector_ges"          # refine where this class's certified/not status changes
    levels = 3                    # each axis's num must be k * 2**levels + 1

    [simulation]
    horizon = "100 s"
    tail = "10 s"                 # the simulated ultimate bound is the sup of |eps| over the tail
    rtol = 1e-8
    scenarios = ["nominal", "constant", "weight", "adversarial"]   # and "worst_case" (opt-in, ~8 s a point)
    initial_position = ["0 mm", "-40 mm"]   # start of the 'nominal' divergence probe

A box sweep (``mode = "boxes"`` in ``[sweep]``, :func:`sweeps.run.run_boxes`) proves whole boxes
instead of sampling points: the axes' values are the edges of the first boxes (``num >= 2`` per
axis gives ``num - 1`` cells), ``classes`` are among ``["prop41_ges", "sector_ges", "ges",
"sos_bound"]`` (classes with box certificates; default the two GES ones ``sector_ges`` and
``ges``, run cheapest first until one certifies; ``prop41_ges`` maps the paper's own condition,
certified or refuted per box; ``sos_bound`` bounds ``limsup |eps|`` over each box and needs
``d_max`` and ``omega_so``), and::

    [sweep.boxes]
    min_relative_width = 0.05     # split undecided boxes until max(hi/lo - 1) is below this
    max_boxes = 400               # budget of boxes computed (leaves and split ones)
    cross_check_points = 2        # random points simulated in every certified box (0: none)
    seed = 0                      # of those random points (per box: independent of run order)

Every number goes through :func:`lyapcheck.paper.params.validate_field` (the one validation path,
with units and ranges from :data:`lyapcheck.paper.params.FIELDS`); every error is an
:class:`~lyapcheck.errors.InvalidParameter` with the one message template, and unknown keys
are errors.

A model file (:class:`ModelSweepSpec`): its parameters swept point by point or box by box. A spec
with ``model`` in its ``[sweep]`` table::

    [sweep]
    model = "../van-der-pol-reversed.toml"   # relative to this spec's directory
    mode = "boxes"                 # "points" (default): a grid of points; "boxes": proved boxes
    classes = ["roa"]              # points: any of linearization, quadratic, sos_gas, roa, sos_bound;
                                   # boxes: linearization (LES for every value of the box), quadratic,
                                   # sos_gas, roa, sos_bound (a map: linearization, quadratic, sos_gas;
                                   # default: every one that applies; sos_bound needs [disturbances])
    chunk_size = 4                 # points (or at most this many boxes) per unit of work

    [[sweep.axes]]                 # one to three axes, each a parameter declared in the model
    name = "mu"
    start = 0.5                    # numbers or unit strings, like the model's own parameters
    stop = 2
    num = 4                        # points mode: grid points; boxes mode: edges of the first boxes
    scale = "log"                  # "linear" (default) or "log" (positive values only)
    # values = [0.5, 1, 2]         # instead of start/stop/num/scale

    [sweep.set]                    # optional: other parameters or disturbance bounds, like --set
    # d = 0.5

    [sweep.boxes]                  # boxes mode only (as for the paper's box sweeps)
    min_relative_width = 0.1       # split undecided boxes while wider than this
    max_boxes = 40                 # budget of boxes computed (leaves and split ones)
    cross_check_points = 2         # random parameter points simulated in every certified box
    seed = 0                       # of those points (drawn from (seed, box id))

    [simulation]                   # optional: the cross-check of certified points and boxes
    starts = 8                     # simulated starts per parameter point and certificate
    seed = 0                       # of the starts
    worst_case = true              # sos_bound: the worst-case disturbance search at every point

A loop with functions (sin, cos, exp, sqrt, atan, tanh, abs, min, max, sat: what
:func:`lyapcheck.models.language.modelfile.parse_any_model` reads as a
:class:`~lyapcheck.models.language.recast.RecastModel`) is swept over the same classes as a
polynomial loop (:data:`MODEL_POINT_CLASSES`, :data:`MODEL_BOX_CLASSES`): each grid point is the
model text read again with the point's values as overrides (:meth:`ModelSweepSpec.model_at`), so
the loop is recast at them. Its boxes (``mode = "boxes"``) are
each what ``lyapcheck certify FILE --box`` certifies: the model read again at the box's centre
(:meth:`ModelSweepSpec.recast_box`), then
:func:`lyapcheck.models.surfaces.certify.certify_model` over the box, after its corners are checked for
instability as a polynomial model's box's (:func:`sweeps.evaluate.unstable_corners`: where one is
unstable, the stability classes are stored ``refuted``, not run); an undecided box is split.

A discrete-time map (``[model] time = "discrete"``, polynomial or with functions) is swept point by point
with the classes that have a discrete-time condition (:func:`map_classes`, ``sos_bound`` included on a
polynomial map; a class a map does not take is refused by the spec, in one line), each point certified as a
map by ``certify_model`` and cross-checked by iterating it (:class:`sweeps.crosscheck._MapLoop`, never
integrated; ``sos_bound`` under random, bang-bang and constant disturbances within its bounds). A map is
also swept box by box (``mode = "boxes"``) with the classes ``certify --box`` proves over a box of it whose
certified boxes the sweep cross-checks by iterating (:func:`map_box_classes`): on a polynomial map
``linearization``, ``quadratic``, ``sos_gas``, ``roa`` and ``sos_bound``; on a map with functions the same
(``linearization`` and ``roa`` with one ``P`` in ball arithmetic, the parameters as balls:
:mod:`lyapcheck.models.classes.discrete_functions_box`; ``quadratic``, ``sos_gas`` and ``sos_bound`` with the
parameters bounded variables of the relations, so are ``barrier`` and ``reach_avoid`` with its sets, each box's
starts in the initial set iterated), its boxes certified as a loop with functions' are
(the model read at the box's centre); any other class is refused in one line naming ``sweep.classes``. The same
tree, store and corner checks as a loop's boxes (a corner's linearization is the map's: an eigenvalue of
modulus > 1 refutes the box), each certified box iterated at its corners and random points (the true map of a
map with functions; :mod:`sweeps.crosscheck`).

The model's text is read once, here, and kept with the spec (:attr:`ModelSweepSpec.worker_text`):
workers (local processes or a Dask cluster) never open the model file, and a resumed run checks
that the file still has the SHA-256 stored with the results. A swept value is validated through
the model file's own path (:func:`lyapcheck.units.parse_si_quantity`, then the exact equilibrium
check of :func:`lyapcheck.models.language.modelfile.with_parameters` at every grid point; over boxes
:func:`lyapcheck.models.loop.boxes.check_box`, the model defined on the whole window). Every bad input
is one line (:class:`~lyapcheck.errors.InvalidParameter` or
:class:`~lyapcheck.errors.ModelFileError`) naming the field, what is accepted and what was given.
"""

from __future__ import annotations

import itertools
import json
import math
import tomllib
from dataclasses import dataclass, replace
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import InputFileError, InvalidParameter, ModelFileError
from lyapcheck.models.classes import registry as model_classes
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.loop.discrete import is_discrete
from lyapcheck.paper.boxes.box import ParameterBox
from lyapcheck.paper.params import (
    FIELD_BY_KEY, POSITIVE, FieldSpec, Interval, Problem, build_problem, flatten_tables, validate_field,
)
from lyapcheck.paper.simulation.scenarios import RTOL_RANGE
from lyapcheck.units import Kind
from sweeps.schema import CLASSES, DEFAULT_CLASSES, DEFAULT_SCENARIOS, SCENARIOS, SWEEPABLE, point_variables

if TYPE_CHECKING:
    from lyapcheck.models.language.recast import RecastModel

#: largest grid a spec may ask for (the store is streamed, but one spec should stay a sweep)
MAX_POINTS: Final = 10_000_000
MAX_CHUNK: Final = 100_000
DEFAULT_CHUNK: Final = 64
MAX_REFINE_LEVELS: Final = 10
_SCALES: Final = ("linear", "log")
_AXIS_KEYS: Final = ("name", "start", "stop", "num", "scale", "values")
_SWEEP_KEYS: Final = ("mode", "classes", "chunk_size", "axes", "refine", "boxes")
_MODES: Final = ("points", "boxes")
_BOX_KEYS: Final = ("min_relative_width", "max_boxes", "cross_check_points", "seed")
#: classes a box sweep runs (among :data:`lyapcheck.paper.boxes.classes.BOX_CLASSES`, cheapest first); the GES
#: ones are the default of a box sweep; ``prop41_ges`` (eq. stabCond, the paper's own condition)
#: is certified or refuted per box; ``sos_bound`` (10-20 s a box, plus the worst-case search at
#: the cross-check points) adds a certified bound on |eps| for every box
BOX_CLASSES: Final = ("prop41_ges", "sector_ges", "ges", "sos_bound")
BOX_GES_CLASSES: Final = ("sector_ges", "ges")
#: largest box budget of one spec (the store preallocates one row per box)
MAX_BOXES: Final = 100_000
MAX_CROSS_CHECK_POINTS: Final = 100
_REFINE_KEYS: Final = ("class", "levels")
_SIM_KEYS: Final = ("horizon", "tail", "rtol", "scenarios", "initial_position")

_SIM_FIELDS: Final[Mapping[str, FieldSpec]] = {
    "horizon": FieldSpec("simulation", "horizon", Kind.TIME, POSITIVE, "100 s", "simulated time"),
    "tail": FieldSpec("simulation", "tail", Kind.TIME, POSITIVE, "10 s", "final window of the measurements"),
    "rtol": FieldSpec("simulation", "rtol", Kind.DIMENSIONLESS, RTOL_RANGE, "1e-8", "integrator tolerance"),
}
_ANY_LENGTH: Final = FieldSpec("simulation", "initial_position", Kind.LENGTH, Interval(-math.inf, math.inf),
                               None, "initial position")
DEFAULT_INITIAL_POSITION: Final = ("0 mm", "-40 mm")


@dataclass(frozen=True)
class Axis:
    """One swept parameter: its name (a key of :data:`SWEEPABLE`) and SI values, increasing."""

    name: str
    values: tuple[float, ...]
    scale: str  # "linear", "log" or "list"

    @property
    def size(self) -> int:
        return len(self.values)


@dataclass(frozen=True)
class SimulationSettings:
    """How each point is simulated (SI)."""

    horizon: float
    tail: float
    rtol: float
    scenarios: tuple[str, ...]
    initial_position: tuple[float, float]


@dataclass(frozen=True)
class Refinement:
    """Quadtree refinement on a 2-D sweep (see :mod:`sweeps.refine`)."""

    cls: str
    levels: int


@dataclass(frozen=True)
class BoxSettings:
    """How a box sweep refines and cross-checks (``[sweep.boxes]``)."""

    min_relative_width: float
    max_boxes: int
    cross_check_points: int
    seed: int


class _AxesGrid:
    """The grid a spec's axes span (both targets' specs): its dimensions, shape and point count."""

    axes: Sequence[Any]

    @property
    def dims(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(a.size for a in self.axes)

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape))


@dataclass(frozen=True)
class SweepSpec(_AxesGrid):
    """A validated sweep spec; ``text`` is the TOML exactly as given (stored in the results)."""

    text: str
    axes: tuple[Axis, ...]
    base: Problem
    classes: tuple[str, ...]
    simulation: SimulationSettings
    refine: Refinement | None
    chunk_size: int
    mode: str = "points"
    boxes: BoxSettings | None = None

    @property
    def worker_text(self) -> str:
        """What a worker receives (:mod:`sweeps.evaluate`): the spec's TOML, parsed once per process."""
        return self.text

    def problem_at(self, coords: Sequence[float]) -> Problem:
        """The exact problem at one grid point (coordinates in SI, in the order of :attr:`dims`).

        The float coordinate is taken exactly (``Fraction(float)``): the certificate is about the
        number stored in the results, not a decimal neighbour of it.
        """
        gains: dict[str, Fraction] = {}
        problem = self.base
        for name, value in zip(self.dims, coords):
            exact = Fraction(float(value))
            if name == "d_max":
                problem = replace(problem, d_max=exact)
            else:
                gains[name] = exact
        return problem.with_gains(**gains) if gains else problem


def int_field(field: str, raw: object, low: int, high: int) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int) or not low <= raw <= high:
        raise InvalidParameter(field, f"an integer in [{low}, {high}]", raw)
    return raw


def known_keys(table: Mapping[str, Any], allowed: Sequence[str], where: str) -> None:
    for key in table:
        if key not in allowed:
            raise InvalidParameter(f"{where}.{key}", f"a known key of [{where}] ({', '.join(allowed)})", key)


def table_field(raw: object, where: str) -> Mapping[str, Any]:
    if not isinstance(raw, Mapping):
        raise InvalidParameter(where, "a table", raw)
    return raw


def _axis(index: int, raw: object) -> tuple[Axis, object]:
    """Validate one ``[[sweep.axes]]`` table; also returns a raw value for the base problem."""
    where = f"sweep.axes[{index}]"
    table = table_field(raw, where)
    known_keys(table, _AXIS_KEYS, where)
    name = table.get("name")
    if name not in SWEEPABLE:
        raise InvalidParameter(f"{where}.name", "one of " + ", ".join(repr(n) for n in SWEEPABLE), name)
    spec = FIELD_BY_KEY[SWEEPABLE[name]]
    def read(_: str, value: object) -> Fraction:
        return validate_field(replace(spec, name=name), value)

    values, scale = axis_values(where, table, read, MAX_POINTS)
    return Axis(name, values, scale), table["values"][0] if scale == "list" else table["start"]


def axis_values(where: str, table: Mapping[str, Any], read: Callable[[str, object], Fraction],
                max_num: int) -> tuple[tuple[float, ...], str]:
    """The values (SI floats, strictly increasing) and the scale (``linear``, ``log`` or ``list``) of
    an ``[[sweep.axes]]`` table: ``values``, or ``start``, ``stop``, ``num`` and ``scale``. ``read``
    reads one number of the axis exactly (the target's own validation path); every target reads
    its axes here."""
    if "values" in table:
        extra = [k for k in ("start", "stop", "num", "scale") if k in table]
        if extra:
            raise InvalidParameter(f"{where}.{extra[0]}", "absent when 'values' is given", table[extra[0]])
        raw_values = table["values"]
        if not isinstance(raw_values, list) or not raw_values:
            raise InvalidParameter(f"{where}.values", "a non-empty list of values", raw_values)
        floats = [float(read(f"{where}.values", v)) for v in raw_values]
        if any(b <= a for a, b in zip(floats, floats[1:])):
            raise InvalidParameter(f"{where}.values", "strictly increasing (as floats)", raw_values)
        return tuple(floats), "list"
    for key in ("start", "stop", "num"):
        if key not in table:
            raise InvalidParameter(f"{where}.{key}", "given (or give 'values')", None)
    start = read(f"{where}.start", table["start"])
    stop = read(f"{where}.stop", table["stop"])
    num = int_field(f"{where}.num", table["num"], 1, max_num)
    scale = table.get("scale", "linear")
    if scale not in _SCALES:
        raise InvalidParameter(f"{where}.scale", "one of 'linear', 'log'", scale)
    if stop < start or (stop == start and num > 1):
        raise InvalidParameter(f"{where}.stop", f"larger than start ({table['start']}): an empty range otherwise",
                               table["stop"])
    if scale == "log" and start <= 0:
        raise InvalidParameter(f"{where}.start", "positive on a log axis", table["start"])
    if num == 1:
        values = np.array([float(start)])
    elif scale == "log":
        values = np.geomspace(float(start), float(stop), num)
    else:
        values = np.linspace(float(start), float(stop), num)
    if np.any(np.diff(values) <= 0):
        raise InvalidParameter(f"{where}.num", "small enough that the grid values are distinct floats", num)
    return tuple(float(v) for v in values), str(scale)


def _simulation(raw: object) -> SimulationSettings:
    table = table_field({} if raw is None else raw, "simulation")
    known_keys(table, _SIM_KEYS, "simulation")
    values = {k: float(validate_field(spec, table.get(k, spec.default))) for k, spec in _SIM_FIELDS.items()}
    if values["tail"] > values["horizon"]:
        raise InvalidParameter("tail", f"at most the horizon ({values['horizon']:g} s)", table.get("tail"))
    scenarios = table.get("scenarios", list(DEFAULT_SCENARIOS))
    if (not isinstance(scenarios, list) or not scenarios or any(s not in SCENARIOS for s in scenarios)
            or len(set(scenarios)) != len(scenarios)):
        raise InvalidParameter("simulation.scenarios", "a list of distinct names from "
                               + ", ".join(repr(s) for s in SCENARIOS), scenarios)
    position = table.get("initial_position", list(DEFAULT_INITIAL_POSITION))
    if not isinstance(position, list) or len(position) != 2:
        raise InvalidParameter("initial_position", "a list of two lengths such as ['0 mm', '-40 mm']", position)
    p0 = tuple(float(validate_field(_ANY_LENGTH, v)) for v in position)
    return SimulationSettings(horizon=values["horizon"], tail=values["tail"], rtol=values["rtol"],
                              scenarios=tuple(s for s in SCENARIOS if s in scenarios),  # canonical order
                              initial_position=(p0[0], p0[1]))


def _classes(raw: object) -> tuple[str, ...]:
    if raw is None:
        return DEFAULT_CLASSES
    if not isinstance(raw, list) or not raw or any(c not in CLASSES for c in raw) or len(set(raw)) != len(raw):
        raise InvalidParameter("sweep.classes", "a list of distinct names from " + ", ".join(repr(c) for c in CLASSES),
                               raw)
    return tuple(c for c in CLASSES if c in raw)  # canonical order


def _refinement(raw: object, axes: tuple[Axis, ...], classes: tuple[str, ...]) -> Refinement | None:
    if raw is None:
        return None
    table = table_field(raw, "sweep.refine")
    known_keys(table, _REFINE_KEYS, "sweep.refine")
    cls = table.get("class")
    if cls not in classes:
        raise InvalidParameter("sweep.refine.class", "one of the classes the sweep runs ("
                               + ", ".join(classes) + ")", cls)
    levels = int_field("sweep.refine.levels", table.get("levels"), 1, MAX_REFINE_LEVELS)
    if len(axes) != 2:
        raise InvalidParameter("sweep.refine", "used with exactly two swept axes (a 2-D slice)",
                               f"{len(axes)} axes")
    step = 2**levels
    for i, axis in enumerate(axes):
        if axis.size < step + 1 or (axis.size - 1) % step:
            raise InvalidParameter(f"sweep.axes[{i}].num", f"k * 2**levels + 1 = k * {step} + 1 with k >= 1 "
                                   "(the finest grid of the refinement)", axis.size)
    return Refinement(str(cls), levels)


def box_settings(raw: object, axes: Sequence[Any], *, default_max_boxes: int = 400,
                 max_boxes_limit: int = MAX_BOXES) -> BoxSettings:
    """``[sweep.boxes]`` of a box sweep over ``axes`` (anything with a ``size``: the values are box
    edges), one-line errors naming the field; shared by the paper's specs and model specs."""
    table = table_field({} if raw is None else raw, "sweep.boxes")
    known_keys(table, _BOX_KEYS, "sweep.boxes")
    width = table.get("min_relative_width", 0.05)
    if isinstance(width, bool) or not isinstance(width, (int, float)) or not 1e-9 <= width <= 100:
        raise InvalidParameter("sweep.boxes.min_relative_width", "a number in [1e-9, 100]", width)
    first = int(np.prod([a.size - 1 for a in axes]))
    max_boxes = table.get("max_boxes", max(default_max_boxes, first))
    if isinstance(max_boxes, bool) or not isinstance(max_boxes, int) or not first <= max_boxes <= max_boxes_limit:
        raise InvalidParameter("sweep.boxes.max_boxes", f"an integer in [{first}, {max_boxes_limit}] (at least the "
                               f"{first} first boxes of the axes' grid)", max_boxes)
    points = int_field("sweep.boxes.cross_check_points", table.get("cross_check_points", 2), 0, MAX_CROSS_CHECK_POINTS)
    seed = int_field("sweep.boxes.seed", table.get("seed", 0), 0, 2**63 - 1)
    for i, axis in enumerate(axes):
        if axis.size < 2:
            raise InvalidParameter(f"sweep.axes[{i}].num", "at least 2 in a box sweep (the values are box edges)",
                                   axis.size)
    return BoxSettings(min_relative_width=float(width), max_boxes=max_boxes, cross_check_points=points, seed=seed)


#: parameters a box sweep may span (the gains: the box certificate's monomial argument covers them)
BOX_AXES: Final = ("alpha_d", "sigma0", "k_d", "delta_los")


def parse_spec(text: str, *, source: str = "spec") -> SweepSpec:
    """Validate a spec given as TOML text (see the module docstring)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(f"sweep spec '{source}' is not valid TOML: {exc}") from None
    if "sweep" not in data:
        raise InvalidParameter("sweep", f"a [sweep] table in {source}", None)
    sweep = table_field(data["sweep"], "sweep")
    known_keys(sweep, _SWEEP_KEYS, "sweep")
    raw_axes = sweep.get("axes")
    if not isinstance(raw_axes, list) or not 1 <= len(raw_axes) <= 3:
        raise InvalidParameter("sweep.axes", "a list of one to three [[sweep.axes]] tables",
                               None if raw_axes is None else f"{len(raw_axes) if isinstance(raw_axes, list) else raw_axes}")
    mode = sweep.get("mode", "points")
    if mode not in _MODES:
        raise InvalidParameter("sweep.mode", "one of " + ", ".join(repr(m) for m in _MODES), mode)
    parsed = [_axis(i, a) for i, a in enumerate(raw_axes)]
    for i, (axis, _) in enumerate(parsed):
        if mode == "boxes" and axis.name not in BOX_AXES:
            raise InvalidParameter(f"sweep.axes[{i}].name", "one of " + ", ".join(repr(n) for n in BOX_AXES)
                                   + " in a box sweep (the ges class does not depend on d_max)", axis.name)
    axes = tuple(a for a, _ in parsed)
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise InvalidParameter("sweep.axes", "distinct parameter names", names)
    n_points = int(np.prod([a.size for a in axes]))
    if n_points > MAX_POINTS:
        raise InvalidParameter("sweep.axes", f"at most {MAX_POINTS} points in all", n_points)

    values = flatten_tables(data, source)
    for axis, first in parsed:
        key = SWEEPABLE[axis.name]
        if key in values:
            raise InvalidParameter(key, "either fixed or swept, not both", values[key])
        values[key] = first  # a valid placeholder; problem_at() sets the exact value per point
    base = build_problem(values, source=source)
    if mode == "boxes":
        if "simulation" in data:
            raise InvalidParameter("simulation", "absent in a box sweep (its cross-check simulates the error "
                                   "dynamics with the box's own envelope)", "a [simulation] table")
        return _box_spec(text, sweep, axes, base)
    # every point is simulated under the saturated command and a bounded disturbance
    base.actuation.step_out()
    base.disturbance_bound()
    if "boxes" in sweep:
        raise InvalidParameter("sweep.boxes", "absent unless mode = \"boxes\"", "a [sweep.boxes] table")

    classes = _classes(sweep.get("classes"))
    chunk = int_field("sweep.chunk_size", sweep.get("chunk_size", DEFAULT_CHUNK), 1, MAX_CHUNK)
    simulation = _simulation(data.get("simulation"))
    if "weight" in simulation.scenarios:
        _check_weight_inputs(base)
    refine = _refinement(sweep.get("refine"), axes, classes)
    return SweepSpec(text=text, axes=axes, base=base, classes=classes, simulation=simulation, refine=refine,
                     chunk_size=chunk)


def _box_spec(text: str, sweep: Mapping[str, Any], axes: tuple[Axis, ...], base: Problem) -> SweepSpec:
    """The rest of a ``mode = "boxes"`` spec (module docstring)."""
    raw = sweep.get("classes", list(BOX_GES_CLASSES))
    if not isinstance(raw, list) or not raw or any(c not in BOX_CLASSES for c in raw) or len(set(raw)) != len(raw):
        raise InvalidParameter("sweep.classes", "in a box sweep, a list of classes with box certificates ("
                               + ", ".join(repr(c) for c in BOX_CLASSES) + ")", raw)
    if "refine" in sweep:
        raise InvalidParameter("sweep.refine", "absent in a box sweep (boxes refine by [sweep.boxes])",
                               "a [sweep.refine] table")
    chunk = int_field("sweep.chunk_size", sweep.get("chunk_size", DEFAULT_CHUNK), 1, MAX_CHUNK)
    boxes = box_settings(sweep.get("boxes"), axes)
    classes = tuple(c for c in BOX_CLASSES if c in raw)  # canonical order: cheapest first
    if "sos_bound" in classes:  # its cross-check simulates the saturated loop under |d| <= d*
        base.actuation.step_out()
        base.disturbance_bound()
    return SweepSpec(text=text, axes=axes, base=base, classes=classes, simulation=_simulation(None), refine=None,
                     chunk_size=chunk, mode="boxes", boxes=boxes)


def _check_weight_inputs(problem: Problem) -> None:
    """The 'weight' scenario needs the helix geometry and the weight (fail now, naming the field)."""
    sw = problem.swimmer
    for name in ("n_turns", "pitch_angle", "helix_radius", "weight"):
        if getattr(sw, name) is None:
            raise InvalidParameter(name, "given in [swimmer] for the 'weight' scenario", None)


def load_spec(path: str | Path) -> SweepSpec:
    """Read and validate a spec file; every failure is one line (InputFileError/InvalidParameter)."""
    return parse_spec(read_spec_text(path), source=str(path))


def read_spec_text(path: str | Path) -> str:
    """A spec file's text (one-line errors: missing or unreadable)."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputFileError(f"sweep spec '{p}' does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"sweep spec '{p}' cannot be read: {exc}") from None


def initial_boxes(spec: SweepSpec) -> list[ParameterBox]:
    """The first boxes of the paper's box sweep: the cells of the axes' grid, in C order (the edges
    taken exactly from the stored floats)."""
    edges = [[Fraction(v) for v in axis.values] for axis in spec.axes]
    cells = [list(zip(e[:-1], e[1:])) for e in edges]
    return [ParameterBox(tuple((axis.name, lo, hi) for axis, (lo, hi) in zip(spec.axes, combo)))
            for combo in itertools.product(*cells)]


@lru_cache(maxsize=4)
def cached_spec(text: str) -> SweepSpec:
    """Parse once per worker process (units are parsed with pint, which is not free)."""
    return parse_spec(text)


# -- a spec that names a model file (target "model"; module docstring) ------------------------------
#: classes of lyapcheck.models a sweep runs only where its spec gives the user's input (``candidate``: the
#: user's own V, ``[sweep] candidate = "..."`` as ``--candidate``; never by default), as :data:`lyapcheck.models.classes.registry.CLASSES` declares them
MODEL_USER_CLASSES: Final = model_classes.USER_GIVEN
#: classes of lyapcheck.models that certify a point only (``not_applicable`` over a box)
MODEL_POINT_ONLY_CLASSES: Final = model_classes.POINT_ONLY
#: classes of a points sweep: every class of :data:`lyapcheck.models.classes.registry.CLASSES` (in its order,
#: cheapest first) but those needing the user's input
MODEL_POINT_CLASSES: Final = tuple(c for c in model_classes.NAMES if c not in MODEL_USER_CLASSES)
#: classes of a boxes sweep: those with box certificates (lyapcheck.models.loop.boxes)
MODEL_BOX_CLASSES: Final = model_classes.OVER_BOX
#: a point or a box costs seconds: a grid of more points is a mistake in the spec, not a sweep
MAX_MODEL_POINTS: Final = 20_000
MAX_MODEL_BOXES: Final = 20_000
MAX_MODEL_CHUNK: Final = 1_000
DEFAULT_MODEL_CHUNK: Final = {"points": 4, "boxes": 8}
MAX_STARTS: Final = 256
DEFAULT_STARTS: Final = 8
_MODEL_SWEEP_KEYS: Final = ("model", "mode", "classes", "chunk_size", "axes", "set", "boxes", "candidate")
_MODEL_SIM_KEYS: Final = ("starts", "seed", "worst_case")
_MODEL_TABLES: Final = ("sweep", "simulation")


@dataclass(frozen=True)
class ModelAxis(Axis):
    """A swept parameter of the model: its name and SI values (increasing), and how they were spaced
    (:class:`Axis`, with how a share of it is measured)."""

    @property
    def measure(self) -> str:
        """How a share of this axis is measured: ``log`` (log(hi/lo)) or ``linear`` (hi - lo)."""
        return "log" if self.scale == "log" else "linear"


@dataclass(frozen=True)
class ModelSimulation:
    """The simulation cross-check of certified points and boxes (``[simulation]``)."""

    starts: int
    seed: int
    worst_case: bool


@dataclass(frozen=True)
class ModelSweepSpec(_AxesGrid):
    """A validated model sweep spec. ``text`` is the spec's TOML as given (stored with the results and
    compared on resume); ``model_text`` the model file's, verbatim; ``model`` the model with
    ``[sweep.set]`` applied (the swept parameters at their file values, replaced point by point): a
    polynomial or rational :class:`Model`, or a loop with functions
    (:class:`~lyapcheck.models.language.recast.RecastModel`)."""

    text: str
    model_file: str
    model_text: str
    model: Model | RecastModel
    overrides: tuple[tuple[str, str], ...]
    axes: tuple[ModelAxis, ...]
    classes: tuple[str, ...]
    mode: str
    chunk_size: int
    simulation: ModelSimulation
    boxes: BoxSettings | None = None
    #: the user's V (``candidate = "..."`` in ``[sweep]``): one text of the states for every point and box, read
    #: as ``certify --candidate`` reads it (:func:`_candidate`); None: the ``candidate`` class is not swept
    candidate: str | None = None

    @property
    def model_sha256(self) -> str:
        return self.model.sha256

    @property
    def discrete(self) -> bool:
        """Whether the model is a discrete-time map (``[model] time = "discrete"``)."""
        return is_discrete(self.model)

    @property
    def has_functions(self) -> bool:
        """Whether the model is a loop with functions (:class:`~lyapcheck.models.language.recast.RecastModel`)."""
        return not isinstance(self.model, Model)

    @property
    def polynomial(self) -> Model:
        """The model as a polynomial or rational loop, which a box's corner checks and
        :mod:`sweeps.crosscheck` take (a loop with functions goes through :meth:`recast_box`)."""
        if not isinstance(self.model, Model):
            raise TypeError(f"the model {self.model_file} is a loop with functions, not a polynomial or rational loop")
        return self.model

    def recast_at(self, values: Mapping[str, Fraction]) -> RecastModel:
        """A loop with functions read again from the text with the swept parameters at the exact
        ``values`` (dyadic: box edges and their midpoints), each written as its exact decimal in
        the model's ``overrides``, as ``lyapcheck certify --set`` would."""
        from lyapcheck.exact import exact_decimal as decimal_of
        from lyapcheck.models.language.modelfile import parse_any_model
        from lyapcheck.models.language.recast import RecastModel

        point = {k: decimal_of(Fraction(v)) for k, v in values.items()}
        model = parse_any_model(self.model_text, self.model_file, {**dict(self.overrides), **point}, self.candidate)
        assert isinstance(model, RecastModel)
        return model

    def recast_box(self, cell: Mapping[str, tuple[Fraction, Fraction]]) -> tuple[RecastModel, Any]:
        """A box of a loop with functions as ``lyapcheck certify FILE --box`` takes it: the model read
        at the box's centre (:meth:`recast_at`: the certificate's overrides say where the centre
        is, so ``verify`` reads the same model) and the box (:func:`window_box`)."""
        box = window_box(self, cell)
        return self.recast_at({name: box.center(name) for name in box.names}), box

    @property
    def outputs(self) -> tuple[str, ...]:
        """The model's outputs (default each state)."""
        return tuple(self.model.outputs)

    @property
    def worker_text(self) -> str:
        """What a worker receives: the spec and the model's text, never a path."""
        return json.dumps({"spec": self.text, "model_file": self.model_file, "model_text": self.model_text},
                          sort_keys=True)

    def parameters_at(self, coords: Sequence[float]) -> dict[str, Fraction]:
        """The exact parameters of one grid point: each stored float coordinate taken exactly, so a
        certificate is about the number in the results, not a decimal neighbour of it."""
        return {name: Fraction(float(v)) for name, v in zip(self.dims, coords)}

    def model_at(self, coords: Sequence[float]) -> Model | RecastModel:
        """The model at one grid point. Its ``overrides`` (what a certificate stores, and what
        ``verify`` re-reads the model text with) hold each swept value as the exact decimal of the
        stored float (:func:`exact_decimal`), so the certificate re-derives the same exact field.
        A loop with functions is read again from the text with those overrides: its recasting (the
        auxiliaries' values at the equilibrium, the equilibrium's exact check) depends on them."""
        from dataclasses import replace

        from lyapcheck.models.language.modelfile import parse_any_model, with_parameters

        exact = self.parameters_at(coords)
        if not isinstance(self.model, Model):
            point = {k: exact_decimal(float(v)) for k, v in exact.items()}
            return parse_any_model(self.model_text, self.model_file, {**dict(self.overrides), **point}, self.candidate)
        model = with_parameters(self.model, exact)
        return replace(model, overrides={**model.overrides, **{k: exact_decimal(float(v)) for k, v in exact.items()}})


def exact_decimal(value: float) -> str:
    """The exact decimal expansion of a float (every binary float has a finite one): read back by
    :func:`lyapcheck.units.parse_si_quantity` as the same rational."""
    from decimal import Decimal

    return str(Decimal(value))


# -- small validators (one message template: InvalidParameter) ------------------------------------
def _quantity(field: str, raw: object) -> Fraction:
    """A number or unit string, read as the model file reads its parameters (SI, exact)."""
    from lyapcheck.units import parse_si_quantity

    return parse_si_quantity(field, raw)


# -- the parts of a spec ------------------------------------------------------------------------
def _model(sweep: Mapping[str, Any], source: str, model_text: str | None) -> tuple[str, str]:
    """(the model file as named in the spec, its text): read relative to the spec's directory."""
    from lyapcheck.models.language.modelfile import load_any_model

    name = sweep.get("model")
    if not isinstance(name, str) or not name.strip():
        raise InvalidParameter("sweep.model", "a model file name, relative to the spec's directory", name)
    if model_text is None:
        model_text = load_any_model(Path(source).parent / name).text
    return name, model_text


def _overrides(raw: object, declared: Model | RecastModel) -> dict[str, str]:
    """``[sweep.set]``: names declared in the model (parameters or disturbance bounds), values checked."""
    table = table_field({} if raw is None else raw, "sweep.set")
    disturbances = declared.disturbances
    known = list(declared.parameters) + list(disturbances)
    out = {}
    for key, value in table.items():
        field = f"sweep.set.{key}"
        if key not in known:
            raise InvalidParameter(field, f"a parameter or disturbance declared in the model ({', '.join(known) or 'none'})",
                                   key)
        if isinstance(value, Mapping) or isinstance(value, list):
            raise InvalidParameter(field, "a number, or a number with a unit such as '0.75 mm'", value)
        exact = _quantity(field, value)
        if key in disturbances and exact < 0:
            raise InvalidParameter(field, "a disturbance bound >= 0", value)
        out[str(key)] = str(value)
    return out


def _model_axis(index: int, raw: object, model: Model | RecastModel, fixed: Mapping[str, str]) -> ModelAxis:
    where = f"sweep.axes[{index}]"
    table = table_field(raw, where)
    known_keys(table, _AXIS_KEYS, where)
    name = table.get("name")
    if not isinstance(name, str) or name not in model.parameters:
        raise InvalidParameter(f"{where}.name", "a parameter declared in the model ("
                               + (", ".join(model.parameters) or "it declares none") + ")", name)
    if name in fixed:
        raise InvalidParameter(f"sweep.set.{name}", f"absent: '{name}' is swept by {where}", fixed[name])
    values, scale = axis_values(where, table, _quantity, MAX_MODEL_POINTS)
    return _readable(ModelAxis(name, values, scale), where)


def _readable(axis: ModelAxis, where: str) -> ModelAxis:
    """Every value of the axis can be written into a certificate exactly (:func:`exact_decimal`, read
    back through the model file's own path): a float far below 1e-30 or above 1e30 has more digits
    than a model file's number may have."""
    for v in axis.values:
        try:
            _quantity(where, exact_decimal(v))
        except InvalidParameter as exc:
            raise InvalidParameter(where, f"values whose exact decimal expansion a model file can hold ({exc.expected})",
                                   v) from None
    return axis


def _model_classes(raw: object, mode: str, model: Model | RecastModel, candidate: str | None = None
                   ) -> tuple[str, ...]:
    polynomial = isinstance(model, Model)
    allowed = MODEL_POINT_CLASSES if mode == "points" else MODEL_BOX_CLASSES  # (the same on every loop)
    # the user's V, where the spec gives it (``candidate = "..."``): one V for every point and box, so the class is
    # taken in both modes, on every kind of loop (certify --box takes --candidate on each); run by default only
    # where the spec gives the V (a key given and not used is refused: the user meant it to run)
    user = MODEL_USER_CLASSES if candidate is not None else ()
    allowed = tuple(c for c in model_classes.NAMES if c in allowed or c in user)
    if is_discrete(model):  # a map: only the classes with a discrete-time condition (every other not_applicable)
        allowed = tuple(c for c in allowed if c in (map_classes(model) if mode == "points"
                                                    else (*map_box_classes(model), *user)))
    # (any loop: barrier with its sets only, reach_avoid with its goal too; a class the model cannot ask is
    # not picked by default, and naming it is refused here rather than at the first point)
    if not ("initial" in model.sets and "unsafe" in model.sets):
        allowed = tuple(c for c in allowed if c != "barrier")
    if not ("initial" in model.sets and "unsafe" in model.sets and "goal" in model.sets):
        allowed = tuple(c for c in allowed if c != "reach_avoid")
    disturbances = model.disturbances
    if raw is None:  # the defaults, and your V's class where the spec gives your V (you asked for it)
        return tuple(c for c in allowed if (c != "sos_bound" or disturbances)
                     and (c not in MODEL_USER_CLASSES or candidate is not None))
    if candidate is not None and isinstance(raw, list) and not any(c in MODEL_USER_CLASSES for c in raw):
        raise InvalidParameter("sweep.candidate", "given only where sweep.classes names 'candidate' (or gives no "
                               "list: then the default classes and candidate run); your V would not be used",
                               candidate)
    if candidate is None and isinstance(raw, list) and any(c in MODEL_USER_CLASSES for c in raw):
        named = next(c for c in raw if c in MODEL_USER_CLASSES)
        raise InvalidParameter("sweep.classes", f"classes without '{named}' unless [sweep] gives your V: add "
                               'candidate = "..." (an expression of the states, as certify --candidate takes it)', raw)
    if not isinstance(raw, list) or not raw or any(c not in allowed for c in raw) or len(set(raw)) != len(raw):
        kind = "" if polynomial else " of a loop with functions"
        others = ""
        if is_discrete(model):
            kind = " of a discrete-time map" + ("" if polynomial else " with functions")
            others = (' (a box sweep of a discrete-time map ([model] time = "discrete") takes these only: the '
                      "classes certify --box proves over a box of it and the sweep cross-checks by iterating)"
                      if mode == "boxes" else
                      ' (the other classes are not taken yet for a discrete-time map ([model] time = "discrete"))')
        raise InvalidParameter("sweep.classes", f"in a {mode} sweep{kind}, a list of distinct names from "
                               + ", ".join(repr(c) for c in allowed) + others, raw)
    if "sos_bound" in raw and not disturbances:
        raise InvalidParameter("sweep.classes", "classes that apply to the model: sos_bound needs [disturbances] "
                               "in the model file", raw)
    return tuple(c for c in allowed if c in raw)  # canonical order: cheapest first


def _candidate(raw: object, model: Model | RecastModel, swept: Sequence[str], model_text: str, model_file: str,
               fixed: Mapping[str, str]) -> str | None:
    """``[sweep] candidate``: the user's V, checked now (one line naming ``sweep.candidate``, exit 2) rather than
    at the first point. It is one V for every value of the sweep: a text naming a swept parameter is refused (read
    off the whitelist parser's syntax tree, never evaluated); the rest is what ``certify --candidate`` checks, by
    its own reader (:func:`lyapcheck.models.surfaces.certify.parse_candidate`; a loop with functions: the model
    read again with the candidate recast along), at the file's values and ``[sweep.set]``."""
    import ast

    from lyapcheck.models.language.expressions import ExpressionError, parse_quietly
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.surfaces.certify import parse_candidate

    if raw is None:
        return None
    expected = "your V: a non-empty expression of the model's states, as certify --candidate takes it"
    if not isinstance(raw, str) or not raw.strip():
        raise InvalidParameter("sweep.candidate", expected, raw)
    try:
        tree = parse_quietly(raw)
    except (SyntaxError, ValueError, RecursionError, ExpressionError) as exc:
        raise InvalidParameter("sweep.candidate", f"{expected} (it does not parse: "
                               f"{exc.msg if isinstance(exc, SyntaxError) else exc})",
                               raw) from None
    named = sorted({node.id for node in ast.walk(tree) if isinstance(node, ast.Name)} & set(swept))
    if named:
        raise InvalidParameter("sweep.candidate", "a V of the states alone, one V for every value of the sweep (it "
                               f"names the swept parameter {', '.join(named)})", raw)
    try:
        if isinstance(model, Model):
            parse_candidate(model, raw)
        else:
            parse_any_model(model_text, model_file, fixed or None, raw)
    except ModelFileError as exc:
        why = str(exc).removeprefix(f"{exc.source}: {exc.key}: ")
        raise InvalidParameter("sweep.candidate", f"{expected} ({why})", raw) from None
    return raw


def map_classes(model: Model | RecastModel) -> tuple[str, ...]:
    """The classes a point sweep of a discrete-time map takes: those with a discrete-time condition
    (:data:`lyapcheck.models.classes.registry.DISCRETE`; ``barrier`` and ``reach_avoid`` cross-checked by
    iterating, :func:`sweeps.crosscheck.check_sets`; ``sos_bound`` by iterating under disturbances,
    :meth:`sweeps.crosscheck._MapLoop.check_bound`), on a map with functions
    :data:`lyapcheck.models.classes.registry.MAP_FUNCTIONS` (its ``sos_bound`` iterated on its true map under
    disturbances)."""
    if isinstance(model, Model):
        return model_classes.DISCRETE
    return model_classes.MAP_FUNCTIONS


#: the classes a box sweep of a polynomial map takes: those ``certify --box`` proves over a box of a map whose
#: certified boxes the sweep cross-checks by iterating at the box's corners and random points (a global V that
#: never rises, a Stein ``P`` along the Jacobian's iterates, a set {V <= c} its starts never leave, a bound under
#: disturbances within its envelope, starts in the initial set never unsafe and, for reach_avoid, in the goal
#: within the certified steps); ``candidate`` (the user's V) is added where the spec gives it
MAP_BOX_SWEPT: Final = ("linearization", "quadratic", "sos_gas", "roa", "sos_bound", "barrier", "reach_avoid")


def map_box_classes(model: Model | RecastModel | None = None) -> tuple[str, ...]:
    """The classes a box sweep of a discrete-time map takes, in :data:`MODEL_BOX_CLASSES` order: on a polynomial
    map (``model`` a :class:`Model` or None) :data:`MAP_BOX_SWEPT`, each among
    :data:`lyapcheck.models.classes.discrete_lyapunov.BOX_CLASSES` (one V, one Stein ``P`` or one bound for every
    value of the box); on a map with functions
    :data:`lyapcheck.models.classes.discrete_functions_box.BOX_CLASSES` but ``candidate`` (each cross-checked
    by iterating its true map). Every other class of a map is not swept over boxes."""
    if model is not None and not isinstance(model, Model):
        from lyapcheck.models.classes.discrete_functions_box import BOX_CLASSES as FUNCTIONS_BOX_CLASSES

        return tuple(c for c in MODEL_BOX_CLASSES if c in FUNCTIONS_BOX_CLASSES)
    from lyapcheck.models.classes.discrete_lyapunov import BOX_CLASSES

    return tuple(c for c in MODEL_BOX_CLASSES if c in MAP_BOX_SWEPT and c in BOX_CLASSES)


def _model_simulation(raw: object) -> ModelSimulation:
    table = table_field({} if raw is None else raw, "simulation")
    known_keys(table, _MODEL_SIM_KEYS, "simulation")
    starts = int_field("simulation.starts", table.get("starts", DEFAULT_STARTS), 1, MAX_STARTS)
    seed = int_field("simulation.seed", table.get("seed", 0), 0, 2**63 - 1)
    worst = table.get("worst_case", True)
    if not isinstance(worst, bool):
        raise InvalidParameter("simulation.worst_case", "true or false", worst)
    return ModelSimulation(starts=starts, seed=seed, worst_case=worst)


#: exact edges of a box of a model file's sweep, by swept parameter (spec order)
Cell = dict[str, tuple[Fraction, Fraction]]


def window_box(spec: ModelSweepSpec, bounds: Mapping[str, tuple[Fraction, Fraction]]) -> Any:
    """A :class:`~lyapcheck.models.loop.boxes.ModelBox` of the swept parameters (in the model's order, as a
    certificate states its box), from exact ``{name: (lo, hi)}``."""
    from lyapcheck.models.loop.boxes import ModelBox

    return ModelBox(tuple((name, *bounds[name]) for name in spec.model.parameters if name in bounds))


def initial_cells(spec: ModelSweepSpec) -> list[Cell]:
    """The first boxes of a box sweep: the cells of the axes' grid in C order (spec order of the
    axes), the edges taken exactly from the stored floats."""
    edges = [[Fraction(v) for v in axis.values] for axis in spec.axes]
    cells = [list(zip(e[:-1], e[1:])) for e in edges]
    return [dict(zip(spec.dims, combo)) for combo in itertools.product(*cells)]


def relative_width(cell: Cell, axes: Sequence[ModelAxis]) -> dict[str, float]:
    """Each axis's width of a box: ``hi / lo - 1`` on a log axis, ``(hi - lo)`` over the window's
    width on a linear one (a parameter may be 0 or negative there, so no ratio to it is taken)."""
    out = {}
    for axis in axes:
        lo, hi = cell[axis.name]
        if axis.measure == "log":
            out[axis.name] = float(hi / lo) - 1.0
        else:
            out[axis.name] = float((hi - lo) / (Fraction(axis.values[-1]) - Fraction(axis.values[0])))
    return out


def split_cell(cell: Cell, axes: Sequence[ModelAxis]) -> tuple[Cell, Cell]:
    """Halve the axis of the largest :func:`relative_width` (the first such axis on a tie), exactly."""
    widths = relative_width(cell, axes)
    name = max(widths, key=lambda k: widths[k])
    lo, hi = cell[name]
    mid = (lo + hi) / 2
    return {**cell, name: (lo, mid)}, {**cell, name: (mid, hi)}


def _describe(bounds: Mapping[str, tuple[Fraction, Fraction]]) -> str:
    from lyapcheck.models.language.parameter_box import box_text

    return box_text((name, lo, hi) for name, (lo, hi) in bounds.items())


def _check_defined(spec: ModelSweepSpec, source: str) -> None:
    """The model is defined at every grid point (points) or on every box of the window (boxes)."""
    from lyapcheck.models.loop.boxes import check_box

    if spec.mode == "points":
        for index in np.ndindex(*spec.shape):
            coords = [axis.values[i] for axis, i in zip(spec.axes, index)]
            try:
                spec.model_at(coords)
            except ModelFileError as exc:
                where = ", ".join(f"{d} = {c:.6g}" for d, c in zip(spec.dims, coords))
                raise ModelFileError(source, f"sweep.axes at the grid point {where}",
                                     f"the model is not defined there ({exc})") from None
        return
    if spec.has_functions:
        from lyapcheck.models.classes.discrete_functions_box import boxed_system
        from lyapcheck.models.classes.recast_regions import boxed_loop

        # the recasting with the box's parameters as bounded constants (a map's: as variables without a flow, its
        # fixed point proved to stay put over the box, as certify --box checks before any class)
        boxed = boxed_system if spec.discrete else boxed_loop
        for cell in initial_cells(spec):
            try:
                boxed(*spec.recast_box(cell))
            except ModelFileError as exc:
                raise ModelFileError(source, f"sweep.axes, the box {_describe(cell)}",
                                     f"the loop cannot be recast over all of it ({exc})") from None
        return
    window = {axis.name: (Fraction(axis.values[0]), Fraction(axis.values[-1])) for axis in spec.axes}
    try:
        check_box(spec.polynomial, window_box(spec, window))
        return
    except ModelFileError:
        pass  # the whole window is refused: find the first box of the grid that is, and name it
    for cell in initial_cells(spec):
        try:
            check_box(spec.polynomial, window_box(spec, cell))
        except ModelFileError as exc:
            raise ModelFileError(source, f"sweep.axes, the box {_describe(cell)}",
                                 f"the model is not defined on all of it, or its equilibrium moves there ({exc})") from None


def parse_model_spec(text: str, *, source: str = "spec", model_text: str | None = None,
                     check: bool = True) -> ModelSweepSpec:
    """Validate a model sweep spec given as TOML text (module docstring).

    Parameters
    ----------
    text
        The spec's TOML.
    source
        Its path: errors name it, and the model file is read relative to its directory.
    model_text
        The model file's text when already read (workers: :func:`cached_model_spec`).
    check
        Check that the model is defined at every grid point or on the window's boxes (exact; done
        once, in the main process).
    """
    from lyapcheck.models.language.modelfile import parse_any_model

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(f"sweep spec '{source}' is not valid TOML: {exc}") from None
    for key in data:
        if key not in _MODEL_TABLES:
            raise InvalidParameter(key, "absent in a model sweep (the model file and [sweep.set] give the parameters; "
                                   "tables: [sweep], [simulation])", f"a [{key}] table")
    sweep = table_field(data.get("sweep"), "sweep")
    known_keys(sweep, _MODEL_SWEEP_KEYS, "sweep")
    model_file, model_text = _model(sweep, source, model_text)
    declared = parse_any_model(model_text, model_file)
    fixed = _overrides(sweep.get("set"), declared)
    model = parse_any_model(model_text, model_file, fixed) if fixed else declared
    mode = sweep.get("mode", "points")
    if mode not in _MODES:
        raise InvalidParameter("sweep.mode", "one of " + ", ".join(repr(m) for m in _MODES), mode)
    raw_axes = sweep.get("axes")
    if not isinstance(raw_axes, list) or not 1 <= len(raw_axes) <= 3:
        raise InvalidParameter("sweep.axes", "a list of one to three [[sweep.axes]] tables",
                               raw_axes if not isinstance(raw_axes, list) else f"{len(raw_axes)} tables")
    axes = tuple(_model_axis(i, a, model, fixed) for i, a in enumerate(raw_axes))
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise InvalidParameter("sweep.axes", "distinct parameter names", names)
    candidate = _candidate(sweep.get("candidate"), model, names, model_text, model_file, fixed)
    classes = _model_classes(sweep.get("classes"), str(mode), model, candidate)
    chunk = int_field("sweep.chunk_size", sweep.get("chunk_size", DEFAULT_MODEL_CHUNK[str(mode)]), 1, MAX_MODEL_CHUNK)
    boxes = None
    if mode == "boxes":
        boxes = box_settings(sweep.get("boxes"), axes, default_max_boxes=100, max_boxes_limit=MAX_MODEL_BOXES)
    else:
        if "boxes" in sweep:
            raise InvalidParameter("sweep.boxes", "absent unless mode = \"boxes\"", "a [sweep.boxes] table")
        points = int(np.prod([a.size for a in axes]))
        if points > MAX_MODEL_POINTS:
            raise InvalidParameter("sweep.axes", f"at most {MAX_MODEL_POINTS} grid points in all", points)
        reserved = {v.name for v in point_variables(classes, tuple(model.outputs), is_discrete(model))}
        for i, name in enumerate(names):
            if name in reserved:
                raise InvalidParameter(f"sweep.axes[{i}].name", "a parameter whose name is not one of the results' "
                                       "variables (rename it in the model file)", name)
    spec = ModelSweepSpec(text=text, model_file=model_file, model_text=model_text, model=model,
                          overrides=tuple(fixed.items()), axes=axes, classes=classes, mode=str(mode), chunk_size=chunk,
                          simulation=_model_simulation(data.get("simulation")), boxes=boxes, candidate=candidate)
    if check:
        _check_defined(spec, source)
    return spec


def load_model_spec(path: str | Path) -> ModelSweepSpec:
    """Read and validate a model sweep spec file (one-line errors)."""
    return parse_model_spec(read_spec_text(path), source=str(path))


@lru_cache(maxsize=4)
def cached_model_spec(worker_text: str) -> ModelSweepSpec:
    """A worker's spec, parsed once per process from :attr:`ModelSweepSpec.worker_text` (no file read,
    no definedness check: the main process did it)."""
    payload = json.loads(worker_text)
    return parse_model_spec(payload["spec"], source="the stored spec", model_text=payload["model_text"], check=False)


__all__ = ["Axis", "SimulationSettings", "Refinement", "BoxSettings", "SweepSpec", "parse_spec", "load_spec",
           "cached_spec", "read_spec_text", "axis_values", "ModelAxis", "ModelSimulation", "ModelSweepSpec",
           "parse_model_spec", "load_model_spec", "cached_model_spec", "initial_cells", "window_box", "exact_decimal",
           "MODEL_POINT_CLASSES", "MODEL_BOX_CLASSES", "initial_boxes", "map_classes", "map_box_classes",
           "relative_width", "split_cell", "Cell"]

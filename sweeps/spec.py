"""Sweep specs: a TOML file read into a validated, immutable :class:`SweepSpec`.

A spec is a parameter file (the sections of ``examples/paper.toml``) without the swept
parameters, plus a ``[sweep]`` and a ``[simulation]`` table::

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

A box sweep (``mode = "boxes"`` in ``[sweep]``, :mod:`sweeps.boxes_run`) proves whole boxes
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
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import Any, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import InputFileError, InvalidParameter
from lyapcheck.paper.params import (
    FIELD_BY_KEY, POSITIVE, FieldSpec, Interval, Problem, build_problem, flatten_tables, validate_field,
)
from lyapcheck.simulation.scenarios import RTOL_RANGE
from lyapcheck.units import Kind
from sweeps.schema import CLASSES, DEFAULT_CLASSES, DEFAULT_SCENARIOS, SCENARIOS, SWEEPABLE

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


@dataclass(frozen=True)
class SweepSpec:
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
    def dims(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(a.size for a in self.axes)

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape))

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
    if "values" in table:
        extra = [k for k in ("start", "stop", "num", "scale") if k in table]
        if extra:
            raise InvalidParameter(f"{where}.{extra[0]}", "absent when 'values' is given", table[extra[0]])
        raw_values = table["values"]
        if not isinstance(raw_values, list) or not raw_values:
            raise InvalidParameter(f"{where}.values", "a non-empty list of values", raw_values)
        exact = [validate_field(replace(spec, name=name), v) for v in raw_values]
        if any(b <= a for a, b in zip(exact, exact[1:])):
            raise InvalidParameter(f"{where}.values", "strictly increasing", raw_values)
        return Axis(name, tuple(float(v) for v in exact), "list"), raw_values[0]
    for key in ("start", "stop", "num"):
        if key not in table:
            raise InvalidParameter(f"{where}.{key}", "given (or give 'values')", None)
    start = validate_field(replace(spec, name=name), table["start"])
    stop = validate_field(replace(spec, name=name), table["stop"])
    num = int_field(f"{where}.num", table["num"], 1, MAX_POINTS)
    scale = table.get("scale", "linear")
    if scale not in _SCALES:
        raise InvalidParameter(f"{where}.scale", "one of 'linear', 'log'", scale)
    if stop < start or (stop == start and num > 1):
        raise InvalidParameter(f"{where}.stop", f"larger than start ({table['start']})", table["stop"])
    if scale == "log" and start <= 0:
        raise InvalidParameter(f"{where}.start", "positive for a log axis", table["start"])
    if num == 1:
        values = np.array([float(start)])
    elif scale == "log":
        values = np.geomspace(float(start), float(stop), num)
    else:
        values = np.linspace(float(start), float(stop), num)
    if np.any(np.diff(values) <= 0):
        raise InvalidParameter(f"{where}.num", "small enough that the grid values are distinct floats", num)
    return Axis(name, tuple(float(v) for v in values), scale), table["start"]


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
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputFileError(f"sweep spec '{p}' does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"sweep spec '{p}' cannot be read: {exc}") from None
    return parse_spec(text, source=str(p))


@lru_cache(maxsize=4)
def cached_spec(text: str) -> SweepSpec:
    """Parse once per worker process (units are parsed with pint, which is not free)."""
    return parse_spec(text)


__all__ = ["Axis", "SimulationSettings", "Refinement", "BoxSettings", "SweepSpec", "parse_spec", "load_spec", "cached_spec"]

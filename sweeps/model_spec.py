"""Sweep specs that name a model file: a model's parameters swept point by point or box by box.

A spec (TOML) with ``model`` in its ``[sweep]`` table::

    [sweep]
    model = "../van-der-pol-reversed.toml"   # relative to this spec's directory
    mode = "boxes"                 # "points" (default): a grid of points; "boxes": proved boxes
    classes = ["roa"]              # points: any of linearization, quadratic, sos_gas, roa, sos_bound;
                                   # boxes: quadratic, sos_gas, roa, sos_bound (default: every one
                                   # that applies; sos_bound needs [disturbances] in the model)
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

The model's text is read once, here, and kept with the spec (:attr:`ModelSweepSpec.worker_text`):
workers (local processes or a Dask cluster) never open the model file, and a resumed run checks
that the file still has the SHA-256 stored with the results. A swept value is validated through
the model file's own path (:func:`lyapcheck.units.parse_si_quantity`, then the exact equilibrium
check of :func:`lyapcheck.models.modelfile.with_parameters` at every grid point; over boxes
:func:`lyapcheck.models.boxes.check_box`, the model defined on the whole window). Every bad input
is one line (:class:`~lyapcheck.errors.InvalidParameter` or
:class:`~lyapcheck.errors.ModelFileError`) naming the field, what is accepted and what was given.
"""

from __future__ import annotations

import itertools
import json
import tomllib
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import Any, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import InputFileError, InvalidParameter, ModelFileError
from lyapcheck.models.modelfile import Model
from sweeps.spec import BoxSettings, SweepSpec, box_settings, int_field, known_keys, table_field

#: classes of a points sweep (every class of a model file but the user's own candidate V)
POINT_CLASSES: Final = ("linearization", "quadratic", "sos_gas", "roa", "sos_bound")
#: classes with box certificates (lyapcheck.models.boxes)
BOX_CLASSES: Final = ("quadratic", "sos_gas", "roa", "sos_bound")
MODES: Final = ("points", "boxes")
#: a point or a box costs seconds: a grid of more points is a mistake in the spec, not a sweep
MAX_MODEL_POINTS: Final = 20_000
MAX_MODEL_BOXES: Final = 20_000
MAX_CHUNK: Final = 1_000
DEFAULT_CHUNK: Final = {"points": 4, "boxes": 8}
MAX_STARTS: Final = 256
DEFAULT_STARTS: Final = 8
_SWEEP_KEYS: Final = ("model", "mode", "classes", "chunk_size", "axes", "set", "boxes")
_AXIS_KEYS: Final = ("name", "start", "stop", "num", "scale", "values")
_SIM_KEYS: Final = ("starts", "seed", "worst_case")
_TABLES: Final = ("sweep", "simulation")


@dataclass(frozen=True)
class ModelAxis:
    """A swept parameter of the model: its name and SI values (increasing), and how they were spaced."""

    name: str
    values: tuple[float, ...]
    scale: str  # "linear", "log" or "list"

    @property
    def size(self) -> int:
        return len(self.values)

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
class ModelSweepSpec:
    """A validated model sweep spec. ``text`` is the spec's TOML as given (stored with the results and
    compared on resume); ``model_text`` the model file's, verbatim; ``model`` the model with
    ``[sweep.set]`` applied (the swept parameters at their file values, replaced point by point)."""

    text: str
    model_file: str
    model_text: str
    model: Model
    overrides: tuple[tuple[str, str], ...]
    axes: tuple[ModelAxis, ...]
    classes: tuple[str, ...]
    mode: str
    chunk_size: int
    simulation: ModelSimulation
    boxes: BoxSettings | None = None

    @property
    def model_sha256(self) -> str:
        return self.model.sha256

    @property
    def dims(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(a.size for a in self.axes)

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape))

    @property
    def outputs(self) -> tuple[str, ...]:
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

    def model_at(self, coords: Sequence[float]) -> Model:
        """The model at one grid point. Its ``overrides`` (what a certificate stores, and what
        ``verify`` re-reads the model text with) hold each swept value as the exact decimal of the
        stored float (:func:`exact_decimal`), so the certificate re-derives the same exact field."""
        from dataclasses import replace

        from lyapcheck.models.modelfile import with_parameters

        exact = self.parameters_at(coords)
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
    from lyapcheck.models.modelfile import load_model

    name = sweep.get("model")
    if not isinstance(name, str) or not name.strip():
        raise InvalidParameter("sweep.model", "a model file name, relative to the spec's directory", name)
    if model_text is None:
        model_text = load_model(Path(source).parent / name).text
    return name, model_text


def _overrides(raw: object, declared: Model) -> dict[str, str]:
    """``[sweep.set]``: names declared in the model (parameters or disturbance bounds), values checked."""
    table = table_field({} if raw is None else raw, "sweep.set")
    known = list(declared.parameters) + list(declared.disturbances)
    out = {}
    for key, value in table.items():
        field = f"sweep.set.{key}"
        if key not in known:
            raise InvalidParameter(field, f"a parameter or disturbance declared in the model ({', '.join(known) or 'none'})",
                                   key)
        if isinstance(value, Mapping) or isinstance(value, list):
            raise InvalidParameter(field, "a number, or a number with a unit such as '0.75 mm'", value)
        exact = _quantity(field, value)
        if key in declared.disturbances and exact < 0:
            raise InvalidParameter(field, "a disturbance bound >= 0", value)
        out[str(key)] = str(value)
    return out


def _axis(index: int, raw: object, model: Model, fixed: Mapping[str, str]) -> ModelAxis:
    where = f"sweep.axes[{index}]"
    table = table_field(raw, where)
    known_keys(table, _AXIS_KEYS, where)
    name = table.get("name")
    if not isinstance(name, str) or name not in model.parameters:
        raise InvalidParameter(f"{where}.name", "a parameter declared in the model ("
                               + (", ".join(model.parameters) or "it declares none") + ")", name)
    if name in fixed:
        raise InvalidParameter(f"sweep.set.{name}", f"absent: '{name}' is swept by {where}", fixed[name])
    if "values" in table:
        extra = [k for k in ("start", "stop", "num", "scale") if k in table]
        if extra:
            raise InvalidParameter(f"{where}.{extra[0]}", "absent when 'values' is given", table[extra[0]])
        raw_values = table["values"]
        if not isinstance(raw_values, list) or not raw_values:
            raise InvalidParameter(f"{where}.values", "a non-empty list of values", raw_values)
        exact = [_quantity(f"{where}.values", v) for v in raw_values]
        floats = [float(v) for v in exact]
        if any(b <= a for a, b in zip(floats, floats[1:])):
            raise InvalidParameter(f"{where}.values", "strictly increasing (as floats)", raw_values)
        return _readable(ModelAxis(name, tuple(floats), "list"), where)
    for key in ("start", "stop", "num"):
        if key not in table:
            raise InvalidParameter(f"{where}.{key}", "given (or give 'values')", None)
    start = _quantity(f"{where}.start", table["start"])
    stop = _quantity(f"{where}.stop", table["stop"])
    num = int_field(f"{where}.num", table["num"], 1, MAX_MODEL_POINTS)
    scale = table.get("scale", "linear")
    if scale not in ("linear", "log"):
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
    return _readable(ModelAxis(name, tuple(float(v) for v in values), str(scale)), where)


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


def _classes(raw: object, mode: str, model: Model) -> tuple[str, ...]:
    allowed = POINT_CLASSES if mode == "points" else BOX_CLASSES
    if raw is None:
        return tuple(c for c in allowed if c != "sos_bound" or model.disturbances)
    if not isinstance(raw, list) or not raw or any(c not in allowed for c in raw) or len(set(raw)) != len(raw):
        raise InvalidParameter("sweep.classes", f"in a {mode} sweep, a list of distinct names from "
                               + ", ".join(repr(c) for c in allowed), raw)
    if "sos_bound" in raw and not model.disturbances:
        raise InvalidParameter("sweep.classes", "classes that apply to the model: sos_bound needs [disturbances] "
                               "in the model file", raw)
    return tuple(c for c in allowed if c in raw)  # canonical order: cheapest first


def _simulation(raw: object) -> ModelSimulation:
    table = table_field({} if raw is None else raw, "simulation")
    known_keys(table, _SIM_KEYS, "simulation")
    starts = int_field("simulation.starts", table.get("starts", DEFAULT_STARTS), 1, MAX_STARTS)
    seed = int_field("simulation.seed", table.get("seed", 0), 0, 2**63 - 1)
    worst = table.get("worst_case", True)
    if not isinstance(worst, bool):
        raise InvalidParameter("simulation.worst_case", "true or false", worst)
    return ModelSimulation(starts=starts, seed=seed, worst_case=worst)


def window_box(spec: ModelSweepSpec, bounds: Mapping[str, tuple[Fraction, Fraction]]) -> Any:
    """A :class:`~lyapcheck.models.boxes.ModelBox` of the swept parameters (in the model's order, as a
    certificate states its box), from exact ``{name: (lo, hi)}``."""
    from lyapcheck.models.boxes import ModelBox

    return ModelBox(tuple((name, *bounds[name]) for name in spec.model.parameters if name in bounds))


def initial_cells(spec: ModelSweepSpec) -> list[dict[str, tuple[Fraction, Fraction]]]:
    """The first boxes of a box sweep: the cells of the axes' grid in C order (spec order of the
    axes), the edges taken exactly from the stored floats."""
    edges = [[Fraction(v) for v in axis.values] for axis in spec.axes]
    cells = [list(zip(e[:-1], e[1:])) for e in edges]
    return [dict(zip(spec.dims, combo)) for combo in itertools.product(*cells)]


def _describe(bounds: Mapping[str, tuple[Fraction, Fraction]]) -> str:
    return ", ".join(f"{name} in [{float(lo):.6g}, {float(hi):.6g}]" for name, (lo, hi) in bounds.items())


def _check_defined(spec: ModelSweepSpec, source: str) -> None:
    """The model is defined at every grid point (points) or on every box of the window (boxes)."""
    from lyapcheck.models.boxes import check_box

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
    window = {axis.name: (Fraction(axis.values[0]), Fraction(axis.values[-1])) for axis in spec.axes}
    try:
        check_box(spec.model, window_box(spec, window))
        return
    except ModelFileError:
        pass  # the whole window is refused: find the first box of the grid that is, and name it
    for cell in initial_cells(spec):
        try:
            check_box(spec.model, window_box(spec, cell))
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
    from lyapcheck.models.modelfile import parse_model

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(f"sweep spec '{source}' is not valid TOML: {exc}") from None
    for key in data:
        if key not in _TABLES:
            raise InvalidParameter(key, "absent in a model sweep (the model file and [sweep.set] give the parameters; "
                                   "tables: [sweep], [simulation])", f"a [{key}] table")
    sweep = table_field(data.get("sweep"), "sweep")
    known_keys(sweep, _SWEEP_KEYS, "sweep")
    model_file, model_text = _model(sweep, source, model_text)
    declared = parse_model(model_text, model_file)
    fixed = _overrides(sweep.get("set"), declared)
    model = parse_model(model_text, model_file, fixed) if fixed else declared
    mode = sweep.get("mode", "points")
    if mode not in MODES:
        raise InvalidParameter("sweep.mode", "one of " + ", ".join(repr(m) for m in MODES), mode)
    raw_axes = sweep.get("axes")
    if not isinstance(raw_axes, list) or not 1 <= len(raw_axes) <= 3:
        raise InvalidParameter("sweep.axes", "a list of one to three [[sweep.axes]] tables",
                               raw_axes if not isinstance(raw_axes, list) else f"{len(raw_axes)} tables")
    axes = tuple(_axis(i, a, model, fixed) for i, a in enumerate(raw_axes))
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise InvalidParameter("sweep.axes", "distinct parameter names", names)
    classes = _classes(sweep.get("classes"), str(mode), model)
    chunk = int_field("sweep.chunk_size", sweep.get("chunk_size", DEFAULT_CHUNK[str(mode)]), 1, MAX_CHUNK)
    boxes = None
    if mode == "boxes":
        boxes = box_settings(sweep.get("boxes"), axes, default_max_boxes=100, max_boxes_limit=MAX_MODEL_BOXES)
    else:
        if "boxes" in sweep:
            raise InvalidParameter("sweep.boxes", "absent unless mode = \"boxes\"", "a [sweep.boxes] table")
        points = int(np.prod([a.size for a in axes]))
        if points > MAX_MODEL_POINTS:
            raise InvalidParameter("sweep.axes", f"at most {MAX_MODEL_POINTS} grid points in all", points)
        from sweeps.model_schema import point_variables

        reserved = {v.name for v in point_variables(classes, tuple(model.outputs))}
        for i, name in enumerate(names):
            if name in reserved:
                raise InvalidParameter(f"sweep.axes[{i}].name", "a parameter whose name is not one of the results' "
                                       "variables (rename it in the model file)", name)
    spec = ModelSweepSpec(text=text, model_file=model_file, model_text=model_text, model=model,
                          overrides=tuple(fixed.items()), axes=axes, classes=classes, mode=str(mode), chunk_size=chunk,
                          simulation=_simulation(data.get("simulation")), boxes=boxes)
    if check:
        _check_defined(spec, source)
    return spec


def load_model_spec(path: str | Path) -> ModelSweepSpec:
    """Read and validate a model sweep spec file (one-line errors)."""
    return parse_model_spec(_read(path), source=str(path))


def names_a_model(text: str) -> bool:
    """Whether a spec's TOML names a model file (``[sweep] model``); False when it is not TOML."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return False
    sweep = data.get("sweep")
    return isinstance(sweep, Mapping) and "model" in sweep


def load_any_spec(path: str | Path) -> SweepSpec | ModelSweepSpec:
    """A spec file of either kind: a model sweep when ``[sweep]`` names a model, else the paper's
    (:func:`sweeps.spec.parse_spec`)."""
    from sweeps.spec import parse_spec

    text = _read(path)
    if names_a_model(text):
        return parse_model_spec(text, source=str(path))
    return parse_spec(text, source=str(path))


def _read(path: str | Path) -> str:
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputFileError(f"sweep spec '{p}' does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"sweep spec '{p}' cannot be read: {exc}") from None


@lru_cache(maxsize=4)
def cached_model_spec(worker_text: str) -> ModelSweepSpec:
    """A worker's spec, parsed once per process from :attr:`ModelSweepSpec.worker_text` (no file read,
    no definedness check: the main process did it)."""
    payload = json.loads(worker_text)
    return parse_model_spec(payload["spec"], source="the stored spec", model_text=payload["model_text"], check=False)


__all__ = ["ModelAxis", "ModelSimulation", "ModelSweepSpec", "parse_model_spec", "load_model_spec", "load_any_spec",
           "cached_model_spec", "names_a_model", "initial_cells", "window_box", "exact_decimal", "POINT_CLASSES",
           "BOX_CLASSES"]

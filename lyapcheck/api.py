"""The Python API: what ``lyapcheck certify | verify | simulate | sweep | report`` do, as functions.

For the notebook user who will not shell out::

    from lyapcheck import certify, verify

    result = certify({"alpha_d": "0.0558", "sigma0": 0.01, "k_d": "0.15 1/s",
                      "delta_los": "0.75 mm", "e11": "9.3e-5 m"}, classes="quick")
    result.verdict                       # "certified", "not_certified", "unsafe", ... (lyapcheck.answers)
    result.conditions["sector_ges"].status
    verify(result.to_json()).valid       # exact re-check, no solver

Every function takes what the command line takes (a parameters object, a mapping with unit
strings, or a TOML path), returns a typed result whose ``to_json()`` is exactly the command's
``--json`` document, and raises :class:`~lyapcheck.errors.LyapcheckError` subclasses on bad
input (the command line maps them to exit codes). The command line calls these functions and
nothing else; ``docs/api.md`` is the user's guide.

This module sits above the core, :mod:`sweeps` and :mod:`reports` (DESIGN.md's layering): it
is the only place besides :mod:`lyapcheck.cli` that imports the two, and it imports them (and
every heavy library) inside the functions, so ``import lyapcheck`` stays instant.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from lyapcheck.errors import InputFileError, InvalidParameter, ModelFileError

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.paper.params import Problem
    from lyapcheck.results import ConditionResult

#: local worker processes a sweep may start (each is a process with its own solver state; far
#: beyond any machine's cores, and below the limits a process pool can represent)
MAX_LOCAL_WORKERS = 1024

#: short names accepted in a parameters mapping (and the command-line flags) -> parameter key
SHORT_KEYS: dict[str, str] = {
    "alpha_d": "gains.alpha_d", "sigma0": "gains.sigma0", "k_d": "gains.k_d", "kd": "gains.k_d",
    "delta_los": "gains.delta_los", "los_speed": "gains.los_speed", "e11": "swimmer.e11",
    "e11_hat": "swimmer.e11_hat", "omega_so": "actuation.omega_so", "omega_0": "actuation.omega_0",
    "theta_r": "path.theta_r", "d_max": "disturbance.d_max",
}

def flat_parameters(params: Mapping[str, Any]) -> dict[str, object]:
    """``{"section.name": value}`` from a nested (TOML-shaped), dotted or short-named mapping."""
    from lyapcheck.paper.params import flatten_tables

    flat: dict[str, object] = {}
    nested = {k: v for k, v in params.items() if isinstance(v, Mapping)}
    flat.update(flatten_tables(nested, "the parameters mapping"))
    for key, value in params.items():
        if key in nested:
            continue
        if not isinstance(key, str):
            raise InvalidParameter("parameters", "string keys", key)
        flat[SHORT_KEYS.get(key, key)] = value
    return flat


def problem_from(params: Any, overrides: Mapping[str, object] | None = None) -> "Problem":
    """A validated :class:`~lyapcheck.paper.params.Problem` from any accepted parameters form.

    Parameters
    ----------
    params
        A ``Problem`` (returned as is when there are no overrides), a mapping (nested like the
        TOML file, dotted ``"gains.alpha_d"`` keys, or short names ``"alpha_d"``; values are
        numbers or strings with units), a path to a gains TOML file, or ``None``.
    overrides
        Values laid over ``params`` (keys as in a mapping), as the command-line flags are.
    """
    from lyapcheck.paper.params import Problem, build_problem, problem_from_sources

    extra = flat_parameters(overrides or {})
    if isinstance(params, Problem):
        if not extra:
            return params
        params = {k: v for k, v in params.given.items()}
    if params is None or isinstance(params, (str, Path)):
        return problem_from_sources(params, extra)
    if not isinstance(params, Mapping):
        raise InvalidParameter("params", "a Problem, a mapping or a TOML path", type(params).__name__)
    return build_problem({**flat_parameters(params), **extra}, source="the parameters mapping", numbers_in_si=True)


# -- certify -------------------------------------------------------------------------------------
def class_selection(classes: str | Sequence[str] | None) -> tuple[str, ...]:
    """``None`` (all), ``"quick"``, a comma-separated string or a sequence of class names."""
    from lyapcheck.paper.certification import CONDITION_ORDER, QUICK_CLASSES

    if classes is None:
        return CONDITION_ORDER
    if isinstance(classes, str):
        if classes.strip() == "quick":
            return QUICK_CLASSES
        classes = classes.split(",")
    chosen = tuple(c.strip() for c in classes if isinstance(c, str) and c.strip())
    if not chosen:
        raise InvalidParameter("classes", "'quick' or names among " + ", ".join(CONDITION_ORDER), classes)
    return chosen


@dataclass(frozen=True, repr=False)
class CertifyResult:
    """What ``lyapcheck certify`` found: the same content as its ``--json`` document.

    Its ``repr`` is a few lines (the verdict, one line per class); in a notebook it shows as a
    small table (``_repr_html_``); ``to_dict()`` is the whole document.

    Attributes
    ----------
    verdict
        One word (:data:`lyapcheck.answers.VERDICTS`): ``certified`` when a claim passed its exact
        check and no question is answered negatively (a model with disturbances:
        ``certified_nominal`` when only claims with them held at 0 passed; ``certified_local`` when
        only the linearization is proved), ``unsafe`` / ``unstable`` for a negative answer, else
        ``not_certified``.
    answers
        Question -> its answer (:func:`lyapcheck.answers.answers_of`): ``stability``, ``safety``,
        ``reach_avoid``, ``bounds``, each ``{"answer", "by", "text", ...}``, for the questions asked.
    dynamics
        ``derived`` or ``printed`` (the paper's loop); ``model`` for a model file.
    conditions
        Condition name -> :class:`~lyapcheck.results.ConditionResult`: ``status``, ``property``,
        ``disturbances``, ``summary``, ``numbers``, the exact ``certificate``; each attribute is
        what the document says under ``conditions[name]`` (``cond.to_json()`` is that entry).
    document
        The certificate document (``to_dict()``), which :func:`verify` re-checks.
    """

    verdict: str
    dynamics: str
    conditions: "Mapping[str, ConditionResult]"
    document: dict[str, Any]

    def __post_init__(self) -> None:
        # the attributes say what the document says: a class's default property (PROPERTY) and
        # which disturbances a claim covers are set on every condition, not only in its JSON
        from dataclasses import replace

        described = self.document.get("conditions", {})
        aligned = {name: replace(cond, property=described.get(name, {}).get("property", cond.proves()),
                                 disturbances=described.get(name, {}).get("disturbances", cond.disturbances))
                   for name, cond in self.conditions.items()}
        object.__setattr__(self, "conditions", aligned)

    @property
    def answers(self) -> dict[str, dict[str, Any]]:
        """The document's ``answers`` (see the class docstring)."""
        import copy

        return copy.deepcopy(self.document.get("answers") or {})

    def unmet(self, require: str | Sequence[str]) -> list[str]:
        """The names of ``require`` (``"GAS,safety"``, as ``--require``) that no certified condition meets."""
        from lyapcheck.answers import parse_requirements, unmet_requirements

        return unmet_requirements(self.document.get("conditions") or {}, parse_requirements(require))

    def V(self, condition: str, output: str | None = None) -> Any:
        """The certified ``V`` of a model's ``condition`` exactly, as a sympy expression in the
        declared states (``x - x_eq`` where the equilibrium is not 0; a box's parameters by name);
        ``sos_bound`` has one per ``output``. A one-line :class:`InvalidParameter` where there is
        none (the condition is not certified, or states no V)."""
        from lyapcheck.models.classes.claims import v_expression

        cond = self.document.get("conditions", {}).get(condition)
        if not isinstance(cond, dict) or cond.get("status") != "certified":
            raise InvalidParameter("condition", "a certified condition of this result",
                                   condition if cond is None else f"{condition} ({cond.get('status')})")
        cert = cond.get("certificate") or {}
        if output is not None or "outputs" in cert:
            outputs = cert.get("outputs") or {}
            if output not in outputs:
                raise InvalidParameter("output", f"one of {', '.join(outputs) or 'no outputs'}", output)
            cert = outputs[output]
        if "V" not in cert or "variables" not in cert:
            raise InvalidParameter("condition", "a condition whose certificate states a V", condition)
        return v_expression(cert["V"], cert["variables"], self.document.get("equilibrium") or {})

    def __repr__(self) -> str:
        from lyapcheck.notebook import certify_repr

        return certify_repr(self.document)

    def _repr_html_(self) -> str:
        from lyapcheck.notebook import certify_html

        return certify_html(self.document)

    def to_dict(self) -> dict[str, Any]:
        """The certificate document (what ``certify --json`` prints), as a copy: editing it (as a
        test that forges a certificate does) leaves this result untouched."""
        import copy

        return copy.deepcopy(self.document)

    def to_json(self) -> dict[str, Any]:
        """The same as :meth:`to_dict` (a dict, not a string: ``json.dumps`` it to write it)."""
        return self.to_dict()

    def write(self, path: str | Path) -> Path:
        """Write the certificate file (atomically: a reader never sees half a file)."""
        from lyapcheck.fileio import atomic_write

        return atomic_write(path, json.dumps(self.document, indent=2) + "\n")


def certify(params: Any = None, *, model: "str | Path | Model | None" = None,
            settings: Mapping[str, object] | Sequence[str] | None = None, candidate: str | None = None,
            box: Sequence[str] | Mapping[str, Any] | None = None,
            dynamics: str = "derived", classes: str | Sequence[str] | None = None,
            linear_views: bool = False, overrides: Mapping[str, object] | None = None,
            worst_case: bool = False, worst_case_budget_s: float = 20.0, degree: int | None = None,
            time_limit_s: float | None = None) -> CertifyResult:
    """Certify a gain set of the paper's loop, or any closed loop from a model file; every class
    is checked exactly.

    Parameters
    ----------
    params
        A model file's path (recognised by its ``[model]`` or ``[dynamics]`` table, as ``model``), or
        the paper's parameters (see :func:`problem_from`). Without ``omega_so`` or ``d_max`` the
        paper's classes that need them are ``not_applicable`` and the others still run.
    model
        Instead of ``params``: a model file (docs/model-files.md), as a path or a loaded
        :class:`lyapcheck.models.language.modelfile.Model`. Its classes are ``linearization``,
        ``quadratic``, ``sos_gas``, ``roa``, ``candidate`` and ``sos_bound``.
    settings
        With ``model``: parameter (or disturbance-bound) values laid over the file's, as a mapping
        ``{"mu": 2}`` or ``["mu=2"]`` (the command line's ``--set``).
    candidate
        With ``model``: the user's own ``V`` (an expression in the states), for class ``candidate``.
    box
        With ``model``: a box of its parameters, ``["mu=0.8..1.2"]`` or ``{"mu": (0.8, 1.2)}``: each
        certified class then holds for every parameter value of the box (``quadratic``, ``sos_gas``,
        ``roa``, ``sos_bound``).
    dynamics
        ``"derived"`` (lyapcheck's derivation) or ``"printed"`` (the paper's eqs. ``los3``,
        ``xCrossdyn2`` as printed).
    classes
        ``None`` for all, ``"quick"`` for the quadratic and arithmetic classes, or names.
    linear_views
        Add python-control views (poles, the Lyapunov P for Gamma = I) under ``linear_views``.
    overrides
        Values laid over ``params`` (as the command-line flags are laid over the TOML file).
    degree
        With ``model``: the largest polynomial degree each class searches (``--degree``; None: each
        class's own ladder, :mod:`lyapcheck.degrees`).
    time_limit_s
        With ``model``: each class's time limit in seconds (``--time-limit``; None: 60 s,
        :data:`lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S`).
    worst_case
        Also search the worst disturbance ``|d| <= d*`` in simulation (about 10-20 s) and report,
        beside each certified ultimate bound, the worst simulated tail ``sup |eps|`` and
        ``tightness_ratio`` = certified / simulated (>= 1 unless the bound is unsound).
    """
    from lyapcheck.models.language.modelfile import is_model_file

    if model is None and is_model_file(params):  # a model file given where the paper's gain file would be
        model, params = params, None
    if model is not None:
        if params is not None or overrides:
            raise InvalidParameter("model", "given without the paper's parameters (a model file carries its own)",
                                   str(params if params is not None else overrides))
        return certify_model_file(model, settings=settings, candidate=candidate, classes=classes, box=box,
                                  degree=degree, time_limit_s=time_limit_s)
    if degree is not None or time_limit_s is not None:
        raise InvalidParameter("degree" if degree is not None else "time_limit_s", "used with a model file "
                               "(model=...)", degree if degree is not None else time_limit_s)
    if settings or candidate is not None:
        raise InvalidParameter("set" if settings else "candidate", "used with a model file (model=...)",
                               settings if settings else candidate)
    from lyapcheck.paper.certificate import build_document
    from lyapcheck.paper.certification import run_conditions, verdict

    problem = problem_from(params, overrides)
    results = run_conditions(problem, dynamics, class_selection(classes))
    if worst_case:
        add_tightness(results, problem, budget_s=worst_case_budget_s)
    outcome = verdict(results)
    doc = build_document(problem, dynamics, results, outcome)
    if linear_views:
        from lyapcheck.paper.certification import build_system
        from lyapcheck.paper.linalg_views import linear_views as views

        doc["linear_views"] = views(build_system(problem, dynamics))
    return CertifyResult(verdict=outcome, dynamics=dynamics, conditions=results, document=doc)


def model_settings(settings: Mapping[str, object] | Sequence[str] | None, source: str | None = None
                   ) -> dict[str, object]:
    """``{"mu": 2}`` or ``["mu=2"]`` (``--set``) as a mapping.

    A malformed or repeated entry is a one-line error: a :class:`ModelFileError` naming ``source``
    (the model file the settings go with) when given, else an :class:`InvalidParameter`.
    """
    if settings is None:
        return {}
    if isinstance(settings, Mapping):
        return {str(k): v for k, v in settings.items()}

    def refuse(expected: str, item: object) -> Exception:
        if source is None:
            return InvalidParameter("set", expected, item)
        return ModelFileError(source, "set", f"must be {expected}, got {item!r}")

    out: dict[str, object] = {}
    for item in settings:
        name, sep, value = str(item).partition("=")
        if not sep or not name.strip() or not value.strip():
            raise refuse("NAME=VALUE, e.g. 'mu=2' or 'd=0.1 mm/s'", item)
        if name.strip() in out:
            raise refuse(f"each name once (got '{name.strip()}' twice)", item)
        out[name.strip()] = value.strip()
    return out


def load_model_file(model: "str | Path | Model", settings: Mapping[str, object] | Sequence[str] | None = None
                    ) -> "Model":
    """A validated model (a path is read; a loaded model gets ``settings`` laid over its parameters)."""
    from lyapcheck.models.language.modelfile import Model, load_model, parse_model

    source = model.source if isinstance(model, Model) else str(model) if isinstance(model, (str, Path)) else None
    extra = model_settings(settings, source)
    if isinstance(model, Model):
        if not extra:
            return model
        return parse_model(model.text, model.source, {**model.overrides, **extra})
    if not isinstance(model, (str, Path)):
        raise InvalidParameter("model", "a model file path or a Model", type(model).__name__)
    return load_model(model, extra)


def _recast_model(model: object, settings: Mapping[str, object] | Sequence[str] | None, candidate: str | None
                  ) -> "RecastModel | None":
    """The model as a loop with functions (lyapcheck.models.language.recast), or None when it is polynomial."""
    from lyapcheck.models.language.modelfile import Model, file_uses_functions, load_any_model, parse_any_model

    if isinstance(model, Model) or (isinstance(model, (str, Path)) and not file_uses_functions(model)):
        return None  # a polynomial loop: read once, by the caller (and lyapcheck.models.language.recast not imported)
    from lyapcheck.models.language.recast import RecastModel

    with _settings_named():
        if isinstance(model, RecastModel):
            extra = model_settings(settings, model.source)
            reread = parse_any_model(model.text, model.source, {**model.overrides, **extra}, candidate)
            return reread if isinstance(reread, RecastModel) else None
        if not isinstance(model, (str, Path)):
            return None
        extra = model_settings(settings, str(model))
        loaded = load_any_model(model, extra, candidate)
        return loaded if isinstance(loaded, RecastModel) else None


def certify_extremum(model: "str | Path | Model", parameter_range: str, *, direction: str = "max",
                     steps: int | str | None = None, settings: Sequence[str] | None = None, candidate: str | None = None,
                     classes: str | Sequence[str] | None = None, require: str | Sequence[str] | None = None,
                     degree: int | None = None, time_limit_s: float | None = None) -> Any:
    """The largest (``direction="max"``) or smallest (``"min"``) value of one parameter or disturbance
    bound at which certifying ``model`` succeeds (``certify`` would exit 0: no negative answer, some
    claim proved, every ``require`` met), by bisection with a whole exact certification at each value
    (:mod:`lyapcheck.models.surfaces.extremum`).

    Parameters
    ----------
    parameter_range
        ``"NAME=LO..HI"``, numbers in the model file's units.
    steps
        Bisection steps after the two ends (default :data:`~lyapcheck.models.surfaces.extremum.DEFAULT_STEPS`).
    settings, candidate, classes, require, degree, time_limit_s
        As for :func:`certify` (``settings`` may not set the searched parameter).

    Returns
    -------
    Extremum
        ``proved`` (the value, or None), ``proved_result`` (its :class:`CertifyResult`), ``failed`` (the
        first value that failed, with ``outcome`` "refuted" or "not proved"), ``steps``, ``sentence()``.
    """
    from lyapcheck.answers import OK_VERDICTS, parse_requirements, unmet_requirements
    from lyapcheck.models.surfaces import extremum

    flag = "maximize" if direction == "max" else "minimize"
    if direction not in ("max", "min"):
        raise InvalidParameter("direction", '"max" or "min"', direction)
    name, low, high = extremum.parse_range(parameter_range, flag)
    count = extremum.DEFAULT_STEPS if steps is None else extremum.check_steps(steps)
    base = list(settings or ())
    if any(str(s).partition("=")[0].strip() == name for s in base):
        raise InvalidParameter("set", f"a parameter other than the one --{flag} searches ({name})",
                               next(s for s in base if str(s).partition("=")[0].strip() == name))
    required = parse_requirements(require)

    def certify_at(value: str) -> tuple[dict[str, Any], bool, Any]:
        try:
            found = certify_model_file(model, settings=[*base, f"{name}={value}"], candidate=candidate,
                                       classes=classes, time_limit_s=time_limit_s, degree=degree)
        except ModelFileError as exc:
            if exc.key != f"settings['{name}']":
                raise
            # the searched name is the flag's, not a --set the user gave: say so
            raise ModelFileError(exc.source, f"--{flag} {name}",
                                 str(exc).removeprefix(f"{exc.source}: {exc.key}: ")) from None
        doc = found.to_json()
        passed = doc.get("verdict") in OK_VERDICTS and not unmet_requirements(doc.get("conditions") or {}, required)
        return doc, passed, found

    return extremum.search(name, low, high, direction, certify_at, count)


def tune(model: "str | Path | Model", box: Sequence[str], objective: str, *, grid: int | str | None = None,
         settings: Mapping[str, object] | Sequence[str] | None = None, classes: str | Sequence[str] | None = None,
         require: str | Sequence[str] | None = None, degree: int | None = None,
         time_limit_s: float | None = None) -> Any:
    """The gains in a box of a model's parameters with the best certified figure (``lyapcheck tune``):
    a grid, one refinement around its best point, the winner certified again, and a neighbourhood
    proved with a box certificate (:mod:`lyapcheck.models.surfaces.tune`).

    Parameters
    ----------
    box
        ``["kp=0.5..4", "ki=0.25..2"]``: the parameters searched, decimal numbers in the file's units.
    objective
        ``"decay_rate"``, ``"roa"``, ``"bound:OUTPUT"``, ``"safety:PARAM=LO..HI"`` or
        ``"safety:min:PARAM=LO..HI"``.
    grid
        Points per axis (default :data:`~lyapcheck.models.surfaces.tune.DEFAULT_GRID`).
    settings, degree, time_limit_s
        As for :func:`certify` (``settings`` may not set a searched parameter).
    classes
        Classes run at every point besides the objective's own (default: the objective's alone).
    require
        Properties a point must also prove to count (as ``certify --require``).

    Returns
    -------
    Tuning
        ``tried`` (every point with its figure or outcome), ``winner``, ``value`` (exact), ``result``
        (the winner's :class:`CertifyResult`), ``neighbourhood``, ``document()`` (its certificate with the
        ``tune`` table, which :func:`verify` re-checks).
    """
    from lyapcheck.answers import parse_requirements, unmet_requirements
    from lyapcheck.models.classes.registry import NAMES, OVER_BOX
    from lyapcheck.models.language.modelfile import Model, load_any_model
    from lyapcheck.models.surfaces import tune as tuning
    from lyapcheck.models.surfaces.extremum import NEGATIVE_VERDICTS, decimal
    from lyapcheck.models.surfaces.extremum import search as bisection

    count = tuning.DEFAULT_GRID if grid is None else tuning.check_grid(grid)
    source = model.source if isinstance(model, Model) else str(model)
    base = [f"{k}={v}" for k, v in model_settings(settings, source).items()]
    with _settings_named():
        loaded = load_model_file(model, base) if isinstance(model, Model) else load_any_model(model, model_settings(base))
    if getattr(loaded, "time", "continuous") == "discrete":  # its figures are per step, and a box is refused on a map
        raise ModelFileError(source, "[model] time", 'tune takes continuous-time loops; a discrete-time map (time = '
                                                     '"discrete") is certified value by value (--set, --maximize)')
    goal = tuning.parse_objective(objective, loaded)
    if goal.kind == "safety" and any(s.partition("=")[0] == goal.target for s in base):
        raise ModelFileError(source, "--objective", f"must search a parameter not given by --set; got {objective!r} "
                                                    f"with --set {goal.target}")
    with _argument_names():
        boxes = tuning.parse_boxes([str(b) for b in box], loaded, goal, base, count)
    required = parse_requirements(require)
    extra = [c.strip() for c in (classes.split(",") if isinstance(classes, str) else classes or ()) if c.strip()]
    if any(c not in NAMES for c in extra):  # refused once, not at every point
        raise InvalidParameter("classes", "names among " + ", ".join(NAMES), classes)
    chosen = ",".join(dict.fromkeys([goal.cls, *extra]))
    centre = [f"{n}={decimal(tuning.axis_values(lo, hi, 1)[0])}" for n, lo, hi in boxes]
    with _settings_named():  # every setting valid once, before any point is certified
        load_model_file(model, [*base, *centre]) if isinstance(model, Model) else \
            load_any_model(model, model_settings([*base, *centre]))

    def run(extra_settings: Sequence[str], over: Sequence[str] | None = None, which: str = chosen) -> dict[str, Any]:
        found = certify_model_file(model, settings=[*base, *extra_settings], classes=which, box=over,
                                   time_limit_s=time_limit_s, degree=degree)
        return {"doc": found.to_json(), "result": found}

    def judged(doc: dict[str, Any]) -> tuple[Any, str]:
        value, why = tuning.figure(goal, doc)
        if doc.get("verdict") in NEGATIVE_VERDICTS:
            return None, f"refuted ({doc.get('verdict')})"
        unmet = unmet_requirements(doc.get("conditions") or {}, required)
        if value is not None and unmet:
            return None, "unmet --require " + ",".join(unmet)
        return value, why

    def point_settings(values: Mapping[str, Any]) -> list[str]:
        return [f"{k}={decimal(v)}" for k, v in values.items()]

    def evaluate(values: dict[str, Any]) -> tuple[Any, str, dict[str, Any]]:
        try:
            if goal.kind != "safety":
                return (*judged(run(point_settings(values))["doc"]), {})

            def certify_at(v: str) -> tuple[dict[str, Any], bool, Any]:
                done = run([*point_settings(values), f"{goal.target}={v}"])
                return done["doc"], judged(done["doc"])[0] is not None, None

            found = bisection(goal.target, goal.low, goal.high, goal.sense, certify_at, tuning.SAFETY_STEPS)
            detail = {"margin_tried": len(found.steps),
                      "first_failed": None if found.failed is None else decimal(found.failed.value),
                      "first_failed_outcome": None if found.failed is None else found.failed.outcome}
            if found.proved is None:
                return None, f"no {goal.target} in {decimal(goal.low)}..{decimal(goal.high)} proved safe", detail
            return found.proved, "certified", detail
        except ModelFileError as exc:  # a point the model refuses (a divisor that vanishes there)
            return None, f"refused: {exc}", {}

    tried = tuning.search(boxes, count, goal.sense, evaluate)
    found = tuning.Tuning(goal, boxes, count, tried, settings=base)
    best = tuning.best_point(tried, goal.sense)
    if best is None or best.value is None:
        found.why = f"none of the {len(tried)} points tried proved it"
        return found
    margin = [f"{goal.target}={decimal(best.value)}"] if goal.kind == "safety" else []
    again = run([*point_settings(best.values), *margin])
    value, why = judged(again["doc"])
    if value is None:
        found.why = f"the best point did not certify again ({why})"
        return found
    found.winner, found.value, found.result = best, value, again["result"]

    def certify_box(texts: list[str], need: Any) -> tuple[Any, str, dict[str, Any] | None]:
        at = [f"{goal.target}={decimal(need)}"] if goal.kind == "safety" else []
        try:
            done = run(at, over=texts, which=goal.cls)
        except (ModelFileError, InvalidParameter) as exc:
            return None, f"refused: {exc}", None
        got, word = tuning.figure(goal, done["doc"], need)
        return got, word, done["doc"]

    found.neighbourhood = tuning.neighbourhood(goal, boxes, best.values, value, count, certify_box, goal.cls in OVER_BOX)
    return found


def certify_model_file(model: "str | Path | Model", *, settings: Mapping[str, object] | Sequence[str] | None = None,
                       candidate: str | None = None, classes: str | Sequence[str] | None = None,
                       time_limit_s: float | None = None, box: Sequence[str] | Mapping[str, Any] | None = None,
                       degree: int | None = None) -> CertifyResult:
    """:func:`certify` for a model file (``certify(model=...)`` calls this)."""
    from lyapcheck.degrees import check_degree, degree_ceiling

    if time_limit_s is not None and not (isinstance(time_limit_s, (int, float)) and 0 < time_limit_s < float("inf")):
        raise InvalidParameter("time_limit_s", "a number of seconds > 0", time_limit_s)
    with degree_ceiling(check_degree(degree)):
        return _certify_model_file(model, settings=settings, candidate=candidate, classes=classes,
                                   time_limit_s=time_limit_s, box=box)


def _certify_model_file(model: "str | Path | Model", *, settings: Mapping[str, object] | Sequence[str] | None,
                        candidate: str | None, classes: str | Sequence[str] | None, time_limit_s: float | None,
                        box: Sequence[str] | Mapping[str, Any] | None) -> CertifyResult:
    from lyapcheck.models.loop.boxes import parse_model_box
    from lyapcheck.models.surfaces.certificate import build_document
    from lyapcheck.models.surfaces.certify import certify_model

    sampled = _certify_sampled(model, settings=settings, candidate=candidate, classes=classes, box=box)
    if sampled is not None:
        return sampled
    recast = _recast_model(model, settings, candidate)
    loaded: "Model | RecastModel"
    if recast is not None:  # a loop with functions over a box is read at the box's centre
        loaded, parsed = _recast_at_box_centre(recast, settings, candidate, box) if box else (recast, None)
    else:
        polynomial = _load_with_settings(model, settings)
        with _argument_names():
            parsed = parse_model_box(polynomial, box) if box else None
        loaded = polynomial
    with _argument_names():
        found = certify_model(loaded, classes=classes, candidate=candidate, time_limit_s=time_limit_s, box=parsed)
    return CertifyResult(verdict=found.verdict, dynamics="model", conditions=found.results,
                         document=build_document(found))


def _certify_sampled(model: "str | Path | Model", *, settings: Mapping[str, object] | Sequence[str] | None,
                     candidate: str | None, classes: str | Sequence[str] | None,
                     box: Sequence[str] | Mapping[str, Any] | None) -> CertifyResult | None:
    """A sampled-data model file's certification (:mod:`lyapcheck.models.surfaces.sampled_run`), or None
    when the file is not one."""
    from lyapcheck.models.language.sampling import file_is_sampled

    if not (isinstance(model, (str, Path)) and file_is_sampled(model)):
        return None
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces.sampled_run import build_sampled_document, certify_sampled

    for given, what in ((box, "box"), (candidate, "candidate")):
        if given:
            raise InvalidParameter(what, f"nothing on a sampled-data loop ({model}: [sampling]): its linearization "
                                         "over one period is decided at the file's parameters", given)
    with _settings_named():
        loaded = load_sampled(model, model_settings(settings, str(model)))
    with _argument_names():
        results = certify_sampled(loaded, classes)
    document = build_sampled_document(loaded, results)
    return CertifyResult(verdict=document["verdict"], dynamics="model", conditions=results, document=document)


def _recast_at_box_centre(recast: "RecastModel", settings: Mapping[str, object] | Sequence[str] | None,
                          candidate: str | None, box: Sequence[str] | Mapping[str, Any]) -> tuple["RecastModel", Any]:
    """A loop with functions over a box: the box (one-line errors naming ``box``), and the model read
    again with each box parameter at the box's centre (an override, so that the certificate's
    ``overrides`` say where the centre is and ``verify`` reads the same model)."""
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.loop.boxes import parse_box_of
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    with _argument_names():
        parsed = parse_box_of(recast.source, recast.parameters, box)
    given = model_settings(settings, recast.source)
    twice = [name for name in parsed.names if name in given]
    if twice:
        raise ModelFileError(recast.source, f"--box {twice[0]}", "also given with --set: a box parameter takes its "
                                                                  "values from the box")
    centres = {name: exact_decimal(parsed.center(name)) for name in parsed.names}
    with _settings_named():
        reread = parse_any_model(recast.text, recast.source, {**recast.overrides, **centres}, candidate)
    assert isinstance(reread, RecastModel)
    return reread, parsed


def add_tightness(results: "Mapping[str, ConditionResult]", problem: "Problem", *, budget_s: float) -> None:
    """Put the worst simulated tail ``sup |eps|`` beside every certified ultimate bound.

    The search runs on the real loop (saturated ODS command, the paper-ilos settings) with
    ``|d_mu| <= d*``; a ratio below 1 would be a soundness violation and is said so.
    """
    from lyapcheck.paper.simulation.worst_case import search_worst_case

    bounds = [r for name, r in results.items() if name in ("ultimate_bound", "sos_bound") and r.status == "certified"]
    if not bounds or problem.d_max is None:
        return
    storage = results["sos_bound"].certificate if "sos_bound" in results and \
        results["sos_bound"].status == "certified" else None
    found = search_worst_case(problem, budget_s=budget_s, storage=storage)
    for result in bounds:
        certified = float(result.numbers["eps_bound_m"])
        ratio = found.tightness_ratio(certified)
        result.numbers["worst_case_sup_abs_eps_tail_m"] = found.sup_abs_eps_tail_m
        result.numbers["tightness_ratio"] = ratio
        result.numbers["worst_case_disturbance"] = found.disturbance
        if ratio < 1:
            result.numbers["soundness_violation"] = True


def certify_box(params: Any = None, box: Sequence[str] | Any = (), *, dynamics: str = "derived",
                overrides: Mapping[str, object] | None = None, classes: str | Sequence[str] | None = None
                ) -> CertifyResult:
    """Condition classes for every gain set in a box (``["alpha_d=540..660", "k_d=0.1..0.2"]``), one exact proof each.

    The parameters not in the box are taken from ``params`` / ``overrides``; see
    :mod:`lyapcheck.paper.boxes.quadratic` for why a check at the corners covers the whole box. ``classes``:
    names among :data:`lyapcheck.paper.boxes.classes.BOX_CLASSES` (comma-separated or a list, or ``"all"``;
    default :data:`lyapcheck.paper.boxes.classes.DEFAULT_BOX_CLASSES`, the paper's eq. ``stabCond`` and the GES
    classes; ``sos_bound`` adds a bound on ``|eps|`` for the whole box, 5-10 s, and with
    ``saturated_loop`` that bound holds for the real, saturated loop).
    The result's document is a certificate that :func:`verify` re-checks without a solver.
    """
    from lyapcheck.paper.boxes.classes import BOX_CLASSES, DEFAULT_BOX_CLASSES, certify_box as prove_box
    from lyapcheck.paper.boxes.box import ParameterBox, parse_box
    from lyapcheck.paper.certificate import build_box_document
    from lyapcheck.results import ConditionResult

    chosen = _box_classes(classes, BOX_CLASSES) if classes is not None else list(DEFAULT_BOX_CLASSES)
    parsed = box if isinstance(box, ParameterBox) else parse_box(list(box))
    problem = problem_from(_box_filled(params, overrides, parsed))
    if dynamics not in ("derived", "printed"):
        raise InvalidParameter("dynamics", "one of 'derived', 'printed'", dynamics)
    results = {cls: prove_box(problem, parsed, dynamics, cls) for cls in chosen}
    doc = build_box_document(problem, parsed, dynamics, results)
    conditions = {
        cls: ConditionResult(cls, result["status"], result["summary"],
                             numbers={k: v for k, v in result.items()
                                      if k not in ("status", "summary", "certificate", "solver", "property", "refutation")},
                             certificate=result.get("certificate", {}), solver=result.get("solver", {}),
                             refutation=result.get("refutation") or {})
        for cls, result in results.items()}
    return CertifyResult(verdict=doc["verdict"], dynamics=dynamics, conditions=conditions, document=doc)


def _box_classes(classes: str | Sequence[str] | None, allowed: Sequence[str]) -> list[str]:
    """The box classes asked for, in the order of ``allowed`` (one-line error naming the field)."""
    if classes is None or classes == "all":
        return list(allowed)
    names = [c.strip() for c in (classes.split(",") if isinstance(classes, str) else classes)]
    if not names or any(n not in allowed for n in names):
        raise InvalidParameter("classes", "box classes among " + ", ".join(allowed), ",".join(map(str, names)))
    return [c for c in allowed if c in names]


def _box_filled(params: Any, overrides: Mapping[str, object] | None, box: Any) -> Any:
    """Parameters with each boxed one set to its interval's low end (a valid placeholder)."""
    from lyapcheck.paper.boxes.box import BOX_FIELDS
    from lyapcheck.paper.params import FIELD_BY_KEY, Problem

    def placeholder(key: str, value: Any) -> str:  # the corners set the exact values
        return f"{float(value)!r} {FIELD_BY_KEY[key].kind.si_unit or ''}".strip()

    lows = {BOX_FIELDS[name]: placeholder(BOX_FIELDS[name], lo) for name, lo, _ in box.bounds}
    if isinstance(params, Problem):
        params = dict(params.given)
    if params is None or isinstance(params, (str, Path)):
        from lyapcheck.paper.params import flatten_tables, load_toml

        params = {} if params is None else flatten_tables(load_toml(params), str(params))
    return {**flat_parameters(params), **flat_parameters(overrides or {}), **lows}


# -- verify --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Check:
    """One exact re-check of a certificate file."""

    check: str
    ok: bool
    message: str

    def to_json(self) -> dict[str, Any]:
        return {"check": self.check, "ok": self.ok, "message": self.message}


@dataclass(frozen=True, repr=False)
class VerifyResult:
    """``valid`` when every claim of the certificate passes its exact re-check; ``checks`` says
    which (a short ``repr`` lists the failing ones; ``to_dict()`` has all)."""

    valid: bool
    checks: tuple[Check, ...]

    def __repr__(self) -> str:
        from lyapcheck.notebook import verify_repr

        return verify_repr(self.to_dict())

    def _repr_html_(self) -> str:
        from lyapcheck.notebook import verify_html

        return verify_html(self.to_dict())

    def to_dict(self) -> dict[str, Any]:
        """What ``verify --json`` prints."""
        return {"valid": self.valid, "checks": [c.to_json() for c in self.checks]}

    def to_json(self) -> dict[str, Any]:
        """The same as :meth:`to_dict`."""
        return self.to_dict()


def verify(certificate: str | Path | Mapping[str, Any] | CertifyResult) -> VerifyResult:
    """Re-check a certificate exactly, without a solver (file path, document or result): the
    paper's certificates and model-file certificates alike."""
    from lyapcheck.paper.certificate import check_document, verify_document
    from lyapcheck.models.surfaces import certificate as model_certificate

    if isinstance(certificate, CertifyResult):
        doc = certificate.document
    elif isinstance(certificate, (str, Path)):
        doc = model_certificate.read_json(certificate)
        if not model_certificate.is_model_document(doc):
            doc = check_document(doc, f"'{certificate}'")
    elif isinstance(certificate, Mapping):
        doc = dict(certificate)
        if not model_certificate.is_model_document(doc):
            doc = check_document(doc, "the certificate mapping")
    else:
        raise InvalidParameter("certificate", "a path, a certificate document or a CertifyResult",
                               type(certificate).__name__)
    rows = model_certificate.verify_document(doc) if model_certificate.is_model_document(doc) else verify_document(doc)
    if model_certificate.is_model_document(doc):  # a search's table: tune's value and neighbourhood, --maximize's value
        from lyapcheck.models.surfaces.search_tables import search_rows

        rows = [*rows, *search_rows(doc)]
    checks = tuple(Check(n, ok, m) for n, ok, m in rows)
    return VerifyResult(valid=all(c.ok for c in checks), checks=checks)


# -- simulate ------------------------------------------------------------------------------------
@dataclass(frozen=True, repr=False)
class SimulationReport:
    """What ``lyapcheck simulate`` measured (SI; the keys of DESIGN.md come first).

    Attributes
    ----------
    diverged
        A trajectory diverged (or, with a certificate, a simulated figure exceeds a certified bound).
    document
        The ``--json`` document (``to_dict()``; ``result["key"]`` reads one key).
    series
        The simulated time series as an :class:`xarray.Dataset` with ``time`` (s) as a coordinate:
        for a model, ``x`` (trajectory, time, state) and ``y`` (trajectory, time, output), the
        trajectories numbered as ``document["trajectories"]`` (:mod:`lyapcheck.models.engines.series`); for
        the paper's loop, ``p_x``, ``p_z``, ``s``, ``eps``, ``u_x``, ``u_z``, ``v_x``, ``v_z``, ``d_x``,
        ``d_z`` over time. None for a worst-case search, or with ``series=False``.
    """

    diverged: bool
    document: dict[str, Any]
    series: Any = None

    def __getitem__(self, key: str) -> Any:
        return self.document[key]

    def __repr__(self) -> str:
        from lyapcheck.notebook import simulation_repr

        return simulation_repr(self.document, self.series)

    def _repr_html_(self) -> str:
        from lyapcheck.notebook import simulation_html

        return simulation_html(self.document)

    def to_dict(self) -> dict[str, Any]:
        """The ``--json`` document (the object itself, not a copy)."""
        return self.document

    def to_json(self) -> dict[str, Any]:
        """The same as :meth:`to_dict`."""
        return self.document


def simulate(scenario: str | Path | None = None, *, preset: str | None = None,
             plot: str | Path | None = None, worst_case: bool = False, budget_s: float = 20.0,
             model: "str | Path | Model | None" = None, settings: Mapping[str, object] | Sequence[str] | None = None,
             x0: Any = (), grid: int | None = None, t_end: str | float | None = None,
             scenarios: Sequence[str] | None = None, frequencies: str | None = None,
             certificate: str | Path | None = None, series: bool = True, steps: int | str | None = None
             ) -> SimulationReport:
    """Simulate the saturated ILOS/ODS closed loop (a scenario TOML or one of the paper's presets),
    or any closed loop from a model file (``model=``; its arguments ``settings``, ``x0``, ``grid``,
    ``t_end``, ``scenarios``, ``frequencies``, ``certificate`` and, for a discrete-time map, ``steps`` are
    :func:`simulate_model_file`'s).

    Parameters
    ----------
    scenario
        Path of a scenario TOML (``examples/scenario-*.toml``), or of a model file (recognised by its
        content, as ``model``); or give ``preset``.
    preset
        ``paper-ilos``, ``paper-los-600`` or ``paper-los-1200`` (the paper's Section 5).
    plot
        Also write the Section 5 figures to this PNG.
    worst_case
        Instead of the scenario's own disturbance, search the worst ``|d_mu| <= d*`` (constant,
        feedback, periodic at the loop's resonances, Pontryagin bang-bang, then a local search
        over the switching law) within ``budget_s`` seconds; the document gives
        ``sup_abs_eps_tail_m`` and the ``disturbance`` that produced it.
    series
        Keep the time series (:attr:`SimulationReport.series`, an :class:`xarray.Dataset`); False
        skips the sampling. A worst-case search keeps none.
    """
    from lyapcheck.models.language.modelfile import is_model_file

    if model is None and is_model_file(scenario):  # a model file given where a scenario would be
        model, scenario = scenario, None
    if model is not None:
        if scenario is not None or preset is not None:
            raise InvalidParameter("model", "given without a scenario or a preset (a model file is its own loop)",
                                   str(scenario if scenario is not None else preset))
        return simulate_model_file(model, settings=settings, x0=x0, grid=grid, t_end=t_end, scenarios=scenarios,
                                   frequencies=frequencies, worst_case=worst_case, budget_s=budget_s,
                                   certificate=certificate, plot=plot, series=series, steps=steps)
    model_only = {"settings": settings, "x0": x0, "grid": grid, "t_end": t_end, "scenarios": scenarios,
                  "frequencies": frequencies, "certificate": certificate, "steps": steps}
    given = [k for k, v in model_only.items() if v is not None and not (isinstance(v, (list, tuple)) and not v)]
    if given:
        raise InvalidParameter(given[0], "used with a model file (model=...; the paper's loop takes a scenario or a "
                               "preset)", model_only[given[0]])
    from lyapcheck.paper.simulation.scenario_run import run_scenarios, scenario_batch, simulation_document

    if plot is not None and Path(plot).suffix.lower() != ".png":
        raise InvalidParameter("plot", "a file name ending in .png", str(plot))
    if not (isinstance(budget_s, (int, float)) and 0 < budget_s < 3600):
        raise InvalidParameter("budget_s", "a number of seconds in (0, 3600)", budget_s)
    if worst_case:
        if plot is not None:
            raise InvalidParameter("plot", "left out with worst_case=True", str(plot))
        from lyapcheck.paper.simulation.worst_case import search_worst_case

        chosen, _, _ = scenario_batch(None if scenario is None else str(scenario), preset)
        found = search_worst_case(chosen, budget_s=float(budget_s))
        return SimulationReport(diverged=False, document={"scenario": chosen.name, "mode": "worst_case",
                                                          **found.to_json()})
    chosen, batch, index = scenario_batch(None if scenario is None else str(scenario), preset,
                                          with_all_presets=plot is not None)
    result = run_scenarios(batch, record=plot is not None or series)
    doc = simulation_document(chosen, result, index)
    if plot is not None:
        from lyapcheck.paper.simulation.plots import section5_figure

        section5_figure(batch, result, str(plot))
        doc["plot"] = str(plot)
    dataset = _paper_series(result.trajectories[index], doc) if series and result.trajectories else None
    return SimulationReport(diverged=bool(doc["diverged"]), document=doc, series=dataset)


def _paper_series(trajectory: Any, doc: Mapping[str, Any]) -> Any:
    """The paper loop's recorded trajectory as an :class:`xarray.Dataset` over ``time`` (SI)."""
    import xarray as xr

    variables = {"p_x": (trajectory.p[:, 0], "m"), "p_z": (trajectory.p[:, 1], "m"), "s": (trajectory.s, "m"),
                 "eps": (trajectory.eps, "m"), "u_x": (trajectory.u[:, 0], "rad/s"),
                 "u_z": (trajectory.u[:, 1], "rad/s"), "v_x": (trajectory.v[:, 0], "m/s"),
                 "v_z": (trajectory.v[:, 1], "m/s"), "d_x": (trajectory.d[:, 0], "m/s"),
                 "d_z": (trajectory.d[:, 1], "m/s")}
    return xr.Dataset({name: ("time", values, {"units": unit}) for name, (values, unit) in variables.items()},
                      coords={"time": ("time", trajectory.t, {"units": "s"})},
                      attrs={"scenario": str(doc["scenario"]), "controller": str(doc["controller"]),
                             "ods_form": str(doc["ods_form"])})


def simulate_model_file(model: "str | Path | Model", *, settings: Mapping[str, object] | Sequence[str] | None = None,
                        x0: Any = (), grid: int | None = None, t_end: str | float | None = None,
                        scenarios: Sequence[str] | None = None, frequencies: str | None = None,
                        worst_case: bool = False, budget_s: float = 20.0, certificate: str | Path | None = None,
                        plot: str | Path | None = None, series: bool = True, steps: int | str | None = None
                        ) -> SimulationReport:
    """``lyapcheck simulate --model``: the model's closed loop from its starts under its disturbance
    scenarios, batched (:mod:`lyapcheck.models.surfaces.simulate`; docs/simulation.md has the JSON keys). A
    loop with functions is the same, on its true loop (:func:`~lyapcheck.models.surfaces.simulate.prepare`).

    Errors name these arguments (``x0``, ``t_end``, ``settings``, ...): an
    :class:`~lyapcheck.errors.InvalidParameter`, or a :class:`~lyapcheck.errors.ModelFileError` for
    the model file and the ``settings`` laid over it.

    Parameters
    ----------
    model, settings
        The model file (or a loaded model) and values laid over its parameters (``{"mu": 2}`` or
        ``["mu=2"]``, the command line's ``--set``).
    x0
        The starts (missing states at the equilibrium; values are numbers or unit strings): one start
        as a mapping ``{"x1": 1, "x2": 0}``, a sequence of one number per state ``[1, 0]`` or a text
        ``"x1=1 x2=0"``; or a list of such starts (a 2-D array: one row per start). Default: the
        equilibrium and a grid over the model's ``[domain]`` (without one, a start on each side of the
        equilibrium along each state).
    grid
        Also a grid of this many points per state over the model's ``[domain]``.
    t_end, frequencies
        The horizon (seconds, or a unit string) and the square waves' band (``"0.1..10"``: rad/s, or Hz).
    scenarios
        Among ``none``, ``constant``, ``bang-bang``, ``square`` (default: all that apply).
    worst_case, budget_s, certificate
        Search the worst disturbance within ``budget_s`` seconds instead; with a certificate file of
        class ``sos_bound``, report ``tightness_ratio`` = certified / worst simulated per output.
    plot
        Also write the figures to this PNG.
    series
        Keep the time series (:attr:`SimulationReport.series`: :mod:`lyapcheck.models.engines.series`);
        a worst-case search keeps none.
    steps
        A discrete-time map only (``[model] time = "discrete"``): the number of iterations (default
        :data:`~lyapcheck.models.surfaces.iterate.DEFAULT_STEPS`); the map is iterated, not integrated
        (:mod:`lyapcheck.models.surfaces.iterate`), and ``t_end``, ``frequencies``, scenarios other than
        ``none``, ``worst_case`` and ``certificate`` are refused there.

    A sampled-data file (``[sampling]``, ``[controller]``) is simulated by
    :func:`lyapcheck.models.surfaces.sampled_simulate.run_sampled`: the true plant between samples with each
    control held, over ``t_end`` (default: a number of periods from its linearization); ``worst_case``,
    ``certificate``, ``frequencies``, scenarios other than ``none``, ``steps`` and ``grid`` are refused there.
    """
    import numpy as np

    from lyapcheck.models.surfaces import simulate as sim

    if plot is not None and Path(plot).suffix.lower() != ".png":
        raise InvalidParameter("plot", "a file name ending in .png", str(plot))
    from lyapcheck.models.language.sampling import file_is_sampled

    if isinstance(model, (str, Path)) and file_is_sampled(model):  # the plant under held controls, period by period
        return _simulate_sampled(model, settings=settings, x0=x0, grid=grid, t_end=t_end, scenarios=scenarios,
                                 frequencies=frequencies, worst_case=worst_case, certificate=certificate, plot=plot,
                                 series=series, steps=steps)
    if certificate is not None and not worst_case:
        raise InvalidParameter("certificate", "used with worst_case=True (the tightness ratio compares the "
                               "certified bound with the worst case found)", str(certificate))
    if worst_case and scenarios:
        raise InvalidParameter("scenarios", "left out with worst_case=True (the search tries every family)",
                               ",".join(scenarios))
    # a loop with functions is simulated on its true loop by the same machinery (sim.prepare's constructors)
    recast = _recast_model(model, settings, None)
    loaded = recast if recast is not None else _load_with_settings(model, settings)
    from lyapcheck.models.language.modelfile import Model as FileModel
    from lyapcheck.models.loop.discrete import is_discrete

    if is_discrete(loaded):  # a map (with functions or not) is iterated, never integrated as a field
        return _iterate_map(loaded, x0=x0, grid=grid, t_end=t_end, scenarios=scenarios, frequencies=frequencies,
                            worst_case=worst_case, certificate=certificate, plot=plot, series=series, steps=steps)
    if steps is not None:
        raise InvalidParameter("steps", 'used with a discrete-time map ([model] time = "discrete"); a continuous-time '
                               "loop takes t_end", steps)
    prepared = sim.prepare(loaded)
    starts = model_starts(loaded, x0)  # type: ignore[arg-type]  # (a RecastModel has the states it reads)
    if grid is not None:
        starts += list(sim.grid_over_domain(loaded, grid))
    start_arr = np.array(starts) if starts else None
    horizon = sim.parse_horizon(str(t_end)) if t_end is not None else None
    band = sim.parse_frequencies(frequencies) if frequencies is not None else None
    plot_path = None if plot is None else str(plot)
    if worst_case:
        bounds = sim.certified_bounds_of(loaded, str(certificate)) if certificate is not None else None
        doc = sim.search_worst_case(loaded, starts=start_arr, t_end=horizon, frequencies=band, budget_s=budget_s,
                                    certified_bounds=bounds, plot=plot_path, prepared=prepared)
        dataset = None
    else:
        run = sim.run_model(loaded, starts=start_arr, scenarios=list(scenarios) if scenarios else None, t_end=horizon,
                            frequencies=band, plot=plot_path, prepared=prepared, series=series)
        doc, dataset = run.document, run.series
    return SimulationReport(diverged=bool(doc["diverged"] or doc.get("soundness_violation", False)), document=doc,
                            series=dataset)


def _iterate_map(model: "Model | RecastModel", *, x0: Any, grid: int | None, t_end: object, scenarios: Sequence[str] | None,
                 frequencies: object, worst_case: bool, certificate: object, plot: str | Path | None, series: bool,
                 steps: int | str | None) -> SimulationReport:
    """:func:`simulate_model_file` on a discrete-time map: its iterates
    (:func:`lyapcheck.models.surfaces.iterate.run_map`), the disturbances held at 0; what only a field
    takes is refused in one line naming ``time = "discrete"``."""
    import numpy as np

    from lyapcheck.models.loop.discrete import refuse
    from lyapcheck.models.surfaces import iterate
    from lyapcheck.models.surfaces import simulate as sim

    held = "its disturbances are held at 0"
    for name, given, instead in (("t_end (--t-end)", t_end is not None, "give the number of iterations (--steps N)"),
                                 ("frequencies (--frequencies)", frequencies is not None, held),
                                 ("worst_case (--worst-case)", worst_case, held),
                                 ("certificate (--certificate)", certificate is not None, held),
                                 ("scenarios (--scenario)", bool(scenarios) and list(scenarios or ()) != ["none"],
                                  held + " (scenario none)")):
        if given:
            refuse(model, name, instead)
    starts = model_starts(model, x0)  # type: ignore[arg-type]  # (a RecastModel has the states it reads)
    if grid is not None:
        starts += list(sim.grid_over_domain(model, grid))
    if starts:
        start_arr, how = sim._check_starts(model, np.array(starts)), "given"
    else:
        start_arr, how = iterate.default_starts(model)
    run = iterate.run_map(model, start_arr, how, steps=steps, plot=None if plot is None else str(plot), series=series)
    return SimulationReport(diverged=bool(run.document["diverged"]), document=run.document, series=run.series)


def _simulate_sampled(model: "str | Path", *, settings: Mapping[str, object] | Sequence[str] | None, x0: Any,
                      grid: int | None, t_end: str | float | None, scenarios: Sequence[str] | None,
                      frequencies: object, worst_case: bool, certificate: object, plot: str | Path | None,
                      series: bool, steps: object) -> SimulationReport:
    """:func:`simulate_model_file` on a sampled-data loop: the true plant between samples with each control
    held (:func:`lyapcheck.models.surfaces.sampled_simulate.run_sampled`); what does not apply is refused in
    one line naming the flag and ``[sampling]``."""
    import numpy as np

    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces import sampled_simulate
    from lyapcheck.models.surfaces import simulate as sim

    source = str(model)
    none = "it has no disturbances: only the scenario none applies"
    for name, given, instead in (("worst_case (--worst-case)", worst_case, none),
                                 ("certificate (--certificate)", certificate is not None, none),
                                 ("frequencies (--frequencies)", frequencies is not None, none),
                                 ("scenarios (--scenario)", bool(scenarios) and list(scenarios or ()) != ["none"],
                                  none),
                                 ("steps (--steps)", steps is not None, "it is integrated over time: give t_end "
                                                                        "(--t-end)"),
                                 ("grid (--grid)", grid is not None, "it has no [domain] to lay a grid over: give "
                                                                     "the starts as x0 (--x0)")):
        if given:
            raise sampled_simulate.refuse(source, name, instead)
    with _settings_named():
        loaded = load_sampled(model, model_settings(settings, source))
    starts = model_starts(loaded, x0)  # type: ignore[arg-type]  # (a SampledModel has the states it reads)
    if starts:
        start_arr, how = sim._check_starts(loaded, np.array(starts)), "given"  # type: ignore[arg-type]
    else:
        start_arr, how = sampled_simulate.default_starts(loaded)
    horizon = sim.parse_horizon(str(t_end)) if t_end is not None else None
    run = sampled_simulate.run_sampled(loaded, start_arr, how, t_end=horizon, plot=None if plot is None else str(plot),
                                       series=series)
    return SimulationReport(diverged=bool(run.document["diverged"]), document=run.document, series=run.series)


@contextlib.contextmanager
def _argument_names() -> Iterator[None]:
    """A model's errors about ``--candidate`` and ``--box NAME`` (the model code speaks the command
    line's words) re-raised naming this API's arguments, ``candidate`` and ``box['NAME']``."""
    try:
        yield
    except ModelFileError as exc:
        message = str(exc).removeprefix(f"{exc.source}: {exc.key}: ")
        if exc.key == "--candidate":
            raise ModelFileError(exc.source, "candidate", message) from None
        if exc.key.startswith("--box"):
            name = exc.key[len("--box"):].strip()
            raise ModelFileError(exc.source, f"box['{name}']" if name else "box", message) from None
        raise


def _load_with_settings(model: "str | Path | Model", settings: Mapping[str, object] | Sequence[str] | None
                        ) -> "Model":
    """:func:`load_model_file`, its errors about a setting naming the argument ``settings`` (the
    model file's reader names the command line's ``--set``)."""
    with _settings_named():
        return load_model_file(model, settings)


@contextlib.contextmanager
def _settings_named() -> Iterator[None]:
    """A model file's errors about a setting re-raised naming the argument ``settings`` (the reader
    names the command line's ``--set``)."""
    try:
        yield
    except ModelFileError as exc:
        prefix = f"{exc.source}: {exc.key}: "
        message = str(exc)[len(prefix):] if str(exc).startswith(prefix) else str(exc)
        if exc.key == "set":
            raise ModelFileError(exc.source, "settings", message) from None
        if exc.key.startswith("--set "):
            # the reader's key already shows the name escaped (a line break as \\n): quoted, not repr'd again
            raise ModelFileError(exc.source, f"settings['{exc.key[len('--set '):]}']", message) from None
        raise


def model_starts(model: "Model", x0: Any) -> list[Any]:
    """The starts ``x0`` gives (see :func:`simulate_model_file`), each an array over the model's
    states; a one-line :class:`InvalidParameter` naming ``x0`` for anything else."""
    import numpy as np

    if x0 is None:
        return []
    if isinstance(x0, (str, Mapping)) or _is_number_vector(x0):
        return [_one_start(model, x0)]
    if isinstance(x0, np.ndarray) and x0.ndim == 2 or isinstance(x0, (list, tuple)):
        return [_one_start(model, item) for item in x0]
    raise InvalidParameter("x0", _x0_expected(model), x0)


def _x0_expected(model: "Model") -> str:
    return (f"a start, or a list of starts, each a mapping {{state: value}}, a sequence of {model.n} numbers (one "
            f"per state: {', '.join(model.states)}) or a text 'NAME=VALUE ...'")


def _is_real(v: Any) -> bool:
    from numbers import Real

    return isinstance(v, Real) and not isinstance(v, bool)


def _is_number_vector(v: Any) -> bool:
    import numpy as np

    if isinstance(v, np.ndarray):
        return v.ndim == 1 and v.size > 0 and all(_is_real(x) for x in v.tolist())
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(_is_real(x) for x in v)


def _one_start(model: "Model", item: Any) -> Any:
    import math

    import numpy as np

    from lyapcheck.models.surfaces.simulate import parse_start
    from lyapcheck.units import parse_si_quantity

    if isinstance(item, str):
        return parse_start(model, item)
    values = [float(v) for v in model.equilibrium]
    if isinstance(item, Mapping):
        for name, value in item.items():
            if name not in model.states:
                raise InvalidParameter("x0", f"a mapping from the model's states ({', '.join(model.states)}) to "
                                       f"numbers or unit strings; {name!r} is not one", dict(item))
            try:
                number = float(value) if _is_real(value) else float(parse_si_quantity(str(name), value))
            except InvalidParameter as exc:
                raise InvalidParameter("x0", f"{exc.expected} for the state '{name}'", dict(item)) from None
            if not math.isfinite(number):
                raise InvalidParameter("x0", f"a finite number for the state '{name}'", dict(item))
            values[model.states.index(name)] = number
        return np.array(values)
    if _is_number_vector(item):
        numbers = [float(v) for v in (item.tolist() if isinstance(item, np.ndarray) else item)]
        if len(numbers) != model.n or not all(math.isfinite(v) for v in numbers):
            raise InvalidParameter("x0", f"{model.n} finite numbers, one per state ({', '.join(model.states)})",
                                   list(numbers))
        return np.array(numbers)
    raise InvalidParameter("x0", _x0_expected(model), item)


# -- sweep ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepResult:
    """A finished (or resumed) sweep: the store's summary and what this run computed."""

    summary: Any  # sweeps.summary.Summary, BoxSummary for mode = "boxes", ModelSweepSummary for a model file
    run: Any  # sweeps.run.SweepReport, BoxSweepReport for mode = "boxes", ModelSweepReport for a model file

    @property
    def mode(self) -> str:
        """``points`` or ``boxes`` (the paper's loop), ``model_points`` or ``model_boxes`` (a model file)."""
        if hasattr(self.run, "model_sha256"):
            return str(self.run.mode)
        return "boxes" if hasattr(self.run, "boxes_computed_now") else "points"

    @property
    def violations(self) -> int:
        from sweeps.summary import violation_count

        return violation_count(self.summary)

    def to_json(self) -> dict[str, Any]:
        payload: dict[str, Any] = self.summary.to_json()
        if self.mode in ("model_points", "model_boxes"):
            payload.update({"store": str(self.run.path), "computed_now": self.run.computed_now,
                            "wall_seconds": self.run.wall_seconds})
            return payload
        if self.mode == "boxes":
            payload.update({"store": str(self.run.path), "computed_now": self.run.boxes_computed_now,
                            "wall_seconds": self.run.wall_seconds})
            return payload
        payload.update({"store": str(self.run.path), "computed_now": self.run.computed_now,
                        "wall_seconds": self.run.wall_seconds})
        if self.run.refinement is not None:
            r = self.run.refinement
            payload["refinement"] = {"class": r.cls, "levels": r.levels, "points_computed": r.points_computed,
                                     "full_grid_points": r.full_grid_points, "saved_fraction": r.saved_fraction}
        return payload


def sweep(spec: str | Path, out: str | Path, *, scheduler: str | None = None, workers: int | None = None,
          exports: Sequence[str | Path] = (), progress: Callable[[int, int], None] | None = None,
          on_ready: Callable[[], None] | None = None) -> SweepResult:
    """Run or resume the sweep ``spec`` (TOML) into the Zarr store ``out``.

    Parameters
    ----------
    spec, out
        The sweep spec and the store; rerunning on a finished store computes nothing.
    scheduler, workers
        A Dask scheduler address, or the number of local worker processes (0: in-process).
    exports
        Also write the results to these ``.nc`` / ``.csv`` files.
    progress, on_ready
        Callbacks for a progress display: (points finished, total), and "workers are up".

    A spec whose ``[sweep]`` names a model file (``model = "FILE.toml"``) sweeps that model's
    parameters (:mod:`sweeps.spec`, ``docs/model-sweeps.md``); the summary is then a
    :class:`sweeps.summary.ModelSweepSummary`.
    """
    from sweeps.export import EXPORT_SUFFIXES
    from sweeps.targets import load_any_spec, sweep_any

    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or not 0 <= workers <= MAX_LOCAL_WORKERS):
        raise InvalidParameter("workers", f"an integer in [0, {MAX_LOCAL_WORKERS}]", workers)
    for target in exports:
        if Path(target).suffix.lower() not in EXPORT_SUFFIXES:
            raise InvalidParameter("export", "a file name ending in .nc or .csv", str(target))
    from lyapcheck.models.language.modelfile import is_model_file

    if is_model_file(spec):  # a model file is what a sweep spec names, not a spec
        raise InputFileError(f"{spec} is a model file; a sweep reads a spec that names it: [sweep] model = "
                             f"\"{Path(spec).name}\", mode = \"points\" or \"boxes\", and [[sweep.axes]] with name = \"PARAMETER\", "
                             "start, stop, num (docs/model-sweeps.md)")
    parsed = load_any_spec(spec)
    summary, run = sweep_any(parsed, out, scheduler=scheduler, workers=workers, exports=tuple(exports),
                             progress=progress, on_ready=on_ready)
    return SweepResult(summary=summary, run=run)


# -- report --------------------------------------------------------------------------------------
def report(source: str | Path | CertifyResult, *, html: str | Path | None = None,
           pdf: str | Path | None = None) -> list[Path]:
    """Render a certificate (file or :class:`CertifyResult`) or a sweep store as HTML and/or PDF;
    a model file is certified first (every class, as ``certify FILE``) and its certificate rendered.

    Without ``html`` or ``pdf``, writes the source's name with ``.html`` in the current
    directory (a :class:`CertifyResult` needs an explicit target). Returns the files written.
    """
    from reports.render import certificate_report, report_files

    if isinstance(source, CertifyResult):
        targets = [t for t in (html, pdf) if t is not None]
        if not targets:
            raise InvalidParameter("html", "a target file for a certificate held in memory", None)
        for name, value, suffix in (("html", html, ".html"), ("pdf", pdf, ".pdf")):
            if value is not None and Path(value).suffix.lower() != suffix:
                raise InvalidParameter(name, f"a file name ending in {suffix}", str(value))
        return [certificate_report(source.document, t) for t in targets]
    if not isinstance(source, (str, Path)):
        raise InputFileError(f"cannot report on a {type(source).__name__}: give a path or a CertifyResult")
    from lyapcheck.models.language.modelfile import is_model_file

    if is_model_file(source):  # a model file: certify it with every class, then report on that
        target_html = html if html is not None or pdf is not None else Path(Path(source).stem + ".html")
        return report(certify(model=source), html=target_html, pdf=pdf)
    return report_files(source, html, pdf)


__all__ = ["certify", "certify_box", "certify_extremum", "tune", "certify_model_file", "verify", "simulate", "simulate_model_file", "sweep", "report", "CertifyResult", "VerifyResult", "Check",
           "SimulationReport", "SweepResult", "problem_from", "class_selection"]

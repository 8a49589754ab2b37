"""Model files: any polynomial or rational closed loop ``x' = f(x, p, d)``, read and validated.

The format (docs/model-files.md, the reference; DESIGN.md's "Model files (contract)")::

    [model]          name, states (the order of the state vector), source (optional), time
                     (optional: "continuous", the default, or "discrete": [dynamics] gives each
                     state's next value, x+ = f(x), a map; lyapcheck.models.loop.discrete)
    [parameters]     name = number or "number unit" (SI inside)
    [disturbances]   name = bound b, meaning |d(t)| <= b
    [dynamics]       one entry per state: its time derivative (or, time = "discrete", its next value)
    [equilibrium]    optional; default every state 0; checked exactly (a map's: a fixed point)
    [outputs]        optional; default each state
    [domain]         optional: a box of initial states, name = [lo, hi]
    [sets]           optional: initial, unsafe, goal, each inequalities over the states (a list:
                     all hold; a list of lists: a union); lyapcheck.models.language.sets
    [units]          optional: a unit per state and time = "s"; every right-hand side is then
                     dimension-checked term by term (lyapcheck.models.language.dimensions)
    [networks.NAME]  optional: a feedforward network (file, inputs, outputs) whose outputs [dynamics]
                     may use; a loop with one is a loop with functions (lyapcheck.models.language.networks)

Every error is one line naming the file, the key and what is wrong (:class:`ModelFileError`,
exit code 2 on the command line). The file's text is kept as it was read, with its SHA-256:
a certificate carries both, so that ``verify`` re-derives the field from the same text.
"""

from __future__ import annotations

import hashlib
import keyword
import math
import tomllib
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.language.expressions import (FUNCTIONS, NUMBER_RANGE, ExpressionError, Rational,
                                          parse_with_divisors, uses_functions)
from lyapcheck.models.language.sets import SET_KEYS, STAY_KEY, SetForms, SetText, StateSet, evaluate_set, evaluate_sets, parse_set
from lyapcheck.sos.polynomials import Poly, Ring, degree_in

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.dimensions import UnitTable
    from lyapcheck.models.language.networks import Network
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.units import SIQuantity

#: the most states a model may have: the networks of issue 43 reach 30, where sos_gas works on
#: cliques of the states (lyapcheck.sos.sparsity); each class has its own size limits below this
MAX_STATES: Final = 30
#: the most parameters and the most disturbances
MAX_PARAMETERS: Final = 64
MAX_DISTURBANCES: Final = 6
#: the largest model file, in bytes
MAX_FILE_BYTES: Final = 256 * 1024

SECTIONS: Final = ("model", "parameters", "disturbances", "dynamics", "equilibrium", "outputs", "domain", "sets",
                    "units", "networks", "sampling", "controller")
MODEL_KEYS: Final = ("name", "states", "source", "time")
#: the values of ``[model] time``: a file says which time its [dynamics] are in, and a value lyapcheck
#: does not take is refused, so that a file never means another system than its author wrote;
#: "discrete": [dynamics] gives each state's next value x+ = f(x) (lyapcheck.models.loop.discrete)
TIME_KINDS: Final = ("continuous", "discrete")
#: ``[model] time`` of a discrete-time map
DISCRETE: Final = "discrete"
#: what a sampled-data file ([sampling], [controller]) can be given to: the readers of continuous loops refuse it
SAMPLED_TAKEN_BY: Final = ("a sampled-data loop (a continuous plant under a digital controller with a zero-order "
                           "hold) is taken by 'certify' and 'verify', which decide its linearization over one "
                           "sampling period, and 'simulate', which integrates the plant between samples (and "
                           "lyapcheck.api's certify, verify and simulate); this command does not take it yet")


def is_sampled(data: Mapping[str, Any]) -> bool:
    """Whether a model file's TOML tables make it a sampled-data loop (:mod:`lyapcheck.models.language.sampling`)."""
    return "sampling" in data or "controller" in data


@dataclass(frozen=True)
class Model:
    """A validated model file: names, exact SI values and the exact field.

    ``ring`` has every declared name: the states, then the disturbances, then the parameters.
    ``dynamics[i]`` is the right-hand side of ``states[i]`` with the parameters still symbols
    (:meth:`with_parameters` gives other values); ``parameters`` are their exact SI values.
    """

    source: str
    text: str
    name: str
    origin: str
    states: tuple[str, ...]
    parameters: dict[str, Fraction]
    parameters_given: dict[str, str]
    disturbances: dict[str, Fraction]
    ring: Ring
    dynamics: tuple[Rational, ...]
    equilibrium: tuple[Fraction, ...]
    outputs: dict[str, Rational]
    output_text: dict[str, str]
    domain: dict[str, tuple[Fraction, Fraction]] | None
    overrides: dict[str, str] = field(default_factory=dict)
    #: per state, each non-constant divisor of its right-hand side as written (before cancelling):
    #: none may vanish at the equilibrium (:func:`check_equilibrium`)
    divisors: tuple[tuple[Poly, ...], ...] = ()
    #: the ``[units]`` table as written (empty when the model declares none: nothing was dimension-checked)
    units: dict[str, str] = field(default_factory=dict)
    #: ``[sets]`` by key (``initial``, ``unsafe``, ``goal``; only those the file gives): each a union of
    #: pieces, each piece polynomials ``p >= 0`` in :attr:`state_ring` at :attr:`parameters`
    #: (:func:`with_parameters` re-evaluates them from :attr:`set_forms`)
    sets: dict[str, StateSet] = field(default_factory=dict)
    #: each set's pieces as written: a tuple of strings per piece (lyapcheck.models.language.sets.to_json)
    set_text: dict[str, SetText] = field(default_factory=dict)
    #: each set's ``p`` with the parameters as symbols, in :attr:`ring`
    set_forms: dict[str, SetForms] = field(default_factory=dict)
    #: ``[sets] stay_in_goal = true``: reach_avoid also proves that the state stays in the goal
    stay_in_goal: bool = False
    #: ``[model] time``: "continuous" (``dynamics`` are time derivatives) or "discrete" (``dynamics``
    #: are the next values of a map; only the classes and surfaces that know maps take it:
    #: lyapcheck.models.loop.discrete)
    time: str = "continuous"

    @property
    def discrete(self) -> bool:
        """A discrete-time map: ``dynamics`` gives each state's next value."""
        return self.time == DISCRETE

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def state_ring(self) -> Ring:
        """The states and the disturbances: the variables of the field once parameters are set."""
        return Ring(self.states + tuple(self.disturbances))

    @property
    def n(self) -> int:
        return len(self.states)

    def to_toml(self) -> str:
        """The model file's text as read: a file with it gives this model (``overrides``, settings laid
        over it, are not in it). A model built in Python (:func:`lyapcheck.models.language.build.from_sympy`) is read
        from this text."""
        return self.text


def load_model(path: str | Path, overrides: Mapping[str, object] | None = None) -> Model:
    """Read and validate a model file; ``overrides`` are ``--set NAME=VALUE`` (parameters or
    disturbance bounds)."""
    source = str(path)
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            raise _error(source, "file", f"is {size} bytes; the limit is {MAX_FILE_BYTES} (MAX_FILE_BYTES)")
        # the bytes decoded as they are: read_text would turn CRLF line ends into LF, and the text
        # (and the SHA-256 a certificate carries) would no longer be the file's, verbatim
        text = p.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise _error(source, "file", "not found") from None
    except IsADirectoryError:
        raise _error(source, "file", "is a directory, not a model file") from None
    except UnicodeDecodeError:
        raise _error(source, "file", "is not UTF-8 text") from None
    return parse_model(text, source, overrides)


def is_model_file(path: object) -> bool:
    """Whether ``path`` names a model file, by its content: a TOML file with a ``[model]`` or a
    ``[dynamics]`` table (a paper gain file has ``[gains]``, a scenario ``[scenario]``, a sweep spec
    ``[sweep]``). Anything unreadable is not one (the caller's own reader then says why)."""
    if not isinstance(path, (str, Path)):
        return False
    p = Path(path)
    try:
        if not p.is_file() or p.stat().st_size > MAX_FILE_BYTES:
            return False
        data = tomllib.loads(p.read_bytes().decode("utf-8"))
    except (OSError, ValueError, RecursionError):  # unreadable, not UTF-8, not TOML, absurd numbers
        return False
    return "sweep" not in data and (isinstance(data.get("model"), dict) or isinstance(data.get("dynamics"), dict))


def parse_model(text: str, source: str = "<model>", overrides: Mapping[str, object] | None = None) -> Model:
    """Validate a model file's text (see :func:`load_model`); a loop with functions is refused
    here, naming the commands that take it (:func:`parse_any_model` reads it)."""
    model = parse_any_model(text, source, overrides)
    if not isinstance(model, Model):  # a loop with functions (lyapcheck.models.language.recast.RecastModel)
        call = next(a.written_as for a in model.system.auxiliaries if a.written_as) \
            if any(a.written_as for a in model.system.auxiliaries) else "pi"
        raise _error(source, model.key_of(call), f"uses {call}: a loop with functions is taken by 'certify "
                                                 "--model', 'verify' and 'simulate --model' (and lyapcheck.api's "
                                                 "certify, verify and simulate); this command takes polynomial and "
                                                 "rational loops only")
    return model


def parse_any_model(text: str, source: str = "<model>", overrides: Mapping[str, object] | None = None,
                    candidate: str | None = None, tables: Mapping[str, Any] | None = None) -> "Model | RecastModel":
    """A model file's text: a :class:`Model` (polynomial or rational loop) or, when its
    ``[dynamics]`` use functions or pi, a :class:`~lyapcheck.models.language.recast.RecastModel` (with a
    ``candidate`` V recast along, whose functions may be new ones). ``tables``, when given, are read
    instead of the text's own (a sampled-data file's plant, :mod:`lyapcheck.models.language.sampling`);
    the text stays the model's, for its SHA-256."""
    if tables is not None:
        data = dict(tables)
    else:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise _error(source, "file", f"is not valid TOML ({exc})") from None
    reader = _Reader(source, text, data, dict(overrides or {}))
    dynamics = data.get("dynamics")
    if isinstance(dynamics, dict) and (uses_functions(list(dynamics.values())) or "networks" in data):
        return reader.recast_model(candidate)
    return reader.model()


def read_laws(text: str, source: str, tables: Mapping[str, Any], overrides: Mapping[str, object] | None,
              section: str, laws: Mapping[str, object]) -> tuple[dict[str, Fraction], tuple[Fraction, ...],
                                                                 dict[str, Rational]]:
    """A sampled-data file's parameters (with ``overrides``), its equilibrium and its ``[section]``
    laws (each polynomial or rational in the states and parameters, returned with the parameters set,
    in ``Ring(states)``), read from ``tables`` (the file's, without its plant) with the model
    reader's one-line errors."""
    reader = _Reader(source, text, dict(tables), dict(overrides or {}))
    _, _, states = reader.head()
    params, _ = reader.quantities("parameters", MAX_PARAMETERS)
    reader.check_unique(states, params, {})
    params, _, _ = reader.apply_overrides(params, {}, {})
    ring = Ring(states + tuple(params))
    state_ring = Ring(states)
    out = {}
    for name, law in laws.items():
        reader.check_name(f"[{section}] {name}", name)
        expr = reader.expression(f"[{section}] {name}", law, ring)
        num = ring.restrict(ring.substitute(expr.numerator, params), state_ring)
        den = ring.restrict(ring.substitute(expr.denominator, params), state_ring)
        if den.is_zero():
            raise reader.fail(f"[{section}] {name}", "division by zero with the parameters' values")
        out[name] = Rational(state_ring, num, den).normalized()
    return params, reader.equilibrium(states, ring), out


def file_uses_functions(path: str | Path) -> bool:
    """Whether the model file's ``[dynamics]`` use functions or pi (False when it cannot be read:
    the loader then says why, in one line)."""
    try:
        data = tomllib.loads(Path(path).read_bytes().decode("utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
    dynamics = data.get("dynamics")
    return isinstance(dynamics, dict) and (uses_functions(list(dynamics.values())) or "networks" in data)


def load_any_model(path: str | Path, overrides: Mapping[str, object] | None = None, candidate: str | None = None
                   ) -> "Model | RecastModel":
    """:func:`load_model`, or a loop with functions as a :class:`~lyapcheck.models.language.recast.RecastModel`."""
    try:
        return load_model(path, overrides)
    except ModelFileError as exc:
        if "a loop with functions is taken by" not in str(exc):
            raise
    return parse_any_model(Path(path).read_bytes().decode("utf-8"), str(path), overrides, candidate)


class _Reader:
    def __init__(self, source: str, text: str, data: dict[str, Any], overrides: dict[str, object]) -> None:
        self.source, self.text, self.data, self.overrides = source, text, data, overrides
        self.divisors: list[tuple[Poly, ...]] = []
        #: each parameter's and disturbance's quantity as the file gives it (its dimension, for [units])
        self.read: dict[str, dict[str, SIQuantity]] = {"parameters": {}, "disturbances": {}}
        #: ``[model] time`` once :meth:`head` read it
        self.time = TIME_KINDS[0]

    def fail(self, key: str, message: str) -> ModelFileError:
        return _error(self.source, key, message)

    def table(self, name: str) -> dict[str, Any]:
        value = self.data.get(name, {})
        if not isinstance(value, dict):
            raise self.fail(f"[{name}]", f"must be a table, got {type(value).__name__}")
        return value

    def head(self) -> tuple[str, str, tuple[str, ...]]:
        """The sections known, and ``[model]``: its name, source and states."""
        unknown = [k for k in self.data if k not in SECTIONS]
        if unknown:
            raise self.fail(f"[{unknown[0]}]", f"unknown section (sections: {', '.join(SECTIONS)})")
        if is_sampled(self.data):  # another system than a continuous loop: only its own reader takes it
            raise self.fail("[sampling]" if "sampling" in self.data else "[controller]", SAMPLED_TAKEN_BY)
        head = self.table("model")
        if "model" not in self.data:
            raise self.fail("[model]", "missing (it declares the states)")
        bad = [k for k in head if k not in MODEL_KEYS]
        if bad:
            raise self.fail(f"[model] {bad[0]}", f"unknown key (keys: {', '.join(MODEL_KEYS)})")
        name = head.get("name", Path(self.source).stem)
        origin = head.get("source", "")
        for key, value in (("name", name), ("source", origin)):
            if not isinstance(value, str):
                raise self.fail(f"[model] {key}", f"must be text, got {value!r}")
        self.check_time(head.get("time", TIME_KINDS[0]))
        return name, origin, self.states(head)

    def check_time(self, value: object) -> None:
        """``[model] time`` is one of :data:`TIME_KINDS` (kept in ``self.time``); anything else is refused,
        naming the accepted values and the value given."""
        if isinstance(value, str) and value in TIME_KINDS:
            self.time = value
            return
        kinds = ", ".join(f'"{k}"' for k in TIME_KINDS)
        raise self.fail("[model] time", f"must be one of {kinds}, got {value!r}")

    def model(self) -> Model:
        name, origin, states = self.head()
        params, params_given = self.quantities("parameters", MAX_PARAMETERS)
        dists = self.disturbance_bounds()
        self.check_unique(states, params, dists)
        params, params_given, dists = self.apply_overrides(params, params_given, dists)
        ring = Ring(states + tuple(dists) + tuple(params))
        dynamics = self.dynamics(states, ring, dists)
        equilibrium = self.equilibrium(states, ring)
        outputs, output_text = self.outputs(states, ring, dists, params)
        domain = self.domain(states)
        set_text, set_forms = self.sets(states, ring, dists)
        stay_in_goal = self.stay_in_goal(set_forms)
        units = self.units(states, set_text)
        sets = {key: evaluate_set(self.source, key, forms, ring, params, Ring(states + tuple(dists)))
                for key, forms in set_forms.items()}
        model = Model(source=self.source, text=self.text, name=name, origin=origin, states=states,
                      parameters=params, parameters_given=params_given, disturbances=dists, ring=ring,
                      dynamics=dynamics, equilibrium=equilibrium, outputs=outputs, output_text=output_text,
                      domain=domain, overrides={k: str(v) for k, v in self.overrides.items()},
                      divisors=tuple(self.divisors), units=units, sets=sets, set_text=set_text,
                      set_forms=set_forms, stay_in_goal=stay_in_goal, time=self.time)
        check_equilibrium(model)
        return model

    def recast_model(self, candidate: str | None = None) -> "RecastModel":
        """A loop with functions (lyapcheck.models.language.recast): the parameters are read, set to their
        values and the loop recast with every disturbance held at 0 (its claims say ``(d = 0)``);
        its outputs (polynomial in the states, as for a polynomial loop; default each state) are read
        with the parameters set; ``[units]`` is checked on the texts as written, before the recasting
        (:meth:`units`)."""
        from lyapcheck.models.language.dimensions import OutsideLanguage
        from lyapcheck.models.language.recast import RecastModel, recast_dynamics  # only a loop with functions needs it

        name, origin, states = self.head()
        params, params_given = self.quantities("parameters", MAX_PARAMETERS)
        dists = self.disturbance_bounds()
        self.check_unique(states, params, dists)
        params, params_given, dists = self.apply_overrides(params, params_given, dists)
        for reserved in ("pi", *FUNCTIONS):
            where = ("[model] states" if reserved in states else f"[parameters] {reserved}" if reserved in params
                     else f"[disturbances] {reserved}" if reserved in dists else None)
            if where is not None:
                raise self.fail(where, f"'{reserved}' is a function or constant of the language; choose another name")
        table = self.table("dynamics")
        for key in table:
            if key not in states:
                raise self.fail(f"[dynamics] {key}", f"an equation without a state: no state named '{key}' "
                                                     f"(states: {', '.join(states)})")
        for s in states:
            if s not in table:
                raise self.fail("[dynamics]", f"the state '{s}' has no equation")
        equilibrium = self.equilibrium(states, Ring(states))
        domain = self.domain(states)
        outputs, output_text = self.recast_outputs(states, params, dists)
        networks = self.networks(states, params, dists, output_text)
        set_text, recast_sets = self.recast_sets(states, params, dists)
        # [units]: the texts as written, term by term, before the recasting (which moves a field to
        # auxiliaries whose dimensions no longer show); None where a text stood aside for the parser
        try:
            units: dict[str, str] | None = self.units(states, set_text, defer_outside=True)
        except OutsideLanguage:
            units = None
        # the nominal loop: every disturbance at 0 (a claim about it says "(d = 0)")
        if self.time == DISCRETE:  # a map: its displacement F(x) - x (lyapcheck.models.classes.discrete_functions)
            return self.recast_map(name, origin, states, params, dists, table, equilibrium, domain, outputs,
                                   output_text, networks, set_text, recast_sets, units, candidate)
        system, V = recast_dynamics(self.source, states, table, {**params, **{d: Fraction(0) for d in dists}},
                                    equilibrium, candidate, networks)
        if units is None:  # the recasting's parser took every text after all: each is checked now
            units = self.units(states, set_text)
        robust = None
        if dists:  # and the loop with its disturbances as states without a flow, for robust claims
            try:
                robust, _ = recast_dynamics(self.source, states + tuple(dists), {**table, **{d: "0" for d in dists}},
                                            params, tuple(equilibrium) + (Fraction(0),) * len(dists),
                                            networks=networks)
            except ModelFileError:  # (a disturbance where the recasting cannot keep it: nominal claims only)
                robust = None
        return RecastModel(source=self.source, text=self.text, name=name, origin=origin, states=states,
                           parameters=params, equilibrium=equilibrium, domain=domain, system=system,
                           overrides={k: str(v) for k, v in self.overrides.items()}, candidate_v=V,
                           disturbances=dists, robust=robust, outputs=outputs, output_text=output_text,
                           sets=recast_sets, set_text=set_text, units=units, networks=networks)

    def recast_map(self, name: str, origin: str, states: tuple[str, ...], params: dict[str, Fraction],
                   dists: dict[str, Fraction], table: Mapping[str, object], equilibrium: tuple[Fraction, ...],
                   domain: Any, outputs: Any, output_text: Any, networks: "tuple[Network, ...]", set_text: Any,
                   sets: Any, units: dict[str, str] | None, candidate: str | None) -> "RecastModel":
        """A discrete-time map with functions (issue 44): ``[dynamics]`` gives ``x+ = F(x)``, and what is recast
        is the displacement ``F(x) - x``, each text as ``(F_s) - (s)``: the recasting's check that every
        right-hand side is 0 at the equilibrium, exactly (each function's value exact there), is then the
        fixed-point check ``F(x_eq) = x_eq``, and the classes of a map
        (:mod:`lyapcheck.models.classes.discrete_functions`) read ``F = x + (F - x)`` back. The auxiliaries'
        flows would be the chain rule of a field
        that is not this map's: they are not derived, nor the relations (``for_map``), and no class of a
        continuous loop runs on a map (``time`` is ``"discrete"``). Disturbances stay at 0 (claims say
        ``(d = 0)``)."""
        from lyapcheck.models.language.recast import RecastModel, recast_dynamics

        displaced: dict[str, object] = {
            s: (f"({table[s]}) - ({s})" if isinstance(table[s], (str, int, float)) and not isinstance(table[s], bool)
                else table[s]) for s in states}
        try:
            system, V = recast_dynamics(self.source, states, displaced, {**params, **{d: Fraction(0) for d in dists}},
                                        equilibrium, candidate, networks, for_map=True)
        except ModelFileError as exc:
            if exc.key != "[equilibrium]":
                raise
            # (the recasting's words are a field's: x' = r there; here r = F(x_eq) - x_eq)
            message = str(exc).removeprefix(f"{exc.source}: {exc.key}: ")
            message = message.replace("is not an equilibrium: ", "is not a fixed point of the map: ")
            for s in states:
                message = message.replace(f" {s}' = ", f" {s}+ - {s} = ")
            raise ModelFileError(self.source, "[equilibrium]", message) from None
        if units is None:  # the recasting's parser took every text after all: each is checked now
            units = self.units(states, set_text)
        return RecastModel(source=self.source, text=self.text, name=name, origin=origin, states=states,
                           parameters=params, equilibrium=equilibrium, domain=domain, system=system,
                           overrides={k: str(v) for k, v in self.overrides.items()}, candidate_v=V,
                           disturbances=dists, robust=None, outputs=outputs, output_text=output_text,
                           sets=sets, set_text=set_text, units=units,
                           networks=networks, time=DISCRETE)

    def networks(self, states: tuple[str, ...], params: Mapping[str, Fraction], dists: Mapping[str, Fraction],
                 outputs: Mapping[str, str]) -> "tuple[Network, ...]":
        """``[networks.NAME]`` (:func:`lyapcheck.models.language.networks.read_networks`): each network's
        outputs are new names, distinct from every name the file declares and from the language's."""
        if "networks" not in self.data:
            return ()
        from lyapcheck.models.language.networks import read_networks

        if "units" in self.data:  # a network's outputs have no declared dimension to check [dynamics] against
            raise self.fail("[units]", "a model with [networks] is not dimension-checked yet: remove [units] (the "
                                       "states' units may stay in comments)")
        taken = {**{s: "a state" for s in states}, **{p: "a parameter" for p in params},
                 **{d: "a disturbance" for d in dists}, **{o: "an output in [outputs]" for o in outputs
                                                           if "outputs" in self.data},
                 **{f: "a function of the language" for f in (*FUNCTIONS, "pi")}}
        return read_networks(self.source, self.data["networks"], states, taken)

    def recast_sets(self, states: tuple[str, ...], params: Mapping[str, Fraction], dists: Mapping[str, Fraction]
                    ) -> tuple[dict[str, SetText], dict[str, StateSet]]:
        """A loop with functions' ``[sets]`` (``initial``, ``unsafe``, ``goal``: the barrier and reach_avoid
        classes), read as a polynomial loop's (an inequality with a function is refused by the expression
        parser, naming it), with the parameters set; ``stay_in_goal`` is refused in one line (not taken here yet)."""
        if "sets" in self.data and isinstance(self.data["sets"], dict):
            if STAY_KEY in self.data["sets"]:
                raise self.fail(f"[sets] {STAY_KEY}", "a loop with functions (sin, sqrt, sat, ...) takes the sets "
                                                      "initial, unsafe and goal (classes barrier and reach_avoid); "
                                                      "staying in the goal is not taken yet: remove it, or write the "
                                                      "field polynomial")
        ring = Ring(states + tuple(dists) + tuple(params))
        set_text, set_forms = self.sets(states, ring, dists)
        sets = {key: evaluate_set(self.source, key, forms, ring, params, Ring(states + tuple(dists)))
                for key, forms in set_forms.items()}
        return set_text, sets

    def recast_outputs(self, states: tuple[str, ...], params: Mapping[str, Fraction],
                       dists: Mapping[str, Fraction]) -> tuple[dict[str, Poly], dict[str, str]]:
        """A loop with functions' outputs, polynomials over the states' ring with the parameters set
        (an output with a function is refused by the expression parser, naming it), and their texts."""
        ring = Ring(states + tuple(dists) + tuple(params))
        rationals, texts = self.outputs(states, ring, dists, params)
        state_ring = Ring(states)
        out: dict[str, Poly] = {}
        for key, expr in rationals.items():
            num = ring.substitute(expr.numerator, params)
            den = ring.substitute(expr.denominator, params)
            if not den.is_constant() or den.is_zero():
                raise self.fail(f"[outputs] {key}", "an output must be polynomial in the states")
            out[key] = ring.restrict(num * (1 / den.leading_coefficient()), state_ring)
        return out, texts

    def states(self, head: dict[str, Any]) -> tuple[str, ...]:
        states = head.get("states")
        if not isinstance(states, list) or not states or not all(isinstance(s, str) for s in states):
            raise self.fail("[model] states", f"must be a non-empty list of names, got {states!r}")
        if len(states) > MAX_STATES:
            raise self.fail("[model] states", f"has {len(states)} states; the limit is {MAX_STATES} (MAX_STATES)")
        for s in states:
            self.check_name("[model] states", s)
        seen: set[str] = set()
        for s in states:
            if s in seen:
                raise self.fail("[model] states", f"the name '{s}' is declared twice")
            seen.add(s)
        return tuple(states)

    def check_name(self, key: str, name: str) -> None:
        if not name.isidentifier() or keyword.iskeyword(name) or not name.isascii():
            raise self.fail(key, f"'{name}' is not a valid name (letters, digits and _, not starting with a digit, "
                                 "not a Python keyword)")

    def quantities(self, section: str, limit: int) -> tuple[dict[str, Fraction], dict[str, str]]:
        from lyapcheck.units import parse_si_with_dimension

        table = self.table(section)
        if len(table) > limit:
            raise self.fail(f"[{section}]", f"has {len(table)} entries; the limit is {limit}")
        values, given = {}, {}
        for key, value in table.items():
            self.check_name(f"[{section}] {key}", key)
            if isinstance(value, dict):
                raise self.fail(f"[{section}] {key}", "must be a number or a string with a unit, not a table")
            try:
                quantity = parse_si_with_dimension(key, value)
            except InvalidParameter as exc:
                raise self.fail(f"[{section}] {key}", _unprefixed(exc)) from None
            values[key], given[key] = quantity.value, str(value)
            self.read[section][key] = quantity
        return values, given

    def disturbance_bounds(self) -> dict[str, Fraction]:
        """``[disturbances]``: each name's bound ``|d| <= b`` (SI), every one ``>= 0``."""
        dists, _ = self.quantities("disturbances", MAX_DISTURBANCES)
        for key, b in dists.items():
            if b < 0:
                raise self.fail(f"[disturbances] {key}", f"is a bound |d| <= b and must be >= 0, got {float(b)!r}")
        return dists

    def check_unique(self, states: Sequence[str], params: Mapping[str, Fraction], dists: Mapping[str, Fraction]) -> None:
        kinds = {s: "a state" for s in states}
        for section, names in (("parameters", params), ("disturbances", dists)):
            for name in names:
                if name in kinds:
                    raise self.fail(f"[{section}] {name}", f"the name '{name}' is declared twice (also {kinds[name]})")
                kinds[name] = "a parameter" if section == "parameters" else "a disturbance"

    def apply_overrides(self, params: dict[str, Fraction], given: dict[str, str], dists: dict[str, Fraction]
                        ) -> tuple[dict[str, Fraction], dict[str, str], dict[str, Fraction]]:
        from lyapcheck.units import parse_si_quantity

        params, given, dists = dict(params), dict(given), dict(dists)
        for key, value in self.overrides.items():
            if key in params:
                target = params
            elif key in dists:
                target = dists
            else:
                names = ", ".join(list(params) + list(dists)) or "none"
                raise self.fail(f"--set {key}", f"no parameter or disturbance named '{key}' (declared: {names})")
            try:
                target[key] = parse_si_quantity(key, value)
                self.check_same_dimension(key, value, "parameters" if target is params else "disturbances")
            except InvalidParameter as exc:
                raise self.fail(f"--set {key}", _unprefixed(exc)) from None
            if target is dists and target[key] < 0:
                raise self.fail(f"--set {key}", f"is a bound |d| <= b and must be >= 0, got {value!r}")
            if target is params:
                given[key] = str(value)
        return params, given, dists

    def check_same_dimension(self, key: str, value: object, section: str) -> None:
        """A ``--set`` value with a unit has the dimension of the file's own value where that has a
        unit too (``k = "2 1/s^2"`` set to ``"2 mm"`` is refused), with or without ``[units]``."""
        from lyapcheck.units import parse_si_with_dimension

        raw = self.table(section).get(key)
        if "units" in self.data or not isinstance(value, str) or not isinstance(raw, str):
            return  # with [units] the dimension check of every name says it (lyapcheck.models.language.dimensions)
        given, declared = parse_si_with_dimension(key, value), parse_si_with_dimension(key, raw)
        if given.unit and declared.unit and given.dimension != declared.dimension:
            raise InvalidParameter(key, f"a value of dimension {declared.dimension}, as the file gives {key} "
                                        f"('{raw}')", value)

    def expression(self, key: str, text: object, ring: Ring) -> Rational:
        return self.expression_with_divisors(key, text, ring)[0]

    def expression_with_divisors(self, key: str, text: object, ring: Ring) -> tuple[Rational, tuple[Poly, ...]]:
        if not isinstance(text, (str, int, float)) or isinstance(text, bool):
            raise self.fail(key, f"must be an expression in a string, got {text!r}")
        if isinstance(text, float) and not math.isfinite(text):  # TOML's inf and nan, unquoted
            raise self.fail(key, f"the number {text!r} is not finite (numbers must be {NUMBER_RANGE})")
        try:
            return parse_with_divisors(str(text), ring)
        except ExpressionError as exc:
            raise self.fail(key, str(exc)) from None

    def dynamics(self, states: tuple[str, ...], ring: Ring, dists: Mapping[str, Fraction]) -> tuple[Rational, ...]:
        table = self.table("dynamics")
        for key in table:
            if key not in states:
                raise self.fail(f"[dynamics] {key}", f"an equation without a state: no state named '{key}' "
                                                     f"(states: {', '.join(states)})")
        out = []
        for s in states:
            if s not in table:
                raise self.fail("[dynamics]", f"the state '{s}' has no equation")
            rhs, divisors = self.expression_with_divisors(f"[dynamics] {s}", table[s], ring)
            self.divisors.append(divisors)
            den_vars = [v for v in dists if degree_in(ring, rhs.denominator, [v]) > 0]
            if den_vars:
                raise self.fail(f"[dynamics] {s}", f"the disturbance '{den_vars[0]}' appears in a denominator; "
                                                   "disturbances may enter numerators only")
            out.append(rhs)
        return tuple(out)

    def equilibrium(self, states: tuple[str, ...], ring: Ring) -> tuple[Fraction, ...]:
        from lyapcheck.units import parse_si_quantity

        table = self.table("equilibrium")
        values = {s: Fraction(0) for s in states}
        for key, value in table.items():
            if key not in states:
                raise self.fail(f"[equilibrium] {key}", f"no state named '{key}' (states: {', '.join(states)})")
            try:
                values[key] = parse_si_quantity(key, value)
            except InvalidParameter as exc:
                raise self.fail(f"[equilibrium] {key}", _unprefixed(exc)) from None
        return tuple(values[s] for s in states)

    def outputs(self, states: tuple[str, ...], ring: Ring, dists: Mapping[str, Fraction],
                params: Mapping[str, Fraction]) -> tuple[dict[str, Rational], dict[str, str]]:
        table = self.table("outputs")
        if not table:
            return ({s: Rational.polynomial(ring, ring.gen(s)) for s in states}, {s: s for s in states})
        out, texts = {}, {}
        for key, text in table.items():
            self.check_name(f"[outputs] {key}", key)
            if key in params or key in dists:
                raise self.fail(f"[outputs] {key}", f"the name '{key}' is declared twice (also a "
                                                    f"{'parameter' if key in params else 'disturbance'})")
            expr = self.expression(f"[outputs] {key}", text, ring)
            if not expr.is_polynomial() and degree_in(ring, expr.denominator, states) > 0:
                raise self.fail(f"[outputs] {key}", "an output must be polynomial in the states (a bound on it is "
                                                    "proved through its square)")
            if any(degree_in(ring, expr.numerator, [d]) > 0 for d in dists):
                raise self.fail(f"[outputs] {key}", "an output may not depend on a disturbance")
            out[key], texts[key] = expr, str(text)
        return out, texts

    def domain(self, states: tuple[str, ...]) -> dict[str, tuple[Fraction, Fraction]] | None:
        from lyapcheck.units import parse_si_quantity

        if "domain" not in self.data:
            return None
        table = self.table("domain")
        box = {}
        for key, value in table.items():
            if key not in states:
                raise self.fail(f"[domain] {key}", f"no state named '{key}' (states: {', '.join(states)})")
            if not isinstance(value, list) or len(value) != 2:
                raise self.fail(f"[domain] {key}", f"must be [lo, hi], got {value!r}")
            try:
                lo, hi = (parse_si_quantity(key, v) for v in value)
            except InvalidParameter as exc:
                raise self.fail(f"[domain] {key}", _unprefixed(exc)) from None
            if not lo < hi:
                raise self.fail(f"[domain] {key}", f"must be [lo, hi] with lo < hi, got {value!r}")
            box[key] = (lo, hi)
        missing = [s for s in states if s not in box]
        if missing:
            raise self.fail("[domain]", f"the state '{missing[0]}' has no interval (the domain is a box over every "
                                        "state)")
        return box

    def sets(self, states: tuple[str, ...], ring: Ring, dists: Mapping[str, Fraction]
             ) -> tuple[dict[str, SetText], dict[str, SetForms]]:
        """``[sets]``: each key among :data:`~lyapcheck.models.language.sets.SET_KEYS`, read by
        :func:`lyapcheck.models.language.sets.parse_set` (parameters still symbols)."""
        if "sets" not in self.data:
            return {}, {}
        table = self.table("sets")
        bad = [k for k in table if k not in SET_KEYS and k != STAY_KEY]
        if bad:
            raise self.fail(f"[sets] {bad[0]}", f"unknown key (keys: {', '.join(SET_KEYS)}, {STAY_KEY})")
        texts: dict[str, SetText] = {}
        forms: dict[str, SetForms] = {}
        for key in SET_KEYS:
            if key in table:
                texts[key], forms[key] = parse_set(self.source, key, table[key], ring, states, tuple(dists))
        return texts, forms

    def stay_in_goal(self, set_forms: Mapping[str, SetForms]) -> bool:
        """``[sets] stay_in_goal``: true or false (default false); true needs a ``goal``."""
        value = self.data.get("sets", {}).get(STAY_KEY, False) if isinstance(self.data.get("sets"), dict) else False
        if not isinstance(value, bool):
            raise self.fail(f"[sets] {STAY_KEY}", f"must be true or false, got {value!r}")
        if value and "goal" not in set_forms:
            raise self.fail(f"[sets] {STAY_KEY}", "asks to stay in the goal, but [sets] has no goal")
        return value

    def units(self, states: tuple[str, ...], set_text: Mapping[str, SetText] | None = None,
              defer_outside: bool = False) -> dict[str, str]:
        """``[units]``, when the file declares it: the table read (SI units only), then every
        right-hand side checked term by term against its state per time, every output's sums for
        consistency, and every quantity given with a unit where a dimension is known (a state's
        ``[equilibrium]`` and ``[domain]`` values, a ``--set``) against it, and the two sides of
        every ``[sets]`` inequality against each other. Runs after the language
        checks, so a text is dimension-checked only once it parses; a loop with functions is checked
        before its recasting parses it, and with ``defer_outside`` a text outside the language (which
        the parser then refuses in its own words) raises
        :class:`~lyapcheck.models.language.dimensions.OutsideLanguage` instead of a one-line error. Returns
        the table as written."""
        from lyapcheck.models.language import dimensions as dims

        if "units" not in self.data:
            return {}
        table = self.table("units")
        file_given = {key: str(value) for section in ("parameters", "disturbances")
                      for key, value in self.table(section).items()}
        try:
            units = dims.read_units(table, states, list(self.read["parameters"]) + list(self.read["disturbances"]))
            names = dims.named_table(units, {**{k: ("parameter", q) for k, q in self.read["parameters"].items()},
                                             **{k: ("disturbance", q) for k, q in self.read["disturbances"].items()}},
                                     file_given)
            for key, value in self.overrides.items():
                dims.check_value(f"--set {key}", value, names[key].dimension,
                                 f"{key} (given as '{file_given[key]}' in the file)")
            for s in states:  # a map's next value has its state's own unit, a field's the state's per time
                check = dims.check_map if self.time == DISCRETE else dims.check_dynamics
                check(s, str(self.table("dynamics")[s]), units, names)
            for key, text in self.table("outputs").items():
                dims.check_output(key, str(text), names)
            for key, value in self.table("equilibrium").items():
                dims.check_value(f"[equilibrium] {key}", value, units.dimension(key), _state_unit(key, units))
            for key, pair in self.table("domain").items():
                for value in pair:
                    dims.check_value(f"[domain] {key}", value, units.dimension(key), _state_unit(key, units))
            for key, pieces in (set_text or {}).items():
                for piece in pieces:
                    for text in piece:
                        dims.check_inequality(f"[sets] {key}", text, names)
        except dims.DimensionError as exc:
            if defer_outside and isinstance(exc, dims.OutsideLanguage):
                raise
            raise self.fail(exc.key, exc.message) from None
        return {str(key): str(value) for key, value in table.items()}


def _state_unit(state: str, units: "UnitTable") -> str:
    unit = units.states[state][0]
    return f"the state {state} (in {unit})" if unit else f"the state {state} (dimensionless)"


def _error(source: str, key: str, message: str) -> ModelFileError:
    """The one-line error of the contract. A character that is not printable is shown escaped: a
    quoted TOML key (``"a\\nb" = 1``) or ``--set`` name may hold a line break, which would
    otherwise split the message over several lines."""
    return ModelFileError(_printable(source), _printable(key), _printable(message))


def _printable(text: str) -> str:
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text)


def _unprefixed(exc: InvalidParameter) -> str:
    """The message of a field error without its "The 'x' parameter" opening (the key says it)."""
    return f"must be {exc.expected}, got {exc.got!r}"


def field_at(model: Model, parameters: Mapping[str, Fraction] | None = None) -> tuple[Rational, ...]:
    """The right-hand sides with the parameters set (default: the model's), in :attr:`Model.state_ring`."""
    values = model.parameters if parameters is None else parameters
    ring = model.state_ring
    out = []
    for s, rhs in zip(model.states, model.dynamics):
        num = model.ring.restrict(model.ring.substitute(rhs.numerator, values), ring)
        den = model.ring.restrict(model.ring.substitute(rhs.denominator, values), ring)
        if den.is_zero():
            # a denominator in the parameters alone that these values make 0 ("x1/mu" with mu = 0):
            # the parser cannot see it (mu is a symbol there), and normalizing would divide by 0
            used = [p for p in model.parameters if degree_in(model.ring, rhs.denominator, [p]) > 0]
            at = ", ".join(f"{p} = {values[p]}" for p in used if p in values)
            raise _error(model.source, f"[dynamics] {s}", f"division by zero: a denominator is 0 with {at} "
                                                          "(the parameters' values)")
        out.append(Rational(ring, num, den).normalized())
    return tuple(out)


def check_equilibrium(model: Model) -> None:
    """The stated equilibrium is one, exactly: every denominator non-zero and every right-hand side
    zero there (a map's: equal to the state's value there, a fixed point ``f(x_eq) = x_eq``), with the
    disturbances 0 (else a :class:`ModelFileError` naming the state)."""
    ring = model.state_ring
    point = list(model.equilibrium) + [Fraction(0)] * len(model.disturbances)
    where = "[equilibrium]" if any(model.equilibrium) else "[equilibrium] (default: every state 0)"
    full_point = point + [model.parameters[p] for p in model.ring.names[len(point):]]
    for s, divisors in zip(model.states, model.divisors):
        for divisor in divisors:
            # a divisor in the parameters alone that is 0 is a division by zero (field_at says so)
            if degree_in(model.ring, divisor, model.states) > 0 and model.ring.evaluate(divisor, full_point) == 0:
                text = str(divisor).replace("^", "**")
                raise ModelFileError(model.source, f"[dynamics] {s}", f"divides by {text}, which is 0 at the "
                                     "equilibrium: the right-hand side is not defined there (a common factor is "
                                     "not cancelled; write the field without the division)")
    for s, rhs in zip(model.states, field_at(model)):
        den = ring.evaluate(rhs.denominator, point)
        if den == 0:
            raise ModelFileError(model.source, where, f"the right-hand side of {s} is not defined there "
                                                      "(its denominator is 0)")
        value = ring.evaluate(rhs.numerator, point) / den
        if model.discrete:
            _check_fixed_point(model, where, s, value)
            continue
        if value != 0:
            raise ModelFileError(model.source, where, f"is not an equilibrium: {s}' = {value} there, not 0 "
                                                      f"(checked exactly, with the disturbances 0)")


def _check_fixed_point(model: Model, where: str, state: str, value: Fraction) -> None:
    """A map's equilibrium is a fixed point: ``state``'s next value there, ``value``, is its own
    (checked exactly; never ``f(x_eq) = 0``, which is a field's)."""
    own = model.equilibrium[model.states.index(state)]
    if value != own:
        raise ModelFileError(model.source, where, f"is not a fixed point of the map: {state}+ = {value} there, not "
                                                  f"{own} (checked exactly, with the disturbances 0)")


def with_parameters(model: Model, values: Mapping[str, Fraction]) -> Model:
    """The model with some parameter values replaced (exact SI), the equilibrium re-checked.

    For computing only: ``overrides`` (what a certificate records to re-read the model) are left as
    they were, so a certificate of the result would not re-read to it. Where a certificate is
    written, read the model with the values as ``--set`` overrides instead (``parse_model(text,
    source, overrides)``, as :mod:`sweeps.spec` does with exact decimals).
    """
    params = {**model.parameters, **values}
    out = replace(model, parameters=params, parameters_given={**model.parameters_given,
                                                              **{k: str(v) for k, v in values.items()}})
    check_equilibrium(out)
    return replace(out, sets=evaluate_sets(out))


def degree_of_field(model: Model) -> int:
    """The largest total degree of a numerator or denominator in the states and disturbances."""
    names = model.states + tuple(model.disturbances)
    return max(max(degree_in(model.ring, r.numerator, names), degree_in(model.ring, r.denominator, names))
               for r in model.dynamics)


__all__ = ["Model", "TIME_KINDS", "DISCRETE", "is_model_file", "load_model", "parse_model", "field_at", "check_equilibrium", "with_parameters",
           "degree_of_field", "MAX_STATES"]

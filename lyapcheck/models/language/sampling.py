"""Sampled-data loops in model files: ``[sampling]`` and ``[controller]`` (issue 44, item 2;
DESIGN.md, "Sampled data").

A sampled-data model file is a continuous plant whose ``[dynamics]`` use the names of
``[controller]``; each controller name is computed from the states at every sampling instant and
held (zero-order hold) until the next::

    [sampling]
    period = "20 ms"            # a time, or the name of a [parameters] entry that is one

    [controller]
    u = "-Kp*theta - Kd*omega"  # in the states and parameters; functions (sat, tanh, ...) are recast

Written as a parameter's name (``period = "T"`` with ``T = "20 ms"`` in ``[parameters]``), the period
takes ``--set T=...``, ``certify --maximize T=a..b`` and everything else a parameter takes.

Such a file is not a continuous loop (reading ``u`` as ``k(x(t))`` would be another system, the
"emulation"), so :class:`~lyapcheck.models.language.modelfile.Model`'s readers refuse it by name, and
only :func:`parse_sampled` reads it, into a :class:`SampledModel`. The plant is read as a continuous
loop over the states and the controller names (each a constant state, ``u' = 0``, at its value at the
equilibrium), by the same reader as any model (so the plant may use functions, recast as usual), which
gives ``[[A, B], [0, 0]]`` exactly (:func:`lyapcheck.models.classes.sampled.linear_parts`); the
controller's gain ``K`` is differentiated exactly. A law with functions (``sat(-Kp*theta - Kd*omega, 20)``)
is recast by the same builder (:func:`lyapcheck.models.language.recast.recast_laws`): its value at the
equilibrium is exact or the file is refused naming the law, and its gain is the chain rule through the
auxiliaries (``not_applicable`` where a function is not differentiable there: ``abs`` at 0, ``sat`` at a
corner).

A trained policy is a ``[networks.NAME]`` table, read as a continuous loop's
(:func:`controller_networks`), whose outputs the laws use (``u = "pi_u"``, ``u = "sat(pi_u, 5)"``): the
network is lowered with the laws (its neurons auxiliaries, as in ``[dynamics]``), so ``K`` is the chain
rule through its layers (``tanh'(0) = 1``; a ReLU neuron whose argument is 0 at the equilibrium is not
differentiable there, and ``linearization`` is ``not_applicable`` naming it).
"""

from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Literal, Mapping

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.language.expressions import Rational, uses_functions
from lyapcheck.models.language.modelfile import is_sampled
from lyapcheck.sos.polynomials import Ring

if TYPE_CHECKING:
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.dimensions import Named
    from lyapcheck.models.language.networks import Network
    from lyapcheck.units import Dimension, SIQuantity
    from lyapcheck.models.language.recast import RecastModel, RecastSystem

#: the sections a sampled-data model file may have; the others ([disturbances], [outputs], [domain],
#: [sets]) ask questions the sampled route does not answer yet, and are refused rather than ignored
SAMPLED_SECTIONS: Final = ("model", "parameters", "dynamics", "equilibrium", "sampling", "controller", "networks",
                           "units")
#: the most controller names
MAX_CONTROLS: Final = 6
def file_is_sampled(path: object) -> bool:
    """Whether the file is a sampled-data model file (False when it cannot be read: the reader says why)."""
    if not isinstance(path, (str, Path)):
        return False
    try:
        return is_sampled(tomllib.loads(Path(path).read_bytes().decode("utf-8")))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
        return False


@dataclass(frozen=True)
class SampledModel:
    """A validated sampled-data model file.

    ``plant`` is the continuous loop over the states and then the controller names (each constant,
    at its equilibrium value ``control_equilibrium``), with the parameters set; ``controller`` maps each
    controller name to its law, exact, in ``Ring(states)``; ``period`` is in seconds."""

    source: str
    text: str
    name: str
    states: tuple[str, ...]
    controls: tuple[str, ...]
    parameters: dict[str, Fraction]
    equilibrium: tuple[Fraction, ...]
    control_equilibrium: tuple[Fraction, ...]
    period: Fraction
    period_text: str
    controller_text: dict[str, str]
    controller: dict[str, Rational]
    plant: "Model | RecastModel"
    overrides: dict[str, str] = field(default_factory=dict)
    #: laws with functions (``sat``, ``tanh``, ...): recast over the states (frozen, each auxiliary at its
    #: exact value at the equilibrium), and then each ``controller`` law is a rational function of this
    #: system's ring (states, then auxiliaries), not of ``Ring(states)``; None for polynomial or rational laws
    controller_system: "RecastSystem | None" = None
    #: ``[networks.NAME]`` as read (:func:`lyapcheck.models.language.networks.read_networks`): the controller's,
    #: lowered into :attr:`controller_system` (its neurons the first auxiliaries), their files' SHA-256 in
    #: certificates
    networks: tuple["Network", ...] = ()

    @property
    def sha256(self) -> str:
        import hashlib

        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def n(self) -> int:
        return len(self.states)

    def to_json(self) -> dict[str, Any]:
        """The document's ``sampling`` table."""
        return {"period": str(self.period), "period_given": self.period_text, "controller": dict(self.controller_text),
                "control_equilibrium": {u: str(v) for u, v in zip(self.controls, self.control_equilibrium)}}


def _error(source: str, key: str, message: str) -> ModelFileError:
    return ModelFileError(source, key, message)


def load_sampled(path: str | Path, overrides: Mapping[str, object] | None = None) -> SampledModel:
    """Read a sampled-data model file (one-line errors as :func:`~lyapcheck.models.language.modelfile.load_model`)."""
    from lyapcheck.models.language.modelfile import MAX_FILE_BYTES

    source = str(path)
    p = Path(path)
    try:
        if p.stat().st_size > MAX_FILE_BYTES:
            raise _error(source, "file", f"is {p.stat().st_size} bytes; the limit is {MAX_FILE_BYTES} (MAX_FILE_BYTES)")
        text = p.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise _error(source, "file", "does not exist") from None
    except UnicodeDecodeError:
        raise _error(source, "file", "is not UTF-8 text") from None
    except OSError as exc:
        raise _error(source, "file", f"cannot be read ({exc.strerror or exc})") from None
    return parse_sampled(text, source, overrides)


def parse_sampled(text: str, source: str = "<model>", overrides: Mapping[str, object] | None = None) -> SampledModel:
    """A sampled-data model file's text, validated (module docstring)."""
    from lyapcheck.models.language.modelfile import parse_any_model, read_laws

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _error(source, "file", f"is not valid TOML ({exc})") from None
    extra = [k for k in data if k not in SAMPLED_SECTIONS]
    if extra:
        raise _error(source, f"[{extra[0]}]", f"is not taken with [sampling] yet (a sampled-data loop may have: "
                                              f"{', '.join(SAMPLED_SECTIONS)})")
    for name in ("sampling", "controller"):
        if not isinstance(data.get(name), dict):
            raise _error(source, f"[{name}]", "a sampled-data loop needs both [sampling] (its period) and "
                                              "[controller] (the law held between samples)")
    head = data.get("model")
    states = head.get("states") if isinstance(head, dict) else None
    if not isinstance(states, list) or not states or not all(isinstance(s, str) for s in states):
        raise _error(source, "[model] states", f"must be a non-empty list of names, got {states!r}")
    if isinstance(head, dict) and head.get("time", "continuous") != "continuous":
        raise _error(source, "[model] time", f"a sampled-data loop's plant is continuous (\"continuous\"); got "
                                             f"{head.get('time')!r}")
    controls = tuple(data["controller"])
    if not controls or len(controls) > MAX_CONTROLS:
        raise _error(source, "[controller]", f"must name 1 to {MAX_CONTROLS} controls; got {len(controls)}")
    dynamics = data.get("dynamics")
    for u in controls:
        if u in states or u in data.get("parameters", {}):
            raise _error(source, f"[controller] {u}", f"the name '{u}' is declared twice (also a "
                                                      f"{'state' if u in states else 'parameter'})")
        if isinstance(dynamics, dict) and u in dynamics:  # (the plant reads each control as a constant state)
            raise _error(source, f"[dynamics] {u}", f"an equation for the control '{u}': a control is computed by "
                                                    "[controller] at each sample and held, it has no dynamics")
    laws = {u: data["controller"][u] for u in controls}
    for u, law in laws.items():
        if not isinstance(law, (str, int, float)) or isinstance(law, bool):
            raise _error(source, f"[controller] {u}", f"must be an expression in a string, got {law!r}")
    plain = {k: v for k, v in data.items() if k not in ("sampling", "controller", "networks")}
    # (a network's outputs are names of the recasting: laws beside [networks] are recast as laws with functions)
    with_functions = uses_functions([str(v) for v in laws.values()]) or "networks" in data
    # (laws with functions are recast below; read here as "0", their names are still checked)
    params, x_eq, controller = read_laws(text, source, plain, overrides, "controller",
                                         {u: "0" for u in laws} if with_functions else laws)
    period, period_text = _period(source, data["sampling"], params, data.get("parameters"))
    ring = Ring(tuple(states))
    u_eq: list[Fraction] = []
    laws_system = None
    networks = controller_networks(source, data, tuple(states), controls, params)
    units = _plant_units(source, data, tuple(states), controls, networks) if "units" in data else None
    if with_functions:  # recast as a loop's right-hand sides are; the values at the equilibrium exact
        laws_system, controller, u_eq = _function_laws(source, tuple(states), laws, params, x_eq, networks)
    else:
        for u, law in controller.items():
            den = ring.evaluate(law.denominator, list(x_eq))
            if den == 0:
                raise _error(source, f"[controller] {u}", "its denominator is 0 at the equilibrium")
            u_eq.append(ring.evaluate(law.numerator, list(x_eq)) / den)
    if units is not None:  # each law in the dimension the plant needs for its control (the plant is checked next)
        _check_laws(source, laws, units[1], units[2])
    plant = parse_any_model(text, source, overrides, tables=_plant_view(data, controls, tuple(u_eq),
                                                                       None if units is None else units[0]))
    return SampledModel(source=source, text=text, name=str(head.get("name", Path(source).stem)) if isinstance(head, dict)
                        else Path(source).stem, states=tuple(states), controls=controls, parameters=params,
                        equilibrium=x_eq, control_equilibrium=tuple(u_eq), period=period, period_text=period_text,
                        controller_text={u: str(v) for u, v in laws.items()}, controller=controller, plant=plant,
                        overrides={k: str(v) for k, v in (overrides or {}).items()}, controller_system=laws_system,
                        networks=networks)


def _function_laws(source: str, states: tuple[str, ...], laws: Mapping[str, object], params: Mapping[str, Fraction],
                   x_eq: tuple[Fraction, ...], networks: tuple["Network", ...] = ()
                   ) -> tuple["RecastSystem", dict[str, Rational], list[Fraction]]:
    """Controller laws with functions, recast as a loop's right-hand sides are
    (:func:`lyapcheck.models.language.recast.recast_laws`, ``networks`` lowered with them), and each law's
    exact value at the equilibrium (a law whose value there is irrational, or whose denominator is 0 there,
    is refused in one line)."""
    from lyapcheck.models.language.recast import recast_laws, value_at_equilibrium

    system, recast = recast_laws(source, "controller", states, laws, params, x_eq, networks)
    u_eq = []
    for u, law in recast.items():
        num, den = value_at_equilibrium(system, law.numerator), value_at_equilibrium(system, law.denominator)
        if num is None or den is None:
            raise _error(source, f"[controller] {u}", "its value at the equilibrium is irrational (sqrt 2 or sqrt 3): "
                                                      "the control held there must be an exact rational")
        if den == 0:
            raise _error(source, f"[controller] {u}", "its denominator is 0 at the equilibrium")
        u_eq.append(num / den)
    return system, recast, u_eq


def controller_networks(source: str, data: Mapping[str, Any], states: tuple[str, ...], controls: tuple[str, ...],
                        params: Mapping[str, Fraction]) -> tuple["Network", ...]:
    """``[networks.NAME]`` of a sampled-data file, read by the model files' reader
    (:func:`lyapcheck.models.language.networks.read_networks`: .npz or ONNX, shapes checked, each file's
    SHA-256): the digital controller's networks, evaluated at each sample, whose outputs the
    ``[controller]`` laws may use (``u = "sat(pi_u, 5)"``). A ``[dynamics]`` right-hand side that uses an
    output is refused naming it: the network would then run inside the continuous plant, another loop."""
    if "networks" not in data:
        return ()
    from lyapcheck.models.language.expressions import FUNCTIONS, written_tree
    from lyapcheck.models.language.networks import read_networks

    taken = {**{s: "a state" for s in states}, **{p: "a parameter" for p in params},
             **{u: "a control in [controller]" for u in controls},
             **{f: "a function of the language" for f in (*FUNCTIONS, "pi")}}
    networks = read_networks(source, data["networks"], states, taken)
    outputs = {o: n.key for n in networks for o in n.outputs}
    dynamics = data.get("dynamics")
    for state, text in (dynamics.items() if isinstance(dynamics, dict) else ()):
        tree = written_tree(text)
        used = next((node.id for node in ast.walk(tree) if isinstance(node, ast.Name) and node.id in outputs), None) \
            if tree is not None else None
        if used is not None:
            raise _error(source, f"[dynamics] {state}", f"uses '{used}', an output of {outputs[used]}: in a sampled-data "
                                                        "loop a network is the digital controller's, evaluated at each "
                                                        f"sample; use its outputs in [controller] (e.g. u = \"{used}\")")
    return networks


def _plant_units(source: str, data: Mapping[str, Any], states: tuple[str, ...], controls: tuple[str, ...],
                 networks: tuple["Network", ...]) -> tuple[dict[str, str], dict[str, "Named"], dict[str, "Dimension"]]:
    """``[units]`` beside ``[sampling]``: the plant's ``[units]`` table with each control's SI unit added, the
    one its right-hand sides need for it (:func:`lyapcheck.models.language.dimensions.infer_controls`), so
    that the plant reader dimension-checks the plant as any continuous loop's; and the names' dimensions
    and the controls' for :func:`_check_laws`. One-line errors naming the key."""
    from lyapcheck.models.language import dimensions as dims
    from lyapcheck.units import DIMENSIONLESS, model_unit, parse_si_with_dimension

    if networks:  # a network's outputs have no declared dimension to check a law against (as in [dynamics])
        raise _error(source, "[units]", "a sampled-data loop with [networks] is not dimension-checked yet: remove "
                                        "[units] (the states' units may stay in comments)")
    table, params, dynamics = data["units"], data.get("parameters", {}), data.get("dynamics")
    if not isinstance(table, dict):
        raise _error(source, "[units]", f"must be a table, got {type(table).__name__}")
    for u in controls:
        if u in table:
            raise _error(source, f"[units] {u}", f"'{u}' is a control ([controller]): it takes the dimension the plant's "
                                                 "[dynamics] need for it, and its law is checked against that; [units] "
                                                 "lists states (and time)")
    try:
        units = dims.read_units(table, states, list(params))
        quantities: dict[str, tuple[Literal["parameter", "disturbance"], SIQuantity]] = {
            k: ("parameter", parse_si_with_dimension(k, v)) for k, v in params.items()}  # (each checked before)
        names = dims.named_table(units, quantities, {k: str(v) for k, v in params.items()})
    except dims.DimensionError as exc:
        raise _error(source, exc.key, exc.message) from None
    texts = {s: str(t) for s, t in dynamics.items() if s in states} if isinstance(dynamics, dict) else {}
    inferred = dims.infer_controls(texts, units, names, controls)
    plant = dict(table)
    for u, dimension in inferred.items():
        unit = dimension.si_unit()
        try:
            if unit:
                model_unit(u, unit, unit)
        except InvalidParameter:
            raise _error(source, f"[controller] {u}", f"the plant's [dynamics] need it in {dimension}, which has no "
                                                      "SI unit to check the law against") from None
        plant[u] = unit
    # the plant's right-hand sides with each control in that dimension first (the plant reader checks them
    # again): a plant that needs two dimensions for one control is named there, not blamed on the law
    with_controls = dims.UnitTable({**units.states, **{u: (plant.get(u, ""), inferred.get(u, DIMENSIONLESS))
                                                       for u in controls}}, units.time)
    named = {**names, **{u: dims.Named("state", with_controls.dimension(u), with_controls.states[u][0] or "1", True)
                         for u in controls}}
    for s, text in texts.items():
        try:
            dims.check_dynamics(s, text, with_controls, named)
        except dims.OutsideLanguage:
            continue  # the plant's parser says what is wrong
        except dims.DimensionError as exc:
            raise _error(source, exc.key, exc.message) from None
    return plant, names, inferred


def _check_laws(source: str, laws: Mapping[str, object], names: Mapping[str, "Named"],
                inferred: Mapping[str, "Dimension"]) -> None:
    """Each ``[controller]`` law has the dimension the plant needs for its control (every term, as a
    right-hand side's), or, where the plant does not tell it, agrees with itself; every function's argument
    is dimensionless (``sin`` of a length is refused, naming it)."""
    from lyapcheck.models.language import dimensions as dims

    for u, law in laws.items():
        dimension = inferred.get(u)
        why = f"the dimension the plant's [dynamics] need for the control {u}" if dimension is not None else ""
        try:
            dims.check_law(u, str(law), dimension, why, names)
        except dims.DimensionError as exc:
            raise _error(source, exc.key, exc.message) from None


def _plant_view(data: Mapping[str, Any], controls: tuple[str, ...], u_eq: tuple[Fraction, ...],
                units: Mapping[str, str] | None = None) -> dict[str, Any]:
    """The file's tables as a continuous loop over the states and the controls, each control a
    constant state (``u' = 0``) at its equilibrium value: its Jacobian is ``[[A, B], [0, 0]]``
    (without ``[networks]``: they are the controller's; ``units``, when given, is its ``[units]`` with the
    controls' units, :func:`_plant_units`)."""
    states = list(data["model"]["states"])
    return {**{k: v for k, v in data.items() if k not in ("sampling", "controller", "networks")},
            **({"units": dict(units)} if units is not None else {}),
            "model": {**data["model"], "states": states + list(controls)},
            "dynamics": {**data["dynamics"], **{u: "0" for u in controls}},
            "equilibrium": {**data.get("equilibrium", {}), **dict(zip(controls, u_eq))}}


def _period(source: str, table: Mapping[str, Any], params: Mapping[str, Fraction],
            given: object = None) -> tuple[Fraction, str]:
    """``[sampling] period``: a time (``"20 ms"``; a bare number is seconds) or a parameter's name (``given``,
    the file's ``[parameters]``: one given with a unit must be a time); > 0."""
    from lyapcheck.units import parse_si_with_dimension

    unknown = [k for k in table if k != "period"]
    if unknown:
        raise _error(source, f"[sampling] {unknown[0]}", "unknown key (keys: period)")
    if "period" not in table:
        raise _error(source, "[sampling] period", "missing (the sampling period, e.g. \"20 ms\")")
    raw = table["period"]
    if isinstance(raw, str) and raw.strip() in params:
        value = params[raw.strip()]
        written = given.get(raw.strip()) if isinstance(given, dict) else None
        quantity = parse_si_with_dimension(raw.strip(), written) if isinstance(written, str) else None
        if quantity is not None and quantity.unit and str(quantity.dimension) != "[time]":
            raise _error(source, "[sampling] period", f"must be a time: the parameter {raw.strip()} = '{written}' has "
                                                      f"dimension {quantity.dimension}")
    else:
        try:
            quantity = parse_si_with_dimension("period", raw)
        except InvalidParameter as exc:
            raise _error(source, "[sampling] period", f"must be a time such as \"20 ms\" or a parameter's name "
                                                      f"({exc.expected}); got {raw!r}") from None
        if quantity.unit and str(quantity.dimension) != "[time]":
            raise _error(source, "[sampling] period", f"must be a time (s, ms, ...), got {raw!r} "
                                                      f"(dimension {quantity.dimension})")
        value = quantity.value
    if not value > 0:
        raise _error(source, "[sampling] period", f"must be > 0 seconds, got {raw!r}")
    return value, str(raw)


__all__ = ["MAX_CONTROLS", "SAMPLED_SECTIONS", "SampledModel", "controller_networks", "file_is_sampled", "is_sampled",
           "load_sampled", "parse_sampled"]

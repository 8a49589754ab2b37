"""Validated, immutable parameters: gains, swimmer, actuation, path and disturbance.

Every number that enters the toolkit from outside (TOML file, command-line flag, sweep spec)
passes through :func:`build_problem`, which checks it against the declarative table
:data:`FIELDS` and raises :class:`~lyapcheck.errors.InvalidParameter` with one message shape:

    The 'alpha_d' parameter must be a number in (0, inf). Got -1 instead.

Values are stored in SI as exact :class:`~fractions.Fraction` (decimal input is exact);
``float(...)`` gives the floating-point view.

Besides its interval, every value is 0 or has the magnitude of a normal double,
:data:`lyapcheck.units.MAGNITUDES` (from 2.2e-308 to 1.8e308, in SI): the classes, the
simulation and the JSON output read the floating-point view, which outside that range is
``inf`` or has lost precision. Within it, a class that cannot decide at an extreme scale
reports ``inconclusive`` with its reason, and the others still run.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, Mapping

from lyapcheck.errors import InputFileError, InvalidParameter
from lyapcheck.units import FLOAT_MAX, FLOAT_MIN_NORMAL, Kind, parse_quantity, representable

INF = math.inf


@dataclass(frozen=True)
class Interval:
    """A real interval; bounds are SI values."""

    low: float
    high: float
    closed_low: bool = False
    closed_high: bool = False

    def contains(self, x: Fraction) -> bool:
        lo_ok = x >= self.low if self.closed_low else x > self.low
        hi_ok = x <= self.high if self.closed_high else x < self.high
        return bool(lo_ok and hi_ok)

    def __str__(self) -> str:
        lo = "[" if self.closed_low else "("
        hi = "]" if self.closed_high else ")"
        fmt = lambda v: "inf" if v == INF else ("-inf" if v == -INF else f"{v:g}")  # noqa: E731
        return f"{lo}{fmt(self.low)}, {fmt(self.high)}{hi}"

    def _part(self, low: float, high: float) -> tuple[float, bool, float, bool] | None:
        """This interval cut to ``[low, high]`` (closed): (low, closed, high, closed), or None if empty."""
        lo, lo_closed = (low, True) if self.low < low else (self.low, self.closed_low)
        hi, hi_closed = (high, True) if self.high > high else (self.high, self.closed_high)
        if lo > hi or (lo == hi and not (lo_closed and hi_closed)):
            return None
        return lo, lo_closed, hi, hi_closed

    def accepted(self) -> str:
        """What this interval accepts once values must be 0 or normal doubles (units.MAGNITUDES).

        ``(0, inf)`` accepts ``[2.2250738585072014e-308, 1.7976931348623157e+308]``; the extreme
        bounds are written exactly (repr), the others like :meth:`__str__`.
        """
        def fmt(v: float) -> str:
            return repr(v) if abs(v) in (FLOAT_MAX, FLOAT_MIN_NORMAL) else f"{v:g}"

        def text(part: tuple[float, bool, float, bool]) -> str:
            lo, lo_closed, hi, hi_closed = part
            return f"{'[' if lo_closed else '('}{fmt(lo)}, {fmt(hi)}{']' if hi_closed else ')'}"

        pos = self._part(FLOAT_MIN_NORMAL, FLOAT_MAX)
        neg = self._part(-FLOAT_MAX, -FLOAT_MIN_NORMAL)
        if pos and neg and (-neg[2], neg[3], -neg[0], neg[1]) == pos:
            pieces = [f"of magnitude in {text(pos)}"]
        else:
            pieces = [f"in {text(p)}" for p in (neg, pos) if p is not None]
        if self.contains(Fraction(0)):
            pieces.insert(0, "0")
        return " or ".join(pieces)


POSITIVE = Interval(0, INF)
NONNEGATIVE = Interval(0, INF, closed_low=True)


@dataclass(frozen=True)
class FieldSpec:
    """Declarative description of one input field."""

    section: str
    name: str
    kind: Kind
    interval: Interval
    default: object | None
    help: str
    bare_allowed: bool = False

    @property
    def key(self) -> str:
        return f"{self.section}.{self.name}"


#: Every input field. Accepted values: the field's interval, in the SI unit of its kind, and
#: (for every field) 0 or a magnitude in the normal double range, 2.2250738585072014e-308 to
#: 1.7976931348623157e+308 (lyapcheck.units.MAGNITUDES; the module docstring says why).
FIELDS: tuple[FieldSpec, ...] = (
    FieldSpec("gains", "alpha_d", Kind.RATE, POSITIVE, None, "ILOS gain alpha_d in 1/s (eq:los)"),
    FieldSpec("gains", "sigma0", Kind.DIMENSIONLESS, POSITIVE, None, "integral gain sigma_0 (eq:los)"),
    FieldSpec("gains", "k_d", Kind.RATE, POSITIVE, None, "damping gain k_d in 1/s (eq:losdynvar)"),
    FieldSpec("gains", "delta_los", Kind.LENGTH, POSITIVE, None, "look-ahead distance Delta_LOS"),
    FieldSpec(
        "gains", "los_speed", Kind.VELOCITY, POSITIVE, "1 m/s",
        "speed U that makes eq:losdynvar dimensionally consistent; 1 m/s reads the paper in SI",
    ),
    FieldSpec("swimmer", "e11", Kind.LENGTH, POSITIVE, None, "propulsion constant e11 (m per rad) (eq:e11)"),
    FieldSpec("swimmer", "e11_hat", Kind.LENGTH, POSITIVE, "1 m", "controller's estimate of e11 (Remark rem:Estimates)"),
    FieldSpec("swimmer", "n_turns", Kind.DIMENSIONLESS, POSITIVE, None, "number of helix turns n_h"),
    FieldSpec("swimmer", "pitch_angle", Kind.ANGLE, Interval(0, math.pi / 2), None, "helix pitch angle theta_h"),
    FieldSpec("swimmer", "helix_radius", Kind.LENGTH, POSITIVE, None, "helix radius r_h"),
    FieldSpec("swimmer", "weight", Kind.FORCE, NONNEGATIVE, None, "weight |d_g| of the swimmer"),
    FieldSpec("swimmer", "xi_par", Kind.DRAG_PER_LENGTH, POSITIVE, None, "parallel RFT drag coefficient"),
    FieldSpec("swimmer", "xi_perp", Kind.DRAG_PER_LENGTH, POSITIVE, None, "normal RFT drag coefficient"),
    FieldSpec("swimmer", "xi_head", Kind.DRAG, NONNEGATIVE, "0 N*s/m", "drag coefficient of the magnetic head xi_vm"),
    FieldSpec("swimmer", "head_offset", Kind.LENGTH, NONNEGATIVE, "0 m", "distance |k_h| from helix centre to head"),
    FieldSpec("actuation", "omega_so", Kind.ROTATION, POSITIVE, None, "step-out frequency Omega_SO"),
    FieldSpec("actuation", "omega_0", Kind.ROTATION, POSITIVE, "1 Hz", "ODS gain Omega_0 (eq:solFinal)"),
    FieldSpec("path", "theta_r", Kind.ANGLE, Interval(-math.pi, math.pi, True, True), "0 deg", "path angle theta_r"),
    FieldSpec("disturbance", "d_max", Kind.VELOCITY, NONNEGATIVE, None, "disturbance bound d* on |d_mu|"),
)

FIELD_BY_KEY: dict[str, FieldSpec] = {spec.key: spec for spec in FIELDS}
SECTIONS: tuple[str, ...] = tuple(dict.fromkeys(spec.section for spec in FIELDS))


def validate_field(spec: FieldSpec, value: object, *, numbers_in_si: bool = False) -> Fraction:
    """Parse `value` for `spec` and check its range; the single validation path.

    ``numbers_in_si``: a plain number (not a string) is read in the field's SI unit (the Python
    API's promise, ``docs/api.md``); TOML files and command-line flags keep requiring units for
    the fields that have one.
    """
    bare = spec.bare_allowed or (numbers_in_si and not isinstance(value, (str, bool)))
    parsed = parse_quantity(spec.name, value, spec.kind, bare_allowed=bare)
    unit = f" {spec.kind.si_unit}" if spec.kind.si_unit else ""
    if not spec.interval.contains(parsed):
        raise InvalidParameter(spec.name, f"in {spec.interval}{unit}", value)
    if not representable(parsed):  # in the interval, yet beyond the normal double range
        raise InvalidParameter(spec.name, f"{spec.interval.accepted()}{unit} (normal doubles)", value)
    return parsed


@dataclass(frozen=True)
class GainSet:
    """ILOS guidance gains (eqs. ``eq:los``, ``eq:losdynvar``), SI."""

    alpha_d: Fraction
    sigma0: Fraction
    k_d: Fraction
    delta_los: Fraction
    los_speed: Fraction = Fraction(1)


@dataclass(frozen=True)
class Swimmer:
    """Swimmer constants (Section 2, Table table:micro1), SI; geometry is optional."""

    e11: Fraction
    e11_hat: Fraction = Fraction(1)
    n_turns: Fraction | None = None
    pitch_angle: Fraction | None = None
    helix_radius: Fraction | None = None
    weight: Fraction | None = None
    xi_par: Fraction | None = None
    xi_perp: Fraction | None = None
    xi_head: Fraction = Fraction(0)
    head_offset: Fraction = Fraction(0)


@dataclass(frozen=True)
class Actuation:
    """Rotation limits as angular velocities in rad/s (Hz inputs are multiplied by 2*pi).

    ``omega_so`` is ``None`` when it was not given: the classes that need it report
    ``not_applicable``, and simulations ask for it through :meth:`step_out`.
    """

    omega_so: Fraction | None
    omega_0: Fraction = Fraction(2 * math.pi)

    def step_out(self) -> Fraction:
        """Omega_SO in rad/s, or a one-line :class:`InvalidParameter` when it was not given."""
        if self.omega_so is None:
            raise InvalidParameter("omega_so", f"given ({FIELD_BY_KEY['actuation.omega_so'].help}, e.g. '2.8 Hz')",
                                   None)
        return self.omega_so

    @property
    def omega_so_hz(self) -> float:
        return float(self.step_out()) / (2 * math.pi)


@dataclass(frozen=True)
class Problem:
    """Everything one certificate or simulation needs, validated and in SI."""

    gains: GainSet
    swimmer: Swimmer
    actuation: Actuation
    theta_r: Fraction = Fraction(0)
    #: ``None`` when not given (the classes that need it report ``not_applicable``)
    d_max: Fraction | None = None
    #: the inputs exactly as given (text), keyed "section.name", for certificates
    given: Mapping[str, str] = field(default_factory=dict, compare=False)

    def disturbance_bound(self) -> Fraction:
        """d* in m/s, or a one-line :class:`InvalidParameter` when it was not given."""
        if self.d_max is None:
            raise InvalidParameter("d_max", f"given ({FIELD_BY_KEY['disturbance.d_max'].help}, e.g. '0.088 mm/s')",
                                   None)
        return self.d_max

    def missing_inputs(self) -> tuple[str, ...]:
        """Keys of the optional inputs that were not given (``actuation.omega_so``, ``disturbance.d_max``)."""
        return tuple(key for key, value in (("actuation.omega_so", self.actuation.omega_so),
                                            ("disturbance.d_max", self.d_max)) if value is None)

    def with_gains(self, **changes: Fraction) -> "Problem":
        """A copy with some gains replaced (used by sweeps); values must already be valid."""
        return replace(self, gains=replace(self.gains, **changes))


def flatten_tables(data: Mapping[str, Any], source: str) -> dict[str, object]:
    """TOML tables as ``{"section.name": raw}``; unknown sections and keys are errors.

    The sections of other readers (``simulation``, ``sweep``, ``meta``) are skipped: the
    scenario and sweep readers validate those themselves.
    """
    flat: dict[str, object] = {}
    for section, content in data.items():
        if section not in SECTIONS:
            if section in ("simulation", "sweep", "meta"):
                continue  # belongs to other readers (scenario / sweep specs)
            raise InvalidParameter(section, f"one of the sections {', '.join(SECTIONS)} in {source}", section)
        if not isinstance(content, Mapping):
            raise InvalidParameter(section, "a table of parameters", content)
        for name, value in content.items():
            key = f"{section}.{name}"
            if key not in FIELD_BY_KEY:
                known = ", ".join(s.name for s in FIELDS if s.section == section)
                raise InvalidParameter(key, f"a known key of [{section}] ({known})", name)
            flat[key] = value
    return flat


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file, mapping every failure to a one-line :class:`InputFileError`."""
    p = Path(path)
    try:
        with p.open("rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        raise InputFileError(f"input file '{p}' does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(f"input file '{p}' is not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:  # TOML is UTF-8
        raise InputFileError(f"input file '{p}' is not UTF-8 text: {exc.reason} at byte {exc.start}") from None
    except OSError as exc:
        raise InputFileError(f"input file '{p}' cannot be read: {exc.strerror}") from None


def build_problem(values: Mapping[str, object], *, source: str = "input", numbers_in_si: bool = False) -> Problem:
    """Validate a flat mapping ``{"section.name": value}`` into a :class:`Problem`.

    Missing required fields raise :class:`InvalidParameter` naming the field. The step-out
    frequency and the disturbance bound are optional: only some classes and the simulations
    need them (see :meth:`Problem.disturbance_bound`, :meth:`Actuation.step_out`).
    ``numbers_in_si``: plain numbers are SI values (see :func:`validate_field`).
    """
    parsed: dict[str, Fraction | None] = {}
    given: dict[str, str] = {}
    for spec in FIELDS:
        raw = values.get(spec.key, spec.default)
        if raw is None:
            parsed[spec.key] = None
            continue
        parsed[spec.key] = validate_field(spec, raw, numbers_in_si=numbers_in_si)
        given[spec.key] = str(raw) if isinstance(raw, str) or not numbers_in_si or spec.bare_allowed \
            else f"{raw} {spec.kind.si_unit}".rstrip()
    unknown = set(values) - set(FIELD_BY_KEY)
    if unknown:
        key = sorted(unknown)[0]
        raise InvalidParameter(key, "a known parameter", values[key])

    def req(key: str) -> Fraction:
        value = parsed[key]
        if value is None:
            spec = FIELD_BY_KEY[key]
            raise InvalidParameter(spec.name, f"given ({spec.help}) in {source}", None)
        return value

    def opt(key: str) -> Fraction | None:
        return parsed[key]

    gains = GainSet(
        alpha_d=req("gains.alpha_d"), sigma0=req("gains.sigma0"), k_d=req("gains.k_d"),
        delta_los=req("gains.delta_los"), los_speed=req("gains.los_speed"),
    )
    swimmer = Swimmer(
        e11=req("swimmer.e11"), e11_hat=req("swimmer.e11_hat"), n_turns=opt("swimmer.n_turns"),
        pitch_angle=opt("swimmer.pitch_angle"), helix_radius=opt("swimmer.helix_radius"),
        weight=opt("swimmer.weight"), xi_par=opt("swimmer.xi_par"), xi_perp=opt("swimmer.xi_perp"),
        xi_head=req("swimmer.xi_head"), head_offset=req("swimmer.head_offset"),
    )
    actuation = Actuation(omega_so=opt("actuation.omega_so"), omega_0=req("actuation.omega_0"))
    return Problem(
        gains=gains, swimmer=swimmer, actuation=actuation, theta_r=req("path.theta_r"),
        d_max=opt("disturbance.d_max"), given=given,
    )


def problem_from_sources(toml_path: str | Path | None, overrides: Mapping[str, object]) -> Problem:
    """TOML file (optional) overlaid with command-line overrides, then validated."""
    values: dict[str, object] = {}
    source = "command-line flags"
    if toml_path is not None:
        values.update(flatten_tables(load_toml(toml_path), str(toml_path)))
        source = str(toml_path)
    values.update({k: v for k, v in overrides.items() if v is not None})
    return build_problem(values, source=source)


__all__ = [
    "FIELDS", "FieldSpec", "Interval", "GainSet", "Swimmer", "Actuation", "Problem",
    "build_problem", "problem_from_sources", "load_toml", "validate_field", "flatten_tables",
]

"""Quantities with units: parsing strings such as ``"0.75 mm"`` into exact SI values.

Everything inside the toolkit is SI. Magnitudes are parsed as exact decimals and kept as
:class:`fractions.Fraction`, so that exact certificate checks see the number the user typed,
not its binary floating-point neighbour.

Every number is finite, and its exact SI value is 0 or has the magnitude of a *normal*
double (:data:`MAGNITUDES`): the classes, the simulation and the JSON output all read the
floating-point view ``float(x)`` of a value, which beyond :data:`FLOAT_MAX` is ``inf`` (no
JSON number, no arithmetic) and below :data:`FLOAT_MIN_NORMAL` a subnormal with fewer
significant bits than the number given (0 below 5e-324). A decimal carries at most
:data:`MAX_SIGNIFICANT_DIGITS` significant digits (see there). :func:`representable` checks
the magnitude; :func:`lyapcheck.paper.params.validate_field` applies it to every field.

Rotation is handled apart from pint's own conversion: pint treats ``Hz`` and ``rad/s`` as the
same dimension (1/s) and would turn ``2.8 Hz`` into ``2.8 rad/s``. A rotation *frequency* in
Hz is cycles per second; the toolkit converts it to an angular velocity with a factor 2*pi,
and refuses a bare ``1/s`` for a rotation because it is ambiguous.

Model files say nothing of which quantity is a rotation, and their values must be exact: there
:func:`parse_si_quantity` converts any unit to SI base units exactly (pint's decimal definitions
read as fractions: ``1/min`` is 1/60), gives its :class:`Dimension` for the ``[units]`` check
(:mod:`lyapcheck.models.language.dimensions`), and refuses ``Hz``, units defined through pi and the symbol
``l`` with a message saying what to write (:func:`model_unit`; docs/model-files-units.md).
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from enum import Enum
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Mapping, NamedTuple

from lyapcheck.errors import InvalidParameter

if TYPE_CHECKING:  # pragma: no cover
    import pint

#: the largest magnitude of a value (SI): the largest finite double
FLOAT_MAX: Final = sys.float_info.max
#: the smallest non-zero magnitude of a value (SI): the smallest normal double
FLOAT_MIN_NORMAL: Final = sys.float_info.min
#: the accepted magnitudes, as error messages state them
MAGNITUDES: Final = f"0 or of magnitude in [{FLOAT_MIN_NORMAL!r}, {FLOAT_MAX!r}] (a normal double)"
#: Significant digits of a decimal input. Exact values are stored in certificates as "p/q"
#: text, and Python writes and reads integers of at most 4300 digits
#: (``sys.get_int_max_str_digits``); a matrix entry multiplies a few inputs, each of which has
#: up to ~430 digits at the ends of the double range with 100 significant digits. A double
#: holds 17; no measured or designed value carries 100.
MAX_SIGNIFICANT_DIGITS: Final = 100
#: A decimal exponent beyond this cannot come back into the double range with any unit (unit
#: factors are doubles, within 1e-324..1e309): rejected before building 10**exponent exactly.
_MAX_DECIMAL_EXPONENT: Final = 700
#: numerator / denominator size of a Fraction given through the Python API (the same budget
#: as MAX_SIGNIFICANT_DIGITS digits at the ends of the double range: about 450 digits)
_MAX_FRACTION_BITS: Final = 1500

_NUMBER = re.compile(r"^\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")


class Kind(Enum):
    """Physical kind of an input quantity, with its SI unit and an example for messages."""

    LENGTH = ("[length]", "m", "a length such as '0.75 mm'")
    VELOCITY = ("[length] / [time]", "m/s", "a velocity such as '0.088 mm/s'")
    FORCE = ("[force]", "N", "a force such as '8.7e-5 N'")
    TIME = ("[time]", "s", "a duration such as '100 s'")
    ANGLE = ("", "rad", "an angle such as '45 deg'")
    ROTATION = ("1 / [time]", "rad/s", "a rotation rate such as '2.8 Hz' or '17.6 rad/s'")
    RATE = ("1 / [time]", "1/s", "a rate in 1/s such as 600 or '600 1/s'")
    DIMENSIONLESS = ("", "", "a plain number")
    DRAG_PER_LENGTH = ("[mass] / [length] / [time]", "N*s/m^2", "a drag coefficient per length such as '1.5 N*s/m^2'")
    DRAG = ("[mass] / [time]", "N*s/m", "a drag coefficient such as '1e-5 N*s/m'")
    VISCOSITY = ("[mass] / [length] / [time]", "Pa*s", "a viscosity such as '2.5 Pa*s'")

    @property
    def dimensionality(self) -> str:
        return self.value[0]

    @property
    def si_unit(self) -> str:
        return self.value[1]

    @property
    def example(self) -> str:
        return self.value[2]


@lru_cache(maxsize=1)
def registry() -> "pint.UnitRegistry[Any]":
    """The toolkit's pint registry (created on first use: pint costs ~0.3 s to import)."""
    import pint

    # the parsed-definitions cache turns ~1 s of registry construction into ~0.1 s
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except OSError:  # pragma: no cover - read-only home: build without the cache
        return pint.UnitRegistry()


def representable(value: Fraction) -> bool:
    """Whether ``value`` is 0 or has the magnitude of a normal double (:data:`MAGNITUDES`)."""
    return value == 0 or FLOAT_MIN_NORMAL <= abs(value) <= FLOAT_MAX


def _exact_decimal(field: str, number: Decimal, got: object) -> Fraction:
    """The exact value of a finite decimal, refusing what no unit brings into range or too many digits."""
    if not number:
        return Fraction(0)
    if abs(number.adjusted()) > _MAX_DECIMAL_EXPONENT:
        raise InvalidParameter(field, MAGNITUDES, got)
    digits = "".join(map(str, number.as_tuple().digits)).strip("0")
    if len(digits) > MAX_SIGNIFICANT_DIGITS:
        raise InvalidParameter(field, f"a number with at most {MAX_SIGNIFICANT_DIGITS} significant digits", got)
    return Fraction(number)


#: unit factors remembered across runs (:func:`_remembered_factors`), at most this many
FACTOR_MEMO_SIZE: Final = 512


def _factor_memo_path() -> Path | None:
    """The memo of unit factors: one file per version of pint and of this module, so that a
    change of either recomputes every factor. None when the version cannot be read."""
    import hashlib
    from importlib import metadata

    from lyapcheck.fileio import cache_dir

    try:
        version = metadata.version("pint")
        source = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
    except (OSError, metadata.PackageNotFoundError):  # pragma: no cover - a broken install
        return None
    return cache_dir() / f"unit-factors-{source}-pint-{version}.json"


@lru_cache(maxsize=1)
def _remembered_factors() -> dict[str, str]:
    """``"KIND|unit text" -> exact factor`` as pint computed it in an earlier run.

    Why: importing pint and building its registry costs about 0.35 s, most of a quick
    ``certify``; the factors of the handful of unit strings a user types never change for one
    version of pint and of this module (the file name carries both). Only successful
    conversions are remembered; an unreadable or malformed memo is ignored (pint decides).
    """
    import json

    path = _factor_memo_path()
    try:
        data = json.loads(path.read_text()) if path is not None else {}
        return {str(k): str(v) for k, v in data.items()} if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def _remember_factor(key: str, factor: Fraction) -> None:
    """Add one factor to the memo (atomically; a read-only or full memo is left as it is)."""
    _remember_text(key, str(factor))


def _si_factor(field: str, unit_text: str, kind: Kind, got: object) -> Fraction:
    """Exact factor that turns one `unit_text` into SI for `kind` (pint's, remembered across runs)."""
    key = f"{kind.name}|{unit_text}"
    remembered = _remembered_factors().get(key)
    if remembered is not None:
        try:
            return Fraction(remembered)
        except (ValueError, ZeroDivisionError):  # a damaged memo entry: ask pint
            pass
    factor = _pint_factor(field, unit_text, kind, got)
    _remember_factor(key, factor)
    return factor


def _pint_factor(field: str, unit_text: str, kind: Kind, got: object) -> Fraction:
    """Exact factor that turns one `unit_text` into SI for `kind`, from pint."""
    ureg = registry()
    import pint

    try:
        unit = ureg.Unit(unit_text) if unit_text else ureg.dimensionless
    except (pint.errors.UndefinedUnitError, AttributeError, ValueError, TypeError, SyntaxError, AssertionError):
        raise InvalidParameter(field, kind.example, got) from None
    except Exception:  # pint raises a zoo of parser errors on odd strings
        raise InvalidParameter(field, kind.example, got) from None
    try:
        factor = _float_factor(field, unit, kind, got)
    except (ArithmeticError, pint.errors.PintError):  # e.g. "(Ym/um)**20*m": 1e720 overflows pint's float
        raise InvalidParameter(field, kind.example, got) from None
    if not math.isfinite(factor) or factor == 0:
        raise InvalidParameter(field, kind.example, got)
    # pint returns floats; the prefixes and units we accept have short exact decimal factors
    # (1e-3, 1e-6, ...), and repr() gives that shortest decimal back. A rotation factor carries
    # 2*pi as a double: taken exactly as that double.
    return Fraction(factor) if kind is Kind.ROTATION else Fraction(Decimal(repr(factor)))


def _float_factor(field: str, unit: Any, kind: Kind, got: object) -> float:
    """The float factor that turns one ``unit`` into SI for ``kind`` (wrong dimension: InvalidParameter)."""
    import pint

    ureg = registry()

    if kind is Kind.ROTATION:
        names = {name for name, _ in (1 * unit).unit_items()}
        try:
            if names & {"radian", "revolution", "turn", "cycle", "revolutions_per_minute", "degree"}:
                # pint carries the 2*pi of revolutions itself; radians pass through
                factor = (1 * unit).to("rad/s").magnitude
            elif "hertz" in names:
                # Hz is cycles per second: the 2*pi that pint does not apply (it maps Hz to 1/s)
                factor = (1 * unit).to("Hz").magnitude * 2 * math.pi
            else:
                raise InvalidParameter(field, kind.example + " (a bare 1/s is ambiguous for a rotation)", got)
        except pint.errors.DimensionalityError:  # e.g. "2 rad": an angle, not a rate
            raise InvalidParameter(field, kind.example, got) from None
        return float(factor)

    expected = ureg.get_dimensionality(kind.dimensionality) if kind.dimensionality else ureg.dimensionless.dimensionality
    if unit.dimensionality != expected:
        raise InvalidParameter(field, kind.example, got)
    return float((1 * unit).to(kind.si_unit or ureg.dimensionless).magnitude)


def parse_quantity(field: str, value: object, kind: Kind, *, bare_allowed: bool = False) -> Fraction:
    """Parse one input quantity to an exact SI value.

    Parameters
    ----------
    field
        Name of the parameter, used in error messages.
    value
        A number (int, float, Decimal, Fraction) or a string ``"<number> <unit>"``.
    kind
        The physical kind expected.
    bare_allowed
        Whether a number without unit is accepted, in the SI unit of `kind`.

    Returns
    -------
    Fraction
        The value in SI units, exact for decimal input.

    Raises
    ------
    InvalidParameter
        Wrong type, not finite, wrong dimension, a bare number where a unit is required, more
        than :data:`MAX_SIGNIFICANT_DIGITS` digits, or an exponent that no unit brings back
        into the range of :data:`MAGNITUDES` (the range itself is checked by
        :func:`lyapcheck.paper.params.validate_field`, which knows the field's interval).
    """
    if isinstance(value, bool) or value is None:
        raise InvalidParameter(field, kind.example, value)
    if isinstance(value, int):
        magnitude, unit_text = _exact_decimal(field, Decimal(value), value), ""
    elif isinstance(value, Fraction):
        if max(value.numerator.bit_length(), value.denominator.bit_length()) > _MAX_FRACTION_BITS:
            raise InvalidParameter(field, f"a fraction of at most {_MAX_FRACTION_BITS} bits above and below", value)
        magnitude, unit_text = value, ""
    elif isinstance(value, float):
        if not math.isfinite(value):
            raise InvalidParameter(field, "a finite number", value)
        magnitude, unit_text = _exact_decimal(field, Decimal(repr(value)), value), ""
    elif isinstance(value, Decimal):
        if not value.is_finite():
            raise InvalidParameter(field, "a finite number", value)
        magnitude, unit_text = _exact_decimal(field, value, value), ""
    elif isinstance(value, str):
        match = _NUMBER.match(value)
        if match is None:
            raise InvalidParameter(field, "a finite number" + (f", {kind.example}" if kind.si_unit else ""), value)
        try:
            number = Decimal(match.group(1))
        except (InvalidOperation, ValueError):  # pragma: no cover - the pattern admits decimals only
            raise InvalidParameter(field, "a finite number", value) from None
        magnitude, unit_text = _exact_decimal(field, number, value), match.group(2)
    else:
        raise InvalidParameter(field, kind.example, value)

    if not unit_text:
        if kind in (Kind.DIMENSIONLESS, Kind.RATE) or bare_allowed:
            return magnitude
        raise InvalidParameter(field, kind.example + " with its unit", value)
    return magnitude * _si_factor(field, unit_text, kind, value)


# -- model files: quantities of any dimension, exactly ----------------------------------------------

#: the longest unit text of a model-file quantity ("0.75 mm" has the unit text "mm"), in characters
MAX_UNIT_LENGTH: Final = 60
#: the largest exponent of one unit in a unit text ("1/s^2" has -2); exponents are integers
MAX_UNIT_EXPONENT: Final = 12
#: the significant digits of the values that an error message suggests writing instead
SUGGESTED_DIGITS: Final = 15

#: pi to 50 digits, for the suggestions of messages only (never for a value: see model_unit)
_PI: Final = Decimal("3.1415926535897932384626433832795028841971693993751")
#: the litre's symbol alone, as a word of a unit text ("l/s", "m*l"; not "ml", "L", "litre")
_LITRE_L = re.compile(r"(?<!\w)l(?!\w)")
#: a power whose exponent is itself a power ("m**9**9**9" would make pint compute 9**387420489)
_STACKED_POWER = re.compile(r"(\*\*|\^)[\s()+\-.\d]*(\*\*|\^)")
#: a number of four digits or more in a unit text ("10**99999999": pint computes it before anything)
_LONG_NUMBER = re.compile(r"\d{4,}")
#: each SI base dimension's unit, for messages
_SI_SYMBOL: Final = {"[length]": "m", "[mass]": "kg", "[time]": "s", "[current]": "A", "[temperature]": "K",
                     "[substance]": "mol", "[luminosity]": "cd"}
#: what a model file's unit text may look like, for messages
_UNIT_EXAMPLE: Final = "such as '0.75 mm', '2 1/s^2' or '0.088 mm/s'"


@dataclass(frozen=True)
class Dimension:
    """A physical dimension: pint's base dimensions with their exponents (``[length] / [time] ** 2``).

    Pint gives the dimension of a unit (:func:`model_unit`); the products, quotients and powers of
    an expression's dimensions are computed here, exponents adding up, so that a model whose units
    the memo knows is checked without building pint's registry (0.35 s). Radians are
    dimensionless, as in pint and in SI.
    """

    exponents: tuple[tuple[str, Fraction], ...] = ()

    @classmethod
    def of(cls, items: Mapping[str, object]) -> "Dimension":
        """From ``{base dimension: exponent}`` (pint's ``dimensionality``); zero exponents dropped."""
        pairs = ((str(k), _exponent(v)) for k, v in items.items())
        return cls(tuple(sorted((k, e) for k, e in pairs if e != 0)))

    def __mul__(self, other: "Dimension") -> "Dimension":
        merged = dict(self.exponents)
        for k, e in other.exponents:
            merged[k] = merged.get(k, Fraction(0)) + e
        return Dimension.of(merged)

    def __truediv__(self, other: "Dimension") -> "Dimension":
        return self * other ** -1

    def __pow__(self, k: int | Fraction) -> "Dimension":
        return Dimension.of({name: e * k for name, e in self.exponents})

    @property
    def is_dimensionless(self) -> bool:
        return not self.exponents

    def __str__(self) -> str:
        """As pint writes a dimensionality: ``[length] / [time] ** 2``, ``1 / [time]``, ``dimensionless``."""
        if not self.exponents:
            return "dimensionless"
        up = [_power_text(k, e, " ** ") for k, e in self.exponents if e > 0]
        down = [_power_text(k, -e, " ** ") for k, e in self.exponents if e < 0]
        return " / ".join([" * ".join(up) or "1"] + down)

    def si_unit(self) -> str:
        """The SI unit of this dimension, as a unit text: ``m/s^2``, ``1/s``, ``kg*m/s^2`` ('' when
        dimensionless)."""
        if not self.exponents:
            return ""
        up = [_power_text(_SI_SYMBOL.get(k, k), e, "^") for k, e in self.exponents if e > 0]
        down = [_power_text(_SI_SYMBOL.get(k, k), -e, "^") for k, e in self.exponents if e < 0]
        return "/".join(["*".join(up) or "1"] + down)

    def serialized(self) -> str:
        """``[length]:1,[time]:-2``: the form the memo keeps (:meth:`parse` reads it back)."""
        return ",".join(f"{k}:{e}" for k, e in self.exponents)

    @classmethod
    def parse(cls, text: str) -> "Dimension":
        if not text:
            return cls()
        items = {}
        for part in text.split(","):
            name, _, exponent = part.rpartition(":")
            if not (name.startswith("[") and name.endswith("]")):
                raise ValueError(f"not a base dimension: {name!r}")
            items[name] = Fraction(exponent)
        return cls.of(items)


#: the dimension of a plain number
DIMENSIONLESS: Final = Dimension()


def _exponent(value: object) -> Fraction:
    """An exponent of pint's (an int, a Fraction, or a float for a registry of floats), exactly."""
    if isinstance(value, (int, Fraction, float)) and not isinstance(value, bool):
        return Fraction(value)
    raise TypeError(f"not an exponent: {value!r}")


def _power_text(name: str, exponent: Fraction, power: str) -> str:
    if exponent == 1:
        return name
    return f"{name}{power}{exponent}" if exponent.denominator == 1 else f"{name}{power}({exponent})"


class SIQuantity(NamedTuple):
    """A model file's quantity: its exact SI value, its dimension and the unit text as written ('' for a
    plain number)."""

    value: Fraction
    dimension: Dimension
    unit: str


def parse_si_quantity(field: str, value: object) -> Fraction:
    """A quantity of any dimension, exactly, in SI base units: what a model file's parameters,
    disturbance bounds, equilibrium and domain are read with (and ``--set``, ``--box``, ``--x0``).

    A number without a unit is taken as it is (already SI). A unit is converted to SI base units
    exactly (:func:`model_unit`): ``"0.75 mm"`` is ``3/4000``, ``"0.5 1/min"`` is ``1/120``. ``Hz``,
    units defined through pi (``deg``, ``rpm``, ``turn``, ``cycle``) and the symbol ``l`` are refused
    with a message that says what to write (docs/model-files-units.md).
    """
    return parse_si_with_dimension(field, value).value


def parse_si_with_dimension(field: str, value: object) -> SIQuantity:
    """:func:`parse_si_quantity`, with the quantity's dimension and unit text (for ``[units]``)."""
    if isinstance(value, bool) or value is None:
        raise InvalidParameter(field, f"a number, or a number with a unit {_UNIT_EXAMPLE}", value)
    if isinstance(value, str):
        match = _NUMBER.match(value)
        if match is None:
            raise InvalidParameter(field, f"a finite number, or a number with a unit {_UNIT_EXAMPLE}", value)
        number = _exact_decimal(field, Decimal(match.group(1)), value)
        unit_text = match.group(2)
        dimension = DIMENSIONLESS
        if unit_text:
            factor, dimension = model_unit(field, unit_text, value, number)
            number *= factor
    else:
        number, unit_text, dimension = parse_quantity(field, value, Kind.DIMENSIONLESS), "", DIMENSIONLESS
    if not representable(number):
        raise InvalidParameter(field, MAGNITUDES, value)
    return SIQuantity(number, dimension, unit_text)


def model_unit(field: str, unit_text: str, got: object, number: Fraction = Fraction(1)) -> tuple[Fraction, Dimension]:
    """The exact factor that turns ``unit_text`` into SI base units, and its dimension.

    Exact: pint's definitions are decimal strings (``foot = 0.3048 * meter``, ``minute = 60 * second``),
    read here by a registry whose numbers are :class:`~fractions.Fraction`\\ s
    (:func:`exact_registry`), so ``1/min`` is ``1/60`` and ``furlong`` ``792000/3937``, not their
    binary neighbours. Refused (:class:`~lyapcheck.errors.InvalidParameter`, the message saying what
    to write; ``number`` is the value before the unit, for those suggestions):

    - a unit pint does not know, or cannot read;
    - ``Hz`` (and kHz, ...): in a model file nothing says whether it is cycles per second (1/s) or
      the angular rate 2 pi f (rad/s), which the paper's flags read (``"2.8 Hz"`` is 17.59 rad/s);
    - a unit defined through pi (``deg``, ``rpm``, ``turn``, ``cycle``, ``hbar``): its SI factor is
      irrational, and a certificate is exact for the number the file gives;
    - the symbol ``l`` (the litre, 1/1000 m^3): ``"0.5 l/s"`` reads like ``"0.5 1/s"``;
    - an offset or logarithmic unit (``degC``, ``dB``), or one with a non-integer exponent
      (``m**0.5``), neither of which has an exact rational factor.

    Remembered across runs like :func:`_si_factor` (accepted units only).
    """
    if len(unit_text) > MAX_UNIT_LENGTH:
        raise InvalidParameter(field, f"a number with a unit of at most {MAX_UNIT_LENGTH} characters "
                                      "(MAX_UNIT_LENGTH)", got)
    if _LITRE_L.search(unit_text):
        raise InvalidParameter(field, "a unit without the symbol 'l': it is the litre (1/1000 m^3) and reads like "
                                      "the digit 1; write '1/s' for a rate, 'L' or 'litre' for litres", got)
    if _STACKED_POWER.search(unit_text) or _LONG_NUMBER.search(unit_text):
        raise InvalidParameter(field, f"a unit with integer exponents of at most {MAX_UNIT_EXPONENT} "
                                      "(MAX_UNIT_EXPONENT), each a plain literal", got)
    key = f"SI_EXACT|{unit_text}"
    remembered = _remembered_factors().get(key)
    if remembered is not None:
        try:
            factor_text, _, dimension_text = remembered.partition("|")
            return Fraction(factor_text), Dimension.parse(dimension_text)
        except (ValueError, ZeroDivisionError):  # a damaged memo entry: ask pint
            pass
    factor, dimension = _exact_unit(field, unit_text, got, number)
    _remember_text(key, f"{factor}|{dimension.serialized()}")
    return factor, dimension


@lru_cache(maxsize=1)
def exact_registry() -> "pint.UnitRegistry[Any]":
    """A pint registry whose numbers are :class:`~fractions.Fraction`\\ s: every decimal of pint's
    definitions is read exactly, so every factor built from them is exact (:func:`model_unit`).
    The paper's flags keep :func:`registry` (their factors are stored in certificates as they are)."""
    import pint

    try:
        return pint.UnitRegistry(non_int_type=Fraction, cache_folder=":auto:")
    except OSError:  # pragma: no cover - read-only home: build without the cache
        return pint.UnitRegistry(non_int_type=Fraction)


def _exact_unit(field: str, unit_text: str, got: object, number: Fraction) -> tuple[Fraction, Dimension]:
    """:func:`model_unit`'s work, from pint (nothing remembered)."""
    import pint

    ureg = exact_registry()
    try:
        unit = ureg.parse_units(unit_text)
    except pint.errors.UndefinedUnitError as exc:
        names = exc.unit_names if isinstance(exc.unit_names, (tuple, list)) else (exc.unit_names,)
        unknown = ", ".join(f"'{n}'" for n in names)
        raise InvalidParameter(field, f"a number with a unit pint knows ({unknown} is not one), {_UNIT_EXAMPLE}",
                               got) from None
    except Exception:  # noqa: BLE001 - pint raises a zoo of parser errors on odd strings
        raise InvalidParameter(field, f"a number with a unit pint can read ('{unit_text}' is not one), "
                                      f"{_UNIT_EXAMPLE}", got) from None
    items = {str(k): _exponent(e) for k, e in dict(unit._units).items()}
    if any(e.denominator != 1 or abs(e) > MAX_UNIT_EXPONENT for e in items.values()):
        raise InvalidParameter(field, f"a unit with integer exponents of at most {MAX_UNIT_EXPONENT} "
                                      "(MAX_UNIT_EXPONENT)", got)
    flags: set[str] = set()
    for name in items:
        flags |= _definition_flags(ureg, name)
    if "offset" in flags:
        raise InvalidParameter(field, f"a unit with an SI factor ('{unit_text}' is an offset or logarithmic unit, "
                                      "such as degC or dB, which has none): give the value in SI", got)
    if "inexact" in flags:
        raise InvalidParameter(field, f"a unit with an exact SI factor ('{unit_text}' is defined through a "
                                      "non-integer power): give the value in SI", got)
    try:
        one = (Fraction(1) * unit).to_base_units()
        two = (Fraction(2) * unit).to_base_units()
    except Exception:  # noqa: BLE001 - e.g. a logarithmic unit
        raise InvalidParameter(field, f"a unit with an exact SI factor ('{unit_text}' has none): give the value "
                                      "in SI", got) from None
    factor = one.magnitude
    if not isinstance(factor, (int, Fraction)) or factor == 0 or two.magnitude != 2 * factor:
        raise InvalidParameter(field, f"a unit with an exact SI factor ('{unit_text}' has none): give the value "
                                      "in SI", got)
    factor = Fraction(factor)
    base = _base_text(ureg, dict(one._units))
    if "hertz" in flags:
        per_second = _decimal_text(number * factor)
        angular = _decimal_text(number * factor * Fraction(2 * _PI))
        angular_unit = "rad/s" if base == "1/s" else f"rad*{base}"
        raise InvalidParameter(
            field, f"in {base} or {angular_unit}, not Hz, which is ambiguous in a model file (cycles per second, "
                   f"or the angular rate 2*pi*f that the paper's flags read): write '{per_second} {base}' for cycles "
                   f"per second, or '{angular} {angular_unit}' for the angular rate (2*pi is irrational: write the "
                   "digits you want certified)", got)
    if "pi" in flags:
        value = _decimal_text(number * factor)
        raise InvalidParameter(
            field, f"in SI units, not '{unit_text}', which is defined through pi (irrational, so its SI factor is "
                   f"not exact): write about '{value} {base}' (the digits you write are the ones certified)", got)
    return factor, Dimension.of(dict(unit.dimensionality))


def _definition_flags(ureg: Any, name: str) -> set[str]:
    """What ``name``'s definition rests on, through every unit it is defined by: ``hertz``, ``pi``,
    ``offset`` (an offset or logarithmic converter), ``inexact`` (a non-integer exponent, or a factor
    that pint holds as a float)."""
    flags: set[str] = set()
    seen: set[str] = set()
    stack = [name]
    units = getattr(ureg, "_units", {})
    while stack:
        current = stack.pop()
        if current in seen or current.startswith("["):
            continue
        seen.add(current)
        try:
            candidates = ureg.parse_unit_name(current)
        except Exception:  # noqa: BLE001 - a name pint lists but cannot split: take it whole
            candidates = ()
        base = candidates[0][1] if candidates else current
        if base == "hertz":
            flags.add("hertz")
        if base in ("pi", "π"):
            flags.add("pi")
        definition = units.get(base)
        if definition is None:
            continue
        converter = getattr(definition, "converter", None)
        if converter is not None:
            if not getattr(converter, "is_multiplicative", True) or getattr(converter, "is_logarithmic", False):
                flags.add("offset")
            if isinstance(getattr(converter, "scale", 1), float):
                flags.add("inexact")
        reference = getattr(definition, "reference", None)
        for ref, exponent in (dict(reference) if reference is not None else {}).items():
            if Fraction(exponent).denominator != 1:
                flags.add("inexact")
            stack.append(str(ref))
    return flags


def _base_text(ureg: Any, items: Mapping[str, object]) -> str:
    """SI base units as a unit text with symbols: ``{'meter': 1, 'second': -1}`` is ``m/s``."""
    def symbol(name: str) -> str:
        try:
            return str(ureg.get_symbol(name))
        except Exception:  # noqa: BLE001
            return name

    pairs = [(symbol(k), _exponent(e)) for k, e in items.items()]
    up = [_power_text(k, e, "^") for k, e in pairs if e > 0]
    down = [_power_text(k, -e, "^") for k, e in pairs if e < 0]
    return "/".join(["*".join(up) or "1"] + down) if pairs else ""


def _decimal_text(value: Fraction | Decimal) -> str:
    """``value`` as a decimal of at most :data:`SUGGESTED_DIGITS` significant digits (exactly when it
    has no more), for a message's suggestion."""
    from decimal import localcontext

    with localcontext() as ctx:
        ctx.prec = SUGGESTED_DIGITS
        if isinstance(value, Fraction):
            number = Decimal(value.numerator) / Decimal(value.denominator)
        else:
            number = +value
    text = format(number.normalize(), "f") if abs(number.adjusted()) < 12 else format(number.normalize(), "e")
    return text


def _remember_text(key: str, text: str) -> None:
    """Add one entry to the memo (atomically; a read-only or full memo is left as it is)."""
    import json

    from lyapcheck.fileio import atomic_write

    memo = _remembered_factors()
    path = _factor_memo_path()
    if path is None or len(memo) >= FACTOR_MEMO_SIZE:
        return
    memo[key] = text
    try:
        atomic_write(path, json.dumps(memo, sort_keys=True))
    except OSError:  # pragma: no cover - a read-only home: pint is asked again next time
        pass

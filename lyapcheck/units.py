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
the magnitude; :func:`lyapcheck.params.validate_field` applies it to every field.

Rotation is handled apart from pint's own conversion: pint treats ``Hz`` and ``rad/s`` as the
same dimension (1/s) and would turn ``2.8 Hz`` into ``2.8 rad/s``. A rotation *frequency* in
Hz is cycles per second; the toolkit converts it to an angular velocity with a factor 2*pi,
and refuses a bare ``1/s`` for a rotation because it is ambiguous.
"""

from __future__ import annotations

import math
import re
import sys
from decimal import Decimal, InvalidOperation
from enum import Enum
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

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
    import os
    from importlib import metadata

    try:
        version = metadata.version("pint")
        source = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
    except (OSError, metadata.PackageNotFoundError):  # pragma: no cover - a broken install
        return None
    root = os.environ.get("LYAPCHECK_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "lyapcheck")
    return Path(root) / f"unit-factors-{source}-pint-{version}.json"


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
    import json

    from lyapcheck.fileio import atomic_write

    memo = _remembered_factors()
    path = _factor_memo_path()
    if path is None or len(memo) >= FACTOR_MEMO_SIZE:
        return
    memo[key] = str(factor)
    try:
        atomic_write(path, json.dumps(memo, sort_keys=True))
    except OSError:  # pragma: no cover - a read-only home: pint is asked again next time
        pass


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
        :func:`lyapcheck.params.validate_field`, which knows the field's interval).
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


def _base_factor(field: str, unit_text: str, got: object) -> Fraction:
    """Exact factor that turns ``unit_text`` into SI base units, whatever its dimension (pint's,
    remembered across runs like :func:`_si_factor`'s)."""
    key = f"SI_BASE|{unit_text}"
    remembered = _remembered_factors().get(key)
    if remembered is not None:
        try:
            return Fraction(remembered)
        except (ValueError, ZeroDivisionError):
            pass
    ureg = registry()
    import pint

    expected = "a number, or a number with a unit such as '0.75 mm' or '2.8 Hz'"
    try:
        unit = ureg.Unit(unit_text)
        one, two = (1 * unit).to_base_units(), (2 * unit).to_base_units()
    except Exception:  # noqa: BLE001 - pint raises a zoo of parser errors on odd strings
        raise InvalidParameter(field, expected, got) from None
    factor = float(one.magnitude)
    if not math.isfinite(factor) or factor == 0 or float(two.magnitude) != 2 * factor:
        # an offset unit (degC) has no factor: 2 degC is not twice 1 degC in kelvin
        raise InvalidParameter(field, expected + " (a unit with an offset, such as degC, has no SI factor)", got)
    del pint
    exact = Fraction(Decimal(repr(factor)))
    _remember_factor(key, exact)
    return exact


def parse_si_quantity(field: str, value: object) -> Fraction:
    """A quantity of any dimension, exactly, in SI base units: what a model file's parameters,
    disturbance bounds, equilibrium and domain are read with.

    A number without a unit is taken as it is (already SI). A unit is converted to SI base units
    by pint: ``"0.75 mm"`` is ``3/4000``, ``"0.088 mm/s"`` is ``11/125000``. A model file does not
    say which of its parameters is a rotation, so ``Hz`` stays cycles per second (``"2.8 Hz"`` is
    2.8 1/s) while ``rad/s`` and ``rpm`` are angular velocities (``"60 rpm"`` is 2 pi rad/s, a
    radian being dimensionless): give an angular velocity in rad/s.
    """
    if isinstance(value, bool) or value is None:
        raise InvalidParameter(field, "a number, or a number with a unit such as '0.75 mm'", value)
    if isinstance(value, str):
        match = _NUMBER.match(value)
        if match is None:
            raise InvalidParameter(field, "a finite number, or a number with a unit such as '0.75 mm'", value)
        number = _exact_decimal(field, Decimal(match.group(1)), value)
        unit_text = match.group(2)
        if unit_text:
            number *= _base_factor(field, unit_text, value)
    else:
        number = parse_quantity(field, value, Kind.DIMENSIONLESS)
    if not representable(number):
        raise InvalidParameter(field, MAGNITUDES, value)
    return number

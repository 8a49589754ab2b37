"""Quantities with units: parsing strings such as ``"0.75 mm"`` into exact SI values.

Everything inside the toolkit is SI. Magnitudes are parsed as exact decimals and kept as
:class:`fractions.Fraction`, so that exact certificate checks see the number the user typed,
not its binary floating-point neighbour.

Rotation is handled apart from pint's own conversion: pint treats ``Hz`` and ``rad/s`` as the
same dimension (1/s) and would turn ``2.8 Hz`` into ``2.8 rad/s``. A rotation *frequency* in
Hz is cycles per second; the toolkit converts it to an angular velocity with a factor 2*pi,
and refuses a bare ``1/s`` for a rotation because it is ambiguous.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal, InvalidOperation
from enum import Enum
from fractions import Fraction
from functools import lru_cache
from typing import TYPE_CHECKING, Any

from lyapcheck.errors import InvalidParameter

if TYPE_CHECKING:  # pragma: no cover
    import pint

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


def _exact_decimal(text: str) -> Fraction:
    try:
        return Fraction(Decimal(text))
    except (InvalidOperation, ValueError) as exc:  # pragma: no cover - regex guards this
        raise ValueError(text) from exc


def _si_factor(field: str, unit_text: str, kind: Kind, got: object) -> Fraction:
    """Exact factor that turns one `unit_text` into SI for `kind`."""
    ureg = registry()
    import pint

    try:
        unit = ureg.Unit(unit_text) if unit_text else ureg.dimensionless
    except (pint.errors.UndefinedUnitError, AttributeError, ValueError, TypeError, SyntaxError, AssertionError):
        raise InvalidParameter(field, kind.example, got) from None
    except Exception:  # pint raises a zoo of parser errors on odd strings
        raise InvalidParameter(field, kind.example, got) from None

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
        return Fraction(factor)

    expected = ureg.get_dimensionality(kind.dimensionality) if kind.dimensionality else ureg.dimensionless.dimensionality
    if unit.dimensionality != expected:
        raise InvalidParameter(field, kind.example, got)
    factor = (1 * unit).to(kind.si_unit or ureg.dimensionless).magnitude
    # pint returns floats; the prefixes and units we accept have short exact decimal factors
    # (1e-3, 1e-6, ...), and repr() gives that shortest decimal back.
    return Fraction(Decimal(repr(float(factor))))


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
        Wrong type, not finite, wrong dimension, or a bare number where a unit is required.
    """
    if isinstance(value, bool) or value is None:
        raise InvalidParameter(field, kind.example, value)
    if isinstance(value, (int, Fraction)):
        magnitude, unit_text = Fraction(value), ""
    elif isinstance(value, float):
        if not math.isfinite(value):
            raise InvalidParameter(field, "a finite number", value)
        magnitude, unit_text = Fraction(Decimal(repr(value))), ""
    elif isinstance(value, Decimal):
        if not value.is_finite():
            raise InvalidParameter(field, "a finite number", value)
        magnitude, unit_text = Fraction(value), ""
    elif isinstance(value, str):
        match = _NUMBER.match(value)
        if match is None:
            raise InvalidParameter(field, "a finite number" + (f", {kind.example}" if kind.si_unit else ""), value)
        magnitude, unit_text = _exact_decimal(match.group(1)), match.group(2)
    else:
        raise InvalidParameter(field, kind.example, value)

    if not unit_text:
        if kind in (Kind.DIMENSIONLESS, Kind.RATE) or bare_allowed:
            return magnitude
        raise InvalidParameter(field, kind.example + " with its unit", value)
    return magnitude * _si_factor(field, unit_text, kind, value)

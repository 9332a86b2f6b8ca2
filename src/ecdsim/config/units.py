"""Quantities written as strings ("1.3e-4 N*m*s/rad", "90 deg", "25 degC"), parsed with pint.

This is the only module that imports pint; it does so lazily and once, and only for a
unit outside :data:`LEAN_FACTORS`: the common units of configs and bench logs (N*m, mN*m,
deg, rpm, degC, / K, %, g, mm, ...) are converted by a table of pint's own conversion
factors, so that ``ecdsim deploy`` does not pay pint's import and registry (about 0.2 s on
a quiet machine, more with dask installed, which pint imports; scipy too). Each physical
kind of quantity has a :class:`Kind` naming its SI unit and an example, so that every error
message can say what was expected.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction
from functools import cache
from typing import Any

# One way to split a digit run (``\d+(?:\.\d*)?``, not ``\d+\.?\d*``), so that a failed
# match of a long number is linear, not quadratic, in its length.
NUMBER_PATTERN = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
_NUMBER = re.compile(rf"^\s*({NUMBER_PATTERN})\s*(.*?)\s*$")
# The unit grammar: names joined by '*', '/' or spaces, each with an optional integer
# power ('^2', '**-1'); a number only as the magnitude (and a leading '1/' for a
# reciprocal). Anything else is refused before pint sees it: pint *evaluates* its unit
# strings, so 'N*m/0' divided by zero and 'deg**999999' overflowed.
_UNIT_NAME = r"(?:[A-Za-z_\u00b0\u00b5\u03bc\u2126][A-Za-z0-9_\u00b0\u00b5\u03bc\u2126]*|%)"
_UNIT_POWER = r"(?:\s*(?:\^|\*\*)\s*[-+]?\d{1,2})?"
_UNIT_FACTOR = rf"{_UNIT_NAME}{_UNIT_POWER}"
_UNIT = re.compile(rf"^(?:1\s*)?(?:/\s*)?{_UNIT_FACTOR}(?:\s*(?:\*|/|\s)\s*{_UNIT_FACTOR})*$")
# The longest quantity string read, and the most of a bad value an error line quotes.
MAX_QUANTITY_LENGTH = 200
MAX_QUOTED = 80
# Offset units are ambiguous inside compound units; in a rate ("per degC") they mean a
# temperature difference, which pint spells delta_degC.
# pint treats the radian as dimensionless, so it would read "30 Hz" as 30 rad/s (not
# 2*pi*30) and "50 %" as 0.5 rad. For angles and angular speeds such units are refused.
_NOT_ANGULAR = re.compile(r"(?<![A-Za-z_])(Hz|kHz|hertz|percent|ppm|%)(?![A-Za-z_])")
_OFFSET_UNIT = re.compile(r"(?<![A-Za-z_])(degC|degF|celsius|fahrenheit)(?![A-Za-z_])")


class QuantityError(ValueError):
    """A value that is not a quantity of the expected kind; the message says why."""


def quoted(value: object, limit: int = MAX_QUOTED) -> str:
    """``repr(value)``, cut to about ``limit`` characters for an error line.

    An integer too long for Python to write out (over ``sys.get_int_max_str_digits()``
    digits, 4,300 by default: ``repr`` raises ValueError) is described by its size.

    >>> quoted(10**5000)
    'an integer of 5001 digits'
    """
    if isinstance(value, int) and value.bit_length() > _BITS_WRITTEN_OUT:
        return f"an integer of {integer_digits(value)} digits"
    text = repr(value)
    if len(text) <= limit:
        return text
    return f"{text[: limit - 3]}... ({len(str(value))} characters)"


# Integers up to this many bits are written out in error lines (about 1,200 digits, well
# inside Python's 4,300-digit limit on converting integers to text).
_BITS_WRITTEN_OUT = 4000


def integer_digits(value: int) -> int:
    """The number of decimal digits of ``value`` (without writing it out: Python refuses
    to convert integers of more than 4,300 digits to text).

    >>> integer_digits(10**5000), integer_digits(-999), integer_digits(0)
    (5001, 3, 1)
    """
    magnitude = abs(value)
    if magnitude == 0:
        return 1
    digits = int(magnitude.bit_length() * 0.30102999566398120)  # log10(2)
    # The estimate is at most one short: correct it with one exact comparison.
    return digits + 1 if magnitude >= 10**digits else digits


def check_unit_grammar(unit_text: str) -> str | None:
    """Why ``unit_text`` is not a unit expression, or None if it is one.

    Accepted: unit names joined by ``*``, ``/`` or spaces, each with an optional integer
    power of at most two digits (``kg*m^2``, ``N*m*s/rad``, ``mm**2/s``, ``/ K``,
    ``1/K``). Refused: numbers inside the unit, parentheses, any other operator.

    >>> check_unit_grammar("N*m*s/rad") is None
    True
    >>> check_unit_grammar("N*m/0")
    'is not a unit expression (unit names joined by *, / or spaces, integer powers)'
    """
    if _UNIT.match(unit_text.strip()) is None:
        return "is not a unit expression (unit names joined by *, / or spaces, integer powers)"
    return None


ABSOLUTE_ZERO_C = -273.15
"""Absolute zero [degC]; temperatures at or below it are refused."""


# Pint's conversion factor of (unit, the kind's SI unit), keyed by the unit as
# :func:`lean_key` writes it: for these, pint's answer is ``number * factor``, bit for bit,
# which tests/test_units_lean.py checks against pint itself (random magnitudes, every
# entry). Anything else, wrong dimensions and offset conversions (K, degF to degC)
# included, goes to pint, whose messages stay the only ones.
LEAN_FACTORS: dict[tuple[str, str], float] = {
    ("N*m", "N*m"): 1.0,
    ("mN*m", "N*m"): 0.001,
    ("uN*m", "N*m"): 1e-06,
    ("N*mm", "N*m"): 0.001,
    ("mN*mm", "N*m"): 1e-06,
    ("kN*m", "N*m"): 1000.0,
    ("N*cm", "N*m"): 0.01,
    ("N*m*s/rad", "N*m*s/rad"): 1.0,
    ("mN*m*s/rad", "N*m*s/rad"): 0.001,
    ("uN*m*s/rad", "N*m*s/rad"): 1e-06,
    ("N*mm*s/rad", "N*m*s/rad"): 0.001,
    ("mN*mm*s/rad", "N*m*s/rad"): 1e-06,
    ("N*m*s", "N*m*s/rad"): 1.0,
    ("mN*m*s", "N*m*s/rad"): 0.001,
    ("rad", "rad"): 1.0,
    ("deg", "rad"): 0.017453292519943295,
    ("degree", "rad"): 0.017453292519943295,
    ("mrad", "rad"): 0.001,
    ("turn", "rad"): 6.283185307179586,
    ("rad/s", "rad/s"): 1.0,
    ("deg/s", "rad/s"): 0.017453292519943295,
    ("rpm", "rad/s"): 0.10471975511965977,
    ("turn/s", "rad/s"): 6.283185307179586,
    ("rad/min", "rad/s"): 0.016666666666666666,
    ("degC", "degC"): 1.0,
    ("/K", "1/K"): 1.0,
    ("1/K", "1/K"): 1.0,
    ("/degC", "1/K"): 1.0,
    ("1/degC", "1/K"): 1.0,
    ("%/K", "1/K"): 0.01,
    ("%/degC", "1/K"): 0.01,
    ("ppm/K", "1/K"): 1e-06,
    ("N*m/K", "N*m/K"): 1.0,
    ("mN*m/K", "N*m/K"): 0.001,
    ("N*m/degC", "N*m/K"): 1.0,
    ("mN*m/degC", "N*m/K"): 0.001,
    ("uN*m/K", "N*m/K"): 1e-06,
    ("%", ""): 0.01,
    ("percent", ""): 0.01,
    ("ppm", ""): 1e-06,
    ("s", "s"): 1.0,
    ("ms", "s"): 0.001,
    ("min", "s"): 60.0,
    ("h", "s"): 3600.0,
    ("us", "s"): 1e-06,
    ("kg", "kg"): 1.0,
    ("g", "kg"): 0.001,
    ("mg", "kg"): 1e-06,
    ("m", "m"): 1.0,
    ("mm", "m"): 0.001,
    ("cm", "m"): 0.01,
    ("um", "m"): 1e-06,
    ("kg*m^2", "kg*m^2"): 1.0,
    ("g*cm^2", "kg*m^2"): 1.0000000000000001e-07,
    ("kg*mm^2", "kg*m^2"): 1e-06,
    ("g*mm^2", "kg*m^2"): 1e-09,
    ("kg*cm^2", "kg*m^2"): 0.0001,
    ("g*m^2", "kg*m^2"): 0.001,
    ("Pa*s", "Pa*s"): 1.0,
    ("mPa*s", "Pa*s"): 0.001,
    ("cP", "Pa*s"): 0.001,
    ("P", "Pa*s"): 0.1,
    ("m^2/s", "m^2/s"): 1.0,
    ("mm^2/s", "m^2/s"): 1e-06,
    ("cSt", "m^2/s"): 1.0000000000000002e-06,
    ("St", "m^2/s"): 0.0001,
    ("J/K", "J/K"): 1.0,
    ("mJ/K", "J/K"): 0.001,
    ("kJ/K", "J/K"): 1000.0,
    ("J/degC", "J/K"): 1.0,
    ("K/W", "K/W"): 1.0,
    ("degC/W", "K/W"): 1.0,
}
_LEAN_OPERATOR = re.compile(r"\s*(\*\*|[*/^])\s*")
_LEAN_SPACE = re.compile(r"\s+")


def lean_key(unit_text: str) -> str:
    """``unit_text`` written one way, as pint reads it: ``N m`` and ``N * m`` are ``N*m``,
    ``m**2`` is ``m^2``, ``1 / K`` is ``1/K``.

    >>> lean_key("mN * m ") , lean_key("kg m**2"), lean_key("/ K")
    ('mN*m', 'kg*m^2', '/K')
    """
    text = _LEAN_OPERATOR.sub(lambda m: "^" if m.group(1) == "**" else m.group(1), unit_text)
    return _LEAN_SPACE.sub("*", text.strip())


@cache
def _registry() -> Any:
    import pint

    return pint.UnitRegistry()


@dataclass(frozen=True)
class Kind:
    """A physical kind of quantity: how to read it and what to say when it is wrong.

    Attributes
    ----------
    name : readable name ("torque")
    unit : the SI unit ecdsim uses inside ("N*m")
    example : a valid example string ("3.73 N*m")
    offset : True for absolute temperatures (converted to degC, not SI kelvin)
    angular : True where the radian is part of the unit (angles, angular speeds), so
        that dimensionless look-alikes (Hz, %) are refused rather than misread
    """

    name: str
    unit: str
    example: str
    offset: bool = False
    angular: bool = False

    @property
    def expected(self) -> str:
        """Phrase for error messages."""
        article = "an" if self.name[0] in "aeiou" else "a"
        if self.unit == "":
            return f"expected {article} {self.name} (a plain number, e.g. {self.example})"
        return (
            f"expected {article} {self.name} in {self.unit} or compatible units, "
            f"e.g. '{self.example}'"
        )

    def parse(self, value: object) -> float:
        """The value in this kind's SI unit (degC for temperatures); QuantityError if not."""
        if isinstance(value, bool):
            raise QuantityError(f"{quoted(value)} is not a number; {self.expected}")
        if isinstance(value, int | float):
            number = _as_float(value, self)
            if self.unit != "":
                raise QuantityError(f"{quoted(value)} has no unit; {self.expected}")
            return _in_range(_finite(number, value, self), value, self)
        if not isinstance(value, str):
            raise QuantityError(f"{quoted(value)} is not a quantity; {self.expected}")
        if len(value) > MAX_QUANTITY_LENGTH:
            raise QuantityError(
                f"{quoted(value)} is too long for a quantity (at most {MAX_QUANTITY_LENGTH} "
                f"characters); {self.expected}"
            )
        match = _NUMBER.match(value)
        if match is None:
            raise QuantityError(
                f"{quoted(value)} does not start with a finite number; {self.expected}"
            )
        number = _finite(float(match.group(1)), value, self)
        unit_text = match.group(2)
        if self.unit == "":
            if unit_text:
                return _convert(number, unit_text, value, self)
            return _in_range(number, value, self)
        if not unit_text:
            raise QuantityError(f"{quoted(value)} has no unit; {self.expected}")
        if self.angular and _NOT_ANGULAR.search(unit_text):
            raise QuantityError(
                f"{quoted(value)} is ambiguous: pint reads Hz and % as plain numbers, not angles; "
                f"{self.expected} (for a frequency write turn/s or rpm)"
            )
        return _convert(number, unit_text, value, self)


# The magnitudes ecdsim accepts, in SI units (0 aside). Every physical input of a
# deployment lies far inside (the smallest, a rotor inertia, ~1e-9 kg*m^2; the largest, a
# test time, ~1e5 s); outside, products such as BT_T * N**2 overflow or underflow to
# meaningless numbers deep inside NumPy, so such values are refused here, by name.
MAGNITUDE_RANGE = (1e-30, 1e30)


def magnitude_problem(value: float) -> str | None:
    """Why ``value`` [SI] is outside :data:`MAGNITUDE_RANGE`, or None (0 is accepted).

    >>> magnitude_problem(1e308)
    'is outside the magnitudes ecdsim accepts (1e-30 to 1e+30 in SI units, or 0)'
    >>> magnitude_problem(0.0) is None
    True
    """
    low, high = MAGNITUDE_RANGE
    if value == 0.0 or low <= abs(value) <= high:
        return None
    return f"is outside the magnitudes ecdsim accepts ({low:g} to {high:g} in SI units, or 0)"


def _as_float(value: int | float, kind: Kind) -> float:
    """``float(value)``; a QuantityError naming the range for an integer beyond float64
    (``10**400``: Python raises OverflowError)."""
    try:
        return float(value)
    except OverflowError:
        low, high = MAGNITUDE_RANGE
        raise QuantityError(
            f"{quoted(value)} is outside the magnitudes ecdsim accepts ({low:g} to {high:g} "
            f"in SI units, or 0); {kind.expected}"
        ) from None


def _finite(number: float, raw: object, kind: Kind) -> float:
    if not math.isfinite(number):
        raise QuantityError(f"{quoted(raw)} is not finite; {kind.expected}")
    return number


def _in_range(number: float, raw: object, kind: Kind) -> float:
    problem = magnitude_problem(number)
    if problem is not None:
        raise QuantityError(f"{quoted(raw)} {problem}; {kind.expected}")
    return number


# Absolute temperature units, converted exactly: degC = x * scale + offset with rational
# scale and offset, from the decimal number as written, rounded once. pint goes through
# kelvin in floats, which leaves rounding noise ('-40 degF' -> -39.99999999999997 degC,
# '77 degF' -> 25.000000000000057); these give -40 and 25, as a person computes them.
# Keyed by the unit as written and as pint names it (str(quantity.units)).
_NINTHS = Fraction(5, 9)
_KELVIN_OFFSET = Fraction("-273.15")
_ABSOLUTE_TEMPERATURE: dict[str, tuple[Fraction, Fraction]] = {
    **dict.fromkeys(("degC", "celsius", "degree_Celsius"), (Fraction(1), Fraction(0))),
    **dict.fromkeys(("K", "kelvin"), (Fraction(1), _KELVIN_OFFSET)),
    **dict.fromkeys(
        ("degF", "fahrenheit", "degree_Fahrenheit"), (_NINTHS, Fraction(-32) * _NINTHS)
    ),
    **dict.fromkeys(("degR", "rankine", "degree_Rankine"), (_NINTHS, _KELVIN_OFFSET)),
}
# Exact decimal arithmetic for numbers written with at most this exponent (every
# temperature); a longer one ('1e-999...') takes the float's own value, not 10**huge.
_EXACT_EXPONENT = 400


def absolute_temperature(number: float, number_text: str, unit_text: str) -> float | None:
    """``number_text`` (parsed as ``number``) in ``unit_text`` as degC, exactly rounded,
    for the absolute temperature units of :data:`_ABSOLUTE_TEMPERATURE`; None for others.

    >>> absolute_temperature(-40.0, "-40", "degF"), absolute_temperature(77.0, "77", "degF")
    (-40.0, 25.0)
    >>> absolute_temperature(298.15, "298.15", "K"), absolute_temperature(1.0, "1", "mK")
    (25.0, None)
    """
    found = _ABSOLUTE_TEMPERATURE.get(unit_text.strip())
    if found is None:
        return None
    scale, offset = found
    decimal = Decimal(number_text)
    exact = Fraction(decimal) if abs(decimal.adjusted()) <= _EXACT_EXPONENT else Fraction(number)
    return float(exact * scale + offset)


def _convert(number: float, unit_text: str, raw: str, kind: Kind) -> float:
    bad_grammar = check_unit_grammar(unit_text)
    if bad_grammar is not None:
        raise QuantityError(f"{quoted(raw)}: {quoted(unit_text)} {bad_grammar}; {kind.expected}")
    if kind.offset:
        written = _NUMBER.match(raw)
        exact = (
            None if written is None else absolute_temperature(number, written.group(1), unit_text)
        )
        if exact is not None:
            return _in_range(_finite(exact, raw, kind), raw, kind)
    factor = LEAN_FACTORS.get((lean_key(unit_text), kind.unit))
    if factor is not None:
        return _in_range(_finite(number * factor, raw, kind), raw, kind)
    return _convert_with_pint(number, unit_text, raw, kind)


def _convert_with_pint(number: float, unit_text: str, raw: str, kind: Kind) -> float:
    """The conversion by pint, for any unit (``LEAN_FACTORS`` are checked against it)."""
    import pint

    registry = _registry()
    if unit_text.startswith("/"):
        unit_text = "1 " + unit_text
    if not kind.offset:
        unit_text = _OFFSET_UNIT.sub(r"delta_\1", unit_text)
    try:
        quantity = registry.Quantity(number, unit_text)
        if kind.offset:
            result = float(quantity.to("degC").magnitude)
        else:
            result = float(quantity.to(kind.unit or "dimensionless").magnitude)
    except pint.errors.DimensionalityError:
        raise QuantityError(f"{quoted(raw)} has the wrong dimension; {kind.expected}") from None
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, AttributeError):
        raise QuantityError(
            f"{quoted(raw)} has a unit pint does not know; {kind.expected}"
        ) from None
    except (pint.errors.PintError, ValueError, TypeError, ArithmeticError) as exc:
        raise QuantityError(
            f"{quoted(raw)} could not be read ({quoted(str(exc))}); {kind.expected}"
        ) from None
    return _in_range(_finite(result, raw, kind), raw, kind)


TORQUE = Kind("torque", "N*m", "3.73 N*m")
DAMPING = Kind("damping rate", "N*m*s/rad", "1.3e-4 N*m*s/rad")
ANGLE = Kind("angle", "rad", "1.57 rad", angular=True)
SPEED = Kind("angular speed", "rad/s", "2000 rad/s", angular=True)
TEMPERATURE = Kind("temperature", "degC", "25 degC", offset=True)
PER_KELVIN = Kind("fractional change per kelvin", "1/K", "-0.004 / K")
TORQUE_PER_KELVIN = Kind("torque change per kelvin", "N*m/K", "-0.0044 N*m/K")
NUMBER = Kind("dimensionless number", "", "380")
# Sizing and fluid-damper quantities (docs/sizing.md).
TIME = Kind("time", "s", "30 s")
MASS = Kind("mass", "kg", "0.185 kg")
LENGTH = Kind("length", "m", "63 mm")
INERTIA = Kind("moment of inertia", "kg*m^2", "2e-7 kg*m^2")
DYNAMIC_VISCOSITY = Kind("dynamic viscosity", "Pa*s", "9.7 Pa*s")
KINEMATIC_VISCOSITY = Kind("kinematic viscosity", "m^2/s", "10000 mm^2/s")
# Dynamics quantities (docs/dynamics.md); INERTIA and TIME above serve them too.
HEAT_CAPACITY = Kind("heat capacity", "J/K", "90 J/K")
THERMAL_RESISTANCE = Kind("thermal resistance", "K/W", "2 K/W")
TORSIONAL_STIFFNESS = Kind("torsional stiffness", "N*m/rad", "2e4 N*m/rad")


def temperature_problem(celsius: float) -> str | None:
    """Why an absolute temperature [degC] is not physical, or None: at or below 0 K."""
    return None if celsius > ABSOLUTE_ZERO_C else "is below absolute zero"


def parse_temperature(value: object) -> float:
    """An absolute temperature [degC] from a quantity ("25 degC", "-40 degF", "300 K").

    The one reader of absolute temperatures at the edge: the config's temperature fields
    (through :func:`temperature_problem`), every command-line temperature option and so
    the explorer's API, which reads configs. Raises :class:`QuantityError` naming the
    value and the expected unit if it is not a temperature or lies at or below absolute
    zero.
    """
    number = TEMPERATURE.parse(value)
    problem = temperature_problem(number)
    if problem:
        raise QuantityError(f"{quoted(value)} {problem}; {TEMPERATURE.expected}")
    return number

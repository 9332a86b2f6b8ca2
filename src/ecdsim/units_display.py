"""Display units: each kind of result in SI or US customary units, for tables, plots, reports.

Results are computed and stored in SI (temperatures in degC); JSON keys stay SI and name
their unit (``temperature_C``, ``friction_Nm``). Only what a person reads is converted:
this module maps each kind of quantity to its display unit in a unit system (``"si"`` or
``"us"``), converts numbers to it and formats them to significant digits. The factors are
derived here from the exact definitions of the US customary units (no pint at display
time: only the standard library is imported, so the CLI starts fast):

- 1 in = 0.0254 m, 1 ft = 12 in, 1 lbm = 0.45359237 kg (international yard and pound, 1959)
- 1 lbf = 1 lbm * 9.80665 m/s^2 = 4.4482216152605 N
- degF = degC * 9/5 + 32; a difference of 1 degF is 5/9 K
- 1 Btu (International Table) = 1055.05585262 J

US display units are what US mechanism engineers write on drawings and in data sheets:
torque in lbf*in, damping rate referred to a shaft in in*lbf*s/rad, moment of inertia in
lbm*in^2 (the unit of motor and mechanism catalogues), energy in in*lbf, mass in lbm,
length in in, temperature in degF. Angles (rad), angular speeds (rad/s) and times (s) are
the same in both systems: the damping rate is per radian, so torque = rate * speed holds
in the displayed numbers too.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    FloatArray = NDArray[np.float64]

UnitSystem = Literal["si", "us"]
UNIT_SYSTEMS: tuple[UnitSystem, ...] = ("si", "us")
DEFAULT_SYSTEM: UnitSystem = "si"

# Exact definitions (SI per US customary unit).
INCH_M = 0.0254
FOOT_M = 12.0 * INCH_M
POUND_MASS_KG = 0.45359237
STANDARD_GRAVITY = 9.80665
POUND_FORCE_N = POUND_MASS_KG * STANDARD_GRAVITY  # 4.4482216152605 N
BTU_J = 1055.05585262
DEGF_PER_K = 9.0 / 5.0
DEGF_OFFSET = 32.0

_LBF_IN = POUND_FORCE_N * INCH_M  # N*m per lbf*in


@dataclass(frozen=True)
class DisplayUnit:
    """A display unit: ``shown = si_value * scale + offset``.

    Attributes
    ----------
    label : the unit as printed ("lbf*in", "degF")
    scale : display units per SI unit
    offset : added after scaling (32 for degF from degC; 0 otherwise)
    """

    label: str
    scale: float = 1.0
    offset: float = 0.0

    def convert(self, si_value: float) -> float:
        """The SI value (degC for temperatures) in this unit."""
        return si_value * self.scale + self.offset

    def to_si(self, shown: float) -> float:
        """Back from this unit to SI (degC for temperatures)."""
        return (shown - self.offset) / self.scale

    def to_dict(self) -> dict[str, Any]:
        """``{"unit": label, "scale": ..., "offset": ...}`` for JSON (the explorer's API)."""
        return {"unit": self.label, "scale": self.scale, "offset": self.offset}


def _same(label: str) -> dict[UnitSystem, DisplayUnit]:
    unit = DisplayUnit(label)
    return {"si": unit, "us": unit}


# Each kind of result quantity: its display unit per system. SI labels are ecdsim's own.
UNITS: dict[str, dict[UnitSystem, DisplayUnit]] = {
    "temperature": {
        "si": DisplayUnit("degC"),
        "us": DisplayUnit("degF", DEGF_PER_K, DEGF_OFFSET),
    },
    "temperature_difference": {"si": DisplayUnit("K"), "us": DisplayUnit("degF", DEGF_PER_K)},
    "torque": {"si": DisplayUnit("N*m"), "us": DisplayUnit("lbf*in", 1.0 / _LBF_IN)},
    "damping_rate": {
        "si": DisplayUnit("N*m*s/rad"),
        "us": DisplayUnit("in*lbf*s/rad", 1.0 / _LBF_IN),
    },
    "torque_per_kelvin": {
        "si": DisplayUnit("N*m/K"),
        "us": DisplayUnit("lbf*in/degF", 1.0 / (_LBF_IN * DEGF_PER_K)),
    },
    "per_kelvin": {"si": DisplayUnit("1/K"), "us": DisplayUnit("1/degF", 1.0 / DEGF_PER_K)},
    "energy": {"si": DisplayUnit("J"), "us": DisplayUnit("in*lbf", 1.0 / _LBF_IN)},
    "mass": {"si": DisplayUnit("kg"), "us": DisplayUnit("lbm", 1.0 / POUND_MASS_KG)},
    "length": {"si": DisplayUnit("m"), "us": DisplayUnit("in", 1.0 / INCH_M)},
    "linear_speed": {"si": DisplayUnit("m/s"), "us": DisplayUnit("in/s", 1.0 / INCH_M)},
    "inertia": {
        "si": DisplayUnit("kg*m^2"),
        "us": DisplayUnit("lbm*in^2", 1.0 / (POUND_MASS_KG * INCH_M**2)),
    },
    "heat_capacity": {
        "si": DisplayUnit("J/K"),
        "us": DisplayUnit("Btu/degF", 1.0 / (BTU_J * DEGF_PER_K)),
    },
    "angle": _same("rad"),
    "angular_speed": _same("rad/s"),
    "time": _same("s"),
    "time_ms": _same("ms"),
    "power": _same("W"),
    "number": _same(""),
}

# JSON key suffixes (the SI unit in the key's name) and the kind they denote. Longest
# first: "_rad_s" must win over "_s", "_Nm_per_K" over "_per_K".
KEY_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_Nms_per_rad", "damping_rate"),
    ("_Nm_per_K", "torque_per_kelvin"),
    ("_J_per_K", "heat_capacity"),
    ("_kg_m2", "inertia"),
    ("_kgm2", "inertia"),
    ("_per_K", "per_kelvin"),
    ("_rad_s", "angular_speed"),
    ("_m_s", "linear_speed"),
    ("_Nm", "torque"),
    ("_rad", "angle"),
    ("_ms", "time_ms"),
    ("_kg", "mass"),
    ("_C", "temperature"),
    ("_K", "temperature_difference"),
    ("_J", "energy"),
    ("_W", "power"),
    ("_m", "length"),
    ("_s", "time"),
)


# The kind of each SI unit a config field is read in (ecdsim.config.units.Kind.unit).
KIND_BY_SI_UNIT: dict[str, str] = {
    "degC": "temperature",
    "N*m": "torque",
    "N*m*s/rad": "damping_rate",
    "N*m/K": "torque_per_kelvin",
    "1/K": "per_kelvin",
    "kg*m^2": "inertia",
    "kg": "mass",
    "m": "length",
    "J/K": "heat_capacity",
    "rad": "angle",
    "rad/s": "angular_speed",
    "s": "time",
}


class UnitSystemError(ValueError):
    """A unit system that is not one of :data:`UNIT_SYSTEMS`; the message says so."""


def check_system(value: object, where: str = "units") -> UnitSystem:
    """``value`` as a unit system; :class:`UnitSystemError` naming ``where`` if it is not one.

    >>> check_system("us")
    'us'
    >>> check_system("metric", "--units")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ecdsim.units_display.UnitSystemError: --units: 'metric' is not a unit system; expected ...
    """
    if value == "si":
        return "si"
    if value == "us":
        return "us"
    text = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
    raise UnitSystemError(f"{where}: {text} is not a unit system; expected 'si' or 'us'")


def unit(kind: str, system: UnitSystem) -> DisplayUnit:
    """The display unit of ``kind`` ("torque", "temperature", ...) in ``system``."""
    return UNITS[kind][system]


def label(kind: str, system: UnitSystem) -> str:
    """The unit label of ``kind`` in ``system`` ("lbf*in")."""
    return UNITS[kind][system].label


def convert(value: float, kind: str, system: UnitSystem) -> float:
    """An SI value (degC for temperatures) of ``kind`` in ``system``'s display unit."""
    return UNITS[kind][system].convert(value)


def kind_of_key(key: str) -> str | None:
    """The kind of quantity a JSON key holds, from its SI-unit suffix; None if it has none.

    >>> kind_of_key("start_speed_rad_s"), kind_of_key("temperature_C"), kind_of_key("relative")
    ('angular_speed', 'temperature', None)
    """
    for suffix, kind in KEY_SUFFIXES:
        if key.endswith(suffix):
            return kind
    return None


def key_units(document: object, system: UnitSystem) -> dict[str, str]:
    """Every unit-bearing key anywhere in ``document`` and its display unit label.

    >>> key_units({"cases": [{"friction_Nm": 1.0, "stalled": False}]}, "us")
    {'friction_Nm': 'lbf*in'}
    """
    found: dict[str, str] = {}
    stack = [document]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            for key, value in item.items():
                kind = kind_of_key(str(key))
                if kind is not None:
                    found[str(key)] = label(kind, system)
                stack.append(value)
        elif isinstance(item, list):
            stack.extend(item)
    return dict(sorted(found.items()))


def describe(system: UnitSystem) -> dict[str, dict[str, Any]]:
    """Every kind's display unit in ``system`` as JSON: ``{kind: {unit, scale, offset}}``."""
    return {kind: units[system].to_dict() for kind, units in UNITS.items()}


def format_value(value: float | None, digits: int = 4, none: str = "-") -> str:
    """A number to ``digits`` significant figures, without float noise.

    -39.99999999999997 prints as "-40", 77.00000000000001 as "77"; None prints ``none``.

    >>> format_value(-39.99999999999997), format_value(0.00016379999999999997, 6)
    ('-40', '0.0001638')
    """
    if value is None:
        return none
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    text = f"{value:.{digits}g}"
    return "0" if text == "-0" else text


def format_quantity(
    value: float | None, kind: str, system: UnitSystem, digits: int = 4, none: str = "-"
) -> str:
    """An SI value converted to ``system`` and formatted with its unit ("77 degF")."""
    if value is None:
        return none
    shown = format_value(convert(value, kind, system), digits)
    unit_label = label(kind, system)
    return f"{shown} {unit_label}" if unit_label else shown


def header(name: str, kind: str, system: UnitSystem) -> str:
    """A table header or axis label: ``"name [unit]"`` ("T [degF]")."""
    unit_label = label(kind, system)
    return f"{name} [{unit_label}]" if unit_label else name


@dataclass(frozen=True)
class Shown:
    """How one command shows numbers: its unit system and significant digits.

    >>> us = Shown("us")
    >>> us.head("T", "temperature"), us.num(-39.99999999999997, "temperature")
    ('T [degF]', '-40')
    >>> us.text(3.73, "torque")
    '33.01 lbf*in'
    """

    system: UnitSystem = DEFAULT_SYSTEM
    digits: int = 4

    def unit(self, kind: str) -> str:
        """The unit label of ``kind``."""
        return label(kind, self.system)

    def head(self, name: str, kind: str, sep: str = " ") -> str:
        """A column header or axis label, ``"name [unit]"``; ``sep`` may be a newline."""
        unit_label = label(kind, self.system)
        return f"{name}{sep}[{unit_label}]" if unit_label else name

    def value(self, si_value: float, kind: str) -> float:
        """The SI value in this system's unit."""
        return convert(si_value, kind, self.system)

    def values(self, si_values: FloatArray, kind: str) -> FloatArray:
        """An array of SI values in this system's unit (for plots)."""
        unit = UNITS[kind][self.system]
        return si_values * unit.scale + unit.offset

    def num(self, si_value: float | None, kind: str, none: str = "-") -> str:
        """The SI value converted and formatted, without its unit (a table cell)."""
        if si_value is None:
            return none
        return format_value(convert(si_value, kind, self.system), self.digits)

    def text(self, si_value: float | None, kind: str, none: str = "-") -> str:
        """The SI value converted and formatted with its unit ("77 degF")."""
        return format_quantity(si_value, kind, self.system, self.digits, none)


# A number followed by an SI unit in a sentence ("at 25 degC", "drive torque 1.45 N*m").
_TEXT_UNITS: dict[str, str] = {
    "degC": "temperature",
    "N*m*s/rad": "damping_rate",
    "N*m/K": "torque_per_kelvin",
    "N*m": "torque",
    "kg*m^2": "inertia",
    "J": "energy",
}
_QUANTITY_IN_TEXT = re.compile(
    r"(?<![\w.])([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?) "
    r"(degC|N\*m\*s/rad|N\*m/K|N\*m|kg\*m\^2|J)(?![\w*/^])"
)


def convert_text(text: str, system: UnitSystem, digits: int = 4) -> str:
    """A sentence with its SI quantities ("at 25 degC", "1.45 N*m") shown in ``system``.

    For messages built in SI by the library (warnings), shown on a terminal in US units.

    >>> convert_text("cannot start: drive torque 1.45 N*m < friction 1.5 N*m at -40 degC", "us")
    'cannot start: drive torque 12.83 lbf*in < friction 13.28 lbf*in at -40 degF'
    """
    if system == "si":
        return text

    def shown(match: re.Match[str]) -> str:
        return format_quantity(float(match.group(1)), _TEXT_UNITS[match.group(2)], system, digits)

    return _QUANTITY_IN_TEXT.sub(shown, text)

"""One naming scheme for every table ecdsim writes: the SI unit at the end of the name.

Every machine-readable name (a JSON key, a DataFrame or Parquet column, an xarray
variable) that holds a number with a unit ends in that unit's suffix: ``friction_Nm``,
``deployment_time_s``, ``temperature_C`` (docs/json.md, "Names and units"). A config key
used as a column (a sweep's varied key, a Monte Carlo study's sampled quantity) keeps
its dotted name and gets the suffix of the SI unit it is given in: ``load.start_torque_Nm``,
``damper.damping_rate_Nms_per_rad``; a dimensionless key has none (``gearbox.ratio``).
Temperature and method are columns of a long (tidy) table, never parts of a name.

This module is the one table of suffixes and of the columns' types, so that DataFrames,
Parquet metadata, xarray attributes and the JSON Schemas agree. It imports nothing of
ecdsim (foundation layer) and nothing heavy.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

# The suffix of each SI unit ecdsim uses inside (ecdsim.config.units.Kind.unit), without
# its leading underscore. Dimensionless numbers ("") have none.
SUFFIX_BY_UNIT: dict[str, str] = {
    "N*m": "Nm",
    "N*m*s/rad": "Nms_per_rad",
    "N*m/K": "Nm_per_K",
    "N*m/rad": "Nm_per_rad",
    "1/K": "per_K",
    "degC": "C",
    "K": "K",
    "rad": "rad",
    "rad/s": "rad_s",
    "s": "s",
    "ms": "ms",
    "kg": "kg",
    "m": "m",
    "m/s": "m_s",
    "m/s^2": "m_s2",
    "kg*m^2": "kg_m2",
    "J": "J",
    "W": "W",
    "J/K": "J_per_K",
    "K/W": "K_per_W",
    "Pa*s": "Pa_s",
    "m^2/s": "m2_s",
}

# Suffix -> SI unit, longest suffix first, so that "_rad_s" wins over "_s" and
# "_Nm_per_K" over "_per_K" and "_K".
_UNIT_BY_SUFFIX: tuple[tuple[str, str], ...] = tuple(
    sorted(
        ((f"_{suffix}", unit) for unit, suffix in SUFFIX_BY_UNIT.items()),
        key=lambda pair: -len(pair[0]),
    )
)

# Columns that hold flags or counts. Where a column exists for some rows only (the
# dynamic method's ``stuck`` and ``impacts`` beside the paper and exact methods' rows)
# the DataFrame keeps the type with pandas' nullable dtypes (<NA> where absent), instead
# of an object column of mixed bools and NaN or a float column of counts.
BOOL_COLUMNS = frozenset({"solved", "stalled", "stuck", "passed", "cannot_start"})
INT_COLUMNS = frozenset({"point", "sample", "impacts", "rank", "n_points", "case"})
TEXT_COLUMNS = frozenset({"method", "status", "error", "damper", "gearbox"})


def suffix(unit: str) -> str:
    """The name suffix of an SI unit, with its underscore; "" for a dimensionless number.

    >>> suffix("N*m"), suffix("kg*m^2"), suffix("")
    ('_Nm', '_kg_m2', '')
    """
    if unit == "":
        return ""
    try:
        return f"_{SUFFIX_BY_UNIT[unit]}"
    except KeyError:
        raise ValueError(f"no name suffix for the unit {unit!r}") from None


def key_column(key: str, unit: str | None) -> str:
    """The column of a dotted config key given in ``unit`` (None or "": no suffix).

    >>> key_column("load.start_torque", "N*m"), key_column("gearbox.ratio", "")
    ('load.start_torque_Nm', 'gearbox.ratio')
    """
    return key if not unit else f"{key}{suffix(unit)}"


def unit_of(name: str) -> str | None:
    """The SI unit a column or key holds, from its suffix; None without one.

    >>> unit_of("deployment_time_s"), unit_of("load.system_friction.at_0C_Nm")
    ('s', 'N*m')
    >>> unit_of("stalled") is None
    True
    """
    for end, unit in _UNIT_BY_SUFFIX:
        if name.endswith(end):
            return unit
    return None


def units_of(names: Iterable[str]) -> dict[str, str]:
    """Every name that carries a unit, and that unit (for Parquet and xarray metadata)."""
    found = {}
    for name in names:
        unit = unit_of(name)
        if unit is not None:
            found[name] = unit
    return found


def flatten(row: Mapping[str, Any]) -> dict[str, Any]:
    """A row whose nested objects become columns: ``X_<unit>: {k: v}`` -> ``X_k_<unit>``.

    The JSON's ``energy_J: {"spring_work": ...}`` becomes ``energy_spring_work_J``; a
    nested object without a unit suffix gives ``X_k``. Lists are left out (not a cell).

    >>> flatten({"energy_J": {"spring_work": 1.0}, "stalled": False})
    {'energy_spring_work_J': 1.0, 'stalled': False}
    """
    out: dict[str, Any] = {}
    for name, value in row.items():
        if isinstance(value, Mapping):
            unit = unit_of(name)
            end = "" if unit is None else suffix(unit)
            stem = name[: len(name) - len(end)] if end else name
            for key, inner in value.items():
                if not isinstance(inner, Mapping | list | tuple):
                    out[f"{stem}_{key}{end}"] = inner
        elif not isinstance(value, list | tuple):
            out[name] = value
    return out


def dataframe(rows: list[dict[str, Any]], columns: list[str] | None = None) -> Any:
    """The rows as a pandas DataFrame with the column types of this module.

    Flags are pandas' nullable ``boolean`` and counts its nullable ``Int64`` (so a
    column that only some rows have keeps its type), text is ``string``, the rest
    float64 where numeric. pandas is imported here (the caller checks that it exists).
    """
    import pandas as pd

    names = columns if columns is not None else list(dict.fromkeys(k for r in rows for k in r))
    frame = pd.DataFrame(rows, columns=names)
    for name in names:
        if name in BOOL_COLUMNS:
            frame[name] = frame[name].astype("boolean")
        elif name in INT_COLUMNS:
            frame[name] = frame[name].astype("Int64")
        elif name in TEXT_COLUMNS:
            frame[name] = frame[name].astype("string")
    return frame

"""Set config keys by dotted name (``gearbox.ratio``, ``load.inertia``) before validation.

The notebook API (:mod:`ecdsim.api`) and sweeps (:mod:`ecdsim.sweeps`) change a config's
values without writing a file: :func:`apply_overrides` copies the parsed TOML document
and sets each key, and the result is validated like any file, so a bad value gets the
same one-line message naming its key. A value may be

* a string with a unit, as in a file (``"5 kg*m^2"``);
* a plain number, read in the field's SI unit (temperatures in degC, the package's
  convention), see :func:`field_unit`;
* a pint quantity (anything with ``magnitude`` and ``to``), converted to the SI unit.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from typing import Any, get_origin

from ecdsim.config.errors import ConfigError
from ecdsim.config.units import Kind, magnitude_problem, quoted


class OverrideError(ConfigError):
    """A key that is not a config field, or a value that cannot be given to it."""


def field_kind(key: str) -> Kind | None:
    """The quantity kind of a dotted config key, or None if it has none (or is unknown)."""
    from pydantic import BaseModel

    from ecdsim.config.full_schema import ConfigSpec, model_in

    model: type[BaseModel] | None = ConfigSpec
    kind: Kind | None = None
    for part in key.split("."):
        if model is None or part not in model.model_fields:
            return None
        info = model.model_fields[part]
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        kind = kinds[0] if kinds else _kind_in(info.annotation)
        model = model_in(info.annotation)
    return kind


def _kind_in(annotation: Any) -> Kind | None:
    # Optional fields hide the Kind inside Annotated[float, ..., Kind] | None.
    for meta in getattr(annotation, "__metadata__", ()):
        if isinstance(meta, Kind):
            return meta
    if hasattr(annotation, "__metadata__") or get_origin(annotation) in (list, tuple, dict):
        return None
    for arg in getattr(annotation, "__args__", ()):
        found = _kind_in(arg)
        if found is not None:
            return found
    return None


def field_unit(key: str) -> str | None:
    """The SI unit a plain number given to ``key`` is read in ("" for a plain number).

    None when the key has no quantity kind (a table such as ``load.system_friction``, a
    string, an unknown key): such a value is passed to the config as it is.

    >>> field_unit("load.inertia"), field_unit("gearbox.ratio")
    ('kg*m^2', '')
    """
    kind = field_kind(key)
    return None if kind is None else kind.unit


def config_value(key: str, value: object) -> object:
    """``value`` as the TOML document holds it: a quantity string, or as given.

    Raises :class:`OverrideError` (one line naming the key) for a pint quantity whose
    unit does not convert to the field's, or a non-finite number.
    """
    unit = field_unit(key)
    if hasattr(value, "magnitude") and hasattr(value, "to"):
        if unit is None:
            raise OverrideError([f"{key}: a quantity ({value}) given to a field without a unit"])
        target = unit or "dimensionless"
        try:
            number = float(value.to(target).magnitude)
        except Exception as exc:  # pint's DimensionalityError and friends
            raise OverrideError(
                [f"{key} = {value}: cannot convert to {target} ({type(exc).__name__})"]
            ) from None
        value = number
    if isinstance(value, bool) or not isinstance(value, int | float):
        return value
    try:
        number = float(value)
    except OverflowError:  # an int beyond float64 (10**400)
        raise OverrideError([f"{key} = {quoted(value)}: {magnitude_problem(math.inf)}"]) from None
    if not math.isfinite(number):
        raise OverrideError([f"{key} = {value!r}: not a finite number"])
    if unit:
        return f"{number!r} {unit}"
    return value


def apply_overrides(raw: Mapping[str, Any], overrides: Mapping[str, object]) -> dict[str, Any]:
    """A deep copy of the TOML document ``raw`` with each dotted key set.

    Missing tables on the way are created; a key that passes through a non-table value
    raises :class:`OverrideError`. Unknown keys are left for validation to name.
    """
    from ecdsim.config.loader import MAX_NESTING, TOO_DEEP, nesting_depth

    # Measured before anything walks them (deepcopy and validation recurse): a mapping
    # nested 5,000 deep would exhaust the stack, where a file or a request is refused.
    if nesting_depth(dict(raw)) > MAX_NESTING:
        raise OverrideError([f"config: {TOO_DEEP}"])
    deep = [key for key, value in overrides.items() if nesting_depth(value) > MAX_NESTING - 1]
    if deep:
        raise OverrideError([f"{key}: {TOO_DEEP}" for key in deep])
    document: dict[str, Any] = copy.deepcopy(dict(raw))
    problems = []
    # The type says str keys; a notebook may pass anything.
    given: list[tuple[object, object]] = list(overrides.items())
    for key, value in given:
        if not isinstance(key, str):
            problems.append(f"{quoted(key)}: not a config key (expected e.g. gearbox.ratio)")
            continue
        parts = key.split(".")
        if not key or any(not p for p in parts):
            problems.append(f"{key!r}: not a config key (expected e.g. gearbox.ratio)")
            continue
        node: Any = document
        for part in parts[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                problems.append(f"{key}: {part} is a value, not a table")
                break
            node = child
        else:
            try:
                node[parts[-1]] = config_value(key, value)
            except OverrideError as exc:
                problems.extend(exc.problems)
    if problems:
        raise OverrideError(problems)
    return document

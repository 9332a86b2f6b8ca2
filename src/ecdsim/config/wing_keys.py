"""A wing file's keys by path, for sweeps and Monte Carlo (docs/wing.md, studies).

A key path is written as the file nests it, list entries counted from 0 and ECDs by
name, as every error message of a wing file names them::

    wing.panels[2].mass
    wing.hinges[1].friction.at_0C
    wing.ecds.cc16.damper.damping_rate
    wing.cables[0].stiffness

:func:`field_kind` finds the quantity kind of a path in the wing file's schema
(:class:`ecdsim.config.wing_schema.WingConfigSpec`), so a plain number is read in the
key's SI unit as everywhere (:mod:`ecdsim.config.overrides`); :func:`set_values` copies
a parsed wing document with keys set, for validation as any file; :func:`nominal` reads
a key's value in the file, in SI. Every problem is one line naming the key. The
paths' parsing and their kinds live with the schema they walk
(:mod:`ecdsim.config.wing_schema`, which checks a ``[tolerances]`` section's keys with
them) and are re-exported here.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from typing import Any

from ecdsim.config.units import QuantityError
from ecdsim.config.wing_schema import (
    EXAMPLE_KEY,
    KEY_PATTERN,
    WingKeyError,
    field_kind,
    is_wing_key,
    key_problem,
    split_key,
)

__all__ = [
    "EXAMPLE_KEY",
    "KEY_PATTERN",
    "WingKeyError",
    "config_value",
    "field_kind",
    "field_unit",
    "is_wing_key",
    "key_problem",
    "nominal",
    "set_values",
    "split_key",
]


def field_unit(key: str) -> str | None:
    """The SI unit a plain number given to ``key`` is read in ("" for a plain number;
    None: not a quantity)."""
    kind = field_kind(key)
    return None if kind is None else kind.unit


def config_value(key: str, value: object) -> object:
    """``value`` as the wing document holds it: a number becomes ``"number unit"`` in the
    key's SI unit; a string is passed on as written."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return value
    number = float(value)
    if not math.isfinite(number):
        raise WingKeyError([f"{key} = {value!r}: not a finite number"])
    unit = field_unit(key)
    return f"{number!r} {unit}" if unit else number


def _walk(document: Any, parts: tuple[str | int, ...], key: str) -> Any:
    """The table holding the last part (created where a table is missing); a missing list
    entry or ECD is an error naming the key."""
    node = document
    shown = ""
    for part in parts[:-1]:
        if isinstance(part, int):
            if not isinstance(node, list) or part >= len(node):
                count = len(node) if isinstance(node, list) else 0
                raise WingKeyError([f"{key}: {shown} has no entry {part} ({count} entries)"])
            node = node[part]
            shown += f"[{part}]"
            continue
        if not isinstance(node, dict):
            raise WingKeyError([f"{key}: {shown} is a value, not a table"])
        if part not in node and shown == "wing.ecds":
            raise WingKeyError([f"{key}: no ECD {part!r} in [wing.ecds] (known: {sorted(node)})"])
        child = node.get(part)
        if child is None:
            child = node[part] = {}
        node = child
        shown += f".{part}" if shown else part
    if not isinstance(node, dict):
        raise WingKeyError([f"{key}: {shown} is a value, not a table"])
    return node


def set_values(raw: Mapping[str, Any], values: Mapping[str, object]) -> dict[str, Any]:
    """A deep copy of the wing document ``raw`` with each key path set (numbers in the
    key's SI unit, strings as written); validate it as a file to check the values."""
    document: dict[str, Any] = copy.deepcopy(dict(raw))
    problems: list[str] = []
    for key, value in values.items():
        try:
            parts = split_key(key)
            node = _walk(document, parts, key)
            node[str(parts[-1])] = config_value(key, value)
        except WingKeyError as exc:
            problems.extend(exc.problems)
    if problems:
        raise WingKeyError(problems)
    return document


def nominal(raw: Mapping[str, Any], key: str) -> float:
    """The value of ``key`` in the wing document, in its SI unit (degC for temperatures);
    :class:`WingKeyError` if the file does not set it."""
    problem = key_problem(key)
    if problem is not None:
        raise WingKeyError([problem])
    kind = field_kind(key)
    assert kind is not None
    parts = split_key(key)
    node: Any = raw
    for part in parts:
        if isinstance(part, int):
            node = node[part] if isinstance(node, list) and part < len(node) else None
        else:
            node = node.get(part) if isinstance(node, dict) else None
        if node is None:
            raise WingKeyError(
                [f"{key}: not set in the file; give it a value there to vary it about"]
            )
    try:
        return kind.parse(node)
    except QuantityError as exc:
        raise WingKeyError([f"{key}: {exc}"]) from None

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
a key's value in the file, in SI. Every problem is one line naming the key.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Mapping
from typing import Any

from ecdsim.config.errors import ConfigError
from ecdsim.config.units import Kind, QuantityError

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
# wing, then dotted names each with optional [index] parts.
KEY_PATTERN = re.compile(rf"^wing(\.{_NAME}(\[\d+\])*)+$")
_PART = re.compile(rf"({_NAME})((?:\[\d+\])*)")
EXAMPLE_KEY = "wing.hinges[1].friction.at_0C"


class WingKeyError(ConfigError):
    """A key path that is not a quantity of the wing file (one line each)."""


def is_wing_key(key: str) -> bool:
    """True for a key path into ``[wing]`` (``wing.panels[0].mass``)."""
    return KEY_PATTERN.match(key) is not None


def split_key(key: str) -> tuple[str | int, ...]:
    """``wing.hinges[1].friction.at_0C`` -> ``("wing", "hinges", 1, "friction", "at_0C")``."""
    if not is_wing_key(key):
        raise WingKeyError([f"{key!r}: not a wing key; expected a path such as {EXAMPLE_KEY}"])
    parts: list[str | int] = []
    for piece in key.split("."):
        found = _PART.fullmatch(piece)
        assert found is not None  # the pattern above admits only such pieces
        parts.append(found.group(1))
        parts.extend(int(i) for i in re.findall(r"\[(\d+)\]", found.group(2)))
    return tuple(parts)


def field_kind(key: str) -> Kind | None:
    """The quantity kind of a wing key path, or None (not a quantity, or unknown)."""
    from ecdsim.config.overrides import _kind_in
    from ecdsim.config.wing_schema import WingConfigSpec, _container, _model_in

    try:
        parts = split_key(key)
    except WingKeyError:
        return None
    model: Any = WingConfigSpec
    kind: Kind | None = None
    expect: str | None = None  # "index" after a list field, "name" after a dict field
    for part in parts:
        if expect == "index":
            if not isinstance(part, int):
                return None
            expect = None
            continue
        if expect == "name":
            expect = None
            continue
        if isinstance(part, int) or model is None or part not in model.model_fields:
            return None
        info = model.model_fields[part]
        container = _container(info.annotation)
        expect = "index" if container is list else "name" if container is dict else None
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        kind = kinds[0] if kinds else (None if container else _kind_in(info.annotation))
        model = _model_in(info.annotation)
    if expect is not None or model is not None:
        return None  # a list, a table or an ECD, not one quantity
    return kind


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


def key_problem(key: str) -> str | None:
    """Why ``key`` cannot be varied (one line), or None."""
    if not is_wing_key(key):
        return (
            f"{key}: not a key of a wing file; give its path in the file, e.g. {EXAMPLE_KEY} "
            "(docs/wing.md)"
        )
    if field_kind(key) is None:
        return (
            f"{key}: not a quantity of a wing file (a path to one number with its unit, "
            f"e.g. {EXAMPLE_KEY}; list entries counted from 0)"
        )
    return None


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

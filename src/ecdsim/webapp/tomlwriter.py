"""Write a JSON-like configuration (the explorer's edited config) back as TOML text.

Only what a config needs: tables, strings, numbers, booleans, lists and inline tables.
Top-level tables become ``[section]`` headers; deeper tables are inline. TOML has no
null, so a ``None`` anywhere is an :class:`UnrepresentableError` naming its key path.

>>> print(to_toml({"title": "x", "load": {"travel": "90 deg", "f": {"a": 1}}}), end="")
title = "x"
<BLANKLINE>
[load]
travel = "90 deg"
f = { a = 1 }
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


class UnrepresentableError(ValueError):
    """A value that TOML cannot hold; ``path`` is its dotted key path."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(f"{path}: {message}")
        self.path = path


def _key(key: str) -> str:
    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def _string(text: str) -> str:
    # JSON string escapes are valid TOML basic-string escapes (\uXXXX, \n, \", \\),
    # except lone surrogates, which TOML (UTF-8) cannot hold.
    if any(0xD800 <= ord(c) <= 0xDFFF for c in text):
        raise ValueError("contains a lone surrogate character")
    return json.dumps(text, ensure_ascii=False)


def _value(value: Any, path: str) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        try:
            return _string(value)
        except ValueError as exc:
            raise UnrepresentableError(path, str(exc)) from None
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v, f"{path}[{i}]") for i, v in enumerate(value)) + "]"
    if isinstance(value, dict):
        items = [f"{_key(str(k))} = {_value(v, f'{path}.{k}')}" for k, v in value.items()]
        return "{ " + ", ".join(items) + " }" if items else "{}"
    if value is None:
        raise UnrepresentableError(path, "null has no TOML form; leave the key out instead")
    raise UnrepresentableError(path, f"{type(value).__name__} has no TOML form")


def to_toml(document: dict[str, Any]) -> str:
    """TOML text for a dictionary of TOML-compatible values (see the module docstring)."""
    lines: list[str] = []
    tables: list[tuple[str, dict[str, Any]]] = []
    for key, value in document.items():
        if isinstance(value, dict):
            tables.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_value(value, key)}")
    for name, table in tables:
        if lines:
            lines.append("")
        lines.append(f"[{_key(name)}]")
        for key, value in table.items():
            lines.append(f"{_key(key)} = {_value(value, f'{name}.{key}')}")
    return "\n".join(lines) + "\n"

"""The configuration edge: TOML files with units as strings, parsed once into SI floats.

Nothing inside the package sees a unit object: :func:`load_config` returns plain model
objects (see :mod:`ecdsim.model`) and SI floats. The file format is in ``docs/config.md``.

The loader (pydantic, the schema and the model it builds) is imported when first named,
so that ``from ecdsim.config.units import ...`` or ``from ecdsim.config.errors import
ConfigError`` (a bench log's reader, ``ecdsim fit``) stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ecdsim.config.errors import ConfigError

if TYPE_CHECKING:
    from ecdsim.config.loader import Config, load_config, parse_config

__all__ = ["Config", "ConfigError", "load_config", "parse_config"]

_LOADER_NAMES = frozenset({"Config", "load_config", "parse_config"})


def __getattr__(name: str) -> Any:
    if name in _LOADER_NAMES:
        from ecdsim.config import loader

        return getattr(loader, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

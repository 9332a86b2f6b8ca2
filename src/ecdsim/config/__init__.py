"""The configuration edge: TOML files with units as strings, parsed once into SI floats.

Nothing inside the package sees a unit object: :func:`load_config` returns plain model
objects (see :mod:`ecdsim.model`) and SI floats. The file format is in ``docs/config.md``.
"""

from ecdsim.config.errors import ConfigError
from ecdsim.config.loader import Config, load_config, parse_config

__all__ = ["Config", "ConfigError", "load_config", "parse_config"]

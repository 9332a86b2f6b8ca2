"""A config whose ``[load]`` is a marked placeholder (issue 26 item 2): one check, one text.

``ecdsim fit drop-test -o`` without ``--config`` writes the fitted damper with a stand-in
load marked ``placeholder = true``. Until the user deletes that line, every output of the
config says its deployment is not the mechanism's: each command's ``warning:`` line, the
deploy table's title, ``"placeholder_load": true`` in the JSON, the report's banner, the
explorer's banner, the notebook API (a :class:`PlaceholderLoadWarning`, the results' repr,
HTML and ``to_dict``) and the FMU (the warning and its description). Each of them asks
:func:`is_placeholder` and words it with :func:`warning_text` or :data:`TITLE`.

The library below the edges stays silent, as everywhere (its findings are data): only the
notebook API and :func:`ecdsim.fmu.build_fmu`, whose callers are Python programs, call
:func:`warn`; the command line prints the same text as a ``warning:`` line.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ecdsim.config.loader import Config

__all__ = [
    "JSON_KEY",
    "TITLE",
    "PlaceholderLoadWarning",
    "is_placeholder",
    "warn",
    "warning_text",
]

# The deploy table's title suffix and the notebook results' one-line flag.
TITLE = "PLACEHOLDER LOAD: not your mechanism's deployment"
# The deploy document's key (docs/json.md), present and true only for a placeholder.
JSON_KEY = "placeholder_load"


class PlaceholderLoadWarning(UserWarning):
    """The config's ``[load]`` is a marked placeholder: no deployment result of it is the
    mechanism's (the notebook API's and ``build_fmu``'s warning; the command line prints
    the same text as a ``warning:`` line)."""


def is_placeholder(config: Config) -> bool:
    """True when the config's ``[load]`` is marked ``placeholder = true`` (written by
    ``ecdsim fit drop-test -o`` without ``--config``)."""
    return bool(getattr(config.spec.load, "placeholder", False))


def warning_text(source: str) -> str:
    """The one warning every output of a placeholder config gives, for the file ``source``."""
    return (
        f"{source}: PLACEHOLDER LOAD ([load] placeholder = true): the spring and travel are "
        "stand-ins, so no deployment result here is your mechanism's; enter its spring "
        "torques and travel in [load], then delete the placeholder line"
    )


def warn(config: Config, stacklevel: int = 2) -> None:
    """Issue a :class:`PlaceholderLoadWarning` when the config's load is a placeholder.

    ``stacklevel`` as :func:`warnings.warn`'s, counted from the caller of this function
    (2: the caller's caller, the user's line that called the notebook API).
    """
    if is_placeholder(config):
        warnings.warn(
            PlaceholderLoadWarning(warning_text(config.source)), stacklevel=stacklevel + 1
        )

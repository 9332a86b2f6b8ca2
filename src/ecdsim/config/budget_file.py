"""Read a torque-budget file (``ecdsim margin BUDGET.toml``, docs/qualification.md).

Apart from :mod:`ecdsim.config.budget_schema` so that the schema imports nothing of the
loader (which imports the whole schema).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ecdsim.config.budget_schema import BudgetFileSpec, WrittenUnit, written_unit
from ecdsim.config.errors import ConfigError
from ecdsim.config.loader import (
    MAX_NESTING,
    _message,
    nesting_depth,
    parse_toml,
    read_config_text,
)
from ecdsim.config.units import TORQUE


@dataclass(frozen=True)
class BudgetFile:
    """A validated budget file.

    Attributes
    ----------
    spec : the validated file
    source : the path as given
    unit : the unit ``available`` was written in, None if it cannot be told
    """

    spec: BudgetFileSpec
    source: str
    unit: WrittenUnit | None


# A deployment config has these sections; a budget file has none of them.
CONFIG_SECTIONS = ("damper", "gearbox", "load")


def is_budget_document(raw: dict[str, Any]) -> bool:
    """True for a budget file (``[budget]`` and no deployment section)."""
    return "budget" in raw and not any(section in raw for section in CONFIG_SECTIONS)


def read_toml(path: Path) -> dict[str, Any]:
    """A TOML file's document; :class:`ConfigError` if unreadable or not TOML."""
    text = read_config_text(path, "budget or config file")
    raw = parse_toml(text, str(path))  # invalid TOML, deep nesting, a 4,300-digit integer
    if nesting_depth(raw) > MAX_NESTING:
        raise ConfigError(
            [f"nested too deeply (at most {MAX_NESTING} levels of tables and lists)"], str(path)
        )
    return raw


def validate_budget(raw: dict[str, Any], source: str) -> BudgetFile:
    """Validate a budget file's document; :class:`ConfigError` lists every problem, one
    line each naming the key, the value and the expected unit (the config's messages)."""

    def message(error: Any) -> str:
        loc = tuple(error["loc"])
        if error["type"] == "extra_forbidden" and len(loc) == 1:
            return (
                f"{loc[0]}: unknown key (a budget file holds title and [budget]; a deployment "
                "config holds [damper], [gearbox] and [load] as well)"
            )
        if error["type"] == "missing" and loc == ("budget", "available"):
            # Optional in a config (the spring's torque), so the whole schema has no unit
            # for it: the budget file requires it and names the unit itself.
            return f"budget.available: missing; {TORQUE.expected}"
        return _message(error)

    try:
        spec = BudgetFileSpec.model_validate(raw)
    except ValidationError as exc:
        raise ConfigError([message(e) for e in exc.errors()], source) from None
    available = raw.get("budget", {}).get("available") if isinstance(raw, dict) else None
    return BudgetFile(spec, source, written_unit(available))

"""Read a life test's CSV: each unit's life and whether it ended in a failure.

Columns: ``unit`` (a number naming the test unit: rows of equal life and outcome are
different units, not a repeated row), ``life`` (cycles, deployments or time, one unit
throughout the file, > 0) and ``failed`` (1 where the life ended in a failure, 0 where
the unit was suspended: removed or still working when the test stopped). Bad rows are
reported and excluded as in every bench file (:mod:`ecdsim.characterize.csvdata`).
"""

from __future__ import annotations

from pathlib import Path

from ecdsim.characterize.csvdata import Column, Table, read_table
from ecdsim.config.units import Kind

UNIT = Kind("test unit number", "", "3")
LIFE = Kind("life (cycles, deployments or time; one unit throughout)", "", "500")
FLAG = Kind("failure flag (1 = failed, 0 = suspended)", "", "1")


def _positive(value: float) -> str | None:
    return None if value > 0.0 else "must be > 0 (a life)"


def _flag(value: float) -> str | None:
    return None if value in (0.0, 1.0) else "must be 1 (failed) or 0 (suspended)"


COLUMNS = (
    Column("unit", UNIT, "unit"),
    Column("life", LIFE, "life", check=_positive),
    Column("failed", FLAG, "failed", check=_flag),
)


def read_lives(path: str | Path) -> Table:
    """The usable rows of a life-test CSV (:class:`~ecdsim.config.ConfigError` for a
    file that cannot be used)."""
    return read_table(path, COLUMNS)

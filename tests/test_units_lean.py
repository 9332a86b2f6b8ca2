"""The lean unit table (config/units.py LEAN_FACTORS) against pint, and where pint loads.

Every entry of the table must give exactly pint's answer (the table holds pint's own
conversion factors; pint's conversion is ``number * factor``), for random magnitudes
over the accepted range; a unit outside the table still goes to pint, with pint's
messages. Reading the paper example must not import pint at all (issue 13, item 4).
"""

from __future__ import annotations

import random
import subprocess
import sys
import zlib
from collections.abc import Callable
from functools import partial

import pytest

from ecdsim.config import units
from ecdsim.config.units import LEAN_FACTORS, Kind, QuantityError, lean_key

KINDS = {k.unit: k for k in vars(units).values() if isinstance(k, Kind)}


def _numbers(seed: int, count: int) -> list[str]:
    rng = random.Random(seed)
    out = ["1", "0", "-1", "2.5e-3", "90", "1e-30", "9.99e29"]
    for _ in range(count):
        out.append(repr(rng.uniform(-1e3, 1e3) * 10.0 ** rng.randint(-25, 25)))
    return out


@pytest.mark.parametrize(("unit", "target"), sorted(LEAN_FACTORS))
def test_lean_factor_gives_pints_answer_bit_for_bit(unit: str, target: str) -> None:
    kind = KINDS[target]
    for text in _numbers(zlib.crc32(f"{unit} {target}".encode()), 300):
        raw = f"{text} {unit}"
        lean = _answer(partial(kind.parse, raw))
        assert lean == _answer(partial(units._convert_with_pint, float(text), unit, raw, kind))


def _answer(read: Callable[[], float]) -> float | str:
    """The value read, or the message of the QuantityError raised (out of range, say)."""
    try:
        return read()
    except QuantityError as exc:
        return str(exc)


@pytest.mark.parametrize(
    ("written", "key"),
    [("N*m", "N*m"), ("N m", "N*m"), ("N * m", "N*m"), ("kg*m**2", "kg*m^2"),
     ("kg m ^ 2", "kg*m^2"), ("/ K", "/K"), ("1 / K", "1/K"), ("mN*m / degC", "mN*m/degC")],
)  # fmt: skip
def test_lean_key_writes_a_unit_one_way(written: str, key: str) -> None:
    assert lean_key(written) == key


def test_spacing_variants_agree_with_pint() -> None:
    torque = KINDS["N*m"]
    for raw in ("3.73 mN m", "3.73 mN * m", "3.73 mN*m"):
        assert torque.parse(raw) == units._convert_with_pint(3.73, raw[5:], raw, torque)


def test_units_outside_the_table_still_go_to_pint() -> None:
    torque = KINDS["N*m"]
    assert ("lbf*in", "N*m") not in LEAN_FACTORS
    assert torque.parse("1 lbf*in") == pytest.approx(0.1129848290276167, rel=1e-15)
    with pytest.raises(QuantityError, match="wrong dimension"):
        torque.parse("3 deg")  # not in the table for torque: pint says why
    with pytest.raises(QuantityError, match="pint does not know"):
        torque.parse("3 blorgs")
    assert KINDS["degC"].parse("300 K") == pytest.approx(26.85, rel=1e-14)


def test_reading_the_paper_example_does_not_import_pint() -> None:
    script = (
        "import sys\n"
        "from ecdsim.config import load_config\n"
        "load_config('examples/paper_cc16.toml')\n"
        "print('pint' in sys.modules)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "False"

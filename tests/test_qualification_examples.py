"""The qualification examples are synthetic and ILLUSTRATIVE: written by the generators
below from known parameters with formulas typed here (not ecdsim's), and checked to be
exactly what the generators write. Regenerate them with::

    .venv/bin/python -m tests.test_qualification_examples

* ``examples/life_test.csv``: 12 units whose lives are drawn from a Weibull distribution
  of shape 2.5 and scale 2000 cycles (numpy seed 20261128); the test stopped at 1800
  cycles, so the units still working then are suspensions; lives to whole cycles.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LIFE_TEST = ROOT / "examples" / "life_test.csv"

LIFE_SHAPE, LIFE_SCALE, LIFE_STOP, LIFE_UNITS = 2.5, 2000.0, 1800, 12


def life_test_text() -> str:
    """The life test: Weibull lives by inversion, ``eta * (-ln U)**(1/beta)``."""
    rng = np.random.default_rng(20261128)
    u = rng.random(LIFE_UNITS)
    lives = LIFE_SCALE * (-np.log(u)) ** (1.0 / LIFE_SHAPE)
    rows = ["unit,life,failed"]
    for unit, life in enumerate(lives, start=1):
        cycles = int(round(float(life)))
        rows.append(f"{unit},{min(cycles, LIFE_STOP)},{1 if cycles < LIFE_STOP else 0}")
    return "\n".join(rows) + "\n"


def test_example_files_are_what_the_generators_write() -> None:
    assert LIFE_TEST.read_text(encoding="utf-8") == life_test_text()


if __name__ == "__main__":
    LIFE_TEST.write_text(life_test_text(), encoding="utf-8")
    print(f"wrote {LIFE_TEST}")

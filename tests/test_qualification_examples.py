"""The qualification examples are synthetic and ILLUSTRATIVE: written by the generators
below from known parameters with formulas typed here (not ecdsim's), and checked to be
exactly what the generators write. Regenerate them with::

    .venv/bin/python -m tests.test_qualification_examples

* ``examples/life_test.csv``: 12 units whose lives are drawn from a Weibull distribution
  of shape 2.5 and scale 2000 cycles (numpy seed 20261128); the test stopped at 1800
  cycles, so the units still working then are suspensions; lives to whole cycles.
* ``examples/drive_test.csv``: a hinge driven open from 0 to 90 deg and closed again in
  2 deg steps at -40, 25 and 100 degC. The spring is the paper's (3.73 N*m falling
  linearly to 1.58 N*m over 90 deg), the friction the paper's FS_T = 0.58 - 0.0044 T N*m
  times (1 + 0.1 sin(4 pi phi / 180 deg)) (its mean over the travel is FS_T); the bench
  reads spring - friction opening, spring + friction closing, with a 0.005 N*m normal
  reading error (numpy seed 20261130); torques to 0.1 mN*m.
* ``examples/fluid_bench.csv``: a shear-thinning rotary damper on a torque-speed bench at
  -15, 10 and 40 degC, 7 speeds from 0.01 to 1 rad/s (equal steps in log), the power law
  T = 1.8 N*m (w / 0.1 rad/s)^n(T) exp(2040 K (1/T_K - 1/298.15 K)) with
  n(T) = 0.45 - 0.0006 (T - 25 degC) (n = 0.474 to 0.441; 4.0 times the torque at
  -15 degC of that at 40 degC), times a lognormal reading error of 2 % (numpy seed
  20261201); torques to 5 significant digits.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LIFE_TEST = ROOT / "examples" / "life_test.csv"
DRIVE_TEST = ROOT / "examples" / "drive_test.csv"
FLUID_BENCH = ROOT / "examples" / "fluid_bench.csv"

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


DRIVE_TEMPERATURES = (-40.0, 25.0, 100.0)
DRIVE_NOISE = 0.005  # N*m


def drive_spring(phi_deg: float) -> float:
    """The paper's spring (Eq. 7): 3.73 N*m at 0 falling linearly to 1.58 N*m at 90 deg."""
    return 3.73 - (3.73 - 1.58) * phi_deg / 90.0


def drive_friction(phi_deg: float, t: float) -> float:
    """The paper's FS_T, varying +-10 % along the travel with mean FS_T over it."""
    return (0.58 - 0.0044 * t) * (1.0 + 0.1 * float(np.sin(4.0 * np.pi * phi_deg / 180.0)))


def drive_test_text() -> str:
    """The drive test: opening then closing at each temperature, rows as recorded."""
    rng = np.random.default_rng(20261130)
    rows = ["temperature [degC],angle [deg],torque [N*m]"]
    for t in DRIVE_TEMPERATURES:
        opening = [float(a) for a in range(0, 91, 2)]
        closing = [float(a) for a in range(90, -1, -2)]  # the turnaround read again
        for phi, sign in [(a, -1.0) for a in opening] + [(a, 1.0) for a in closing]:
            torque = drive_spring(phi) + sign * drive_friction(phi, t)
            torque += float(rng.normal(0.0, DRIVE_NOISE))
            rows.append(f"{t:g},{phi:g},{torque:.4f}")
    return "\n".join(rows) + "\n"


FLUID_TEMPERATURES = (-15.0, 10.0, 40.0)
FLUID_SPEEDS = tuple(float(w) for w in np.logspace(-2.0, 0.0, 7))
FLUID_TORQUE, FLUID_SPEED, FLUID_ACTIVATION = 1.8, 0.1, 2040.0  # N*m, rad/s, K
FLUID_NOISE = 0.02  # relative


def fluid_exponent(t: float) -> float:
    """n(T) of the example damper."""
    return 0.45 - 0.0006 * (t - 25.0)


def fluid_torque(w: float, t: float) -> float:
    """The example damper's torque, typed from its definition [N*m]."""
    factor = float(np.exp(FLUID_ACTIVATION * (1.0 / (t + 273.15) - 1.0 / 298.15)))
    return float(FLUID_TORQUE * factor * (w / FLUID_SPEED) ** fluid_exponent(t))


def fluid_bench_text() -> str:
    """The bench points, with the reading error."""
    rng = np.random.default_rng(20261201)
    rows = ["temperature [degC],speed [rad/s],torque [N*m]"]
    for t in FLUID_TEMPERATURES:
        for w in FLUID_SPEEDS:
            torque = fluid_torque(w, t) * float(np.exp(rng.normal(0.0, FLUID_NOISE)))
            rows.append(f"{t:g},{w:.5g},{torque:.5g}")
    return "\n".join(rows) + "\n"


def test_example_files_are_what_the_generators_write() -> None:
    assert LIFE_TEST.read_text(encoding="utf-8") == life_test_text()
    assert DRIVE_TEST.read_text(encoding="utf-8") == drive_test_text()
    assert FLUID_BENCH.read_text(encoding="utf-8") == fluid_bench_text()


if __name__ == "__main__":
    LIFE_TEST.write_text(life_test_text(), encoding="utf-8")
    DRIVE_TEST.write_text(drive_test_text(), encoding="utf-8")
    FLUID_BENCH.write_text(fluid_bench_text(), encoding="utf-8")
    print(f"wrote {LIFE_TEST}, {DRIVE_TEST} and {FLUID_BENCH}")

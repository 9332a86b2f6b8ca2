"""Drive-test reduction: the spring, the friction and the available torque of a hinge.

On a torque bench the hinge is driven slowly open, then closed (docs/qualification.md).
Opening, the spring drives and friction resists, so the bench reads the spring torque
less the friction; closing, the bench drives the hinge against the spring and the
friction, and reads the spring torque plus the friction::

    T_open(phi)  = T_spring(phi) - F(phi)        T_close(phi) = T_spring(phi) + F(phi)
    T_spring     = (T_open + T_close) / 2        F = (T_close - T_open) / 2
    available    = min over phi of T_open        (usually at the end of travel)

The two curves are interpolated linearly onto the union of their angles inside the range
both cover (the deployed angle counted from the smallest). The spring law is the
least-squares line of T_spring against angle (:func:`ecdsim.characterize.linefit.fit_line`:
start and end torque with 95 % intervals) and the table of T_spring itself; the friction
against angle is F; with several temperatures the mean friction of each is fitted by the
line ``FS_T = slope * T + at_0C`` (:data:`ecdsim.characterize.templaws.FRICTION_LINE`),
the config's ``[load] system_friction``.

CSV columns (any unit in brackets): ``angle`` (increasing as the hinge opens),
``torque`` (the bench reading, positive in the deploying direction), optional
``temperature`` (a file per temperature, or one file with a column). Rows in the order
recorded: the run opens to the largest angle, then closes; the first reading at the
largest angle ends the opening run, so record that angle again as the closing run's first
row for the two to cover the whole travel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ecdsim._types import FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.characterize.csvdata import (
    Column,
    Table,
    above_absolute_zero,
    read_table,
    temperature_groups,
)
from ecdsim.characterize.findings import FitWarning
from ecdsim.characterize.linefit import LineFit, LineFitError, fit_line
from ecdsim.characterize.stats import Estimate
from ecdsim.characterize.templaws import FRICTION_LINE, LawFit, LawFitError, fit_law
from ecdsim.config.units import ANGLE, TEMPERATURE, TORQUE

COLUMNS = (
    Column("angle", ANGLE, "angle_rad"),
    Column("torque", TORQUE, "torque_Nm"),
    Column("temperature", TEMPERATURE, "temperature_C", required=False,
           check=above_absolute_zero),
)  # fmt: skip

# A spring that departs from its straight line by more than this fraction of its mean
# torque is written as a table by default (a line would misstate it by that much).
LINEAR_TOLERANCE = 0.02
# The most rows of a spring table written to a config (equal steps of the travel).
TABLE_ROWS = 13


class DriveTestError(ValueError):
    """A temperature's data cannot be reduced; the message says why."""


@dataclass(frozen=True)
class DriveCurves:
    """One temperature's drive test on a common angle grid.

    Attributes
    ----------
    temperature : T [degC]
    rows : file rows of the temperature's points
    angle : deployed angle of the grid, from the smallest angle both runs cover [rad]
    start_angle : the bench angle that is deployed angle 0 [rad]
    opening, closing : the bench torque of each run on the grid [N*m]
    spring : T_spring = (opening + closing) / 2 [N*m]
    friction : F = (closing - opening) / 2 [N*m]
    line : the least-squares line of the spring against angle
    start_torque, end_torque : the line at 0 and at the travel [N*m], with 95 % intervals
    linear_deviation : the largest |spring - line| over the mean spring torque [-]
    available : the smallest opening torque [N*m]
    available_angle : where it occurs [rad]
    """

    temperature: float
    rows: tuple[int, ...]
    angle: FloatArray
    start_angle: float
    opening: FloatArray
    closing: FloatArray
    spring: FloatArray
    friction: FloatArray
    line: LineFit
    start_torque: Estimate
    end_torque: Estimate
    linear_deviation: float
    available: float
    available_angle: float

    @property
    def travel(self) -> float:
        """The angle both runs cover [rad]."""
        return float(self.angle[-1])

    @property
    def mean_friction(self) -> Estimate:
        """The friction's mean over the grid with its standard error and 95 % interval
        (the points taken as independent; the grid's interpolated points are not, so the
        interval is indicative)."""
        n = self.friction.size
        mean = float(np.mean(self.friction))
        if n < 2:
            return Estimate(mean, None, None)
        se = float(np.std(self.friction, ddof=1)) / math.sqrt(n)
        from ecdsim.characterize.stats import t_quantile

        q = t_quantile(n - 1)
        return Estimate(mean, se, (mean - q * se, mean + q * se))

    def table(self, rows: int = TABLE_ROWS) -> list[tuple[float, float]]:
        """(deployed angle [rad], spring torque [N*m]) at ``rows`` equal steps of the
        travel, interpolated in the reduced spring."""
        steps = np.linspace(0.0, self.travel, rows)
        return [
            (float(a), float(t))
            for a, t in zip(steps, np.interp(steps, self.angle, self.spring), strict=True)
        ]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (SI)."""
        friction = self.mean_friction
        return {
            "temperature_C": self.temperature,
            "rows": list(self.rows),
            "start_angle_rad": self.start_angle,
            "travel_rad": self.travel,
            "start_torque_Nm": self.start_torque.value,
            "start_torque_ci95_Nm": self.start_torque.interval(),
            "end_torque_Nm": self.end_torque.value,
            "end_torque_ci95_Nm": self.end_torque.interval(),
            "spring_r_squared": self.line.r_squared,
            "linear_deviation": self.linear_deviation,
            "mean_friction_Nm": friction.value,
            "mean_friction_ci95_Nm": friction.interval(),
            "min_friction_Nm": float(np.min(self.friction)),
            "max_friction_Nm": float(np.max(self.friction)),
            "available_torque_Nm": self.available,
            "available_angle_rad": self.available_angle,
            "points": [
                {
                    "angle_rad": float(a),
                    "opening_Nm": float(o),
                    "closing_Nm": float(c),
                    "spring_Nm": float(s),
                    "friction_Nm": float(f),
                }
                for a, o, c, s, f in zip(
                    self.angle, self.opening, self.closing, self.spring, self.friction,
                    strict=True,
                )
            ],
        }  # fmt: skip


def split_runs(
    angle: FloatArray, torque: FloatArray
) -> tuple[tuple[FloatArray, FloatArray], tuple[FloatArray, FloatArray]]:
    """The opening and the closing run of one temperature's rows (in file order): up to
    the first reading at the largest angle, and every row after it; each sorted by angle.
    DriveTestError where a run has fewer than two distinct angles."""
    turn = int(np.argmax(angle))
    runs = []
    # The first reading at the largest angle ends the opening run; the closing run is
    # every row after it (record the turnaround angle again as the closing run's first
    # row for it to cover the whole travel).
    for name, part in (("opening", slice(0, turn + 1)), ("closing", slice(turn + 1, None))):
        a, t = angle[part], torque[part]
        if np.unique(a).size < 2:
            raise DriveTestError(
                f"the {name} run has fewer than two distinct angles: record the hinge driven "
                "open to its largest angle, then closed (rows in the order recorded)"
            )
        order = np.argsort(a, kind="stable")
        runs.append((a[order], t[order]))
    return runs[0], runs[1]


def _average_repeats(angle: FloatArray, torque: FloatArray) -> tuple[FloatArray, FloatArray]:
    """One torque per angle (the mean of readings at the same angle), for interpolation."""
    unique, inverse = np.unique(angle, return_inverse=True)
    sums = np.bincount(inverse, weights=torque)
    counts = np.bincount(inverse)
    return as_float(unique), as_float(sums / counts)


def reduce_curves(temperature: float, rows: tuple[int, ...], angle: FloatArray,
                  torque: FloatArray) -> DriveCurves:  # fmt: skip
    """One temperature's drive test (module docstring); DriveTestError if it cannot be."""
    (oa, ot), (ca, ct) = split_runs(angle, torque)
    oa, ot = _average_repeats(oa, ot)
    ca, ct = _average_repeats(ca, ct)
    low, high = max(oa[0], ca[0]), min(oa[-1], ca[-1])
    if not high > low:
        raise DriveTestError("the opening and closing runs cover no common range of angle")
    grid = np.unique(np.concatenate([oa, ca]))
    grid = grid[(grid >= low) & (grid <= high)]
    opening = as_float(np.interp(grid, oa, ot))
    closing = as_float(np.interp(grid, ca, ct))
    spring = as_float(0.5 * (opening + closing))
    friction = as_float(0.5 * (closing - opening))
    deployed = as_float(grid - low)
    try:
        line = fit_line(deployed, spring)
    except LineFitError as exc:
        raise DriveTestError(f"no spring line: {exc}") from None
    travel = float(deployed[-1])
    start, end = _line_ends(line, travel)
    residual = spring - (line.intercept.value + line.slope.value * deployed)
    deviation = float(np.max(np.abs(residual)) / abs(float(np.mean(spring))))
    k = int(np.argmin(opening))
    return DriveCurves(
        temperature=temperature,
        rows=rows,
        angle=deployed,
        start_angle=float(low),
        opening=opening,
        closing=closing,
        spring=spring,
        friction=friction,
        line=line,
        start_torque=start,
        end_torque=end,
        linear_deviation=deviation,
        available=float(opening[k]),
        available_angle=float(deployed[k]),
    )


def _line_ends(line: LineFit, travel: float) -> tuple[Estimate, Estimate]:
    """The line at 0 (its intercept) and at the travel, with 95 % intervals from its
    covariance (Student t, the line's degrees of freedom)."""
    start = line.intercept
    value = line.intercept.value + line.slope.value * travel
    covariance = line.statistics.covariance
    if covariance is None or start.ci95 is None or start.standard_error is None:
        return start, Estimate(value, None, None)
    g = np.array([1.0, travel])
    se = math.sqrt(max(float(g @ covariance @ g), 0.0))
    q = (start.ci95[1] - start.value) / start.standard_error if start.standard_error else 0.0
    return start, Estimate(value, se, (value - q * se, value + q * se))


@dataclass(frozen=True)
class DriveTestResult:
    """Everything a drive-test reduction found.

    Attributes
    ----------
    table : the data read (usable rows, bad-row report, notes)
    curves : one reduction per temperature, coldest first
    failed : (temperature, rows, reason) of temperatures that could not be reduced
    friction_law : FS_T = slope * T + at_0C over the temperatures; None with one
    warnings : findings (a spring that is not straight, negative friction, ...)
    """

    table: Table
    curves: tuple[DriveCurves, ...]
    failed: tuple[tuple[float, tuple[int, ...], str], ...]
    friction_law: LawFit | None
    warnings: tuple[FitWarning, ...]

    @property
    def available(self) -> tuple[float, float, float]:
        """The drive's minimum available torque over every temperature [N*m], with its
        temperature [degC] and deployed angle [rad]."""
        worst = min(self.curves, key=lambda c: c.available)
        return worst.available, worst.temperature, worst.available_angle

    def reference(self, temperature: float = 25.0) -> DriveCurves:
        """The temperature's reduction closest to ``temperature`` [degC] (the spring the
        config holds, at its reference temperature)."""
        return min(self.curves, key=lambda c: (abs(c.temperature - temperature), c.temperature))

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of ``ecdsim fit drive-test --json`` (docs/qualification.md)."""
        available, at_t, at_angle = self.available
        law = self.friction_law
        return {
            "ecdsim_version": __version__,
            "kind": "drive_test",
            "source": self.table.source,
            "source_sha256": self.table.sha256,
            "temperatures": [c.to_dict() for c in self.curves],
            "failed_temperatures": [
                {"temperature_C": t, "rows": list(rows), "error": why}
                for t, rows, why in self.failed
            ],
            "available_torque": {
                "value_Nm": available,
                "temperature_C": at_t,
                "angle_rad": at_angle,
            },
            "friction_law": None if law is None else law.to_dict(),
            "bad_rows": [b.to_dict() for b in self.table.bad_rows],
            "warnings": [w.to_dict() for w in self.warnings],
        }


def read_drive_test(path: str | Path) -> Table:
    """The usable rows of a drive-test CSV (ConfigError for a file that cannot be used)."""
    return read_table(path, COLUMNS)


def _findings(curves: DriveCurves) -> list[FitWarning]:
    t = curves.temperature
    out = []
    if curves.linear_deviation > LINEAR_TOLERANCE:
        out.append(
            FitWarning(
                "spring_not_linear",
                f"at {t:g} degC the spring departs from its straight line by "
                f"{100 * curves.linear_deviation:.3g} % of its mean torque: the -o file "
                "holds it as a spring_table",
                t,
            )
        )
    if float(np.mean(curves.friction)) < 0.0:
        out.append(
            FitWarning(
                "negative_friction",
                f"at {t:g} degC the opening curve lies above the closing one (mean friction "
                f"{float(np.mean(curves.friction)):.4g} N*m < 0): check that the torque is "
                "positive in the deploying direction and that the hinge opened first",
                t,
            )
        )
    return out


def fit_drive_test(path: str | Path) -> DriveTestResult:
    """Reduce a drive-test CSV, one temperature at a time (module docstring)."""
    table = read_drive_test(path)
    angle, torque = table.values["angle"], table.values["torque"]
    temps = table.values.get("temperature")
    groups = temperature_groups(temps) if temps is not None else [(25.0, np.arange(angle.size))]
    curves: list[DriveCurves] = []
    failed: list[tuple[float, tuple[int, ...], str]] = []
    warnings: list[FitWarning] = []
    if temps is None:
        warnings.append(
            FitWarning(
                "no_temperature",
                "no temperature column: the test is taken at 25 degC (the spring's "
                "reference temperature)",
            )
        )
    for temperature, members in groups:
        members = np.sort(members)  # file order within the temperature
        rows = tuple(int(r) for r in table.rows[members])
        try:
            reduced = reduce_curves(temperature, rows, angle[members], torque[members])
        except DriveTestError as exc:
            failed.append((temperature, rows, str(exc)))
            continue
        curves.append(reduced)
        warnings.extend(_findings(reduced))
    law = None
    if len(curves) >= 2:
        try:
            law = fit_law(
                FRICTION_LINE, [c.temperature for c in curves], [c.mean_friction for c in curves]
            )
        except LawFitError as exc:
            warnings.append(FitWarning("friction_law", f"no friction law: {exc}"))
    return DriveTestResult(table, tuple(curves), tuple(failed), law, tuple(warnings))

"""Figures of the qualification reductions: the drive test and the fluid damper's bench
fit (docs/qualification.md). Each returns a matplotlib Figure, never shows it; matplotlib
is imported inside the functions."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ecdsim.characterize.drivetest import DriveTestResult
from ecdsim.plotting import save_figure, temperature_colors
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_drive_test(result: DriveTestResult, units: UnitSystem = "si") -> Figure:
    """Bench torque opening and closing, the spring (their mean) and the friction (half
    their difference) against deployed angle, per temperature; the available torque
    (the smallest opening torque) marked."""
    from matplotlib.figure import Figure

    u = Shown(units)
    fig = Figure(figsize=(7.5, 7.0), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    colors = temperature_colors(len(result.curves))
    for curves, color in zip(result.curves, colors, strict=True):
        degrees = np.degrees(curves.angle)
        label = u.text(curves.temperature, "temperature")
        top.plot(degrees, u.values(curves.opening, "torque"), ":", color=color)
        top.plot(degrees, u.values(curves.closing, "torque"), "--", color=color)
        top.plot(degrees, u.values(curves.spring, "torque"), "-", color=color,
                 label=f"{label}: spring (mean)")  # fmt: skip
        top.plot(math.degrees(curves.available_angle), u.value(curves.available, "torque"),
                 "v", color=color, markersize=8)  # fmt: skip
        bottom.plot(degrees, u.values(curves.friction, "torque"), "-", color=color, label=label)
    top.plot([], [], ":", color="grey", label="opening (spring - friction)")
    top.plot([], [], "--", color="grey", label="closing (spring + friction)")
    top.plot([], [], "v", color="grey", label="available: smallest opening torque")
    top.set_title("Drive test: bench torque against deployed angle")
    top.set_ylabel(u.head("torque", "torque"))
    top.grid(True, alpha=0.3)
    top.legend(fontsize="small")
    bottom.set_title("Friction: half the closing minus opening torque")
    bottom.set_xlabel("deployed angle [deg]")
    bottom.set_ylabel(u.head("friction", "torque"))
    bottom.grid(True, alpha=0.3)
    bottom.legend(fontsize="small", loc="lower left", ncols=3)
    return fig


def write_drive_test_plots(
    result: DriveTestResult, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """Write the drive-test figure into ``folder``; its path."""
    return [save_figure(plot_drive_test(result, units), Path(folder) / "drive_test.png")]

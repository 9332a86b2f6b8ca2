"""Figures of the qualification reductions: the drive test and the fluid damper's bench
fit (docs/qualification.md). Each returns a matplotlib Figure, never shows it; matplotlib
is imported inside the functions."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ecdsim.characterize.drivetest import DriveTestResult
from ecdsim.characterize.fluidfit import FluidFitResult
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


def plot_fluid_fit(result: FluidFitResult, units: UnitSystem = "si") -> Figure:
    """The bench points and each temperature's power law on log-log axes; below, the
    torque at the reference speed and the exponent against temperature with their 95 %
    intervals and the fitted laws."""
    from matplotlib.figure import Figure

    u = Shown(units)
    fig = Figure(figsize=(7.5, 8.0), layout="constrained")
    grid = fig.add_gridspec(2, 2, height_ratios=(3, 2))
    top = fig.add_subplot(grid[0, :])
    left = fig.add_subplot(grid[1, 0])
    right = fig.add_subplot(grid[1, 1])
    colors = temperature_colors(len(result.fits))
    for fit, color in zip(result.fits, colors, strict=True):
        label = u.text(fit.temperature, "temperature")
        top.loglog(fit.speed, u.values(fit.torque, "torque"), "o", color=color, markersize=4)
        w = np.geomspace(float(fit.speed.min()), float(fit.speed.max()), 50)
        line = fit.reference_torque.value * (w / fit.reference_speed) ** fit.exponent.value
        top.loglog(w, u.values(line, "torque"), "-", color=color,
                   label=f"{label}: n = {fit.exponent.value:.3f}")  # fmt: skip
    top.set_title("Fluid damper bench: torque against speed, power law per temperature")
    top.set_xlabel("speed [rad/s]")
    top.set_ylabel(u.head("torque", "torque"))
    top.grid(True, which="both", alpha=0.3)
    top.legend(fontsize="small")
    temps = np.array([f.temperature for f in result.fits])
    shown_t = u.values(temps, "temperature")
    span = np.linspace(float(temps.min()), float(temps.max()), 60)
    for ax, estimates, law, title, ylabel, transform in (
        (left, [f.reference_torque for f in result.fits], result.torque_law,
         f"torque at {result.reference_speed:g} rad/s", u.head("torque", "torque"), np.exp),
        (right, [f.exponent for f in result.fits], result.exponent_law,
         "exponent n", "n [-]", None),
    ):  # fmt: skip
        values = np.array([e.value for e in estimates])
        low = np.array([e.ci95[0] if e.ci95 else e.value for e in estimates])
        high = np.array([e.ci95[1] if e.ci95 else e.value for e in estimates])
        scale = (lambda v: u.values(v, "torque")) if transform is not None else (lambda v: v)
        shown_values = scale(values)
        errors = [shown_values - scale(low), scale(high) - shown_values]
        ax.errorbar(shown_t, shown_values, yerr=errors, fmt="o", capsize=3,
                    label="per temperature")  # fmt: skip
        if law is not None:
            curve = law(span)
            ax.plot(u.values(span, "temperature"),
                    scale(transform(curve) if transform is not None else curve),
                    "-", label=f"law ({law.law.name})")  # fmt: skip
        ax.set_title(title, fontsize="medium")
        ax.set_xlabel(u.head("T", "temperature"))
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    return fig


def write_fluid_fit_plots(
    result: FluidFitResult, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """Write the fluid-damper fit figure into ``folder``; its path."""
    return [save_figure(plot_fluid_fit(result, units), Path(folder) / "fluid_damper_fit.png")]

"""Figures of a characterisation: each function returns a matplotlib Figure, never shows it.

* :func:`plot_torque_speed`: torque against speed with the fitted line per temperature
  (the paper's Figure 8), outliers ringed;
* :func:`plot_parameters`: BECD and FECD against temperature with 95 % intervals and the
  fitted laws with their 95 % confidence bands (:func:`plot_parameter`: one of the two);
* :func:`plot_line_residuals` and :func:`plot_trace_residuals`: residuals;
* :func:`plot_traces`: recorded and fitted deployments.

Each takes the display unit system (``units``, "si" or "us"; :mod:`ecdsim.units_display`);
those of one axes also ``ax``, a matplotlib Axes to draw on instead of a new figure (the
notebook API's ``plot(ax=...)``). matplotlib is imported inside the functions (Agg
canvas, no display needed).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ecdsim._types import ArrayLike
from ecdsim.characterize.droptest import DropTestResult
from ecdsim.characterize.stats import Estimate
from ecdsim.characterize.templaws import TemperatureLaws
from ecdsim.characterize.tracefit import TraceResult, model_angle
from ecdsim.plotting import save_figure, target, temperature_colors
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_LAW_STYLES = {"linear": "-", "resistivity": "--"}


def _figure(width: float = 7.5, height: float = 4.8) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _finish(ax: Axes, title: str, xlabel: str, ylabel: str) -> None:
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")


def plot_torque_speed(
    result: DropTestResult, units: UnitSystem = "si", ax: Axes | None = None
) -> Figure:
    """Drive torque against (corrected) speed with each temperature's line (paper Fig. 8),
    on ``ax`` if given (its figure is returned), else on a new figure."""
    u = Shown(units)
    fig, ax = target(ax)
    colors = temperature_colors([f.temperature for f in result.fits])
    top = max((float(np.max(f.corrected)) for f in result.fits), default=1.0) * 1.1
    speeds = np.linspace(0.0, top, 50)
    for fit, color in zip(result.fits, colors, strict=True):
        b, f = fit.line.slope, fit.line.intercept
        ax.plot(fit.corrected, u.values(fit.torque, "torque"), "o", color=color, markersize=4)
        ax.plot(
            speeds,
            u.values(f.value + b.value * speeds, "torque"),
            color=color,
            label=(
                f"{u.text(fit.temperature, 'temperature')}: BECD "
                f"{u.text(b.value, 'damping_rate')}, FECD {Shown(units, 3).text(f.value, 'torque')}"
            ),
        )
        out = fit.line.outliers
        if np.any(out):
            ax.plot(
                fit.corrected[out],
                u.values(fit.torque[out], "torque"),
                "o",
                markersize=11,
                markerfacecolor="none",
                markeredgecolor="black",
                label=f"outlier ({u.text(fit.temperature, 'temperature')})",
            )
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    _finish(
        ax, "Drop test: torque against speed", "speed [rad/s]", u.head("drive torque", "torque")
    )
    return fig


def _error_bars(
    ax: Axes, temperatures: ArrayLike, values: Sequence[Estimate], u: Shown, kind: str
) -> None:
    t = u.values(np.asarray(temperatures, dtype=float), "temperature")
    scale = u.value(1.0, kind) - u.value(0.0, kind)  # a length on the axis: no offset
    y = u.values(np.array([v.value for v in values]), kind)
    low = scale * np.array([v.value - v.ci95[0] if v.ci95 else 0.0 for v in values])
    high = scale * np.array([v.ci95[1] - v.value if v.ci95 else 0.0 for v in values])
    ax.errorbar(t, y, yerr=[low, high], fmt="o", color="black", capsize=3, label="per temperature")


def plot_parameters(
    temperatures: Sequence[float],
    damping: Sequence[Estimate],
    friction: Sequence[Estimate],
    laws: TemperatureLaws | None,
    units: UnitSystem = "si",
) -> Figure:
    """BECD and FECD against temperature: 95 % intervals, laws and their 95 % bands.

    Parameters
    ----------
    temperatures : the fitted temperatures [degC]
    damping : BECD at each [N*m*s/rad]
    friction : FECD at each [N*m]
    laws : the laws over temperature, or None
    units : the display unit system
    """
    fig = _figure(7.5, 7.0)
    top, bottom = fig.subplots(2, 1, sharex=True)
    _parameter_panel(top, "damping_rate", temperatures, damping, laws, Shown(units), False)
    _parameter_panel(bottom, "friction", temperatures, friction, laws, Shown(units), True)
    return fig


# Each parameter's panel: its title, its symbol and the kind of its values.
PARAMETERS = {
    "damping_rate": ("Damping rate against temperature (95 % intervals)", "BECD", "damping_rate"),
    "friction": ("Friction against temperature", "FECD", "torque"),
}


def plot_parameter(
    quantity: str,
    temperatures: Sequence[float],
    values: Sequence[Estimate],
    laws: TemperatureLaws | None,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """One panel of :func:`plot_parameters`: ``quantity`` (``"damping_rate"``, BECD
    [N*m*s/rad], or ``"friction"``, FECD [N*m]) against temperature with its 95 %
    intervals, law and band, on ``ax`` if given, else on a new figure."""
    fig, ax = target(ax)
    _parameter_panel(ax, quantity, temperatures, values, laws, Shown(units), True)
    return fig


def _parameter_panel(
    ax: Axes,
    quantity: str,
    temperatures: Sequence[float],
    values: Sequence[Estimate],
    laws: TemperatureLaws | None,
    u: Shown,
    xlabel: bool,
) -> None:
    title, symbol, kind = PARAMETERS[quantity]
    t = np.asarray(temperatures, dtype=float)
    span = max(float(np.ptp(t)), 1.0)
    grid = np.linspace(float(np.min(t)) - 0.1 * span, float(np.max(t)) + 0.1 * span, 100)
    _error_bars(ax, t, values, u, kind)
    x = u.values(grid, "temperature")
    curves = []
    if laws is not None and quantity == "damping_rate":
        curves = [
            (f, _LAW_STYLES.get(name, ":"), f"{name} law") for name, f in laws.damping.items()
        ]
    elif laws is not None and laws.friction is not None:
        curves = [(laws.friction, "-", "line")]
    for law, style, label in curves:
        line = ax.plot(x, u.values(law(grid), kind), style, label=label)[0]
        band = law.band(grid)
        if band is not None:
            low, high = (u.values(edge, kind) for edge in band)
            ax.fill_between(x, low, high, color=line.get_color(), alpha=0.15)
    _finish(ax, title, u.head("temperature", "temperature") if xlabel else "", u.head(symbol, kind))


def plot_line_residuals(
    result: DropTestResult, units: UnitSystem = "si", ax: Axes | None = None
) -> Figure:
    """Residual torque of each drop-test point against its speed, per temperature (on
    ``ax`` if given, else on a new figure)."""
    u = Shown(units)
    fig, ax = target(ax)
    temps = [fit.temperature for fit in result.fits]
    for fit, color in zip(result.fits, temperature_colors(temps), strict=True):
        # Points, not a line: residuals are independent scatter, and a line joining them
        # would suggest a trend between tests that the data do not have.
        ax.plot(
            fit.corrected,
            u.values(fit.torque - fit.line.fitted, "torque"),
            "o",
            color=color,
            markersize=5,
            label=u.text(fit.temperature, "temperature"),
        )
    ax.axhline(0.0, color="black", linewidth=0.8)
    _finish(
        ax,
        "Drop test: residuals of the lines",
        "speed [rad/s]",
        u.head("residual torque", "torque"),
    )
    return fig


def plot_traces(result: TraceResult, n_points: int = 400, units: UnitSystem = "si") -> Figure:
    """Recorded angle against time (dots) and the fitted exact solution (lines)."""
    u = Shown(units)
    fig = _figure()
    ax = fig.add_subplot()
    curves = result.curves
    for curve, color in zip(
        curves, temperature_colors([c.trace.temperature for c in curves]), strict=True
    ):
        trace = curve.trace
        times = np.linspace(0.0, float(np.max(trace.time)), n_points)
        ax.plot(trace.time, np.degrees(trace.angle), ".", color=color, markersize=3)
        ax.plot(
            times,
            np.degrees(model_angle(curve.problem, times)),
            color=color,
            label=f"{u.text(trace.temperature, 'temperature')}, fitted (exact solution)",
        )
    _finish(ax, "Recorded deployments and fits", "time since release [s]", "angle [deg]")
    return fig


def plot_trace_residuals(result: TraceResult, units: UnitSystem = "si") -> Figure:
    """Recorded minus fitted angle against time, per trace."""
    u = Shown(units)
    fig = _figure()
    ax = fig.add_subplot()
    curves = result.curves
    temps = [curve.trace.temperature for curve in curves]
    for curve, color in zip(curves, temperature_colors(temps), strict=True):
        ax.plot(
            curve.trace.time,
            np.degrees(curve.residuals),
            "o",
            color=color,
            markersize=3,
            label=u.text(curve.trace.temperature, "temperature"),
        )
    ax.axhline(0.0, color="black", linewidth=0.8)
    _finish(ax, "Trace fit residuals", "time since release [s]", "residual angle [deg]")
    return fig


def write_drop_test_plots(
    result: DropTestResult, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """Write the drop-test figures as PNG files into ``folder``, in ``units``; their paths."""
    out = Path(folder)
    fits = result.fits
    return [
        save_figure(plot_torque_speed(result, units), out / "torque_vs_speed_fit.png"),
        save_figure(
            plot_parameters(
                [f.temperature for f in fits],
                [f.line.slope for f in fits],
                [f.line.intercept for f in fits],
                result.laws,
                units,
            ),
            out / "parameters_vs_temperature.png",
        ),
        save_figure(plot_line_residuals(result, units), out / "drop_test_residuals.png"),
    ]


def write_trace_plots(
    result: TraceResult, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """Write the trace-fit figures as PNG files into ``folder``, in ``units``; their paths."""
    out = Path(folder)
    written = [
        save_figure(plot_traces(result, units=units), out / "trace_fit.png"),
        save_figure(plot_trace_residuals(result, units), out / "trace_residuals.png"),
    ]
    if result.fits:
        fits = result.fits
        written.append(
            save_figure(
                plot_parameters(
                    [f.temperature for f in fits],
                    [f.damping_rate for f in fits],
                    [f.friction for f in fits],
                    result.laws,
                    units,
                ),
                out / "parameters_vs_temperature.png",
            )
        )
    return written

"""Plots of results. Every function returns a matplotlib Figure and never shows it.

matplotlib is imported lazily (inside the functions) so that the CLI starts fast; the
non-interactive Agg backend is used, so plotting works on machines with no display.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal, cast

import numpy as np

from ecdsim.atomic import write_with
from ecdsim.deployment import Prediction
from ecdsim.methods import SOLVERS
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_LINESTYLES = {"exact": "-", "paper": "--"}


def _figure(width: float = 7.5, height: float = 4.8) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _target(ax: Axes | None) -> tuple[Figure, Axes]:
    """The figure and axes to draw on: the caller's ``ax`` (and its figure), or new ones."""
    if ax is not None:
        return cast("Figure", ax.figure), ax
    fig = _figure()
    return fig, fig.add_subplot()


def plot_title(system: str, what: str, width: int = 70) -> str:
    """``"system: what"``, wrapped so that a long system name is not cut off the figure."""
    import textwrap

    return "\n".join(textwrap.wrap(f"{system}: {what}", width))


def time_span(prediction: Prediction) -> float:
    """The length of a time axis for plots of a prediction [s].

    1.1 times the longest finite deployment time over every method and temperature; if
    every case stalls, five times the largest ``B / k`` (damping rate over the spring's
    mean torque drop per radian), a time scale of the motion towards the stall.
    """
    finite = [
        t
        for s in prediction.solutions.values()
        for t in np.ravel(s.deployment_time)
        if np.isfinite(t)
    ]
    if finite:
        return 1.1 * max(finite)
    problem = prediction.problem
    drop = np.abs(problem.torques[0] - problem.torques[-1]) / problem.travel
    scale = problem.damping_rate / np.where(drop > 0.0, drop, 1.0)
    span = float(5.0 * np.max(scale))
    # No damping and no finite time (nothing solved, nothing to scale by): one second.
    return span if span > 0.0 else 1.0


def _plot_against_time(
    prediction: Prediction,
    quantity: Literal["angle", "speed"],
    ylabel: str,
    title: str,
    n_points: int,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """One line per (method, temperature) of a trajectory field against time (on ``ax``
    if given, else on a new figure)."""
    u = Shown(units)
    fig, ax = _target(ax)
    times = np.linspace(0.0, time_span(prediction), n_points)
    temps = np.ravel(prediction.temperatures)
    colors = temperature_colors(len(temps))
    for name, solution in prediction.solutions.items():
        trajectory = prediction.trajectory(name, times)
        solved = np.ravel(np.broadcast_to(solution.solved_mask, prediction.temperatures.shape))
        if quantity == "angle":
            values = np.degrees(trajectory.angle.reshape(len(times), -1))
        else:
            values = trajectory.speed.reshape(len(times), -1)
        for j, temp in enumerate(temps):
            if not solved[j]:
                # No curve to draw, but the case must not vanish silently from the legend.
                ax.plot(
                    [],
                    [],
                    _LINESTYLES.get(name, ":"),
                    color=colors[j],
                    label=f"{u.text(temp, 'temperature')}, {SOLVERS[name].label}: "
                    "not solved (BECD = 0)",
                )
                continue
            ax.plot(
                times,
                values[:, j],
                _LINESTYLES.get(name, ":"),
                color=colors[j],
                label=f"{u.text(temp, 'temperature')}, {SOLVERS[name].label}",
            )
    ax.set_xlabel("time since release [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(plot_title(prediction.system.name, title))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def plot_deployment(
    prediction: Prediction,
    n_points: int = 400,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """Deployed angle against time at each temperature, by each method (paper Fig. 4-6)."""
    return _plot_against_time(
        prediction, "angle", "deployed angle [deg]", "angle against time", n_points, units, ax
    )


def plot_speed(
    prediction: Prediction,
    n_points: int = 400,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """Input-shaft speed against time at each temperature, by each method."""
    return _plot_against_time(
        prediction, "speed", "input shaft speed [rad/s]", "speed against time", n_points, units, ax
    )


def plot_torque_speed(
    prediction: Prediction,
    n_points: int = 50,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """The ECD's input torque against speed at each temperature (paper Fig. 8).

    Each line is ``T = FECD_T + BECD_T * omega`` (Eq. 5 inverted); the markers show the
    deployment's operating range, from the start to the end speed of the exact solution.
    """
    u = Shown(units, digits=3)
    fig, ax = _target(ax)
    ecd = prediction.ecd
    temps = np.ravel(prediction.temperatures)
    damping = np.ravel(np.broadcast_to(ecd.ecd_damping_rate, prediction.temperatures.shape))
    friction = np.ravel(np.broadcast_to(ecd.ecd_friction, prediction.temperatures.shape))
    reference = prediction.solutions.get("exact") or next(iter(prediction.solutions.values()))
    start = np.ravel(reference.start_speed)
    end = np.ravel(reference.end_speed)
    top = 1.2 * float(np.max(start)) if np.max(start) > 0 else 1.0
    speeds = np.linspace(0.0, top, n_points)
    colors = temperature_colors(len(temps))
    for j, temp in enumerate(temps):
        ax.plot(
            speeds,
            u.value(friction[j] + damping[j] * speeds, "torque"),
            color=colors[j],
            label=f"{Shown(units).text(temp, 'temperature')}: "
            f"BECD {u.text(damping[j], 'damping_rate')}, FECD {u.text(friction[j], 'torque')}",
        )
        ends = np.array([end[j], start[j]])
        ax.plot(ends, u.value(friction[j] + damping[j] * ends, "torque"), "o", color=colors[j])
    ax.set_xlabel("input shaft speed [rad/s]")
    ax.set_ylabel(u.head("ECD reaction torque", "torque"))
    ax.set_title(plot_title(prediction.system.name, "ECD torque against speed"))
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def temperature_colors(n: int) -> list[tuple[float, float, float, float]]:
    """``n`` RGBA colours from cold blue to hot red, one per temperature in rising order."""
    from matplotlib import colormaps

    # Cold blue to hot red through green: every temperature stays readable on white,
    # which a diverging map with a pale middle (coolwarm) is not.
    cmap = colormaps["turbo"]
    return [cmap(x) for x in np.linspace(0.1, 0.9, n)] if n > 1 else [cmap(0.1)]


def save_figure(fig: Figure, path: str | Path, dpi: int = 120) -> Path:
    """Save a figure atomically; the format follows the file's suffix (PNG, SVG, PDF)."""
    target = Path(path)
    fmt = target.suffix.lstrip(".") or "png"
    return write_with(target, lambda stream: fig.savefig(stream, format=fmt, dpi=dpi))


def write_deployment_plots(
    prediction: Prediction, folder: str | Path, units: UnitSystem = "si"
) -> list[Path]:
    """Write the standard plots of a prediction as PNG files into ``folder``, in ``units``.

    The dynamic method's own plots (events marked, damper temperature) are
    :func:`ecdsim.plotting_dynamic.write_dynamic_plots`, a layer above this module.
    """
    out = Path(folder)
    return [
        save_figure(plot_deployment(prediction, units=units), out / "angle_vs_time.png"),
        save_figure(plot_torque_speed(prediction, units=units), out / "torque_vs_speed.png"),
    ]

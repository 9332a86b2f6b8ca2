"""Plots of results. Every function returns a matplotlib Figure and never shows it.

matplotlib is imported lazily (inside the functions) so that the CLI starts fast; the
non-interactive Agg backend is used, so plotting works on machines with no display.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.atomic import make_folder, write_with
from ecdsim.deployment import Prediction
from ecdsim.methods import SOLVERS
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_LINESTYLES = {"exact": "-", "paper": "--"}

# The methods from the most complete model to the least: the dynamic method integrates the
# equation of motion (inertia, stiction, end stop), the exact method solves the paper's
# quasi-static equations exactly, and the paper's Eq. 8-11 underestimate that by up to
# 29 % (docs/model.md). A plot that shows one method shows the first of these that ran.
MOST_EXACT_FIRST = ("dynamic", "exact", "paper")


def most_exact(methods: tuple[str, ...] | list[str]) -> str:
    """The most exact of the methods run (:data:`MOST_EXACT_FIRST`); else the first one.

    >>> most_exact(("paper", "exact")), most_exact(["paper"])
    ('exact', 'paper')
    """
    for name in MOST_EXACT_FIRST:
        if name in methods:
            return name
    return methods[0]


def _figure(width: float = 7.5, height: float = 4.8) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def target(ax: Axes | None, width: float = 7.5, height: float = 4.8) -> tuple[Figure, Axes]:
    """The figure and axes to draw on: the caller's ``ax`` (and its figure), or a new
    figure of ``width`` x ``height`` inches with one axes (every plot that takes ``ax=``)."""
    if ax is not None:
        return cast("Figure", ax.figure), ax
    fig = _figure(width, height)
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
    fig, ax = target(ax)
    times = np.linspace(0.0, time_span(prediction), n_points)
    temps = np.ravel(prediction.temperatures)
    colors = temperature_colors(temps)
    marked = False
    for name, solution in prediction.solutions.items():
        trajectory = prediction.trajectory(name, times)
        shape = prediction.temperatures.shape
        solved = np.ravel(np.broadcast_to(solution.solved_mask, shape))
        stalled = np.ravel(np.broadcast_to(solution.stalled, shape))
        stall_angle = np.ravel(np.broadcast_to(solution.stall_angle, shape))
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
            if quantity == "angle" and stalled[j]:
                marked = True
                _mark_stop(ax, times, values[:, j], float(np.degrees(stall_angle[j])), colors[j])
    if marked:
        ax.plot([], [], "x", color="0.2", ms=9, mew=2.2, label="stalls here (cannot start: t = 0)")
    ax.set_xlabel("time since release [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(plot_title(prediction.system.name, title))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def _mark_stop(ax: Axes, times: FloatArray, degrees: FloatArray, stall: float, color: Any) -> None:
    """A cross where a stalled curve stops, in its colour: at (0, 0) when it cannot start;
    else at the stall angle, at the first time the curve comes within 0.5 % of it (the
    speed falls to zero there, so the exact curve only approaches it), or at the end."""
    if stall == 0.0:
        at = 0.0
    else:
        reached = np.flatnonzero(degrees >= 0.995 * stall)
        at = float(times[reached[0]]) if reached.size else float(times[-1])
    ax.plot([at], [stall], "x", color=color, ms=10, mew=2.4, clip_on=False)


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

    Each line is ``T = FECD_T + BECD_T * omega`` (Eq. 5 inverted); a thick band between
    two dots shows the deployment's operating range, from the end (latch) speed to the
    start speed of the exact solution, and the legend says so.
    """
    u = Shown(units, digits=3)
    fig, ax = target(ax)
    ecd = prediction.ecd
    temps = np.ravel(prediction.temperatures)
    damping = np.ravel(np.broadcast_to(ecd.ecd_damping_rate, prediction.temperatures.shape))
    friction = np.ravel(np.broadcast_to(ecd.ecd_friction, prediction.temperatures.shape))
    reference = prediction.solutions.get("exact") or next(iter(prediction.solutions.values()))
    start = np.ravel(reference.start_speed)
    end = np.ravel(reference.end_speed)
    top = 1.2 * float(np.max(start)) if np.max(start) > 0 else 1.0
    speeds = np.linspace(0.0, top, n_points)
    colors = temperature_colors(temps)
    for j, temp in enumerate(temps):
        ax.plot(
            speeds,
            u.value(friction[j] + damping[j] * speeds, "torque"),
            color=colors[j],
            label=f"{Shown(units).text(temp, 'temperature')}: "
            f"BECD {u.text(damping[j], 'damping_rate')}, FECD {u.text(friction[j], 'torque')}",
        )
        ends = np.array([end[j], start[j]])
        # The deployment's operating range on the line: from the end (latch) speed to the
        # start speed, a thick band between two dots, explained once in the legend.
        ax.plot(
            ends,
            u.value(friction[j] + damping[j] * ends, "torque"),
            "o-",
            color=colors[j],
            linewidth=5.0,
            alpha=0.45,
            markersize=7,
        )
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    handles.append(Line2D([], [], marker="o", color="0.4", linewidth=5.0, alpha=0.45))
    method = "exact" if "exact" in prediction.solutions else next(iter(prediction.solutions))
    labels.append(f"operating range: end (latch) to start speed, {method} method")
    ax.set_xlabel("input shaft speed [rad/s]")
    ax.set_ylabel(u.head("ECD reaction torque", "torque"))
    ax.set_title(plot_title(prediction.system.name, "ECD torque against speed"))
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(handles, labels, fontsize="small")
    return fig


# Cold blue, a dark green, hot red (ColorBrewer's darkest of each hue): every temperature
# stays readable as a thin line on white, which the light middle of a rainbow (lime) or of
# a diverging map (grey) is not. The explorer uses the same three (webapp/static/app.js).
TEMPERATURE_ANCHORS = ("#2166ac", "#1b7837", "#b2182b")


def temperature_colors(
    temperatures: int | Sequence[float] | FloatArray,
) -> list[tuple[float, float, float, float]]:
    """One RGBA colour per temperature, cold blue through green to hot red.

    Given temperatures, each colour follows its value over their range (so a temperature
    keeps its colour when another is added in between); given a count ``n``, ``n``
    evenly spaced colours for temperatures in rising order. A single temperature is blue.
    """
    from matplotlib.colors import LinearSegmentedColormap

    cmap = LinearSegmentedColormap.from_list("ecdsim_temperature", TEMPERATURE_ANCHORS)
    if isinstance(temperatures, int):
        positions = np.linspace(0.0, 1.0, temperatures) if temperatures > 1 else np.zeros(1)
    else:
        values = np.asarray(temperatures, dtype=float)
        finite = values[np.isfinite(values)]
        low = float(finite.min()) if finite.size else 0.0
        span = float(finite.max()) - low if finite.size else 0.0
        positions = (values - low) / span if span > 0.0 else np.zeros(values.shape)
    return [tuple(float(c) for c in cmap(float(x))) for x in positions]  # type: ignore[misc]


def level_colors(n: int) -> list[tuple[float, float, float, float]]:
    """``n`` colours for the levels of a varied key (dark purple to orange, rising): a
    sequential map whose lightest end stays readable on white, and whose hues are none of
    the temperatures' blue, green and red."""
    from matplotlib import colormaps

    cmap = colormaps["plasma"]
    positions = np.linspace(0.0, 0.8, n) if n > 1 else np.zeros(1)
    return [tuple(float(c) for c in cmap(float(x))) for x in positions]  # type: ignore[misc]


def save_figure(fig: Figure, path: str | Path, dpi: int = 120) -> Path:
    """Save a figure atomically; the format follows the file's suffix (PNG, SVG, PDF).

    Its folder is created without a note: plots go into the folder ``--plot DIR`` names
    (creating it is what was asked), where a file option's missing folder is said
    (``ecdsim.atomic.on_folder_created``)."""
    target = Path(path)
    fmt = target.suffix.lstrip(".") or "png"
    make_folder(target.parent, announce=False)
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

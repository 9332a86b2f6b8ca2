"""Pictures of a wing's deployment: hinge angles against time, and the wing's shape.

:func:`plot_hinge_angles` draws each hinge's deployed angle against time, one panel per
temperature, with each hinge's travel dotted and the events marked where they happen
(latch, rebound, stick, breakaway). :func:`plot_wing_shapes` draws a strip of the wing's
outline at chosen instants, from the panels' geometry (:func:`drawn_outlines`, through
:func:`ecdsim.physics.chain.panel_outlines`; the explorer's animation draws the same)
and the case's sampled angles (linear between samples). Both return a matplotlib
``Figure`` and never show it; matplotlib is imported lazily, through
:mod:`ecdsim.plotting`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.physics import chain
from ecdsim.plotting import _figure, plot_title, save_figure
from ecdsim.wing.model import Wing
from ecdsim.wing.result import WingCase, WingResult

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

# Event kind -> (marker, size, legend text); drawn in this order.
MARKERS: dict[str, tuple[str, float, str]] = {
    "breakaway": ("^", 7.0, "breaks away"),
    "rebound": ("v", 7.0, "rebounds off its latch"),
    "stick": ("X", 9.0, "sticks"),
    "latch_engage": ("D", 6.0, "compliant latch engages"),
    "settle": ("s", 7.0, "rebounds settle: latched"),
    "latch": ("o", 7.0, "latches"),
}


# Hinges that move together (a synchronised or symmetric wing) would hide each other's
# curve: each hinge also has its own line style.
LINESTYLES: tuple[Literal["-", "--", "-."], ...] = ("-", "--", "-.")


def hinge_colors(n: int) -> list[tuple[float, float, float, float]]:
    """``n`` distinct colours, one per hinge (root first)."""
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return [cmap(i % 10) for i in range(n)]


def _case_title(result: WingResult, case: WingCase) -> str:
    t = f"T = {case.temperature:+g} degC"
    if math.isfinite(case.deployment_time):
        order = ", ".join(result.hinges[i] for i in case.sequence)
        return f"{t}: deployed in {case.deployment_time:.4g} s (latch order: {order})"
    stuck = ", ".join(result.hinges[i] for i in case.stuck_hinges) or "none"
    return f"{t}: not deployed ({case.status}; stuck: {stuck})"


def _angle_at(case: WingCase, time: float) -> FloatArray:
    """Each hinge's deployed angle at ``time``, linear between the case's samples [rad]."""
    return np.array(
        [np.interp(time, case.time, case.angle[:, j]) for j in range(case.hinges)], dtype=float
    )


def _mark_events(
    ax: Axes, result: WingResult, case: WingCase, colors: Sequence[object]
) -> set[str]:
    """Mark the case's events on its hinges' curves; the kinds drawn."""
    drawn: set[str] = set()
    for kind, (symbol, size, _) in MARKERS.items():
        for event in case.events:
            if event.kind != kind or event.hinge is None or not math.isfinite(event.time):
                continue
            angle = _angle_at(case, event.time)[event.hinge]
            ax.plot(
                [event.time],
                [angle],
                symbol,
                color=colors[event.hinge],
                markersize=size,
                markeredgecolor="black",
                markeredgewidth=0.6,
                zorder=3,
            )
            drawn.add(kind)
    return drawn


def plot_hinge_angles(
    result: WingResult, wing: Wing | None = None, temperatures: Sequence[float] | None = None
) -> Figure:
    """Each hinge's deployed angle against time, one panel per temperature.

    ``wing`` (optional) draws each hinge's travel as a dotted line; ``temperatures``
    picks the cases (default: all, in the result's order).
    """
    from matplotlib.lines import Line2D

    cases = (
        list(result.cases) if temperatures is None else [result.case_at(t) for t in temperatures]
    )
    rows = max(len(cases), 1)
    fig = _figure(7.5, 1.0 + 2.6 * rows)
    axes = fig.subplots(rows, 1, squeeze=False)[:, 0]
    colors = hinge_colors(len(result.hinges))
    kinds: set[str] = set()
    for ax, case in zip(axes, cases, strict=False):
        for j, name in enumerate(result.hinges):
            style = LINESTYLES[j % len(LINESTYLES)]
            ax.plot(
                case.time,
                case.angle[:, j],
                color=colors[j],
                linestyle=style,
                label=name,
                linewidth=1.6,
            )
            if wing is not None:
                ax.axhline(wing.hinges[j].travel, color=colors[j], linestyle=":", linewidth=1.0)
        kinds |= _mark_events(ax, result, case, list(colors))
        ax.set_title(_case_title(result, case), fontsize="medium")
        ax.set_ylabel("deployed angle [rad]")
        ax.set_xlim(left=0.0)
        ax.set_ylim(bottom=0.0)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    handles = [
        Line2D([], [], color=colors[j], linestyle=LINESTYLES[j % len(LINESTYLES)], label=n)
        for j, n in enumerate(result.hinges)
    ]
    if wing is not None:
        handles.append(Line2D([], [], color="grey", linestyle=":", label="travel (latch)"))
    for kind in MARKERS:
        if kind in kinds:
            symbol, size, text = MARKERS[kind]
            handles.append(
                Line2D(
                    [],
                    [],
                    marker=symbol,
                    linestyle="",
                    color="grey",
                    markeredgecolor="black",
                    markersize=size,
                    label=text,
                )
            )
    axes[0].legend(handles=handles, fontsize="small", loc="lower right", ncol=2)
    fig.suptitle(plot_title(result.wing, "hinge angles against time"))
    return fig


def shape_times(case: WingCase, count: int = 6) -> list[float]:
    """``count`` instants from release to the end of the case's samples, evenly spaced [s]."""
    end = float(case.time[-1])
    return [float(t) for t in np.linspace(0.0, end, count)]


# The thinnest a panel is drawn, as a fraction of the wing's length (hinge to tip), so
# that a thin panel shows in a picture of the whole wing.
DRAWN_THICKNESS_FRACTION = 0.025


def drawn_outlines(wing: Wing, deployed: FloatArray) -> FloatArray:
    """The panels' outlines as the pictures draw them, at deployed angles phi [m], (n, 4, 2).

    :func:`ecdsim.physics.chain.panel_outlines` (through :meth:`Wing.outlines`'s
    geometry) with every panel drawn as thick as the thickest panel, and at least
    :data:`DRAWN_THICKNESS_FRACTION` of the wing's length. The shape strip and the
    explorer's animation both draw these (one source).
    """
    arrays = wing.chain_arrays()
    extent = float(np.sum(arrays["length"]))
    drawn = max(DRAWN_THICKNESS_FRACTION * extent, float(np.max(arrays["thickness"])))
    return chain.panel_outlines(
        wing.relative_angles(deployed), arrays["length"], np.full(wing.size, drawn)
    )


def _draw_shape(ax: Axes, wing: Wing, angles: FloatArray, colors: Sequence[object]) -> None:
    from matplotlib.patches import Polygon

    outlines = drawn_outlines(wing, angles)
    for i, polygon in enumerate(outlines):
        ax.add_patch(
            Polygon(
                polygon,
                closed=True,
                facecolor=colors[i],
                edgecolor="black",
                linewidth=0.6,
                alpha=0.6,
                gid=f"panel {i + 1}",
            )
        )
    hinges = (outlines[:, 0] + outlines[:, 3]) / 2
    ax.plot(hinges[:, 0], hinges[:, 1], "o", color="black", markersize=3)


def plot_wing_shapes(
    wing: Wing, result: WingResult, temperature: float, times: Sequence[float] | None = None
) -> Figure:
    """A strip of the wing's shape at ``times`` (default: six, release to the end).

    The spacecraft side is the hatched wall through the root hinge along the base's y
    axis (the stowed panels lie along it in the examples); each panel is drawn from
    hinge to hinge with its thickness, coloured as in :func:`plot_hinge_angles`.
    """
    case = result.case_at(temperature)
    instants = list(times) if times is not None else shape_times(case)
    fig = _figure(2.0 + 1.9 * len(instants), 3.6)
    axes = fig.subplots(1, len(instants), squeeze=False)[0]
    colors = list(hinge_colors(wing.size))
    extent = sum(p.length for p in wing.panels)
    for ax, t in zip(axes, instants, strict=True):
        ax.axvspan(-0.12 * extent, 0.0, facecolor="0.85", hatch="///", edgecolor="0.6")
        _draw_shape(ax, wing, _angle_at(case, t), colors)
        ax.set_xlim(-0.15 * extent, 1.05 * extent)
        ax.set_ylim(-1.05 * extent, 1.05 * extent)
        ax.set_aspect("equal")
        ax.set_title(f"t = {t:.3g} s", fontsize="medium")
        ax.set_xlabel("x [m]")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("y [m]")
    from matplotlib.patches import Patch

    handles = [
        Patch(facecolor=colors[i], edgecolor="black", alpha=0.6, label=panel.name)
        for i, panel in enumerate(wing.panels)
    ]
    handles.append(Patch(facecolor="0.85", hatch="///", edgecolor="0.6", label="spacecraft"))
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize="small")
    fig.suptitle(plot_title(result.wing, f"the wing's shape at {temperature:+g} degC"))
    return fig


def write_wing_plots(result: WingResult, wing: Wing, folder: str | Path) -> list[Path]:
    """Write the hinge angles and, per temperature, the shape strip as PNG files."""
    out = Path(folder)
    paths = [save_figure(plot_hinge_angles(result, wing), out / "wing_hinge_angles.png")]
    for case in result.cases:
        name = f"wing_shapes_{case.temperature:+g}C.png".replace("+", "p").replace("-", "m")
        paths.append(save_figure(plot_wing_shapes(wing, result, case.temperature), out / name))
    return paths

"""Sizing figures: deployment time against temperature, margins against gear ratio, and the
ECD against a fluid damper. Each function returns a matplotlib Figure and never shows it;
those of one axes draw on a given matplotlib Axes (``ax``) instead of a new figure if
asked (the notebook API's ``plot(ax=...)``). matplotlib is imported lazily (see
:mod:`ecdsim.plotting`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.plotting import save_figure, target
from ecdsim.sizing.fluid import FluidComparison
from ecdsim.sizing.ratio import RatioIntervals
from ecdsim.sizing.requirements import Requirements
from ecdsim.sizing.search import CandidateResult
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _figure(width: float = 7.5, height: float = 4.8) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _window(ax: Axes, requirements: Requirements) -> None:
    for value, text in (
        (requirements.min_deployment_time, "min"),
        (requirements.max_deployment_time, "max"),
    ):
        if value is not None:
            ax.axhline(value, color="0.3", linestyle=":", linewidth=1.0)
            ax.annotate(
                f"required {text} {value:g} s",
                (0.01, value),
                xycoords=("axes fraction", "data"),
                fontsize="small",
                va="bottom",
            )


def plot_candidate_times(
    results: Sequence[CandidateResult],
    temperatures: FloatArray,
    times: FloatArray,
    requirements: Requirements,
    units: UnitSystem = "si",
    ax: Axes | None = None,
) -> Figure:
    """Deployment time against temperature for the given candidates, with the window.

    ``times`` has shape (len(results), len(temperatures)) [s]; +inf (stall) is not drawn.
    Illustrative (invented) catalogue entries are labelled so in the legend. On ``ax`` if
    given (its figure is returned), else on a new figure.
    """
    u = Shown(units)
    fig, ax = target(ax)
    shown_t = u.values(np.asarray(temperatures, dtype=float), "temperature")
    for result, row in zip(results, np.atleast_2d(times), strict=True):
        shown = np.where(np.isfinite(row), row, np.nan)
        tag = " (illustrative, not vendor data)" if result.candidate.illustrative else ""
        ax.plot(shown_t, shown, marker=".", label=f"#{result.rank} {result.candidate.label}{tag}")
    _window(ax, requirements)
    ax.set_xlabel(u.head("temperature", "temperature"))
    ax.set_ylabel("exact deployment time [s]")
    ax.set_title("Deployment time over temperature, best-ranked candidates")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="x-small")
    return fig


# Curve colours of the margins: none is the green of the feasible band or the grey of the
# catalogue ratios.
_MARGIN_COLORS = ("#1f77b4", "#d62728", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")


def binding_checks(intervals: RatioIntervals) -> list[str]:
    """The checks that bind somewhere in the scanned range: those whose margin changes
    sign there (an interval end that is not the scan's) or is never met. A check met at
    every scanned ratio limits no ratio."""
    from ecdsim.sizing.ratio import SCAN_RANGE

    found = []
    for name, own in intervals.by_check.items():
        ends = [i.low_limited_by for i in own] + [i.high_limited_by for i in own]
        if not own or any(end != SCAN_RANGE for end in ends):
            found.append(name)
    return found


def plot_ratio_margins(
    intervals: RatioIntervals, labels: Mapping[str, str] | None = None, ax: Axes | None = None
) -> Figure:
    """The margin (worst over temperature) of each requirement that binds, against N.

    Only the requirements whose margin crosses zero in the scanned range (or is never
    met) are drawn, labelled in words (``labels``, e.g. "deployment time <= 60 s"); the
    ones met at every scanned ratio are named in a note. The feasible interval is shaded
    and in the legend with its ends (exact roots, docs/sizing.md); the gearbox's
    catalogued ratios are dashed grey lines, marked whether they meet every requirement.
    On ``ax`` if given (its figure is returned; the axes' own legend below it), else on a
    new figure (the figure's legend below the axes).
    """
    import textwrap

    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from ecdsim.sizing.report import PLAIN_NAMES, interval_text

    words = dict(PLAIN_NAMES, **(labels or {}))
    given = ax is not None
    fig, ax = target(ax, 8.0, 5.4)
    binding = binding_checks(intervals)
    # The requirements at the feasible interval's ends: bold, and said so in the legend.
    ends = {i.low_limited_by for i in intervals.intervals}
    ends |= {i.high_limited_by for i in intervals.intervals}
    for k, name in enumerate(binding):
        margins = intervals.grid_margins[name]
        sets = name in ends
        ax.plot(
            intervals.grid,
            np.clip(margins, -1.5, 1.5),
            color=_MARGIN_COLORS[k % len(_MARGIN_COLORS)],
            linewidth=2.6 if sets else 1.3,
            alpha=1.0 if sets else 0.75,
            label=words.get(name, name) + (" (sets an end)" if sets else ""),
        )
    handles, texts = ax.get_legend_handles_labels()
    for interval in intervals.intervals:
        ax.axvspan(interval.low, interval.high, color="tab:green", alpha=0.15, lw=0)
    if intervals.intervals:
        handles.append(Patch(color="tab:green", alpha=0.3))
        shown = ", ".join(interval_text(i) for i in intervals.intervals)
        texts.append(f"meets every requirement: N {shown}")
    else:
        handles.append(Patch(color="white"))
        texts.append("no N meets every requirement in the scanned range")
    for ratio, feasible in intervals.catalogue_ratios:
        ax.axvline(ratio, color="0.35", linestyle="--" if feasible else ":", linewidth=1.2)
        ax.annotate(
            f"{ratio:g}:1",
            (ratio, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(2, -2),
            textcoords="offset points",
            fontsize="x-small",
            color="0.3",
            va="top",
            rotation=90,
        )
    kinds = {feasible for _, feasible in intervals.catalogue_ratios}
    for feasible in sorted(kinds, reverse=True):
        handles.append(Line2D([], [], color="0.35", linestyle="--" if feasible else ":"))
        texts.append(
            "catalogue ratio, meets every requirement"
            if feasible
            else "catalogue ratio, misses a requirement"
        )
    ax.axhline(0.0, color="0.2", linewidth=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("gear ratio N [-]")
    ax.set_ylabel("margin, >= 0 where met [-] (clipped to +-1.5)")
    ax.set_title(
        f"{intervals.damper} + {intervals.gearbox}:\nthe requirements that limit the gear ratio"
    )
    ax.grid(True, alpha=0.3, which="both")
    always = [words.get(n, n) for n in intervals.by_check if n not in binding]
    if always:
        low, high = intervals.ratio_range
        handles.append(Patch(color="none"))
        said = f"met at every N from {low:g} to {high:g}, not drawn: " + "; ".join(always)
        texts.append("\n".join(textwrap.wrap(said, 48)))
    if given:  # the caller's axes may share its figure: the legend belongs to them, below
        from matplotlib.transforms import offset_copy

        ax.legend(
            handles,
            texts,
            loc="upper center",
            # below the tick labels and the axis label (about 40 points), whatever the
            # axes' height
            bbox_to_anchor=(0.5, 0.0),
            bbox_transform=offset_copy(ax.transAxes, fig=fig, y=-40.0, units="points"),
            ncols=2,
            fontsize="x-small",
        )
    else:
        fig.legend(handles, texts, loc="outside lower center", ncols=2, fontsize="small")
    return fig


def plot_fluid_comparison(comparison: FluidComparison, units: UnitSystem = "si") -> Figure:
    """Deployment time of the ECD and the matched fluid damper against temperature.

    The fluid curve is the damped phase after its deadband (plus the free time through
    the deadband when a load inertia is given); the lower panel shows both dampings.
    """
    u = Shown(units)
    fig = _figure(7.5, 6.4)
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    t = u.values(np.asarray(comparison.temperatures, dtype=float), "temperature")
    for label, side in (("ECD", comparison.ecd), (comparison.name, comparison.fluid)):
        times = side.total_time if side.total_time is not None else side.damped_time
        top.plot(t, np.where(np.isfinite(times), times, np.nan), marker=".", label=label)
    top.set_ylabel("deployment time [s]")
    top.grid(True, alpha=0.3)
    if comparison.match_temperature is None:
        return _power_law_panels(comparison, fig, top, bottom, t, u)
    top.axvline(u.value(comparison.match_temperature, "temperature"), color="0.4", linestyle=":")
    top.set_title("ECD against a fluid damper matched at "
                  f"{u.text(comparison.match_temperature, 'temperature')}"
                  + _method_note(comparison))  # fmt: skip
    top.legend(fontsize="small")
    # One axis for both: the ECD's rate is the n = 1 case of the fluid's c(T), and a
    # torque per speed^n converts as the torque does.
    bottom.plot(
        t,
        u.values(np.asarray(comparison.ecd_damping_rate), "torque"),
        label=f"ECD: BECD_T [{u.unit('damping_rate')}]",
    )
    bottom.plot(
        t,
        u.values(np.asarray(comparison.fluid_coefficient), "torque"),
        label=f"fluid: c(T) (n = {comparison.exponent:g})",
    )
    bottom.set_yscale("log")
    bottom.set_xlabel(u.head("temperature", "temperature"))
    bottom.set_ylabel(f"damping [{u.unit('torque')}*(s/rad)^n]")
    bottom.grid(True, alpha=0.3, which="both")
    bottom.legend(fontsize="small")
    return fig


def _method_note(comparison: FluidComparison) -> str:
    """The title's note of the method (the default, quasi-static, is not named)."""
    return "" if comparison.method == "quasi-static" else f", {comparison.method} method"


def _power_law_panels(
    comparison: FluidComparison, fig: Figure, top: Axes, bottom: Axes, t: FloatArray, u: Shown
) -> Figure:
    """The measured (power-law) fluid damper: not matched to the ECD, so the lower panel
    compares both dampers' damping torque at the law's reference speed."""
    top.set_title("ECD against a fluid damper (measured power law)" + _method_note(comparison))
    # Times spread over decades: a log axis shows both dampers' spread.
    top.set_yscale("log")
    tested = getattr(comparison.law, "temperatures", ())
    if tested:
        for ax in (top, bottom):
            ax.axvspan(u.value(min(tested), "temperature"), u.value(max(tested), "temperature"),
                       color="0.9", zorder=0)  # fmt: skip
        top.plot([], [], "s", color="0.9", label="bench data's temperatures")
    top.legend(fontsize="small")
    torques = comparison.torques_at_reference()
    assert torques is not None
    assert comparison.reference_speed is not None
    speed = comparison.reference_speed
    bottom.plot(t, u.values(torques[0], "torque"), label="ECD: BECD_T * w_r")
    bottom.plot(t, u.values(torques[1], "torque"), label="fluid: c(T) w_r^n(T)")
    bottom.set_yscale("log")
    bottom.set_title(f"Damping torque at w_r = {speed:g} rad/s", fontsize="medium")
    bottom.set_xlabel(u.head("temperature", "temperature"))
    bottom.set_ylabel(u.head("torque", "torque"))
    bottom.grid(True, alpha=0.3, which="both")
    bottom.legend(fontsize="small")
    return fig


def write_sizing_plots(
    folder: str | Path,
    results: Sequence[CandidateResult],
    temperatures: FloatArray,
    times: FloatArray,
    requirements: Requirements,
    intervals: RatioIntervals | None,
    units: UnitSystem = "si",
    labels: Mapping[str, str] | None = None,
) -> list[Path]:
    """Write the sizing plots as PNG files into ``folder``, in ``units``; returns the paths.

    ``labels``: each check's name in words, for the margins plot."""
    out = Path(folder)
    written = [
        save_figure(
            plot_candidate_times(results, temperatures, times, requirements, units),
            out / "sizing_time_vs_temperature.png",
        )
    ]
    if intervals is not None:
        written.append(
            save_figure(plot_ratio_margins(intervals, labels), out / "ratio_margins.png")
        )
    return written


def write_fluid_plots(
    folder: str | Path, comparison: FluidComparison, units: UnitSystem = "si"
) -> list[Path]:
    """Write the ECD-against-fluid plot as PNG into ``folder``, in ``units``; returns the paths."""
    out = Path(folder)
    return [save_figure(plot_fluid_comparison(comparison, units), out / "ecd_vs_fluid.png")]

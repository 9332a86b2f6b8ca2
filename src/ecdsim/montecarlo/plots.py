"""Plots of a Monte Carlo study: histograms, CDF and tornado. Figures are returned, never shown.

matplotlib is imported lazily; files are written atomically by
:func:`ecdsim.plotting.save_figure`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.plotting import temperature_colors
from ecdsim.units_display import Shown, UnitSystem

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ecdsim.montecarlo.run import Plan

CDF_POINTS = 2001
# The files write_plots writes into OUT/plots (and montecarlo --overwrite removes).
PLOT_NAMES = ("time_histogram", "time_cdf", "end_speed_histogram", "tornado")


# Characters per title line (10 pt on 7.5 in): full-width axes, and the tornado's, which
# its long input names narrow.
TITLE_WIDTH, NARROW_TITLE_WIDTH = 80, 60


def _figure(width: float = 7.5, height: float = 4.8) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def study_title(system: str, what: str, width: int = TITLE_WIDTH) -> str:
    """A plot title: the system's name, then what is shown, each wrapped to fit the axes.

    >>> print(study_title("A rather long system name", "deployment time: 10 samples"))
    A rather long system name
    deployment time: 10 samples
    """
    return "\n".join([*_balanced(system, width), *_balanced(what, width)])


def _balanced(text: str, width: int) -> list[str]:
    """``text`` wrapped to at most ``width`` characters on as few, evenly long lines.

    >>> _balanced("CDA Cc-16 test deployment (paper section 6), illustrative tolerances", 60)
    ['CDA Cc-16 test deployment (paper', 'section 6), illustrative tolerances']
    """
    import textwrap

    lines = textwrap.wrap(text, width)
    for narrower in range(math.ceil(len(text) / max(len(lines), 1)), width):
        candidate = textwrap.wrap(text, narrower)
        if len(candidate) <= len(lines):
            return candidate
    return lines


def bin_count(n: int) -> int:
    """Histogram bins for ``n`` finite samples: Rice's rule 2 n^(1/3), kept within 10..80.

    >>> [bin_count(n) for n in (100, 20_000, 1_000_000)]
    [10, 55, 80]
    """
    return int(min(80, max(10, math.ceil(2.0 * n ** (1.0 / 3.0)))))


def density_label(quantity: str) -> str:
    """The y label of a density of ``quantity``: its unit inverted.

    A quotient unit is turned over (a density of a speed in rad/s is in s/rad).

    >>> density_label("deployment time [s]")
    'probability density [1/s]'
    >>> density_label("latch speed [rad/s]")
    'probability density [s/rad]'
    >>> density_label("torque [N*m]")
    'probability density [1/(N*m)]'
    """
    unit = quantity[quantity.rfind("[") + 1 : -1] if quantity.endswith("]") else ""
    if not unit:
        return "probability density [1/unit of x]"
    if unit.count("/") == 1 and "*" not in unit and "(" not in unit:
        numerator, denominator = unit.split("/")
        inverted = denominator if numerator == "1" else f"{denominator}/{numerator}"
        return f"probability density [{inverted}]"
    return f"probability density [1/({unit})]" if "*" in unit else f"probability density [1/{unit}]"


def plot_histogram(
    samples: Mapping[float, FloatArray],
    quantity: str,
    title: str,
    bins: int | None = None,
    units: UnitSystem = "si",
) -> Figure:
    """Histogram of a quantity's finite samples at each temperature [degC].

    Each temperature has its own bins over its own range (``bins`` of them, or
    :func:`bin_count` of its finite samples), so that a narrow distribution beside a wide
    one is resolved too; as densities, the areas stay comparable. The legend gives each
    temperature's share of non-finite (stalled) samples, which a histogram cannot show.
    """
    u = Shown(units)
    fig = _figure()
    ax = fig.add_subplot()
    for color, (temperature, x) in zip(
        temperature_colors(list(samples)), samples.items(), strict=True
    ):
        finite = x[np.isfinite(x)]
        stalled = 1.0 - finite.size / x.size if x.size else 0.0
        at = u.text(temperature, "temperature")
        label = at + (f" ({100 * stalled:.2g} % stall)" if stalled else "")
        if finite.size == 0:
            ax.plot([], [], color=color, label=f"{at}: every sample stalls")
            continue
        low, high = float(finite.min()), float(finite.max())
        if not high > low:  # one value: a bin of 1 % of it (or of 1) around it
            half = 0.005 * abs(low) or 0.5
            low, high = low - half, high + half
        edges = np.linspace(low, high, (bins or bin_count(finite.size)) + 1)
        ax.hist(
            finite, bins=edges.tolist(), histtype="step", color=color, label=label, density=True
        )
    ax.set_xlabel(quantity)
    ax.set_ylabel(density_label(quantity))
    ax.set_title(title, fontsize="medium")
    ax.grid(True, alpha=0.3)
    if samples:
        ax.legend(fontsize="small")
    return fig


def plot_cdf(
    samples: Mapping[float, FloatArray], quantity: str, title: str, units: UnitSystem = "si"
) -> Figure:
    """Empirical CDF at each temperature; stalled samples keep it below 1 (they never arrive)."""
    u = Shown(units)
    fig = _figure()
    ax = fig.add_subplot()
    for color, (temperature, x) in zip(
        temperature_colors(list(samples)), samples.items(), strict=True
    ):
        n = x.size
        if n == 0:
            continue
        ranks = np.unique(np.linspace(0, n - 1, min(n, CDF_POINTS)).astype(np.int64))
        ordered = np.partition(x, ranks)[ranks]
        levels = (ranks + 1) / n
        keep = np.isfinite(ordered)
        ax.step(
            ordered[keep],
            levels[keep],
            where="post",
            color=color,
            label=u.text(temperature, "temperature"),
        )
    for p in (0.01, 0.5, 0.99):
        ax.axhline(p, color="grey", linewidth=0.6, linestyle=":")
    ax.set_xlabel(quantity)
    ax.set_ylabel("cumulative probability [-]")
    ax.set_ylim(0.0, 1.0)
    ax.set_title(title, fontsize="medium")
    ax.grid(True, alpha=0.3)
    if samples:
        ax.legend(fontsize="small")
    return fig


def plot_tornado(summary: Mapping[str, Any], units: UnitSystem = "si") -> Figure:
    """Standardised regression coefficients of the deployment time, per input and temperature."""
    u = Shown(units)
    cases = summary["cases"]
    keys = [t["key"] for t in summary["tolerances"]]
    table = np.zeros((len(cases), len(keys)))
    for i, case in enumerate(cases):
        for row in case["sensitivity"]["inputs"]:
            table[i, keys.index(row["key"])] = row["src"] if row["src"] is not None else 0.0
    order = np.argsort(np.max(np.abs(table), axis=0)) if keys else np.zeros(0, dtype=int)
    fig = _figure(7.5, max(3.0, 0.45 * len(keys) * max(1, len(cases)) ** 0.5 + 1.5))
    ax = fig.add_subplot()
    height = 0.8 / max(1, len(cases))
    positions = np.arange(len(keys))
    colors = temperature_colors([c["temperature_C"] for c in cases])
    for i, (color, case) in enumerate(zip(colors, cases, strict=True)):
        r2 = case["sensitivity"]["r_squared"]
        label = u.text(case["temperature_C"], "temperature") + (
            f" (R^2 = {r2:.3f})" if r2 is not None else ""
        )
        ax.barh(
            positions + (i - (len(cases) - 1) / 2) * height,
            table[i, order],
            height=height,
            color=color,
            label=label,
        )
    ax.set_yticks(positions, [keys[j] for j in order])
    ax.axvline(0.0, color="black", linewidth=0.8)
    ax.set_xlabel("standardised regression coefficient of deployment time [-]")
    what = f"sensitivity of deployment time ({summary['method']} method)"
    ax.set_title(study_title(summary["system"], what, NARROW_TITLE_WIDTH), fontsize="medium")
    ax.grid(True, axis="x", alpha=0.3)
    if cases:
        ax.legend(fontsize="small")
    return fig


def write_plots(
    plan: Plan,
    out: Path,
    summary: Mapping[str, Any],
    units: UnitSystem = "si",
    folder: Path | None = None,
) -> list[Path]:
    """Write the study's plots as PNG files into ``folder`` (default ``out/plots``),
    temperatures in ``units``; ``out`` is the run's folder, which holds the samples."""
    from ecdsim.montecarlo.columns import output_column
    from ecdsim.montecarlo.store import ChunkReader
    from ecdsim.plotting import save_figure

    reader = ChunkReader(out, plan.chunks)
    times = {t: reader.floats(output_column("deployment_time_s", t)) for t in plan.temperatures}
    speeds = {}
    for t in plan.temperatures:
        stalled = np.asarray(reader.column(output_column("stalled", t)), dtype=bool)
        speeds[t] = reader.floats(output_column("end_speed_rad_s", t))[~stalled]
    study = f"{plan.samples:,} samples, {plan.method} method"
    time_title = study_title(plan.system.name, f"deployment time, {study}")
    speed_title = study_title(
        plan.system.name, f"end (latch) speed of the samples that arrive, {study}"
    )
    figures = {
        "time_histogram": plot_histogram(times, "deployment time [s]", time_title, units=units),
        "time_cdf": plot_cdf(times, "deployment time [s]", time_title, units),
        "end_speed_histogram": plot_histogram(
            speeds, "end (latch) speed [rad/s]", speed_title, units=units
        ),
        "tornado": plot_tornado(summary, units),
    }
    target = folder if folder is not None else out / "plots"
    return [save_figure(figures[name], target / f"{name}.png") for name in PLOT_NAMES]

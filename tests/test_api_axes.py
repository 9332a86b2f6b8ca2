"""Every notebook result draws one plot on a caller's matplotlib Axes (issue 27 item 5).

``plot(ax=ax, ...)`` of the deploy, fit, size and sweep results draws on the given Axes,
inside the caller's figure (no axes or figure legend added), titled, labelled with units,
its legend inside the axes, and returns ``ax``; without ``ax`` each still returns its
figures. Each test draws on the axes of one figure of its own layout and reads the
artists back: their data are the result's numbers, and the numbers a test can derive
on its own (the stall of the paper example above N = 533.4 at -40 degC) are checked
against that derivation.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import ecdsim
from ecdsim.config import ConfigError
from tests.conftest import ROOT

PAPER = ROOT / "examples" / "paper_cc16.toml"
DROP_TEST = ROOT / "examples" / "drop_test.csv"
SIZING = ROOT / "examples" / "sizing.toml"
CATALOGUE = ROOT / "examples" / "catalogue.toml"


def _grid(rows: int, cols: int) -> tuple[Any, list[Any]]:
    from matplotlib.figure import Figure

    figure = Figure(figsize=(5.5 * cols, 4.5 * rows), layout="constrained")
    return figure, list(np.ravel(figure.subplots(rows, cols)))


def _drawn_in_place(figure: Any, axes: list[Any], tmp_path: Path, name: str) -> None:
    """Each axes drawn on has a title, axis labels (the y one with its unit) and its own
    legend; the figure holds only the caller's axes and no legend of its own."""
    assert figure.axes == axes
    assert figure.legends == []
    for ax in axes:
        assert ax.get_title()
        assert ax.get_xlabel()  # with its unit but for a plain number (gearbox.ratio)
        assert "[" in ax.get_ylabel()
        assert ax.get_legend() is not None
    figure.savefig(tmp_path / f"{name}.png")  # the tests' PNGs, to look at


def _line(ax: Any, label: str) -> Any:
    (found,) = [line for line in ax.get_lines() if line.get_label() == label]
    return found


def test_fit_draws_each_plot_on_a_given_axes(tmp_path: Path) -> None:
    fitted = ecdsim.fit(DROP_TEST)
    fits = fitted.result.fits
    figure, axes = _grid(2, 2)
    kinds = ("torque_speed", "damping_rate", "friction", "residuals")
    for ax, kind in zip(axes, kinds, strict=True):
        assert fitted.plot(ax=ax, kind=kind) is ax
    _drawn_in_place(figure, axes, tmp_path, "fit")
    speed, damping, friction, residuals = axes
    # Torque against speed: each temperature's points and its line, which starts at FECD.
    points = [line for line in speed.get_lines() if line.get_linestyle() == "None"]
    assert len(points) == len(fits) == 3
    for line, fit in zip(points, fits, strict=True):
        np.testing.assert_array_equal(line.get_xdata(), fit.corrected)
        np.testing.assert_array_equal(line.get_ydata(), fit.torque)
    lines = [line for line in speed.get_lines() if line.get_linestyle() == "-"]
    for line, fit in zip(lines, fits, strict=True):
        x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
        assert x[0] == 0.0
        assert y[0] == fit.line.intercept.value
        slope = (y[-1] - y[0]) / (x[-1] - x[0])
        # the line's slope is BECD, to the rounding of two subtractions
        assert slope == pytest.approx(fit.line.slope.value, rel=1e-12)
    # BECD and FECD over temperature: the error bars at the fitted values, the law drawn.
    for ax, values in (
        (damping, [f.line.slope.value for f in fits]),
        (friction, [f.line.intercept.value for f in fits]),
    ):
        (bars,) = ax.containers
        data_line = bars.lines[0]
        np.testing.assert_array_equal(data_line.get_xdata(), [-40.0, 25.0, 100.0])
        np.testing.assert_array_equal(data_line.get_ydata(), values)
        assert ax.get_xlabel() == "temperature [degC]"
    assert _line(damping, "linear law")
    assert _line(friction, "line")
    assert "BECD" in damping.get_ylabel()
    assert "FECD" in friction.get_ylabel()
    # Residuals: torque minus the line at each point.
    for line, fit in zip(residuals.get_lines()[:3], fits, strict=True):
        np.testing.assert_array_equal(line.get_ydata(), fit.torque - fit.line.fitted)
    # Without ax: the three figures, as before.
    assert [len(f.axes) for f in fitted.plot()] == [1, 2, 1]
    with pytest.raises(ecdsim.api.UnknownNameError, match=r"kind: 'speed' is not one of"):
        fitted.plot(ax=speed, kind="speed")


def test_fit_plot_in_us_units() -> None:
    figure, (ax,) = _grid(1, 1)
    ecdsim.fit(DROP_TEST).plot("us", ax=ax, kind="friction")
    assert ax.get_xlabel() == "temperature [degF]"
    assert "lbf*in" in ax.get_ylabel()
    (bars,) = ax.containers
    # -40 degC is -40 degF; 25 degC is 77 degF; 100 degC is 212 degF (exact conversions)
    np.testing.assert_allclose(bars.lines[0].get_xdata(), [-40.0, 77.0, 212.0], rtol=1e-15)


def test_size_draws_each_plot_on_a_given_axes(tmp_path: Path) -> None:
    from ecdsim.sizing.plots import binding_checks
    from ecdsim.sizing.report import PLAIN_NAMES

    sized = ecdsim.size(SIZING, CATALOGUE)
    figure, (times, margins) = _grid(1, 2)
    assert sized.plot(3, ax=times) is times
    assert sized.plot(ax=margins, kind="margins") is margins
    _drawn_in_place(figure, [times, margins], tmp_path, "size")
    # One curve per candidate shown, best first; at -40 degC (the grid's first point) it
    # is the search's own deployment time of that candidate.
    curves = [line for line in times.get_lines() if line.get_label().startswith("#")]
    valid = [c for c in sized.search.candidates if c.error is None][:3]
    assert [line.get_label().split()[0] for line in curves] == [f"#{c.rank}" for c in valid]
    for line, candidate in zip(curves, valid, strict=True):
        assert line.get_xdata()[0] == -40.0
        expected = candidate.deployment_time[0]
        # the same exact solution by the search and by the curves' batch, to round-off
        assert line.get_ydata()[0] == pytest.approx(expected, rel=1e-9)
    # The margins: one curve per binding requirement, labelled in words, legend inside.
    assert sized.intervals is not None
    binding = binding_checks(sized.intervals)
    labels = [
        line.get_label() for line in margins.get_lines() if not line.get_label().startswith("_")
    ]
    assert [label.split(" (sets")[0] for label in labels] == [
        PLAIN_NAMES.get(name, name) for name in binding
    ]
    assert margins.get_xscale() == "log"
    # Without a valid candidate there is no margin plot to draw.
    with pytest.raises(ConfigError, match="'margins' needs a valid candidate"):
        dataclasses.replace(sized, intervals=None).plot(ax=margins, kind="margins")
    with pytest.raises(ecdsim.api.UnknownNameError, match=r"kind: 'ratio' is not one of"):
        sized.plot(ax=times, kind="ratio")
    assert len(sized.plot()) == 2


def _times(frame: Any, temperature: float, **where: float) -> list[float]:
    """The exact method's deployment times at ``temperature`` along gearbox.ratio."""
    mine = frame[(frame["method"] == "exact") & (frame["temperature_C"] == temperature)]
    for column, value in where.items():
        mine = mine[np.isclose(mine[column], value)]
    mine = mine.sort_values("gearbox.ratio")
    return [
        t if not stalled else math.nan
        for t, stalled in zip(mine["deployment_time_s"], mine["stalled"], strict=True)
    ]


def test_sweep_of_one_key_draws_its_panel_with_the_stall_marked(tmp_path: Path) -> None:
    swept = ecdsim.sweep(
        PAPER, {"gearbox.ratio": [300, 450, 600]}, temperatures=[-40, 25], methods="exact"
    )
    assert swept.panels() == []  # one panel: a line per temperature
    figure, (ax,) = _grid(1, 1)
    assert swept.plot(ax=ax) is ax
    _drawn_in_place(figure, [ax], tmp_path, "sweep_one_key")
    frame = swept.to_dataframe()
    for temperature, label in ((-40.0, "-40 degC"), (25.0, "25 degC")):
        line = _line(ax, label)
        np.testing.assert_array_equal(line.get_xdata(), [300.0, 450.0, 600.0])
        np.testing.assert_array_equal(line.get_ydata(), _times(frame, temperature))
    # At -40 degC the paper example stalls above N = (1.58 N*m - FS(-40 degC)) / FT(-40
    # degC) = 533.4 (docs/api.md): N = 600 is drawn as a cross, N = 450 moves.
    cold = _line(ax, "-40 degC").get_ydata()
    assert np.isfinite(cold[1])
    assert np.isnan(cold[2])
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert [list(c.get_xdata()) for c in crosses if c.get_label().startswith("_")] == [[600.0]]
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert "x at the top: stalls (no deployment)" in legend
    assert "CDA Cc-16" in ax.get_title()


def test_sweep_of_two_keys_draws_a_chosen_temperature(tmp_path: Path) -> None:
    swept = ecdsim.sweep(
        PAPER,
        {"gearbox.ratio": [300, 380, 450], "load.start_torque": ["3.2 N*m", "3.73 N*m"]},
        temperatures=[-40, 25],
        methods="exact",
    )
    assert swept.panels() == [-40.0, 25.0]
    figure, (cold, warm) = _grid(1, 2)
    assert swept.plot(ax=cold) is cold  # the first panel by default
    assert swept.plot(ax=warm, panel=25) is warm
    _drawn_in_place(figure, [cold, warm], tmp_path, "sweep_two_keys")
    assert "T = -40 degC" in cold.get_title()
    assert "T = 25 degC" in warm.get_title()
    frame = swept.to_dataframe()
    for ax, temperature in ((cold, -40.0), (warm, 25.0)):
        assert ax.get_legend().get_title().get_text() == "load.start_torque"
        for torque in (3.2, 3.73):
            line = _line(ax, f"{torque:g} N*m")
            np.testing.assert_array_equal(line.get_xdata(), [300.0, 380.0, 450.0])
            np.testing.assert_array_equal(
                line.get_ydata(), _times(frame, temperature, **{"load.start_torque_Nm": torque})
            )
    with pytest.raises(
        ecdsim.api.UnknownNameError, match=r"panel: 100 is not one of \[-40.0, 25.0\]"
    ):
        swept.plot(ax=cold, panel=100)
    # A panel without ax: that panel alone on a new figure.
    alone = swept.plot(panel=25.0)
    assert len(alone.axes) == 1
    assert "T = 25 degC" in alone.axes[0].get_title()


def test_latin_hypercube_draws_a_chosen_key(tmp_path: Path) -> None:
    swept = ecdsim.sweep(
        PAPER,
        {"gearbox.ratio": "300:450:4", "load.start_torque": "3.2:4.2:3 N*m"},
        latin=10,
        temperatures=[25],
        methods="exact",
    )
    assert swept.panels() == ["gearbox.ratio", "load.start_torque"]
    figure, (ax,) = _grid(1, 1)
    assert swept.plot(ax=ax, panel="load.start_torque", units="us") is ax
    _drawn_in_place(figure, [ax], tmp_path, "sweep_latin")
    assert ax.get_xlabel().startswith("load.start_torque")
    assert "lbf*in" in ax.get_xlabel()
    (points,) = [line for line in ax.get_lines() if line.get_label() == "77 degF"]
    frame = swept.to_dataframe().sort_values("load.start_torque_Nm", kind="stable")
    # N*m to lbf*in: 1 / (0.45359237 kg * 9.80665 m/s^2 * 0.0254 m), exact by definition
    lbf_in = 1.0 / (0.45359237 * 9.80665 * 0.0254)
    np.testing.assert_allclose(
        np.sort(points.get_xdata()), frame["load.start_torque_Nm"] * lbf_in, rtol=1e-12
    )
    assert len(points.get_xdata()) == 10

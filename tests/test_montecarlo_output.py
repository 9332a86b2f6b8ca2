"""What a Monte Carlo study shows (issue 14, item 6): reruns, plots and repeatability in words.

Numbers are checked against hand derivations: each sample's time from the paper's
Eq. 1-4 and the exact solution typed in tests/hand.py (via ``hand_times``), order
statistics by numpy, the normal tail by math.erf.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.cli.montecarlo import _chance
from ecdsim.montecarlo.plots import (
    bin_count,
    density_label,
    plot_cdf,
    plot_histogram,
    plot_tornado,
    study_title,
)
from ecdsim.montecarlo.repeatability import required_std
from ecdsim.montecarlo.store import MANIFEST, SUMMARY
from tests import hand
from tests.conftest import SavedFigures
from tests.test_montecarlo_config import PAPER_TEXT, write_config
from tests.test_montecarlo_run import hand_times

runner = CliRunner()

# Run-to-run scatter small enough that 500 deployments at -40 degC sometimes all stay
# within 0.5 s: a campaign probability between 0 and 1 that the table must show.
TIGHT = "\n".join(
    [
        '"damper.damping_rate" = { distribution = "normal", three_sigma = "0.36 %" }',
        '"load.end_torque" = { distribution = "normal", sigma = "0.1 %" }',
        '"load.system_friction.at_0C" = { distribution = "uniform", plus_minus = "0.36 %" }',
    ]
)
# Unit-to-unit sized tolerances: far wider than the paper's 500-run repeatability.
WIDE = "\n".join(
    [
        '"damper.damping_rate" = { distribution = "normal", three_sigma = "10 %" }',
        '"load.end_torque" = { distribution = "normal", sigma = "3 %" }',
        '"load.system_friction.at_0C" = { distribution = "uniform", plus_minus = "10 %" }',
    ]
)
SETTINGS = 'seed = 7\nsampling = "random"'
LONG_NAME = (
    "A deliberately long system name for a solar array hinge with an eddy current damper, "
    "qualification model, build 3"
)


def args(config: Path, out: Path, *extra: str) -> list[str]:
    return ["montecarlo", str(config), "--out", str(out), "--no-progress", *extra]


# --- reruns: --overwrite and --resume ---------------------------------------------------


def test_a_rerun_names_both_options_and_overwrite_replaces_only_the_run(tmp_path: Path) -> None:
    config = write_config(tmp_path, TIGHT, SETTINGS)
    out = tmp_path / "study"
    first = runner.invoke(app, args(config, out, "-n", "600", "--chunk-size", "200", "-T", "25"))
    assert first.exit_code == 0, first.output
    assert len(list((out / "chunks").glob("chunk-*.parquet"))) == 3
    # The user's own files in the folder are not the run's: --overwrite keeps them.
    (out / "notes.txt").write_text("mine", encoding="utf-8")
    (out / "plots" / "mine.png").write_bytes(b"mine")

    again = runner.invoke(app, args(config, out, "-n", "600", "--chunk-size", "200", "-T", "25"))
    assert again.exit_code == 2
    assert again.stderr.splitlines() == [
        f"error: --out {out}: this folder already holds a Monte Carlo run; add --resume to "
        "continue it, --overwrite to replace it, or choose another --out"
    ]

    both = runner.invoke(app, args(config, out, "-n", "600", "--resume", "--overwrite"))
    assert both.exit_code == 2
    assert both.stderr.startswith("error: --resume continues the run in --out and --overwrite")
    assert "Traceback" not in both.output + again.output

    # A different design (2 chunks of 300): the third chunk of the old run must not
    # survive next to the new run's two.
    replaced = runner.invoke(
        app, args(config, out, "-n", "600", "--chunk-size", "300", "-T", "25", "--overwrite")
    )
    assert replaced.exit_code == 0, replaced.output
    # manifest, summary, 3 chunks and 4 plots of the earlier run
    assert f"--overwrite: removed the earlier run's 9 file(s) in {out}" in replaced.stderr
    assert sorted(p.name for p in (out / "chunks").glob("*")) == [
        "chunk-000000.parquet",
        "chunk-000001.parquet",
    ]
    manifest = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
    assert manifest["identity"]["chunk_size"] == 300
    assert json.loads((out / SUMMARY).read_text(encoding="utf-8"))["chunk_size"] == 300
    assert (out / "notes.txt").read_text(encoding="utf-8") == "mine"
    assert (out / "plots" / "mine.png").read_bytes() == b"mine"


def test_overwrite_into_a_new_folder_is_a_plain_run(tmp_path: Path) -> None:
    config = write_config(tmp_path, TIGHT, SETTINGS)
    out = tmp_path / "fresh"
    result = runner.invoke(app, args(config, out, "-n", "200", "-T", "25", "--overwrite"))
    assert result.exit_code == 0, result.output
    assert "removed" not in result.stderr
    assert (out / SUMMARY).exists()


# --- plots ---------------------------------------------------------------------------------


def assert_title_inside(figure: object) -> None:
    """Every axes title of a drawn figure lies inside the figure: nothing is clipped."""
    from matplotlib.figure import Figure

    assert isinstance(figure, Figure)
    figure.draw_without_rendering()  # runs the constrained layout, as saving does
    width, height = figure.bbox.width, figure.bbox.height
    for axes in figure.axes:
        title = axes.title
        assert title.get_text()
        box = title.get_window_extent()
        assert box.x0 >= 0.0, title.get_text()
        assert box.y0 >= 0.0, title.get_text()
        assert box.x1 <= width, title.get_text()
        assert box.y1 <= height, title.get_text()


def test_titles_with_a_long_system_name_are_not_clipped(
    tmp_path: Path, saved_figures: SavedFigures
) -> None:
    base = PAPER_TEXT.replace(
        PAPER_TEXT.splitlines()[
            next(i for i, line in enumerate(PAPER_TEXT.splitlines()) if line.startswith("title"))
        ],
        f'title = "{LONG_NAME}"',
    )
    config = write_config(tmp_path, WIDE, SETTINGS, base=base)
    result = runner.invoke(app, args(config, tmp_path / "out", "-n", "500"))
    assert result.exit_code == 0, result.output
    for name in ("time_histogram", "time_cdf", "end_speed_histogram", "tornado"):
        figure = saved_figures.figures[f"{name}.png"]
        (axes,) = figure.axes
        # The whole name is there, on lines of their own, then what the plot shows.
        assert axes.get_title().replace("\n", " ").startswith(LONG_NAME)
        assert axes.get_xlabel().endswith("]")  # a unit
        assert_title_inside(figure)
    (histogram,) = saved_figures.axes("time_histogram.png")
    assert histogram.get_title().endswith("deployment time, 500 samples, exact method")
    assert saved_figures.legend(histogram) == ["-40 degC", "25 degC", "100 degC"]


def test_density_axes_carry_the_inverse_unit() -> None:
    assert density_label("deployment time [s]") == "probability density [1/s]"
    # 1/(rad/s) written as a unit an engineer reads: s/rad.
    assert density_label("end (latch) speed [rad/s]") == "probability density [s/rad]"
    assert density_label("torque [N*m]") == "probability density [1/(N*m)]"
    assert density_label("rate [1/s]") == "probability density [s]"


def test_each_temperature_has_its_own_bins_and_unit_area() -> None:
    rng = np.random.default_rng(3)
    wide = rng.normal(50.0, 5.0, 500)
    narrow = rng.normal(15.0, 0.5, 500)
    stalled = np.concatenate([narrow[:400], np.full(100, np.inf)])
    figure = plot_histogram({-40.0: wide, 100.0: stalled}, "deployment time [s]", "t")
    from matplotlib.patches import Polygon

    (axes,) = figure.axes
    polygons = [p for p in axes.patches if isinstance(p, Polygon)]
    assert len(polygons) == 2
    # Rice's rule by hand: 2 * 500^(1/3) = 15.87 -> 16 bins; 2 * 400^(1/3) = 14.74 -> 15.
    assert bin_count(500) == 16
    assert bin_count(400) == 15
    for polygon, finite, bins in ((polygons[0], wide, 16), (polygons[1], narrow[:400], 15)):
        xy = np.asarray(polygon.get_xy())
        edges = np.unique(xy[:, 0])
        assert edges.size == bins + 1
        # Each set's bins span its own range, not the union of both.
        assert edges[0] == pytest.approx(finite.min(), rel=1e-12)
        assert edges[-1] == pytest.approx(finite.max(), rel=1e-12)
        # A density: the step heights times the bin widths add up to 1 (to rounding).
        # The outline's horizontal segments are the bins' tops.
        dx, dy = np.diff(xy[:, 0]), np.diff(xy[:, 1])
        tops = (dy == 0.0) & (dx > 0.0)
        assert np.count_nonzero(tops) == bins
        assert np.sum(dx[tops] * xy[:-1, 1][tops]) == pytest.approx(1.0, rel=1e-9)
    legend = axes.get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == [
        "-40 degC",
        "100 degC (20 % stall)",
    ]
    assert axes.get_ylabel() == "probability density [1/s]"


def test_plots_of_synthetic_studies_keep_titles_inside() -> None:
    samples = {25.0: np.linspace(10.0, 12.0, 50)}
    title = study_title(LONG_NAME, "deployment time, 50 samples, exact method")
    assert_title_inside(plot_histogram(samples, "deployment time [s]", title))
    assert_title_inside(plot_cdf(samples, "deployment time [s]", title))
    keys = [f"load.a_rather_long_input_name_{i}.at_0C" for i in range(6)]
    summary = {
        "system": LONG_NAME,
        "method": "exact",
        "tolerances": [{"key": k} for k in keys],
        "cases": [
            {
                "temperature_C": t,
                "sensitivity": {
                    "r_squared": 0.99,
                    "inputs": [{"key": k, "src": 0.1 * i - 0.2} for i, k in enumerate(keys)],
                },
            }
            for t in (-40.0, 100.0)
        ],
    }
    assert_title_inside(plot_tornado(summary))


# --- repeatability in words ----------------------------------------------------------------


def test_required_spread_for_the_papers_500_runs() -> None:
    sigma = required_std(0.5, 500)
    # By hand: P(|x| <= 0.5) for x ~ N(0, sigma) is erf(0.5 / (sigma sqrt 2)); 500
    # independent runs all within with probability one half.
    assert math.erf(0.5 / (sigma * math.sqrt(2.0))) ** 500 == pytest.approx(0.5, rel=1e-12)
    # Tables: the two-sided tail 1 - 0.5^(1/500) = 1.386e-3 is z = 3.198 -> 0.5/3.198 s.
    assert sigma == pytest.approx(0.1564, abs=5e-5)  # 4-digit table value
    # One run: the median of |x| is 0.6745 sigma (the normal's quartile).
    assert required_std(0.6745, 1) == pytest.approx(1.0, abs=1e-4)


def test_chances_are_written_in_plain_terms() -> None:
    assert _chance(1.3e-180, True) == "< 0.01"  # tiny, not "1.3e-178 %"
    assert _chance(0.0, False) == "0"  # no sample within: impossible, not small
    assert _chance(0.4712, True) == "47.1"
    assert _chance(0.999995, True) == "> 99.99"
    assert _chance(1.0, True) == "100"


def repeat_rows(stdout: str) -> dict[float, list[str]]:
    rows = {}
    section = stdout.split("Repeatability:")[1]
    for line in section.splitlines():
        cells = [c.strip() for c in line.split("│")[1:-1]]
        if len(cells) == 7 and cells[0] in {"-40", "25", "100"}:
            rows[float(cells[0])] = cells
    return rows


def test_repeatability_table_against_hand_counts(tmp_path: Path) -> None:
    config = write_config(tmp_path, TIGHT, SETTINGS)
    out = tmp_path / "out"
    n = 4000
    result = runner.invoke(
        app, args(config, out, "-n", str(n), "-T", "-40", "--no-plot"), env={"COLUMNS": "120"}
    )
    assert result.exit_code == 0, result.output
    assert "Repeatability: 500 deployments of one unit, each within +-0.5 s" in result.stdout
    cells = repeat_rows(result.stdout)[-40.0]
    times = hand_times(out, -40.0)
    nominal = hand.exact_time(-40.0)
    deviation = np.abs(times - nominal)
    p = np.count_nonzero(deviation <= 0.5) / n
    campaign = p**500
    assert 1e-4 < campaign < 1 - 1e-4  # the configuration does what it is meant to
    # The largest of 500 draws has its median at the 0.5^(1/500) quantile.
    worst = np.quantile(deviation, 0.5 ** (1 / 500), method="inverted_cdf")
    # Columns: T, nominal, spread, one within, all 500 within, worst of 500, as paper.
    assert cells[1] == f"{nominal:.4g}"
    assert cells[2] == f"{np.std(times, ddof=1):.4g}"
    assert cells[3] == f"{100 * p:.3g}"
    assert cells[4] == f"{100 * campaign:.3g}"
    assert cells[5] == f"{worst:.4g}"
    ratio = np.std(times, ddof=1) / required_std(0.5, 500)
    assert cells[6] == ("yes" if worst <= 0.5 else f"no: {ratio:.2g}x")
    words = " ".join(result.stdout.split())
    assert "the chance that 500 deployments all do" in words
    assert "as the paper's one unit was over 500 deployments" in words
    assert "That needs a spread (1 sigma) of at most 0.156 s" in words


def test_unit_to_unit_tolerances_are_called_out(tmp_path: Path) -> None:
    config = write_config(tmp_path, WIDE, SETTINGS)
    out = tmp_path / "out"
    result = runner.invoke(
        app, args(config, out, "-n", "2000", "--no-plot"), env={"COLUMNS": "120"}
    )
    assert result.exit_code == 0, result.output
    rows = repeat_rows(result.stdout)
    assert sorted(rows) == [-40.0, 25.0, 100.0]
    for t, cells in rows.items():
        times = hand_times(out, t)
        p = np.count_nonzero(np.abs(times - hand.exact_time(t)) <= 0.5) / times.size
        assert 0.0 < p < 0.9  # far from the paper's repeatability
        assert cells[4] == "< 0.01"  # p^500 < 1e-4: not 1.3e-178
        # How many times the spread one unit may have (issue 26 item 10: "no" says why).
        ratio = np.std(times, ddof=1) / required_std(0.5, 500)
        assert cells[6] == f"no: {ratio:.2g}x"
    words = " ".join(result.stdout.split())
    assert "At -40, 25, 100 degC the spread is far wider than one unit's" in words
    assert "'no' says that different units differ by more than +-0.5 s" in words


def test_every_sample_within_shows_the_lower_bound_below_100() -> None:
    from ecdsim.cli.montecarlo import _lower_bound

    # 20 000 samples all within: the exact (Clopper-Pearson) 95 % interval's lower end is
    # 0.025^(1/20000) = 0.999816 by hand, and 500 runs all within at least its 500th
    # power, 0.912. Shown so that it never reads "> 100".
    low = 0.025 ** (1 / 20000)
    assert _lower_bound(low) == "99.98"
    assert _lower_bound(low**500) == "91.2"
    assert _lower_bound(1e-5) == "0"

"""The drop test's timing-noise model (``--noise timing``, issue 11 item 6).

A drop times a fixed angle; with the masses and the radius known precisely, the error
is in the recorded time, and relative (1 % of the drop). Under that model the line is
fitted as least squares of ``log t`` against the model's drop time (docs/characterize.md
section 1). Checked here against independent oracles: the drop time by a root finder on
the typed start-up angle, the fit by ``scipy.optimize.curve_fit`` of the typed model,
the exact-data fit with a large transient, and the per-temperature intervals' coverage.
The coverage of the laws over temperature under timing noise is in
``tests/test_characterize_coverage.py``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import curve_fit

from ecdsim.characterize.droptest import (
    NOISE_MODELS,
    drop_time,
    fit_drop_test,
    fit_temperature,
    noise_model,
)
from tests.test_characterize_coverage import binomial_band
from tests.test_characterize_synthetic import G, Truth, drop_csv, drop_points, startup_time

TRUTH = Truth()
MASSES = [3.0, 4.5, 6.0, 7.5, 9.0]  # kg
RADIUS, ANGLE = 0.05, math.pi  # m, rad


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "drops.csv"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("steady", "damping", "inertia"),
    [
        (0.5, 24.0, 0.0),  # no inertia: theta / w_ss
        (0.5, 24.0, 0.005),  # the example rig: tau = 0.2 ms against a 6 s drop
        (2.0, 0.05, 0.01),  # tau = 0.2 s against a 1.6 s drop
        (2.0, 0.05, 10.0),  # tau = 200 s >> the drop: the shaft never nears w_ss
    ],
)
def test_drop_time_is_the_root_of_the_start_up_angle(
    steady: float, damping: float, inertia: float
) -> None:
    # The oracle: brentq on the typed theta(t) = w_ss (t - tau (1 - exp(-t / tau)))
    # (tests/test_characterize_synthetic.py, xtol 1e-15). Newton's answer agrees to
    # round-off of t: 1e-12 relative.
    expected = startup_time(ANGLE, steady, damping, inertia)
    assert float(drop_time(ANGLE, steady, damping, inertia)) == pytest.approx(expected, rel=1e-12)


def test_drop_time_broadcasts() -> None:
    # Scalar, 1-D and 2-D speeds give the elementwise answers of the scalar calls.
    speeds = np.array([[0.2, 0.5], [1.0, 2.0]])
    grid = drop_time(ANGLE, speeds, 24.0, 0.5)
    assert grid.shape == (2, 2)
    for (i, j), w in np.ndenumerate(speeds):
        assert grid[i, j] == pytest.approx(startup_time(ANGLE, float(w), 24.0, 0.5), rel=1e-12)
    assert drop_time(ANGLE, speeds[0], 24.0, 0.5).shape == (2,)


def test_timing_fit_is_the_least_squares_fit_of_log_time() -> None:
    # One temperature, 1 % relative timing noise, no inertia: the model is
    # log t = log(theta) + log(BECD) - log(torque - FECD). scipy's curve_fit of that
    # typed model (absolute_sigma=False: covariance scaled by SSR / (n - 2)) is the
    # oracle for the estimates and the covariance; intervals are t(0.975, n - 2) * se.
    rng = np.random.default_rng(11)
    b, f = TRUTH.damping(25.0), TRUTH.friction(25.0)
    torque = np.array(MASSES) * G * RADIUS
    time = ANGLE * b / (torque - f) * (1.0 + 0.01 * rng.standard_normal(torque.size))
    fit = fit_temperature(
        25.0, np.arange(5), torque, np.full(5, ANGLE), time, np.zeros(5), noise="timing"
    )

    def log_time(x: np.ndarray, friction: float, damping: float) -> np.ndarray:
        return np.asarray(np.log(ANGLE) + np.log(damping) - np.log(x - friction), dtype=float)

    popt, pcov = curve_fit(log_time, torque, np.log(time), p0=[f, b], xtol=1e-14, ftol=1e-14)
    # Two minimisers of the same smooth problem (LM in a different parametrisation vs
    # curve_fit's): 1e-8 relative; the covariances differ by curve_fit's
    # finite-difference Jacobian: 1e-5.
    assert fit.line.intercept.value == pytest.approx(popt[0], rel=1e-8)
    assert fit.line.slope.value == pytest.approx(popt[1], rel=1e-8)
    assert fit.line.statistics.covariance == pytest.approx(pcov, rel=1e-5)
    half = float(stats.t.ppf(0.975, 3)) * math.sqrt(pcov[1, 1])
    assert fit.line.slope.ci95 == pytest.approx((popt[1] - half, popt[1] + half), rel=1e-6)
    # The residual scatter is the relative timing scatter: its square is SSR / (n - 2)
    # of the log times.
    ssr = float(np.sum((np.log(time) - log_time(torque, *popt)) ** 2))
    assert fit.line.statistics.residual_std == pytest.approx(math.sqrt(ssr / 3), rel=1e-6)
    assert fit.noise == "timing"
    assert fit.speed_noise_bias is None  # the model fits the speed error: no dilution
    entry = fit.to_dict()
    assert entry["noise_model"] == "timing"
    assert entry["residual_std_Nm"] is None
    assert entry["relative_time_std"] == pytest.approx(math.sqrt(ssr / 3), rel=1e-6)
    # The points' torque residuals are torque minus the line at the (corrected) speed.
    residuals = [p["residual_Nm"] for p in entry["points"]]
    line = fit.line.intercept.value + fit.line.slope.value * ANGLE / time
    assert residuals == pytest.approx(list(torque - line), rel=1e-9, abs=1e-15)


def test_exact_data_with_a_large_start_up_transient_are_recovered(tmp_path: Path) -> None:
    # Exact drop times from brentq on the typed start-up angle (a 20 kg*m**2 rig: tau
    # about 1 s against 3 to 25 s drops): the timing fit recovers the truth to 1e-9.
    temperatures = [-40.0, 25.0, 100.0]
    points = drop_points(TRUTH, temperatures, MASSES, rig_inertia=20.0, angle=math.pi / 2)
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=True)), noise="timing")
    assert result.noise == "timing"
    assert result.to_dict()["noise_model"] == "timing"
    for fit in result.fits:
        assert fit.corrected_for_inertia
        assert float(np.max(fit.correction)) > 0.05
        assert fit.line.slope.value == pytest.approx(TRUTH.damping(fit.temperature), rel=1e-9)
        assert fit.line.intercept.value == pytest.approx(TRUTH.friction(fit.temperature), rel=1e-9)


@pytest.mark.slow
def test_noisy_timing_fits_with_a_transient_cover_95_percent() -> None:
    # The start-up-corrected timing fit (tau about 1 s against 3 to 25 s drops), 1 %
    # timing noise, 400 data sets: each per-temperature interval covers within
    # 0.95 +- 3.5 sqrt(0.95 * 0.05 / 400) = [0.912, 0.988] (3.5 sigma as for the
    # torque-noise fit in tests/test_characterize_droptest.py).
    rng = np.random.default_rng(20261123)
    seeds, covered_b, covered_f = 400, 0, 0
    b, f = TRUTH.damping(25.0), TRUTH.friction(25.0)
    points = drop_points(TRUTH, [25.0], MASSES, rig_inertia=20.0, angle=math.pi / 2)
    exact = np.array([p.time for p in points])
    for _ in range(seeds):
        fit = fit_temperature(
            25.0,
            np.arange(len(points)),
            [p.true_torque for p in points],
            [p.angle for p in points],
            exact * (1.0 + 0.01 * rng.standard_normal(exact.size)),
            [20.0 + p.mass * p.radius**2 for p in points],
            noise="timing",
        )
        slope, intercept = fit.line.slope.ci95, fit.line.intercept.ci95
        assert slope is not None
        assert intercept is not None
        covered_b += slope[0] <= b <= slope[1]
        covered_f += intercept[0] <= f <= intercept[1]
    low, high = binomial_band(0.95, seeds, k=3.5)
    assert low <= covered_b / seeds <= high
    assert low <= covered_f / seeds <= high


def test_an_unknown_noise_model_names_the_choices() -> None:
    assert set(NOISE_MODELS) == {"torque", "timing"}
    with pytest.raises(
        ValueError, match="unknown noise model 'speed'; choose one of: torque, timing"
    ):
        noise_model("speed")

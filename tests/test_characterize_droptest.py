"""Drop-test reduction: steady and start-up-corrected fits, per-temperature failures."""

from __future__ import annotations

import inspect
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ecdsim.characterize.droptest import (
    corrected_speed,
    drive_torque,
    falling_mass_inertia,
    fit_drop_test,
    fit_temperature,
    startup_angle,
    steady_speed,
    transient_lag,
)
from ecdsim.characterize.linefit import LineFitError
from ecdsim.characterize.templaws import resistivity_law
from tests.test_atomic_and_docs import PARAMETER
from tests.test_characterize_linefit import binomial_band
from tests.test_characterize_synthetic import G, Truth, drop_csv, drop_points

TRUTH = Truth()
TEMPERATURES = [-40.0, 25.0, 100.0]
MASSES = [2.0, 3.5, 5.0, 6.5, 8.0, 9.5]  # kg on a 50 mm flywheel: 1 to 4.7 N*m


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "drops.csv"
    path.write_text(text, encoding="utf-8")
    return path


def test_exact_steady_data_recover_every_temperature(tmp_path: Path) -> None:
    points = drop_points(TRUTH, TEMPERATURES, MASSES, rig_friction=0.01)
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=False)))
    assert [f.temperature for f in result.fits] == TEMPERATURES
    for fit in result.fits:
        t = fit.temperature
        # Noise-free data: only round-off (repr in the CSV, the OLS solve) remains.
        assert fit.line.slope.value == pytest.approx(TRUTH.damping(t), rel=1e-9)
        assert fit.line.intercept.value == pytest.approx(TRUTH.friction(t), rel=1e-9)
        assert not fit.corrected_for_inertia
    assert result.failed == ()
    assert result.laws is not None
    linear = result.laws.damping["linear"]
    assert linear.parameters[0].value == pytest.approx(TRUTH.b_ref, rel=1e-9)
    assert linear.parameters[1].value == pytest.approx(TRUTH.c, rel=1e-9)
    assert result.laws.friction is not None
    at_0c, slope = result.laws.friction.parameters
    assert at_0c.value == pytest.approx(TRUTH.at_0c, rel=1e-9)
    assert slope.value == pytest.approx(TRUTH.slope, rel=1e-9)
    assert result.laws.comparison.better == "linear"


def test_exact_data_with_a_large_start_up_transient_are_recovered(tmp_path: Path) -> None:
    # A 20 kg*m**2 rig: tau = J / B is about 1 s against drop times of 3 to 25 s, so
    # steady-state reading would be several per cent off; the exact correction is not.
    points = drop_points(TRUTH, TEMPERATURES, MASSES, rig_inertia=20.0, angle=math.pi / 2)
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=True)))
    for fit in result.fits:
        t = fit.temperature
        b = TRUTH.damping(t)
        assert fit.corrected_for_inertia
        assert fit.line.slope.value == pytest.approx(b, rel=1e-9)
        assert fit.line.intercept.value == pytest.approx(TRUTH.friction(t), rel=1e-9)
        # The reported correction is lag / (t - lag) with lag = tau (1 - exp(-t / tau)),
        # tau = J / B, J = J_rig + m r**2 (hand formula of the synthetic data).
        inertia = 20.0 + np.array(MASSES) * 0.05**2
        time = np.array([p.time for p in points if p.temperature == t])
        tau = inertia / b
        lag = tau * (1.0 - np.exp(-time / tau))
        assert fit.correction == pytest.approx(lag / (time - lag), rel=1e-7)
        assert float(np.max(fit.correction)) > 0.05
    assert {w.code for w in result.warnings} >= {"inertia_correction"}


def test_ignoring_the_transient_biases_the_fit_and_warns(tmp_path: Path) -> None:
    # A small damper (0.05 N*m*s/rad) and light masses: the falling mass's own m r**2
    # gives tau = 5 to 25 ms against drop times of a few tenths of a second.
    small = Truth(b_ref=0.05, slope=0.0, at_0c=0.01)
    masses = [0.1, 0.2, 0.3, 0.4, 0.5]
    points = drop_points(small, [25.0], masses, rig_inertia=0.0, angle=math.pi / 8)
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=False)))
    (fit,) = result.fits
    # Without the column the transient is not corrected: the fit is biased by percents.
    assert abs(fit.line.slope.value / small.damping(25.0) - 1.0) > 0.01
    codes = [w.code for w in result.warnings]
    assert "inertia_not_given" in codes
    assert "single_temperature" in codes
    assert result.laws is None
    # With the column (rig inertia 0: only m r**2) the same drops are fitted exactly.
    corrected = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=True)))
    assert corrected.fits[0].line.slope.value == pytest.approx(small.damping(25.0), rel=1e-9)


def test_noisy_corrected_fits_cover_95_percent() -> None:
    # The start-up-corrected fit is non-linear; its Jacobian intervals must still cover.
    rng = np.random.default_rng(20240602)
    seeds, covered_b, covered_f = 400, 0, 0
    b, f = TRUTH.damping(25.0), TRUTH.friction(25.0)
    for _ in range(seeds):
        points = drop_points(
            TRUTH, [25.0], MASSES, rig_inertia=20.0, angle=math.pi / 2, torque_noise=0.01, rng=rng
        )
        fit = fit_temperature(
            25.0,
            np.arange(len(points)),
            [p.mass * G * p.radius for p in points],
            [p.angle for p in points],
            [p.time for p in points],
            [20.0 + p.mass * p.radius**2 for p in points],
        )
        slope, intercept = fit.line.slope.ci95, fit.line.intercept.ci95
        assert slope is not None
        assert intercept is not None
        covered_b += slope[0] <= b <= slope[1]
        covered_f += intercept[0] <= f <= intercept[1]
    low, high = binomial_band(0.95, seeds)
    assert low <= covered_b / seeds <= high
    assert low <= covered_f / seeds <= high


def test_noisy_example_style_data_fall_within_the_intervals(tmp_path: Path) -> None:
    rng = np.random.default_rng(17)
    points = drop_points(
        TRUTH,
        TEMPERATURES,
        MASSES,
        rig_friction=0.02,
        rig_inertia=0.005,
        torque_noise=0.01,
        rng=rng,
    )
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=True)))
    for fit in result.fits:
        t = fit.temperature
        assert fit.line.slope.ci95 is not None
        assert fit.line.intercept.ci95 is not None
        assert fit.line.slope.ci95[0] < TRUTH.damping(t) < fit.line.slope.ci95[1]
        assert fit.line.intercept.ci95[0] < TRUTH.friction(t) < fit.line.intercept.ci95[1]


def test_a_temperature_with_one_speed_fails_alone(tmp_path: Path) -> None:
    points = drop_points(TRUTH, TEMPERATURES, MASSES) + drop_points(TRUTH, [60.0], [5.0])
    result = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=False)))
    assert [f.temperature for f in result.fits] == TEMPERATURES
    (failed,) = result.failed
    assert failed.temperature == 60.0
    assert failed.rows == (20,)
    assert "fewer than two distinct speeds" in failed.reason
    assert failed.message().startswith("60 degC (rows 20): fewer than two distinct speeds")
    assert result.laws is not None  # the other three temperatures still give the laws


def test_a_falling_line_is_an_error_for_its_temperature() -> None:
    with pytest.raises(LineFitError, match="not positive"):
        fit_temperature(25.0, [2, 3], [2.0, 1.0], [3.0, 3.0], [10.0, 5.0], [0.0, 0.0])


def test_transient_lag_limits() -> None:
    # J = 0: no lag. t >> tau: lag -> tau. t << tau: lag -> t (the shaft has not moved).
    assert transient_lag(5.0, 24.0, 0.0) == 0.0
    assert transient_lag(100.0, 2.0, 1.0) == pytest.approx(0.5, rel=1e-15)
    assert transient_lag(1e-6, 2.0, 1.0) == pytest.approx(1e-6, rel=1e-5)  # 1 - t/2tau


def test_json_document_has_the_issue_keys(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    points = drop_points(TRUTH, TEMPERATURES, MASSES, torque_noise=0.01, rng=rng)
    document = fit_drop_test(write(tmp_path, drop_csv(points, inertia_column=False))).to_dict()
    entry = document["temperatures"][0]
    for key in (
        "temperature_C",
        "damping_rate_Nms_per_rad",
        "damping_rate_ci95_Nms_per_rad",
        "friction_Nm",
        "friction_ci95_Nm",
        "r_squared",
        "n_points",
        "roll_off",
        "outlier_rows",
        "points",
    ):
        assert key in entry
    assert entry["n_points"] == len(MASSES)
    assert len(entry["damping_rate_ci95_Nms_per_rad"]) == 2
    laws = document["temperature_laws"]
    assert set(laws["damping_rate"]) == {"linear", "resistivity"}
    assert "better" in laws["comparison"]
    assert document["bad_rows"] == []


def _speed_noise_bias_by_numpy(torque: np.ndarray, speed: np.ndarray) -> tuple[float, float]:
    """(reported fraction, slope) by the formula of the docstring, with numpy's polyfit.

    Residual variance with n - 2 degrees of freedom, over the slope squared: the speed
    variance that would explain it; divided by the variance of the measured speeds.
    """
    slope, intercept = np.polyfit(speed, torque, 1)
    residual = torque - (intercept + slope * speed)
    sigma_w_squared = float(residual @ residual) / (speed.size - 2) / slope**2
    return sigma_w_squared / float(np.var(speed)), float(slope)


def test_timing_noise_bias_is_estimated_and_flagged(tmp_path: Path) -> None:
    # Torques exact, times with 10 % scatter: regression dilution lowers BECD (Draper and
    # Smith, section 3.4); the fit reports by how much it would if all the scatter were
    # timing error, and warns.
    rng = np.random.default_rng(21)
    points = drop_points(TRUTH, [25.0], MASSES * 4)
    noisy = [replace(p, time=p.time * (1.0 + 0.1 * rng.standard_normal())) for p in points]
    result = fit_drop_test(write(tmp_path, drop_csv(noisy, inertia_column=False)))
    (fit,) = result.fits
    assert "speed_noise_bias" in [w.code for w in result.warnings]
    torque = np.array([p.mass * G * p.radius for p in noisy])
    speed = np.array([p.angle / p.time for p in noisy])
    expected, _ = _speed_noise_bias_by_numpy(torque, speed)
    # The same arithmetic by lstsq and by polyfit: rounding only (measured 4e-15).
    assert fit.speed_noise_bias == pytest.approx(expected, rel=1e-9)

    # Does the fraction estimate the dilution it warns about? Over 1000 seeded repeats,
    # its mean against the mean actual shortfall of the slope, 1 - b / BECD, taken from
    # the same repeats (paired). Five standard errors of the paired mean difference: a
    # correct estimator fails with probability below 1e-6. (The first-order target
    # sigma_w**2 / var(w) differs from the exact shortfall by about sigma_w**2 / var(w)
    # of itself, 4 % here, under two standard errors.)
    repeats, estimates, shortfalls = 1000, [], []
    b_true = TRUTH.damping(25.0)
    times = np.array([p.time for p in points])
    angle = np.array([p.angle for p in points])
    torque = np.array([p.mass * G * p.radius for p in points])
    for _ in range(repeats):
        measured = times * (1.0 + 0.1 * rng.standard_normal(times.size))
        one = fit_temperature(25.0, np.arange(times.size), torque, angle, measured, 0.0 * times)
        assert one.speed_noise_bias is not None
        by_numpy, slope = _speed_noise_bias_by_numpy(torque, angle / measured)
        assert one.speed_noise_bias == pytest.approx(by_numpy, rel=1e-9)
        estimates.append(one.speed_noise_bias)
        shortfalls.append(1.0 - slope / b_true)
    difference = np.array(estimates) - np.array(shortfalls)
    standard_error = float(np.std(difference, ddof=1)) / math.sqrt(repeats)
    assert abs(float(np.mean(difference))) <= 5.0 * standard_error
    # Not trivially close: the shortfall is 10 standard errors away from zero.
    assert float(np.mean(shortfalls)) > 10.0 * standard_error


@pytest.mark.parametrize(
    "function",
    [
        drive_torque,
        falling_mass_inertia,
        steady_speed,
        transient_lag,
        startup_angle,
        corrected_speed,
        resistivity_law,
    ],
)
def test_physical_functions_document_units_and_sources(function: object) -> None:
    # The same contract the core's physics functions are held to (test_atomic_and_docs).
    assert callable(function)
    doc = inspect.getdoc(function) or ""
    documented = set(PARAMETER.findall("    " + doc.replace("\n", "\n    ")))
    missing = set(inspect.signature(function).parameters) - documented
    assert not missing, f"undocumented parameters: {missing}"
    assert re.search(r"Eq\.|paper|section|ECD", doc)


def test_the_start_up_jacobian_matches_finite_differences() -> None:
    # The corrected fit's analytic d lag / d BECD against a central difference of
    # transient_lag (step 1e-6 relative: truncation ~1e-12, round-off ~1e-10).
    from ecdsim.characterize.droptest import _lag_derivative

    time = np.array([0.01, 0.5, 3.0, 40.0])
    inertia = np.array([2.0, 2.0, 0.5, 0.0])
    b, h = 24.0, 24.0e-6
    numeric = (transient_lag(time, b + h, inertia) - transient_lag(time, b - h, inertia)) / (2 * h)
    assert _lag_derivative(time, b, inertia) == pytest.approx(numeric, rel=1e-7, abs=1e-15)

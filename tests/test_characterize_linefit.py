"""The torque-speed line: OLS by hand and against scipy, interval coverage, flags."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from ecdsim.characterize.linefit import (
    BENDING_LEVEL,
    OUTLIER_LEVEL,
    LineFitError,
    curvature_test,
    fit_line,
)

SEEDS = 1000
SPEEDS = np.linspace(0.02, 0.2, 8)  # rad/s, a drop test's range (paper Figure 8 scale)
B_TRUE, F_TRUE, NOISE = 24.0, 0.52, 0.02  # N*m*s/rad, N*m, N*m


def binomial_band(p: float, n: int, k: float = 3.5) -> tuple[float, float]:
    """p +- k standard deviations of a binomial proportion over n trials.

    With k = 3.5 a correct implementation fails such a check with probability ~5e-4.
    """
    sigma = math.sqrt(p * (1.0 - p) / n)
    return p - k * sigma, p + k * sigma


def test_line_matches_a_hand_calculation() -> None:
    # x = 1..4, y = 2.1, 3.9, 6.2, 7.8. By hand: xbar = 2.5, ybar = 5, Sxx = 5, Sxy = 9.7,
    # slope 1.94, intercept 0.15, residuals 0.01 -0.13 0.23 -0.11, SSR 0.082, s**2 0.041,
    # se(slope) = sqrt(0.041/5), se(intercept) = sqrt(0.041 * (1/4 + 2.5**2/5)),
    # t(0.975, 2) = 4.302653, SST = 18.9.
    fit = fit_line([1.0, 2.0, 3.0, 4.0], [2.1, 3.9, 6.2, 7.8])
    assert fit.slope.value == pytest.approx(1.94, rel=1e-12)  # float64 round-off only
    assert fit.intercept.value == pytest.approx(0.15, rel=1e-11)
    assert fit.statistics.residuals == pytest.approx([0.01, -0.13, 0.23, -0.11], abs=1e-12)
    se_slope = math.sqrt(0.041 / 5.0)
    se_intercept = math.sqrt(0.041 * 1.5)
    assert fit.slope.standard_error == pytest.approx(se_slope, rel=1e-10)
    assert fit.intercept.standard_error == pytest.approx(se_intercept, rel=1e-10)
    assert fit.slope.ci95 == pytest.approx(
        (1.94 - 4.302653 * se_slope, 1.94 + 4.302653 * se_slope), rel=1e-6
    )  # the t quantile is typed to 7 digits
    assert fit.r_squared == pytest.approx(1.0 - 0.082 / 18.9, rel=1e-12)
    assert fit.statistics.dof == 2


def test_line_agrees_with_scipy_linregress() -> None:
    rng = np.random.default_rng(7)
    x = rng.uniform(0.01, 0.3, 12)
    y = F_TRUE + B_TRUE * x + rng.normal(0.0, NOISE, x.size)
    fit = fit_line(x, y)
    ref = stats.linregress(x, y)
    # Two implementations of the same closed form: agreement to float64 round-off.
    assert fit.slope.value == pytest.approx(ref.slope, rel=1e-12)
    assert fit.intercept.value == pytest.approx(ref.intercept, rel=1e-10)
    assert fit.slope.standard_error == pytest.approx(ref.stderr, rel=1e-9)
    assert fit.intercept.standard_error == pytest.approx(ref.intercept_stderr, rel=1e-9)
    assert fit.r_squared == pytest.approx(ref.rvalue**2, rel=1e-12)


def test_exact_data_recover_the_parameters() -> None:
    fit = fit_line(SPEEDS, F_TRUE + B_TRUE * SPEEDS)
    # Noise-free: only float64 round-off, far below the required 1e-9.
    assert fit.slope.value == pytest.approx(B_TRUE, rel=1e-9)
    assert fit.intercept.value == pytest.approx(F_TRUE, rel=1e-9)
    assert fit.statistics.exact
    assert not fit.outliers.any()
    assert fit.curvature is not None
    assert fit.curvature.p_value == 1.0  # straight: no evidence of bending
    assert np.isnan(fit.studentized).all()  # no scatter to studentise by


def test_noisy_data_fall_within_the_intervals_and_cover_95_percent() -> None:
    rng = np.random.default_rng(20240601)
    covered_b = covered_f = bending = outliers = 0
    for _ in range(SEEDS):
        y = F_TRUE + B_TRUE * SPEEDS + rng.normal(0.0, NOISE, SPEEDS.size)
        fit = fit_line(SPEEDS, y)
        assert fit.slope.ci95 is not None
        assert fit.intercept.ci95 is not None
        covered_b += fit.slope.ci95[0] <= B_TRUE <= fit.slope.ci95[1]
        covered_f += fit.intercept.ci95[0] <= F_TRUE <= fit.intercept.ci95[1]
        assert fit.curvature is not None
        bending += fit.curvature.bending
        outliers += bool(fit.outliers.any())
    low, high = binomial_band(0.95, SEEDS)
    assert low <= covered_b / SEEDS <= high
    assert low <= covered_f / SEEDS <= high
    # The flags are 1 % tests: on clean data they fire at about that rate.
    for count, level in ((bending, BENDING_LEVEL), (outliers, OUTLIER_LEVEL)):
        assert count / SEEDS <= binomial_band(level, SEEDS)[1]


def test_one_seed_recovers_the_truth_within_its_intervals() -> None:
    rng = np.random.default_rng(3)
    fit = fit_line(SPEEDS, F_TRUE + B_TRUE * SPEEDS + rng.normal(0.0, NOISE, SPEEDS.size))
    assert fit.slope.ci95 is not None
    assert fit.intercept.ci95 is not None
    assert fit.slope.ci95[0] < B_TRUE < fit.slope.ci95[1]
    assert fit.intercept.ci95[0] < F_TRUE < fit.intercept.ci95[1]


def test_roll_off_is_flagged() -> None:
    # Torque bending down by 8 % at the top speed (a damper past its linear range),
    # with noise 50 times smaller than the bend.
    rng = np.random.default_rng(11)
    y = F_TRUE + B_TRUE * SPEEDS * (1.0 - 0.4 * SPEEDS) + rng.normal(0.0, 0.002, SPEEDS.size)
    fit = fit_line(SPEEDS, y)
    assert fit.curvature is not None
    assert fit.curvature.roll_off
    assert fit.curvature.quadratic == pytest.approx(-0.4 * B_TRUE, rel=0.05)  # noise 0.2 %


def test_upward_bending_is_flagged_but_is_not_roll_off() -> None:
    y = F_TRUE + B_TRUE * SPEEDS * (1.0 + 0.4 * SPEEDS)
    result = curvature_test(SPEEDS, y)
    assert result is not None
    assert result.bending
    assert not result.roll_off
    assert result.p_value == 0.0  # exact and curved


def test_an_outlier_is_flagged_at_its_point() -> None:
    rng = np.random.default_rng(5)
    y = F_TRUE + B_TRUE * SPEEDS + rng.normal(0.0, NOISE, SPEEDS.size)
    y[5] += 12 * NOISE
    fit = fit_line(SPEEDS, y)
    assert fit.outliers.tolist() == [i == 5 for i in range(SPEEDS.size)]


def test_two_points_give_a_line_without_uncertainty() -> None:
    fit = fit_line([0.1, 0.2], [2.92, 5.32])
    assert fit.slope.value == pytest.approx(24.0, rel=1e-12)  # (5.32 - 2.92) / 0.1
    assert fit.intercept.value == pytest.approx(0.52, rel=1e-12)
    assert fit.slope.ci95 is None
    assert fit.slope.standard_error is None
    assert fit.statistics.dof == 0
    assert fit.curvature is None
    assert not fit.outliers.any()


def test_too_few_distinct_speeds_or_loads_is_a_clear_error() -> None:
    with pytest.raises(LineFitError, match="fewer than two distinct speeds"):
        fit_line([0.1, 0.1, 0.1], [2.0, 2.1, 2.2])
    with pytest.raises(LineFitError, match="fewer than two distinct speeds"):
        fit_line([0.1], [2.0])
    with pytest.raises(LineFitError, match="same torque"):
        fit_line([0.1, 0.11, 0.12], [2.0, 2.0, 2.0])

"""Laws over temperature: recovery, agreement with curve_fit, comparison, coverage."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import curve_fit

from ecdsim.characterize.linefit import fit_line
from ecdsim.characterize.stats import Estimate
from ecdsim.characterize.templaws import (
    DAMPING_LAWS,
    FRICTION_LINE,
    fit_law,
    fit_temperature_laws,
    resistivity_law,
)
from tests.test_characterize_linefit import binomial_band

TEMPS = np.array([-40.0, -10.0, 25.0, 60.0, 100.0])
B_REF, C, ALPHA = 24.0, -0.004, 0.004


def linear_truth(t: np.ndarray) -> np.ndarray:
    return B_REF * (1.0 + C * (t - 25.0))


def resistivity_truth(t: np.ndarray) -> np.ndarray:
    return B_REF / (1.0 + ALPHA * (t - 25.0))


def with_errors(values: np.ndarray, relative: float) -> list[Estimate]:
    return [Estimate(float(v), relative * float(v), None) for v in values]


def test_resistivity_law_by_hand() -> None:
    # 24 / (1 + 0.004 * 75) = 24 / 1.3
    assert float(resistivity_law(100.0, 24.0, 0.004)) == pytest.approx(24.0 / 1.3, rel=1e-15)


@pytest.mark.parametrize(
    ("name", "truth", "coefficient"),
    [("linear", linear_truth, C), ("resistivity", resistivity_truth, ALPHA)],
)
def test_exact_values_recover_each_law(name: str, truth: object, coefficient: float) -> None:
    assert callable(truth)
    fit = fit_law(DAMPING_LAWS[name], TEMPS, with_errors(truth(TEMPS), 0.01))
    # Noise-free: the least-squares solution is the truth to round-off.
    assert fit.parameters[0].value == pytest.approx(B_REF, rel=1e-9)
    assert fit.parameters[1].value == pytest.approx(coefficient, rel=1e-9)
    assert fit.chi_square == pytest.approx(0.0, abs=1e-18)


@pytest.mark.parametrize("name", ["linear", "resistivity"])
def test_weighted_fit_agrees_with_scipy_curve_fit(name: str) -> None:
    rng = np.random.default_rng(4)
    sigma = 0.02 * linear_truth(TEMPS)
    y = linear_truth(TEMPS) + rng.normal(0.0, sigma)
    values = [Estimate(float(v), float(s), None) for v, s in zip(y, sigma, strict=True)]
    fit = fit_law(DAMPING_LAWS[name], TEMPS, values)

    def model(t: np.ndarray, b: float, k: float) -> np.ndarray:
        if name == "linear":
            return b * (1.0 + k * (t - 25.0))
        return b / (1.0 + k * (t - 25.0))

    ref, ref_cov = curve_fit(
        model, TEMPS, y, p0=[20.0, 0.0], sigma=sigma, absolute_sigma=True, xtol=1e-14, ftol=1e-14
    )
    # Two optimisers of the same weighted problem, both run to 1e-14 steps; the small
    # coefficient (4e-3) is the last to settle: agreement to 1e-8 relative.
    assert fit.parameter_values == pytest.approx(ref, rel=1e-8)
    if not fit.scaled:
        assert fit.covariance == pytest.approx(ref_cov, rel=1e-5)


def test_unweighted_fit_uses_the_scatter_like_curve_fit() -> None:
    rng = np.random.default_rng(8)
    y = linear_truth(TEMPS) + rng.normal(0.0, 0.3, TEMPS.size)
    fit = fit_law(DAMPING_LAWS["linear"], TEMPS, [Estimate(float(v), None, None) for v in y])
    ref, ref_cov = curve_fit(
        lambda t, b, k: b * (1.0 + k * (t - 25.0)),
        TEMPS,
        y,
        p0=[20.0, 0.0],
        absolute_sigma=False,
        xtol=1e-14,
        ftol=1e-14,
    )
    assert not fit.weighted
    assert fit.parameter_values == pytest.approx(ref, rel=1e-9)
    assert fit.covariance == pytest.approx(ref_cov, rel=1e-5)
    assert fit.quantile == pytest.approx(stats.t.ppf(0.975, TEMPS.size - 2), rel=1e-12)


def test_a_law_missing_its_errors_is_scaled_and_warned() -> None:
    # Resistivity-law values with 0.1 % errors: the linear law misses them by far more.
    fit = fit_law(DAMPING_LAWS["linear"], TEMPS, with_errors(resistivity_truth(TEMPS), 0.001))
    assert fit.p_value is not None
    assert fit.p_value < 0.01
    assert fit.scaled
    assert fit.quantile == pytest.approx(stats.t.ppf(0.975, 3), rel=1e-12)


def test_comparison_names_the_true_law() -> None:
    for truth, expected in ((linear_truth, "linear"), (resistivity_truth, "resistivity")):
        laws = fit_temperature_laws(
            TEMPS, with_errors(truth(TEMPS), 0.002), with_errors(0.5 - 0.002 * TEMPS, 0.01)
        )
        assert laws.comparison.better == expected
        assert expected in laws.comparison.statement


def test_comparison_with_two_temperatures_or_wide_errors_decides_nothing() -> None:
    two = fit_temperature_laws(
        [-40.0, 100.0],
        with_errors(linear_truth(np.array([-40.0, 100.0])), 0.01),
        with_errors(np.array([0.6, 0.3]), 0.01),
    )
    assert two.comparison.better is None
    assert "two temperatures" in two.comparison.statement
    # Both laws fit within 20 % errors: the data cannot tell them apart.
    wide = fit_temperature_laws(
        TEMPS, with_errors(linear_truth(TEMPS), 0.2), with_errors(0.5 - 0.002 * TEMPS, 0.01)
    )
    assert wide.comparison.better is None
    assert "do not tell the laws apart" in wide.comparison.statement


def test_laws_that_cannot_be_determined_are_reported_not_raised() -> None:
    # Zero damping at every temperature: B_ref = 0 leaves the coefficient without any
    # effect, so neither damping law is determined; the friction line still is.
    laws = fit_temperature_laws(
        TEMPS,
        [Estimate(0.0, 0.01, None)] * TEMPS.size,
        with_errors(0.5 - 0.002 * TEMPS, 0.01),
    )
    assert set(laws.damping_failures) == {"linear", "resistivity"}
    assert "cannot be determined" in laws.damping_failures["linear"]
    assert laws.friction is not None
    assert "not compared" in laws.comparison.statement


def test_a_law_needs_two_temperatures() -> None:
    with pytest.raises(ValueError, match="at least two temperatures"):
        fit_law(DAMPING_LAWS["linear"], [25.0, 25.0], with_errors(np.array([24.0, 24.1]), 0.01))


def test_friction_line_by_hand() -> None:
    # Equal errors 0.01 N*m on F = 0.58 - 0.0044 T (the paper's FS_T) plus deviations
    # (+0.005, -0.01, +0.005) within those errors (chi-square about 1.5, no scaling): the
    # textbook line slope = Sxy / Sxx, intercept = Fbar - slope * Tbar, se = sigma / sqrt(Sxx).
    t = np.array([-40.0, 25.0, 100.0])
    f = 0.58 - 0.0044 * t + np.array([0.005, -0.01, 0.005])
    fit = fit_law(FRICTION_LINE, t, [Estimate(float(v), 0.01, None) for v in f])
    sxx = float(np.sum((t - t.mean()) ** 2))
    slope = float(np.sum((t - t.mean()) * (f - f.mean()))) / sxx
    assert fit.parameters[1].value == pytest.approx(slope, rel=1e-10)
    assert fit.parameters[0].value == pytest.approx(f.mean() - slope * t.mean(), rel=1e-10)
    assert not fit.scaled
    intercept = f.mean() - slope * t.mean()
    chi_square = float(np.sum(((f - intercept - slope * t) / 0.01) ** 2))
    assert fit.chi_square == pytest.approx(chi_square, rel=1e-8)
    assert fit.parameters[1].standard_error == pytest.approx(0.01 / np.sqrt(sxx), rel=1e-8)


def test_law_intervals_cover_with_estimated_per_temperature_errors() -> None:
    # The full chain: a line per temperature (8 points, 6 dof), then the laws weighted by
    # the lines' standard errors. Those errors are estimates, so the normal-quantile
    # intervals cover a little less than 95 %: no less than P(|t_6| < 1.96), the coverage
    # if every temperature's error were as uncertain as one line's.
    rng = np.random.default_rng(20240603)
    speeds = np.linspace(0.02, 0.2, 8)
    seeds = 300
    covered = {"b_ref": 0, "c": 0, "slope": 0}
    for _ in range(seeds):
        b_fits, f_fits = [], []
        for t in TEMPS:
            y = (0.5 - 0.002 * t) + linear_truth(t) * speeds + rng.normal(0.0, 0.02, speeds.size)
            line = fit_line(speeds, y)
            b_fits.append(line.slope)
            f_fits.append(line.intercept)
        law = fit_law(DAMPING_LAWS["linear"], TEMPS, b_fits)
        friction = fit_law(FRICTION_LINE, TEMPS, f_fits)
        (b_lo, b_hi), (c_lo, c_hi) = (p.ci95 or (0.0, 0.0) for p in law.parameters)
        s_lo, s_hi = friction.parameters[1].ci95 or (0.0, 0.0)
        covered["b_ref"] += b_lo <= B_REF <= b_hi
        covered["c"] += c_lo <= C <= c_hi
        covered["slope"] += s_lo <= -0.002 <= s_hi
    floor = float(stats.t.cdf(1.959964, 6) - stats.t.cdf(-1.959964, 6))  # 0.902
    low = binomial_band(floor, seeds)[0]
    high = binomial_band(0.95, seeds)[1]
    for name, count in covered.items():
        assert low <= count / seeds <= high, name

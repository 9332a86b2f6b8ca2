"""Do the 95 % intervals of the laws over temperature cover 95 %? (issue 11, item 6)

Repeated synthetic drop-test campaigns with known truth and known noise go through the
whole reduction (:func:`ecdsim.characterize.droptest.reduce_drop_test`): one line per
temperature, then BECD(T) and FECD(T) laws. Each campaign is 5 temperatures x 5 masses
with Gaussian scatter in the torque, speeds exact: the statistical model the intervals
claim (docs/characterize.md section 1), once with the same noise at every temperature
and once with three times the noise at the hottest one.

The issue's own scenario has the noise in the drop TIME instead (1 % relative, masses
exact). The torque-noise line is the wrong model for it (its FECD intervals cover about
99 %), so those campaigns are reduced with ``noise="timing"`` (least squares of log t,
docs/characterize.md section 1) and checked against the same bands; the torque-noise
line's over-coverage is kept visible.

Checks, each against a binomial band (a correct 95 % interval covers in a fraction of
campaigns that is binomial with p = 0.95):

* every law parameter's interval covers the truth in 95 % +- 3 sigma of the campaigns,
  sigma = sqrt(0.95 * 0.05 / n): a correct implementation fails one such check with
  probability 0.0027, and with a fixed seed the result is reproducible;
* the law-misfit test (at 1 %) fires on the true law in 1 % +- 3 sigma of them,
  sigma = sqrt(0.01 * 0.99 / n);
* the earlier method (per-temperature standard errors taken as known, 3 degrees of
  freedom each) covers far less, the defect these tests would catch again.

The intervals' Welch-Satterthwaite degrees of freedom are an approximation, so they are
checked twice: by closed forms typed here, and by coverage.

Run as a script, the module prints the figures quoted in docs/characterize.md
section 2 (5000 campaigns each, and the 1 % timing-noise campaigns of the issue under
both noise models)::

    .venv/bin/python -m tests.test_characterize_coverage
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy import stats

from ecdsim.characterize.csvdata import Table
from ecdsim.characterize.droptest import DropTestResult, reduce_drop_test
from ecdsim.characterize.stats import Estimate, Scatter
from ecdsim.characterize.templaws import DAMPING_LAWS, FRICTION_LINE, LawFit, fit_law
from tests.test_characterize_synthetic import G, Truth

TRUTH = Truth()  # BECD = 24 (1 - 0.004 (T - 25)) N*m*s/rad, FECD = 0.57 - 0.002 T N*m
TEMPERATURES = np.array([-40.0, -10.0, 25.0, 60.0, 100.0])  # degC
MASSES = np.array([3.0, 4.5, 6.0, 7.5, 9.0])  # kg
RADIUS, ANGLE = 0.05, math.pi  # m, rad (180 deg drops, paper section 7)
TORQUE_NOISE = 0.02  # N*m, standard deviation; about 1 % of the mean drive torque
TIMING_NOISE = 0.01  # relative standard deviation of the recorded time (issue 11)
REPLICATES = 1000
SEED = 20261123
# (name, truth, which fit, which parameter) for every law parameter checked
PARAMETERS = {
    "B_ref": (TRUTH.b_ref, "linear", 0),
    "temperature coefficient": (TRUTH.c, "linear", 1),
    "friction at 0 degC": (TRUTH.at_0c, "friction", 0),
    "friction slope": (TRUTH.slope, "friction", 1),
}


def binomial_band(p: float, n: int, k: float = 3.0) -> tuple[float, float]:
    """p +- k sigma, sigma = sqrt(p (1 - p) / n): the spread of a binomial proportion.

    With k = 3 a correct implementation lands outside with probability 0.0027 (normal
    approximation, good here: n p >= 10 for p = 0.01 and n = 1000).
    """
    sigma = math.sqrt(p * (1.0 - p) / n)
    return p - k * sigma, p + k * sigma


def campaign_table(
    rng: np.random.Generator,
    *,
    torque_noise: float = 0.0,
    timing_noise: float = 0.0,
    hot_factor: float = 1.0,
) -> Table:
    """One campaign's drops, typed from the drop-test equations (not from ecdsim).

    Steady state (no rig inertia column): speed = (m g r - FECD(T)) / BECD(T) and
    time = angle / speed. ``torque_noise`` [N*m] is a weighing error in the recorded mass
    (the classical model), ``hot_factor`` times larger at the hottest temperature;
    ``timing_noise`` [-] a relative error of the recorded time.
    """
    t = np.repeat(TEMPERATURES, MASSES.size)
    m = np.tile(MASSES, TEMPERATURES.size)
    damping = TRUTH.b_ref * (1.0 + TRUTH.c * (t - TRUTH.t_ref))
    friction = TRUTH.slope * t + TRUTH.at_0c
    speed = (m * G * RADIUS - friction) / damping
    time = ANGLE / speed * (1.0 + timing_noise * rng.standard_normal(t.size))
    noise = torque_noise * np.where(t == TEMPERATURES[-1], hot_factor, 1.0)
    mass = m + noise * rng.standard_normal(t.size) / (G * RADIUS)
    n = t.size
    values = {
        "temperature": t,
        "mass": mass,
        "radius": np.full(n, RADIUS),
        "angle": np.full(n, ANGLE),
        "time": time,
    }
    headers = {key: key for key in values}
    return Table("synthetic", "", headers, np.arange(2, n + 2), values, (), ())


@dataclass
class Tally:
    """Counts over the campaigns: intervals covering the truth, misfit alarms."""

    n: int
    covered: dict[str, int]
    covered_known_errors: dict[str, int]
    alarms: dict[str, int]
    alarms_known_errors: dict[str, int]


def _covers(estimate: Estimate, truth: float) -> bool:
    assert estimate.ci95 is not None
    return estimate.ci95[0] <= truth <= estimate.ci95[1]


def _alarm(fit: LawFit) -> bool:
    return fit.p_value is not None and fit.p_value < 0.01


def _known_error_fits(result: DropTestResult) -> dict[str, LawFit]:
    """The same laws with the per-temperature errors taken as known (no pooling)."""
    temperatures = [f.temperature for f in result.fits]
    return {
        "linear": fit_law(
            DAMPING_LAWS["linear"], temperatures, [f.line.slope for f in result.fits]
        ),
        "friction": fit_law(FRICTION_LINE, temperatures, [f.line.intercept for f in result.fits]),
    }


def run_campaigns(
    n: int,
    seed: int,
    *,
    torque_noise: float = 0.0,
    timing_noise: float = 0.0,
    hot_factor: float = 1.0,
    known_errors: bool = True,
    noise: str = "torque",
) -> Tally:
    """Reduce ``n`` campaigns under the ``noise`` model and count coverage and alarms."""
    rng = np.random.default_rng(seed)
    laws = ("linear", "friction")
    tally = Tally(
        n,
        dict.fromkeys(PARAMETERS, 0),
        dict.fromkeys(PARAMETERS, 0),
        dict.fromkeys(laws, 0),
        dict.fromkeys(laws, 0),
    )
    for _ in range(n):
        table = campaign_table(
            rng, torque_noise=torque_noise, timing_noise=timing_noise, hot_factor=hot_factor
        )
        result = reduce_drop_test(table, TRUTH.t_ref, noise=noise)
        assert result.laws is not None
        assert result.laws.friction is not None
        fits = {"linear": result.laws.damping["linear"], "friction": result.laws.friction}
        old = _known_error_fits(result) if known_errors else {}
        for name, (truth, which, i) in PARAMETERS.items():
            tally.covered[name] += _covers(fits[which].parameters[i], truth)
            if known_errors:
                tally.covered_known_errors[name] += _covers(old[which].parameters[i], truth)
        for which, fit in fits.items():
            tally.alarms[which] += _alarm(fit)
        for which, fit in old.items():
            tally.alarms_known_errors[which] += _alarm(fit)
    return tally


@pytest.fixture(scope="module")
def tally() -> Tally:
    return run_campaigns(REPLICATES, SEED, torque_noise=TORQUE_NOISE)


@pytest.fixture(scope="module")
def unequal_tally() -> Tally:
    return run_campaigns(
        REPLICATES, SEED + 10, torque_noise=TORQUE_NOISE, hot_factor=3.0, known_errors=False
    )


@pytest.fixture(scope="module")
def timing_tally() -> Tally:
    # The campaigns (1 % timing noise), reduced under the timing-noise model.
    return run_campaigns(
        REPLICATES, SEED + 20, timing_noise=TIMING_NOISE, known_errors=False, noise="timing"
    )


@pytest.fixture(scope="module")
def timing_tally_torque_model() -> Tally:
    # The same campaigns (same seed) reduced under the torque-noise model.
    return run_campaigns(REPLICATES, SEED + 20, timing_noise=TIMING_NOISE, known_errors=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PARAMETERS))
def test_law_intervals_cover_95_percent(tally: Tally, name: str) -> None:
    # 1000 campaigns: band 0.95 +- 3 * sqrt(0.95 * 0.05 / 1000) = [0.929, 0.971]. Before
    # the fix these were 0.81 (B_ref), 0.85, 0.82, 0.85 (5000 campaigns, docs).
    low, high = binomial_band(0.95, tally.n)
    assert low <= tally.covered[name] / tally.n <= high


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PARAMETERS))
def test_law_intervals_cover_95_percent_with_unequal_noise(unequal_tally: Tally, name: str) -> None:
    # Three times the noise at 100 degC: one pooled noise level would be wrong there
    # (c's interval then covers about 84 %); each temperature's own scatter with
    # Welch-Satterthwaite dof keeps 95 %. Same band as above.
    low, high = binomial_band(0.95, unequal_tally.n)
    assert low <= unequal_tally.covered[name] / unequal_tally.n <= high


@pytest.mark.slow
@pytest.mark.parametrize("which", ["linear", "friction"])
def test_law_misfit_false_alarm_rate_is_1_percent(tally: Tally, which: str) -> None:
    # The true law, tested at 1 %: band 0.01 +- 3 * sqrt(0.01 * 0.99 / 1000) =
    # [0.0006, 0.0194] (at least one alarm, at most 19). Before the fix: 9 %.
    low, high = binomial_band(0.01, tally.n)
    assert low <= tally.alarms[which] / tally.n <= high


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PARAMETERS))
def test_law_intervals_cover_95_percent_with_timing_noise(timing_tally: Tally, name: str) -> None:
    # 1 % relative timing noise, masses exact, fitted as such (least squares of log t):
    # each line's residuals are the drops' relative timing errors, with the same
    # variance at every temperature, so the pooling and the Welch-Satterthwaite dof hold
    # as under torque noise. 1000 campaigns: band 0.95 +- 3 * sqrt(0.95 * 0.05 / 1000)
    # = [0.929, 0.971].
    low, high = binomial_band(0.95, timing_tally.n)
    assert low <= timing_tally.covered[name] / timing_tally.n <= high


@pytest.mark.slow
@pytest.mark.parametrize("which", ["linear", "friction"])
def test_law_misfit_false_alarm_rate_is_1_percent_with_timing_noise(
    timing_tally: Tally, which: str
) -> None:
    # The true laws under timing noise, tested at 1 %: band 0.01 +- 3 * sqrt(0.01 * 0.99
    # / 1000) = [0.0006, 0.0194]. The torque-noise line gave 1.3 % and 0.02 % here
    # (5000 campaigns, docs/characterize.md section 2): the friction test nearly never
    # fired, because its errors were overstated.
    low, high = binomial_band(0.01, timing_tally.n)
    assert low <= timing_tally.alarms[which] / timing_tally.n <= high


@pytest.mark.slow
@pytest.mark.parametrize("name", ["friction at 0 degC", "friction slope"])
def test_the_torque_noise_line_overcovers_friction_under_timing_noise(
    timing_tally_torque_model: Tally, name: str
) -> None:
    # Why the timing model is needed, kept visible: a relative timing error eps puts
    # BECD * speed * eps into the torque, so the torque-space scatter grows with speed.
    # The plain line's pooled residual variance then averages the fast points' large
    # scatter into the intercept's error, which is set by the slow points: FECD's
    # intervals come out too wide (about 99 % measured), above the band of a correct one.
    tally = timing_tally_torque_model
    assert tally.covered[name] / tally.n > binomial_band(0.95, tally.n)[1]


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PARAMETERS))
def test_taking_the_per_temperature_errors_as_known_undercovers(tally: Tally, name: str) -> None:
    # The defect, kept visible: each line's standard error rests on 5 - 2 = 3 degrees of
    # freedom, so treating it as known (normal quantile 1.96) is far too optimistic.
    # For one temperature alone the coverage would be P(|t_3| < 1.96) = 0.855; combining
    # five such errors helps only a little. Below the band of a correct interval.
    one_temperature = float(stats.t.cdf(1.959964, 3) - stats.t.cdf(-1.959964, 3))
    assert one_temperature == pytest.approx(0.855, abs=5e-4)
    assert tally.covered_known_errors[name] / tally.n < binomial_band(0.95, tally.n)[0]


def test_friction_line_by_hand() -> None:
    # One campaign; the friction line is linear in its parameters, so everything has a
    # closed form. u_i = (D_i^T D_i)^-1 [0, 0] of each line (D_i = [1, speed]), pooled
    # s**2 = sum(SSR_i) / sum(nu_i), weights w_i = 1 / (s**2 u_i); the weighted normal
    # equations give theta = H y with H = (A^T W A)^-1 A^T W. Each parameter's variance
    # is sum_i H_ji**2 se_i**2 with the line's own se_i, its dof the Welch-Satterthwaite
    # (sum_i H_ji**2 se_i**2)**2 / sum_i (H_ji**2 se_i**2)**2 / nu_i; the misfit p-value
    # is F.sf(chi2 / (k - 2), k - 2, sum(nu_i)) with chi2 = sum w_i r_i**2.
    rng = np.random.default_rng(7)
    result = reduce_drop_test(campaign_table(rng, torque_noise=TORQUE_NOISE), TRUTH.t_ref)
    assert result.laws is not None
    fit = result.laws.friction
    assert fit is not None
    temperature = np.array([f.temperature for f in result.fits])
    value = np.array([f.line.intercept.value for f in result.fits])
    nu = np.array([f.line.n_points - 2 for f in result.fits])
    ssr = np.array([np.sum(f.line.statistics.residuals**2) for f in result.fits])
    u = []
    for f in result.fits:
        design = np.column_stack([np.ones_like(f.speed), f.speed])
        u.append(float(np.linalg.inv(design.T @ design)[0, 0]))
    se2 = ssr / nu * np.array(u)
    w = 1.0 / (float(np.sum(ssr) / np.sum(nu)) * np.array(u))
    a = np.column_stack([np.ones_like(temperature), temperature])
    h = np.linalg.inv(a.T @ (w[:, None] * a)) @ (a.T * w)
    at_0c, slope = h @ value
    terms = h**2 * se2
    cov = (h * se2) @ h.T
    dof = np.sum(terms, axis=1) ** 2 / np.sum(terms**2 / nu, axis=1)
    chi2 = float(np.sum(w * (value - at_0c - slope * temperature) ** 2))
    # Two solutions of the same linear problem (lstsq-based Levenberg-Marquardt vs the
    # normal equations): round-off of a condition number ~1e4, so 1e-9 relative.
    assert fit.parameters[0].value == pytest.approx(at_0c, rel=1e-9)
    assert fit.parameters[1].value == pytest.approx(slope, rel=1e-9)
    assert fit.covariance == pytest.approx(cov, rel=1e-8)
    assert fit.effective_dof == pytest.approx(dof, rel=1e-8)
    # Satterthwaite's dof lies between the smallest nu_i and their sum.
    assert min(dof) >= 3.0
    assert max(dof) <= 15.0
    assert fit.scatter_dof == int(np.sum(nu)) == 15
    assert fit.chi_square == pytest.approx(chi2, rel=1e-8)
    assert fit.p_value == pytest.approx(float(stats.f.sf(chi2 / 3, 3, 15)), rel=1e-8)
    for i, estimate in enumerate(fit.parameters):
        half = float(stats.t.ppf(0.975, dof[i])) * math.sqrt(cov[i, i])
        assert estimate.ci95 == pytest.approx((h[i] @ value - half, h[i] @ value + half))
    # The confidence band at T is the combination (1, T): at T = 0 it is at_0C's interval.
    band = fit.band(0.0)
    assert band is not None
    assert (band[0][0], band[1][0]) == pytest.approx(fit.parameters[0].ci95, rel=1e-12)


def test_damping_coefficient_by_hand() -> None:
    # The linear law B_ref (1 + c dT) is the line b0 + b1 dT with B_ref = b0, c = b1 / b0:
    # the same weighted line as above (weights 1 / (s**2 u_i), u_i = (D_i^T D_i)^-1 [1, 1]),
    # then c's error by the delta method, gradient (-b1 / b0**2, 1 / b0), each
    # temperature's contribution (g . h_i) se_i, Welch-Satterthwaite dof as above.
    rng = np.random.default_rng(8)
    result = reduce_drop_test(campaign_table(rng, torque_noise=TORQUE_NOISE), TRUTH.t_ref)
    assert result.laws is not None
    fit = result.laws.damping["linear"]
    dt = np.array([f.temperature for f in result.fits]) - TRUTH.t_ref
    value = np.array([f.line.slope.value for f in result.fits])
    se = np.array([f.line.slope.standard_error or 0.0 for f in result.fits])
    nu = np.array([f.line.n_points - 2 for f in result.fits])
    ssr = np.array([np.sum(f.line.statistics.residuals**2) for f in result.fits])
    u = []
    for f in result.fits:
        design = np.column_stack([np.ones_like(f.speed), f.speed])
        u.append(float(np.linalg.inv(design.T @ design)[1, 1]))
    w = 1.0 / (float(np.sum(ssr) / np.sum(nu)) * np.array(u))
    a = np.column_stack([np.ones_like(dt), dt])
    h = np.linalg.inv(a.T @ (w[:, None] * a)) @ (a.T * w)
    b0, b1 = h @ value
    contribution = ((-b1 / b0**2) * h[0] + (1.0 / b0) * h[1]) * se
    se_c = math.sqrt(float(np.sum(contribution**2)))
    dof = float(np.sum(contribution**2) ** 2 / np.sum(contribution**4 / nu))
    half = float(stats.t.ppf(0.975, dof)) * se_c
    # The fit's Jacobian at the solution is exact (not differenced): 1e-8 relative.
    assert fit.parameters[0].value == pytest.approx(b0, rel=1e-9)
    assert fit.parameters[1].value == pytest.approx(b1 / b0, rel=1e-8)
    assert fit.parameters[1].standard_error == pytest.approx(se_c, rel=1e-8)
    assert fit.effective_dof is not None
    assert fit.effective_dof[1] == pytest.approx(dof, rel=1e-8)
    assert fit.parameters[1].ci95 == pytest.approx((b1 / b0 - half, b1 / b0 + half), rel=1e-8)


def test_scatter_must_match_the_temperatures() -> None:
    values = [Estimate(24.0, 0.1, None), Estimate(20.0, 0.1, None)]
    with pytest.raises(ValueError, match="1 scatter entries for 2 temperatures"):
        fit_law(DAMPING_LAWS["linear"], [0.0, 50.0], values, scatter=[Scatter(0.01, 3)])


def test_a_temperature_without_scatter_falls_back_to_known_errors() -> None:
    # One temperature has no residual variance to pool: nothing is pooled, the errors
    # are taken as known (normal quantile), as without scatter.
    values = [Estimate(v, 0.1, None) for v in (30.2, 27.1, 24.0, 20.6, 16.8)]
    scatter = [Scatter(0.01, 3)] * 4 + [None]
    fit = fit_law(DAMPING_LAWS["linear"], TEMPERATURES, values, scatter=scatter)
    assert fit.scatter_dof is None
    assert fit.quantile == pytest.approx(stats.norm.ppf(0.975), rel=1e-12)


def test_two_temperatures_by_hand() -> None:
    # Two temperatures with s**2 = 1 and 3 (3 and 1 dof): pooled s**2 = (3 + 3) / 4 = 1.5,
    # so the weights use 0.1 * sqrt(1.5 / 1) and 0.2 * sqrt(1.5 / 3). The line passes
    # through both points whatever the weights: at_0C = y_0 (its error 0.1, from one
    # temperature, t with 3 dof) and slope = (y_1 - y_0) / 50 (variance
    # (0.1**2 + 0.2**2) / 50**2, Welch-Satterthwaite dof
    # (0.01 + 0.04)**2 / (0.01**2 / 3 + 0.04**2 / 1) = 1.5306).
    values = [Estimate(24.0, 0.1, None), Estimate(20.0, 0.2, None)]
    fit = fit_law(FRICTION_LINE, [0.0, 50.0], values, scatter=[Scatter(1.0, 3), Scatter(3.0, 1)])
    assert fit.sigma == pytest.approx([0.1 * math.sqrt(1.5), 0.2 * math.sqrt(0.5)], rel=1e-12)
    at_0c, slope = fit.parameters
    # round-off of a 2 x 2 solve: 1e-9
    assert at_0c.value == pytest.approx(24.0, rel=1e-9)
    assert at_0c.standard_error == pytest.approx(0.1, rel=1e-9)
    assert at_0c.ci95 == pytest.approx((24.0 - 0.1 * 3.182446, 24.0 + 0.1 * 3.182446), rel=1e-6)
    assert slope.value == pytest.approx(-4.0 / 50.0, rel=1e-9)
    assert slope.standard_error == pytest.approx(math.sqrt(0.05) / 50.0, rel=1e-9)
    dof = 0.05**2 / (0.01**2 / 3.0 + 0.04**2)
    assert fit.effective_dof == pytest.approx([3.0, dof], rel=1e-9)
    half = float(stats.t.ppf(0.975, dof)) * math.sqrt(0.05) / 50.0
    assert slope.ci95 == pytest.approx((-0.08 - half, -0.08 + half), rel=1e-9)
    assert fit.scatter_dof == 4
    assert fit.p_value is None  # no degree of freedom to test the law


def _report(label: str, tally: Tally) -> None:
    covered = ", ".join(f"{k} {v / tally.n:.3f}" for k, v in tally.covered.items())
    known = ", ".join(f"{k} {v / tally.n:.3f}" for k, v in tally.covered_known_errors.items())
    alarms = ", ".join(f"{k} {v / tally.n:.4f}" for k, v in tally.alarms.items())
    old = ", ".join(f"{k} {v / tally.n:.4f}" for k, v in tally.alarms_known_errors.items())
    print(f"{label}, {tally.n} campaigns")
    print(f"  coverage, now: {covered}")
    print(f"  coverage, errors taken as known (before): {known}")
    print(f"  misfit alarms at 1 %, now: {alarms}; before: {old}")


if __name__ == "__main__":
    _report(
        f"torque noise {TORQUE_NOISE} N*m",
        run_campaigns(5000, SEED + 1, torque_noise=TORQUE_NOISE),
    )
    _report(
        f"torque noise {TORQUE_NOISE} N*m, three times that at 100 degC",
        run_campaigns(5000, SEED + 3, torque_noise=TORQUE_NOISE, hot_factor=3.0),
    )
    _report(
        "timing noise 1 %, torque-noise line (--noise torque)",
        run_campaigns(5000, SEED + 2, timing_noise=TIMING_NOISE),
    )
    _report(
        "timing noise 1 %, timing-noise line (--noise timing)",
        run_campaigns(5000, SEED + 2, timing_noise=TIMING_NOISE, noise="timing"),
    )
    _report(
        f"torque noise {TORQUE_NOISE} N*m, timing-noise line (--noise timing)",
        run_campaigns(5000, SEED + 1, torque_noise=TORQUE_NOISE, noise="timing"),
    )

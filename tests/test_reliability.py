"""Demonstrated reliability (issue 28, item 2), against hand formulas and simulation.

Hand formulas: the success run ``R = (1 - C)**(1/N)`` and ``N = ceil(ln(1 - C) / ln R)``;
the Clopper-Pearson bounds checked by summing the binomial probabilities with
``math.comb`` at the bound (the tail equals the confidence's complement there); Crow's
power-law process by its closed form; the Weibull fit against scipy's maximum likelihood.
Coverage by simulation where the bound is exact or conservative by construction.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy import optimize, stats
from typer.testing import CliRunner

from ecdsim.characterize.reliability import (
    life_test,
    miss_probability,
    power_law_process,
    proportion_interval,
    reliability_lower_bound,
    runs_needed,
    success_run_reliability,
    upper_bound,
    weibull_fit,
)
from ecdsim.cli.app import app
from ecdsim.montecarlo.misses import miss_flags, requirement_misses
from ecdsim.sizing.requirements import Requirements
from tests.conftest import ROOT

runner = CliRunner()
# Closed forms evaluated in a different order: equal to rounding.
TIGHT = 1e-12


def binomial_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k), X ~ Binomial(n, p), summed by hand."""
    return sum(math.comb(n, i) * p**i * (1.0 - p) ** (n - i) for i in range(k + 1))


def test_success_run_by_hand() -> None:
    assert success_run_reliability(22, 0.90) == pytest.approx(0.1 ** (1 / 22), rel=TIGHT)
    assert success_run_reliability(59, 0.95) == pytest.approx(0.05 ** (1 / 59), rel=TIGHT)
    # 22 successes show R = 0.9006 at 90 %: the classic "22 for 90/90".
    assert success_run_reliability(22, 0.90) >= 0.9 > success_run_reliability(21, 0.90)


@pytest.mark.parametrize(
    ("target", "confidence", "expected"),
    [(0.9, 0.9, 22), (0.99, 0.95, 299), (0.95, 0.95, 59), (0.999, 0.9, 2302)],
)
def test_runs_needed_without_failures_by_hand(
    target: float, confidence: float, expected: int
) -> None:
    # N = ceil(ln(1 - C) / ln R), and N is the first count whose R**N <= 1 - C.
    assert math.ceil(math.log(1 - confidence) / math.log(target)) == expected
    assert runs_needed(target, confidence) == expected
    assert target**expected <= 1 - confidence < target ** (expected - 1)


@pytest.mark.parametrize(
    ("runs", "failures", "confidence"), [(30, 2, 0.95), (59, 1, 0.95), (10, 9, 0.9)]
)
def test_the_binomial_bound_makes_the_tail_equal_one_minus_c(
    runs: int, failures: int, confidence: float
) -> None:
    low = reliability_lower_bound(runs, failures, confidence)
    # At R_L, f or fewer failures among N happen with probability 1 - C exactly.
    assert binomial_cdf(failures, runs, 1.0 - low) == pytest.approx(1.0 - confidence, rel=1e-9)
    assert low == pytest.approx(
        stats.beta.ppf(1 - confidence, runs - failures, failures + 1), rel=1e-12
    )


def test_the_bound_reduces_to_the_success_run_and_to_zero() -> None:
    assert reliability_lower_bound(40, 0, 0.9) == pytest.approx(0.1 ** (1 / 40), rel=TIGHT)
    assert reliability_lower_bound(5, 5, 0.9) == 0.0


def test_runs_needed_with_failures_by_hand() -> None:
    n = runs_needed(0.9, 0.9, failures=1)
    assert binomial_cdf(1, n, 0.1) <= 0.1 < binomial_cdf(1, n - 1, 0.1)
    assert n == 38


def test_proportion_intervals_by_hand() -> None:
    low, high = proportion_interval(3, 100)
    # Two-sided: each tail 2.5 % at its bound.
    assert 1 - binomial_cdf(2, 100, low) == pytest.approx(0.025, rel=1e-9)
    assert binomial_cdf(3, 100, high) == pytest.approx(0.025, rel=1e-9)
    # No miss: the upper bound is 1 - 0.025**(1/n) two-sided, 1 - 0.05**(1/n) one-sided,
    # about 3 / n (the "rule of three").
    assert proportion_interval(0, 200) == pytest.approx((0.0, 1 - 0.025 ** (1 / 200)), rel=TIGHT)
    assert upper_bound(0, 200) == pytest.approx(1 - 0.05 ** (1 / 200), rel=TIGHT)
    assert upper_bound(0, 200) == pytest.approx(3 / 200, rel=0.01)


def test_the_one_sided_upper_bound_covers_at_least_95_percent() -> None:
    # Clopper-Pearson is conservative: over 4000 samples of 300 draws at p = 1 %, the bound
    # lies above p at least 95 % of the time (3 binomial sigma: 0.95 - 3 * 0.0034).
    rng = np.random.default_rng(20261128)
    counts = rng.binomial(300, 0.01, size=4000)
    bounds = {k: upper_bound(int(k), 300) for k in np.unique(counts)}
    covered = np.mean([bounds[k] >= 0.01 for k in counts])
    assert covered >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / 4000)


def test_miss_probability_counts_and_bounds() -> None:
    found = miss_probability([True, False, False, True] + [False] * 96)
    assert (found.misses, found.samples, found.probability) == (2, 100, 0.02)
    assert found.interval == proportion_interval(2, 100)
    assert found.upper == pytest.approx(1 - reliability_lower_bound(100, 2), rel=TIGHT)


# Crow's power-law process -------------------------------------------------------------


def test_power_law_process_by_hand() -> None:
    failures = [50, 120, 300, 420, 480]
    fit = power_law_process(failures, 500)
    assert fit is not None
    beta = 5 / sum(math.log(500 / t) for t in failures)
    assert fit.beta == pytest.approx(beta, rel=TIGHT)
    assert fit.scale == pytest.approx(5 / 500**beta, rel=TIGHT)
    chi2 = stats.chi2(10)
    assert fit.beta_interval == pytest.approx(
        (beta * chi2.ppf(0.025) / 10, beta * chi2.ppf(0.975) / 10), rel=1e-9
    )
    assert fit.expected_failures(500) == pytest.approx(5.0, rel=TIGHT)
    assert fit.intensity == pytest.approx(fit.scale * beta * 500 ** (beta - 1), rel=TIGHT)
    assert power_law_process([], 100) is None
    assert power_law_process([100, 100], 100) is None  # every failure at the end


def test_power_law_interval_covers_95_percent() -> None:
    # Given n failures by T, the times are T * U**(1/beta): the chi-square interval is
    # exact, so over 2000 tests its coverage lies within 3 binomial sigma of 95 %.
    rng = np.random.default_rng(20261129)
    beta, runs, covered, tests = 1.6, 1000, 0, 2000
    for _ in range(tests):
        n = 0
        while n == 0:
            n = int(rng.poisson(8.0))
        times = np.maximum(1, np.ceil(runs * rng.random(n) ** (1 / beta))).astype(int)
        fit = power_law_process(times.tolist(), runs)
        if fit is not None and fit.beta_interval[0] <= beta <= fit.beta_interval[1]:
            covered += 1
    sigma = math.sqrt(0.95 * 0.05 / tests)
    # Deployments are whole numbers: ceil() moves each time by under one deployment of
    # 1000, a bias far inside the band.
    assert abs(covered / tests - 0.95) <= 3 * sigma


# Weibull lives --------------------------------------------------------------------------


def test_weibull_of_complete_lives_equals_scipys_maximum_likelihood() -> None:
    lives = stats.weibull_min.rvs(2.0, scale=1000.0, size=40, random_state=np.random.default_rng(1))
    fit = weibull_fit(lives, np.ones(40, dtype=bool))
    shape, _, scale = stats.weibull_min.fit(lives, floc=0)
    # scipy's optimiser stops at its own tolerance (about 1e-7 relative here).
    assert fit.shape == pytest.approx(shape, rel=1e-6)
    assert fit.scale == pytest.approx(scale, rel=1e-6)


def _loglik(p: np.ndarray[Any, Any], t: np.ndarray[Any, Any], dead: np.ndarray[Any, Any]) -> float:
    """The Weibull log-likelihood with suspensions, typed from its definition: the failed
    lives' densities, every life's survival."""
    beta, eta = p
    density = np.log(beta / eta) + (beta - 1) * np.log(t / eta)
    return float(np.sum(density[dead]) - np.sum((t / eta) ** beta))


def test_weibull_with_suspensions_maximises_the_likelihood() -> None:
    rng = np.random.default_rng(7)
    lives = stats.weibull_min.rvs(2.5, scale=2000.0, size=12, random_state=rng)
    dead = lives < 2500.0
    lives = np.minimum(lives, 2500.0)  # the test stopped at 2500 cycles: suspensions
    fit = weibull_fit(lives, dead)
    best = optimize.minimize(
        lambda p: -_loglik(p, lives, dead), x0=[1.0, 1500.0], method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000},
    )  # fmt: skip
    assert fit.shape == pytest.approx(best.x[0], rel=1e-6)
    assert fit.scale == pytest.approx(best.x[1], rel=1e-6)
    # The Fisher matrix: minus the inverse Hessian of the log-likelihood, by central
    # differences at the maximum (steps 1e-4 relative: truncation about 1e-8).
    p0 = np.array([fit.shape, fit.scale])
    h = p0 * 1e-4
    hessian = np.zeros((2, 2))

    def at(i: int, a: float, j: int, b: float) -> float:
        p = p0.copy()
        p[i] += a
        p[j] += b
        return _loglik(p, lives, dead)

    for i in range(2):
        for j in range(2):
            hessian[i, j] = (
                at(i, h[i], j, h[j])
                - at(i, h[i], j, -h[j])
                - at(i, -h[i], j, h[j])
                + at(i, -h[i], j, -h[j])
            ) / (4 * h[i] * h[j])
    np.testing.assert_allclose(fit.covariance, np.linalg.inv(-hessian), rtol=1e-4)
    assert fit.b_life(0.1) == pytest.approx(fit.scale * (-math.log(0.9)) ** (1 / fit.shape))


def test_weibull_needs_two_failures() -> None:
    with pytest.raises(ValueError, match="at least two failures"):
        weibull_fit([100.0, 200.0, 300.0], [True, False, False])


# Monte Carlo and repeat -------------------------------------------------------------------


def test_miss_flags_by_hand() -> None:
    requirements = Requirements(
        temperatures=(25.0,),
        min_deployment_time=10.0,
        max_deployment_time=60.0,
        max_end_speed=0.1,
        min_torque_margin=0.0,
    )
    times = np.array([5.0, 20.0, 70.0, np.inf, 30.0])
    stalled = ~np.isfinite(times)
    speeds = np.array([0.05, 0.2, 0.01, 0.0, 0.05])
    margins = np.array([0.1, 0.1, 0.1, -0.2, -0.01])
    flags = {
        k: v[1].tolist()
        for k, v in miss_flags(requirements, times, stalled, speeds, margins).items()
    }
    assert flags == {
        "min_deployment_time": [True, False, False, False, False],
        "max_deployment_time": [False, False, True, True, False],
        "max_end_speed": [False, True, False, False, False],
        "no_stall": [False, False, False, True, False],
        "min_torque_margin": [False, False, False, True, True],
    }
    block = requirement_misses(requirements, times, stalled, speeds, margins)
    assert block["any"]["misses"] == 5
    assert block["max_deployment_time"]["probability"] == pytest.approx(0.4)


def test_a_monte_carlo_study_reports_each_requirements_miss(tmp_path: Path) -> None:
    sizing = (ROOT / "examples" / "sizing.toml").read_text(encoding="utf-8")
    tolerances = (ROOT / "examples" / "paper_cc16_tolerances.toml").read_text(encoding="utf-8")
    config = tmp_path / "study.toml"
    config.write_text(
        sizing + "\n" + tolerances[tolerances.index("\n[tolerances]\n") :], encoding="utf-8"
    )
    result = runner.invoke(
        app,
        ["montecarlo", str(config), "--samples", "2000", "--no-plot", "--json", "--out",
         str(tmp_path / "out"), "--no-progress"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    for case in summary["cases"]:
        block = case["requirements"]
        # The stall block and the margin's own count agree with the requirement misses.
        assert block["no_stall"]["misses"] == case["stall"]["count"]
        below = case["min_torque_margin"]["probability_below_required"]
        assert block["min_torque_margin"]["probability"] == pytest.approx(below)
        assert block["any"]["misses"] >= max(b["misses"] for b in block.values())
        assert block["any"]["samples"] == 2000
    table = runner.invoke(
        app,
        ["montecarlo", str(config), "--samples", "2000", "--no-plot", "--out",
         str(tmp_path / "out"), "--resume", "--no-progress"],
        env={"COLUMNS": "80"},
    )  # fmt: skip
    assert "Probability of missing each requirement" in table.stdout


def test_life_test_by_hand() -> None:
    times = np.array([[30.0, 30.0], [29.0, np.inf], [28.0, 31.0], [27.0, 30.5]])
    cases = life_test(times, minimum=27.5, maximum=None, confidence=0.9)
    first, second = cases
    assert first["failed_deployments"] == [4]  # 27 < 27.5
    assert first["drift"] == {
        "total_s": -3.0, "per_deployment_s": -1.0, "largest_departure_s": 3.0,
    }  # fmt: skip
    assert first["demonstrated"]["demonstrated_reliability"] == pytest.approx(
        reliability_lower_bound(4, 1, 0.9), rel=TIGHT
    )
    assert first["power_law_process"] is None  # its only failure at the last deployment
    assert second["failed_deployments"] == [2]  # the stall
    assert second["power_law_process"]["beta"] == pytest.approx(1 / math.log(4 / 2), rel=TIGHT)
    assert second["drift"]["largest_departure_s"] == 1.0


def test_repeat_reports_its_reliability() -> None:
    result = runner.invoke(
        app,
        ["repeat", str(ROOT / "examples" / "paper_cc16_dynamic.toml"), "--count", "3",
         "--cool-down", "60 s", "-T", "25", "--json"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    block = json.loads(result.stdout)["reliability"]
    (case,) = block["cases"]
    assert block["failure_criteria"] == ["stall"]
    assert case["failed_deployments"] == []
    assert case["demonstrated"]["demonstrated_reliability"] == pytest.approx(0.05 ** (1 / 3))


# The command -------------------------------------------------------------------------------


def test_reliability_commands() -> None:
    shown = runner.invoke(
        app, ["reliability", "demonstrated", "--runs", "22", "-C", "90%", "--json"]
    )
    assert shown.exit_code == 0, shown.output
    assert json.loads(shown.stdout)["demonstrated_reliability"] == pytest.approx(0.1 ** (1 / 22))
    needed = runner.invoke(app, ["reliability", "runs-needed", "--target", "0.99", "-C", "0.9"])
    assert needed.exit_code == 0
    assert needed.stdout.startswith("230 deployments")
    text = runner.invoke(app, ["reliability", "demonstrated", "--runs", "59", "-f", "1"])
    assert "Clopper-Pearson" in text.stdout
    life = runner.invoke(
        app, ["reliability", "weibull", str(ROOT / "examples" / "life_test.csv"), "--json"]
    )
    assert life.exit_code == 0, life.output
    assert json.loads(life.stdout)["failures"] >= 2


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["demonstrated", "--runs", "0"], "--runs 0: expected a number of deployments >= 1"),
        (["demonstrated", "--runs", "5", "-f", "7"], "--failures 7: expected 0 to --runs (5)"),
        (
            ["demonstrated", "--runs", "5", "-C", "1.5"],
            "--confidence: '1.5' must lie strictly between 0 and 1",
        ),
        (["demonstrated", "--runs", "5", "-C", "high"], "--confidence: 'high' is not a number"),
        (["runs-needed", "--target", "100%"], "--target: '100%' must lie strictly between 0 and 1"),
        (["weibull", "missing.csv"], "data file not found"),
    ],
)
def test_bad_reliability_arguments_are_one_line_errors(args: list[str], fragment: str) -> None:
    result = runner.invoke(app, ["reliability", *args])
    assert result.exit_code == 2, result.output
    assert fragment in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_the_help_screens_and_their_examples(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.helptext import assert_options, read_help, run_example

    group = read_help(runner, app, ["reliability"])
    assert set(group.commands) == {"demonstrated", "runs-needed", "weibull"}
    expected = {
        "demonstrated": {"--runs": "-n", "--failures": "-f", "--confidence": "-C", "--json": None,
                         "--wide": None, "--plain": None},
        "runs-needed": {"--target": "-R", "--failures": "-f", "--confidence": "-C", "--json": None,
                        "--wide": None, "--plain": None},
        "weibull": {"--confidence": "-C", "--at": None, "--json": None, "--wide": None,
                    "--plain": None},
    }  # fmt: skip
    for i, (name, options) in enumerate(expected.items()):
        screen = read_help(runner, app, ["reliability", name])
        assert_options(screen, options | {"--help": None})
        run_example(runner, app, screen, tmp_path / str(i), monkeypatch)


def test_the_report_shows_the_probability_of_missing_each_requirement(tmp_path: Path) -> None:
    sizing = (ROOT / "examples" / "sizing.toml").read_text(encoding="utf-8")
    tolerances = (ROOT / "examples" / "paper_cc16_tolerances.toml").read_text(encoding="utf-8")
    config = tmp_path / "study.toml"
    config.write_text(sizing + "\n" + tolerances[tolerances.index("\n[tolerances]\n") :],
                      encoding="utf-8")  # fmt: skip
    out = tmp_path / "report.html"
    done = runner.invoke(app, ["report", str(config), "-o", str(out)])
    assert done.exit_code == 0, done.output
    html = out.read_text(encoding="utf-8")
    assert 'id="requirement-misses"' in html
    for name in ("max_deployment_time", "min_torque_margin", "any"):
        assert f'data-requirement="{name}"' in html

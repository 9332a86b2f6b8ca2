"""Monte Carlo percentiles against distributions derived by hand (issue 6's required test).

Case 1. Only the damper's BD scatters, normally, by 5 %. Friction and spring torques do
not depend on BD, and the gearbox damping is a fixed fraction of BD (BG = 0.26 BD), so
BECD_T = BD (1 - 0.004 (T - 25) + 0.26) N^2 is proportional to BD at every temperature,
and the exact deployment time ``B * L / logmean(a, b)`` is proportional to BECD_T:
``t = t_nominal * BD / BD_nominal``. The time is therefore normal with mean t_nominal
(tests/hand.py) and standard deviation 0.05 t_nominal, and its p-percentile is
``t_nominal * (1 + 0.05 z_p)`` with z_p the standard normal quantile.

Case 2. Only the spring's end torque Te scatters, normally, wide enough that some
deployments stall at -40 degC. A linear spring torque falling from Ts to Te stalls iff
Te <= F (the total friction FECD + FS): P(stall) = Phi((F - Te_nominal) / sigma). The
time falls as Te grows, so the time's p-percentile is the time at Te's (1 - p)-quantile,
or +inf where that quantile lies at or below F.

Tolerances come from the sampling error of a sample quantile:
``SE = sqrt(p (1 - p) / n) / f(q_p)``, f the density at the quantile; every check allows
five standard errors (a false failure has probability below 1e-6 per check).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats as scipy_stats

from ecdsim.config import load_config
from ecdsim.montecarlo import build_plan, run
from ecdsim.montecarlo.run import output_column
from ecdsim.montecarlo.stats import summarize
from ecdsim.montecarlo.store import ChunkReader
from tests import hand
from tests.test_montecarlo_config import PAPER_TEXT, write_config

TEMPERATURES = (-40.0, 25.0, 100.0)
SIGMA_RELATIVE = 0.05
SAMPLES = 40_000
ALLOWED = 5.0  # standard errors


def quantile_error(p: float, n: int, sigma: float) -> float:
    """Standard error of the p-quantile of n draws from a normal of std sigma."""
    density = scipy_stats.norm.pdf(scipy_stats.norm.ppf(p)) / sigma
    return float(math.sqrt(p * (1.0 - p) / n) / density)


@pytest.mark.parametrize("sampling", ["random", "lhs", "sobol"])
def test_time_percentiles_of_a_normal_damping_rate(tmp_path: Path, sampling: str) -> None:
    config = load_config(
        write_config(
            tmp_path,
            '"damper.damping_rate" = { distribution = "normal", sigma = "5 %" }',
            f'sampling = "{sampling}"\nseed = 314\nchunk_size = 8192',
        )
    )
    plan = build_plan(config, SAMPLES)
    out = tmp_path / "run"
    run(plan, out)
    summary = summarize(plan, out)
    reader = ChunkReader(out, plan.chunks)
    bd = reader.floats("damper.damping_rate")
    for case, temperature in zip(summary["cases"], TEMPERATURES, strict=True):
        nominal = hand.exact_time(temperature)
        sigma = SIGMA_RELATIVE * nominal
        assert case["nominal"]["deployment_time_s"] == pytest.approx(nominal, rel=1e-12)
        # Sample by sample, t = t_nominal * BD / BD_nominal: exact up to rounding (1e-12).
        times = reader.floats(output_column("deployment_time_s", temperature))
        np.testing.assert_allclose(times, nominal * bd / 1.3e-4, rtol=1e-12)
        found = case["deployment_time_s"]
        for name, p in {"P1": 0.01, "P5": 0.05, "P50": 0.5, "P95": 0.95, "P99": 0.99}.items():
            expected = nominal * (1.0 + SIGMA_RELATIVE * scipy_stats.norm.ppf(p))
            tolerance = ALLOWED * quantile_error(p, SAMPLES, sigma)
            assert found["percentiles"][name]["value"] == pytest.approx(expected, abs=tolerance)
            low = found["percentiles"][name]["low"]
            high = found["percentiles"][name]["high"]
            assert low <= found["percentiles"][name]["value"] <= high
        # Mean: SE sigma / sqrt(n); standard deviation: SE sigma / sqrt(2 n).
        assert found["mean"] == pytest.approx(nominal, abs=ALLOWED * sigma / math.sqrt(SAMPLES))
        assert found["std"] == pytest.approx(sigma, abs=ALLOWED * sigma / math.sqrt(2 * SAMPLES))
        assert case["stall"]["count"] == 0
        # One input, exactly proportional: the regression is perfect.
        sensitivity = case["sensitivity"]
        assert sensitivity["r_squared"] == pytest.approx(1.0, abs=1e-9)
        assert sensitivity["inputs"][0]["src"] == pytest.approx(1.0, abs=1e-9)


def test_stall_probability_and_percentiles_in_the_stalled_tail(tmp_path: Path) -> None:
    temperature = -40.0
    friction = hand.fecd(temperature) + hand.fs(temperature)  # 1.343 N*m, by hand
    te_nominal = hand.TE
    sigma = 0.185  # N*m: P(stall) = Phi((1.343 - 1.58) / 0.185) = 10 %
    config = load_config(
        write_config(
            tmp_path,
            f'"load.end_torque" = {{ distribution = "normal", sigma = "{sigma} N*m" }}',
            'sampling = "random"\nseed = 2718\nchunk_size = 8192',
        )
    )
    plan = build_plan(config, SAMPLES, temperatures=[temperature])
    out = tmp_path / "run"
    run(plan, out)
    case = summarize(plan, out)["cases"][0]
    p_stall = scipy_stats.norm.cdf((friction - te_nominal) / sigma)
    assert 0.09 < p_stall < 0.11  # the case is what it claims to be
    stall = case["stall"]
    binomial_se = math.sqrt(p_stall * (1 - p_stall) / SAMPLES)
    assert stall["probability"] == pytest.approx(p_stall, abs=ALLOWED * binomial_se)
    assert stall["interval95"][0] < p_stall < stall["interval95"][1]
    found = case["deployment_time_s"]
    for name, p in {"P1": 0.01, "P5": 0.05, "P50": 0.5, "P95": 0.95, "P99": 0.99}.items():
        value = found["percentiles"][name]["value"]
        te = te_nominal + sigma * scipy_stats.norm.ppf(1.0 - p)
        if 1.0 - p < p_stall:
            # Te's (1 - p)-quantile lies below the friction: the percentile is a stall.
            assert value is None, name
            continue
        # Bound the Te quantile by five standard errors, then map it through the
        # decreasing time function t(Te) of the exact hand solution.
        se = quantile_error(1.0 - p, SAMPLES, sigma)
        slowest = hand.exact_time(temperature, te=te - ALLOWED * se)
        fastest = hand.exact_time(temperature, te=te + ALLOWED * se)
        assert fastest <= value <= slowest, (name, fastest, value, slowest)
    assert found["mean"] is None  # some samples never arrive: the mean is infinite
    assert found["mean_arriving"] is not None
    assert found["arriving"] == SAMPLES - stall["count"]


def test_torque_margin_distribution_of_a_normal_end_torque(tmp_path: Path) -> None:
    # Case 3. With a fixed damping speed the factored resistance D = 1.2 F + B omega_req
    # does not depend on the angle, so the margin T_spring / D - 1 is lowest where the
    # spring torque is lowest, at the end of travel: min margin = Te / D - 1, linear in Te.
    # A normal Te (sigma 2 %, far from a stall) gives a normal margin: mean Te_nom / D - 1,
    # standard deviation sigma / D; P(margin < m) = Phi(((m + 1) D - Te_nom) / sigma).
    temperature, speed, factor, required = 25.0, 0.005, 1.2, 0.2
    requirements = (
        f'\n[requirements]\ntemperatures = ["{temperature} degC"]\n'
        f"min_torque_margin = {required}\n"
        f'[requirements.torque_margin]\ndamping_speed = "{speed} rad/s"\n'
        f"factors = {{ friction = {factor} }}\n"
    )
    config = load_config(
        write_config(
            tmp_path,
            '"load.end_torque" = { distribution = "normal", sigma = "2 %" }',
            'sampling = "random"\nseed = 161\nchunk_size = 8192',
            base=PAPER_TEXT + requirements,
        )
    )
    plan = build_plan(config, SAMPLES, temperatures=[temperature])
    out = tmp_path / "run"
    run(plan, out)
    case = summarize(plan, out)["cases"][0]
    resistance = factor * (hand.fecd(temperature) + hand.fs(temperature))
    resistance += hand.becd(temperature) * speed
    sigma = 0.02 * hand.TE / resistance  # of the margin
    mean = hand.TE / resistance - 1.0
    assert case["nominal"]["min_torque_margin"] == pytest.approx(mean, rel=1e-12)
    found = case["min_torque_margin"]
    for name, p in {"P1": 0.01, "P5": 0.05, "P50": 0.5, "P95": 0.95, "P99": 0.99}.items():
        expected = mean + sigma * scipy_stats.norm.ppf(p)
        tolerance = ALLOWED * quantile_error(p, SAMPLES, sigma)
        assert found["percentiles"][name]["value"] == pytest.approx(expected, abs=tolerance)
    below = scipy_stats.norm.cdf(((required + 1.0) * resistance - hand.TE) / (0.02 * hand.TE))
    assert 0.05 < below < 0.95  # the check is not trivially 0 or 1
    binomial_se = math.sqrt(below * (1 - below) / SAMPLES)
    assert found["probability_below_required"] == pytest.approx(below, abs=ALLOWED * binomial_se)
    assert found["factors_applied"] is True

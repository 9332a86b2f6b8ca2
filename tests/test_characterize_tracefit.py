"""Fits of recorded deployments against the exact solution."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ecdsim.characterize.tracefit import (
    Trace,
    durbin_watson,
    fit_damper_trace,
    fit_traces,
    model_angle,
    problem_for,
)
from ecdsim.config import load_config, parse_config
from tests import hand
from tests.conftest import PAPER_CONFIG
from tests.test_characterize_linefit import binomial_band
from tests.test_characterize_synthetic import paper_trace

TEMPERATURES = (-40.0, 25.0, 100.0)


def times_for(temperature: float, step: float = 0.25) -> np.ndarray:
    """Samples from release to 10 % past the hand-computed arrival."""
    return np.arange(0.0, 1.1 * hand.exact_time(temperature), step)


def trace_csv(
    tmp_path: Path,
    temperatures: tuple[float, ...] = TEMPERATURES,
    noise: float = 0.0,
    seed: int = 0,
    column: bool = True,
) -> Path:
    rng = np.random.default_rng(seed)
    lines = ["time_s,angle_rad" + (",temperature_C" if column else "")]
    for t in temperatures:
        times = times_for(t)
        angles = paper_trace(t, times) + rng.normal(0.0, noise, times.size)
        for time, angle in zip(times, angles, strict=True):
            lines.append(f"{float(time)!r},{float(angle)!r}" + (f",{t!r}" if column else ""))
    path = tmp_path / "trace.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def total_friction(t: float) -> float:
    return hand.fecd(t) + hand.fs(t)


def test_exact_traces_recover_damping_and_friction(tmp_path: Path) -> None:
    result = fit_traces(trace_csv(tmp_path), load_config(PAPER_CONFIG))
    assert [f.temperature for f in result.fits] == list(TEMPERATURES)
    for fit in result.fits:
        t = fit.temperature
        # Noise-free traces from the hand closed form; the fit stops at 1e-13 steps.
        assert fit.damping_rate.value == pytest.approx(hand.becd(t), rel=1e-6)
        assert fit.total_friction.value == pytest.approx(total_friction(t), rel=1e-6)
        assert fit.system_friction == pytest.approx(hand.fs(t), rel=1e-12)
        assert fit.friction.value == pytest.approx(hand.fecd(t), rel=1e-6)
    # The paper's BECD is linear in T: BECD_25 * (1 - (0.004 / 1.26) (T - 25)) since the
    # gearbox part (0.26 BD) does not change with temperature (Eq. 1, 3).
    assert result.laws is not None
    b_ref, c = result.laws.damping["linear"].parameters
    assert b_ref.value == pytest.approx(hand.becd(25.0), rel=1e-6)
    assert c.value == pytest.approx(-0.004 / 1.26, rel=1e-5)  # a difference of 1e-6 values
    # FECD = N (FD + FL_T + FG): slope N * -2.12e-6, at 0 degC N * (7.9 + 2.2 + 4.5)e-4.
    assert result.laws.friction is not None
    at_0c, slope = result.laws.friction.parameters
    assert slope.value == pytest.approx(380 * -2.12e-6, rel=1e-5)
    assert at_0c.value == pytest.approx(380 * 14.6e-4, rel=1e-6)


def test_a_noisy_trace_lies_within_its_intervals(tmp_path: Path) -> None:
    result = fit_traces(
        trace_csv(tmp_path, (25.0,), noise=0.002, seed=9), load_config(PAPER_CONFIG)
    )
    (fit,) = result.fits
    assert fit.damping_rate.ci95 is not None
    assert fit.total_friction.ci95 is not None
    assert fit.damping_rate.ci95[0] < hand.becd(25.0) < fit.damping_rate.ci95[1]
    assert fit.total_friction.ci95[0] < total_friction(25.0) < fit.total_friction.ci95[1]
    # White noise: Durbin-Watson is about 2 with standard deviation 2 / sqrt(n).
    assert fit.curve.durbin_watson is not None
    n = fit.statistics.n_points
    assert abs(fit.curve.durbin_watson - 2.0) < 4.0 * 2.0 / np.sqrt(n)


def test_trace_intervals_cover_95_percent() -> None:
    config = load_config(PAPER_CONFIG)
    times = times_for(25.0, step=1.0)
    clean = paper_trace(25.0, times)
    rng = np.random.default_rng(20240606)
    seeds, covered_b, covered_f = 200, 0, 0
    for _ in range(seeds):
        trace = Trace(
            25.0, np.arange(times.size), times, clean + rng.normal(0.0, 0.003, times.size)
        )
        fit = fit_damper_trace(trace, config)
        assert fit.damping_rate.ci95 is not None
        assert fit.total_friction.ci95 is not None
        b_lo, b_hi = fit.damping_rate.ci95
        f_lo, f_hi = fit.total_friction.ci95
        covered_b += b_lo <= hand.becd(25.0) <= b_hi
        covered_f += f_lo <= total_friction(25.0) <= f_hi
    low, high = binomial_band(0.95, seeds)
    assert low <= covered_b / seeds <= high
    assert low <= covered_f / seeds <= high


def test_fit_spring_recovers_the_spring_torques(tmp_path: Path) -> None:
    result = fit_traces(trace_csv(tmp_path), load_config(PAPER_CONFIG), mode="spring")
    assert result.spring is not None
    assert result.spring.start_torque.value == pytest.approx(hand.TS, rel=1e-6)
    assert result.spring.end_torque.value == pytest.approx(hand.TE, rel=1e-6)
    assert len(result.spring.curves) == 3
    assert result.fits == ()


def test_scaling_every_torque_and_the_damping_leaves_the_trace_unchanged() -> None:
    # Why a trace cannot give BECD, friction and the spring torques together.
    config = load_config(PAPER_CONFIG)
    load = config.system.load
    times = np.linspace(0.0, 30.0, 50)
    angles, torques = load.spring.breakpoints(load.travel, 25.0)
    base = model_angle(problem_for(load, 25.0, 24.0, 1.0), times)
    from ecdsim.solvers import QuasiStaticProblem

    scaled = QuasiStaticProblem(angles, 3.0 * torques, np.asarray(3.0), np.asarray(72.0))
    assert model_angle(scaled, times) == pytest.approx(base, rel=1e-12)


def config_text(load: str) -> str:
    return f"""
[damper]
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"
[gearbox]
ratio = 380
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
[load]
{load}
"""


def test_fit_spring_needs_a_linear_spring(tmp_path: Path) -> None:
    table = 'spring_table = [["0 rad", "3.73 N*m"], ["1.57 rad", "1.58 N*m"]]\ntravel = "1.57 rad"'
    config = parse_config(config_text(table))
    result = fit_traces(trace_csv(tmp_path, (25.0,)), config, mode="spring")
    assert result.spring is None
    (failed,) = result.failed
    assert "needs a linear spring" in failed.reason


def test_a_constant_spring_torque_cannot_separate_damping_from_friction(tmp_path: Path) -> None:
    constant = 'start_torque = "3 N*m"\nend_torque = "3 N*m"\ntravel = "1.57 rad"'
    config = parse_config(config_text(constant))
    times = np.linspace(0.0, 20.0, 40)
    path = tmp_path / "line.csv"
    rows = [f"{float(t)!r},{0.05 * float(t)!r}" for t in times]
    path.write_text("time_s,angle_rad\n" + "\n".join(rows) + "\n", encoding="utf-8")
    result = fit_traces(path, config, temperature=25.0)
    (failed,) = result.failed
    assert "cannot tell the parameters apart" in failed.reason


def test_a_file_without_temperatures_uses_the_option_or_warns(tmp_path: Path) -> None:
    path = trace_csv(tmp_path, (25.0,), column=False)
    config = load_config(PAPER_CONFIG)
    assumed = fit_traces(path, config)
    assert "temperature_assumed" in [w.code for w in assumed.warnings]
    assert assumed.fits[0].temperature == 25.0
    # Told it was 100 degC, the fit reads the same trace with FS(100): the total friction
    # is the same (the trace fixes it), FECD = total - FS changes by FS(25) - FS(100).
    hot = fit_traces(path, config, temperature=100.0)
    assert hot.fits[0].temperature == 100.0
    difference = assumed.fits[0].friction.value - hot.fits[0].friction.value
    assert difference == pytest.approx(hand.fs(100.0) - hand.fs(25.0), rel=1e-6)


def test_too_few_samples_fail_that_trace_only(tmp_path: Path) -> None:
    path = trace_csv(tmp_path, (25.0,))
    with path.open("a", encoding="utf-8") as stream:
        stream.write("0.0,0.0,60.0\n1.0,0.05,60.0\n")
    result = fit_traces(path, load_config(PAPER_CONFIG))
    assert [f.temperature for f in result.fits] == [25.0]
    (failed,) = result.failed
    assert failed.temperature == 60.0
    assert "2 sample(s)" in failed.reason


def test_systematic_misfit_and_overtravel_are_flagged(tmp_path: Path) -> None:
    times = times_for(25.0)
    # A resolver whose scale is 5 % high: the trace overshoots the travel and the residuals
    # run in long waves instead of white noise.
    angles = 1.05 * paper_trace(25.0, times)
    path = tmp_path / "scaled.csv"
    rows = [f"{float(t)!r},{float(a)!r},25" for t, a in zip(times, angles, strict=True)]
    path.write_text("time_s,angle_rad,temperature_C\n" + "\n".join(rows) + "\n", encoding="utf-8")
    codes = [w.code for w in fit_traces(path, load_config(PAPER_CONFIG)).warnings]
    assert "beyond_travel" in codes
    assert "correlated_residuals" in codes


def test_durbin_watson_by_hand() -> None:
    # e = 1, 2, 3: sum(diff**2) = 2, sum(e**2) = 14.
    assert durbin_watson(np.array([1.0, 2.0, 3.0])) == pytest.approx(2.0 / 14.0, rel=1e-15)
    assert durbin_watson(np.zeros(4)) is None


def test_json_document(tmp_path: Path) -> None:
    result = fit_traces(trace_csv(tmp_path, noise=0.002, seed=1), load_config(PAPER_CONFIG))
    document = result.to_dict()
    assert document["kind"] == "trace"
    assert document["mode"] == "damper"
    entry = document["temperatures"][1]
    for key in (
        "temperature_C",
        "damping_rate_Nms_per_rad",
        "damping_rate_ci95_Nms_per_rad",
        "friction_Nm",
        "friction_ci95_Nm",
        "total_friction_Nm",
        "r_squared",
        "n_points",
        "durbin_watson",
        "points",
    ):
        assert key in entry
    assert entry["temperature_C"] == 25.0
    assert document["temperature_laws"] is not None


def test_a_placeholder_damper_in_the_config_does_not_stop_the_fit(tmp_path: Path) -> None:
    # The config's damper is only a starting point. Here it is silly (its damping law is
    # negative at 100 degC) and the trace is too sparse for the quadratic start (2 samples
    # before 80 % of the travel): the start then comes from the data's mean speed.
    silly = PAPER_CONFIG.read_text().replace(
        'damping_temperature_coefficient = "-0.004 / K"',
        'damping_temperature_coefficient = "-0.5 / K"',
    )
    config = parse_config(silly)
    assert float(config.system.ecd.at(100.0).ecd_damping_rate) < 0.0
    times = np.arange(0.0, 17.0, 4.0)
    trace = Trace(100.0, np.arange(times.size), times, paper_trace(100.0, times))
    assert np.count_nonzero((trace.angle < 0.8 * hand.TRAVEL) & (times > 0)) == 2
    fit = fit_damper_trace(trace, config)
    assert fit.damping_rate.value == pytest.approx(hand.becd(100.0), rel=1e-6)
    assert fit.total_friction.value == pytest.approx(total_friction(100.0), rel=1e-6)

"""Real (shear-thinning) fluid dampers (issue 28, item 3), against hand formulas and scipy.

* the power-law torque and its speed derivative against their definitions and a central
  difference; the Arrhenius factor by hand;
* the quasi-static time across a linear net torque, closed form, against
  ``scipy.integrate.quad`` of ``c**(1/n) (a - k phi)**(-1/n)``; the paper's mean-speed
  analogue by hand;
* the bench fit: exact data give back the law that made them; noisy data cover it
  (interval coverage over simulated benches);
* ``compare-fluid`` with a measured law against the closed form typed here.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from typer.testing import CliRunner

from ecdsim.characterize.csvdata import Table
from ecdsim.characterize.fluidfit import fit_fluid, fit_fluid_bench
from ecdsim.cli.app import app
from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.physics.fluid import (
    arrhenius_factor,
    power_law_mean_speed_time,
    power_law_segment_duration,
    power_law_torque,
    power_law_torque_slope,
)
from ecdsim.sizing.fluid import compare_fluid
from tests import hand
from tests.conftest import ROOT
from tests.test_qualification_examples import (
    FLUID_ACTIVATION,
    FLUID_BENCH,
    FLUID_SPEEDS,
    FLUID_TEMPERATURES,
    FLUID_TORQUE,
    fluid_exponent,
    fluid_torque,
)

runner = CliRunner()
MEASURED = ROOT / "examples" / "fluid_measured.toml"


# Physics ---------------------------------------------------------------------------------


def test_power_law_torque_and_its_slope() -> None:
    c, n = 2.0, 0.45
    w = np.array([-0.3, 0.02, 0.5, 2.0])
    np.testing.assert_allclose(
        power_law_torque(w, c, n), np.sign(w) * c * np.abs(w) ** n, rtol=1e-15
    )
    # The derivative against a central difference (step 1e-6 relative: error ~1e-12).
    h = np.abs(w) * 1e-6
    difference = (power_law_torque(w + h, c, n) - power_law_torque(w - h, c, n)) / (2 * h)
    np.testing.assert_allclose(power_law_torque_slope(w, c, n), difference, rtol=1e-8)
    # The linear core below omega_l: c omega_l^(n-1) omega, continuous at omega_l.
    wl = 0.01
    assert float(power_law_torque(0.004, c, n, wl)) == pytest.approx(c * wl ** (n - 1) * 0.004)
    assert float(power_law_torque(wl * (1 - 1e-12), c, n, wl)) == pytest.approx(c * wl**n, rel=1e-9)
    assert float(power_law_torque_slope(0.0, c, n, wl)) == pytest.approx(c * wl ** (n - 1))
    assert math.isinf(float(power_law_torque_slope(0.0, c, n)))


def test_the_arrhenius_factor_by_hand() -> None:
    # 2040 K between -15 and +40 degC: exp(2040 (1/258.15 - 1/313.15)) = 4.00.
    by_hand = math.exp(2040.0 * (1.0 / 258.15 - 1.0 / 313.15))
    assert float(arrhenius_factor(-15.0, 2040.0, 40.0)) == pytest.approx(by_hand, rel=1e-14)
    assert 3.9 < by_hand < 4.1


@pytest.mark.parametrize("n", [0.43, 0.47, 0.8, 1.0, 1.5])
@pytest.mark.parametrize(("a", "b"), [(2.5, 0.6), (0.6, 2.5), (1.2, 1.2 * (1 + 1e-9))])
def test_the_segment_time_is_the_integral(n: float, a: float, b: float) -> None:
    # t = integral_0^L c^(1/n) (a - k phi)^(-1/n) dphi, k = (a - b) / L, by quad.
    length, c = 1.3, 1.7
    k = (a - b) / length
    p = 1.0 / n

    def integrand(phi: float) -> float:
        return float(c**p * (a - k * phi) ** (-p))

    reference, _ = quad(integrand, 0.0, length, epsabs=0.0, epsrel=1e-13)
    assert float(power_law_segment_duration(length, c, n, a, b)) == pytest.approx(
        reference, rel=1e-11
    )


def test_closed_form_by_hand_and_a_stall() -> None:
    length, c, n, a, b = 1.57, 1.7, 0.45, 2.5, 0.6
    p = 1 / n
    k = (a - b) / length
    by_hand = c**p * (a ** (1 - p) - b ** (1 - p)) / (k * (1 - p))
    assert float(power_law_segment_duration(length, c, n, a, b)) == pytest.approx(
        by_hand, rel=1e-12
    )
    assert math.isinf(float(power_law_segment_duration(length, c, n, a, -0.1)))
    # Exponents per temperature broadcast: each equals its own scalar call.
    ns = np.array([0.43, 0.45, 0.47])
    np.testing.assert_allclose(
        power_law_segment_duration(length, c, ns, a, b),
        [float(power_law_segment_duration(length, c, float(x), a, b)) for x in ns],
        rtol=1e-15,
    )


def test_the_papers_method_with_a_power_law_by_hand() -> None:
    c, n, a, b, travel = 1.7, 0.45, 2.5, 0.6, 1.57
    ws, we = (a / c) ** (1 / n), (b / c) ** (1 / n)
    by_hand = travel / ((ws + we) / 2)
    assert float(power_law_mean_speed_time(travel, c, n, a, b)) == pytest.approx(by_hand, rel=1e-14)
    # n = 1 is Eq. 8-11 of the paper with B = c.
    assert float(power_law_mean_speed_time(travel, c, 1.0, a, b)) == pytest.approx(
        travel / ((a + b) / (2 * c)), rel=1e-14
    )


# The bench fit ----------------------------------------------------------------------------


def _table() -> Table:
    return Table("synthetic", "", {}, np.zeros(0, dtype=np.int64), {}, (), ())


def _bench(noise: float, rng: np.random.Generator | None = None) -> tuple[np.ndarray, ...]:
    temps, speeds, torques = [], [], []
    for t in FLUID_TEMPERATURES:
        for w in FLUID_SPEEDS:
            error = 1.0 if rng is None else float(np.exp(rng.normal(0.0, noise)))
            temps.append(t)
            speeds.append(w)
            torques.append(fluid_torque(w, t) * error)
    rows = np.arange(2, 2 + len(temps))
    return np.array(temps), np.array(speeds), np.array(torques), rows


def test_exact_bench_data_give_back_their_law() -> None:
    temps, speeds, torques, rows = _bench(0.0)
    result = fit_fluid(temps, speeds, torques, rows, _table(), 0.1, 25.0)
    for fit in result.fits:
        assert fit.exponent.value == pytest.approx(fluid_exponent(fit.temperature), rel=1e-12)
        assert fit.reference_torque.value == pytest.approx(
            fluid_torque(0.1, fit.temperature), rel=1e-12
        )
    constants = result.law_constants()
    assert constants["torque"] == pytest.approx(FLUID_TORQUE, rel=1e-10)
    assert constants["activation"] == pytest.approx(FLUID_ACTIVATION, rel=1e-10)
    assert constants["exponent"] == pytest.approx(0.45, rel=1e-10)
    assert constants["exponent_slope"] == pytest.approx(-0.0006, rel=1e-9)
    # 3 to 5 times the torque at -15 degC of that at 40 degC, as the flight dampers.
    assert result.torque_ratio(-15.0, 40.0) == pytest.approx(
        math.exp(FLUID_ACTIVATION * (1 / 258.15 - 1 / 313.15)), rel=1e-10
    )


def test_the_example_bench_recovers_its_law_within_the_intervals() -> None:
    result = fit_fluid_bench(FLUID_BENCH, 0.1)
    assert result.torque_law is not None
    assert result.exponent_law is not None
    (log_torque, activation) = result.torque_law.parameters
    (exponent, slope) = result.exponent_law.parameters
    for estimate, truth in (
        (log_torque, math.log(FLUID_TORQUE)),
        (activation, FLUID_ACTIVATION),
        (exponent, 0.45),
        (slope, -0.0006),
    ):
        assert estimate.ci95 is not None
        assert estimate.ci95[0] <= truth <= estimate.ci95[1]
    assert 3.0 < result.torque_ratio(-15.0, 40.0) < 5.0


def test_interval_coverage_over_simulated_benches() -> None:
    # The log-log line is ordinary least squares with Gaussian errors: n's 95 % interval is
    # exact per temperature. The activation's interval combines three temperatures by
    # Welch-Satterthwaite, as the ECD's laws do (docs/characterize.md: 95-96 %). 400
    # benches, the band 95 % +- 3.5 sigma of a binomial proportion.
    rng = np.random.default_rng(20261202)
    benches = 400
    hit_n = hit_b = total_n = 0
    for _ in range(benches):
        temps, speeds, torques, rows = _bench(0.02, rng)
        result = fit_fluid(temps, speeds, torques, rows, _table(), 0.1, 25.0)
        for fit in result.fits:
            low, high = fit.exponent.ci95 or (0.0, 0.0)
            hit_n += low <= fluid_exponent(fit.temperature) <= high
            total_n += 1
        assert result.torque_law is not None
        low, high = result.torque_law.parameters[1].ci95 or (0.0, 0.0)
        hit_b += low <= FLUID_ACTIVATION <= high
    for hits, count in ((hit_n, total_n), (hit_b, benches)):
        sigma = math.sqrt(0.95 * 0.05 / count)
        assert abs(hits / count - 0.95) <= 3.5 * sigma, (hits, count)


# The comparison ----------------------------------------------------------------------------


def test_compare_fluid_with_a_measured_law_by_hand() -> None:
    config = load_config(MEASURED)
    spec = config.spec.fluid_damper
    assert spec is not None
    assert spec.power_law is not None
    law = spec.power_law
    # No deadband and no inertia: the damped phase over the whole travel, by hand.
    spec = spec.model_copy(update={"deadband": 0.0, "load_inertia": None})
    temps = (-40.0, 25.0, 100.0)
    result = compare_fluid(config.system, spec, temps)
    for i, t in enumerate(temps):
        n = law.exponent + law.exponent_slope * (t - 25.0)
        torque_r = law.torque * math.exp(law.activation * (1 / (t + 273.15) - 1 / 298.15))
        c = torque_r / law.reference_speed**n
        friction = hand.fecd(t) + hand.fs(t)  # the fluid takes the ECD's FECD by default
        a, b = hand.TS - friction, hand.TE - friction
        p = 1 / n
        k = (a - b) / hand.TRAVEL
        by_hand = c**p * (a ** (1 - p) - b ** (1 - p)) / (k * (1 - p))
        assert float(result.fluid.damped_time[i]) == pytest.approx(by_hand, rel=1e-12)
        assert float(result.ecd.damped_time[i]) == pytest.approx(hand.exact_time(t), rel=1e-12)
        ws, we = (a / c) ** p, (b / c) ** p
        assert result.fluid.paper_time is not None
        assert float(result.fluid.paper_time[i]) == pytest.approx(
            hand.TRAVEL / ((ws + we) / 2), rel=1e-12
        )
    assert bool(result.extrapolated[0])
    assert not bool(result.extrapolated[1])


def test_compare_fluid_command_on_the_measured_example(tmp_path: Path) -> None:
    done = runner.invoke(app, ["compare-fluid", str(MEASURED), "--json", "--plot", str(tmp_path)])
    assert done.exit_code == 0, done.output
    document = json.loads(done.stdout)
    assert document["fluid_damper"]["law"] == "power_law"
    assert document["fluid_damper"]["matched_coefficient"] is None
    cold, *_, hot = document["cases"]
    # The spread: the fluid's torque at w_r falls by far more over temperature than the ECD's.
    fluid_spread = cold["fluid_torque_at_reference_Nm"] / hot["fluid_torque_at_reference_Nm"]
    ecd_spread = cold["ecd_torque_at_reference_Nm"] / hot["ecd_torque_at_reference_Nm"]
    assert fluid_spread > 10 * ecd_spread
    assert "extrapolated" in done.stderr
    assert (tmp_path / "ecd_vs_fluid.png").read_bytes().startswith(b"\x89PNG")
    table = runner.invoke(app, ["compare-fluid", str(MEASURED)], env={"COLUMNS": "100"})
    assert "measured (power law" in table.stdout
    assert "outside the bench data's temperatures" in table.stdout


FLUID_HEAD = (ROOT / "examples" / "paper_cc16.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("section", "fragment"),
    [
        (
            '[fluid_damper]\nsource = "x"\nlaw = "andrade"\n[fluid_damper.power_law]\n'
            'reference_speed = "0.1 rad/s"\ntorque = "1 N*m"\nexponent = 0.45\n',
            "power_law replaces law",
        ),
        ('[fluid_damper]\nsource = "x"\n', 'give law = "andrade" or "walther"'),
        (
            '[fluid_damper]\nsource = "x"\n[fluid_damper.power_law]\nreference_speed = '
            '"0.1 rad/s"\ntorque = "1 N*m"\nexponent = 0.45\nactivation = "2000 N*m"\n',
            "fluid_damper.power_law.activation: '2000 N*m' has the wrong dimension; expected "
            "an activation temperature",
        ),
        (
            '[fluid_damper]\nsource = "x"\n[fluid_damper.power_law]\nreference_speed = '
            '"0.1 rad/s"\ntorque = "1 N*m"\nexponent = 0.05\n',
            "fluid_damper.power_law.exponent: 0.05 must be in [0.1, 3]",
        ),
    ],
)
def test_bad_power_laws_are_one_line_errors(section: str, fragment: str) -> None:
    with pytest.raises(ConfigError) as raised:
        parse_config(FLUID_HEAD + "\n" + section)
    assert any(fragment in line for line in str(raised.value).splitlines()), str(raised.value)


# The command -------------------------------------------------------------------------------


def test_fit_fluid_damper_writes_a_config_compare_fluid_reads(tmp_path: Path) -> None:
    out = tmp_path / "measured.toml"
    done = runner.invoke(
        app, ["fit", "fluid-damper", str(FLUID_BENCH), "--config", str(ROOT / "examples" /
              "fluid.toml"), "-o", str(out), "--json", "--reference-speed", "0.1"],
    )  # fmt: skip
    assert done.exit_code == 0, done.output
    document = json.loads(done.stdout)
    assert document["reference_speed_rad_s"] == 0.1
    assert 3.0 < document["cold_to_hot_torque_ratio"] < 5.0
    loaded = load_config(out)
    spec = loaded.spec.fluid_damper
    assert spec is not None
    assert spec.power_law is not None
    assert spec.law is None
    assert spec.power_law.activation == pytest.approx(document["power_law"]["activation"], rel=1e-5)
    assert runner.invoke(app, ["compare-fluid", str(out)]).exit_code == 0
    # Without --config: a placeholder ECD and load, marked as such.
    bare = tmp_path / "bare.toml"
    done = runner.invoke(app, ["fit", "fluid-damper", str(FLUID_BENCH), "-o", str(bare)])
    assert done.exit_code == 0, done.output
    assert "PLACEHOLDER" in bare.read_text(encoding="utf-8")
    assert runner.invoke(app, ["compare-fluid", str(bare)]).exit_code == 0


def test_fit_fluid_damper_table_and_plot(tmp_path: Path) -> None:
    done = runner.invoke(
        app, ["fit", "fluid-damper", str(FLUID_BENCH), "--plot", str(tmp_path)],
        env={"COLUMNS": "80"},
    )  # fmt: skip
    assert done.exit_code == 0, done.output
    assert "x that at 40 degC" in done.stdout
    table = [line for line in done.stdout.splitlines() if not line.startswith("wrote ")]
    assert max(len(line) for line in table) <= 80
    assert (tmp_path / "fluid_damper_fit.png").read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize(
    ("text", "args", "fragment"),
    [
        ("temperature [degC],torque [N*m]\n25,1\n", [], "missing column 'speed_rad_s'"),
        ("speed [rad/s],torque [N*m]\n0.1,1\n0.1,1.1\n", [], "no temperature could be fitted"),
        ("speed [rad/s],torque [N*m]\n0.1,1\n0.2,-1\n", [], "must be > 0"),
        ("speed [rad/s],torque [N*m]\n0.1,1\n0.2,1.4\n", ["--reference-speed", "-1"],
         "--reference-speed: '-1' must be > 0"),
        ("speed [rad/s],torque [N*m]\n0.1,1\n0.2,1.4\n", ["--reference-speed", "1 N"],
         "--reference-speed: '1 N' has the wrong dimension"),
    ],
)  # fmt: skip
def test_bad_bench_files_and_options(
    tmp_path: Path, text: str, args: list[str], fragment: str
) -> None:
    path = tmp_path / "bench.csv"
    path.write_text(text, encoding="utf-8")
    done = runner.invoke(app, ["fit", "fluid-damper", str(path), *args])
    assert done.exit_code == 2, done.output
    assert fragment in done.stderr


def test_the_help_and_its_example(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from tests.helptext import assert_options, read_help, run_example

    screen = read_help(runner, app, ["fit", "fluid-damper"])
    assert_options(
        screen,
        {"--json": None, "--plot": None, "--output": "-o", "--config": None,
         "--reference-speed": None, "--reference-temperature": None, "--units": None,
         "--wide": None, "--plain": None, "--help": None},
    )  # fmt: skip
    run_example(runner, app, screen, tmp_path, monkeypatch)
    assert (tmp_path / "fluid_measured.toml").is_file()

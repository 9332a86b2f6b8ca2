"""FMU export (issue 17 item 1): the model by hand, and the FMUs run by FMPy.

* the damper model against the paper's Eq. 1-4 by hand (tests/hand.py) and its heat
  balance against the closed-form adiabatic solution;
* the damper FMU driven by FMPy with the speed history of an ecdsim dynamic run
  reproduces the run's damper torque and damper temperature (to 1e-6);
* the deployment FMU reproduces the dynamic method's angle and speed and latches at its
  deployment time.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import ecdsim
from ecdsim.cli.app import app
from ecdsim.fmu.model import DamperModel
from tests import hand
from tests.conftest import require

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT / "examples" / "paper_cc16.toml"
DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"
BD, C_T, N = 1.3e-4, -0.004, 380.0  # the paper's damper (section 6)


def heated_config(folder: Path, heat_capacity: str = "5 J/K") -> Path:
    """The paper's dynamic example with a small lumped damper (rises about 0.34 K)."""
    text = DYNAMIC.read_text(encoding="utf-8").replace(
        "[gearbox]",
        f'[damper.thermal]\nheat_capacity = "{heat_capacity}"\n'
        'thermal_resistance = "20 K/W"\n\n[gearbox]',
        1,
    )
    path = folder / "heated.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_damper_model_is_the_papers_ecd_by_hand() -> None:
    model = DamperModel.from_config(ecdsim.load(PAPER), 25.0)
    for t in (-40.0, 25.0, 100.0):
        # BECD_T * u and FECD_T of Eq. 1-4 (tests/hand.py), the same sums in another
        # order: 1e-12.
        assert model.damper_torque(0.1, t) == pytest.approx(hand.becd(t) * 0.1, rel=1e-12)
        assert model.friction_torque(0.1, t) == pytest.approx(hand.fecd(t), rel=1e-12)
        assert model.friction_torque(-0.1, t) == pytest.approx(-hand.fecd(t), rel=1e-12)
    assert model.friction_torque(0.0, 25.0) == 0.0
    # No [damper.thermal]: the damper is at the ambient temperature.
    model.advance(0.2, 0.0, 40.0, 1.0)
    assert model.temperature == 40.0


def _paper_with(tmp_path: Path, old: str, new: str) -> DamperModel:
    text = PAPER.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "variant.toml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return DamperModel.from_config(ecdsim.load(path), 25.0)


def test_damper_model_with_a_lossy_mesh_by_hand(tmp_path: Path) -> None:
    # A lossy mesh (eta_f = 0.8, FG = 0 as the config requires) used to be dropped from
    # the damper FMU's damping torque (its friction had it, through FECD_T). By hand: the
    # torque is N (BD f(T) + BG) N u / eta_f (Modelica's LossyGear, forward: the shaft
    # always drives this inertia-free damper), the friction (FD + FL_T) N / eta_f
    # (Eq. 2 and 4 without FG).
    eta = 0.8
    model = _paper_with(
        tmp_path,
        'coulomb_friction = "4.5e-4 N*m"',
        'coulomb_friction = "0 N*m"\nefficiency = { forward = 0.8 }',
    )
    for t in (-40.0, 25.0, 100.0):
        becd = (BD * (1.0 + C_T * (t - 25.0)) + 0.26 * BD) * N**2 / eta
        fecd = (7.9e-4 + (-2.12e-6 * t + 2.2e-4)) * N / eta
        # The same sums in another order: 1e-12.
        assert model.damper_torque(0.1, t) == pytest.approx(becd * 0.1, rel=1e-12)
        assert model.friction_torque(-0.1, t) == pytest.approx(-fecd, rel=1e-12)


def test_damper_model_with_stribeck_friction_by_hand(tmp_path: Path) -> None:
    # A Stribeck curve (f_D = 1.5, w_St = 0.02 rad/s at the slow shaft) used to be
    # dropped: the FMU's friction was the kinetic FECD at every speed. By hand, the ECD's
    # share of the dynamic method's curve: FECD (1 + (f_D - 1) e^{-(u/w_St)^2}).
    f_d, w_st = 1.5, 0.02
    model = _paper_with(
        tmp_path,
        'coulomb_friction = "7.9e-4 N*m"',
        'coulomb_friction = "7.9e-4 N*m"\nstatic_friction_factor = 1.5\n'
        'stribeck_speed = "0.02 rad/s"',
    )
    for t in (-40.0, 25.0, 100.0):
        assert model.damper_torque(0.1, t) == pytest.approx(hand.becd(t) * 0.1, rel=1e-12)
        for u in (0.005, 0.02, 0.05, -0.01):
            curve = 1.0 + (f_d - 1.0) * math.exp(-((u / w_st) ** 2))
            expected = math.copysign(hand.fecd(t) * curve, u)
            assert model.friction_torque(u, t) == pytest.approx(expected, rel=1e-12)
    # Near rest the friction is the breakaway f_D FECD; far from it the kinetic FECD.
    assert model.friction_torque(1e-9, 25.0) == pytest.approx(f_d * hand.fecd(25.0), rel=1e-12)
    assert model.friction_torque(1.0, 25.0) == pytest.approx(hand.fecd(25.0), rel=1e-12)


def test_a_compliant_mesh_is_refused_by_the_damper_fmu(tmp_path: Path) -> None:
    # The damper FMU is rigid from shaft to rotor: a compliant mesh would be dropped.
    text = DYNAMIC.read_text(encoding="utf-8").replace(
        'lost_motion = "0 deg"', 'lost_motion = "0.25 deg"\nstiffness = "2 kN*m/rad"'
    )
    assert "stiffness" in text
    path = tmp_path / "compliant.toml"
    path.write_text(text, encoding="utf-8")
    result = CliRunner().invoke(app, ["export-fmu", str(path), "-o", str(tmp_path / "x.fmu")])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "gearbox.stiffness: a compliant mesh is not in the damper FMU" in result.stderr
    assert not (tmp_path / "x.fmu").exists()


def test_heat_balance_matches_the_adiabatic_closed_form(tmp_path: Path) -> None:
    # The [damper.thermal] table without its resistance (None removes it): adiabatic.
    thermal = {"heat_capacity": "0.05 J/K", "thermal_resistance": None}
    config = ecdsim.load(heated_config(tmp_path), overrides={"damper.thermal": thermal})
    model = DamperModel.from_config(config, 25.0)
    u = 0.1  # slow shaft [rad/s]
    # Adiabatic, constant speed: C dT/dt = BD f(T) (N u)^2 with f = 1 + c (T - 25), so
    # f(t) = exp(c k t), k = BD (N u)^2 / C, and T = 25 + (f - 1) / c.
    k = BD * (N * u) ** 2 / 0.05
    for _ in range(10):
        model.advance(u, 0.0, 25.0, 1.0)
    expected = 25.0 + (math.exp(C_T * k * 10.0) - 1.0) / C_T
    assert expected - 25.0 > 30.0  # a real rise, so that the factor matters
    # Runge-Kutta 4 with 1 ms steps on a smooth exponential: far below 1e-9 K.
    assert model.temperature == pytest.approx(expected, abs=1e-9)


def _run(kind: str, fmu: Path, folder: Path, **inputs: Any) -> Any:
    """Simulate ``fmu`` with FMPy in a child process (tests/fmu_driver.py says why)."""
    require("pythonfmu")
    require("fmpy")
    source, target = folder / f"{kind}-in.npz", folder / f"{kind}-out.npz"
    start = inputs.pop("start", {})
    np.savez(
        source,
        start_names=np.array(list(start), dtype=str),
        start_values=np.array(list(start.values()), dtype=float),
        **inputs,
    )
    subprocess.run(
        [sys.executable, "-m", "tests.fmu_driver", kind, str(fmu), str(source), str(target)],
        cwd=ROOT,
        check=True,
        timeout=600,
    )
    with np.load(target) as data:
        return {name: data[name] for name in data.files}


@pytest.mark.slow
def test_damper_fmu_reproduces_a_dynamic_run(tmp_path: Path) -> None:
    require("pythonfmu")
    from ecdsim.fmu import build_fmu
    from ecdsim.plotting_dynamic import dynamic_result

    config = heated_config(tmp_path)
    fmu = build_fmu(config, tmp_path / "damper.fmu")
    ambient = 25.0
    run = ecdsim.deploy(config, temperatures=ambient, methods="dynamic")
    result = dynamic_result(run.prediction)
    assert result is not None
    latch = run.deployment_time("dynamic")[ambient]
    step = 2e-3
    times = np.arange(0.0, latch, step)
    series = result.sample(times)
    speed = series.speed[:, 0]
    heat = series.damper_temperature[:, 0]
    torque = -series.damping_torque[:, 0]  # the run's, opposing the motion
    assert heat[-1] - ambient > 0.3  # the damper heats: the check has something to see

    got = _run(
        "damper", fmu, tmp_path, time=times, speed=speed, start={"ambient_temperature": ambient}
    )
    # 1e-6: the FMU integrates the heat balance with the speed extrapolated over each
    # 2 ms step from the last two inputs (error ~ step^2, about 4e-7 K here); the run's
    # own tolerance (rtol 1e-8) is far below.
    assert np.max(np.abs(got["damper_temperature"] - heat)) < 1e-6
    moving = np.abs(torque) > 0.0
    assert np.max(np.abs(got["damper_torque"][moving] / torque[moving] - 1.0)) < 1e-6
    # The same torque by hand from the run's speed and damper temperature (Eq. 1, 3):
    # N^2 (BD (1 + c (T_d - 25)) + BG) u, BG = 0.26 BD.
    by_hand = N**2 * (BD * (1.0 + C_T * (heat - 25.0)) + 0.26 * BD) * speed
    assert np.max(np.abs(got["damper_torque"][moving] / by_hand[moving] - 1.0)) < 1e-6
    # Friction: the ECD's FECD(25 degC) (hand.fecd); the run's friction also holds FS_T.
    friction = got["friction_torque"][moving]
    assert friction == pytest.approx(np.full(friction.size, hand.fecd(25.0)), rel=1e-12)
    assert hand.fecd(25.0) + hand.fs(25.0) == pytest.approx(
        -float(series.friction_torque[5, 0]), rel=1e-12
    )


@pytest.mark.slow
def test_damper_fmu_parameters_override_the_config(tmp_path: Path) -> None:
    require("pythonfmu")
    from ecdsim.fmu import build_fmu

    fmu = build_fmu(PAPER, tmp_path / "damper.fmu")
    got = _run(
        "damper",
        fmu,
        tmp_path,
        time=np.array([0.0]),
        speed=np.array([0.05]),
        start={"gear_ratio": 400.0, "ambient_temperature": -40.0},
    )
    # Eq. 1 and 3 at -40 degC with N = 400, by hand.
    becd = (BD * (1.0 + C_T * (-40.0 - 25.0)) + 0.26 * BD) * 400.0**2
    assert float(got["damper_torque"][0]) == pytest.approx(becd * 0.05, rel=1e-12)
    assert float(got["damper_temperature"][0]) == -40.0


@pytest.mark.slow
def test_deployment_fmu_follows_the_dynamic_method(tmp_path: Path) -> None:
    require("pythonfmu")
    code = CliRunner().invoke(
        app, ["export-fmu", str(DYNAMIC), "--deployment", "-o", str(tmp_path / "d.fmu")]
    )
    assert code.exit_code == 0, code.output
    out = _run(
        "deployment",
        tmp_path / "d.fmu",
        tmp_path,
        stop_time=35.0,
        output_interval=0.25,
        start={"ambient_temperature": 100.0},
    )
    run = ecdsim.deploy(DYNAMIC, temperatures=100.0, methods="dynamic")
    latch = run.deployment_time("dynamic")[100.0]
    before = out["time"] < latch
    trajectory = run.prediction.trajectory("dynamic", out["time"][before])
    # The FMU evaluates the same solution at the same times: equal to rounding.
    assert out["angle"][before] == pytest.approx(np.ravel(trajectory.angle), abs=1e-12)
    assert out["speed"][before] == pytest.approx(np.ravel(trajectory.speed), abs=1e-12)
    assert not out["latched"][before].any()
    assert out["latched"][~before].all()
    assert out["angle"][-1] == pytest.approx(1.57, abs=1e-9)  # the travel
    assert out["speed"][-1] == 0.0


def test_export_fmu_errors_are_one_line_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["export-fmu", str(PAPER), "--deployment", "-o", "x.fmu"])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "load.inertia: missing" in result.stderr
    result = runner.invoke(app, ["export-fmu", str(PAPER), "-o", str(tmp_path / "x.zip")])
    assert result.exit_code == 2
    assert "--out" in result.stderr
    monkeypatch.setitem(sys.modules, "pythonfmu.builder", None)
    result = runner.invoke(app, ["export-fmu", str(PAPER), "-o", str(tmp_path / "x.fmu")])
    assert result.exit_code == 2
    assert "pip install 'ecdsim[fmu]'" in result.stderr
    assert not (tmp_path / "x.fmu").exists()


@pytest.mark.slow
def test_help_lists_the_options_and_its_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    require("pythonfmu")
    from tests.helptext import assert_options, read_help, run_example

    runner = CliRunner()
    screen = read_help(runner, app, ["export-fmu"])
    assert_options(screen, {"--out": "-o", "--deployment": None, "--help": None})
    run_example(runner, app, screen, tmp_path, monkeypatch)
    assert (tmp_path / "damper.fmu").read_bytes().startswith(b"PK")  # a zip archive

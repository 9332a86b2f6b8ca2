"""Temperature laws, table extrapolation, linear-range limits and other flagged results."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ecdsim.deployment import ModelDomainError, predict
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    HighSpeedDamper,
    LinearTemperatureLaw,
    Load,
    TabulatedSpring,
    TabulatedTemperatureLaw,
)
from ecdsim.physics import laws
from tests import hand
from tests.conftest import paper_system


def test_table_law_interpolates_and_holds_ends() -> None:
    law = TabulatedTemperatureLaw((-40.0, 25.0, 100.0), (3.0e-4, 1.7e-4, 1.0e-5))
    # Linear between points: halfway from 25 to 100 degC -> (1.7e-4 + 1.0e-5)/2 = 9.0e-5.
    assert float(law(62.5)) == pytest.approx(9.0e-5, rel=1e-12)
    # Outside: held at the nearest end, and flagged.
    np.testing.assert_allclose(law(np.array([-60.0, 120.0])), [3.0e-4, 1.0e-5], rtol=1e-15)
    np.testing.assert_array_equal(law.out_of_range(np.array([-60.0, 0.0, 120.0])), [1, 0, 1])


def test_table_law_validation() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        TabulatedTemperatureLaw((25.0, -40.0), (1.0, 2.0))
    with pytest.raises(ValueError, match="two"):
        TabulatedTemperatureLaw((25.0,), (1.0,))


def test_linear_law_scalar_1d_2d() -> None:
    # Every check here repeats the law's one multiply-add by hand: rounding only (1e-12).
    assert float(laws.linear_in_temperature(25.0, -0.0044, 0.58)) == pytest.approx(0.47, rel=1e-12)
    temps = np.array([[-40.0], [100.0]])
    slopes = np.array([-0.0044, -0.004, 0.0])
    out = laws.linear_in_temperature(temps, slopes, 0.58)
    assert out.shape == (2, 3)
    assert out[0, 0] == pytest.approx(-0.0044 * -40.0 + 0.58, rel=1e-12)
    assert out[1, 2] == 0.58  # slope 0: the value at 0 degC, exactly


def test_table_extrapolation_warning_in_prediction() -> None:
    base = paper_system()
    table = TabulatedTemperatureLaw((-20.0, 25.0, 80.0), (0.66, 0.47, 0.23))
    load = dataclasses.replace(base.load, system_friction=table)
    prediction = predict(DeploymentSystem(base.ecd, load), [-40.0, 25.0, 100.0])
    extrapolated = [w for w in prediction.warnings if w.code == "table_extrapolation"]
    assert [w.temperature_C for w in extrapolated] == [-40.0, 100.0]
    assert "load.system_friction" in extrapolated[0].message
    # Held at the end values: FS(-40) = 0.66, FS(100) = 0.23.
    np.testing.assert_allclose(prediction.system_friction, [0.66, 0.47, 0.23])


def test_linear_range_warnings_say_by_how_much() -> None:
    base = paper_system()
    # At 25 degC the start speed is (3.73 - 1.00466)/23.65272 = 0.115223 rad/s, so the
    # high-speed shaft turns at 380 * 0.115223 = 43.785 rad/s; a 40 rad/s limit is
    # exceeded by 9.46 %. Eddy torque there: 1.3e-4 * 43.785 = 5.692e-3 N*m.
    damper = dataclasses.replace(base.ecd.damper, max_linear_speed=40.0, max_linear_torque=5.0e-3)
    system = DeploymentSystem(Ecd(damper, base.ecd.gearbox), base.load)
    prediction = predict(system, [25.0], methods=["exact"])
    speed = 380.0 * (3.73 - 1.00466) / 23.65272
    by_code = {w.code: w for w in prediction.warnings}
    assert f"{100.0 * (speed / 40.0 - 1.0):.1f} %" in by_code["linear_range_speed"].message
    torque = 1.3e-4 * speed
    assert f"{100.0 * (torque / 5.0e-3 - 1.0):.1f} %" in by_code["linear_range_torque"].message
    # Limits above the operating point: no warning.
    relaxed = dataclasses.replace(damper, max_linear_speed=50.0, max_linear_torque=1.0e-2)
    quiet = predict(DeploymentSystem(Ecd(relaxed, base.ecd.gearbox), base.load), [25.0])
    assert not [w for w in quiet.warnings if w.code.startswith("linear_range")]


def test_negative_friction_is_flagged_not_hidden() -> None:
    # FS_T = -0.0044 T + 0.58 turns negative above 131.8 degC.
    prediction = predict(paper_system(), [140.0])
    codes = {w.code for w in prediction.warnings}
    assert "negative_friction" in codes
    # The same multiply-add by hand: rounding only.
    assert float(prediction.system_friction[0]) == pytest.approx(-0.0044 * 140.0 + 0.58, rel=1e-12)


def test_damping_law_out_of_domain_is_a_clear_error() -> None:
    # BD_T = BD (1 - 0.004 (T - 25)) = 0 at T = 275 degC. The total BT_T = BD_T + 0.26 BD
    # would stay positive up to 340 degC, but a negative BD_T is already outside the law.
    with pytest.raises(ModelDomainError, match="damping_temperature_coefficient"):
        predict(paper_system(), [280.0])
    with pytest.raises(ModelDomainError, match="BD_T"):
        predict(paper_system(), [345.0])
    ok = predict(paper_system(), [270.0])
    assert float(ok.ecd.damper_damping_rate[0]) > 0.0


def test_spring_temperature_coefficient() -> None:
    base = paper_system()
    from ecdsim.model import LinearSpring

    spring = LinearSpring(3.73, 1.58, temperature_coefficient=-2e-4, reference_temperature=25.0)
    system = DeploymentSystem(base.ecd, Load(spring, 1.57, base.load.system_friction))
    prediction = predict(system, [-40.0])
    factor = 1.0 + -2e-4 * (-40.0 - 25.0)  # 1.013
    assert prediction.problem.torques[0, 0] == pytest.approx(3.73 * factor, rel=1e-12)  # rounding
    expected = hand.exact_time(-40.0, ts=3.73 * factor, te=1.58 * factor)
    assert prediction.solutions["exact"].deployment_time[0] == pytest.approx(expected, rel=1e-12)


def test_tabulated_spring_validation() -> None:
    with pytest.raises(ValueError, match="start at angle 0"):
        TabulatedSpring((0.1, 1.0), (2.0, 1.0))
    with pytest.raises(ValueError, match="increasing"):
        TabulatedSpring((0.0, 1.0, 0.5), (2.0, 1.0, 1.0))


def test_to_dict_needs_a_1d_sweep() -> None:
    damper = HighSpeedDamper(np.array([1.2e-4, 1.3e-4]), 7.9e-4)
    base = paper_system()
    system = DeploymentSystem(Ecd(damper, base.ecd.gearbox), base.load)
    prediction = predict(system, np.array([[25.0]]))
    with pytest.raises(ValueError, match="1-D"):
        prediction.to_dict()


def test_zero_law_default() -> None:
    assert float(LinearTemperatureLaw()(123.0)) == 0.0

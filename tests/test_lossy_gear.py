"""[gearbox] efficiency (issue 16 item 5): a lossy mesh instead of the constant FG.

Checked against hand calculations: Eq. 1-4 with the forward efficiency typed out, the
exact and paper deployment times of the paper's example through it (the closed forms of
tests/hand.py with the new BECD and FECD), the mesh law of Modelica's LossyGear and the
power-flow indicator on a two-inertia system solved by hand; and the config's refusals.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import predict
from ecdsim.montecarlo.apply import NotTolerable, Parameters, apply, nominal
from ecdsim.montecarlo.tolerances import resolve
from ecdsim.physics import gearing
from ecdsim.sizing.margin import MarginSettings, margin_over_travel
from tests import hand

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16.toml"
TEXT = EXAMPLE.read_text()
TEMPERATURES = (-40.0, 25.0, 100.0)
FG_LINE = 'coulomb_friction = "4.5e-4 N*m"                    # FG'


def _lossy(efficiency: str, fg: str = "0 N*m") -> str:
    assert FG_LINE in TEXT
    return TEXT.replace(FG_LINE, f'coulomb_friction = "{fg}"\nefficiency = {efficiency}')


def _becd(t: float, eta_f: float) -> float:
    """Eq. 1 and 3 by hand through the mesh: (BD_T + BG) N^2 / eta_f."""
    return (hand.BD * (1.0 - 0.004 * (t - 25.0)) + hand.BG_FRACTION * hand.BD) * hand.N**2 / eta_f


def _fecd(t: float, eta_f: float) -> float:
    """Eq. 2 and 4 by hand through the mesh, FG = 0: (FD + FL_T) N / eta_f."""
    return (hand.FD + (-2.12e-6 * t + 2.2e-4)) * hand.N / eta_f


def _exact_time(t: float, eta_f: float) -> float:
    # B dphi/dt = Ts - k phi - F, integrated by hand: t = (B/k) ln(a / (a - k travel)).
    friction = _fecd(t, eta_f) + hand.fs(t)
    a = hand.TS - friction
    k = (hand.TS - hand.TE) / hand.TRAVEL
    return _becd(t, eta_f) / k * math.log(a / (a - k * hand.TRAVEL))


def _paper_time(t: float, eta_f: float) -> float:
    # Eq. 8-11 by hand.
    friction = _fecd(t, eta_f) + hand.fs(t)
    ws = (hand.TS - friction) / _becd(t, eta_f)
    we = (hand.TE - friction) / _becd(t, eta_f)
    return hand.TRAVEL / ((ws + we) / 2.0)


def test_becd_and_fecd_are_divided_by_the_forward_efficiency() -> None:
    config = parse_config(_lossy("{ forward = 0.8, backward = 0.7 }"))
    state = config.system.ecd.at(np.array(TEMPERATURES))
    for i, t in enumerate(TEMPERATURES):
        # 1e-13: the same products and one division, in another order
        assert state.ecd_damping_rate[i] == pytest.approx(_becd(t, 0.8), rel=1e-13)
        assert state.ecd_friction[i] == pytest.approx(_fecd(t, 0.8), rel=1e-13)
    # At +25 degC by hand: BT = 1.638e-4, BECD = 1.638e-4 * 380^2 / 0.8 = 29.5659 N*m*s/rad;
    # FT = 7.9e-4 + 1.67e-4 = 9.57e-4, FECD = 9.57e-4 * 380 / 0.8 = 0.454575 N*m.
    assert float(state.ecd_damping_rate[1]) == pytest.approx(29.5659, rel=1e-12)
    assert float(state.ecd_friction[1]) == pytest.approx(0.454575, rel=1e-12)
    assert float(state.backward_efficiency) == 0.7


def test_exact_and_paper_times_through_the_lossy_mesh_by_hand() -> None:
    config = parse_config(_lossy("{ forward = 0.85 }"))
    prediction = predict(config.system, np.array(TEMPERATURES), ("exact", "paper"))
    for i, t in enumerate(TEMPERATURES):
        # 1e-12: the same closed forms in another order of operations
        exact = prediction.solutions["exact"].deployment_time[i]
        paper = prediction.solutions["paper"].deployment_time[i]
        assert exact == pytest.approx(_exact_time(t, 0.85), rel=1e-12)
        assert paper == pytest.approx(_paper_time(t, 0.85), rel=1e-12)


def test_a_lossy_mesh_slows_more_than_the_constant_fg_it_replaces_at_this_load() -> None:
    # FG = 4.5e-4 N*m at the fast shaft is 0.171 N*m at the input; eta_f = 0.85 adds
    # (1/0.85 - 1) = 17.6 % to BECD (about 4.2 N*m*s/rad) and to FECD: slower, by hand:
    plain = predict(parse_config(TEXT).system, np.array([25.0]), ("exact",))
    lossy = predict(parse_config(_lossy("{ forward = 0.85 }")).system, np.array([25.0]), ("exact",))
    t_plain = float(plain.solutions["exact"].deployment_time[0])
    t_lossy = float(lossy.solutions["exact"].deployment_time[0])
    assert t_plain == pytest.approx(hand.exact_time(25.0), rel=1e-12)  # today's value
    assert t_lossy == pytest.approx(_exact_time(25.0, 0.85), rel=1e-12)
    assert t_lossy > t_plain


def test_an_ideal_mesh_gives_the_example_without_fg() -> None:
    # eta = 1 is an ideal gear: the same numbers as FG = 0 without the key, to the bit
    # (x / 1.0 is x in IEEE arithmetic).
    ideal = parse_config(_lossy("{ forward = 1 }"))
    plain = parse_config(TEXT.replace(FG_LINE, 'coulomb_friction = "0 N*m"'))
    temps = np.array(TEMPERATURES)
    a = predict(ideal.system, temps, ("exact", "paper"))
    b = predict(plain.system, temps, ("exact", "paper"))
    for method in ("exact", "paper"):
        np.testing.assert_array_equal(
            a.solutions[method].deployment_time, b.solutions[method].deployment_time
        )


def test_the_mesh_law_forward_and_back_driven() -> None:
    # Modelica LossyGear: forward tau_in = N tau_out / eta_f, back-driven N tau_out eta_b.
    reflected = np.array([2.0, 2.0, -2.0, -2.0, 2.0])
    speed = np.array([1.0, -1.0, -1.0, 1.0, 0.0])
    tau_in = gearing.input_torque(reflected, speed, 0.8, 0.5)
    # by hand: 2/0.8, 2*0.5, -2/0.8, -2*0.5, and at rest forward (breakaway drives)
    assert tau_in.tolist() == pytest.approx([2.5, 1.0, -2.5, -1.0, 2.5], rel=1e-15)
    loss = gearing.mesh_loss_power(reflected, speed, 0.8, 0.5)
    # (tau_in - N tau_out) omega: 0.5, 1.0 (back-driven: 2 W in, 1 W out), 0.5, 1.0, 0
    assert loss.tolist() == pytest.approx([0.5, 1.0, 0.5, 1.0, 0.0], rel=1e-15)


def test_the_power_flow_indicator_has_the_sign_of_the_mesh_torque() -> None:
    # Load J_L = 2 feels A; damper side J_D = 3 (at the input) feels D; mesh torque M
    # (N tau_out), load side tau_in = M/eta_f forward or M eta_b back. Solved by hand:
    # forward J_L a = A - M/eta_f, J_D a = M - D  =>  M = (J_L D + J_D A)/(J_L + J_D/eta_f)
    # Case 1: A = 5, D = 1 (spring drives, damper resists): M > 0, forward.
    # Case 2: A = -4, D = 1 (load braked hard, rotor overruns): J_L D + J_D A = -10 < 0.
    j_l, j_d, eta_f, eta_b = 2.0, 3.0, 0.8, 0.5
    for a_load, d in ((5.0, 1.0), (-4.0, 1.0)):
        sigma = float(gearing.power_flow_indicator(j_l, j_d, d, a_load))
        m = sigma / (j_l + (j_d / eta_f if sigma >= 0.0 else j_d * eta_b))
        acc_load = (a_load - (m / eta_f if m >= 0.0 else m * eta_b)) / j_l
        acc_damper = (m - d) / j_d
        # one rigid gear: both sides accelerate together (1e-14: rounding of a few ops)
        assert acc_load == pytest.approx(acc_damper, rel=1e-14)
    assert float(gearing.power_flow_indicator(j_l, j_d, 1.0, 5.0)) == 17.0  # 2*1 + 3*5
    assert float(gearing.power_flow_indicator(j_l, j_d, 1.0, -4.0)) == -10.0


@pytest.mark.parametrize(
    ("efficiency", "fg", "message"),
    [
        ("{ forward = 0 }", "0 N*m", "gearbox.efficiency.forward: 0 must be in (0, 1]"),
        ("{ forward = 1.2 }", "0 N*m", "gearbox.efficiency.forward: 1.2 must be in (0, 1]"),
        ("{ forward = 0.9, backward = -0.1 }", "0 N*m", "gearbox.efficiency.backward"),
        ("{ forward = '0.9 N*m' }", "0 N*m", "gearbox.efficiency.forward"),
        ("{ backward = 0.9 }", "0 N*m", "gearbox.efficiency.forward"),
        ("{ forward = 0.9, sideways = 0.5 }", "0 N*m", "sideways"),
        ("{ forward = 0.9 }", "4.5e-4 N*m", "efficiency replaces the constant gearbox friction"),
    ],
)
def test_bad_efficiencies_are_refused_by_name(
    efficiency: str, fg: str, message: str, tmp_path: Path
) -> None:
    text = _lossy(efficiency, fg)
    with pytest.raises(ConfigError) as caught:
        parse_config(text)
    assert message in str(caught.value)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = CliRunner().invoke(app, ["deploy", str(path)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    assert message in result.output


def test_the_torque_margin_counts_the_mesh_loss_as_its_own_kind() -> None:
    # FECD = 0.5 and BECD = 10 include 1/eta_f with eta_f = 0.8; damping taken at 0.1 rad/s.
    # By hand: ideal-gear parts 0.8 * 0.5 = 0.4 (friction) and 0.8 * 1.0 = 0.8 (damping),
    # mesh loss 0.2 * (0.5 + 1.0) = 0.3; with factor 2 on it and FS = 0.3, the resistance
    # is 0.4 + 0.3 + 0.8 + 0.6 = 2.1 and TM = 4.2 / 2.1 - 1 = 1 at the first point.
    terms = margin_over_travel(
        np.array([0.0, 1.0]),
        np.array([4.2, 2.1]),
        ecd_friction=0.5,
        system_friction=0.3,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=MarginSettings(factors={"gear_loss": 2.0}, damping_speed=0.1),
        forward_efficiency=0.8,
    )
    assert terms.resistive["ecd_friction"][0] == pytest.approx(0.4, rel=1e-15)
    assert terms.resistive["damping"][0] == pytest.approx(0.8, rel=1e-15)
    assert terms.resistive["gear_loss"][0] == pytest.approx(0.3, rel=1e-14)
    assert terms.margin[:2].tolist() == pytest.approx([1.0, 0.0], abs=1e-14)
    # Unit factors: the kinds add up to FECD + BECD w, the margin of an ideal split.
    plain = margin_over_travel(
        np.array([0.0, 1.0]),
        np.array([4.2, 2.1]),
        ecd_friction=0.5,
        system_friction=0.3,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=MarginSettings(damping_speed=0.1),
    )
    split = margin_over_travel(
        np.array([0.0, 1.0]),
        np.array([4.2, 2.1]),
        ecd_friction=0.5,
        system_friction=0.3,
        damping_rate=10.0,
        stalled=False,
        stall_angle=math.nan,
        settings=MarginSettings(damping_speed=0.1),
        forward_efficiency=0.8,
    )
    # 1e-14: the same sum in another order
    np.testing.assert_allclose(split.margin, plain.margin, rtol=1e-14)


def test_monte_carlo_takes_tolerances_on_the_efficiencies() -> None:
    config = parse_config(_lossy("{ forward = 0.85, backward = 0.7 }"))
    assert nominal(Parameters(config.system), "gearbox.efficiency.forward") == 0.85
    assert nominal(Parameters(config.system), "gearbox.efficiency.backward") == 0.7
    with pytest.raises(NotTolerable, match="efficiency, which this config does not give"):
        nominal(Parameters(parse_config(TEXT).system), "gearbox.efficiency.forward")
    sampled = apply(Parameters(config.system), {"gearbox.efficiency.forward": np.array([0.8, 0.9])})
    state = sampled.system.ecd.at(25.0)
    # BECD at +25 degC by hand: 1.638e-4 * 380^2 / eta_f
    np.testing.assert_allclose(state.ecd_damping_rate, [23.65272 / 0.8, 23.65272 / 0.9], rtol=1e-12)


@pytest.mark.parametrize(
    ("spread", "message"),
    [
        ('{ distribution = "uniform", plus_minus = "0.2" }', "must stay <= 1"),
        ('{ distribution = "uniform", plus_minus = "0.9" }', "must stay > 0"),
    ],
)
def test_an_efficiency_spread_must_stay_within_0_and_1(spread: str, message: str) -> None:
    text = _lossy("{ forward = 0.85 }") + (
        f'\n[tolerances]\n[tolerances.quantities]\n"gearbox.efficiency.forward" = {spread}\n'
    )
    with pytest.raises(ConfigError) as caught:
        resolve(parse_config(text))
    assert message in str(caught.value)
    assert "gearbox.efficiency.forward" in str(caught.value)

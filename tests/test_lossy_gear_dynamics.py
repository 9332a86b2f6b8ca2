"""The dynamic method through a lossy gear (issue 16 item 5): power flow, switch, energy.

The reference is a tight scipy integration of the same equations typed here from the
mesh law (Modelica's LossyGear): the load J_L and the damper side J_D (rotor at the fast
shaft times N^2) are one rigid train; the damper side needs D = B_q w + F_q sign(w) (an
ideal gear's BECD and FECD), the load feels A = T_net(phi) - FS_T sign(w). The mesh passes
M = N tau_out; forward (M w >= 0) the load supplies M / eta_f, back-driven M eta_b:

    J_L w' = A - M / eta_f  (or - M eta_b),   J_D w' = M - D.

Solved per mode: w' = (A - m D) / (J_L + m J_D), m = 1/eta_f or eta_b, with the mode that
of the sign of (J_L D + J_D A) w. The reference stops at every mode switch, zero speed
and breakpoint (terminal events) and restarts, so each piece is smooth.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import parse_config
from ecdsim.deployment import Prediction, predict
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.result import DynamicResult
from tests import hand

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16_dynamic.toml"
TEXT = EXAMPLE.read_text()
FG_LINE = 'coulomb_friction = "4.5e-4 N*m"                    # FG'
ETA_F, ETA_B = 0.8, 0.6
J_LOAD = 5.0
ROTOR = 1e-4  # kg*m^2 at the fast shaft: a heavy rotor, so that it can overrun the load
BD = 1.3e-5  # a tenth of the paper's damper: little damping, so that the load decelerates
# Resistance rising from 0 to 5 N*m over 0.3..0.6 rad: beyond the spring, so the load is
# braked hard, the rotor overruns it (back-driven) and the motion stops and turns back.
RESIST = [(0.0, 0.0), (0.3, 0.0), (0.6, 5.0), (1.6, 5.0)]


def _result(prediction: Prediction) -> DynamicResult:
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    return solution.result


def _crossing(row: float) -> Callable[[float, np.ndarray], float]:
    """An event: the angle passes a table row."""

    def event(_s: float, y: np.ndarray) -> float:
        return float(y[0]) - row

    return event


def _config_text(efficiency: str, restitution: float = 0.0) -> str:
    table = ", ".join(f'["{a} rad", "{r} N*m"]' for a, r in RESIST)
    text = TEXT.replace(FG_LINE, f'coulomb_friction = "0 N*m"\nefficiency = {efficiency}')
    text = text.replace('rotor_inertia = "2e-7 kg*m^2"', f'rotor_inertia = "{ROTOR} kg*m^2"')
    text = text.replace('damping_rate = "1.3e-4 N*m*s/rad"', f'damping_rate = "{BD} N*m*s/rad"')
    text = text.replace('travel = "1.57 rad"', f'travel = "1.57 rad"\nresistive_table = [{table}]')
    return text.replace("restitution = 0.0 ", f"restitution = {restitution} ")


def _reference(
    t: float,
    bd: float = BD,
    rotor: float = ROTOR,
    resist: list[tuple[float, float]] = RESIST,
    eta_f: float = ETA_F,
    eta_b: float = ETA_B,
) -> dict[str, object]:
    """Integrate the two-inertia train through the lossy mesh until it sticks or latches."""
    n = hand.N
    bq = (bd * (1.0 - 0.004 * (t - 25.0)) + hand.BG_FRACTION * bd) * n**2
    fq = (hand.FD + (-2.12e-6 * t + 2.2e-4)) * n  # FG = 0
    fs = hand.fs(t)
    j_d = rotor * n**2
    angles = [a for a, _ in resist]
    torques = [r for _, r in resist]

    def net(phi: float) -> float:
        spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
        return spring - float(np.interp(phi, angles, torques))

    state = np.array([0.0, 0.0, 0.0])  # phi, w, gear loss
    time = 0.0
    switches: list[float] = []
    sign = 1.0
    forward = True
    just_switched = False
    for _ in range(100):
        phi, w = float(state[0]), float(state[1])
        if w == 0.0:
            drive = net(phi)
            if abs(drive) <= fs + fq / eta_f:  # breakaway drives the damper: forward
                return {
                    "end": "stick",
                    "time": time,
                    "angle": phi,
                    "speed": 0.0,
                    "gear_loss": float(state[2]),
                    "switches": switches,
                }
            sign = math.copysign(1.0, drive)
        if not just_switched:
            sigma = J_LOAD * (bq * w + fq * sign) + j_d * (net(phi) - fs * sign)
            forward = sigma * sign >= 0.0
        just_switched = False
        m = 1.0 / eta_f if forward else eta_b

        def rhs(_s: float, y: np.ndarray, m: float = m, sg: float = sign) -> list[float]:
            d = bq * float(y[1]) + fq * sg
            acc = (net(float(y[0])) - fs * sg - m * d) / (J_LOAD + m * j_d)
            mesh = d + j_d * acc  # N tau_out
            return [float(y[1]), acc, (m - 1.0) * mesh * float(y[1])]

        def stop(_s: float, y: np.ndarray, sg: float = sign) -> float:
            return float(y[1]) * sg

        def flow(_s: float, y: np.ndarray, sg: float = sign) -> float:
            d = bq * float(y[1]) + fq * sg
            return (J_LOAD * d + j_d * (net(float(y[0])) - fs * sg)) * sg

        def latch(_s: float, y: np.ndarray) -> float:
            return float(y[0]) - hand.TRAVEL

        stop.direction = -1  # type: ignore[attr-defined]
        flow.direction = -1 if forward else 1  # type: ignore[attr-defined]
        events: list[Callable[[float, np.ndarray], float]] = [stop, flow, latch]
        for b in angles[1:-1]:
            if abs(b - phi) > 1e-12:
                events.append(_crossing(b))
        for event in events:
            event.terminal = True  # type: ignore[attr-defined]
        sol = solve_ivp(
            rhs, (0.0, 1e3), state, method="DOP853", rtol=1e-12, atol=1e-15, events=events
        )
        hit = [k for k, te in enumerate(sol.t_events) if len(te)]
        k = min(hit, key=lambda j: float(sol.t_events[j][0]))
        time += float(sol.t_events[k][0])
        state = np.array(sol.y_events[k][0], dtype=float)
        if k == 0:
            state[1] = 0.0
        elif k == 1:
            switches.append(time)
            forward = not forward
            just_switched = True
        elif k == 2:
            return {
                "end": "latch",
                "time": time,
                "angle": hand.TRAVEL,
                "speed": float(state[1]),
                "gear_loss": float(state[2]),
                "switches": switches,
            }
    raise AssertionError("the reference did not come to rest")


@pytest.mark.parametrize("temperature", [-40.0, 25.0, 100.0])
def test_a_braked_load_is_back_driven_by_its_rotor_as_the_reference(temperature: float) -> None:
    config = parse_config(_config_text(f"{{ forward = {ETA_F}, backward = {ETA_B} }}"))
    prediction = predict(
        config.system, np.array([temperature]), ("dynamic",), dynamics=config.spec.dynamics()
    )
    result = _result(prediction)
    expected = _reference(temperature)
    assert expected["end"] == "stick"
    switches = expected["switches"]
    assert isinstance(switches, list)
    assert len(switches) >= 1  # the case has a back-driven phase
    events = result.events.for_case(0)
    found = [e["time_s"] for e in events if e["kind"] == "power_flow"]
    # 1e-8: the reference integrates at rtol 1e-12; ecdsim's pieces are closed forms
    assert found == pytest.approx(switches, rel=1e-8)
    assert bool(result.stuck[0])
    assert float(result.stuck_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.stuck_angle[0]) == pytest.approx(expected["angle"], rel=1e-8)
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    # Every term is computed on its own (closed forms), so the balance closes to rounding.
    assert abs(float(result.energy.error[0])) < 1e-12


def test_a_forward_deployment_through_the_lossy_gear_matches_the_reference() -> None:
    # The paper's damper, no resistance: the load drives the damper all the way (no switch).
    config = parse_config(
        _config_text("{ forward = 0.85, backward = 0.5 }")
        .replace(f'damping_rate = "{BD} N*m*s/rad"', 'damping_rate = "1.3e-4 N*m*s/rad"')
        .replace("resistive_table", "# resistive_table")
    )
    prediction = predict(
        config.system, np.array([25.0]), ("dynamic",), dynamics=config.spec.dynamics()
    )
    result = _result(prediction)
    expected = _reference(25.0, bd=1.3e-4, resist=[(0.0, 0.0), (2.0, 0.0)], eta_f=0.85, eta_b=0.5)
    assert expected["end"] == "latch"
    assert expected["switches"] == []
    # 1e-8: the reference integrates at rtol 1e-12
    assert float(result.deployment_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.arrival_speed[0]) == pytest.approx(expected["speed"], rel=1e-7)
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    assert abs(float(result.energy.error[0])) < 1e-12


def test_an_ideal_gear_changes_nothing_in_the_dynamic_method() -> None:
    # efficiency = 1 both ways is an ideal gear: the same path and bits as no key.
    ideal = parse_config(_config_text("{ forward = 1, backward = 1 }"))
    plain = parse_config(
        _config_text("{ forward = 1 }").replace("efficiency = { forward = 1 }", "")
    )
    temps = np.array([-40.0, 25.0, 100.0])
    a = predict(ideal.system, temps, ("dynamic",), dynamics=ideal.spec.dynamics())
    b = predict(plain.system, temps, ("dynamic",), dynamics=plain.spec.dynamics())
    ra, rb = _result(a), _result(b)
    np.testing.assert_array_equal(ra.final_time, rb.final_time)
    np.testing.assert_array_equal(ra.final_angle, rb.final_angle)
    np.testing.assert_array_equal(ra.energy.gear_loss, np.zeros(3))


def test_the_dynamic_method_takes_a_lossy_gear_with_heating_but_not_with_stribeck() -> None:
    # Once refused (the integrated segments had no power-flow switch): a heated damper
    # through a lossy gear now runs (its accuracy: tests/test_lossy_gear_nonlinear.py).
    text = _config_text("{ forward = 0.9 }").replace(
        "[load]", '[damper.thermal]\nheat_capacity = "50 J/K"\n\n[load]', 1
    )
    config = parse_config(text)
    result = _result(
        predict(config.system, np.array([25.0]), ("dynamic",), dynamics=config.spec.dynamics())
    )
    assert float(result.energy.gear_loss[0]) > 0.0
    stribeck = parse_config(
        _config_text("{ forward = 0.9 }").replace(
            "[gearbox]", 'stribeck_speed = "5 rad/s"\n\n[gearbox]', 1
        )
    )
    with pytest.raises(ValueError, match="gearbox.efficiency: the dynamic method takes"):
        predict(stribeck.system, np.array([25.0]), ("dynamic",), dynamics=stribeck.spec.dynamics())


def test_a_backward_breakaway_from_rest_runs_forward_in_time() -> None:
    # No efficiency key (an ideal gear): the braked load stops, breaks away backward from
    # rest on an underdamped segment and stops again. Its start speed was -0.0, whose
    # atan2 gave a zero-speed time of -pi/beta: negative durations until the event limit.
    text = _config_text("{ forward = 1 }").replace("efficiency = { forward = 1 }", "")
    config = parse_config(text)
    prediction = predict(
        config.system, np.array([25.0]), ("dynamic",), dynamics=config.spec.dynamics()
    )
    result = _result(prediction)
    expected = _reference(25.0, eta_f=1.0, eta_b=1.0)
    assert expected["end"] == "stick"
    times = [e["time_s"] for e in result.events.for_case(0)]
    assert times == sorted(times)
    assert bool(result.stuck[0])
    # 1e-8: the reference integrates at rtol 1e-12
    assert float(result.stuck_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.stuck_angle[0]) == pytest.approx(expected["angle"], rel=1e-8)


def test_a_long_table_keeps_the_lossy_gear_on_its_closed_form() -> None:
    # 40 zero rows add breakpoints only: the same physics as no table. A long table is
    # otherwise crossed by the compiled table kernel, which does not carry the power flow
    # or book the mesh loss; the lossy gear must stay on its closed-form segments.
    rows = ", ".join(f'["{0.04 * k:.2f} rad", "0 N*m"]' for k in range(41))
    base = (
        _config_text("{ forward = 0.85, backward = 0.5 }")
        .replace(f'damping_rate = "{BD} N*m*s/rad"', 'damping_rate = "1.3e-4 N*m*s/rad"')
        .replace("resistive_table", "# resistive_table")
    )
    plain = parse_config(base)
    tabled = parse_config(
        base.replace('travel = "1.57 rad"', f'travel = "1.57 rad"\nresistive_table = [{rows}]', 1)
    )
    temps = np.array([25.0])
    a = _result(predict(plain.system, temps, ("dynamic",), dynamics=plain.spec.dynamics()))
    b = _result(predict(tabled.system, temps, ("dynamic",), dynamics=tabled.spec.dynamics()))
    # 1e-10: the same closed forms, cut at 40 more breakpoints
    np.testing.assert_allclose(b.deployment_time, a.deployment_time, rtol=1e-10)
    np.testing.assert_allclose(b.energy.gear_loss, a.energy.gear_loss, rtol=1e-10)
    assert abs(float(b.energy.error[0])) < 1e-12

"""A lossy gear (issue 16 item 5) on the dynamic method's integrated segments: roll-off,
self-heating, and a power-flow reversal located inside an integrated segment.

The reference is a tight scipy integration (DOP853, rtol 1e-12) of the equations of
docs/model.md (lossy gear) and docs/dynamics.md (roll-off, heating), typed here: the load
J_L and the damper side J_D = J_rotor N^2 are one rigid train; the damper side needs

    D = N (T_eddy(N w, T_d) + BG N w) + F_q sign(w),   F_q = (FD + FL_T) N  (FG = 0)
    T_eddy = 2 T_peak x / (1 + x^2), x = N w / (w_peak (1 + alpha (T_d - T_ref)))  (roll-off)
    T_eddy = BD (1 - 0.004 (T_d - 25)) N w                                       (Eq. 1)
    C T_d' = T_eddy N w - (T_d - T) / R

the load feels A = T_net(phi) - FS_T sign(w); w' = (A - m D) / (J_L + m J_D) with
m = 1/eta_f while (J_L D + J_D A) w > 0 (forward), eta_b otherwise, and the mesh loses
(m - 1) (D + J_D w') w. The reference stops at every switch, zero speed and breakpoint.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.result import DynamicResult
from tests import hand

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "paper_cc16_dynamic.toml"
TEXT = EXAMPLE.read_text()
FG_LINE = 'coulomb_friction = "4.5e-4 N*m"                    # FG'
BD_LINE = 'damping_rate = "1.3e-4 N*m*s/rad"'
ROTOR_LINE = 'rotor_inertia = "2e-7 kg*m^2"'
J_LOAD = 5.0
PEAK, ALPHA = 200.0, 3.9e-3  # roll-off: omega_peak at 25 degC [rad/s], copper-like alpha
HEAT_C, HEAT_R = 0.1, 100.0  # J/K, K/W: a small damper that heats by tens of kelvin
# The back-driven case of tests/test_lossy_gear_dynamics.py: a heavy rotor, a tenth of the
# paper's damping and a resistance rising beyond the spring, so the rotor overruns the load.
HEAVY_ROTOR, LIGHT_BD = 1e-4, 1.3e-5
RESIST = [(0.0, 0.0), (0.3, 0.0), (0.6, 5.0), (1.6, 5.0)]
NO_RESIST = [(0.0, 0.0), (2.0, 0.0)]
# A ground test's gravity (docs/model.md): W = m g r (1 - offload) against deployment,
# W sin(theta_0 + phi), with 2.4 kg at 0.35 m released at 30 deg, 97 % offloaded.
GRAVITY_W = 2.4 * 9.80665 * 0.35 * (1.0 - 0.97)
GRAVITY_THETA0 = math.radians(30.0)
GRAVITY_TOML = (
    '\n\n[load.gravity]\nmass = "2.4 kg"\ncg_radius = "0.35 m"\nrelease_angle = "30 deg"\n'
    'offload = "97 %"\n'
)


def _config_text(
    efficiency: str | None,
    rolloff: bool = False,
    heating: bool = False,
    back_driven: bool = False,
    gravity: bool = False,
) -> str:
    gear = 'coulomb_friction = "0 N*m"'
    if efficiency is not None:
        gear += f"\nefficiency = {efficiency}"
    text = TEXT.replace(FG_LINE, gear)
    extra = ""
    if rolloff:
        extra += (
            f'\nrolloff = {{ peak_speed = "{PEAK} rad/s", '
            f'resistivity_coefficient = "{ALPHA} / K" }}'
        )
    if heating:
        extra += (
            f'\nthermal = {{ heat_capacity = "{HEAT_C} J/K", thermal_resistance = "{HEAT_R} K/W" }}'
        )
    bd = LIGHT_BD if back_driven else hand.BD
    text = text.replace(BD_LINE, f'damping_rate = "{bd} N*m*s/rad"{extra}', 1)
    if back_driven:
        table = ", ".join(f'["{a} rad", "{r} N*m"]' for a, r in RESIST)
        text = text.replace(ROTOR_LINE, f'rotor_inertia = "{HEAVY_ROTOR} kg*m^2"')
        text = text.replace(
            'travel = "1.57 rad"', f'travel = "1.57 rad"\nresistive_table = [{table}]'
        )
    if gravity:
        text = text.replace("\n\n[analysis]", GRAVITY_TOML + "\n[analysis]", 1)
    return text


def _solve(text: str, temperature: float, rtol: float = 1e-10) -> DynamicResult:
    config = parse_config(text)
    dynamics = config.spec.dynamics()
    assert dynamics is not None
    params = dataclasses.replace(dynamics, rtol=rtol)
    prediction = predict(config.system, np.array([temperature]), ("dynamic",), dynamics=params)
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    return solution.result


def _crossing(row: float) -> Callable[[float, np.ndarray], float]:
    def event(_s: float, y: np.ndarray) -> float:
        return float(y[0]) - row

    return event


def _reference(
    t: float,
    eta_f: float,
    eta_b: float,
    rolloff: bool,
    heating: bool,
    back_driven: bool,
    gravity: bool = False,
) -> dict[str, object]:
    """The two-inertia train through the lossy mesh until it sticks or latches."""
    n = hand.N
    bd = LIGHT_BD if back_driven else hand.BD
    bg = hand.BG_FRACTION * bd  # at the fast shaft, not temperature dependent
    fq = (hand.FD + (-2.12e-6 * t + 2.2e-4)) * n  # FD + FL_T at the ambient T, FG = 0
    fs = hand.fs(t)
    j_d = (HEAVY_ROTOR if back_driven else 2e-7) * n**2
    resist = RESIST if back_driven else NO_RESIST
    angles = [a for a, _ in resist]
    torques = [r for _, r in resist]

    def net(phi: float) -> float:
        spring = hand.TS + (hand.TE - hand.TS) * phi / hand.TRAVEL
        weight = GRAVITY_W * math.sin(GRAVITY_THETA0 + phi) if gravity else 0.0
        return spring - float(np.interp(phi, angles, torques)) - weight

    def eddy(w: float, td: float) -> float:
        shaft = n * w
        if rolloff:
            p = PEAK * (1.0 + ALPHA * (td - 25.0))
            return 2.0 * (bd * PEAK / 2.0) * shaft * p / (shaft * shaft + p * p)
        return bd * (1.0 - 0.004 * (td - 25.0)) * shaft

    state = np.array([0.0, 0.0, 0.0, t])  # phi, w, gear loss, T_d
    time = 0.0
    switches: list[float] = []
    sign = 1.0
    forward = True
    just_switched = False
    for _ in range(100):
        phi, w = float(state[0]), float(state[1])
        if w == 0.0:
            drive = net(phi)
            if abs(drive) <= fs + fq / eta_f:  # a breakaway drives the damper: forward
                return {"end": "stick", "time": time, "angle": phi, "switches": switches,
                        "gear_loss": float(state[2]), "temp": float(state[3])}  # fmt: skip
            sign = math.copysign(1.0, drive)

        def need(y: np.ndarray, sg: float) -> float:
            w_ = float(y[1])
            return n * (eddy(w_, float(y[3])) + bg * n * w_) + fq * sg

        if not just_switched:
            sigma = J_LOAD * need(state, sign) + j_d * (net(phi) - fs * sign)
            forward = sigma * sign >= 0.0
        just_switched = False
        m = 1.0 / eta_f if forward else eta_b

        def rhs(_s: float, y: np.ndarray, m: float = m, sg: float = sign) -> list[float]:
            d = need(y, sg)
            acc = (net(float(y[0])) - fs * sg - m * d) / (J_LOAD + m * j_d)
            mesh = d + j_d * acc  # N tau_out
            shaft = n * float(y[1])
            heat = 0.0
            if heating:
                heat = (
                    eddy(float(y[1]), float(y[3])) * shaft - (float(y[3]) - t) / HEAT_R
                ) / HEAT_C
            return [float(y[1]), acc, (m - 1.0) * mesh * float(y[1]), heat]

        def stop(_s: float, y: np.ndarray, sg: float = sign) -> float:
            return float(y[1]) * sg

        def flow(_s: float, y: np.ndarray, sg: float = sign) -> float:
            return (J_LOAD * need(y, sg) + j_d * (net(float(y[0])) - fs * sg)) * sg

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
            return {"end": "latch", "time": time, "speed": float(state[1]), "switches": switches,
                    "gear_loss": float(state[2]), "temp": float(state[3])}  # fmt: skip
    raise AssertionError("the reference did not come to rest")


def _use_numba(monkeypatch: pytest.MonkeyPatch, numba: bool) -> None:
    monkeypatch.setenv("ECDSIM_NUMBA", "1" if numba else "0")


@pytest.mark.parametrize("numba", [True, False])
@pytest.mark.parametrize(("rolloff", "heating"), [(True, False), (False, True), (True, True)])
def test_a_forward_deployment_with_nonlinear_damping_matches_the_reference(
    rolloff: bool, heating: bool, numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # (a) roll-off, (b) heating (and both): the load drives the damper to the latch.
    _use_numba(monkeypatch, numba)
    text = _config_text("{ forward = 0.8, backward = 0.6 }", rolloff, heating)
    result = _solve(text, 25.0)
    expected = _reference(25.0, 0.8, 0.6, rolloff, heating, back_driven=False)
    assert expected["end"] == "latch"
    assert expected["switches"] == []
    assert result.status_names() == ["latched"]
    # 1e-8: ecdsim integrates at rtol 1e-10 (the reference at 1e-12); the arrival time and
    # speed inherit the integrator's error, amplified little over one smooth segment.
    assert float(result.deployment_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.arrival_speed[0]) == pytest.approx(expected["speed"], rel=1e-8)
    # 1e-7: the gear loss is a difference of accumulated terms ((m - 1)(dKE_D + E + F_q x)).
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    # 1e-9 K-scale: the damper temperature (tens of kelvin of rise) at rtol 1e-10.
    assert float(result.final_temperature[0]) == pytest.approx(expected["temp"], abs=1e-6)
    # The energy balance: rtol 1e-10 closes it far below 1e-9.
    assert abs(float(result.energy.error[0])) < 1e-9


@pytest.mark.parametrize("numba", [True, False])
@pytest.mark.parametrize("temperature", [-40.0, 25.0, 100.0])
def test_a_back_driven_phase_inside_an_integrated_segment_matches_the_reference(
    temperature: float, numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # (c) roll-off makes every engaged segment integrated: the switch is found on the
    # integrator's interpolant (compiled and NumPy), then the next segment runs back-driven.
    _use_numba(monkeypatch, numba)
    text = _config_text("{ forward = 0.8, backward = 0.6 }", rolloff=True, back_driven=True)
    result = _solve(text, temperature)
    expected = _reference(temperature, 0.8, 0.6, True, False, back_driven=True)
    assert expected["end"] == "stick"
    switches = expected["switches"]
    assert isinstance(switches, list)
    assert len(switches) >= 1  # the case has a back-driven phase
    events = result.events.for_case(0)
    found = [e["time_s"] for e in events if e["kind"] == "power_flow"]
    # 1e-8: ecdsim at rtol 1e-10, the reference at 1e-12; the switch is bisected on the
    # step's interpolant to 2^-50 of a step.
    assert found == pytest.approx(switches, rel=1e-8)
    assert bool(result.stuck[0])
    assert float(result.stuck_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.stuck_angle[0]) == pytest.approx(expected["angle"], rel=1e-8)
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    assert abs(float(result.energy.error[0])) < 1e-9


def test_compiled_and_plain_kernels_agree_through_a_switch(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The same kernel twice (compiled, and run as plain Python): the same events and
    # numbers to well within the tolerance (1e-9 at rtol 1e-10; the same arithmetic).
    text = _config_text(
        "{ forward = 0.8, backward = 0.6 }", rolloff=True, heating=True, back_driven=True
    )
    _use_numba(monkeypatch, True)
    fast = _solve(text, 25.0)
    _use_numba(monkeypatch, False)
    slow = _solve(text, 25.0)
    kinds = [e["kind"] for e in fast.events.for_case(0)]
    assert "power_flow" in kinds
    assert kinds == [e["kind"] for e in slow.events.for_case(0)]
    for a, b in (
        (fast.final_time, slow.final_time),
        (fast.final_angle, slow.final_angle),
        (fast.energy.gear_loss, slow.energy.gear_loss),
        (fast.final_temperature, slow.final_temperature),
    ):
        assert float(a[0]) == pytest.approx(float(b[0]), rel=1e-9)


def test_an_ideal_gear_with_nonlinear_damping_is_bit_identical_to_no_efficiency_key() -> None:
    for back_driven in (False, True):
        ideal = _config_text("{ forward = 1.0 }", True, True, back_driven)
        plain = _config_text(None, True, True, back_driven)
        a = _solve(ideal, 25.0)
        b = _solve(plain, 25.0)
        np.testing.assert_array_equal(a.final_time, b.final_time)
        np.testing.assert_array_equal(a.final_angle, b.final_angle)
        np.testing.assert_array_equal(a.final_temperature, b.final_temperature)
        np.testing.assert_array_equal(a.energy.gear_loss, np.zeros(1))


def test_scipy_radau_segments_stop_at_the_switch_too() -> None:
    # integrator = "Radau": one solve_ivp call per segment, the switch a terminal event of
    # the same indicator. Roll-off and heating, back-driven phase included.
    config = parse_config(
        _config_text(
            "{ forward = 0.8, backward = 0.6 }", rolloff=True, heating=True, back_driven=True
        )
    )
    dynamics = config.spec.dynamics()
    assert dynamics is not None
    params = dataclasses.replace(dynamics, rtol=1e-10, integrator="Radau")
    prediction = predict(config.system, np.array([25.0]), ("dynamic",), dynamics=params)
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    result = solution.result
    expected = _reference(25.0, 0.8, 0.6, True, True, back_driven=True)
    found = [e["time_s"] for e in result.events.for_case(0) if e["kind"] == "power_flow"]
    assert len(found) >= 1
    # 1e-8 as above (Radau at rtol 1e-10 against DOP853 at 1e-12)
    assert found == pytest.approx(expected["switches"], rel=1e-8)
    assert float(result.stuck_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    assert float(result.final_temperature[0]) == pytest.approx(expected["temp"], abs=1e-6)
    assert abs(float(result.energy.error[0])) < 1e-9


@pytest.mark.parametrize("numba", [True, False])
def test_gravity_with_a_lossy_gear_matches_the_reference(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A ground test's gravity makes every segment integrated even with linear damping:
    # before, the integrated segments took the mesh's inertia but not its factor on the
    # damper's torque, and booked no mesh loss.
    _use_numba(monkeypatch, numba)
    text = _config_text("{ forward = 0.8, backward = 0.6 }", gravity=True)
    result = _solve(text, 25.0)
    expected = _reference(25.0, 0.8, 0.6, False, False, back_driven=False, gravity=True)
    assert expected["end"] == "latch"
    # 1e-8 and 1e-7 as in the forward test above
    assert float(result.deployment_time[0]) == pytest.approx(expected["time"], rel=1e-8)
    assert float(result.arrival_speed[0]) == pytest.approx(expected["speed"], rel=1e-8)
    assert float(result.energy.gear_loss[0]) == pytest.approx(expected["gear_loss"], rel=1e-7)
    assert abs(float(result.energy.error[0])) < 1e-9

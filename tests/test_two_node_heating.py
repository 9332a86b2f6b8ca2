"""Two-node self-heating: the damper's rotor and its housing (issue 16, item 6).

References, written here from docs/dynamics.md and tests/hand.py without ecdsim code:

- the constant-power step response of the two-node network, two exponentials by hand;
- a scipy Radau integration (rtol 1e-12) of the paper's example with the rotor and
  housing temperatures as plain states;
- the heat balance: with BG = 0 and an adiabatic housing, the eddy-current energy is
  exactly the heat stored in the two nodes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config.schema import ThermalSpec
from ecdsim.deployment import ModelDomainError, predict
from ecdsim.dynamics import DynamicParameters, DynamicResult, Thermal
from ecdsim.dynamics.kernel.build import backend
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
)
from tests import hand
from tests.conftest import paper_system
from tests.dynamics_reference import assert_energy_closes, toy_system

T_ZERO = 25.0 + 1.0 / 0.004  # Eq. 1's BD_T = 0 [degC]
C_R, R_RH, C_H, R_HE = 0.002, 40.0, 0.02, 100.0  # rotor, rotor-housing, housing, mount
INTEGRATORS = ["RODAS4", "Radau"]


def _dynamic(
    params: DynamicParameters, temps: list[float], system: DeploymentSystem
) -> DynamicResult:
    solution = predict(system, temps, ["dynamic"], dynamics=params).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    assert_energy_closes(solution.result)
    return solution.result


# --- the constant-power step response ------------------------------------------------


def step_response(power: float, t: float) -> tuple[float, float]:
    """Rotor and housing rises after t at constant power P from 0, by hand.

    theta' = A theta + (P / C_r, 0), A = [[-a, a], [b, -(b + d)]] with a = 1/(R_rh C_r),
    b = 1/(R_rh C_h), d = 1/(R_he C_h). Steady state: theta_h = P R_he, theta_r =
    P (R_rh + R_he). Eigenvalues l of A from l^2 + (a + b + d) l + a d = 0, eigenvectors
    (a, l + a); theta = theta_ss + k1 v1 e^{l1 t} + k2 v2 e^{l2 t} with k from theta(0) = 0.
    """
    a, b, d = 1.0 / (R_RH * C_R), 1.0 / (R_RH * C_H), 1.0 / (R_HE * C_H)
    tr, det = a + b + d, a * d
    root = math.sqrt(tr * tr / 4.0 - det)
    l1, l2 = -tr / 2.0 + root, -tr / 2.0 - root
    ss_r, ss_h = power * (R_RH + R_HE), power * R_HE
    # k1 a + k2 a = -ss_r ; k1 (l1 + a) + k2 (l2 + a) = -ss_h
    k2 = (-ss_h + ss_r * (l1 + a) / a) / ((l2 + a) - (l1 + a))
    k1 = -ss_r / a - k2
    e1, e2 = math.exp(l1 * t), math.exp(l2 * t)
    rotor = ss_r + k1 * a * e1 + k2 * a * e2
    housing = ss_h + k1 * (l1 + a) * e1 + k2 * (l2 + a) * e2
    return rotor, housing


@pytest.mark.parametrize("method", INTEGRATORS)
def test_constant_power_step_response(method: str) -> None:
    # A load held at constant speed: J = 1 kg*m^2 launched at 0.5 rad/s against a drive
    # equal to the damping torque there (BD = 1 N*m*s/rad at N = 1, c = 0: the damping,
    # hence the power BD u^2 = 0.25 W, independent of the temperature; no friction, no
    # spring slope), over 5 rad: 10 s at constant power, then the latch.
    speed, length = 0.5, 5.0
    power = 1.0 * speed**2
    system = toy_system(1.0, 0.0, speed, speed, length)
    thermal = Thermal(C_R, R_RH, C_H, R_HE)
    params = DynamicParameters(1.0, initial_speed=speed, thermal=thermal, rtol=1e-10)
    params = replace(params, integrator=method)
    result = _dynamic(params, [25.0], system)
    duration = length / speed
    rotor, housing = step_response(power, duration)
    # The run ends on x = L at t = L / u exactly (u stays u0): the integrator's error.
    assert float(result.deployment_time[0]) == pytest.approx(duration, rel=1e-9)
    # Global error of an rtol 1e-10 integration: a few 1e-10 of the ~10 K rises.
    assert float(result.final_temperature[0]) - 25.0 == pytest.approx(rotor, rel=1e-8)
    assert result.final_housing_temperature is not None
    housing_rise = float(result.final_housing_temperature[0]) - 25.0
    assert housing_rise == pytest.approx(housing, rel=1e-8)
    # Heat balance: P t = C_r theta_r + C_h theta_h + int theta_h / R_he dt, the last from
    # the housing's equation: int theta_h dt = R_he (P t - C_r theta_r - C_h theta_h) is
    # what is checked against the closed form's integral of the two exponentials.
    a, b, d = 1.0 / (R_RH * C_R), 1.0 / (R_RH * C_H), 1.0 / (R_HE * C_H)
    tr, det = a + b + d, a * d
    root = math.sqrt(tr * tr / 4.0 - det)
    lam = (-tr / 2.0 + root, -tr / 2.0 - root)
    ss_r, ss_h = power * (R_RH + R_HE), power * R_HE
    k2 = (-ss_h + ss_r * (lam[0] + a) / a) / (lam[1] - lam[0])
    k1 = -ss_r / a - k2
    housing_integral = ss_h * duration + sum(
        k * (lv + a) * (math.exp(lv * duration) - 1.0) / lv
        for k, lv in zip((k1, k2), lam, strict=True)
    )
    stored = C_R * (float(result.final_temperature[0]) - 25.0) + C_H * housing_rise
    # The damper dissipation E is the eddy energy (BG = 0): E = stored + to the mount.
    damper = float(result.energy.damper_dissipation[0])
    assert damper == pytest.approx(power * duration, rel=1e-9)
    assert stored + housing_integral / R_HE == pytest.approx(power * duration, rel=1e-8)


# --- the paper's example against a tight reference -----------------------------------


@dataclass(frozen=True)
class Reference:
    time: float
    max_rotor: float
    rotor: float
    housing: float


def two_node_deploy(
    temp0: float,
    inertia: float,
    c_r: float,
    r_rh: float,
    c_h: float,
    r_he: float,
    start: tuple[float, float] = (0.0, 0.0),
) -> Reference:
    """The paper's example (Eq. 1-4, 7 by hand) with the rotor and housing temperatures
    as plain states: C_r T_r' = BD_T(T_r) (N w)^2 - (T_r - T_h) / R_rh,
    C_h T_h' = (T_r - T_h) / R_rh - (T_h - T0) / R_he; Radau at rtol 1e-12."""
    friction = hand.fecd(temp0) + hand.fs(temp0)
    k = (hand.TS - hand.TE) / hand.TRAVEL
    bg = hand.BG_FRACTION * hand.BD

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        phi, w, tr, th = y
        shaft = hand.N * w
        eddy = hand.BD * (1.0 - 0.004 * (tr - 25.0)) * shaft
        flow = (tr - th) / r_rh
        return np.array(
            [
                w,
                (hand.TS - k * phi - friction - hand.N * (eddy + bg * shaft)) / inertia,
                (eddy * shaft - flow) / c_r,
                (flow - (th - temp0) / r_he) / c_h,
            ]
        )

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - hand.TRAVEL)

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = 1  # type: ignore[attr-defined]

    def hottest(t: float, y: np.ndarray) -> float:  # the rotor's maxima, between steps
        return float(rhs(t, y)[2])

    hottest.direction = -1  # type: ignore[attr-defined]
    y0 = [0.0, 0.0, temp0 + start[0], temp0 + start[1]]
    sol = solve_ivp(
        rhs, (0.0, 500.0), y0, method="Radau", rtol=1e-12, atol=1e-12, events=[arrive, hottest]
    )
    assert sol.status == 1
    end = sol.y_events[0][0]
    peak = max([float(np.max(sol.y[2])), *(float(y[2]) for y in sol.y_events[1])])
    return Reference(float(sol.t_events[0][0]), peak, float(end[2]), float(end[3]))


@pytest.mark.parametrize("method", INTEGRATORS)
def test_paper_example_against_reference(method: str) -> None:
    thermal = Thermal(C_R, R_RH, C_H, R_HE)
    params = DynamicParameters(load_inertia=1.0, thermal=thermal, integrator=method, rtol=1e-10)
    result = _dynamic(params, [25.0, -40.0], paper_system())
    assert result.final_housing_temperature is not None
    for i, temp in enumerate([25.0, -40.0]):
        ref = two_node_deploy(temp, 1.0, C_R, R_RH, C_H, R_HE)
        # rtol 1e-10 against 1e-12: the integration's global error, a few 1e-10.
        assert result.deployment_time[i] == pytest.approx(ref.time, rel=1e-8)
        assert result.max_damper_temperature[i] == pytest.approx(ref.max_rotor, abs=1e-7)
        assert result.final_temperature[i] == pytest.approx(ref.rotor, abs=1e-7)
        assert result.final_housing_temperature[i] == pytest.approx(ref.housing, abs=1e-7)
    # The housing matters here: the one-node model (rotor to mount through R_rh) differs.
    one = _dynamic(replace(params, thermal=Thermal(C_R, R_RH)), [25.0, -40.0], paper_system())
    assert np.all(np.abs(one.max_damper_temperature - result.max_damper_temperature) > 0.1)


@pytest.mark.parametrize("method", INTEGRATORS)
def test_rotor_never_crosses_zero_damping(method: str) -> None:
    # A tiny rotor (the issue 11 repro's 0.5 mJ/K) behind a large rotor-housing resistance
    # heats towards Eq. 1's zero at 275 degC: it approaches it, never crosses it, and the
    # run latches on the gearbox damping.
    thermal = Thermal(5e-4, 1e6, 0.01, 1e3)
    params = DynamicParameters(load_inertia=1.0, thermal=thermal, integrator=method)
    result = _dynamic(params, [25.0], paper_system())
    assert result.status_names() == ["latched"]
    assert np.isfinite(result.deployment_time[0])
    assert result.max_damper_temperature[0] < T_ZERO
    assert result.max_damper_temperature[0] > T_ZERO - 1.0  # it did get close
    ref = two_node_deploy(25.0, 1.0, 5e-4, 1e6, 0.01, 1e3)
    # rtol 1e-8 (default) against the rtol 1e-12 reference: 10 rtol of margin.
    assert result.deployment_time[0] == pytest.approx(ref.time, rel=1e-7)


def _no_bg_system() -> DeploymentSystem:
    damper = HighSpeedDamper(damping_rate=hand.BD, coulomb_friction=hand.FD)
    gearbox = Gearbox(ratio=hand.N, coulomb_friction=hand.FG, damping_rate=0.0)
    load = Load(
        spring=LinearSpring(hand.TS, hand.TE),
        travel=hand.TRAVEL,
        system_friction=LinearTemperatureLaw(slope=-0.0044, at_0c=0.58),
    )
    return DeploymentSystem(ecd=Ecd(damper=damper, gearbox=gearbox), load=load)


@pytest.mark.parametrize("method", INTEGRATORS)
def test_heat_stored_in_both_nodes_closes_the_balance(method: str) -> None:
    # Adiabatic housing, BG = 0: all the damper dissipation is eddy-current heat, and it
    # is all stored: E = C_r (T_r - T) + C_h (T_h - T) at the end.
    params = DynamicParameters(load_inertia=1.0, thermal=Thermal(C_R, R_RH, C_H), integrator=method)
    result = _dynamic(params, [25.0], _no_bg_system())
    assert result.final_housing_temperature is not None
    stored = C_R * (result.final_temperature - 25.0) + C_H * (
        result.final_housing_temperature - 25.0
    )
    # The integrated E and temperatures each carry rtol 1e-8 errors.
    assert stored[0] == pytest.approx(result.energy.damper_dissipation[0], rel=1e-6)
    assert result.final_housing_temperature[0] > 25.1  # the housing did heat


def test_omitted_housing_keys_are_the_one_node_model() -> None:
    spec = ThermalSpec.model_validate(
        {"heat_capacity": "0.002 J/K", "thermal_resistance": "40 K/W"}
    )
    assert spec.to_model() == Thermal(C_R, R_RH)
    params = DynamicParameters(load_inertia=1.0, thermal=spec.to_model())
    result = _dynamic(params, [25.0], paper_system())
    assert result.final_housing_temperature is None
    # The one-node model: the two-node reference with a housing so large it stays at T
    # (C_h = 1e12 J/K) is the rotor cooled to T through R_rh.
    ref = two_node_deploy(25.0, 1.0, C_R, R_RH, 1e12, 1.0)
    assert result.deployment_time[0] == pytest.approx(ref.time, rel=1e-7)  # 10 rtol
    assert result.max_damper_temperature[0] == pytest.approx(ref.max_rotor, abs=1e-6)


@pytest.mark.parametrize(
    ("keys", "message"),
    [
        ({"housing_heat_capacity": "0.02 J/K"}, "needs thermal_resistance"),
        ({"thermal_resistance": "40 K/W", "housing_thermal_resistance": "1 K/W"}, "needs housing"),
        ({"thermal_resistance": "40 K/W", "housing_heat_capacity": "-1 J/K"}, "must be > 0"),
        (
            {
                "thermal_resistance": "40 K/W",
                "housing_heat_capacity": "1 J/K",
                "housing_thermal_resistance": "1 K",
            },
            "wrong dimension",
        ),  # fmt: skip
    ],
)
def test_bad_housing_keys(keys: dict[str, str], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ThermalSpec.model_validate({"heat_capacity": "0.002 J/K", **keys})


@pytest.mark.parametrize("numba", [True, False])
def test_compiled_and_plain_kernels_agree(monkeypatch: pytest.MonkeyPatch, numba: bool) -> None:
    # The kernel compiled (numba) and the same kernel run as plain Python integrate the
    # same equations; each is checked against the Radau rtol 1e-12 reference at rtol
    # 1e-10 (global error a few 1e-10), with the housing and a warm start.
    assert backend().name == "numba" or not numba
    monkeypatch.setenv("ECDSIM_NUMBA", "1" if numba else "0")
    thermal = Thermal(C_R, R_RH, C_H, R_HE, initial_rotor_rise=5.0, initial_housing_rise=2.0)
    params = DynamicParameters(load_inertia=1.0, thermal=thermal, rtol=1e-10)
    solution = predict(paper_system(), [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    result = solution.result
    assert result.final_housing_temperature is not None
    ref = two_node_deploy(25.0, 1.0, C_R, R_RH, C_H, R_HE, start=(5.0, 2.0))
    assert result.deployment_time[0] == pytest.approx(ref.time, rel=1e-8)
    assert result.final_housing_temperature[0] == pytest.approx(ref.housing, abs=1e-7)
    assert result.max_damper_temperature[0] == pytest.approx(ref.max_rotor, abs=1e-7)


def test_a_warm_start_beyond_the_zero_of_the_damping_law_is_refused() -> None:
    # Eq. 1 reaches zero damping at 275 degC: a rotor started 260 K above 25 degC would be
    # beyond it. A domain error naming the field, not a NaN from the log state.
    thermal = Thermal(C_R, R_RH, C_H, R_HE, initial_rotor_rise=260.0)
    with pytest.raises(ModelDomainError, match="initial_rotor_rise"):
        predict(
            paper_system(), [25.0], ["dynamic"], dynamics=DynamicParameters(1.0, thermal=thermal)
        )


def test_the_housing_temperature_is_reported_only_with_a_housing() -> None:
    # The JSON case of the dynamic method gains final_housing_temperature_C with two nodes,
    # equal to the result's; without a housing the document keeps its old keys.
    for thermal, has_housing in ((Thermal(C_R, R_RH, C_H, R_HE), True), (Thermal(C_R), False)):
        params = DynamicParameters(load_inertia=1.0, thermal=thermal)
        prediction = predict(paper_system(), [25.0], ["dynamic"], dynamics=params)
        case = prediction.to_dict()["cases"][0]["dynamic"]
        assert ("final_housing_temperature_C" in case) == has_housing
        solution = prediction.solutions["dynamic"]
        assert isinstance(solution, DynamicSolution)
        housing = solution.result.final_housing_temperature
        if has_housing:
            assert housing is not None
            assert case["final_housing_temperature_C"] == float(housing[0])

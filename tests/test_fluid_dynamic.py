"""The shear-thinning fluid damper by the dynamic method (issue 28 item 3).

References: a tight scipy integration of the same equation written here, the closed-form
quasi-static time of :func:`ecdsim.physics.fluid.power_law_segment_duration` in the limit
of a small inertia, and the quasi-static comparison's own free motion through the deadband.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import load_config
from ecdsim.dynamics.damping import PowerLawDamper
from ecdsim.dynamics.kernel import layout, loop
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.solver import pack, solve_dynamic
from ecdsim.physics.fluid import power_law_parts, power_law_segment_duration
from ecdsim.sizing.fluid import compare_fluid

# A boom hinge with a fluid damper: linear spring 3 -> 1.5 N*m over 1.5 rad, Coulomb
# friction 0.6 N*m, c = 5 N*m*(s/rad)^0.45 (T_r = 1.8 N*m at 0.1 rad/s), n = 0.45.
J, T0, T1, TRAVEL, FRICTION, C, N = 0.05, 3.0, 1.5, 1.5, 0.6, 5.0, 0.45
OMEGA_L = 1e-7  # the linear core: 1e-6 of omega_r = 0.1 rad/s (sizing.fluid_dynamic)
ROOT = Path(__file__).resolve().parents[1]


def _problem(inertia: float = J, deadband: float = 0.0, core: float = OMEGA_L) -> DynamicProblem:
    return DynamicProblem(
        angles=np.array([0.0, TRAVEL]),
        torques=np.array([T0, T1]),
        friction=np.asarray(FRICTION),
        damping_rate=C * 0.1 ** (N - 1.0),
        load_inertia=np.asarray(inertia),
        damper_inertia=np.asarray(0.0),
        ecd_friction=np.asarray(FRICTION),
        system_friction=np.asarray(0.0),
        static_friction_factor=np.asarray(1.0),
        system_static_friction_factor=np.asarray(1.0),
        restitution=np.asarray(0.0),
        lost_motion=np.asarray(deadband),
        initial_angle=np.asarray(0.0),
        initial_speed=np.asarray(0.0),
        ambient_temperature=np.asarray(25.0),
        gear_ratio=np.asarray(1.0),
        gearbox_damping_rate=np.asarray(0.0),
        heat_capacity=np.asarray(math.inf),
        thermal_resistance=np.asarray(math.inf),
        eddy=PowerLawDamper(C, N, core),
        rtol=1e-10,
    )


def _reference(deadband: float, core: float = OMEGA_L) -> tuple[float, float]:
    """Arrival time and speed by Radau at rtol 1e-11 of the same equation, written here:
    ``J w' = T(phi) - F - c max(|w|, w_l)^(n-1) w`` once engaged, ``J w' = T(phi)``
    through the deadband (no friction: the damper's friction is its own, disengaged)."""

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        phi, w = y
        spring = T0 - (T0 - T1) / TRAVEL * phi
        if phi < deadband:
            return [w, spring / J]
        fluid = C * max(abs(w), core) ** (N - 1.0) * w
        return [w, (spring - FRICTION - fluid) / J]

    def engage(_t: float, y: np.ndarray) -> float:
        return float(y[0] - deadband)

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - TRAVEL)

    arrive.terminal = True  # type: ignore[attr-defined]
    t0, y0 = 0.0, [0.0, 0.0]
    if deadband > 0.0:
        engage.terminal = True  # type: ignore[attr-defined]
        free = solve_ivp(rhs, (0, 100), y0, method="Radau", rtol=1e-11, atol=1e-14, events=engage)
        t0, y0 = float(free.t_events[0][0]), list(free.y_events[0][0])
        y0[0] = deadband
    sol = solve_ivp(rhs, (t0, 1e3), y0, method="Radau", rtol=1e-11, atol=1e-14, events=arrive)
    return float(sol.t_events[0][0]), float(sol.y_events[0][0][1])


def test_power_law_parts_matches_the_quasi_static_law_and_its_slope() -> None:
    # Above omega_l: c w^n and c n w^(n-1) by hand; below it the Newtonian core c w_l^(n-1) w.
    torque, slope = (
        np.asarray(v) for v in power_law_parts(np.array([0.3, -2.0, 1e-9]), C, N, OMEGA_L)
    )
    assert torque[0] == pytest.approx(C * 0.3**N, rel=1e-14)  # rounding only
    assert torque[1] == pytest.approx(-C * 2.0**N, rel=1e-14)
    assert slope[1] == pytest.approx(C * N * 2.0 ** (N - 1.0), rel=1e-14)
    assert torque[2] == pytest.approx(C * OMEGA_L ** (N - 1.0) * 1e-9, rel=1e-14)
    assert slope[2] == pytest.approx(C * OMEGA_L ** (N - 1.0), rel=1e-14)
    # Continuous at omega_l.
    edge = np.array([OMEGA_L * (1 - 1e-12), OMEGA_L])
    inside, outside = np.asarray(power_law_parts(edge, C, N, OMEGA_L)[0])
    assert inside == pytest.approx(outside, rel=1e-11)


@pytest.mark.parametrize("deadband", [0.0, math.radians(15.0)])
def test_dynamic_fluid_deployment_matches_a_tight_scipy_integration(deadband: float) -> None:
    result = solve_dynamic(_problem(deadband=deadband))
    time, speed = _reference(deadband)
    # Both integrators at rtol 1e-10 / 1e-11 over a ~20 s deployment: agree to 1e-8 (seen:
    # 3e-13 without a deadband); not the last bits (other CPUs round differently).
    assert float(np.ravel(result.deployment_time)[0]) == pytest.approx(time, rel=1e-8)
    assert float(np.ravel(result.arrival_speed)[0]) == pytest.approx(speed, rel=1e-6)
    # The energy account closes: spring work = damper + friction dissipation + final KE.
    assert abs(float(np.ravel(result.energy_balance_error)[0])) < 1e-8


def test_quasi_static_limit_is_the_closed_form_time() -> None:
    # With a small inertia the deployment tends to the quasi-static closed form
    # c w^n = T(phi) - F (docs/qualification.md section 3); the lag is O(J): measured
    # -3.5e-5 at J = 1e-2, -3.5e-7 at 1e-4, -3.5e-9 at 1e-6.
    closed = float(power_law_segment_duration(TRAVEL, C, N, T0 - FRICTION, T1 - FRICTION))
    errors = []
    for inertia in (1e-2, 1e-4):
        time = float(solve_dynamic(_problem(inertia=inertia)).deployment_time.flat[0])
        errors.append(time / closed - 1.0)
    assert abs(errors[0]) < 1e-4
    assert abs(errors[1]) < 1e-6
    # and it falls with J, in proportion (within 10 %: the next order of J).
    assert errors[0] / errors[1] == pytest.approx(100.0, rel=0.1)


def test_the_linear_core_does_not_move_the_deployment() -> None:
    # omega_l = 1e-6 omega_r against 1e-9 omega_r: the time through the core (J w_l / A,
    # ~1e-9 s) and its torque deficit are far below the integrator's tolerance.
    coarse = float(solve_dynamic(_problem(core=OMEGA_L)).deployment_time.flat[0])
    fine = float(solve_dynamic(_problem(core=OMEGA_L * 1e-3)).deployment_time.flat[0])
    assert coarse == pytest.approx(fine, rel=1e-8)


def test_closed_form_segments_refuse_the_power_law() -> None:
    # Gates closed by default: the power law is outside CLOSED_FORM_EFFECTS, and engaged
    # segments with it are integrated.
    assert not layout.EFFECT_POWER_LAW & layout.CLOSED_FORM_EFFECTS
    assert layout.EFFECT_POWER_LAW & layout.KERNEL_EFFECTS
    packed = pack(_problem(), record=False)
    assert int(packed.table[0, layout.EFFECTS]) & layout.EFFECT_POWER_LAW
    cw = np.zeros(layout.case_words(1))
    cw[: layout.COLUMNS] = packed.table[0]
    cw[layout.SG_ENG] = 1.0
    assert not loop.closed_form_applies(cw, 1)
    cw[layout.SG_ENG] = 0.0  # in the deadband the damper is disengaged: closed form again
    assert loop.closed_form_applies(cw, 1)


def test_self_heating_with_a_fluid_damper_is_refused() -> None:
    heated = replace(_problem(), thermal=True, heat_capacity=np.asarray(10.0))
    with pytest.raises(TypeError, match="self-heating of a fluid damper"):
        solve_dynamic(heated)


def test_compare_fluid_dynamic_against_the_quasi_static_comparison() -> None:
    config = load_config(ROOT / "examples" / "fluid_measured.toml")
    spec = config.spec.fluid_damper
    assert spec is not None
    temps = np.array([10.0, 40.0])
    quasi = compare_fluid(config.system, spec, temps)
    dynamic = compare_fluid(config.system, spec, temps, method="dynamic")
    assert dynamic.method == "dynamic"
    assert dynamic.fluid.free_time is not None
    assert quasi.fluid.free_time is not None
    assert dynamic.fluid.engage_speed is not None
    assert quasi.fluid.engage_speed is not None
    # Through the deadband both integrate the same undamped motion J phi'' = T - FS
    # (sizing.fluid.free_motion, its own integration): to their tolerances.
    assert dynamic.fluid.free_time == pytest.approx(quasi.fluid.free_time, rel=1e-6)
    assert dynamic.fluid.engage_speed == pytest.approx(quasi.fluid.engage_speed, rel=1e-6)
    # The ECD engages at rest (no lost motion): its dynamic time is the quasi-static exact
    # time plus an inertial lag of J/B_T ~ 0.05 / 2.4 s; within 1 %.
    assert dynamic.ecd.total_time is not None
    assert quasi.ecd.total_time is not None
    assert dynamic.ecd.total_time == pytest.approx(quasi.ecd.total_time, rel=1e-2)
    # The fluid engages at ~5.6 rad/s, far above its quasi-static speed: the dynamic damped
    # phase (carried by the load's momentum) is shorter than the quasi-static one.
    assert np.all(dynamic.fluid.damped_time < quasi.fluid.damped_time)


def test_compare_fluid_cli_dynamic_method() -> None:
    runner = CliRunner()
    out = runner.invoke(
        app,
        [
            "compare-fluid",
            str(ROOT / "examples" / "fluid_measured.toml"),
            "-m",
            "dynamic",
            "--json",
        ],
    )
    assert out.exit_code == 0, out.output
    document = json.loads(out.stdout)
    assert document["method"] == "dynamic"
    case = document["cases"][0]
    assert case["fluid"]["total_time_s"] > case["fluid"]["free_time_s"] > 0.0
    bad = runner.invoke(
        app, ["compare-fluid", str(ROOT / "examples" / "fluid_measured.toml"), "-m", "rk4"]
    )
    assert bad.exit_code == 2
    assert "--method" in bad.output

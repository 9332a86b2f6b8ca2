"""Independent references for the dynamics tests: systems built by hand and tight scipy
integrations of the equations of motion, written here from their definitions.

Nothing here calls ecdsim's dynamics code; the right-hand sides are typed from
docs/dynamics.md (and the paper's Eq. 1-4 through tests/hand.py).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ecdsim.dynamics.result import DynamicResult
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    Spring,
)

# The closed forms are exact; the balance is limited by rounding in sums of a few terms
# (1e-15) and, for integrated segments, by the integrator's tolerance (rtol 1e-8 gives
# about 1e-9). The requirement is 1e-6.
ENERGY_TOLERANCE = 1e-6


def assert_energy_closes(result: DynamicResult, tolerance: float = ENERGY_TOLERANCE) -> None:
    """Spring work + initial KE = dissipation + losses + final KE, every case."""
    error = np.abs(np.ravel(result.energy_balance_error))
    assert np.all(np.isfinite(error))
    assert float(np.max(error)) < tolerance, f"energy balance error {np.max(error):.3g}"


def toy_system(
    damping: float,
    system_friction: float,
    start_torque: float,
    end_torque: float,
    travel: float,
    ecd_friction: float = 0.0,
    spring: Spring | None = None,
    lost_motion: float = 0.0,
) -> DeploymentSystem:
    """A system whose input-shaft values are the given numbers exactly (N = 1, no BG,
    no temperature dependence): BECD = damping, FECD = ecd_friction, FS = system_friction.
    """
    damper = HighSpeedDamper(
        damping_rate=damping, coulomb_friction=ecd_friction, damping_temperature_coefficient=0.0
    )
    gearbox = Gearbox(ratio=1.0, coulomb_friction=0.0, damping_rate=0.0, lost_motion=lost_motion)
    load = Load(
        spring=spring if spring is not None else LinearSpring(start_torque, end_torque),
        travel=travel,
        system_friction=LinearTemperatureLaw(0.0, system_friction),
    )
    return DeploymentSystem(Ecd(damper, gearbox), load, name="toy")


@dataclass(frozen=True)
class Arrival:
    """A reference deployment: arrival time and speed, largest speed, dense solution."""

    time: float
    speed: float
    max_speed: float
    solution: Callable[[float], np.ndarray]


def linear_deploy(
    inertia: float,
    damping: float,
    friction: float,
    start_torque: float,
    end_torque: float,
    travel: float,
    speed0: float = 0.0,
    method: str = "Radau",
    rtol: float = 1e-10,
) -> Arrival:
    """J phi'' = Ts - (Ts - Te) phi / travel - F - B phi' from rest to phi = travel.

    Radau with the analytic Jacobian (the issue's reference), rtol 1e-10, atol 1e-14 on
    both the angle and the speed; a second event marks the speed's maximum.
    """
    k = (start_torque - end_torque) / travel

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        return np.array([y[1], (start_torque - k * y[0] - friction - damping * y[1]) / inertia])

    def jac(_t: float, _y: np.ndarray) -> np.ndarray:
        return np.array([[0.0, 1.0], [-k / inertia, -damping / inertia]])

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - travel)

    def peak(t: float, y: np.ndarray) -> float:
        return float(rhs(t, y)[1])

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = 1  # type: ignore[attr-defined]
    peak.direction = -1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (0.0, 1e5),
        [0.0, speed0],
        method=method,
        rtol=rtol,
        atol=1e-14,
        jac=jac if method in ("Radau", "BDF", "LSODA") else None,
        events=[arrive, peak],
        dense_output=True,
    )
    assert sol.status == 1, "the reference did not arrive"
    time = float(sol.t_events[0][0])
    speed = float(sol.y_events[0][0][1])
    peaks = [float(y[1]) for y in sol.y_events[1]]
    return Arrival(time, speed, max([speed0, speed, *peaks]), sol.sol)

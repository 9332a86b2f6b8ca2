"""The event rules at a swing's turnaround and on the stops, against hand analyses.

Two rules of the event loop (docs/dynamics.md, "The solver"):

- A speed falling towards zero is an asymptotic approach to rest ("creep") only while the
  load is short of its static equilibrium (the net drive at rest still pushes it on). A
  swing past the equilibrium turns round at a finite time (zero speed), then sticks or
  breaks away backward. Before, an integrated segment took the speed's fall through the
  creep threshold (1e-9 of its scale) just before the turnaround as creep.
- At rest on the start stop (angle 0) a backward drive is held by the stop: the run ends
  stuck there. Before, the load broke away "through" the stop (then ran to negative
  angles, or met the stop again at zero speed until the event limit).

Each motion here is solved in closed form (linear damping at ambient) and integrated
(the damper heats, with a damping law independent of temperature, c = 0, so the motion
is the same linear one): by the kernel compiled, the same kernel as plain Python
(``ECDSIM_NUMBA=0``) and with scipy's Radau as its stepper. The reference values are
the hand solutions written in each test.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.deployment import build_problem
from ecdsim.dynamics import DynamicParameters, DynamicProblem, DynamicResult, Rolloff, Thermal
from ecdsim.dynamics.kernel.build import backend
from ecdsim.dynamics.problem import dynamic_problem
from ecdsim.dynamics.result import STATUSES
from ecdsim.dynamics.solver import solve_dynamic
from ecdsim.model import DeploymentSystem
from tests.dynamics_reference import assert_energy_closes, toy_system

PATHS = ["closed form", "compiled", "python", "Radau"]
# The integrated paths' own error: rtol 1e-8 (the default) per segment, the events on the
# step's interpolant; over a few segments the times and angles stay within 1e-7 relative
# of the exact values (measured: up to 5e-10 in time and 6e-9 in angle, RODAS4 and Radau).
INTEGRATED = 1e-7
# The closed form is exact up to rounding, accumulated over a few segments.
EXACT = 1e-12


def _problem(system: DeploymentSystem, params: DynamicParameters) -> DynamicProblem:
    """The one-case problem at 25 degC, built as predict() builds it."""
    temps = np.asarray([25.0])
    ecd = system.ecd.at(temps)
    base, fs = build_problem(system, ecd, temps)
    return dynamic_problem(system, ecd, temps, base, fs, params)


def _solve(
    system: DeploymentSystem,
    params: DynamicParameters,
    path: str,
    monkeypatch: pytest.MonkeyPatch,
    heated: DynamicParameters | None = None,
) -> DynamicResult:
    """The case on one path; ``heated`` (default: ``params`` with a heat capacity) is
    what the integrated paths solve."""
    if path != "closed form":
        params = heated if heated is not None else replace(params, thermal=Thermal(0.05))
    if path == "Radau":
        params = replace(params, integrator="Radau")
    problem = _problem(system, params)
    assert problem.nonlinear == (path != "closed form")
    result = solve_dynamic(problem, kernel=backend("python") if path == "python" else None)
    assert_energy_closes(result)
    return result


def _status(result: DynamicResult) -> str:
    return STATUSES[int(result.status.ravel()[0])]


def _tolerance(path: str) -> float:
    return EXACT if path == "closed form" else INTEGRATED


# The underdamped swing: J = 0.2 kg*m^2, B = 4e-3 N*m*s/rad, the spring T = 1 - (4/3) phi
# N*m over 1.5 rad, kinetic = static friction F = 0.1 N*m.
J_SWING, B_SWING, T0, K, F = 0.2, 4e-3, 1.0, 4.0 / 3.0, 0.1


def _hand_swings(
    inertia: float, damping: float, torque0: float, stiffness: float, friction: float
) -> tuple[list[float], list[float]]:
    """Turnaround times and angles of an underdamped swing with Coulomb friction.

    From rest, ``J x'' + B x' + k x = a`` (a = |T| - F along the drive) gives
    ``x = (a/k) (1 - e^{-pt} (cos bt + (p/b) sin bt))``, p = B/2J, b = sqrt(k/J - p^2),
    whose speed ``(a/k) (b + p^2/b) e^{-pt} sin bt`` first vanishes at t = pi/b, where
    ``x = (a/k) (1 + e^{-p pi/b})``. The load then sticks if ``|T| <= F`` there, else it
    swings back from rest the same way.
    """
    p = damping / (2.0 * inertia)
    b = math.sqrt(stiffness / inertia - p * p)
    half = math.pi / b
    reach = 1.0 + math.exp(-p * half)
    times, angles = [], []
    t, phi = 0.0, 0.0
    while abs(torque0 - stiffness * phi) > friction:
        torque = torque0 - stiffness * phi
        phi += math.copysign((abs(torque) - friction) / stiffness * reach, torque)
        t += half
        times.append(t)
        angles.append(phi)
    return times, angles


@pytest.mark.parametrize("path", PATHS)
def test_an_underdamped_swing_turns_round_and_sticks(
    path: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    times, angles = _hand_swings(J_SWING, B_SWING, T0, K, F)
    # The hand swings stay inside the travel (0, 1.5): no stop is met.
    assert min(angles) > 0.0
    assert max(angles) < 1.5
    assert len(times) == 5
    system = toy_system(B_SWING, F, T0, T0 - K * 1.5, 1.5)
    result = _solve(system, DynamicParameters(J_SWING), path, monkeypatch)
    names = result.events.names()
    assert names == ["release", "breakaway"] + ["zero_speed", "breakaway"] * 4 + [
        "zero_speed",
        "stick",
    ]
    turns = [k for k, name in enumerate(names) if name == "zero_speed"]
    tol = _tolerance(path)
    assert np.allclose(result.events.time[turns], times, rtol=tol, atol=0.0)
    assert np.allclose(result.events.angle[turns], angles, rtol=tol, atol=0.0)
    assert _status(result) == "stuck"
    assert float(result.stuck_time.ravel()[0]) == pytest.approx(times[-1], rel=tol)
    assert float(result.stuck_angle.ravel()[0]) == pytest.approx(angles[-1], rel=tol)


@pytest.mark.parametrize("path", PATHS)
def test_an_overdamped_overshoot_stops_then_creeps_back(
    path: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # J = 0.2, B = 2 (overdamped: B^2 > 4 J k), launched forward at 10 rad/s from 0: it
    # overshoots the equilibrium x* = (T0 - F)/k = 0.675 rad and stops at a finite time,
    # where the spring (T0 - k x < -F) sends it back; backward it creeps to where the
    # spring equals the friction the other way, T0 - k phi = -F: phi = (T0 + F)/k.
    inertia, damping, w0 = 0.2, 2.0, 10.0
    p = damping / (2.0 * inertia)
    h = math.sqrt(p * p - K / inertia)
    r1, r2 = -p + h, -p - h
    x_eq = (T0 - F) / K
    # x = x* + A e^{r1 t} + C e^{r2 t} with x(0) = 0, x'(0) = w0.
    a_coef = (w0 + r2 * x_eq) / (r1 - r2)
    c_coef = -x_eq - a_coef
    assert a_coef > 0.0  # the speed r1 A e^{r1 t} + r2 C e^{r2 t} changes sign once
    t_stop = math.log(-r2 * c_coef / (r1 * a_coef)) / (r1 - r2)
    x_stop = x_eq + a_coef * math.exp(r1 * t_stop) + c_coef * math.exp(r2 * t_stop)
    assert T0 - K * x_stop < -F  # beyond the static friction: it breaks away backward
    system = toy_system(damping, F, T0, T0 - K * 1.5, 1.5)
    result = _solve(system, DynamicParameters(inertia, initial_speed=w0), path, monkeypatch)
    assert result.events.names() == ["release", "zero_speed", "breakaway", "creep"]
    tol = _tolerance(path)
    assert result.events.time[1] == pytest.approx(t_stop, rel=tol)
    assert result.events.angle[1] == pytest.approx(x_stop, rel=tol)
    assert _status(result) == "creep"
    # Creep ends where the speed is below 1e-9 of its scale: within 1e-9 rad of the limit.
    assert float(result.stuck_angle.ravel()[0]) == pytest.approx((T0 + F) / K, abs=1e-9)
    assert math.isinf(float(result.stuck_time.ravel()[0]))


# Constant torques (k = 0) and no damping: uniform accelerations, J = 0.5 kg*m^2,
# |T| = 0.5 N*m, F = 0.1 N*m, the release 1 rad from the stop.
J_STOP, T_STOP, F_STOP, L_STOP = 0.5, 0.5, 0.1, 1.0


def _hand_bounces(restitution: float) -> tuple[list[float], list[float], list[float]]:
    """Impact times and speeds of a constant drive towards a stop, and the distances run.

    From rest at L_STOP the load reaches the stop at ``v1^2 = 2 (|T| - F) L / J``. Each
    rebound at ``e v`` runs against |T| + F for ``e v J / (|T| + F)`` over
    ``d = J (e v)^2 / (2 (|T| + F))``, then back with |T| - F: ``v'^2 = 2 (|T| - F) d / J``
    after ``v' J / (|T| - F)``. The rebounds end when one would carry at most 1e-12 of
    the first impact's kinetic energy (docs/dynamics.md, end of travel): that impact
    settles on the stop.
    """
    ahead = (T_STOP - F_STOP) / J_STOP  # the acceleration towards the stop
    away = (T_STOP + F_STOP) / J_STOP  # the deceleration of a rebound
    v = math.sqrt(2.0 * ahead * L_STOP)
    times, speeds, distances = [v / ahead], [v], [L_STOP]
    first = 0.5 * J_STOP * v * v
    while restitution > 0.0 and restitution**2 * 0.5 * J_STOP * v * v > 1e-12 * first:
        up = restitution * v
        distance = up * up / (2.0 * away)
        v = math.sqrt(2.0 * ahead * distance)
        times.append(times[-1] + up / away + v / ahead)
        speeds.append(v)
        distances.append(distance)
    return times, speeds, distances


@pytest.mark.parametrize("restitution", [0.0, 0.5])
def test_the_start_stop_holds_a_backward_drive(
    restitution: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    times, speeds, distances = _hand_bounces(restitution)
    path = distances[0] + 2.0 * sum(distances[1:])
    system = toy_system(0.0, F_STOP, -T_STOP, -T_STOP, 1.5)
    params = DynamicParameters(J_STOP, initial_angle=L_STOP, restitution=restitution)
    result = _solve(system, params, "closed form", monkeypatch)
    names = result.events.names()
    hits = [k for k, name in enumerate(names) if name == "start_stop"]
    assert names[-2:] == ["start_stop", "stick"]
    assert len(hits) == len(times)
    assert np.allclose(result.events.time[hits], times, rtol=EXACT, atol=0.0)
    assert np.allclose(-result.events.speed[hits], speeds, rtol=EXACT, atol=0.0)
    assert float(np.min(result.events.angle)) == 0.0  # never beyond the stop
    assert _status(result) == "stuck"
    assert float(result.final_angle.ravel()[0]) == 0.0
    assert float(result.stuck_time.ravel()[0]) == pytest.approx(times[-1], rel=EXACT)
    assert int(result.impacts.ravel()[0]) == (len(times) if restitution > 0.0 else 0)
    # Energy: the spring's work |T| L goes to friction over the path and to the stop.
    energy = result.energy
    assert float(energy.spring_work.ravel()[0]) == pytest.approx(T_STOP * L_STOP, rel=EXACT)
    assert float(energy.friction_dissipation.ravel()[0]) == pytest.approx(F_STOP * path, rel=EXACT)
    # A difference of two sums of rounded terms: a few ulp of the larger.
    assert float(energy.impact_loss.ravel()[0]) == pytest.approx(
        T_STOP * L_STOP - F_STOP * path, rel=1e-11
    )
    assert float(energy.final_kinetic_energy.ravel()[0]) == 0.0


def test_the_end_stop_settles_a_forward_drive(monkeypatch: pytest.MonkeyPatch) -> None:
    # The mirror image: a forward drive onto the end stop with rebounds settles there.
    times, speeds, distances = _hand_bounces(0.5)
    system = toy_system(0.0, F_STOP, T_STOP, T_STOP, 1.5)
    params = DynamicParameters(J_STOP, initial_angle=1.5 - L_STOP, restitution=0.5)
    result = _solve(system, params, "closed form", monkeypatch)
    names = result.events.names()
    hits = [k for k, name in enumerate(names) if name == "arrive"]
    assert names[-2:] == ["arrive", "settle"]
    # Near the end the angle 1.5 - d holds d to an absolute eps * 1.5 only: a bounce of
    # d rad (down to 1e-11) has its speed (sqrt(d)) to eps * 1.5 / d relative, and the
    # times add those up (measured: speeds 2e-5 at the last bounce, times 1.3e-11).
    eps = float(np.finfo(float).eps)
    speed_tolerance = EXACT + 4.0 * eps * 1.5 / np.array(distances)
    assert np.all(np.abs(result.events.speed[hits] / speeds - 1.0) <= speed_tolerance)
    assert np.allclose(result.events.time[hits], times, rtol=1e-10, atol=0.0)
    assert float(np.max(result.events.angle)) == 1.5  # never beyond the stop
    assert _status(result) == "settled"
    assert float(result.final_angle.ravel()[0]) == 1.5
    assert int(result.impacts.ravel()[0]) == len(times)
    assert float(result.deployment_time.ravel()[0]) == pytest.approx(times[0], rel=EXACT)


INTEGRATED_PATHS = PATHS[1:]
# A light roll-off damper (B = 0.05 N*m*s/rad at rest) on the constant backward drive.
ROLLED = toy_system(0.05, F_STOP, -T_STOP, -T_STOP, 1.5)


@pytest.mark.parametrize("restitution", [0.0, 0.5])
@pytest.mark.parametrize("path", INTEGRATED_PATHS)
def test_integrated_paths_hold_the_start_stop(
    path: str, restitution: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    params = DynamicParameters(J_STOP, initial_angle=L_STOP, restitution=restitution)
    rolled = replace(params, rolloff=Rolloff(2.0, 0.0039))
    result = _solve(ROLLED, params, path, monkeypatch, heated=rolled)
    names = result.events.names()
    assert names[-2:] == ["start_stop", "stick"]
    assert _status(result) == "stuck"
    assert float(result.final_angle.ravel()[0]) == 0.0
    assert float(np.min(result.events.angle)) == 0.0
    series = result.sample(n_points=201)
    assert float(np.min(series.angle)) >= 0.0
    if restitution > 0.0:
        # Rebounds that die out (no event limit), each impact slower than the last.
        hits = result.events.speed[[k for k, n in enumerate(names) if n == "start_stop"]]
        assert 2 <= hits.size == int(result.impacts.ravel()[0]) < 100
        assert np.all(np.diff(-hits) < 0.0)


@pytest.mark.parametrize("path", PATHS)
def test_a_backward_launch_on_the_start_stop_stops_at_once(
    path: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Launched backward at 1 rad/s from angle 0 (restitution 0): the stop takes the whole
    # kinetic energy J w0^2 / 2 at t = 0 and holds the backward drive. (Before, the
    # integrated segment of no length was not ended and ran to negative angles.)
    params = DynamicParameters(J_STOP, initial_speed=-1.0)
    rolled = replace(params, rolloff=Rolloff(2.0, 0.0039))
    result = _solve(ROLLED, params, path, monkeypatch, heated=rolled)
    assert result.events.names() == ["release", "start_stop", "stick"]
    assert _status(result) == "stuck"
    assert float(result.final_time.ravel()[0]) == 0.0
    assert float(result.final_angle.ravel()[0]) == 0.0
    assert float(result.energy.impact_loss.ravel()[0]) == 0.5 * J_STOP * 1.0**2


@pytest.mark.parametrize("path", INTEGRATED_PATHS)
def test_a_swing_against_gravity_turns_round(path: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # Under gravity every segment may creep (the sine moves the equilibrium), so the rule
    # matters on every turnaround: here the load swings past sin x = a/W (0.524 rad) and
    # turns round near 1.1 rad, at a finite time. Reference: x'' = 0.5 - 0.05 x' - sin x
    # by scipy DOP853 at rtol 1e-12, to the zero of the speed.
    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [float(y[1]), 0.5 - 0.05 * float(y[1]) - math.sin(float(y[0]))]

    def turns(_t: float, y: np.ndarray) -> float:
        return float(y[1])

    turns.terminal = True  # type: ignore[attr-defined]
    turns.direction = -1.0  # type: ignore[attr-defined]
    ref = solve_ivp(
        rhs, (0.0, 100.0), [0.0, 0.0], method="DOP853", events=turns, rtol=1e-12, atol=1e-14
    )
    t_turn, x_turn = float(ref.t_events[0][0]), float(ref.y_events[0][0][0])
    assert math.sin(x_turn) > 0.5  # past the equilibrium: gravity sends it back
    # J = 1 kg*m^2, B = 0.05 N*m*s/rad, a constant drive of 0.5 N*m over 3 rad (no
    # friction), gravity W sin(phi) with W = 1 N*m, from rest at 0.
    system = toy_system(0.05, 0.0, 0.5, 0.5, 3.0)
    # The swing then decays over some fifty periods; the run stops soon after the turn.
    params = DynamicParameters(
        1.0,
        rtol=1e-10,
        integrator="Radau" if path == "Radau" else "RODAS4",
        stop_time=1.5 * t_turn,
    )
    problem = replace(
        _problem(system, params), gravity_amplitude=np.ones(1), gravity_angle=np.zeros(1)
    )
    result = solve_dynamic(problem, kernel=backend("python") if path == "python" else None)
    names = result.events.names()
    assert names[:3] == ["release", "breakaway", "zero_speed"]
    # 1e-7: the integrator at rtol 1e-10 (the event on its interpolant), the reference at
    # 1e-12
    assert float(result.events.time[2]) == pytest.approx(t_turn, rel=1e-7)
    assert float(result.events.angle[2]) == pytest.approx(x_turn, rel=1e-7)
    assert_energy_closes(result)

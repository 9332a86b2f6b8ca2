"""Synthetic bench data from known parameters, written out independently of ecdsim.

The other ``test_characterize_*`` modules import these generators. Each formula here is
typed from its derivation (docs/characterize.md), not taken from ecdsim; the tests of
this module check the formulas against a tight scipy integration of the same equations,
and check that ``examples/drop_test.csv`` and ``examples/deployment_trace.csv`` are
exactly what the generators write (their provenance). Regenerate the examples with::

    .venv/bin/python -m tests.test_characterize_synthetic
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from tests import hand
from tests.conftest import ROOT

G = 9.80665  # m/s**2, standard gravity
EXAMPLE_DROP_TEST = ROOT / "examples" / "drop_test.csv"
EXAMPLE_TRACE = ROOT / "examples" / "deployment_trace.csv"


@dataclass(frozen=True)
class Truth:
    """Known ECD parameters: BECD(T) = b_ref (1 + c (T - t_ref)), FECD(T) = slope T + at_0c."""

    b_ref: float = 24.0
    c: float = -0.004
    t_ref: float = 25.0
    slope: float = -0.002
    at_0c: float = 0.57

    def damping(self, t: float) -> float:
        return self.b_ref * (1.0 + self.c * (t - self.t_ref))

    def friction(self, t: float) -> float:
        return self.slope * t + self.at_0c


def startup_angle(t: float, steady: float, damping: float, inertia: float) -> float:
    """Angle after release from rest: J w' = T - F - B w gives w = w_ss (1 - exp(-t B/J)).

    Integrating, theta(t) = w_ss * (t - (J/B) * (1 - exp(-t B/J))); J = 0 is steady from t=0.
    """
    if inertia == 0.0:
        return steady * t
    tau = inertia / damping
    return steady * (t - tau * (1.0 - math.exp(-t / tau)))


def startup_time(angle: float, steady: float, damping: float, inertia: float) -> float:
    """The time to turn ``angle`` from rest (root of startup_angle = angle)."""
    if inertia == 0.0:
        return angle / steady
    tau = inertia / damping
    # theta(t) lies between w (t - tau) and w t: the root is in [angle/w, angle/w + tau];
    # the bracket is widened to 2 tau so that round-off cannot close it.
    low, high = angle / steady, angle / steady + 2.0 * tau
    return float(
        brentq(
            lambda t: startup_angle(t, steady, damping, inertia) - angle,
            low,
            high,
            xtol=1e-15,
            rtol=1e-15,
        )
    )


@dataclass(frozen=True)
class DropPoint:
    """One drop: what a CSV row records, plus the truth behind it."""

    temperature: float
    mass: float  # recorded mass [kg]
    radius: float
    angle: float
    time: float
    rig_friction: float
    rig_inertia: float
    true_torque: float


def drop_points(
    truth: Truth,
    temperatures: Sequence[float],
    masses: Sequence[float],
    *,
    radius: float = 0.05,
    angle: float = math.pi,
    rig_friction: float = 0.0,
    rig_inertia: float | None = None,
    torque_noise: float = 0.0,
    rng: np.random.Generator | None = None,
) -> list[DropPoint]:
    """Drops of each mass at each temperature from ``truth``.

    The speed follows from the true torque (Eq. 5); the recorded mass carries a weighing
    error whose torque has standard deviation ``torque_noise`` [N*m]: the classical
    regression model (error in torque, speed exact). ``rig_inertia`` None: no transient
    (the times are angle / speed); else J = rig_inertia + m r**2 and the exact transient.
    """
    points = []
    for t in temperatures:
        b, f = truth.damping(t), truth.friction(t)
        for m in masses:
            torque = m * G * radius - rig_friction
            steady = (torque - f) / b
            inertia = 0.0 if rig_inertia is None else rig_inertia + m * radius**2
            time = startup_time(angle, steady, b, inertia)
            error = float(rng.normal(0.0, torque_noise)) if rng is not None else 0.0
            recorded = m + error / (G * radius)
            points.append(
                DropPoint(
                    t,
                    recorded,
                    radius,
                    angle,
                    time,
                    rig_friction,
                    rig_inertia or 0.0,
                    torque + error,
                )
            )
    return points


def drop_csv(points: Sequence[DropPoint], *, inertia_column: bool) -> str:
    """CSV text in SI headers, every number written exactly (repr)."""
    header = "temperature_C,mass_kg,radius_m,angle_rad,time_s,rig_friction_Nm"
    header += ",rig_inertia_kg_m2" if inertia_column else ""
    lines = [header]
    for p in points:
        cells = [p.temperature, p.mass, p.radius, p.angle, p.time, p.rig_friction]
        cells += [p.rig_inertia] if inertia_column else []
        lines.append(",".join(repr(float(c)) for c in cells))
    return "\n".join(lines) + "\n"


def linear_spring_angle(
    times: np.ndarray, start: float, end: float, travel: float, damping: float, friction: float
) -> np.ndarray:
    """Exact deployed angle for a linear spring, by hand.

    B phi' = a - k phi, a = Ts - F, k = (Ts - Te) / travel, phi(0) = 0 gives
    phi(t) = (a / k) (1 - exp(-k t / B)), held at the travel once reached.
    """
    a = start - friction
    k = (start - end) / travel
    phi = (a / k) * (1.0 - np.exp(-k * np.asarray(times, dtype=float) / damping))
    return np.minimum(phi, travel)


def paper_trace(
    temperature: float,
    times: np.ndarray,
    *,
    start: float = hand.TS,
    end: float = hand.TE,
    damping: float | None = None,
    friction: float | None = None,
) -> np.ndarray:
    """A deployment of the paper's example (section 6) at T, exact, from hand.py values."""
    b = hand.becd(temperature) if damping is None else damping
    f = hand.fecd(temperature) + hand.fs(temperature) if friction is None else friction
    return linear_spring_angle(times, start, end, hand.TRAVEL, b, f)


def example_drop_test_text() -> str:
    """examples/drop_test.csv: three temperatures, six masses, weighing noise, mixed units."""
    truth = Truth()
    rng = np.random.default_rng(20240604)
    masses = [3.0, 4.5, 6.0, 7.5, 9.0, 10.5]
    points = drop_points(
        truth,
        [-40.0, 25.0, 100.0],
        masses,
        radius=0.05,
        angle=math.pi,
        rig_friction=0.02,
        rig_inertia=0.005,
        torque_noise=0.01,
        rng=rng,
    )
    lines = [
        "temperature [degC],mass [g],radius [mm],angle [deg],time [s],rig_friction [N*m],"
        "rig_inertia [kg*m^2]"
    ]
    for p in points:
        lines.append(
            f"{p.temperature:g},{1000 * p.mass:.1f},{1000 * p.radius:g},"
            f"{math.degrees(p.angle):g},{p.time:.3f},{p.rig_friction:g},{p.rig_inertia:g}"
        )
    return "\n".join(lines) + "\n"


def example_trace_text() -> str:
    """examples/deployment_trace.csv: the paper's example at -40, 25, 100 degC, 0.1 deg noise."""
    rng = np.random.default_rng(20240605)
    lines = ["time_s,angle [deg],temperature_C"]
    for temperature in (-40.0, 25.0, 100.0):
        arrival = hand.exact_time(temperature)
        times = np.arange(0.0, 1.15 * arrival, 0.5)
        angle = np.degrees(paper_trace(temperature, times))
        angle = angle + rng.normal(0.0, 0.1, times.size)
        for t, a in zip(times, angle, strict=True):
            lines.append(f"{t:.1f},{a:.3f},{temperature:g}")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- tests of the generators


def test_startup_angle_matches_an_ode_integration() -> None:
    # J w' = T - F - B w, theta' = w, integrated by scipy at rtol 1e-12: the closed form
    # must agree to 1e-9 relative (the integrator's tolerance, with margin).
    torque, friction, damping, inertia = 3.0, 0.5, 24.0, 4.0
    steady = (torque - friction) / damping

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], (torque - friction - damping * y[1]) / inertia]

    t_end = 2.0  # about 12 time constants of J / B = 1/6 s, transient and steady both seen
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], rtol=1e-12, atol=1e-15, method="DOP853")
    assert startup_angle(t_end, steady, damping, inertia) == pytest.approx(sol.y[0, -1], rel=1e-9)
    time = startup_time(0.2, steady, damping, inertia)
    assert startup_angle(time, steady, damping, inertia) == pytest.approx(0.2, rel=1e-13)


def test_linear_spring_trace_arrives_at_the_hand_exact_time() -> None:
    # hand.exact_time integrates the same ODE by separation of variables.
    t = hand.exact_time(25.0)
    before, after = paper_trace(25.0, np.array([t * (1 - 1e-9), t * (1 + 1e-9)]))
    assert before == pytest.approx(hand.TRAVEL, rel=1e-7)  # slope * 1e-9 t, tiny
    assert after == hand.TRAVEL


def test_linear_spring_trace_matches_an_ode_integration() -> None:
    b = hand.becd(-40.0)
    f = hand.fecd(-40.0) + hand.fs(-40.0)
    k = (hand.TS - hand.TE) / hand.TRAVEL
    sol = solve_ivp(
        lambda _t, y: [(hand.TS - k * y[0] - f) / b], (0.0, 10.0), [0.0], rtol=1e-12, atol=1e-14
    )
    assert paper_trace(-40.0, np.array([10.0]))[0] == pytest.approx(sol.y[0, -1], rel=1e-9)


def test_example_files_are_what_the_generators_write() -> None:
    # Provenance of the examples: regenerate with `python -m tests.test_characterize_synthetic`.
    assert EXAMPLE_DROP_TEST.read_text(encoding="utf-8") == example_drop_test_text()
    assert EXAMPLE_TRACE.read_text(encoding="utf-8") == example_trace_text()


if __name__ == "__main__":
    EXAMPLE_DROP_TEST.write_text(example_drop_test_text(), encoding="utf-8")
    EXAMPLE_TRACE.write_text(example_trace_text(), encoding="utf-8")
    print(f"wrote {EXAMPLE_DROP_TEST} and {EXAMPLE_TRACE}")

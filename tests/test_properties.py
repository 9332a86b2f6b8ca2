"""Property-based tests (hypothesis) of invariants that hold for every input, not one example.

- Energy: every dynamic run closes its energy account (spring work + initial kinetic energy
  = dissipation + losses + final kinetic energy) to 1e-6.
- Colder is never faster under the paper's laws: with the paper's signs (damping falling
  0.4 %/K, i.e. a negative Eq. 1 coefficient, and frictions FL_T, FS_T falling with
  temperature) every resisting torque is larger at the colder temperature, so no method
  may deploy faster there.
- More damping is never faster, by any method.
- Units: the same configuration written in SI and in US customary units gives the same
  results.

Why the two monotonicity properties hold for the dynamic method too (not only for the
quasi-static formulas): along the travel, the speed as a function of angle obeys
``dv/dx = (T_s(x) - F - M_d(v)) / (J v)``. Where two runs from the same start have the
same speed at the same angle, the one with the larger resisting torque (F, or M_d at that
speed) has the smaller slope, so its v(x) can never cross above the other's; the
deployment time ``int dx / v`` is then the longer. (With roll-off the eddy torque is
``BD * peak_speed * x / (1 + x^2)``, larger at every speed for a larger BD; the argument
does not cover roll-off against temperature, whose peak speed moves the other way, nor
self-heating, whose temperature is a state of its own, so neither is drawn there.)

Runs are bounded for CI on a loaded 2-core machine: few examples, no deadline, and
derandomised (the same examples every run, no example database).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from ecdsim.config import parse_config
from ecdsim.deployment import Prediction, predict
from ecdsim.dynamics import DynamicParameters, Rolloff, Thermal
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

BOUNDED = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
METHODS = ("paper", "exact", "dynamic")

# The energy requirement; closed-form runs close to ~1e-15, integrated ones to ~1e-9
# at the default rtol 1e-8 (docs/dynamics.md).
ENERGY_TOLERANCE = 1e-6
# Monotonicity compares two runs of the same solver: closed forms are exact to rounding and
# the quasi-static times agree across runs to ~1e-15 relative; integrated runs carry their
# rtol (1e-8). A difference in the "wrong" direction smaller than 1e-7 relative is solver
# noise, not physics.
ORDER_SLACK = 1e-7


def _floats(low: float, high: float) -> st.SearchStrategy[float]:
    # Magnitudes below 1e-30 (which hypothesis likes to draw near a bound of 0) are outside
    # what the config accepts (docs/config.md, Units): drawn as the 0 they stand for.
    return st.floats(low, high, allow_nan=False, allow_infinity=False).map(
        lambda x: 0.0 if abs(x) < 1e-30 else x
    )


@dataclass(frozen=True)
class Draw:
    """One drawn system, in SI units at the high-speed shaft (as the paper gives them)."""

    damping_rate: float  # BD [N*m*s/rad]
    coefficient: float  # Eq. 1 [1/K]
    bg_fraction: float  # BG / BD [-]
    damper_friction: float  # FD [N*m]
    lube_slope: float  # FL_T slope [N*m/K]
    lube_at_0: float  # FL_T at 0 degC [N*m]
    gearbox_friction: float  # FG [N*m]
    ratio: float  # N [-]
    start_torque: float  # Ts [N*m]
    end_fraction: float  # Te / Ts [-]
    travel: float  # [rad]
    fs_slope: float  # FS_T slope [N*m/K]
    fs_at_0: float  # FS_T at 0 degC [N*m]
    load_inertia: float  # [kg*m^2]
    rotor_inertia: float  # [kg*m^2], high-speed shaft
    static_factor: float  # [-]

    def system(self, damping_scale: float = 1.0) -> DeploymentSystem:
        """The system; ``damping_scale`` multiplies BD (and so BG, a fraction of it)."""
        damper = HighSpeedDamper(
            damping_rate=self.damping_rate * damping_scale,
            coulomb_friction=self.damper_friction,
            lubrication_friction=LinearTemperatureLaw(self.lube_slope, self.lube_at_0),
            damping_temperature_coefficient=self.coefficient,
        )
        gearbox = Gearbox(
            ratio=self.ratio,
            coulomb_friction=self.gearbox_friction,
            damping_fraction=self.bg_fraction,
        )
        load = Load(
            spring=LinearSpring(self.start_torque, self.start_torque * self.end_fraction),
            travel=self.travel,
            system_friction=LinearTemperatureLaw(self.fs_slope, self.fs_at_0),
        )
        return DeploymentSystem(Ecd(damper, gearbox), load)

    def dynamics(self, **extra: object) -> DynamicParameters:
        """Inertia and stiction; ``extra`` adds further DynamicParameters fields."""
        return DynamicParameters(
            load_inertia=self.load_inertia,
            rotor_inertia=self.rotor_inertia,
            static_friction_factor=self.static_factor,
            **extra,  # type: ignore[arg-type]
        )


# Ranges around the paper's Cc-16 example (BD 1.3e-4, N 380, Ts 3.73, FS 0.47 at 25 degC),
# wide enough for slow and fast deployments, stalls and no-stalls. The paper's signs: the
# damping and every friction fall with temperature.
paper_like = st.builds(
    Draw,
    damping_rate=_floats(2e-5, 5e-4),
    coefficient=_floats(-0.006, -0.001),
    bg_fraction=_floats(0.0, 0.5),
    damper_friction=_floats(0.0, 2e-3),
    lube_slope=_floats(-5e-6, 0.0),
    lube_at_0=_floats(0.0, 5e-4),
    gearbox_friction=_floats(0.0, 1e-3),
    ratio=_floats(50.0, 600.0),
    start_torque=_floats(1.0, 8.0),
    end_fraction=_floats(0.2, 1.0),
    travel=_floats(0.3, 3.0),
    fs_slope=_floats(-0.006, 0.0),
    fs_at_0=_floats(0.0, 0.8),
    load_inertia=_floats(0.05, 20.0),
    rotor_inertia=_floats(0.0, 5e-7),
    static_factor=_floats(1.0, 1.3),
)


def _times(prediction: Prediction, method: str) -> np.ndarray:
    return np.ravel(prediction.solutions[method].deployment_time)


def _not_faster(slow: float, fast: float) -> bool:
    """``slow >= fast`` up to solver noise; infinite (stalled) times compare exactly."""
    if math.isinf(slow):
        return True
    return slow >= fast * (1.0 - ORDER_SLACK)


def _safe_temperatures(draw: Draw, cold: float, hot: float) -> bool:
    """Both temperatures where BD_T > 0 and every friction >= 0 (inside the laws' domain)."""
    for t in (cold, hot):
        if 1.0 + draw.coefficient * (t - 25.0) <= 0.05:
            return False
        if draw.lube_slope * t + draw.lube_at_0 < 0.0 or draw.fs_slope * t + draw.fs_at_0 < 0:
            return False
    return True


# -- energy -----------------------------------------------------------------------------


@st.composite
def dynamic_cases(draw: st.DrawFn) -> tuple[Draw, float, DynamicParameters]:
    """A paper-like system, a temperature and dynamics with every optional feature drawn."""
    base = draw(paper_like)
    temperature = draw(_floats(-40.0, 100.0))
    rolloff = draw(
        st.none()
        | st.builds(
            Rolloff, peak_speed=_floats(20.0, 3000.0), resistivity_coefficient=_floats(0.0, 0.005)
        )
    )
    thermal = draw(
        st.none()
        | st.builds(
            Thermal,
            heat_capacity=_floats(0.05, 50.0),
            thermal_resistance=st.just(math.inf) | _floats(1.0, 1000.0),
        )
    )
    params = base.dynamics(
        restitution=draw(_floats(0.0, 0.7)),
        initial_speed=draw(_floats(-0.3, 0.3)),
        rolloff=rolloff,
        thermal=thermal,
    )
    return base, temperature, params


# The nonlinear runs (roll-off, heating) cost ~0.1-1 s each on a loaded machine: fewer here.
@settings(BOUNDED, max_examples=15)
@given(dynamic_cases(), _floats(0.0, 0.02))
def test_every_dynamic_run_closes_its_energy_balance(
    case: tuple[Draw, float, DynamicParameters], lost_motion: float
) -> None:
    base, temperature, params = case
    system = base.system()
    system = DeploymentSystem(
        Ecd(
            system.ecd.damper,
            Gearbox(
                ratio=base.ratio,
                coulomb_friction=base.gearbox_friction,
                damping_fraction=base.bg_fraction,
                lost_motion=lost_motion,
            ),
        ),
        system.load,
    )
    prediction = predict(system, temperature, ["dynamic"], dynamics=params)
    solution = prediction.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    energy = solution.result.energy
    error = np.ravel(energy.error)
    assert np.all(np.isfinite(error))
    assert float(np.max(np.abs(error))) <= ENERGY_TOLERANCE, (
        f"energy balance error {float(np.max(np.abs(error))):.3g}: "
        f"supplied {np.ravel(energy.supplied)}, accounted {np.ravel(energy.accounted)}, "
        f"status {solution.result.status_names()}"
    )


# -- monotonicity -----------------------------------------------------------------------


@BOUNDED
@given(paper_like, _floats(-60.0, 120.0), _floats(1.0, 80.0))
def test_colder_is_never_faster_under_the_papers_laws(
    base: Draw, cold: float, warmer_by: float
) -> None:
    hot = cold + warmer_by
    assume(_safe_temperatures(base, cold, hot))
    prediction = predict(base.system(), [cold, hot], METHODS, dynamics=base.dynamics())
    for method in METHODS:
        t_cold, t_hot = _times(prediction, method)
        assert _not_faster(t_cold, t_hot), f"{method}: {t_cold} s at {cold} < {t_hot} s at {hot}"


@BOUNDED
@given(
    paper_like,
    _floats(-40.0, 100.0),
    _floats(0.01, 3.0),
    st.none() | _floats(20.0, 3000.0),
)
def test_more_damping_is_never_faster(
    base: Draw, temperature: float, more: float, peak_speed: float | None
) -> None:
    assume(_safe_temperatures(base, temperature, temperature))
    rolloff = None if peak_speed is None else Rolloff(peak_speed, 0.0039)
    dynamics = base.dynamics(rolloff=rolloff)
    less = predict(base.system(), temperature, METHODS, dynamics=dynamics)
    damped = predict(base.system(1.0 + more), temperature, METHODS, dynamics=dynamics)
    for method in METHODS:
        (t_less,) = _times(less, method)
        (t_more,) = _times(damped, method)
        assert _not_faster(t_more, t_less), f"{method}: {t_more} s with more damping < {t_less}"


# -- units ------------------------------------------------------------------------------

# Exact definitions (NIST SP 811, appendix B): the international pound-force and foot, the
# inch, the avoirdupois pound; the ounce-force and ounce are 1/16 of them.
LBF = 4.4482216152605  # N
FT = 0.3048  # m
INCH = 0.0254  # m
LB = 0.45359237  # kg
LBF_FT = LBF * FT  # N*m
OZF_IN = LBF / 16.0 * INCH  # N*m
LB_FT2 = LB * FT**2  # kg*m^2
OZ_IN2 = LB / 16.0 * INCH**2  # kg*m^2
PER_DEGF = 1.8  # kelvin per degF difference is 5/9: a "per K" rate is 1.8 x a "per degF"


def _fahrenheit(celsius: float) -> float:
    return celsius * 1.8 + 32.0


def _si_config(d: Draw, temperatures: list[float], initial_speed: float) -> str:
    temps = ", ".join(f'"{t!r} degC"' for t in temperatures)
    return f"""
[damper]
damping_rate = "{d.damping_rate!r} N*m*s/rad"
reference_temperature = "25 degC"
damping_temperature_coefficient = "{d.coefficient!r} / K"
coulomb_friction = "{d.damper_friction!r} N*m"
lubrication_friction = {{ slope = "{d.lube_slope!r} N*m/K", at_0C = "{d.lube_at_0!r} N*m" }}
rotor_inertia = "{d.rotor_inertia!r} kg*m^2"
static_friction_factor = {d.static_factor!r}

[gearbox]
ratio = {d.ratio!r}
damping_fraction = {d.bg_fraction!r}
coulomb_friction = "{d.gearbox_friction!r} N*m"

[load]
start_torque = "{d.start_torque!r} N*m"
end_torque = "{d.start_torque * d.end_fraction!r} N*m"
travel = "{d.travel!r} rad"
system_friction = {{ slope = "{d.fs_slope!r} N*m/K", at_0C = "{d.fs_at_0!r} N*m" }}
inertia = "{d.load_inertia!r} kg*m^2"

[initial]
speed = "{initial_speed!r} rad/s"

[analysis]
temperatures = [{temps}]
methods = ["paper", "exact", "dynamic"]
"""


def _us_config(d: Draw, temperatures: list[float], initial_speed: float) -> str:
    temps = ", ".join(f'"{_fahrenheit(t)!r} degF"' for t in temperatures)
    return f"""
[damper]
damping_rate = "{d.damping_rate / OZF_IN!r} in*ozf*s/rad"
reference_temperature = "77 degF"
damping_temperature_coefficient = "{d.coefficient / PER_DEGF!r} / degF"
coulomb_friction = "{d.damper_friction / OZF_IN!r} in*ozf"
rotor_inertia = "{d.rotor_inertia / OZ_IN2!r} oz*in^2"
static_friction_factor = {d.static_factor!r}

[damper.lubrication_friction]
slope = "{d.lube_slope / OZF_IN / PER_DEGF!r} in*ozf/degF"
at_0C = "{d.lube_at_0 / OZF_IN!r} in*ozf"

[gearbox]
ratio = {d.ratio!r}
damping_fraction = {d.bg_fraction!r}
coulomb_friction = "{d.gearbox_friction / OZF_IN!r} in*ozf"

[load]
start_torque = "{d.start_torque / LBF_FT!r} lbf*ft"
end_torque = "{d.start_torque * d.end_fraction / LBF_FT!r} lbf*ft"
travel = "{math.degrees(d.travel)!r} deg"
inertia = "{d.load_inertia / LB_FT2!r} lb*ft^2"

[load.system_friction]
slope = "{d.fs_slope / LBF_FT / PER_DEGF!r} lbf*ft/degF"
at_0C = "{d.fs_at_0 / LBF_FT!r} lbf*ft"

[initial]
speed = "{math.degrees(initial_speed)!r} deg/s"

[analysis]
temperatures = [{temps}]
methods = ["paper", "exact", "dynamic"]
"""


# Each converted input differs from its SI twin by a few ulp (one multiplication and one
# division, ~4e-16 relative). The outputs are smooth functions of the inputs; drawn
# systems keep the end torque clear of the friction (no near-stall, where the time's
# sensitivity is unbounded), so 1e-9 relative is rounding times a condition number below
# 1e6 with room to spare.
UNIT_RTOL = 1e-9


@BOUNDED
@given(paper_like, st.lists(_floats(-40.0, 100.0), min_size=1, max_size=3), _floats(0.0, 0.3))
def test_results_do_not_depend_on_the_unit_system(
    base: Draw, temperatures: list[float], initial_speed: float
) -> None:
    si = parse_config(_si_config(base, temperatures, initial_speed))
    us = parse_config(_us_config(base, temperatures, initial_speed))
    np.testing.assert_allclose(us.temperatures, si.temperatures, rtol=1e-12, atol=1e-12)
    runs = []
    for config in (si, us):
        runs.append(
            predict(
                config.system,
                list(config.temperatures),
                list(config.methods),
                dynamics=config.spec.dynamics(),
            )
        )
    a, b = runs
    np.testing.assert_allclose(b.ecd.ecd_damping_rate, a.ecd.ecd_damping_rate, rtol=1e-12)
    np.testing.assert_allclose(b.ecd.ecd_friction, a.ecd.ecd_friction, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(b.problem.torques, a.problem.torques, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(b.problem.friction, a.problem.friction, rtol=1e-12, atol=1e-12)
    margin = np.min(a.problem.torques[-1] - a.problem.friction)
    if margin <= 0.05 * base.start_torque:  # near a stall: see UNIT_RTOL
        return
    for method in METHODS:
        sa, sb = a.solutions[method], b.solutions[method]
        np.testing.assert_allclose(sb.deployment_time, sa.deployment_time, rtol=UNIT_RTOL)
        np.testing.assert_allclose(sb.end_speed, sa.end_speed, rtol=UNIT_RTOL, atol=1e-15)
        np.testing.assert_array_equal(sb.stalled, sa.stalled)

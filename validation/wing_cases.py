"""The wing's validation cases: each a wing file for ecdsim and the same wing typed for the
independent reference (validation/wing_reference.py), with the reference's own checks.

Every case is two descriptions of one wing: ``validation/configs/wing_*.toml`` (what a
user writes; ecdsim reads it) and :data:`CASES`' ``build(T)``, the same numbers typed
here in SI with the paper's Eq. 1-4 evaluated by the reference's own
:func:`~validation.wing_reference.ecd_at`. ``tests/test_wing_validation.py`` holds the
two together (a wrong mapping cannot pass).

What runs today (docs/wing.md):

- :func:`reference_checks`: the reference against itself, the energy balance of every
  run closing to 1e-8;
- :func:`rigid_cable_limit`: stiffer and stiffer elastic cables approach the rigid
  cable's deployment (the error falling as 1/K);
- :func:`wing_one_panel_limit`: a one-panel wing against ecdsim's single-hinge dynamic
  method (``Wing.as_single_hinge``), in flight and in a ground test.

What the wing's solver adds: :func:`compare` turns ecdsim's
:class:`~ecdsim.wing.result.WingResult` for a case's file into the checks of that case
(each latch's time, speed and kinetic energy, the sequence, the stuck hinges, the final
angles, the energy balance), so that each comparison in ``make validate`` is one line,
``lambda: compare(CASE, solve(load_wing_config(CASE.config)))``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ecdsim.config.wing_schema import load_wing_config
from ecdsim.deployment import predict
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.wing.model import Wing as EcdsimWing
from ecdsim.wing.result import LatchEvent, WingCase, WingEnergy, WingEvent, WingResult
from ecdsim.wing.solver import deploy_wing
from validation.checks import CaseResult, Check
from validation.wing_reference import Cable, Hinge, Panel, Reference, Solution, Wing, ecd_at

HERE = Path(__file__).resolve().parent
CONFIGS = HERE / "configs"
EXAMPLES = HERE.parent / "examples"

# The paper's Cc-16 (section 6), typed: Eq. 1-4's constants.
CC16 = {
    "bd": 1.3e-4,
    "bd_coefficient": -0.004,
    "bg_fraction": 0.26,
    "fd": 7.9e-4,
    "fl_slope": -2.12e-6,
    "fl_at_0": 2.2e-4,
    "fg": 4.5e-4,
    "ratio": 380.0,
}
ROTOR_REFLECTED = 2e-7 * 380.0**2  # the illustrative rotor through 380:1 [kg*m^2]
DEG = math.pi / 180.0
STANDARD_GRAVITY = 9.80665

ENERGY_BOUND = 1e-8
ENERGY_REASON = (
    "1e-8 of the energy supplied: the reference integrates every dissipation with the "
    "motion at rtol 1e-11, so its own balance closes to about 1e-10"
)


def _paper_friction(temperature: float) -> float:
    """The paper's FS_T, -0.0044 T + 0.58 [N*m] (used as an illustrative hinge friction)."""
    return -0.0044 * temperature + 0.58


def _cc16_hinge(temperature: float, stowed: float, deployed: float, **latch: float | None) -> Hinge:
    """A hinge with the paper's spring (Ts 3.73, Te 1.58 N*m over its travel), FS_T and
    a Cc-16 (static factor 1)."""
    becd, fecd = ecd_at(temperature, **CC16)
    friction = fecd + _paper_friction(temperature)
    return Hinge(
        stowed * DEG,
        deployed * DEG,
        3.73,
        1.58,
        becd,
        friction,
        friction,
        ROTOR_REFLECTED,
        **latch,  # type: ignore[arg-type]
    )


def _undamped(
    stowed: float, deployed: float, ts: float, te: float, friction: float, factor: float = 1.0
) -> Hinge:
    return Hinge(stowed * DEG, deployed * DEG, ts, te, 0.0, friction, factor * friction)


SMALL = Panel(1.0, 0.5, 0.25, 0.0, 0.0208)
SMALL_OFFSET = Panel(1.0, 0.5, 0.25, 0.02, 0.0208)
HEAVY = Panel(2.0, 0.8, 0.3, 0.04, 0.1)


def _one_panel(t: float) -> Wing:
    return Wing((HEAVY,), (_cc16_hinge(t, 90.0, 0.0),))


def _one_panel_ground(t: float) -> Wing:
    return Wing(
        (HEAVY,), (_cc16_hinge(t, 90.0, 0.0),), gravity=(0.0, -STANDARD_GRAVITY), offload=(0.5,)
    )


def _two(t: float, cables: tuple[Cable, ...] = ()) -> Wing:
    hinges = (_cc16_hinge(t, 90.0, 0.0), _cc16_hinge(t, -180.0, 0.0))
    return Wing((SMALL, SMALL_OFFSET), hinges, cables)


def _three(t: float, cables: tuple[Cable, ...] = ()) -> Wing:
    hinges = (_cc16_hinge(t, 90.0, 0.0), _cc16_hinge(t, -180.0, 0.0), _cc16_hinge(t, 180.0, 0.0))
    return Wing((SMALL, SMALL, SMALL), hinges, cables)


def _elastic(stiffness: float, pretension: float = 20.0) -> tuple[Cable, ...]:
    slack = 2.0 * pretension * 0.015  # 2 T0 rho: T0 per strand on 15 mm pulleys
    return (Cable(0, 2.0, stiffness, slack), Cable(1, 1.0, stiffness, slack))


def _two_stick(_t: float) -> Wing:
    hinges = (_undamped(90.0, 0.0, 2.0, 0.3, 1.3), _undamped(-180.0, 0.0, 1.2, 0.2, 0.9, 1.3))
    return Wing((SMALL, SMALL_OFFSET), hinges)


def _three_stick(_t: float, offload: float | None = None) -> Wing:
    hinges = (
        _undamped(90.0, 0.0, 2.0, 0.3, 1.3),
        _undamped(-180.0, 0.0, 1.2, 0.2, 0.9, 1.3),
        _undamped(180.0, 0.0, 1.0, 0.2, 0.7, 1.2),
    )
    if offload is None:
        return Wing((SMALL, SMALL, SMALL), hinges)
    return Wing(
        (SMALL, SMALL, SMALL), hinges, gravity=(0.0, -STANDARD_GRAVITY), offload=(offload,) * 3
    )


# The heating case's warm start (no file key: a deployment that follows another gives it,
# ecdsim.dynamics.params.Thermal's initial rises), and its thermal constants typed.
WARM_ROTOR = (20.0, 30.0)  # [K] root, outer
WARM_HOUSING = 10.0  # [K] the root's housing


def _two_heating(t: float) -> Wing:
    bd, c, n = CC16["bd"], CC16["bd_coefficient"], CC16["ratio"]
    eddy = bd * (1.0 + c * (t - 25.0)) * n * n  # Eq. 1's BD_T through N^2 (Eq. 3)
    slope = bd * c * n * n
    root, outer = _cc16_hinge(t, 90.0, 0.0), _cc16_hinge(t, -180.0, 0.0)
    hinges = (
        replace(
            root,
            eddy_damping=eddy,
            eddy_slope=slope,
            heat_capacity=0.5,
            thermal_resistance=4.0,
            housing_heat_capacity=2.0,
            housing_resistance=20.0,
            initial_rotor_rise=WARM_ROTOR[0],
            initial_housing_rise=WARM_HOUSING,
        ),
        replace(
            outer,
            eddy_damping=eddy,
            eddy_slope=slope,
            heat_capacity=0.3,
            initial_rotor_rise=WARM_ROTOR[1],
        ),
    )
    return Wing((SMALL, SMALL_OFFSET), hinges)


STRIBECK_FACTOR = 1.5  # breakaway over kinetic, the ECD's and the hinge's
STRIBECK_SPEED = 0.03  # [rad/s] at the hinge


def _two_stribeck(t: float) -> Wing:
    hinges = []
    for stowed in (90.0, -180.0):
        hinge = _cc16_hinge(t, stowed, 0.0)
        hinges.append(
            replace(
                hinge,
                breakaway=STRIBECK_FACTOR * hinge.friction,
                stribeck_speed=STRIBECK_SPEED,
            )
        )
    return Wing((SMALL, SMALL_OFFSET), tuple(hinges))


# validation/configs/wing_two_panel_lossy_gear.toml typed in SI: a weak damper behind a
# heavy rotor, a lossy gear (eta_f 0.7, eta_b 0.6, no FG) and a large hinge friction.
LOSSY = {
    "bd": 1e-6,
    "bd_coefficient": -0.004,
    "bg_fraction": 0.26,
    "fd": 1e-4,
    "fl_slope": -2.12e-6,
    "fl_at_0": 1e-4,
    "fg": 0.0,
    "ratio": 380.0,
}
LOSSY_ROTOR = 1e-5 * 380.0**2  # [kg*m^2] at the hinge
LOSSY_EFFICIENCY = (0.7, 0.6)  # forward, back-driven
LOSSY_HINGE_FRICTION = 2.5  # [N*m]


def _two_lossy(t: float) -> Wing:
    """Each hinge's damping and ECD friction through an ideal gear (Eq. 3-4 as printed,
    BT N^2 and FT N), the gear's efficiencies on top; the breakaway at eta_f (from rest
    the hinge drives the damper)."""
    becd, fecd = ecd_at(t, **LOSSY)
    forward, backward = LOSSY_EFFICIENCY
    hinges = tuple(
        Hinge(
            stowed * DEG,
            0.0,
            3.73,
            1.58,
            damping=becd,
            friction=fecd + LOSSY_HINGE_FRICTION,
            breakaway=fecd / forward + LOSSY_HINGE_FRICTION,
            inertia=LOSSY_ROTOR,
            forward_efficiency=forward,
            backward_efficiency=backward,
            gear_friction=fecd,
        )
        for stowed in (90.0, -180.0)
    )
    return Wing((SMALL, SMALL_OFFSET), hinges)


LOST_MOTION = (2.0 * DEG, 10.0 * DEG)  # [rad] root, outer (the file's gearboxes)


def _two_lost_motion(t: float) -> Wing:
    """The free two-panel wing, each hinge's damper side idle in its gear's lost motion
    (its FECD_T, the ECD's share of the friction and breakaway, idle with it)."""
    _, fecd = ecd_at(t, **CC16)
    hinges = tuple(
        replace(
            _cc16_hinge(t, stowed, 0.0),
            lost_motion=gap,
            ecd_friction=fecd,
            ecd_breakaway=fecd,
        )
        for stowed, gap in zip((90.0, -180.0), LOST_MOTION, strict=True)
    )
    return Wing((SMALL, SMALL_OFFSET), hinges)


def _warm_start(wing: EcdsimWing) -> EcdsimWing:
    """The heating case's file with its warm start (ecdsim's Thermal initial rises)."""
    hinges = []
    for j, hinge in enumerate(wing.hinges):
        assert hinge.ecd is not None
        assert hinge.ecd.thermal is not None
        thermal = replace(
            hinge.ecd.thermal,
            initial_rotor_rise=WARM_ROTOR[j],
            initial_housing_rise=WARM_HOUSING if hinge.ecd.thermal.two_node else 0.0,
        )
        hinges.append(replace(hinge, ecd=replace(hinge.ecd, thermal=thermal)))
    return replace(wing, hinges=tuple(hinges))


def _two_latches(t: float) -> Wing:
    hinges = (
        _cc16_hinge(t, 90.0, 0.0, latch_stiffness=500.0, latch_damping=1.0),
        _cc16_hinge(t, -180.0, 0.0, restitution=0.5),
    )
    return Wing((SMALL, SMALL_OFFSET), hinges)


@dataclass(frozen=True)
class WingValidationCase:
    """One wing described twice: a file for ecdsim, SI numbers for the reference.

    Attributes
    ----------
    name : identifier (tables, tests)
    title : one line
    config : the wing file ecdsim reads
    temperatures : the temperatures compared [degC] (the file's)
    build : the reference's wing at a temperature
    stop_time : end of the reference's run [s] (inf: until it latches or rests)
    adjust : what the file cannot say, applied to ecdsim's wing after reading it (a
        warm start); None: the file as it is
    """

    name: str
    title: str
    config: Path
    temperatures: tuple[float, ...]
    build: Callable[[float], Wing]
    stop_time: float = math.inf
    adjust: Callable[[EcdsimWing], EcdsimWing] | None = None

    def wing(self) -> EcdsimWing:
        """ecdsim's wing of the case: its file, adjusted."""
        wing = load_wing_config(self.config).wing
        return wing if self.adjust is None else self.adjust(wing)


ALL_T = (-40.0, 25.0, 100.0)
CASES: tuple[WingValidationCase, ...] = (
    WingValidationCase(
        "wing_one_panel",
        "One panel, Cc-16 (the one-panel limit)",
        CONFIGS / "wing_one_panel.toml",
        ALL_T,
        _one_panel,
    ),
    WingValidationCase(
        "wing_one_panel_ground_test",
        "One panel in a ground test, half offloaded (the one-panel limit)",
        CONFIGS / "wing_one_panel_ground_test.toml",
        ALL_T,
        _one_panel_ground,
    ),
    WingValidationCase(
        "wing_two_panel_free",
        "Two panels, a Cc-16 at each hinge, free",
        CONFIGS / "wing_two_panel_free.toml",
        ALL_T,
        _two,
    ),
    WingValidationCase(
        "wing_two_panel_synchronised",
        "Two panels, a rigid 2:1 cable",
        CONFIGS / "wing_two_panel_synchronised.toml",
        ALL_T,
        lambda t: _two(t, (Cable(0, 2.0),)),
    ),
    WingValidationCase(
        "wing_three_panel_free",
        "Three panels, a Cc-16 at each hinge, free",
        EXAMPLES / "wing_cc16_three_panel.toml",
        ALL_T,
        _three,
    ),
    WingValidationCase(
        "wing_three_panel_synchronised",
        "Three panels, rigid cables 2:1, 1:1",
        CONFIGS / "wing_three_panel_synchronised.toml",
        ALL_T,
        lambda t: _three(t, (Cable(0, 2.0), Cable(1, 1.0))),
    ),
    WingValidationCase(
        "wing_three_panel_cable",
        "Three panels, elastic pretensioned cables (strands slacken)",
        CONFIGS / "wing_three_panel_cable.toml",
        (25.0,),
        lambda t: _three(t, _elastic(40.0)),
    ),
    WingValidationCase(
        "wing_two_panel_stick_slip",
        "Two undamped hinges: stick-slip, breakaway 1.3x at the outer one",
        CONFIGS / "wing_two_panel_stick_slip.toml",
        (25.0,),
        _two_stick,
    ),
    WingValidationCase(
        "wing_three_panel_stick_slip",
        "Three undamped hinges: breakaways, then all three stuck at once",
        CONFIGS / "wing_three_panel_stick_slip.toml",
        (25.0,),
        _three_stick,
    ),
    WingValidationCase(
        "wing_three_panel_stick_slip_ground_test",
        "Three undamped hinges in a ground test, 90 % offloaded",
        CONFIGS / "wing_three_panel_stick_slip_ground_test.toml",
        (25.0,),
        lambda t: _three_stick(t, 0.9),
    ),
    WingValidationCase(
        "wing_two_panel_latches",
        "A compliant root latch and a rebounding outer latch (e = 0.5)",
        CONFIGS / "wing_two_panel_latches.toml",
        (25.0,),
        _two_latches,
    ),
    WingValidationCase(
        "wing_two_panel_heating",
        "Two panels, heated dampers from a warm start: rotor and housing, one node",
        CONFIGS / "wing_two_panel_heating.toml",
        (-40.0, 100.0),
        _two_heating,
        adjust=_warm_start,
    ),
    WingValidationCase(
        "wing_two_panel_stribeck",
        "Two panels, Stribeck friction at both hinges (breakaway 1.5x, 0.03 rad/s)",
        CONFIGS / "wing_two_panel_stribeck.toml",
        (25.0, 100.0),
        _two_stribeck,
    ),
    WingValidationCase(
        "wing_two_panel_lossy_gear",
        "Two panels, a lossy gear at each hinge (eta_f 0.7, eta_b 0.6): power flow switches",
        CONFIGS / "wing_two_panel_lossy_gear.toml",
        (-40.0, 100.0),
        _two_lossy,
    ),
    WingValidationCase(
        "wing_two_panel_lost_motion",
        "Two panels, lost motion in each gear (2 deg root, 10 deg outer)",
        CONFIGS / "wing_two_panel_lost_motion.toml",
        (-40.0, 100.0),
        _two_lost_motion,
    ),
)


def case(name: str) -> WingValidationCase:
    """The case called ``name``."""
    for item in CASES:
        if item.name == name:
            return item
    raise KeyError(name)


@functools.cache
def reference(name: str, temperature: float) -> Solution:
    """The reference's run of case ``name`` at ``temperature`` (computed once)."""
    item = case(name)
    return Reference(item.build(temperature)).run(item.stop_time)


def _times(solution: Solution, points: int = 400) -> list[float]:
    """Sample times: a uniform grid, and both ends of every segment (events resolved)."""
    end = solution.final_time if math.isfinite(solution.final_time) else 0.0
    grid = set(np.linspace(0.0, end, points).tolist())
    for segment in solution.segments:
        grid.update((segment.start, segment.end))
    return sorted(t for t in grid if t <= end)


def as_result(item: WingValidationCase, hinges: tuple[str, ...]) -> WingResult:
    """The reference's runs of a case as a :class:`WingResult` (comparisons, fixtures)."""
    cases = []
    for temperature in item.temperatures:
        solution = reference(item.name, temperature)
        times = _times(solution)
        angle, speed = solution.sample(times)
        n = solution.wing.size
        energy = WingEnergy(
            spring_work=solution.spring_work,
            damper_dissipation=solution.damper,
            friction_dissipation=solution.friction,
            latch_dissipation=solution.latch_damping,
            impact_loss=solution.impact_loss,
            gravity_work=solution.gravity_work,
            final_kinetic=solution.final_kinetic,
            cable_elastic=solution.cable_elastic,
            latch_elastic=solution.latch_elastic,
            gear_loss=solution.gear_loss,
            engagement_loss=solution.engagement_loss,
        )
        cases.append(
            WingCase(
                temperature=temperature,
                time=np.array(times),
                angle=angle.reshape(len(times), n),
                speed=speed.reshape(len(times), n),
                events=tuple(WingEvent(t, kind, hinge) for t, kind, hinge in solution.events),
                latches=tuple(
                    LatchEvent(
                        latch.hinge,
                        latch.time,
                        latch.speed,
                        latch.kinetic_energy,
                        latch.impact_loss,
                        latch.peak_torque,
                        latch.impulse,
                    )
                    for latch in solution.latches
                ),
                status=solution.status,
                stuck_hinges=solution.stuck_hinges,
                energy=energy,
            )
        )
    return WingResult(item.name, hinges, tuple(cases), source="validation reference (scipy Radau)")


def _energy_check(at: str, error: float) -> Check:
    return Check(
        f"energy balance of the reference {at}",
        "-",
        0.0,
        "the reference's own account",
        error,
        ENERGY_BOUND,
        ENERGY_REASON,
    )


def reference_checks(item: WingValidationCase) -> CaseResult:
    """The reference against itself: every run's energy balance closes to 1e-8."""
    checks = [
        _energy_check(f"at {t:+g} degC", reference(item.name, t).energy_error)
        for t in item.temperatures
    ]
    return CaseResult(
        name=f"{item.name}_reference",
        title=f"{item.title}: the reference's energy balance",
        source="validation/wing_reference.py: sympy Lagrangian, scipy Radau rtol 1e-11",
        mapping=f"`{item.config.relative_to(HERE.parent)}` typed in SI in validation/wing_cases.py",
        checks=tuple(checks),
    )


# Relative tolerances of the comparisons (the ecdsim side; see compare()).
INTEGRATED_RTOL = 1e-7
INTEGRATED_REASON = (
    "1e-7 relative: ecdsim integrates at its default rtol 1e-8, the reference at 1e-11"
)


PEAK_RTOL = 1e-4
PEAK_REASON = (
    "1e-4 of the rise: each solver takes the peak at its own steps, and a peak inside the "
    "motion (a rotor cooling into its housing) is flat there, so a step misses it by "
    "(step x rate)^2 / curvature; at the end of the motion (adiabatic) both are exact"
)


def compare(item: WingValidationCase, ecdsim: WingResult) -> CaseResult:
    """ecdsim's result for a case's file against the reference, as validation checks.

    Per temperature: the latching sequence and the stuck hinges (as counts of
    disagreements, tolerance 0), each latch's time, arrival speed and the wing's kinetic
    energy then, each hinge's final angle, and ecdsim's energy balance (1e-6, issue 25).
    """
    checks: list[Check] = []
    for temperature in item.temperatures:
        ref = reference(item.name, temperature)
        got = ecdsim.case_at(temperature)
        at = f"at {temperature:+g} degC"
        sequence = [latch.hinge for latch in ref.latches]
        checks.append(
            Check(
                f"latching sequence {at} (hinges out of order)",
                "-",
                0.0,
                f"reference {sequence}",
                float(
                    sum(a != b for a, b in zip(sequence, got.sequence, strict=False))
                    + abs(len(sequence) - len(got.sequence))
                ),
                0.0,
                "the order is exact",
            )
        )
        checks.append(
            Check(
                f"stuck hinges {at} (differences)",
                "-",
                0.0,
                f"reference {list(ref.stuck_hinges)}",
                float(len(set(ref.stuck_hinges) ^ set(got.stuck_hinges))),
                0.0,
                "a hinge is stuck or not",
            )
        )
        by_hinge = {latch.hinge: latch for latch in got.latches}
        for latch in ref.latches:
            mine = by_hinge.get(latch.hinge)
            for quantity, unit, reference_value, value in (
                ("latch time", "s", latch.time, math.nan if mine is None else mine.time),
                ("arrival speed", "rad/s", latch.speed, math.nan if mine is None else mine.speed),
                (
                    "kinetic energy at the latch",
                    "J",
                    latch.kinetic_energy,
                    math.nan if mine is None else mine.kinetic_energy,
                ),
            ):
                checks.append(
                    Check(
                        f"hinge {latch.hinge + 1} {quantity} {at}",
                        unit,
                        reference_value,
                        "scipy Radau rtol 1e-11",
                        value,
                        INTEGRATED_RTOL * abs(reference_value),
                        INTEGRATED_REASON,
                    )
                )
        for j, angle in enumerate(ref.final_angle):
            checks.append(
                Check(
                    f"hinge {j + 1} final angle {at}",
                    "rad",
                    float(angle),
                    "scipy Radau rtol 1e-11",
                    float(got.angle[-1, j]),
                    INTEGRATED_RTOL * max(abs(float(angle)), 1e-3),
                    INTEGRATED_REASON,
                )
            )
        for j, rise in enumerate(ref.peak_rise):
            peak = got.peak_damper_temperature[j] if got.peak_damper_temperature else None
            if item.build(temperature).hinges[j].heat_capacity is None:
                continue
            checks.append(
                Check(
                    f"hinge {j + 1} peak damper temperature {at}",
                    "degC",
                    temperature + float(rise),
                    "scipy Radau rtol 1e-11, at its steps",
                    math.nan if peak is None else peak,
                    PEAK_RTOL * max(float(rise), 1.0),
                    PEAK_REASON,
                )
            )
        checks.extend(_gear_checks(item, ref, got, temperature))
        checks.append(
            Check(
                f"energy balance of ecdsim {at}",
                "-",
                0.0,
                "ecdsim's account",
                got.energy.error,
                1e-6,
                "issue 25: the balance closes to 1e-6",
            )
        )
    return CaseResult(
        name=item.name,
        title=item.title,
        source="validation/wing_reference.py: sympy Lagrangian, scipy Radau rtol 1e-11",
        mapping=f"`{item.config.relative_to(HERE.parent)}`",
        checks=tuple(checks),
    )


def wing_one_panel_limit() -> CaseResult:
    """A one-panel wing against ecdsim's single-hinge dynamic method, now.

    The wing files' one panel as today's hinge (``Wing.as_single_hinge``: the panel's
    inertia about the hinge, the ground test as ``[load.gravity]``), solved by the
    dynamic method at its defaults, against the reference's chain of one panel.
    """
    checks: list[Check] = []
    for name in ("wing_one_panel", "wing_one_panel_ground_test"):
        item = case(name)
        wing = load_wing_config(item.config).wing
        system, dynamics = wing.as_single_hinge()
        found = predict(system, list(item.temperatures), ["dynamic"], dynamics=dynamics)
        solution = found.solutions["dynamic"]
        assert isinstance(solution, DynamicSolution)
        result = solution.result
        label = "ground test" if "ground" in name else "flight"
        for i, temperature in enumerate(item.temperatures):
            ref = reference(name, temperature)
            latch = ref.latches[0]
            at = f"{label} at {temperature:+g} degC"
            # Closed-form linear segments in flight, integrated with gravity.
            rtol = 1e-9 if "ground" not in name else INTEGRATED_RTOL
            reason = (
                "1e-9 relative: ecdsim's closed form is exact to rounding, the reference "
                "is integrated at rtol 1e-11"
                if rtol == 1e-9
                else INTEGRATED_REASON
            )
            for quantity, unit, reference_value, value in (
                ("deployment time", "s", latch.time, float(result.deployment_time[i])),
                ("arrival speed", "rad/s", latch.speed, float(result.arrival_speed[i])),
                (
                    "kinetic energy at the latch",
                    "J",
                    latch.kinetic_energy,
                    float(result.arrival_kinetic_energy[i]),
                ),
            ):
                checks.append(
                    Check(
                        f"{quantity}, {at}",
                        unit,
                        reference_value,
                        "wing reference, one panel",
                        value,
                        rtol * abs(reference_value),
                        reason,
                    )
                )
            checks.append(_energy_check(at, ref.energy_error))
    return CaseResult(
        name="wing_one_panel_limit",
        title="A one-panel wing is today's hinge: the wing reference against the dynamic method",
        source=(
            "validation/wing_reference.py (sympy Lagrangian of the chain, scipy Radau rtol "
            "1e-11) with one panel"
        ),
        mapping=(
            "`validation/configs/wing_one_panel.toml` and `wing_one_panel_ground_test.toml` "
            "read as wings and solved as single hinges (`Wing.as_single_hinge`: inertia "
            "I + m (a^2 + b^2) about the hinge, the ground test as `[load.gravity]`); "
            "ILLUSTRATIVE panel, the paper's Cc-16, spring and FS_T"
        ),
        checks=tuple(checks),
    )


RIGID_LIMIT_STIFFNESSES = (1e3, 1e4)  # [N*m/rad]
# Strands pretensioned so that they stay taut (slack torque 15 N*m, far above the few N*m
# the cables carry): the limit of the linear law.
LIMIT_PRETENSION = 500.0  # [N]


def _one_over_k(quantity: str, differences: list[float]) -> Check:
    """The difference to the rigid cable at K = 1e4 over K = 1e3 N*m/rad: 0.1 for 1/K."""
    return Check(
        quantity,
        "-",
        0.1,
        "1/K convergence",
        differences[1] / differences[0],
        0.1,
        "1/K gives 0.1 per decade; +-0.1 accepts anything from no better than 1/K^0.7 to faster",
    )


def rigid_cable_limit(panels: int = 3) -> CaseResult:
    """Stiff elastic cables approach the rigid cable (the reference against itself).

    The synchronised wing of ``panels`` (2 or 3) at +25 degC with cable stiffness K: the
    root hinge's latch time against the rigid cable's. The cable's stretch, and with it
    the difference, falls as 1/K (0.1 per decade), and at K = 1e4 N*m/rad the time is
    the rigid one within 2e-5.
    """
    temperature = 25.0
    name = {2: "wing_two_panel_synchronised", 3: "wing_three_panel_synchronised"}[panels]
    rigid = reference(name, temperature).latches[0].time
    differences = []
    checks: list[Check] = []
    for stiffness in RIGID_LIMIT_STIFFNESSES:
        cables = _elastic(stiffness, LIMIT_PRETENSION)[: panels - 1]
        wing = _three(temperature, cables) if panels == 3 else _two(temperature, cables)
        run = Reference(wing).run()
        first = next(latch for latch in run.latches if latch.hinge == 0)
        differences.append(first.time - rigid)
        checks.append(_energy_check(f"with K = {stiffness:g} N*m/rad", run.energy_error))
    checks.append(
        _one_over_k(
            "root latch time's difference to the rigid cable, K = 1e4 over K = 1e3 N*m/rad",
            differences,
        )
    )
    checks.append(
        Check(
            f"root latch time with K = {RIGID_LIMIT_STIFFNESSES[-1]:g} N*m/rad",
            "s",
            rigid,
            "the rigid cable (reduced coordinates)",
            rigid + differences[-1],
            2e-5 * rigid,
            "2e-5 relative: the cable's stretch at this stiffness (about 1e-5 of the time)",
        )
    )
    return CaseResult(
        name=f"wing_rigid_cable_limit_{panels}",
        title=(
            f"Stiff elastic cables approach the rigid cable, {panels} panels (the reference "
            "against itself)"
        ),
        source="validation/wing_reference.py",
        mapping=(
            f"`validation/configs/{name}.toml` with elastic cables of stiffness K and 500 N "
            "of pretension on 15 mm pulleys instead of the rigid ones"
        ),
        checks=tuple(checks),
    )


def _gear_checks(
    item: WingValidationCase, ref: Solution, got: WingCase, temperature: float
) -> list[Check]:
    """Where a hinge has a lossy gear: its power flow's switches (their count exactly,
    each time) and the energy its mesh lost; where it has lost motion: its engagements
    (count, times) and the kinetic energy they lost."""
    checks: list[Check] = []
    at = f"at {temperature:+g} degC"
    for j, hinge in enumerate(item.build(temperature).hinges):
        if hinge.lost_motion > 0.0:
            losses = (float(ref.engagement_loss[j]), float(got.energy.engagement_losses[j]))
            checks.extend(_event_checks(ref, got, j, at, "gear_engage", losses))
        if hinge.lossy:
            losses = (float(ref.gear_loss[j]), float(got.energy.mesh_loss[j]))
            checks.extend(_event_checks(ref, got, j, at, "power_flow", losses))
    return checks


# What _event_checks calls an event of the kind, several, and the energy lost with them.
_EVENT_WORDS = {
    "power_flow": ("power flow switch", "power flow switches", "gear loss"),
    "gear_engage": ("gear engagement", "gear engagements", "engagement loss"),
}


def _event_checks(
    ref: Solution, got: WingCase, j: int, at: str, kind: str, losses: tuple[float, float]
) -> list[Check]:
    """Hinge j's events of ``kind``: how many (exactly), each one's time, and the energy
    lost with them (``losses``: the reference's, ecdsim's)."""
    event, events, lost = _EVENT_WORDS[kind]
    theirs = [t for t, k, h in ref.events if k == kind and h == j]
    mine = [e.time for e in got.events if e.kind == kind and e.hinge == j]
    checks = [
        Check(
            f"hinge {j + 1} {events} {at} (count difference)",
            "-",
            0.0,
            f"reference {len(theirs)}",
            float(abs(len(theirs) - len(mine))),
            0.0,
            "an event happens or not",
        )
    ]
    for k, (time, other) in enumerate(zip(theirs, mine, strict=False)):
        checks.append(
            Check(
                f"hinge {j + 1} {event} {k + 1} time {at}",
                "s",
                time,
                "scipy Radau rtol 1e-11",
                other,
                INTEGRATED_RTOL * abs(time),
                INTEGRATED_REASON,
            )
        )
    checks.append(
        Check(
            f"hinge {j + 1} {lost} {at}",
            "J",
            losses[0],
            "scipy Radau rtol 1e-11",
            losses[1],
            INTEGRATED_RTOL * abs(losses[0]),
            INTEGRATED_REASON,
        )
    )
    return checks


def solve(item: WingValidationCase, backend: str | None = None) -> WingResult:
    """ecdsim's wing solver on the case's file, at the case's temperatures."""
    return deploy_wing(
        item.wing(), list(item.temperatures), stop_time=item.stop_time, backend=backend
    )


def solver_case(name: str) -> Callable[[], CaseResult]:
    """The validation case comparing ecdsim's wing solver with the reference on ``name``
    (one entry of ``make validate``)."""

    def run() -> CaseResult:
        item = case(name)
        return compare(item, solve(item))

    run.__name__ = name
    run.__doc__ = f"ecdsim's wing solver against the reference: {case(name).title}."
    return run


SOLVER_CASES: tuple[Callable[[], CaseResult], ...] = tuple(solver_case(c.name) for c in CASES)


def wing_solver_rigid_cable_limit() -> CaseResult:
    """ecdsim's wing with stiffer and stiffer elastic cables approaches ecdsim's rigid
    cable and the reference's: the three-panel synchronised wing at +25 degC."""
    temperature = 25.0
    item = case("wing_three_panel_synchronised")
    rigid = reference(item.name, temperature).latches[0].time
    config = load_wing_config(item.config).wing
    mine_rigid = deploy_wing(config, [temperature]).cases[0].latches[0].time
    differences = []
    for stiffness in RIGID_LIMIT_STIFFNESSES:
        slack = 2.0 * LIMIT_PRETENSION * 0.015
        cables = tuple(replace(c, stiffness=stiffness, slack_torque=slack) for c in config.cables)
        run = deploy_wing(replace(config, cables=cables), [temperature]).cases[0]
        first = next(latch for latch in run.latches if latch.hinge == 0)
        differences.append(first.time - mine_rigid)
    checks = (
        Check(
            "ecdsim's rigid cable: root latch time",
            "s",
            rigid,
            "wing reference (reduced coordinates)",
            mine_rigid,
            INTEGRATED_RTOL * rigid,
            INTEGRATED_REASON,
        ),
        _one_over_k(
            "ecdsim's root latch time's difference to its rigid cable, K = 1e4 over 1e3 N*m/rad",
            differences,
        ),
    )
    return CaseResult(
        name="wing_solver_rigid_cable_limit",
        title="ecdsim's elastic cables approach its rigid cable (three panels, +25 degC)",
        source="validation/wing_reference.py and ecdsim's wing solver",
        mapping=(
            f"`{item.config.relative_to(HERE.parent)}`, its rigid cables replaced by elastic "
            "ones of stiffness K and 500 N of pretension on 15 mm pulleys"
        ),
        checks=checks,
    )


def main() -> int:
    """``python -m validation.wing_cases``: run every reference case and its checks."""
    failed = False
    results = [reference_checks(item) for item in CASES]
    results += [rigid_cable_limit(), wing_one_panel_limit()]
    results += [run() for run in SOLVER_CASES] + [wing_solver_rigid_cable_limit()]
    for result in results:
        for check in result.checks:
            status = check.status
            failed |= check.failed
            print(
                f"{status:5} {result.name}: {check.quantity}: {check.value:.6g} "
                f"(reference {check.reference:.10g}, tolerance {check.tolerance:.2e})"
            )
    for item in CASES:
        for t in item.temperatures:
            sol = reference(item.name, t)
            print(
                f"{item.name} {t:+g} degC: {sol.status}, deployment {sol.deployment_time:.6g} s, "
                f"latches {[(x.hinge + 1, round(x.time, 4)) for x in sol.latches]}, "
                f"stuck {[j + 1 for j in sol.stuck_hinges]}, events {len(sol.events)}"
            )
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = [
    "CASES",
    "SOLVER_CASES",
    "WingValidationCase",
    "as_result",
    "compare",
    "wing_one_panel_limit",
    "reference",
    "reference_checks",
    "rigid_cable_limit",
    "solve",
    "solver_case",
    "wing_solver_rigid_cable_limit",
]

"""The wing's validation reference (validation/wing_reference.py) and its cases.

- Every case's wing file and the reference's typed wing are the same wing (a wrong
  mapping cannot pass): panels, hinges at each temperature (the ECD by ecdsim's Eq. 1-4
  against the reference's own), latches, cables, gravity.
- The reference against hand solutions: one undamped hinge swinging from rest against
  Coulomb friction (a half cosine, then stuck where the hand statics says).
- Its own checks: the energy balance (1e-8), the stuck hinges' holding torques within
  their breakaway, the rigid-cable limit, and ``compare`` passing the reference against
  itself and failing a perturbed result.

The one-panel limit against the single-hinge dynamic method runs in
tests/test_validation.py with the other validation cases.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ecdsim.config.wing_schema import load_wing_config
from ecdsim.physics.gravity import STANDARD_GRAVITY
from ecdsim.wing.model import Hinge as EcdsimHinge
from ecdsim.wing.result import LatchEvent, WingResult
from validation.wing_cases import (
    CASES,
    ENERGY_BOUND,
    WingValidationCase,
    as_result,
    case,
    compare,
    reference,
    rigid_cable_limit,
)
from validation.wing_reference import Hinge, Panel, Reference, Wing


def _efficiencies(hinge: EcdsimHinge, temperature: float) -> tuple[float, float]:
    """A hinge's gear's (eta_f, eta_b); (1, 1) for an ideal gear or no ECD."""
    if hinge.ecd is None:
        return 1.0, 1.0
    state = hinge.ecd.ecd.at(temperature)
    return float(state.forward_efficiency), float(state.backward_efficiency)


@pytest.mark.parametrize("item", CASES, ids=[c.name for c in CASES])
def test_the_case_file_is_the_reference_wing(item: WingValidationCase) -> None:
    config = load_wing_config(item.config)
    wing = item.wing()  # the file, with what no file key says (a warm start)
    assert config.temperatures == item.temperatures
    for temperature in item.temperatures:
        ref = item.build(temperature)
        assert wing.size == ref.size
        for panel, typed in zip(wing.panels, ref.panels, strict=True):
            assert (panel.mass, panel.length, panel.cg_along, panel.cg_across, panel.inertia) == (
                pytest.approx(
                    (typed.mass, typed.length, typed.cg_along, typed.cg_across, typed.inertia),
                    rel=1e-15,
                )
            )
        for hinge, typed_hinge in zip(wing.hinges, ref.hinges, strict=True):
            state = hinge.at(temperature)
            # Eq. 1-4 by ecdsim and by the reference's own arithmetic: rounding apart. A
            # lossy gear: ecdsim's BECD_T and FECD_T are through the mesh driven forward
            # (/ eta_f, physics.gearing), the reference's through an ideal gear with the
            # efficiencies on top.
            forward = typed_hinge.forward_efficiency
            assert _efficiencies(hinge, temperature) == (forward, typed_hinge.backward_efficiency)
            assert float(state.damping_rate) == pytest.approx(
                typed_hinge.damping / forward, rel=1e-13
            )
            mesh = typed_hinge.gear_friction * (1.0 / forward - 1.0)
            assert float(state.kinetic_friction) == pytest.approx(
                typed_hinge.friction + mesh, rel=1e-13
            )
            assert float(state.breakaway_friction) == pytest.approx(
                typed_hinge.breakaway, rel=1e-13
            )
            gap = 0.0 if hinge.ecd is None else hinge.ecd.lost_motion
            assert gap == pytest.approx(typed_hinge.lost_motion, rel=1e-15)
            if gap > 0.0:  # the ECD's shares that idle in the lost motion
                assert hinge.ecd is not None
                fecd = float(state.ecd_friction)
                assert fecd == pytest.approx(typed_hinge.ecd_friction, rel=1e-13)
                breakaway = hinge.ecd.static_friction_factor * fecd
                assert breakaway == pytest.approx(typed_hinge.ecd_breakaway, rel=1e-13)
            assert hinge.stowed_angle == pytest.approx(typed_hinge.stowed, rel=1e-15)
            assert hinge.deployed_angle == pytest.approx(typed_hinge.deployed, abs=1e-15)
            reflected = 0.0 if hinge.ecd is None else hinge.ecd.reflected_inertia
            assert reflected == pytest.approx(typed_hinge.inertia, rel=1e-14)
            for phi in (0.0, 0.5 * hinge.travel, hinge.travel):
                drive = float(hinge.drive_torque(phi, temperature))
                assert drive == pytest.approx(typed_hinge.spring(phi), rel=1e-13)
            _same_heating(hinge, typed_hinge, temperature)
            stribeck = None if hinge.ecd is None else hinge.ecd.stribeck_speed
            assert (math.inf if stribeck is None else stribeck) == typed_hinge.stribeck_speed
            latch = hinge.latch
            assert latch.restitution == typed_hinge.restitution
            assert latch.stiffness == typed_hinge.latch_stiffness
            assert latch.damping == typed_hinge.latch_damping
        assert [(c.inboard, c.ratio, c.stiffness) for c in wing.cables] == [
            (c.inboard, c.ratio, c.stiffness) for c in ref.cables
        ]
        for cable, typed_cable in zip(wing.cables, ref.cables, strict=True):
            if cable.stiffness is not None:
                assert cable.slack_torque == pytest.approx(typed_cable.slack_torque, rel=1e-15)
        if wing.ground_test is None:
            assert ref.gravity == (0.0, 0.0)
        else:
            np.testing.assert_allclose(wing.ground_test.gravity, ref.gravity, atol=1e-15)
            assert ref.offload == pytest.approx(wing.ground_test.offload, rel=1e-15)


def _same_heating(hinge: EcdsimHinge, typed: Hinge, temperature: float) -> None:
    """The file's damper heating is the reference's typed one: capacities, resistances,
    the warm start, and the eddy damping (Eq. 1 through N^2) and its slope per kelvin."""
    thermal = None if hinge.ecd is None else hinge.ecd.thermal
    if thermal is None:
        assert typed.heat_capacity is None
        return
    assert hinge.ecd is not None
    assert thermal.heat_capacity == typed.heat_capacity
    assert thermal.thermal_resistance == typed.thermal_resistance
    assert thermal.housing_heat_capacity == typed.housing_heat_capacity
    assert thermal.initial_rotor_rise == typed.initial_rotor_rise
    assert thermal.initial_housing_rise == typed.initial_housing_rise
    if thermal.two_node:
        assert thermal.housing_thermal_resistance == typed.housing_resistance
    damper = hinge.ecd.ecd.damper
    ratio = hinge.ecd.ecd.gearbox.ratio
    eddy = float(damper.damping_rate_at(temperature)) * ratio**2
    assert eddy == pytest.approx(typed.eddy_damping, rel=1e-13)
    slope = damper.damping_rate * damper.damping_temperature_coefficient * ratio**2
    assert slope == pytest.approx(typed.eddy_slope, rel=1e-13)


def test_reference_heating_is_the_hand_heat_balance() -> None:
    # An adiabatic rotor whose damping is all eddy current (no BG): every joule the
    # damper dissipates heats it, so C (r_end - r_0) equals the damper's dissipation
    # (Incropera Eq. 5.2 integrated with R = inf), whatever Eq. 1's slope makes of the
    # damping on the way; the two are integrated separately (the rise as a state, the
    # dissipation as a quadrature), both at rtol 1e-11, so they agree to 1e-9.
    eddy, slope, capacity, warm = 3.0, -0.012, 0.2, 15.0
    hinge = Hinge(
        0.0, 1.0, 2.0, 1.0, eddy, 0.05, 0.05,
        eddy_damping=eddy, eddy_slope=slope, heat_capacity=capacity,
        initial_rotor_rise=warm,
    )  # fmt: skip
    run = Reference(Wing((Panel(1.0, 0.5, 0.25, 0.0, 0.02),), (hinge,))).run()
    assert run.status == "latched"
    rise = float(run.peak_rise[0]) - warm  # adiabatic: the peak is the end
    assert rise > 1.0  # it heats by kelvins (the effect is there)
    assert capacity * rise == pytest.approx(float(run.damper[0]), rel=1e-9)
    assert run.energy_error < ENERGY_BOUND


def test_reference_stribeck_friction_is_the_hand_curve() -> None:
    # Canudas de Wit et al. 1995's g(v) typed by hand: the breakaway at rest, the kinetic
    # value far above the Stribeck speed, 1/e of the excess at it; and a hinge whose
    # spring lies between its kinetic friction and its breakaway stays stuck at release.
    hinge = Hinge(0.0, 1.0, 1.5, 1.5, 0.0, 1.0, 2.0, stribeck_speed=0.1)
    assert hinge.sliding(0.0) == 2.0
    assert hinge.sliding(0.1) == pytest.approx(1.0 + math.exp(-1.0), rel=1e-15)
    assert hinge.sliding(-10.0) == pytest.approx(1.0, abs=1e-15)
    run = Reference(Wing((Panel(1.0, 0.5, 0.25, 0.0, 0.02),), (hinge,))).run()
    assert run.status == "stuck"
    assert run.final_angle[0] == 0.0


def test_one_undamped_hinge_swings_and_sticks_as_the_hand_solution() -> None:
    # J phi'' = Ts - F - k phi from rest (k = (Ts - Te) / travel): phi = A (1 - cos wt),
    # A = (Ts - F) / k, w = sqrt(k / J); the speed is zero again at t = pi / w, at 2A,
    # where the spring Ts - 2 k A = 2 F - Ts is within the breakaway: it sticks there.
    mass, length, along, inertia = 2.0, 1.0, 0.5, 0.05
    j = inertia + mass * along**2  # about the hinge
    travel = math.pi / 2
    ts, te, friction = 2.0, 0.2, 1.2
    k = (ts - te) / travel
    amplitude = (ts - friction) / k
    omega = math.sqrt(k / j)
    wing = Wing(
        (Panel(mass, length, along, 0.0, inertia),),
        (Hinge(0.0, travel, ts, te, 0.0, friction, 1.1 * friction),),
    )
    run = Reference(wing).run()
    assert run.status == "stuck"
    assert run.stuck_hinges == (0,)
    stop = next(t for t, kind, _ in run.events if kind == "zero_speed")
    assert stop == pytest.approx(math.pi / omega, rel=1e-9)  # rtol 1e-11, located on it
    assert run.final_angle[0] == pytest.approx(2.0 * amplitude, rel=1e-9)
    assert abs(ts - k * 2.0 * amplitude) <= 1.1 * friction  # the hand statics: it holds
    # Half a swing: the friction took F * 2A, the spring gave its work, nothing is left.
    assert run.friction[0] == pytest.approx(friction * 2.0 * amplitude, rel=1e-9)
    assert run.energy_error < ENERGY_BOUND


@pytest.mark.parametrize("name", ["wing_two_panel_stick_slip", "wing_two_panel_latches"])
def test_reference_runs_close_their_energy_balance(name: str) -> None:
    for temperature in case(name).temperatures:
        assert reference(name, temperature).energy_error < ENERGY_BOUND


def test_stick_slip_case_sticks_both_hinges_within_their_breakaway() -> None:
    item = case("wing_two_panel_stick_slip")
    run = reference(item.name, 25.0)
    kinds = [kind for _, kind, _ in run.events]
    # The outer hinge is held at release by the root panel's acceleration and breaks
    # away as it slows; both then stop and stick, short of their latches.
    assert kinds.count("breakaway") == 1
    assert kinds.count("stick") == 2
    assert run.status == "stuck"
    assert run.stuck_hinges == (0, 1)
    wing = item.build(25.0)
    for j, hinge in enumerate(wing.hinges):
        assert 0.0 < run.final_angle[j] < hinge.travel
        # At rest in 0 g with no cable, each hinge's friction holds its spring alone.
        assert abs(hinge.spring(run.final_angle[j])) <= hinge.breakaway * (1 + 1e-12)


def test_latches_case_resolves_the_compliant_latch_and_the_rebounds() -> None:
    run = reference("wing_two_panel_latches", 25.0)
    root, outer = run.latches
    assert (root.hinge, outer.hinge) == (0, 1)
    assert root.peak_torque is not None
    assert root.impulse is None
    # The compliant latch holds the root slightly beyond its travel, where the latch
    # spring balances the hinge spring less what friction holds (at most the breakaway).
    hinge = case("wing_two_panel_latches").build(25.0).hinges[0]
    assert hinge.latch_stiffness is not None
    overshoot = run.final_angle[0] - hinge.travel
    latch = hinge.latch_stiffness * overshoot
    assert abs(hinge.spring(run.final_angle[0]) - latch) <= hinge.breakaway * (1 + 1e-9)
    # The peak latch torque exceeds the static load it settles at.
    assert root.peak_torque > latch
    # The outer latch rebounds (e = 0.5) until its rebounds settle.
    kinds = [(kind, hinge) for _, kind, hinge in run.events]
    assert kinds.count(("rebound", 1)) >= 5
    assert ("settle", 1) in kinds
    assert outer.impact_loss > 0.0
    assert run.status == "latched"


def test_compare_passes_the_reference_and_fails_a_perturbed_result() -> None:
    item = case("wing_two_panel_latches")
    names = tuple(h.name for h in load_wing_config(item.config).wing.hinges)
    result = as_result(item, names)
    assert not compare(item, result).failed
    first = result.cases[0]
    late = LatchEvent(**{**first.latches[0].__dict__, "time": first.latches[0].time * 1.001})
    perturbed = WingResult(
        result.wing,
        result.hinges,
        (replace(first, latches=(late, *first.latches[1:])),),
        result.source,
    )
    failed = [c.quantity for c in compare(item, perturbed).checks if c.failed]
    assert failed == ["hinge 1 latch time at +25 degC"]


def test_rigid_cable_limit_of_two_panels() -> None:
    result = rigid_cable_limit(2)
    assert not result.failed, [(c.quantity, c.value, c.reference) for c in result.checks]


def test_gravity_constant_is_the_standard_one() -> None:
    # The reference types g; ecdsim's ground test uses the standard value.
    from validation import wing_cases

    assert wing_cases.STANDARD_GRAVITY == STANDARD_GRAVITY

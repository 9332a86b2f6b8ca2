"""The wing's solver on the dynamic core (issue 25 items 2-4): against the independent
reference (validation/wing_reference.py, sympy Lagrangian + scipy Radau rtol 1e-11) on a
fast subset of the validation cases (``make validate`` runs all of them), against hand
solutions, the one-panel wing against today's hinge, and its refusals."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config.wing_schema import load_wing_config
from ecdsim.deployment import predict
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.params import Rolloff, Thermal
from ecdsim.model import ZERO_LAW, GearEfficiency, LinearSpring, Load, ResistiveTable
from ecdsim.wing import Hinge, Panel, Wing
from ecdsim.wing.model import HingeEcd
from ecdsim.wing.result import WingResult
from ecdsim.wing.solver import WingUnsupported, deploy_wing
from validation.wing_cases import case, compare, solve
from validation.wing_reference import Reference

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "wing_cc16_three_panel.toml"


@pytest.mark.parametrize(
    "name",
    [
        "wing_two_panel_stick_slip",
        "wing_three_panel_stick_slip_ground_test",
        "wing_two_panel_latches",
        # A lossy gear at both hinges: each hinge's power flow switches to back-driven.
        "wing_two_panel_lossy_gear",
        # Lost motion at both hinges: each damper side engages in a plastic impact.
        "wing_two_panel_lost_motion",
    ],
)
def test_solver_agrees_with_the_reference(name: str) -> None:
    # compare() holds each latch's time, arrival speed and kinetic energy and each final
    # angle to 1e-7 relative (ecdsim at rtol 1e-8, the reference at 1e-11), the latching
    # sequence and the stuck hinges exactly, and ecdsim's energy balance to 1e-6.
    item = case(name)
    # The plain-Python backend (the same functions as the compiled one, which
    # test_python_and_compiled_backends_agree holds together): no compile in the suite.
    result = compare(item, solve(item, backend="python"))
    failed = [(c.quantity, c.value, c.reference) for c in result.checks if c.failed]
    assert not failed
    assert len(result.checks) >= 5


def _free_panel(torque: float, inertia: float, travel_deg: float) -> Wing:
    """One panel about its hinge with a constant spring, no damper, no friction."""
    travel = math.radians(travel_deg)
    load = Load(LinearSpring(torque, torque), travel)
    hinge = Hinge("root", travel, 0.0, load)
    # A point mass at the centre of gravity plus its own inertia: J = I + m a^2.
    panel = Panel("panel", 2.0, 1.0, 0.5, 0.0, inertia - 2.0 * 0.25)
    return Wing("hand", (panel,), (hinge,))


def test_constant_torque_panel_latches_at_the_hand_time() -> None:
    # J phi'' = T from rest: phi = T t^2 / (2 J), so the latch at phi = travel comes at
    # t = sqrt(2 J travel / T) with speed sqrt(2 T travel / J) (integrated at rtol 1e-8:
    # 1e-7 relative).
    torque, inertia, travel = 0.3, 0.7, 90.0
    result = deploy_wing(_free_panel(torque, inertia, travel), [25.0])
    latch = result.cases[0].latches[0]
    angle = math.radians(travel)
    assert latch.time == pytest.approx(math.sqrt(2 * inertia * angle / torque), rel=1e-7)
    assert latch.speed == pytest.approx(math.sqrt(2 * torque * angle / inertia), rel=1e-7)
    # Its kinetic energy on arrival is the spring's work T travel, all lost in the latch.
    assert latch.kinetic_energy == pytest.approx(torque * angle, rel=1e-7)
    assert latch.impact_loss == pytest.approx(torque * angle, rel=1e-7)
    assert result.cases[0].energy.error < 1e-8


def test_one_panel_wing_is_todays_hinge() -> None:
    # The one-panel file solved by the wing's solver and by the single hinge's dynamic
    # method (Wing.as_single_hinge): the two paths agree to their integration accuracy
    # (the single hinge's flight case is in closed form; 1e-7 relative).
    item = case("wing_one_panel")
    wing = load_wing_config(item.config).wing
    mine = deploy_wing(wing, list(item.temperatures))
    system, dynamics = wing.as_single_hinge()
    single = predict(system, list(item.temperatures), ["dynamic"], dynamics=dynamics)
    solution = single.solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    for i, wing_case in enumerate(mine.cases):
        latch = wing_case.latches[0]
        assert latch.time == pytest.approx(float(solution.result.deployment_time[i]), rel=1e-7)
        assert latch.speed == pytest.approx(float(solution.result.arrival_speed[i]), rel=1e-7)


def test_python_and_compiled_backends_agree() -> None:
    # The same functions compiled by numba and run as plain Python: the same steps up to
    # rounding (1e-9 relative on the latch times, far above rounding, far below rtol).
    wing = load_wing_config(case("wing_two_panel_stick_slip").config).wing
    plain = deploy_wing(wing, [25.0], backend="python").cases[0]
    compiled = deploy_wing(wing, [25.0], backend="numba").cases[0]
    assert plain.stuck_hinges == compiled.stuck_hinges
    np.testing.assert_allclose(compiled.angle[-1], plain.angle[-1], rtol=1e-9)


def test_stuck_wing_does_not_chatter() -> None:
    # Three undamped hinges end stuck at once: a few dozen events, not thousands.
    wing = load_wing_config(case("wing_three_panel_stick_slip").config).wing
    run = deploy_wing(wing, [25.0]).cases[0]
    assert run.status == "stuck"
    assert run.stuck_hinges == (0, 1, 2)
    assert len(run.events) < 60


def _lost_motion(ecd: HingeEcd, gap: float = 0.01) -> HingeEcd:
    gearbox = replace(ecd.ecd.gearbox, lost_motion=gap)
    return replace(ecd, ecd=replace(ecd.ecd, gearbox=gearbox))


@pytest.mark.parametrize(
    ("change", "key"),
    [
        (lambda ecd: replace(ecd, gear_stiffness=50.0), "gearbox.stiffness"),
        # Lost motion is modelled, but not yet with a Stribeck speed.
        (lambda ecd: replace(_lost_motion(ecd), stribeck_speed=0.03), "gearbox.lost_motion"),
    ],
    ids=["stiffness", "lost_motion_with_stribeck"],
)
def test_unsupported_ecd_effects_are_refused_in_one_line(
    change: Callable[[HingeEcd], HingeEcd], key: str
) -> None:
    # The keys the wing's path does not model yet (docs/wing.md); heating with two nodes,
    # a warm start and Stribeck friction are modelled now (the one-panel tests below).
    wing = load_wing_config(EXAMPLE).wing
    ecd = wing.hinges[1].ecd
    assert ecd is not None
    hinges = list(wing.hinges)
    hinges[1] = replace(hinges[1], ecd=change(ecd))
    with pytest.raises(WingUnsupported) as info:
        deploy_wing(replace(wing, hinges=tuple(hinges)), [25.0])
    message = str(info.value)
    assert "\n" not in message
    assert "wing.hinges[1]" in message
    assert key in message


def test_warm_start_beyond_the_damping_laws_zero_is_refused_in_one_line() -> None:
    # Eq. 1's factor 1 - 0.004 (T - 25) reaches zero at 275 degC: a rotor 300 K above
    # 25 degC is beyond it (the single hinge's _check_start refuses it the same way).
    wing = load_wing_config(EXAMPLE).wing
    ecd = wing.hinges[0].ecd
    assert ecd is not None
    warm = replace(ecd, thermal=Thermal(heat_capacity=0.5, initial_rotor_rise=300.0))
    wing = replace(wing, hinges=(replace(wing.hinges[0], ecd=warm), *wing.hinges[1:]))
    with pytest.raises(WingUnsupported) as info:
        deploy_wing(wing, [25.0], backend="python")
    message = str(info.value)
    assert "\n" not in message
    assert "initial_rotor_rise" in message


def test_cli_deploys_a_wing_with_json_and_plots(tmp_path: Path) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["deploy", str(EXAMPLE), "-T", "25", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert json.dumps(data)  # JSON all the way down
    shown = runner.invoke(app, ["deploy", str(EXAMPLE), "-T", "25", "--plot", str(tmp_path)])
    assert shown.exit_code == 0, shown.output
    assert "latch order: root > outer > middle" in shown.stdout
    assert (tmp_path / "wing_hinge_angles.png").stat().st_size > 10_000
    assert (tmp_path / "wing_shapes_p25C.png").exists()


def test_api_returns_the_wing_result() -> None:
    import ecdsim

    result = ecdsim.deploy_wing(EXAMPLE, temperatures=[25, "212 degF"])
    assert [c.temperature for c in result.cases] == [25.0, pytest.approx(100.0)]
    assert all(c.status == "latched" for c in result.cases)


def _with_single_hinge(wing: Wing, temperatures: list[float]) -> tuple[WingResult, DynamicSolution]:
    """A one-panel wing solved by the wing's solver (plain Python, the compiled kernel's
    source) and as today's hinge (``Wing.as_single_hinge``, the dynamic method)."""
    mine = deploy_wing(wing, temperatures, backend="python")
    system, dynamics = wing.as_single_hinge()
    solution = predict(system, temperatures, ["dynamic"], dynamics=dynamics).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    return mine, solution


@pytest.mark.parametrize(
    ("rolloff", "thermal"),
    [
        (Rolloff(peak_speed=20.0, resistivity_coefficient=0.0039), None),
        (None, Thermal(heat_capacity=0.5, thermal_resistance=40.0)),
        (Rolloff(peak_speed=20.0, resistivity_coefficient=0.0039), Thermal(heat_capacity=0.5)),
        # Rotor and housing (two nodes) from a warm start: the rotor 20 K and the housing
        # 10 K above the deployment temperature at release.
        (
            None,
            Thermal(
                heat_capacity=0.5,
                thermal_resistance=4.0,
                housing_heat_capacity=2.0,
                housing_thermal_resistance=20.0,
                initial_rotor_rise=20.0,
                initial_housing_rise=10.0,
            ),
        ),
        # One adiabatic node from a warm start of 30 K.
        (None, Thermal(heat_capacity=0.5, initial_rotor_rise=30.0)),
    ],
    ids=["rolloff", "heating", "both", "two_nodes_warm", "warm"],
)
def test_one_panel_with_rolloff_and_heating_is_todays_hinge(
    rolloff: Rolloff | None, thermal: Thermal | None
) -> None:
    # Roll-off (the Kloss law at the rotor's 20 rad/s peak, reached at 0.05 rad/s of the
    # hinge through 380:1) and self-heating (a small 0.5 J/K rotor, so that it heats by
    # degrees) on the one-panel wing against the single hinge's dynamic method, which
    # validation/cases.py holds to Modelica and scipy references: both integrate at rtol
    # 1e-8 with different steppers' paths, so 1e-6 relative (seen: 2e-9 for the warm
    # starts and the housing node).
    wing = load_wing_config(case("wing_one_panel").config).wing
    ecd = wing.hinges[0].ecd
    assert ecd is not None
    hinge = replace(wing.hinges[0], ecd=replace(ecd, rolloff=rolloff, thermal=thermal))
    wing = replace(wing, hinges=(hinge,))
    temperatures = [-40.0, 100.0]
    mine, solution = _with_single_hinge(wing, temperatures)
    plain = load_wing_config(case("wing_one_panel").config).wing
    base = deploy_wing(plain, temperatures, backend="python")
    for i, wing_case in enumerate(mine.cases):
        latch = wing_case.latches[0]
        assert latch.time == pytest.approx(float(solution.result.deployment_time[i]), rel=1e-6)
        assert latch.speed == pytest.approx(float(solution.result.arrival_speed[i]), rel=1e-6)
        # ...and the effect is there: the deployment differs from the linear, cold one.
        assert abs(latch.time / base.cases[i].latches[0].time - 1.0) > 1e-4
        assert wing_case.energy.error < 1e-6
        # The peak damper temperature, where heating is on, is the single hinge's
        # max_damper_temperature (the same heat balance). With a thermal resistance the
        # peak lies inside the motion, where cooling balances heating, and each solver
        # takes it at its own steps: 1e-3 of the rise (the temperature moves by less than
        # that over a step near its flat maximum; seen: 4e-5).
        peak = wing_case.peak_damper_temperature
        if thermal is None:
            assert peak == (None,)
        else:
            single_peak = float(solution.result.max_damper_temperature[i])
            assert single_peak > temperatures[i] + 0.5  # it heats (0.65 to 1.7 K here),
            # or starts warm (a housing cooling the rotor from its warm start: the peak is
            # the start, T + 20 K, on both)
            rise = single_peak - temperatures[i]
            assert peak[0] is not None
            assert peak[0] == pytest.approx(single_peak, abs=1e-3 * rise)


def test_one_panel_with_stribeck_friction_is_todays_hinge() -> None:
    # The ECD's and the hinge's frictions break away at 1.5 x their kinetic value and fall
    # back to it over 0.03 rad/s at the hinge (the hinge's speeds: 0.003 to 0.05 rad/s,
    # so the curve matters), on the one-panel wing and on the single hinge's dynamic
    # method: both at rtol 1e-8, so 1e-6 relative (seen: 2e-13 on the latch time, 7e-11
    # on the speed; the one-node Stribeck friction is the same law on both).
    wing = load_wing_config(case("wing_one_panel").config).wing
    ecd = wing.hinges[0].ecd
    assert ecd is not None
    stribeck = replace(ecd, stribeck_speed=0.03, static_friction_factor=1.5)
    wing = replace(wing, hinges=(replace(wing.hinges[0], ecd=stribeck),))
    temperatures = [25.0, 100.0]
    mine, solution = _with_single_hinge(wing, temperatures)
    plain = deploy_wing(load_wing_config(case("wing_one_panel").config).wing, temperatures)
    for i, wing_case in enumerate(mine.cases):
        latch = wing_case.latches[0]
        assert latch.time == pytest.approx(float(solution.result.deployment_time[i]), rel=1e-6)
        assert latch.speed == pytest.approx(float(solution.result.arrival_speed[i]), rel=1e-6)
        # The effect is there: at 25 degC the hinge is slow and the breakaway friction
        # holds it back (42.1 s against 26.9 s Coulomb), less so at 100 degC.
        assert latch.time > plain.cases[i].latches[0].time * (1.0 + 1e-4)
        assert wing_case.energy.error < 1e-6


def test_cli_refuses_single_hinge_options_with_a_wing_file() -> None:
    # Never silently ignored: each option a wing's table does not take, one line each.
    result = CliRunner().invoke(app, ["deploy", str(EXAMPLE), "--units", "us", "-m", "exact"])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "error: --method: not taken with a wing file (its table is SI; docs/wing.md)",
        "error: --units: not taken with a wing file (its table is SI; docs/wing.md)",
    ]


def test_stop_time_ends_the_run_where_the_reference_does() -> None:
    # Both stop at 10 s, short of every latch: the angles there agree to 1e-7 relative
    # (ecdsim at rtol 1e-8, the reference at 1e-11).
    item = case("wing_two_panel_free")
    wing = load_wing_config(item.config).wing
    mine = deploy_wing(wing, [25.0], stop_time=10.0, backend="python").cases[0]
    ref = Reference(item.build(25.0)).run(10.0)
    assert mine.status == "stop_time"
    assert ref.status == "stop_time"
    assert mine.time[-1] == pytest.approx(10.0, rel=1e-12)
    np.testing.assert_allclose(mine.angle[-1], ref.final_angle, rtol=1e-7)
    assert mine.latches == ()


def _lossy(wing: Wing, back_driven: bool) -> Wing:
    """The one-panel wing with a lossy gear (eta_f 0.7, eta_b 0.6; FG 0, as the file's
    rule wants). ``back_driven``: a weak damper (BD 1e-7), a heavy rotor (2e-6 kg*m^2:
    0.29 kg*m^2 at the hinge, as much as the panel) and a spring falling from +3 to -3
    N*m with no hinge friction, so that the panel decelerates hard, the rotor drives it
    through the gear (back-driven), it swings back and sticks."""
    hinge = wing.hinges[0]
    ecd = hinge.ecd
    assert ecd is not None
    efficiency = GearEfficiency(forward=0.7, backward=0.6)
    gearbox = replace(ecd.ecd.gearbox, efficiency=efficiency, coulomb_friction=0.0)
    lossy = replace(ecd, ecd=replace(ecd.ecd, gearbox=gearbox))
    if back_driven:
        damper = replace(lossy.ecd.damper, damping_rate=1e-7)
        lossy = replace(lossy, rotor_inertia=2e-6, ecd=replace(lossy.ecd, damper=damper))
        load = replace(hinge.load, spring=LinearSpring(3.0, -3.0), system_friction=ZERO_LAW)
        hinge = replace(hinge, load=load)
    return replace(wing, hinges=(replace(hinge, ecd=lossy),))


@pytest.mark.parametrize("back_driven", [False, True], ids=["forward", "back_driven"])
def test_one_panel_with_a_lossy_gear_is_todays_hinge(back_driven: bool) -> None:
    # A lossy gear (issue 25 item 1) on the one-panel wing against the single hinge's
    # dynamic method (held to Modelica's LossyGear in validation/cases.py): the same
    # power flows (the switches' times too), latch or stuck angle, and gear loss. Both
    # integrate at rtol 1e-8 on different steppers' paths, so 1e-6 relative (seen: 1e-10
    # on the latch times, 2e-10 on the stuck angles and the gear losses).
    plain = load_wing_config(case("wing_one_panel").config).wing
    wing = _lossy(plain, back_driven)
    temperatures = [-40.0, 100.0]
    mine, solution = _with_single_hinge(wing, temperatures)
    single = solution.result
    names = single.events.names()
    for i, run in enumerate(mine.cases):
        flows = [e.time for e in run.events if e.kind == "power_flow"]
        theirs = [
            float(t)
            for t, k, c in zip(single.events.time, names, single.events.case, strict=True)
            if k == "power_flow" and c == i
        ]
        assert flows == pytest.approx(theirs, rel=1e-6)
        assert float(run.energy.mesh_loss[0]) == pytest.approx(
            float(single.energy.gear_loss[i]), rel=1e-6
        )
        assert run.energy.error < 1e-6
        if back_driven:
            # It swings forward, is back-driven while it decelerates, swings back, and
            # sticks short of its latch (one switch at -40 degC, two at 100 degC).
            assert run.status == "stuck"
            assert len(flows) == i + 1
            assert run.angle[-1][0] == pytest.approx(float(single.final_angle[i]), rel=1e-6)
        else:
            # Driven forward all the way: the efficiency slows it (69.6 s against 48.1 s
            # through an ideal gear at -40 degC), the loss is (1/eta_f - 1) of the power.
            latch = run.latches[0]
            assert flows == []
            assert latch.time == pytest.approx(float(single.deployment_time[i]), rel=1e-6)
            assert latch.speed == pytest.approx(float(single.arrival_speed[i]), rel=1e-6)
            ideal = deploy_wing(plain, [temperatures[i]], backend="python").cases[0]
            assert latch.time > ideal.latches[0].time * 1.1


def test_a_lossy_gear_with_stribeck_friction_is_refused_in_one_line() -> None:
    # The single hinge refuses the pair (docs/dynamics.md); so does the wing, naming the
    # hinge and the key.
    wing = _lossy(load_wing_config(case("wing_one_panel").config).wing, back_driven=False)
    ecd = wing.hinges[0].ecd
    assert ecd is not None
    hinge = replace(wing.hinges[0], ecd=replace(ecd, stribeck_speed=0.03))
    with pytest.raises(WingUnsupported) as info:
        deploy_wing(replace(wing, hinges=(hinge,)), [25.0], backend="python")
    message = str(info.value)
    assert "\n" not in message
    assert "wing.hinges[0]" in message
    assert "gearbox.efficiency" in message


def test_one_panel_with_a_resistive_table_is_todays_hinge() -> None:
    # A harness torque rising from 0 to 1 N*m over the travel: the drive's table then
    # repeats its breakpoints at 0 and at the travel (the spring's and the table's meet),
    # pieces of no width the wing's drive steps over (it read them as 0/0 and stuck at
    # release). Against the single hinge's dynamic method: the same stuck angle (the
    # harness outgrows the spring less the friction), both at rtol 1e-8, so 1e-6
    # relative (seen: 1e-10).
    wing = load_wing_config(case("wing_one_panel").config).wing
    hinge = wing.hinges[0]
    load = replace(hinge.load, resistance=ResistiveTable((0.0, hinge.travel), (0.0, 1.0)))
    wing = replace(wing, hinges=(replace(hinge, load=load),))
    temperatures = [-40.0, 100.0]
    mine, solution = _with_single_hinge(wing, temperatures)
    for i, run in enumerate(mine.cases):
        assert run.status == "stuck"
        final = float(solution.result.final_angle[i])
        assert 0.5 < final < hinge.travel
        assert run.angle[-1][0] == pytest.approx(final, rel=1e-6)
        assert run.energy.error < 1e-6


@pytest.mark.parametrize("lossy", [False, True], ids=["ideal_gear", "lossy_gear"])
def test_one_panel_with_lost_motion_is_todays_hinge(lossy: bool) -> None:
    # 0.05 rad of lost motion in the gear (issue 25 item 1): the damper side idles until
    # the panel has turned through it, then engages in a plastic impact (its rotor seen
    # through the gear driven forward, J_D / eta_f, with a lossy gear). Against the single
    # hinge's dynamic method: the engagement's time and loss, the latch time and speed;
    # both at rtol 1e-8 on different steppers' paths, so 1e-6 relative (seen: 1e-9).
    plain = load_wing_config(case("wing_one_panel").config).wing
    wing = _lossy(plain, back_driven=False) if lossy else plain
    ecd = wing.hinges[0].ecd
    assert ecd is not None
    wing = replace(wing, hinges=(replace(wing.hinges[0], ecd=_lost_motion(ecd, 0.05)),))
    temperatures = [-40.0, 100.0]
    mine, solution = _with_single_hinge(wing, temperatures)
    single = solution.result
    for i, run in enumerate(mine.cases):
        engaged = [e.time for e in run.events if e.kind == "gear_engage"]
        assert engaged == pytest.approx([float(single.engagement_time[i])], rel=1e-6)
        loss = float(single.energy.engagement_loss[i])
        assert loss > 0.01  # the rotor's catch is felt: 0.014 to 0.029 J here
        assert float(run.energy.engagement_losses[0]) == pytest.approx(loss, rel=1e-6)
        latch = run.latches[0]
        assert latch.time == pytest.approx(float(single.deployment_time[i]), rel=1e-6)
        assert latch.speed == pytest.approx(float(single.arrival_speed[i]), rel=1e-6)
        assert run.energy.error < 1e-6

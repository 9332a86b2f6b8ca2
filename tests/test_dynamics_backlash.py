"""Compliant backlash (issue 16 item 3): the load and the damper side coupled by an elastic
mesh with lost motion (Modelica's ElastoBacklash2), against hand solutions, a tight scipy
Radau integration of the same equations written here, and the rigid limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ecdsim.config import load_config, parse_config
from ecdsim.config.errors import ConfigError
from ecdsim.deployment import ModelDomainError, predict
from ecdsim.dynamics import DynamicParameters, Thermal
from ecdsim.dynamics.result import DynamicResult
from ecdsim.montecarlo.apply import NotTolerable, Parameters, apply, nominal
from ecdsim.physics.mechanics import mesh_torque
from tests.dynamics_reference import assert_energy_closes, toy_system

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_cc16_dynamic.toml"


def _solve(system_kwargs: dict[str, float], **params: object) -> DynamicResult:
    system = toy_system(**system_kwargs)  # type: ignore[arg-type]
    prediction = predict(system, 25.0, ["dynamic"], dynamics=DynamicParameters(**params))  # type: ignore[arg-type]
    result = prediction.solutions["dynamic"].result  # type: ignore[attr-defined]
    assert isinstance(result, DynamicResult)
    return result


def _times(result: DynamicResult, kind: str) -> list[float]:
    return [
        float(t)
        for t, k in zip(result.events.time, result.events.names(), strict=True)
        if k == kind
    ]


def _speeds(result: DynamicResult, kind: str) -> list[float]:
    return [
        float(w)
        for w, k in zip(result.events.speed, result.events.names(), strict=True)
        if k == kind
    ]


def test_contact_torque_by_hand() -> None:
    # c = 100, d = 2, b = 0.02 (flanks at +-0.01): inside the gap nothing; past the forward
    # flank c (0.03 - 0.01) + d w; the damping cannot make it pull (limited at 0).
    tau = mesh_torque(
        np.array([0.005, 0.03, 0.03, -0.03, -0.03]),
        np.array([5.0, 0.5, -5.0, 5.0, -0.5]),
        0.01,
        100.0,
        2.0,
    )
    assert np.asarray(tau).tolist() == pytest.approx([0.0, 3.0, 0.0, 0.0, -3.0], abs=1e-15)


def test_elastic_impacts_through_the_backlash_by_hand() -> None:
    """A free load (no spring, no friction, no damping) crosses the gap and hits the
    resting damper side through an undamped mesh. Each contact lasts half a period of the
    two-inertia mode, pi / sqrt(c (1/J_L + 1/J_D)), and is an elastic collision; the
    damper side then runs ahead across the gap at the same relative speed and strikes the
    load's other flank (the load is overrun), which gives the speeds back."""
    jl, jd, c, w0, gap = 2.0, 0.5, 1e3, 0.2, 0.1
    result = _solve(
        {
            "damping": 0.0,
            "system_friction": 0.0,
            "start_torque": 0.0,
            "end_torque": 0.0,
            "travel": 1.0,
            "lost_motion": gap,
        },
        load_inertia=jl,
        rotor_inertia=jd,
        initial_speed=w0,
        gear_stiffness=c,
        stop_time=20.0,  # held at the latch, the undamped damper side would bounce forever
    )
    omega = math.sqrt(c * (1.0 / jl + 1.0 / jd))  # 50 rad/s
    half_period = math.pi / omega
    arrival = float(result.deployment_time)
    engage = _times(result, "engage")
    contacts = [t for t in _times(result, "contact") if t < arrival]
    parts = [t for t in _times(result, "separate") if t < arrival]
    assert engage == pytest.approx([gap / w0], rel=1e-12)  # free flight over the gap
    starts = engage + contacts
    assert len(starts) >= 2
    assert len(parts) >= 2
    # Event times are located to 1e-13 of a step, the state to rtol 1e-8.
    for begin, end in zip(starts, parts, strict=False):
        assert end - begin == pytest.approx(half_period, rel=1e-8)
    # The relative speed is reversed, not reduced: the gap is crossed in b / w0.
    assert starts[1] - parts[0] == pytest.approx(gap / w0, rel=1e-8)
    w_load = (jl - jd) / (jl + jd) * w0  # elastic collision with the resting damper side
    assert _speeds(result, "separate")[:2] == pytest.approx([w_load, w0], rel=1e-7)
    e = result.energy
    assert float(e.mesh_dissipation) == pytest.approx(0.0, abs=1e-12)  # type: ignore[arg-type]
    assert float(e.spring_work) == 0.0
    # Nothing dissipates: the kinetic energy at the latch plus the mesh's stored energy is
    # the initial kinetic energy J_L w0^2 / 2 = 0.04 J.
    stored = float(e.elastic_energy)  # type: ignore[arg-type]
    assert float(result.arrival_kinetic_energy) + stored == pytest.approx(0.04, rel=1e-8)
    assert_energy_closes(result)


# A small deployment where the damper side bounces off the load several times before the
# contact closes for good: J_D / B = 15 ms against the mesh's period of 11 ms.
_SYSTEM = {
    "damping": 2.0,
    "system_friction": 0.3,
    "start_torque": 4.0,
    "end_torque": 2.0,
    "travel": 1.5,
    "lost_motion": 0.05,
}
_JL, _JD, _C, _D = 5.0, 0.03, 1e4, 0.3


@dataclass(frozen=True)
class _Reference:
    time: float
    speed: float
    engage: float
    contacts: int
    parts: int
    mesh_loss: float
    damper_loss: float
    max_torque: float = math.nan  # largest mesh torque before the arrival [N*m]


def _radau_reference(until: float = math.inf) -> _Reference:
    """The two-inertia equations of docs/dynamics.md typed here, integrated by Radau at
    rtol 1e-12 from mode to mode (gap, pressing, released), with terminal events, to the
    arrival or to the time ``until`` (then ``time`` is nan and the energies are there)."""
    ts, te, travel, fs, b = 4.0, 2.0, 1.5, 0.3, 0.025  # b: half the lost motion
    slope = (te - ts) / travel

    def raw(y: np.ndarray) -> float:
        return float(_C * (y[2] - b) + _D * (y[1] - y[3]))

    def rhs_of(mode: str):  # type: ignore[no-untyped-def]
        def rhs(_t: float, y: np.ndarray) -> np.ndarray:
            w_rel = y[1] - y[3]
            tau = max(raw(y), 0.0) if mode == "press" else 0.0
            mesh = 0.0
            if mode == "press":
                mesh = _D * w_rel * w_rel
            elif mode == "released":
                mesh = -_C * (y[2] - b) * w_rel
            return np.array(
                [
                    y[1],
                    (ts + slope * y[0] - fs - tau) / _JL,
                    w_rel,
                    (tau - 2.0 * y[3]) / _JD,
                    2.0 * y[3] * y[3],
                    mesh,
                ]
            )

        return rhs

    def event(func, direction: float):  # type: ignore[no-untyped-def]
        func.terminal = True
        func.direction = direction
        return func

    arrive = event(lambda _t, y: y[0] - travel, 1.0)

    def rate(t: float, y: np.ndarray) -> float:
        dy = rhs_of("press")(t, y)
        return float(_C * dy[2] + _D * (dy[1] - dy[3]))

    rate.direction = -1.0  # type: ignore[attr-defined]
    peaks: list[float] = []
    y = np.array([0.0, 0.0, -b, 0.0, 0.0, 0.0])
    t, mode = 0.0, "gap"
    engage, contacts, parts = math.nan, 0, 0
    while True:
        if mode == "gap":
            events = [
                arrive,
                event(lambda _t, y: y[2] - b, 1.0),
                event(lambda _t, y: y[2] + b, -1.0),
            ]
        elif mode == "press":
            # The last, not terminal: the torque's maxima (d tau / dt = 0, falling).
            events = [arrive, event(lambda _t, y: raw(y), -1.0), rate]
        else:
            events = [arrive, event(lambda _t, y: raw(y), 1.0), event(lambda _t, y: y[2] - b, -1.0)]
        end = min(t + 100.0, until)
        sol = solve_ivp(
            rhs_of(mode), (t, end), y, method="Radau", rtol=1e-12, atol=1e-15, events=events
        )
        if sol.status == 0:  # reached ``until``
            return _Reference(
                math.nan,
                math.nan,
                engage,
                contacts,
                parts,
                float(sol.y[5, -1]),
                float(sol.y[4, -1]),
            )
        if mode == "press":
            peaks += [raw(p) for p in sol.y_events[2]]
        assert sol.status == 1
        hit = next(
            i for i, te_ in enumerate(sol.t_events) if len(te_) and i < 2 + (mode != "press")
        )
        t, y = float(sol.t_events[hit][0]), sol.y_events[hit][0].copy()
        assert y[1] > 0.0
        assert y[3] >= 0.0
        if hit == 0:
            return _Reference(
                t, float(y[1]), engage, contacts, parts, float(y[5]), float(y[4]), max(peaks)
            )
        if mode == "gap":
            assert hit == 1, "the damper side reached the backward flank"
            if math.isnan(engage):
                engage = t
            else:
                contacts += 1
            mode = "press"
        elif mode == "press":
            parts += 1
            mode = "released" if y[2] > b else "gap"
        else:
            if hit == 1:
                contacts += 1
            mode = "press" if hit == 1 else "gap"


@pytest.fixture(scope="module")
def bouncing() -> DynamicResult:
    return _solve(
        _SYSTEM,
        load_inertia=_JL,
        rotor_inertia=_JD,
        gear_stiffness=_C,
        gear_mesh_damping=_D,
        rtol=1e-10,
    )


_PART = 2.0  # [s] before the arrival (2.487 s): the energies are compared here


def test_contact_lost_and_regained_against_radau(bouncing: DynamicResult) -> None:
    ref = _radau_reference()
    result = bouncing
    arrival = float(result.deployment_time)
    assert ref.parts >= 2  # the case does bounce: the contact is lost and regained
    assert len([t for t in _times(result, "separate") if t < arrival]) == ref.parts
    assert len([t for t in _times(result, "contact") if t < arrival]) == ref.contacts
    # Both integrations at rtol 1e-10 and 1e-12; the event times are those of the state.
    assert _times(result, "engage") == pytest.approx([ref.engage], rel=1e-9)
    assert arrival == pytest.approx(ref.time, rel=1e-8)
    assert float(result.arrival_speed) == pytest.approx(ref.speed, rel=1e-7)
    # The largest mesh torque before the arrival (the engagement's), at a located maximum.
    part_max = _solve(
        _SYSTEM,
        load_inertia=_JL,
        rotor_inertia=_JD,
        gear_stiffness=_C,
        gear_mesh_damping=_D,
        rtol=1e-10,
        stop_time=ref.time * (1.0 - 1e-9),
    ).max_mesh_torque
    assert part_max is not None
    assert float(part_max) == pytest.approx(ref.max_torque, rel=1e-8)
    # The energies up to a time before the arrival (the run goes on after the latch).
    part = _solve(
        _SYSTEM,
        load_inertia=_JL,
        rotor_inertia=_JD,
        gear_stiffness=_C,
        gear_mesh_damping=_D,
        rtol=1e-10,
        stop_time=_PART,
    )
    ref_part = _radau_reference(_PART)
    e = part.energy
    assert part.status_names() == ["stop_time"]
    assert float(e.damper_dissipation) == pytest.approx(ref_part.damper_loss, rel=1e-7)
    # The mesh loss is 1e-5 of the energy moved: compared to 1e-5 of itself.
    mesh = e.mesh_dissipation
    assert mesh is not None
    assert float(mesh) == pytest.approx(ref_part.mesh_loss, rel=1e-5)
    assert_energy_closes(part, 1e-8)


def test_energy_balance_closes_with_the_mesh_terms(bouncing: DynamicResult) -> None:
    e = bouncing.energy
    assert e.mesh_dissipation is not None
    assert e.elastic_energy is not None
    assert float(e.mesh_dissipation) > 0.0
    # Held at the latch, the damper side overruns the load, strikes the other flank and
    # comes to rest in the gap (no friction holds it against a flank): nothing stored.
    assert bouncing.status_names() == ["latched"]
    assert float(e.elastic_energy) == 0.0
    assert bouncing.latch_mesh_torque is not None
    assert float(bouncing.latch_mesh_torque) > 0.0
    assert_energy_closes(bouncing, 1e-8)  # the integrator's rtol 1e-10, summed


def _rigid_and_compliant(
    stiffness: float, stop_time: float = math.inf
) -> tuple[DynamicResult, DynamicResult]:
    system = dict(_SYSTEM, ecd_friction=0.1)
    mu = _JL * _JD / (_JL + _JD)
    rigid = _solve(system, load_inertia=_JL, rotor_inertia=_JD, stop_time=stop_time)
    compliant = _solve(
        system,
        load_inertia=_JL,
        rotor_inertia=_JD,
        gear_stiffness=stiffness,
        gear_mesh_damping=2.0 * math.sqrt(stiffness * mu),
        stop_time=stop_time,
    )
    return rigid, compliant


def test_stiff_mesh_tends_to_the_rigid_engagement() -> None:
    """A critically damped mesh of growing stiffness: the compliant deployment tends to
    today's rigid one (plastic engagement), the error falling with the stiffness."""
    errors = []
    for c in (1e4, 1e6):
        rigid, compliant = _rigid_and_compliant(c)
        assert_energy_closes(compliant)
        errors.append(abs(float(compliant.deployment_time / rigid.deployment_time) - 1.0))
        # Up to a time before the latch (after which the damper side's overrun loads the
        # mesh again), the mesh absorbs most of the engagement's loss J_L J_D w^2 /
        # (2 (J_L + J_D)) (rigid: engagement_loss); the critically damped contact parts
        # once and the rest of the relative motion ends in the eddy damping (measured
        # 3.6 % and 0.7 % below).
        rigid_part, part = _rigid_and_compliant(c, 1.0)
        loss = float(rigid_part.energy.engagement_loss)
        assert float(part.energy.mesh_dissipation) == pytest.approx(loss, rel=0.05)  # type: ignore[arg-type]
        assert float(compliant.arrival_speed) == pytest.approx(float(rigid.arrival_speed), rel=1e-3)
    # The compliance delays the motion by about the mesh's deflection over the speed, an
    # error of order 1/c: measured 3.5e-5 at c = 1e4 and 3.5e-7 at 1e6 N*m/rad. Asserted:
    # below 1e-6 at 1e6, and falling by more than 50x for the 100x stiffer mesh.
    assert errors[1] < 1e-6
    assert errors[0] / errors[1] > 50.0


def test_config_keys_and_messages(tmp_path: Path) -> None:
    text = EXAMPLE.read_text()
    old = 'lost_motion = "0 deg"'
    assert old in text
    stiff = text.replace(
        old, 'lost_motion = "0.25 deg"\nstiffness = "2 kN*m/rad"\nmesh_damping = "500 mN*m*s/rad"'
    )
    path = tmp_path / "compliant.toml"
    path.write_text(stiff)
    params = load_config(path).spec.dynamics()
    assert params is not None
    assert params.gear_stiffness == pytest.approx(2000.0)
    assert params.gear_mesh_damping == pytest.approx(0.5)
    plain = load_config(EXAMPLE).spec.dynamics()
    assert plain is not None
    assert plain.gear_stiffness is None
    path.write_text(text.replace(old, old + '\nmesh_damping = "1 N*m*s/rad"'))
    with pytest.raises(ConfigError, match="mesh_damping needs stiffness"):
        load_config(path)
    path.write_text(text.replace(old, old + '\nstiffness = "-1 N*m/rad"'))
    with pytest.raises(ConfigError, match="stiffness"):
        load_config(path)


def test_unsupported_combinations_name_the_key() -> None:
    system = toy_system(
        damping=20.0, system_friction=0.3, start_torque=4.0, end_torque=2.0, travel=1.5
    )
    with pytest.raises(ModelDomainError, match="gearbox.stiffness"):
        predict(
            system,
            25.0,
            ["dynamic"],
            dynamics=DynamicParameters(
                load_inertia=5.0, rotor_inertia=0.03, gear_stiffness=1e4, thermal=Thermal(90.0)
            ),
        )
    with pytest.raises(ModelDomainError, match="damper-side inertia"):
        predict(
            system,
            25.0,
            ["dynamic"],
            dynamics=DynamicParameters(load_inertia=5.0, gear_stiffness=1e4),
        )
    # Beyond a 1e7 rad/s mode (or 1e7 1/s damping rate) the mesh is the rigid one: here
    # sqrt(1e13 (1/5 + 1/0.03)) = 1.8e7 rad/s, and 4e5 (1/5 + 1/0.03) = 1.3e7 1/s.
    with pytest.raises(ModelDomainError, match="gearbox.stiffness.*natural frequency"):
        predict(
            system,
            25.0,
            ["dynamic"],
            dynamics=DynamicParameters(load_inertia=5.0, rotor_inertia=0.03, gear_stiffness=1e13),
        )
    with pytest.raises(ModelDomainError, match="gearbox.mesh_damping.*damping rate"):
        predict(
            system,
            25.0,
            ["dynamic"],
            dynamics=DynamicParameters(
                load_inertia=5.0, rotor_inertia=0.03, gear_stiffness=1e4, gear_mesh_damping=4e5
            ),
        )


def test_creep_to_the_static_equilibrium_by_hand() -> None:
    """Spring 4 -> 0 N*m over 1.5 rad against FS + FECD = 1 N*m, overdamped: both bodies
    creep to where the spring balances both frictions, T_s(phi*) = FS + FECD (the load
    carries FS, the mesh carries FECD to the damper side), phi* = (4 - 1) / (4 / 1.5)."""
    result = _solve(
        {
            "damping": 20.0,
            "system_friction": 0.6,
            "ecd_friction": 0.4,
            "start_torque": 4.0,
            "end_torque": 0.0,
            "travel": 1.5,
            "lost_motion": 0.05,
        },
        load_inertia=5.0,
        rotor_inertia=0.03,
        gear_stiffness=1e4,
        gear_mesh_damping=1.0,
    )
    assert result.status_names() == ["creep"]
    assert math.isinf(float(result.stuck_time))
    # Declared at rest at 1e-9 of the speed scale: the angle is short by that speed times
    # the slow time constant B / k (7.5 s), 1e-8 relative here.
    assert float(result.stuck_angle) == pytest.approx(1.125, rel=1e-7)
    # The mesh holds FECD: elastic energy FECD^2 / (2 c).
    assert float(result.energy.elastic_energy) == pytest.approx(0.4**2 / 2e4, rel=1e-6)  # type: ignore[arg-type]
    assert_energy_closes(result)


def test_rebound_overruns_the_load_through_the_backlash() -> None:
    """A rebounding end stop (e = 0.5): the load bounces back while the damper side goes
    on; the gap is crossed and the flanks meet again, and the account still closes."""
    system = {
        "damping": 2.0,
        "system_friction": 0.3,
        "ecd_friction": 0.1,
        "start_torque": 4.0,
        "end_torque": 2.0,
        "travel": 1.5,
        "lost_motion": 0.05,
    }
    rigid = _solve(system, load_inertia=5.0, rotor_inertia=0.03, restitution=0.5)
    result = _solve(
        system,
        load_inertia=5.0,
        rotor_inertia=0.03,
        gear_stiffness=1e4,
        gear_mesh_damping=0.3,
        restitution=0.5,
    )
    names = result.events.names()
    first = names.index("arrive")
    assert "contact" in names[first:]
    assert "separate" in names[first:]
    assert result.status_names() == ["settled"]
    # The first rebound: -e times the arrival speed (Newton's law on the load alone).
    assert float(result.rebound_speed) == pytest.approx(
        -0.5 * float(result.arrival_speed), rel=1e-12
    )
    # The mesh's compliance changes the first arrival by the engagement's transient only
    # (rigid: 2.52358 s); 1e-4 of it with c = 1e4 N*m/rad (measured 3.5e-5).
    assert float(result.deployment_time) == pytest.approx(float(rigid.deployment_time), rel=1e-4)
    assert_energy_closes(result)


def test_stiction_at_release_as_the_rigid_mesh() -> None:
    """With lost motion the load starts free: it stays only if FS's breakaway holds the
    spring (2.9 N*m <= 1.2 * 3 N*m), compliant or rigid."""
    system = {
        "damping": 2.0,
        "system_friction": 3.0,
        "ecd_friction": 0.1,
        "start_torque": 2.9,
        "end_torque": 2.0,
        "travel": 1.5,
        "lost_motion": 0.05,
    }
    for stiffness in (None, 1e4):
        result = _solve(
            system,
            load_inertia=5.0,
            rotor_inertia=0.03,
            gear_stiffness=stiffness,
            static_friction_factor=1.2,
        )
        assert result.events.names() == ["release", "stick"]
        assert float(result.stuck_angle) == 0.0
        assert float(result.stuck_time) == 0.0


# The shipped example's dynamic results at commit 54410d1, before compliant backlash
# (printed by that commit's code; -40, +25, +100 degC): deployment time [s], arrival speed
# [rad/s], damper and friction dissipation [J].
_BEFORE = (
    (47.89552767513658, 0.008376667722624683, 2.0596258853606253, 2.1085476799999996),
    (26.746425203015804, 0.02463150915038869, 2.5895082609820865, 1.5773161999999998),
    (15.368363283744932, 0.05477777404454956, 3.1964483599474067, 0.9643567999999999),
)


def test_without_the_keys_results_are_those_of_before() -> None:
    config = load_config(EXAMPLE)
    params = config.spec.dynamics()
    assert params is not None
    assert params.gear_stiffness is None
    prediction = predict(config.system, [-40.0, 25.0, 100.0], ["dynamic"], dynamics=params)
    result = prediction.solutions["dynamic"].result  # type: ignore[attr-defined]
    assert isinstance(result, DynamicResult)
    for i, (time, speed, damper, friction) in enumerate(_BEFORE):
        summary = result.case_summary(i)
        # The rigid path is unchanged: equal to rounding (1e-12, as the Stribeck test).
        assert summary["deployment_time_s"] == pytest.approx(time, rel=1e-12)
        assert summary["end_speed_rad_s"] == pytest.approx(speed, rel=1e-12)
        energy = summary["energy_J"]
        assert energy["damper_dissipation"] == pytest.approx(damper, rel=1e-12)
        assert energy["friction_dissipation"] == pytest.approx(friction, rel=1e-12)
        # No new energy terms in the rigid account (JSON unchanged).
        assert "mesh_dissipation" not in energy
        assert "final_elastic" not in energy
    assert result.energy.mesh_dissipation is None


def test_a_batch_is_its_cases_one_by_one_and_takes_tolerances() -> None:
    """Monte Carlo puts arrays into the parameters (gearbox.stiffness and mesh_damping are
    tolerable keys): each case of a batch is the same as alone, bit for bit (the cases are
    solved one at a time by the same code)."""
    system = toy_system(**_SYSTEM)  # type: ignore[arg-type]
    stiffness = np.array([5e3, 2e4])
    damping = np.array([0.3, 1.0])
    batch = predict(
        system,
        [25.0],
        ["dynamic"],
        dynamics=DynamicParameters(
            load_inertia=_JL, rotor_inertia=_JD, gear_stiffness=stiffness, gear_mesh_damping=damping
        ),
    )
    times = np.ravel(batch.solutions["dynamic"].deployment_time)
    for i in range(2):
        alone = _solve(
            _SYSTEM,
            load_inertia=_JL,
            rotor_inertia=_JD,
            gear_stiffness=float(stiffness[i]),
            gear_mesh_damping=float(damping[i]),
        )
        assert times[i] == float(alone.deployment_time)
    params = Parameters(
        system, DynamicParameters(load_inertia=_JL, rotor_inertia=_JD, gear_stiffness=1e4)
    )
    assert nominal(params, "gearbox.stiffness") == 1e4
    varied = apply(params, {"gearbox.stiffness": stiffness})
    assert varied.dynamics is not None
    assert np.asarray(varied.dynamics.gear_stiffness).tolist() == stiffness.tolist()
    with pytest.raises(NotTolerable, match="not set"):
        nominal(Parameters(system, DynamicParameters(load_inertia=_JL)), "gearbox.stiffness")


def test_a_speed_jump_at_the_stop_releases_a_pressing_mesh() -> None:
    """A stiff, well damped mesh pressing at the end stop: the rebound reverses the load's
    speed at once, so the limited torque c (delta - b/2) + d delta' drops to zero there and
    the mesh is released (not kept pressing with a negative torque, which once made the
    mesh's dissipation negative and the account miss by 7e-4)."""
    system = {
        "damping": 20.0,
        "system_friction": 0.3,
        "ecd_friction": 0.2,
        "start_torque": 4.0,
        "end_torque": 2.0,
        "travel": 1.5,
        "lost_motion": 0.02,
    }
    result = _solve(
        system,
        load_inertia=5.0,
        rotor_inertia=0.03,
        gear_stiffness=1e6,
        gear_mesh_damping=20.0,
        restitution=0.3,
    )
    names = result.events.names()
    assert names[names.index("arrive") + 1] == "separate"
    mesh = result.energy.mesh_dissipation
    assert mesh is not None
    assert float(mesh) > 0.0
    assert_energy_closes(result, 1e-8)


def test_time_series_follow_the_load(bouncing: DynamicResult) -> None:
    """The sampled angle and speed are the load's, from the recorded steps: at each event
    time they are the event's (to the dense output's cubic interpolation), and the run ends
    on the travel with the arrival speed."""
    events = bouncing.events
    times = np.asarray(events.time, dtype=float)
    inside = times[(times > 0.0) & (times < float(bouncing.deployment_time))]
    series = bouncing.sample(np.concatenate([inside, [float(bouncing.deployment_time)]]))
    angle = np.ravel(series.angle)
    chosen = (times > 0.0) & (times < float(bouncing.deployment_time))
    # An event's state starts the next step: the series holds it exactly there.
    assert angle[:-1] == pytest.approx(np.asarray(events.angle)[chosen], rel=1e-12)
    # From the arrival on the load is held by the latch: the travel, at rest.
    assert angle[-1] == pytest.approx(1.5, rel=1e-12)
    assert float(np.ravel(series.speed)[-1]) == 0.0
    frame = bouncing.to_pandas("events")
    assert set(frame["kind"]) >= {"engage", "separate", "contact", "arrive", "latch"}


def test_the_damper_side_overruns_the_latched_load_by_hand() -> None:
    """Nothing dissipates (no friction, no damping, d = 0): the latch takes the load's
    kinetic energy J_L w_a^2 / 2, and the damper side keeps the rest of the spring's work
    W = 1 N*m x 1 rad. Held at the end, the load is overrun: the damper side crosses the
    gap and strikes the flank, and stops where its whole energy E_D is in the mesh, so the
    largest mesh torque after the latch is sqrt(2 c E_D)."""
    jl, jd, c = 2.0, 0.5, 1e3
    result = _solve(
        {
            "damping": 0.0,
            "system_friction": 0.0,
            "start_torque": 1.0,
            "end_torque": 1.0,
            "travel": 1.0,
            "lost_motion": 0.1,
        },
        load_inertia=jl,
        rotor_inertia=jd,
        gear_stiffness=c,
        stop_time=10.0,  # undamped, the damper side would swing between the flanks forever
    )
    arrival = float(result.deployment_time)
    assert arrival < 10.0
    assert result.status_names() == ["stop_time"]
    energy = 1.0 - 0.5 * jl * float(result.arrival_speed) ** 2
    assert energy > 0.0
    # The peak is at the damper side's zero speed, an event located to rtol 1e-8.
    assert result.latch_mesh_torque is not None
    assert float(result.latch_mesh_torque) == pytest.approx(math.sqrt(2.0 * c * energy), rel=1e-7)
    assert float(result.energy.impact_loss) == pytest.approx(
        0.5 * jl * float(result.arrival_speed) ** 2, rel=1e-12
    )
    assert_energy_closes(result)


@pytest.mark.parametrize(
    ("extra", "what"),
    [
        (
            '[load.gravity]\nmass = "2.4 kg"\ncg_radius = "0.35 m"\nrelease_angle = "30 deg"\n'
            'offload = "90 %"\n',
            "load.gravity",
        ),
        ("", "gearbox\\] efficiency"),
    ],
)
def test_lossy_gear_and_gravity_are_refused_by_name(tmp_path: Path, extra: str, what: str) -> None:
    text = EXAMPLE.read_text().replace(
        'lost_motion = "0 deg"', 'lost_motion = "0 deg"\nstiffness = "2e3 N*m/rad"', 1
    )
    if not extra:  # the lossy gear replaces FG
        text = text.replace(
            'coulomb_friction = "4.5e-4 N*m"',
            'coulomb_friction = "0 N*m"\nefficiency = { forward = 0.8 }',
            1,
        )
    path = tmp_path / "combined.toml"
    path.write_text(text + "\n" + extra)
    config = load_config(path)
    with pytest.raises(ModelDomainError, match=f"gearbox.stiffness.*{what}"):
        predict(config.system, 25.0, ["dynamic"], dynamics=config.spec.dynamics())


def test_deploy_shows_the_mesh_torques(tmp_path: Path) -> None:
    """ecdsim deploy: the 'Dynamic method: damper' table gains the mesh torque's peak and
    its largest value once latched, and the JSON carries them (the same numbers)."""
    import json

    from typer.testing import CliRunner

    from ecdsim.cli.app import app

    path = tmp_path / "compliant.toml"
    path.write_text(
        EXAMPLE.read_text().replace(
            'lost_motion = "0 deg"',
            'lost_motion = "0.25 deg"\nstiffness = "2e3 N*m/rad"\nmesh_damping = "0.5 N*m*s/rad"',
            1,
        )
    )
    runner = CliRunner()
    table = runner.invoke(app, ["deploy", str(path), "--method", "dynamic", "-T", "25"])
    assert table.exit_code == 0, table.output
    assert "mesh" in table.output
    document = runner.invoke(
        app, ["deploy", str(path), "--method", "dynamic", "-T", "25", "--json"]
    )
    assert document.exit_code == 0
    case = json.loads(document.output)["cases"][0]["dynamic"]
    peak, latched = case["max_mesh_torque_Nm"], case["latch_mesh_torque_Nm"]
    # The engagement through the lost motion loads the mesh beyond the spring's 3.73 N*m
    # less friction (its impact); the damper side's overrun at the latch less.
    assert peak > 3.73 - 1.0
    assert 0.0 < latched < peak
    assert f"{peak:.4g}" in table.output
    assert f"{latched:.4g}" in table.output


def _example(stiffness: float, damping: float, rtol: float = 1e-8) -> DynamicResult:
    """The dynamic example at 25 degC with a 0.25 deg lost motion and a compliant mesh."""
    text = EXAMPLE.read_text().replace(
        'lost_motion = "0 deg"',
        f'lost_motion = "0.25 deg"\nstiffness = "{stiffness!r} N*m/rad"\n'
        f'mesh_damping = "{damping!r} N*m*s/rad"',
        1,
    )
    config = parse_config(text.replace("[analysis]", f"[analysis]\nrtol = {rtol!r}", 1))
    found = predict(config.system, [25.0], ["dynamic"], dynamics=config.spec.dynamics())
    result = found.solutions["dynamic"].result  # type: ignore[attr-defined]
    assert isinstance(result, DynamicResult)
    return result


# The dynamic example at 25 degC (T_ref: Eq. 1's factor 1): BECD = N^2 (BD + BG) and
# FECD = N (FD + FG + FL_T) (Eq. 2-4), the spring 3.73 -> 1.58 N*m over 1.57 rad, the
# system friction FS_T, the load and the reflected rotor.
N, BD = 380.0, 1.3e-4
BECD = N * N * 1.26 * BD
FECD = N * (7.9e-4 + 4.5e-4 + (-2.12e-6 * 25.0 + 2.2e-4))
FS25 = -0.0044 * 25.0 + 0.58
J_LOAD, J_DAMPER = 5.0, 2e-7 * N * N
LOST = math.radians(0.25)


def test_the_latch_mesh_torque_is_taken_at_the_latch() -> None:
    # Issue 23 item 8: a stiff undamped mesh (1e8 N*m/rad). At the latch the damper side
    # runs pressed against the load's flank: the mesh carries its damping and friction,
    # BECD w + FECD at the latch speed w (by hand, Eq. 2-4), less the rotor's inertia
    # torque J_D w' (3e-5 of it here). Before, the value came from the first step after
    # the latch: 0.414 N*m at rtol 1e-8, 0.893 at 1e-10.
    results = [_example(1e8, 0.0), _example(1e8, 0.0, rtol=1e-10)]
    for result in results:
        assert result.status_names() == ["latched"]
        speed = _speeds(result, "latch")[0]
        assert result.latch_mesh_torque is not None
        latched = float(result.latch_mesh_torque[0])
        assert latched == pytest.approx(BECD * speed + FECD, rel=1e-4)
        # The hand value, c (delta - b/2) at the latch: 1.1172 N*m (5 digits).
        assert latched == pytest.approx(1.1172, abs=5e-5)
    torques = [float(r.latch_mesh_torque[0]) for r in results]  # type: ignore[index]
    assert torques[0] == pytest.approx(torques[1], rel=1e-6)


def test_the_contact_jump_is_the_peak_mesh_torque() -> None:
    # Issue 23 item 8: a critically damped 1e8 N*m/rad mesh, d = 2 sqrt(c J_L J_D / (J_L +
    # J_D)). The load crosses the lost motion alone from rest: by hand (a linear spring,
    # constant friction), v0^2 = 2 / J_L ((T0 - FS) b + slope b^2 / 2). At contact the
    # mesh torque jumps to d v0 and then falls (critically damped: its rate at contact is
    # (c - d^2 / J) v0 = -3 c v0 < 0), so d v0 is the peak (before: 252.07 against 255.52
    # N*m, the jump missed between steps).
    c = 1e8
    d = 2.0 * math.sqrt(c * J_LOAD * J_DAMPER / (J_LOAD + J_DAMPER))
    slope = (1.58 - 3.73) / 1.57
    v0 = math.sqrt(2.0 / J_LOAD * ((3.73 - FS25) * LOST + 0.5 * slope * LOST * LOST))
    result = _example(c, d)
    assert result.max_mesh_torque is not None
    assert float(result.max_mesh_torque[0]) == pytest.approx(d * v0, rel=1e-9)


def test_a_mesh_that_would_ring_too_long_is_refused_in_one_line(tmp_path: Path) -> None:
    # Issue 23 item 8: stiffness 1e12 N*m/rad undamped ran 15 s and ended "horizon" at
    # 0.14 s. Its mode (5.9e6 rad/s) decays only through the damper's damping (410 1/s):
    # 14,000 rad per e-fold, above MAX_MESH_RING. One line, exit status 2.
    from typer.testing import CliRunner

    from ecdsim.cli.app import app

    path = tmp_path / "stiff.toml"
    path.write_text(
        EXAMPLE.read_text().replace(
            'lost_motion = "0 deg"',
            'lost_motion = "0.25 deg"\nstiffness = "1e12 N*m/rad"\nmesh_damping = "0 N*m*s/rad"',
            1,
        )
    )
    result = CliRunner().invoke(app, ["deploy", str(path), "--method", "dynamic", "-T", "25"])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "gearbox.stiffness" in result.stderr
    assert "1.44e+04 rad per e-fold" in result.stderr

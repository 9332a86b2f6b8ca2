"""The compiled RODAS4 kernel (numba) against the NumPy integrator and scipy references.

``ecdsim.dynamics.compiled`` is a second implementation of ``ecdsim.dynamics.rosenbrock``
(same tableau, step control, events and maxima, one segment at a time): the two are run
on the same segments and deployments, and both against tight scipy integrations of the
equations written here from docs/dynamics.md. ``ECDSIM_NUMBA=0`` selects the NumPy path,
which is what runs where numba is not installed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters, Rolloff, Thermal, integrate, rosenbrock
from ecdsim.dynamics.damping import KlossEddy, LinearEddy
from ecdsim.dynamics.equations import Model
from ecdsim.dynamics.result import DynamicResult
from ecdsim.model import DeploymentSystem, Ecd, LinearSpring
from tests.conftest import paper_system, require
from tests.dynamics_reference import assert_energy_closes, toy_system

# numba is in the test extra: without it this fails with the install command.
compiled = require("ecdsim.dynamics.compiled")


def _dynamic(
    system: DeploymentSystem,
    temperatures: ArrayLike,
    params: DynamicParameters,
    numba: bool,
    monkeypatch: pytest.MonkeyPatch,
) -> DynamicResult:
    monkeypatch.setenv("ECDSIM_NUMBA", "1" if numba else "0")
    solution = predict(system, temperatures, ["dynamic"], dynamics=params).solutions["dynamic"]
    return solution.result  # type: ignore[attr-defined,no-any-return]


def test_the_switch_selects_the_integrator(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    assert integrate.compiled_kernel() is None
    monkeypatch.setenv("ECDSIM_NUMBA", "1")
    assert integrate.compiled_kernel() is compiled


def _segments(law: str, heating: bool, n: int = 24) -> tuple[Model, rosenbrock.Segments]:
    """Random segments spanning the events: reach, zero speed, creep, cap."""
    rng = np.random.default_rng(13)
    inertia = rng.uniform(0.01, 5.0, n)
    stiffness = rng.uniform(-0.5, 3.0, n)
    drive = rng.uniform(-0.5, 3.0, n)
    eddy: LinearEddy | KlossEddy
    if law == "linear":
        eddy = LinearEddy(rng.uniform(1e-4, 2e-4, n), 25.0, -0.004)
    else:
        eddy = KlossEddy(rng.uniform(1e-3, 5e-3, n), rng.uniform(20.0, 80.0, n), 0.0039, 25.0)
    model = Model(
        inertia=inertia,
        stiffness=stiffness,
        drive=drive,
        ratio=np.full(n, 380.0),
        gearbox_damping=np.full(n, 3e-5),
        heat_capacity=rng.uniform(0.05, 1.0, n) if heating else np.full(n, np.inf),
        thermal_resistance=np.where(np.arange(n) % 2 == 0, np.inf, 100.0),
        ambient=rng.uniform(-40.0, 100.0, n),
        eddy=eddy.flattened((n,)),
        heating=heating,
    )
    speed0 = rng.uniform(0.0, 0.3, n)
    length = rng.uniform(0.1, 2.0, n)
    with np.errstate(divide="ignore"):
        equilibrium = np.where(stiffness > 0.0, drive / stiffness, np.inf)
    y0 = np.stack([np.zeros(n), speed0, np.zeros(n), np.zeros(n)])
    cap = np.where(np.arange(n) % 5 == 0, rng.uniform(0.5, 5.0, n), np.inf)
    segments = rosenbrock.Segments(
        y0=y0,
        length=length,
        cap=cap,
        # Far above the speed's absolute tolerance, so that the creep time is well
        # conditioned (near 1e-12 it is fixed only to the few digits atol leaves).
        creep_speed=np.full(n, 1e-5),
        creeps=(equilibrium > 0.0) & (equilibrium <= length),
        atol=np.full((4, n), 1e-12),
        first_step=np.full(n, 1e-4),
    )
    return model, segments


@pytest.mark.parametrize(("law", "heating"), [("linear", True), ("kloss", False), ("kloss", True)])
@pytest.mark.parametrize("record", [False, True])
def test_compiled_kernel_matches_the_numpy_integrator(
    law: str, heating: bool, record: bool
) -> None:
    model, segments = _segments(law, heating)
    control = rosenbrock.Control(rtol=1e-9, horizon=1e9, horizon_kind=4, record=record)
    ref = rosenbrock.integrate_batch(model, segments, control)
    out = compiled.integrate_batch(model, segments, control)
    # Every event kind is exercised (reach, zero speed or creep, cap).
    assert {0, 2} <= set(ref.kind.tolist())
    assert set(ref.kind.tolist()) & {1, 3}
    assert np.array_equal(out.kind, ref.kind)
    # The same algorithm in the same order of operations: the step sequences coincide
    # unless a last-ulp difference of exp/expm1 between libm and NumPy flips one step's
    # acceptance, after which both remain within the same error control (rtol 1e-9).
    # 1e-9 relative bounds either case; measured, they agree to 4e-12 or better.
    assert np.allclose(out.duration, ref.duration, rtol=1e-9, atol=0.0)
    assert np.allclose(out.state, ref.state, rtol=1e-9, atol=1e-12)
    assert np.allclose(out.max_speed, ref.max_speed, rtol=1e-9, atol=0.0)
    assert np.allclose(out.max_thermal_state, ref.max_thermal_state, rtol=1e-9, atol=1e-12)
    for a, b, d in zip(out.trajectories, ref.trajectories, ref.duration, strict=True):
        assert (a is None) == (b is None)
        if a is not None and b is not None and np.isfinite(d):
            times = np.linspace(0.0, d, 7)
            # Dense output of the same steps: same bound as the states.
            assert np.allclose(a(times), b(times), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("threads", [2, 3, 7])
def test_a_batch_split_over_threads_gives_the_same_bits(
    threads: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Each segment is integrated from its own row only, so splitting the batch into
    # contiguous parts run on several threads must change no bit of any result (the
    # uneven splits 3 and 7 put part edges at arbitrary segments).
    model, segments = _segments("kloss", True, n=61)
    control = rosenbrock.Control(rtol=1e-9, horizon=1e9, horizon_kind=4, record=False)
    monkeypatch.setattr(compiled, "PARALLEL_MIN", 1)
    monkeypatch.setattr(compiled, "THREADS", 1)
    one = compiled.integrate_batch(model, segments, control)
    monkeypatch.setattr(compiled, "THREADS", threads)
    split = compiled.integrate_batch(model, segments, control)
    assert compiled._split(61, threads)[-1][1] == 61
    for a, b in zip(
        (one.kind, one.duration, one.state, one.max_speed, one.max_thermal_state),
        (split.kind, split.duration, split.state, split.max_speed, split.max_thermal_state),
        strict=True,
    ):
        assert np.array_equal(a, b)


def test_an_error_in_a_worker_thread_reaches_the_caller() -> None:
    def run(lo: int, _hi: int) -> None:
        if lo > 0:
            raise ValueError("worker failed")

    with pytest.raises(ValueError, match="worker failed"):
        compiled._in_threads(run, compiled._split(10, 2))


@pytest.mark.parametrize("coefficient", [-0.004, 0.0039, -1.0])
def test_the_thermal_terms_match_numpy_on_both_sides_of_the_polynomial(
    coefficient: float,
) -> None:
    # compiled._thermal gives f_a e^{cs}, s E(-cs) = (1 - e^{-cs}) / c and e^{cs} from a
    # Taylor polynomial of e^{cs} - 1 where |cs| <= 2^-5 and from exp and expm1 beyond:
    # against NumPy's exp and expm1 (independent implementations) over z = cs across that
    # edge, at 0 and at a subnormal-small z. Eq. 1's c (-0.004/K), the Kloss law's alpha
    # and a steep c of -1/K.
    par = np.zeros(compiled._COLUMNS)
    par[compiled._FA] = 1.3
    par[compiled._COEF] = coefficient
    edge = 2.0**-5
    z = np.concatenate(
        [np.linspace(-3 * edge, 3 * edge, 601), [edge, -edge, np.nextafter(edge, 1.0), 0.0]]
    )
    z = np.append(z, 1e-300)
    for s in z / coefficient:
        factor, drop, grown = compiled._thermal(par, s, True)
        # Without cooling (adiabatic, or the Jacobian) the rise is not computed: 0, and
        # the factor and e^{cs} are the same numbers.
        assert compiled._thermal(par, s, False) == (factor, 0.0, grown)
        cs = coefficient * s
        exact_drop = s if cs == 0.0 else s * (np.expm1(-cs) / -cs)
        # 2e-15 (about 9 units in the last place): the polynomial and the library each
        # round to a few units, and E(-cs) and the products add a rounding each.
        assert factor == pytest.approx(1.3 * np.exp(cs), rel=2e-15, abs=0.0)
        assert grown == pytest.approx(np.exp(cs), rel=2e-15, abs=0.0)
        assert drop == pytest.approx(exact_drop, rel=2e-15, abs=0.0)


def _rolloff_heating_params(rtol: float = 1e-9) -> DynamicParameters:
    return DynamicParameters(
        load_inertia=np.array([0.5, 5.0]),
        rotor_inertia=2e-7,
        rolloff=Rolloff(60.0, 0.0039),
        thermal=Thermal(0.2, 100.0),
        rtol=rtol,
    )


def test_paper_example_with_rolloff_and_heating_same_on_both_paths(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Three temperatures x two inertias with roll-off beyond the peak and self-heating.
    temps = np.array([-40.0, 25.0, 100.0])[:, None]
    params = _rolloff_heating_params()
    fast = _dynamic(paper_system(), temps, params, True, monkeypatch)
    slow = _dynamic(paper_system(), temps, params, False, monkeypatch)
    assert fast.status_names() == slow.status_names()
    # As in the kernel test above: the same steps, or both within rtol 1e-9 of the truth.
    for name in ("deployment_time", "arrival_speed", "max_speed", "max_damper_temperature"):
        assert np.allclose(getattr(fast, name), getattr(slow, name), rtol=1e-8, atol=0.0), name
    assert_energy_closes(fast)
    assert np.array_equal(fast.events.kind, slow.events.kind)


def _msl_reference(j: float, w0: float, t_end: float) -> tuple[float, float, float]:
    """The MSL EddyCurrentBrake spin-down typed from its equations: Kloss torque with
    tau_peak = 100 N*m, w_peak(T) = 10 (1 + 0.00392 (T - 20)) rad/s, adiabatic 1 J/K;
    solve_ivp Radau at rtol 1e-10, atol 1e-12. Returns angle, speed, temperature."""

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        w, temp = y[1], y[2]
        peak = 10.0 * (1.0 + 0.00392 * (temp - 20.0))
        x = w / peak
        torque = 2.0 * 100.0 * x / (1.0 + x * x)
        return np.array([w, -torque / j, torque * w / 1.0])

    sol = solve_ivp(rhs, (0.0, t_end), [0.0, w0, 20.0], method="Radau", rtol=1e-10, atol=1e-12)
    return float(sol.y[0, -1]), float(sol.y[1, -1]), float(sol.y[2, -1])


@pytest.mark.parametrize("numba", [True, False])
def test_rolloff_heating_spin_down_against_scipy(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The Modelica EddyCurrentBrake case (validation/configs/msl_eddy_current_brake.toml):
    # a 1 kg*m^2 flywheel at 20 rad/s, no spring, no friction, braked for 1 s.
    base = toy_system(20.0, 0.0, 0.0, 0.0, 100.0)
    damper = replace(base.ecd.damper, reference_temperature=20.0)
    system = DeploymentSystem(
        Ecd(damper, base.ecd.gearbox), replace(base.load, spring=LinearSpring(0.0, 0.0))
    )
    params = DynamicParameters(
        load_inertia=1.0,
        initial_speed=20.0,
        rolloff=Rolloff(10.0, 3.92e-3),
        thermal=Thermal(1.0),
        stop_time=1.0,
        rtol=1e-10,
    )
    result = _dynamic(system, [20.0], params, numba, monkeypatch)
    angle, speed, temp = _msl_reference(1.0, 20.0, 1.0)
    assert result.status_names() == ["stop_time"]
    # ecdsim at rtol 1e-10 against Radau at 1e-10: each within a few rtol of the truth.
    assert result.final_angle[0] == pytest.approx(angle, rel=1e-8)
    assert result.final_speed[0] == pytest.approx(speed, rel=1e-7)
    assert result.final_temperature[0] == pytest.approx(temp, rel=1e-9)
    assert_energy_closes(result)


@pytest.mark.parametrize(("law", "heating"), [("linear", False), ("kloss", True)])
def test_compiled_kernel_matches_the_numpy_integrator_with_stribeck_friction(
    law: str, heating: bool
) -> None:
    # The same random segments with a Stribeck excess F_brk - F_C and speed w_St on
    # their scale (speeds up to ~0.3 rad/s), half of them without (excess 0).
    base, segments = _segments(law, heating)
    n = base.inertia.size
    rng = np.random.default_rng(29)
    model = replace(
        base,
        stribeck_excess=np.where(np.arange(n) % 2 == 0, rng.uniform(0.05, 0.5, n), 0.0),
        stribeck_speed=rng.uniform(0.02, 0.2, n),
    )
    control = rosenbrock.Control(rtol=1e-9, horizon=1e9, horizon_kind=4, record=False)
    ref = rosenbrock.integrate_batch(model, segments, control)
    out = compiled.integrate_batch(model, segments, control)
    assert np.array_equal(out.kind, ref.kind)
    # As in the test above: the same steps, or both within rtol 1e-9 of the truth.
    assert np.allclose(out.duration, ref.duration, rtol=1e-9, atol=0.0)
    assert np.allclose(out.state, ref.state, rtol=1e-9, atol=1e-12)
    assert np.allclose(out.max_speed, ref.max_speed, rtol=1e-9, atol=0.0)
    # The friction matters: the Stribeck segments end otherwise than without it.
    plain = rosenbrock.integrate_batch(base, segments, control)
    assert not np.allclose(plain.duration[::2], ref.duration[::2], rtol=1e-6)
    # The segments without an excess are those of the plain model, bit for bit.
    assert np.array_equal(ref.duration[1::2], plain.duration[1::2])
    assert np.array_equal(
        out.duration[1::2], compiled.integrate_batch(base, segments, control).duration[1::2]
    )


@pytest.mark.parametrize("heating", [False, True])
def test_paper_example_with_stribeck_friction_same_on_both_paths(
    heating: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The paper's damper with stiction 1.5 and w_St = 0.02 rad/s (its speeds are 0.01 to
    # 0.06 rad/s), with or without self-heating, at three temperatures.
    temps = np.array([-40.0, 25.0, 100.0])
    params = DynamicParameters(
        load_inertia=5.0,
        rotor_inertia=2e-7,
        static_friction_factor=1.5,
        stribeck_speed=0.02,
        thermal=Thermal(0.5, 50.0) if heating else None,
        rtol=1e-9,
    )
    fast = _dynamic(paper_system(), temps, params, True, monkeypatch)
    slow = _dynamic(paper_system(), temps, params, False, monkeypatch)
    assert fast.status_names() == slow.status_names()
    # As above: the same steps, or both within rtol 1e-9 of the truth.
    for name in ("deployment_time", "arrival_speed", "max_speed", "final_angle"):
        assert np.allclose(getattr(fast, name), getattr(slow, name), rtol=1e-8, atol=0.0), name
    assert_energy_closes(fast)
    assert_energy_closes(slow)
    assert np.array_equal(fast.events.kind, slow.events.kind)

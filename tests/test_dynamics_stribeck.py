"""Stribeck friction in the dynamic method (issue 16 item 4; docs/model.md, docs/dynamics.md).

With ``[damper] stribeck_speed`` w_St the sliding friction is

    F(w) = F_C + (F_brk - F_C) exp(-(|w| / w_St)^2)

(F_C = FECD + FS engaged, F_brk = f_D FECD + f_S FS). The references here are the same
equations written independently and integrated by scipy's Radau at rtol 1e-10, or hand
calculations; without the key the results are those of commit 81b50d7 (before Stribeck
friction existed), held as numbers.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters, Rolloff, Thermal
from ecdsim.dynamics.result import DynamicResult
from ecdsim.model import DeploymentSystem
from ecdsim.physics.friction import stribeck_excess
from tests.dynamics_reference import assert_energy_closes, toy_system

ROOT = Path(__file__).resolve().parents[1]
DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"

# The deployment that slides through the Stribeck region: input-shaft values exactly
# (toy_system: N = 1, no BG, no temperature dependence). F_C = 0.2 + 0.3 = 0.5 N*m,
# F_brk = 1.6 * 0.5 = 0.8 N*m; the spring falls from 1.2 to 0.85 N*m over 1 rad, so it
# always beats the breakaway, and the speed (about (T - F_C) / B = 0.04 to 0.07 rad/s)
# crosses w_St = 0.05 rad/s. max |dg/dw| = (F_brk - F_C) sqrt(2/e) / w_St = 5.1 < B = 10:
# the sliding is stable (no stick-slip limit cycle).
J, B, FECD, FS, FACTOR, W_ST = 1.0, 10.0, 0.2, 0.3, 1.6, 0.05
START, END, TRAVEL = 1.2, 0.85, 1.0


def _dynamic(
    system: DeploymentSystem,
    params: DynamicParameters,
    numba: bool,
    monkeypatch: pytest.MonkeyPatch,
    temperatures: list[float] | tuple[float, ...] = (25.0,),
) -> DynamicResult:
    monkeypatch.setenv("ECDSIM_NUMBA", "1" if numba else "0")
    solution = predict(system, list(temperatures), ["dynamic"], dynamics=params)
    return solution.solutions["dynamic"].result  # type: ignore[attr-defined,no-any-return]


def test_stribeck_excess_by_hand() -> None:
    # g(0) = F_brk - F_C; g(w_St) = (F_brk - F_C) / e; dg/dw = -2 w / w_St^2 g.
    g, slope = (
        np.asarray(v)
        for v in stribeck_excess(np.array([0.0, 0.05, -0.05]), np.full(3, 0.3), np.full(3, 0.05))
    )
    assert g[0] == 0.3
    assert g[1] == pytest.approx(0.3 / math.e, rel=1e-15)  # one exp, rounding only
    assert g[2] == g[1]  # even in w
    assert slope[0] == 0.0
    assert slope[1] == pytest.approx(-2.0 / 0.05 * 0.3 / math.e, rel=1e-15)
    assert slope[2] == -slope[1]


# The shipped examples' dynamic results at commit 81b50d7 (before Stribeck friction), by
# the compiled kernel; 'heat_rolloff' adds roll-off, heating and stiction to exercise the
# integrated segments. Deployment time, arrival speed, damper and friction dissipation.
_BEFORE = {
    "": (
        [47.89552767513658, 26.746425203015804, 15.368363283744932],
        [0.008376667722624683, 0.02463150915038869, 0.05477777404454956],
        [2.0596258853606253, 2.5895082609820865, 3.1964483599474067],
        [2.1085476799999996, 1.5773161999999998, 0.9643567999999999],
    ),
    "heat_rolloff": (
        [50.127341176719206, 26.576477637344894, 16.457653409845125],
        [0.00798072028622497, 0.02478771434100845, 0.051091064634045814],
        [2.0596421707487664, 2.5894888512212417, 3.197429770260804],
        [2.1085476799999996, 1.5773161999999998, 0.9643567999999999],
    ),
}


@pytest.mark.parametrize("numba", [True, False])
@pytest.mark.parametrize("variant", ["", "heat_rolloff"])
def test_without_stribeck_speed_the_results_are_unchanged(
    variant: str, numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = load_config(DYNAMIC_CONFIG)
    params = config.spec.dynamics()
    assert params is not None
    assert params.stribeck_speed is None
    if variant:
        params = replace(
            params,
            rolloff=Rolloff(2000.0, 0.0039),
            thermal=Thermal(0.5, 50.0),
            static_friction_factor=1.3,
        )
    result = _dynamic(config.system, params, numba, monkeypatch, config.temperatures)
    got = (
        result.deployment_time,
        result.arrival_speed,
        result.energy.damper_dissipation,
        result.energy.friction_dissipation,
    )
    for value, before in zip(got, _BEFORE[variant], strict=True):
        # The closed form is bit for bit; the integrated variant too by the compiled
        # kernel, and within 1e-15 relative by the NumPy one (it differs from the
        # compiled kernel by that much, before and after): 1e-12 bounds both.
        assert np.allclose(np.ravel(value), before, rtol=1e-12, atol=0.0)


def _reference(
    start: float, end: float, w_st: float | None, t_end: float = 1e4
) -> tuple[float, float, float, float]:
    """J w' = T(x) - F_C - (F_brk - F_C) exp(-(w/w_St)^2) - B w, from rest at x = 0, to
    x = TRAVEL; Radau at rtol 1e-10. Returns the arrival time and speed, the dissipation
    of B and of the Stribeck excess (together: ecdsim's damper dissipation), and the
    Coulomb friction work."""
    f_c = FECD + FS
    excess = (FACTOR - 1.0) * f_c if w_st is not None else 0.0

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        x, w = y[0], y[1]
        spring = start + (end - start) * x / TRAVEL
        extra = excess * math.exp(-((w / w_st) ** 2)) if w_st is not None else 0.0
        return np.array([w, (spring - f_c - extra - B * w) / J, (B * w + extra) * w])

    def arrive(_t: float, y: np.ndarray) -> float:
        return float(y[0] - TRAVEL)

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, t_end), [0.0, 0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-13, events=arrive
    )
    assert sol.status == 1
    y = sol.y_events[0][0]
    return float(sol.t_events[0][0]), float(y[1]), float(y[2]), f_c * TRAVEL


@pytest.mark.parametrize("numba", [True, False])
def test_sliding_through_the_stribeck_region_against_scipy(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    system = toy_system(B, FS, START, END, TRAVEL, ecd_friction=FECD)
    params = DynamicParameters(
        load_inertia=J, static_friction_factor=FACTOR, stribeck_speed=W_ST, rtol=1e-10
    )
    result = _dynamic(system, params, numba, monkeypatch)
    time, speed, dissipation, coulomb = _reference(START, END, W_ST)
    assert result.status_names() == ["latched"]
    # The speed passes through w_St: the friction there is between F_C and F_brk.
    assert result.max_speed[0] > W_ST
    # ecdsim at rtol 1e-10 against Radau at rtol 1e-10: each within a few rtol of the
    # truth over a 46 s deployment (measured: 1.3e-12 apart); 1e-8 leaves a wide margin.
    assert result.deployment_time[0] == pytest.approx(time, rel=1e-8)
    assert result.arrival_speed[0] == pytest.approx(speed, rel=1e-8)
    assert result.energy.damper_dissipation[0] == pytest.approx(dissipation, rel=1e-8)
    # Coulomb work F_C x exactly (summed over segments: rounding only).
    assert result.energy.friction_dissipation[0] == pytest.approx(coulomb, rel=1e-14)
    assert_energy_closes(result)
    # The Stribeck friction slows the deployment against Coulomb friction alone (46 s
    # against 20 s by the two references).
    without, _, _, _ = _reference(START, END, None)
    assert time > 1.05 * without


@pytest.mark.parametrize("numba", [True, False])
def test_a_slow_creep_comes_to_rest_where_the_spring_equals_the_breakaway(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The spring falls from 0.9 to 0.7 N*m over 1 rad, below F_brk = 0.8 N*m beyond
    # x = 0.5 rad (0.9 - 0.2 x = 0.8, by hand). Starting at 0.01 rad/s, well below w_St,
    # the friction stays near F_brk: the motion approaches rest at 0.5 rad, asymptotically.
    system = toy_system(B, FS, 0.9, 0.7, TRAVEL, ecd_friction=FECD)
    params = DynamicParameters(
        load_inertia=J, static_friction_factor=FACTOR, stribeck_speed=W_ST, rtol=1e-10
    )
    result = _dynamic(system, params, numba, monkeypatch)
    assert result.status_names() == ["creep"]
    # Rest is declared at 1e-9 of the speed scale: the angle is then 0.5 rad to ~1e-9.
    assert result.final_angle[0] == pytest.approx(0.5, abs=1e-7)
    assert_energy_closes(result)
    # Without Stribeck friction (kinetic 0.5 N*m at every speed) it latches.
    coulomb = _dynamic(system, replace(params, stribeck_speed=None), numba, monkeypatch)
    assert coulomb.status_names() == ["latched"]


def test_breakaway_keeps_its_threshold() -> None:
    # At rest the friction holds up to F_brk = 0.8 N*m, Stribeck speed or not: a spring
    # of 0.79 N*m at release sticks, one of 0.81 N*m breaks away (and, the friction
    # falling with speed, slides to the latch).
    for start, status in ((0.79, "stuck"), (0.81, "latched")):
        system = toy_system(B, FS, start, start, TRAVEL, ecd_friction=FECD)
        params = DynamicParameters(
            load_inertia=J, static_friction_factor=FACTOR, stribeck_speed=W_ST
        )
        result = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
        assert result.result.status_names() == [status]  # type: ignore[attr-defined]


@pytest.mark.parametrize("numba", [True, False])
def test_free_play_slides_with_the_system_friction_alone(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Lost motion 0.2 rad: the load first moves alone against FS's Stribeck friction,
    # F(w) = FS + (f - 1) FS exp(-(w/w_St)^2), then engages. The compiled and NumPy paths
    # agree and the energy balance (with the engagement loss) closes.
    system = toy_system(B, FS, START, END, TRAVEL, ecd_friction=FECD, lost_motion=0.2)
    params = DynamicParameters(
        load_inertia=J,
        rotor_inertia=0.5,
        static_friction_factor=FACTOR,
        stribeck_speed=W_ST,
        rtol=1e-10,
    )
    result = _dynamic(system, params, numba, monkeypatch)
    assert result.status_names() == ["latched"]
    assert result.energy.engagement_loss[0] > 0.0
    assert_energy_closes(result)
    # Free play by hand: J_L w' = T(x) - FS - 0.18 exp(-(w/0.05)^2), integrated here.
    excess = (FACTOR - 1.0) * FS

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        spring = START + (END - START) * y[0] / TRAVEL
        return np.array([y[1], spring - FS - excess * math.exp(-((y[1] / W_ST) ** 2))])

    def engage(_t: float, y: np.ndarray) -> float:
        return float(y[0] - 0.2)

    engage.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 100.0), [0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-13,
                    events=engage)  # fmt: skip
    # Engagement time within a few rtol of each other (ecdsim and Radau at 1e-10).
    assert result.engagement_time[0] == pytest.approx(float(sol.t_events[0][0]), rel=1e-8)


_PAPER = DYNAMIC_CONFIG.read_text()


def test_the_key_parses_with_units_and_reaches_the_parameters() -> None:
    text = _PAPER.replace(
        "static_friction_factor = 1.0", 'static_friction_factor = 1.2\nstribeck_speed = "6 deg/s"'
    )
    params = parse_config(text, "<string>").spec.dynamics()
    assert params is not None
    assert params.stribeck_speed == pytest.approx(math.radians(6.0), rel=1e-15)
    assert load_config(DYNAMIC_CONFIG).spec.dynamics().stribeck_speed is None  # type: ignore[union-attr]


@pytest.mark.parametrize("value", ['"0 rad/s"', '"-1 rad/s"', '"1 N*m"'])
def test_a_bad_stribeck_speed_is_refused_naming_the_key(value: str, tmp_path: Path) -> None:
    text = _PAPER.replace(
        "static_friction_factor = 1.0", f"static_friction_factor = 1.0\nstribeck_speed = {value}"
    )
    with pytest.raises(ConfigError) as info:
        parse_config(text, "<string>")
    assert "damper.stribeck_speed" in str(info.value)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    run = CliRunner().invoke(app, ["deploy", str(path)])
    assert run.exit_code == 2
    assert "stribeck_speed" in run.output


def test_the_parameters_refuse_a_non_positive_speed() -> None:
    with pytest.raises(ValueError, match="stribeck_speed must be > 0"):
        DynamicParameters(load_inertia=1.0, stribeck_speed=0.0)


def test_the_time_series_friction_torque_follows_the_stribeck_curve() -> None:
    system = toy_system(B, FS, START, END, TRAVEL, ecd_friction=FECD)
    params = DynamicParameters(
        load_inertia=J, static_friction_factor=FACTOR, stribeck_speed=W_ST, rtol=1e-10
    )
    result = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    series = result.result.sample(n_points=51)  # type: ignore[attr-defined]
    speed = series.speed[:, 0]
    moving = speed > 0.0
    assert moving.sum() > 40
    # F(w) = F_C + (F_brk - F_C) exp(-(w/w_St)^2) = 0.5 + 0.3 exp(-(w/0.05)^2), opposing;
    # the same formula evaluated here (rounding only).
    expected = -(0.5 + 0.3 * np.exp(-((speed[moving] / W_ST) ** 2)))
    assert np.allclose(series.friction_torque[moving, 0], expected, rtol=1e-14, atol=0.0)
    # At release (at rest) the friction holds up to the breakaway F_brk = 0.8 N*m, which
    # the spring's 1.2 N*m beats: the holding torque shown there is -F_brk.
    assert series.friction_torque[0, 0] == pytest.approx(-0.8, rel=1e-14)


def test_a_batch_of_sampled_stribeck_speeds_equals_the_cases_one_by_one() -> None:
    # Monte Carlo puts n samples of damper.stribeck_speed into one DynamicParameters
    # (TOLERABLE's model path); each case of the batch is then the scalar run's, since
    # every case is integrated on its own (compiled kernel, or NumPy with per-case steps).
    from ecdsim.montecarlo import apply

    config = load_config(DYNAMIC_CONFIG)
    base = config.spec.dynamics()
    assert base is not None
    parameters = apply.Parameters(config.system, replace(base, static_friction_factor=1.5))
    with pytest.raises(apply.NotTolerable, match="not set in this config's \\[damper\\]"):
        apply.nominal(parameters, "damper.stribeck_speed")
    parameters = apply.Parameters(
        config.system, replace(base, static_friction_factor=1.5, stribeck_speed=0.02)
    )
    assert apply.nominal(parameters, "damper.stribeck_speed") == 0.02
    speeds = np.array([0.01, 0.02, 0.04])
    varied = apply.apply(parameters, {"damper.stribeck_speed": speeds})
    assert varied.dynamics is not None
    batch = predict(varied.system, [25.0], ["dynamic"], dynamics=varied.dynamics)
    times = np.ravel(batch.solutions["dynamic"].deployment_time)
    for speed, time in zip(speeds, times, strict=True):
        one = replace(varied.dynamics, stribeck_speed=float(speed))
        alone = predict(config.system, [25.0], ["dynamic"], dynamics=one)
        # Per-case step control: the same steps, so the same numbers to rounding.
        assert time == pytest.approx(
            float(np.ravel(alone.solutions["dynamic"].deployment_time)[0]), rel=1e-12
        )
    # A larger w_St keeps the friction above F_C over more of the speeds: slower.
    assert times[0] < times[1] < times[2]


@pytest.mark.parametrize("integrator", ["Radau", "BDF", "LSODA"])
def test_the_scipy_integrators_carry_the_stribeck_term(integrator: str) -> None:
    # The solve_ivp path (Model.rhs and its Jacobian) on the deployment above.
    system = toy_system(B, FS, START, END, TRAVEL, ecd_friction=FECD)
    params = DynamicParameters(
        load_inertia=J,
        static_friction_factor=FACTOR,
        stribeck_speed=W_ST,
        rtol=1e-10,
        integrator=integrator,
    )
    result = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    time, _, _, _ = _reference(START, END, W_ST)
    # Each integrator at rtol 1e-10 against Radau at 1e-10; measured within 1e-9
    # (LSODA, the loosest); 1e-8 leaves a margin of 10.
    assert result.result.deployment_time[0] == pytest.approx(time, rel=1e-8)  # type: ignore[attr-defined]
    assert_energy_closes(result.result)  # type: ignore[attr-defined]

"""Dynamic method: single deployments and batches against scipy ``solve_ivp`` LSODA.

Issue 13 item 3's cases, for ``benchmarks/run.py`` (``make bench``; :func:`cases`) or
alone (``python benchmarks/bench_dynamic.py [--quick]``). Each case times ecdsim and a
baseline interleaved (``benchmarks/harness.py``: >= 5 repeats, min and median, the ratio
per deployment as the median of the pairs). The baselines are the scipy scripts an
engineer would write instead: a plain Python right-hand side typed from the equations of
``docs/dynamics.md`` and ``solve_ivp(method="LSODA")`` with a terminal event at the end of
travel, one call per deployment.

* **One nonlinear deployment** through ``ecdsim.deployment.predict`` (what a user calls:
  model evaluation, event loop, result objects, warnings):
  - the paper example (``examples/paper_cc16_dynamic.toml``: J = 5 kg*m^2, +25 degC) with
    roll-off (omega_peak = 60 rad/s, alpha = 0.0039/K) and self-heating (0.2 J/K,
    100 K/W) switched on;
  - the Modelica EddyCurrentBrake spin-down (``validation/configs/
    msl_eddy_current_brake.toml``: roll-off and adiabatic heating, 1 s).
  **Equal accuracy**: a Radau run at rtol 1e-12 gives the reference answer; ecdsim runs at
  its default rtol (1e-8); LSODA runs at the loosest rtol of 1e-6 .. 1e-12 whose error
  against the reference is no larger than ecdsim's. Goal: LSODA time / ecdsim time >= 5.
* **Batches** (roll-off; self-heating; linear closed form): the paper example with BD, FD,
  FG, FS, Ts, Te each uniform within +-10 % (seeded), case i at T[i % 3] of -40, +25,
  +100 degC; ecdsim solves the whole batch in one ``predict`` call, LSODA (rtol 1e-10,
  atol 1e-12) loops over the first cases; the ratio is per deployment. Each nonlinear
  batch runs at ecdsim's default rtol (1e-8) and, when it differs, at the loosest rtol
  of 1e-6 .. 1e-8 whose error on the first 3 cases (against Radau at rtol 1e-12) is no
  larger than LSODA's (equal accuracy). Goals: >= 100x with roll-off and with heating.
* **Tabulated spring** of P = 1,000 points, one deployment, against LSODA on
  ``np.interp`` of the same table (ecdsim crosses each breakpoint as an event of its
  compiled event loop, ``ecdsim.dynamics.kernel``); a note gives ecdsim's time per breakpoint at two
  sizes, 2,000 and 10,000 (O(P) per deployment: it stays flat).

Agreement: largest relative difference in deployment time (final angle for the
spin-down) between ecdsim and the baseline. One core: the thread variables are set
before NumPy is imported.
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import dataclasses  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable, Sequence  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import harness  # noqa: E402
from ecdsim.config import load_config  # noqa: E402
from ecdsim.deployment import predict  # noqa: E402
from ecdsim.dynamics import (  # noqa: E402
    DynamicParameters,
    DynamicProblem,
    Rolloff,
    Thermal,
    solve_dynamic,
)
from ecdsim.dynamics.damping import KlossEddy  # noqa: E402
from ecdsim.model import (  # noqa: E402
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    TabulatedSpring,
)
from harness import Case, Notes, max_relative_difference  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "paper_cc16.toml"
DYNAMIC_EXAMPLE = ROOT / "examples" / "paper_cc16_dynamic.toml"
MSL_BRAKE = ROOT / "validation" / "configs" / "msl_eddy_current_brake.toml"
SEED = 20240612
SPREAD = 0.10
LOAD_INERTIA = 5.0  # [kg*m^2], issue 3
LSODA_RTOL, LSODA_ATOL = 1e-10, 1e-12  # the batch baselines
# Both sides solve the linear model to ~1e-9 or better (ecdsim exactly, in closed form).
AGREEMENT_LINEAR = 1e-6
# Both sides integrate the nonlinear models numerically (ecdsim at rtol 1e-8): agreement
# is bounded by that tolerance.
AGREEMENT_NONLINEAR = 1e-5
# Illustrative nonlinear settings: omega_peak = 60 rad/s puts the damper (380:1, up to
# ~44 rad/s at the high-speed shaft) well into its roll-off; 0.2 J/K with 100 K/W heats
# it by several kelvin.
ROLLOFF = Rolloff(peak_speed=60.0, resistivity_coefficient=0.0039)
THERMAL = Thermal(heat_capacity=0.2, thermal_resistance=100.0)

Floats = NDArray[np.float64]


@dataclass(frozen=True)
class Batch:
    """Randomised cases: the system of arrays, per-case temperatures and input-shaft values."""

    system: DeploymentSystem
    temperatures: Floats
    damping: Floats  # BECD_T [N*m*s/rad]
    friction: Floats  # FECD_T + FS_T [N*m]
    start_torque: Floats
    end_torque: Floats
    travel: float
    gear_ratio: float
    damper_rate: Floats  # BD [N*m*s/rad]
    gearbox_rate: Floats  # BG [N*m*s/rad]
    damper_coefficient: float
    reference_temperature: float


def make_batch(n: int, rng: np.random.Generator) -> Batch:
    """The paper example with +-10 % uniform spreads, as model objects holding arrays."""
    config = load_config(EXAMPLE)
    base = config.system
    damper, gearbox, load = base.ecd.damper, base.ecd.gearbox, base.load
    spring, fs_law = load.spring, load.system_friction
    assert isinstance(spring, LinearSpring)
    assert isinstance(fs_law, LinearTemperatureLaw)
    assert gearbox.damping_fraction is not None

    def spread(value: float) -> Floats:
        return float(value) * rng.uniform(1.0 - SPREAD, 1.0 + SPREAD, n)

    system = DeploymentSystem(
        ecd=Ecd(
            HighSpeedDamper(
                damping_rate=spread(float(damper.damping_rate)),
                coulomb_friction=spread(float(damper.coulomb_friction)),
                lubrication_friction=damper.lubrication_friction,
                reference_temperature=damper.reference_temperature,
                damping_temperature_coefficient=damper.damping_temperature_coefficient,
            ),
            Gearbox(
                ratio=gearbox.ratio,
                coulomb_friction=spread(float(gearbox.coulomb_friction)),
                damping_fraction=gearbox.damping_fraction,
            ),
        ),
        load=Load(
            spring=LinearSpring(
                spread(float(spring.start_torque)), spread(float(spring.end_torque))
            ),
            travel=load.travel,
            system_friction=LinearTemperatureLaw(fs_law.slope, spread(float(fs_law.at_0c))),
        ),
        name=base.name,
    )
    temps = np.asarray(config.temperatures, dtype=float)[np.arange(n) % len(config.temperatures)]
    state = system.ecd.at(temps)
    fs = system.load.system_friction(temps)
    _, torques = system.load.spring.breakpoints(system.load.travel, temps)
    return Batch(
        system=system,
        temperatures=temps,
        damping=np.asarray(state.ecd_damping_rate, dtype=float),
        friction=np.asarray(state.ecd_friction + fs, dtype=float),
        start_torque=np.asarray(torques[0], dtype=float),
        end_torque=np.asarray(torques[-1], dtype=float),
        travel=float(load.travel),
        gear_ratio=float(gearbox.ratio),
        damper_rate=np.asarray(system.ecd.damper.damping_rate, dtype=float),
        gearbox_rate=np.asarray(state.gearbox_damping_rate, dtype=float) * np.ones(n),
        damper_coefficient=float(damper.damping_temperature_coefficient),
        reference_temperature=float(damper.reference_temperature),
    )


def _lsoda(
    rhs: Callable[[float, Floats], Floats],
    y0: Sequence[float],
    travel: float,
    rtol: float = LSODA_RTOL,
    atol: float = LSODA_ATOL,
    method: str = "LSODA",
) -> float:
    """Deployment time by solve_ivp (LSODA) with a terminal event (inf if never)."""

    def arrive(_t: float, y: Floats) -> float:
        return float(y[0]) - travel

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = 1  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 1e4), y0, method=method, rtol=rtol, atol=atol, events=arrive)
    return float(sol.t_events[0][0]) if len(sol.t_events[0]) else math.inf


RHS = Callable[[float, Floats], Floats]


def _linear_rhs(ts: float, k: float, friction: float, b: float) -> RHS:
    def rhs(_t: float, y: Floats) -> Floats:
        return np.array([y[1], (ts - k * y[0] - friction - b * y[1]) / LOAD_INERTIA])

    return rhs


def _rolloff_rhs(
    ts: float, k: float, friction: float, n: float, bg: float, peak: float, tp: float
) -> RHS:
    def rhs(_t: float, y: Floats) -> Floats:
        x = n * y[1] / peak
        torque = n * (2 * tp * x / (1 + x * x) + bg * n * y[1])
        return np.array([y[1], (ts - k * y[0] - friction - torque) / LOAD_INERTIA])

    return rhs


def _heating_rhs(
    ts: float,
    k: float,
    friction: float,
    n: float,
    bg: float,
    bd: float,
    coefficient: float,
    t_ref: float,
    temp0: float,
) -> RHS:
    def rhs(_t: float, y: Floats) -> Floats:
        bd_t = bd * (1 + coefficient * (y[2] - t_ref))  # Eq. 1 at the damper's temperature
        torque = n * n * (bd_t + bg) * y[1]
        power = bd_t * (n * y[1]) ** 2
        heat = (power - (y[2] - temp0) / THERMAL.thermal_resistance) / THERMAL.heat_capacity
        return np.array([y[1], (ts - k * y[0] - friction - torque) / LOAD_INERTIA, heat])

    return rhs


def reference_times(
    batch: Batch,
    count: int,
    model: str,
    rtol: float = LSODA_RTOL,
    atol: float = LSODA_ATOL,
    method: str = "LSODA",
) -> Floats:
    """The LSODA loop over the first ``count`` cases of the batch: deployment times.

    The right-hand sides are written here from the equations (docs/dynamics.md), with the
    per-case input-shaft values of :func:`make_batch`.
    """
    travel, n = batch.travel, batch.gear_ratio
    peak_torque = batch.damper_rate * ROLLOFF.peak_speed / 2.0  # Kloss slope BD at T_ref
    out = np.empty(count)
    for i in range(count):
        ts, te, friction = batch.start_torque[i], batch.end_torque[i], batch.friction[i]
        k = (ts - te) / travel
        temp0 = batch.temperatures[i]
        bg = float(batch.gearbox_rate[i])
        if model == "linear":
            rhs = _linear_rhs(ts, k, friction, batch.damping[i])
            out[i] = _lsoda(rhs, [0.0, 0.0], travel, rtol, atol, method)
        elif model == "rolloff":
            peak = ROLLOFF.peak_speed * (1 + ROLLOFF.resistivity_coefficient * (temp0 - 25.0))
            rhs = _rolloff_rhs(ts, k, friction, n, bg, float(peak), float(peak_torque[i]))
            out[i] = _lsoda(rhs, [0.0, 0.0], travel, rtol, atol, method)
        else:
            rhs = _heating_rhs(
                ts,
                k,
                friction,
                n,
                bg,
                float(batch.damper_rate[i]),
                batch.damper_coefficient,
                batch.reference_temperature,
                temp0,
            )
            out[i] = _lsoda(rhs, [0.0, 0.0, temp0], travel, rtol, atol, method)
    return out


def dynamic_times(batch: Batch, model: str, count: int, rtol: float = 1e-8) -> Floats:
    """ecdsim's dynamic method on the first ``count`` cases, one predict call: times."""
    params = DynamicParameters(
        load_inertia=LOAD_INERTIA,
        rolloff=ROLLOFF if model == "rolloff" else None,
        thermal=THERMAL if model == "heating" else None,
        rtol=rtol,
    )
    system = batch.system if count == batch.temperatures.size else _subset(batch.system, count)
    prediction = predict(system, batch.temperatures[:count], ["dynamic"], dynamics=params)
    return np.asarray(prediction.solutions["dynamic"].deployment_time, dtype=float)


def _subset(system: DeploymentSystem, count: int) -> DeploymentSystem:
    d, g, load = system.ecd.damper, system.ecd.gearbox, system.load
    spring = load.spring
    law = load.system_friction
    assert isinstance(spring, LinearSpring)
    assert isinstance(law, LinearTemperatureLaw)

    def head(value: object) -> Floats:
        return np.asarray(value, dtype=float)[:count]

    return DeploymentSystem(
        Ecd(
            HighSpeedDamper(
                head(d.damping_rate),
                head(d.coulomb_friction),
                d.lubrication_friction,
                d.reference_temperature,
                d.damping_temperature_coefficient,
            ),
            Gearbox(g.ratio, head(g.coulomb_friction), damping_fraction=g.damping_fraction),
        ),
        Load(
            LinearSpring(head(spring.start_torque), head(spring.end_torque)),
            load.travel,
            LinearTemperatureLaw(law.slope, head(law.at_0c)),
        ),
        system.name,
    )


ACCURACY_CASES = 3  # cases of a batch whose error both sides report


def batch_errors(
    batch: Batch, model: str, rtols: Sequence[float]
) -> tuple[dict[float, float], float]:
    """ecdsim's error at each rtol and LSODA's (rtol 1e-10), against Radau at rtol 1e-12,
    over the first :data:`ACCURACY_CASES` cases of the batch (not timed)."""
    exact = reference_times(batch, ACCURACY_CASES, model, 1e-12, 1e-14, "Radau")
    mine = {
        rtol: max_relative_difference(dynamic_times(batch, model, ACCURACY_CASES, rtol), exact)
        for rtol in rtols
    }
    return mine, max_relative_difference(reference_times(batch, ACCURACY_CASES, model), exact)


def equal_accuracy_rtol(batch: Batch, model: str) -> float:
    """The loosest of ecdsim's rtol 1e-6 .. 1e-8 whose error is no larger than LSODA's."""
    ladder = (1e-6, 3e-7, 1e-7, 3e-8, 1e-8)
    mine, lsoda = batch_errors(batch, model, ladder)
    good = [rtol for rtol in ladder if mine[rtol] <= lsoda]
    return max(good) if good else min(ladder)


def _batch_case(
    model: str, batch: Batch, n: int, n_reference: int, rtol: float = 1e-8
) -> Case[Any]:
    label = {"linear": "linear (closed form)", "rolloff": "roll-off", "heating": "heating"}
    goal = "goal >= 100x LSODA per deployment" if model != "linear" else "no goal"
    setting = "" if model == "linear" else f", rtol {rtol:g}"

    def ours() -> Floats:
        return dynamic_times(batch, model, n, rtol)

    def theirs() -> Floats:
        return reference_times(batch, n_reference, model)

    def agree(a: Floats, b: Floats) -> float:
        return max_relative_difference(a[:n_reference], b)

    def accuracy() -> Notes:
        errors, lsoda = batch_errors(batch, model, (rtol,))
        mine = errors[rtol]
        return Notes(
            lines=(
                f"error against Radau at rtol 1e-12 (first {ACCURACY_CASES} cases): ecdsim "
                f"{mine:.1e}, LSODA {lsoda:.1e}",
            ),
            data={"ecdsim_error": mine, "lsoda_error": lsoda},
        )

    return Case(
        name=f"dynamic batch, {label[model]}{setting}",
        ecdsim=ours,
        baseline=theirs,
        baseline_name=f"a solve_ivp LSODA loop (rtol {LSODA_RTOL:g}, atol {LSODA_ATOL:g}) over "
        f"the first {n_reference} cases; {goal}",
        agree=agree,
        tolerance=AGREEMENT_LINEAR if model == "linear" else AGREEMENT_NONLINEAR,
        items=n,
        baseline_items=n_reference,
        item_name="deployments",
        notes=accuracy,
        description=f"predict(..., ['dynamic']) on {n:,} cases (+-10 %, 3 temperatures), "
        f"{label[model]}{setting}, against LSODA per case",
    )


# ---------------------------------------------------------------------------------------
# one deployment


@dataclass(frozen=True)
class Single:
    """One nonlinear deployment: ecdsim's call, its baseline's equations, the reference."""

    name: str
    system: DeploymentSystem
    temperature: float
    params: DynamicParameters
    rhs: Callable[[float, Floats], Floats]
    y0: tuple[float, ...]
    travel: float  # the event's angle (inf: run to stop_time and compare the angle)
    stop_time: float

    def ecdsim(self) -> float:
        prediction = predict(self.system, [self.temperature], ["dynamic"], dynamics=self.params)
        result = prediction.solutions["dynamic"].result  # type: ignore[attr-defined]
        if math.isfinite(self.travel):
            return float(result.deployment_time[0])
        return float(result.final_angle[0])

    def scipy(self, rtol: float, method: str = "LSODA", atol: float = 1e-12) -> float:
        if math.isfinite(self.travel):
            return _lsoda(self.rhs, self.y0, self.travel, rtol, atol, method)
        sol = solve_ivp(
            self.rhs, (0.0, self.stop_time), self.y0, method=method, rtol=rtol, atol=atol
        )
        return float(sol.y[0, -1])


def _engaged_problem(system: DeploymentSystem, temp: float, params: DynamicParameters) -> Any:
    solution = predict(system, [temp], ["dynamic"], dynamics=params).solutions["dynamic"]
    problem = solution.problem  # type: ignore[attr-defined]
    assert isinstance(problem, DynamicProblem)
    return problem


def _kloss_heating_rhs(problem: DynamicProblem) -> Callable[[float, Floats], Floats]:
    """State [phi, omega, T_d]; Kloss law with omega_peak(T_d), lumped heat balance."""
    eddy = problem.eddy
    assert isinstance(eddy, KlossEddy)

    def scalar(value: object) -> float:
        return float(np.ravel(np.asarray(value, dtype=float))[0])

    j = scalar(problem.total_inertia)
    friction = scalar(problem.ecd_friction) + scalar(problem.system_friction)
    n, bg = scalar(problem.gear_ratio), scalar(problem.gearbox_damping_rate)
    ts = scalar(problem.torques[0])
    k = (ts - scalar(problem.torques[-1])) / scalar(problem.travel)
    tp, wp = scalar(eddy.peak_torque), scalar(eddy.reference_peak_speed)
    alpha, t_ref = scalar(eddy.resistivity_coefficient), scalar(eddy.reference_temperature)
    cap, resistance = scalar(problem.heat_capacity), scalar(problem.thermal_resistance)
    ambient = scalar(problem.ambient_temperature)

    def rhs(_t: float, y: Floats) -> Floats:
        w_d = n * y[1]
        peak = wp * (1.0 + alpha * (y[2] - t_ref))
        eddy_torque = 2.0 * tp * w_d * peak / (w_d * w_d + peak * peak)
        torque = n * (eddy_torque + bg * w_d)
        loss = (y[2] - ambient) / resistance if math.isfinite(resistance) else 0.0
        return np.array(
            [
                y[1],
                (ts - k * y[0] - friction - torque) / j,
                (eddy_torque * w_d - loss) / cap,
            ]
        )

    return rhs


def singles() -> list[Single]:
    """The two single nonlinear deployments of the module docstring."""
    paper = load_config(DYNAMIC_EXAMPLE)
    dynamics = paper.spec.dynamics()
    assert dynamics is not None
    params = dataclasses.replace(dynamics, rolloff=ROLLOFF, thermal=THERMAL)
    problem = _engaged_problem(paper.system, 25.0, params)
    paper_case = Single(
        name="paper, roll-off + heating",
        system=paper.system,
        temperature=25.0,
        params=params,
        rhs=_kloss_heating_rhs(problem),
        y0=(0.0, 0.0, 25.0),
        travel=float(np.ravel(problem.travel)[0]),
        stop_time=math.inf,
    )
    msl = load_config(MSL_BRAKE)
    msl_params = msl.spec.dynamics()
    assert msl_params is not None
    msl_problem = _engaged_problem(msl.system, 20.0, msl_params)
    brake = Single(
        name="MSL brake spin-down 1 s",
        system=msl.system,
        temperature=20.0,
        params=msl_params,
        rhs=_kloss_heating_rhs(msl_problem),
        y0=(0.0, float(np.ravel(msl_problem.initial_speed)[0]), 20.0),
        travel=math.inf,
        stop_time=msl_params.stop_time,
    )
    return [paper_case, brake]


LSODA_LADDER = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
# A one-deployment sample is a block of this many calls (timeit's number): ecdsim's call
# takes 0.2-0.4 ms, LSODA's 1-5 ms, so a block lasts several ms on either side and a
# sample is not one call right after the other side's (cold caches; a note gives that
# figure too, from SINGLE_CALLS alternating pairs of single calls).
SINGLE_NUMBER = 20
SINGLE_CALLS = 41


def _single_case(single: Single) -> Case[float]:
    """ecdsim at its default rtol against LSODA at the loosest rtol as accurate."""
    reference = single.scipy(1e-12, "Radau", 1e-14)
    ours = single.ecdsim()
    error = abs(ours - reference) / abs(reference)
    errors = {rtol: abs(single.scipy(rtol) - reference) / abs(reference) for rtol in LSODA_LADDER}
    matching = [rtol for rtol, e in errors.items() if e <= error]
    rtol = max(matching) if matching else min(LSODA_LADDER)

    def notes() -> Notes:
        problem = _engaged_problem(single.system, single.temperature, single.params)
        solver = []
        for _ in range(9):
            start = time.perf_counter()
            solve_dynamic(problem, record=False)
            solver.append(time.perf_counter() - start)
        # The same pair timed one call at a time, alternating (no blocks): each call then
        # runs right after the other side's, in caches that side has just filled.
        alone: dict[str, list[float]] = {"ecdsim": [], "lsoda": []}
        for i in range(SINGLE_CALLS):
            pair = (("ecdsim", single.ecdsim), ("lsoda", lambda: single.scipy(rtol)))
            for side, call in pair if i % 2 == 0 else pair[::-1]:
                alone[side].append(harness.timed_once(call))
        one_by_one = statistics.median(
            b / a for a, b in zip(alone["ecdsim"], alone["lsoda"], strict=True)
        )
        lines = (
            f"error against Radau at rtol 1e-12: ecdsim (rtol {single.params.rtol:g}) "
            f"{error:.1e}, LSODA (rtol {rtol:g}) {errors[rtol]:.1e}; LSODA at rtol 1e-8: "
            f"{errors[1e-8]:.1e}",
            f"ecdsim's solver alone (solve_dynamic on the built problem, not interleaved): "
            f"min {1e3 * min(solver):.2f} ms, median {1e3 * statistics.median(solver):.2f} ms",
            f"one call at a time instead of blocks of {SINGLE_NUMBER} ({SINGLE_CALLS} "
            f"alternating pairs): ecdsim median {1e3 * statistics.median(alone['ecdsim']):.3f} "
            f"ms, LSODA {1e3 * statistics.median(alone['lsoda']):.3f} ms, ratio "
            f"{one_by_one:.2f}x",
        )
        return Notes(
            lines=lines,
            data={
                "ecdsim_error": error,
                "lsoda_rtol": rtol,
                "lsoda_errors": {str(r): e for r, e in errors.items()},
                "one_call_ratio": one_by_one,
            },
        )

    return Case(
        name=f"1 deployment: {single.name}",
        ecdsim=single.ecdsim,
        baseline=lambda: single.scipy(rtol),
        baseline_name=f"solve_ivp LSODA at rtol {rtol:g} (the loosest of 1e-6..1e-12 as "
        "accurate as ecdsim), plain Python right-hand side; goal >= 5x",
        agree=lambda a, b: max_relative_difference(a, b),
        tolerance=AGREEMENT_NONLINEAR,
        repeats=15,
        number=SINGLE_NUMBER,
        notes=notes,
        description=f"predict(...) of one deployment ({single.name}) against one solve_ivp call",
    )


# ---------------------------------------------------------------------------------------
# tabulated spring


def _tabulated(points: int) -> tuple[DeploymentSystem, Floats, Floats]:
    config = load_config(EXAMPLE)
    base = config.system
    spring = base.load.spring
    assert isinstance(spring, LinearSpring)
    travel = float(base.load.travel)
    ts, te = float(spring.start_torque), float(spring.end_torque)
    angles = np.linspace(0.0, travel, points)
    torques = ts - (ts - te) * (angles / travel) ** 1.5  # a curved spring law, tabulated
    load = dataclasses.replace(
        base.load, spring=TabulatedSpring(tuple(angles.tolist()), tuple(torques.tolist()))
    )
    return DeploymentSystem(base.ecd, load, name="table"), angles, torques


def _tabulated_case(points: int, scaling: tuple[int, ...]) -> Case[float]:
    system, angles, torques = _tabulated(points)
    params = DynamicParameters(load_inertia=LOAD_INERTIA)
    problem = _engaged_problem(system, 25.0, params)
    friction = float(np.ravel(problem.ecd_friction)[0] + np.ravel(problem.system_friction)[0])
    damping = float(np.ravel(problem.damping_rate)[0])
    travel = float(angles[-1])

    def ours(system: DeploymentSystem = system) -> float:
        prediction = predict(system, [25.0], ["dynamic"], dynamics=params)
        return float(prediction.solutions["dynamic"].deployment_time[0])

    def rhs(_t: float, y: Floats) -> Floats:
        spring = np.interp(y[0], angles, torques)
        return np.array([y[1], (spring - friction - damping * y[1]) / LOAD_INERTIA])

    def notes() -> Notes:
        per_point = {}
        for size in scaling:
            bigger, _, _ = _tabulated(size)
            start = time.perf_counter()
            ours(bigger)
            per_point[size] = (time.perf_counter() - start) / size
        # Microseconds: crossed in compiled code, a breakpoint costs a few, which "0.00 ms"
        # hid.
        text = ", ".join(f"P = {p:,}: {1e6 * t:.1f} us" for p, t in per_point.items())
        return Notes(
            lines=(f"ecdsim per breakpoint (one run each): {text}",),
            data={f"ms_per_breakpoint_P{p}": 1e3 * t for p, t in per_point.items()},
        )

    return Case(
        name=f"tabulated spring, P = {points:,}",
        ecdsim=ours,
        baseline=lambda: _lsoda(rhs, (0.0, 0.0), travel),
        baseline_name=f"solve_ivp LSODA (rtol {LSODA_RTOL:g}) on np.interp of the table",
        agree=lambda a, b: max_relative_difference(a, b),
        tolerance=AGREEMENT_LINEAR,
        notes=notes if scaling else None,
        description="one deployment over a spring table (breakpoints crossed compiled)",
    )


def cases(quick: bool) -> list[Case[Any]]:
    """Single nonlinear deployments, batches, a tabulated spring (quick: smaller sizes)."""
    n_linear, n_linear_reference = (10_000, 50) if quick else (100_000, 200)
    n_nonlinear, n_nonlinear_reference = (1_000, 10) if quick else (10_000, 30)
    batch = make_batch(max(n_linear, n_nonlinear), np.random.default_rng(SEED))
    out: list[Case[Any]] = [_single_case(single) for single in singles()]
    for model in ("rolloff", "heating"):
        # ecdsim's default rtol, and the loosest rtol at which it is as accurate as the
        # LSODA baseline (equal accuracy), when that is a different one.
        rtols = sorted({1e-8, equal_accuracy_rtol(batch, model)})
        out += [
            _batch_case(model, batch, n_nonlinear, n_nonlinear_reference, rtol) for rtol in rtols
        ]
    out += [
        _batch_case("linear", batch, n_linear, n_linear_reference),
        _tabulated_case(1_000, () if quick else (2_000, 10_000)),
    ]
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run this file's cases alone and print their table (exit 1 if an agreement fails)."""
    return harness.run_alone(cases, __doc__, argv, quick_help="smaller sizes")


if __name__ == "__main__":
    raise SystemExit(main())

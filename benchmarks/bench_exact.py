"""Exact-solver throughput: vectorised deployments per second against a plain Python loop.

One million parameter sets are drawn uniformly within +-10 % of the paper example
(``examples/paper_cc16.toml``) with an explicit, seeded ``numpy.random.Generator``: BD,
FD, FL slope and value at 0 degC, gear ratio, BG fraction, FG, start and end spring
torque, travel, FS slope and value at 0 degC. Each set is solved at the example's
temperatures (-40, +25, +100 degC), so one "deployment" is one (parameter set,
temperature) pair.

Two vectorised paths are timed, as a user would write them:

* ``predict``: model objects holding arrays -> ``ecdsim.deployment.predict(system,
  temperatures, methods=("exact",))`` (includes the domain check and the warnings);
* ``core``: the same objects -> ``Ecd.at`` -> ``build_problem`` (spring breakpoints,
  FS_T, ``QuasiStaticProblem``) -> ``EXACT.solve``.

The same two paths are then timed as a plain Python loop over a sample of the same sets
(one scalar system per iteration, all temperatures per call), the loop's results are
checked against the vectorised ones, and the ratio of throughputs is reported.

Run on one core: the BLAS thread variables are set before NumPy is imported and, where
the OS allows it, the process is pinned to one CPU.
"""

from __future__ import annotations

import os

# One core: BLAS/OpenMP pools are sized when NumPy is first imported, so set these first.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402 - after the thread settings above, on purpose
import cProfile  # noqa: E402
import dataclasses  # noqa: E402
import io  # noqa: E402
import pstats  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from collections.abc import Callable, Sequence  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, TypeVar  # noqa: E402

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from ecdsim.config import load_config  # noqa: E402
from ecdsim.deployment import build_problem, collect_warnings, predict  # noqa: E402
from ecdsim.model import (  # noqa: E402
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    Param,
)
from ecdsim.physics.quasistatic import locate_stall, log_mean  # noqa: E402
from ecdsim.solvers import EXACT, DeploymentSolution  # noqa: E402
from ecdsim.solvers.exact import segment_start_times  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_cc16.toml"
GOAL_DEPLOYMENTS_PER_S = 5e6  # issue 2, "Performance"
SEED = 20240611
SPREAD = 0.10  # +-10 % uniform around the paper example
# The loop and the vectorised path evaluate the same formulas on the same float64 inputs;
# only NumPy's SIMD (array) and scalar code paths for log/exp differ, by a few ulp, so
# anything above 1e-12 relative would be a real disagreement.
AGREEMENT_TOLERANCE = 1e-12
SCALING_SIZES = (100, 1_000, 10_000, 100_000)

T = TypeVar("T")
Floats = NDArray[np.float64]


@dataclass(frozen=True)
class Parameters:
    """The randomised parameters of one deployment system (scalars or 1-D arrays), SI."""

    damping_rate: Param  # BD [N*m*s/rad]
    damper_friction: Param  # FD [N*m]
    lubrication_slope: Param  # FL slope [N*m/K]
    lubrication_at_0c: Param  # FL at 0 degC [N*m]
    gear_ratio: Param  # N [-]
    gearbox_damping_fraction: Param  # BG / BD [-]
    gearbox_friction: Param  # FG [N*m]
    start_torque: Param  # Ts [N*m]
    end_torque: Param  # Te [N*m]
    travel: Param  # [rad]
    system_friction_slope: Param  # FS slope [N*m/K]
    system_friction_at_0c: Param  # FS at 0 degC [N*m]

    def subset(self, stop: int) -> Parameters:
        """The first ``stop`` parameter sets (arrays only)."""
        return Parameters(
            **{f.name: np.asarray(getattr(self, f.name))[:stop] for f in dataclasses.fields(self)}
        )

    def scalar_sets(self, count: int) -> list[Parameters]:
        """The first ``count`` sets as scalar Parameters (plain Python floats)."""
        columns = {
            f.name: np.asarray(getattr(self, f.name))[:count].tolist()
            for f in dataclasses.fields(self)
        }
        return [Parameters(**{k: v[i] for k, v in columns.items()}) for i in range(count)]


@dataclass(frozen=True)
class Example:
    """The paper example: its system (for the fixed values), parameters and temperatures."""

    system: DeploymentSystem
    parameters: Parameters
    temperatures: tuple[float, ...]


def load_example(path: Path = EXAMPLE) -> Example:
    """Read the paper example and pull out the parameters the benchmark randomises."""
    config = load_config(path)
    system = config.system
    damper, gearbox, load = system.ecd.damper, system.ecd.gearbox, system.load
    lubrication, friction, spring = damper.lubrication_friction, load.system_friction, load.spring
    if not (
        isinstance(lubrication, LinearTemperatureLaw)
        and isinstance(friction, LinearTemperatureLaw)
        and isinstance(spring, LinearSpring)
        and gearbox.damping_fraction is not None
    ):
        raise SystemExit(
            f"{path}: the benchmark needs linear friction laws, a linear spring and a "
            "gearbox damping_fraction"
        )
    base = Parameters(
        damping_rate=float(damper.damping_rate),
        damper_friction=float(damper.coulomb_friction),
        lubrication_slope=float(lubrication.slope),
        lubrication_at_0c=float(lubrication.at_0c),
        gear_ratio=float(gearbox.ratio),
        gearbox_damping_fraction=float(gearbox.damping_fraction),
        gearbox_friction=float(gearbox.coulomb_friction),
        start_torque=float(spring.start_torque),
        end_torque=float(spring.end_torque),
        travel=float(load.travel),
        system_friction_slope=float(friction.slope),
        system_friction_at_0c=float(friction.at_0c),
    )
    return Example(system=system, parameters=base, temperatures=config.temperatures)


def sample_parameters(
    base: Parameters, count: int, spread: float, rng: np.random.Generator
) -> Parameters:
    """``count`` sets, each parameter uniform in ``base * [1 - spread, 1 + spread]``."""
    return Parameters(
        **{
            f.name: float(getattr(base, f.name)) * rng.uniform(1.0 - spread, 1.0 + spread, count)
            for f in dataclasses.fields(base)
        }
    )


def make_system(fixed: DeploymentSystem, p: Parameters) -> DeploymentSystem:
    """A deployment system holding ``p`` (scalars or arrays); other values from ``fixed``."""
    damper = fixed.ecd.damper
    spring = fixed.load.spring
    assert isinstance(spring, LinearSpring)  # checked by load_example
    return DeploymentSystem(
        ecd=Ecd(
            damper=HighSpeedDamper(
                damping_rate=p.damping_rate,
                coulomb_friction=p.damper_friction,
                lubrication_friction=LinearTemperatureLaw(p.lubrication_slope, p.lubrication_at_0c),
                reference_temperature=damper.reference_temperature,
                damping_temperature_coefficient=damper.damping_temperature_coefficient,
            ),
            gearbox=Gearbox(
                ratio=p.gear_ratio,
                coulomb_friction=p.gearbox_friction,
                damping_fraction=p.gearbox_damping_fraction,
            ),
        ),
        load=Load(
            spring=LinearSpring(
                p.start_torque,
                p.end_torque,
                spring.temperature_coefficient,
                spring.reference_temperature,
            ),
            travel=p.travel,
            system_friction=LinearTemperatureLaw(p.system_friction_slope, p.system_friction_at_0c),
        ),
        name=fixed.name,
    )


def solve_predict(
    fixed: DeploymentSystem, p: Parameters, temperatures: Floats
) -> DeploymentSolution:
    """The user-level path: objects -> ``predict(..., methods=("exact",))``."""
    prediction = predict(make_system(fixed, p), temperatures, methods=("exact",))
    return prediction.solutions["exact"]


def solve_core(fixed: DeploymentSystem, p: Parameters, temperatures: Floats) -> DeploymentSolution:
    """The lower-level path: objects -> ``Ecd.at`` -> ``build_problem`` -> ``EXACT.solve``."""
    system = make_system(fixed, p)
    state = system.ecd.at(temperatures)
    problem, _ = build_problem(system, state, temperatures)
    return EXACT.solve(problem)


Solve = Callable[[DeploymentSystem, Parameters, Floats], DeploymentSolution]
PATHS: dict[str, tuple[str, Solve]] = {
    "predict": ('predict(system, T, methods=("exact",))', solve_predict),
    "core": ("Ecd.at + build_problem + EXACT.solve", solve_core),
}


@dataclass(frozen=True)
class Timing:
    """Wall-clock times of one call: the first (cold) call and the timed repeats [s]."""

    cold_s: float
    times_s: tuple[float, ...]

    @property
    def median_s(self) -> float:
        """Median of the timed repeats [s]."""
        return statistics.median(self.times_s)

    @property
    def best_s(self) -> float:
        """Fastest timed repeat [s]."""
        return min(self.times_s)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "cold_s": self.cold_s,
            "median_s": self.median_s,
            "best_s": self.best_s,
            "times_s": list(self.times_s),
        }


def measure(call: Callable[[], T], repeats: int) -> tuple[Timing, T]:
    """Time a first (cold) call of ``call``, then ``repeats`` more; return the last result.

    The cold call pays one-off costs (first touch of fresh memory, caches) and is reported
    apart; the medians quoted everywhere are of the repeats.
    """
    start = time.perf_counter()
    result = call()
    cold = time.perf_counter() - start
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return Timing(cold_s=cold, times_s=tuple(times)), result


def autorange(call: Callable[[], object], min_total_s: float = 0.3, max_calls: int = 500) -> float:
    """Median time of one call [s], over at least 3 calls and about ``min_total_s``."""
    call()  # warm-up
    times: list[float] = []
    while len(times) < 3 or (sum(times) < min_total_s and len(times) < max_calls):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


@dataclass(frozen=True)
class Agreement:
    """How closely the loop reproduces the vectorised results."""

    compared_deployments: int
    stalled_deployments: int
    max_relative_difference: float
    worst_field: str
    stalled_identical: bool
    infinities_identical: bool

    @property
    def ok(self) -> bool:
        """True when every field agrees within :data:`AGREEMENT_TOLERANCE`."""
        return (
            self.stalled_identical
            and self.infinities_identical
            and self.max_relative_difference <= AGREEMENT_TOLERANCE
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "compared_deployments": self.compared_deployments,
            "stalled_deployments": self.stalled_deployments,
            "max_relative_difference": self.max_relative_difference,
            "worst_field": self.worst_field,
            "stalled_identical": self.stalled_identical,
            "infinities_identical": self.infinities_identical,
            "tolerance": AGREEMENT_TOLERANCE,
            "ok": self.ok,
        }


def compare(vectorised: DeploymentSolution, loop: Sequence[DeploymentSolution]) -> Agreement:
    """Compare the loop's per-set solutions with the first columns of the vectorised one."""
    count = len(loop)
    pairs = {
        "deployment_time": (
            vectorised.deployment_time,
            [s.deployment_time for s in loop],
        ),
        "start_speed": (vectorised.start_speed, [s.start_speed for s in loop]),
        "end_speed": (vectorised.end_speed, [s.end_speed for s in loop]),
        "max_speed": (vectorised.max_speed, [s.max_speed for s in loop]),
    }
    worst, worst_field, infinities = 0.0, "-", True
    for name, (vec_full, per_set) in pairs.items():
        vec = vec_full[..., :count]
        looped = np.stack([np.asarray(x).reshape(vec.shape[:-1]) for x in per_set], axis=-1)
        infinities &= bool(np.array_equal(np.isinf(vec), np.isinf(looped)))
        finite = np.isfinite(vec) & np.isfinite(looped)
        scale = np.maximum(np.abs(looped[finite]), np.finfo(float).tiny)
        relative = np.abs(vec[finite] - looped[finite]) / scale
        largest = float(relative.max(initial=0.0))
        if largest > worst:
            worst, worst_field = largest, name
    stalled_vec = vectorised.stalled[..., :count]
    stalled_loop = np.stack([s.stalled.reshape(stalled_vec.shape[:-1]) for s in loop], axis=-1)
    return Agreement(
        compared_deployments=int(stalled_vec.size),
        stalled_deployments=int(np.count_nonzero(stalled_vec)),
        max_relative_difference=worst,
        worst_field=worst_field,
        stalled_identical=bool(np.array_equal(stalled_vec, stalled_loop)),
        infinities_identical=infinities,
    )


def identical(first: DeploymentSolution, second: DeploymentSolution) -> bool:
    """True when two solutions hold bit-identical arrays (NaN stall angles match NaN)."""
    pairs = [
        (first.deployment_time, second.deployment_time),
        (first.start_speed, second.start_speed),
        (first.end_speed, second.end_speed),
        (first.max_speed, second.max_speed),
        (first.stall_angle, second.stall_angle),
    ]
    return bool(
        all(np.array_equal(a, b, equal_nan=True) for a, b in pairs)
        and np.array_equal(first.stalled, second.stalled)
    )


def stage_breakdown(
    fixed: DeploymentSystem,
    p: Parameters,
    temperatures: Floats,
    repeats: int,
) -> list[dict[str, Any]]:
    """Median time of each step of ``predict`` at full size, each timed on its own [s]."""
    system = make_system(fixed, p)
    state = system.ecd.at(temperatures)
    problem, _ = build_problem(system, state, temperatures)
    net = problem.net_torques
    prediction = predict(system, temperatures, methods=("exact",))
    steps: list[tuple[str, int, Callable[[], object]]] = [
        ("predict (whole call)", 0, lambda: predict(system, temperatures, methods=("exact",))),
        ("model objects from arrays", 1, lambda: make_system(fixed, p)),
        ("Ecd.at (Eq. 1-4)", 1, lambda: system.ecd.at(temperatures)),
        (
            "build_problem (breakpoints, FS_T)",
            1,
            lambda: build_problem(system, state, temperatures),
        ),
        ("EXACT.solve", 1, lambda: EXACT.solve(problem)),
        ("problem.net_torques", 2, lambda: problem.net_torques),
        ("locate_stall", 2, lambda: locate_stall(problem.angles, net)),
        ("segment_start_times", 2, lambda: segment_start_times(problem)),
        ("log_mean (inside it)", 3, lambda: log_mean(net[0], net[1])),
        ("collect_warnings", 1, lambda: collect_warnings(prediction)),
    ]
    rows = []
    whole = 0.0
    for label, depth, call in steps:
        timing, _ = measure(call, repeats)
        if depth == 0:
            whole = timing.median_s
        rows.append(
            {
                "stage": label,
                "depth": depth,
                "median_s": timing.median_s,
                "share_of_predict": timing.median_s / whole if whole > 0.0 else None,
            }
        )
    return rows


def profile_predict(fixed: DeploymentSystem, p: Parameters, temperatures: Floats) -> str:
    """cProfile of one ``predict`` call, top 20 functions by own time."""
    system = make_system(fixed, p)
    predict(system, temperatures, methods=("exact",))  # warm-up
    profiler = cProfile.Profile()
    profiler.enable()
    predict(system, temperatures, methods=("exact",))
    profiler.disable()
    stream = io.StringIO()
    pstats.Stats(profiler, stream=stream).sort_stats("tottime").print_stats(20)
    return stream.getvalue()


def predict_memory(
    fixed: DeploymentSystem, p: Parameters, temperatures: Floats
) -> dict[str, float]:
    """Peak and retained memory of one ``predict`` call, traced by tracemalloc [bytes].

    NumPy reports its array buffers to tracemalloc, so this counts the temporaries of
    the call (peak) and the size of the returned Prediction (retained).
    """
    system = make_system(fixed, p)
    tracemalloc.start()
    try:
        prediction = predict(system, temperatures, methods=("exact",))
        retained, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    deployments = prediction.problem.friction.size
    return {
        "peak_bytes": float(peak),
        "retained_bytes": float(retained),
        "peak_bytes_per_deployment": peak / deployments,
        "retained_bytes_per_deployment": retained / deployments,
    }


def pin_to_one_cpu() -> int | None:
    """Pin this process to one CPU where the OS allows it; return that CPU's number."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    return cpu


def peak_memory_mib() -> float | None:
    """Peak resident memory of this process [MiB], where the OS reports it."""
    if sys.platform == "win32":
        return None
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 1024.0 if sys.platform != "darwin" else peak / 2**20


def run(
    sets: int = 1_000_000,
    loop_sets: int = 2_000,
    repeats: int = 5,
    seed: int = SEED,
    profile: bool = False,
) -> dict[str, Any]:
    """Run the throughput benchmark and return its results (JSON-ready)."""
    pinned = pin_to_one_cpu()
    example = load_example()
    rng = np.random.default_rng(seed)
    params = sample_parameters(example.parameters, sets, SPREAD, rng)
    # Temperatures down axis 0, parameter sets along axis 1: a (n_T, sets) batch.
    temps_column = np.asarray(example.temperatures, dtype=float)[:, np.newaxis]
    temps_row = np.asarray(example.temperatures, dtype=float)
    n_temps = temps_row.size
    deployments = sets * n_temps
    loop_count = min(loop_sets, sets)
    scalar_sets = params.scalar_sets(loop_count)
    fixed = example.system

    vectorised: dict[str, Any] = {}
    looped: dict[str, Any] = {}
    agreement: dict[str, Agreement] = {}
    solutions: dict[str, DeploymentSolution] = {}
    for key, (label, solve) in PATHS.items():
        timing, solution = measure(partial(solve, fixed, params, temps_column), repeats)
        solutions[key] = solution
        vectorised[key] = {
            "label": label,
            **timing.to_dict(),
            "deployments_per_s": deployments / timing.median_s,
            "deployments_per_s_best": deployments / timing.best_s,
        }

        def loop_once(s: Solve = solve) -> list[DeploymentSolution]:
            return [s(fixed, one, temps_row) for one in scalar_sets]

        loop_timing, loop_solutions = measure(loop_once, max(1, min(3, repeats)))
        loop_rate = loop_count * n_temps / loop_timing.median_s
        looped[key] = {
            "label": f"loop over sets: {label}",
            **loop_timing.to_dict(),
            "deployments_per_s": loop_rate,
            "per_set_us": 1e6 * loop_timing.median_s / loop_count,
            "speedup_of_vectorised": vectorised[key]["deployments_per_s"] / loop_rate,
        }
        agreement[key] = compare(solution, loop_solutions)

    stalled = solutions["predict"].stalled
    scaling = []
    for size in (s for s in SCALING_SIZES if s < sets):
        subset = params.subset(size)
        per_call = autorange(partial(solve_predict, fixed, subset, temps_column))
        scaling.append(
            {
                "parameter_sets": size,
                "deployments": size * n_temps,
                "median_s": per_call,
                "deployments_per_s": size * n_temps / per_call,
            }
        )
    scaling.append(
        {
            "parameter_sets": sets,
            "deployments": deployments,
            "median_s": vectorised["predict"]["median_s"],
            "deployments_per_s": vectorised["predict"]["deployments_per_s"],
        }
    )
    stages = stage_breakdown(fixed, params, temps_column, repeats)
    result: dict[str, Any] = {
        "parameter_sets": sets,
        "temperatures_C": list(example.temperatures),
        "deployments": deployments,
        "spread": SPREAD,
        "seed": seed,
        "repeats": repeats,
        "pinned_cpu": pinned,
        "source": str(EXAMPLE.relative_to(EXAMPLE.parents[1])),
        "vectorised": vectorised,
        "loop": {"parameter_sets": loop_count, **looped},
        "agreement": {key: a.to_dict() for key, a in agreement.items()},
        "paths_identical": identical(solutions["predict"], solutions["core"]),
        "stalled_fraction": float(np.mean(stalled)),
        "scaling": scaling,
        "stages": stages,
        "goal_deployments_per_s": GOAL_DEPLOYMENTS_PER_S,
        "meets_goal": vectorised["predict"]["deployments_per_s"] >= GOAL_DEPLOYMENTS_PER_S,
        "meets_goal_core": vectorised["core"]["deployments_per_s"] >= GOAL_DEPLOYMENTS_PER_S,
        "predict_memory": predict_memory(fixed, params, temps_column),
        "peak_memory_mib": peak_memory_mib(),
    }
    if profile:
        result["profile"] = profile_predict(fixed, params, temps_column)
    return result


def ok(result: dict[str, Any]) -> bool:
    """True when the correctness checks passed (the speed goal is reported, not enforced)."""
    return bool(all(a["ok"] for a in result["agreement"].values()) and result["paths_identical"])


def _rate(value: float) -> str:
    for scale, suffix in ((1e6, "M"), (1e3, "k")):
        if value >= scale:
            return f"{value / scale:.2f} {suffix}"
    return f"{value:.0f}"


def summary(result: dict[str, Any]) -> list[str]:
    """The compact human summary of one run."""
    r = result
    lines = [
        f"exact solver: {r['parameter_sets']:,} parameter sets (+-{100 * r['spread']:.0f} %, "
        f"seed {r['seed']}) x {len(r['temperatures_C'])} temperatures "
        f"{r['temperatures_C']} degC = {r['deployments']:,} deployments, one core"
        + (f" (pinned to CPU {r['pinned_cpu']})" if r["pinned_cpu"] is not None else ""),
        f"  {'':<10} {'path':<38} {'sets':>10} {'median s':>9} {'best s':>8} "
        f"{'deployments/s':>14} {'speed-up':>9}",
    ]
    for key, v in r["vectorised"].items():
        loop = r["loop"][key]
        lines.append(
            f"  {'vectorised':<10} {v['label']:<38} {r['parameter_sets']:>10,} "
            f"{v['median_s']:>9.3f} {v['best_s']:>8.3f} {_rate(v['deployments_per_s']):>14} "
            f"{loop['speedup_of_vectorised']:>8.0f}x"
        )
    for key, v in r["vectorised"].items():
        loop = r["loop"][key]
        lines.append(
            f"  {'loop':<10} {v['label']:<38} {r['loop']['parameter_sets']:>10,} "
            f"{loop['median_s']:>9.3f} {loop['best_s']:>8.3f} "
            f"{_rate(loop['deployments_per_s']):>14} {'1x':>9}"
        )
    goal = r["goal_deployments_per_s"]
    lines.append(
        f"  goal >= {_rate(goal)}/s on one core via predict: "
        + ("MET" if r["meets_goal"] else "NOT MET")
        + f" (core path: {'met' if r['meets_goal_core'] else 'not met'})"
    )
    for key, a in r["agreement"].items():
        difference = a["max_relative_difference"]
        where = f"in {a['worst_field']}" if difference > 0.0 else "bit-identical"
        lines.append(
            f"  loop vs vectorised ({key}): max relative difference "
            f"{difference:.1e} ({where}) over "
            f"{a['compared_deployments']:,} deployments ({a['stalled_deployments']} stalled); "
            "stall flags "
            f"{'identical' if a['stalled_identical'] else 'DIFFER'}: "
            + ("OK" if a["ok"] else "FAILED")
        )
    lines.append(
        f"  predict and core paths give identical results: {r['paths_identical']}; "
        f"stalled: {100 * r['stalled_fraction']:.2f} % of deployments"
    )
    scaling = ", ".join(
        f"{s['parameter_sets']:,}: {_rate(s['deployments_per_s'])}/s" for s in r["scaling"]
    )
    lines.append(f"  batch size (sets) -> predict throughput: {scaling}")
    lines.append("  where the time goes (each step timed alone, median; share of predict):")
    for s in r["stages"]:
        share = s["share_of_predict"]
        lines.append(
            f"    {'  ' * s['depth']}{s['stage']:<{40 - 2 * s['depth']}} "
            f"{1e3 * s['median_s']:>8.1f} ms {100 * share:>5.0f} %"
        )
    memory = r["predict_memory"]
    lines.append(
        f"  memory of one predict call: peak {memory['peak_bytes'] / 2**20:.0f} MiB "
        f"({memory['peak_bytes_per_deployment']:.0f} B per deployment), result "
        f"{memory['retained_bytes'] / 2**20:.0f} MiB"
        + (
            f"; benchmark process peak RSS {r['peak_memory_mib']:.0f} MiB"
            if r["peak_memory_mib"] is not None
            else ""
        )
    )
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    """Run this benchmark alone and print its summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--sets", type=int, default=1_000_000, help="parameter sets")
    parser.add_argument("--loop-sets", type=int, default=2_000, help="sets in the Python loop")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats")
    parser.add_argument("--profile", action="store_true", help="print a cProfile of predict")
    args = parser.parse_args(argv)
    result = run(args.sets, args.loop_sets, args.repeats, profile=args.profile)
    print("\n".join(summary(result)))
    if args.profile:
        print(result["profile"])
    return 0 if ok(result) else 1


if __name__ == "__main__":
    raise SystemExit(main())

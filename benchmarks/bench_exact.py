"""The exact solver's kernels against its reference implementation (issue 13, item 1).

Inputs: twelve parameters of the paper example (``examples/paper_cc16.toml``) drawn
uniformly within +-10 % (``numpy.random.default_rng(20240611)``), 1,000,000 sets (100,000
with ``quick``), each at -40, +25 and +100 degC: a (3, N) batch of deployments, about
0.15 % of them stalled (at -40 degC), so the reference's fallback runs too. The problem
(``Ecd.at`` -> ``build_problem``) is built once; each case times ``EXACT.solve`` on it.

Cases (``cases(quick)``, run by ``benchmarks/run.py``), each interleaved with its baseline:

- ``exact kernel, numba``: the compiled kernel (the default for batches of 50,000 cases
  and more when numba is installed) against the reference implementation
  (``ExactMethod.solve_reference``, the code before issue 13);
- ``exact kernel, NumPy``: the blocked NumPy kernel (used without numba) against the
  same reference;
- ``predict vs Python loop``: ``predict(system, T, methods=("exact",))`` on the whole
  batch against a plain Python loop of ``predict`` calls over 2,000 scalar sets (per
  deployment).

Agreement: the largest relative difference over deployment time, start, end and peak
speed and stall angle (infinities and NaN must match); tolerance 1e-12. Notes: the
kernels' peak memory per deployment (``tracemalloc``, which NumPy reports its buffers to)
on a Monte Carlo chunk (65,536 sets x 3 temperatures), outputs included.
All the code timed is single-threaded. ``python benchmarks/bench_exact.py [--quick]``
runs these cases alone.
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import sys  # noqa: E402
import tracemalloc  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

import harness  # noqa: E402
from ecdsim.config import load_config  # noqa: E402
from ecdsim.deployment import build_problem, predict  # noqa: E402
from ecdsim.model import (  # noqa: E402
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
)
from ecdsim.solvers import EXACT, DeploymentSolution, QuasiStaticProblem  # noqa: E402
from harness import Case, Notes, max_relative_difference  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_cc16.toml"
SEED = 20240611
SPREAD = 0.10
LOOP_SETS = 2_000
CHUNK_SETS = 65_536  # a Monte Carlo chunk
# The kernels evaluate the reference's formulas on the same float64 inputs; the compiled
# one calls the C library's log/log1p (NumPy's are SIMD), a few ulp apart: 1e-12 is the
# issue's agreement target, far above that and far below any physical resolution.
TOLERANCE = 1e-12
FIELDS = ("deployment_time", "start_speed", "end_speed", "max_speed", "stall_angle")
KEYS = [
    "damping_rate",
    "damper_friction",
    "lubrication_slope",
    "lubrication_at_0c",
    "gear_ratio",
    "gearbox_damping_fraction",
    "gearbox_friction",
    "start_torque",
    "end_torque",
    "travel",
    "system_friction_slope",
    "system_friction_at_0c",
]


def nominal() -> tuple[DeploymentSystem, dict[str, float], tuple[float, ...]]:
    """The example's system, its randomised parameters' values, and its temperatures."""
    config = load_config(EXAMPLE)
    s = config.system
    damper, gearbox, load = s.ecd.damper, s.ecd.gearbox, s.load
    fl, fs, spring = damper.lubrication_friction, load.system_friction, load.spring
    assert isinstance(fl, LinearTemperatureLaw)
    assert isinstance(fs, LinearTemperatureLaw)
    assert isinstance(spring, LinearSpring)
    assert gearbox.damping_fraction is not None
    values = [
        damper.damping_rate, damper.coulomb_friction, fl.slope, fl.at_0c, gearbox.ratio,
        gearbox.damping_fraction, gearbox.coulomb_friction, spring.start_torque,
        spring.end_torque, load.travel, fs.slope, fs.at_0c,
    ]  # fmt: skip
    return s, {k: float(v) for k, v in zip(KEYS, values, strict=True)}, config.temperatures


def make_system(fixed: DeploymentSystem, p: dict[str, Any]) -> DeploymentSystem:
    """The example's system holding the parameters ``p`` (scalars or arrays)."""
    damper, spring = fixed.ecd.damper, fixed.load.spring
    assert isinstance(spring, LinearSpring)
    return DeploymentSystem(
        ecd=Ecd(
            damper=HighSpeedDamper(
                damping_rate=p["damping_rate"],
                coulomb_friction=p["damper_friction"],
                lubrication_friction=LinearTemperatureLaw(
                    p["lubrication_slope"], p["lubrication_at_0c"]
                ),
                reference_temperature=damper.reference_temperature,
                damping_temperature_coefficient=damper.damping_temperature_coefficient,
            ),
            gearbox=Gearbox(
                ratio=p["gear_ratio"],
                coulomb_friction=p["gearbox_friction"],
                damping_fraction=p["gearbox_damping_fraction"],
            ),
        ),
        load=Load(
            spring=LinearSpring(
                p["start_torque"],
                p["end_torque"],
                spring.temperature_coefficient,
                spring.reference_temperature,
            ),
            travel=p["travel"],
            system_friction=LinearTemperatureLaw(
                p["system_friction_slope"], p["system_friction_at_0c"]
            ),
        ),
        name=fixed.name,
    )


def problem_of(system: DeploymentSystem, temperatures: np.ndarray[Any, Any]) -> QuasiStaticProblem:
    """The quasi-static problem ``predict`` would solve."""
    return build_problem(system, system.ecd.at(temperatures), temperatures)[0]


def difference(a: DeploymentSolution, b: DeploymentSolution) -> float:
    """Largest relative difference over the fields; inf if the stall flags differ."""
    if not np.array_equal(a.stalled, b.stalled):
        return float("inf")
    return max(max_relative_difference(getattr(a, f), getattr(b, f)) for f in FIELDS)


def peak_bytes_per_deployment(kernel: str, problem: QuasiStaticProblem) -> float:
    """Peak traced memory of one solve over its deployments (outputs included) [B]."""
    EXACT.solve(problem, kernel)  # compiled and imported before tracing
    tracemalloc.start()
    try:
        EXACT.solve(problem, kernel)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak / problem.friction.size


def cases(quick: bool) -> list[Case[Any]]:
    """The two kernels against the reference, and predict against a Python loop."""
    sets = 100_000 if quick else 1_000_000
    fixed, base, temps = nominal()
    rng = np.random.default_rng(SEED)
    params = {k: v * rng.uniform(1.0 - SPREAD, 1.0 + SPREAD, sets) for k, v in base.items()}
    column = np.asarray(temps, dtype=float)[:, np.newaxis]
    system = make_system(fixed, params)
    problem = problem_of(system, column)
    deployments = problem.friction.size
    chunk = problem_of(make_system(fixed, {k: v[:CHUNK_SETS] for k, v in params.items()}), column)
    memory: dict[str, float] = {}

    def kernel_notes(kernel: str) -> Notes:
        memory[kernel] = peak_bytes_per_deployment(kernel, chunk)
        memory["reference"] = peak_bytes_per_deployment("reference", chunk)
        stalled = int(np.count_nonzero(EXACT.solve(problem, kernel).stalled))
        return Notes(
            lines=(
                f"peak memory on a {CHUNK_SETS:,} x {len(temps)} chunk: "
                f"{memory[kernel]:.0f} B/deployment (outputs included, 42 B), "
                f"reference {memory['reference']:.0f} B/deployment; "
                f"{stalled:,} stalled deployments go through the reference",
            ),
            data={"peak_bytes_per_deployment": memory[kernel], "stalled": stalled},
        )

    scalar_sets = [{k: float(v[i]) for k, v in params.items()} for i in range(min(LOOP_SETS, sets))]
    row = np.asarray(temps, dtype=float)

    def loop() -> list[DeploymentSolution]:
        return [
            predict(make_system(fixed, p), row, methods=("exact",)).solutions["exact"]
            for p in scalar_sets
        ]

    def vectorised() -> DeploymentSolution:
        return predict(system, column, methods=("exact",)).solutions["exact"]

    def loop_agreement(vec: DeploymentSolution, looped: list[DeploymentSolution]) -> float:
        count = len(looped)
        worst = 0.0
        for f in ("deployment_time", "start_speed", "end_speed", "max_speed"):
            stacked = np.stack([getattr(s, f) for s in looped], axis=-1)
            worst = max(worst, max_relative_difference(getattr(vec, f)[..., :count], stacked))
        return worst

    reference = lambda: EXACT.solve(problem, "reference")  # noqa: E731
    return [
        Case(
            name="exact kernel, numba",
            ecdsim=lambda: EXACT.solve(problem, "numba"),
            baseline=reference,
            baseline_name="the reference implementation (ExactMethod.solve_reference, the "
            "whole-batch NumPy code before issue 13), same problem",
            agree=difference,
            tolerance=TOLERANCE,
            items=deployments,
            item_name="deployments",
            notes=lambda: kernel_notes("numba"),
            description="EXACT.solve(problem, 'numba') on a (3, N) batch",
        ),
        Case(
            name="exact kernel, NumPy",
            ecdsim=lambda: EXACT.solve(problem, "numpy"),
            baseline=reference,
            baseline_name="the reference implementation, same problem",
            agree=difference,
            tolerance=TOLERANCE,
            items=deployments,
            item_name="deployments",
            notes=lambda: kernel_notes("numpy"),
            description="EXACT.solve(problem, 'numpy') on a (3, N) batch",
        ),
        Case(
            name="predict vs Python loop",
            ecdsim=vectorised,
            baseline=loop,
            baseline_name=f"a plain Python loop of predict calls over {len(scalar_sets):,} "
            "scalar sets (3 temperatures each), per deployment",
            agree=loop_agreement,
            tolerance=TOLERANCE,
            items=deployments,
            baseline_items=len(scalar_sets) * len(temps),
            item_name="deployments",
            description="predict(system, T, methods=('exact',)) vectorised vs looped",
        ),
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Run this file's cases alone and print their table (exit 1 if an agreement fails)."""
    return harness.run_alone(cases, __doc__, argv, quick_help="100,000 sets, not 1,000,000")


if __name__ == "__main__":
    sys.exit(main())

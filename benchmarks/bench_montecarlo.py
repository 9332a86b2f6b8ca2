"""Monte Carlo throughput: samples per second in process and on a Dask LocalCluster.

The study is ``examples/paper_cc16_tolerances.toml`` (the paper example with its eight
illustrative tolerances, Latin hypercube sampling, chunks of 65 536 samples), each
sample solved at the example's three temperatures (-40, +25, +100 degC), streamed to
Parquet in a temporary folder exactly as ``ecdsim montecarlo`` does it. Timed:

* ``exact``: 10 million samples (30 million deployments) by the exact method,
  (a) in this process (the vectorised path, one chunk after another), (b) on a
  LocalCluster of 1 worker process and (c) of 2 worker processes; plus the statistics
  (percentiles, SRC, first-order indices) over the finished study;
* ``dynamic``: 100 000 samples by the dynamic method (the same example with a load
  inertia of 5 kg*m^2 and the rotor inertia of ``examples/paper_cc16_dynamic.toml``), in
  process and on 1 and 2 workers, if the method is registered; otherwise the result
  says that it is not.

A Dask run's time includes starting and stopping its LocalCluster (as a user sees it);
the cluster's start-up alone is timed separately. The Dask path's overhead is its time
over the in-process time for the same study on one worker. Every run's results are
checked to be identical to the in-process run's (the worker count must not matter).

BLAS threads are set to 1 (before NumPy is imported), so that "2 workers" means two
cores' worth of work, not two processes each fighting over every core.
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402 - after the thread settings above, on purpose
import hashlib  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

from ecdsim.config import load_config, parse_config  # noqa: E402
from ecdsim.methods import SOLVERS  # noqa: E402
from ecdsim.montecarlo import DaskExecutor, InProcess, Plan, build_plan  # noqa: E402
from ecdsim.montecarlo import run as run_study  # noqa: E402
from ecdsim.montecarlo.run import Executor, output_column  # noqa: E402
from ecdsim.montecarlo.stats import summarize  # noqa: E402
from ecdsim.montecarlo.store import ChunkReader  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_cc16_tolerances.toml"
EXACT_SAMPLES = 10_000_000
DYNAMIC_SAMPLES = 100_000
# The dynamic example's illustrative inertias (examples/paper_cc16_dynamic.toml).
DYNAMIC_LOAD = 'travel = "1.57 rad"\ninertia = "5 kg*m^2"'
DYNAMIC_ROTOR = 'coulomb_friction = "7.9e-4 N*m"\nrotor_inertia = "2e-7 kg*m^2"'


def dynamic_plan(samples: int) -> Plan:
    """The example with the dynamic method's inertias."""
    text = EXAMPLE.read_text(encoding="utf-8")
    text = text.replace('travel = "1.57 rad"', DYNAMIC_LOAD, 1)
    text = text.replace('coulomb_friction = "7.9e-4 N*m"', DYNAMIC_ROTOR, 1)
    return build_plan(parse_config(text, str(EXAMPLE)), samples, "dynamic")


def digest(plan: Plan, out: Path) -> str:
    """SHA-256 over every sample's deployment time and stall flag, in sample order."""
    reader = ChunkReader(out, plan.chunks)
    h = hashlib.sha256()
    for t in plan.temperatures:
        h.update(reader.floats(output_column("deployment_time_s", t)).tobytes())
        h.update(reader.column(output_column("stalled", t)).tobytes())
    return h.hexdigest()


def folder_bytes(out: Path) -> int:
    """Bytes of the study's chunk files."""
    return sum(p.stat().st_size for p in (out / "chunks").glob("*.parquet"))


def timed_run(plan: Plan, executor: Executor, out: Path, repeats: int) -> dict[str, Any]:
    """A study from scratch into ``out``, ``repeats`` times: best wall time, rate, digest.

    The best of several runs is reported because the machine may be shared: other jobs
    only ever slow a run down. The last run's folder is left for the caller.
    """
    times = []
    for _ in range(repeats):
        shutil.rmtree(out, ignore_errors=True)
        if hasattr(os, "sync"):
            os.sync()  # the previous run's gigabyte of writes must not slow this one down
        started = time.perf_counter()
        run_study(plan, out, executor)
        times.append(time.perf_counter() - started)
    elapsed = min(times)
    return {
        "executor": executor.describe(),
        "seconds": elapsed,
        "all_seconds": times,
        "samples_per_s": plan.samples / elapsed,
        "deployments_per_s": plan.samples * len(plan.temperatures) / elapsed,
        "parquet_bytes": folder_bytes(out),
        "digest": digest(plan, out),
    }


def cluster_startup(workers: int) -> float:
    """Seconds to start and stop an idle LocalCluster of ``workers`` processes, as run uses it."""
    started = time.perf_counter()
    with DaskExecutor(workers=workers)._client():
        pass
    return time.perf_counter() - started


def study(
    plan: Plan, scratch: Path, workers: Sequence[int], with_stats: bool, repeats: int
) -> dict[str, Any]:
    """One plan in process and on each worker count; rates, overhead, identity.

    The statistics are timed last, on the in-process run's folder, so that their memory
    use does not disturb the timed runs.
    """
    base_out = scratch / "in_process"
    runs = {"in_process": timed_run(plan, InProcess(), base_out, repeats)}
    for n in workers:
        out = scratch / f"dask_{n}"
        runs[f"dask_{n}"] = timed_run(plan, DaskExecutor(workers=n), out, repeats)
        shutil.rmtree(out, ignore_errors=True)
    if with_stats:
        started = time.perf_counter()
        summarize(plan, base_out)
        runs["in_process"]["statistics_seconds"] = time.perf_counter() - started
    shutil.rmtree(base_out, ignore_errors=True)
    base = runs["in_process"]
    one = runs.get("dask_1")
    return {
        "method": plan.method,
        "samples": plan.samples,
        "temperatures_C": list(plan.temperatures),
        "chunk_size": plan.chunk_size,
        "chunks": plan.chunks,
        "sampling": plan.sampling,
        "quantities": list(plan.tolerances.keys),
        "runs": runs,
        "dask_overhead_1_worker": (one["seconds"] / base["seconds"] - 1.0) if one else None,
        "identical": all(r["digest"] == base["digest"] for r in runs.values()),
    }


def run(
    exact_samples: int = EXACT_SAMPLES,
    dynamic_samples: int = DYNAMIC_SAMPLES,
    workers: Sequence[int] = (1, 2),
    scratch: Path | None = None,
    repeats: int = 1,
) -> dict[str, Any]:
    """Run the Monte Carlo benchmark and return its results (JSON-ready)."""
    folder = Path(tempfile.mkdtemp(prefix="ecdsim-bench-mc-", dir=scratch))
    try:
        result: dict[str, Any] = {
            "cpu_count": os.cpu_count(),
            "load_average_before": os.getloadavg() if hasattr(os, "getloadavg") else None,
            "repeats": repeats,
            "cluster_startup_s": {str(n): cluster_startup(n) for n in workers},
        }
        exact = build_plan(load_config(EXAMPLE), exact_samples, "exact")
        result["exact"] = study(exact, folder, workers, True, repeats)
        if "dynamic" in SOLVERS:
            dynamic = dynamic_plan(dynamic_samples)
            result["dynamic"] = study(dynamic, folder, workers, False, repeats)
        else:
            result["dynamic"] = {"skipped": "the dynamic method is not registered in SOLVERS"}
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return result


def summary(result: dict[str, Any]) -> list[str]:
    """The compact human summary."""
    load = result["load_average_before"]
    lines = [
        f"Monte Carlo ({result['cpu_count']} CPUs, load average before "
        f"{'n/a' if load is None else f'{load[0]:.2f}'}, best of {result['repeats']} run(s)); "
        "LocalCluster start+stop: "
        + ", ".join(f"{n} worker(s) {s:.1f} s" for n, s in result["cluster_startup_s"].items())
    ]
    for key in ("exact", "dynamic"):
        r = result[key]
        if "skipped" in r:
            lines.append(f"  {key}: skipped ({r['skipped']})")
            continue
        lines.append(
            f"  {key}: {r['samples']:,} samples x {len(r['temperatures_C'])} temperatures, "
            f"{r['chunks']} chunks of {r['chunk_size']:,}, {r['sampling']} sampling, "
            f"{len(r['quantities'])} toleranced quantities"
        )
        for run_ in r["runs"].values():
            stats = (
                f", statistics {run_['statistics_seconds']:.1f} s"
                if "statistics_seconds" in run_
                else ""
            )
            lines.append(
                f"    {run_['executor']:<38} {run_['seconds']:8.1f} s "
                f"{run_['samples_per_s']:>12,.0f} samples/s "
                f"({run_['deployments_per_s']:,.0f} deployments/s), "
                f"Parquet {run_['parquet_bytes'] / 2**20:,.0f} MiB{stats}"
            )
        overhead = r["dask_overhead_1_worker"]
        if overhead is not None:
            lines.append(f"    Dask overhead, 1 worker against in process: {100 * overhead:+.0f} %")
        lines.append(f"    results identical for every executor: {r['identical']}")
    return lines


def ok(result: dict[str, Any]) -> bool:
    """True when every executor gave identical results."""
    return all(result[k].get("identical", True) for k in ("exact", "dynamic"))


def main(argv: Sequence[str] | None = None) -> int:
    """Run this benchmark alone and print its summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--exact-samples", type=int, default=EXACT_SAMPLES)
    parser.add_argument("--dynamic-samples", type=int, default=DYNAMIC_SAMPLES)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--scratch", type=Path, default=None, help="folder for temporary runs")
    parser.add_argument("--repeats", type=int, default=1, help="runs per case; the best counts")
    args = parser.parse_args(argv)
    result = run(args.exact_samples, args.dynamic_samples, args.workers, args.scratch, args.repeats)
    print("\n".join(summary(result)))
    return 0 if ok(result) else 1


if __name__ == "__main__":
    raise SystemExit(main())

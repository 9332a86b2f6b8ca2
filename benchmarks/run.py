"""Run ecdsim's benchmarks, print a compact summary and write ``benchmarks/results.json``.

``make bench`` runs this file. The two benchmarks are :mod:`bench_exact` (exact-solver
throughput, vectorised against a plain Python loop, on one core) and
:mod:`bench_startup` (``ecdsim --help`` start-up time and lazy imports). See
``benchmarks/README.md`` for what each measures and the figures last measured.

Exit status: 0 when the correctness checks pass (loop and vectorised results agree,
``--help`` works, no heavy module is imported at start-up), 1 otherwise. The speed goals
are reported as MET / NOT MET but do not fail the run: timings depend on the machine.
"""

from __future__ import annotations

import os

# One core: BLAS/OpenMP pools are sized when NumPy is first imported, so set these first.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402 - after the thread settings above, on purpose
import datetime  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

import bench_exact  # noqa: E402
import bench_startup  # noqa: E402
from ecdsim import atomic  # noqa: E402
from ecdsim._version import __version__  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results.json"


def git_commit() -> str | None:
    """The checked-out commit, with ``+dirty`` if the tree has changes; None outside git."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=HERE, capture_output=True, text=True, check=True
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=HERE,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return head + ("+dirty" if status else "")


def machine() -> dict[str, Any]:
    """Where and with what the benchmarks ran."""
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "numpy": np.__version__,
        "ecdsim": __version__,
        "cpu_count": os.cpu_count(),
        "threads": {
            name: os.environ.get(name)
            for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
        },
        "pythondontwritebytecode": bool(os.environ.get("PYTHONDONTWRITEBYTECODE")),
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmarks; return the exit status."""
    parser = argparse.ArgumentParser(description="Run ecdsim's benchmarks.")
    parser.add_argument("--sets", type=int, default=1_000_000, help="parameter sets (exact)")
    parser.add_argument("--loop-sets", type=int, default=2_000, help="sets in the Python loop")
    parser.add_argument("--repeats", type=int, default=7, help="timed repeats (exact)")
    parser.add_argument("--runs", type=int, default=7, help="timed runs (start-up)")
    parser.add_argument(
        "--only", choices=("exact", "startup"), default=None, help="run one benchmark"
    )
    parser.add_argument("--profile", action="store_true", help="also print a cProfile")
    parser.add_argument(
        "--output", type=Path, default=RESULTS, help=f"results file (default {RESULTS})"
    )
    parser.add_argument("--no-write", action="store_true", help="do not write the results file")
    args = parser.parse_args(argv)

    now = datetime.datetime.now(datetime.UTC)
    results: dict[str, Any] = {
        "date": now.isoformat(timespec="seconds"),
        "git_commit": git_commit(),
        "machine": machine(),
    }
    lines = [
        f"ecdsim {__version__} benchmarks, {results['date']}",
        f"{platform.platform()}, Python {platform.python_version()}, NumPy {np.__version__}, "
        f"{os.cpu_count()} CPUs",
        "",
    ]
    passed = True
    if args.only in (None, "startup"):
        # Start-up first: its subprocesses should not compete with the big arrays' memory.
        startup = bench_startup.run(args.runs)
        results["startup"] = startup
        lines += [*bench_startup.summary(startup), ""]
        passed &= bench_startup.ok(startup)
    if args.only in (None, "exact"):
        exact = bench_exact.run(args.sets, args.loop_sets, args.repeats, profile=args.profile)
        results["exact"] = exact
        lines += bench_exact.summary(exact)
        passed &= bench_exact.ok(exact)
    print("\n".join(lines))
    if args.profile and "exact" in results:
        print(results["exact"]["profile"])
    if not args.no_write:
        atomic.write_text(args.output, json.dumps(results, indent=2, sort_keys=True) + "\n")
        print(f"\nresults written to {args.output}")
    if not passed:
        print("a correctness check FAILED (see above)", file=sys.stderr)
    return 0 if passed else 1


if __name__ == "__main__":
    raise SystemExit(main())

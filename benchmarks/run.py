"""Run every ecdsim benchmark, print ONE table and write ``benchmarks/results.json``.

``make bench`` runs this file. Each bench file (``BENCH_FILES``) exposes ``cases(quick:
bool) -> list[harness.Case]``; every case is timed by :func:`harness.measure` (ecdsim and
its baseline interleaved, at least 5 repeats, min and median kept) and printed as one row
of one table: case, ecdsim (min/median), baseline (min/median), ratio (baseline/ecdsim
per item, median of the interleaved pairs), agreement (max relative difference of the
results, or same/DIFFERS). Notes (what each baseline is, goals, throughputs, checks)
follow the table. A bench file without ``cases`` yet is run as before, as its own process
(``python benchmarks/bench_X.py``), and its output printed after the table ("legacy").

Options: ``--quick`` (smaller sizes, for a check in a minute or two), ``--only NAME ...``
(bench files by name: exact, startup, csv, ...), ``--repeats N`` (at least 5),
``--output PATH``, ``--no-write``, ``--list``.

``results.json`` (written atomically with ``ecdsim.atomic.write_text``) holds every row
with its raw times, the machine (CPU model from /proc/cpuinfo, cores, Python, NumPy), the
git commit (``+dirty`` when tracked files differ) and the command line.

Exit status: 1 when a case failed, its results disagreed beyond its tolerance or one of
its checks failed (a heavy module imported, say), or a legacy file exited non-zero; 0
otherwise. Speed goals are printed as MET / NOT MET but never fail the run.
"""

from __future__ import annotations

import os

# One core per process: BLAS/OpenMP pools are sized when NumPy is first imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402 - after the thread settings above, on purpose
import datetime  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import textwrap  # noqa: E402
import time  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

import harness  # noqa: E402
from ecdsim import atomic  # noqa: E402
from ecdsim._version import __version__  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results.json"
# In the order run: the start-up processes first, before big arrays take the memory.
BENCH_FILES = ("startup", "exact", "dynamic", "wing", "montecarlo", "csv", "webapp")


def git_commit() -> str | None:
    """The checked-out commit, with ``+dirty`` if tracked files differ; None outside git."""
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


def cpu_model() -> str | None:
    """The CPU's model name from /proc/cpuinfo (Linux); None elsewhere."""
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return platform.processor() or None
    for line in text.splitlines():
        if line.startswith("model name"):
            return line.partition(":")[2].strip()
    return platform.processor() or None


def machine() -> dict[str, Any]:
    """Where and with what the benchmarks ran."""
    try:
        usable = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        usable = None
    return {
        "cpu_model": cpu_model(),
        "cores": os.cpu_count(),
        "cores_usable": usable,
        "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "platform": platform.platform(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "numpy": np.__version__,
        "ecdsim": __version__,
        "threads": {
            name: os.environ.get(name)
            for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
        },
        "pythondontwritebytecode": bool(os.environ.get("PYTHONDONTWRITEBYTECODE")),
    }


def run_file(name: str, quick: bool, repeats: int | None) -> tuple[list[harness.Row], str]:
    """Measure one bench file's cases; a file without ``cases`` runs as legacy output."""
    module_name = f"bench_{name}"
    try:
        module = importlib.import_module(module_name)
    except Exception as error:  # noqa: BLE001 - report it as a row, run the others
        return [harness.Row(name=f"{name}: import", error=f"{type(error).__name__}: {error}")], ""
    cases = getattr(module, "cases", None)
    if cases is None:
        return run_legacy(name)
    try:
        selected: list[harness.Case[Any]] = cases(quick)
    except Exception as error:  # noqa: BLE001
        return [harness.Row(name=f"{name}: cases", error=f"{type(error).__name__}: {error}")], ""
    rows = []
    for case in selected:
        print(f"  {name}: {case.name} ...", file=sys.stderr, flush=True)
        rows.append(harness.measure(case, repeats))
    return rows, ""


def run_legacy(name: str) -> tuple[list[harness.Row], str]:
    """Run a not yet converted bench file as its own process; its output is kept."""
    script = HERE / f"bench_{name}.py"
    print(f"  {name}: legacy {script.name} ...", file=sys.stderr, flush=True)
    start = time.perf_counter()
    completed = subprocess.run(
        [sys.executable, str(script)], cwd=HERE.parent, capture_output=True, text=True, check=False
    )
    elapsed = time.perf_counter() - start
    output = (
        f"--- legacy output of benchmarks/{script.name} (exit {completed.returncode}, "
        f"{elapsed:.0f} s; not yet in the table) ---\n{completed.stdout}{completed.stderr}"
    )
    if completed.returncode != 0:
        row = harness.Row(name=f"{name} (legacy)", error=f"exit {completed.returncode}")
        return [row], output
    return [], output


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmarks; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--quick", action="store_true", help="smaller sizes (a quick check)")
    parser.add_argument("--only", nargs="+", choices=BENCH_FILES, help="bench files to run")
    parser.add_argument("--repeats", type=int, default=None, help="timed repeats (>= 5)")
    parser.add_argument("--output", type=Path, default=RESULTS, help="results file")
    parser.add_argument("--no-write", action="store_true", help="do not write the results file")
    parser.add_argument("--list", action="store_true", help="list the bench files and stop")
    args = parser.parse_args(argv)
    if args.list:
        print("\n".join(f"{name}: benchmarks/bench_{name}.py" for name in BENCH_FILES))
        return 0

    now = datetime.datetime.now(datetime.UTC)
    facts = machine()
    command = " ".join(["python benchmarks/run.py", *(argv if argv is not None else sys.argv[1:])])
    rows: list[harness.Row] = []
    legacy: list[str] = []
    files: dict[str, list[int]] = {}
    for name in args.only or BENCH_FILES:
        file_rows, output = run_file(name, args.quick, args.repeats)
        files[name] = list(range(len(rows), len(rows) + len(file_rows)))
        rows.extend(file_rows)
        if output:
            legacy.append(output)

    cores = facts["cores"]
    heading = (
        f"ecdsim {__version__} benchmarks, {now.isoformat(timespec='seconds')}: {command}. "
        f"{facts['cpu_model']}, {cores} cores; Python {facts['python']}, NumPy "
        f"{facts['numpy']}; commit {git_commit()}. ecdsim and baseline interleaved, "
        "min/median of the repeats; ratio = baseline/ecdsim per item (above 1: ecdsim "
        "faster), median of the pairs."
    )
    print("\n".join(textwrap.wrap(heading, 78)))
    print()
    print("\n".join(harness.table(rows)))
    for output in legacy:
        print()
        print(output.rstrip())

    results: dict[str, Any] = {
        "date": now.isoformat(timespec="seconds"),
        "command": command,
        "quick": args.quick,
        "git_commit": git_commit(),
        "machine": facts,
        "load_average_after": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "files": {name: [rows[i].name for i in indices] for name, indices in files.items()},
        "rows": [row.to_json() for row in rows],
        "legacy_output": legacy,
    }
    if not args.no_write:
        atomic.write_text(args.output, json.dumps(results, indent=2, sort_keys=True) + "\n")
        print(f"\nresults written to {args.output}")
    failed = [row.name for row in rows if not row.ok]
    if failed:
        print(f"FAILED: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Large bench-test CSV files: the block reader against the row-by-row reader.

Cases (``cases(quick)``, run by ``benchmarks/run.py``): a synthetic drop-test log of
1,000,000 rows (100,000 with ``quick``; the example's 18 rows repeated, times perturbed
so that no row repeats another) read by :func:`ecdsim.characterize.csvdata.read_table`
two ways, interleaved, each read a fresh process (so that each peak memory is its own;
the time is that of the ``read_table`` call, measured inside the process):

- baseline: the row-by-row csv-module reader (forced by quoting one header cell, which
  sends any file down that path), the reader ecdsim used for every file before;
- ecdsim: the block reader that NumPy parses, used for plain files.

Agreement: both give the same table (a digest of rows, values and bad-row report). A
second case times ``ecdsim fit drop-test FILE`` end to end as a whole process (no
baseline). A third times ``ecdsim fit drop-test FILE --json`` (every point listed; issue
12's goal: under 10 s and 500 MB at 1,000,000 rows) against what it did before: the same
fit's ``to_dict()`` (one dict per point) through ``json.dumps(indent=2)``; agreement: the
same number of points, and the peak memory of each process.
``python benchmarks/bench_csv.py [--quick]`` runs these cases alone.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

import harness
from harness import (
    Case,
    Command,
    Notes,
    Timed,
    run_process,
    same,
    scratch,
    venv_script,
)

HERE = Path(__file__).resolve().parent
EXAMPLE = HERE.parent / "examples" / "drop_test.csv"

READ = """
import resource, sys, time, hashlib
import numpy as np
from ecdsim.characterize.csvdata import read_table
from ecdsim.characterize.droptest import DROP_TEST_COLUMNS
start = time.perf_counter()
table = read_table(sys.argv[1], DROP_TEST_COLUMNS)
elapsed = time.perf_counter() - start
digest = hashlib.sha256(table.rows.tobytes())
for key in sorted(table.values):
    digest.update(table.values[key].tobytes())
for bad in table.bad_rows:
    digest.update(bad.message().encode())
# VmHWM: this process's own peak (ru_maxrss would also count the parent's resident
# memory at fork, which Linux carries across exec).
status = open("/proc/self/status").read().split("VmHWM:")
if len(status) > 1:
    peak = int(status[1].split()[0]) / 1024
else:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(elapsed, peak, digest.hexdigest())
"""


def write_log(path: Path, rows: int, quoted: bool) -> None:
    """The example's rows repeated to ``rows`` rows, each time perturbed by 0.1 %."""
    lines = EXAMPLE.read_text().splitlines()
    header = lines[0]
    if quoted:
        header = header.replace("time [s]", '"time [s]"')
    data = np.array([[float(c) for c in line.split(",")] for line in lines[1:] if line])
    table = data[np.arange(rows) % len(data)]
    table[:, 4] *= 1.0 + 1e-3 * np.random.default_rng(1).standard_normal(rows)
    formats = ["%g", "%g", "%g", "%g", "%.9f", "%g", "%g"]
    np.savetxt(path, table, delimiter=",", fmt=formats, header=header, comments="")


def read_once(path: Path) -> tuple[float, float, str]:
    """(seconds, peak MB, digest of the table) of one read in a fresh process."""
    out = subprocess.run(
        [sys.executable, "-c", READ, str(path)], capture_output=True, text=True, check=True
    ).stdout.split()
    return float(out[0]), float(out[1]), out[2]


# The --json document as ecdsim wrote it before the points were streamed (issue 12).
JSON_BEFORE = """
import json, sys
from ecdsim.characterize.droptest import fit_drop_test
result = fit_drop_test(sys.argv[1], 25.0)
document = result.to_dict()
document["warnings"] = [w.to_dict() for w in result.warnings]
document["parameter_file"] = None
document["plots"] = []
sys.stdout.write(json.dumps(document, indent=2, sort_keys=True, allow_nan=False) + "\\n")
"""


def cases(quick: bool) -> list[Case[Any]]:
    """Reading a large log both ways, and the fit end to end on it (quick: 100,000 rows)."""
    rows = 100_000 if quick else 1_000_000
    folder = scratch()
    plain, quoted = folder / f"plain-{rows}.csv", folder / f"quoted-{rows}.csv"
    write_log(plain, rows, quoted=False)
    write_log(quoted, rows, quoted=True)
    peaks: dict[str, list[float]] = {"block": [], "row-by-row": []}

    def reader(path: Path, key: str) -> Callable[[], Timed[str]]:
        def read() -> Timed[str]:
            seconds, peak, digest = read_once(path)
            peaks[key].append(peak)
            return Timed(seconds, digest)  # the read itself, not the interpreter start

        return read

    def memory() -> Notes:
        block, row = max(peaks["block"]), max(peaks["row-by-row"])
        return Notes(
            lines=(f"peak memory of the reading process: {block:.0f} MB, row by row {row:.0f} MB",),
            data={"peak_mb_block": block, "peak_mb_row_by_row": row},
        )

    fit = Command((venv_script("ecdsim"), "fit", "drop-test", str(plain)))
    json_peaks: dict[str, list[float]] = {"ecdsim": [], "before": []}

    def json_run(argv: tuple[str, ...], key: str) -> Callable[[], Timed[int]]:
        def run() -> Timed[int]:
            done = run_process(argv)
            if done.peak_bytes is not None:
                json_peaks[key].append(done.peak_bytes / 2**20)
            # Each point holds one "row" key, in either layout.
            return Timed(done.seconds, done.stdout.count('"row": '))

        return run

    def json_memory() -> Notes:
        if not json_peaks["ecdsim"] or not json_peaks["before"]:
            return Notes(lines=("peak memory not measured (no /usr/bin/time)",))
        now, before = max(json_peaks["ecdsim"]), max(json_peaks["before"])
        return Notes(
            lines=(
                f"fit --json peak memory: {now:.0f} MB (goal < 500 MB), before {before:.0f} MB",
            ),
            data={"peak_mb_json": now, "peak_mb_json_before": before},
            ok=True,
        )

    fit_json = json_run((venv_script("ecdsim"), "fit", "drop-test", str(plain), "--json"), "ecdsim")
    before = json_run((sys.executable, "-c", JSON_BEFORE, str(plain)), "before")
    return [
        Case(
            name=f"read_table {rows:,} rows",
            ecdsim=reader(plain, "block"),
            baseline=reader(quoted, "row-by-row"),
            baseline_name="the row-by-row csv-module reader ecdsim used before, "
            "same file with one header cell quoted; each read a whole process",
            agree=same,
            notes=memory,
            description="read_table of a synthetic drop-test log, block reader vs csv module",
        ),
        Case(
            name=f"fit drop-test {rows:,} rows",
            ecdsim=fit,
            repeats=5,
            description="ecdsim fit drop-test FILE end to end as a whole process (no baseline)",
        ),
        Case(
            name=f"fit --json {rows:,} rows",
            ecdsim=fit_json,
            baseline=before,
            baseline_name="the same fit's to_dict() through json.dumps(indent=2), as "
            "fit --json wrote it before the points were streamed",
            agree=same,
            repeats=5,
            goal_s=10.0 if not quick else None,
            notes=json_memory,
            description="ecdsim fit drop-test FILE --json end to end as a whole process",
        ),
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Run this file's cases alone and print their table (exit 1 if an agreement fails)."""
    return harness.run_alone(cases, __doc__, argv, quick_help="100,000 rows instead of 1,000,000")


if __name__ == "__main__":
    sys.exit(main())

"""Large bench-test CSV files: the block reader against the row-by-row reader.

``make bench`` runs this file. It writes a synthetic drop-test log of ``--rows`` rows
(the example's 18 rows repeated, times perturbed so that no row repeats another), then
reads it with :func:`ecdsim.characterize.csvdata.read_table` two ways, interleaved over
``--repeats`` rounds in fresh processes (so that each peak memory is its own):

- baseline: the row-by-row csv-module reader (forced by quoting one header cell, which
  sends any file down that path), the reader ecdsim used for every file before;
- ecdsim: the block reader that NumPy parses, used for plain files.

Prints the minimum and median time and peak resident memory of each and their ratio,
checks that both give the same table, and runs ``ecdsim fit drop-test`` once on the
file end to end, with the table and with ``--json`` (which lists every point). Exit
status 1 if the two tables differ.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

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


FIT = """
import resource, subprocess, sys, time
start = time.perf_counter()
subprocess.run(sys.argv[1:], capture_output=True, check=True)
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
print(time.perf_counter() - start, peak)
"""


def fit_once(path: Path, *options: str) -> tuple[float, float]:
    """(seconds, peak MB) of ``ecdsim fit drop-test PATH [options]`` as a whole process."""
    ecdsim = str(Path(sys.executable).parent / "ecdsim")
    command = [sys.executable, "-c", FIT, ecdsim, "fit", "drop-test", str(path), *options]
    out = subprocess.run(command, capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), float(out[1])


def main() -> int:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        plain, quoted = Path(folder) / "plain.csv", Path(folder) / "quoted.csv"
        write_log(plain, args.rows, quoted=False)
        write_log(quoted, args.rows, quoted=True)
        runs: dict[str, list[tuple[float, float, str]]] = {"row-by-row": [], "block": []}
        for _ in range(args.repeats):  # interleaved: both see the same machine load
            runs["row-by-row"].append(read_once(quoted))
            runs["block"].append(read_once(plain))
        print(f"read_table on {args.rows:,} drop-test rows, {args.repeats} interleaved rounds")
        for name, results in runs.items():
            times = [r[0] for r in results]
            peaks = [r[1] for r in results]
            print(
                f"  {name:10s} time min {min(times):6.2f} s, median "
                f"{statistics.median(times):6.2f} s; peak memory {max(peaks):6.0f} MB"
            )
        ratios = [a[0] / b[0] for a, b in zip(runs["row-by-row"], runs["block"], strict=True)]
        print(
            f"  speed-up per round: min {min(ratios):.1f}x, median {statistics.median(ratios):.1f}x"
        )
        digests = {r[2] for results in runs.values() for r in results}
        same = len(digests) == 1
        print(f"  same table both ways: {'yes' if same else 'NO'}")
        for options in ((), ("--json",)):
            seconds, peak = fit_once(plain, *options)
            shown = " ".join(("ecdsim fit drop-test FILE", *options))
            print(f"  {shown}: {seconds:.1f} s, peak memory {peak:.0f} MB")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

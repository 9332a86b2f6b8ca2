"""The dynamic benchmarks of this checkout against a baseline checkout, interleaved.

``make bench BENCH_BASELINE=REF`` (or ``python benchmarks/bench_before.py REF``) runs the
cases of ``bench_dynamic.py`` (one nonlinear deployment: the MSL brake and the paper
example; the roll-off, heating and linear batches; the tabulated spring of P = 1,000)
on two versions of ecdsim: this checkout ("after") and the baseline ("before"). REF is a
folder holding a checkout (its ``src`` is put first on ``PYTHONPATH``) or a git ref of
this repository (exported with ``git archive`` into a scratch folder). Both sides run
the same case definitions (this checkout's ``bench_dynamic.py``), each in its own
process, the sides alternating over ``--rounds`` rounds (before, after, after, before,
...) so that both see the same machine load. In each process every case times ecdsim
and its scipy LSODA baseline interleaved (``harness.measure``).

Printed per case: each side's median time per deployment and ratio to LSODA (medians
over the rounds), and after / before: the median over the rounds of the before side's
ratio to LSODA over the after side's, i.e. the time ratio of the two ecdsim versions with
each measured against the same LSODA call in its own process (below 1: this checkout is
faster). Normalised so, it does not depend on how loaded the machine was while each
process ran, which the raw times (also printed) do. ``--quick`` (default)
uses bench_dynamic's quick batch sizes (1,000 nonlinear, 10,000 linear cases).
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
MARK = "BENCH-BEFORE-JSON "


def _cases(quick: bool) -> list[Any]:
    """bench_dynamic's cases at ecdsim's default rtol, without their (slow) notes."""
    import numpy as np

    import bench_dynamic as bd

    n_linear, n_reference_linear = (10_000, 50) if quick else (100_000, 200)
    n_nonlinear, n_reference = (1_000, 10) if quick else (10_000, 30)
    batch = bd.make_batch(max(n_linear, n_nonlinear), np.random.default_rng(bd.SEED))
    cases = [bd._single_case(single) for single in bd.singles()]
    cases += [bd._batch_case(m, batch, n_nonlinear, n_reference) for m in ("rolloff", "heating")]
    cases += [bd._batch_case("linear", batch, n_linear, n_reference_linear)]
    cases += [bd._tabulated_case(1_000, ())]
    return [dataclasses.replace(case, notes=None) for case in cases]


def worker(quick: bool, repeats: int) -> int:
    """Measure every case in this process (whichever ecdsim it imports); print JSON."""
    import ecdsim
    import harness

    rows = []
    for case in _cases(quick):
        row = harness.measure(case, repeats)
        median = row.ecdsim_median_s
        rows.append(
            {
                "name": row.name,
                "ecdsim_s": None if median is None else median / row.items,
                "ratio": row.ratio_median,
                "agreement": row.agreement,
                "error": row.error,
            }
        )
    print(MARK + json.dumps({"ecdsim": str(Path(ecdsim.__file__).parent), "rows": rows}))
    return 0


def _baseline_source(ref: str, scratch: Path) -> Path:
    """The baseline's ``src`` folder: REF's own, or REF exported from this repository."""
    folder = Path(ref)
    if (folder / "src" / "ecdsim").is_dir():
        return folder.resolve() / "src"
    target = scratch / "baseline"
    target.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", ref, "src"], check=True, capture_output=True
    )
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, check=True)
    return target / "src"


def _run_side(src: Path | None, quick: bool, repeats: int) -> dict[str, Any]:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(src), str(HERE)])
    else:
        env["PYTHONPATH"] = str(HERE)
    argv = [sys.executable, str(Path(__file__)), "--worker", "--repeats", str(repeats)]
    argv += ["--quick"] if quick else ["--full"]
    done = subprocess.run(argv, env=env, cwd=ROOT, capture_output=True, text=True, check=False)
    for line in done.stdout.splitlines():
        if line.startswith(MARK):
            result: dict[str, Any] = json.loads(line[len(MARK) :])
            return result
    raise RuntimeError(f"worker failed ({done.returncode}):\n{done.stderr[-2000:]}")


def _median(values: Sequence[float | None]) -> float:
    kept = [v for v in values if v is not None]
    return statistics.median(kept) if kept else float("nan")


def compare(ref: str, rounds: int, quick: bool, repeats: int) -> int:
    """Alternate the two sides ``rounds`` times and print the table."""
    import tempfile

    with tempfile.TemporaryDirectory() as scratch:
        src = _baseline_source(ref, Path(scratch))
        runs: dict[str, list[dict[str, Any]]] = {"before": [], "after": []}
        for r in range(rounds):
            order = ("before", "after") if r % 2 == 0 else ("after", "before")
            for side in order:
                result = _run_side(src if side == "before" else None, quick, repeats)
                runs[side].append(result)
                print(f"round {r + 1}/{rounds}: {side} done ({result['ecdsim']})", flush=True)
    names = [row["name"] for row in runs["after"][0]["rows"]]
    print(f"\n{'case':44} {'before':>10} {'after':>10} {'after/':>7} {'before':>8} {'after':>8}")
    print(f"{'':44} {'ms/dep':>10} {'ms/dep':>10} {'before':>7} {'xLSODA':>8} {'xLSODA':>8}")
    for k, name in enumerate(names):
        before = [run["rows"][k] for run in runs["before"]]
        after = [run["rows"][k] for run in runs["after"]]
        pairs = [
            b["ratio"] / a["ratio"]
            for a, b in zip(after, before, strict=True)
            if a["ratio"] and b["ratio"]
        ]
        errors = {row["error"] for row in before + after if row["error"]}
        print(
            f"{name[:44]:44} {1e3 * _median([b['ecdsim_s'] for b in before]):10.4f} "
            f"{1e3 * _median([a['ecdsim_s'] for a in after]):10.4f} {_median(pairs):7.2f} "
            f"{_median([b['ratio'] for b in before]):8.1f} "
            f"{_median([a['ratio'] for a in after]):8.1f}" + (f"  ERROR {errors}" if errors else "")
        )
    print(f"\n{rounds} rounds, each side in its own process, sides alternating; medians.")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("baseline", nargs="?", help="baseline folder or git ref")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=5)
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--quick", dest="quick", action="store_true", default=True)
    size.add_argument("--full", dest="quick", action="store_false")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return worker(args.quick, args.repeats)
    if not args.baseline:
        parser.error("name the baseline: a checkout folder or a git ref")
    return compare(args.baseline, args.rounds, args.quick, args.repeats)


if __name__ == "__main__":
    raise SystemExit(main())

"""``python -m validation [--out docs/validation.md]``: run every case, write the page.

Prints one line per failing check and a summary; exits 1 if any check fails.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ecdsim.atomic import write_text
from validation.cases import run_all
from validation.report import render, summary


def main(argv: Sequence[str] | None = None) -> int:
    """Run the validation; return the exit code."""
    parser = argparse.ArgumentParser(prog="python -m validation", description=__doc__)
    parser.add_argument("--out", type=Path, help="write the Markdown page here")
    args = parser.parse_args(argv)
    results = run_all()
    if args.out is not None:
        write_text(args.out, render(results))
    for case in results:
        for check in case.checks:
            if check.failed:
                print(
                    f"FAIL {case.name}: {check.quantity}: ecdsim {check.value:.10g} "
                    f"{check.unit}, reference {check.reference:.10g} ({check.source}), "
                    f"difference {check.difference:+.3e} > tolerance {check.tolerance:.2e}",
                    file=sys.stderr,
                )
    print(summary(results) + (f"; wrote {args.out}" if args.out is not None else ""))
    return 1 if any(case.failed for case in results) else 0


if __name__ == "__main__":
    raise SystemExit(main())

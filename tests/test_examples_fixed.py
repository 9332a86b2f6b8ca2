"""Every shipped example's results stay what they were (issue 16: omitted keys, today's results).

Each new physics option (resistive tables, gravity, compliant backlash, Stribeck friction,
lossy gears, two-node heating) must leave a config that does not use it exactly as it was.
This test runs every command of the README's example table on the shipped files and
compares the JSON with the documents kept in ``tests/golden/``, written by the code of
commit 54410d1 (before issue 16's items 2, 3, 5 and 6).

This is a regression guard, not a proof of correctness: the numbers themselves are checked
against independent references elsewhere (tests/test_solvers.py against the paper,
tests/test_dynamics_*.py against scipy, validation/). A deliberate change of a result
regenerates the documents with ``python -m tests.test_examples_fixed --write`` and says
why in its commit.

Rules of the comparison: every key of the kept document must be present with an equal
value; keys added since (a new result field, say) are allowed. Strings and booleans must be
equal; numbers within the relative tolerance of the case (below, with why).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = Path(__file__).resolve().parent / "golden"

# Keys whose value is not a result: the package version and the hash of the config file's
# bytes (a comment edited in an example changes it).
IGNORED_KEYS = frozenset({"ecdsim_version", "config_sha256"})

# The closed forms (paper, exact, sizing, fluid, fits, Monte Carlo statistics) are
# deterministic: the same inputs give the same floats up to summation order (the compiled
# and NumPy kernels agree to 1e-12 relative, tests/test_exact_kernel.py). 1e-9 tolerates
# that and catches any change of the model.
CLOSED_FORM_RTOL = 1e-9
# The dynamic method integrates its nonlinear segments at rtol 1e-8 per step; a rework of
# the integrator (step control, event location) may move a result within its accuracy,
# which docs/dynamics.md states as about 1e-7 relative on times and speeds. 1e-6 holds a
# change of the equations (a new term that is not zero when omitted) to account.
DYNAMIC_RTOL = 1e-6
# Results that are zero in one document and a few ulps in the other: absolute floor, in
# the unit of the quantity (s, rad, N*m ...), far below anything printed.
ABSOLUTE_FLOOR = 1e-12

CASES: dict[str, tuple[list[str], float]] = {
    "deploy_paper": (["deploy", "examples/paper_cc16.toml", "--json"], CLOSED_FORM_RTOL),
    "deploy_dynamic": (["deploy", "examples/paper_cc16_dynamic.toml", "--json"], DYNAMIC_RTOL),
    "size": (
        ["size", "examples/sizing.toml", "--catalog", "examples/catalogue.toml", "--json"],
        CLOSED_FORM_RTOL,
    ),
    "compare_fluid": (["compare-fluid", "examples/fluid.toml", "--json"], CLOSED_FORM_RTOL),
    "fit_drop_test": (["fit", "drop-test", "examples/drop_test.csv", "--json"], CLOSED_FORM_RTOL),
    "fit_trace": (
        [
            "fit",
            "trace",
            "examples/deployment_trace.csv",
            "--config",
            "examples/paper_cc16.toml",
            "--json",
        ],
        CLOSED_FORM_RTOL,
    ),
    "montecarlo": (
        [
            "montecarlo",
            "examples/paper_cc16_tolerances.toml",
            "--samples",
            "4096",
            "--json",
            "--no-plot",
            "--no-progress",
        ],
        CLOSED_FORM_RTOL,
    ),
}


def run_case(name: str, out: Path) -> Any:
    """The JSON document the case's command prints (Monte Carlo writes its run into ``out``)."""
    args = list(CASES[name][0])
    if name == "montecarlo":
        args += ["--out", str(out / "mc")]
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, f"{name}: exit {done.returncode}\n{done.stderr}"
    return json.loads(done.stdout)


def differences(kept: Any, now: Any, rtol: float, path: str = "$") -> list[str]:
    """Where ``now`` departs from ``kept`` (see the module docstring for the rules)."""
    if isinstance(kept, dict):
        if not isinstance(now, dict):
            return [f"{path}: was an object, now {type(now).__name__}"]
        found: list[str] = []
        for key, value in kept.items():
            if key in IGNORED_KEYS:
                continue
            if key not in now:
                found.append(f"{path}.{key}: missing")
                continue
            found += differences(value, now[key], rtol, f"{path}.{key}")
        return found
    if isinstance(kept, list):
        if not isinstance(now, list) or len(now) != len(kept):
            size = len(now) if isinstance(now, list) else type(now).__name__
            return [f"{path}: was a list of {len(kept)}, now {size}"]
        found = []
        for i, (a, b) in enumerate(zip(kept, now, strict=True)):
            found += differences(a, b, rtol, f"{path}[{i}]")
        return found
    numbers = (int, float)
    if isinstance(kept, numbers) and not isinstance(kept, bool):
        if not isinstance(now, numbers) or isinstance(now, bool):
            return [f"{path}: was {kept!r}, now {now!r}"]
        if math.isclose(kept, now, rel_tol=rtol, abs_tol=ABSOLUTE_FLOOR):
            return []
        return [f"{path}: was {kept!r}, now {now!r}"]
    return [] if kept == now else [f"{path}: was {kept!r}, now {now!r}"]


def test_the_comparison_catches_a_changed_number_and_a_missing_key() -> None:
    # The guard itself must be able to fail: one relative change of 1e-8 and a lost key.
    kept = {"a": [1.0, {"b": 2.0, "c": "x"}], "ecdsim_version": "0"}
    assert differences(kept, {"a": [1.0, {"b": 2.0, "c": "x"}], "new": 1}, 1e-9) == []
    assert differences(kept, {"a": [1.0, {"b": 2.0 * (1 + 1e-8), "c": "x"}]}, 1e-9)
    assert differences(kept, {"a": [1.0, {"b": 2.0}]}, 1e-9) == ["$.a[1].c: missing"]
    assert differences(kept, {"a": [1.0]}, 1e-9) == ["$.a: was a list of 2, now 1"]


@pytest.mark.parametrize("name", sorted(CASES))
def test_shipped_example_results_are_unchanged(name: str, tmp_path: Path) -> None:
    kept = json.loads((GOLDEN / f"{name}.json").read_text(encoding="utf-8"))
    now = run_case(name, tmp_path)
    found = differences(kept, now, CASES[name][1])
    assert not found, f"{name}: {len(found)} differences, first: " + "; ".join(found[:8])


def _write() -> None:
    """Write the kept documents anew from this checkout's code (a deliberate change)."""
    import tempfile

    GOLDEN.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        for name in sorted(CASES):
            document = run_case(name, Path(folder))
            text = json.dumps(document, indent=1, sort_keys=True) + "\n"
            (GOLDEN / f"{name}.json").write_text(text, encoding="utf-8")
            print(f"wrote tests/golden/{name}.json")


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python -m tests.test_examples_fixed --write")
    _write()

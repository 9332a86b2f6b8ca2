"""Start-up of the command line: whole ``ecdsim`` processes against a bare interpreter.

Cases (``cases(quick)``, run by ``benchmarks/run.py``): ``ecdsim deploy
examples/paper_cc16.toml``, ``ecdsim fit drop-test examples/drop_test.csv`` and ``ecdsim
--help``, each run through the installed console script beside this interpreter as a
whole process (its output captured), interleaved with the baseline ``python -c pass``
(a bare interpreter start, the floor of any Python command). Goals (issue 13, item 4):
deploy < 0.35 s, fit drop-test < 0.6 s median (issue 2: --help < 0.3 s).

ecdsim's bytecode is written first (``compileall``, as ``pip install`` does). Each case
also checks, in a fresh interpreter that runs the same command in process
through the typer app, which heavy third-party modules were loaded: those the command
does not use must be absent (the check fails the run), and lists the slowest imports of
the command (``python -X importtime``, cumulative).

Run alone: ``python benchmarks/bench_startup.py [--quick]`` prints the same table for
these cases only.
"""

from __future__ import annotations

import compileall
import importlib.util
import json
import resource
import statistics
import subprocess
import sys
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import harness
from harness import ROOT, Case, Command, Notes, venv_script

MARKER = "ECDSIM-BENCH-MODULES="
HEAVY = ("numpy", "scipy", "matplotlib", "pint", "pydantic", "pandas", "jinja2")

# Run in a fresh interpreter: run the command in process through the typer app (output
# captured), then print the top-level names of every loaded module after MARKER.
_MODULES_SCRIPT = """
import contextlib, io, json, sys
from ecdsim.cli.app import main
sys.argv = ["ecdsim", *sys.argv[1:]]
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        main()
    except SystemExit:
        pass
print("MARKER" + json.dumps(sorted({name.split(".")[0] for name in sys.modules})))
""".replace("MARKER", MARKER)

# What each command may not load (it does not use it); tests/test_startup_imports.py
# asserts the same. pint: every unit of the examples is in the lean table; dask: pint
# imports it; scipy: the drop-test fit solves and computes its distributions itself
# (characterize/leastsq.py, distributions.py).
# markdown_it: typer's help renderer imports it (rich.markdown); a command that prints no
# help has no use for it.
_NEVER = ("matplotlib", "pandas", "jinja2", "pint", "dask")
COMMANDS: tuple[tuple[str, tuple[str, ...], float, tuple[str, ...]], ...] = (
    ("ecdsim deploy (paper)", ("deploy", "examples/paper_cc16.toml"), 0.35,
     (*_NEVER, "scipy", "markdown_it")),
    ("ecdsim fit drop-test", ("fit", "drop-test", "examples/drop_test.csv"), 0.6,
     (*_NEVER, "scipy", "markdown_it")),
    ("ecdsim --help", ("--help",), 0.3, (*_NEVER, "scipy", "numpy", "pydantic")),
)  # fmt: skip


def loaded_modules(arguments: Sequence[str]) -> list[str]:
    """Top-level names of the modules loaded by running ``ecdsim *arguments`` in process."""
    completed = subprocess.run(
        [sys.executable, "-c", _MODULES_SCRIPT, *arguments],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    for line in completed.stdout.splitlines():
        if line.startswith(MARKER):
            names: list[str] = json.loads(line[len(MARKER) :])
            return names
    raise RuntimeError(f"no module list from ecdsim {' '.join(arguments)}")


def import_times(arguments: Sequence[str], top: int) -> list[dict[str, Any]]:
    """The ``top`` imports by cumulative time of ``python -X importtime ecdsim ...``."""
    completed = subprocess.run(
        [sys.executable, "-X", "importtime", venv_script("ecdsim"), *arguments],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    rows: list[dict[str, Any]] = []
    for line in completed.stderr.splitlines():
        # "import time:  self [us] | cumulative | imported package", one line per module.
        if not line.startswith("import time:") or "imported package" in line:
            continue
        self_us, cumulative_us, name = line.removeprefix("import time:").split("|")
        rows.append(
            {
                "module": name.strip(),
                "self_ms": int(self_us) / 1e3,
                "cumulative_ms": int(cumulative_us) / 1e3,
            }
        )
    rows.sort(key=lambda row: row["cumulative_ms"], reverse=True)
    return rows[:top]


def with_cpu_time(command: Command, sink: list[float]) -> Callable[[], str]:
    """``command``, also appending the CPU time (user + sys) of its process to ``sink``.

    On a loaded machine the wall time includes waiting for a core; the CPU time is what
    the process itself spent, closer to the wall time it takes on a quiet machine.
    """

    def run() -> str:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        out = command()
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        sink.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
        return out

    return run


def checks(arguments: Sequence[str], forbidden: Sequence[str], cpu_times: Sequence[float]) -> Notes:
    """Heavy modules loaded by the command (those in ``forbidden`` fail) and slow imports."""
    names = loaded_modules(arguments)
    heavy = [m for m in HEAVY if m in names]
    bad = [m for m in forbidden if m in names]
    slowest = import_times(arguments, top=60)
    top_level = [r for r in slowest if "." not in r["module"] and r["module"] != "ecdsim"]
    slowest = slowest[:10]
    timed = list(cpu_times[1:])  # the first is the warm-up's
    lines = [
        f"CPU time (user + sys) of the ecdsim process: min {min(timed):.3f} s, median "
        f"{statistics.median(timed):.3f} s (the wall time adds waiting for a core)",
        f"heavy modules loaded: {', '.join(heavy) or 'none'}; must be absent: "
        f"{', '.join(forbidden)}: {'OK' if not bad else 'FAILED (' + ', '.join(bad) + ')'}",
        "slowest imports (-X importtime, cumulative, one run): "
        + ", ".join(f"{r['module']} {r['cumulative_ms']:.0f} ms" for r in top_level[:4]),
    ]
    return Notes(
        lines=tuple(lines),
        data={
            "cpu_times_s": timed,
            "heavy_loaded": heavy,
            "forbidden": list(forbidden),
            "slowest_imports": slowest,
        },
        ok=not bad,
    )


def compile_package() -> None:
    """Write ecdsim's bytecode, as ``pip install`` does, so that no run compiles sources.

    With ``PYTHONDONTWRITEBYTECODE`` set (as on this project's machines) an edited module
    would otherwise be compiled again by every start, which a user's install never does.
    """
    spec = importlib.util.find_spec("ecdsim")
    for folder in (spec.submodule_search_locations or []) if spec else []:
        compileall.compile_dir(folder, quiet=1)


def cases(quick: bool) -> list[Case[Any]]:
    """The start-up cases; ``quick`` changes nothing (they are already short)."""
    del quick
    compile_package()
    ecdsim = venv_script("ecdsim")
    bare = Command((sys.executable, "-c", "pass"))
    out = []
    for name, arguments, goal, forbidden in COMMANDS:
        cpu_times: list[float] = []
        out.append(
            Case(
                name=name,
                ecdsim=with_cpu_time(Command((ecdsim, *arguments)), cpu_times),
                baseline=bare,
                baseline_name="a bare interpreter start, python -c pass",
                goal_s=goal,
                repeats=7,
                notes=partial(checks, arguments, forbidden, cpu_times),
                description=f"ecdsim {' '.join(arguments)} as a whole process",
            )
        )
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run this file's cases alone and print their table (exit 1 if an agreement fails)."""
    return harness.run_alone(cases, __doc__, argv, quick_help="smaller sizes")


if __name__ == "__main__":
    raise SystemExit(main())

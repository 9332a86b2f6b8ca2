"""Start-up time of the command line: ``ecdsim --help`` against a bare Python start.

Times the installed console script (the ``ecdsim`` next to this interpreter) as a
subprocess, after one untimed warm-up run, and reports the median; ``python -c pass``
and ``python -c "import ecdsim.cli.app"`` are timed the same way in the same run, so the
ratio to a bare interpreter is comparable across machines. It also lists the slowest
imports (``python -X importtime``) and checks which heavy third-party modules are loaded
by importing the CLI and by running ``--help`` (numpy, scipy, matplotlib, pint, pydantic,
pandas and jinja2 must all stay lazy; typer, click and rich are allowed).
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

GOAL_S = 0.3  # issue 2, "Performance"
HEAVY = ("numpy", "scipy", "matplotlib", "pint", "pydantic", "pandas", "jinja2")
MARKER = "ECDSIM-BENCH-MODULES="

# Run in a fresh interpreter: import the CLI (and optionally run --help with its output
# captured), then print the top-level names of every module loaded, after MARKER.
_MODULES_SCRIPT = """
import contextlib, io, json, sys
import ecdsim.cli.app
if sys.argv[1] == "help":
    sys.argv = ["ecdsim", "--help"]
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            ecdsim.cli.app.main()
        except SystemExit:
            pass
names = sorted({name.split(".")[0] for name in sys.modules})
print("MARKER" + json.dumps(names))
""".replace("MARKER", MARKER)


def console_script() -> Path:
    """The installed ``ecdsim`` script beside this interpreter, else the one on PATH."""
    beside = Path(sys.executable).parent / "ecdsim"
    if beside.exists():
        return beside
    found = shutil.which("ecdsim")
    if found is None:
        raise SystemExit("the ecdsim console script is not installed (run: make demo)")
    return Path(found)


def time_command(command: Sequence[str], runs: int) -> tuple[list[float], int]:
    """Wall-clock times of ``runs`` runs after one warm-up [s], and the last exit code."""
    code = 0
    times = []
    for i in range(runs + 1):
        start = time.perf_counter()
        completed = subprocess.run(
            list(command), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False
        )
        elapsed = time.perf_counter() - start
        code = completed.returncode
        if i > 0:  # the first run warms the file cache; it is not counted
            times.append(elapsed)
    return times, code


def loaded_modules(after_help: bool) -> list[str]:
    """Top-level names of the modules loaded by importing the CLI (and running --help)."""
    completed = subprocess.run(
        [sys.executable, "-c", _MODULES_SCRIPT, "help" if after_help else "import"],
        capture_output=True,
        text=True,
        check=True,
    )
    for line in completed.stdout.splitlines():
        if line.startswith(MARKER):
            names: list[str] = json.loads(line[len(MARKER) :])
            return names
    raise RuntimeError("the module listing subprocess printed no module list")


def third_party(names: Sequence[str]) -> list[str]:
    """The names that are neither standard library, built in, nor ecdsim itself."""
    own = {"ecdsim", "__main__", "_distutils_hack"}
    return [
        n
        for n in names
        if n not in sys.stdlib_module_names
        and n not in sys.builtin_module_names
        and n not in own
        and not n.startswith("_")
    ]


def import_times(arguments: Sequence[str], top: int) -> list[dict[str, Any]]:
    """The ``top`` imports by cumulative time of ``python -X importtime *arguments``."""
    completed = subprocess.run(
        [sys.executable, "-X", "importtime", *arguments],
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
                "depth": (len(name) - len(name.lstrip()) - 1) // 2,
                "self_ms": int(self_us) / 1e3,
                "cumulative_ms": int(cumulative_us) / 1e3,
            }
        )
    rows.sort(key=lambda row: row["cumulative_ms"], reverse=True)
    return rows[:top]


def run(runs: int = 7) -> dict[str, Any]:
    """Run the start-up benchmark and return its results (JSON-ready)."""
    script = console_script()
    help_times, help_code = time_command([str(script), "--help"], runs)
    bare_times, _ = time_command([sys.executable, "-c", "pass"], runs)
    import_times_s, import_code = time_command(
        [sys.executable, "-c", "import ecdsim.cli.app"], runs
    )
    after_import = loaded_modules(after_help=False)
    after_help = loaded_modules(after_help=True)
    help_median = statistics.median(help_times)
    bare_median = statistics.median(bare_times)
    heavy_import = [m for m in HEAVY if m in after_import]
    heavy_help = [m for m in HEAVY if m in after_help]
    return {
        "command": f"{script} --help",
        "runs": runs,
        "help_exit_code": help_code,
        "help_times_s": help_times,
        "help_median_s": help_median,
        "python_pass_times_s": bare_times,
        "python_pass_median_s": bare_median,
        "ratio_to_python_pass": help_median / bare_median,
        "import_cli_exit_code": import_code,
        "import_cli_median_s": statistics.median(import_times_s),
        "goal_s": GOAL_S,
        "meets_goal": help_median < GOAL_S,
        "heavy_checked": list(HEAVY),
        "heavy_after_import": heavy_import,
        "heavy_after_help": heavy_help,
        "third_party_after_import": third_party(after_import),
        "third_party_after_help": third_party(after_help),
        "slowest_imports": import_times(["-c", "import ecdsim.cli.app"], top=10),
        "slowest_imports_help": import_times([str(script), "--help"], top=10),
    }


def ok(result: dict[str, Any]) -> bool:
    """True when --help works and no heavy module is imported at start-up."""
    return bool(
        result["help_exit_code"] == 0
        and result["import_cli_exit_code"] == 0
        and not result["heavy_after_import"]
        and not result["heavy_after_help"]
    )


def summary(result: dict[str, Any]) -> list[str]:
    """The compact human summary of one run."""
    r = result
    goal = "MET" if r["meets_goal"] else "NOT MET"
    lines = [
        f"start-up: median of {r['runs']} runs after one warm-up, as subprocesses",
        f"  ecdsim --help                      {r['help_median_s']:.3f} s "
        f"(exit {r['help_exit_code']}; goal < {r['goal_s']} s: {goal})",
        f"  python -c pass                     {r['python_pass_median_s']:.3f} s "
        f"(ecdsim --help / python -c pass = {r['ratio_to_python_pass']:.1f})",
        f"  python -c 'import ecdsim.cli.app'  {r['import_cli_median_s']:.3f} s",
        f"  heavy modules after import: {', '.join(r['heavy_after_import']) or 'none'}; "
        f"after --help: {', '.join(r['heavy_after_help']) or 'none'} "
        f"(checked: {', '.join(r['heavy_checked'])})",
        f"  third-party packages loaded by --help: {', '.join(r['third_party_after_help'])}",
        "  slowest imports (-X importtime; cumulative / self, ms), top "
        f"{len(r['slowest_imports'])}:",
        f"    {'import ecdsim.cli.app':<48} ecdsim --help",
    ]
    for a, b in zip(r["slowest_imports"], r["slowest_imports_help"], strict=False):
        lines.append(f"    {_import_row(a):<48} {_import_row(b):<48}".rstrip())
    return lines


def _import_row(row: dict[str, Any]) -> str:
    return f"{row['module']:<30} {row['cumulative_ms']:>7.1f} {row['self_ms']:>7.1f}"


def main(argv: Sequence[str] | None = None) -> int:
    """Run this benchmark alone and print its summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--runs", type=int, default=7, help="timed runs of each command")
    args = parser.parse_args(argv)
    result = run(args.runs)
    print("\n".join(summary(result)))
    return 0 if ok(result) else 1


if __name__ == "__main__":
    raise SystemExit(main())

"""How the console script starts (issue 13, item 4).

``ecdsim.cli.app.main`` runs ``only(name)``: the app with just the command or group
named first on the command line, so that typer builds one click command instead of all
of them. A user must not see the difference: every command's help, usage errors and
output are compared here with the whole app's, through typer's test runner.
``main`` also keeps the garbage collector off until a command runs (for the whole of a
quick one), and the quick commands load NumPy with OpenBLAS's thread pool off.
No wall-clock assertion: the time saved is a benchmark (benchmarks/bench_startup.py).
"""

from __future__ import annotations

import gc
import json
import os
import subprocess
import sys

import pytest
import typer
from typer.main import get_command
from typer.testing import CliRunner

from ecdsim.cli.app import app, only
from ecdsim.cli.common import pause_gc, resume_gc
from ecdsim.cli.display import HelpCommand, QuickCommand
from tests.conftest import ROOT

runner = CliRunner()
PAPER = str(ROOT / "examples" / "paper_cc16.toml")
WIDE = {"COLUMNS": "250", "TERMINAL_WIDTH": "250"}

# Every command and group of the whole app, as click lists them (so that a command added
# later is covered without editing this list).
NAMES = sorted(get_command(app).commands)  # type: ignore[attr-defined]


def test_every_command_is_found_by_name() -> None:
    # The listing is not empty, and each name gives an app holding that command alone.
    assert {"deploy", "demo", "fit", "size", "montecarlo", "report"} <= set(NAMES)
    for name in NAMES:
        lean = get_command(only(name))
        assert sorted(lean.commands) == [name], name  # type: ignore[attr-defined]


@pytest.mark.parametrize("arguments", [[], ["--help"], ["--version"], ["bogus"], ["Deploy"]])
def test_anything_else_runs_the_whole_app(arguments: list[str]) -> None:
    # No command named (the root's options, an unknown or miscased name): the whole app,
    # whose errors list or suggest every command.
    assert only(arguments[0] if arguments else "") is app


@pytest.mark.parametrize("name", NAMES)
def test_a_commands_help_is_the_same(name: str) -> None:
    whole = runner.invoke(app, [name, "--help"], env=WIDE)
    lean = runner.invoke(only(name), [name, "--help"], env=WIDE)
    assert whole.exit_code == 0, whole.output
    assert (lean.exit_code, lean.output) == (whole.exit_code, whole.output)


@pytest.mark.parametrize(
    "arguments",
    [
        ["deploy"],  # the argument missing
        ["deploy", PAPER, "--bogus"],  # an unknown option
        ["deploy", PAPER, "-m", "guess"],  # a bad value (exit 2)
        ["deploy", PAPER, "--json"],
        ["fit"],  # a group without its subcommand
        ["fit", "drop-test", "--help"],
        ["fit", "bogus"],
    ],
    ids=" ".join,
)
def test_errors_and_output_are_the_same(arguments: list[str]) -> None:
    whole = runner.invoke(app, arguments, env=WIDE)
    lean = runner.invoke(only(arguments[0]), arguments, env=WIDE)
    assert (lean.exit_code, lean.output) == (whole.exit_code, whole.output)


def test_the_console_script_runs_the_command_named() -> None:
    # main() itself (through python -m ecdsim): the version option of the root callback
    # and a command both work.
    version = subprocess.run(
        [sys.executable, "-m", "ecdsim", "--version"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    assert version.stdout.startswith("ecdsim ")
    deploy = subprocess.run(
        [sys.executable, "-m", "ecdsim", "deploy", PAPER, "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    assert runner.invoke(app, ["deploy", PAPER, "--json"]).stdout == deploy.stdout


def test_the_collector_is_on_in_a_command_and_off_in_a_quick_one() -> None:
    # pause_gc as main() calls it, then one command of each class: a HelpCommand runs
    # with the collector on again, a QuickCommand without it; resume_gc (main's last
    # step) turns it on. A collector the caller turned off stays off.
    seen: list[tuple[str, bool]] = []
    probe = typer.Typer()

    @probe.command(cls=HelpCommand)
    def slow() -> None:
        seen.append(("slow", gc.isenabled()))

    @probe.command(cls=QuickCommand)
    def quick() -> None:
        seen.append(("quick", gc.isenabled()))

    assert gc.isenabled()
    try:
        for name in ("slow", "quick"):
            pause_gc()
            assert not gc.isenabled()
            probe([name], standalone_mode=False)
            resume_gc()
            assert gc.isenabled()
        gc.disable()
        pause_gc()
        probe(["slow"], standalone_mode=False)
        resume_gc()
        assert not gc.isenabled()
    finally:
        gc.enable()
    assert seen == [("slow", True), ("quick", False), ("slow", False)]


PROBE = """
import contextlib, io, json, os, sys
from ecdsim.cli.app import main
sys.argv = ["ecdsim", "deploy", sys.argv[1]]
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main()
    except SystemExit:
        pass
tasks = os.listdir("/proc/self/task") if os.path.isdir("/proc/self/task") else None
print(json.dumps({"threads": None if tasks is None else len(tasks),
                  "blas": {k: v for k, v in os.environ.items() if k.endswith("_NUM_THREADS")}}))
"""


@pytest.mark.parametrize("user", [{}, {"OMP_NUM_THREADS": "2"}, {"OPENBLAS_NUM_THREADS": "2"}])
def test_deploy_loads_numpy_single_threaded_unless_the_user_sized_it(
    user: dict[str, str],
) -> None:
    # The variable is set only while NumPy loads (a child process does not inherit it),
    # and a size the user chose is left alone. On Linux, the process's threads are
    # counted: one with the pool off, more with the user's two (on a machine with two
    # cores or more, as the project's).
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")} | user
    done = subprocess.run(
        [sys.executable, "-c", PROBE, PAPER],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(done.stdout)
    assert result["blas"] == user
    if result["threads"] is not None and (os.cpu_count() or 1) >= 2:
        assert (result["threads"] == 1) == (user == {})

"""The console script builds only the command it is asked for (issue 13, item 4).

``ecdsim.cli.app.main`` runs ``only(name)``: the app with just the command or group
named first on the command line, so that typer builds one click command instead of all
of them. A user must not see the difference: every command's help, usage errors and
output are compared here with the whole app's, through typer's test runner.
No wall-clock assertion: the time saved is a benchmark (benchmarks/bench_startup.py).
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from typer.main import get_command
from typer.testing import CliRunner

from ecdsim.cli.app import app, only
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

"""Read a ``--help`` screen as a user does: the options and commands it lists, its example.

Help tests assert the listed options against the command's documented interface and run
the example exactly as printed (in a scratch folder holding a copy of ``examples/``), so a
renamed option or a stale example fails the tests instead of the user.
"""

from __future__ import annotations

import re
import shlex
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer import Typer
from typer.testing import CliRunner, Result

from tests.conftest import ROOT

# Wide enough that rich wraps no option description or example line.
WIDE = {"COLUMNS": "250", "TERMINAL_WIDTH": "250"}
_OPTION = re.compile(r"^│\s+\*?\s*(--[\w-]+)(?:\s+(-\w))?\s+(\S.*?)\s*│$")
_COMMAND = re.compile(r"^│ ([a-z][\w-]*)\s{2,}(\S.*?)\s*│$")


@dataclass(frozen=True)
class HelpScreen:
    """What one ``--help`` screen shows."""

    text: str
    options: dict[str, str]  # long option -> the rest of its line (type and description)
    short: dict[str, str]  # long option -> its short alias
    commands: dict[str, str]  # subcommand -> its one-line description
    example: list[str]  # the example's arguments after ``ecdsim``


def read_help(
    runner: CliRunner, app: Typer, args: list[str], *, has_example: bool = True
) -> HelpScreen:
    """Run ``ecdsim <args> --help`` and parse the screen (``has_example``: it must show one)."""
    result = runner.invoke(app, [*args, "--help"], env=WIDE)
    assert result.exit_code == 0, result.output
    text = result.stdout
    options: dict[str, str] = {}
    short: dict[str, str] = {}
    commands: dict[str, str] = {}
    section = ""
    for line in text.splitlines():
        if line.startswith("╭─"):
            section = line.strip("╭─ ╮")
            continue
        match = _OPTION.match(line)
        if match and section == "Options":
            options[match[1]] = match[3]
            if match[2]:
                short[match[1]] = match[2]
        command = _COMMAND.match(line)
        if command and section == "Commands":
            commands[command[1]] = command[2]
    example: list[str] = []
    for line in text.split("Example:", 1)[1].splitlines() if "Example:" in text else []:
        if not line.strip() or line.startswith("╭"):
            break
        example.append(line.strip())
    # The command ends where prose starts: ", then ..." or a "(...)" remark.
    words = shlex.split(" ".join(example).split(", then")[0].split(" (")[0])
    if not has_example:
        return HelpScreen(text, options, short, commands, [])
    assert words[:1] == ["ecdsim"], f"no 'Example: ecdsim ...' on the help of {args}"
    return HelpScreen(text, options, short, commands, words[1:])


def run_example(
    runner: CliRunner, app: Typer, screen: HelpScreen, folder: Path, mp: pytest.MonkeyPatch
) -> Result:
    """Run the screen's example as printed, in ``folder`` holding a copy of examples/."""
    shutil.copytree(ROOT / "examples", folder / "examples")
    mp.chdir(folder)
    result = runner.invoke(app, screen.example, env=WIDE)
    assert result.exit_code == 0, (screen.example, result.output)
    return result


def assert_options(screen: HelpScreen, expected: dict[str, str | None]) -> None:
    """The screen lists exactly these options (long -> short alias), each described."""
    assert {k: screen.short.get(k) for k in screen.options} == expected
    for name, rest in screen.options.items():
        # "<type> description": a description of at least two words after the type.
        assert len(rest.split()) >= 3, f"{name} has no description: {rest!r}"
    # A group's example runs a subcommand, whose own screen lists its options.
    for word in [] if screen.commands else screen.example:
        if word.startswith("--"):
            assert word in screen.options, f"the example uses {word}, which is not listed"

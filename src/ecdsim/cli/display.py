"""Tables on the terminal: the terminal's width, ``--wide`` and ``--plain``.

Every command that prints tables prints them with :func:`show` on a console from
:func:`make_console`, which

* takes the width from the terminal (``COLUMNS`` or the real width; 80 when the output
  is piped to a file or another program), never a forced minimum;
* hides the table's secondary columns, in the order the command lists them, while the
  table is wider than that, then wraps text cells at spaces (numbers are never cut off),
  and says which columns it hid; ``--wide`` shows every column whatever the width;
* with ``--plain`` prints plain aligned text, without box-drawing characters or colour,
  for logs and scripts.

The choice is set once per command by :func:`configure`. rich is imported inside the
functions: the CLI imports this module at start-up.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer import _click
from typer.core import TyperCommand, TyperGroup

from ecdsim.cli.common import resume_gc

if TYPE_CHECKING:
    from rich.console import Console
    from rich.table import Column, Table

WideOpt = Annotated[
    bool,
    typer.Option(
        "--wide", help="Show every table column, even wider than the terminal.", metavar=""
    ),
]
PlainOpt = Annotated[
    bool,
    typer.Option(
        "--plain",
        help="Plain aligned text: no box-drawing characters or colour (for logs, pipes).",
        metavar="",
    ),
]


@dataclass
class Display:
    """How the current command prints its tables."""

    wide: bool = False
    plain: bool = False


_DISPLAY = Display()


def configure(*, wide: bool = False, plain: bool = False) -> None:
    """Set how the current command prints its tables (call it first in each command)."""
    _DISPLAY.wide = wide
    _DISPLAY.plain = plain


def current() -> Display:
    """The display settings of the current command."""
    return _DISPLAY


def make_console(*, stderr: bool = False) -> Console:
    """A rich console as wide as the terminal (80 when piped), plain if ``--plain``."""
    from rich.console import Console

    if _DISPLAY.plain:
        return Console(
            stderr=stderr, soft_wrap=False, color_system=None, highlight=False, emoji=False
        )
    return Console(stderr=stderr, soft_wrap=False)


def header_text(column: Column) -> str:
    """A column's header as plain text on one line ("start speed [rad/s]")."""
    from rich.text import Text

    header = column.header
    text = header.plain if isinstance(header, Text) else Text.from_markup(str(header)).plain
    return " ".join(text.split())


def _needed(console: Console, table: Table) -> int:
    """The narrowest width at which ``table`` prints with no cell cut or folded: the
    wrappable (text) columns at their longest word, every other column in full."""
    from rich.measure import Measurement

    options = console.options.update(width=100_000)
    natural = Measurement.get(console, options, table).maximum
    slack = 0
    for column in table.columns:
        if column.no_wrap:
            continue
        cells = [column.header, *column._cells]
        sizes = [Measurement.get(console, options, cell) for cell in cells if cell is not None]
        if sizes:
            # A wrapped text column keeps at least WRAP_WIDTH characters (or its full
            # width, if narrower), so that a name is not cut into one word per line.
            full = max(m.maximum for m in sizes)
            least = max(max(m.minimum for m in sizes), min(full, WRAP_WIDTH))
            slack += full - least
    return natural - slack


WRAP_WIDTH = 16  # the narrowest a wrapped text column is made before columns are hidden


def _unit_line(header: str) -> str:
    """A one-line header (rich markup) with its unit on a line of its own:
    "T [degC]" becomes "T" over "[degC]"."""
    if "\n" in header or not header.endswith("]"):
        return header
    cut = max(header.rfind(" \\["), header.rfind(" ["))
    if cut <= 0:
        return header
    return f"{header[:cut]}\n{header[cut + 1 :]}"


def _style(table: Table, wrap: Sequence[str]) -> None:
    from rich import box

    for column in table.columns:
        if isinstance(column.header, str):
            column.header = _unit_line(column.header)
        # Only the named text columns wrap (at spaces); numbers are never folded, and a
        # number too wide for its column folds rather than printing as "1.2…".
        column.no_wrap = not any(header_text(column).startswith(w) for w in wrap)
        column.overflow = "fold"
    if _DISPLAY.plain:
        table.box = None
        table.show_edge = False
        table.pad_edge = False
        table.header_style = ""
        table.title_style = ""
        table.border_style = ""
    elif table.box is None:
        table.box = box.HEAVY_HEAD


_PLAIN_NUMBER = re.compile(r"^([-+]?)(\d+)(?:\.(\d+))?$")


def _significant(integer: str, fraction: str) -> int:
    """The significant digits of a plain decimal number's digits."""
    digits = (integer + fraction).lstrip("0")
    return len(digits) if digits else 1


def align_decimals(cells: list[str]) -> list[str]:
    """Restore the trailing zeros that ``g`` formatting drops, so that a column's numbers
    align ("22.50" under "34.15", not "22.5"): every plain decimal number (no exponent)
    gets zeros up to the column's most decimals, but never more significant digits than
    the column's most precise number shows (a zero is only put back where it is one of
    the figures the column is printed to). Other cells ("-", "inf", "no") are left alone.

    >>> align_decimals(["34.15", "22.5", "13.86"])
    ['34.15', '22.50', '13.86']
    >>> align_decimals(["0.08366", "0.1152", "0.13", "-"])
    ['0.08366', '0.1152', '0.1300', '-']
    >>> align_decimals(["-40", "25", "100"])
    ['-40', '25', '100']
    """
    parsed = [_PLAIN_NUMBER.match(cell.strip()) for cell in cells]
    numbers = [m for m in parsed if m is not None]
    if not numbers:
        return cells
    decimals = max(len(m.group(3) or "") for m in numbers)
    if decimals == 0:
        return cells
    # A small number "g" wrote with an exponent (9.1e-05 among 0.0001638): in the column's
    # decimals when that keeps all its figures.
    cells = list(cells)
    for i, (cell, m) in enumerate(zip(cells, parsed, strict=True)):
        fixed = _fixed(cell.strip(), decimals) if m is None else None
        if fixed is not None:
            cells[i] = fixed
            parsed[i] = _PLAIN_NUMBER.match(fixed)
    precision = max(_significant(m.group(2), m.group(3) or "") for m in numbers)
    out = []
    for cell, m in zip(cells, parsed, strict=True):
        if m is None:
            out.append(cell)
            continue
        sign, integer, fraction = m.group(1), m.group(2), m.group(3) or ""
        room = precision - _significant(integer, fraction)
        if integer.strip("0") == "" and fraction.strip("0") == "":
            room = decimals - len(fraction)  # zero itself: "0.000" beside "0.125"
        pad = max(0, min(decimals - len(fraction), room))
        if pad == 0:
            out.append(cell)
        else:
            out.append(f"{sign}{integer}.{fraction}{'0' * pad}")
    return out


_EXPONENT = re.compile(r"^[-+]?\d(?:\.(\d+))?e([-+]\d+)$")


def _fixed(cell: str, decimals: int) -> str | None:
    """``9.1e-05`` as ``0.000091`` when ``decimals`` decimals hold all its figures."""
    m = _EXPONENT.match(cell)
    if m is None:
        return None
    needed = len(m.group(1) or "") - int(m.group(2))
    if int(m.group(2)) >= 0 or needed > decimals:
        return None
    return f"{float(cell):.{needed}f}"


def _align_numbers(table: Table) -> None:
    """:func:`align_decimals` on every column whose cells are all plain strings."""
    for column in table.columns:
        cells = column._cells
        if cells and all(isinstance(cell, str) for cell in cells):
            column._cells = list[Any](align_decimals([str(cell) for cell in cells]))


def _parse_once(console: Console, table: Table) -> None:
    """Replace each str header and cell with the Text rich makes of it.

    rich parses a str cell (markup, emoji codes) again each time it measures or renders
    it: three times or more per table here (:func:`_needed`, then the print, which
    measures before it renders), about half the time spent printing the tables.
    ``render_str`` with the column's ``highlight`` is what rich's Table does with a str
    cell, so the printed table is the same.
    """
    for column in table.columns:
        if isinstance(column.header, str):
            column.header = console.render_str(column.header, highlight=column.highlight)
        column._cells = [
            console.render_str(cell, highlight=column.highlight) if isinstance(cell, str) else cell
            for cell in column._cells
        ]


def fit(console: Console, table: Table, drop: Sequence[str] = ()) -> list[str]:
    """Hide ``drop`` columns (header prefixes, first hidden first) until ``table`` fits.

    Returns the hidden columns' headers. With ``--wide`` nothing is hidden.
    """
    return _hide(console, table, drop)[0]


def _hide(console: Console, table: Table, drop: Sequence[str]) -> tuple[list[str], int | None]:
    """:func:`fit`, also returning the width the table needs as it is left, where that
    was measured (None where a column was hidden after the last measurement): measuring
    renders every cell, so :func:`show` does not measure the same table twice."""
    if _DISPLAY.wide:
        return [], None
    hidden: list[str] = []
    needed: int | None = None
    for prefix in drop:
        needed = _needed(console, table)
        if needed <= console.width or len(table.columns) < 2:
            break
        # The header itself, else the first one that starts with it ("p" is not "parameter").
        names = [header_text(column) for column in table.columns]
        exact = [j for j, name in enumerate(names) if name == prefix]
        starts = [j for j, name in enumerate(names) if name.startswith(prefix)]
        found = (exact or starts)[:1]
        for j in found:
            hidden.append(names[j])
            del table.columns[j]
            needed = None
    return hidden, needed


def show(
    console: Console, table: Table, drop: Sequence[str] = (), wrap: Sequence[str] = ()
) -> None:
    """Print ``table`` to fit the console (see the module docstring).

    ``drop``: header prefixes of secondary columns, in the order they are hidden when the
    table is too wide. ``wrap``: header prefixes of text columns that may wrap at spaces
    (every other column prints on one line). A header's unit goes on a line of its own.
    A dim line after the table names any hidden column and ``--wide``.
    """
    from rich.measure import Measurement

    _style(table, wrap)
    _align_numbers(table)
    _parse_once(console, table)
    hidden, needed = _hide(console, table, drop)
    if (
        not _DISPLAY.wide
        and (needed if needed is not None else _needed(console, table)) > console.width
    ):
        # Still too wide: let every column with spaces in its cells wrap there, so that
        # rich narrows those rather than cutting a number or a name without spaces.
        options = console.options.update(width=100_000)
        for column in table.columns:
            cells = [c for c in [column.header, *column._cells] if c is not None]
            sizes = [Measurement.get(console, options, cell) for cell in cells]
            column.no_wrap = all(m.minimum == m.maximum for m in sizes)
    if _DISPLAY.wide:
        # As wide as the table needs: --wide cuts nothing, even beyond the terminal.
        options = console.options.update(width=100_000)
        need = Measurement.get(console, options, table).maximum
        # (print's width= is capped at the console's width: widen the console itself.)
        width = console.width
        console.width = max(width, need)
        try:
            _print(console, table)
        finally:
            console.width = width
    else:
        _print(console, table)
    if hidden:
        note(console, f"not shown at {console.width} columns: {'; '.join(hidden)} (--wide)")


def _print(console: Console, table: Table) -> None:
    """Print a table; with ``--plain`` without the spaces rich pads each line with."""
    if not _DISPLAY.plain:
        console.print(table)
        return
    with console.capture() as captured:
        console.print(table)
    lines = captured.get().splitlines()
    console.file.write("".join(line.rstrip() + "\n" for line in lines))


def note(console: Console, text: str) -> None:
    """A dim note line (plain text with ``--plain``), wrapped to the console's width."""
    from rich.markup import escape

    # Without colours (a pipe, a file, --plain) highlighting would only add styles that
    # are never shown, after compiling rich's highlighter's regular expressions.
    highlight = False if console.color_system is None else None
    console.print(escape(text), style="" if _DISPLAY.plain else "dim", highlight=highlight)


def _no_type(ctx: _click.Context) -> str | None:
    return None


def _quiet_flags(params: list[_click.Parameter]) -> None:
    from typer.core import TyperArgument, TyperOption

    for param in params:
        # A flag takes no value: show no "<bool>" type after it in --help.
        if isinstance(param, TyperOption) and param.is_flag and param.metavar is None:
            param.metavar = ""
        # An argument named by its metavar (CONFIG, CSV) needs no "<path>" beside it.
        if isinstance(param, TyperArgument) and param.metavar is not None:
            param.display_type_rich = _no_type  # type: ignore[method-assign]


# ``{install:EXTRA}`` in a command's epilog: the command that installs ``ecdsim[EXTRA]``
# here (:func:`with_install_commands`).
_INSTALL = re.compile(r"\{install:([a-z]+)\}")


def with_install_commands(epilog: str) -> str:
    """``epilog`` with each ``{install:EXTRA}`` replaced by this installation's command
    for ``ecdsim[EXTRA]`` (ecdsim.invocation.pip_install: ``.venv/bin/python -m pip
    install -e '.[fmu]'`` in a checkout), escaped for rich markup.

    Filled in only when the help is shown, so that naming the command costs start-up
    nothing (it looks up the PATH and the working folder).
    """
    if "{install:" not in epilog:
        return epilog
    from rich.markup import escape

    from ecdsim.invocation import pip_install

    return _INSTALL.sub(lambda found: escape(pip_install(found.group(1))), epilog)


class HelpCommand(TyperCommand):
    """A command whose --help shows no ``<bool>`` after flags (``--json``, ``--help``),
    run with the garbage collector on (:meth:`invoke`), and whose epilog may name an
    install command (:func:`with_install_commands`)."""

    collect = True  # turn the garbage collector on again as the command starts

    def format_help(self, ctx: _click.Context, formatter: _click.HelpFormatter) -> None:
        """The help, the epilog's install commands filled in for this installation (the
        placeholder kept, so that help shown again from another folder is right too)."""
        written = self.epilog
        try:
            if written:
                self.epilog = with_install_commands(written)
            super().format_help(ctx, formatter)
        finally:
            self.epilog = written

    def get_params(self, ctx: _click.Context) -> list[_click.Parameter]:
        """The parameters, flags with an empty metavar."""
        params = super().get_params(ctx)
        _quiet_flags(params)
        return params

    def invoke(self, ctx: _click.Context) -> Any:
        """Run the command, with the garbage collector on again (``cli.common.pause_gc``)
        unless the command is a :class:`QuickCommand`."""
        if self.collect:
            resume_gc()
        return super().invoke(ctx)


class QuickCommand(HelpCommand):
    """A :class:`HelpCommand` that runs in a fraction of a second (``deploy``, ``demo``,
    ``fit drop-test``), with the garbage collector left off as the command line started
    it (``cli.common.pause_gc``).

    Such a command spends most of its time importing what it uses (NumPy, pydantic's
    config schema, rich): objects that live until the process ends, over which the
    collector would run some 40 times more (about 5 ms). Reference counting frees the
    rest; the process ends with the command.
    """

    collect = False


class HelpGroup(TyperGroup):
    """A command group whose --help shows no ``<bool>`` after flags, and each command's
    summary as one paragraph."""

    def get_params(self, ctx: _click.Context) -> list[_click.Parameter]:
        """The parameters, flags with an empty metavar."""
        params = super().get_params(ctx)
        _quiet_flags(params)
        return params

    def get_command(self, ctx: _click.Context, cmd_name: str) -> _click.Command | None:
        """The command, its summary in the group's list the first paragraph of its help
        with the docstring's line breaks joined: typer's rich mode keeps them, and the
        list showed a summary broken mid-sentence at the docstring's width."""
        command = super().get_command(ctx, cmd_name)
        if command is not None and command.short_help is None and command.help:
            first = command.help.split("\n\n", 1)[0]
            command.short_help = " ".join(first.split())
        return command

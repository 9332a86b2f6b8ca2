"""What every command shares: user errors, temperature options, loading and predicting.

The subcommand modules (:mod:`ecdsim.cli.fit`, ``montecarlo``, ``report``, ``size``) and
:mod:`ecdsim.cli.app` import these from here, never from each other, so the command
line has no import cycle. Only typer is imported at start-up; the library is imported
inside the functions, so that ``ecdsim --help`` stays fast.
"""

from __future__ import annotations

import gc
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.deployment import Prediction
    from ecdsim.units_display import UnitSystem

USER_ERROR = 2

# Whether pause_gc turned the collector off (and resume_gc is to turn it on again).
_gc_paused = False


def pause_gc() -> None:
    """Turn the cyclic garbage collector off while the command line starts.

    Parsing the command line imports pydantic and builds typer's option adapters, and a
    short command then imports NumPy, the config schema and rich: tens of thousands of
    objects that live as long as the process, over which the collector would run some
    70 times (about 10 ms of a ``deploy``) and free nothing of note. :func:`resume_gc`
    turns it on again as a command starts (``display.HelpCommand.invoke``), so that a
    long command (a Monte Carlo run, the explorer) collects as usual; a
    ``display.QuickCommand`` (``deploy``, ``demo``, ``fit drop-test``) runs without it,
    reference counting freeing the rest, and the process ends with it. Without effect if
    the collector is already off.
    """
    global _gc_paused
    if gc.isenabled():
        gc.disable()
        _gc_paused = True


def resume_gc() -> None:
    """Turn the collector on again if :func:`pause_gc` turned it off."""
    global _gc_paused
    if _gc_paused:
        _gc_paused = False
        gc.enable()


# The variables OpenBLAS reads for the size of its thread pool, in its order of priority.
_BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")


def import_numpy_single_threaded() -> None:
    """Import NumPy with OpenBLAS's thread pool off, unless the user sized it.

    NumPy's OpenBLAS starts one worker thread per further core when it is loaded, and
    each worker spins waiting for work before it sleeps: about 30 ms of CPU time of a
    ``deploy`` (its whole start-up is some 250 ms), taken from the core the command runs
    on when the machine is busy. ``deploy``, ``demo`` and ``fit drop-test`` call it
    first: what they hand BLAS is small (6 x 6 matrices, least squares over a drop
    test's rows), mostly below the sizes at which OpenBLAS splits work between threads,
    and the shipped examples' output is the same byte for byte either way.
    ``OPENBLAS_NUM_THREADS`` is read once, as the library loads; it is removed again at
    once, so that no child process inherits it. Without effect once NumPy is imported,
    or with a BLAS other than OpenBLAS.
    """
    if "numpy" in sys.modules or any(name in os.environ for name in _BLAS_THREADS):
        return
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    try:
        import numpy  # noqa: F401  (loads OpenBLAS now, with one thread)
    finally:
        del os.environ["OPENBLAS_NUM_THREADS"]


def terminal_width() -> int:
    """The terminal's width: ``COLUMNS``, else the real width, else 80 (a pipe, a file)."""
    import shutil

    return max(shutil.get_terminal_size((80, 24)).columns, 20)


def echo_wrapped(text: str, *, err: bool = True) -> None:
    """A ``warning:`` or ``note:`` line on stderr, wrapped at spaces to the terminal's
    width (80 in a pipe) with its continuation lines indented, so that every line fits
    and each message still starts with its word. Long words (a path) are never cut."""
    import textwrap

    lines = textwrap.wrap(
        text,
        terminal_width(),
        subsequent_indent="  ",
        break_long_words=False,
        break_on_hyphens=False,
    )
    typer.echo("\n".join(lines) if lines else text, err=err)


def note_created_folders() -> None:
    """Say on stderr, in a note, whenever an output creates a folder that did not exist
    (``-o new/dir/file``): a mistyped folder name does not pass unnoticed. The writes go
    through :mod:`ecdsim.atomic`, which tells its listeners; registered once per process,
    as a command starts (``cli.app``'s root callback)."""
    from ecdsim import atomic

    atomic.on_folder_created(_note_folder)


def _note_folder(folder: Path) -> None:
    # One line, not wrapped: the path stays whole (as the report's note always was).
    typer.echo(f"note: created the folder {folder} (it did not exist)", err=True)


def fail(problems: list[str]) -> NoReturn:
    """Print user errors on stderr, one line each, and exit with code 2."""
    for problem in problems:
        typer.echo(f"error: {problem}", err=True)
    raise typer.Exit(USER_ERROR)


def os_error_line(option: str, path: Path | str, exc: OSError) -> str:
    """The one line for an OSError met while a command writes ``path`` (given by
    ``option``): "cannot write", except where the system ran out of memory (ENOMEM, e.g.
    a large mapping refused), which is not a writing problem and is said as such.

    >>> os_error_line("--out", "run", OSError(12, "Cannot allocate memory"))
    '--out run: out of memory (Cannot allocate memory)'
    """
    import errno

    if exc.errno == errno.ENOMEM:
        return f"{option} {path}: out of memory ({exc.strerror or exc})"
    return f"{option} {path}: cannot write ({exc.strerror or exc})"


UnitsOpt = Annotated[
    str | None,
    typer.Option(
        "--units",
        help="Units of tables, plots and report: si or us (degF, lbf*in, in*lbf*s/rad, "
        "lbm*in^2). Default: the config's \\[output] units, else si. JSON stays SI.",
        metavar="si|us",
    ),
]


# Every command's --plot takes a folder and writes named PNG files into it (issue 26 item 9).
# A path ending in an image suffix was the form of `repeat` and `sweep` before: still
# written as that file, with a note, for one deprecation period.
_IMAGE_SUFFIXES = (".png", ".svg", ".pdf")


def plot_file(option: Path, name: str, *, quiet: bool = False) -> Path:
    """Where a command writes its plot ``name`` (``sweep.png``) for ``--plot DIR``:
    ``DIR/name``. The old form ``--plot FILE.png`` still writes ``FILE.png``, after a
    ``note:`` on stderr saying that ``--plot`` takes a folder (unless ``quiet``)."""
    if option.suffix.lower() in _IMAGE_SUFFIXES and not option.is_dir():
        if not quiet:
            echo_wrapped(
                f"note: --plot {option}: a file name is deprecated; --plot takes a folder in "
                f"every command (--plot {option.parent} writes {option.parent / name})"
            )
        return option
    return option / name


def units_option(option: str | None, config: Config | None = None) -> UnitSystem:
    """The display unit system: ``--units`` if given, else the config's ``[output] units``.

    A value other than si or us exits with code 2 and one line naming ``--units``.
    """
    from ecdsim.units_display import UnitSystemError, check_system

    try:
        if option is not None:
            return check_system(option, "--units")
        if config is not None:
            return check_system(config.spec.output.units, "output.units")
    except UnitSystemError as exc:
        fail([str(exc)])
    return "si"


def parse_temperature(text: str) -> float:
    """A temperature option's value [degC]; a bare number is degC, the field's convention.

    Any temperature unit pint knows may be given ("233.15 K", "-40 degF"). The value is
    read by :func:`ecdsim.config.units.parse_temperature`, under the config file's rule,
    so the command line refuses what the file refuses (a temperature at or below
    absolute zero among them): raises :class:`~ecdsim.config.units.QuantityError`
    naming the value and the expected unit.
    """
    from ecdsim.config.units import parse_temperature as parse

    return parse(text if any(c.isalpha() for c in text) else f"{text} degC")


def temperature_option(option: str, text: str) -> float:
    """:func:`parse_temperature`, or exit with code 2 and one line naming ``option``."""
    from ecdsim.config.units import QuantityError

    try:
        return parse_temperature(text)
    except QuantityError as exc:
        fail([f"{option}: {exc}"])


def temperature_options(texts: list[str], problems: list[str]) -> tuple[float, ...]:
    """Each ``--temperature`` parsed (:func:`parse_temperature`); a bad one adds its line
    to ``problems`` (reported with the others, all at once) and is left out."""
    from ecdsim.config.units import QuantityError

    parsed = []
    for text in texts:
        try:
            parsed.append(parse_temperature(text))
        except QuantityError as exc:
            problems.append(f"--temperature: {exc}")
    return tuple(parsed)


def load_run(
    config_path: Path, temperatures: list[str] | None, methods: list[str] | None
) -> Config:
    """The config file, with the ``--temperature`` and ``--method`` overrides applied.

    Every problem (the file's, each bad temperature, each unknown method) is reported at
    once, one line each, with exit code 2.
    """
    from dataclasses import replace

    from ecdsim.config import ConfigError, load_config
    from ecdsim.methods import SOLVERS

    try:
        config = load_config(config_path)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    problems: list[str] = []
    temps = config.temperatures
    if temperatures:
        temps = temperature_options(temperatures, problems)
    chosen = config.methods
    if methods:
        unknown = [m for m in methods if m not in SOLVERS]
        problems += [
            f"--method: {m!r} is not a method; expected one of {sorted(SOLVERS)}" for m in unknown
        ]
        chosen = tuple(methods)
    if problems:
        fail(problems)
    warn_placeholder(config)
    return replace(config, temperatures=temps, methods=chosen)


def is_placeholder(config: Config) -> bool:
    """True when the config's ``[load]`` is a marked placeholder (the one check of
    :mod:`ecdsim.config.placeholder`, which every output of such a config asks)."""
    from ecdsim.config.placeholder import is_placeholder as marked

    return marked(config)


def warn_placeholder(config: Config) -> None:
    """A ``warning:`` on stderr when the config's load is a placeholder: every command
    that reads such a file says so until the line is deleted (issue 26 item 2)."""
    from ecdsim.config.placeholder import warning_text

    if is_placeholder(config):
        echo_wrapped(f"warning: {warning_text(config.source)}")


def predict_run(config: Config) -> Prediction:
    """:func:`ecdsim.deployment.predict` on a loaded config; a domain error exits 2."""
    from ecdsim.deployment import ModelDomainError, predict, with_flight

    try:
        dynamics = config.spec.dynamics()
        # With [load.gravity], the flight (0 g) twin too: the output shows both.
        return with_flight(
            predict(config.system, config.temperatures, config.methods, dynamics=dynamics),
            dynamics,
        )
    except ModelDomainError as exc:
        fail([f"{config.source}: {exc}"])


def echo_warnings(prediction: Prediction, units: UnitSystem = "si") -> None:
    """Print the prediction's findings on stderr, one ``warning:`` line each, in ``units``."""
    from ecdsim.units_display import convert_text

    for warning in prediction.warnings:
        where = f"[{warning.method}] " if warning.method else ""
        echo_wrapped(f"warning: {where}{convert_text(warning.message, units)}")

"""``ecdsim``: the command-line entry point.

It defines ``deploy`` and ``demo`` and registers the other commands from their modules
(``fit``, ``size``, ``montecarlo``, ``report``); what they all share (``fail``, loading a
config with its overrides, predicting) is in :mod:`ecdsim.cli.common`. Commands import
the library lazily so that ``ecdsim --help`` starts fast. User errors (bad config, bad
arguments, a model asked outside its domain) print one line per problem on stderr and
exit with code 2, with no traceback.
"""

from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ecdsim._version import __version__
from ecdsim.cli import display, failon
from ecdsim.cli.common import (
    USER_ERROR,
    UnitsOpt,
    echo_warnings,
    fail,
    import_numpy_single_threaded,
    is_placeholder,
    load_run,
    note_created_folders,
    pause_gc,
    predict_run,
    resume_gc,
    units_option,
)
from ecdsim.cli.display import HelpCommand, HelpGroup, PlainOpt, QuickCommand, WideOpt
from ecdsim.cli.drivetest import EPILOG as DRIVE_EPILOG
from ecdsim.cli.drivetest import drive_test
from ecdsim.cli.fit import fit_app
from ecdsim.cli.fluidfit import EPILOG as FLUID_FIT_EPILOG
from ecdsim.cli.fluidfit import fluid_damper
from ecdsim.cli.fmu import EPILOG as FMU_EPILOG
from ecdsim.cli.fmu import export_fmu
from ecdsim.cli.margin import EPILOG as MARGIN_EPILOG
from ecdsim.cli.margin import margin
from ecdsim.cli.montecarlo import EPILOG as MONTECARLO_EPILOG
from ecdsim.cli.montecarlo import montecarlo
from ecdsim.cli.precompile import EPILOG as PRECOMPILE_EPILOG
from ecdsim.cli.precompile import precompile
from ecdsim.cli.reliability import reliability_app
from ecdsim.cli.repeat import EPILOG as REPEAT_EPILOG
from ecdsim.cli.repeat import repeat
from ecdsim.cli.report import APP_EPILOG, REPORT_EPILOG, explore, report
from ecdsim.cli.size import FLUID_EPILOG, SIZE_EPILOG, compare_fluid, size
from ecdsim.cli.sweep import EPILOG as SWEEP_EPILOG
from ecdsim.cli.sweep import sweep

if TYPE_CHECKING:
    from ecdsim.deployment import Prediction
    from ecdsim.units_display import UnitSystem

__all__ = ["USER_ERROR", "app", "main"]

app = typer.Typer(
    name="ecdsim",
    help=(
        "Model, size and verify eddy current dampers (ECDs) in spring-driven deployments.\n\n"
        "Example: [bold]ecdsim deploy examples/paper_cc16.toml --plot plots[/bold]"
    ),
    rich_markup_mode="rich",
    cls=HelpGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"ecdsim {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version_callback, is_eager=True, help="Print the version."
        ),
    ] = False,
) -> None:
    """Model, size and verify eddy current dampers in spring-driven deployments."""
    note_created_folders()  # every command: say when an output creates a folder


def _write_timeseries(prediction: Prediction, path: Path, as_json: bool) -> None:
    from ecdsim.atomic import write_text

    # The first method, in the order asked, whose solution records a time series.
    recorded = (s.time_series_csv() for s in prediction.solutions.values())
    text = next((csv for csv in recorded if csv is not None), None)
    if text is None:
        fail(["--timeseries needs the dynamic method (--method dynamic, or in [analysis])"])
    try:
        write_text(path, text)
    except OSError as exc:
        fail([f"--timeseries {path}: cannot write ({exc.strerror or exc})"])
    typer.echo(f"wrote {path}", err=as_json)


def _render(
    prediction: Prediction,
    as_json: bool,
    plot_dir: Path | None,
    units: UnitSystem = "si",
    placeholder: bool = False,
) -> None:
    from ecdsim.cli import render

    if plot_dir is not None:
        from ecdsim.plotting import write_deployment_plots
        from ecdsim.plotting_dynamic import write_dynamic_plots

        try:
            written = write_deployment_plots(prediction, plot_dir, units)
            # With the dynamic method: angle and speed against time with the events
            # marked, and the damper's temperature when it heats.
            written += write_dynamic_plots(prediction, plot_dir, units)
        except OSError as exc:
            fail([f"--plot {plot_dir}: cannot write plots ({exc.strerror or exc})"])
    else:
        written = []
    if as_json:
        typer.echo(render.to_json(prediction, units, placeholder))
    else:
        render.print_tables(prediction, units, placeholder)
    echo_warnings(prediction, units)
    for path in written:
        typer.echo(f"wrote {path}", err=as_json)


ConfigArg = Annotated[
    Path, typer.Argument(help="TOML configuration file (see docs/config.md).", metavar="CONFIG")
]
JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print stable JSON on stdout (docs/json.md).")
]
PlotOpt = Annotated[
    Path | None, typer.Option("--plot", help="Write PNG plots into this folder.", metavar="DIR")
]
TempOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--temperature",
        "-T",
        help="Analysis temperature, repeatable; overrides \\[analysis] (bare numbers are degC).",
        metavar="TEMP",
    ),
]
MethodOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--method",
        "-m",
        help="Solver, repeatable: paper, exact, dynamic. Overrides \\[analysis].",
        metavar="METHOD",
    ),
]
TimeseriesOpt = Annotated[
    Path | None,
    typer.Option(
        "--timeseries",
        help="Write the dynamic method's time series (one block per temperature) as CSV.",
        metavar="FILE.csv",
    ),
]


@app.command(
    cls=QuickCommand,
    epilog=(
        "Example: [bold]ecdsim deploy examples/paper_cc16.toml -T -40 -T 25 -T 100 --json[/bold]"
    ),
)
def deploy(
    config: ConfigArg,
    as_json: JsonOpt = False,
    plot: PlotOpt = None,
    temperature: TempOpt = None,
    method: MethodOpt = None,
    timeseries: TimeseriesOpt = None,
    fail_on: failon.FailOnOpt = None,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Predict deployment time, speeds and stall at each temperature (paper Eq. 1-13);
    a wing file: each hinge's latching over temperature (docs/wing.md)."""
    display.configure(wide=wide, plain=plain)
    import_numpy_single_threaded()
    from ecdsim.cli.wing import is_wing_file, run_wing

    if is_wing_file(config):
        given = {
            "--method": bool(method),
            "--timeseries": timeseries is not None,
            "--fail-on": bool(fail_on),
            "--units": units is not None and units.strip().lower() != "si",
        }
        refused = [name for name, present in given.items() if present]
        if refused:
            fail(
                [
                    f"{option}: not taken with a wing file (its table is SI; docs/wing.md)"
                    for option in refused
                ]
            )
        run_wing(config, as_json, plot, temperature)
        return
    conditions = failon.parse(fail_on)
    loaded = load_run(config, temperature, method)
    system = units_option(units, loaded)
    failon.require_requirements(conditions, loaded)
    prediction = predict_run(loaded)
    if timeseries is not None:
        _write_timeseries(prediction, timeseries, as_json)
    _render(prediction, as_json, plot, system, is_placeholder(loaded))
    reasons = failon.stall_reasons(prediction) if "stall" in conditions else []
    if "requirements" in conditions:
        reasons += failon.requirement_reasons(loaded)
    failon.finish(conditions, reasons)


@app.command(cls=QuickCommand, epilog="Example: [bold]ecdsim demo --out ecdsim-demo[/bold]")
def demo(
    out: Annotated[
        Path, typer.Option("--out", help="Folder for the demo's plots.", metavar="DIR")
    ] = Path("ecdsim-demo"),
    wide: WideOpt = False,
    plain: PlainOpt = False,
    units: UnitsOpt = None,
) -> None:
    """Run the paper's Cc-16 example (section 6) and write its plots."""
    display.configure(wide=wide, plain=plain)
    import_numpy_single_threaded()
    from importlib.resources import as_file, files

    from ecdsim.atomic import write_text

    resource = files("ecdsim") / "data" / "paper_cc16.toml"
    with as_file(resource) as path:
        loaded = load_run(path, None, None)
        text = path.read_text(encoding="utf-8")
    system = units_option(units, loaded)
    # The example ships inside the package, wherever ecdsim is installed: copy it beside
    # the plots so that the path printed exists, to edit and run with `ecdsim deploy`.
    try:
        config = write_text(out / "paper_cc16.toml", text)
    except OSError as exc:
        fail([f"--out {out}: cannot write ({exc.strerror or exc})"])
    # Two lines, so that they fit 80 columns with the default folder (issue 14 item 2). The
    # command as it runs here: after make demo, .venv/bin/ecdsim is not on the PATH.
    from ecdsim.invocation import ecdsim_command

    command = ecdsim_command()
    typer.echo(f"{loaded.system.name}\nconfig: {config}\nedit it, then: {command} deploy {config}")
    _render(predict_run(loaded), False, out, system)


# Registered after deploy and demo so that --help lists the commands in the order users
# ask their questions: deploy, characterise, size, tolerances, report.
fit_app.command("drive-test", cls=HelpCommand, epilog=DRIVE_EPILOG)(drive_test)
fit_app.command("fluid-damper", cls=HelpCommand, epilog=FLUID_FIT_EPILOG)(fluid_damper)
app.add_typer(fit_app, name="fit", help="Fit BECD(T) and FECD(T) to bench data (paper section 7).")
app.command(cls=HelpCommand, epilog=SIZE_EPILOG)(size)
app.command(cls=HelpCommand, name="compare-fluid", epilog=FLUID_EPILOG)(compare_fluid)
app.command(cls=HelpCommand, epilog=MARGIN_EPILOG)(margin)
app.add_typer(reliability_app, name="reliability")
app.command(cls=HelpCommand, epilog=MONTECARLO_EPILOG)(montecarlo)
app.command(cls=HelpCommand, epilog=SWEEP_EPILOG)(sweep)
app.command(cls=HelpCommand, epilog=REPEAT_EPILOG)(repeat)
app.command(cls=HelpCommand, name="export-fmu", epilog=FMU_EPILOG)(export_fmu)
app.command(cls=HelpCommand, epilog=REPORT_EPILOG)(report)
app.command(cls=HelpCommand, name="app", epilog=APP_EPILOG)(explore)
app.command(cls=HelpCommand, epilog=PRECOMPILE_EPILOG)(precompile)


def only(name: str) -> typer.Typer:
    """``app`` with only the command or group ``name`` registered (``app`` itself when
    ``name`` is none of them).

    typer builds the click command of every registered command before it parses the
    arguments (reading each function's signature and evaluating its annotations), about
    20 ms for all of them: a command that is named needs only its own, and the root
    callback's ``--version``. Its help, usage lines and errors are the same
    (``tests/test_cli_lean_app.py``).
    """
    from typer.main import get_command_name

    commands = [
        c
        for c in app.registered_commands
        if c.callback is not None and (c.name or get_command_name(c.callback.__name__)) == name
    ]
    groups = [g for g in app.registered_groups if g.name == name]
    if not commands and not groups:
        return app
    lean = copy.copy(app)
    lean.registered_commands = commands
    lean.registered_groups = groups
    return lean


def main() -> None:
    """Console-script entry point: the command named first is the only one built, with
    the garbage collector off until the command runs (:func:`~ecdsim.cli.common.pause_gc`)."""
    pause_gc()
    try:
        only(sys.argv[1] if len(sys.argv) > 1 else "")()
    finally:
        resume_gc()

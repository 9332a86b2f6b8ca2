"""``ecdsim fit drive-test``: reduce a hinge's drive test (docs/qualification.md).

Registered on the ``fit`` group by :mod:`ecdsim.cli.app`. Only typer is imported at
start-up; the library inside the command. User errors print one ``error:`` line each and
exit with code 2.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ecdsim.cli import display
from ecdsim.cli.common import UnitsOpt, fail, units_option
from ecdsim.cli.display import PlainOpt, WideOpt

if TYPE_CHECKING:
    from ecdsim.characterize.drivetest import DriveTestResult
    from ecdsim.units_display import Shown

EPILOG = (
    "Example: [bold]ecdsim fit drive-test examples/drive_test.csv --config "
    "examples/paper_cc16_budget.toml -o hinge.toml[/bold]"
)


def _print(result: DriveTestResult, u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    table = Table(
        title="Drive test: spring = mean of opening and closing, friction = half their difference",
        title_justify="left",
    )
    headers = [
        u.head("T", "temperature"),
        "travel [deg]",
        u.head("start", "torque"),
        u.head("end", "torque"),
        "R^2",
        "off line [%]",
        u.head("friction", "torque"),
        u.head("available", "torque"),
        "at [deg]",
    ]
    for header in headers:
        table.add_column(escape(header), justify="right")
    for c in result.curves:
        friction = c.mean_friction
        table.add_row(
            u.num(c.temperature, "temperature"),
            f"{math.degrees(c.travel):.4g}",
            u.num(c.start_torque.value, "torque"),
            u.num(c.end_torque.value, "torque"),
            f"{c.line.r_squared:.5f}",
            f"{100 * c.linear_deviation:.2g}",
            u.num(friction.value, "torque"),
            u.num(c.available, "torque"),
            f"{math.degrees(c.available_angle):.4g}",
        )
    display.show(console, table, drop=("R^2", "off line", "travel"))
    available, at_t, at_angle = result.available
    display.note(
        console,
        f"available torque (the drive's minimum): {u.text(available, 'torque')} at "
        f"{u.text(at_t, 'temperature')}, {math.degrees(at_angle):.4g} deg of travel; "
        "start and end: the spring's line; friction: its mean over the travel",
    )
    law = result.friction_law
    if law is not None:
        at_0c, slope = law.parameters

        def ci(estimate: object) -> str:
            bounds = getattr(estimate, "ci95", None)
            return "" if bounds is None else f" [{bounds[0]:.4g}, {bounds[1]:.4g}]"

        display.note(
            console,
            f"system friction over temperature, FS_T = slope * T + at_0C: slope = "
            f"{slope.value:.4g}{ci(slope)} N*m/K, at_0C = {at_0c.value:.4g}{ci(at_0c)} N*m "
            "(95 % intervals)",
        )


def drive_test(
    data: Annotated[
        Path,
        typer.Argument(
            help="CSV: angle, torque (bench reading, positive deploying), optional "
            "temperature; opening then closing (docs/qualification.md).",
            metavar="CSV",
        ),
    ],
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON on stdout.")] = False,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", help="Write PNG plots into this folder.", metavar="DIR"),
    ] = None,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Write the spring, friction and available torque into a configuration.",
            metavar="FILE",
        ),
    ] = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Configuration the -o file starts from (else a marked placeholder ECD).",
            metavar="FILE",
        ),
    ] = None,
    spring: Annotated[
        str,
        typer.Option(
            "--spring",
            help="Spring form in the -o file: auto (a table where the line is off by > 2 %), "
            "linear or table.",
            metavar="FORM",
        ),
    ] = "auto",
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Spring law, friction against angle and available torque from a drive test."""
    display.configure(wide=wide, plain=plain)

    from ecdsim.characterize.driveexport import SPRING_FORMS, drive_test_config_text
    from ecdsim.characterize.drivetest import fit_drive_test
    from ecdsim.config import ConfigError

    if spring not in SPRING_FORMS:
        fail([f"--spring: {spring!r} is not a spring form; expected {', '.join(SPRING_FORMS)}"])
    loaded = None
    user_text = None
    if config is not None:
        from ecdsim.config import load_config

        try:
            loaded = load_config(config)
            user_text = config.read_text(encoding="utf-8")
        except ConfigError as exc:
            fail([f"--config: {line}" for line in str(exc).splitlines()])
    u_system = units_option(units, loaded)
    try:
        result = fit_drive_test(data)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    bad = [b.message() for b in result.table.bad_rows]
    if not result.curves:
        fail([*bad, *(f"not reduced: {t:g} degC: {why}" for t, _, why in result.failed),
              "no temperature could be reduced"])  # fmt: skip
    from ecdsim.characterize.qualplots import write_drive_test_plots
    from ecdsim.cli.benchfit import finish_bench_fit

    finish_bench_fit(
        result,
        command="ecdsim fit drive-test",
        output=output,
        parameter_text=lambda lines: drive_test_config_text(
            result, lines, spring, user_text, config.name if config else ""
        ),
        plot=plot,
        write_plots=write_drive_test_plots,
        as_json=as_json,
        u_system=u_system,
        print_table=_print,
        bad=bad,
        not_done="not reduced",
    )

"""``ecdsim sweep``: vary config keys over a grid or a Latin hypercube, write a tidy table.

Only typer is imported at start-up; the library (:mod:`ecdsim.sweeps`) inside the command.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ecdsim.cli.common import UnitsOpt, echo_wrapped, fail

EPILOG = (
    "Example: [bold]ecdsim sweep examples/paper_cc16.toml --vary gearbox.ratio=200:600:21 "
    "--vary load.start_torque=3.2,3.73,4.2 -o sweep.csv --plot plots[/bold]"
)


def sweep(
    config: Annotated[
        Path, typer.Argument(help="TOML configuration file (see docs/config.md).", metavar="CONFIG")
    ],
    vary: Annotated[
        list[str],
        typer.Option(
            "--vary",
            help="A config key and its values, repeatable: KEY=START:STOP:N [UNIT] "
            "(N evenly spaced values) or KEY=V1,V2,... (each a number with an optional unit). "
            "Plain numbers are SI (temperatures degC).",
            metavar="KEY=VALUES",
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="The table: CSV, or Parquet if the name ends .parquet (default sweep.csv; "
            "none with --json unless given).",
            metavar="FILE",
        ),
    ] = None,
    latin: Annotated[
        int | None,
        typer.Option(
            "--latin",
            help="N points of a Latin hypercube (ranges sampled continuously) instead of the "
            "full factorial grid.",
            metavar="N",
        ),
    ] = None,
    seed: Annotated[
        int, typer.Option("--seed", help="Seed of the Latin hypercube.", metavar="SEED")
    ] = 0,
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Analysis temperature, repeatable; overrides \\[analysis] (bare numbers are "
            "degC).",
            metavar="TEMP",
        ),
    ] = None,
    method: Annotated[
        list[str] | None,
        typer.Option(
            "--method",
            "-m",
            help="Solver, repeatable: paper, exact, dynamic. Overrides \\[analysis].",
            metavar="METHOD",
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Write sweep_COLUMN.png into this folder: --column against the varied keys "
            "by --plot-method, one line per level, stalls marked.",
            metavar="DIR",
        ),
    ] = None,
    column: Annotated[
        str,
        typer.Option(
            "--column",
            help="The table column --plot draws (e.g. deployment_time_s, end_speed_rad_s).",
            metavar="COLUMN",
        ),
    ] = "deployment_time_s",
    as_json: Annotated[
        bool,
        typer.Option("--json", help="Print the table as JSON on stdout (docs/json.md)."),
    ] = False,
    plot_method: Annotated[
        str | None,
        typer.Option(
            "--plot-method",
            help="The method --plot draws. Default: the most exact method run (dynamic, "
            "else exact, else paper).",
            metavar="METHOD",
        ),
    ] = None,
    output: Annotated[
        str | None,
        typer.Option("--output", hidden=True, help="Deprecated: --column.", metavar="COLUMN"),
    ] = None,
    units: UnitsOpt = None,
) -> None:
    """Vary config keys (full factorial or Latin hypercube) and tabulate every result."""
    from ecdsim.cli.common import load_run, units_option
    from ecdsim.cli.wing import is_wing_file
    from ecdsim.config import ConfigError
    from ecdsim.config.loader import parse_toml, read_config_text
    from ecdsim.config.seeds import seed_problem
    from ecdsim.sweeps import SweepError, design, parse_vary, run_sweep

    wing = is_wing_file(config)
    if wing:  # a wing file: its keys are the file's paths (docs/wing.md, studies)
        from ecdsim.cli.wing import load_wing_run

        wing_run = load_wing_run(config, temperature, method, units)
        system = wing_run.units
    else:
        loaded = load_run(config, temperature, method)  # the base config, checked once
        system = units_option(units, loaded)
    try:
        raw = parse_toml(read_config_text(config), str(config))
    except ConfigError as exc:  # pragma: no cover - load_run read it
        fail(str(exc).splitlines())
    problems: list[str] = []
    varies = []
    for text in vary:
        try:
            varies.append(parse_vary(text))
        except SweepError as exc:
            problems.extend(exc.problems)
    if latin is not None and latin < 1:
        problems.append(f"--latin {latin}: expected a number of points >= 1")
    bad_seed = seed_problem(seed)
    if bad_seed is not None:
        problems.append(f"--seed {seed}: {bad_seed}")
    if problems:
        fail(problems)
    try:
        points = design(varies, latin, seed)
        if wing:
            from ecdsim.sizing.catalogue import load_catalogue
            from ecdsim.sweeps import run_wing_sweep

            result = run_wing_sweep(
                raw,
                str(config),
                varies,
                points,
                wing_run.temperatures,
                wing_run.config.sha256,
                read_catalogue=load_catalogue,
            )
        else:
            result = run_sweep(
                raw, str(config), varies, points, loaded.temperatures, loaded.methods, loaded.sha256
            )
    except SweepError as exc:
        fail(exc.problems)
    if output is not None:
        echo_wrapped("note: --output is deprecated: it is --column now (the plotted column)")
        column = output
    if plot is not None and column not in result.columns:
        known = [c for c in result.columns if c not in {v.column for v in varies}]
        fail([f"--column {column!r}: not a column of the table; expected one of {known}"])
    if plot is not None and plot_method is not None and plot_method not in result.methods:
        fail([f"--plot-method {plot_method!r}: not run; expected one of {list(result.methods)}"])
    if out is None and not as_json:
        out = Path("sweep.csv")
    if out is not None:
        try:
            result.write(out)
        except ModuleNotFoundError as exc:
            fail([f"--out {out}: {exc}"])
        except OSError as exc:
            fail([f"--out {out}: cannot write ({exc.strerror or exc})"])
        typer.echo(f"wrote {out} ({len(points)} points, {len(result.rows)} rows)", err=as_json)
    for index, message in result.errors:
        echo_wrapped(f"warning: point {index}: {message}")
    if as_json:
        import sys

        from ecdsim.jsonrows import write_json

        write_json(result.to_document(), sys.stdout.write)
    if plot is not None:
        from ecdsim.cli.common import plot_file
        from ecdsim.plotting import save_figure

        target = plot_file(plot, f"sweep_{_file_name(column)}.png")
        try:
            save_figure(result.plot(column, plot_method, system), target)
        except OSError as exc:
            fail([f"--plot {plot}: cannot write ({exc.strerror or exc})"])
        typer.echo(f"wrote {target}", err=as_json)


def _file_name(column: str) -> str:
    """A column name as part of a file name: ``load.start_torque_Nm`` (or, before the
    tidy column names, ``load.start_torque [N*m]``) -> ``load.start_torque_Nm``."""
    import re

    return re.sub(r"[^A-Za-z0-9.]+", "_", column).strip("_")

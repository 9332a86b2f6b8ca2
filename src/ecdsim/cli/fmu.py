"""``ecdsim export-fmu``: an FMI 2.0 FMU of the damper (C) or of the deployment (Python).

Only typer is imported at start-up; the builder (:mod:`ecdsim.fmu`) inside the command.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ecdsim.cli.common import echo_wrapped, fail

EPILOG = (
    "Example: [bold]ecdsim export-fmu examples/paper_cc16_dynamic.toml -o damper.fmu[/bold]"
    "\n\nThe damper FMU is compiled with the system's C compiler (cc) and needs no Python "
    "to run; the deployment FMU needs pythonfmu to build ({install:fmu}) "
    "and a Python with this ecdsim to run (docs/fmu.md)."
)  # {install:fmu}: this installation's command, filled in when the help is shown


def export_fmu(
    config: Annotated[
        Path, typer.Argument(help="TOML configuration file (see docs/config.md).", metavar="CONFIG")
    ],
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            "-o",
            help="The FMU file (default: damper.fmu, or deployment.fmu with --deployment).",
            metavar="FILE.fmu",
        ),
    ] = None,
    deployment: Annotated[
        bool,
        typer.Option(
            "--deployment",
            help="Export the whole spring-driven hinge (dynamic method; no inputs; outputs "
            "angle, speed, latched, status) instead of the damper.",
        ),
    ] = False,
    name: Annotated[
        str | None,
        typer.Option(
            "--name",
            help="The FMU's model identifier (default: the file name and a hash of the "
            "config, unique per export).",
            metavar="NAME",
        ),
    ] = None,
) -> None:
    """Write an FMI 2.0 FMU: the damper + gearbox at the slow shaft (model exchange and
    co-simulation, in C; inputs shaft speed and ambient temperature; outputs damper
    torque, frictions, damper temperature), or with --deployment the whole hinge
    (co-simulation, in Python)."""
    import warnings

    from ecdsim.config import ConfigError
    from ecdsim.config.placeholder import PlaceholderLoadWarning
    from ecdsim.fmu import FmuCompilerError, FmuDependencyError, FmuNameError, build_fmu

    target = out or Path("deployment.fmu" if deployment else "damper.fmu")
    if target.suffix.lower() != ".fmu":
        fail([f"--out {target}: expected a file name ending .fmu"])
    try:
        # A placeholder load: the library's warning becomes the line every command prints.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PlaceholderLoadWarning)
            written = build_fmu(config, target, deployment=deployment, name=name)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    except FmuDependencyError as exc:
        fail([str(exc)])
    except (FmuNameError, FmuCompilerError) as exc:
        fail([str(exc)])
    except OSError as exc:
        fail([f"--out {target}: cannot write ({exc.strerror or exc})"])
    for caught_warning in caught:
        if issubclass(caught_warning.category, PlaceholderLoadWarning):
            echo_wrapped(f"warning: {caught_warning.message}")
        else:  # any other warning as Python would have shown it
            warnings.showwarning(
                caught_warning.message,
                caught_warning.category,
                caught_warning.filename,
                caught_warning.lineno,
            )
    typer.echo(f"wrote {written}")

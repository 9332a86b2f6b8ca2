"""``ecdsim export-fmu``: an FMI 2.0 co-simulation FMU of the damper or the deployment.

Only typer is imported at start-up; the builder (:mod:`ecdsim.fmu`) inside the command.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ecdsim.cli.common import fail

EPILOG = (
    "Example: [bold]ecdsim export-fmu examples/paper_cc16_dynamic.toml -o damper.fmu[/bold]"
    "\n\nNeeds pythonfmu (pip install 'ecdsim\\[fmu]'); the FMU runs in a Python with "
    "ecdsim installed (docs/fmu.md)."
)


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
            "angle, speed, latched) instead of the damper.",
        ),
    ] = False,
) -> None:
    """Write an FMI 2.0 co-simulation FMU: the damper + gearbox at the slow shaft (inputs
    shaft speed and ambient temperature; outputs damper torque, friction torque, damper
    temperature), or with --deployment the whole hinge."""
    from ecdsim.config import ConfigError
    from ecdsim.fmu import FmuDependencyError, build_fmu

    target = out or Path("deployment.fmu" if deployment else "damper.fmu")
    if target.suffix.lower() != ".fmu":
        fail([f"--out {target}: expected a file name ending .fmu"])
    try:
        written = build_fmu(config, target, deployment=deployment)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    except FmuDependencyError as exc:
        fail([str(exc)])
    except OSError as exc:
        fail([f"--out {target}: cannot write ({exc.strerror or exc})"])
    typer.echo(f"wrote {written}")

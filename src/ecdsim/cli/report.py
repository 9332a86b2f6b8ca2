"""``ecdsim report`` (one self-contained HTML file, optional PDF) and ``ecdsim app`` (explorer).

Both reuse the ``deploy`` command's loading and prediction (``load_run``,
``predict_run`` in :mod:`ecdsim.cli.common`), so the numbers are those of
``ecdsim deploy --json``. FastAPI and uvicorn (the ``app`` extra) are imported only by
``ecdsim app``. User errors print ``error: ...`` lines and exit with code 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ecdsim.cli import failon
from ecdsim.cli.common import UnitsOpt, echo_warnings, fail, load_run, predict_run, units_option
from ecdsim.cli.montecarlo import INTERRUPTED

REPORT_EPILOG = "Example: [bold]ecdsim report examples/paper_cc16.toml -o report.html --pdf[/bold]"
APP_EPILOG = (
    "Example: [bold]ecdsim app examples/paper_cc16.toml[/bold], then open the printed URL "
    "(docs/report.md)"
)


def report(
    config: Annotated[
        Path,
        typer.Argument(help="TOML configuration file (see docs/config.md).", metavar="CONFIG"),
    ],
    output: Annotated[
        Path, typer.Option("--output", "-o", help="HTML file to write.", metavar="FILE.html")
    ] = Path("report.html"),
    pdf: Annotated[
        bool,
        typer.Option("--pdf", help="Also print it to FILE.pdf with headless Chromium."),
    ] = False,
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Analysis temperature, repeatable; overrides \\[analysis] (bare numbers: degC).",
            metavar="TEMP",
        ),
    ] = None,
    method: Annotated[
        list[str] | None,
        typer.Option(
            "--method", "-m", help="Solver, repeatable; overrides \\[analysis].", metavar="METHOD"
        ),
    ] = None,
    fail_on: failon.FailOnOpt = None,
    units: UnitsOpt = None,
) -> None:
    """Write a self-contained HTML report: inputs, components, deployment, plots, warnings."""
    from ecdsim.cli.wing import is_wing_file
    from ecdsim.report import write_report

    if is_wing_file(config):  # the wing's report (docs/wing.md, report)
        from ecdsim.cli.wing import wing_report

        written = wing_report(config, output, temperature, method, units, fail_on)
        if pdf:
            _write_pdf(written, output)
        return
    conditions = failon.parse(fail_on)
    loaded = load_run(config, temperature, method)
    system = units_option(units, loaded)
    failon.require_requirements(conditions, loaded)
    prediction = predict_run(loaded)
    text = config.read_text(encoding="utf-8")
    try:
        written = write_report(loaded, prediction, text, output, system)
    except OSError as exc:
        fail([f"--output {output}: cannot write ({exc.strerror or exc})"])
    except KeyboardInterrupt:
        # The write is atomic: say so, since the shell only shows ^C.
        typer.echo(
            f"interrupted: {output} not written (an earlier file there is unchanged)", err=True
        )
        raise typer.Exit(INTERRUPTED) from None
    echo_warnings(prediction, system)
    typer.echo(f"wrote {written}")
    if pdf:
        _write_pdf(written, output)
    reasons = failon.stall_reasons(prediction) if "stall" in conditions else []
    if "requirements" in conditions:
        reasons += failon.requirement_reasons(loaded)
    failon.finish(conditions, reasons)


def _write_pdf(written: Path, output: Path) -> None:
    """Print the HTML report ``written`` to ``output`` with a .pdf suffix (--pdf)."""
    from ecdsim.report.pdf import PdfUnavailable, html_to_pdf

    target = output.with_suffix(".pdf")
    try:
        html_to_pdf(written, target)
    except PdfUnavailable as exc:
        fail([str(exc)])
    except OSError as exc:
        fail([f"--pdf {target}: cannot write ({exc.strerror or exc})"])
    typer.echo(f"wrote {target}")


def explore(
    config: Annotated[
        Path | None,
        typer.Argument(
            help="TOML configuration to start from (default: the paper example).",
            metavar="CONFIG",
        ),
    ] = None,
    host: Annotated[
        str,
        typer.Option(
            "--host", help="Interface to bind; keep 127.0.0.1 (local only).", metavar="HOST"
        ),
    ] = "127.0.0.1",
    port: Annotated[int, typer.Option("--port", help="TCP port.", metavar="PORT")] = 8765,
    units: UnitsOpt = None,
) -> None:
    """Start the local explorer (web app + JSON API with OpenAPI docs at /docs)."""
    try:
        import uvicorn

        from ecdsim.webapp.server import create_app, exposure_warning
    except ImportError as exc:
        from ecdsim.invocation import install_hint

        fail(
            [
                f"ecdsim app needs the optional 'app' extra (missing module {exc.name!r}); "
                f"{install_hint('app')}"
            ]
        )
    text = None
    loaded = None
    if config is not None:
        from ecdsim.cli.wing import is_wing_file

        if is_wing_file(config):  # a wing (docs/wing.md): validated by its own reader
            _check_wing(config)
        else:
            loaded = load_run(config, None, None)  # validate first: errors exit 2
        text = config.read_text(encoding="utf-8")
    # The page starts in --units if given (else the config's [output] units) and may switch.
    system = units_option(units, loaded) if units is not None else None
    application = create_app(text, units=system, host=host)
    typer.echo(f"ecdsim explorer on http://{host}:{port}/ (Ctrl-C stops it)")
    warning = exposure_warning(host, port)
    if warning is not None:
        typer.echo(warning, err=True)
    uvicorn.run(application, host=host, port=port, log_level="warning")


def _check_wing(path: Path) -> None:
    """Validate a wing file for ``ecdsim app``; its problems exit 2, one line each."""
    from ecdsim.config import ConfigError
    from ecdsim.config.wing_schema import load_wing_config
    from ecdsim.sizing.catalogue import load_catalogue

    try:
        load_wing_config(path, read_catalogue=load_catalogue)
    except ConfigError as exc:
        fail(str(exc).splitlines())

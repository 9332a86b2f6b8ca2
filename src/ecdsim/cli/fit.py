"""``ecdsim fit``: characterise a damper from bench tests (paper section 7).

A thin shell over :mod:`ecdsim.characterize`: parse the arguments, call one library
function, render. Only typer is imported at start-up; the library, scipy, pint and
matplotlib are imported inside the commands. User errors print one ``error:`` line per
problem and exit with code 2; bad rows and flags print as ``warning:`` lines on stderr.
Exit code 2 also where nothing could be fitted, or with ``--strict`` where any row was
excluded or any temperature could not be fitted.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ecdsim.cli import display
from ecdsim.cli.common import (
    UnitsOpt,
    echo_wrapped,
    fail,
    import_numpy_single_threaded,
    temperature_option,
    units_option,
)
from ecdsim.cli.display import HelpCommand, HelpGroup, PlainOpt, QuickCommand, WideOpt
from ecdsim.units_display import KEY_SUFFIXES, Shown, UnitSystem, kind_of_key

if TYPE_CHECKING:
    from ecdsim.characterize.droptest import DropTestResult, FailedTemperature
    from ecdsim.characterize.export import FittedEcd
    from ecdsim.characterize.findings import FitWarning
    from ecdsim.characterize.stats import Estimate
    from ecdsim.characterize.templaws import TemperatureLaws
    from ecdsim.characterize.tracefit import TraceResult
    from ecdsim.config import Config

fit_app = typer.Typer(
    help=(
        "Fit the ECD's damping rate BECD(T) and friction FECD(T) to bench data "
        "(paper section 7) and write them as a configuration file."
    ),
    rich_markup_mode="rich",
    cls=HelpGroup,
    no_args_is_help=True,
    epilog="Example: [bold]ecdsim fit drop-test examples/drop_test.csv -o fitted.toml[/bold]",
)

DataArg = Annotated[
    Path,
    typer.Argument(
        help="CSV file with unit-bearing headers (docs/characterize.md).", metavar="CSV"
    ),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON on stdout.")]
PlotOpt = Annotated[
    Path | None, typer.Option("--plot", help="Write PNG plots into this folder.", metavar="DIR")
]
OutputOpt = Annotated[
    Path | None,
    typer.Option(
        "--output",
        "-o",
        help="Write the fitted parameters as a TOML configuration for `ecdsim deploy`.",
        metavar="FILE",
    ),
]
ReferenceOpt = Annotated[
    str,
    typer.Option(
        "--reference-temperature",
        help="Reference temperature T_ref of the damping laws (bare numbers are degC).",
        metavar="DEGC",
    ),
]
StrictOpt = Annotated[
    bool,
    typer.Option(
        "--strict", help="Exit with code 2 if any row is excluded or any temperature fails."
    ),
]


def _fmt(value: float | None, digits: int = 4) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:.{digits}g}"


def _ci(estimate: Estimate, digits: int = 4, u: Shown | None = None, kind: str = "") -> str:
    if estimate.ci95 is None:
        return "-"
    low, high = estimate.ci95
    if u is not None and kind:
        low, high = u.value(low, kind), u.value(high, kind)
    return f"[{low:.{digits}g}, {high:.{digits}g}]"


def _q(u: Shown, value: float | None, kind: str, digits: int = 4) -> str:
    """A fitted SI value in ``u``'s unit; "-" if missing or not finite."""
    if value is None or not math.isfinite(value):
        return "-"
    return _fmt(u.value(value, kind), digits)


# A law parameter's short name (the symbol of docs/characterize.md) by its JSON key's stem.
_PARAMETER_NAMES = {
    "damping_rate_ref": "B_ref",
    "temperature_coefficient": "c",
    "alpha": "alpha",
    "slope": "slope",
    "at_0C": "at 0 degC",
}


def _parameter(u: Shown, key: str) -> tuple[str, str]:
    """A law parameter's row label and kind: its symbol and unit, ``"B_ref [N*m*s/rad]"``
    (the JSON key, which bakes the SI unit into the name, stays in ``--json``)."""
    kind = kind_of_key(key) or "number"
    suffix = next(s for s, k in KEY_SUFFIXES if k == kind) if kind != "number" else ""
    stem = key.removesuffix(suffix) if suffix and key.endswith(suffix) else key
    name = _PARAMETER_NAMES.get(stem, stem.replace("_", " "))
    if stem == "at_0C" and u.system == "us":
        name = "at 32 degF"  # 0 degC is 32 degF
    return u.head(name, kind), kind


def _export(output: Path, build: Callable[[], str]) -> str:
    """The -o file's text from ``build``; an ``error:`` line where it cannot be written."""
    from ecdsim.characterize.export import ExportError

    try:
        return build()
    except ExportError as exc:
        fail([f"-o {output}: {exc}"])


def _not_carried(output: Path, config: Path, ecd: FittedEcd) -> list[FitWarning]:
    """A warning naming the --config's damper and gearbox keys the -o file does not hold."""
    from ecdsim.characterize.export import keys_not_carried
    from ecdsim.characterize.findings import FitWarning

    dropped = keys_not_carried(_config_text(config), ecd)
    if not dropped:
        return []
    return [
        FitWarning(
            "keys_not_carried",
            f"{output}: {', '.join(dropped)} of {config.name} not carried over: the "
            "fitted ECD is one 1:1 body at the input shaft; enter them again referred to it",
        )
    ]


def _config_text(path: Path) -> str:
    """The --config file's text, to be written back with the fit (read once loaded)."""
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        fail([f"--config {path}: cannot read ({exc.strerror or exc})"])


def _load_config(path: Path) -> Config:
    from ecdsim.config import ConfigError, load_config

    try:
        config = load_config(path)
    except ConfigError as exc:
        fail([f"--config: {line}" for line in str(exc).splitlines()])
    from ecdsim.cli.common import warn_placeholder

    warn_placeholder(config)
    return config


# Rows with problems listed one per line on stderr before the rest are summarised.
MAX_BAD_ROW_LINES = 20


def _report(
    bad_rows: list[str], failed: tuple[FailedTemperature, ...], warnings: list[FitWarning]
) -> None:
    for line in bad_rows[:MAX_BAD_ROW_LINES]:
        echo_wrapped(f"warning: {line}")
    if len(bad_rows) > MAX_BAD_ROW_LINES:
        # A large log can have thousands; all are in the --json document's bad_rows.
        hidden = len(bad_rows) - MAX_BAD_ROW_LINES
        echo_wrapped(
            f"warning: {hidden} more rows with problems not shown (all are listed under "
            "bad_rows with --json)"
        )
    for item in failed:
        typer.echo(f"error: not fitted: {item.message()}", err=True)
    for warning in warnings:
        echo_wrapped(f"warning: {warning.message}")


def _check_fitted(
    fitted: bool,
    what: str,
    bad_rows: list[str],
    failed: tuple[FailedTemperature, ...],
    strict: bool,
) -> None:
    """Fail where no ``what`` could be fitted, or with ``--strict`` where any data had problems."""
    problems = [*bad_rows, *(f"not fitted: {f.message()}" for f in failed)]
    if not fitted:
        fail([*problems, f"no {what} could be fitted"])
    if strict and problems:
        fail([*problems, "--strict: the data have problems (listed above)"])


def _fitted_ecd(
    output: Path,
    temperatures: Sequence[float],
    damping: Sequence[Estimate],
    friction: Sequence[Estimate],
    laws: TemperatureLaws | None,
) -> FittedEcd:
    """The fitted ECD for the ``-o`` file; an ``error:`` line where it cannot be written."""
    from ecdsim.characterize.export import ExportError, fitted_ecd

    try:
        return fitted_ecd(temperatures, damping, friction, laws)
    except ExportError as exc:
        fail([f"-o {output}: {exc}"])


def _write_outputs(
    text: str | None, output: Path | None, plot: Path | None, plotter: Any
) -> tuple[str | None, list[str]]:
    """Write the parameter file and the plots; their paths."""
    from ecdsim.characterize.export import ExportError, write_parameter_file

    written_file: str | None = None
    if output is not None and text is not None:
        try:
            written_file = str(write_parameter_file(output, text))
        except ExportError as exc:
            fail([f"-o {output}: {exc}"])
        except OSError as exc:
            fail([f"-o {output}: cannot write ({exc.strerror or exc})"])
    plots: list[str] = []
    if plot is not None:
        try:
            plots = [str(p) for p in plotter(plot)]
        except OSError as exc:
            fail([f"--plot {plot}: cannot write plots ({exc.strerror or exc})"])
    return written_file, plots


def _emit_json(document: dict[str, Any]) -> None:
    # Points stay columns and are streamed: a million-row log writes in seconds, in
    # bounded memory (ecdsim.jsonrows).
    import sys

    from ecdsim.jsonrows import write_json

    # Straight to the stream: typer.echo would scan every block for ANSI codes to strip
    # when stdout is not a terminal (a regex over hundreds of MB for a large log).
    write_json(document, sys.stdout.write)
    sys.stdout.flush()


def _finish(
    result: DropTestResult | TraceResult,
    bad_rows: list[str],
    warnings: list[FitWarning],
    text: str | None,
    output: Path | None,
    plot: Path | None,
    plotter: Callable[[Path], list[Path]],
    printer: Callable[[], None],
    as_json: bool,
    units: UnitSystem = "si",
) -> None:
    """Write the -o file and plots, render the result, then warnings and written paths."""
    written, plots = _write_outputs(text, output, plot, plotter)
    if as_json:
        document = result.to_dict(points_as_table=True)
        document["warnings"] = [w.to_dict() for w in warnings]
        document["parameter_file"] = written
        document["plots"] = plots
        document["display_units"] = units
        _emit_json(document)
    else:
        printer()
    _report(bad_rows, result.failed, warnings)
    for path in [*([written] if written else []), *plots]:
        typer.echo(f"wrote {path}", err=as_json)


@fit_app.command(
    "drop-test",
    cls=QuickCommand,
    epilog=(
        "Example: [bold]ecdsim fit drop-test examples/drop_test.csv --plot plots "
        "-o fitted.toml[/bold]"
    ),
)
def drop_test(
    data: DataArg,
    as_json: JsonOpt = False,
    plot: PlotOpt = None,
    output: OutputOpt = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Configuration whose \\[load] goes into the -o file (else a marked placeholder).",
            metavar="FILE",
        ),
    ] = None,
    reference_temperature: ReferenceOpt = "25",
    noise: Annotated[
        str,
        typer.Option(
            "--noise",
            help=(
                "Where the scatter lies: 'torque' (speeds exact; the default) or 'timing' "
                "(a relative error of the recorded time; masses and radius exact)."
            ),
            metavar="MODEL",
        ),
    ] = "torque",
    strict: StrictOpt = False,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Fit BECD and FECD per temperature from drop tests, then laws over temperature."""
    display.configure(wide=wide, plain=plain)
    import_numpy_single_threaded()
    from ecdsim.characterize.droptest import fit_drop_test, noise_model
    from ecdsim.characterize.export import (
        fitted_config_text,
        fitted_parameter_text,
        largest_torque,
        provenance,
    )
    from ecdsim.config import ConfigError

    reference = temperature_option("--reference-temperature", reference_temperature)
    try:
        noise = noise_model(noise).name
    except ValueError as exc:
        fail([f"--noise: {exc}"])
    loaded = _load_config(config) if config is not None else None
    u = Shown(units_option(units, loaded))
    try:
        result = fit_drop_test(data, reference, noise=noise)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    bad_rows = [b.message() for b in result.table.bad_rows]
    _check_fitted(bool(result.fits), "temperature", bad_rows, result.failed, strict)
    warnings = list(result.warnings)
    text: str | None = None
    if output is not None:
        fits = result.fits
        ecd = _fitted_ecd(
            output,
            [f.temperature for f in fits],
            [f.line.slope for f in fits],
            [f.line.intercept for f in fits],
            result.laws,
        )
        warnings.extend(ecd.warnings)
        if loaded is None:
            from ecdsim.characterize.findings import FitWarning

            warnings.append(
                FitWarning(
                    "placeholder_load",
                    f"{output}: no --config given, so its [load] is a marked placeholder; "
                    "edit it before trusting a deployment time",
                )
            )
        lines = provenance(
            f"ecdsim fit drop-test --noise {result.noise}",
            result.table.source,
            result.table.sha256,
        )
        if config is not None:
            # The user's file as written, with the fitted ECD (comments, title, units kept).
            text = _export(
                output, lambda: fitted_config_text(_config_text(config), ecd, lines, config.name)
            )
            warnings.extend(_not_carried(output, config, ecd))
        else:
            text = fitted_parameter_text(
                ecd,
                None,
                largest_torque([t for f in fits for t in f.torque]),
                f"ECD fitted from drop tests ({Path(data).name})",
                lines,
            )

    def plotter(folder: Path) -> list[Path]:
        from ecdsim.characterize.plots import write_drop_test_plots

        return write_drop_test_plots(result, folder, u.system)

    _finish(
        result,
        bad_rows,
        warnings,
        text,
        output,
        plot,
        plotter,
        lambda: _print_drop_test(result, u),
        as_json,
        u.system,
    )


def _print_drop_test(result: DropTestResult, u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    name = result.noise
    table = Table(
        title=(f"Drop test: torque = FECD + BECD * speed (paper Eq. 5, Figure 8), --noise {name}"),
        title_justify="left",
    )
    headers = [
        u.head("T", "temperature"),
        "n",
        u.head("BECD", "damping_rate"),
        "95 % CI",
        u.head("FECD", "torque"),
        "95 % CI",
        "R^2",
        "start-up corr. [%]",
        "flags",
    ]
    for header in headers:
        table.add_column(escape(header), justify="left" if header == "flags" else "right")
    for fit in result.fits:
        line = fit.line
        flags = []
        if line.curvature is not None and line.curvature.bending:
            flags.append("roll-off" if line.curvature.roll_off else "bends up")
        if line.outliers.any():
            flags.append("outlier rows " + ", ".join(str(int(r)) for r in fit.rows[line.outliers]))
        correction = float(abs(fit.correction).max()) * 100.0
        table.add_row(
            u.num(fit.temperature, "temperature"),
            str(line.n_points),
            _q(u, line.slope.value, "damping_rate"),
            _ci(line.slope, u=u, kind="damping_rate"),
            _q(u, line.intercept.value, "torque"),
            _ci(line.intercept, u=u, kind="torque"),
            f"{line.r_squared:.5f}",
            f"{correction:.2f}" if fit.corrected_for_inertia else "not corrected",
            escape("; ".join(flags)) or "-",
        )
    drop = ("start-up corr.", "R^2", "n", "95 % CI", "95 % CI")
    display.show(console, table, drop=drop, wrap=("flags",))
    _print_footer(console, result, u)


def _print_footer(console: Any, result: DropTestResult | TraceResult, u: Shown) -> None:
    """The laws over temperature, then how many rows were used."""
    from rich.markup import escape

    _print_laws(console, result.laws, u)
    used, excluded = result.table.rows.size, len(result.table.excluded_rows)
    console.print(
        escape(f"{result.table.source}: {used} rows used, {excluded} excluded"), style="dim"
    )


def _print_laws(console: Any, laws: Any, u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    if laws is None:
        return
    table = Table(
        title="Laws over temperature "
        f"(T_ref = {u.text(laws.reference_temperature, 'temperature')})",
        title_justify="left",
    )
    for header in ("law", "parameter", "value", "95 % CI", "chi^2 / dof", "p"):
        table.add_column(
            escape(header), justify="left" if header in ("law", "parameter") else "right"
        )
    fits = [(f"BECD {name}", fit) for name, fit in laws.damping.items()]
    if laws.friction is not None:
        fits.append(("FECD line", laws.friction))
    for label, fit in fits:
        for i, (key, estimate) in enumerate(zip(fit.law.keys, fit.parameters, strict=True)):
            name, kind = _parameter(u, key)
            table.add_row(
                escape(label if i == 0 else ""),
                escape(name),
                _q(u, estimate.value, kind, 5),
                _ci(estimate, 5, u, kind),
                (f"{fit.chi_square:.3g} / {fit.dof}" if i == 0 else ""),
                (_fmt(fit.p_value, 3) if i == 0 else ""),
            )
    # Names and units wrap at their space; numbers and intervals stay on one line.
    display.show(console, table, drop=("p", "chi^2 / dof"), wrap=("law", "parameter"))
    console.print(escape(f"BECD laws: {laws.comparison.statement}"))
    for name, why in laws.damping_failures.items():
        console.print(escape(f"{name} law not fitted: {why}"))


@fit_app.command(
    "trace",
    cls=HelpCommand,
    epilog=(
        "Example: [bold]ecdsim fit trace examples/deployment_trace.csv "
        "--config examples/paper_cc16.toml --plot plots[/bold]"
    ),
)
def trace(
    data: DataArg,
    config: Annotated[
        Path,
        typer.Option(
            "--config",
            help="Configuration giving the spring and travel (and the ECD for --fit-spring).",
            metavar="FILE",
        ),
    ],
    as_json: JsonOpt = False,
    plot: PlotOpt = None,
    output: OutputOpt = None,
    fit_spring: Annotated[
        bool,
        typer.Option(
            "--fit-spring",
            help=(
                "Fit the spring's start and end torques instead, with BECD and friction "
                "from --config (a trace cannot give both; docs/characterize.md)."
            ),
        ),
    ] = False,
    temperature: Annotated[
        str | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Temperature of a file without a temperature column (bare numbers are degC).",
            metavar="DEGC",
        ),
    ] = None,
    reference_temperature: ReferenceOpt = "25",
    strict: StrictOpt = False,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Fit recorded deployments (angle against time) against the exact solution."""
    display.configure(wide=wide, plain=plain)
    from ecdsim.characterize.export import fitted_config_text, provenance, spring_config_text
    from ecdsim.characterize.tracefit import fit_traces
    from ecdsim.config import ConfigError

    reference = temperature_option("--reference-temperature", reference_temperature)
    at = None if temperature is None else temperature_option("--temperature", temperature)
    loaded = _load_config(config)
    u = Shown(units_option(units, loaded))
    try:
        result = fit_traces(
            data,
            loaded,
            "spring" if fit_spring else "damper",
            at,
            reference,
        )
    except ConfigError as exc:
        fail(str(exc).splitlines())
    bad_rows = [b.message() for b in result.table.bad_rows]
    fitted = bool(result.fits) or result.spring is not None
    _check_fitted(fitted, "trace", bad_rows, result.failed, strict)
    warnings = list(result.warnings)
    source = provenance("ecdsim fit trace", result.table.source, result.table.sha256)
    text: str | None = None
    if output is not None and result.spring is not None:
        spring = result.spring
        text = _export(
            output,
            lambda: spring_config_text(
                _config_text(config), spring.start_torque, spring.end_torque, source, config.name
            ),
        )
    elif output is not None:
        fits = result.fits
        ecd = _fitted_ecd(
            output,
            [f.temperature for f in fits],
            [f.damping_rate for f in fits],
            [f.friction for f in fits],
            result.laws,
        )
        warnings.extend(ecd.warnings)
        text = _export(
            output, lambda: fitted_config_text(_config_text(config), ecd, source, config.name)
        )
        warnings.extend(_not_carried(output, config, ecd))

    def plotter(folder: Path) -> list[Path]:
        from ecdsim.characterize.plots import write_trace_plots

        return write_trace_plots(result, folder, u.system)

    _finish(
        result,
        bad_rows,
        warnings,
        text,
        output,
        plot,
        plotter,
        lambda: _print_traces(result, u),
        as_json,
        u.system,
    )


def _print_traces(result: TraceResult, u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    if result.spring is not None:
        spring = result.spring
        table = Table(
            title=(
                "Spring torques fitted to the traces (at "
                f"{u.text(spring.reference_temperature, 'temperature')}; BECD and friction "
                "from the config)"
            ),
            title_justify="left",
        )
        for header in ("parameter", u.head("value", "torque"), "95 % CI"):
            table.add_column(escape(header), justify="right")
        for name, estimate in (
            ("start_torque", spring.start_torque),
            ("end_torque", spring.end_torque),
        ):
            table.add_row(
                name, _q(u, estimate.value, "torque", 5), _ci(estimate, u=u, kind="torque")
            )
        display.show(console, table)
    else:
        table = Table(
            title="Trace fit: BECD and total friction against the exact solution",
            title_justify="left",
        )
        headers = [
            u.head("T", "temperature"),
            "n",
            u.head("BECD", "damping_rate"),
            "95 % CI",
            u.head("F total", "torque"),
            "95 % CI",
            u.head("FS", "torque"),
            u.head("FECD", "torque"),
        ]
        for header in headers:
            table.add_column(escape(header), justify="right")
        for fit in result.fits:
            table.add_row(
                u.num(fit.temperature, "temperature"),
                str(fit.statistics.n_points),
                _q(u, fit.damping_rate.value, "damping_rate"),
                _ci(fit.damping_rate, u=u, kind="damping_rate"),
                _q(u, fit.total_friction.value, "torque"),
                _ci(fit.total_friction, u=u, kind="torque"),
                _q(u, fit.system_friction, "torque"),
                _q(u, fit.friction.value, "torque"),
            )
        display.show(console, table, drop=("n", "FS", "95 % CI", "95 % CI"))
    residuals = Table(title="Residuals", title_justify="left")
    for header in (
        u.head("T", "temperature"),
        "rms [deg]",
        "R^2",
        "Durbin-Watson",
        "fitted time [s]",
    ):
        residuals.add_column(escape(header), justify="right")
    for curve in result.curves:
        e = curve.residuals
        residuals.add_row(
            u.num(curve.trace.temperature, "temperature"),
            _fmt(math.degrees(float((e * e).mean()) ** 0.5), 3),
            f"{curve.r_squared:.6f}",
            _fmt(curve.durbin_watson, 3),
            _fmt(curve.deployment_time),
        )
    display.show(console, residuals, drop=("Durbin-Watson",))
    _print_footer(console, result, u)

"""``ecdsim fit fluid-damper``: a fluid damper's power law from bench data
(docs/qualification.md, section 3).

Registered on the ``fit`` group by :mod:`ecdsim.cli.app`. Only typer is imported at
start-up; the library inside the command. User errors print one ``error:`` line each and
exit with code 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ecdsim.cli import display
from ecdsim.cli.common import UnitsOpt, fail, temperature_option, units_option
from ecdsim.cli.display import PlainOpt, WideOpt

if TYPE_CHECKING:
    from ecdsim.characterize.fluidfit import FluidFitResult
    from ecdsim.units_display import Shown

EPILOG = (
    "Example: [bold]ecdsim fit fluid-damper examples/fluid_bench.csv --config "
    "examples/fluid.toml -o fluid_measured.toml[/bold], then ecdsim compare-fluid "
    "fluid_measured.toml"
)


def _ci(estimate: object, digits: int = 4) -> str:
    bounds = getattr(estimate, "ci95", None)
    return "-" if bounds is None else f"[{bounds[0]:.{digits}g}, {bounds[1]:.{digits}g}]"


def _print(result: FluidFitResult, u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    speed = result.reference_speed
    table = Table(
        title=f"Fluid damper: torque = T_r (w / {speed:g} rad/s)^n at each temperature "
        "(log-log least squares)",
        title_justify="left",
    )
    headers = [
        u.head("T", "temperature"),
        "n",
        "n 95 % CI",
        u.head("T_r", "torque"),
        "T_r 95 % CI",
        "scatter [%]",
        "flags",
    ]
    for header in headers:
        table.add_column(escape(header), justify="left" if header == "flags" else "right")
    for fit in result.fits:
        torque = fit.reference_torque
        scatter = fit.line.statistics.residual_std
        flags = []
        if fit.line.curvature is not None and fit.line.curvature.bending:
            flags.append("bends")
        if fit.line.outliers.any():
            flags.append("outliers")
        low_high = (
            "-"
            if torque.ci95 is None
            else f"[{u.num(torque.ci95[0], 'torque')}, {u.num(torque.ci95[1], 'torque')}]"
        )
        table.add_row(
            u.num(fit.temperature, "temperature"),
            f"{fit.exponent.value:.4g}",
            _ci(fit.exponent),
            u.num(torque.value, "torque"),
            low_high,
            "-" if scatter is None else f"{100 * scatter:.2g}",
            ", ".join(flags) or "-",
        )
    display.show(console, table, drop=("scatter", "T_r 95 % CI", "n 95 % CI"), wrap=("flags",))
    constants = result.law_constants()
    lines = []
    if result.torque_law is not None and result.exponent_law is not None:
        log_torque, activation = result.torque_law.parameters
        exponent, slope = result.exponent_law.parameters
        lines.append(
            f"T_r(T) = {constants['torque']:.4g} N*m exp(B (1/T_K - 1/T_ref)) at T_ref = "
            f"{result.reference_temperature:g} degC, B = {activation.value:.4g} K "
            f"{_ci(activation)}"
        )
        lines.append(
            f"n(T) = {exponent.value:.4g} {_ci(exponent)} + ({slope.value:.3g} "
            f"{_ci(slope, 3)}) / K * (T - T_ref)"
        )
        temps = [f.temperature for f in result.fits]
        cold, hot = min(temps), max(temps)
        lines.append(
            f"torque at {u.text(cold, 'temperature')} = {result.torque_ratio(cold, hot):.3g} "
            f"x that at {u.text(hot, 'temperature')}, speed for speed (95 % intervals in "
            "brackets)"
        )
    for line in lines:
        console.print(escape(line), highlight=False)
    display.note(
        console,
        f"{result.table.source}: {result.table.rows.size} rows used, "
        f"{len(result.table.excluded_rows)} excluded",
    )


def fluid_damper(
    data: Annotated[
        Path,
        typer.Argument(
            help="CSV: temperature, speed, torque (unit-bearing headers; docs/qualification.md).",
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
            help="Write a configuration with the fitted \\[fluid_damper.power_law].",
            metavar="FILE",
        ),
    ] = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Configuration the -o file starts from (else a marked placeholder).",
            metavar="FILE",
        ),
    ] = None,
    reference_speed: Annotated[
        str | None,
        typer.Option(
            "--reference-speed",
            help="Speed w_r of the law's torque T_r (default: a power of ten mid-range).",
            metavar="SPEED",
        ),
    ] = None,
    reference_temperature: Annotated[
        str,
        typer.Option(
            "--reference-temperature",
            help="Reference temperature of the laws (bare numbers are degC).",
            metavar="DEGC",
        ),
    ] = "25",
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """A fluid damper's torque-speed power law over temperature, from bench data."""
    display.configure(wide=wide, plain=plain)

    from ecdsim.characterize.fluidexport import fluid_damper_text
    from ecdsim.characterize.fluidfit import fit_fluid_bench
    from ecdsim.config import ConfigError
    from ecdsim.config.units import SPEED, QuantityError

    reference = temperature_option("--reference-temperature", reference_temperature)
    speed = None
    if reference_speed is not None:
        text = reference_speed if any(c.isalpha() for c in reference_speed) else (
            f"{reference_speed} rad/s"
        )  # fmt: skip
        try:
            speed = SPEED.parse(text)
        except QuantityError as exc:
            fail([f"--reference-speed: {exc}"])
        if not speed > 0.0:
            fail([f"--reference-speed: {reference_speed!r} must be > 0 (rad/s)"])
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
        result = fit_fluid_bench(data, speed, reference)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    bad = [b.message() for b in result.table.bad_rows]
    if not result.fits:
        fail([*bad, *(f"not fitted: {t:g} degC: {why}" for t, _, why in result.failed),
              "no temperature could be fitted"])  # fmt: skip
    from ecdsim.characterize.qualplots import write_fluid_fit_plots
    from ecdsim.cli.benchfit import finish_bench_fit

    finish_bench_fit(
        result,
        command="ecdsim fit fluid-damper",
        output=output,
        parameter_text=lambda lines: fluid_damper_text(
            result, lines, user_text, config.name if config else ""
        ),
        plot=plot,
        write_plots=write_fluid_fit_plots,
        as_json=as_json,
        u_system=u_system,
        print_table=_print,
        bad=bad,
        not_done="not fitted",
    )

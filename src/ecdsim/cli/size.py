"""``ecdsim size`` and ``ecdsim compare-fluid``: thin shells over :mod:`ecdsim.sizing`.

Only typer and the standard library are imported at start-up; the library is imported
inside the commands. User errors print ``error: ...`` lines and exit with code 2
(``ecdsim.cli.app.fail``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer

from ecdsim.cli import display, failon
from ecdsim.cli.common import UnitsOpt, echo_wrapped, units_option
from ecdsim.cli.display import PlainOpt, WideOpt
from ecdsim.units_display import Shown, convert_text

if TYPE_CHECKING:
    from ecdsim.config import Config

ConfigArg = Annotated[
    Path,
    typer.Argument(
        help="TOML configuration file (see docs/config.md, docs/sizing.md).", metavar="CONFIG"
    ),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON on stdout (docs/sizing.md).")]
PlotOpt = Annotated[
    Path | None, typer.Option("--plot", help="Write PNG plots into this folder.", metavar="DIR")
]
CatalogOpt = Annotated[
    Path,
    typer.Option(
        "--catalog", help="Damper and gearbox catalogue, .toml or .csv (docs/sizing.md).",
        metavar="FILE",
    ),
]  # fmt: skip
DamperOpt = Annotated[
    str | None,
    typer.Option(
        "--damper", help="Damper for the ratio intervals (default: best-ranked).", metavar="NAME"
    ),
]
GearboxOpt = Annotated[
    str | None,
    typer.Option(
        "--gearbox", help="Gearbox for the ratio intervals (default: best-ranked).", metavar="NAME"
    ),
]

SIZE_EPILOG = (
    "Example: [bold]ecdsim size examples/sizing.toml --catalog examples/catalogue.toml[/bold]"
)
FLUID_EPILOG = "Example: [bold]ecdsim compare-fluid examples/fluid.toml --plot plots[/bold]"


def _fail(problems: list[str]) -> NoReturn:
    from ecdsim.cli.common import fail

    fail(problems)


def _config(path: Path, section: str) -> Config:
    from ecdsim.config import ConfigError, load_config

    try:
        config = load_config(path)
    except ConfigError as exc:
        _fail(str(exc).splitlines())
    if getattr(config.spec, section) is None:
        _fail([f"{path}: no [{section}] section; see docs/sizing.md"])
    from ecdsim.cli.common import warn_placeholder

    warn_placeholder(config)
    return config


# Secondary columns of the sizing tables, hidden in this order when a table is wider than
# the terminal (--wide shows them), and the text columns that may wrap at spaces.
_DROP = ("at [deg", "torque margin", "spread", "mass", "at T", "value (worst)")
_FLUID_DROP = (
    "fluid t (paper)", "fluid deadband", "engage speed", "fluid t (damped)", "fluid c", "BECD",
    "fluid n",
)  # fmt: skip
_WRAP = ("damper + gearbox", "requirement", "limit", "check", "gear ratios", "recommended")


def _print(
    tables: list[tuple[str, list[str], list[list[str]]]],
    notes: list[str],
    drop: tuple[str, ...] = _DROP,
    lead: list[str] | None = None,
) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    for line in lead or []:  # the answer first (size: the recommended choice and why)
        console.print(escape(line), highlight=False)
    for title, headers, rows in tables:
        table = Table(title=escape(title), title_justify="left")
        for header in headers:
            table.add_column(escape(header))
        for row in rows:
            table.add_row(*[escape(cell) for cell in row])
        display.show(console, table, drop=drop, wrap=_WRAP)
    for note in notes:
        display.note(console, note)


def _write_plots(plot: Path, make: Any) -> list[Path]:
    try:
        return list(make())
    except OSError as exc:
        _fail([f"--plot {plot}: cannot write plots ({exc.strerror or exc})"])


def size(
    config: ConfigArg,
    catalog: CatalogOpt,
    as_json: JsonOpt = False,
    plot: PlotOpt = None,
    damper: DamperOpt = None,
    gearbox: GearboxOpt = None,
    fail_on: failon.FailOnOpt = None,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Rank catalogue dampers and gear ratios against the requirements; exact ratio ranges."""
    display.configure(wide=wide, plain=plain)
    conditions = failon.parse(fail_on)
    import json

    import numpy as np

    from ecdsim.config import ConfigError
    from ecdsim.deployment import ModelDomainError
    from ecdsim.sizing import report
    from ecdsim.sizing.catalogue import ILLUSTRATIVE, load_catalogue
    from ecdsim.sizing.ratio import ratio_intervals
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import deployment_time_curves, search

    loaded = _config(config, "requirements")
    u = Shown(units_option(units, loaded))
    assert loaded.spec.requirements is not None
    try:
        catalogue = load_catalogue(catalog)
    except ConfigError as exc:
        _fail(str(exc).splitlines())
    requirements = Requirements.from_spec(loaded.spec.requirements)
    load = loaded.system.load
    try:
        result = search(catalogue, load, requirements)
    except ValueError as exc:
        _fail([f"{catalog}: {exc}"])
    valid = [c for c in result.candidates if c.error is None]
    intervals = None
    problems = []
    chosen_damper = damper or (valid[0].candidate.damper.name if valid else None)
    chosen_gearbox = gearbox or (valid[0].candidate.gearbox.name if valid else None)
    try:
        damper_entry = catalogue.damper(chosen_damper) if chosen_damper else None
    except KeyError as exc:
        problems.append(f"--damper: {exc.args[0]}")
    try:
        gearbox_entry = catalogue.gearbox(chosen_gearbox) if chosen_gearbox else None
    except KeyError as exc:
        problems.append(f"--gearbox: {exc.args[0]}")
    if problems:
        _fail(problems)
    if damper_entry is not None and gearbox_entry is not None:
        try:
            intervals = ratio_intervals(damper_entry, gearbox_entry, load, requirements)
        except ModelDomainError as exc:
            _fail([f"{loaded.source}: {exc}"])
    notes = []
    if any(c.candidate.illustrative for c in result.candidates):
        notes.append(f"* illustrative entries: {ILLUSTRATIVE}; never use them as vendor data")
    if any(c.candidate.mass is None for c in result.candidates):
        notes.append(
            "mass '-': unknown (not in the catalogue, or the damper's catalogue mass is an "
            "assembly mass with another gearbox); unknown masses rank after every known one"
        )
    if not requirements.margin.factors_applied:
        notes.append(
            "torque margin: no uncertainty factors applied (all 1); take the factors from the "
            "standard your project applies (docs/sizing.md)"
        )
    labels = report.check_labels(result, chosen_damper, chosen_gearbox, u)
    written: list[Path] = []
    if plot is not None:
        from ecdsim.sizing.plots import write_sizing_plots

        top = valid[:5]
        temps = np.linspace(min(requirements.temperatures), max(requirements.temperatures), 57)
        times = (
            deployment_time_curves([c.candidate for c in top], load, temps)
            if top
            else np.zeros((0, temps.size))
        )
        written = _write_plots(
            plot,
            lambda: write_sizing_plots(
                plot, top, temps, times, requirements, intervals, units=u.system, labels=labels
            ),
        )
    if as_json:
        document = result.to_dict()
        document["config"] = loaded.source
        document["ratio_intervals"] = None if intervals is None else intervals.to_dict()
        document["recommendation"] = report.recommendation(result)
        document["display_units"] = u.system
        typer.echo(json.dumps(document, indent=2, sort_keys=True, allow_nan=False))
    else:
        tables = [report.requirements_table(result, u), report.candidates_table(result, u)]
        chosen = [
            c
            for c in valid
            if c.candidate.damper.name == chosen_damper
            and c.candidate.gearbox.name == chosen_gearbox
        ]
        if chosen:
            tables.append(report.checks_table(chosen[0], u))
            tables.append(report.torque_margin_table(chosen[0], u))
            notes[:0] = report.margin_definitions(chosen[0], u)
        if intervals is not None:
            tables.append(report.intervals_table(intervals, labels))
        _print(tables, notes, lead=report.recommendation(result, u))
    for c in result.candidates:
        for warning in c.warnings:
            echo_wrapped(f"warning: {c.candidate.label}: {warning}")
    for path in written:
        typer.echo(f"wrote {path}", err=as_json)
    failon.finish(conditions, _size_failures(conditions, valid, chosen_damper, chosen_gearbox, u))


def _size_failures(
    conditions: frozenset[str],
    valid: list[Any],
    damper: str | None,
    gearbox: str | None,
    u: Shown | None = None,
) -> list[str]:
    """Why ``--fail-on`` fails for the chosen candidate (best-ranked or --damper/--gearbox)."""
    if not conditions:
        return []
    chosen = [
        c
        for c in valid
        if c.candidate.damper.name == damper and c.candidate.gearbox.name == gearbox
    ]
    if not chosen:
        return [f"{sorted(conditions)[0]}: no catalogue candidate could be evaluated"]
    result = chosen[0]
    u = u or Shown()
    label = result.candidate.label
    reasons = []
    if "stall" in conditions:
        stalled = [
            u.num(t, "temperature")
            for t, s in zip(result.temperatures, result.stalled, strict=True)
            if s
        ]
        if stalled:
            where = f"{', '.join(stalled)} {u.unit('temperature')}"
            reasons.append(f"stall: {label} stalls at {where}")
    if "requirements" in conditions:
        reasons += [
            f"requirements: {label}: {convert_text(check.label, u.system)} missed "
            f"(worst at {u.text(check.temperature_C, 'temperature')})"
            for check in result.checks
            if not check.passed
        ]
    return reasons


FluidMethodOpt = Annotated[
    str,
    typer.Option(
        "--method",
        "-m",
        help="quasi-static (closed-form times) or dynamic (both dampers integrated with "
        "inertia; needs a load inertia).",
        metavar="METHOD",
    ),
]


def compare_fluid(
    config: ConfigArg,
    method: FluidMethodOpt = "quasi-static",
    as_json: JsonOpt = False,
    plot: PlotOpt = None,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Compare the ECD with a fluid damper: viscous and matched, or its measured power law."""
    display.configure(wide=wide, plain=plain)
    import json

    import numpy as np

    from ecdsim.deployment import ModelDomainError
    from ecdsim.sizing import report
    from ecdsim.sizing.fluid import compare_fluid as run

    loaded = _config(config, "fluid_damper")
    u = Shown(units_option(units, loaded))
    spec = loaded.spec.fluid_damper
    assert spec is not None
    temps = np.asarray(loaded.temperatures, dtype=float)
    inertia = getattr(loaded.spec.load, "inertia", None)  # [load] inertia, if the schema has it
    if method not in ("quasi-static", "dynamic"):
        _fail([f"--method: {method!r} is not a method; use quasi-static or dynamic"])
    try:
        dynamics = loaded.spec.dynamics() if method == "dynamic" else None
        comparison = run(loaded.system, spec, temps, inertia, method, dynamics)
        dense = (
            run(
                loaded.system,
                spec,
                np.linspace(temps.min(), temps.max(), 57),
                inertia,
                method,
                dynamics,
            )
            if plot is not None and temps.min() < temps.max()
            else comparison
        )
    except (ModelDomainError, ValueError) as exc:
        _fail([f"{loaded.source}: {exc}"])
    written: list[Path] = []
    if plot is not None:
        from ecdsim.sizing.plots import write_fluid_plots

        written = _write_plots(plot, lambda: write_fluid_plots(plot, dense, units=u.system))
    what = "the torque-speed law" if spec.power_law is not None else "viscosity"
    warnings = [
        f"warning: {what} at {u.text(t, 'temperature')} is extrapolated beyond the fitted points"
        for t, out in zip(comparison.temperatures, comparison.extrapolated, strict=True)
        if out
    ]
    for label, side in (("ECD", comparison.ecd), ("fluid damper", comparison.fluid)):
        warnings += [
            f"warning: the {label} stalls at {u.text(t, 'temperature')}"
            for t, stalled in zip(comparison.temperatures, side.stalled, strict=True)
            if stalled
        ]
    if as_json:
        document = comparison.to_dict()
        document["config"] = loaded.source
        document["display_units"] = u.system
        typer.echo(json.dumps(document, indent=2, sort_keys=True, allow_nan=False))
    else:
        notes = [
            f"{'torque-speed' if spec.power_law is not None else 'viscosity'} data: {spec.source}",
            "the fluid time is the damped phase after the deadband; during the deadband the "
            "load is undamped (docs/sizing.md)",
        ]
        if spec.power_law is not None and bool(comparison.extrapolated.any()):
            notes.append("*: outside the bench data's temperatures (the law is extrapolated there)")
        if comparison.fluid.free_time is None:
            notes.append(
                "no load inertia given ([fluid_damper] load_inertia or [load] inertia): the "
                "free time through the deadband and the engagement shock are not computed"
            )
        else:
            lost = np.degrees(comparison.ecd.deadband)
            notes.append(
                "shock: the damping torque when the damper engages at the end of its deadband, "
                "coefficient x engagement speed (the load crosses the deadband undamped); "
                f"the ECD's lost motion is {lost:.3g} deg"
                + (", so it engages at rest" if lost == 0.0 else "")
            )
        _print([report.fluid_table(comparison, u)], notes, _FLUID_DROP)
    for line in warnings:
        echo_wrapped(line)
    for path in written:
        typer.echo(f"wrote {path}", err=as_json)

"""``ecdsim margin``: a torque budget as flight programs keep it (docs/qualification.md).

``ecdsim margin BUDGET.toml`` reads a budget file; ``ecdsim margin CONFIG`` fills the
budget from the config's model at every temperature. Only typer is imported at start-up;
the library inside the command. User errors print one ``error:`` line each and exit with
code 2; ``--fail-on margin`` exits with code 1 where a margin is negative.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ecdsim.cli import display
from ecdsim.cli.common import UnitsOpt, fail, units_option
from ecdsim.cli.display import PlainOpt, WideOpt

if TYPE_CHECKING:
    from ecdsim.config.budget_schema import WrittenUnit
    from ecdsim.sizing.budget import PhaseMargin, TorqueBudget

EPILOG = (
    "Example: [bold]ecdsim margin examples/paper_cc16_budget.toml --phase qualification[/bold] "
    "(a config's budget; a budget file: examples/torque_budget.toml)"
)

FAIL_CONDITIONS = ("margin",)


def _fail_on(values: list[str] | None) -> bool:
    """True with ``--fail-on margin``; another value exits with code 2."""
    chosen = False
    for value in values or []:
        for item in value.split(","):
            name = item.strip()
            if name not in FAIL_CONDITIONS:
                fail([f"--fail-on: {name!r} is not a condition here; expected margin"])
            chosen = True
    return chosen


class _Unit:
    """How torques are shown: a unit label and N*m per unit."""

    def __init__(self, label: str, si_per_unit: float) -> None:
        self.label = label
        self.si_per_unit = si_per_unit

    def num(self, si_value: float) -> str:
        from ecdsim.formatting import format_number

        return format_number(si_value / self.si_per_unit, 4)


def _display_unit(units: str | None, written: WrittenUnit | None, default: str) -> _Unit:
    """``--units`` if given, else the unit the budget's ``available`` was written in, else
    the config's ``[output] units``."""
    from ecdsim.units_display import UNITS

    if units is None and written is not None:
        return _Unit(written.label, written.si_per_unit)
    system = units_option(units) if units is not None else default
    unit = UNITS["torque"][system]  # type: ignore[index]
    return _Unit(unit.label, 1.0 / unit.scale)


def _ratio_text(value: float) -> str:
    import math

    return "inf" if math.isinf(value) else f"{value:.4g}"


def _print_phase(budget: TorqueBudget, phase: PhaseMargin, unit: _Unit, temp_unit: str) -> None:
    import numpy as np
    from rich.markup import escape
    from rich.table import Table

    from ecdsim.units_display import Shown

    console = display.make_console()
    shown = Shown(temp_unit)  # type: ignore[arg-type]
    title = "Torque budget" if budget.name == "torque budget" else f"Torque budget: {budget.name}"
    if phase.phase:
        title += f", phase {phase.phase}"
    table = Table(title=escape(f"{title} [{unit.label}]"), title_justify="left")
    single = budget.temperatures is None
    headers = ["torque", "kind", "factor"]
    if single:
        headers += [f"value [{unit.label}]", f"factored [{unit.label}]"]
    else:
        assert budget.temperatures is not None
        headers += [shown.text(t, "temperature") for t in budget.temperatures]
    for i, header in enumerate(headers):
        table.add_column(escape(header), justify="left" if i < 2 else "right")

    def cells(values: object) -> list[str]:
        flat = np.atleast_1d(np.asarray(values, dtype=float))
        count = 1 if single else len(budget.temperatures or ())
        return [unit.num(float(flat[min(i, flat.size - 1)])) for i in range(count)]

    for term in phase.terms:
        factor = phase.factor(term)
        row = [escape(term.name), escape(term.kind), f"{factor:g}"]
        if single:
            row += [cells(term.value)[0], unit.num(factor * float(np.ravel(term.value)[0]))]
        else:
            row += cells(term.value)
        table.add_row(*row)
    table.add_section()
    margins = np.atleast_1d(phase.margin)
    ratios = np.atleast_1d(phase.torque_ratio)
    if single:
        table.add_row("sum", "", "", cells(phase.total)[0], cells(phase.factored)[0])
        table.add_row("available", "", "", cells(phase.available)[0], "")
    else:
        table.add_row("sum", "", "", *cells(phase.total))
        table.add_row("factored sum", "", "f * T", *cells(phase.factored))
        table.add_row("available", "", "", *cells(phase.available))
        table.add_row("margin", "", "", *[f"{m:+.4g}" for m in margins])
        table.add_row("torque ratio", "", "", *[_ratio_text(r) for r in ratios])
    display.show(console, table, wrap=("torque",))
    verdicts = phase.verdicts()
    if single:
        line = (
            f"margin = {unit.num(float(phase.available))} / {unit.num(float(phase.factored))} - 1"
            f" = {float(margins[0]):+.4g} ({100.0 * float(margins[0]):+.1f} %): {verdicts[0]}"
        )
        ratio = (
            f"torque ratio = {unit.num(float(phase.available))} / "
            f"{unit.num(float(phase.total))} = {_ratio_text(float(ratios[0]))}"
        )
        console.print(escape(line), highlight=False)
        console.print(escape(ratio), highlight=False)
    else:
        assert budget.temperatures is not None
        flagged = [
            f"{shown.text(t, 'temperature')}: {v}"
            for t, v in zip(budget.temperatures, verdicts, strict=True)
            if v != "positive margin"
        ]
        if flagged:
            console.print(escape("; ".join(flagged)), highlight=False)
        if phase.angle is not None:
            seen = dict.fromkeys(f"{np.degrees(a):.4g}" for a in np.atleast_1d(phase.angle))
            angles = ", ".join(seen)
            display.note(console, f"taken where the margin is lowest, at {angles} deg of travel")


def margin(
    path: Annotated[
        Path,
        typer.Argument(
            help="A torque budget (\\[budget]) or a deployment config (docs/qualification.md).",
            metavar="BUDGET_OR_CONFIG",
        ),
    ],
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON on stdout (SI).")] = False,
    phase: Annotated[
        list[str] | None,
        typer.Option("--phase", help="Show only this program phase, repeatable.", metavar="NAME"),
    ] = None,
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Temperature of a config's budget, repeatable; overrides \\[analysis] "
            "(bare numbers are degC).",
            metavar="TEMP",
        ),
    ] = None,
    fail_on: Annotated[
        list[str] | None,
        typer.Option(
            "--fail-on",
            help="'margin': exit with code 1 if any margin is negative.",
            metavar="WHAT",
        ),
    ] = None,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Torque budget: each torque, its factor, the margin and the torque ratio."""
    display.configure(wide=wide, plain=plain)
    import json
    from dataclasses import replace

    from ecdsim.config import ConfigError
    from ecdsim.config.budget_file import is_budget_document, read_toml, validate_budget
    from ecdsim.config.budget_schema import written_unit
    from ecdsim.deployment import ModelDomainError
    from ecdsim.sizing.budget import BudgetError, budget_from_config, budget_from_file

    failing = _fail_on(fail_on)
    try:
        raw = read_toml(path)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    if is_budget_document(raw):
        if temperature:
            fail(["--temperature: a budget file has no temperatures (a config's budget has)"])
        try:
            budget_file = validate_budget(raw, str(path))
        except ConfigError as exc:
            fail(str(exc).splitlines())
        budget = budget_from_file(budget_file)
        unit = _display_unit(units, budget_file.unit, "si")
        temp_unit = units_option(units) if units is not None else "si"
    else:
        from ecdsim.cli.common import load_run
        from ecdsim.config.loader import WING_FILE

        if "wing" in raw:  # the wing's margins are not modelled: say what takes the file
            fail([f"{path}: {WING_FILE}"])
        if not any(key in raw for key in ("damper", "gearbox", "load")):
            fail(
                [
                    f"{path}: neither a torque budget ([budget] with available and "
                    "[[budget.torque]]) nor a deployment config ([damper], [gearbox], [load]); "
                    "see docs/qualification.md"
                ]
            )
        loaded = load_run(path, temperature, None)
        temp_unit = units_option(units, loaded)
        section = raw.get("budget")
        written = written_unit(section.get("available")) if isinstance(section, dict) else None
        unit = _display_unit(units, written, temp_unit)
        try:
            budget = budget_from_config(loaded, loaded.temperatures)
        except (BudgetError, ModelDomainError) as exc:
            fail([f"{loaded.source}: {exc}"])
    if phase:
        names = [p.phase for p in budget.phases]
        unknown = [p for p in phase if p not in names]
        if unknown:
            listed = ", ".join(n for n in names if n) or "none (the budget has no phases)"
            fail([f"--phase: {unknown[0]!r} is not a phase of the budget; its phases: {listed}"])
        budget = replace(budget, phases=tuple(p for p in budget.phases if p.phase in phase))
    if as_json:
        document = budget.to_dict()
        document["display_unit"] = {"torque": unit.label, "N*m_per_unit": unit.si_per_unit}
        typer.echo(json.dumps(document, indent=2, sort_keys=True, allow_nan=False))
    else:
        for one in budget.phases:
            _print_phase(budget, one, unit, temp_unit)
        console = display.make_console()
        if not budget.factors_applied:
            display.note(
                console,
                "no uncertainty factors applied (all 1): take the factors from the standard "
                "your program applies (docs/qualification.md)",
            )
        for note in budget.notes:
            display.note(console, note)
    if failing:
        from ecdsim.cli.failon import exit_failed

        reasons = budget.failures()
        if reasons:
            exit_failed(reasons)

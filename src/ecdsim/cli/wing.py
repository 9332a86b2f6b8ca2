"""``ecdsim deploy WING.toml``: a wing file's deployment over temperature (docs/wing.md).

``deploy`` hands a file with ``[wing]`` here: the wing is solved at each temperature by
:func:`ecdsim.wing.solver.deploy_wing`, and printed as a table per temperature (fits 80
columns): how the run ended, the deployment time, then one row per latch in latching
order (time, arrival speed, the wing's kinetic energy, the compliant latch's peak torque
or the rigid latch's impulse, the impact loss), the hinges left stuck and the energy
balance. ``--json`` prints :meth:`~ecdsim.wing.result.WingResult.to_dict`; ``--plot DIR``
writes the hinge angles and the shape strips (:mod:`ecdsim.plotting_wing`).
"""

from __future__ import annotations

import json
import math
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from ecdsim.cli.common import fail, parse_temperature
from ecdsim.wing.result import WingCase, WingResult

if TYPE_CHECKING:
    from ecdsim.config.wing_schema import WingConfig
    from ecdsim.units_display import UnitSystem


def is_wing_file(path: Path) -> bool:
    """True for a readable TOML file with ``[wing]`` (anything else: the single hinge's
    loader reports it)."""
    from ecdsim.config import ConfigError
    from ecdsim.config.loader import parse_toml

    try:
        text = path.read_text(encoding="utf-8")
        return "wing" in parse_toml(text, str(path))
    except (OSError, UnicodeDecodeError, ConfigError):
        return False


@dataclass(frozen=True)
class WingRun:
    """A wing file read for a command: the config, the temperatures [degC] (``-T`` or
    the file's) and the display units (``--units`` or the file's ``[output]``)."""

    config: WingConfig
    temperatures: tuple[float, ...]
    units: UnitSystem


def load_wing_run(
    path: Path,
    temperatures: list[str] | None,
    methods: list[str] | None = None,
    units: str | None = None,
) -> WingRun:
    """Read a wing file for ``sweep``, ``montecarlo`` or ``report``; every problem (the
    file's, a bad ``-T``, a ``--method``, which a wing does not take) exits with code 2,
    one line each."""
    from ecdsim.config import ConfigError
    from ecdsim.config.units import QuantityError
    from ecdsim.config.wing_schema import load_wing_config
    from ecdsim.sizing.catalogue import load_catalogue
    from ecdsim.units_display import UnitSystemError, check_system

    try:
        config = load_wing_config(path, read_catalogue=load_catalogue)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    problems = []
    if methods:
        problems.append(
            "--method: not taken with a wing file (one solver: the wing's dynamics; "
            "docs/wing.md)"
        )
    temps = list(config.temperatures)
    if temperatures:
        temps = []
        for text in temperatures:
            try:
                temps.append(parse_temperature(text))
            except QuantityError as exc:
                problems.append(f"--temperature: {exc}")
    system: UnitSystem = "si"
    try:
        system = check_system(units or config.spec.output.units, "--units" if units else "output.units")
    except UnitSystemError as exc:
        problems.append(str(exc))
    if problems:
        fail(problems)
    return WingRun(config, tuple(temps), system)


def run_wing(path: Path, as_json: bool, plot: Path | None, temperatures: list[str] | None) -> None:
    """Solve and print a wing file (module notes); user errors exit with code 2."""
    from ecdsim.wing.solver import WingUnsupported, deploy_wing

    run = load_wing_run(path, temperatures)
    config = run.config
    temps = list(run.temperatures)
    try:
        result = deploy_wing(config.wing, temps, rtol=config.rtol, stop_time=config.stop_time)
    except WingUnsupported as exc:
        fail([f"{path}: {exc}"])
    if as_json:
        typer.echo(json.dumps(result.to_dict(), indent=2))
    else:
        typer.echo(format_wing(result))
    if plot is not None:
        from ecdsim.plotting_wing import write_wing_plots

        for written in write_wing_plots(result, config.wing, plot):
            typer.echo(f"wrote {written}", err=as_json)


def _time(value: float) -> str:
    return f"{value:.4g} s" if math.isfinite(value) else "never"


def format_case(result: WingResult, case: WingCase) -> list[str]:
    """One temperature's lines (80 columns)."""
    names = result.hinges
    head = f"{case.temperature:+g} degC: {case.status}"
    if math.isfinite(case.deployment_time):
        head += f", deployed in {case.deployment_time:.4g} s"
    order = " > ".join(names[j] for j in case.sequence) or "none"
    lines = [head, f"  latch order: {order}"]
    lines.append(
        f"  {'hinge':<12}{'time [s]':>10}{'speed':>10}{'KE [J]':>10}  {'latch load':<22}"
        f"{'loss [J]':>10}"
    )
    lines.append(f"  {'':<12}{'':>10}{'[rad/s]':>10}")
    for latch in case.latches:
        if latch.peak_torque is not None:
            load = f"peak {latch.peak_torque:.3g} N*m"
        elif latch.impulse is not None:
            load = f"impulse {abs(latch.impulse):.3g} N*m*s"
        else:
            load = "(with its group)"
        lines.append(
            f"  {names[latch.hinge][:11]:<12}{latch.time:>10.4f}{latch.speed:>10.4g}"
            f"{latch.kinetic_energy:>10.3g}  {load:<22}{latch.impact_loss:>10.3g}"
        )
    for j in case.stuck_hinges:
        lines.append(f"  stuck: {names[j]} at {case.angle[-1, j]:.4g} rad (short of its latch)")
    peaks = [
        f"{names[j]} {peak:.4g} degC"
        for j, peak in enumerate(case.peak_damper_temperature)
        if peak is not None
    ]
    if peaks:
        lines.extend(textwrap.wrap("peak damper temperature: " + ", ".join(peaks), 78,
                                   initial_indent="  ", subsequent_indent="    "))
    lines.append(f"  energy balance closes to {case.energy.error:.1e}")
    return lines


def format_wing(result: WingResult) -> str:
    """The table of every temperature."""
    lines = textwrap.wrap(f"{result.wing}: {len(result.hinges)} hinges", 80)
    for case in result.cases:
        lines.append("")
        lines.extend(format_case(result, case))
    return "\n".join(lines)

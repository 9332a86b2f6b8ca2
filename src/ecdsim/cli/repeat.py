"""``ecdsim repeat``: a life test's repeated deployments with cool-down and stow.

Only typer is imported at start-up; the library (:mod:`ecdsim.dynamics.sequence`) inside
the command.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ecdsim.cli.common import UnitsOpt, fail
from ecdsim.cli.display import PlainOpt, WideOpt

if TYPE_CHECKING:
    from ecdsim.dynamics.sequence import SequenceResult
    from ecdsim.units_display import UnitSystem

EPILOG = (
    "Example: [bold]ecdsim repeat examples/paper_cc16_dynamic.toml --count 500 "
    '--cool-down "60 s" --stow-time "30 s" --plot plots[/bold]'
)


# The most deployments ``--count`` accepts (2,000 times the paper's 500-deployment life
# test), and in all over the temperatures: every deployment keeps seven float64 results
# per temperature (56 bytes), reserved up front, so 10,000,000 deployments hold 560 MB
# (--count 1000000000 reserved 22.4 GiB per array before the first deployment).
MAX_COUNT = 1_000_000
MAX_DEPLOYMENTS = 10_000_000


def _duration(option: str, text: str) -> float:
    """A time option [s]; a bare number is seconds."""
    from ecdsim.config.units import TIME, QuantityError

    try:
        value = TIME.parse(text if any(c.isalpha() for c in text) else f"{text} s")
    except QuantityError as exc:
        fail([f"{option}: {exc}"])
    if not (math.isfinite(value) and value >= 0.0):
        fail([f"{option}: {text!r} must be a finite time >= 0 (e.g. '60 s')"])
    return value


def _shown_rows(result: SequenceResult) -> list[int]:
    """Deployment numbers (1-based) for the table: 1, 2, 3, 5, 10, 20, 50, 100, ... and N,
    with the first periodic one."""
    n = result.cycle.count
    picks = {1, 2, 3, n}
    decade = 1
    while decade <= n:
        picks.update(m * decade for m in (1, 2, 5))
        decade *= 10
    picks.update(k for k in result.periodic_after if k is not None)
    return sorted(k for k in picks if 1 <= k <= n)


def _time_cells(time: float, first: float) -> list[str]:
    """The time and its change from deployment 1 [%]: "stalled" and "-" where a deployment
    never reaches the end of travel (no NaN is ever shown)."""
    from ecdsim.formatting import format_number

    if not math.isfinite(time):
        return ["stalled", "-"]
    if not math.isfinite(first):
        return [format_number(time, 6), "-"]
    return [format_number(time, 6), f"{100.0 * (time / first - 1.0):+.3f}"]


def _stall_note(stalls: list[int], count: int) -> str:
    """The note under a table with stalled deployments."""
    if len(stalls) == count:
        which = "no deployment reaches"
    else:
        listed = ", ".join(str(k) for k in stalls[:10]) + (", ..." if len(stalls) > 10 else "")
        one = len(stalls) == 1
        which = f"deployment{'' if one else 's'} {listed} never reach{'es' if one else ''}"
    return (
        f"stalled: {which} the end of travel (the spring torque falls to the friction "
        "first; see the warning), so there is no time; '-': no time change to show"
    )


def _print(
    result: SequenceResult, heat_per_stow: list[float], heated: bool, units: UnitSystem = "si"
) -> None:
    import numpy as np
    from rich.markup import escape
    from rich.table import Table

    from ecdsim.cli import display
    from ecdsim.units_display import Shown

    u = Shown(units, digits=6)

    def short(value: float) -> str:
        return u.num(float(value), "temperature")

    console = display.make_console()
    housing = result.start_housing_temperature
    drift = result.drift()
    for j, temp in enumerate(result.temperatures):
        table = Table(
            title=f"Repeated deployments at T = {Shown(units).text(float(temp), 'temperature')}",
            title_justify="left",
        )
        headers = ["deployment", u.head("start rotor", "temperature")]
        if housing is not None:
            headers.append(u.head("start housing", "temperature"))
        headers += [u.head("peak rotor", "temperature"), "time [s]", "time change [%]"]
        for header in headers:
            table.add_column(escape(header), justify="right")
        first = float(result.deployment_time[0, j])
        for k in _shown_rows(result):
            i = k - 1
            time = float(result.deployment_time[i, j])
            row = [str(k), short(result.start_rotor_temperature[i, j])]
            if housing is not None:
                row.append(short(housing[i, j]))
            row += [short(result.peak_rotor_temperature[i, j]), *_time_cells(time, first)]
            table.add_row(*row)
        display.show(console, table)
        stalls = [int(i) + 1 for i in np.flatnonzero(result.stalled[:, j])]
        if stalls:
            display.note(console, _stall_note(stalls, result.cycle.count))
        periodic = result.periodic_after[j]
        state = (
            f"periodic from deployment {periodic} (start temperatures within "
            f"{result.tolerance:g} K of the one before)"
            if periodic is not None
            else f"not periodic within {result.cycle.count} deployments"
        )
        time_drift = float(drift["deployment_time_s"][j])
        time_text = f"{time_drift:+.4g} s" if math.isfinite(time_drift) else "- (stalled)"
        kelvin = u.value(1.0, "temperature_difference")
        degree = u.unit("temperature_difference")
        display.note(
            console,
            f"drift 1 to {result.cycle.count}: time {time_text}, "
            f"peak rotor {kelvin * drift['peak_rotor_temperature_K'][j]:+.4g} {degree}, "
            f"start rotor {kelvin * drift['start_rotor_temperature_K'][j]:+.4g} {degree}; "
            f"{state}",
        )
    if not heated:
        display.note(console, "no [damper.thermal]: the damper does not heat, nothing drifts")
    if all(math.isfinite(e) for e in heat_per_stow):
        estimate = (
            "back-driving an engaged damper at travel / stow time would add about "
            + ", ".join(Shown(units, digits=3).text(e, "energy") for e in heat_per_stow)
            + " per stow (BD_T N^2 travel^2 / t_stow)"
        )
    else:  # --stow-time 0: no speed to estimate it from
        estimate = "give --stow-time for the heat a back-driven damper would add"
    display.note(console, f"the stow generates no heat here; {estimate}")


def repeat(
    config: Annotated[
        Path, typer.Argument(help="TOML configuration file (see docs/config.md).", metavar="CONFIG")
    ],
    cool_down: Annotated[
        str,
        typer.Option(
            "--cool-down",
            help="Time from the end of a deployment to the start of the stow (bare numbers "
            "are seconds).",
            metavar="TIME",
        ),
    ],
    count: Annotated[
        int,
        typer.Option(
            "--count", "-n", help="Number of deployments (the paper's life test: 500).", metavar="N"
        ),
    ] = 500,  # fmt: skip
    stow_time: Annotated[
        str,
        typer.Option(
            "--stow-time",
            help="Time to re-arm the spring, up to the next release; no heat is generated.",
            metavar="TIME",
        ),
    ] = "0 s",
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Deployment temperature, repeatable; overrides \\[analysis] (bare numbers "
            "are degC).",
            metavar="TEMP",
        ),
    ] = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print the per-deployment results as JSON.")
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Write repeat.png into this folder: the deployment time and rotor "
            "temperatures against the deployment number.",
            metavar="DIR",
        ),
    ] = None,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Deploy N times in a row: how the deployment time drifts as the damper warms."""
    import json

    from ecdsim.cli import display
    from ecdsim.cli.common import echo_warnings, load_run, plot_file, units_option
    from ecdsim.deployment import ModelDomainError, Prediction, predict
    from ecdsim.dynamics import DynamicParameters, DynamicResult
    from ecdsim.dynamics.method import DynamicSolution
    from ecdsim.dynamics.sequence import Cycle, run_sequence, stow_heat

    display.configure(wide=wide, plain=plain)
    problems = []
    if not 1 <= count <= MAX_COUNT:
        problems.append(
            f"--count {count}: expected 1 to {MAX_COUNT:,} deployments (the results of "
            "every deployment are kept in memory, 56 bytes per temperature)"
        )
    cool = _duration("--cool-down", cool_down)
    stow = _duration("--stow-time", stow_time)
    loaded = load_run(config, temperature, ["dynamic"])
    system = units_option(units, loaded)
    if count <= MAX_COUNT and count * len(loaded.temperatures) > MAX_DEPLOYMENTS:
        problems.append(
            f"--count {count} at {len(loaded.temperatures)} temperatures: at most "
            f"{MAX_DEPLOYMENTS:,} deployments in all (56 bytes of results each, kept in memory)"
        )
    params = loaded.spec.dynamics()
    if params is None:
        problems.append(
            f"{config}: repeated deployments need the dynamic method's [load] inertia (kg*m^2)"
        )
    if problems:
        fail(problems)
    assert params is not None
    temps = loaded.temperatures
    first: list[Prediction] = []

    def solve(run: DynamicParameters) -> DynamicResult:
        prediction = predict(loaded.system, temps, ["dynamic"], dynamics=run)
        if not first:
            first.append(prediction)
        solution = prediction.solutions["dynamic"]
        assert isinstance(solution, DynamicSolution)
        return solution.result

    try:
        result = run_sequence(solve, params, temps, Cycle(count, cool, stow))
    except ModelDomainError as exc:
        fail([f"{config}: {exc}"])
    echo_warnings(first[0], system)
    state = loaded.system.ecd.at(list(temps))
    heat = stow_heat(state.damper_damping_rate * state.gear_ratio**2, loaded.system.load.travel,
                     stow)  # fmt: skip
    # The life test's reliability and drift (docs/qualification.md).
    from ecdsim.cli.reliability import print_life_test, repeat_reliability

    life = repeat_reliability(result.deployment_time, loaded)
    if as_json:
        document = result.to_dict()
        document["stow_heat_not_modelled_J"] = [
            float(e) if math.isfinite(e) else None for e in heat.ravel()
        ]
        document["reliability"] = life
        typer.echo(json.dumps(document, indent=2))
    else:
        _print(result, [float(e) for e in heat.ravel()], params.thermal is not None, system)
        print_life_test(life, system)
    if plot is not None:
        from ecdsim.plotting import save_figure
        from ecdsim.plotting_dynamic import plot_sequence

        target = plot_file(plot, "repeat.png")
        try:
            save_figure(plot_sequence(result, loaded.system.name, system), target)
        except OSError as exc:
            fail([f"--plot {plot}: cannot write ({exc.strerror or exc})"])
        typer.echo(f"wrote {target}", err=as_json)

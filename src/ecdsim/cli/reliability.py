"""``ecdsim reliability``: what a test campaign demonstrates (docs/qualification.md).

Subcommands: ``demonstrated`` (N deployments, f failures: the reliability shown at a
confidence), ``runs-needed`` (the deployments a target needs) and ``weibull`` (lives of
several units, some suspended). The Monte Carlo and ``repeat`` commands show their own
reliability fields through :func:`print_requirement_misses` and :func:`repeat_block`.
Only typer is imported at start-up; the library inside the commands.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ecdsim.cli import display
from ecdsim.cli.common import fail
from ecdsim.cli.display import HelpCommand, HelpGroup, PlainOpt, WideOpt

if TYPE_CHECKING:
    from rich.console import Console

    from ecdsim.units_display import Shown

reliability_app = typer.Typer(
    help="Demonstrated reliability of a test campaign: success runs, binomial bounds, "
    "Weibull lives (docs/qualification.md).",
    rich_markup_mode="rich",
    cls=HelpGroup,
    no_args_is_help=True,
    epilog="Example: [bold]ecdsim reliability demonstrated --runs 22 --confidence 90%[/bold]",
)

JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON on stdout.")]
ConfidenceOpt = Annotated[
    str,
    typer.Option(
        "--confidence",
        "-C",
        help="Confidence level, a fraction or a percentage (0.95, 95%).",
        metavar="C",
    ),
]
FailuresOpt = Annotated[
    int, typer.Option("--failures", "-f", help="Deployments that failed.", metavar="F")
]


def _fraction(option: str, text: str) -> float:
    """A probability option: ``0.95``, ``95%`` or ``95 %``; strictly between 0 and 1."""
    value = text.strip()
    try:
        number = float(value[:-1]) / 100.0 if value.endswith("%") else float(value)
    except ValueError:
        fail(
            [
                f"{option}: {text!r} is not a number; expected a fraction or a percentage, "
                "e.g. 0.95 or 95%"
            ]
        )
    if not 0.0 < number < 1.0:
        fail([f"{option}: {text!r} must lie strictly between 0 and 1 (0 % and 100 %)"])
    return number


def _percent(value: float, digits: int = 4) -> str:
    return f"{100.0 * value:.{digits}g} %"


@reliability_app.command(
    "demonstrated",
    cls=HelpCommand,
    epilog="Example: [bold]ecdsim reliability demonstrated --runs 59 --failures 1[/bold]",
)
def demonstrated_command(
    runs: Annotated[int, typer.Option("--runs", "-n", help="Deployments made.", metavar="N")],
    failures: FailuresOpt = 0,
    confidence: ConfidenceOpt = "0.95",
    as_json: JsonOpt = False,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """The reliability N deployments with f failures demonstrate at a confidence."""
    display.configure(wide=wide, plain=plain)
    import json

    from ecdsim.characterize.reliability import demonstrated

    level = _fraction("--confidence", confidence)
    if runs < 1:
        fail([f"--runs {runs}: expected a number of deployments >= 1"])
    if not 0 <= failures <= runs:
        fail([f"--failures {failures}: expected 0 to --runs ({runs})"])
    result = demonstrated(runs, failures, level)
    if as_json:
        typer.echo(json.dumps(result.to_dict(), indent=2, sort_keys=True))
        return
    how = (
        f"success run: R = (1 - C)^(1/N) = {1 - level:.4g}^(1/{runs})"
        if failures == 0
        else "binomial (Clopper-Pearson) one-sided lower bound"
    )
    typer.echo(f"{runs} deployments, {failures} failed")
    typer.echo(
        f"reliability demonstrated at {_percent(level)} confidence: {result.lower_bound:.6g}"
    )
    typer.echo(how)
    typer.echo(f"observed: {result.observed:.6g} (1 - f/N)")


@reliability_app.command(
    "runs-needed",
    cls=HelpCommand,
    epilog="Example: [bold]ecdsim reliability runs-needed --target 0.99 --confidence 90%[/bold]",
)
def runs_needed_command(
    target: Annotated[
        str,
        typer.Option("--target", "-R", help="Reliability to demonstrate (0.99, 99%).", metavar="R"),
    ],
    failures: Annotated[
        int,
        typer.Option("--failures", "-f", help="Failures the campaign may have.", metavar="F"),
    ] = 0,
    confidence: ConfidenceOpt = "0.95",
    as_json: JsonOpt = False,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """The deployments needed to demonstrate a reliability at a confidence."""
    display.configure(wide=wide, plain=plain)
    import json

    from ecdsim.characterize.reliability import runs_needed

    level = _fraction("--confidence", confidence)
    goal = _fraction("--target", target)
    if failures < 0:
        fail([f"--failures {failures}: expected a number of failures >= 0"])
    needed = runs_needed(goal, level, failures)
    if as_json:
        document = {
            "target_reliability": goal,
            "confidence": level,
            "failures_allowed": failures,
            "runs_needed": needed,
        }
        typer.echo(json.dumps(document, indent=2, sort_keys=True))
        return
    allowed = "none may fail" if failures == 0 else f"at most {failures} may fail"
    typer.echo(f"{needed} deployments demonstrate R = {goal:.6g} at {_percent(level)} confidence")
    typer.echo(f"({allowed})")
    if failures == 0:
        typer.echo(
            f"success run: N = ceil(ln(1 - C) / ln R) = ceil({math.log(1 - level):.6g} / "
            f"{math.log(goal):.6g})"
        )


LIFE_EXAMPLE = "examples/life_test.csv"


@reliability_app.command(
    "weibull",
    cls=HelpCommand,
    epilog=f"Example: [bold]ecdsim reliability weibull {LIFE_EXAMPLE}[/bold]",
)
def weibull_command(
    data: Annotated[
        Path,
        typer.Argument(
            help="CSV of lives: 'unit' (its number), 'life' (cycles or time, one unit "
            "throughout) and 'failed' (1 = failed, 0 = suspended).",
            metavar="CSV",
        ),
    ],
    confidence: ConfidenceOpt = "0.95",
    at: Annotated[
        list[float] | None,
        typer.Option("--at", help="Also the reliability at this life, repeatable.", metavar="LIFE"),
    ] = None,
    as_json: JsonOpt = False,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Weibull fit of lives of several units, suspensions included."""
    display.configure(wide=wide, plain=plain)
    import json

    from ecdsim.characterize.lifedata import read_lives
    from ecdsim.characterize.reliability import weibull_fit
    from ecdsim.config import ConfigError

    level = _fraction("--confidence", confidence)
    try:
        table = read_lives(data)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    lives, failed = table.values["life"], table.values["failed"] > 0.5
    try:
        fit = weibull_fit(lives, failed, level)
    except ValueError as exc:
        fail([f"{data}: {exc}"])
    points = [float(x) for x in at or []]
    bad = [x for x in points if not (math.isfinite(x) and x > 0.0)]
    if bad:
        fail([f"--at {bad[0]:g}: expected a life > 0"])
    if as_json:
        document = fit.to_dict()
        document.update(
            source=str(data),
            confidence=level,
            reliability_at=[{"life": x, "reliability": float(fit.reliability(x))} for x in points],
            bad_rows=[b.to_dict() for b in table.bad_rows],
        )
        typer.echo(json.dumps(document, indent=2, sort_keys=True))
    else:
        low, high = fit.shape_interval
        typer.echo(
            f"Weibull fit of {fit.failures} failures and {fit.suspensions} suspensions ({data}):"
        )
        typer.echo(f"  shape beta = {fit.shape:.4g} [{low:.4g}, {high:.4g}]")
        low, high = fit.scale_interval
        typer.echo(f"  scale eta  = {fit.scale:.5g} [{low:.5g}, {high:.5g}] (63.2 % fail by it)")
        typer.echo(f"  B10 life   = {fit.b_life(0.1):.5g} (10 % fail by it)")
        for x in points:
            typer.echo(f"  R({x:g}) = {float(fit.reliability(x)):.6g}")
        typer.echo(
            f"intervals: {_percent(level)}, Fisher matrix on log scale; lives in the file's unit"
        )
        if fit.shape_interval[0] > 1.0:
            typer.echo("beta > 1 at this confidence: failures grow with life (wear-out)")
        elif fit.shape_interval[1] < 1.0:
            typer.echo("beta < 1 at this confidence: early failures (infant mortality)")
    for bad_row in table.bad_rows:
        typer.echo(f"warning: {bad_row.message()}", err=True)


def print_requirement_misses(console: Console, cases: list[dict[str, Any]], u: Shown) -> None:
    """The Monte Carlo table of the probability of missing each requirement."""
    from rich.markup import escape
    from rich.table import Table

    if not cases or not all("requirements" in case for case in cases):
        return
    table = Table(
        title="Probability of missing each requirement [%]: estimate (95 % upper bound)",
        title_justify="left",
    )
    table.add_column("requirement")
    for case in cases:
        table.add_column(escape(u.text(case["temperature_C"], "temperature")), justify="right")
    names = list(cases[0]["requirements"])
    for name in names:
        cells = []
        for case in cases:
            block = case["requirements"][name]
            cells.append(f"{100 * block['probability']:.3g} ({100 * block['upper95']:.2g})")
        table.add_row(escape(cases[0]["requirements"][name]["label"]), *cells)
    display.show(console, table, wrap=("requirement",))
    samples = cases[0]["requirements"][names[0]]["samples"] if names else 0
    display.note(
        console,
        f"from {samples:,} samples; upper bound one-sided, Clopper-Pearson (with no miss "
        f"about 3/N = {300.0 / max(samples, 1):.2g} %); docs/qualification.md",
    )


def repeat_reliability(deployment_times: Any, config: Any) -> dict[str, Any]:
    """The ``reliability`` block of ``ecdsim repeat``: per temperature, the failed
    deployments (a stall, or a time outside the config's [requirements] window), the
    reliability they demonstrate at 95 %, the drift and, where any fail, Crow's
    power-law process (:func:`ecdsim.characterize.reliability.life_test`)."""
    from ecdsim.characterize.reliability import CONFIDENCE, life_test

    spec = config.spec.requirements
    low = None if spec is None else spec.min_deployment_time
    high = None if spec is None else spec.max_deployment_time
    criteria = ["stall"]
    if low is not None:
        criteria.append(f"time < {low:g} s")
    if high is not None:
        criteria.append(f"time > {high:g} s")
    return {
        "failure_criteria": criteria,
        "confidence": CONFIDENCE,
        "temperatures_C": [float(t) for t in config.temperatures],
        "cases": life_test(deployment_times, low, high, CONFIDENCE),
    }


def print_life_test(block: dict[str, Any], units: str = "si") -> None:
    """The repeat command's reliability lines, one paragraph per temperature, the
    temperatures in ``units`` (si or us)."""
    from ecdsim.units_display import Shown

    shown = Shown(units)  # type: ignore[arg-type]
    console = display.make_console()
    criteria = " or ".join(block["failure_criteria"])
    for t, case in zip(block["temperatures_C"], block["cases"], strict=True):
        done = case["demonstrated"]
        shown_t = shown.text(t, "temperature")
        failed = case["failed_deployments"]
        listed = ", ".join(str(k) for k in failed[:8]) + (", ..." if len(failed) > 8 else "")
        text = (
            f"at {shown_t}: {done['runs']} deployments, {len(failed)} failed ({criteria})"
            + (f": {listed}" if failed else "")
            + f"; reliability demonstrated at {_percent(block['confidence'])} confidence: "
            f"{done['demonstrated_reliability']:.4g} ({done['bound']})"
        )
        process = case["power_law_process"]
        if process is not None:
            low, high = process["beta_interval95"]
            text += (
                f"; power-law process beta = {process['beta']:.3g} [{low:.3g}, {high:.3g}]"
                " (> 1: failures come faster with use)"
            )
        display.note(console, text)
    display.note(
        console,
        "a simulated sequence is one unit's deterministic life: the bound is what a test "
        "with these outcomes would demonstrate (docs/qualification.md)",
    )

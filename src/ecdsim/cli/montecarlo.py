"""``ecdsim montecarlo``: a tolerance study, resumable, in process or on Dask.

A thin shell over :mod:`ecdsim.montecarlo`: parse, build the plan, run it with a progress
bar, summarise, render. Only typer is imported at start-up. User errors print one
``error:`` line per problem and exit with code 2; Ctrl-C leaves every finished chunk on
disk, prints the command that resumes, and exits with code 130.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ecdsim.cli.common import fail, load_run
from ecdsim.formatting import format_number

if TYPE_CHECKING:
    from collections.abc import Callable

    from rich.console import Console

    from ecdsim.montecarlo.run import Plan

INTERRUPTED = 130  # the shell's code for a process stopped by SIGINT

EPILOG = (
    "Example: [bold]ecdsim montecarlo examples/paper_cc16_tolerances.toml --samples 100000"
    "[/bold] (tolerances in the config's \\[tolerances] section, docs/montecarlo.md)"
)


def montecarlo(
    config: Annotated[
        Path, typer.Argument(help="TOML configuration with a \\[tolerances] section.")
    ],
    samples: Annotated[
        int, typer.Option("--samples", "-n", help="Number of samples (parameter sets).")
    ],
    method: Annotated[
        str, typer.Option("--method", "-m", help="Solver: exact, dynamic (if installed), paper.")
    ] = "exact",
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            help="Dask LocalCluster workers; 0 runs in this process. Default: in process, "
            "or one worker per CPU for 2,000,000 samples and more on 2 or more CPUs.",
        ),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="Address of a running Dask scheduler.", metavar="ADDR"),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out", help="Folder for the run (default: CONFIG-montecarlo).", metavar="DIR"
        ),
    ] = None,
    resume: Annotated[
        bool, typer.Option("--resume", help="Continue an interrupted run in --out.")
    ] = False,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print the summary as JSON on stdout.")
    ] = False,
    seed: Annotated[
        int | None, typer.Option("--seed", help="Seed; overrides \\[tolerances] seed.")
    ] = None,
    sampling: Annotated[
        str | None,
        typer.Option("--sampling", help="random, lhs or sobol; overrides \\[tolerances]."),
    ] = None,
    chunk_size: Annotated[
        int | None,
        typer.Option("--chunk-size", help="Samples per chunk; overrides \\[tolerances]."),
    ] = None,
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Temperature, repeatable; overrides \\[analysis] (bare numbers are degC).",
        ),
    ] = None,
    plot: Annotated[
        bool, typer.Option("--plot/--no-plot", help="Write PNG plots into DIR/plots.")
    ] = True,
    show_progress: Annotated[
        bool, typer.Option("--progress/--no-progress", help="Show the progress bar.")
    ] = True,
) -> None:
    """Monte Carlo tolerance study: percentiles, stall probability, sensitivities."""
    from ecdsim.config import ConfigError
    from ecdsim.deployment import ModelDomainError
    from ecdsim.montecarlo import (
        MissingDependency,
        RunError,
        RunInterrupted,
        build_plan,
        choose_executor,
        run,
    )

    loaded = load_run(config, temperature, None)
    folder = out if out is not None else Path(f"{config.stem}-montecarlo")
    try:
        plan = build_plan(
            loaded,
            samples,
            method,
            seed=seed,
            sampling_method=sampling,
            chunk_size=chunk_size,
            out=folder,
            resume=resume,
        )
        executor = choose_executor(samples, workers, scheduler)
    except ConfigError as exc:
        fail(str(exc).splitlines())
    except RunError as exc:
        fail(exc.problems)
    console = _console()
    console.print(
        f"{plan.samples:,} samples x {len(plan.temperatures)} temperatures, {plan.method} "
        f"method, {plan.sampling} sampling, seed {plan.seed}, {plan.chunks:,} chunk(s) of "
        f"{plan.chunk_size:,}; {executor.describe()} -> {folder}",
        highlight=False,
    )
    resume_command = _resume_command(config, plan, folder, workers, scheduler)
    try:
        with _progress(console, show_progress) as update:
            report = run(plan, folder, executor, resume=resume, progress=update)
        for note in report.notes:
            console.print(f"note: {note}", highlight=False)
        console.print(
            f"{report.chunks_computed:,} chunk(s) computed, {report.chunks_reused:,} reused, "
            f"in {report.elapsed_s:.1f} s",
            highlight=False,
        )
        summary = _summarize(plan, folder, plot, console)
    except RunInterrupted as exc:
        console.print(
            f"interrupted: {exc.chunks_done:,} of {exc.chunks_total:,} chunks are on disk in "
            f"{exc.out}; continue with:\n  {resume_command}",
            highlight=False,
        )
        raise typer.Exit(INTERRUPTED) from None
    except KeyboardInterrupt:
        console.print(
            "interrupted while summarising: every chunk is on disk; write the summary with:\n"
            f"  {resume_command}",
            highlight=False,
        )
        raise typer.Exit(INTERRUPTED) from None
    except (RunError, ConfigError) as exc:
        fail(exc.problems)
    except MissingDependency as exc:
        fail([str(exc)])
    except ModelDomainError as exc:
        fail([f"{plan.config_source}: {exc}"])
    except OSError as exc:
        fail([f"--out {folder}: cannot write ({exc.strerror or exc})"])
    if as_json:
        typer.echo(json.dumps(summary, indent=2, sort_keys=True, allow_nan=False))
    else:
        _print_tables(summary)


def _console() -> Console:
    from rich.console import Console

    return Console(stderr=True, soft_wrap=True)  # paths and commands stay on one line


def _resume_command(
    config: Path, plan: Plan, out: Path, workers: int | None, scheduler: str | None
) -> str:
    parts = [
        "ecdsim",
        "montecarlo",
        str(config),
        "--samples",
        str(plan.samples),
        "--method",
        plan.method,
        "--seed",
        str(plan.seed),
        "--sampling",
        plan.sampling,
        "--chunk-size",
        str(plan.chunk_size),
    ]
    for t in plan.temperatures:
        parts += ["-T", f"{t:g}"]
    if workers is not None:
        parts += ["--workers", str(workers)]
    if scheduler is not None:
        parts += ["--scheduler", scheduler]
    return shlex.join([*parts, "--out", str(out), "--resume"])


class _progress:  # noqa: N801 - used as a context manager, like a function
    """A rich progress bar (samples, rate, ETA) on stderr, or nothing."""

    def __init__(self, console: Console, enabled: bool) -> None:
        self.console = console
        self.enabled = enabled
        self.bar: Any = None
        self.task: Any = None

    def __enter__(self) -> Callable[[int, int], None]:
        if not self.enabled:
            return lambda done, total: None
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            ProgressColumn,
            Task,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.text import Text

        class Rate(ProgressColumn):
            def render(self, task: Task) -> Text:
                speed = task.speed
                return Text(f"{speed:,.0f} samples/s" if speed else "- samples/s")

        self.bar = Progress(
            TextColumn("[bold]Monte Carlo"),
            BarColumn(),
            MofNCompleteColumn(),
            Rate(),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=self.console,
            transient=False,
        )
        self.bar.start()

        def update(done: int, total: int) -> None:
            if self.task is None:
                self.task = self.bar.add_task("samples", total=total, completed=done)
            else:
                self.bar.update(self.task, completed=done)

        return update

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()


def _summarize(plan: Plan, out: Path, plot: bool, console: Console) -> dict[str, Any]:
    from ecdsim import atomic
    from ecdsim.montecarlo.stats import summarize
    from ecdsim.montecarlo.store import SUMMARY

    summary = summarize(plan, out)
    text = json.dumps(summary, indent=2, sort_keys=True, allow_nan=False) + "\n"
    written = [atomic.write_text(out / SUMMARY, text)]
    if plot:
        from ecdsim.montecarlo.plots import write_plots

        written += write_plots(plan, out, summary)
    for path in written:
        console.print(f"wrote {path}", highlight=False)
    return summary


def _fmt(value: float | None, digits: int = 4) -> str:
    # The summary JSON stores non-finite values (a stall's time) as null: show "inf".
    return format_number(value, digits, none="inf", signed_inf=False)


def _print_tables(summary: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    console = Console(soft_wrap=False, width=max(120, Console().width))
    cases = summary["cases"]
    title = (
        f"{summary['system']}: {summary['samples']:,} samples, {summary['method']} method, "
        f"{summary['sampling']} sampling, seed {summary['seed']}"
    )
    times = Table(title=escape(f"Deployment time [s]  ({title})"), title_justify="left")
    for header in ("T [degC]", "nominal", "P1", "P5", "P50", "P95", "P99", "mean", "std"):
        times.add_column(escape(header), justify="right")
    times.add_column(escape("stall [%] (95 % interval)"), justify="right")
    for case in cases:
        d = case["deployment_time_s"]
        p = d["percentiles"]
        s = case["stall"]
        low, high = s["interval95"]
        mean = d["mean"] if d["mean"] is not None else d["mean_arriving"]
        std = d["std"] if d["std"] is not None else d["std_arriving"]
        marker = "" if d["mean"] is not None else "*"
        times.add_row(
            f"{case['temperature_C']:g}",
            _fmt(case["nominal"]["deployment_time_s"]),
            *(_fmt(p[name]["value"]) for name in ("P1", "P5", "P50", "P95", "P99")),
            _fmt(mean) + marker,
            _fmt(std) + marker,
            f"{100 * s['probability']:.3g} [{100 * low:.2g}, {100 * high:.2g}]",
        )
    console.print(times)
    if any(c["deployment_time_s"]["mean"] is None for c in cases):
        console.print(
            escape(
                "* over the samples that arrive (some stall: the mean over all is infinite);"
                " 'inf' percentiles fall among stalled samples"
            ),
            style="dim",
        )

    speeds = Table(
        title=escape("End (latch) speed [rad/s], samples that arrive"), title_justify="left"
    )
    for header in ("T [degC]", "nominal", "P1", "P50", "P99", "mean", "std"):
        speeds.add_column(escape(header), justify="right")
    for case in cases:
        e = case["end_speed_rad_s"]
        p = e["percentiles"]
        speeds.add_row(
            f"{case['temperature_C']:g}",
            _fmt(case["nominal"]["end_speed_rad_s"]),
            _fmt(p["P1"]["value"]),
            _fmt(p["P50"]["value"]),
            _fmt(p["P99"]["value"]),
            _fmt(e["mean"]),
            _fmt(e["std"]),
        )
    console.print(speeds)

    if all("min_torque_margin" in case for case in cases):
        margins = Table(
            title="Minimum torque margin over the travel (docs/sizing.md section 5)",
            title_justify="left",
        )
        for header in ("T [degC]", "nominal", "P1", "P5", "P50", "mean", "P(< required) [%]"):
            margins.add_column(escape(header), justify="right")
        for case in cases:
            m = case["min_torque_margin"]
            p = m["percentiles"]
            below = m.get("probability_below_required")
            margins.add_row(
                f"{case['temperature_C']:g}",
                _fmt(case["nominal"]["min_torque_margin"]),
                _fmt(p["P1"]["value"]),
                _fmt(p["P5"]["value"]),
                _fmt(p["P50"]["value"]),
                _fmt(m["mean"] if m["mean"] is not None else m["mean_arriving"]),
                "-" if below is None else f"{100 * below:.3g}",
            )
        console.print(margins)

    sensitivity = Table(
        title="Sensitivity of deployment time: SRC / first-order index (docs/montecarlo.md)",
        title_justify="left",
    )
    sensitivity.add_column("quantity")
    for case in cases:
        r2 = case["sensitivity"]["r_squared"]
        label = f"{case['temperature_C']:g} degC\nR^2 {_fmt(r2, 3)}"
        sensitivity.add_column(escape(label), justify="right")
    keys = [row["key"] for row in cases[0]["sensitivity"]["inputs"]] if cases else []
    for key in keys:
        cells = []
        for case in cases:
            row = next(r for r in case["sensitivity"]["inputs"] if r["key"] == key)
            src = "-" if row["src"] is None else f"{row['src']:+.3f}"
            first = "-" if row["first_order"] is None else f"{row['first_order']:.3f}"
            cells.append(f"{src} / {first}")
        sensitivity.add_row(key, *cells)
    console.print(sensitivity)

    repeat = Table(title="Repeatability (paper section 6: 500 deployments)", title_justify="left")
    for header in (
        "T [degC]",
        "within [s]",
        "runs",
        "P(one within) [%]",
        "P(all within) [%]",
        "typical max dev. [s]",
        "meets",
    ):
        repeat.add_column(escape(header), justify="right")
    for case in cases:
        r = case["repeatability"]
        if "fraction_within" not in r:
            repeat.add_row(
                f"{case['temperature_C']:g}",
                _fmt(r["within_s"]),
                str(r["runs"]),
                "-",
                "-",
                "-",
                "no (nominal stalls)",
            )
            continue
        repeat.add_row(
            f"{case['temperature_C']:g}",
            _fmt(r["within_s"]),
            str(r["runs"]),
            f"{100 * r['fraction_within']:.4g}",
            f"{100 * r['probability_all_within']:.3g}",
            _fmt(r["typical_max_deviation_s"]),
            "yes" if r["meets_stated_spread"] else "no",
        )
    console.print(repeat)
    for warning in summary["warnings"]:
        console.print(
            escape(
                f"warning: [{warning['code']}] in {warning['chunks']} chunk(s), e.g. "
                f"{warning['example']}"
            ),
            style="yellow",
        )
    for note in summary["notes"]:
        console.print(escape(f"note: {note}"), style="dim")

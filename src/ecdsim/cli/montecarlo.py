"""``ecdsim montecarlo``: a tolerance study, resumable, in process or on Dask.

A thin shell over :mod:`ecdsim.montecarlo`: parse, build the plan, run it with a progress
bar, summarise, render. Only typer is imported at start-up. User errors print one
``error:`` line per problem and exit with code 2; Ctrl-C leaves every finished chunk on
disk, prints the command that resumes, and exits with code 130.
"""

from __future__ import annotations

import contextlib
import json
import shlex
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ecdsim.cli import display
from ecdsim.cli.common import UnitsOpt, fail, load_run, os_error_line, units_option
from ecdsim.cli.display import PlainOpt, WideOpt
from ecdsim.formatting import format_number
from ecdsim.units_display import Shown, UnitSystem

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
        Path,
        typer.Argument(help="TOML configuration with a \\[tolerances] section.", metavar="CONFIG"),
    ],
    samples: Annotated[
        int,
        typer.Option("--samples", "-n", help="Number of samples (parameter sets).", metavar="N"),
    ],
    method: Annotated[
        str,
        typer.Option(
            "--method", "-m", help="Solver: exact, dynamic (if installed), paper.", metavar="METHOD"
        ),
    ] = "exact",
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            help="Dask LocalCluster workers; 0 runs in this process. Default: in process, "
            "or one worker per CPU for 2,000,000 samples and more on 3 or more CPUs (on "
            "Linux; 2 or more elsewhere).",
            metavar="N",
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
    overwrite: Annotated[
        bool,
        typer.Option(
            "--overwrite",
            help="Replace the run already in --out (its manifest, chunks, summary and plots; "
            "other files are kept).",
        ),
    ] = False,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print the summary as JSON on stdout.")
    ] = False,
    seed: Annotated[
        int | None,
        typer.Option("--seed", help="Seed; overrides \\[tolerances] seed.", metavar="SEED"),
    ] = None,
    sampling: Annotated[
        str | None,
        typer.Option(
            "--sampling", help="random, lhs or sobol; overrides \\[tolerances].", metavar="SCHEME"
        ),
    ] = None,
    chunk_size: Annotated[
        int | None,
        typer.Option(
            "--chunk-size", help="Samples per chunk; overrides \\[tolerances].", metavar="N"
        ),
    ] = None,
    temperature: Annotated[
        list[str] | None,
        typer.Option(
            "--temperature",
            "-T",
            help="Temperature, repeatable; overrides \\[analysis] (bare numbers are degC).",
            metavar="TEMP",
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot", help="Folder for the PNG plots (default: DIR/plots).", metavar="DIR"
        ),
    ] = None,
    no_plot: Annotated[bool, typer.Option("--no-plot", help="Write no plots.")] = False,
    show_progress: Annotated[
        bool,
        typer.Option(
            "--progress/--no-progress",
            help="Show the progress bar (only ever on a terminal, never in a pipe or log).",
        ),
    ] = True,
    units: UnitsOpt = None,
    wide: WideOpt = False,
    plain: PlainOpt = False,
) -> None:
    """Monte Carlo tolerance study: percentiles, stall probability, sensitivities."""
    display.configure(wide=wide, plain=plain)
    from ecdsim.cli.wing import is_wing_file

    if is_wing_file(config):  # the wing's study (docs/wing.md, studies)
        from ecdsim.cli.wing import run_wing_montecarlo

        run_wing_montecarlo(
            config,
            samples,
            seed=seed,
            sampling=sampling,
            temperatures=temperature,
            out=out,
            plot=plot,
            no_plot=no_plot,
            as_json=as_json,
            units=units,
            refused={
                "--method": method != "exact",
                "--workers": workers is not None,
                "--scheduler": scheduler is not None,
                "--resume": resume,
                "--chunk-size": chunk_size is not None,
            },
        )
        return
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
    u = Shown(units_option(units, loaded))
    folder = out if out is not None else Path(f"{config.stem}-montecarlo")
    if plot is not None and str(plot).startswith("-"):
        # `--plot` was a switch before issue 26 (plots are on by default): a bare --plot
        # followed by another option would take that option as the folder.
        fail(
            [
                f"--plot {plot}: --plot takes a folder now (plots go to DIR/plots by "
                "default: drop a bare --plot; --no-plot writes none)"
            ]
        )
    plots = None if no_plot else (plot if plot is not None else folder / "plots")
    if resume and overwrite:
        fail(["--resume continues the run in --out and --overwrite replaces it: give one"])
    _check_folder(folder, resume, overwrite)
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
    if overwrite:
        removed = _clear_run(folder)
        if removed:
            console.print(f"--overwrite: removed the earlier run's {removed} file(s) in {folder}")
    console.print(
        f"{plan.samples:,} samples x {len(plan.temperatures)} temperatures, {plan.method} "
        f"method, {plan.sampling} sampling, seed {plan.seed}, {plan.chunks:,} chunk(s) of "
        f"{plan.chunk_size:,}; {executor.describe()} -> {folder}",
        highlight=False,
        soft_wrap=False,  # wrapped to the terminal's width (80 in a pipe)
    )
    resume_command = _resume_command(config, plan, folder, workers, scheduler)
    new_folder = not folder.exists()  # said once the run stands (a failed one removes it)
    try:
        # The bar redraws itself: on a terminal only, never into a pipe or a log file.
        with _progress(console, show_progress and console.is_terminal) as update:
            report = run(plan, folder, executor, resume=resume, progress=update)
        if new_folder:
            console.print(  # one line, the path whole, as the other commands' note
                f"note: created the folder {folder} (it did not exist)",
                highlight=False,
                soft_wrap=True,
            )
        for note in report.notes:
            console.print(f"note: {note}", highlight=False, soft_wrap=False)
        console.print(
            f"{report.chunks_computed:,} chunk(s) computed, {report.chunks_reused:,} reused, "
            f"in {report.elapsed_s:.1f} s",
            highlight=False,
        )
        summary = _summarize(plan, folder, plots, console, u.system)
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
        fail([os_error_line("--out", folder, exc)])
    except MemoryError:
        # Checked before the run (ecdsim.montecarlo.budget), but memory is shared: other
        # programs may take it meanwhile.
        fail([f"--samples {samples}: out of memory while running or summarising the study"])
    if as_json:
        document = {**summary, "display_units": u.system}
        typer.echo(json.dumps(document, indent=2, sort_keys=True, allow_nan=False))
    else:
        _print_tables(summary, u)


def _check_folder(folder: Path, resume: bool, overwrite: bool) -> None:
    """Exit 2 with one line naming both ways on when ``folder`` holds a run already."""
    from ecdsim.montecarlo.store import MANIFEST

    if (folder / MANIFEST).exists() and not (resume or overwrite):
        fail(
            [
                f"--out {folder}: this folder already holds a Monte Carlo run; add --resume "
                "to continue it, --overwrite to replace it, or choose another --out"
            ]
        )


def _clear_run(folder: Path) -> int:
    """Delete what a run writes into ``folder`` (nothing else); the number of files.

    The manifest goes first, so that a run stopped half-way through the deletion leaves
    a folder without a run rather than one with a run missing its chunks.
    """
    from ecdsim.montecarlo.plots import PLOT_NAMES
    from ecdsim.montecarlo.store import CHUNKS, MANIFEST, SUMMARY

    targets = [folder / MANIFEST, folder / SUMMARY]
    targets += sorted(folder.glob(f".{MANIFEST}.*.tmp")) + sorted(folder.glob(f".{SUMMARY}.*.tmp"))
    chunks, plots = folder / CHUNKS, folder / "plots"
    if chunks.is_dir():
        targets += sorted(chunks.glob("chunk-*.parquet")) + sorted(chunks.glob(".chunk-*.tmp"))
    if plots.is_dir():
        targets += [plots / f"{name}.png" for name in PLOT_NAMES]
    removed = 0
    for path in targets:
        if path.is_file():
            path.unlink()
            removed += 1
    for empty in (chunks, plots):
        with contextlib.suppress(OSError):  # absent, or holding the user's own files
            empty.rmdir()
    return removed


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


def _summarize(
    plan: Plan, out: Path, plots: Path | None, console: Console, units: UnitSystem = "si"
) -> dict[str, Any]:
    from ecdsim import atomic
    from ecdsim.montecarlo.stats import summarize
    from ecdsim.montecarlo.store import SUMMARY

    summary = summarize(plan, out)
    text = json.dumps(summary, indent=2, sort_keys=True, allow_nan=False) + "\n"
    written = [atomic.write_text(out / SUMMARY, text)]
    if plots is not None:
        from ecdsim.montecarlo.plots import write_plots

        written += write_plots(plan, out, summary, units, plots)
    for path in written:
        console.print(f"wrote {path}", highlight=False)
    return summary


def _fmt(value: float | None, digits: int = 4) -> str:
    # The summary JSON stores non-finite values (a stall's time) as null: show "inf".
    return format_number(value, digits, none="inf", signed_inf=False)


def _print_tables(summary: dict[str, Any], u: Shown) -> None:
    from rich.markup import escape
    from rich.table import Table

    console = display.make_console()
    cases = summary["cases"]
    title = (
        f"{summary['system']}: {summary['samples']:,} samples, {summary['method']} method, "
        f"{summary['sampling']} sampling, seed {summary['seed']}"
    )
    times = Table(title=escape(f"Deployment time [s]  ({title})"), title_justify="left")
    for header in (u.head("T", "temperature"), "nominal", "P1", "P5", "P50", "P95", "P99"):
        times.add_column(escape(header), justify="right")
    for header in ("mean", "std"):
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
            u.num(case["temperature_C"], "temperature"),
            _fmt(case["nominal"]["deployment_time_s"]),
            *(_fmt(p[name]["value"]) for name in ("P1", "P5", "P50", "P95", "P99")),
            _fmt(mean) + marker,
            _fmt(std) + marker,
            f"{100 * s['probability']:.3g} [{100 * low:.2g}, {100 * high:.2g}]",
        )
    display.show(console, times, drop=("P5", "P95", "std", "mean"), wrap=("stall",))
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
    for header in (u.head("T", "temperature"), "nominal", "P1", "P50", "P99", "mean", "std"):
        speeds.add_column(escape(header), justify="right")
    for case in cases:
        e = case["end_speed_rad_s"]
        p = e["percentiles"]
        speeds.add_row(
            u.num(case["temperature_C"], "temperature"),
            _fmt(case["nominal"]["end_speed_rad_s"]),
            _fmt(p["P1"]["value"]),
            _fmt(p["P50"]["value"]),
            _fmt(p["P99"]["value"]),
            _fmt(e["mean"]),
            _fmt(e["std"]),
        )
    display.show(console, speeds, drop=("std", "mean"))

    if all("min_torque_margin" in case for case in cases):
        margins = Table(
            title="Minimum torque margin over the travel (docs/sizing.md section 5)",
            title_justify="left",
        )
        for header in (
            u.head("T", "temperature"),
            "nominal",
            "P1",
            "P5",
            "P50",
            "mean",
            "P(< required) [%]",
        ):
            margins.add_column(escape(header), justify="right")
        for case in cases:
            m = case["min_torque_margin"]
            p = m["percentiles"]
            below = m.get("probability_below_required")
            margins.add_row(
                u.num(case["temperature_C"], "temperature"),
                _fmt(case["nominal"]["min_torque_margin"]),
                _fmt(p["P1"]["value"]),
                _fmt(p["P5"]["value"]),
                _fmt(p["P50"]["value"]),
                _fmt(m["mean"] if m["mean"] is not None else m["mean_arriving"]),
                "-" if below is None else f"{100 * below:.3g}",
            )
        display.show(console, margins, drop=("P5", "mean"))

    # With [requirements]: how often each is missed (docs/qualification.md).
    from ecdsim.cli.reliability import print_requirement_misses

    print_requirement_misses(console, cases, u)

    sensitivity = Table(
        title="Sensitivity of deployment time: SRC / first-order index (docs/montecarlo.md)",
        title_justify="left",
    )
    sensitivity.add_column("quantity")
    for case in cases:
        r2 = case["sensitivity"]["r_squared"]
        label = f"{u.text(case['temperature_C'], 'temperature')}\nR^2 {_fmt(r2, 3)}"
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
    display.show(console, sensitivity, wrap=("quantity",))

    if cases:
        _print_repeatability(console, cases, u)
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


def _chance(probability: float, possible: bool) -> str:
    """A probability in percent, in plain terms: tiny or near-certain values as bounds.

    ``possible`` is False when no sample at all stayed within (the chance is then 0, not
    merely small).
    """
    if not possible or probability <= 0.0:
        return "0" if not possible else "< 0.01"
    if probability >= 1.0:
        return "100"
    if probability < 1e-4:
        return "< 0.01"
    if probability > 1.0 - 1e-4:
        return "> 99.99"
    return f"{100 * probability:.3g}"


def _lower_bound(probability: float) -> str:
    """A lower bound in percent, with the digits that keep it below 100 ("> 99.98").

    >>> [_lower_bound(p) for p in (0.631, 0.99982, 0.0)]
    ['63.1', '99.98', '0']
    """
    if probability < 1e-4:
        return "0"
    for digits in range(3, 8):
        text = f"{100 * probability:.{digits}g}"
        if text != "100":
            return text
    return text


def _as_paper(meets: bool, spread: float | None, required: float | None) -> str:
    """The 'as paper' cell: "yes", or "no" with how many times the allowed spread the
    tolerances give ("no: 35x"), so that a "no" says at once by how much."""
    if meets:
        return "yes"
    if spread is None or required is None or required <= 0.0:
        return "no"
    return f"no: {spread / required:.2g}x"


def _as_paper_lines(
    spreads: list[tuple[float, float]], required: float | None, runs: int, window: str, u: Shown
) -> list[str]:
    """What "as paper" means and why a "no" need not alarm, first under the table."""
    lines = [
        f"'as paper': the typical worst of {runs} deployments is within {window}, as the "
        "paper's one unit was over 500 deployments at each temperature extreme (section 6)."
    ]
    if required is None:
        return lines
    lines.append(
        f"That needs a spread (1 sigma) of at most {_fmt(required, 3)} s; 'no: Nx' gives "
        "the spread of these tolerances in multiples of it."
    )
    wide = [(t, x) for t, x in spreads if x > 3.0 * required]
    if wide:
        where = ", ".join(u.num(t, "temperature") for t, _ in wide)
        lines.append(
            f"At {where} {u.unit('temperature')} the spread is far wider than one unit's "
            "run-to-run scatter usually is: these read as unit-to-unit (manufacturing) "
            f"tolerances, and then 'no' says that different units differ by more than "
            f"{window}, not that one unit repeats badly. For the paper's test, give the "
            "scatter of one unit instead (docs/montecarlo.md)."
        )
    return lines


def _print_repeatability(console: Console, cases: list[dict[str, Any]], u: Shown) -> None:
    """The repeated-deployment table and what it means, in words (docs/montecarlo.md)."""
    from rich.markup import escape
    from rich.table import Table

    first = cases[0]["repeatability"]
    runs, within, required = first["runs"], first["within_s"], first.get("required_std_s")
    window = f"+-{_fmt(within)} s"
    table = Table(
        title=escape(f"Repeatability: {runs} deployments of one unit, each within {window}"),
        title_justify="left",
    )
    headers = (
        u.head("T", "temperature"),
        "nominal [s]",
        "spread [s]",
        "one within [%]",
        f"all {runs} within [%]",
        f"worst of {runs} [s]",
        "as paper",
    )
    for header in headers:
        table.add_column(escape(header), justify="right")
    spreads: list[tuple[float, float]] = []  # (temperature, spread) of the rows shown
    bounded = False  # some row shows lower bounds (every sample within)
    for case in cases:
        r = case["repeatability"]
        d = case["deployment_time_s"]
        spread = d["std"] if d["std"] is not None else d["std_arriving"]
        marker = "" if d["std"] is not None else "*"
        if "fraction_within" not in r:
            table.add_row(
                u.num(case["temperature_C"], "temperature"), "stalls", "-", "-", "-", "-", "no"
            )
            continue
        if spread is not None:
            spreads.append((case["temperature_C"], spread))
        possible = r["fraction_within"] > 0.0
        one = _chance(r["fraction_within"], possible)
        every = _chance(r["probability_all_within"], possible)
        if r["fraction_within"] >= 1.0:  # every sample within: the lower 95 % bounds
            one, every = (
                "> " + _lower_bound(low)
                for low in (
                    r["fraction_within_interval95"][0],
                    r["probability_all_within_interval95"][0],
                )
            )
            bounded = True
        table.add_row(
            u.num(case["temperature_C"], "temperature"),
            _fmt(r["nominal_time_s"]),
            _fmt(spread) + marker,
            one,
            every,
            _fmt(r["typical_max_deviation_s"]),
            _as_paper(r["meets_stated_spread"], spread, required),
        )
    display.show(console, table)
    lines = _as_paper_lines(spreads, required, runs, window, u)
    lines += [
        "Each sample is read as one deployment of the same unit. 'spread': the standard "
        f"deviation of one deployment's time (1 sigma); 'one within': the chance that one "
        f"deployment ends within {window} of the nominal time; 'all {runs} within': the "
        f"chance that {runs} deployments all do; 'worst of {runs}': the largest deviation "
        f"among {runs}, typically (the median).",
    ]
    if bounded:
        lines.append(
            "'> x': every sample was within; x is the lower end of the 95 % interval "
            "(more samples raise it)."
        )
    if any(c["deployment_time_s"]["std"] is None for c in cases):
        lines.append("* over the samples that arrive (some stall)")
    for line in lines:
        console.print(escape(line), style="dim")

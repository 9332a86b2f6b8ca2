"""``ecdsim deploy WING.toml``: a wing file's deployment over temperature (docs/wing.md).

``deploy`` hands a file with ``[wing]`` here: the wing is solved at each temperature by
:func:`ecdsim.wing.solver.deploy_wing`, and printed as a table per temperature (fits 80
columns): how the run ended, the deployment time, then one row per latch in latching
order (time, arrival speed, the wing's kinetic energy, the compliant latch's peak torque
or the rigid latch's impulse, the impact loss), the hinges left stuck and the energy
balance (and each heated damper's peak temperature). ``--json`` prints
:meth:`~ecdsim.wing.result.WingResult.to_dict`; ``--plot DIR``
writes the hinge angles and the shape strips (:mod:`ecdsim.plotting_wing`).

``sweep``, ``montecarlo`` and ``report`` hand a wing file here too: :func:`load_wing_run`
reads it with the options they share, :func:`run_wing_montecarlo` runs and prints the
tolerance study (:mod:`ecdsim.montecarlo.wing`), :func:`wing_report` writes the report
(:mod:`ecdsim.report.wing`); the sweep itself is :func:`ecdsim.sweeps.run_wing_sweep`.
"""

from __future__ import annotations

import json
import math
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from ecdsim.cli.common import fail, temperature_options
from ecdsim.wing.result import WingCase, WingResult

if TYPE_CHECKING:
    from ecdsim.config.wing_schema import WingConfig
    from ecdsim.montecarlo.wing import WingStudy
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
            "--method: not taken with a wing file (one solver: the wing's dynamics; docs/wing.md)"
        )
    temps = tuple(config.temperatures)
    if temperatures:
        temps = temperature_options(temperatures, problems)
    system: UnitSystem = "si"
    try:
        system = check_system(
            units or config.spec.output.units, "--units" if units else "output.units"
        )
    except UnitSystemError as exc:
        problems.append(str(exc))
    if problems:
        fail(problems)
    return WingRun(config, temps, system)


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
        typer.echo(json.dumps(result.to_dict(), indent=2, allow_nan=False))
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
        lines.extend(
            textwrap.wrap(
                "peak damper temperature: " + ", ".join(peaks),
                78,
                initial_indent="  ",
                subsequent_indent="    ",
            )
        )
    lines.append(f"  energy balance closes to {case.energy.error:.1e}")
    return lines


def format_wing(result: WingResult) -> str:
    """The table of every temperature."""
    lines = textwrap.wrap(f"{result.wing}: {len(result.hinges)} hinges", 80)
    for case in result.cases:
        lines.append("")
        lines.extend(format_case(result, case))
    return "\n".join(lines)


def run_wing_montecarlo(
    path: Path,
    samples: int,
    *,
    seed: int | None,
    sampling: str | None,
    temperatures: list[str] | None,
    out: Path | None,
    plot: Path | None,
    no_plot: bool,
    as_json: bool,
    units: str | None,
    refused: dict[str, bool],
) -> None:
    """``ecdsim montecarlo WING.toml``: the wing's tolerance study (docs/wing.md, studies;
    :mod:`ecdsim.montecarlo.wing`). Writes ``samples.csv``, ``summary.json`` and the
    plots into the run's folder; prints the statistics per temperature (80 columns) or,
    with ``--json``, the summary. ``refused``: the single hinge's options given (each
    refused in one line)."""
    from ecdsim import atomic
    from ecdsim.config import ConfigError
    from ecdsim.config.loader import parse_toml, read_config_text
    from ecdsim.config.seeds import seed_problem
    from ecdsim.montecarlo import wing as study_of
    from ecdsim.sizing.catalogue import load_catalogue

    problems = [
        f"{option}: not taken with a wing file (its samples run in one process; docs/wing.md)"
        for option, given in refused.items()
        if given
    ]
    if seed is not None and (bad := seed_problem(seed)) is not None:
        problems.append(f"--seed {seed}: {bad}")
    if sampling is not None and sampling not in ("random", "lhs", "sobol"):
        problems.append(f"--sampling {sampling!r}: expected random, lhs or sobol")
    if problems:
        fail(problems)
    run = load_wing_run(path, temperatures, None, units)
    raw = parse_toml(read_config_text(path), str(path))
    try:
        study = study_of.run(
            run.config,
            raw,
            samples,
            seed=seed,
            sampling=sampling,
            temperatures=run.temperatures,
            read_catalogue=load_catalogue,
        )
    except ConfigError as exc:
        fail(str(exc).splitlines())
    summary = study.summary()
    folder = out if out is not None else Path(f"{path.stem}-montecarlo")
    written = []
    try:
        written.append(study.table().write(folder / "samples.csv"))
        text = json.dumps(summary, indent=2, allow_nan=False)
        written.append(atomic.write_text(folder / "summary.json", text + "\n"))
        if not no_plot:
            written.extend(write_study_plots(study, summary, plot or folder / "plots"))
    except OSError as exc:
        fail([f"--out {folder}: cannot write ({exc.strerror or exc})"])
    for message in {m for _, m in study.errors}:
        typer.echo(f"warning: {message}", err=True)
    if as_json:
        typer.echo(json.dumps(summary, indent=2, allow_nan=False))
    else:
        typer.echo(format_study(summary))
    for target in written:
        typer.echo(f"wrote {target}", err=as_json)


def _stat(block: dict[str, object] | None, name: str) -> str:
    """A statistic of a :func:`ecdsim.montecarlo.stats.describe` block, 4 digits."""
    if not block:
        return "-"
    value: object
    if name in ("mean", "std", "max", "min"):
        value = block.get(name)
    else:
        found = block.get("percentiles")
        value = found.get(name, {}).get("value") if isinstance(found, dict) else None
    return f"{value:.4g}" if isinstance(value, float | int) else "-"


def format_study(summary: dict[str, object]) -> str:
    """The study's statistics per temperature, at 80 columns."""
    cases = summary["cases"]
    assert isinstance(cases, list)
    lines = textwrap.wrap(
        f"{summary['system']}: {summary['samples']:,} samples, {summary['sampling']} "
        f"sampling, seed {summary['seed']}",
        80,
    )
    for case in cases:
        times = case["deployment_time_s"]
        missed = case["not_latched"]
        lines.append("")
        lines.append(
            f"{case['temperature_C']:+g} degC: deployment time [s] mean {_stat(times, 'mean')}, "
            f"std {_stat(times, 'std')}, P1 {_stat(times, 'P1')}, P99 {_stat(times, 'P99')}"
        )
        low, high = missed["interval95"]
        lines.append(
            f"  not latched: {missed['count']} ({100 * (missed['probability'] or 0.0):.3g} %, "
            f"95 % interval {100 * low:.3g} to {100 * high:.3g} %)"
        )
        lines.append(
            f"  {'hinge':<12}{'latch time [s]':>20}{'latch speed [rad/s]':>22}{'stuck':>10}"
        )
        lines.append(f"  {'':<12}{'mean':>10}{'P99':>10}{'mean':>11}{'P99':>11}{'[%]':>10}")
        for hinge in case["hinges"]:
            time, speed = hinge.get("latch_time_s"), hinge.get("latch_speed_rad_s")
            stuck = hinge["stuck"]["probability"] or 0.0
            lines.append(
                f"  {str(hinge['hinge'])[:11]:<12}{_stat(time, 'mean'):>10}"
                f"{_stat(time, 'P99'):>10}{_stat(speed, 'mean'):>11}{_stat(speed, 'P99'):>11}"
                f"{100 * stuck:>10.3g}"
            )
            peak = hinge.get("peak_damper_temperature_C")
            if peak:
                lines.append(
                    f"  {'':<12}peak damper temperature [degC]: mean {_stat(peak, 'mean')}, "
                    f"P99 {_stat(peak, 'P99')}"
                )
        sens = case["sensitivity"]
        ranked = [
            f"{row['key']} {row['src']:+.2f}" for row in sens["inputs"] if row["src"] is not None
        ]
        r2 = sens["r_squared"]
        head = "  drivers of the deployment time (SRC"
        head += f", R^2 {r2:.3f}): " if r2 is not None else "): "
        lines.extend(
            textwrap.wrap(
                head + (", ".join(ranked) if ranked else "not defined (too few latched samples)"),
                80,
                subsequent_indent="    ",
            )
        )
    return "\n".join(lines)


def write_study_plots(study: WingStudy, summary: dict[str, object], folder: Path) -> list[Path]:
    """The study's plots (:mod:`ecdsim.montecarlo.plots`): the deployment time's histogram
    and CDF, each hinge's latch speed histogram, the drivers (tornado)."""
    import numpy as np

    from ecdsim.montecarlo.plots import plot_cdf, plot_histogram, plot_tornado, study_title
    from ecdsim.plotting import save_figure

    temps = study.temperatures
    what = f"{study.samples:,} samples, wing solver"
    times = {t: study.column("deployment_time_s", t) for t in temps}
    title = study_title(study.title, f"deployment time (last latch), {what}")
    figures = {
        "time_histogram": plot_histogram(times, "deployment time [s]", title),
        "time_cdf": plot_cdf(times, "deployment time [s]", title),
        "tornado": plot_tornado(summary),
    }
    for j, name in enumerate(study.hinges):
        speeds = {t: study.column(f"hinge_{j}_latch_speed_rad_s", t) for t in temps}
        speeds = {t: x[~np.isnan(x)] for t, x in speeds.items()}
        figures[f"latch_speed_hinge_{j}"] = plot_histogram(
            speeds,
            "latch (arrival) speed [rad/s]",
            study_title(study.title, f"{name}: latch speed of the samples that latch, {what}"),
        )
    return [save_figure(fig, folder / f"{name}.png") for name, fig in figures.items()]


def wing_report(
    path: Path,
    output: Path,
    temperatures: list[str] | None,
    methods: list[str] | None,
    units: str | None,
    fail_on: object,
) -> Path:
    """``ecdsim report WING.toml``: solve the wing and write its report
    (:mod:`ecdsim.report.wing`); returns the file written."""
    from ecdsim.report.wing import write_wing_report
    from ecdsim.wing.solver import WingUnsupported, deploy_wing

    if fail_on:
        fail(["--fail-on: not taken with a wing file (docs/wing.md)"])
    run = load_wing_run(path, temperatures, methods, units)
    config = run.config
    try:
        result = deploy_wing(
            config.wing, run.temperatures, rtol=config.rtol, stop_time=config.stop_time
        )
    except WingUnsupported as exc:
        fail([f"{path}: {exc}"])
    text = path.read_text(encoding="utf-8")
    try:
        written = write_wing_report(config, result, text, output, run.units)
    except OSError as exc:
        fail([f"--output {output}: cannot write ({exc.strerror or exc})"])
    typer.echo(f"wrote {written}")
    return written

"""The shared benchmark harness: interleaved timing of ecdsim against a baseline.

Every bench file exposes its cases the same way, a function ``cases(quick: bool) ->
list[Case]``; ``benchmarks/run.py`` (``make bench``) imports each file, measures each case
with :func:`measure` and prints one table (case, ecdsim, baseline, ratio, agreement) from
the :class:`Row` it returns. A case is two zero-argument callables, ``ecdsim`` and
``baseline``: Python functions timed in this process, or a :class:`Command` (a whole
process, timed from outside, returning its standard output); a callable may return a
:class:`Timed` to report the time of its own work. They are called in turn,
A B B A A B ..., after one untimed warm-up of each, so that both see the same machine load
(the machine is shared: absolute times swing, ratios of neighbouring calls much less).

Example, a bench file ``bench_example.py``::

    import numpy as np
    from harness import Case, Command, max_relative_difference

    def cases(quick: bool) -> list[Case]:
        n = 10_000 if quick else 1_000_000
        x = np.linspace(0.0, 1.0, n)
        return [
            Case(
                name="sum of squares",
                ecdsim=lambda: np.dot(x, x),
                baseline=lambda: sum(v * v for v in x.tolist()),
                baseline_name="a plain Python loop over the same floats",
                agree=max_relative_difference,  # ecdsim result, baseline result -> float
                tolerance=1e-12,  # agreement above this fails the run (exit 1)
                items=n, item_name="elements",  # adds a throughput note
            ),
            Case(
                name="ecdsim --help",
                ecdsim=Command(("ecdsim", "--help")),
                baseline=Command(("python", "-c", "pass")),
                baseline_name="a bare interpreter start",
                goal_s=0.3,  # ecdsim's median must stay below: MET / NOT MET
            ),
        ]

Conventions: ``ratio`` is baseline time over ecdsim time per item (above 1: ecdsim is
faster), the median of the ratios of each interleaved pair; ``agreement`` is what
``agree(ecdsim_result, baseline_result)`` returns for the warm-up results (a max relative
difference, or True/False for "same output"); ``items`` and ``baseline_items`` let the two
sides run different sizes (a Python loop over 2,000 sets against a vectorised call over
1,000,000), the ratio being per item. A case may also attach ``notes`` (a callable run once
after timing, returning lines to print under the table and a dict for results.json).
"""

from __future__ import annotations

import argparse
import atexit
import gc
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, TypeVar

T = TypeVar("T")

ROOT = Path(__file__).resolve().parent.parent
MIN_REPEATS = 5

Agreement = float | bool | None


@dataclass(frozen=True)
class Command:
    """A whole process to time: ``argv`` run with its output captured; returns its stdout.

    A non-zero exit status (other than ``expect_status``) raises ``RuntimeError`` with the
    process's standard error, so that a broken command is never timed as a fast one.
    """

    argv: tuple[str, ...]
    cwd: Path = ROOT
    env: Mapping[str, str] | None = None
    expect_status: int = 0

    def __call__(self) -> str:
        environment = None if self.env is None else {**os.environ, **self.env}
        completed = subprocess.run(
            list(self.argv),
            cwd=self.cwd,
            env=environment,
            capture_output=True,
            text=True,
            check=False,
        )
        if completed.returncode != self.expect_status:
            raise RuntimeError(
                f"{' '.join(self.argv)} exited {completed.returncode}: "
                f"{completed.stderr.strip()[-500:]}"
            )
        return completed.stdout

    def __str__(self) -> str:
        return " ".join(self.argv)


@dataclass(frozen=True)
class ProcessRun:
    """One whole process: wall time [s], its own peak resident memory [bytes], output."""

    seconds: float
    peak_bytes: int | None
    stdout: str
    stderr: str


_GNU_TIME = Path("/usr/bin/time")


def run_process(argv: Sequence[str], cwd: Path = ROOT) -> ProcessRun:
    """Run ``argv``; its wall time and its OWN peak memory (RuntimeError if it fails).

    Beware ``wait4``/``RUSAGE_CHILDREN``'s ``ru_maxrss`` for a child of a big process:
    Linux starts the child's maximum at the parent's resident size at fork and keeps it
    across exec, so a small command run from a driver holding 900 MB reports 900 MB.
    Here the command is started by ``/usr/bin/time`` (a small process), whose report of
    its own child is that child's alone; without it the peak is None. The wall time
    includes the launcher's start (about a millisecond).
    """
    with tempfile.TemporaryDirectory() as folder:
        report = Path(folder) / "peak"
        launcher: list[str] = []
        if _GNU_TIME.exists():
            launcher = [str(_GNU_TIME), "-f", "%M", "-o", str(report)]
        started = time.perf_counter()
        completed = subprocess.run(
            [*launcher, *argv], cwd=cwd, capture_output=True, text=True, check=False
        )
        elapsed = time.perf_counter() - started
        peak = None
        if launcher and report.exists():
            lines = report.read_text().split()
            peak = int(lines[-1]) * 1024 if lines and lines[-1].isdigit() else None
    if completed.returncode != 0:
        raise RuntimeError(
            f"{' '.join(argv)} exited {completed.returncode}: {completed.stderr.strip()[-500:]}"
        )
    return ProcessRun(elapsed, peak, completed.stdout, completed.stderr)


def venv_script(name: str) -> str:
    """The console script ``name`` beside this interpreter (``.venv/bin/ecdsim``)."""
    beside = Path(sys.executable).parent / name
    if beside.exists():
        return str(beside)
    found = shutil.which(name)
    if found is None:
        raise RuntimeError(f"the {name} console script is not installed (run: make demo)")
    return found


@dataclass(frozen=True)
class Timed(Generic[T]):
    """A result that carries its own time: return it to time only part of a call.

    E.g. a subprocess that measures its own work with ``time.perf_counter`` (excluding
    the interpreter start); ``measure`` then uses ``seconds`` and compares ``value``.
    """

    seconds: float
    value: T


@dataclass(frozen=True)
class Notes:
    """What a case reports beside its timings: lines for the console, data for the JSON."""

    lines: tuple[str, ...] = ()
    data: Mapping[str, Any] = field(default_factory=dict)
    ok: bool = True  # False fails the run (exit status 1), e.g. a heavy module imported


@dataclass(frozen=True)
class Case(Generic[T]):
    """One benchmark case: ecdsim against a baseline, timed in turn.

    ``name`` is the table's first column (keep it under about 24 characters); the other
    fields are described in the module docstring.
    """

    name: str
    ecdsim: Callable[[], T]
    baseline: Callable[[], T] | None = None
    baseline_name: str = ""
    agree: Callable[[T, T], Agreement] | None = None
    tolerance: float | None = None
    repeats: int = MIN_REPEATS
    warmup: int = 1
    # Calls per timed sample (``timeit``'s ``number``): a sample of a sub-millisecond call
    # is a block of ``number`` calls, its time divided by ``number``; the blocks alternate.
    number: int = 1
    items: int = 1
    baseline_items: int | None = None
    item_name: str = ""
    goal_s: float | None = None
    notes: Callable[[], Notes] | None = None
    description: str = ""


@dataclass
class Row:
    """The measured figures of one case (all times in seconds)."""

    name: str
    ecdsim_min_s: float = math.nan
    ecdsim_median_s: float = math.nan
    baseline_min_s: float | None = None
    baseline_median_s: float | None = None
    ratio_median: float | None = None
    ratio_min: float | None = None
    agreement: Agreement = None
    tolerance: float | None = None
    items: int = 1
    baseline_items: int = 1
    item_name: str = ""
    goal_s: float | None = None
    baseline_name: str = ""
    description: str = ""
    repeats: int = 0
    ecdsim_times_s: list[float] = field(default_factory=list)
    baseline_times_s: list[float] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    notes_ok: bool = True

    @property
    def agrees(self) -> bool:
        """False when the results disagree beyond the tolerance (or differ, for a bool)."""
        if isinstance(self.agreement, bool):
            return self.agreement
        if self.agreement is None or self.tolerance is None:
            return True
        return self.agreement <= self.tolerance

    @property
    def goal_met(self) -> bool | None:
        """Whether ecdsim's median is below ``goal_s``; None without a goal."""
        if self.goal_s is None:
            return None
        return self.ecdsim_median_s < self.goal_s

    @property
    def ok(self) -> bool:
        """No error, the results agree and the notes' checks passed (goals never fail)."""
        return self.error is None and self.agrees and self.notes_ok

    def to_json(self) -> dict[str, Any]:
        """JSON-ready form (NaN written as null)."""
        out: dict[str, Any] = {}
        for key, value in vars(self).items():
            out[key] = None if isinstance(value, float) and not math.isfinite(value) else value
        out["goal_met"] = self.goal_met
        out["ok"] = self.ok
        return out


def _timed(call: Callable[[], Any], number: int = 1) -> tuple[float, Any]:
    """Time ``number`` calls in a row with the garbage collector off, as ``timeit`` does;
    the time per call and the last call's result.

    No collection is forced right before the calls: a full collection walks every live
    object, and the call after it paid for that in cold caches (a one-deployment
    ``predict`` took 0.5-0.6 ms longer, LSODA 0.25 ms), a cost neither side has in a
    loop of calls. The collector runs again between samples, outside the timing.
    """
    enabled = gc.isenabled()
    gc.disable()
    result: Any = None
    try:
        start = time.perf_counter()
        for _ in range(number):
            result = call()
        elapsed = (time.perf_counter() - start) / number
    finally:
        if enabled:
            gc.enable()
    if isinstance(result, Timed):  # a self-timed call (number 1): its own figure
        return result.seconds, result.value
    return elapsed, result


def timed_once(call: Callable[[], Any]) -> float:
    """The time of one call of ``call`` [s], as :func:`measure` times a sample of one."""
    return _timed(call)[0]


def measure(case: Case[Any], repeats: int | None = None) -> Row:
    """Time ``case``: warm-up, then ecdsim and baseline in turn; never raises.

    The order alternates each round (A B, B A, ...) so that neither side always runs
    right after the other. Each sample is ``case.number`` calls in a row (one by
    default). An exception in the case is recorded in ``Row.error``.
    """
    count = max(MIN_REPEATS, repeats if repeats is not None else case.repeats)
    row = Row(
        name=case.name,
        tolerance=case.tolerance,
        items=case.items,
        baseline_items=case.baseline_items or case.items,
        item_name=case.item_name,
        goal_s=case.goal_s,
        baseline_name=case.baseline_name,
        description=case.description,
        repeats=count,
    )
    try:
        first: Any = None
        reference: Any = None
        for _ in range(case.warmup):
            _, first = _timed(case.ecdsim)
            if case.baseline is not None:
                _, reference = _timed(case.baseline)
        if case.warmup == 0:
            first = None
        if case.agree is not None and case.baseline is not None and case.warmup > 0:
            row.agreement = case.agree(first, reference)
        del first, reference
        for i in range(count):
            order = (case.ecdsim, case.baseline) if i % 2 == 0 else (case.baseline, case.ecdsim)
            for call in order:
                if call is None:
                    continue
                elapsed, _ = _timed(call, case.number)
                (row.ecdsim_times_s if call is case.ecdsim else row.baseline_times_s).append(
                    elapsed
                )
        row.ecdsim_min_s = min(row.ecdsim_times_s)
        row.ecdsim_median_s = statistics.median(row.ecdsim_times_s)
        if row.baseline_times_s:
            row.baseline_min_s = min(row.baseline_times_s)
            row.baseline_median_s = statistics.median(row.baseline_times_s)
            scale = row.items / row.baseline_items
            ratios = [
                b / a * scale for a, b in zip(row.ecdsim_times_s, row.baseline_times_s, strict=True)
            ]
            row.ratio_median = statistics.median(ratios)
            row.ratio_min = row.baseline_min_s / row.ecdsim_min_s * scale
        if case.notes is not None:
            notes = case.notes()
            row.notes.extend(notes.lines)
            row.data.update(notes.data)
            row.notes_ok = notes.ok
    except Exception as error:  # noqa: BLE001 - one failing case must not stop the others
        row.error = f"{type(error).__name__}: {error}"
    return row


# ---------------------------------------------------------------------------------------
# agreement helpers


def max_relative_difference(a: Any, b: Any) -> float:
    """Largest ``|a - b| / max(|a|, |b|)`` over two arrays (or scalars) of the same shape.

    Equal values (infinities included) count 0; a NaN against a number, or infinities that
    differ, count ``inf``.
    """
    import numpy as np

    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    if x.shape != y.shape:
        return math.inf
    if x.size == 0:
        return 0.0
    same = (x == y) | (np.isnan(x) & np.isnan(y))
    scale = np.maximum(np.abs(x), np.abs(y))
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = np.where(same, 0.0, np.abs(x - y) / scale)
    diff = np.where(np.isnan(diff), math.inf, diff)
    return float(np.max(diff))


def same(a: object, b: object) -> bool:
    """Agreement as identity of outputs (``a == b``)."""
    return bool(a == b)


# ---------------------------------------------------------------------------------------
# scratch folder shared by the cases of one run


_SCRATCH: list[Path] = []


def scratch() -> Path:
    """A temporary folder for this process's cases, removed when the process exits."""
    if not _SCRATCH:
        folder = Path(tempfile.mkdtemp(prefix="ecdsim-bench-"))
        _SCRATCH.append(folder)
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return _SCRATCH[0]


# ---------------------------------------------------------------------------------------
# the table


def format_seconds(low: float | None, middle: float | None) -> str:
    """``min/median`` in one unit chosen from the median: ``231/289 ms``, ``1.23/1.45 s``."""
    if low is None or middle is None or not math.isfinite(middle):
        return "-"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if middle >= scale or unit == "us":
            a, b = low / scale, middle / scale
            digits = 2 if b < 10 else 1 if b < 100 else 0
            return f"{a:.{digits}f}/{b:.{digits}f} {unit}"
    raise AssertionError("unreachable")


def format_ratio(ratio: float | None) -> str:
    """``942x``, ``2.3x``, ``0.06x``; ``-`` without a baseline."""
    if ratio is None or not math.isfinite(ratio):
        return "-"
    if ratio >= 100:
        return f"{ratio:,.0f}x"
    if ratio >= 10:
        return f"{ratio:.1f}x"
    if ratio >= 0.1:
        return f"{ratio:.2f}x"
    return f"{ratio:.3f}x"


def format_agreement(row: Row) -> str:
    """``same`` / ``DIFFERS``, ``0``, ``3e-16``; ``!`` marks one above the tolerance."""
    value = row.agreement
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "same" if value else "DIFFERS"
    text = "0" if value == 0 else f"{value:.0e}" if math.isfinite(value) else "inf"
    return text if row.agrees else f"{text} !"


COLUMNS = (("case", 26, "<"), ("ecdsim", 15, ">"), ("baseline", 15, ">"),
           ("ratio", 8, ">"), ("agreement", 10, ">"))  # fmt: skip


def table(rows: Sequence[Row]) -> list[str]:
    """The one table: case, ecdsim and baseline (min/median), ratio, agreement; 78 wide.

    A case name longer than its column wraps onto the next lines; goals, throughputs,
    notes and errors follow under the table, numbered by row.
    """
    header = " ".join(f"{title:{align}{width}}" for title, width, align in COLUMNS)
    lines = [header, "-" * len(header)]
    below: list[str] = []
    for number, row in enumerate(rows, start=1):
        label = f"{number}. {row.name}"
        wrapped = textwrap.wrap(label, COLUMNS[0][1], subsequent_indent="   ") or [label]
        if row.error is not None:
            cells = ["ERROR", "-", "-", "-"]
        else:
            cells = [
                format_seconds(row.ecdsim_min_s, row.ecdsim_median_s),
                format_seconds(row.baseline_min_s, row.baseline_median_s),
                format_ratio(row.ratio_median),
                format_agreement(row),
            ]
        values = " ".join(
            f"{cell:{align}{width}}"
            for cell, (_, width, align) in zip(cells, COLUMNS[1:], strict=True)
        )
        lines.append(f"{wrapped[0]:<{COLUMNS[0][1]}} {values}")
        lines.extend(wrapped[1:])
        for text in row_notes(row):
            below.extend(textwrap.wrap(f"{number}. {text}", 78, subsequent_indent="     "))
    if below:
        lines += ["", *below]
    return lines


def row_notes(row: Row) -> list[str]:
    """The lines printed under the table for one row."""
    out: list[str] = []
    if row.error is not None:
        return [f"ERROR {row.error}"]
    if row.baseline_name:
        out.append(f"baseline: {row.baseline_name}")
    if row.goal_s is not None:
        verdict = "MET" if row.goal_met else "NOT MET"
        out.append(f"goal: median < {row.goal_s:g} s: {verdict}")
    if row.item_name and math.isfinite(row.ecdsim_median_s):
        rate = row.items / row.ecdsim_median_s
        text = f"ecdsim {_rate(rate)} {row.item_name}/s"
        if row.baseline_median_s:
            text += f", baseline {_rate(row.baseline_items / row.baseline_median_s)}/s"
        out.append(text + " (medians)")
    if row.tolerance is not None and not isinstance(row.agreement, bool):
        out.append(f"agreement tolerance {row.tolerance:g}: {'OK' if row.agrees else 'FAILED'}")
    out.extend(row.notes)
    return out


def _rate(value: float) -> str:
    for suffix, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if value >= scale:
            return f"{value / scale:.2f} {suffix}"
    return f"{value:.1f}"


def run_alone(
    cases: Callable[[bool], Sequence[Case[Any]]],
    doc: str | None,
    argv: Sequence[str] | None = None,
    quick_help: str = "smaller sizes",
) -> int:
    """A bench file's own ``main``: run its cases alone and print their table.

    Options ``--quick`` (``quick_help``) and ``--repeats``; exit status 1 if an agreement
    fails, as ``run.py``'s.
    """
    parser = argparse.ArgumentParser(description=doc.splitlines()[0] if doc else None)
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--repeats", type=int, default=None, help="timed repeats per case")
    args = parser.parse_args(argv)
    rows = [measure(case, args.repeats) for case in cases(args.quick)]
    print("\n".join(table(rows)))
    return 0 if all(row.ok for row in rows) else 1

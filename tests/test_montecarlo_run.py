"""Running studies: resume after SIGKILL and Ctrl-C, worker-count invariance, Dask, the CLI.

"Identical" here means bit for bit: every chunk's table and the summary's JSON text.
The Dask tests use a LocalCluster of worker *threads* (processes=False) where they only
need to show that the scheduling does not change the numbers: a chunk is a pure function
of (plan, chunk index), whichever worker runs it, and threads start in a fraction of the
seconds that worker processes take. One CLI test runs real worker processes.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import logging
import os
import select
import shlex
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import load_config
from ecdsim.deployment import predict
from ecdsim.methods import SOLVERS
from ecdsim.montecarlo import (
    DaskExecutor,
    InProcess,
    RunError,
    build_plan,
    choose_executor,
    run,
)
from ecdsim.montecarlo import apply as apply_values
from ecdsim.montecarlo.run import (
    LARGE_RUN_SAMPLES,
    chunk_values,
    fork_available,
    output_column,
)
from ecdsim.montecarlo.store import MANIFEST, SUMMARY, ChunkReader, chunk_path, read_manifest
from tests import hand
from tests.conftest import ROOT, SavedFigures
from tests.test_montecarlo_config import PAPER_TEXT, write_config

runner = CliRunner()

QUANTITIES = "\n".join(
    [
        '"damper.damping_rate" = { distribution = "normal", three_sigma = "10 %" }',
        '"load.end_torque" = { distribution = "normal", sigma = "3 %" }',
        '"load.system_friction.at_0C" = { distribution = "uniform", plus_minus = "10 %" }',
    ]
)
SETTINGS = 'seed = 99\nsampling = "lhs"'
SAMPLES, CHUNK = 40_000, 200  # 200 chunks: a kill lands well inside the run
CHUNKS = SAMPLES // CHUNK


def study_args(config: Path, out: Path, *extra: str) -> list[str]:
    return [
        "montecarlo",
        str(config),
        "--samples",
        str(SAMPLES),
        "--chunk-size",
        str(CHUNK),
        "--out",
        str(out),
        "--no-plot",
        "--no-progress",
        *extra,
    ]


def chunk_files(out: Path) -> list[Path]:
    return sorted((out / "chunks").glob("chunk-*.parquet")) if (out / "chunks").is_dir() else []


def assert_identical_runs(first: Path, second: Path) -> None:
    names = [p.name for p in chunk_files(first)]
    assert names == [p.name for p in chunk_files(second)]
    for name in names:
        a = pq.read_table(first / "chunks" / name)
        b = pq.read_table(second / "chunks" / name)
        assert a.equals(b), name
    assert (first / SUMMARY).read_text() == (second / SUMMARY).read_text()


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A config and its uninterrupted reference run (in process)."""
    folder = tmp_path_factory.mktemp("study")
    config = write_config(folder, QUANTITIES, SETTINGS)
    out = folder / "reference"
    result = runner.invoke(app, study_args(config, out))
    assert result.exit_code == 0, result.output
    assert len(chunk_files(out)) == CHUNKS
    return config, out


# A guard against a hang, never a verdict: a run held at its gate waits for the test's
# signal, so nothing here depends on how fast the machine is; a test still waiting after
# this long has found a hang (a run that neither reaches its gate nor ends).
HANG_GUARD_S = 1800.0


@contextlib.contextmanager
def held_run(
    args: list[str], cwd: Path, chunks: int, *, group: bool = False
) -> Iterator[subprocess.Popen[str]]:
    """``ecdsim ARGS`` in a process whose Monte Carlo run holds after ``chunks`` chunks are
    on disk (tests/montecarlo_gate.py); yields once it holds there. On the way out the
    process is reaped and its pipe closed whatever happened (killed with its process
    group, ``group``, if it still runs), so that no test leaves an open pipe behind."""
    read_end, write_end = os.pipe()
    process = subprocess.Popen(
        [sys.executable, "-m", "tests.montecarlo_gate", str(write_end), str(chunks), *args],
        cwd=cwd,
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "src")])},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        pass_fds=(write_end,),
        start_new_session=group,  # its own process group, as under a terminal
        preexec_fn=as_under_a_terminal,
    )
    os.close(write_end)
    try:
        ready, _, _ = select.select([read_end], [], [], HANG_GUARD_S)
        if not ready:
            pytest.fail(f"the run neither held after {chunks} chunks nor ended in {HANG_GUARD_S} s")
        if os.read(read_end, 1) != b"!":  # the pipe closed: the run ended before its gate
            _, stderr = process.communicate()
            pytest.fail(f"the run ended before it could be interrupted: {stderr}")
        yield process
    finally:
        os.close(read_end)
        if process.poll() is None:
            if group:
                os.killpg(process.pid, signal.SIGKILL)
            else:
                process.kill()
        if process.stderr is not None and not process.stderr.closed:
            process.communicate()  # reaps it and closes its stderr pipe


def as_under_a_terminal() -> None:
    """In the study's process before it starts: Ctrl-C as a terminal delivers it.

    SIGINT is set to its default and unblocked: a test run started in the background
    (``make test &``, a CI runner) inherits SIGINT ignored, and the study would then
    finish as if never interrupted. Its workers (Dask) inherit it.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def test_resume_after_sigkill_is_identical_to_an_uninterrupted_run(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    config, reference = study
    out = tmp_path / "killed"
    with held_run(study_args(config, out), tmp_path, 3) as process:
        process.kill()
        process.communicate()
    assert process.returncode == -signal.SIGKILL
    on_disk = len(chunk_files(out))
    # Held after 3; the writer may have installed a chunk or two queued behind them.
    assert 3 <= on_disk < CHUNKS, "the kill must land in the middle of the run"
    assert read_manifest(out) is not None
    result = runner.invoke(app, study_args(config, out, "--resume"))
    assert result.exit_code == 0, result.output
    assert f"{CHUNKS - on_disk:,} chunk(s) computed, {on_disk:,} reused" in result.stderr
    samples = ChunkReader(out, CHUNKS).column("sample")
    np.testing.assert_array_equal(samples, np.arange(SAMPLES))  # none lost, none twice
    assert_identical_runs(reference, out)


def test_ctrl_c_stops_cleanly_and_prints_the_resume_command(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    config, reference = study
    out = tmp_path / "interrupted"
    with held_run(study_args(config, out), tmp_path, 2) as process:
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate()
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert "interrupted:" in stderr
    assert not list((out / "chunks").glob(".*.tmp"))  # the chunk being written was dropped
    assert read_manifest(out) is not None
    on_disk = len(chunk_files(out))
    assert 2 <= on_disk < CHUNKS
    assert f"{on_disk:,} of {CHUNKS:,} chunks are on disk" in stderr
    command = shlex.split(stderr.split("continue with:")[1].strip().splitlines()[0])
    assert command[:2] == ["ecdsim", "montecarlo"]
    assert command[-1] == "--resume"
    result = runner.invoke(app, [*command[1:], "--no-progress", "--no-plot"])
    assert result.exit_code == 0, result.output
    assert_identical_runs(reference, out)


def test_ctrl_c_in_a_terminal_stops_a_dask_run_cleanly(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    # A terminal's Ctrl-C reaches the whole process group, worker processes included.
    config, reference = study
    out = tmp_path / "dask"
    args = study_args(config, out, "--workers", "2")
    with held_run(args, tmp_path, 3, group=True) as process:
        os.killpg(process.pid, signal.SIGINT)
        _, stderr = process.communicate()
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr  # the workers leave Ctrl-C to the client
    assert "interrupted:" in stderr
    assert 3 <= len(chunk_files(out)) < CHUNKS
    # Resume in this process: the worker count is not part of the study's identity.
    result = runner.invoke(app, study_args(config, out, "--resume"))
    assert result.exit_code == 0, result.output
    assert_identical_runs(reference, out)


def test_resume_recomputes_a_damaged_chunk_and_drops_partial_files(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    config, reference = study
    out = tmp_path / "damaged"
    result = runner.invoke(app, study_args(config, out))
    assert result.exit_code == 0, result.output
    path = chunk_path(out, 7)
    path.write_bytes(path.read_bytes()[:100])  # a truncated file (not ecdsim's doing)
    chunk_path(out, 8).unlink()
    (out / "chunks" / ".chunk-000009.parquet.x1.tmp").write_bytes(b"partial")
    result = runner.invoke(app, study_args(config, out, "--resume"))
    assert result.exit_code == 0, result.output
    assert "2 chunk(s) computed" in result.stderr
    assert "removed 1 unfinished file(s)" in " ".join(result.stderr.split())
    assert_identical_runs(reference, out)


def test_an_existing_run_needs_resume_and_a_matching_command(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    config, reference = study
    result = runner.invoke(app, study_args(config, reference))
    assert result.exit_code == 2
    assert "already holds a Monte Carlo run; add --resume" in result.stderr
    result = runner.invoke(app, study_args(config, reference, "--resume", "--seed", "100"))
    assert result.exit_code == 2
    assert f"error: --resume: {reference / MANIFEST} has seed = 99, this run has 100" in (
        result.stderr
    )
    assert "Traceback" not in result.output


def run_with(executor: Any, config: Path, out: Path) -> ChunkReader:
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    run(plan, out, executor)
    return ChunkReader(out, plan.chunks)


def test_results_do_not_depend_on_the_worker_count(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    readers = {
        "in process": run_with(InProcess(), config, tmp_path / "a"),
        "2 threads": run_with(InProcess(threads=2), config, tmp_path / "t"),
        "3 threads": run_with(InProcess(threads=3), config, tmp_path / "u"),
        "1 worker": run_with(DaskExecutor(1, processes=False), config, tmp_path / "b"),
        "2 workers": run_with(DaskExecutor(2, processes=False, window=3), config, tmp_path / "c"),
    }
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    for name in plan.columns:
        reference = readers["in process"].column(name)
        for label, reader in readers.items():
            np.testing.assert_array_equal(reader.column(name), reference, err_msg=label)


def test_threaded_chunks_are_bit_identical_and_in_order(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    order = [5, 0, 11, 2, 7, 1]  # any order a resume may ask for
    sequential = list(InProcess().results(plan, order, tmp_path))
    threaded = list(InProcess(threads=2).results(plan, order, tmp_path))
    assert [r.index for r in threaded] == order
    for one, two in zip(sequential, threaded, strict=True):
        assert one.sensitivity_sums == two.sensitivity_sums
        assert one.warnings == two.warnings
        assert list(one.columns) == list(two.columns)
        for name, column in one.columns.items():
            np.testing.assert_array_equal(two.columns[name], column, err_msg=name)
    # Through run(), which writes each chunk on its own thread meanwhile: the same files.
    run(plan, tmp_path / "one", InProcess())
    run(plan, tmp_path / "two", InProcess(threads=2))
    names = [p.name for p in chunk_files(tmp_path / "one")]
    assert names == [p.name for p in chunk_files(tmp_path / "two")]
    assert len(names) == plan.chunks
    for name in names:
        one_table = pq.read_table(tmp_path / "one" / "chunks" / name)
        assert one_table.equals(pq.read_table(tmp_path / "two" / "chunks" / name)), name


def test_summary_on_threads_is_the_one_thread_summary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from ecdsim.montecarlo import stats

    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    run(plan, tmp_path / "out", InProcess())
    summaries = []
    for threads in (1, 2):
        monkeypatch.setattr(stats, "SUMMARY_THREADS", threads)
        summaries.append(json.dumps(stats.summarize(plan, tmp_path / "out")))
    assert summaries[0] == summaries[1]


def test_in_process_uses_at_most_two_threads() -> None:
    threads = choose_executor(10, 0, None)
    assert isinstance(threads, InProcess)
    assert threads.threads == min(2, os.cpu_count() or 1)
    assert "2 threads" in InProcess(threads=2).describe()


def test_cli_workers_and_scheduler_give_the_in_process_numbers(tmp_path: Path) -> None:
    import distributed  # a test dependency (the montecarlo extra): never skipped

    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    args = ["--samples", "2000", "--chunk-size", "500", "--no-plot", "--json"]
    base = runner.invoke(app, ["montecarlo", str(config), "--out", str(tmp_path / "a"), *args])
    assert base.exit_code == 0, base.output
    # Real worker processes, as a user gets them from --workers.
    workers = runner.invoke(
        app,
        ["montecarlo", str(config), "--out", str(tmp_path / "b"), "--workers", "2", *args],
    )
    assert workers.exit_code == 0, workers.output
    assert "dask LocalCluster, 2 worker processes" in " ".join(workers.stderr.split())
    with distributed.LocalCluster(  # type: ignore[no-untyped-call]
        n_workers=1, processes=False, threads_per_worker=1, dashboard_address=":0"
    ) as cluster:
        remote = runner.invoke(
            app,
            [
                "montecarlo",
                str(config),
                "--out",
                str(tmp_path / "c"),
                "--scheduler",
                cluster.scheduler_address,
                *args,
            ],
        )
    assert remote.exit_code == 0, remote.output
    assert json.loads(base.stdout) == json.loads(workers.stdout) == json.loads(remote.stdout)
    assert_identical_runs(tmp_path / "a", tmp_path / "b")
    assert_identical_runs(tmp_path / "a", tmp_path / "c")


def test_an_unreachable_scheduler_is_a_clear_error_and_leaves_no_run(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 100)
    executor = DaskExecutor(address="tcp://127.0.0.1:1", connect_timeout="1s")
    with pytest.raises(RunError, match="--scheduler: cannot connect to 'tcp://127.0.0.1:1'"):
        run(plan, tmp_path / "out", executor)
    assert not (tmp_path / "out" / MANIFEST).exists()  # the same command can be repeated


def test_executor_choice(monkeypatch: pytest.MonkeyPatch) -> None:
    assert isinstance(choose_executor(10, None, None), InProcess)
    assert isinstance(choose_executor(10**8, 0, None), InProcess)
    assert choose_executor(10, 3, None) == DaskExecutor(workers=3)
    assert choose_executor(10, None, "tcp://h:8786") == DaskExecutor(address="tcp://h:8786")
    monkeypatch.setattr(os, "cpu_count", lambda: 4)
    assert choose_executor(LARGE_RUN_SAMPLES, None, None) == DaskExecutor(workers=4)
    assert isinstance(choose_executor(LARGE_RUN_SAMPLES - 1, None, None), InProcess)
    # Issue 6: the cluster is the default for large runs on a multi-core machine, unless
    # the in-process path already forks one worker per CPU (Linux, 2 CPUs): no scheduler
    # and client then share the CPUs with the workers.
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    expected = InProcess(threads=2, fork=True) if fork_available() else DaskExecutor(workers=2)
    assert choose_executor(LARGE_RUN_SAMPLES, None, None) == expected
    run_module = importlib.import_module("ecdsim.montecarlo.run")  # the package's run is a function
    monkeypatch.setattr(run_module, "fork_available", lambda: False)
    assert choose_executor(LARGE_RUN_SAMPLES, None, None) == DaskExecutor(workers=2)
    monkeypatch.setattr(run_module, "fork_available", lambda: True)
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    assert isinstance(choose_executor(LARGE_RUN_SAMPLES, None, None), InProcess)
    monkeypatch.setattr(os, "cpu_count", lambda: 3)
    assert choose_executor(LARGE_RUN_SAMPLES, None, None) == DaskExecutor(workers=3)
    with pytest.raises(RunError, match="either --workers or --scheduler"):
        choose_executor(10, 2, "tcp://h:8786")
    # Issue 23: at most one worker per CPU, and 4 on any machine (each is a process).
    assert choose_executor(10, 4, None) == DaskExecutor(workers=4)
    for workers in (-1, 5, 100_000):
        message = rf"--workers {workers}: expected 0 .* to 4: .*\(3 here\)"
        with pytest.raises(RunError, match=message):
            choose_executor(10, workers, None)
    monkeypatch.setattr(os, "cpu_count", lambda: 8)
    assert choose_executor(10, 8, None) == DaskExecutor(workers=8)
    with pytest.raises(RunError, match="--workers 9: expected 0 .* to 8"):
        choose_executor(10, 9, None)


def test_cli_both_workers_and_scheduler_exit_2(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    result = runner.invoke(
        app,
        ["montecarlo", str(config), "-n", "10", "--workers", "2", "--scheduler", "tcp://h:1"],
    )
    assert result.exit_code == 2
    assert result.stderr.strip() == "error: give either --workers or --scheduler, not both"


def hand_times(out: Path, temperature: float) -> np.ndarray:
    """Each sample's exact deployment time for the QUANTITIES study, independently.

    The sampled inputs read back with pyarrow; Eq. 1-4 and the exact solution
    t = (B/k) ln(a / (a - k L)) typed here (tests/hand.py), not ecdsim's solver.
    """
    table = pa.concat_tables([pq.read_table(path) for path in chunk_files(out)])
    bd = table.column("damper.damping_rate").to_numpy()
    te = table.column("load.end_torque").to_numpy()
    fs_0c = table.column("load.system_friction.at_0C").to_numpy()
    # BECD is proportional to BD (BG = 0.26 BD); FS_T = -0.0044 T + at_0C.
    damping = hand.becd(temperature) * bd / hand.BD
    net_start = hand.TS - hand.fecd(temperature) - (-0.0044 * temperature + fs_0c)
    k = (hand.TS - te) / hand.TRAVEL
    times: np.ndarray = damping / k * np.log(net_start / (net_start - k * hand.TRAVEL))
    return times


def test_progress_bar_only_on_a_terminal(tmp_path: Path) -> None:
    """...only on a terminal (rich takes FORCE_COLOR as one), unless --no-progress."""
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    args = ["montecarlo", str(config), "-n", "500", "--no-plot", "-T", "25", "--overwrite"]
    shown = runner.invoke(app, [*args, "--out", str(tmp_path / "a")], env={"FORCE_COLOR": "1"})
    assert shown.exit_code == 0, shown.output
    assert "samples/s" in shown.stderr
    assert "ETA" in shown.stderr
    off = [*args, "--out", str(tmp_path / "b"), "--no-progress"]
    hidden = runner.invoke(app, off, env={"FORCE_COLOR": "1"})
    assert hidden.exit_code == 0, hidden.output
    assert "samples/s" not in hidden.stderr


def test_plot_takes_a_folder_and_refuses_the_old_switch(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    args = ["montecarlo", str(config), "-n", "500", "-T", "25", "--out", str(tmp_path / "run")]
    result = runner.invoke(app, [*args, "--plot", str(tmp_path / "figures")])
    assert result.exit_code == 0, result.output
    for name in ("time_histogram", "time_cdf", "end_speed_histogram", "tornado"):
        assert (tmp_path / "figures" / f"{name}.png").read_bytes()[:4] == b"\x89PNG"
    assert not (tmp_path / "run" / "plots").exists()
    # Before issue 26 --plot was a switch: a bare one would take the next option as DIR.
    old = runner.invoke(app, [*args, "--plot", "--overwrite"])
    assert old.exit_code == 2
    assert "--plot --overwrite: --plot takes a folder now" in old.stderr


def test_cli_json_summary_progress_and_plots(tmp_path: Path, saved_figures: SavedFigures) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    out = tmp_path / "out"
    result = runner.invoke(
        app,
        [
            "montecarlo",
            str(config),
            "-n",
            "3000",
            "--chunk-size",
            "1000",
            "--out",
            str(out),
            "--json",
            "-T",
            "25",
        ],
    )
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    # The printed summary is the stored one plus the display unit system it was shown in.
    assert document.pop("display_units") == "si"
    assert document == json.loads((out / SUMMARY).read_text())
    assert document["samples"] == 3000
    assert document["seed"] == 99
    assert [c["temperature_C"] for c in document["cases"]] == [25.0]
    case = document["cases"][0]
    assert set(case["deployment_time_s"]["percentiles"]) == {"P1", "P5", "P50", "P95", "P99"}
    assert {"end_speed_rad_s", "stall", "sensitivity", "repeatability"} <= set(case)
    keys = {"damper.damping_rate", "load.end_torque", "load.system_friction.at_0C"}
    assert {r["key"] for r in case["sensitivity"]["inputs"]} == keys
    # The progress bar redraws itself: never into a pipe or a log (issue 26 item 8)...
    assert "samples/s" not in result.stderr
    assert "ETA" not in result.stderr
    for name in ("time_histogram", "time_cdf", "end_speed_histogram", "tornado"):
        assert (out / "plots" / f"{name}.png").read_bytes()[:4] == b"\x89PNG"
    system = "CDA Cc-16 test deployment (paper section 6)"
    time_title = f"{system}\ndeployment time, 3,000 samples, exact method"
    speed_title = (
        f"{system}\nend (latch) speed of the samples that arrive, 3,000 samples, exact method"
    )
    for name, title, quantity in (
        ("time_histogram.png", time_title, "deployment time [s]"),
        ("time_cdf.png", time_title, "deployment time [s]"),
        ("end_speed_histogram.png", speed_title, "end (latch) speed [rad/s]"),
    ):
        (axes,) = saved_figures.axes(name)
        assert (axes.get_title(), axes.get_xlabel()) == (title, quantity)
        assert saved_figures.legend(axes) == ["25 degC"]  # no stall: no stall share shown
    (cdf,) = saved_figures.axes("time_cdf.png")
    assert cdf.get_ylabel() == "cumulative probability [-]"
    # A density's unit is the inverse of its quantity's.
    (histogram,) = saved_figures.axes("time_histogram.png")
    assert histogram.get_ylabel() == "probability density [1/s]"
    (speeds,) = saved_figures.axes("end_speed_histogram.png")
    assert speeds.get_ylabel() == "probability density [s/rad]"
    # The empirical CDF: level (r + 1)/n at the r-th smallest time, times by hand.
    step = cdf.get_lines()[0]
    levels = np.asarray(step.get_ydata(), float)
    ranks = np.rint(levels * 3000).astype(int) - 1
    ordered = np.sort(hand_times(out, 25.0))[ranks]
    np.testing.assert_allclose(np.asarray(step.get_xdata(), float), ordered, rtol=1e-12)
    assert levels[-1] == 1.0
    (tornado,) = saved_figures.axes("tornado.png")
    assert tornado.get_xlabel() == "standardised regression coefficient of deployment time [-]"
    assert tornado.get_title().endswith("sensitivity of deployment time (exact method)")
    from matplotlib.patches import Rectangle

    rectangles = [patch for patch in tornado.patches if isinstance(patch, Rectangle)]
    bars = {
        label.get_text(): patch.get_width()
        for label, patch in zip(tornado.get_yticklabels(), rectangles, strict=True)
    }
    # Signs by the physics of Eq. 1-11: more damping or more friction is slower, a
    # stronger spring end torque is faster.
    assert set(bars) == keys
    assert bars["damper.damping_rate"] > 0.0
    assert bars["load.system_friction.at_0C"] > 0.0
    assert bars["load.end_torque"] < 0.0


def test_cli_table_output(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["montecarlo", str(config), "-n", "2000", "--out", str(out), "--no-plot", "--wide"]
    )  # --wide: every percentile column (at 80 columns P5 and P95 are hidden)
    assert result.exit_code == 0, result.output
    # Independent of ecdsim's solver and statistics: the sampled inputs read back with
    # pyarrow, each sample's time from the paper's Eq. 1-4 and the exact solution typed
    # here, and the percentiles as order statistics by numpy ("inverted_cdf": the
    # ceil(p n)-th smallest, the definition in docs/montecarlo.md).
    rows = {}
    for line in result.stdout.split("End (latch) speed")[0].splitlines():
        cells = [c.strip() for c in line.split("│")[1:-1]]
        if len(cells) == 10 and cells[0] in {"-40", "25", "100"}:
            rows[float(cells[0])] = cells
    assert sorted(rows) == [-40.0, 25.0, 100.0]
    for t, cells in rows.items():
        times = hand_times(out, t)
        assert times.size == 2000
        assert np.all(np.isfinite(times))  # no sample stalls: the P50 column is a number
        percentiles = np.percentile(times, [1, 5, 50, 95, 99], method="inverted_cdf")
        # Columns: T, nominal, P1, P5, P50, P95, P99, mean, std (4 significant digits,
        # trailing zeros kept so that the columns align: 40.20 for 40.2).
        assert float(cells[1]) == float(f"{hand.exact_time(t):.4g}")
        assert [float(c) for c in cells[2:7]] == [float(f"{v:.4g}") for v in percentiles]
        assert float(cells[7]) == float(f"{np.mean(times):.4g}")
    for title in ("Deployment time [s]", "End (latch) speed", "Sensitivity", "Repeatability"):
        assert title in result.stdout


def test_dynamic_method(tmp_path: Path) -> None:
    # The Monte Carlo must reproduce, sample for sample, what predict() gives for the same
    # parameters with the dynamic method, including a tolerance on a parameter only the
    # dynamic method has (the load's inertia). The method is registered (issue 3): a
    # fallback for its absence would let this test pass on a build that lost it.
    assert "dynamic" in SOLVERS
    base = PAPER_TEXT.replace('travel = "1.57 rad"', 'travel = "1.57 rad"\ninertia = "5 kg*m^2"')
    assert base != PAPER_TEXT
    quantities = QUANTITIES + '\n"load.inertia" = { distribution = "uniform", plus_minus = "20 %" }'
    config = write_config(tmp_path, quantities, SETTINGS, base=base)
    out = tmp_path / "out"
    args = ["montecarlo", str(config), "-n", "64", "--chunk-size", "32", "--out", str(out)]
    result = runner.invoke(app, [*args, "--method", "dynamic", "--no-plot", "--no-progress"])
    assert result.exit_code == 0, result.output
    plan = build_plan(load_config(config), 64, "dynamic", chunk_size=32)
    reader = ChunkReader(out, plan.chunks)
    assert "load.inertia" in plan.tolerances.keys
    for index in (0, 1):
        values = chunk_values(plan, index)
        for row in (0, 31):
            one = {key: values[row : row + 1, j] for j, key in enumerate(plan.tolerances.keys)}
            varied = apply_values.apply(plan.parameters, one)
            solution = predict(
                varied.system, list(plan.temperatures), ["dynamic"], dynamics=varied.dynamics
            ).solutions["dynamic"]
            for i, temperature in enumerate(plan.temperatures):
                column = reader.floats(output_column("deployment_time_s", temperature))
                expected = float(np.ravel(solution.deployment_time)[i])
                # Batch and single solves of the same equations: 1e-6 relative covers an
                # integrator whose steps depend on the batch (issue 3's agreement goal).
                assert column[index * 32 + row] == pytest.approx(expected, rel=1e-6)


def test_a_drawn_seed_is_recorded_and_reused_by_resume(tmp_path: Path) -> None:
    config = write_config(tmp_path, QUANTITIES, 'sampling = "random"')  # no seed
    out = tmp_path / "out"
    args = ["montecarlo", str(config), "-n", "600", "--chunk-size", "200", "--out", str(out)]
    first = runner.invoke(app, [*args, "--resume", "--no-plot"])  # nothing to resume yet
    assert first.exit_code == 0, first.output
    said = " ".join(first.stderr.split())  # notes and the header wrap at the width
    assert f"note: nothing to resume in {out}: starting a new run" in said
    manifest = read_manifest(out)
    assert manifest is not None
    seed = manifest["identity"]["seed"]
    assert f"seed {seed}," in said
    assert json.loads((out / SUMMARY).read_text())["seed"] == seed
    chunk_path(out, 1).unlink()
    again = runner.invoke(app, [*args, "--resume", "--no-plot"])
    assert again.exit_code == 0, again.output
    assert "1 chunk(s) computed, 2 reused" in again.stderr  # the same seed: chunks match


def test_samples_read_back_as_a_dataframe(study: tuple[Path, Path]) -> None:
    _, reference = study
    reader = ChunkReader(reference, CHUNKS)
    frame = reader.to_pandas(["sample", "load.end_torque", "deployment_time_s@25.0C"])
    assert list(frame.columns) == ["sample", "load.end_torque", "deployment_time_s@25.0C"]
    assert len(frame) == SAMPLES
    np.testing.assert_array_equal(frame["sample"].to_numpy(), np.arange(SAMPLES))
    np.testing.assert_array_equal(
        frame["deployment_time_s@25.0C"].to_numpy(), reader.floats("deployment_time_s@25.0C")
    )


@pytest.mark.parametrize(
    "column",
    [
        np.linspace(-1.0, 2.0, 13),
        np.arange(1_000, 1_011, dtype=np.int64),
        np.array([True, False, True, True, False, False, True, True, True, False, True]),
        np.arange(40.0).reshape(8, 5)[:, 2],  # a strided view, as a column of a 2-D block
        np.array([], dtype=float),
    ],
)
def test_chunk_columns_become_the_arrow_arrays_pa_array_builds(column: np.ndarray) -> None:
    from ecdsim.montecarlo.store import _arrow_array

    built = _arrow_array(pa, column)
    assert built.equals(pa.array(column))  # pyarrow's own conversion is the reference
    assert built.to_pylist() == column.tolist()


def test_queued_writes_stop_at_a_failed_one(
    study: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Chunks are computed ahead of a slow write (queued behind it); when a write fails,
    the writes queued behind it are not made: exactly the chunks before it are on disk."""
    import errno
    import importlib
    import threading

    # The module (the package's ``run`` attribute is the function of that name).
    run_module = importlib.import_module("ecdsim.montecarlo.run")

    plan = build_plan(load_config(study[0]), 3_000, chunk_size=256)
    ahead = threading.Event()
    original_write, original_evaluate = run_module.write_result, run_module.evaluate_chunk

    def evaluate(plan: Any, index: int) -> Any:
        if index == 4:
            ahead.set()  # chunk 4 computed while chunk 1's write is still under way
        return original_evaluate(plan, index)

    def write(plan: Any, out: Path, result: Any) -> Path:
        if result.index == 1:
            # a guard against a hang only: the event comes as soon as chunk 4 is computed
            ahead.wait(timeout=HANG_GUARD_S)
        if result.index == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written: Path = original_write(plan, out, result)
        return written

    monkeypatch.setattr(run_module, "evaluate_chunk", evaluate)
    monkeypatch.setattr(run_module, "write_result", write)
    out = tmp_path / "run"
    with pytest.raises(OSError, match="No space left"):
        run(plan, out, InProcess(threads=1))
    assert ahead.is_set()
    assert [p.name for p in chunk_files(out)] == ["chunk-000000.parquet", "chunk-000001.parquet"]


def test_forked_workers_write_the_same_files_and_summary(tmp_path: Path) -> None:
    """InProcess(fork=True): the chunks after the first in forked processes, which stage
    their files for this process to install and fill the summary's columns in shared
    memory; the files, the kept columns and the summary are those of one thread."""
    import importlib

    from ecdsim.montecarlo import stats, store

    run_module = importlib.import_module("ecdsim.montecarlo.run")
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    assert plan.chunks - 1 >= run_module.FORK_MIN_CHUNKS  # the forked path is taken
    run(plan, tmp_path / "one", InProcess())
    one = json.dumps(stats.summarize(plan, tmp_path / "one"))
    report = run(plan, tmp_path / "forked", InProcess(threads=2, fork=True))
    assert "2 forked workers" in report.executor
    assert report.chunks_computed == plan.chunks
    assert not list((tmp_path / "forked" / "chunks").glob(".*.tmp"))
    names = [p.name for p in chunk_files(tmp_path / "one")]
    assert names == [p.name for p in chunk_files(tmp_path / "forked")]
    for name in names:
        a = pq.read_table(tmp_path / "one" / "chunks" / name)
        assert a.equals(pq.read_table(tmp_path / "forked" / "chunks" / name)), name
    # Every chunk's summary columns were kept (the first by this process, the others by
    # the workers in shared memory): the same values as the files hold.
    kept = store.take_kept(tmp_path / "forked", plan.identity_sha256)
    assert kept is not None
    columns, filled = kept
    assert filled == set(range(plan.chunks))
    reader = ChunkReader(tmp_path / "forked", plan.chunks)
    for name in plan.summary_columns:
        np.testing.assert_array_equal(columns[name], reader.column(name), err_msg=name)
    # Kept again as the run left them: the summary from them, and then (forgotten) from
    # the files, are both the one-thread summary.
    store.start_keeping(tmp_path / "forked", plan.identity_sha256, plan.samples)
    for k in range(plan.chunks):
        start, stop = plan.bounds(k)
        part = {name: values[start:stop] for name, values in columns.items()}
        store.keep(tmp_path / "forked", plan.identity_sha256, k, start, part)
    assert json.dumps(stats.summarize(plan, tmp_path / "forked")) == one
    assert json.dumps(stats.summarize(plan, tmp_path / "forked")) == one  # from the files


def test_forked_workers_stop_at_a_failed_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A staged file that cannot be installed (ENOSPC) stops the line as in process: the
    chunks before it are on disk, none after it, and no staged file is left behind."""
    import errno

    from ecdsim.montecarlo import store

    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    original = store.install_chunk

    def install(out: Path, index: int, temporary: Path) -> Path:
        if index == 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        installed: Path = original(out, index, temporary)
        return installed

    monkeypatch.setattr(store, "install_chunk", install)
    out = tmp_path / "run"
    with pytest.raises(OSError, match="No space left"):
        run(plan, out, InProcess(threads=2, fork=True))
    assert [p.name for p in chunk_files(out)] == [f"chunk-00000{k}.parquet" for k in range(3)]
    assert not list((out / "chunks").glob(".*.tmp"))


def test_a_forked_workers_error_reaches_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An exception in a forked worker is raised by run() (the same type and message);
    the files on disk are whole chunks from the first on, and none is left staged."""
    import importlib

    run_module = importlib.import_module("ecdsim.montecarlo.run")
    original = run_module.evaluate_chunk

    def evaluate(plan: Any, index: int) -> Any:
        if index == 5:
            raise ValueError("chunk 5 cannot be evaluated")
        return original(plan, index)

    monkeypatch.setattr(run_module, "evaluate_chunk", evaluate)  # inherited by the fork
    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    out = tmp_path / "run"
    with pytest.raises(ValueError, match="chunk 5 cannot be evaluated"):
        run(plan, out, InProcess(threads=2, fork=True))
    names = [p.name for p in chunk_files(out)]
    assert names == [f"chunk-00000{k}.parquet" for k in range(len(names))]
    assert len(names) <= 5
    assert not list((out / "chunks").glob(".*.tmp"))


def test_an_interrupted_forked_run_resumes_to_the_same_files(tmp_path: Path) -> None:
    """Ctrl-C in the parent (here from its progress callback) stops a forked run: the
    chunks under way finish, nothing staged is left, and a resume completes the study
    with the files an uninterrupted run writes."""
    from ecdsim.montecarlo import RunInterrupted

    config = write_config(tmp_path, QUANTITIES, SETTINGS)
    plan = build_plan(load_config(config), 3_000, chunk_size=256)
    run(plan, tmp_path / "reference", InProcess())

    def progress(done: int, total: int) -> None:
        if done >= 4 * 256:
            raise KeyboardInterrupt

    out = tmp_path / "interrupted"
    with pytest.raises(RunInterrupted) as stopped:
        run(plan, out, InProcess(threads=2, fork=True), progress=progress)
    assert 4 <= stopped.value.chunks_done < plan.chunks
    assert not list((out / "chunks").glob(".*.tmp"))
    report = run(plan, out, InProcess(threads=2, fork=True), resume=True)
    assert report.chunks_reused == stopped.value.chunks_done
    names = [p.name for p in chunk_files(tmp_path / "reference")]
    assert names == [p.name for p in chunk_files(out)]
    for name in names:
        a = pq.read_table(tmp_path / "reference" / "chunks" / name)
        assert a.equals(pq.read_table(out / "chunks" / name)), name


def _name_error_from(filename: str, function: str) -> BaseException:
    """A NameError raised in ``function`` of a module whose file is ``filename``."""
    namespace: dict[str, Any] = {}
    source = f"def {function}():\n    return undefined_name\n"
    exec(compile(source, filename, "exec"), namespace)  # noqa: S102 - a fixed test snippet
    try:
        namespace[function]()
    except NameError as error:
        return error
    raise AssertionError("no NameError")


def test_distributeds_cancel_race_on_ctrl_c_is_not_reported(
    caplog: pytest.LogCaptureFixture,
) -> None:
    # distributed's sync() reads an unassigned `future` in its `cancel` callback when
    # Ctrl-C comes early, and tornado logged that NameError with a traceback under the
    # run's clean "interrupted" message (seen in test_ctrl_c_in_a_terminal_stops_a_dask_
    # run_cleanly). Only that record is dropped: the same error from elsewhere is shown.
    run_module = importlib.import_module("ecdsim.montecarlo.run")
    run_module.quiet_cancel_race()
    run_module.quiet_cancel_race()  # once only
    logger = logging.getLogger("tornado.application")
    assert logger.filters.count(run_module._CANCEL_RACE_FILTER) == 1
    race = _name_error_from(str(Path("site-packages", "distributed", "utils.py")), "cancel")
    other = _name_error_from(str(Path("site-packages", "mine", "utils.py")), "cancel")
    elsewhere = _name_error_from(str(Path("site-packages", "distributed", "utils.py")), "f")
    with caplog.at_level(logging.ERROR, logger="tornado.application"):
        for error in (race, other, elsewhere):
            logger.error(
                "Exception in callback", exc_info=(type(error), error, error.__traceback__)
            )
    shown = [record.exc_info[1] for record in caplog.records if record.exc_info]
    assert shown == [other, elsewhere]

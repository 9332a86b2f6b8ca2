"""A full disk and Ctrl-C while `report` and `montecarlo` write (issue 12, item 9).

Both are simulated in process at the one place every output goes through,
:func:`ecdsim.atomic.write_with`: the writer puts a few bytes into the temporary file and
then raises ``OSError(ENOSPC)`` (a full disk) or ``KeyboardInterrupt`` (Ctrl-C), as a real
write would mid-file. What must hold: one clear error line and exit code 2 (130 for
Ctrl-C), the earlier result byte for byte, no temporary file left, and a Monte Carlo run
that ``--resume`` finishes identical to an uninterrupted one. Ctrl-C by a real SIGINT
during a Monte Carlo run is tested in tests/test_montecarlo_run.py.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path
from typing import IO

import pytest
from typer.testing import CliRunner, Result

from ecdsim import atomic
from ecdsim.cli.app import app
from ecdsim.montecarlo.store import SUMMARY
from tests.conftest import PAPER_CONFIG
from tests.test_montecarlo_config import write_config
from tests.test_montecarlo_run import assert_identical_runs, chunk_files

runner = CliRunner()
FULL = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
QUANTITIES = '"damper.damping_rate" = { distribution = "normal", three_sigma = "10 %" }'
SAMPLES, CHUNK = 40, 10  # four chunks


def fail_writes(
    monkeypatch: pytest.MonkeyPatch, error: BaseException, when: Callable[[Path], bool]
) -> list[Path]:
    """Make every atomic write to a target for which ``when`` holds fail after a few bytes."""
    original = atomic.write_with
    failed: list[Path] = []

    def write_with(target: str | Path, writer: Callable[[IO[bytes]], object]) -> Path:
        if not when(Path(target)):
            return original(target, writer)

        def partial(stream: IO[bytes]) -> None:
            stream.write(b"half a file")
            failed.append(Path(target))
            raise error

        return original(target, partial)

    monkeypatch.setattr(atomic, "write_with", write_with)
    return failed


def no_temporary_files(folder: Path) -> bool:
    return not list(folder.rglob(".*.tmp"))


def assert_one_error_line(result: Result, code: int, *expected: str) -> None:
    assert result.exit_code == code, result.output
    assert not isinstance(result.exception, Exception), result.exception
    assert "Traceback" not in result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, result.output
    for text in expected:
        assert text in errors[0], result.output


# --- report -----------------------------------------------------------------------------


def test_report_on_a_full_disk_keeps_the_earlier_report(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    output = tmp_path / "report.html"
    good = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(output)])
    assert good.exit_code == 0, good.output
    before = output.read_bytes()
    failed = fail_writes(monkeypatch, FULL, lambda target: True)
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(output), "-T", "0"])
    assert failed == [output]
    assert_one_error_line(result, 2, f"--output {output}", "No space left on device")
    assert output.read_bytes() == before
    assert no_temporary_files(tmp_path)


def test_ctrl_c_while_the_report_is_written_keeps_the_earlier_report(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    output = tmp_path / "report.html"
    good = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(output)])
    assert good.exit_code == 0, good.output
    before = output.read_bytes()
    fail_writes(monkeypatch, KeyboardInterrupt(), lambda target: True)
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(output), "-T", "0"])
    assert result.exit_code == 130, result.output
    assert "Traceback" not in result.output
    assert f"interrupted: {output} not written (an earlier file there is unchanged)" in (
        result.output
    )
    assert output.read_bytes() == before
    assert no_temporary_files(tmp_path)


# --- montecarlo -------------------------------------------------------------------------


def _study(config: Path, out: Path, *extra: str) -> list[str]:
    return [
        "montecarlo", str(config), "--samples", str(SAMPLES), "--chunk-size", str(CHUNK),
        "--out", str(out), "--no-plot", "--no-progress", "--workers", "0", *extra,
    ]  # fmt: skip


@pytest.fixture
def config(tmp_path: Path) -> Path:
    return write_config(tmp_path, QUANTITIES, "seed = 7")


@pytest.fixture
def reference(config: Path, tmp_path: Path) -> Path:
    out = tmp_path / "reference"
    result = runner.invoke(app, _study(config, out))
    assert result.exit_code == 0, result.output
    return out


def test_montecarlo_disk_full_at_a_chunk_stops_with_one_line_and_resumes(
    config: Path, reference: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "run"
    failed = fail_writes(monkeypatch, FULL, lambda target: target.name == "chunk-000002.parquet")
    result = runner.invoke(app, _study(config, out))
    assert [p.name for p in failed] == ["chunk-000002.parquet"]
    assert_one_error_line(result, 2, f"--out {out}", "No space left on device")
    # The chunks before the full disk are kept, the failed one is not half there.
    assert [p.name for p in chunk_files(out)] == ["chunk-000000.parquet", "chunk-000001.parquet"]
    assert no_temporary_files(out)
    monkeypatch.undo()  # space freed
    resumed = runner.invoke(app, _study(config, out, "--resume"))
    assert resumed.exit_code == 0, resumed.output
    assert "2 chunk(s) computed, 2 reused" in resumed.output
    assert_identical_runs(reference, out)


def test_montecarlo_disk_full_at_the_summary_keeps_the_earlier_summary(
    config: Path, reference: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    before = (reference / SUMMARY).read_bytes()
    failed = fail_writes(monkeypatch, FULL, lambda target: target.name == SUMMARY)
    result = runner.invoke(app, _study(config, reference, "--resume"))
    assert failed == [reference / SUMMARY]
    assert_one_error_line(result, 2, f"--out {reference}", "No space left on device")
    assert (reference / SUMMARY).read_bytes() == before
    assert no_temporary_files(reference)


def test_montecarlo_ctrl_c_at_a_chunk_write_resumes_identically(
    config: Path, reference: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "run"
    fail_writes(
        monkeypatch, KeyboardInterrupt(), lambda target: target.name == "chunk-000001.parquet"
    )
    result = runner.invoke(app, _study(config, out))
    assert result.exit_code == 130, result.output
    assert "Traceback" not in result.output
    assert "interrupted: 1 of 4 chunks are on disk" in result.output
    assert no_temporary_files(out)
    monkeypatch.undo()
    resumed = runner.invoke(app, _study(config, out, "--resume"))
    assert resumed.exit_code == 0, resumed.output
    assert_identical_runs(reference, out)


# --- what is at the output path (issue 23, item 5) ---------------------------------------

SWEEP = [
    "sweep", str(PAPER_CONFIG), "--vary", "gearbox.ratio=300:400:3", "-m", "exact", "-T", "25",
]  # fmt: skip


def _sweep_to(target: Path | str) -> Result:
    return runner.invoke(app, [*SWEEP, "-o", str(target)])


@pytest.fixture
def expected_csv(tmp_path: Path) -> bytes:
    """The table the sweep writes into a plain new file (what every other target must get)."""
    plain = tmp_path / "plain.csv"
    result = _sweep_to(plain)
    assert result.exit_code == 0, result.output
    return plain.read_bytes()


def test_a_symlink_is_written_through_to_its_target(tmp_path: Path, expected_csv: bytes) -> None:
    # The temporary file was renamed over the link: the link became a file and its target
    # kept the old content.
    target = tmp_path / "results" / "real.csv"
    target.parent.mkdir()
    target.write_text("an earlier result\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    result = _sweep_to(link)
    assert result.exit_code == 0, result.output
    assert link.is_symlink()
    assert link.readlink() == target
    assert target.read_bytes() == expected_csv
    assert no_temporary_files(tmp_path)
    # A dangling link is written where it points (as the shell's > does).
    dangling = tmp_path / "dangling.csv"
    dangling.symlink_to(tmp_path / "results" / "new.csv")
    assert _sweep_to(dangling).exit_code == 0
    assert dangling.is_symlink()
    assert (tmp_path / "results" / "new.csv").read_bytes() == expected_csv


def test_a_fifo_is_written_directly_and_stays_a_fifo(tmp_path: Path, expected_csv: bytes) -> None:
    import stat
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()  # a FIFO's writer waits for a reader, as with the shell's >
    result = _sweep_to(fifo)
    reader.join(60.0)
    assert result.exit_code == 0, result.output
    assert received == [expected_csv]
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert no_temporary_files(tmp_path)


def _full_device(tmp_path: Path) -> Path:
    """A node of /dev/full (character device 1, 7): its own node where this process may
    create one (root), so that a regression replaces the copy, not the system's device;
    else /dev/full itself, which a non-root process cannot replace."""
    import stat

    if os.geteuid() == 0:
        node = tmp_path / "full"
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
        return node
    return Path("/dev/full")


def test_a_full_device_fails_in_one_line_and_stays_a_device(tmp_path: Path) -> None:
    import stat

    # Run as root, -o /dev/full exited 0 and turned the device into a 3 kB regular file.
    device = _full_device(tmp_path)
    result = _sweep_to(device)
    assert_one_error_line(
        result, 2, f"error: --out {device}: cannot write (No space left on device)"
    )
    assert stat.S_ISCHR(device.stat().st_mode)
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(device)])
    assert_one_error_line(result, 2, f"error: --output {device}: cannot write (No space left")
    assert stat.S_ISCHR(device.stat().st_mode)


def test_a_folder_or_a_socket_is_refused_in_one_line(tmp_path: Path) -> None:
    import socket

    folder = tmp_path / "folder"
    folder.mkdir()
    result = _sweep_to(folder)
    assert_one_error_line(
        result,
        2,
        f"error: --out {folder}: cannot write (it is a folder, not a file; ecdsim writes "
        "files, FIFOs and character devices)",
    )
    path = tmp_path / "socket"
    with socket.socket(socket.AF_UNIX) as server:
        server.bind(str(path))
        result = _sweep_to(path)
    assert_one_error_line(result, 2, f"error: --out {path}: cannot write (it is a socket,")
    assert not list(tmp_path.glob(".*.tmp"))


def test_a_block_device_is_never_written() -> None:
    import stat

    # A block device is a disk: refused before anything is written (no device is needed
    # to test the rule: the mode decides).
    assert atomic._what(stat.S_IFBLK | 0o660) == "block device"
    assert atomic._what(stat.S_IFCHR | 0o666) in atomic.STREAMS
    assert atomic._what(stat.S_IFIFO | 0o644) in atomic.STREAMS
    assert atomic._what(stat.S_IFREG | 0o644) is None


def test_a_missing_folder_is_created_and_said(tmp_path: Path, expected_csv: bytes) -> None:
    # -o /nonexistent/dir/s.csv created the folders silently.
    target = tmp_path / "new" / "deeper" / "s.csv"
    result = _sweep_to(target)
    assert result.exit_code == 0, result.output
    assert target.read_bytes() == expected_csv
    notes = [line for line in result.stderr.splitlines() if line.startswith("note:")]
    assert notes == [f"note: created the folder {target.parent} (it did not exist)"]
    assert "note:" not in _sweep_to(target).stderr  # there now: nothing to say
    # A file where a folder should be is one line, not a traceback.
    result = _sweep_to(target / "s.csv")
    assert_one_error_line(result, 2, f"error: --out {target / 's.csv'}: cannot write")


def test_stdout_redirected_to_a_file_gets_the_table_then_the_messages(tmp_path: Path) -> None:
    import subprocess
    import sys

    # -o /dev/stdout with stdout redirected to a file: /dev/stdout is a link to this
    # process's descriptor 1; renaming over the file it names, or opening it anew
    # (truncated, written from the start), would lose what the process prints around it.
    captured = tmp_path / "captured.txt"
    with captured.open("wb") as stdout:
        done = subprocess.run(
            [sys.executable, "-m", "ecdsim", *SWEEP, "-o", "/dev/stdout"],
            stdout=stdout,
            stderr=subprocess.PIPE,
            check=False,
        )
    assert done.returncode == 0, done.stderr
    plain = tmp_path / "plain.csv"
    assert _sweep_to(plain).exit_code == 0
    assert captured.read_bytes() == plain.read_bytes() + b"wrote /dev/stdout (3 points, 3 rows)\n"


def test_a_failed_montecarlo_leaves_no_folder(tmp_path: Path) -> None:
    # The dynamic method needs [load] inertia: the run fails at its first chunk, and left
    # empty out/ and out/chunks/ folders although nothing was written.
    config = write_config(tmp_path, QUANTITIES)
    out = tmp_path / "new" / "run"
    result = runner.invoke(app, _study(config, out, "--method", "dynamic"))
    assert_one_error_line(result, 2, "load.inertia: missing")
    assert not (tmp_path / "new").exists()
    # An existing folder stays, with what the user had in it.
    out.mkdir(parents=True)
    (out / "notes.txt").write_text("mine")
    result = runner.invoke(app, _study(config, out, "--method", "dynamic"))
    assert result.exit_code == 2
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_a_montecarlo_folder_is_said_once_the_run_stands_and_a_reports_is_not(
    tmp_path: Path,
) -> None:
    config = write_config(tmp_path, QUANTITIES, "seed = 7")
    out = tmp_path / "new" / "run"
    result = runner.invoke(app, _study(config, out))
    assert result.exit_code == 0, result.output
    notes = [line for line in result.output.splitlines() if line.startswith("note: created")]
    assert notes == [f"note: created the folder {out} (it did not exist)"]
    # A report's Monte Carlo study runs in a temporary folder of its own: nothing to say.
    report = runner.invoke(app, ["report", str(config), "-o", str(tmp_path / "r.html")])
    assert report.exit_code == 0, report.output
    assert "note: created" not in report.output

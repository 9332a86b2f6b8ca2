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

"""A Monte Carlo study too large for this machine is refused before it starts (issue 23).

``ecdsim montecarlo ... --samples 100000000000`` used to start ("1,525,879 chunk(s) ...")
and end with "--out ...: cannot write (Cannot allocate memory)": the summary's whole
columns (exact percentiles need every sample) were refused by the system. The estimate
(ecdsim.montecarlo.budget) is checked here against a hand count of the bytes per sample
and per chunk, and against the files a run writes.
"""

from __future__ import annotations

import errno
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import load_config
from ecdsim.montecarlo import RunError, budget, build_plan, store
from ecdsim.montecarlo.run import CHUNKS_IN_FLIGHT
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "paper_cc16_tolerances.toml"
runner = CliRunner()


def test_the_estimate_is_the_hand_count_of_bytes() -> None:
    # The example: d = 8 toleranced quantities, 3 temperatures, no [requirements] (no
    # margin column), chunks of 65,536.
    plan = build_plan(load_config(EXAMPLE), 200_000, seed=1)
    assert (plan.tolerances.dimension, len(plan.temperatures), plan.chunks) == (8, 3, 4)
    assert CHUNKS_IN_FLIGHT == 6  # 2 chunks computed at once, 4 waiting to be written
    needs = budget.estimate(plan, CHUNKS_IN_FLIGHT)
    # Memory per sample: time and speed (float64, 8 bytes each) and the stall flag (1)
    # at 3 temperatures held whole, and a float and a flag for each of the 2
    # temperatures summarised at once: 3 * 17 + 2 * 9 = 69.
    assert needs.memory_per_sample == 3 * (8 + 8 + 1) + 2 * (8 + 1) == 69
    # Disk per sample: the sample index, 8 values, 2 floats at 3 temperatures (8 bytes
    # each, plain), 3 stall flags packed to bits: 8 * 15 + 3 / 8 = 120.375.
    assert needs.disk_per_sample == 8 * (1 + 8 + 3 * 2) + 3 / 8 == 120.375
    # A chunk's tag: the sensitivity sums, 3 + 2*8 + 8^2 + 2*8*58 = 1,011 float64 per
    # temperature (58 bins: the cube root of 200,000, rounded), as base64: 3 * 1,011 * 8
    # = 24,264 bytes -> 32,352 characters; the moments, 12 per temperature: 288 bytes
    # -> 384; and 1,024 for the rest.
    tag = 32_352 + 384 + 1_024
    assert budget.tag_bytes(8, 3, 200_000) == tag
    assert needs.memory_per_chunk == tag + budget.TAG_OBJECTS
    # On disk the tag is there twice, the second time inside the Arrow schema, base64
    # again (45,016 characters).
    assert needs.disk_per_chunk == tag + 45_016 + budget.FILE_FIXED
    # In flight: 2 chunks computed and 4 waiting to be written, each 65,536 * 120.375
    # bytes (7,888,896).
    in_flight = 6 * 7_888_896
    assert needs.memory_bytes == 200_000 * 69 + 4 * needs.memory_per_chunk + in_flight
    assert needs.disk_bytes == math.ceil(200_000 * 120.375) + 4 * needs.disk_per_chunk


def test_the_disk_estimate_is_the_size_of_the_files_a_run_writes(tmp_path: Path) -> None:
    out = tmp_path / "run"
    arguments = ["montecarlo", str(EXAMPLE), "--samples", "20000", "--chunk-size", "4096"]
    result = runner.invoke(app, [*arguments, "--out", str(out), "--no-plot", "--seed", "3"])
    assert result.exit_code == 0, result.output
    written = sum(path.stat().st_size for path in (out / store.CHUNKS).glob("*.parquet"))
    plan = build_plan(load_config(EXAMPLE), 20_000, seed=3, chunk_size=4096)
    # The per-chunk constants were measured at another chunk size and bin count, and
    # rounded (module budget): 2 % covers them; a wrong count of columns or of the tag's
    # copies would be off by far more (a float column is 8 % of these files, the tag 60 %).
    assert budget.estimate(plan, CHUNKS_IN_FLIGHT).disk_bytes == pytest.approx(written, rel=0.02)


def test_an_absurd_sample_count_is_refused_before_anything_starts(tmp_path: Path) -> None:
    out = tmp_path / "absurd"
    result = runner.invoke(
        app, ["montecarlo", str(EXAMPLE), "--samples", "100000000000", "--out", str(out)]
    )
    assert result.exit_code == 2, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    # Memory: 1e11 samples of 69 bytes, 6.9 TB, more than any machine this runs on.
    memory = next(line for line in errors if "of memory" in line)
    assert memory.startswith("error: --samples 100000000000: the study needs about 6.9")
    assert "69 bytes per sample" in memory
    assert "available here" in memory
    assert "samples fit" in memory
    assert "chunk(s)" not in result.output  # no run started
    assert not out.exists()  # nor a folder made


def test_the_limits_decide_and_a_normal_plan_passes(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    config = load_config(EXAMPLE)
    build_plan(config, 100_000, seed=1, out=tmp_path / "fits")  # this machine's limits
    # 1,000,000 samples need 69 MB and 120 MB (and the chunks in flight, 47 MB): refused
    # with 100 MB of memory and 50 MB of disk, and the samples that fit said.
    monkeypatch.setattr(budget, "available_memory", lambda: (100_000_000, "a test's limit"))
    monkeypatch.setattr(budget, "free_disk", lambda out: (50_000_000, tmp_path))
    with pytest.raises(RunError) as info:
        build_plan(config, 1_000_000, seed=1, out=tmp_path / "big")
    memory, disk = info.value.problems
    assert memory.startswith("--samples 1000000: the study needs about ")
    assert "more than the 100 MB available here (a test's limit)" in memory
    assert disk.startswith("--samples 1000000: the chunk files need about ")
    assert f"more than the 50 MB free at {tmp_path}" in disk
    # The samples that fit: 50e6 / (120.375 + disk per chunk / 65,536) on disk, a chunk
    # file holding its tag (64 bins at 1,000,000 samples) twice, once as base64.
    tag = budget.tag_bytes(8, 3, 1_000_000)
    per_chunk = tag + 4 * math.ceil(tag / 3) + budget.FILE_FIXED
    assert f"at most about {int(50e6 / (120.375 + per_chunk / 65_536)):,} samples" in disk
    build_plan(config, 100_000, seed=1, out=tmp_path / "small")  # within both: accepted


def test_out_of_memory_is_not_called_a_write_error(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    def refused(*_: object) -> None:
        raise OSError(errno.ENOMEM, "Cannot allocate memory")

    monkeypatch.setattr(store, "start_keeping", refused)
    out = tmp_path / "run"
    result = runner.invoke(
        app, ["montecarlo", str(EXAMPLE), "--samples", "1000", "--out", str(out), "--no-plot"]
    )
    assert result.exit_code == 2, result.output
    assert f"error: --out {out}: out of memory (Cannot allocate memory)" in result.output
    assert "cannot write" not in result.output

"""What a Monte Carlo study needs in memory and on disk, checked before it starts.

A study of N samples in chunks of c holds, until its summary is written:

* in memory, every sample's outputs at every temperature (the summary's percentiles are
  exact order statistics over all N samples, docs/montecarlo.md: they cannot be
  streamed): the deployment time and end speed (float64, 8 bytes each), the stall flag
  (1 byte) and, with ``[requirements]``, the torque margin (8 bytes), in
  :func:`ecdsim.montecarlo.store.keep` or read back from the chunk files; while up to
  ``SUMMARY_THREADS`` temperatures are summarised at once, each needs one more float
  and one flag per sample (the speeds of the samples that arrive, the finite filter);
* in memory, each chunk's metadata tag (:func:`ecdsim.montecarlo.store.chunk_tag`),
  read for the summary: the sensitivity sums, ``3 + 2d + d^2 + 2 d M`` float64 per
  temperature for d toleranced quantities and M bins, as base64 (4/3 of the bytes),
  and the merged moments, 12 float64 per temperature;
* in memory, the chunks under way: up to ``IN_PROCESS_THREADS`` computed and
  ``WRITE_QUEUE`` waiting to be written, each with its columns;
* on disk, one Parquet file per chunk: plain float64 columns (8 bytes per value: the
  sample index, the d sampled values, each float output at each temperature), the
  stall flags packed to bits, and the tag twice (as key-value metadata and inside the
  Arrow schema, base64 again) besides a fixed part.

The two per-chunk constants below were measured on ``examples/paper_cc16_tolerances.toml``
(d = 8, 3 temperatures, 65,536 samples per chunk); tests/test_montecarlo_budget.py holds
the disk estimate to the files a run writes (within 0.4 %). The memory per sample came
out at 69 bytes for that example against 60 measured (peak resident memory from 1,000,000
to 5,000,000 samples, in process, no stalls: the copies counted for stalled samples were
not made). The solver's own temporaries for a chunk under way are left out.
"""

from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from ecdsim.montecarlo.columns import SUMMARY_THREADS, bin_count


class _Tolerances(Protocol):
    @property
    def dimension(self) -> int: ...


class _Study(Protocol):
    """What the estimate reads of a :class:`ecdsim.montecarlo.run.Plan` (a protocol, so
    that this module imports nothing of the run, which calls it)."""

    @property
    def samples(self) -> int: ...
    @property
    def chunk_size(self) -> int: ...
    @property
    def chunks(self) -> int: ...
    @property
    def temperatures(self) -> tuple[float, ...]: ...
    @property
    def outputs(self) -> tuple[str, ...]: ...
    @property
    def tolerances(self) -> _Tolerances: ...


FLOAT = 8  # bytes of a float64 (and of the int64 sample index)
FLAG = 1  # bytes of a NumPy bool in memory
# A chunk's tag besides its sums and moments (identity, hashes, version, column units),
# as JSON text: 748 bytes measured, rounded up.
TAG_FIXED = 1_024
# The tag as a Python dict in memory beyond its JSON text, with the run's own record of
# the chunk (its index in lists, the kept chunks): 4,241 bytes measured, rounded up.
TAG_OBJECTS = 4_608
# A chunk file's bytes besides its columns and its tag's two copies (Arrow schema,
# Parquet footer, page headers): 6,100 bytes measured at 21 columns, rounded down.
FILE_FIXED = 6_000


@dataclass(frozen=True)
class Needs:
    """A study's estimated needs.

    Attributes
    ----------
    memory_bytes : memory the run and its summary hold at their peak [bytes]
    memory_per_sample : of which, per sample [bytes]
    memory_per_chunk : of which, per chunk [bytes]
    memory_in_flight : of which, the chunks under way [bytes]
    disk_bytes : the chunk files' total size [bytes]
    disk_per_sample : of which, per sample [bytes]
    disk_per_chunk : of which, per chunk file [bytes]
    """

    memory_bytes: int
    memory_per_sample: float
    memory_per_chunk: int
    memory_in_flight: int
    disk_bytes: int
    disk_per_sample: float
    disk_per_chunk: int


def _base64(raw: int) -> int:
    """Length of the base64 text of ``raw`` bytes."""
    return 4 * math.ceil(raw / 3)


def tag_bytes(dimension: int, temperatures: int, samples: int) -> int:
    """A chunk tag's JSON text: the sensitivity sums and moments (base64) and the rest."""
    bins = bin_count(samples)
    sums = temperatures * (3 + 2 * dimension + dimension**2 + 2 * dimension * bins)
    moments = temperatures * 12
    return _base64(FLOAT * sums) + _base64(FLOAT * moments) + TAG_FIXED


def estimate(plan: _Study, chunks_in_flight: int) -> Needs:
    """The memory and disk the plan needs (module docstring), with up to
    ``chunks_in_flight`` chunks in memory at once (computed or waiting to be written)."""
    temperatures = len(plan.temperatures)
    d = plan.tolerances.dimension
    floats = len(plan.outputs) - 1  # every output but the stall flag is a float
    held = temperatures * (floats * FLOAT + FLAG)
    working = min(SUMMARY_THREADS, temperatures) * (FLOAT + FLAG)
    memory_per_sample = held + working
    file_per_sample = FLOAT * (1 + d + temperatures * floats) + temperatures / 8
    tag = tag_bytes(d, temperatures, plan.samples)
    in_flight = chunks_in_flight * math.ceil(plan.chunk_size * file_per_sample)
    memory_per_chunk = tag + TAG_OBJECTS
    disk_per_chunk = tag + _base64(tag) + FILE_FIXED
    return Needs(
        memory_bytes=math.ceil(plan.samples * memory_per_sample)
        + plan.chunks * memory_per_chunk
        + in_flight,
        memory_per_sample=memory_per_sample,
        memory_per_chunk=memory_per_chunk,
        memory_in_flight=in_flight,
        disk_bytes=math.ceil(plan.samples * file_per_sample) + plan.chunks * disk_per_chunk,
        disk_per_sample=file_per_sample,
        disk_per_chunk=disk_per_chunk,
    )


def available_memory() -> tuple[int, str] | None:
    """Memory available to a new process [bytes] and where that figure comes from.

    /proc/meminfo's MemAvailable (Linux: free memory and what the kernel can reclaim),
    else the free physical pages (os.sysconf); None where neither is known.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as lines:
            for line in lines:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024, "MemAvailable in /proc/meminfo"
    except (OSError, ValueError, IndexError):
        pass
    try:
        pages = os.sysconf("SC_AVPHYS_PAGES")
        size = os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None
    if pages <= 0 or size <= 0:
        return None
    return pages * size, "free physical memory"


def free_disk(out: Path) -> tuple[int, Path] | None:
    """Free bytes on the file system that will hold ``out``, and the folder asked: the
    nearest folder of ``out`` and its parents that exists; None if none can be asked."""
    for folder in (Path(out).absolute(), *Path(out).absolute().parents):
        if folder.is_dir():
            try:
                return shutil.disk_usage(folder).free, folder
            except OSError:
                return None
    return None


def existing_chunks_bytes(out: Path) -> int:
    """The size of the chunk files already in ``out`` (a resumed run keeps the valid ones)."""
    from ecdsim.montecarlo.store import CHUNKS

    folder = Path(out) / CHUNKS
    if not folder.is_dir():
        return 0
    total = 0
    for path in folder.glob("chunk-*.parquet"):
        try:
            total += path.stat().st_size
        except OSError:
            continue
    return total


def size_text(count: float) -> str:
    """A byte count for a person: ``"5.1 TB"``, ``"820 MB"`` (SI prefixes, 3 digits).

    >>> size_text(5.1e12), size_text(820e6), size_text(999)
    ('5.1 TB', '820 MB', '999 bytes')
    """
    for power, prefix in ((5, "P"), (4, "T"), (3, "G"), (2, "M"), (1, "k")):
        scale = 1000.0**power
        if count >= scale:
            return f"{count / scale:.3g} {prefix}B"
    return f"{count:.0f} bytes"


def problems(
    plan: _Study, chunks_in_flight: int, out: Path | None, resume: bool = False
) -> list[str]:
    """One line for each of memory and disk the plan needs more of than this machine
    has (empty if it fits, or where the machine does not say); ``chunks_in_flight`` as
    for :func:`estimate`."""
    needs = estimate(plan, chunks_in_flight)
    found: list[str] = []
    start = f"--samples {plan.samples}"
    memory = available_memory()
    if memory is not None and needs.memory_bytes > memory[0]:
        limit, source = memory
        per_sample = needs.memory_per_sample + needs.memory_per_chunk / plan.chunk_size
        most = max(0, int((limit - needs.memory_in_flight) / per_sample))
        found.append(
            f"{start}: the study needs about {size_text(needs.memory_bytes)} of memory (its "
            f"summary holds {needs.memory_per_sample:g} bytes per sample for the exact "
            f"percentiles and {size_text(needs.memory_per_chunk)} per chunk), more than the "
            f"{size_text(limit)} available here ({source}); at most about {most:,} samples fit"
        )
    if out is not None:
        disk = free_disk(out)
        need = needs.disk_bytes - (existing_chunks_bytes(out) if resume else 0)
        if disk is not None and need > disk[0]:
            free, folder = disk
            per_sample = needs.disk_per_sample + needs.disk_per_chunk / plan.chunk_size
            most = max(0, int(free / per_sample))
            found.append(
                f"{start}: the chunk files need about {size_text(need)} of disk "
                f"({needs.disk_per_sample:g} bytes per sample and "
                f"{size_text(needs.disk_per_chunk)} per chunk file), more than the "
                f"{size_text(free)} free at {folder} (for --out {out}); at most about "
                f"{most:,} samples fit"
            )
    return found

"""A study's folder: its manifest, one Parquet file per chunk, and the summary.

Layout (docs/montecarlo.md)::

    OUT/manifest.json                  the study's identity, written once, atomically
    OUT/chunks/chunk-000000.parquet    samples 0 .. c-1, written atomically when computed
    OUT/chunks/chunk-000001.parquet    ...
    OUT/summary.json                   the statistics, written at the end
    OUT/plots/*.png

Every chunk file carries, in its Parquet key-value metadata, the hash of the study's
identity and its own index, so that a resumed run accepts only chunks of the same study.
pyarrow is imported lazily: it is an optional dependency (the ``montecarlo`` extra).
"""

from __future__ import annotations

import hashlib
import json
import mmap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from ecdsim import atomic
from ecdsim._types import FloatArray

MANIFEST = "manifest.json"
SUMMARY = "summary.json"
CHUNKS = "chunks"
FORMAT = "ecdsim-montecarlo/1"
METADATA_KEY = b"ecdsim.montecarlo"


class MissingDependency(RuntimeError):
    """An optional package the Monte Carlo needs is not installed; the message says how."""


def require(module: str) -> Any:
    """Import an optional module, or raise MissingDependency naming the extra to install."""
    import importlib

    from ecdsim.invocation import install_hint

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependency(
            f"the Monte Carlo needs {module.split('.')[0]}, which is not installed; "
            f"{install_hint('montecarlo')}"
        ) from None


def identity_hash(identity: Mapping[str, Any]) -> str:
    """SHA-256 of the study identity's canonical JSON."""
    text = json.dumps(identity, sort_keys=True, allow_nan=False, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def chunk_path(out: Path, index: int) -> Path:
    """Where chunk ``index`` lives."""
    return out / CHUNKS / f"chunk-{index:06d}.parquet"


def read_manifest(out: Path) -> dict[str, Any] | None:
    """The manifest of the study in ``out``, or None if there is none."""
    path = out / MANIFEST
    if not path.exists():
        return None
    try:
        document: Any = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as exc:
        raise ValueError(f"{path}: not a readable manifest ({exc})") from None
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise ValueError(f"{path}: not an ecdsim Monte Carlo manifest (format {FORMAT})")
    return document


def write_manifest(out: Path, identity: Mapping[str, Any], extra: Mapping[str, Any]) -> Path:
    """Write the manifest atomically: the identity, its hash, and descriptive extras."""
    document = {
        "format": FORMAT,
        "identity": dict(identity),
        "identity_sha256": identity_hash(identity),
        **extra,
    }
    text = json.dumps(document, indent=2, sort_keys=True, allow_nan=False) + "\n"
    return atomic.write_text(out / MANIFEST, text)


def column_units(columns: Sequence[str], tolerances: Any) -> dict[str, str]:
    """The SI unit of each chunk column that has one ("1" for a dimensionless number):
    a sampled quantity's from its tolerance, a result's from its name's suffix
    (``deployment_time_s@-40.0C``: s; ecdsim.tidy). ``stalled`` and ``sample`` have none.
    """
    from ecdsim.tidy import unit_of

    given = {t.key: t.unit for t in getattr(tolerances, "tolerances", ())}
    units = {}
    for name in columns:
        if name in given:
            units[name] = given[name] or "1"
        elif name != "sample":
            prefix = name.split("@", 1)[0]
            unit = unit_of(prefix)
            if unit is not None:
                units[name] = unit
            elif prefix == "min_torque_margin":
                units[name] = "1"
    return units


def remove_partial_files(out: Path) -> list[Path]:
    """Delete temporary files a killed run left behind (atomic writes never finished)."""
    stale = sorted((out / CHUNKS).glob(".chunk-*.tmp")) if (out / CHUNKS).is_dir() else []
    stale += sorted(p for name in (MANIFEST, SUMMARY) for p in out.glob(f".{name}.*.tmp"))
    for path in stale:
        path.unlink(missing_ok=True)
    return stale


def write_chunk(
    out: Path,
    index: int,
    columns: Mapping[str, np.ndarray[Any, Any]],
    identity_sha256: str,
    extra: Mapping[str, Any],
) -> Path:
    """Write one chunk's columns as Parquet, atomically, tagged with the study's identity."""
    table = _chunk_table(index, columns, identity_sha256, extra)

    def write(stream: IO[bytes]) -> None:
        # pyarrow writes the temporary file itself, by its path (its own file, no Python
        # in between), page by page; write_with then fsyncs the file through ``stream``
        # (the same inode) and renames it. Building the file in an Arrow buffer and
        # writing that in one call cost 3 to 4 times the system time (11 to 12 ms against
        # 2.6 to 3.5 ms per 65,536-sample chunk, measured alternately).
        _write_table(table, stream.name)

    return atomic.write_with(chunk_path(out, index), write)


def _chunk_table(
    index: int,
    columns: Mapping[str, np.ndarray[Any, Any]],
    identity_sha256: str,
    extra: Mapping[str, Any],
) -> Any:
    """The chunk's Arrow table, its metadata tagged with the study's identity."""
    pa = require("pyarrow")
    arrays = [_arrow_array(pa, values) for values in columns.values()]
    # Declared non-nullable (no column holds a null): Parquet then writes no definition
    # levels, which halved the encoding of a 65,536-sample chunk (10.3 to 4.9 ms of CPU);
    # the values read back are the same.
    fields = zip(columns, arrays, strict=True)
    units = extra.get("units", {})
    schema = pa.schema(
        [
            pa.field(
                name,
                array.type,
                nullable=False,
                metadata={b"unit": units[name].encode()} if name in units else None,
            )
            for name, array in fields
        ]
    )
    table = pa.Table.from_arrays(arrays, schema=schema)
    tag = json.dumps(
        {"identity_sha256": identity_sha256, "chunk": index, **extra},
        sort_keys=True,
        allow_nan=False,
    )
    return table.replace_schema_metadata({METADATA_KEY: tag.encode("utf-8")})


def _write_table(table: Any, path: str) -> None:
    """Write a chunk's table as Parquet to ``path`` (pyarrow opens the file itself)."""
    pa = require("pyarrow")
    pq = require("pyarrow.parquet")
    # Sampled floats do not repeat and do not compress: dictionary encoding cost 4x the
    # write time, snappy 1.5x and per-page min/max statistics 2.5x, for files 3 % smaller
    # at best.
    with pa.OSFile(path, "wb") as sink:
        pq.write_table(
            table, sink, use_dictionary=False, compression="none", write_statistics=False
        )


def stage_chunk(
    out: Path,
    index: int,
    columns: Mapping[str, np.ndarray[Any, Any]],
    identity_sha256: str,
    extra: Mapping[str, Any],
) -> Path:
    """Write chunk ``index``'s Parquet file under a temporary name beside its final one
    (``.chunk-NNNNNN.parquet.*.tmp``, as ecdsim.atomic names them, which
    :func:`remove_partial_files` sweeps up), not yet synced; :func:`install_chunk` syncs
    and renames it. :func:`write_chunk` in two halves, the same file and the same steps
    as ecdsim.atomic.write_with, so that a forked worker (ecdsim.montecarlo.run) encodes
    the file while the parent's writer line syncs and installs the files in chunk order.
    """
    table = _chunk_table(index, columns, identity_sha256, extra)
    temporary = atomic.stage(chunk_path(out, index))
    try:
        _write_table(table, str(temporary))
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return temporary


def install_chunk(out: Path, index: int, temporary: Path) -> Path:
    """Sync a staged chunk file (:func:`stage_chunk`) and rename it to its final name:
    the chunk appears whole or not at all. The temporary file is removed on failure."""
    return atomic.install(temporary, chunk_path(out, index))


def _arrow_array(pa: Any, values: np.ndarray[Any, Any]) -> Any:
    """An Arrow array over a NumPy column, built from its buffer.

    ``pa.array`` first asks whether the column is a pandas object, which imports pandas
    (0.2 to 0.3 s) into a run that never uses it; float64, int64 and bool columns (all a
    chunk holds) are wrapped directly (bool packed to Arrow's bits), the same arrays.
    """
    column = np.ascontiguousarray(values)
    if column.ndim != 1 or column.dtype.kind not in "fib":
        return pa.array(column)
    if column.dtype == np.bool_:
        bits = np.packbits(column, bitorder="little")
        return pa.Array.from_buffers(pa.bool_(), column.size, [None, pa.py_buffer(bits)])
    native = column.astype(column.dtype.newbyteorder("="), copy=False)
    kind = pa.from_numpy_dtype(native.dtype)
    return pa.Array.from_buffers(kind, native.size, [None, pa.py_buffer(native)])


def chunk_tag(path: Path) -> dict[str, Any] | None:
    """The identity tag of a chunk file, or None if the file is absent or unreadable."""
    pq = require("pyarrow.parquet")
    if not path.exists():
        return None
    try:
        metadata = pq.read_metadata(path)
        raw = (metadata.metadata or {}).get(METADATA_KEY)
        if raw is None:
            return None
        tag: dict[str, Any] = json.loads(raw.decode("utf-8"))
        tag["_rows"] = metadata.num_rows
        tag["_columns"] = list(metadata.schema.to_arrow_schema().names)
    except Exception:  # noqa: BLE001 - any unreadable file is simply not a valid chunk
        return None
    return tag


def chunk_is_valid(
    out: Path, index: int, identity_sha256: str, rows: int, columns: Sequence[str]
) -> bool:
    """True if chunk ``index`` exists, is readable, and belongs to this study."""
    tag = chunk_tag(chunk_path(out, index))
    return bool(
        tag is not None
        and tag.get("identity_sha256") == identity_sha256
        and tag.get("chunk") == index
        and tag["_rows"] == rows
        and tag["_columns"] == list(columns)
    )


@dataclass
class _Kept:
    """The summary's whole columns of one study, filled as this process writes its chunks."""

    out: Path
    identity_sha256: str
    samples: int
    columns: dict[str, np.ndarray[Any, Any]]
    filled: dict[int, int]  # chunk index -> its first sample


_KEPT: list[_Kept] = []  # at most one study's: the latest run in this process


def start_keeping(out: Path, identity_sha256: str, samples: int) -> None:
    """Drop what an earlier run kept; keep this study's columns from now on."""
    _KEPT.clear()
    _KEPT.append(_Kept(Path(out).resolve(), identity_sha256, samples, {}, {}))


def _kept_for(out: Path, identity_sha256: str) -> _Kept | None:
    found = _KEPT[0] if _KEPT else None
    if found and found.out == Path(out).resolve() and found.identity_sha256 == identity_sha256:
        return found
    return None


def keep(
    out: Path, identity_sha256: str, index: int, start: int, columns: Mapping[str, Any]
) -> None:
    """Copy the summary's columns of chunk ``index`` (first sample ``start``), just written
    by this process, into the study's whole columns.

    So that the summary of an in-process run need not read them back from the files
    (the values are the same: Parquet stores float64 and bool exactly). The whole columns
    are allocated once, so that they are never held twice.
    """
    kept = _kept_for(out, identity_sha256)
    if kept is None:
        return
    for name, values in columns.items():
        whole = kept.columns.get(name)
        if whole is None:
            whole = kept.columns[name] = np.empty(kept.samples, dtype=np.asarray(values).dtype)
        whole[start : start + len(values)] = values
    kept.filled[index] = start


def share_kept(
    out: Path, identity_sha256: str, like: Mapping[str, np.ndarray[Any, Any]]
) -> dict[str, np.ndarray[Any, Any]]:
    """Allocate the study's whole columns (those of ``like``, with their dtypes) in
    anonymous shared memory, and return them; empty if this study is not being kept.

    Child processes forked after this call write their chunks' values into the same
    pages (``mmap(-1, ...)`` maps MAP_SHARED), so that the summary reads them here
    without a copy through a pipe; :func:`mark_kept` then records the chunk as filled.
    Columns already allocated are kept as they are.
    """
    kept = _kept_for(out, identity_sha256)
    if kept is None:
        return {}
    for name, values in like.items():
        if name not in kept.columns:
            dtype = np.asarray(values).dtype
            buffer = mmap.mmap(-1, max(1, kept.samples * dtype.itemsize))
            kept.columns[name] = np.frombuffer(buffer, dtype=dtype, count=kept.samples)
    return {name: kept.columns[name] for name in like}


def mark_kept(out: Path, identity_sha256: str, index: int, start: int) -> None:
    """Record that chunk ``index`` (first sample ``start``) was filled into the shared
    columns by a child process (:func:`share_kept`)."""
    kept = _kept_for(out, identity_sha256)
    if kept is not None:
        kept.filled[index] = start


def take_kept(
    out: Path, identity_sha256: str
) -> tuple[dict[str, np.ndarray[Any, Any]], set[int]] | None:
    """The whole columns kept for this study and the chunks filled in (and forget them)."""
    kept = _kept_for(out, identity_sha256)
    if kept is None:
        return None
    _KEPT.clear()
    return kept.columns, set(kept.filled)


@dataclass(frozen=True)
class ChunkReader:
    """Reads columns of a finished study, chunk by chunk, in sample order.

    Attributes
    ----------
    out : the study's folder
    chunks : number of chunks
    """

    out: Path
    chunks: int

    def column(self, name: str) -> np.ndarray[Any, Any]:
        """One column over all samples, in sample order."""
        pq = require("pyarrow.parquet")
        parts = [
            pq.read_table(chunk_path(self.out, k), columns=[name]).column(0).to_numpy()
            for k in range(self.chunks)
        ]
        return np.concatenate(parts)

    def read(
        self,
        names: Sequence[str],
        rows: Sequence[int] | None = None,
        kept: tuple[dict[str, np.ndarray[Any, Any]], set[int]] | None = None,
        *,
        check_samples: bool = False,
    ) -> dict[str, np.ndarray[Any, Any]]:
        """Several columns over all samples, each chunk file opened once.

        Each column is filled chunk by chunk into one array, so that the peak memory is
        the columns plus one chunk (not the columns twice, as concatenating would).
        ``rows`` are the chunks' row counts if known (their tags hold them). ``kept``
        (:func:`take_kept`) are whole columns already filled for some chunks: only the
        other chunks are read, into those arrays. ``check_samples``: ValueError unless
        each chunk read holds the next samples in order (its ``sample`` column).
        """
        pq = require("pyarrow.parquet")
        paths = [chunk_path(self.out, k) for k in range(self.chunks)]
        if rows is None:
            rows = [pq.read_metadata(path).num_rows for path in paths]
        total = sum(rows)
        found, filled = kept if kept is not None else ({}, set())
        if any(name not in found or found[name].shape != (total,) for name in names):
            found, filled = {}, set()
        start = 0
        for k, (path, count) in enumerate(zip(paths, rows, strict=True)):
            if k not in filled:
                wanted = [*names, "sample"] if check_samples else list(names)
                table = pq.read_table(path, columns=wanted)
                if check_samples and not np.array_equal(
                    table.column("sample").to_numpy(), np.arange(start, start + count)
                ):
                    raise ValueError(f"{path}: does not hold samples {start}..{start + count - 1}")
                for name in names:
                    part = table.column(name).to_numpy()
                    if name not in found:
                        found[name] = np.empty(total, dtype=part.dtype)
                    found[name][start : start + count] = part
            start += count
        return {name: found[name] for name in names}

    def chunk(self, index: int, names: Sequence[str]) -> dict[str, np.ndarray[Any, Any]]:
        """Columns of one chunk file."""
        pq = require("pyarrow.parquet")
        table = pq.read_table(chunk_path(self.out, index), columns=list(names))
        return {name: table.column(name).to_numpy() for name in names}

    def floats(self, name: str) -> FloatArray:
        """One float column over all samples."""
        return np.asarray(self.column(name), dtype=float)

    def to_pandas(self, columns: Sequence[str] | None = None) -> Any:
        """The samples as a pandas DataFrame, one row per sample (all or some columns)."""
        pa = require("pyarrow")
        pq = require("pyarrow.parquet")
        require("pandas")
        names = None if columns is None else list(columns)
        tables = [pq.read_table(chunk_path(self.out, k), columns=names) for k in range(self.chunks)]
        return pa.concat_tables(tables).to_pandas()

    def tags(self) -> list[dict[str, Any]]:
        """Every chunk's metadata tag, in chunk order."""
        found = []
        for k in range(self.chunks):
            tag = chunk_tag(chunk_path(self.out, k))
            if tag is None:
                raise ValueError(f"{chunk_path(self.out, k)}: missing or unreadable chunk")
            found.append(tag)
        return found

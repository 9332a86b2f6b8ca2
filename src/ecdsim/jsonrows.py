"""Write a JSON document whose long lists of points are held as columns, streaming.

A drop-test log of a million rows gives a million point objects in
``ecdsim fit drop-test --json``. Built as Python dicts and passed through
``json.dumps(indent=2)`` (the pure-Python encoder, since the C one cannot indent), that
took 34 s and 2.9 GB (issue 12). Here the points stay NumPy columns (:class:`RowTable`);
the rest of the document is encoded as usual and each table is written in blocks of
rows, one object per line, the numbers formatted by the C encoder a column at a time.
The text is the same JSON (same keys, same float repr) with a different layout of
whitespace, and memory stays bounded by the block size.
"""

from __future__ import annotations

import json
import re
import secrets
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

# The JSON Schema of every --json document, shipped with the package (docs/json.md).
SCHEMA_DIR = Path(__file__).resolve().parent / "schemas"
SCHEMAS = (
    "deploy",
    "fit_drop_test",
    "fit_trace",
    "size",
    "compare_fluid",
    "montecarlo",
    "repeat",
    "sweep",
    # The qualification commands (docs/qualification.md).
    "margin",
    "reliability_demonstrated",
    "reliability_runs_needed",
    "reliability_weibull",
    "fit_drive_test",
    "fit_fluid_damper",
    # A wing file's documents (docs/wing.md); its sweep is a "sweep" document.
    "wing_deploy",
    "wing_montecarlo",
)


def schema(name: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a ``--json`` document: ``"deploy"``,
    ``"fit_drop_test"``, ``"fit_trace"``, ``"size"``, ``"compare_fluid"``,
    ``"montecarlo"``, ``"repeat"``, ``"sweep"``, ``"margin"``,
    ``"reliability_demonstrated"``, ``"reliability_runs_needed"``, ``"reliability_weibull"``,
    ``"fit_drive_test"``, ``"fit_fluid_damper"``, or a wing file's ``"wing_deploy"`` or
    ``"wing_montecarlo"``.

    >>> schema("deploy")["title"]
    'ecdsim deploy --json'
    """
    if not isinstance(name, str) or name not in SCHEMAS:
        raise ValueError(
            f"{name!r} is not a JSON document of ecdsim; expected one of {list(SCHEMAS)}"
        )
    found: dict[str, Any] = json.loads((SCHEMA_DIR / f"{name}.schema.json").read_text("utf-8"))
    return found


# Rows per block: large enough that the per-block overhead is negligible, small enough
# that a block's strings (about 100 B per cell) stay a few tens of MB.
BLOCK_ROWS = 16_384


@dataclass(frozen=True)
class RowTable:
    """Equal-length columns written to JSON as a list of objects, one per row.

    Columns may be float (NaN written as null; infinities refused, as by
    ``json.dumps(allow_nan=False)``), integer or bool arrays.
    """

    columns: Mapping[str, ArrayLike]

    def arrays(self) -> dict[str, np.ndarray[Any, Any]]:
        """The columns as 1-D arrays, checked to have one length."""
        arrays = {name: _column(values) for name, values in self.columns.items()}
        lengths = {a.size for a in arrays.values()}
        if len(lengths) > 1:
            raise ValueError(f"RowTable columns differ in length: {sorted(lengths)}")
        return arrays

    def __len__(self) -> int:
        arrays = self.arrays()
        return next(iter(arrays.values())).size if arrays else 0

    def records(self) -> list[dict[str, Any]]:
        """The rows as plain dicts (NaN as None): the small-data form of the table."""
        columns = {name: _python_values(a) for name, a in self.arrays().items()}
        return [dict(zip(columns, row, strict=True)) for row in zip(*columns.values(), strict=True)]


def _column(values: ArrayLike) -> np.ndarray[Any, Any]:
    """One column as a contiguous 1-D array; floats as float64, the type JSON round-trips."""
    array = np.ravel(np.asarray(values))
    if array.dtype.kind == "f":
        array = array.astype(np.float64, copy=False)
    return np.ascontiguousarray(array)


def _python_values(values: np.ndarray[Any, Any]) -> list[Any]:
    listed: list[Any] = values.tolist()
    if values.dtype.kind == "f" and np.isnan(values).any():
        return [None if v != v else v for v in listed]  # v != v only for NaN
    return listed


def _cell_texts(values: np.ndarray[Any, Any], name: str, look: bool = True) -> list[str]:
    """The JSON text of each value of one column block, by the C encoder.

    A column that repeats a few values (a constant inertia, the set of masses, the
    outlier flags) has each distinct value formatted once. Distinct means distinct bits,
    so that -0.0 keeps its sign as ``json.dumps`` would write it. ``look=False`` skips
    that search (a column whose first block had no repeats to speak of).
    """
    if values.size == 0:
        return []
    if look:
        bits = values.view(np.uint64) if values.dtype == np.float64 else values
        distinct, inverse = np.unique(bits, return_inverse=True)
        if 4 * distinct.size <= values.size:
            once = _texts(distinct.view(values.dtype) if bits is not values else distinct, name)
            return [once[i] for i in inverse.ravel().tolist()]
    return _texts(values, name)


def _repeats(values: np.ndarray[Any, Any]) -> bool:
    """True where a column block repeats its values enough to format each only once."""
    bits = values.view(np.uint64) if values.dtype == np.float64 else values
    return values.size > 0 and 4 * np.unique(bits).size <= values.size


def _texts(values: np.ndarray[Any, Any], name: str) -> list[str]:
    if values.dtype.kind == "f":
        if np.isinf(values).any():
            raise ValueError(f"column {name!r} holds an infinite value, not valid JSON")
        missing = np.isnan(values)
        texts = json.dumps(values.tolist()).strip("[]").split(", ")
        if missing.any():
            for i in np.flatnonzero(missing).tolist():
                texts[i] = "null"
        return texts
    return json.dumps(values.tolist()).strip("[]").split(", ")


def _table_chunks(table: RowTable, indent: str) -> Iterator[str]:
    """The text of ``table`` as a JSON list, one object per line, at ``indent``."""
    arrays = table.arrays()
    names = sorted(arrays)
    n = next(iter(arrays.values())).size if arrays else 0
    if n == 0:
        yield "[]"
        return
    # '%' formatting of one template per row: the keys are fixed, only numbers vary.
    template = "{" + ", ".join(json.dumps(k).replace("%", "%%") + ": %s" for k in names) + "}"
    row_indent = indent + "  "
    yield "["
    # Whether to look for repeats, decided on each column's first block (a million
    # distinct speeds need no search for duplicates in every block).
    look = {k: _repeats(arrays[k][:BLOCK_ROWS]) for k in names}
    for start in range(0, n, BLOCK_ROWS):
        block = [_cell_texts(arrays[k][start : start + BLOCK_ROWS], k, look[k]) for k in names]
        lines = [template % cells for cells in zip(*block, strict=True)]
        joiner = ",\n" + row_indent
        yield ("\n" if start == 0 else ",\n") + row_indent + joiner.join(lines)
    yield "\n" + indent + "]"


def iter_json(document: Any) -> Iterator[str]:
    """Pieces of ``document`` as JSON (indent 2, keys sorted), tables streamed in blocks.

    Everything except :class:`RowTable` values is encoded by ``json.dumps`` with
    ``allow_nan=False``, so a non-finite number outside a table raises ``ValueError``.
    """
    tables: list[RowTable] = []
    token = secrets.token_hex(8)  # so that no string of the document can match a marker

    def replace(value: Any) -> Any:
        if isinstance(value, RowTable):
            tables.append(value)
            return _marker(token, len(tables) - 1)
        if isinstance(value, dict):
            return {k: replace(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [replace(v) for v in value]
        return value

    text = json.dumps(replace(document), indent=2, sort_keys=True, allow_nan=False)
    # Markers appear in the text in key-sorted order, not in the order they were made.
    position = 0
    for found in re.finditer(f'"ecdsim-row-table-{token}-([0-9]+)"', text):
        line = text[text.rfind("\n", 0, found.start()) + 1 : found.start()]
        indent = " " * (len(line) - len(line.lstrip(" ")))
        yield text[position : found.start()]
        yield from _table_chunks(tables[int(found.group(1))], indent)
        position = found.end()
    yield text[position:]


def _marker(token: str, index: int) -> str:
    return f"ecdsim-row-table-{token}-{index}"


def write_json(document: Any, write: Callable[[str], object]) -> None:
    """Write ``document`` as JSON through ``write`` (e.g. ``sys.stdout.write``)."""
    for piece in iter_json(document):
        write(piece)
    write("\n")

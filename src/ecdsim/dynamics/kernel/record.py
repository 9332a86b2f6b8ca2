"""The kernel's outputs that grow as a case runs: its events and its time series.

Three tables: events (case, time, kind, angle, speed), spans (one per segment: a closed
form's constants, or the range of an integrated segment's points) and points (an
integrated segment's accepted steps: time, load angle and speed, the damper's log state
and their rates, for cubic Hermite interpolation). They are plain arrays allocated by
the caller; ``counts`` holds their filled lengths. A case that would overflow one marks
it (``counts[OVERFLOW]``) and stops; its caller enlarges the tables and runs that case
again from its start (``counts[START + table]``: the lengths before it). So the kernel
allocates nothing while it runs, and numba compiles it without reference counting.
"""

from __future__ import annotations

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L

EVENTS, SPANS, POINTS = 0, 1, 2
OVERFLOW = 3  # counts[OVERFLOW]: 1 + the table that was full, 0 while none was
START = 4  # counts[START + table]: its length when the current case started
COUNTS = 7
Buffers = tuple[FloatArray, FloatArray, FloatArray]


def _room(rows: FloatArray, table: int, counts: FloatArray) -> int:
    """The next free row of a table, or -1 (the overflow marked) when it is full."""
    filled = int(counts[table])
    if filled < rows.shape[0]:
        return filled
    counts[OVERFLOW] = table + 1.0
    return -1


def begin_case(counts: FloatArray) -> None:
    """Remember the tables' lengths at a case's start (to run it again after growing)."""
    for table in range(3):
        counts[START + table] = counts[table]


def log_event(
    buffers: Buffers, counts: FloatArray, case: int, time: float, kind: int, angle: float,
    speed: float,
) -> None:  # fmt: skip
    """Append an event: the case, its time, kind, the load's angle and speed."""
    rows = buffers[EVENTS]
    i = _room(rows, EVENTS, counts)
    if i < 0:
        return
    rows[i, 0] = case
    rows[i, 1] = time
    rows[i, 2] = kind
    rows[i, 3] = angle
    rows[i, 4] = speed
    counts[EVENTS] = i + 1


def open_span(
    buffers: Buffers, counts: FloatArray, case: int, kind: int, t0: float, engaged: float
) -> int:
    """Start a span of ``kind`` (the damper engaged or not); returns its row (filled by
    the caller), -1 if full."""
    rows = buffers[SPANS]
    i = _room(rows, SPANS, counts)
    if i < 0:
        return -1
    for j in range(L.SPAN_FIELDS):
        rows[i, j] = 0.0
    rows[i, L.SPAN_CASE] = case
    rows[i, L.SPAN_KIND] = kind
    rows[i, L.SPAN_T0] = t0
    rows[i, L.SPAN_T1] = t0
    rows[i, L.SPAN_ENGAGED] = engaged
    if kind == L.SPAN_STEPS:
        rows[i, L.SPAN_FIRST] = counts[POINTS]
    counts[SPANS] = i + 1
    return i


def add_point(
    buffers: Buffers, counts: FloatArray, span: int, t: float, phi: float, w: float, s: float,
    dphi: float, dw: float, ds: float,
) -> None:  # fmt: skip
    """Append a point to the integrated span ``span`` (its time, state and rates)."""
    rows = buffers[POINTS]
    i = _room(rows, POINTS, counts)
    if i < 0 or span < 0:
        return
    rows[i, L.POINT_T] = t
    rows[i, L.POINT_PHI] = phi
    rows[i, L.POINT_W] = w
    rows[i, L.POINT_S] = s
    rows[i, L.POINT_DPHI] = dphi
    rows[i, L.POINT_DW] = dw
    rows[i, L.POINT_DS] = ds
    counts[POINTS] = i + 1
    spans = buffers[SPANS]
    spans[span, L.SPAN_COUNT] += 1.0
    spans[span, L.SPAN_T1] = t

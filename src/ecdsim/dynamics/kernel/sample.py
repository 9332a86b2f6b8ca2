"""Time series re-evaluated from a run's recorded spans, and the torques at them.

A closed-form span is evaluated exactly (:mod:`ecdsim.dynamics.kernel.closed`), an
integrated one by cubic Hermite interpolation between its recorded steps (the dense
output its events were located on); before release the initial state, after a case's
last segment its final state held. The torques at the samples are the hinge's laws
(:mod:`ecdsim.physics`), the same the integration evaluated.
"""

from __future__ import annotations

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel import layout as L
from ecdsim.dynamics.kernel.closed import evaluate, prepare
from ecdsim.dynamics.kernel.dense import hermite
from ecdsim.physics.thermal import temperature_from_factor_log

# Columns of the initial and final states handed to :func:`sample_cases`.
STATE_ANGLE, STATE_SPEED, STATE_TEMPERATURE, STATE_ENGAGED, STATE_HOLD = range(5)


def _span_at(spans: FloatArray, first: int, last: int, t: float) -> int:
    """The last span of [first, last) starting at or before t (bisection); -1 if none."""
    lo = first
    hi = last
    while lo < hi:
        mid = (lo + hi) // 2
        if spans[mid, L.SPAN_T0] <= t:
            lo = mid + 1
        else:
            hi = mid
    return lo - 1 if lo > first else -1


def _in_steps(
    points: FloatArray, span: FloatArray, t: float, par: FloatArray
) -> tuple[float, float, float]:
    """An integrated span at t: angle, speed, damper temperature (Hermite between steps)."""
    first = int(span[L.SPAN_FIRST])
    last = first + int(span[L.SPAN_COUNT]) - 1
    lo = first
    hi = last
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if points[mid, L.POINT_T] <= t:
            lo = mid
        else:
            hi = mid
    h = points[hi, L.POINT_T] - points[lo, L.POINT_T]
    s = (t - points[lo, L.POINT_T]) / h if h > 0.0 else 0.0
    a = points[lo]
    b = points[hi]
    angle = hermite(a[L.POINT_PHI], a[L.POINT_DPHI], b[L.POINT_PHI], b[L.POINT_DPHI], h, s)
    speed = hermite(a[L.POINT_W], a[L.POINT_DW], b[L.POINT_W], b[L.POINT_DW], h, s)
    heat: float = par[L.AMB]
    if par[L.NODES] > 0.0:
        state = hermite(a[L.POINT_S], a[L.POINT_DS], b[L.POINT_S], b[L.POINT_DS], h, s)
        heat = min(
            temperature_from_factor_log(state, par[L.AMB], par[L.FA], par[L.COEF]), par[L.TZERO]
        )
    return angle, speed, heat


def sample_cases(
    times: FloatArray, table: FloatArray, spans: FloatArray, points: FloatArray,
    span_start: FloatArray, initial: FloatArray, final: FloatArray, out: FloatArray,
) -> None:  # fmt: skip
    """Angle, speed, damper temperature and engagement at ``times`` (n_times, cases):
    ``out`` of shape (4, n_times, cases)."""
    for c in range(times.shape[1]):
        first = int(span_start[c])
        last = int(span_start[c + 1])
        hold = final[c, STATE_HOLD]
        for j in range(times.shape[0]):
            t = times[j, c]
            state = final[c] if t >= hold else initial[c]
            for k in range(4):
                out[k, j, c] = state[k]
            if t < 0.0 or t >= hold:
                continue
            k = _span_at(spans, first, last, t)
            if k < 0 or not t < spans[k, L.SPAN_T1]:
                continue
            span = spans[k]
            if span[L.SPAN_KIND] == L.SPAN_CLOSED:
                seg = prepare(
                    span[L.SPAN_J], span[L.SPAN_B], span[L.SPAN_K], span[L.SPAN_A], span[L.SPAN_W0]
                )
                x, v, _, _ = evaluate(seg, t - span[L.SPAN_T0], False)
                angle = span[L.SPAN_PHI0] + span[L.SPAN_DIR] * x
                speed = span[L.SPAN_DIR] * v
                heat = span[L.SPAN_TEMP]
            elif span[L.SPAN_COUNT] >= 2.0:
                angle, speed, heat = _in_steps(points, span, t, table[c])
            else:
                continue
            out[0, j, c] = angle
            out[1, j, c] = speed
            out[2, j, c] = heat
            out[3, j, c] = span[L.SPAN_ENGAGED]

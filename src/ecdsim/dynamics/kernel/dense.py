"""Dense output between two accepted steps, and the event locator that works on it.

Between the states ``y0``, ``y1`` of a step of size h, with slopes ``f0``, ``f1``, each
row follows the cubic Hermite interpolant (exact slopes at both ends: an O(h^4) local
error, the integrator's own order). Every event of the dynamic kernel is a function of
the state, ``g(y) > 0`` inside the segment's mode, reaching 0 at the event; the locator
finds the first fraction of the step where ``g`` of the interpolated state reaches 0
(the Illinois variant of regula falsi, to 2^-50 of the step), whatever the event: one
locator for every event and every integrator, as scipy's ``solve_ivp`` locates its
events on any method's dense output (``scipy/integrate/_ivp/ivp.py``,
``solve_event_equation``). The extremes of a row inside a step (the largest speed, the
damper's peak temperature) are the interpolant's interior maxima.
"""

from __future__ import annotations

import math

from ecdsim._types import FloatArray

# The locator stops when its bracket is below this fraction of the step.
LOCATE_TOLERANCE = 2.0**-50
LOCATE_ITERATIONS = 200


def hermite(y0: float, f0: float, y1: float, f1: float, h: float, s: float) -> float:
    """The cubic Hermite interpolant at the fraction s of a step of size h."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * f0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * f1
    )


def interpolate(
    y0: FloatArray, f0: FloatArray, y1: FloatArray, f1: FloatArray, h: float, s: float,
    out: FloatArray, n: int,
) -> None:  # fmt: skip
    """Every row of the state at the fraction s of the step, into ``out``."""
    for i in range(n):
        out[i] = hermite(y0[i], f0[i], y1[i], f1[i], h, s)


def quadratic_root(c0: float, c1: float, c2: float) -> float:
    """The first root in (0, 1] of ``c0 + c1 s + c2 s^2`` with ``c0 > 0`` going down
    through zero before s = 1 (the derivative of a cubic turning from + to -); 2.0 if
    there is none."""
    if c2 == 0.0:
        if c1 < 0.0:
            root = -c0 / c1
            return root if root <= 1.0 else 2.0
        return 2.0
    disc = c1 * c1 - 4.0 * c0 * c2
    if disc < 0.0:
        return 2.0
    sq = math.sqrt(disc)
    # The two roots without cancellation (Numerical Recipes 5.6).
    q = -0.5 * (c1 + math.copysign(sq, c1))
    first = q / c2 if q != 0.0 else 2.0
    second = c0 / q if q != 0.0 else 2.0
    best = 2.0
    for root in (first, second):
        if root > 0.0 and root <= 1.0 and root < best:
            best = root
    return best


def interior_peak(y0: float, f0: float, y1: float, f1: float, h: float, stop: float) -> float:
    """The interpolant's maximum inside the step where its slope turns from + to -, if
    it lies before the fraction ``stop``; -inf otherwise."""
    if not (f0 > 0.0 and f1 < 0.0):
        return -math.inf
    hf0 = h * f0
    hf1 = h * f1
    dy = y1 - y0
    c2 = 3.0 * dy - 2.0 * hf0 - hf1
    c3 = hf0 + hf1 - 2.0 * dy
    s_turn = quadratic_root(hf0, 2.0 * c2, 3.0 * c3)
    if s_turn <= stop:
        return hermite(y0, f0, y1, f1, h, s_turn)
    return -math.inf


def crossed(g0: float, g1: float) -> bool:
    """An event function went from inside its mode (> 0) to its event (<= 0) in a step;
    one already at 0 at the step's start fires when it goes negative."""
    return (g0 > 0.0 and g1 <= 0.0) or (g0 == 0.0 and g1 < 0.0)


def illinois(
    ga: float, gb: float, a: float, b: float, gs: float, s: float, side: int
) -> tuple[float, float, float, float, int]:
    """One update of the Illinois bracket ``[a, b]`` (g(a) > 0 >= g(b)) with the trial
    ``s``, ``g(s) = gs``: returns (ga, gb, a, b, side), halving the retained end's value
    when the same end is kept twice (Dowell and Jarratt 1971)."""
    if gs > 0.0:
        if side == 1:
            gb *= 0.5
        return gs, gb, s, b, 1
    if side == -1:
        ga *= 0.5
    return ga, gs, a, s, -1


def next_trial(ga: float, gb: float, a: float, b: float) -> float:
    """The regula falsi point of the bracket, or its midpoint if that falls outside."""
    s = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
    if not (a < s < b):
        s = 0.5 * (a + b)
    return s

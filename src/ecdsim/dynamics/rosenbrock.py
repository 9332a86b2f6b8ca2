"""A batched stiff integrator for the nonlinear segments: Rosenbrock RODAS4, vectorised.

``solve_ivp`` integrates one case per call; a Monte Carlo batch of roll-off or self-heating
deployments then costs a Python-level integration per case. This module advances every
case of a batch together, each with its own step size, error control and events, in
NumPy arrays.

Method: RODAS4 (Hairer, E. and Wanner, G., *Solving Ordinary Differential Equations II*,
2nd ed., Springer 1996, section VI.4; coefficients as tabulated there and in KPP/FATODE,
Sandu et al.): 6 stages, order 4 with an embedded order-3 solution for the error
estimate, stiffly accurate and L-stable, so stiffness (``J / B`` of milliseconds) costs
nothing. In the transformed form (Hairer and Wanner, IV.7, Eq. 7.4'):

    (I / (h g) - J) K_i = f(y + sum_j A_ij K_j) + sum_j (C_ij / h) K_j,
    y1 = y + sum_i M_i K_i,     error = sum_i E_i K_i

with the analytic Jacobian J of the segment's equations (:mod:`ecdsim.dynamics.equations`,
whose temperature state is the damping law's log factor, so that no stage can cross the
law's zero). The linear systems are solved by elimination specific to their sparsity
(the position row is ``x' = u``; the energy does not feed back). Steps are accepted when
the embedded error, in the max norm over ``atol + rtol |y|``, is <= 1. Dense output
between steps is the cubic Hermite interpolant of the step's end states and derivatives;
events and the interior maxima of speed and temperature state are located on it by
Newton's iteration safeguarded by bisection. The method's order (4) is checked in
``tests/test_dynamics_rosenbrock.py``.

Cost: every array operation runs over the whole batch, so the step works in place on
preallocated arrays, skips the rows that cannot change (without heating the temperature
stages are zero), builds the last stage and the solution from stage 5 (stiffly
accurate), and a rejected step simply leaves its case unchanged instead of gathering the
accepted cases.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import BoolArray, FloatArray
from ecdsim.dynamics import linear
from ecdsim.dynamics.equations import SWITCH, Model

__all__ = ["Control", "Model", "Outcome", "Segments", "Trajectory", "integrate_batch"]

GAMMA = 0.25
_A21, _A31, _A32 = 1.544, 0.9466785280815826, 0.2557011698983284
_A41, _A42, _A43 = 3.314825187068521, 2.896124015972201, 0.9986419139977817
_A51, _A52, _A53, _A54 = 1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895
A = (
    (),
    (_A21,),
    (_A31, _A32),
    (_A41, _A42, _A43),
    (_A51, _A52, _A53, _A54),
    (_A51, _A52, _A53, _A54, 1.0),
)
C = (
    (),
    (-5.6688,),
    (-2.430093356833875, -0.2063599157091915),
    (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
    (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
    (
        8.083246795921522,
        -7.981132988064893,
        -31.52159432874371,
        16.31930543123136,
        -6.058818238834054,
    ),
)
# RODAS4 is stiffly accurate: the solution weights are the last row of A plus the last
# stage (y1 = stage 6's state + K6) and the error estimate is K6 alone, so neither has a
# table of its own here. The step size follows the estimate's order 4 (the fourth root).
MAX_STEPS = 200_000  # step attempts per segment before it is reported as cut short


class _Solver:
    """``(I - c J) z = r`` for the sparsity of :meth:`Model.jacobian`, many right-hand sides.

    Without heating the temperature row of every right-hand side is zero, and so is the
    solution's (``z[2] = r[2]``); :meth:`solve` then skips the temperature coupling.
    """

    def __init__(
        self,
        jac: tuple[FloatArray, ...],
        c: FloatArray,
        heating: bool = True,
        housing: tuple[FloatArray, FloatArray, FloatArray] | None = None,
    ) -> None:
        j10, j11, j12, j21, j22, j31, j32 = jac
        self.c = c
        self.heating = heating
        self.housing = housing is not None
        den2 = 1.0 - c * j22
        if housing is not None:
            # Two-node heating: z4 = (r4 + c j42 z2) / (1 - c j44) eliminated from row 2
            # leaves the one-node system with den2 - c^2 j24 j42 / (1 - c j44) and
            # r2 + c j24 r4 / (1 - c j44) in place of den2 and r2.
            j24, j42, j44 = housing
            self.inv4 = 1.0 / (1.0 - c * j44)  # j44 <= 0: never singular
            self.p42 = c * j42 * self.inv4
            self.p24 = c * j24 * self.inv4
            den2 = den2 - self.p24 * c * j42
        safe2 = np.where(den2 != 0.0, den2, 1.0)
        den1 = 1.0 - c * j11 - c * c * j10 - c * c * j12 * j21 / safe2
        self.ok = (np.abs(den2) > 1e-12) & (np.abs(den1) > 1e-12)
        inv1 = 1.0 / np.where(self.ok, den1, 1.0)
        inv2 = 1.0 / np.where(self.ok, den2, 1.0)
        # z1 = (r1 + c j10 r0 + c j12 r2 / den2) / den1,   z0 = r0 + c z1,
        # z2 = (r2 + c j21 z1) / den2,                     z3 = r3 + c (j31 z1 + j32 z2).
        self.inv1 = inv1
        self.p10 = c * j10 * inv1
        self.p31 = c * j31
        if heating:
            self.inv2 = inv2
            self.p12 = c * j12 * inv2 * inv1
            self.p21 = c * j21 * inv2
            self.p32 = c * j32

    def solve(
        self, r: FloatArray, out: FloatArray | None = None, scratch: FloatArray | None = None
    ) -> FloatArray:
        """z with ``(I - c J) z = r``; r and z of shape (rows, n); ``out`` must not be r."""
        z = np.empty_like(r) if out is None else out
        tmp = np.empty_like(r[0]) if scratch is None else scratch
        if self.housing:
            r = r.copy()
            r[2] += self.p24 * r[4]
        z1 = z[1]
        np.multiply(r[1], self.inv1, out=z1)
        np.multiply(self.p10, r[0], out=tmp)
        z1 += tmp
        if self.heating:
            np.multiply(self.p12, r[2], out=tmp)
            z1 += tmp
        np.multiply(self.c, z1, out=z[0])
        z[0] += r[0]
        np.multiply(self.p31, z1, out=z[3])
        z[3] += r[3]
        if self.heating:
            np.multiply(r[2], self.inv2, out=z[2])
            np.multiply(self.p21, z1, out=tmp)
            z[2] += tmp
            np.multiply(self.p32, z[2], out=tmp)
            z[3] += tmp
            if self.housing:
                np.multiply(r[4], self.inv4, out=z[4])
                z[4] += self.p42 * z[2]
        else:
            z[2] = r[2]
        return z


# GAMMA * C: the coupling terms enter the stage equations scaled by GAMMA.
_GC = tuple(tuple(GAMMA * c for c in row) for row in C)


class _Work:
    """Preallocated arrays for :func:`_step` on a batch of n cases."""

    def __init__(self, n: int, rows: int = 4) -> None:
        self.n = n
        self.rows = rows
        self.k = np.empty((6, rows, n))
        self.stage = np.empty((rows, n))
        self.last = np.empty((rows, n))
        self.coupling = np.empty((rows, n))
        self.value = np.empty((rows, n))
        self.scratch = np.empty((rows, n))


def _step(
    model: Model, y: FloatArray, f0: FloatArray, h: FloatArray, work: _Work | None = None
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """One RODAS4 step: new state, error estimate, and where the linear solve was sound.

    ``work`` (reused between calls) avoids allocations; the error estimate returned is
    then a view into it, valid until its next use.
    """
    n = y.shape[1]
    size = model.rows
    if work is None or work.n != n or work.rows != size:
        work = _Work(n, size)
    heating = model.heating
    hg = h * GAMMA
    housing = model.housing_jacobian(y) if model.two_node else None
    solver = _Solver(model.jacobian(y), hg, heating, housing)
    k, stage, last = work.k, work.stage, work.last
    coupling, value, scratch = work.coupling, work.value, work.scratch
    # Rows that vary: without heating the temperature stages are all zero (the stage
    # temperature stays y's) and the energy row is never read by the right-hand side.
    # With a housing node (row 4) every row varies; the energy row 3 is then carried along.
    every = slice(0, size)
    stage_rows = every if size > 4 else slice(0, 3) if heating else slice(0, 2)
    coupling_rows = (every,) if heating else (slice(0, 2), slice(3, 4))
    np.copyto(stage, y)
    coupling[2] = 0.0
    np.multiply(f0, hg, out=value)
    solver.solve(value, k[0], scratch[0])
    for i in range(1, 6):
        # Stage states y + sum_j A_ij K_j. RODAS4 is stiffly accurate: stage 6's state is
        # stage 5's plus K5, and y1 is stage 6's plus K6; those are kept, in full, in
        # ``last``.
        if i < 4:
            target, rows = stage, stage_rows
            if i > 1:
                np.copyto(stage[rows], y[rows])
        else:
            target, rows = last, every
            if i == 4:
                np.copyto(last, y)
        if i < 5:
            for a, kj in zip(A[i], k[:i], strict=True):
                np.multiply(kj[rows], a, out=scratch[rows])
                target[rows] += scratch[rows]
        else:
            last += k[4]
        # coupling = GAMMA * sum_j C_ij K_j
        for rs in coupling_rows:
            np.multiply(k[0][rs], _GC[i][0], out=coupling[rs])
            for gc, kj in zip(_GC[i][1:], k[1:i], strict=True):
                np.multiply(kj[rs], gc, out=scratch[rs])
                coupling[rs] += scratch[rs]
        model.rhs(target, out=value)
        value *= hg
        value += coupling
        solver.solve(value, k[i], scratch[0])
    y1 = last + k[5]
    return y1, k[5], solver.ok  # the error estimate is K6 (stiffly accurate)


def _hermite(
    y0: FloatArray, f0: FloatArray, y1: FloatArray, f1: FloatArray, h: FloatArray, s: FloatArray
) -> FloatArray:
    """Cubic Hermite interpolant at fractions s of the step (broadcast over rows)."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2 * s3 - 3 * s2 + 1) * y0
        + (s3 - 2 * s2 + s) * h * f0
        + (-2 * s3 + 3 * s2) * y1
        + (s3 - s2) * h * f1
    )


def _hermite_slope(
    y0: FloatArray, f0: FloatArray, y1: FloatArray, f1: FloatArray, h: FloatArray, s: FloatArray
) -> FloatArray:
    """d/dt of :func:`_hermite` (per unit time)."""
    s2 = s * s
    return (
        (6 * s2 - 6 * s) * y0 / h
        + (3 * s2 - 4 * s + 1) * f0
        + (-6 * s2 + 6 * s) * y1 / h
        + (3 * s2 - 2 * s) * f1
    )


def _cubic(
    y0: FloatArray, f0: FloatArray, y1: FloatArray, f1: FloatArray, h: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Power-basis coefficients (in the step fraction s) of :func:`_hermite`."""
    hf0 = h * f0
    hf1 = h * f1
    dy = y1 - y0
    return y0, hf0, 3.0 * dy - 2.0 * hf0 - hf1, hf0 + hf1 - 2.0 * dy


def _root(coef: tuple[FloatArray, ...]) -> FloatArray:
    """The root in [0, 1] of ``sum_k coef[k] s**k`` whose values at 0 and 1 differ in sign.

    Newton's method safeguarded by bisection: the bracket shrinks every iteration and a
    Newton step leaving it is replaced by the bracket's midpoint; it ends when the update
    or the bracket is below 2^-48 of a step (the rounding of the event time).
    """
    degree = len(coef) - 1
    lo = np.zeros_like(coef[0])
    hi = np.ones_like(coef[0])
    start = coef[0] > 0.0
    total = coef[0] + coef[1]
    for c in coef[2:]:
        total = total + c
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(coef[0] / (coef[0] - total), 0.0, 1.0)  # secant on [0, 1]
    s = np.where(np.isfinite(s), s, 0.5)
    for _ in range(64):
        p = coef[degree] * s + coef[degree - 1]
        dp = coef[degree] * degree * s + (degree - 1) * coef[degree - 1]
        for j in range(degree - 2, -1, -1):
            p = p * s + coef[j]
            if j > 0:
                dp = dp * s + j * coef[j]
        same = (p > 0.0) == start
        lo = np.where(same, s, lo)
        hi = np.where(same, hi, s)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = s - p / dp
        inside = (newton > lo) & (newton < hi)
        new = np.where(inside, newton, 0.5 * (lo + hi))
        settled = (np.abs(new - s) <= 2.0**-48) | (hi - lo <= 2.0**-48) | (p == 0.0)
        s = np.where(p == 0.0, s, new)
        if np.all(settled):
            break
    return np.asarray(s)


def _earliest(
    event_s: FloatArray,
    event_kind: NDArray[np.int8],
    hit: NDArray[np.intp],
    s_hit: FloatArray,
    code: int,
) -> None:
    """Keep, per case, the earliest event found so far."""
    earlier = s_hit < event_s[hit]
    event_s[hit] = np.where(earlier, s_hit, event_s[hit])
    event_kind[hit] = np.where(earlier, code, event_kind[hit])


@dataclass(frozen=True)
class Trajectory:
    """One case's accepted steps, evaluable at any time in [0, duration] (forward frame)."""

    times: FloatArray  # step start times, and the final time last
    states: FloatArray  # (4, n_steps + 1)
    slopes: FloatArray  # (4, n_steps + 1)

    def __call__(self, t: FloatArray) -> FloatArray:
        """``[x, u, T_d, E]`` at times t [s] since the segment's start; shape (4, len(t))."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        i = np.clip(np.searchsorted(self.times, tt, side="right") - 1, 0, self.times.size - 2)
        h = self.times[i + 1] - self.times[i]
        safe = np.where(h > 0.0, h, 1.0)
        s = np.clip((tt - self.times[i]) / safe, 0.0, 1.0)
        return np.asarray(
            _hermite(
                self.states[:, i],
                self.slopes[:, i],
                self.states[:, i + 1],
                self.slopes[:, i + 1],
                h,
                s,
            )
        )


@dataclass(frozen=True)
class Outcome:
    """Per segment: kind (linear's codes, HORIZON), duration, end state, extremes."""

    kind: NDArray[np.int8]
    duration: FloatArray
    state: FloatArray  # (4, n)
    max_speed: FloatArray
    max_thermal_state: FloatArray  # largest s, the temperature state (increasing in T_d)
    trajectories: list[Trajectory | None]


@dataclass(frozen=True)
class Segments:
    """The segments to integrate, in their forward frames; arrays over n segments.

    Attributes
    ----------
    y0 : start states ``[x, u, s, E]``, shape (4, n)
    length : x at which the segment ends (REACH) [rad]
    cap : time available (CAP) [s]; inf for none
    creep_speed : speed taken as at rest (REST) where ``creeps`` [rad/s]
    creeps : whether the segment can approach rest asymptotically (equilibrium ahead)
    atol : absolute tolerances, shape (4, n)
    first_step : first trial step [s]
    """

    y0: FloatArray
    length: FloatArray
    cap: FloatArray
    creep_speed: FloatArray
    creeps: BoolArray
    atol: FloatArray
    first_step: FloatArray


@dataclass(frozen=True)
class Control:
    """How to integrate: tolerance, horizon and recording.

    Attributes
    ----------
    rtol : relative tolerance [-]
    horizon : time after which a segment without an event ends [s]
    horizon_kind : the event code it then ends with
    record : keep every accepted step for dense output
    """

    rtol: float
    horizon: float
    horizon_kind: int
    record: bool = False


# A step whose record is (cases, times, states, slopes).
_Steps = list[tuple[NDArray[np.intp], FloatArray, FloatArray, FloatArray]]
# A step inside which a row peaks: (row, cases, fraction the peak must lie before,
# stacked (y0, f0, y1) of the row, stacked (f1, h)); resolved after the loop.
_Peaks = list[tuple[int, NDArray[np.intp], FloatArray, FloatArray, FloatArray]]


class _Running:
    """The running segments' arrays, compact: a segment leaves them when it ends."""

    def __init__(self, model: Model, segments: Segments) -> None:
        n = segments.y0.shape[1]
        cap = segments.cap
        self.work = np.arange(n)
        self.model = model
        self.tol = segments.atol.copy()
        self.y = segments.y0.copy()
        self.f = model.rhs(self.y)
        self.t = np.zeros(n)
        self.h = np.minimum(segments.first_step, np.where(np.isfinite(cap), cap, np.inf))
        self.level = segments.length.copy()
        self.creep = segments.creep_speed.copy()
        self.creeping = segments.creeps.copy()
        self.top_speed = segments.y0[1].copy()
        self.top_temp = segments.y0[2].copy()
        self.buffers = _Work(n, model.rows)

    def keep(self, keep: NDArray[np.intp], end: FloatArray) -> FloatArray:
        """Keep only the segments ``keep``; returns ``end`` restricted to them."""
        self.work, self.y, self.f = self.work[keep], self.y[:, keep], self.f[:, keep]
        self.t, self.h, self.tol = self.t[keep], self.h[keep], self.tol[:, keep]
        self.level, self.creep, self.creeping = (
            self.level[keep],
            self.creep[keep],
            self.creeping[keep],
        )
        self.top_speed, self.top_temp = self.top_speed[keep], self.top_temp[keep]
        self.model = self.model.take(keep)
        self.buffers = _Work(keep.size, self.model.rows)
        return end[keep]


class _Results:
    """Per-segment outcome arrays, filled as segments end."""

    def __init__(self, segments: Segments) -> None:
        y0 = segments.y0
        n = y0.shape[1]
        self.kind = np.full(n, -1, dtype=np.int8)
        self.duration = np.zeros(n)
        self.final = y0.copy()
        self.max_speed = y0[1].copy()
        self.max_temp = y0[2].copy()


def _attempt(run: _Running, rtol: float) -> tuple[FloatArray, FloatArray, BoolArray]:
    """One trial step of every running segment: new states, next step sizes, accepted.

    A rejected step's state is its start state (the caller can then treat it like an
    accepted step of length 0).
    """
    y, h = run.y, run.h
    y1, error, sound = _step(run.model, y, run.f, h, run.buffers)
    scale = np.maximum(np.abs(y), np.abs(y1))
    scale *= rtol
    scale += run.tol
    np.abs(error, out=error)
    error /= scale
    err = np.max(error, axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        finite = np.isfinite(err + np.sum(y1, axis=0))
    accept = sound & finite & (err <= 1.0)
    factor = np.where(
        finite & sound,
        np.clip(0.9 / np.sqrt(np.sqrt(np.maximum(err, 1e-10))), 0.2, 5.0),
        0.25,
    )
    np.copyto(y1, y, where=~accept)
    return y1, h * factor, accept


def _find_events(
    run: _Running, y1: FloatArray, f1: FloatArray
) -> tuple[FloatArray, NDArray[np.int8]]:
    """Per running segment, the earliest event inside its step: fraction and kind (-1)."""
    ya, fa, h = run.y, run.f, run.h
    event_s = np.full(run.work.size, np.inf)
    event_kind = np.full(run.work.size, -1, dtype=np.int8)
    level, creep = run.level, run.creep
    crossings = [
        (linear.REACH, 0, level, (ya[0] < level) & (y1[0] >= level)),
        (linear.ZERO, 1, None, (ya[1] > 0.0) & (y1[1] <= 0.0)),
        (linear.REST, 1, creep, run.creeping & (ya[1] > creep) & (y1[1] <= creep)),
    ]
    for code, row, target, crossed in crossings:
        hit = np.flatnonzero(crossed)
        if hit.size:
            c0, c1, c2, c3 = _cubic(ya[row, hit], fa[row, hit], y1[row, hit], f1[row, hit], h[hit])
            if target is not None:
                c0 = c0 - target[hit]
            s_hit = _root((c0, c1, c2, c3))
            if code == linear.REST:
                s_hit = _creeping(run, y1, f1, hit, s_hit)
            _earliest(event_s, event_kind, hit, s_hit, code)
    if run.model.mesh is not None:
        _find_switch(run, y1, f1, event_s, event_kind)
    return event_s, event_kind


def _creeping(
    run: _Running, y1: FloatArray, f1: FloatArray, hit: NDArray[np.intp], s_hit: FloatArray
) -> FloatArray:
    """The creep crossings ``s_hit`` of the segments ``hit`` that are an approach to rest.

    The speed falls through the creep threshold either approaching the static equilibrium
    from short of it (the net drive at rest still pushes forward, :meth:`Model.rest_push`
    > 0, balanced by the damping: creep) or at the turnaround of a swing past it (the
    push is backward and the speed reaches zero in finite time: the ZERO event follows).
    The latter crossings are dropped (inf).
    """
    h = run.h[hit]
    x = _hermite(run.y[0, hit], run.f[0, hit], y1[0, hit], f1[0, hit], h, s_hit)
    push = run.model.take(hit).rest_push(x)
    return np.where(push > 0.0, s_hit, np.inf)


def _find_switch(
    run: _Running,
    y1: FloatArray,
    f1: FloatArray,
    event_s: FloatArray,
    event_kind: NDArray[np.int8],
) -> None:
    """A lossy gear's power-flow reversal inside the step (equations.SWITCH).

    The indicator (:meth:`Model.indicator`) is a function of the state: its sign change
    is bisected on the step's interpolant, to 2^-48 of a step like the other events.
    """
    model = run.model
    before = model.indicator(run.y)
    after = model.indicator(y1)
    hit = np.flatnonzero((before > 0.0) & (after <= 0.0) & (model.flow != 0.0))
    if hit.size == 0:
        return
    sub = model.take(hit)
    ya, fa, yb, fb, h = run.y[:, hit], run.f[:, hit], y1[:, hit], f1[:, hit], run.h[hit]
    lo = np.zeros(hit.size)
    hi = np.ones(hit.size)
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        positive = sub.indicator(_hermite(ya, fa, yb, fb, h, mid)) > 0.0
        lo = np.where(positive, mid, lo)
        hi = np.where(positive, hi, mid)
    _earliest(event_s, event_kind, hit, hi, SWITCH)


def _track_extremes(
    run: _Running,
    y1: FloatArray,
    f1: FloatArray,
    event_s: FloatArray,
    event_kind: NDArray[np.int8],
    peaks: _Peaks,
) -> None:
    """The step's end value, and steps whose slope turns from + to - before the event
    (their interior maximum is resolved after the loop)."""
    ya, fa, h = run.y, run.f, run.h
    rows = (1, 2) if run.model.heating else (1,)
    for row, tracker in zip(rows, (run.top_speed, run.top_temp), strict=False):
        np.maximum(tracker, y1[row], out=tracker, where=event_kind < 0)
        turning = np.flatnonzero((fa[row] > 0.0) & (f1[row] < 0.0))
        if turning.size:
            peaks.append(
                (
                    row,
                    run.work[turning],
                    np.minimum(event_s[turning], 1.0),
                    np.stack([ya[row, turning], fa[row, turning], y1[row, turning]]),
                    np.stack([f1[row, turning], h[turning]]),
                )
            )


def _finish_events(
    run: _Running,
    y1: FloatArray,
    f1: FloatArray,
    event_s: FloatArray,
    event_kind: NDArray[np.int8],
    out: _Results,
    steps: _Steps | None,
) -> NDArray[np.intp]:
    """End the segments with an event inside their step, at the event; their indices."""
    e_idx = np.flatnonzero(event_kind >= 0)
    if e_idx.size == 0:
        return e_idx
    ya, fa = run.y, run.f
    s_e = event_s[e_idx]
    h_e = run.h[e_idx]
    state = _hermite(ya[:, e_idx], fa[:, e_idx], y1[:, e_idx], f1[:, e_idx], h_e, s_e)
    run.top_speed[e_idx] = np.maximum(run.top_speed[e_idx], state[1])
    if run.model.heating:
        run.top_temp[e_idx] = np.maximum(run.top_temp[e_idx], state[2])
    codes = event_kind[e_idx]
    state[0] = np.where(codes == linear.REACH, run.level[e_idx], state[0])
    state[1] = np.where(codes == linear.ZERO, 0.0, state[1])
    g = run.work[e_idx]
    out.kind[g] = codes
    out.duration[g] = run.t[e_idx] + s_e * h_e
    out.final[:, g] = state
    if steps is not None:
        steps.append((g, out.duration[g].copy(), state, run.model.take(e_idx).rhs(state)))
    return e_idx


def _resolve_peaks(peaks: _Peaks, out: _Results) -> None:
    """Interior maxima of the speed and temperature state on the steps' interpolants."""
    for row, cases, stop, ends, rest in peaks:
        coef = _cubic(ends[0], ends[1], ends[2], rest[0], rest[1])
        s_turn = _root((coef[1], 2.0 * coef[2], 3.0 * coef[3]))
        top = _hermite(ends[0], ends[1], ends[2], rest[0], rest[1], s_turn)
        tracker = out.max_speed if row == 1 else out.max_temp
        inside = s_turn <= stop
        np.maximum.at(tracker, cases[inside], top[inside])


def integrate_batch(model: Model, segments: Segments, control: Control) -> Outcome:
    """Integrate every segment from ``segments.y0`` to its first event; see the module doc.

    Events: x reaches ``length`` (REACH), u falls to 0 (ZERO), u falls to
    ``creep_speed`` where ``creeps`` (REST), the time reaches ``cap`` (CAP) or
    ``control.horizon`` (``control.horizon_kind``). The damper cannot leave its damping
    law's domain: the temperature state is the law's log factor
    (:mod:`ecdsim.dynamics.equations`).

    Each pass of the loop steps every running segment (:func:`_attempt`), finds the
    events inside the accepted steps (:func:`_find_events`), tracks the maxima
    (:func:`_track_extremes`) and ends the segments whose event, cap or horizon came
    (:func:`_finish_events`); the running arrays are then compacted (:class:`_Running`).
    A rejected step leaves its segment unchanged, so no step gathers the accepted ones.
    :mod:`ecdsim.dynamics.compiled` is the same algorithm, compiled, one segment at a time.
    """
    n = segments.y0.shape[1]
    out = _Results(segments)
    run = _Running(model, segments)
    end = np.minimum(segments.cap, control.horizon)
    steps: _Steps | None = [] if control.record else None
    peaks: _Peaks = []
    if steps is not None:
        steps.append((run.work.copy(), run.t.copy(), run.y.copy(), run.f.copy()))
    # A segment of no length (a backward motion from the start stop) reaches its end at
    # once: the crossing test below needs x to start short of it.
    instant = segments.length <= 0.0
    if np.any(instant):
        at_once = np.flatnonzero(instant)
        out.kind[at_once] = linear.REACH
        out.final[0, at_once] = segments.length[at_once]
        end = run.keep(np.flatnonzero(~instant), end)
    for _ in range(MAX_STEPS):
        if run.work.size == 0:
            break
        np.minimum(run.h, end - run.t, out=run.h)
        y1, h_next, accept = _attempt(run, control.rtol)
        if not np.any(accept):
            run.h = h_next
            continue
        f1 = run.model.rhs(y1)
        np.copyto(f1, run.f, where=~accept)  # a rejected step keeps its slope too
        event_s, event_kind = _find_events(run, y1, f1)
        _track_extremes(run, y1, f1, event_s, event_kind, peaks)
        e_idx = _finish_events(run, y1, f1, event_s, event_kind, out, steps)
        # Advance the others; those that reached the cap or the horizon end there.
        run.t += np.where(accept, run.h, 0.0)
        run.y, run.f = y1, f1
        ended = event_kind >= 0
        going = accept & ~ended
        if steps is not None and np.any(going):
            go = np.flatnonzero(going)
            steps.append((run.work[go], run.t[go], run.y[:, go], run.f[:, go]))
        at_end = np.flatnonzero(going & (run.t >= end * (1.0 - 1e-15)))
        if at_end.size:
            g = run.work[at_end]
            out.kind[g] = np.where(
                segments.cap[g] <= control.horizon, linear.CAP, control.horizon_kind
            )
            out.duration[g] = run.t[at_end]
            out.final[:, g] = run.y[:, at_end]
        run.h = h_next
        if e_idx.size or at_end.size:
            ended[at_end] = True
            gone = run.work[ended]
            out.max_speed[gone] = np.maximum(out.max_speed[gone], run.top_speed[ended])
            out.max_temp[gone] = np.maximum(out.max_temp[gone], run.top_temp[ended])
            end = run.keep(np.flatnonzero(~ended), end)
    # Anything still running after MAX_STEPS is reported as cut short.
    if run.work.size:
        out.kind[run.work] = control.horizon_kind
        out.duration[run.work] = run.t
        out.final[:, run.work] = run.y
        out.max_speed[run.work] = np.maximum(out.max_speed[run.work], run.top_speed)
        out.max_temp[run.work] = np.maximum(out.max_temp[run.work], run.top_temp)
    _resolve_peaks(peaks, out)
    trajectories: list[Trajectory | None] = [None] * n
    if steps is not None:
        trajectories = _trajectories(steps, n)
    return Outcome(out.kind, out.duration, out.final, out.max_speed, out.max_temp, trajectories)


def _trajectories(steps: _Steps, n: int) -> list[Trajectory | None]:
    cases = np.concatenate([s[0] for s in steps])
    times = np.concatenate([s[1] for s in steps])
    states = np.concatenate([s[2] for s in steps], axis=1)
    slopes = np.concatenate([s[3] for s in steps], axis=1)
    order = np.lexsort((times, cases))
    cases, times, states, slopes = cases[order], times[order], states[:, order], slopes[:, order]
    bounds = np.searchsorted(cases, np.arange(n + 1))
    out: list[Trajectory | None] = []
    for i in range(n):
        lo, hi = bounds[i], bounds[i + 1]
        if hi - lo < 2:
            out.append(None)
            continue
        out.append(Trajectory(times[lo:hi], states[:, lo:hi], slopes[:, lo:hi]))
    return out

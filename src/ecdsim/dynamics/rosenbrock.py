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

with the analytic Jacobian J of the segment's equations (see
:mod:`ecdsim.dynamics.integrate`). The linear systems are solved by elimination specific
to their sparsity (the position row is ``x' = u``; the energy does not feed back). Steps
are accepted when the embedded error, in the max norm over ``atol + rtol |y|``, is <= 1.
Dense output between steps is the cubic Hermite interpolant of the step's end states
and derivatives; events are located on it by bisection. The method's order (4) is
checked in ``tests/test_dynamics_rosenbrock.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import BoolArray, FloatArray
from ecdsim.dynamics import linear
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.physics import thermal as heat

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
M = (_A51, _A52, _A53, _A54, 1.0, 1.0)
E = (0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
ERROR_EXPONENT = -1.0 / 4.0  # local order of the error estimate
MAX_STEPS = 200_000


@dataclass(frozen=True)
class Model:
    """The engaged equations of a set of segments, in the forward frame (1-D arrays).

    ``y = [x, u, T_d, E]``: ``x' = u``, ``J u' = a - k x - N (T_eddy(N u, T_d) + BG N u)``,
    ``T_d' = (T_eddy N u - (T_d - T_amb) / R) / C`` if heating, ``E' = N (T_eddy + BG N u) u``.
    """

    inertia: FloatArray
    stiffness: FloatArray
    drive: FloatArray
    ratio: FloatArray
    gearbox_damping: FloatArray
    heat_capacity: FloatArray
    thermal_resistance: FloatArray
    ambient: FloatArray
    eddy: EddyLaw
    heating: bool

    def take(self, index: NDArray[np.intp]) -> Model:
        """The model of a subset of the segments."""
        return Model(
            inertia=self.inertia[index],
            stiffness=self.stiffness[index],
            drive=self.drive[index],
            ratio=self.ratio[index],
            gearbox_damping=self.gearbox_damping[index],
            heat_capacity=self.heat_capacity[index],
            thermal_resistance=self.thermal_resistance[index],
            ambient=self.ambient[index],
            eddy=self.eddy.take(index),
            heating=self.heating,
        )

    def rhs(self, y: FloatArray) -> FloatArray:
        """``dy/dt``, shape (4, n)."""
        x, u, temp = y[0], y[1], y[2]
        shaft = self.ratio * u
        eddy = self.eddy.torque(shaft, temp)
        torque = self.ratio * (eddy + self.gearbox_damping * shaft)
        out = np.empty_like(y)
        out[0] = u
        out[1] = (self.drive - self.stiffness * x - torque) / self.inertia
        if self.heating:
            out[2] = heat.temperature_rate(
                eddy * shaft, temp, self.ambient, self.heat_capacity, self.thermal_resistance
            )
        else:
            out[2] = 0.0
        out[3] = torque * u
        return out

    def jacobian(self, y: FloatArray) -> tuple[FloatArray, ...]:
        """Nonzero entries (j10, j11, j12, j21, j22, j31, j32) of ``df/dy``."""
        u, temp = y[1], y[2]
        n = self.ratio
        shaft = n * u
        eddy = self.eddy.torque(shaft, temp)
        d_speed = self.eddy.speed_derivative(shaft, temp)
        d_temp = self.eddy.temperature_derivative(shaft, temp)
        torque = n * (eddy + self.gearbox_damping * shaft)
        d_torque_du = n * n * (d_speed + self.gearbox_damping)
        d_torque_dtemp = n * d_temp
        j10 = -self.stiffness / self.inertia
        j11 = -d_torque_du / self.inertia
        j12 = -d_torque_dtemp / self.inertia
        if self.heating:
            finite = np.isfinite(self.thermal_resistance)
            conduct = np.where(finite, 1.0 / np.where(finite, self.thermal_resistance, 1.0), 0.0)
            j21 = n * (d_speed * shaft + eddy) / self.heat_capacity
            j22 = (d_temp * shaft - conduct) / self.heat_capacity
        else:
            j21 = np.zeros_like(u)
            j22 = np.zeros_like(u)
        j31 = torque + d_torque_du * u
        j32 = d_torque_dtemp * u
        return j10, j11, j12, j21, j22, j31, j32


class _Solver:
    """``(I - c J) z = r`` for the sparsity of :meth:`Model.jacobian`, many right-hand sides."""

    def __init__(self, jac: tuple[FloatArray, ...], c: FloatArray) -> None:
        j10, j11, j12, j21, j22, j31, j32 = jac
        self.c = c
        self.jac = jac
        self.den2 = 1.0 - c * j22
        safe2 = np.where(self.den2 != 0.0, self.den2, 1.0)
        self.den1 = 1.0 - c * j11 - c * c * j10 - c * c * j12 * j21 / safe2
        self.ok = (np.abs(self.den2) > 1e-12) & (np.abs(self.den1) > 1e-12)
        self.safe1 = np.where(self.ok, self.den1, 1.0)
        self.safe2 = np.where(self.ok, self.den2, 1.0)

    def solve(self, r: FloatArray) -> FloatArray:
        """z with ``(I - c J) z = r``; r and z of shape (4, n)."""
        j10, _, j12, j21, _, j31, j32 = self.jac
        c = self.c
        z = np.empty_like(r)
        z[1] = (r[1] + c * j10 * r[0] + c * j12 * r[2] / self.safe2) / self.safe1
        z[0] = r[0] + c * z[1]
        z[2] = (r[2] + c * j21 * z[1]) / self.safe2
        z[3] = r[3] + c * (j31 * z[1] + j32 * z[2])
        return z


def _step(
    model: Model, y: FloatArray, f0: FloatArray, h: FloatArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """One RODAS4 step: new state, error estimate, and where the linear solve was sound."""
    solver = _Solver(model.jacobian(y), h * GAMMA)
    hg = h * GAMMA
    stages = [solver.solve(hg * f0)]
    scratch = np.empty_like(y)
    for i in range(1, 6):
        stage_y = y.copy()
        coupling = np.zeros_like(y)
        for a, c, k in zip(A[i], C[i], stages, strict=True):
            if a != 0.0:
                np.multiply(k, a, out=scratch)
                stage_y += scratch
            np.multiply(k, c, out=scratch)
            coupling += scratch
        value = model.rhs(stage_y)
        value *= hg
        coupling *= GAMMA
        value += coupling
        stages.append(solver.solve(value))
    y1 = y.copy()
    for m, k in zip(M, stages, strict=True):
        np.multiply(k, m, out=scratch)
        y1 += scratch
    return y1, stages[5], solver.ok  # E = (0, 0, 0, 0, 0, 1)


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


def _bisect(func: Callable[[FloatArray], FloatArray], n: int) -> FloatArray:
    """First sign change of func(s) on [0, 1] (func(0) and func(1) differ in sign)."""
    lo = np.zeros(n)
    hi = np.ones(n)
    start = func(lo) > 0.0
    for _ in range(48):  # 2^-48 of a step: below rounding of the event time
        mid = 0.5 * (lo + hi)
        same = (func(mid) > 0.0) == start
        lo = np.where(same, mid, lo)
        hi = np.where(same, hi, mid)
    return hi


@dataclass(frozen=True)
class _Span:
    """The accepted steps of one iteration: end states and slopes, for interpolation."""

    y0: FloatArray
    f0: FloatArray
    y1: FloatArray
    f1: FloatArray
    h: FloatArray

    def value(self, row: int, s: FloatArray, i: NDArray[np.intp]) -> FloatArray:
        """Component ``row`` at fractions s of the steps of cases i."""
        return _hermite(
            self.y0[row, i], self.f0[row, i], self.y1[row, i], self.f1[row, i], self.h[i], s
        )

    def crossing(self, row: int, target: FloatArray, i: NDArray[np.intp]) -> FloatArray:
        """Fraction of the step where component ``row`` crosses ``target`` (cases i)."""

        def gap(s: FloatArray) -> FloatArray:
            return self.value(row, s, i) - target

        return _bisect(gap, i.size)

    def domain_crossing(self, law: EddyLaw, i: NDArray[np.intp]) -> FloatArray:
        """Fraction of the step where the damping law's domain margin reaches 0."""

        def margin(s: FloatArray) -> FloatArray:
            return law.domain_margin(self.value(2, s, i))

        return _bisect(margin, i.size)

    def turning_point(self, row: int, i: NDArray[np.intp]) -> FloatArray:
        """Fraction of the step where component ``row`` has a zero derivative."""

        def slope(s: FloatArray) -> FloatArray:
            return _hermite_slope(
                self.y0[row, i], self.f0[row, i], self.y1[row, i], self.f1[row, i], self.h[i], s
            )

        return _bisect(slope, i.size)


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
    """Per segment: kind (linear's codes, HORIZON, DOMAIN), duration, end state, extremes."""

    kind: NDArray[np.int8]
    duration: FloatArray
    state: FloatArray  # (4, n)
    max_speed: FloatArray
    max_temperature: FloatArray
    trajectories: list[Trajectory | None]


def integrate_batch(
    model: Model,
    y0: FloatArray,
    length: FloatArray,
    cap: FloatArray,
    horizon: float,
    creep_speed: FloatArray,
    creeps: BoolArray,
    atol: FloatArray,
    rtol: float,
    first_step: FloatArray,
    record: bool,
    horizon_kind: int,
    domain_kind: int,
) -> Outcome:
    """Integrate every segment from ``y0`` (4, n) to its first event; see the module doc.

    Events: x reaches ``length`` (REACH), u falls to 0 (ZERO), u falls to
    ``creep_speed`` where ``creeps`` (REST), the damping law's domain margin falls to 0
    when heating (``domain_kind``), the time reaches ``cap`` (CAP) or ``horizon``
    (``horizon_kind``).
    """
    n = y0.shape[1]
    kind = np.full(n, -1, dtype=np.int8)
    duration = np.zeros(n)
    final = y0.copy()
    max_speed = y0[1].copy()
    max_temp = y0[2].copy()
    steps: list[tuple[NDArray[np.intp], FloatArray, FloatArray, FloatArray]] = []

    work = np.arange(n)
    sub = model
    tol = atol.copy()
    y = y0.copy()
    f = sub.rhs(y)
    t = np.zeros(n)
    h = np.minimum(first_step, np.where(np.isfinite(cap), cap, np.inf))
    end = np.minimum(cap, horizon)
    if record:
        steps.append((work.copy(), t.copy(), y.copy(), f.copy()))
    for _ in range(MAX_STEPS):
        if work.size == 0:
            break
        h = np.minimum(h, end[work] - t)
        y1, error, sound = _step(sub, y, f, h)
        scale = tol + rtol * np.maximum(np.abs(y), np.abs(y1))
        err = np.max(np.abs(error) / scale, axis=0)
        finite = np.all(np.isfinite(y1), axis=0) & np.isfinite(err)
        accept = sound & finite & (err <= 1.0)
        factor = np.where(
            finite & sound,
            np.clip(0.9 * np.maximum(err, 1e-10) ** ERROR_EXPONENT, 0.2, 5.0),
            0.25,
        )
        h_next = h * factor
        if not np.any(accept):
            h = h_next
            continue
        every = bool(np.all(accept))
        acc = np.arange(work.size) if every else np.flatnonzero(accept)
        ya, yb, ha = (y, y1, h) if every else (y[:, acc], y1[:, acc], h[acc])
        fa = f if every else f[:, acc]
        sub_acc = sub if every else sub.take(acc)
        fb = sub_acc.rhs(yb)
        glob = work[acc]
        span = _Span(ya, fa, yb, fb, ha)
        event_s = np.full(acc.size, np.inf)
        event_kind = np.full(acc.size, -1, dtype=np.int8)
        level = length[glob]
        crossings = [
            (linear.REACH, 0, level, (ya[0] < level) & (yb[0] >= level)),
            (linear.ZERO, 1, np.zeros(acc.size), (ya[1] > 0.0) & (yb[1] <= 0.0)),
            (
                linear.REST,
                1,
                creep_speed[glob],
                creeps[glob] & (ya[1] > creep_speed[glob]) & (yb[1] <= creep_speed[glob]),
            ),
        ]
        for code, row, target, crossed in crossings:
            hit = np.flatnonzero(crossed)
            if hit.size:
                _earliest(event_s, event_kind, hit, span.crossing(row, target[hit], hit), code)
        if model.heating:
            margin_a = sub_acc.eddy.domain_margin(ya[2])
            margin_b = sub_acc.eddy.domain_margin(yb[2])
            hit = np.flatnonzero((margin_a > 0.0) & (margin_b <= 0.0))
            if hit.size:
                s_hit = span.domain_crossing(sub_acc.eddy.take(hit), hit)
                _earliest(event_s, event_kind, hit, s_hit, domain_kind)
        ended = event_kind >= 0
        # Extremes: the step's end (or event) value, and an interior maximum where the
        # derivative changes sign from + to - before that point.
        stop = np.where(ended, event_s, 1.0)
        for row, tracker in ((1, max_speed), (2, max_temp)):
            values = yb[row].copy()
            e_idx = np.flatnonzero(ended)
            if e_idx.size:
                values[e_idx] = span.value(row, stop[e_idx], e_idx)
            turning = np.flatnonzero((fa[row] > 0.0) & (fb[row] < 0.0))
            if turning.size:
                s_turn = span.turning_point(row, turning)
                top = span.value(row, s_turn, turning)
                inside = s_turn <= stop[turning]
                values[turning] = np.where(
                    inside, np.maximum(values[turning], top), values[turning]
                )
            tracker[glob] = np.maximum(tracker[glob], values)
        # Finish the cases with an event inside this step.
        if np.any(ended):
            e_idx = np.flatnonzero(ended)
            s_e = event_s[e_idx]
            state = _hermite(ya[:, e_idx], fa[:, e_idx], yb[:, e_idx], fb[:, e_idx], ha[e_idx], s_e)
            codes = event_kind[e_idx]
            state[0] = np.where(codes == linear.REACH, length[glob[e_idx]], state[0])
            state[1] = np.where(codes == linear.ZERO, 0.0, state[1])
            g = glob[e_idx]
            kind[g] = codes
            duration[g] = t[acc[e_idx]] + s_e * ha[e_idx]
            final[:, g] = state
            if record:
                slope = sub_acc.take(e_idx).rhs(state)
                steps.append((g, duration[g].copy(), state, slope))
        # Advance the others; those that reached the cap or the horizon end there.
        go = np.flatnonzero(~ended)
        idx = acc[go]
        t[idx] = t[idx] + ha[go]
        y[:, idx] = yb[:, go]
        f[:, idx] = fb[:, go]
        if record and go.size:
            steps.append((work[idx].copy(), t[idx].copy(), yb[:, go].copy(), fb[:, go].copy()))
        at_end = go[t[idx] >= end[work[idx]] * (1.0 - 1e-15)]
        if at_end.size:
            g = glob[at_end]
            kind[g] = np.where(cap[g] <= horizon, linear.CAP, horizon_kind)
            duration[g] = t[acc[at_end]]
            final[:, g] = yb[:, at_end]
        h = h_next
        done_now = np.zeros(work.size, dtype=bool)
        done_now[acc[ended]] = True
        done_now[acc[at_end]] = True
        if np.any(done_now):
            keep = np.flatnonzero(~done_now)
            work, y, f, t, h = work[keep], y[:, keep], f[:, keep], t[keep], h[keep]
            tol = tol[:, keep]
            sub = sub.take(keep)
    # Anything still running after MAX_STEPS is reported as cut short.
    if work.size:
        kind[work] = horizon_kind
        duration[work] = t
        final[:, work] = y
    trajectories: list[Trajectory | None] = [None] * n
    if record:
        trajectories = _trajectories(steps, n)
    return Outcome(kind, duration, final, max_speed, max_temp, trajectories)


def _trajectories(
    steps: list[tuple[NDArray[np.intp], FloatArray, FloatArray, FloatArray]], n: int
) -> list[Trajectory | None]:
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

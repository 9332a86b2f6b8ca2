"""The quasi-static deployment with gravity: ``B dphi/dt = L(phi) - W sin(theta_0 + phi)``.

``L`` is the piecewise-linear net drive of the gravity-free problem (spring less the
resistive table, less the friction F), ``W sin(theta_0 + phi)`` the gravity torque of a
ground test (:mod:`ecdsim.physics.gravity`, opposing deployment positive). The net torque
``N(phi)`` is no longer piecewise linear, so the time is the integral

    t(phi) = B * int_0^phi dx / N(x)

taken numerically (issue 16 item 2, "exactly or to a stated 1e-9"):

1. Every piece of ``L`` is cut at the critical points of ``N`` inside it, where
   ``N' = s - W cos(theta_0 + phi) = 0`` (s the piece's slope), found in closed form
   (``theta_0 + phi = +-acos(s / W) + 2 pi k``). On each resulting sub-interval ``N`` is
   smooth and monotone, so its extremes are at sub-interval ends.
2. Stall: the first sub-interval whose end value is <= 0 holds the first zero of ``N``
   (or the start does); the zero is found by a bracketed, safeguarded Newton iteration
   to the last bit (:func:`_first_zero`). There the time diverges (logarithmically for a
   simple zero, faster for a tangent one): the case is flagged stalled, time +inf.
3. Otherwise ``int dx / N`` is summed over the sub-intervals by vectorised adaptive
   Gauss-Kronrod (7-15 points, QUADPACK's QK15 rule), bisecting every interval whose
   ``|K15 - G7|`` exceeds :data:`RTOL_INTERVAL` times the case's running integral in
   proportion to its width. ``|K15 - G7|`` bounds the error of G7, the K15 value is
   much better still, so the time is accurate to 1e-9 relative (stated, tested against
   ``scipy.integrate.quad`` at 1e-13).

The gravity-free path (:mod:`ecdsim.solvers.exact` and its kernels) is not touched:
only problems that carry a gravity torque come here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim.physics.gravity import gravity_torque, gravity_torque_slope
from ecdsim.solvers.base import (
    DeploymentSolution,
    QuasiStaticProblem,
    Trajectory,
    mark_unsolved,
    undamped_cases,
)

# QUADPACK QK15: Kronrod nodes (positive half, centre last) and weights, and the
# weights of the embedded 7-point Gauss rule (on the odd Kronrod nodes).
_XGK = np.array(
    [
        0.991455371120812639206854697526329,
        0.949107912342758524526189684047851,
        0.864864423359769072789712788640926,
        0.741531185599394439863864773280788,
        0.586087235467691130294144845693013,
        0.405845151377397166906606412076961,
        0.207784955007898467600689403773245,
        0.0,
    ]
)
_WGK = np.array(
    [
        0.022935322010529224963732008058970,
        0.063092092629978553290700663189204,
        0.104790010322250183839876322541518,
        0.140653259715525918745189590510238,
        0.169004726639267902826583426598550,
        0.190350578064785409913256402421014,
        0.204432940075298892414161999234649,
        0.209482141084727828012999174891714,
    ]
)
_WG = np.array(
    [
        0.129484966168869693270611432679082,
        0.279705391489276667901467771423780,
        0.381830050505118944950369775488975,
        0.417959183673469387755102040816327,
    ]
)
# The 15 nodes on [-1, 1] and both rules' weights on them (G7 is zero on the even nodes).
NODES = np.concatenate([-_XGK[:-1], _XGK[::-1]])
KRONROD_WEIGHTS = np.concatenate([_WGK[:-1], _WGK[::-1]])
_G_ON_K = np.zeros(8)
_G_ON_K[1::2] = _WG  # nodes 0.949..., 0.741..., 0.405..., 0 (the centre)
GAUSS_WEIGHTS = np.concatenate([_G_ON_K[:-1], _G_ON_K[::-1]])

IndexArray = NDArray[np.intp]

# Error target of one interval, relative to its case's integral and in proportion to its
# width: 1e-11, a hundred times below the stated 1e-9 (|K15 - G7| overestimates K15's
# error by orders of magnitude on smooth integrands).
RTOL_INTERVAL = 1e-11
STATED_RTOL = 1e-9
# Bisection levels of the adaptive quadrature: a near-tangent minimum of N of depth d
# needs about log2(travel / sqrt(d)) levels; 60 reach below float resolution.
MAX_LEVELS = 60


@dataclass(frozen=True)
class Profile:
    """The net torque ``N`` of a flattened batch, cut into monotone sub-intervals.

    Arrays of sub-intervals have shape (n_sub, n_cases), in order of angle; on each,
    ``N(x) = base + slope * (x - start) - W sin(theta_0 + x)``.
    """

    left: FloatArray
    right: FloatArray
    base: FloatArray
    start: FloatArray
    slope: FloatArray
    amplitude: FloatArray
    phase: FloatArray
    net_left: FloatArray
    net_right: FloatArray

    def net(self, x: FloatArray, index: tuple[FloatArray, ...] | slice = slice(None)) -> FloatArray:
        """``N`` at ``x`` on the sub-intervals selected by ``index`` [N*m]."""
        return net_torque(
            x,
            self.base[index],
            self.start[index],
            self.slope[index],
            np.broadcast_to(self.amplitude, self.base.shape)[index],
            np.broadcast_to(self.phase, self.base.shape)[index],
        )


def net_torque(
    x: FloatArray,
    base: FloatArray,
    start: FloatArray,
    slope: FloatArray,
    amplitude: FloatArray,
    phase: FloatArray,
) -> FloatArray:
    """``N(x) = base + slope (x - start) - W sin(theta_0 + x)`` [N*m]: drive less friction,
    less gravity (:func:`ecdsim.physics.gravity.gravity_torque`)."""
    return as_float(base + slope * (x - start) - gravity_torque(x, amplitude, phase))


def profile(
    angles: FloatArray,
    net_torques: FloatArray,
    amplitude: FloatArray,
    phase: FloatArray,
) -> Profile:
    """Cut the net torque into monotone sub-intervals (module docstring, step 1).

    Parameters
    ----------
    angles : breakpoints of the piecewise-linear drive, (n_points, n_cases) [rad]
    net_torques : drive less friction at the breakpoints, (n_points, n_cases) [N*m]
    amplitude : W per case [N*m], >= 0
    phase : theta_0 per case [rad]
    """
    lo = angles[:-1]
    hi = angles[1:]
    length = hi - lo
    positive = length > 0.0
    slope = np.where(
        positive, (net_torques[1:] - net_torques[:-1]) / np.where(positive, length, 1.0), 0.0
    )
    base = net_torques[:-1]
    # Critical points of N inside each piece: cos(theta_0 + x) = slope / W.
    has_gravity = amplitude > 0.0
    ratio = np.where(has_gravity, slope / np.where(has_gravity, amplitude, 1.0), 2.0)
    reachable = np.abs(ratio) <= 1.0
    c = np.arccos(np.clip(ratio, -1.0, 1.0))
    turns = int(np.ceil(float(np.max(length, initial=0.0)) / (2.0 * np.pi))) + 1
    candidates = []
    for root in (c, -c):
        first = np.floor((phase + lo - root) / (2.0 * np.pi))
        for k in range(turns + 1):
            x = root + 2.0 * np.pi * (first + k) - phase
            inside = reachable & (x > lo) & (x < hi)
            candidates.append(np.where(inside, x, hi))
    cuts = np.sort(np.stack([lo, *candidates, hi]), axis=0)  # (n_cut, pieces, cases)
    left = cuts[:-1]
    right = cuts[1:]
    n_cut = left.shape[0]

    def per_piece(values: FloatArray) -> FloatArray:
        return np.broadcast_to(values, (n_cut, *values.shape))

    shape = (n_cut * lo.shape[0], lo.shape[1])
    # Order: piece by piece, each piece's cuts in order (axis 1 first, then axis 0).
    left = np.swapaxes(left, 0, 1).reshape(shape)
    right = np.swapaxes(right, 0, 1).reshape(shape)
    base_s = np.swapaxes(per_piece(base), 0, 1).reshape(shape)
    start_s = np.swapaxes(per_piece(lo), 0, 1).reshape(shape)
    slope_s = np.swapaxes(per_piece(slope), 0, 1).reshape(shape)
    net_left = net_torque(left, base_s, start_s, slope_s, amplitude, phase)
    net_right = net_torque(right, base_s, start_s, slope_s, amplitude, phase)
    return Profile(
        left=left,
        right=right,
        base=base_s,
        start=start_s,
        slope=slope_s,
        amplitude=amplitude,
        phase=phase,
        net_left=net_left,
        net_right=net_right,
    )


def locate_stall(shape: Profile) -> tuple[BoolArray, FloatArray, FloatArray]:
    """The first zero of ``N`` over the travel (module docstring, step 2).

    Returns
    -------
    stalled : True where N reaches zero at or before the end of travel
    stall_angle : its angle [rad], NaN where not stalled
    index : the sub-interval holding it (0 where not stalled), as float for masking
    """
    bad = shape.net_right <= 0.0
    bad[0] |= shape.net_left[0] <= 0.0
    stalled = np.any(bad, axis=0)
    index = np.argmax(bad, axis=0)
    cases = np.arange(bad.shape[1])
    stall_angle = np.full(bad.shape[1], np.nan)
    at_left = stalled & (shape.net_left[index, cases] <= 0.0)
    stall_angle[at_left] = shape.left[index, cases][at_left]
    inside = stalled & ~at_left
    if np.any(inside):
        rows = index[inside]
        cols = cases[inside]
        stall_angle[inside] = _first_zero(shape, rows, cols)
    return stalled, stall_angle, index.astype(float)


def _first_zero(shape: Profile, rows: IndexArray, cols: IndexArray) -> FloatArray:
    """The zero of ``N`` on sub-intervals where ``N(left) > 0 >= N(right)``, to the last bit.

    N is monotone there (step 1), so the bracket holds one zero. Newton steps, replaced
    by bisection when they leave the bracket and on every fourth iteration (so the
    bracket at least halves every four rounds), until the bracket is a few ulp wide.
    """
    index = (rows, cols)
    a = shape.left[index].copy()
    b = shape.right[index].copy()
    base, start, slope = shape.base[index], shape.start[index], shape.slope[index]
    w = np.broadcast_to(shape.amplitude, shape.base.shape)[index]
    ph = np.broadcast_to(shape.phase, shape.base.shape)[index]
    x = 0.5 * (a + b)
    for iteration in range(400):
        n = net_torque(x, base, start, slope, w, ph)
        exact = n == 0.0
        a = np.where(n > 0.0, x, a)
        b = np.where(n < 0.0, x, b)
        a = np.where(exact, x, a)
        b = np.where(exact, x, b)
        if np.all(b - a <= 4.0 * np.spacing(np.maximum(np.abs(a), np.abs(b)))):
            break
        dn = slope - gravity_torque_slope(x, w, ph)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = x - n / dn
        ok = np.isfinite(step) & (step > a) & (step < b) & (iteration % 4 != 3)
        x = np.where(ok, step, 0.5 * (a + b))
    return as_float(np.where(b - a <= 0.0, a, 0.5 * (a + b)))


@dataclass(frozen=True)
class Integral:
    """``int dx / N`` over each case's sub-intervals, and its estimated error bound."""

    value: FloatArray
    error: FloatArray
    converged: BoolArray


def inverse_integral(shape: Profile, cases: BoolArray) -> Integral:
    """``int dx / N(x)`` over every sub-interval of the selected cases (step 3).

    ``cases`` selects cases where N > 0 over the whole travel (not stalled); the others
    get 0. Cases go in blocks of :data:`CASE_BLOCK`; within a block the intervals of all
    its cases are one work list, evaluated together at the 15 Kronrod nodes each round;
    those that meet the tolerance are summed, the others are halved.
    """
    n_cases = shape.left.shape[1]
    value = np.zeros(n_cases)
    error = np.zeros(n_cases)
    converged = np.ones(n_cases, dtype=bool)
    for first in range(0, n_cases, CASE_BLOCK):
        block = slice(first, min(first + CASE_BLOCK, n_cases))
        rows, cols = np.nonzero(np.broadcast_to(cases[block], shape.left[:, block].shape))
        cols_full = cols + first
        coef = (
            shape.base[rows, cols_full],
            shape.start[rows, cols_full],
            shape.slope[rows, cols_full],
            np.broadcast_to(shape.amplitude, shape.left.shape)[rows, cols_full],
            np.broadcast_to(shape.phase, shape.left.shape)[rows, cols_full],
        )
        found = _integrate_block(
            shape.left[rows, cols_full], shape.right[rows, cols_full], cols, coef, block
        )
        value[block], error[block], converged[block] = found
    return Integral(value=value, error=error, converged=converged)


# Cases per block of the adaptive quadrature, and the most open intervals a block may
# hold (15 nodes each: 120 MB of float64 at most, whatever the integrand).
CASE_BLOCK = 2048
MAX_OPEN = 1_000_000


def _integrate_block(
    lo: FloatArray,
    hi: FloatArray,
    case: IndexArray,
    coef: tuple[FloatArray, ...],
    block: slice,
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Adaptive K15 on intervals [lo, hi] of the block's cases (indices ``case``)."""
    n_cases = block.stop - block.start
    span = np.zeros(n_cases)
    np.add.at(span, case, hi - lo)
    value = np.zeros(n_cases)
    error = np.zeros(n_cases)
    estimate = np.zeros(n_cases)
    converged = np.ones(n_cases, dtype=bool)
    eps = np.finfo(float).eps
    for level in range(MAX_LEVELS + 1):
        if case.size == 0:
            break
        half = 0.5 * (hi - lo)
        mid = 0.5 * (hi + lo)
        x = mid[:, None] + half[:, None] * NODES[None, :]
        net = net_torque(x, *(c[:, None] for c in coef))
        # N <= 0 only on a trajectory's cell at a stall (the time there is infinite).
        f = np.where(net > 0.0, 1.0 / np.where(net > 0.0, net, 1.0), np.inf)
        empty = half <= 0.0
        kronrod = np.where(empty, 0.0, half * (f @ KRONROD_WEIGHTS))
        gauss = np.where(empty, 0.0, half * (f @ GAUSS_WEIGHTS))
        err = np.where(np.isfinite(kronrod), np.abs(kronrod - gauss), 0.0)
        # The case's integral so far (accepted plus every open interval's K15 value).
        estimate[:] = value
        np.add.at(estimate, case, kronrod)
        share = np.where(
            span[case] > 0.0, (hi - lo) / np.where(span[case] > 0.0, span[case], 1.0), 0.0
        )
        # Accepted: the error within RTOL_INTERVAL of the interval's own integral (the
        # integrand is positive, so these sum to RTOL_INTERVAL of the case's), or of its
        # width's share of the case's; or below the rounding of N itself (each N carries
        # about eps * (|base| + |slope| |x - start| + W) absolute, relative eps * that / N
        # in 1/N), which no refinement can beat near a grazing minimum.
        base, start, slope, amplitude = coef[0], coef[1], coef[2], coef[3]
        scale = np.abs(base) + np.abs(slope) * np.maximum(np.abs(hi - start), np.abs(lo - start))
        scale = scale + np.abs(amplitude)
        with np.errstate(invalid="ignore", over="ignore"):
            rounding = 50.0 * eps * scale * np.abs(half) * ((f * f) @ KRONROD_WEIGHTS)
        target = RTOL_INTERVAL * np.maximum(np.abs(kronrod), np.abs(estimate[case]) * share)
        done = (err <= target) | (err <= rounding) | (half <= 4.0 * np.spacing(np.abs(mid)))
        if level == MAX_LEVELS or 2 * np.count_nonzero(~done) > MAX_OPEN:
            converged[np.unique(case[~done])] = False
            done[:] = True
        np.add.at(value, case[done], kronrod[done])
        np.add.at(error, case[done], err[done])
        keep = ~done
        lo, hi, mid, case = lo[keep], hi[keep], mid[keep], case[keep]
        coef = tuple(c[keep] for c in coef)
        lo, hi = np.concatenate([lo, mid]), np.concatenate([mid, hi])
        case = np.concatenate([case, case])
        coef = tuple(np.concatenate([c, c]) for c in coef)
    return value, error, converged


def peak_net(shape: Profile, stalled: BoolArray, stall_angle: FloatArray) -> FloatArray:
    """Highest ``max(N, 0)`` over the part of the travel covered [N*m].

    N's interior maxima are critical points, which are sub-interval ends (step 1), so
    the maximum over the ends is the maximum over the travel.
    """
    reach = np.where(stalled, stall_angle, np.inf)
    covered_left = shape.left <= reach
    covered_right = shape.right <= reach
    left = np.where(covered_left, np.maximum(shape.net_left, 0.0), 0.0)
    right = np.where(covered_right, np.maximum(shape.net_right, 0.0), 0.0)
    return as_float(np.maximum(left.max(axis=0), right.max(axis=0)))


@dataclass(frozen=True)
class GravitySolution:
    """The flattened answer of :func:`solve_flat`; arrays of shape (n_cases,)."""

    time: FloatArray
    start_speed: FloatArray
    end_speed: FloatArray
    max_speed: FloatArray
    stalled: BoolArray
    stall_angle: FloatArray
    integral: Integral


def flat_inputs(
    problem: QuasiStaticProblem,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """(angles, net torques) as (n_points, n_cases), and W, theta_0, B as (n_cases,)."""
    shape = problem.batch_shape
    n_points = problem.angles.shape[0]
    n = int(np.prod(shape, dtype=np.int64))
    full = (n_points, *shape)
    angles = np.broadcast_to(problem.angles, full).reshape(n_points, n)
    net = np.broadcast_to(problem.net_torques, full).reshape(n_points, n)
    assert problem.gravity_amplitude is not None
    assert problem.gravity_angle is not None
    amplitude = np.broadcast_to(problem.gravity_amplitude, shape).reshape(n)
    phase = np.broadcast_to(problem.gravity_angle, shape).reshape(n)
    damping = np.broadcast_to(problem.damping_rate, shape).reshape(n)
    return as_float(angles), as_float(net), as_float(amplitude), as_float(phase), as_float(damping)


def solve_flat(
    angles: FloatArray,
    net: FloatArray,
    amplitude: FloatArray,
    phase: FloatArray,
    damping: FloatArray,
) -> GravitySolution:
    """Deployment time and speeds of each case with gravity (module docstring).

    Parameters
    ----------
    angles : breakpoints, (n_points, n_cases) [rad]
    net : drive less friction at them (no gravity), (n_points, n_cases) [N*m]
    amplitude : W [N*m]; phase : theta_0 [rad]; damping : B > 0 [N*m*s/rad], (n_cases,)
    """
    shape = profile(angles, net, amplitude, phase)
    stalled, stall_angle, _ = locate_stall(shape)
    integral = inverse_integral(shape, ~stalled)
    time = np.where(stalled, np.inf, damping * integral.value)
    start = np.maximum(shape.net_left[0], 0.0) / damping
    end = np.where(stalled, 0.0, shape.net_right[-1] / damping)
    peak = peak_net(shape, stalled, stall_angle) / damping
    return GravitySolution(
        time=as_float(time),
        start_speed=as_float(start),
        end_speed=as_float(end),
        max_speed=as_float(peak),
        stalled=stalled,
        stall_angle=as_float(stall_angle),
        integral=integral,
    )


def solve(problem: QuasiStaticProblem, method: str) -> DeploymentSolution:
    """The exact method's answer for a problem with gravity (undamped cases flagged)."""
    problem, undamped = undamped_cases(problem)
    found = solve_flat(*flat_inputs(problem))
    shape = problem.batch_shape
    solution = DeploymentSolution(
        method=method,
        deployment_time=found.time.reshape(shape),
        start_speed=found.start_speed.reshape(shape),
        end_speed=found.end_speed.reshape(shape),
        max_speed=found.max_speed.reshape(shape),
        stalled=found.stalled.reshape(shape),
        stall_angle=found.stall_angle.reshape(shape),
    )
    return mark_unsolved(solution, undamped)


def stall_and_peak(problem: QuasiStaticProblem) -> tuple[BoolArray, FloatArray, FloatArray]:
    """(stalled, stall angle, peak speed) of a problem with gravity, batch-shaped.

    What the paper method shares with the exact one (the stall and the linear-range peak
    are properties of the load, not of a method).
    """
    angles, net, amplitude, phase, damping = flat_inputs(problem)
    shape = profile(angles, net, amplitude, phase)
    stalled, stall_angle, _ = locate_stall(shape)
    peak = peak_net(shape, stalled, stall_angle) / damping
    batch = problem.batch_shape
    return stalled.reshape(batch), stall_angle.reshape(batch), as_float(peak).reshape(batch)


# Cells per monotone sub-interval of the trajectory's time table: a cubic Hermite
# interpolation of phi(t) between them (its derivative N/B is known at every node).
_TRAJECTORY_CELLS = 48


def trajectory(problem: QuasiStaticProblem, times: ArrayLike, method: str) -> Trajectory:
    """Angle and speed against time with gravity; held at the latch after arrival.

    The time at a fine table of angles (each monotone sub-interval in
    ``_TRAJECTORY_CELLS`` cells, each cell by the adaptive quadrature above; a stalled
    case's last sub-interval graded geometrically toward the stall), then ``phi(t)`` by
    cubic Hermite interpolation with the slopes ``N / B``, and the speed ``N(phi) / B``
    (Eq. 5). For plots and time series: the arrival time is :func:`solve`'s.
    """
    safe, undamped = undamped_cases(problem)
    batch = safe.batch_shape
    angles, net, amplitude, phase, damping = flat_inputs(safe)
    shape = profile(angles, net, amplitude, phase)
    stalled, stall_angle, index = locate_stall(shape)
    n_sub, n = shape.left.shape
    cells = _TRAJECTORY_CELLS
    k = np.arange(cells + 1, dtype=float)[:, None, None]
    uniform = k / cells
    graded = 1.0 - 0.5**k  # toward a stall: the last node 2**-48 of the width short
    stall_row = np.arange(n_sub)[:, None] == index[None, :].astype(int)
    in_stall = stall_row & stalled[None, :]
    # A stalled case's table ends at its stall: the sub-intervals beyond shrink onto it.
    beyond = stalled[None, :] & (np.arange(n_sub)[:, None] > index[None, :])
    left = np.where(beyond, stall_angle[None, :], shape.left)
    right = np.where(beyond | in_stall, stall_angle[None, :], shape.right)
    fraction = np.where(in_stall[None], graded, uniform)
    nodes = left[None] + fraction * (right - left)[None]  # (cells+1, n_sub, n)
    # The table of each case in order of angle: sub-interval by sub-interval.
    lo = nodes[:-1].transpose(1, 0, 2).reshape(n_sub * cells, n)
    hi = nodes[1:].transpose(1, 0, 2).reshape(n_sub * cells, n)

    def per_cell(values: FloatArray) -> FloatArray:
        return np.repeat(values, cells, axis=0)

    cell_shape = Profile(
        left=lo,
        right=hi,
        base=per_cell(shape.base),
        start=per_cell(shape.start),
        slope=per_cell(shape.slope),
        amplitude=amplitude,
        phase=phase,
        net_left=np.zeros_like(lo),
        net_right=np.zeros_like(lo),
    )
    # Each cell's integral on its own: one case per cell in the adaptive quadrature.
    flat = Profile(
        left=cell_shape.left.reshape(1, -1),
        right=cell_shape.right.reshape(1, -1),
        base=cell_shape.base.reshape(1, -1),
        start=cell_shape.start.reshape(1, -1),
        slope=cell_shape.slope.reshape(1, -1),
        amplitude=np.broadcast_to(amplitude, lo.shape).reshape(1, -1),
        phase=np.broadcast_to(phase, lo.shape).reshape(1, -1),
        net_left=np.zeros((1, lo.size)),
        net_right=np.zeros((1, lo.size)),
    )
    cell_times = inverse_integral(flat, np.ones(lo.size, dtype=bool)).value.reshape(lo.shape)
    cum = np.concatenate([np.zeros((1, n)), np.cumsum(cell_times, axis=0)]) * damping[None, :]
    table_angle = np.concatenate([lo[:1], hi])
    rate_shape = Profile(
        left=table_angle,
        right=table_angle,
        base=np.concatenate([cell_shape.base[:1], cell_shape.base]),
        start=np.concatenate([cell_shape.start[:1], cell_shape.start]),
        slope=np.concatenate([cell_shape.slope[:1], cell_shape.slope]),
        amplitude=amplitude,
        phase=phase,
        net_left=table_angle,
        net_right=table_angle,
    )
    table_speed = np.maximum(rate_shape.net(table_angle), 0.0) / damping[None, :]
    t = np.asarray(times, dtype=float).reshape(-1)
    found = solve_flat(angles, net, amplitude, phase, damping)
    angle = np.zeros((t.size, n))
    speed = np.zeros((t.size, n))
    for case in range(n):
        column = cum[:, case]
        ok = np.isfinite(column)
        tc, pc, vc = column[ok], table_angle[ok, case], table_speed[ok, case]
        j = np.clip(np.searchsorted(tc, t, side="right") - 1, 0, max(tc.size - 2, 0))
        if tc.size < 2:
            continue
        h = tc[j + 1] - tc[j]
        s = np.clip((t - tc[j]) / np.where(h > 0.0, h, 1.0), 0.0, 1.0)
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        phi = h00 * pc[j] + h10 * h * vc[j] + h01 * pc[j + 1] + h11 * h * vc[j + 1]
        phi = np.clip(phi, pc[0], pc[-1])
        piece = np.clip(
            np.searchsorted(table_angle[:, case], phi, side="right") - 1, 0, lo.shape[0]
        )
        row = np.minimum(piece, cell_shape.base.shape[0] - 1)
        v = net_torque(
            phi,
            cell_shape.base[row, case],
            cell_shape.start[row, case],
            cell_shape.slope[row, case],
            np.full(t.size, amplitude[case]),
            np.full(t.size, phase[case]),
        )
        beyond_table = t >= tc[-1]
        phi = np.where(beyond_table, pc[-1], phi)
        arrived = t >= found.time[case]
        angle[:, case] = np.where(arrived, angles[-1, case], phi)
        speed[:, case] = np.where(arrived, 0.0, np.maximum(v, 0.0) / damping[case])
    angle_b = angle.reshape((t.size, *batch))
    speed_b = speed.reshape((t.size, *batch))
    if np.any(undamped):
        angle_b = np.where(undamped, 0.0, angle_b)
        speed_b = np.where(undamped, 0.0, speed_b)
    return Trajectory(method=method, time=t, angle=angle_b, speed=speed_b)

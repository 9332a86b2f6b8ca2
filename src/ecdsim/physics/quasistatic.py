"""Exact pieces of the quasi-static deployment equation ``B * dphi/dt = T(phi) - F``.

With a damping rate B, a constant resisting friction F and a net torque that is linear in
angle over a segment of length L (net torque a at the segment's start, b at its end), the
equation is linear and first order. Its solution is (derivation in ``docs/model.md``)::

    phi(s)   = phi_0 + (a / B) * s * h(k s / B),   h(y) = (1 - exp(-y)) / y,   k = (a - b) / L
    omega(s) = (a / B) * exp(-k s / B)
    duration = B * L / logmean(a, b),   logmean(a, b) = (a - b) / ln(a / b)

The paper's mean-velocity method (Eq. 10-11) gives ``B * L / ((a + b) / 2)`` instead; since
the logarithmic mean never exceeds the arithmetic mean, the paper method never
overestimates the time.
"""

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float

# Below this relative difference of a and b, the series of the log-mean is used: its
# truncation error (x**3/4 relative) is then below 1e-18, far below float64 resolution.
_SERIES_LIMIT = 1e-6


def log_mean(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Logarithmic mean ``(a - b) / ln(a / b)`` of positive a, b; a where a == b.

    The exact counterpart of the paper's mean of Eq. 10 (derivation in docs/model.md).

    Evaluated stably near a == b. Returns 0 where either argument is <= 0 (the net
    torque has reached zero: the segment can never be completed).

    Parameters
    ----------
    a : first value, net torque at a segment's start [N*m]
    b : second value, net torque at a segment's end [N*m]

    >>> round(float(log_mean(2.0, 1.0)), 12)  # 1 / ln 2
    1.442695040889
    """
    a_arr = np.asarray(a, dtype=float)
    b_arr = np.asarray(b, dtype=float)
    valid = (a_arr > 0.0) & (b_arr > 0.0)
    a_safe = np.where(valid, a_arr, 1.0)
    b_safe = np.where(valid, b_arr, 1.0)
    x = 1.0 - b_safe / a_safe  # relative drop over the segment, x < 1
    small = np.abs(x) < _SERIES_LIMIT
    x_safe = np.where(small, 0.5, x)
    # logmean / a = x / (-ln(1 - x)); series 1 - x/2 - x**2/12 for small |x|. Where b < a/2,
    # 1 - x has lost b/a's digits (and is 0 once b/a < 1e-16: log1p(-1) = -inf), so
    # -ln(1 - x) = ln a - ln b is taken from the logs, which cannot overflow.
    far = b_safe < 0.5 * a_safe
    log_ratio = np.where(
        far, np.log(a_safe) - np.log(b_safe), -np.log1p(-np.where(far, 0.5, x_safe))
    )
    ratio = np.where(small, 1.0 - x / 2.0 - x * x / 12.0, x_safe / log_ratio)
    return np.where(valid, a_safe * ratio, 0.0)


def segment_duration(
    length: ArrayLike, damping_rate: ArrayLike, net_start: ArrayLike, net_end: ArrayLike
) -> FloatArray:
    """Exact time to cross a segment of linear net torque: ``B * L / logmean(a, b)``.

    Eq. 5 with the linear spring of Eq. 7 integrated exactly; the paper's Eq. 11 uses the
    arithmetic mean of a and b instead.

    +inf where the net torque reaches zero within the segment (stall). A zero-length
    segment takes zero time.

    Parameters
    ----------
    length : segment length L [rad]
    damping_rate : B, damping referred to the moving shaft [N*m*s/rad]
    net_start : a, spring torque minus friction at the segment's start [N*m]
    net_end : b, spring torque minus friction at the segment's end [N*m]
    """
    length_arr = np.asarray(length, dtype=float)
    mean = log_mean(net_start, net_end)
    moving = mean > 0.0
    duration = np.asarray(damping_rate, dtype=float) * length_arr / np.where(moving, mean, 1.0)
    blocked = ~moving & (length_arr > 0.0)
    return np.where(blocked, np.inf, np.where(length_arr > 0.0, duration, 0.0))


def _one_minus_exp_over(y: FloatArray) -> FloatArray:
    """``(1 - exp(-y)) / y`` evaluated stably, 1 at y = 0."""
    small = np.abs(y) < 1e-8
    y_safe = np.where(small, 1.0, y)
    return np.where(small, 1.0 - y / 2.0, -np.expm1(-y_safe) / y_safe)


def segment_angle(
    elapsed: ArrayLike, damping_rate: ArrayLike, net_start: ArrayLike, slope: ArrayLike
) -> FloatArray:
    """Angle advanced within a segment after time s: ``(a / B) * s * h(k s / B)``.

    The exact counterpart of the paper's Eq. 13 (``h(y) = (1 - exp(-y)) / y``).

    Parameters
    ----------
    elapsed : time since the segment's start, s [s]
    damping_rate : B [N*m*s/rad]
    net_start : a, net torque at the segment's start [N*m]
    slope : k, decrease of net torque per radian in the segment [N*m/rad]
    """
    s = np.asarray(elapsed, dtype=float)
    b = np.asarray(damping_rate, dtype=float)
    y = np.asarray(slope, dtype=float) * s / b
    # A rising torque (k < 0) makes exp(-y) grow; cap it so that it cannot overflow.
    y = np.maximum(y, -700.0)
    return as_float(np.asarray(net_start, dtype=float) / b * s * _one_minus_exp_over(y))


def segment_speed(
    elapsed: ArrayLike, damping_rate: ArrayLike, net_start: ArrayLike, slope: ArrayLike
) -> FloatArray:
    """Speed within a segment after time s: ``(a / B) * exp(-k s / B)``.

    Eq. 5 along the exact trajectory (speed = net torque / BECD at every instant).

    Parameters
    ----------
    elapsed : time since the segment's start, s [s]
    damping_rate : B [N*m*s/rad]
    net_start : a, net torque at the segment's start [N*m]
    slope : k, decrease of net torque per radian in the segment [N*m/rad]
    """
    b = np.asarray(damping_rate, dtype=float)
    exponent = np.minimum(-np.asarray(slope, dtype=float) * np.asarray(elapsed, float) / b, 700.0)
    return as_float(np.asarray(net_start, dtype=float) / b * np.exp(exponent))


def locate_stall(
    breakpoint_angles: ArrayLike, net_torques: ArrayLike
) -> tuple[BoolArray, FloatArray]:
    """Where a piecewise-linear net torque first falls to zero over the travel.

    Eq. 5 gives zero speed there: the paper's Eq. 8-11 are invalid for such a case.

    A quasi-static mechanism cannot pass the first angle at which spring torque no longer
    exceeds friction. Axis 0 of both arrays runs over the breakpoints.

    Parameters
    ----------
    breakpoint_angles : deployed angles of the breakpoints, increasing along axis 0 [rad]
    net_torques : spring torque minus total friction at each breakpoint [N*m]

    Returns
    -------
    stalled : True where the net torque reaches zero at or before the end of travel
    stall_angle : the first zero of the net torque [rad]; NaN where not stalled (the
        ``stalled`` flag says so; JSON output turns it into null)
    """
    angles = np.asarray(breakpoint_angles, dtype=float)
    net = np.asarray(net_torques, dtype=float)
    angles, net = np.broadcast_arrays(angles, net)
    shape = net.shape[1:]
    stalled = np.zeros(shape, dtype=bool)
    stall_angle = np.full(shape, np.nan)
    at_start = net[0] <= 0.0
    stall_angle = np.where(at_start, angles[0], stall_angle)
    stalled |= at_start
    for i in range(net.shape[0] - 1):
        a, b = net[i], net[i + 1]
        crosses = ~stalled & (a > 0.0) & (b <= 0.0)
        fraction = a / np.where(crosses, a - b, 1.0)
        here = angles[i] + fraction * (angles[i + 1] - angles[i])
        stall_angle = np.where(crosses, here, stall_angle)
        stalled |= crosses
    return stalled, stall_angle

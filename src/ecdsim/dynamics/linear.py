r"""Closed-form solution of one linear segment, ``J x'' + B x' + k x = a``, and its events.

Within a segment the inertia J > 0, damping B >= 0, stiffness k (any sign: the spring
torque falls by k per radian) and net drive a (spring torque minus friction at the
segment's start) are constant, and ``x(0) = 0``, ``x'(0) = w0``. The derivation is in
``docs/dynamics.md``; in short, with ``p = B / 2J``, ``q = k / J`` and ``h**2 = p**2 - q``
(h real: overdamped, imaginary: underdamped, 0: critical), the speed is

    v(t) = e^{-p t} (w0 cosh(h t) + Q sinh(h t) / h),    Q = a / J - p w0,

a solution of the homogeneous equation. Two evaluations are used, each where it is
accurate to a few ulp:

* modal ("far", ``|h| t >= 0.05``): ``v = c1 e^{r1 t} + c2 e^{r2 t}`` with the roots
  ``r2 = -p - h`` and ``r1 = -q / (p + h)`` (Vieta's form: no cancellation when
  ``J / B`` is tiny, the usual ECD case) and ``c1 = (a / J + r1 w0) / 2h``,
  ``c2 = w0 - c1``; ``x = c1 E(r1, t) + c2 E(r2, t)`` with ``E(r, t) = expm1(r t) / r``.
  Complex arithmetic covers the underdamped case.
* series ("near critical", ``|h| t < 0.05``): the bracket is expanded in powers of
  ``h**2 t**2`` (12 terms, truncation below 1e-24) and integrated term by term with
  ``M_j(mu, t) = int_0^t s^j e^{-mu s} ds``, evaluated through the regularised incomplete
  gamma function.

The damping dissipation ``int_0^t v**2 ds`` is integrated in the same two forms. Event
times are closed form (first zero of the speed, via ``atan2``/``artanh``/``log``) or found
by a safeguarded Newton iteration on the closed-form position (reaching a length L).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, BoolArray, FloatArray

ComplexArray = NDArray[np.complex128]

NEAR_CRITICAL = 0.05  # |h| t below which the series form is used
_SERIES_DEGREE = 11  # highest power of t kept in the series of the speed
_SMALL_MU_T = 1e-2  # mu t below which M_j uses its own power series
_EXP_CAP = 700.0  # cap on the real part of exponents (beyond any meaningful time)
_EPS = np.finfo(float).eps
# Slow time constants after which an asymptotic approach to rest has ended in double
# precision (e^-800 underflows): where :func:`rest_time` evaluates its dissipation.
REST_TIME_CONSTANTS = 800.0

# Event kinds returned by :func:`advance`.
REACH = 0  # x reached the segment length
ZERO = 1  # the speed fell to zero
CAP = 2  # the time cap (stop time) came first
REST = 3  # asymptotic approach to rest (infinite time) before reaching the length


@dataclass(frozen=True)
class Segment:
    """Coefficients of ``J x'' + B x' + k x = a``, ``x(0) = 0``, ``x'(0) = w0``, prepared.

    All arrays have the same 1-D shape (one entry per case).

    Attributes
    ----------
    inertia : J [kg*m^2], > 0
    damping : B [N*m*s/rad], >= 0
    stiffness : k [N*m/rad]
    drive : a [N*m]
    speed0 : w0 [rad/s]
    p : B / 2J [1/s]
    q : k / J [1/s^2]
    h2 : p**2 - q [1/s^2]
    h : principal square root of h2 (complex) [1/s]
    r1 : slow root -q / (p + h) [1/s]
    r2 : fast root -p - h [1/s]
    c1, c2 : modal coefficients of the speed [rad/s]
    big_q : Q = a / J - p w0 [rad/s^2]
    overdamped : h2 > 0 (real roots: the modal form needs no complex arithmetic)
    """

    inertia: FloatArray
    damping: FloatArray
    stiffness: FloatArray
    drive: FloatArray
    speed0: FloatArray
    p: FloatArray
    q: FloatArray
    h2: FloatArray
    h: ComplexArray
    r1: ComplexArray
    r2: ComplexArray
    c1: ComplexArray
    c2: ComplexArray
    big_q: FloatArray
    overdamped: BoolArray

    def take(self, index: NDArray[np.intp] | BoolArray) -> Segment:
        """The segments of a subset of cases."""
        return Segment(**{name: getattr(self, name)[index] for name in self.__dataclass_fields__})


def segment(
    inertia: ArrayLike,
    damping: ArrayLike,
    stiffness: ArrayLike,
    drive: ArrayLike,
    speed0: ArrayLike,
) -> Segment:
    """Prepare the closed form of ``J x'' + B x' + k x = a``, ``x(0)=0``, ``x'(0)=w0``.

    Parameters
    ----------
    inertia : J [kg*m^2], > 0
    damping : B [N*m*s/rad], >= 0
    stiffness : k, fall of the drive per radian [N*m/rad]
    drive : a, net torque at x = 0 [N*m]
    speed0 : w0, speed at t = 0 [rad/s]
    """
    j, b, k, a, w0 = np.broadcast_arrays(
        *(
            np.atleast_1d(np.asarray(v, dtype=float))
            for v in (inertia, damping, stiffness, drive, speed0)
        )
    )
    p = b / (2.0 * j)
    q = k / j
    h2 = p * p - q
    h = np.sqrt(h2.astype(complex))
    denominator = p + h
    safe = denominator != 0.0
    r1 = np.where(safe, -q / np.where(safe, denominator, 1.0), 0.0).astype(complex)
    r2 = (-p - h).astype(complex)
    two_h = 2.0 * h
    nonzero = two_h != 0.0
    c1 = np.where(nonzero, (a / j + r1 * w0) / np.where(nonzero, two_h, 1.0), 0.0)
    c2 = w0 - c1
    return Segment(
        inertia=j.copy(),
        damping=b.copy(),
        stiffness=k.copy(),
        drive=a.copy(),
        speed0=w0.copy(),
        p=p,
        q=q,
        h2=h2,
        h=h,
        r1=r1,
        r2=r2,
        c1=c1.astype(complex),
        c2=c2.astype(complex),
        big_q=a / j - p * w0,
        overdamped=h2 > 0.0,
    )


@dataclass(frozen=True)
class SegmentState:
    """Position, speed, acceleration and damping integral at the evaluation times.

    Attributes
    ----------
    x : displacement since the segment's start [rad]
    v : speed [rad/s]
    acceleration : [rad/s^2]
    speed_squared_integral : ``int_0^t v**2 ds``; times B gives the damping dissipation
        [rad^2/s]
    """

    x: FloatArray
    v: FloatArray
    acceleration: FloatArray
    speed_squared_integral: FloatArray


def _phi1(z: ComplexArray) -> ComplexArray:
    """``expm1(z) / z``, 1 at z = 0; the real part of z capped to avoid overflow."""
    z = np.minimum(z.real, _EXP_CAP) + 1j * z.imag
    zero = z == 0.0
    safe = np.where(zero, 1.0, z)
    return np.where(zero, 1.0 + 0.0j, np.expm1(safe) / safe)


def _exp(z: ComplexArray) -> ComplexArray:
    capped: ComplexArray = np.exp(np.minimum(z.real, _EXP_CAP) + 1j * z.imag)
    return capped


def _moments(mu: FloatArray, t: FloatArray, degree: int) -> FloatArray:
    """``M_j(mu, t) = int_0^t s^j e^{-mu s} ds`` for j = 0..degree; shape (degree+1, n).

    ``M_j = j! P(j+1, mu t) / mu^(j+1)`` (P the regularised lower incomplete gamma
    function, Abramowitz and Stegun 6.5.2) for ``mu t >= 0.01``, computed in logarithms so
    that no power overflows; below, the power series ``t^(j+1) sum_n (-mu t)^n / (n!
    (n + j + 1))``, whose 9th term is below 1e-21.
    """
    orders = np.arange(degree + 1, dtype=float)[:, None]
    mt = mu * t
    small = mt < _SMALL_MU_T
    everywhere = bool(np.all(small))
    # Power series (also covers mu = 0); each form is skipped where no case needs it.
    if not np.any(small):
        return _gamma_moments(mu, mt, orders, small)
    series = np.zeros((degree + 1, mt.size))
    term = np.ones_like(mt)
    for n_term in range(9):
        series += term / (n_term + orders + 1.0)
        term = term * (-mt) / (n_term + 1.0)
    with np.errstate(divide="ignore", over="ignore", under="ignore"):
        tpow = np.exp((orders + 1.0) * np.log(np.where(t > 0.0, t, 1.0)))
    by_series = np.where(t > 0.0, tpow * series, 0.0)
    if everywhere:
        return by_series
    return np.where(small, by_series, _gamma_moments(mu, mt, orders, small))


def _gamma_moments(
    mu: FloatArray, mt: FloatArray, orders: FloatArray, small: BoolArray
) -> FloatArray:
    """``j! P(j+1, mu t) / mu^(j+1)`` of :func:`_moments` (its values where small are
    placeholders)."""
    from scipy.special import gammainc, gammaln

    safe_mu = np.where(small, 1.0, mu)
    log_scale = gammaln(orders + 1.0) - (orders + 1.0) * np.log(safe_mu)
    return np.asarray(
        np.exp(np.minimum(log_scale, _EXP_CAP)) * gammainc(orders + 1.0, np.where(small, 1.0, mt))
    )


def _series_coefficients(seg: Segment, h2: FloatArray) -> FloatArray:
    """Coefficients beta_j of ``e^{pt} v(t) = sum_j beta_j t^j``; shape (degree+1, n)."""
    beta = np.zeros((_SERIES_DEGREE + 1, h2.size))
    even = seg.speed0.copy()
    odd = seg.big_q.copy()
    for j in range(0, _SERIES_DEGREE + 1, 2):
        beta[j] = even
        if j + 1 <= _SERIES_DEGREE:
            beta[j + 1] = odd
        even = even * h2 / ((j + 1) * (j + 2))
        odd = odd * h2 / ((j + 2) * (j + 3))
    return beta


def _near(seg: Segment, t: FloatArray, energy: bool) -> tuple[FloatArray, ...]:
    """Series evaluation (x, v, acceleration, int v**2) for near-critical points."""
    beta = _series_coefficients(seg, seg.h2)
    p = seg.p
    x = np.sum(beta * _moments(p, t, _SERIES_DEGREE), axis=0)
    powers = np.ones_like(beta)
    for j in range(1, _SERIES_DEGREE + 1):
        powers[j] = powers[j - 1] * t
    decay = np.exp(-p * t)
    poly = np.sum(beta * powers, axis=0)
    orders = np.arange(1, _SERIES_DEGREE + 1, dtype=float)[:, None]
    dpoly = np.sum(beta[1:] * orders * powers[:-1], axis=0)
    v = decay * poly
    acc = decay * (dpoly - p * poly)
    if not energy:
        return x, v, acc, np.zeros_like(x)
    degree = 2 * _SERIES_DEGREE
    gamma = np.zeros((degree + 1, t.size))
    for i in range(_SERIES_DEGREE + 1):
        gamma[i : i + _SERIES_DEGREE + 1] += beta[i] * beta
    v2 = np.sum(gamma * _moments(2.0 * p, t, degree), axis=0)
    return x, v, acc, v2


def _phi1_real(z: FloatArray) -> FloatArray:
    """``expm1(z) / z`` for real z, 1 at z = 0, z capped at 700."""
    z = np.minimum(z, _EXP_CAP)
    zero = z == 0.0
    safe = np.where(zero, 1.0, z)
    return np.where(zero, 1.0, np.expm1(safe) / safe)


def _modal_real(seg: Segment, time: FloatArray, energy: bool) -> tuple[FloatArray, ...]:
    """Modal form in real arithmetic (overdamped segments)."""
    r1, r2 = seg.r1.real, seg.r2.real
    c1, c2 = seg.c1.real, seg.c2.real
    z1 = r1 * time
    z2 = r2 * time
    e1 = np.exp(np.minimum(z1, _EXP_CAP))
    e2 = np.exp(z2)  # r2 < 0: never overflows
    v = c1 * e1 + c2 * e2
    x = time * (c1 * _phi1_real(z1) + c2 * _phi1_real(z2))
    acc = c1 * r1 * e1 + c2 * r2 * e2
    if energy:
        v2 = time * (
            c1 * c1 * _phi1_real(2.0 * z1)
            + 2.0 * c1 * c2 * _phi1_real(z1 + z2)
            + c2 * c2 * _phi1_real(2.0 * z2)
        )
    else:
        v2 = np.zeros_like(x)
    return x, v, acc, v2


def _modal_complex(seg: Segment, time: FloatArray, energy: bool) -> tuple[FloatArray, ...]:
    """Modal form in complex arithmetic (any segment; needed when underdamped)."""
    r1, r2, c1, c2 = seg.r1, seg.r2, seg.c1, seg.c2
    e1 = _exp(r1 * time)
    e2 = _exp(r2 * time)
    v = (c1 * e1 + c2 * e2).real
    x = (c1 * time * _phi1(r1 * time) + c2 * time * _phi1(r2 * time)).real
    acc = (c1 * r1 * e1 + c2 * r2 * e2).real
    if energy:
        v2 = (
            c1 * c1 * time * _phi1(2.0 * r1 * time)
            + 2.0 * c1 * c2 * time * _phi1((r1 + r2) * time)
            + c2 * c2 * time * _phi1(2.0 * r2 * time)
        ).real
    else:
        v2 = np.zeros_like(x)
    return x, v, acc, v2


def evaluate(seg: Segment, t: ArrayLike, energy: bool = True) -> SegmentState:
    """The segment's state at times t >= 0 (finite), t broadcasting against the cases.

    Parameters
    ----------
    seg : the prepared segments (1-D over cases)
    t : times since the segment's start [s]; shape (n,) or (m, n)
    energy : also compute ``int_0^t v**2 ds`` (skip it in root finding)
    """
    time = np.asarray(t, dtype=float)
    shape = np.broadcast_shapes(time.shape, seg.p.shape)
    if time.shape != shape or seg.p.shape != shape:
        index = np.broadcast_to(np.arange(seg.p.size), shape).reshape(-1)
        flat = evaluate(seg.take(index), np.broadcast_to(time, shape).reshape(-1), energy)
        return SegmentState(
            x=flat.x.reshape(shape),
            v=flat.v.reshape(shape),
            acceleration=flat.acceleration.reshape(shape),
            speed_squared_integral=flat.speed_squared_integral.reshape(shape),
        )
    near = np.sqrt(np.abs(seg.h2)) * time < NEAR_CRITICAL
    real = seg.overdamped & ~near
    if np.all(real):
        x, v, acc, v2 = _modal_real(seg, time, energy)
        return SegmentState(x=x, v=v, acceleration=acc, speed_squared_integral=v2)
    x, v, acc, v2 = (np.zeros(shape) for _ in range(4))
    parts = (
        (real, _modal_real),
        (~real & ~near, _modal_complex),
        (near, _near),
    )
    for mask, method in parts:
        if np.any(mask):
            idx = np.flatnonzero(mask)
            xs, vs, accs, v2s = method(seg.take(idx), time[idx], energy)
            x[idx], v[idx], acc[idx], v2[idx] = xs, vs, accs, v2s
    return SegmentState(x=x, v=v, acceleration=acc, speed_squared_integral=v2)


def _first_zero(
    y0: FloatArray, qy: FloatArray, m1: ComplexArray, m2: ComplexArray, seg: Segment
) -> FloatArray:
    """First t > 0 where ``y = e^{-pt}(y0 cosh ht + qy sinh(ht)/h) = m1 e^{r1 t} + m2 e^{r2 t}``
    vanishes; inf if never. A zero at t = 0 itself (y0 = 0) is skipped.
    """
    flip = (y0 < 0.0) | ((y0 == 0.0) & (qy < 0.0))
    sign = np.where(flip, -1.0, 1.0)
    y0 = y0 * sign
    qy = qy * sign
    m1 = m1 * sign
    m2 = m2 * sign
    result = np.full(y0.shape, np.inf)
    trivial = (y0 == 0.0) & (qy == 0.0)
    under = (seg.h2 < 0.0) & ~trivial
    beta = np.sqrt(np.where(under, -seg.h2, 1.0))
    result = np.where(under, np.arctan2(y0 * beta, -qy) / beta, result)
    over = (seg.h2 >= 0.0) & ~trivial
    h = np.sqrt(np.where(over, seg.h2, 0.0))
    # A root exists iff qy < 0 and h y0 < -qy; for h > 0 the sign of m1 (computed without
    # cancellation) decides, which stays correct very close to the limit y = 1.
    exists = over & (qy < 0.0) & np.where(h > 0.0, m1.real < 0.0, True) & (y0 > 0.0)
    tau0 = y0 / np.where(exists, -qy, 1.0)
    y = h * tau0
    small = y < 0.5
    y_safe = np.where(small & (y > 0.0), y, 0.5)
    artanh_over = np.where(y > 0.0, np.arctanh(y_safe) / y_safe, 1.0)
    ratio = np.where(exists & ~small, -m2.real / np.where(m1.real != 0.0, m1.real, -1.0), 2.0)
    log_form = np.log(np.where(ratio > 1.0, ratio, 2.0)) / np.where(h > 0.0, 2.0 * h, 1.0)
    t_over = np.where(small, tau0 * artanh_over, log_form)
    return np.where(exists, t_over, np.where(over, np.inf, result))


def zero_speed_time(seg: Segment) -> FloatArray:
    """First t > 0 at which the speed is zero [s]; inf if it never is."""
    return _first_zero(seg.speed0, seg.big_q, seg.c1, seg.c2, seg)


def peak_speed_time(seg: Segment) -> FloatArray:
    """First t > 0 at which the acceleration is zero (a speed extremum) [s]; inf if none."""
    a0 = (seg.drive - seg.damping * seg.speed0) / seg.inertia
    da0 = (-seg.damping * a0 - seg.stiffness * seg.speed0) / seg.inertia
    return _first_zero(a0, da0 + seg.p * a0, seg.c1 * seg.r1, seg.c2 * seg.r2, seg)


def limit_position(seg: Segment) -> FloatArray:
    """Where the motion comes to rest asymptotically, if it does without a zero of speed.

    ``a / k`` for k > 0 (the static equilibrium), ``w0 J / B`` for k = a = 0 and B > 0;
    +inf otherwise (the motion does not converge to a finite position).
    """
    q_pos = seg.q > 0.0
    coast = (seg.q == 0.0) & (seg.drive == 0.0) & (seg.p > 0.0)
    eq = seg.drive / np.where(q_pos, seg.stiffness, 1.0)
    glide = seg.speed0 / np.where(coast, 2.0 * seg.p, 1.0)
    return np.where(q_pos, eq, np.where(coast, glide, np.inf))


def rest_time(seg: Segment, time_constants: float = REST_TIME_CONSTANTS) -> FloatArray:
    """``time_constants`` slow time constants of an asymptotically resting segment [s].

    The slow mode decays as ``e^{r1 t}`` (``e^{-2 p t}`` for its coasting case k = a = 0),
    so after ``time_constants / |r1|`` its remaining motion is ``e^-time_constants`` of
    its start. With the default :data:`REST_TIME_CONSTANTS` (800) nothing is left in
    double precision: the dissipation of a segment ending at rest is evaluated there.
    """
    slow = np.where(seg.q > 0.0, np.abs(seg.r1.real), 2.0 * seg.p)
    return time_constants / np.where(slow > 0.0, slow, 1.0)


def _reach_guess(seg: Segment, length: FloatArray) -> FloatArray:
    """A first estimate of the time to reach ``length`` (NaN where none is available).

    Overdamped: once the fast mode has died out, ``x ~ c1 E(r1, t) - c2 / r2``, which is
    solved for t in closed form; otherwise the distance over a speed scale.
    """
    r1, r2 = seg.r1.real, seg.r2.real
    c1, c2 = seg.c1.real, seg.c2.real
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        target = (length + c2 / np.where(r2 != 0.0, r2, -np.inf)) / c1
        slow = np.where(r1 != 0.0, np.log1p(r1 * target) / np.where(r1 != 0.0, r1, 1.0), target)
    modal = seg.overdamped & (c1 > 0.0) & np.isfinite(slow) & (slow > 0.0)
    a_pos = np.maximum(seg.drive, 0.0)
    speeds = np.maximum.reduce(
        [
            np.abs(seg.speed0),
            a_pos / np.where(seg.damping > 0.0, seg.damping, np.inf),
            np.sqrt(2.0 * a_pos * length / seg.inertia),
            np.full(length.shape, 1e-300),
        ]
    )
    plain = length / speeds
    guess = np.where(modal, slow, plain)
    return np.where(np.isfinite(guess) & (guess > 0.0), guess, np.nan)


def _bracket_upper(seg: Segment, length: FloatArray, guess: FloatArray) -> FloatArray:
    """A finite time by which x >= length, for motions that get there without stopping."""
    t = np.where(np.isfinite(guess), 1.5 * guess, 1.0)
    need = evaluate(seg, t, energy=False).x < length
    for _ in range(2100):
        if not np.any(need):
            break
        t = np.where(need, 2.0 * t, t)
        idx = np.flatnonzero(need)
        need[idx] = evaluate(seg.take(idx), t[idx], energy=False).x < length[idx]
    return t


def time_to_reach(seg: Segment, length: FloatArray, upper: FloatArray) -> FloatArray:
    """Time at which x(t) = length, for x increasing until ``upper`` (inf: unbounded).

    Safeguarded Newton iteration from :func:`_reach_guess` (bisection whenever the Newton
    step leaves the bracket), vectorised over the cases; converges to a few ulp of the
    time, usually in two or three iterations.
    """
    guess = _reach_guess(seg, length)
    lo = np.zeros_like(length)
    hi = np.array(upper, dtype=float)
    unbounded = ~np.isfinite(hi)
    if np.any(unbounded):
        idx = np.flatnonzero(unbounded)
        hi[idx] = _bracket_upper(seg.take(idx), length[idx], guess[idx])
    usable = np.isfinite(guess) & (guess > lo) & (guess < hi)
    t = np.where(usable, guess, 0.5 * (lo + hi))
    active = np.ones(length.shape, dtype=bool)
    result = t.copy()
    everything = np.arange(length.size)
    for _ in range(200):
        idx = everything if np.all(active) else np.flatnonzero(active)
        if idx.size == 0:
            break
        sub = seg if idx.size == length.size else seg.take(idx)
        t_i = t[idx]
        state = evaluate(sub, t_i, energy=False)
        f = state.x - length[idx]
        below = f < 0.0
        lo_i = np.where(below, t_i, lo[idx])
        hi_i = np.where(below, hi[idx], t_i)
        lo[idx], hi[idx] = lo_i, hi_i
        v = state.v
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            newton = t_i - f / v
        inside = (v > 0.0) & (newton > lo_i) & (newton < hi_i)
        new = np.where(inside, newton, 0.5 * (lo_i + hi_i))
        done = (
            (f == 0.0)
            | (np.abs(new - t_i) <= 4.0 * _EPS * t_i)
            | (hi_i - lo_i <= 4.0 * _EPS * hi_i)
        )
        result[idx] = np.where(f == 0.0, t_i, new)
        t[idx] = new
        active[idx[done]] = False
    return result


@dataclass(frozen=True)
class Advance:
    """What happened within a segment, per case.

    Attributes
    ----------
    kind : REACH, ZERO, CAP or REST (module constants)
    duration : time spent in the segment [s]; inf for REST
    x : displacement at the end of the segment [rad] (the length exactly for REACH)
    v : speed at the end [rad/s] (0 for ZERO and REST)
    speed_squared_integral : ``int v**2 dt`` over the segment [rad^2/s]
    max_speed : largest speed within the segment [rad/s]
    """

    kind: NDArray[np.int8]
    duration: FloatArray
    x: FloatArray
    v: FloatArray
    speed_squared_integral: FloatArray
    max_speed: FloatArray


def advance(seg: Segment, length: FloatArray, cap: FloatArray) -> Advance:
    """Run each segment until x = length, the speed vanishes, or time ``cap`` passes.

    The motion must start forward: ``w0 > 0``, or ``w0 = 0`` with ``a > 0``. A motion that
    approaches rest asymptotically (at its static equilibrium) before the length ends
    with kind REST and infinite duration.

    Parameters
    ----------
    seg : prepared segments
    length : distance to the segment's end [rad], >= 0
    cap : time available [s], >= 0 (inf for none)
    """
    n = length.shape[0]
    t_zero = zero_speed_time(seg)
    t_hi = np.minimum(t_zero, cap)
    finite_hi = np.isfinite(t_hi)
    x_at_hi = np.full(n, np.inf)
    v_at_hi = np.zeros(n)
    v2 = np.zeros(n)
    bounded = np.flatnonzero(finite_hi)
    if bounded.size:
        at_hi = evaluate(seg.take(bounded), t_hi[bounded], energy=True)
        x_at_hi[bounded] = at_hi.x
        v_at_hi[bounded] = at_hi.v
        v2[bounded] = at_hi.speed_squared_integral
    x_limit = limit_position(seg)
    reach = np.where(finite_hi, x_at_hi >= length, x_limit > length) | (length <= 0.0)
    kind = np.where(finite_hi, np.where(t_zero <= cap, ZERO, CAP), REST).astype(np.int8)
    kind[reach] = REACH
    duration = np.where(finite_hi, t_hi, np.inf)
    x = np.where(finite_hi, x_at_hi, x_limit)
    v = np.where(kind == CAP, v_at_hi, 0.0)
    # Asymptotic rest: the state once the remaining motion is below e^-REST_TIME_CONSTANTS.
    resting = np.flatnonzero(kind == REST)
    if resting.size:
        sub = seg.take(resting)
        v2[resting] = evaluate(sub, rest_time(sub), energy=True).speed_squared_integral
    moving = np.flatnonzero(reach & (length > 0.0))
    if moving.size:
        sub = seg if moving.size == n else seg.take(moving)
        t_reach = time_to_reach(sub, length[moving], t_hi[moving])
        state = evaluate(sub, t_reach, energy=True)
        duration[moving] = t_reach
        v[moving] = state.v
        v2[moving] = state.speed_squared_integral
    instant = np.flatnonzero(reach & (length <= 0.0))
    duration[instant] = 0.0
    v[instant] = seg.speed0[instant]
    v2[instant] = 0.0
    x[reach] = length[reach]
    # Largest speed: at the start, the end, or an interior extremum.
    t_peak = peak_speed_time(seg)
    interior = np.flatnonzero((t_peak > 0.0) & (t_peak < duration))
    v_peak = np.zeros(n)
    if interior.size:
        sub = seg if interior.size == n else seg.take(interior)
        v_peak[interior] = evaluate(sub, t_peak[interior], energy=False).v
    max_speed = np.maximum.reduce([seg.speed0, v, v_peak])
    return Advance(
        kind=kind,
        duration=duration,
        x=x,
        v=v,
        speed_squared_integral=v2,
        max_speed=max_speed,
    )


def homogeneous_zero_time(
    seg: Segment, y0: FloatArray, dy0: FloatArray, m1: ComplexArray, m2: ComplexArray
) -> FloatArray:
    """First t > 0 where a solution of the segment's homogeneous equation vanishes [s].

    ``y = m1 e^{r1 t} + m2 e^{r2 t}`` with ``y(0) = y0``, ``y'(0) = dy0`` (any linear
    combination of the speed and its derivatives is one); inf if it never vanishes. The
    lossy gear's power-flow search (:mod:`ecdsim.dynamics.gearflow`) uses it to split a
    segment where its switching function is monotone.
    """
    return _first_zero(y0, dy0 + seg.p * y0, m1, m2, seg)

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
  ``M_j(mu, t) = int_0^t s^j e^{-mu s} ds`` (:func:`moment`).

The damping dissipation ``int_0^t v**2 ds`` is integrated in the same two forms. Event
times are closed form (first zero of the speed, via ``atan2``/``artanh``/``log``) or found
by a safeguarded Newton iteration on the closed-form position (reaching a length L).
Scalar code, one segment at a time: the dynamic kernel compiles it with numba.

A segment is the tuple ``(J, B, k, a, w0, p, q, h2, h, r1, r2, c1, c2, Q)`` made by
:func:`prepare` (h .. c2 complex).
"""

from __future__ import annotations

import cmath
import math

NEAR_CRITICAL = 0.05  # |h| t below which the series form is used
SERIES_DEGREE = 11  # highest power of t kept in the series of the speed
_SMALL_MU_T = 1e-2  # mu t below which M_j uses its own power series
_EXP_CAP = 700.0  # cap on the real part of exponents (beyond any meaningful time)
_EPS = 2.220446049250313e-16
# Slow time constants after which an asymptotic approach to rest has ended in double
# precision (e^-800 underflows): where :func:`rest_time` evaluates its dissipation.
REST_TIME_CONSTANTS = 800.0
# Outcomes of :func:`advance`.
REACH, ZERO, CAP, REST = 0, 1, 2, 3

Segment = tuple[
    float, float, float, float, float, float, float, float,
    complex, complex, complex, complex, complex, float,
]  # fmt: skip


def prepare(
    inertia: float, damping: float, stiffness: float, drive: float, speed0: float
) -> Segment:
    """The closed form's constants of ``J x'' + B x' + k x = a``, ``x(0)=0``, ``x'(0)=w0``.

    Parameters: J [kg*m^2] > 0, B [N*m*s/rad] >= 0, k (the drive's fall per radian)
    [N*m/rad], a [N*m], w0 [rad/s].
    """
    p = damping / (2.0 * inertia)
    q = stiffness / inertia
    h2 = p * p - q
    h = cmath.sqrt(complex(h2, 0.0))
    denominator = p + h
    r1 = -q / denominator if denominator != 0.0 else complex(0.0, 0.0)
    r2 = -p - h
    c1 = (drive / inertia + r1 * speed0) / (2.0 * h) if h != 0.0 else complex(0.0, 0.0)
    c2 = speed0 - c1
    return (
        inertia, damping, stiffness, drive, speed0, p, q, h2, h, r1, r2, c1, c2,
        drive / inertia - p * speed0,
    )  # fmt: skip


def _expm1_complex(z: complex) -> complex:
    """``e^z - 1`` without cancellation for small |z| (the real part of z capped)."""
    x = min(z.real, _EXP_CAP)
    y = z.imag
    half = math.sin(0.5 * y)
    real = math.expm1(x) * math.cos(y) - 2.0 * half * half
    return complex(real, math.exp(x) * math.sin(y))


def _phi1(z: complex) -> complex:
    """``expm1(z) / z``, 1 at z = 0."""
    if z == 0.0:
        return complex(1.0, 0.0)
    return _expm1_complex(z) / complex(min(z.real, _EXP_CAP), z.imag)


def _phi1_real(z: float) -> float:
    """``expm1(z) / z`` for real z, 1 at z = 0, z capped at 700."""
    z = min(z, _EXP_CAP)
    if z == 0.0:
        return 1.0
    return math.expm1(z) / z


def moment(j: int, mu: float, t: float) -> float:
    """``M_j(mu, t) = int_0^t s^j e^{-mu s} ds`` (mu >= 0, t >= 0).

    ``j! P(j+1, mu t) / mu^(j+1)`` (P the regularised lower incomplete gamma function,
    Abramowitz and Stegun 6.5.2): for ``mu t < 0.01`` the power series
    ``t^(j+1) sum_n (-mu t)^n / (n! (n + j + 1))``; up to ``mu t = j + 21`` the series
    ``t^(j+1) e^{-mu t} sum_k (mu t)^k / ((j+1)...(j+1+k))`` (A&S 6.5.29, all terms
    positive); beyond, ``1 - P`` as the finite sum ``e^{-x} sum_{k<=j} x^k / k!``
    (A&S 6.5.13), each term in logarithms so that nothing overflows.
    """
    if t <= 0.0:
        return 0.0
    x = mu * t
    if x < _SMALL_MU_T:
        series = 0.0
        term = 1.0
        for n in range(9):
            series += term / (n + j + 1.0)
            term *= -x / (n + 1.0)
        return math.exp((j + 1.0) * math.log(t)) * series
    if x < j + 21.0:
        total = 0.0
        term = 1.0 / (j + 1.0)
        for k in range(400):
            total += term
            term *= x / (j + 2.0 + k)
            if term < 1e-17 * total:
                break
        log_front = (j + 1.0) * math.log(t) - x
        return math.exp(min(log_front, _EXP_CAP)) * total
    tail = 0.0
    log_x = math.log(x)
    for k in range(j + 1):
        tail += math.exp(-x + k * log_x - math.lgamma(k + 1.0))
    log_scale = math.lgamma(j + 1.0) - (j + 1.0) * math.log(mu)
    return math.exp(min(log_scale, _EXP_CAP)) * (1.0 - tail)


def _betas(seg: Segment) -> tuple[float, ...]:
    """Coefficients beta_0 .. beta_11 of ``e^{pt} v(t) = sum_j beta_j t^j`` (SERIES_DEGREE
    = 11): ``w0 h^2k / (2k)!`` for j = 2k, ``Q h^2k / (2k+1)!`` for j = 2k + 1, each
    from the one two below (``beta_j = beta_{j-2} h^2 / (j (j - 1))``)."""
    h2 = seg[7]
    b0, b1 = seg[4], seg[13]
    b2, b3 = b0 * h2 / 2.0, b1 * h2 / 6.0
    b4, b5 = b2 * h2 / 12.0, b3 * h2 / 20.0
    b6, b7 = b4 * h2 / 30.0, b5 * h2 / 42.0
    b8, b9 = b6 * h2 / 56.0, b7 * h2 / 72.0
    b10, b11 = b8 * h2 / 90.0, b9 * h2 / 110.0
    return (b0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11)


def _series(seg: Segment, t: float, energy: bool) -> tuple[float, float, float, float]:
    """Series evaluation (x, v, acceleration, int v**2) for near-critical points.

    ``x = sum_j beta_j M_j(p, t)`` and ``int v**2 = sum_n c_n M_n(2p, t)`` with ``c_n =
    sum_{i+k=n} beta_i beta_k`` the coefficients of the squared polynomial. Each sum runs
    from its highest power down, the moments by the backward recurrence ``M_{j-1} = (mu
    M_j + t^j e^{-mu t}) / j`` from one :func:`moment`: a sum of positive terms, as
    accurate as each moment alone, for 2 evaluations of the series rather than 35 (a table
    of short pieces crosses one segment per breakpoint, each evaluated here).
    """
    if t <= 0.0:
        return 0.0, seg[4], seg[13] - seg[5] * seg[4], 0.0
    p = seg[5]
    b = _betas(seg)
    poly = 0.0
    dpoly = 0.0
    for j in range(SERIES_DEGREE, 0, -1):  # Horner: poly(t) and its derivative
        poly = poly * t + b[j]
        dpoly = dpoly * t + j * b[j]
    poly = poly * t + b[0]
    decay = math.exp(-p * t)
    x = _moment_sum(b, SERIES_DEGREE, p, t, decay, False)
    v = decay * poly
    acc = decay * (dpoly - p * poly)
    if not energy:
        return x, v, acc, 0.0
    return x, v, acc, _moment_sum(b, 2 * SERIES_DEGREE, 2.0 * p, t, decay * decay, True)


def _moment_sum(
    b: tuple[float, ...], top: int, mu: float, t: float, decay: float, squared: bool
) -> float:
    """``sum_{j<=top} c_j M_j(mu, t)``, c_j = beta_j, or the squared polynomial's
    coefficients (``squared``); ``decay`` is e^{-mu t}."""
    moment_j = moment(top, mu, t)
    power = t**top  # t^j (afresh where a running quotient would have lost its digits)
    total = 0.0
    for j in range(top, -1, -1):
        if squared:
            c = 0.0
            for i in range(max(0, j - SERIES_DEGREE), min(j, SERIES_DEGREE) + 1):
                c += b[i] * b[j - i]
        else:
            c = b[j]
        total += c * moment_j
        if j > 0:
            moment_j = (mu * moment_j + power * decay) / j
            power = power / t if power > 1e-250 else t ** (j - 1)
    return total


def _modal(seg: Segment, t: float, energy: bool) -> tuple[float, float, float, float]:
    """Modal form (x, v, acceleration, int v**2): real or complex arithmetic."""
    h2, r1, r2, c1, c2 = seg[7], seg[9], seg[10], seg[11], seg[12]
    if h2 > 0.0:  # overdamped: real roots
        a1, a2, b1, b2 = r1.real, r2.real, c1.real, c2.real
        z1 = a1 * t
        z2 = a2 * t
        e1 = math.exp(min(z1, _EXP_CAP))
        e2 = math.exp(min(z2, _EXP_CAP))
        v = b1 * e1 + b2 * e2
        x = t * (b1 * _phi1_real(z1) + b2 * _phi1_real(z2))
        acc = b1 * a1 * e1 + b2 * a2 * e2
        v2 = 0.0
        if energy:
            v2 = t * (
                b1 * b1 * _phi1_real(2.0 * z1)
                + 2.0 * b1 * b2 * _phi1_real(z1 + z2)
                + b2 * b2 * _phi1_real(2.0 * z2)
            )
        return x, v, acc, v2
    w1 = r1 * t
    w2 = r2 * t
    q1 = cmath.exp(complex(min(w1.real, _EXP_CAP), w1.imag))
    q2 = cmath.exp(complex(min(w2.real, _EXP_CAP), w2.imag))
    vc = c1 * q1 + c2 * q2
    xc = c1 * t * _phi1(w1) + c2 * t * _phi1(w2)
    ac = c1 * r1 * q1 + c2 * r2 * q2
    v2c = 0.0
    if energy:
        v2c = (
            c1 * c1 * t * _phi1(2.0 * w1)
            + 2.0 * c1 * c2 * t * _phi1(w1 + w2)
            + c2 * c2 * t * _phi1(2.0 * w2)
        ).real
    return xc.real, vc.real, ac.real, v2c


def evaluate(seg: Segment, t: float, energy: bool) -> tuple[float, float, float, float]:
    """``(x, v, acceleration, int_0^t v**2)`` of the segment at time t >= 0 (finite)."""
    if math.sqrt(abs(seg[7])) * t < NEAR_CRITICAL:
        return _series(seg, t, energy)
    return _modal(seg, t, energy)


def _first_zero(y0: float, qy: float, m1: complex, m2: complex, seg: Segment) -> float:
    """First t > 0 where ``y = e^{-pt}(y0 cosh ht + qy sinh(ht)/h) = m1 e^{r1 t} + m2 e^{r2 t}``
    vanishes; inf if never. A zero at t = 0 itself (y0 = 0) is skipped."""
    if y0 < 0.0 or (y0 == 0.0 and qy < 0.0):
        y0, qy, m1, m2 = -y0, -qy, -m1, -m2
    if y0 == 0.0 and qy == 0.0:
        return math.inf
    h2 = seg[7]
    if h2 < 0.0:
        beta = math.sqrt(-h2)
        return math.atan2(y0 * beta, -qy) / beta
    h = math.sqrt(h2)
    # A root exists iff qy < 0 and h y0 < -qy; for h > 0 the sign of m1 (computed without
    # cancellation) decides, which stays correct very close to the limit y = 1.
    exists = qy < 0.0 and (m1.real < 0.0 if h > 0.0 else True) and y0 > 0.0
    if not exists:
        return math.inf
    tau0 = y0 / -qy
    y = h * tau0
    if y < 0.5:
        return tau0 * (math.atanh(y) / y if y > 0.0 else 1.0)
    ratio = -m2.real / m1.real if m1.real != 0.0 else 2.0
    return math.log(ratio if ratio > 1.0 else 2.0) / (2.0 * h)


def zero_speed_time(seg: Segment) -> float:
    """First t > 0 at which the speed is zero [s]; inf if it never is."""
    return _first_zero(seg[4], seg[13], seg[11], seg[12], seg)


def peak_speed_time(seg: Segment) -> float:
    """First t > 0 at which the acceleration is zero (a speed extremum) [s]; inf if none."""
    j, b, k, a, w0, p = seg[0], seg[1], seg[2], seg[3], seg[4], seg[5]
    a0 = (a - b * w0) / j
    da0 = (-b * a0 - k * w0) / j
    return _first_zero(a0, da0 + p * a0, seg[11] * seg[9], seg[12] * seg[10], seg)


def limit_position(seg: Segment) -> float:
    """Where the motion comes to rest asymptotically without a zero of speed: ``a / k``
    for k > 0, ``w0 J / B`` for k = a = 0 and B > 0, +inf otherwise."""
    k, a, w0, p, q = seg[2], seg[3], seg[4], seg[5], seg[6]
    if q > 0.0:
        return a / k
    if q == 0.0 and a == 0.0 and p > 0.0:
        return w0 / (2.0 * p)
    return math.inf


def rest_time(seg: Segment, time_constants: float) -> float:
    """``time_constants`` slow time constants of an asymptotically resting segment [s]."""
    slow = abs(seg[9].real) if seg[6] > 0.0 else 2.0 * seg[5]
    return time_constants / (slow if slow > 0.0 else 1.0)


def _reach_guess(seg: Segment, length: float) -> float:
    """A first estimate of the time to reach ``length`` (NaN where none is available)."""
    j, b, a, w0, h2 = seg[0], seg[1], seg[3], seg[4], seg[7]
    r1, r2, c1, c2 = seg[9].real, seg[10].real, seg[11].real, seg[12].real
    guess = math.nan
    if h2 > 0.0 and c1 > 0.0:
        target = (length + (c2 / r2 if r2 != 0.0 else 0.0)) / c1
        slow = math.log1p(r1 * target) / r1 if r1 != 0.0 else target
        if math.isfinite(slow) and slow > 0.0:
            guess = slow
    if not guess > 0.0:
        a_pos = max(a, 0.0)
        speed = max(abs(w0), a_pos / b if b > 0.0 else 0.0, math.sqrt(2.0 * a_pos * length / j))
        guess = length / max(speed, 1e-300)
    return guess if math.isfinite(guess) and guess > 0.0 else math.nan


def time_to_reach(seg: Segment, length: float, upper: float) -> float:
    """Time at which x(t) = length, for x increasing until ``upper`` (inf: unbounded):
    Newton's iteration safeguarded by bisection, to a few ulp of the time."""
    guess = _reach_guess(seg, length)
    lo = 0.0
    hi = upper
    if not math.isfinite(hi):
        hi = 1.5 * guess if math.isfinite(guess) else 1.0
        for _ in range(2100):
            if evaluate(seg, hi, False)[0] >= length:
                break
            hi *= 2.0
    t = guess if (math.isfinite(guess) and lo < guess < hi) else 0.5 * (lo + hi)
    for _ in range(200):
        x, v, _, _ = evaluate(seg, t, False)
        f = x - length
        if f == 0.0:
            return t
        if f < 0.0:
            lo = t
        else:
            hi = t
        newton = t - f / v if v > 0.0 else math.nan
        new = newton if (newton > lo and newton < hi) else 0.5 * (lo + hi)
        if abs(new - t) <= 4.0 * _EPS * t or hi - lo <= 4.0 * _EPS * hi:
            return new
        t = new
    return t


def advance(
    seg: Segment, length: float, cap: float
) -> tuple[int, float, float, float, float, float]:
    """Run the segment until x = length, the speed vanishes, or time ``cap`` passes.

    The motion starts forward (``w0 > 0``, or ``w0 = 0`` with ``a > 0``). Returns
    ``(outcome, duration, x, v, int v**2, max speed)``; an asymptotic approach to rest
    before the length is REST, of infinite duration (its dissipation is evaluated after
    :data:`REST_TIME_CONSTANTS` slow time constants).
    """
    w0 = seg[4]
    t_zero = zero_speed_time(seg)
    t_hi = min(t_zero, cap)
    if length <= 0.0:
        return REACH, 0.0, length, w0, 0.0, w0
    if math.isfinite(t_hi):
        x_hi, v_hi, _, v2 = evaluate(seg, t_hi, True)
        reach = x_hi >= length
        kind = ZERO if t_zero <= cap else CAP
        duration, x, v = t_hi, x_hi, (v_hi if kind == CAP else 0.0)
    else:
        x = limit_position(seg)
        reach = x > length
        kind = REST
        duration, v = math.inf, 0.0
        if not reach:
            v2 = evaluate(seg, rest_time(seg, REST_TIME_CONSTANTS), True)[3]
    if reach:
        kind = REACH
        duration = time_to_reach(seg, length, t_hi)
        _, v, _, v2 = evaluate(seg, duration, True)
        x = length
    top = max(w0, v)
    t_peak = peak_speed_time(seg)
    if t_peak > 0.0 and t_peak < duration:
        top = max(top, evaluate(seg, t_peak, False)[1])
    return kind, duration, x, v, v2, top


def homogeneous_zero_time(seg: Segment, y0: float, dy0: float, m1: complex, m2: complex) -> float:
    """First t > 0 where a solution ``m1 e^{r1 t} + m2 e^{r2 t}`` of the segment's
    homogeneous equation with ``y(0) = y0``, ``y'(0) = dy0`` vanishes [s]; inf if never."""
    return _first_zero(y0, dy0 + seg[5] * y0, m1, m2, seg)


# Monotone pieces of the power-flow indicator examined per segment (an underdamped segment
# has one per half period of its oscillation; ECD segments are overdamped: at most two).
_MAX_PIECES = 64
_BISECTIONS = 200


def _indicator(
    seg: Segment, t: float, ideal_damping: float, constant: float, load_inertia: float,
    damper_inertia: float, flow: float,
) -> float:  # fmt: skip
    """``flow (J_L (B_q v + F_q) + J_D (A_0 - k x))`` at time t (:func:`switch_time`)."""
    x, v, _, _ = evaluate(seg, t, False)
    torque = ideal_damping * load_inertia * v - damper_inertia * seg[2] * x
    return flow * (torque + constant)


def switch_time(
    seg: Segment, ideal_damping: float, ideal_friction: float, load_inertia: float,
    damper_inertia: float, load_drive: float, flow: float, horizon: float,
) -> float:  # fmt: skip
    """First time in (0, horizon] at which a lossy gear's power flow reverses [s]; inf if
    it does not.

    In the segment's forward frame the mesh torque has the sign of ``sigma = J_L (B_q v
    + F_q) + J_D (A_0 - k x)`` (:func:`ecdsim.physics.gearing.power_flow_indicator`;
    B_q, F_q the ECD's damping and friction through an ideal gear, A_0 the spring less
    the system friction along the motion). ``sigma' = J_L B_q v' - J_D k v`` solves the
    segment's homogeneous equation, so its zeros are known in closed form: between them
    sigma is monotone, and its first sign change is bracketed exactly and bisected.
    ``flow``: +1 where the segment is forward (sigma >= 0 expected), -1 back-driven.
    """
    j, b, k, a, w0 = seg[0], seg[1], seg[2], seg[3], seg[4]
    constant = load_inertia * ideal_friction + damper_inertia * load_drive
    a0 = (a - b * w0) / j
    da0 = (-b * a0 - k * w0) / j
    y0 = load_inertia * ideal_damping * a0 - damper_inertia * k * w0
    dy0 = load_inertia * ideal_damping * da0 - damper_inertia * k * a0
    m1 = seg[11] * (load_inertia * ideal_damping * seg[9] - damper_inertia * k)
    m2 = seg[12] * (load_inertia * ideal_damping * seg[10] - damper_inertia * k)
    first = homogeneous_zero_time(seg, y0, dy0, m1, m2)
    half_period = math.pi / math.sqrt(-seg[7]) if seg[7] < 0.0 else math.inf
    lo = 0.0
    hi = math.inf
    for piece in range(1, _MAX_PIECES + 1):
        # The end of the piece: the next zero of sigma' or the horizon.
        steps = (piece - 1) * half_period if piece > 1 else 0.0
        boundary = min(first + steps, horizon)
        value = _indicator(
            seg, boundary, ideal_damping, constant, load_inertia, damper_inertia, flow
        )
        if value < 0.0:
            hi = boundary
            break
        if boundary >= horizon:
            break
        lo = boundary
    if not math.isfinite(hi):
        return math.inf
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        value = _indicator(seg, mid, ideal_damping, constant, load_inertia, damper_inertia, flow)
        if value < 0.0:
            hi = mid
        else:
            lo = mid
        if hi - lo <= 4.0 * _EPS * hi:
            break
    return hi

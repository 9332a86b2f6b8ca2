"""The power flow through a lossy gear within a closed-form segment (issue 16 item 5).

With a lossy mesh (:mod:`ecdsim.physics.gearing`) a segment is linear while the power
flows one way: forward (the load drives the damper) the damper side's inertia, damping
and friction reach the input divided by eta_f, back-driven (the damper side's inertia
drives the load) multiplied by eta_b. The flow reverses where the mesh torque
``N tau_out`` changes sign; in a segment's forward frame (x along the motion, v >= 0)
it has the sign of

    sigma(t) = J_L (B_q v + F_q) + J_D (A_0 - k x),

(``ecdsim.physics.gearing.power_flow_indicator``): ``B_q``, ``F_q`` the ECD's damping
and friction as an ideal gear reflects them, ``A_0 - k x`` the spring torque less the
system friction along the motion. ``sigma' = J_L B_q v' - J_D k v`` solves the segment's
homogeneous equation, so its zeros are known in closed form
(:func:`ecdsim.dynamics.linear.homogeneous_zero_time`): between them sigma is monotone,
and the first sign change is bracketed exactly and found by bisection.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics import linear

# Monotone pieces of sigma examined per segment (an underdamped segment has one per half
# period of its oscillation; ECD segments are overdamped and have at most two).
_MAX_PIECES = 64
_BISECTIONS = 200


def switch_time(
    seg: linear.Segment,
    ideal_damping: FloatArray,
    ideal_friction: FloatArray,
    load_inertia: FloatArray,
    damper_inertia: FloatArray,
    load_drive: FloatArray,
    mode: FloatArray,
    horizon: FloatArray,
) -> FloatArray:
    """First time in (0, horizon] at which the power flow reverses [s]; inf if it does not.

    Parameters
    ----------
    seg : the closed-form segments (effective inertia, damping and drive of their mode)
    ideal_damping : B_q = BT_T N^2, the ECD's damping through an ideal gear [N*m*s/rad]
    ideal_friction : F_q = FT_T N [N*m]
    load_inertia : J_L [kg*m^2]
    damper_inertia : J_D referred to the input [kg*m^2]
    load_drive : A_0, spring torque less system friction along the motion at x = 0 [N*m]
    mode : +1 where the segment is forward (sigma >= 0 expected), -1 back-driven
    horizon : end of the segment without a switch [s] (finite)
    """
    n = horizon.shape[0]
    jl, jd, bq = load_inertia, damper_inertia, ideal_damping
    constant = jl * ideal_friction + jd * load_drive

    def sigma(idx: NDArray[np.intp], t: FloatArray) -> FloatArray:
        sub = seg if idx.size == n else seg.take(idx)
        state = linear.evaluate(sub, t, energy=False)
        torque = bq[idx] * jl[idx] * state.v - jd[idx] * seg.stiffness[idx] * state.x
        signed: FloatArray = mode[idx] * (torque + constant[idx])
        return signed

    # sigma' as a homogeneous solution: value and slope at 0, modal coefficients.
    a0 = (seg.drive - seg.damping * seg.speed0) / seg.inertia
    da0 = (-seg.damping * a0 - seg.stiffness * seg.speed0) / seg.inertia
    y0 = jl * bq * a0 - jd * seg.stiffness * seg.speed0
    dy0 = jl * bq * da0 - jd * seg.stiffness * a0
    m1 = seg.c1 * (jl * bq * seg.r1 - jd * seg.stiffness)
    m2 = seg.c2 * (jl * bq * seg.r2 - jd * seg.stiffness)
    first = linear.homogeneous_zero_time(seg, y0, dy0, m1, m2)
    under = seg.h2 < 0.0
    half_period = np.where(under, np.pi / np.sqrt(np.where(under, -seg.h2, 1.0)), np.inf)

    lo = np.zeros(n)
    hi = np.full(n, np.inf)
    searching = np.ones(n, dtype=bool)
    for piece in range(1, _MAX_PIECES + 1):
        idx = np.flatnonzero(searching)
        if idx.size == 0:
            break
        # The end of the piece: the next zero of sigma' (one per half period when
        # underdamped, at most one otherwise), or the horizon.
        if piece == 1:
            boundary = np.minimum(first[idx], horizon[idx])
        else:
            steps = np.where(under[idx], (piece - 1) * half_period[idx], np.inf)
            boundary = np.minimum(first[idx] + steps, horizon[idx])
        crossed = sigma(idx, boundary) < 0.0
        hi[idx[crossed]] = boundary[crossed]
        finished = crossed | (boundary >= horizon[idx])
        lo[idx[~finished]] = boundary[~finished]
        searching[idx[finished]] = False
    found = np.flatnonzero(np.isfinite(hi))
    result = np.full(n, np.inf)
    if found.size == 0:
        return result
    a, b = lo[found], hi[found]
    for _ in range(_BISECTIONS):
        mid = 0.5 * (a + b)
        negative = sigma(found, mid) < 0.0
        b = np.where(negative, mid, b)
        a = np.where(negative, a, mid)
        if np.all(b - a <= 4.0 * np.finfo(float).eps * b):
            break
    result[found] = b
    return result

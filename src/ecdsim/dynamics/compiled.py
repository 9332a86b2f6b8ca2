"""The RODAS4 integrator of :mod:`ecdsim.dynamics.rosenbrock`, compiled per segment (numba).

A second implementation of the same integrator: the same equations
(:class:`ecdsim.dynamics.equations.Model`, here in scalar form), the same RODAS4 tableau,
step-size control, event location on the cubic Hermite interpolant and tracking of the
speed and temperature maxima, applied to one segment at a time in compiled scalar code
instead of to the whole batch in NumPy arrays. Both return the same
:class:`~ecdsim.dynamics.rosenbrock.Outcome`; ``tests/test_dynamics_compiled.py`` checks
them against each other and against a tight scipy reference.

Why: NumPy's per-operation overhead (about a microsecond) dominates a step on a small
batch, so one nonlinear deployment cost more than a scipy ``solve_ivp`` call; compiled,
a step of a 4-state segment costs one to two hundred nanoseconds, and a batch is a loop
over its segments with no array traffic. Inside a segment the state, the stages and the
parameters are tuples of floats held in registers, and the step's helpers are inlined:
numba counts references to every array passed to a function with atomic operations,
which had cost a third of a step.

numba is an optional extra (``pip install ecdsim[numba]``). This module imports it at
once, so it is itself imported only when a nonlinear segment is integrated
(:func:`ecdsim.dynamics.integrate.compiled_kernel`), never at start-up; without numba,
or with ``ECDSIM_NUMBA=0``, the NumPy integrator runs. The kernels are cached on disk
(numba's ``cache=True``): the first run on a machine compiles them (a few seconds).

Sources: RODAS4 (Hairer and Wanner, *Solving ODEs II*, VI.4), the segment equations of
``docs/dynamics.md`` (Eq. 1 of the ECD paper, the Kloss law of Wouterse 1991, Incropera's
lumped heat balance Eq. 5.2 in the log state of :mod:`ecdsim.physics.thermal`).
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable
from typing import Any, TypeVar, cast

import numba
import numpy as np
from numba.np.unsafe.ndarray import to_fixed_tuple as _to_fixed_tuple
from numpy.typing import NDArray

from ecdsim._types import FloatArray
from ecdsim.dynamics import linear
from ecdsim.dynamics.damping import KlossEddy, LinearEddy
from ecdsim.dynamics.equations import SWITCH, Model
from ecdsim.dynamics.rosenbrock import (
    _GC,
    GAMMA,
    MAX_STEPS,
    A,
    Control,
    Outcome,
    Segments,
    Trajectory,
)

__all__ = ["integrate_batch"]

_F = TypeVar("_F", bound=Callable[..., Any])
# Compiled on first call, cached on disk; typed as the identity for mypy.
# NumPy's error model: a division by zero gives inf or NaN as in the NumPy integrator.
_jit = cast("Callable[[_F], _F]", numba.njit(cache=True, nogil=True, error_model="numpy"))
# The step, its stages, the right-hand side and the Jacobian, inlined into their callers
# in numba's IR, so that the step loop is one function in which the segment's constants
# (1/J, ...) are hoisted and the stage values stay in registers (about 25 % faster than
# leaving them to LLVM). The small helpers (tuple arithmetic, the laws, events) are
# plain functions that LLVM inlines as it sees fit: inlining them in the IR as well gave
# no speed and made the first compilation (cold cache) 20 s instead of 9 s.
_inline = cast(
    "Callable[[_F], _F]",
    numba.njit(cache=True, nogil=True, error_model="numpy", inline="always"),
)

# Columns of the per-segment parameter table handed to the kernels.
_J, _K, _DRIVE, _N, _BG, _C, _R, _FA, _COEF, _LAW_A, _LAW_B, _FIXED, _DF, _WS = range(14)
# Two-node heating (issue 16 item 6): the housing's heat capacity and its resistance to
# the mount, used only when the state has the housing row (5 rows).
_CH, _RHE = 14, 15
# A ground test's gravity (issue 16 item 2): W, theta_0 + phi at the segment's start and
# the direction (Model.gravity); W = 0 for none (the kernels skip the term).
_GW, _GP, _GD = 16, 17, 18
# A lossy gear (issue 16 item 5): the mesh factor m on the damper side's torque (1: ideal),
# the power flow whose reversal ends the segment (0: none), J_L, J_D, F_q and a_L of the
# indicator (Model.indicator).
_MESH, _FLOW, _JL, _JD, _FQ, _AL = 19, 20, 21, 22, 23, 24
_COLUMNS = 25
LINEAR_LAW, KLOSS_LAW = 0, 1
_REACH, _ZERO, _CAP, _REST = linear.REACH, linear.ZERO, linear.CAP, linear.REST

# RODAS4's coefficients as module-level floats: numba freezes globals into the compiled
# code as constants. Named one-based as in Hairer and Wanner: stage i's state is
# y + sum_j A_ij K_j, its coupling GAMMA sum_j C_ij K_j (_GC_ij).
_A21 = A[1][0]
_A31, _A32 = A[2]
_A41, _A42, _A43 = A[3]
_A51, _A52, _A53, _A54 = A[4]
_GC21 = _GC[1][0]
_GC31, _GC32 = _GC[2]
_GC41, _GC42, _GC43 = _GC[3]
_GC51, _GC52, _GC53, _GC54 = _GC[4]
_GC61, _GC62, _GC63, _GC64, _GC65 = _GC[5]
# Stiffly accurate: stage 6's weights are stage 5's plus 1 on K5 (y1 = stage 6's + K6).
assert A[5] == (*A[4], 1.0)

# A segment's state in the kernels: (x, u, s, E, housing rise), the last 0 and unused
# with one node. A tuple of floats, not an array: it lives in registers, and neither it
# nor the parameter tuple (:func:`_segment`) takes the atomic reference counting that
# numba applies to every array passed to a function (which cost a third of a step).
State = tuple[float, float, float, float, float]
# A segment's row of the parameter table: a tuple of _COLUMNS floats in the step loop
# (the helpers accept the array row too, as the tests call them).
Params = tuple[float, ...] | FloatArray
# numba's array -> tuple of a length known when compiling (typed here for mypy).
_as_tuple = cast("Callable[[FloatArray, int], tuple[float, ...]]", _to_fixed_tuple)
# A step's linear solve: hg, inv1, inv2, p10, p12, p21, hg j31, hg j32, inv4, p42, p24.
Solve = tuple[float, float, float, float, float, float, float, float, float, float, float]


@_jit
def _exprel(z: float) -> float:
    """``(e^z - 1) / z``, 1 at z = 0 (thermal._exprel)."""
    if z == 0.0:
        return 1.0
    return math.expm1(z) / z


@_jit
def _law(kind: int, a: float, b: float, w: float, f: float) -> tuple[float, ...]:
    """Torque, d/dw, d/df, power over f, and its d/dw and d/df at shaft speed w, factor f.

    Linear (Eq. 1): ``BD f w`` with a = BD. Kloss: ``2 T_p w p / (w^2 + p^2)``, p = b f
    with a = T_p, b = omega_peak_ref (the rational forms of :mod:`ecdsim.physics.rolloff`).
    """
    if kind == 0:
        return a * f * w, a * f, a * w, a * w * w, 2.0 * a * w, 0.0
    p = b * f
    den = w * w + p * p
    if not den > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    scale = 2.0 * a
    # One division: the terms over den and den^2 as products with its reciprocals.
    inv = 1.0 / den
    inv2 = inv * inv
    torque = scale * w * p * inv
    d_speed = scale * p * (p * p - w * w) * inv2
    d_factor = scale * w * (w * w - p * p) * inv2 * b
    power = scale * w * w * inv * b
    common = 2.0 * scale * w * p * inv2
    return torque, d_speed, d_factor, power, common * p * b, -common * w * b * b


@_jit
def _torque(
    kind: int, heating: bool, a: float, b: float, w: float, f: float
) -> tuple[float, float]:
    """:func:`_law`'s torque and (with heating; else 0) power over f: what a stage needs."""
    if kind == 0:
        return a * f * w, a * w * w if heating else 0.0
    p = b * f
    den = w * w + p * p
    if not den > 0.0:
        return 0.0, 0.0
    scale = 2.0 * a
    if not heating:
        return scale * w * p / den, 0.0
    inv = 1.0 / den
    return scale * w * p * inv, scale * w * w * inv * b


# expm1(z) = z P(z), P(z) = sum_k z^k / (k + 1)! for |z| <= 2^-5: eight terms leave out
# z^8 / 9! < 3e-18 relative (below the rounding of a double).
_SMALL = 2.0**-5
_P1, _P2, _P3, _P4, _P5, _P6, _P7 = (1.0 / math.factorial(k + 1) for k in range(1, 8))


@_jit
def _expm1_small(z: float) -> float:
    """``e^z - 1`` for ``|z| <= 2^-5`` (the Taylor polynomial above, in Estrin's order).

    glibc's expm1 takes several times exp's latency, and a stage of a heating segment
    waits on it; this polynomial is as accurate (a few units in the last place) and short.
    """
    z2 = z * z
    low = (1.0 + _P1 * z) + z2 * (_P2 + _P3 * z)
    high = (_P4 + _P5 * z) + z2 * (_P6 + _P7 * z)
    return z * (low + (z2 * z2) * high)


@_jit
def _thermal(par: Params, s: float, cooling: bool) -> tuple[float, float, float]:
    """``f_a e^{cs}``, ``s E(-cs) = (1 - e^{-cs}) / c`` and ``e^{cs}`` at the log state s.

    The damping factor (thermal.damping_factor_from_log) and the cooling's temperature
    rise over f_a (thermal.temperature_from_factor_log) from one ``e^{cs} - 1`` where
    ``|cs| <= 2^-5`` (a damper within about 8 K of its ambient for Eq. 1's c = -0.004/K;
    ``1 + (e^{cs} - 1)`` then keeps every digit of e^{cs}); an exp and an expm1 beyond.
    A stage of a heating segment needs both, so this spares it two library calls.
    Without ``cooling`` (an adiabatic damper, R = inf, or the Jacobian, which reads only
    the factor and e^{cs}) the rise is not used and not computed: 0 in its place, and
    an expm1 less per stage beyond the polynomial's range.
    """
    c = par[_COEF]
    z = c * s
    if abs(z) <= _SMALL:
        grown = _expm1_small(z)
        e = 1.0 + grown
        if not cooling:
            return par[_FA] * e, 0.0, e
        return par[_FA] * e, s if z == 0.0 else grown / (c * e), e
    e = math.exp(z)
    return par[_FA] * e, s * _exprel(-z) if cooling else 0.0, e


@_jit
def _factor(par: Params, heating: bool, s: float) -> float:
    """The damping law's temperature factor ``f_a exp(c s)`` (thermal.damping_factor_from_log).

    Without heating s keeps its start value in every stage (its stages are exactly 0), so
    the factor is the one :func:`_segment` stored at the start: the same number, no exp.
    """
    factor: float = par[_FA] * math.exp(par[_COEF] * s) if heating else par[_FIXED]
    return factor


@_jit
def _stribeck(par: Params, u: float) -> tuple[float, float]:
    """The Stribeck friction above Coulomb and its slope (equations.stribeck_excess)."""
    ratio = u / par[_WS]
    g = par[_DF] * math.exp(-ratio * ratio)
    return g, -2.0 * ratio / par[_WS] * g


@_jit
def _housing_rates(par: Params, s: float, housing: float) -> tuple[float, float]:
    """The two-node terms of :meth:`Model.rhs`: the housing's return into ds/dt
    (thermal.housing_return) and the housing rate (thermal.housing_rate)."""
    c = par[_COEF]
    f = par[_FA] * math.exp(c * s)
    r = par[_R]
    den = r * f * par[_C]
    back = housing / den if math.isfinite(r) and math.isfinite(den) and den > 0.0 else 0.0
    rise = par[_FA] * s * _exprel(c * s)
    gain = (rise - housing) / r if math.isfinite(r) else 0.0
    loss = housing / par[_RHE] if math.isfinite(par[_RHE]) else 0.0
    return back, (gain - loss) / par[_CH]


@_inline
def _slope(par: Params, kind: int, heating: bool, two_node: bool, y: State) -> State:
    """``dy/dt`` of :meth:`Model.rhs` for one segment."""
    u = y[1]
    s = y[2]
    f = par[_FIXED]
    drop = 0.0
    if heating:
        f, drop, _ = _thermal(par, s, math.isfinite(par[_R]))
    shaft = par[_N] * u
    eddy, power = _torque(kind, heating, par[_LAW_A], par[_LAW_B], shaft, f)
    torque = par[_N] * (eddy + par[_BG] * shaft)
    if par[_DF] > 0.0:
        # The Stribeck excess is a speed-dependent torque like the damping (Model.rhs).
        torque = torque + _stribeck(par, u)[0]
    accel = (par[_DRIVE] - par[_K] * y[0]) - (torque if par[_MESH] == 1.0 else par[_MESH] * torque)
    if par[_GW] != 0.0:
        # The gravity torque against the motion (Model.gravity).
        accel = accel - par[_GD] * par[_GW] * math.sin(par[_GP] + par[_GD] * y[0])
    heat = 0.0
    rate = 0.0
    if heating:
        r = par[_R]
        # 1 / R, 1 / J and 1 / C: constants of the segment, hoisted out of the step loop,
        # leaving the stage's chain of dependent operations without their divisions.
        loss = drop * (1.0 / r) if math.isfinite(r) else 0.0
        heat = (power - loss) * (1.0 / par[_C])
        if two_node:
            back, rate = _housing_rates(par, s, y[4])
            heat += back
    return u, accel * (1.0 / par[_J]), heat, torque * u, rate


@_jit
def _rhs(par: FloatArray, kind: int, heating: bool, y: FloatArray, out: FloatArray) -> None:
    """:func:`_slope` on arrays (``y`` and ``out`` of 4 rows, or 5 with two-node heating)."""
    two_node = y.shape[0] > 4
    state = (y[0], y[1], y[2], y[3], y[4] if two_node else 0.0)
    slope = _slope(_as_tuple(par, _COLUMNS), kind, heating, two_node, state)
    for r in range(y.shape[0]):
        out[r] = slope[r]


@_jit
def _housing_jacobian(par: Params, y: State) -> tuple[float, float, float, float]:
    """The two-node entries of :meth:`Model.jacobian` and :meth:`Model.housing_jacobian`:
    (the housing's addition to j22, j24, j42, j44)."""
    c = par[_COEF]
    f = par[_FA] * math.exp(c * y[2])
    r = par[_R]
    den = r * f * par[_C]
    inverse = 1.0 / den if math.isfinite(r) and math.isfinite(den) and den > 0.0 else 0.0
    coupling = 1.0 / r  # 0 where R is inf
    j42 = f * coupling / par[_CH]
    j44 = -(coupling + 1.0 / par[_RHE]) / par[_CH]
    return -c * (y[4] * inverse), inverse, j42, j44


@_inline
def _jacobian(par: Params, kind: int, heating: bool, y: State | FloatArray) -> tuple[float, ...]:
    """Nonzero entries (j10, j11, j12, j21, j22, j31, j32) of :meth:`Model.jacobian`."""
    u = y[1]
    s = y[2]
    n = par[_N]
    c = par[_COEF]
    f = par[_FIXED]
    e = 1.0
    if heating:
        f, _, e = _thermal(par, s, False)
    shaft = n * u
    eddy, d_speed, d_factor, _, by_speed, by_factor = _law(kind, par[_LAW_A], par[_LAW_B], shaft, f)
    torque = n * (eddy + par[_BG] * shaft)
    d_torque_du = n * n * (d_speed + par[_BG])
    d_torque_ds = n * d_factor * (c * f)
    if par[_DF] > 0.0:
        g, slope = _stribeck(par, u)
        torque = torque + g
        d_torque_du = d_torque_du + slope
    j21 = 0.0
    j22 = 0.0
    if heating:
        j21 = n * by_speed / par[_C]
        slope = c * f * by_factor
        r = par[_R]
        if math.isfinite(r):
            slope = slope - 1.0 / e / r  # e^{-cs} / R
        j22 = slope / par[_C]
    j = par[_J]
    stiffness = par[_K]
    if par[_GW] != 0.0:
        stiffness = stiffness + par[_GW] * math.cos(par[_GP] + par[_GD] * y[0])
    mesh = par[_MESH]  # the lossy gear's m on the motion, not on E (Model.jacobian)
    return (
        -stiffness / j,
        -(d_torque_du if mesh == 1.0 else mesh * d_torque_du) / j,
        -(d_torque_ds if mesh == 1.0 else mesh * d_torque_ds) / j,
        j21,
        j22,
        torque + d_torque_du * u,
        d_torque_ds * u,
    )


@_jit
def _solve(heating: bool, two_node: bool, lin: Solve, v: State) -> State:
    """z with ``(I - hg J) z = v``: the elimination of ``rosenbrock._Solver`` (z1 first,
    then z0, z2, z3; with two nodes z4 eliminated from row 2 first)."""
    hg, inv1, inv2, p10, p12, p21, q31, q32, inv4, p42, p24 = lin
    v2 = v[2] + p24 * v[4] if two_node else v[2]
    z1 = v[1] * inv1 + p10 * v[0]
    if not heating:
        # The temperature row of every stage is zero, and so is its solution's.
        return v[0] + hg * z1, z1, v2, v[3] + q31 * z1, 0.0
    z1 += p12 * v2
    z2 = v2 * inv2 + p21 * z1
    z4 = v[4] * inv4 + p42 * z2 if two_node else 0.0
    return v[0] + hg * z1, z1, z2, v[3] + q31 * z1 + q32 * z2, z4


@_jit
def _scaled(a: float, k: State) -> State:
    """``a K``."""
    return a * k[0], a * k[1], a * k[2], a * k[3], a * k[4]


@_jit
def _plus(acc: State, a: float, k: State) -> State:
    """``acc + a K``."""
    return (
        acc[0] + a * k[0],
        acc[1] + a * k[1],
        acc[2] + a * k[2],
        acc[3] + a * k[3],
        acc[4] + a * k[4],
    )


@_inline
def _stage(
    par: Params, kind: int, heating: bool, two_node: bool, lin: Solve, y: State, c: State
) -> State:
    """K_i of the stage whose state is y (``y + sum_j A_ij K_j``) and coupling c
    (``GAMMA sum_j C_ij K_j``): ``(I - hg J) K_i = hg f(y) + c``."""
    hg = lin[0]
    f = _slope(par, kind, heating, two_node, y)
    return _solve(
        heating,
        two_node,
        lin,
        (f[0] * hg + c[0], f[1] * hg + c[1], f[2] * hg + c[2], f[3] * hg + c[3], f[4] * hg + c[4]),
    )


@_inline
def _step(
    par: Params, kind: int, heating: bool, two_node: bool, y: State, f0: State, h: float
) -> tuple[State, State, bool]:
    """One RODAS4 step: (y1, the error estimate K6, whether the linear solve was sound).

    The stage equations and their elimination are those of ``rosenbrock._step`` and
    ``rosenbrock._Solver``.
    """
    hg = h * GAMMA
    j10, j11, j12, j21, j22, j31, j32 = _jacobian(par, kind, heating, y)
    inv4 = p42 = p24 = j42 = 0.0
    if two_node:
        # rosenbrock._Solver: z4 eliminated from row 2 (two-node heating)
        dj22, j24, j42, j44 = _housing_jacobian(par, y)
        j22 = j22 + dj22
        inv4 = 1.0 / (1.0 - hg * j44)
        p42 = hg * j42 * inv4
        p24 = hg * j24 * inv4
    den2 = 1.0 - hg * j22
    if two_node:
        den2 = den2 - p24 * hg * j42
    safe2 = den2 if den2 != 0.0 else 1.0
    den1 = 1.0 - hg * j11 - hg * hg * j10 - hg * hg * j12 * j21 / safe2
    sound = abs(den2) > 1e-12 and abs(den1) > 1e-12
    inv1 = 1.0 / den1 if sound else 1.0
    inv2 = 1.0 / den2 if sound else 1.0
    lin = (
        hg,
        inv1,
        inv2,
        hg * j10 * inv1,
        hg * j12 * inv2 * inv1,
        hg * j21 * inv2,
        hg * j31,
        hg * j32,
        inv4,
        p42,
        p24,
    )
    k1 = _solve(heating, two_node, lin, _scaled(hg, f0))
    k2 = _stage(par, kind, heating, two_node, lin, _plus(y, _A21, k1), _scaled(_GC21, k1))
    k3 = _stage(
        par,
        kind,
        heating,
        two_node,
        lin,
        _plus(_plus(y, _A31, k1), _A32, k2),
        _plus(_scaled(_GC31, k1), _GC32, k2),
    )
    k4 = _stage(
        par,
        kind,
        heating,
        two_node,
        lin,
        _plus(_plus(_plus(y, _A41, k1), _A42, k2), _A43, k3),
        _plus(_plus(_scaled(_GC41, k1), _GC42, k2), _GC43, k3),
    )
    y5 = _plus(_plus(_plus(_plus(y, _A51, k1), _A52, k2), _A53, k3), _A54, k4)
    k5 = _stage(
        par,
        kind,
        heating,
        two_node,
        lin,
        y5,
        _plus(_plus(_plus(_scaled(_GC51, k1), _GC52, k2), _GC53, k3), _GC54, k4),
    )
    y6 = _plus(y5, 1.0, k5)
    k6 = _stage(
        par,
        kind,
        heating,
        two_node,
        lin,
        y6,
        _plus(_plus(_plus(_plus(_scaled(_GC61, k1), _GC62, k2), _GC63, k3), _GC64, k4), _GC65, k5),
    )
    return _plus(y6, 1.0, k6), k6, sound


@_jit
def _hermite(y0: float, f0: float, y1: float, f1: float, h: float, s: float) -> float:
    """Cubic Hermite interpolant at the fraction s of a step (``rosenbrock._hermite``)."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2 * s3 - 3 * s2 + 1) * y0
        + (s3 - 2 * s2 + s) * h * f0
        + (-2 * s3 + 3 * s2) * y1
        + (s3 - s2) * h * f1
    )


@_jit
def _root(c0: float, c1: float, c2: float, c3: float, degree: int) -> float:
    """The root in [0, 1] of ``sum_k c_k s^k`` bracketed by its values at 0 and 1.

    ``rosenbrock._root`` for one polynomial: Newton safeguarded by bisection, to 2^-48.
    """
    coef = (c0, c1, c2, c3)
    lo = 0.0
    hi = 1.0
    start = c0 > 0.0
    total = c0 + c1 + c2 + (c3 if degree == 3 else 0.0)
    den = c0 - total
    # The secant on [0, 1], clipped; as in NumPy, c0 / 0 is +-inf (clipped) or NaN (0.5).
    if den != 0.0:
        s = c0 / den
    elif c0 != 0.0:
        s = math.copysign(math.inf, c0) * math.copysign(1.0, den)
    else:
        s = math.nan
    s = 0.5 if math.isnan(s) else min(max(s, 0.0), 1.0)
    for _ in range(64):
        p = coef[degree] * s + coef[degree - 1]
        dp = coef[degree] * degree * s + (degree - 1) * coef[degree - 1]
        for j in range(degree - 2, -1, -1):
            p = p * s + coef[j]
            if j > 0:
                dp = dp * s + j * coef[j]
        if (p > 0.0) == start:
            lo = s
        else:
            hi = s
        newton = s - p / dp if dp != 0.0 else math.nan
        new = newton if (newton > lo and newton < hi) else 0.5 * (lo + hi)
        settled = abs(new - s) <= 2.0**-48 or hi - lo <= 2.0**-48 or p == 0.0
        if p != 0.0:
            s = new
        if settled:
            break
    return s


@_jit
def _rest_push(par: Params, x: float) -> float:
    """``J u'`` at ``u = 0+`` and displacement x (:meth:`Model.rest_push`): the drive less
    the spring, the Stribeck excess at rest and gravity; the damping vanishes at rest."""
    push = par[_DRIVE] - par[_K] * x
    if par[_DF] > 0.0:
        push = push - par[_DF]
    if par[_GW] != 0.0:
        push = push - par[_GD] * par[_GW] * math.sin(par[_GP] + par[_GD] * x)
    return push


@_jit
def _crossing(ya: float, fa: float, yb: float, fb: float, h: float, target: float) -> float:
    """Fraction of the step at which the interpolant of a row crosses ``target``."""
    hf0 = h * fa
    hf1 = h * fb
    dy = yb - ya
    return _root(ya - target, hf0, 3.0 * dy - 2.0 * hf0 - hf1, hf0 + hf1 - 2.0 * dy, 3)


@_jit
def _interior_peak(ya: float, fa: float, yb: float, fb: float, h: float, stop: float) -> float:
    """The interpolant's maximum inside a step where its slope turns from + to -, if it
    lies before the fraction ``stop``; -inf otherwise."""
    hf0 = h * fa
    hf1 = h * fb
    dy = yb - ya
    c2 = 3.0 * dy - 2.0 * hf0 - hf1
    c3 = hf0 + hf1 - 2.0 * dy
    s_turn = _root(hf0, 2.0 * c2, 3.0 * c3, 0.0, 2)
    if s_turn <= stop:
        return _hermite(ya, fa, yb, fb, h, s_turn)
    return -math.inf


@_jit
def _indicator(par: Params, kind: int, heating: bool, x: float, u: float, s: float) -> float:
    """The power-flow indicator times the segment's flow (:meth:`Model.indicator`)."""
    f = _factor(par, heating, s)
    shaft = par[_N] * u
    eddy = _law(kind, par[_LAW_A], par[_LAW_B], shaft, f)[0]
    damper = par[_N] * (eddy + par[_BG] * shaft) + par[_FQ]
    load = par[_AL] - par[_K] * x
    if par[_GW] != 0.0:
        load = load - par[_GD] * par[_GW] * math.sin(par[_GP] + par[_GD] * x)
    value: float = par[_FLOW] * (par[_JL] * damper + par[_JD] * load)
    return value


@_jit
def _switch(
    par: Params, kind: int, heating: bool, y: State, f: State, y1: State, fb: State, h: float
) -> float:
    """Fraction of the step where the power flow reverses, bisected on the interpolant
    (``rosenbrock._find_switch``); inf where it does not."""
    if not (
        _indicator(par, kind, heating, y[0], y[1], y[2]) > 0.0
        and _indicator(par, kind, heating, y1[0], y1[1], y1[2]) <= 0.0
    ):
        return math.inf
    lo = 0.0
    hi = 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        x = _hermite(y[0], f[0], y1[0], fb[0], h, mid)
        u = _hermite(y[1], f[1], y1[1], fb[1], h, mid)
        s = _hermite(y[2], f[2], y1[2], fb[2], h, mid)
        if _indicator(par, kind, heating, x, u, s) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@_inline
def _grow(buffer: FloatArray, count: int) -> FloatArray:
    """The recorded steps' table, full at ``count`` rows, in one twice as long."""
    bigger = np.empty((2 * buffer.shape[0], buffer.shape[1]))
    bigger[:count] = buffer[:count]
    return bigger


@_inline
def _store(steps: FloatArray, count: int, t: float, y: State, f: State, rows: int) -> None:
    """Row ``count`` of the recorded steps: time, state and slope.

    A step is a row, its values side by side. As columns of a (1 + 2 rows, capacity)
    table each step wrote 9 values a power-of-two stride apart (one L1 cache set from
    512 columns on); that layout, a call per step and the table reassigned at every
    step (reference counts) made recording cost 8.5 us of the MSL brake's 93 us
    segment, 6 us now (issue 13; the values stored cost the most of what is left).
    """
    steps[count, 0] = t
    for r in range(rows):
        steps[count, 1 + r] = y[r]
        steps[count, 1 + rows + r] = f[r]


@_jit
def _segment(
    par: FloatArray,
    kind: int,
    heating: bool,
    y0: FloatArray,
    length: float,
    cap: float,
    creep: float,
    creeps: bool,
    atol: FloatArray,
    first_step: float,
    rtol: float,
    horizon: float,
    horizon_kind: int,
    record: bool,
    final: FloatArray,
) -> tuple[int, float, float, float, FloatArray, int]:
    """Integrate one segment to its first event (``rosenbrock.integrate_batch``, one case).

    Returns (event kind, duration, max speed, max temperature state, recorded steps as the
    first m rows of a (capacity, 1 + 2 rows) table of time, state and slope, m); the end
    state is written into ``final``. The state has 4 rows, or 5 with two-node heating
    (the housing rise).
    """
    par[_FIXED] = par[_FA] * math.exp(par[_COEF] * y0[2])
    rows = y0.shape[0]
    if length <= 0.0:
        # No length (a backward motion from the start stop): its end is reached at once
        # (rosenbrock.integrate_batch); the crossing test below needs x short of it.
        for r in range(rows):
            final[r] = y0[r]
        final[0] = length
        return _REACH, 0.0, y0[1], y0[2], np.empty((1 + 2 * rows, 1)), 0
    # The parameters and the state as tuples in the step loop (see State).
    p = _as_tuple(par, _COLUMNS)
    two_node = rows > 4
    y = (y0[0], y0[1], y0[2], y0[3], y0[4] if two_node else 0.0)
    tol = (atol[0], atol[1], atol[2], atol[3], atol[4] if two_node else 1.0)
    flow = p[_FLOW] != 0.0
    f = _slope(p, kind, heating, two_node, y)
    t = 0.0
    h = min(first_step, cap if math.isfinite(cap) else math.inf)
    end = min(cap, horizon)
    top_speed = y0[1]
    top_temp = y0[2]
    steps = np.empty((64 if record else 1, 1 + 2 * rows))
    count = 0
    if record:
        _store(steps, 0, t, y, f, rows)
        count = 1
    for _ in range(MAX_STEPS):
        h = min(h, end - t)
        y1, error, sound = _step(p, kind, heating, two_node, y, f, h)
        err = 0.0
        total = 0.0
        for r in range(4):
            scale = max(abs(y[r]), abs(y1[r])) * rtol + tol[r]
            err = max(err, abs(error[r]) / scale)
            total += y1[r]
        if two_node:  # the housing row
            scale = max(abs(y[4]), abs(y1[4])) * rtol + tol[4]
            err = max(err, abs(error[4]) / scale)
            total += y1[4]
        finite = math.isfinite(err + total)
        if finite and sound:
            factor = min(max(0.9 / math.sqrt(math.sqrt(max(err, 1e-10))), 0.2), 5.0)
        else:
            factor = 0.25
        h_next = h * factor
        if not (sound and finite and err <= 1.0):
            h = h_next
            continue
        fb = _slope(p, kind, heating, two_node, y1)
        # Events in this step: the earliest of reaching the length, zero speed, creep.
        event_s = math.inf
        event = -1
        if y[0] < length and y1[0] >= length:
            event_s = _crossing(y[0], f[0], y1[0], fb[0], h, length)
            event = _REACH
        if y[1] > 0.0 and y1[1] <= 0.0:
            s_hit = _crossing(y[1], f[1], y1[1], fb[1], h, 0.0)
            if s_hit < event_s:
                event_s, event = s_hit, _ZERO
        if creeps and y[1] > creep and y1[1] <= creep:
            s_hit = _crossing(y[1], f[1], y1[1], fb[1], h, creep)
            # Creep only short of the equilibrium: past it (the turnaround of a swing)
            # the speed reaches zero in finite time (rosenbrock._creeping).
            if s_hit < event_s:
                x_hit = _hermite(y[0], f[0], y1[0], fb[0], h, s_hit)
                if _rest_push(p, x_hit) > 0.0:
                    event_s, event = s_hit, _REST
        if flow:
            s_hit = _switch(p, kind, heating, y, f, y1, fb, h)
            if s_hit < event_s:
                event_s, event = s_hit, SWITCH
        # Maxima of the speed and the temperature state: step ends and interior peaks.
        stop = min(event_s, 1.0)
        if event < 0:
            top_speed = max(top_speed, y1[1])
        if f[1] > 0.0 and fb[1] < 0.0:
            top_speed = max(top_speed, _interior_peak(y[1], f[1], y1[1], fb[1], h, stop))
        if heating:
            if event < 0:
                top_temp = max(top_temp, y1[2])
            if f[2] > 0.0 and fb[2] < 0.0:
                top_temp = max(top_temp, _interior_peak(y[2], f[2], y1[2], fb[2], h, stop))
        if event >= 0:
            for r in range(rows):
                final[r] = _hermite(y[r], f[r], y1[r], fb[r], h, event_s)
            top_speed = max(top_speed, final[1])
            if heating:
                top_temp = max(top_temp, final[2])
            if event == _REACH:
                final[0] = length
            if event == _ZERO:
                final[1] = 0.0
            duration = t + event_s * h
            if record:
                last = (final[0], final[1], final[2], final[3], final[4] if two_node else 0.0)
                if count == steps.shape[0]:
                    steps = _grow(steps, count)
                _store(steps, count, duration, last, _slope(p, kind, heating, two_node, last), rows)
                count += 1
            return event, duration, top_speed, top_temp, steps, count
        t += h
        y = y1
        f = fb
        if record:
            if count == steps.shape[0]:  # full (a reassignment costs reference counts)
                steps = _grow(steps, count)
            _store(steps, count, t, y, f, rows)
            count += 1
        if t >= end * (1.0 - 1e-15):
            for r in range(rows):
                final[r] = y[r]
            code = _CAP if cap <= horizon else horizon_kind
            return code, t, top_speed, top_temp, steps, count
        h = h_next
    for r in range(rows):
        final[r] = y[r]
    return horizon_kind, t, top_speed, top_temp, steps, count


@_jit
def _batch(
    par: FloatArray,
    kind: int,
    heating: bool,
    y0: FloatArray,
    length: FloatArray,
    cap: FloatArray,
    creep: FloatArray,
    creeps: NDArray[np.bool_],
    atol: FloatArray,
    first_step: FloatArray,
    rtol: float,
    horizon: float,
    horizon_kind: int,
    kinds: NDArray[np.int8],
    duration: FloatArray,
    final: FloatArray,
    max_speed: FloatArray,
    max_temp: FloatArray,
) -> None:
    """:func:`_segment` over every segment of a batch (no recording)."""
    end = np.empty(y0.shape[0])
    for j in range(par.shape[0]):
        code, time, top_speed, top_temp, _, _ = _segment(
            par[j],
            kind,
            heating,
            y0[:, j].copy(),
            length[j],
            cap[j],
            creep[j],
            creeps[j],
            atol[:, j].copy(),
            first_step[j],
            rtol,
            horizon,
            horizon_kind,
            False,
            end,
        )
        kinds[j] = code
        duration[j] = time
        final[:, j] = end
        max_speed[j] = top_speed
        max_temp[j] = top_temp


def _parameters(model: Model) -> tuple[FloatArray, int]:
    """The per-segment parameter table and the law's code."""
    n = np.shape(model.inertia)[0]
    eddy = model.eddy
    table = np.empty((n, _COLUMNS))
    table[:, _J] = model.inertia
    table[:, _K] = model.stiffness
    table[:, _DRIVE] = model.drive
    table[:, _N] = model.ratio
    table[:, _BG] = model.gearbox_damping
    table[:, _C] = model.heat_capacity
    table[:, _R] = model.thermal_resistance
    # The factor at s = 0 is f_a exp(0) = f_a exactly: the model's ambient factor.
    table[:, _FA] = (
        model.factor(np.zeros(n)) if model.ambient_factor is None else model.ambient_factor
    )
    table[:, _COEF] = eddy.coefficient
    table[:, _FIXED] = np.nan  # set by _segment from the start state
    # No Stribeck friction: excess 0 (the kernels skip the term), w_St 1 (unused).
    table[:, _DF] = 0.0 if model.stribeck_excess is None else model.stribeck_excess
    table[:, _WS] = 1.0 if model.stribeck_speed is None else model.stribeck_speed
    # One node: C_h, R_he unused (the state has no housing row).
    table[:, _CH] = np.inf if model.housing_heat_capacity is None else model.housing_heat_capacity
    table[:, _RHE] = np.inf if model.housing_resistance is None else model.housing_resistance
    table[:, _GW] = 0.0 if model.gravity_amplitude is None else model.gravity_amplitude
    table[:, _GP] = 0.0 if model.gravity_phase is None else model.gravity_phase
    table[:, _GD] = 1.0 if model.gravity_direction is None else model.gravity_direction
    # An ideal gear: m = 1 (the kernels skip the product) and no power-flow event.
    table[:, _MESH] = 1.0 if model.mesh is None else model.mesh
    table[:, _FLOW] = 0.0 if model.flow is None else model.flow
    for column, values in (
        (_JL, model.load_inertia),
        (_JD, model.damper_inertia),
        (_FQ, model.mesh_friction),
        (_AL, model.load_drive),
    ):
        table[:, column] = 0.0 if values is None else values
    if isinstance(eddy, LinearEddy):
        table[:, _LAW_A] = eddy.damping_rate
        table[:, _LAW_B] = 0.0
        return table, LINEAR_LAW
    if isinstance(eddy, KlossEddy):
        table[:, _LAW_A] = eddy.peak_torque
        table[:, _LAW_B] = eddy.reference_peak_speed
        return table, KLOSS_LAW
    raise TypeError(f"no compiled form of the eddy law {eddy.name!r}")


# A batch of at least PARALLEL_MIN segments runs on THREADS threads (the kernels release
# the GIL), each over a contiguous part of it; results are bit for bit those of one thread.
THREADS = max(1, min(2, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1))
PARALLEL_MIN = 256


def _split(n: int, parts: int) -> list[tuple[int, int]]:
    """``parts`` contiguous ranges covering 0 .. n (as equal as possible)."""
    edges = [n * i // parts for i in range(parts + 1)]
    return [(lo, hi) for lo, hi in zip(edges[:-1], edges[1:], strict=True) if hi > lo]


def _in_threads(run: Callable[[int, int], None], parts: list[tuple[int, int]]) -> None:
    """``run(lo, hi)`` for each part: the first in this thread, the others in new ones."""
    errors: list[BaseException] = []

    def guarded(lo: int, hi: int) -> None:
        try:
            run(lo, hi)
        except BaseException as exc:  # re-raised in the calling thread
            errors.append(exc)

    workers = [threading.Thread(target=guarded, args=part) for part in parts[1:]]
    for worker in workers:
        worker.start()
    try:
        if parts:
            run(*parts[0])
    finally:
        for worker in workers:
            worker.join()
    if errors:
        raise errors[0]


def integrate_batch(model: Model, segments: Segments, control: Control) -> Outcome:
    """:func:`ecdsim.dynamics.rosenbrock.integrate_batch`, one compiled segment at a time."""
    par, law = _parameters(model)
    n = par.shape[0]
    y0 = np.ascontiguousarray(segments.y0, dtype=float)
    atol = np.ascontiguousarray(segments.atol, dtype=float)
    kinds = np.empty(n, dtype=np.int8)
    duration = np.empty(n)
    rows = y0.shape[0]
    final = np.empty((rows, n))
    max_speed = np.empty(n)
    max_temp = np.empty(n)
    length = np.ascontiguousarray(segments.length, dtype=float)
    cap = np.ascontiguousarray(segments.cap, dtype=float)
    creep = np.ascontiguousarray(segments.creep_speed, dtype=float)
    creeps = np.ascontiguousarray(segments.creeps, dtype=np.bool_)
    first = np.ascontiguousarray(segments.first_step, dtype=float)
    heating = bool(model.heating)
    trajectories: list[Trajectory | None] = [None] * n
    if not control.record:
        parts = _split(n, THREADS if n >= PARALLEL_MIN else 1)

        def run(lo: int, hi: int) -> None:
            # Each segment depends on its own row only: any split gives the same bits.
            part_final = np.empty((rows, hi - lo))
            _batch(
                par[lo:hi],
                law,
                heating,
                np.ascontiguousarray(y0[:, lo:hi]),
                length[lo:hi],
                cap[lo:hi],
                creep[lo:hi],
                creeps[lo:hi],
                np.ascontiguousarray(atol[:, lo:hi]),
                first[lo:hi],
                control.rtol,
                control.horizon,
                control.horizon_kind,
                kinds[lo:hi],
                duration[lo:hi],
                part_final,
                max_speed[lo:hi],
                max_temp[lo:hi],
            )
            final[:, lo:hi] = part_final

        _in_threads(run, parts)
        return Outcome(kinds, duration, final, max_speed, max_temp, trajectories)
    end = np.empty(rows)
    for j in range(n):
        result: tuple[Any, ...] = _segment(
            par[j],
            law,
            heating,
            y0[:, j].copy(),
            length[j],
            cap[j],
            creep[j],
            bool(creeps[j]),
            atol[:, j].copy(),
            first[j],
            control.rtol,
            control.horizon,
            control.horizon_kind,
            True,
            end,
        )
        code, time, top_speed, top_temp, steps, count = result
        kinds[j], duration[j], max_speed[j], max_temp[j] = code, time, top_speed, top_temp
        final[:, j] = end
        if count >= 2:
            trajectories[j] = Trajectory(
                steps[:count, 0].copy(),
                steps[:count, 1 : 1 + rows].T.copy(),
                steps[:count, 1 + rows :].T.copy(),
            )
    return Outcome(kinds, duration, final, max_speed, max_temp, trajectories)

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
a step of a 4-state segment costs a few hundred nanoseconds, and a batch is a loop over
its segments with no array traffic.

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

# RODAS4's A and GAMMA * C as module-level arrays: numba freezes globals into the compiled
# code as constants (about 8 % faster than passing them as arguments).
_A_TABLE = np.zeros((6, 5))
_GC_TABLE = np.zeros((6, 5))
for _i in range(6):
    for _j, _a in enumerate(A[_i]):
        _A_TABLE[_i, _j] = _a
    for _j, _g in enumerate(_GC[_i]):
        _GC_TABLE[_i, _j] = _g


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
    torque = scale * w * p / den
    d_speed = scale * p * (p * p - w * w) / den / den
    d_factor = scale * w * (w * w - p * p) / den / den * b
    power = scale * w * w / den * b
    common = 2.0 * scale * w * p / den / den
    return torque, d_speed, d_factor, power, common * p * b, -common * w * b * b


@_jit
def _factor(par: FloatArray, heating: bool, s: float) -> float:
    """The damping law's temperature factor ``f_a exp(c s)`` (thermal.damping_factor_from_log).

    Without heating s keeps its start value in every stage (its stages are exactly 0), so
    the factor is the one :func:`_segment` stored at the start: the same number, no exp.
    """
    factor: float = par[_FA] * math.exp(par[_COEF] * s) if heating else par[_FIXED]
    return factor


@_jit
def _stribeck(par: FloatArray, u: float) -> tuple[float, float]:
    """The Stribeck friction above Coulomb and its slope (equations.stribeck_excess)."""
    ratio = u / par[_WS]
    g = par[_DF] * math.exp(-ratio * ratio)
    return g, -2.0 * ratio / par[_WS] * g


@_jit
def _rhs(par: FloatArray, kind: int, heating: bool, y: FloatArray, out: FloatArray) -> None:
    """``dy/dt`` of :meth:`Model.rhs` for one segment."""
    u = y[1]
    s = y[2]
    f = _factor(par, heating, s)
    shaft = par[_N] * u
    eddy, _, _, power, _, _ = _law(kind, par[_LAW_A], par[_LAW_B], shaft, f)
    torque = par[_N] * (eddy + par[_BG] * shaft)
    out[0] = u
    if par[_DF] > 0.0:
        # The Stribeck excess is a speed-dependent torque like the damping (Model.rhs).
        torque = torque + _stribeck(par, u)[0]
    accel = (par[_DRIVE] - par[_K] * y[0]) - (torque if par[_MESH] == 1.0 else par[_MESH] * torque)
    if par[_GW] != 0.0:
        # The gravity torque against the motion (Model.gravity).
        accel = accel - par[_GD] * par[_GW] * math.sin(par[_GP] + par[_GD] * y[0])
    out[1] = accel / par[_J]
    if heating:
        r = par[_R]
        loss = s * _exprel(-par[_COEF] * s) / r if math.isfinite(r) else 0.0
        out[2] = (power - loss) / par[_C]
    else:
        out[2] = 0.0
    out[3] = torque * u
    if y.shape[0] > 4:
        _housing_rhs(par, y, out)


@_jit
def _housing_rhs(par: FloatArray, y: FloatArray, out: FloatArray) -> None:
    """The two-node terms of :meth:`Model.rhs`: the housing's return into ``out[2]``
    (thermal.housing_return) and the housing rate ``out[4]`` (thermal.housing_rate)."""
    s = y[2]
    h = y[4]
    c = par[_COEF]
    f = par[_FA] * math.exp(c * s)
    r = par[_R]
    den = r * f * par[_C]
    if math.isfinite(r) and math.isfinite(den) and den > 0.0:
        out[2] += h / den
    rise = par[_FA] * s * _exprel(c * s)
    gain = (rise - h) / r if math.isfinite(r) else 0.0
    loss = h / par[_RHE] if math.isfinite(par[_RHE]) else 0.0
    out[4] = (gain - loss) / par[_CH]


@_jit
def _housing_jacobian(par: FloatArray, y: FloatArray) -> tuple[float, float, float, float]:
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


@_jit
def _jacobian(par: FloatArray, kind: int, heating: bool, y: FloatArray) -> tuple[float, ...]:
    """Nonzero entries (j10, j11, j12, j21, j22, j31, j32) of :meth:`Model.jacobian`."""
    u = y[1]
    s = y[2]
    n = par[_N]
    c = par[_COEF]
    f = _factor(par, heating, s)
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
            slope = slope - math.exp(-c * s) / r
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
def _step(
    par: FloatArray,
    kind: int,
    heating: bool,
    y: FloatArray,
    f0: FloatArray,
    h: float,
    k: FloatArray,
    stage: FloatArray,
    value: FloatArray,
    y1: FloatArray,
) -> bool:
    """One RODAS4 step into ``y1``; the error estimate is ``k[5]``; False if singular.

    The stage equations and their elimination are those of ``rosenbrock._step`` and
    ``rosenbrock._Solver`` (z1 first, then z0, z2, z3).
    """
    hg = h * GAMMA
    j10, j11, j12, j21, j22, j31, j32 = _jacobian(par, kind, heating, y)
    m = y.shape[0]
    two_node = m > 4
    inv4 = p42 = p24 = 0.0
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
    p10 = hg * j10 * inv1
    p12 = hg * j12 * inv2 * inv1
    p21 = hg * j21 * inv2
    # The row loops run over the four one-node rows with a constant bound (as before the
    # housing row existed: the compiler unrolls them), the housing row after them.
    for i in range(6):
        if i == 0:
            for r in range(4):
                value[r] = f0[r] * hg
            if two_node:
                value[4] = f0[4] * hg
        else:
            for r in range(4):
                stage[r] = _stage_row(y, k, i, r)
            if two_node:
                stage[4] = _stage_row(y, k, i, 4)
            _rhs(par, kind, heating, stage, value)
            for r in range(4):
                value[r] = value[r] * hg + _coupling_row(k, i, r)
            if two_node:
                value[4] = value[4] * hg + _coupling_row(k, i, 4)
        v2 = value[2] + p24 * value[4] if two_node else value[2]
        z1 = value[1] * inv1 + p10 * value[0]
        if heating:
            z1 += p12 * v2
        k[i, 1] = z1
        k[i, 0] = value[0] + hg * z1
        if heating:
            z2 = v2 * inv2 + p21 * z1
            k[i, 2] = z2
            k[i, 3] = value[3] + hg * j31 * z1 + hg * j32 * z2
            if two_node:
                k[i, 4] = value[4] * inv4 + p42 * z2
        else:
            k[i, 2] = value[2]
            k[i, 3] = value[3] + hg * j31 * z1
    for r in range(4):
        y1[r] = _stage_row(y, k, 5, r) + k[5, r]
    if two_node:
        y1[4] = _stage_row(y, k, 5, 4) + k[5, 4]
    return sound


@_jit
def _stage_row(y: FloatArray, k: FloatArray, i: int, r: int) -> float:
    """Row r of stage i's state, ``y + sum_j A_ij K_j`` (stage 5's for i = 5)."""
    acc: float = y[r]
    for jj in range(min(i, 5)):
        acc += _A_TABLE[i, jj] * k[jj, r]
    return acc


@_jit
def _coupling_row(k: FloatArray, i: int, r: int) -> float:
    """Row r of ``GAMMA * sum_j C_ij K_j`` for stage i."""
    coupling = 0.0
    for jj in range(i):
        coupling += _GC_TABLE[i, jj] * k[jj, r]
    return coupling


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
def _indicator(par: FloatArray, kind: int, heating: bool, y: FloatArray) -> float:
    """The power-flow indicator times the segment's flow (:meth:`Model.indicator`)."""
    f = _factor(par, heating, y[2])
    shaft = par[_N] * y[1]
    eddy = _law(kind, par[_LAW_A], par[_LAW_B], shaft, f)[0]
    damper = par[_N] * (eddy + par[_BG] * shaft) + par[_FQ]
    load = par[_AL] - par[_K] * y[0]
    if par[_GW] != 0.0:
        load = load - par[_GD] * par[_GW] * math.sin(par[_GP] + par[_GD] * y[0])
    value: float = par[_FLOW] * (par[_JL] * damper + par[_JD] * load)
    return value


@_jit
def _switch(
    par: FloatArray,
    kind: int,
    heating: bool,
    y: FloatArray,
    f: FloatArray,
    y1: FloatArray,
    fb: FloatArray,
    h: float,
    probe: FloatArray,
) -> float:
    """Fraction of the step where the power flow reverses, bisected on the interpolant
    (``rosenbrock._find_switch``); inf where it does not."""
    if par[_FLOW] == 0.0:
        return math.inf
    if not (_indicator(par, kind, heating, y) > 0.0 and _indicator(par, kind, heating, y1) <= 0.0):
        return math.inf
    lo = 0.0
    hi = 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        for r in range(y.shape[0]):
            probe[r] = _hermite(y[r], f[r], y1[r], fb[r], h, mid)
        if _indicator(par, kind, heating, probe) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@_jit
def _grow(buffer: FloatArray, count: int) -> FloatArray:
    if count < buffer.shape[1]:
        return buffer
    bigger = np.empty((buffer.shape[0], 2 * buffer.shape[1]))
    bigger[:, :count] = buffer[:, :count]
    return bigger


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

    Returns (event kind, duration, max speed, max temperature state, recorded steps as a
    (1 + 2 rows, m) table of time, state and slope, m); the end state is written into
    ``final``. The state has 4 rows, or 5 with two-node heating (the housing rise).
    """
    par[_FIXED] = par[_FA] * math.exp(par[_COEF] * y0[2])
    rows = y0.shape[0]
    k = np.empty((6, rows))
    stage = np.empty(rows)
    value = np.empty(rows)
    y = y0.copy()
    y1 = np.empty(rows)
    f = np.empty(rows)
    fb = np.empty(rows)
    _rhs(par, kind, heating, y, f)
    t = 0.0
    h = min(first_step, cap if math.isfinite(cap) else math.inf)
    end = min(cap, horizon)
    top_speed = y0[1]
    top_temp = y0[2]
    steps = np.empty((1 + 2 * rows, 64 if record else 1))
    count = 0
    if record:
        steps[0, 0] = t
        steps[1 : 1 + rows, 0] = y
        steps[1 + rows :, 0] = f
        count = 1
    for _ in range(MAX_STEPS):
        h = min(h, end - t)
        sound = _step(par, kind, heating, y, f, h, k, stage, value, y1)
        err = 0.0
        total = 0.0
        for r in range(4):
            scale = max(abs(y[r]), abs(y1[r])) * rtol + atol[r]
            err = max(err, abs(k[5, r]) / scale)
            total += y1[r]
        if rows > 4:  # the housing row (two-node heating)
            scale = max(abs(y[4]), abs(y1[4])) * rtol + atol[4]
            err = max(err, abs(k[5, 4]) / scale)
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
        _rhs(par, kind, heating, y1, fb)
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
            if s_hit < event_s:
                event_s, event = s_hit, _REST
        if par[_FLOW] != 0.0:
            s_hit = _switch(par, kind, heating, y, f, y1, fb, h, stage)
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
                _rhs(par, kind, heating, final, fb)
                steps = _grow(steps, count)
                steps[0, count] = duration
                steps[1 : 1 + rows, count] = final
                steps[1 + rows :, count] = fb
                count += 1
            return event, duration, top_speed, top_temp, steps, count
        t += h
        y[:] = y1
        f[:] = fb
        if record:
            steps = _grow(steps, count)
            steps[0, count] = t
            steps[1 : 1 + rows, count] = y
            steps[1 + rows :, count] = f
            count += 1
        if t >= end * (1.0 - 1e-15):
            final[:] = y
            code = _CAP if cap <= horizon else horizon_kind
            return code, t, top_speed, top_temp, steps, count
        h = h_next
    final[:] = y
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
                par[lo:hi], law, heating, np.ascontiguousarray(y0[:, lo:hi]), length[lo:hi],
                cap[lo:hi], creep[lo:hi], creeps[lo:hi], np.ascontiguousarray(atol[:, lo:hi]),
                first[lo:hi], control.rtol, control.horizon, control.horizon_kind,
                kinds[lo:hi], duration[lo:hi], part_final, max_speed[lo:hi], max_temp[lo:hi],
            )  # fmt: skip
            final[:, lo:hi] = part_final

        _in_threads(run, parts)
        return Outcome(kinds, duration, final, max_speed, max_temp, trajectories)
    end = np.empty(rows)
    for j in range(n):
        result: tuple[Any, ...] = _segment(
            par[j], law, heating, y0[:, j].copy(), length[j], cap[j], creep[j],
            bool(creeps[j]), atol[:, j].copy(), first[j], control.rtol, control.horizon,
            control.horizon_kind, True, end,
        )  # fmt: skip
        code, time, top_speed, top_temp, steps, count = result
        kinds[j], duration[j], max_speed[j], max_temp[j] = code, time, top_speed, top_temp
        final[:, j] = end
        if count >= 2:
            trajectories[j] = Trajectory(
                steps[0, :count].copy(),
                steps[1 : 1 + rows, :count].copy(),
                steps[1 + rows :, :count].copy(),
            )
    return Outcome(kinds, duration, final, max_speed, max_temp, trajectories)

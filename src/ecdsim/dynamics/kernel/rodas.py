"""RODAS4 for a mechanical state: N coordinates, N speeds, auxiliary states, quadratures.

Method: RODAS4 (Hairer, E. and Wanner, G., *Solving Ordinary Differential Equations II*,
2nd ed., Springer 1996, section VI.4; coefficients as tabulated there and in KPP/FATODE,
Sandu et al.): 6 stages, order 4 with an embedded order-3 solution for the error
estimate, stiffly accurate and L-stable, so stiffness (``J / B`` of milliseconds, a stiff
gear mesh) costs nothing. In the transformed form (Hairer and Wanner, IV.7, Eq. 7.4'):

    (I - h g J) K_i = h g f(y + sum_j A_ij K_j) + g sum_j C_ij K_j,
    y1 = y + sum_j A_6j K_j + K_6,     error = K_6

with the analytic Jacobian J of the model (:mod:`ecdsim.dynamics.kernel.hinge`).

The state is ``y = [q (m), v (m), z (a), e (e)]``: generalised coordinates, their
speeds, auxiliary states (the damper's heating) and quadratures (dissipated energies,
which nothing reads back). The linear systems use that structure: ``q' = v`` and the
quadratures' columns of J are zero, so with ``K_q = r_q + h g K_v`` the system reduces
to the speeds and auxiliary states, ``m + a`` unknowns (2 for a heated hinge), solved by
LU with partial pivoting; the quadratures follow by substitution.

The sizes are compile-time constants for numba: they are the lengths of the tuples
``dm``, ``da``, ``dq`` (tuple lengths are part of a function's type), so that every loop
below has a fixed trip count; numba compiles one version per state layout.
"""

from __future__ import annotations

import math

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel.hinge import derivatives, jacobian

GAMMA = 0.25
A21 = 1.544
A31, A32 = 0.9466785280815826, 0.2557011698983284
A41, A42, A43 = 3.314825187068521, 2.896124015972201, 0.9986419139977817
A51, A52, A53, A54 = 1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895
C21 = -5.6688
C31, C32 = -2.430093356833875, -0.2063599157091915
C41, C42, C43 = -0.1073529058151375, -9.594562251023355, -20.47028614809616
C51, C52, C53, C54 = 7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160
C61, C62, C63 = 8.083246795921522, -7.981132988064893, -31.52159432874371
C64, C65 = 16.31930543123136, -6.058818238834054
# The coupling coefficients times GAMMA, as the stages use them.
G21 = GAMMA * C21
G31, G32 = GAMMA * C31, GAMMA * C32
G41, G42, G43 = GAMMA * C41, GAMMA * C42, GAMMA * C43
G51, G52, G53, G54 = GAMMA * C51, GAMMA * C52, GAMMA * C53, GAMMA * C54
G61, G62, G63, G64, G65 = GAMMA * C61, GAMMA * C62, GAMMA * C63, GAMMA * C64, GAMMA * C65
# Below this pivot the stage matrix is taken as singular and the step is rejected.
SINGULAR = 1e-12


def factorize(
    jac: FloatArray, hg: float, lu: FloatArray, pivot: FloatArray, m: int, na: int
) -> bool:
    """LU of the reduced stage matrix, in place; False when it is (nearly) singular.

    Rows and columns are the speeds and the auxiliary states: ``I - hg J_vv - hg^2 J_vq``,
    ``-hg J_vz`` / ``-hg J_zv - hg^2 J_zq``, ``I - hg J_zz`` (module notes).
    """
    size = m + na
    for i in range(size):
        row = m + i
        for j in range(size):
            col = m + j
            value = -hg * jac[row, col]
            if j < m:
                value -= hg * hg * jac[row, j]
            if i == j:
                value += 1.0
            lu[i, j] = value
    sound = True
    for k in range(size):
        best = k
        for i in range(k + 1, size):
            if abs(lu[i, k]) > abs(lu[best, k]):
                best = i
        pivot[k] = best
        if best != k:
            for j in range(size):
                held = lu[k, j]
                lu[k, j] = lu[best, j]
                lu[best, j] = held
        head = lu[k, k]
        if not abs(head) > SINGULAR:
            sound = False
            head = 1.0
            lu[k, k] = 1.0
        for i in range(k + 1, size):
            lu[i, k] /= head
            factor = lu[i, k]
            for j in range(k + 1, size):
                lu[i, j] -= factor * lu[k, j]
    return sound


def stage_solve(
    jac: FloatArray,
    hg: float,
    lu: FloatArray,
    pivot: FloatArray,
    r: FloatArray,
    k: FloatArray,
    m: int,
    na: int,
    n: int,
) -> None:
    """``k`` with ``(I - hg J) k = r``, by the factorisation of :func:`factorize`."""
    size = m + na
    for i in range(size):
        row = m + i
        acc = r[row]
        for j in range(m):
            acc += hg * jac[row, j] * r[j]
        k[row] = acc
    for i in range(size):  # the row exchanges of the factorisation, in order
        p = int(pivot[i])
        if p != i:
            held = k[m + i]
            k[m + i] = k[m + p]
            k[m + p] = held
    for i in range(size):
        acc = k[m + i]
        for j in range(i):
            acc -= lu[i, j] * k[m + j]
        k[m + i] = acc
    for i in range(size - 1, -1, -1):
        acc = k[m + i]
        for j in range(i + 1, size):
            acc -= lu[i, j] * k[m + j]
        k[m + i] = acc / lu[i, i]
    for j in range(m):
        k[j] = r[j] + hg * k[m + j]
    for row in range(m + size, n):  # quadratures: nothing depends on them
        acc = r[row]
        for j in range(m + size):
            acc += hg * jac[row, j] * k[j]
        k[row] = acc


def rodas_step(
    cw: FloatArray,
    y: FloatArray,
    f0: FloatArray,
    h: float,
    work: FloatArray,
    jac: FloatArray,
    lu: FloatArray,
    pivot: FloatArray,
    dm: tuple[int, ...],
    da: tuple[int, ...],
    dq: tuple[int, ...],
) -> bool:
    """One RODAS4 step from ``y`` (slope ``f0``) over ``h``: ``work[8]`` gets y1 and
    ``work[5]`` the error estimate K6. False when the stage matrix was singular.

    ``work`` rows: K1..K6 (0-5), the stage state (6), the stage right-hand side (7), y1 (8).
    """
    m = len(dm)
    na = len(da)
    n = 2 * m + na + len(dq)
    hg = h * GAMMA
    jacobian(cw, y, jac, dm, da, dq)
    sound = factorize(jac, hg, lu, pivot, m, na)
    st = work[6]
    r = work[7]
    for i in range(n):
        r[i] = hg * f0[i]
    stage_solve(jac, hg, lu, pivot, r, work[0], m, na, n)
    k1 = work[0]
    for i in range(n):
        st[i] = y[i] + A21 * k1[i]
    derivatives(cw, st, r, dm, da, dq)
    for i in range(n):
        r[i] = hg * r[i] + G21 * k1[i]
    stage_solve(jac, hg, lu, pivot, r, work[1], m, na, n)
    k2 = work[1]
    for i in range(n):
        st[i] = y[i] + A31 * k1[i] + A32 * k2[i]
    derivatives(cw, st, r, dm, da, dq)
    for i in range(n):
        r[i] = hg * r[i] + G31 * k1[i] + G32 * k2[i]
    stage_solve(jac, hg, lu, pivot, r, work[2], m, na, n)
    k3 = work[2]
    for i in range(n):
        st[i] = y[i] + A41 * k1[i] + A42 * k2[i] + A43 * k3[i]
    derivatives(cw, st, r, dm, da, dq)
    for i in range(n):
        r[i] = hg * r[i] + G41 * k1[i] + G42 * k2[i] + G43 * k3[i]
    stage_solve(jac, hg, lu, pivot, r, work[3], m, na, n)
    k4 = work[3]
    for i in range(n):
        st[i] = y[i] + A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]
    derivatives(cw, st, r, dm, da, dq)
    for i in range(n):
        r[i] = hg * r[i] + G51 * k1[i] + G52 * k2[i] + G53 * k3[i] + G54 * k4[i]
    stage_solve(jac, hg, lu, pivot, r, work[4], m, na, n)
    k5 = work[4]
    for i in range(n):  # stiffly accurate: stage 6 is stage 5's state plus K5
        st[i] += k5[i]
    derivatives(cw, st, r, dm, da, dq)
    for i in range(n):
        r[i] = hg * r[i] + G61 * k1[i] + G62 * k2[i] + G63 * k3[i] + G64 * k4[i] + G65 * k5[i]
    stage_solve(jac, hg, lu, pivot, r, work[5], m, na, n)
    k6 = work[5]
    y1 = work[8]
    for i in range(n):
        y1[i] = st[i] + k6[i]
    return sound


def error_norm(
    y: FloatArray, y1: FloatArray, error: FloatArray, rtol: float, atol: FloatArray, n: int
) -> float:
    """The max norm of ``error / (atol + rtol max(|y|, |y1|))``; inf if not finite."""
    norm = 0.0
    total = 0.0
    for i in range(n):
        scale = max(abs(y[i]), abs(y1[i])) * rtol + atol[i]
        norm = max(norm, abs(error[i]) / scale)
        total += y1[i]
    if not math.isfinite(norm + total):
        return math.inf
    return norm


def step_factor(norm: float) -> float:
    """The next step's size over this one's, from the error norm (order 4: fourth root)."""
    if not math.isfinite(norm):
        return 0.25
    return min(max(0.9 / math.sqrt(math.sqrt(max(norm, 1e-10))), 0.2), 5.0)


def new_work(n: int, m: int, na: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The step's work arrays: stages and states (9 x n), Jacobian, LU and pivots."""
    size = m + na
    return np.zeros((9, n)), np.zeros((n, n)), np.zeros((size, size)), np.zeros(size)

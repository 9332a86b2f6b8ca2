"""Fast kernels of the exact solution: the same function as :mod:`ecdsim.solvers.exact`.

:meth:`ExactMethod.solve <ecdsim.solvers.exact.ExactMethod.solve>` is written for clarity:
whole-batch ``np.where`` selections, a full-size net-torque array and a separate pass that
finds the undamped cases. This module evaluates the same formulas (``B * L / logmean(a,
b)`` summed over the segments, Eq. 5 with the piecewise-linear spring of Eq. 7 integrated
exactly; :mod:`ecdsim.physics.quasistatic`) in two faster ways:

* ``numpy``: over blocks of :data:`BLOCK` cases of one row of the batch, so that every
  temporary is block-sized (it stays in cache, and no full-size temporary is made), with
  in-place ufuncs and the branches of the log-mean taken per block (all "far", none "far",
  or a fix-up of the few elements of the other kind). Bit-identical to the reference:
  the operations are the reference's, in the same order (the sign flips used are exact);
* ``numba``: one compiled loop over the cases (:mod:`ecdsim.solvers._exact_numba`), numba
  is a core dependency (:mod:`ecdsim._numba`). Its ``log``/``log1p`` are the C
  library's, not NumPy's SIMD ones, so it agrees with the reference to a few ulp (tested
  <= 1e-12 relative).

Both fast kernels handle the *ordinary* case: damping 0 < B < inf, every net torque at
the breakpoints > 0 (so no stall), every segment of positive length, a positive log-mean
and a finite peak speed. Every other case (a stall, a start against friction, no
damping, NaN, zero-length segments, an overflowing speed) is gathered and solved by the
reference implementation, so that its edge-case semantics exist in one place only.

:func:`choose` picks the kernel: ``numba`` when it is importable and the batch holds at
least :data:`NUMBA_MIN_CASES` cases (importing numba costs about 0.3 s, which only a large
batch repays, so that ``ecdsim deploy`` never imports it), ``numpy`` otherwise or when
``ECDSIM_NUMBA=0`` (the switch every compiled kernel obeys, :mod:`ecdsim._numba`). The
environment variable ``ECDSIM_EXACT_KERNEL`` (``reference``, ``numpy``, ``numba``) forces
one, for benchmarks and tests.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ecdsim import _numba
from ecdsim._types import BoolArray, FloatArray

KERNELS = ("reference", "numpy", "numba")
ENVIRONMENT = "ECDSIM_EXACT_KERNEL"
# Cases per block of the NumPy kernel: 8 block-sized float64 temporaries of 128 KiB each
# stay within a core's L2 cache.
BLOCK = 16_384
# From this many cases the numba kernel is used when installed: its import (about 0.3 s)
# and the load of its cached machine code are then a small part of the call.
NUMBA_MIN_CASES = 50_000
# Below this relative difference of a and b the log-mean's series is used (the same
# limit as ecdsim.physics.quasistatic._SERIES_LIMIT, which the reference uses).
SERIES_LIMIT = 1e-6


@dataclass(frozen=True)
class ExactArrays:
    """The exact solution's arrays, each of the batch shape.

    Attributes
    ----------
    deployment_time : [s], +inf where stalled or not solved
    start_speed, end_speed, max_speed : [rad/s]
    stalled : True where the net torque reaches zero before the end of travel
    stall_angle : [rad], NaN where not stalled
    solved : False where the case has no damping (BECD_T = 0, see
        :func:`ecdsim.solvers.base.undamped_cases`)
    """

    deployment_time: FloatArray
    start_speed: FloatArray
    end_speed: FloatArray
    max_speed: FloatArray
    stalled: BoolArray
    stall_angle: FloatArray
    solved: BoolArray


def as_cube(
    problem: Any,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, tuple[int, ...]]:
    """The problem's arrays as (n_points, rows, cols) and (rows, cols) views, and the shape.

    The batch axes are folded into rows (all but the last) and columns (the last), which
    keeps a broadcast view a view for the usual batches ((T, N), (N,), ()).
    """
    shape = problem.batch_shape
    cols = shape[-1] if shape else 1
    rows = int(np.prod(shape[:-1], dtype=np.int64)) if len(shape) > 1 else 1
    n = problem.angles.shape[0]
    angles = np.reshape(problem.angles, (n, rows, cols))
    torques = np.reshape(problem.torques, (n, rows, cols))
    friction = np.reshape(problem.friction, (rows, cols))
    damping = np.reshape(problem.damping_rate, (rows, cols))
    return angles, torques, friction, damping, shape


def _ordinary_block(
    angles: FloatArray,
    torques: FloatArray,
    friction: FloatArray,
    damping: FloatArray,
    time: FloatArray,
    start: FloatArray,
    end: FloatArray,
    peak: FloatArray,
) -> BoolArray | None:
    """The ordinary-case formulas on one block (1-D views), written into the outputs.

    Returns None when every case of the block is ordinary, else the mask of the cases that
    are not (their outputs are garbage, to be overwritten by the reference).
    """
    n = angles.shape[0]
    a = np.subtract(torques[0], friction)  # net torque at the segment's start [N*m]
    b = np.empty_like(a)
    r = np.empty_like(a)
    lr = np.empty_like(a)
    bl = np.empty_like(a)
    first = a.copy()
    np.copyto(peak, a)
    bad: BoolArray | None = None
    # An ordinary block has every net torque > 0 (so no NaN), 0 < B < inf and L > 0; min
    # and max reductions check that without a mask.
    if not (damping.min() > 0.0 and damping.max() < np.inf and a.min() > 0.0):
        bad = ~((damping > 0.0) & (damping < np.inf) & (a > 0.0))
    for i in range(n - 1):
        np.subtract(torques[i + 1], friction, out=b)
        length = np.subtract(angles[i + 1], angles[i])
        if not (b.min() > 0.0 and length.min() > 0.0):
            more = ~((b > 0.0) & (length > 0.0))
            bad = more if bad is None else bad | more
        # x' = b/a - 1 = -(1 - b/a) exactly; the reference's x = 1 - b/a.
        np.divide(b, a, out=r)
        np.subtract(r, 1.0, out=r)
        # far: b < a/2, where the reference takes ln a - ln b. The ratio decides unless it
        # is within rounding of 1/2; then the reference's own test is made.
        r_max, r_min = r.max(), r.min()
        if r_max < -0.5000001:
            far: BoolArray | bool = True
        elif r_min > -0.4999999:
            far = False
        else:
            far = b < 0.5 * a
        # ratio = x / ln(a/b) = x' / ln(b/a); ln(b/a) from the logs where far, else log1p.
        if far is True:
            np.log(b, out=lr)
            lr -= np.log(a)
        else:
            np.log1p(r, out=lr)
            if far is not False:
                where = np.flatnonzero(far)
                lr[where] = np.log(b[where]) - np.log(a[where])
        # The series 1 - x/2 - x^2/12 below SERIES_LIMIT (x = -x'), as the reference.
        small = None
        # Written so that a NaN of a non-ordinary case leads to the explicit test.
        if not (r_max <= -SERIES_LIMIT or r_min >= SERIES_LIMIT):
            small = np.flatnonzero(np.abs(r) < SERIES_LIMIT)
            series = (1.0 + r[small] / 2.0) - r[small] * r[small] / 12.0
        np.divide(r, lr, out=lr)  # the log-mean over a
        if small is not None:
            lr[small] = series
        np.multiply(a, lr, out=lr)  # the log-mean [N*m]
        if not lr.min() > 0.0:
            more = ~(lr > 0.0)
            bad = more if bad is None else bad | more
        np.multiply(damping, length, out=bl)
        np.divide(bl, lr, out=bl)  # B * L / logmean: the segment's duration [s]
        if i == 0:
            np.copyto(time, bl)
        else:
            np.add(time, bl, out=time)
        np.maximum(peak, b, out=peak)
        a, b = b, a
    np.divide(first, damping, out=start)
    np.divide(a, damping, out=end)
    np.divide(peak, damping, out=peak)
    if not peak.max() < np.inf:
        more = ~(peak < np.inf)
        bad = more if bad is None else bad | more
    return bad


def _numpy_ordinary(
    angles: FloatArray,
    torques: FloatArray,
    friction: FloatArray,
    damping: FloatArray,
    outputs: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> BoolArray:
    """The NumPy kernel over (n, rows, cols) views; the mask of non-ordinary cases."""
    rows, cols = friction.shape
    exceptional = np.zeros((rows, cols), dtype=bool)
    time, start, end, peak = outputs
    with np.errstate(all="ignore"):  # non-ordinary cases are recomputed by the reference
        for p in range(rows):
            for s in range(0, cols, BLOCK):
                e = min(s + BLOCK, cols)
                bad = _ordinary_block(
                    angles[:, p, s:e],
                    torques[:, p, s:e],
                    friction[p, s:e],
                    damping[p, s:e],
                    time[p, s:e],
                    start[p, s:e],
                    end[p, s:e],
                    peak[p, s:e],
                )
                if bad is not None:
                    exceptional[p, s:e] = bad
    return exceptional


def _numba_ordinary(
    angles: FloatArray,
    torques: FloatArray,
    friction: FloatArray,
    damping: FloatArray,
    outputs: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> BoolArray:
    """The compiled kernel over (n, rows, cols) views; the mask of non-ordinary cases."""
    from ecdsim.solvers._exact_numba import ordinary

    exceptional = np.zeros(friction.shape, dtype=bool)
    ordinary(angles, torques, friction, damping, *outputs, exceptional)
    return exceptional


Ordinary = Callable[
    [FloatArray, FloatArray, FloatArray, FloatArray, tuple[FloatArray, ...]], BoolArray
]


def choose(cases: int) -> str:
    """The kernel for a batch of ``cases`` cases (module docstring)."""
    forced = os.environ.get(ENVIRONMENT, "").strip().lower()
    if forced:
        if forced not in KERNELS:
            raise ValueError(f"{ENVIRONMENT}={forced!r}: expected one of {list(KERNELS)}")
        return forced
    if _numba.switched_off():
        return "numpy"
    if cases >= NUMBA_MIN_CASES and _numba.available():
        return "numba"
    return "numpy"


def solve_fast(problem: Any, kernel: str, reference: Callable[[Any], Any]) -> ExactArrays:
    """The exact solution by a fast kernel; non-ordinary cases by ``reference``.

    ``problem`` is a :class:`~ecdsim.solvers.base.QuasiStaticProblem`; ``reference``
    solves a sub-problem of the gathered non-ordinary cases and returns its
    :class:`~ecdsim.solvers.base.DeploymentSolution` (the reference implementation).
    """
    angles, torques, friction, damping, shape = as_cube(problem)
    ordinary: Any = _numba_ordinary if kernel == "numba" else _numpy_ordinary
    rows, cols = friction.shape
    outputs = tuple(np.empty((rows, cols)) for _ in range(4))
    exceptional = ordinary(angles, torques, friction, damping, outputs)
    time, start, end, peak = outputs
    stalled = np.zeros((rows, cols), dtype=bool)
    stall_angle = np.full((rows, cols), np.nan)
    solved = np.ones((rows, cols), dtype=bool)
    flat = np.flatnonzero(exceptional)
    if flat.size:
        p, q = np.divmod(flat, cols)
        from ecdsim.solvers.base import QuasiStaticProblem

        sub = QuasiStaticProblem(
            angles=angles[:, p, q],
            torques=torques[:, p, q],
            friction=friction[p, q],
            damping_rate=damping[p, q],
        )
        fixed = reference(sub)
        for target, values in (
            (time, fixed.deployment_time),
            (start, fixed.start_speed),
            (end, fixed.end_speed),
            (peak, fixed.max_speed),
            (stalled, fixed.stalled),
            (stall_angle, fixed.stall_angle),
            (solved, fixed.solved_mask),
        ):
            target[p, q] = values
    return ExactArrays(
        deployment_time=time.reshape(shape),
        start_speed=start.reshape(shape),
        end_speed=end.reshape(shape),
        max_speed=peak.reshape(shape),
        stalled=stalled.reshape(shape),
        stall_angle=stall_angle.reshape(shape),
        solved=solved.reshape(shape),
    )

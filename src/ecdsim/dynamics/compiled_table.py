"""A forward engaged segment over many spring-table pieces in one compiled call (numba).

The solver's Python event loop takes one pass per spring breakpoint (a closed-form or
integrated segment per piece, then the bookkeeping): about a millisecond each, so a table
of P points cost about P milliseconds per deployment. Here the walk over the pieces runs
compiled: each piece is integrated by :func:`ecdsim.dynamics.compiled._segment` (RODAS4,
the same step control and events as every integrated segment) with that piece's drive,
stiffness and length and the scales of :func:`ecdsim.dynamics.integrate._scales`; the
crossing of a breakpoint is the piece's REACH event, located on the step's Hermite
interpolant, and the next piece starts from the state there. The run stops at the first
event that is not a breakpoint (end of travel, zero speed, creep, stop time); the solver
applies it as usual. The reference is the solver's own per-piece path (closed form for
linear damping, :mod:`ecdsim.dynamics.integrate` otherwise), which runs where numba is
missing; ``tests/test_dynamics_table_kernel.py`` compares the two.
"""

from __future__ import annotations

import math

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.compiled import _DRIVE, _J, _K, _REACH, _jit, _segment
from ecdsim.dynamics.integrate import CREEP_FRACTION

__all__ = ["table_run"]


@_jit
def _append(
    steps: FloatArray, count: int, piece: FloatArray, m: int, dt: float, dx: float
) -> tuple[FloatArray, int]:
    """Append a piece's recorded steps (time and x shifted to the run's start)."""
    if count + m > steps.shape[1]:
        bigger = np.empty((steps.shape[0], max(2 * steps.shape[1], count + m)))
        bigger[:, :count] = steps[:, :count]
        steps = bigger
    for j in range(m):
        steps[:, count + j] = piece[j, :]  # the piece's steps are rows (compiled._store)
        steps[0, count + j] += dt
        steps[1, count + j] += dx
    return steps, count + m


@_jit
def table_run(
    par: FloatArray,
    kind: int,
    heating: bool,
    y0: FloatArray,
    torques: FloatArray,
    stiffness: FloatArray,
    lengths: FloatArray,
    kinetic: float,
    cap: float,
    rtol: float,
    horizon: float,
    horizon_kind: int,
    linear_damping: float,
    record: bool,
    final: FloatArray,
    cross_time: FloatArray,
    cross_speed: FloatArray,
) -> tuple[int, float, float, float, float, int, FloatArray, int]:
    """Integrate the pieces in turn until an event other than a breakpoint.

    Piece i starts at the spring torque ``torques[i]`` (forward frame), falls by
    ``stiffness[i]`` per radian and is ``lengths[i]`` long; ``kinetic`` is the kinetic
    friction. Returns (event kind, duration, max speed, max temperature state, spring
    work, breakpoints crossed, recorded steps (time, state, slope rows; x and time from
    the run's start), their count); ``final`` gets the end state with x the whole
    displacement and E the whole dissipation; ``cross_time`` and ``cross_speed`` the time
    and speed of each breakpoint crossed.
    """
    rows = y0.shape[0]
    y = y0.copy()
    end = np.empty(rows)
    atol = np.empty(rows)
    steps = np.empty((1 + 2 * rows, 64 if record else 1))
    count = 0
    t = 0.0
    x_total = 0.0
    dissipated = 0.0
    spring = 0.0
    top_speed = y0[1]
    top_temp = y0[2]
    damping0 = max(linear_damping, 1e-300)
    small = rtol * 1e-3
    pieces = lengths.shape[0]
    code = horizon_kind
    crossed = 0
    for i in range(pieces):
        crossed = i
        drive = torques[i] - kinetic
        k = stiffness[i]
        length = lengths[i]
        par[_DRIVE] = drive
        par[_K] = k
        speed0 = y[1]
        # The scales of integrate._scales for this piece alone.
        speed = max(max(abs(speed0), abs(drive) / damping0), 1e-300)
        reach = max(length, 1e-9)
        energy = max(max(abs(drive) * length, 0.5 * par[_J] * speed0**2), 1e-300)
        atol[0] = small * reach
        atol[1] = min(small, 1e-12) * speed
        atol[2] = small
        atol[3] = small * energy
        equilibrium = drive / k if k > 0.0 else math.inf
        creeps = equilibrium > 0.0 and equilibrium <= length
        first = 1e-3 * min(par[_J] / damping0, reach / speed)
        y[0] = 0.0
        y[3] = 0.0
        code, duration, piece_speed, piece_temp, piece_steps, m = _segment(
            par, kind, heating, y, length, max(cap - t, 0.0), CREEP_FRACTION * speed,
            creeps, atol, first, rtol, horizon, horizon_kind, record, end,
        )  # fmt: skip
        x = end[0]
        spring += torques[i] * x - 0.5 * k * x * x
        dissipated += end[3]
        top_speed = max(top_speed, piece_speed)
        top_temp = max(top_temp, piece_temp)
        if record:
            steps, count = _append(steps, count, piece_steps, m, t, x_total)
        t += duration
        x_total += x
        y[:] = end
        if code != _REACH or i == pieces - 1:
            break
        cross_time[i] = t
        cross_speed[i] = end[1]
    final[:] = y
    final[0] = x_total
    final[3] = dissipated
    return code, t, top_speed, top_temp, spring, crossed, steps, count

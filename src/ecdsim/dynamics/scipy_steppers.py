"""scipy's stiff integrators as the kernel's stepper: ``[analysis] integrator`` Radau,
BDF or LSODA.

The event loop, the equations and the event locator stay the kernel's
(:mod:`ecdsim.dynamics.kernel`, run as plain Python): only the step is scipy's. Each
segment is a ``scipy.integrate`` ``OdeSolver`` of the kernel's right-hand side and
analytic Jacobian, stepped one accepted step at a time (its own step-size control); the
segment's events are located on each step's dense output by the kernel's locator, as
for RODAS4. Slow (plain Python), for cross-checks and references.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.kernel.hinge import derivatives, jacobian

_METHODS = {1: "Radau", 2: "BDF", 3: "LSODA"}


def start_stepper(
    cw: FloatArray, y: FloatArray, span: float, rtol: float, atol: FloatArray, h: float,
    method: int, dm: tuple[int, ...], da: tuple[int, ...], dq: tuple[int, ...],
) -> Any:  # fmt: skip
    """The segment's scipy solver, from the state y over ``span`` seconds."""
    from scipy import integrate

    n = y.shape[0]
    m = len(dm)

    def fun(_t: float, state: FloatArray) -> FloatArray:
        slope = np.empty(n)
        derivatives(cw, state, slope, dm, da, dq)
        return slope

    def jac(_t: float, state: FloatArray) -> FloatArray:
        matrix = np.zeros((n, n))
        jacobian(cw, state, matrix, dm, da, dq)
        matrix[:m, m : 2 * m] = np.eye(m)  # q' = v
        return matrix

    solver: Any = getattr(integrate, _METHODS[method])
    return solver(fun, 0.0, y.copy(), span, rtol=rtol, atol=atol.copy(), jac=jac)


def attempt(
    stepper: Any, cw: FloatArray, y: FloatArray, f: FloatArray, h: float, t: float, limit: float,
    rtol: float, atol: FloatArray, ws: tuple[FloatArray, ...], dm: tuple[int, ...],
    da: tuple[int, ...], dq: tuple[int, ...],
) -> tuple[float, float]:  # fmt: skip
    """One accepted step of the scipy solver: its state in ``ws[0][8]``; (0, 0) when the
    solver has finished or failed."""
    if stepper.status != "running":
        return 0.0, 0.0
    before = stepper.t
    stepper.step()
    if stepper.status == "failed":
        return 0.0, 0.0
    ws[0][8][:] = stepper.y
    return float(stepper.t - before), 1.0

"""Small non-linear least squares (Levenberg-Marquardt), without scipy.optimize.

The drop-test fits solve problems of two parameters and a few dozen residuals with an
analytic Jacobian: the start-up-corrected line, the timing-noise line and each law over
temperature. ``scipy.optimize.least_squares`` solves them, but importing scipy.optimize
costs several times the whole fit, so :func:`solve` does it here: Levenberg-Marquardt
(K. Levenberg, Q. Appl. Math. 2, 1944; D. W. Marquardt, J. SIAM 11, 1963) with the
parameters scaled by the Jacobian's column norms as in MINPACK (J. J. More, "The
Levenberg-Marquardt algorithm: implementation and theory", Lecture Notes in Mathematics
630, 1978). Each step is the least-squares solution of ``[J; sqrt(lam) D] d = [-r; 0]``
(no normal equations, so no squared condition number); ``lam`` starts at 0 (a
Gauss-Newton step) and grows tenfold while a step does not lower the cost.

It iterates until the scaled step is below 1e-15 of the scaled parameters, i.e. to
float64 round-off, so its answer is the minimum itself, not a point within a tolerance
of it: where scipy's solver also converges, both agree to about ``cond(J) * 1e-16``
(tests/test_characterize_leastsq.py compares them on the drop-test fits).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ecdsim._types import FloatArray

# A step below this fraction of the (scaled) parameters is round-off: converged.
STEP_TOLERANCE = 1e-15
# Once a step promises less than this fraction of the cost, one last Gauss-Newton step
# ends the search (see solve).
FINAL_REDUCTION = 1e-12
_MAX_DAMPING = 1e30  # past this the step is zero in float64: nothing better nearby


@dataclass(frozen=True)
class Solution:
    """The outcome of :func:`solve`.

    Attributes
    ----------
    x : the parameters at the minimum (the last accepted point when not converged)
    success : True when the step fell to round-off
    message : why it stopped, for a user's error message
    evaluations : number of residual evaluations
    """

    x: FloatArray
    success: bool
    message: str
    evaluations: int


def _step(
    jacobian: FloatArray, residual: FloatArray, scale: FloatArray, damping: float
) -> FloatArray:
    """The Levenberg-Marquardt step: least squares of ``[J; sqrt(lam) D] d = [-r; 0]``."""
    if damping == 0.0:
        matrix, rhs = jacobian, -residual
    else:
        matrix = np.vstack([jacobian, np.diag(np.sqrt(damping) * scale)])
        rhs = np.concatenate([-residual, np.zeros(scale.size)])
    return np.asarray(np.linalg.lstsq(matrix, rhs, rcond=None)[0], dtype=np.float64)


def solve(
    residual: Callable[[FloatArray], FloatArray],
    jacobian: Callable[[FloatArray], FloatArray],
    x0: FloatArray,
    *,
    lower: FloatArray | None = None,
    max_evaluations: int | None = None,
) -> Solution:
    """Minimise ``sum(residual(x)**2)`` from ``x0``.

    Parameters
    ----------
    residual : ``x -> r``, shape (m,)
    jacobian : ``x -> d r / d x``, shape (m, n)
    x0 : the starting point, shape (n,)
    lower : optional lower bounds, shape (n,): every trial point is clipped onto them
    max_evaluations : the most residual evaluations (default ``100 * (n + 1)``, MINPACK's)

    Raises ValueError when the residuals are not finite at ``x0`` (scipy's message).
    """
    x = np.array(x0, dtype=float)
    if lower is not None:
        x = np.maximum(x, lower)
    limit = max_evaluations if max_evaluations is not None else 100 * (x.size + 1)
    r = np.asarray(residual(x), dtype=float)
    if not np.all(np.isfinite(r)):
        raise ValueError("Residuals are not finite in the initial point.")
    cost = float(r @ r)
    evaluations = 1
    damping = 0.0
    scale = np.zeros(x.size)
    while True:
        j = np.asarray(jacobian(x), dtype=float)
        # MINPACK's scaling: each parameter by the largest column norm seen so far.
        scale = np.maximum(scale, np.linalg.norm(j, axis=0))
        scale = np.where(scale > 0.0, scale, 1.0)
        while True:
            d = _step(j, r, scale, damping)
            trial = x + d
            if lower is not None:
                trial = np.maximum(trial, lower)
            size = float(np.linalg.norm(scale * (trial - x)))
            if size <= STEP_TOLERANCE * float(np.linalg.norm(scale * x)):
                return Solution(x, True, "the step fell to round-off", evaluations)
            if evaluations >= limit:
                message = "The maximum number of function evaluations is exceeded."
                return Solution(x, False, message, evaluations)
            linear = r + j @ (trial - x)
            if cost - float(linear @ linear) <= FINAL_REDUCTION * cost:
                # The local model has nothing left to gain: the cost itself no longer
                # tells better from worse (its round-off, or a model computed by an
                # inner iteration, can exceed what remains), but the Gauss-Newton step,
                # made of the residuals and the Jacobian, still points at the minimum.
                final = x + _step(j, r, scale, 0.0)
                if lower is not None:
                    final = np.maximum(final, lower)
                r_final = np.asarray(residual(final), dtype=float)
                if np.all(np.isfinite(r_final)):
                    x = final
                return Solution(
                    x, True, "the predicted reduction fell to round-off", evaluations + 1
                )
            r_trial = np.asarray(residual(trial), dtype=float)
            evaluations += 1
            trial_cost = float(r_trial @ r_trial)
            # Strictly lower: at round-off a step that only ties is refused, and the
            # damping then shrinks the steps until they are below the tolerance.
            if np.all(np.isfinite(r_trial)) and trial_cost < cost:
                x, r, cost = trial, r_trial, trial_cost
                damping = damping / 10.0 if damping > 1e-12 else 0.0
                break
            damping = 1e-3 if damping == 0.0 else 10.0 * damping
            if damping > _MAX_DAMPING:
                return Solution(x, True, "no lower cost nearby", evaluations)

"""The torque-speed line of one temperature: ``torque = FECD + BECD * speed`` (paper Eq. 5).

The paper (section 7, Figure 8) plots torque against speed and reads the damping rate as
the slope and the Coulomb friction as the offset. This module fits that line by ordinary
least squares and adds what the paper leaves to the eye:

* standard errors and 95 % confidence intervals (Student t, n - 2 degrees of freedom);
* R**2 and the residuals;
* a bending test: the t test of a quadratic term (roll-off when it bends down, as an ECD
  does beyond its linear range, paper section 2.1), at the 1 % level;
* an outlier test: externally studentised residuals, Bonferroni-corrected over the
  points of the temperature, at the 1 % family-wise level.

Each flag therefore fires on about 1 % of clean (linear, Gaussian) data sets; the tests
of this module check that rate. Statistics: see :mod:`ecdsim.characterize.stats`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray
from ecdsim.characterize.stats import (
    EXACT_FIT_RESOLUTION,
    Estimate,
    Linearised,
    estimates,
    linearised,
    student_t_sf,
    t_quantile,
    t_two_sided_p,
)

BENDING_LEVEL = 0.01
OUTLIER_LEVEL = 0.01


class LineFitError(ValueError):
    """The points cannot define a line (too few, or no spread); the message says why."""


@dataclass(frozen=True)
class CurvatureTest:
    """The t test of a quadratic term added to the line.

    Attributes
    ----------
    quadratic : coefficient of speed**2 [N*m*s**2/rad**2]; < 0 bends down (roll-off)
    p_value : two-sided p-value of the quadratic term (1 where the data are exact and
        straight, 0 where they are exact and curved)
    bending : True where p_value < BENDING_LEVEL
    roll_off : True where bending and the line bends down
    """

    quadratic: float
    p_value: float
    bending: bool
    roll_off: bool


@dataclass(frozen=True)
class LineFit:
    """A fitted torque-speed line with its statistics.

    Attributes
    ----------
    intercept : FECD, the torque at zero speed [N*m]
    slope : BECD, the damping rate [N*m*s/rad]
    r_squared : coefficient of determination [-]
    statistics : residuals, covariance and leverage (:class:`Linearised`)
    fitted : the line's torque at each point [N*m]
    studentized : externally studentised residuals [-]; NaN where undefined
    outlier_p : Bonferroni-adjusted outlier p-value of each point; NaN where undefined
    outliers : True where outlier_p < OUTLIER_LEVEL
    curvature : the bending test; None with fewer than 4 points or 3 distinct speeds
    """

    intercept: Estimate
    slope: Estimate
    r_squared: float
    statistics: Linearised
    fitted: FloatArray
    studentized: FloatArray
    outlier_p: FloatArray
    outliers: BoolArray
    curvature: CurvatureTest | None

    @property
    def n_points(self) -> int:
        """Number of points."""
        return self.statistics.n_points


def check_line_data(speed: ArrayLike, torque: ArrayLike) -> None:
    """Raise :class:`LineFitError` unless the points can define a line.

    A line needs at least two distinct speeds, and at least two distinct torques (load
    levels): replicate drops of one mass scatter in speed, but they say nothing about
    the slope.

    Parameters
    ----------
    speed : speeds of the points [rad/s]
    torque : torques of the points [N*m]
    """
    x = np.asarray(speed, dtype=float)
    y = np.asarray(torque, dtype=float)
    distinct_speeds = np.unique(x).size
    distinct_torques = np.unique(y).size
    if distinct_speeds < 2:
        raise LineFitError(
            f"fewer than two distinct speeds ({x.size} point(s), {distinct_speeds} distinct "
            "speed); a line needs at least two"
        )
    if distinct_torques < 2:
        raise LineFitError(
            f"all {y.size} points have the same torque {y[0]:.6g} N*m (one load level); "
            "a line needs at least two different loads"
        )


def fit_line(speed: ArrayLike, torque: ArrayLike) -> LineFit:
    """Ordinary least-squares line ``torque = FECD + BECD * speed`` (Eq. 5 inverted).

    Parameters
    ----------
    speed : steady speeds of the points [rad/s]
    torque : driving torques of the points [N*m]

    >>> fit = fit_line([1.0, 2.0, 3.0], [2.5, 4.5, 6.5])
    >>> round(fit.slope.value, 12), round(fit.intercept.value, 12)
    (2.0, 0.5)
    """
    x = np.asarray(speed, dtype=float)
    y = np.asarray(torque, dtype=float)
    check_line_data(x, y)
    design = np.column_stack([np.ones_like(x), x])
    # Centre the speeds for the solve: the same line, better conditioned.
    centre = float(np.mean(x))
    centred = np.column_stack([np.ones_like(x), x - centre])
    solution = np.linalg.lstsq(centred, y, rcond=None)[0]
    slope = float(solution[1])
    intercept = float(solution[0] - slope * centre)
    return summarise_line(x, y, intercept, slope, design)


def summarise_line(
    speed: ArrayLike,
    torque: ArrayLike,
    intercept: float,
    slope: float,
    design: ArrayLike,
    *,
    statistics: Linearised | None = None,
    curvature_weights: ArrayLike | None = None,
) -> LineFit:
    """Statistics, flags and intervals of a line whose parameters are already fitted.

    ``design`` is the derivative of the model torque with respect to (FECD, BECD) at each
    point: ``[1, speed]`` for a plain line; for the drop test with the start-up
    correction, the speed column also carries the derivative of the correction.

    A fit whose scatter is not in the torque (the drop test's timing-noise model, whose
    residuals are relative errors of the drop time) passes its own ``statistics``: the
    intervals, the outlier test and the scatter handed to the laws over temperature then
    come from them, and ``design`` is not used; R**2 stays a torque-space figure.

    Parameters
    ----------
    speed : the (corrected) speeds of the points [rad/s]
    torque : driving torques of the points [N*m]
    intercept : fitted FECD [N*m]
    slope : fitted BECD [N*m*s/rad]
    design : d torque / d (FECD, BECD), shape (n, 2) [-, rad/s]
    statistics : the fit's own linearised statistics; None: torque residuals and ``design``
    curvature_weights : weights of the bending test's points [1/(N*m)**2], e.g.
        ``1 / speed**2`` where the torque-space scatter grows with speed; None: equal
    """
    x = np.asarray(speed, dtype=float)
    y = np.asarray(torque, dtype=float)
    fitted = intercept + slope * x
    if statistics is None:
        stats = linearised(np.asarray(design, dtype=float), y - fitted, y)
    else:
        stats = statistics
    quantile = t_quantile(stats.dof) if stats.dof > 0 else None
    friction, damping = estimates(np.array([intercept, slope]), stats.covariance, quantile)
    total = float(np.sum((y - np.mean(y)) ** 2))
    r_squared = 1.0 - float(np.sum((y - fitted) ** 2)) / total
    studentized = stats.studentized()
    outlier_p = _bonferroni(studentized, stats)
    return LineFit(
        intercept=friction,
        slope=damping,
        r_squared=r_squared,
        statistics=stats,
        fitted=fitted,
        studentized=studentized,
        outlier_p=outlier_p,
        outliers=np.asarray(np.nan_to_num(outlier_p, nan=1.0) < OUTLIER_LEVEL),
        curvature=curvature_test(x, y, weights=curvature_weights),
    )


def _bonferroni(studentized: FloatArray, stats: Linearised) -> FloatArray:
    """Outlier p-values, each multiplied by the number of points (capped at 1).

    One vectorised call for all points (a scalar call per point was a fifth of the
    time of a whole drop-test reduction, measured).
    """
    n = stats.n_points
    p = np.full(studentized.shape, np.nan)
    finite = np.isfinite(studentized)
    if np.any(finite):
        two_sided = 2.0 * student_t_sf(np.abs(studentized[finite]), stats.dof - 1)
        p[finite] = np.minimum(1.0, n * two_sided)
    return p


def curvature_test(
    speed: ArrayLike, torque: ArrayLike, *, weights: ArrayLike | None = None
) -> CurvatureTest | None:
    """Test a quadratic term ``c * speed**2`` against the straight line.

    The F statistic ``(SSR_line - SSR_quad) / (SSR_quad / (n - 3))`` equals the square
    of the quadratic coefficient's t statistic (Draper and Smith, section 6.2); with
    ``weights`` both fits are weighted least squares (the same test on the rows scaled by
    ``sqrt(weight)``). None with fewer than 4 points or fewer than 3 distinct speeds (no
    degree of freedom to test).

    Parameters
    ----------
    speed : speeds [rad/s]
    torque : torques [N*m]
    weights : each point's weight, proportional to 1 / its torque variance
        [1/(N*m)**2]; None: equal
    """
    x = np.asarray(speed, dtype=float)
    n = x.size
    if n < 4 or np.unique(x).size < 3:
        return None
    root = np.ones_like(x) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    y = np.asarray(torque, dtype=float) * root
    # Centred and scaled speed: the quadratic fit is well conditioned at any speed scale.
    centre = float(np.mean(x))
    spread = float(np.max(np.abs(x - centre)))
    z = (x - centre) / spread
    line = np.column_stack([root, z * root])
    quad = np.column_stack([line, z * z * root])
    coef_line = np.linalg.lstsq(line, y, rcond=None)[0]
    coef_quad = np.linalg.lstsq(quad, y, rcond=None)[0]
    ssr_line = float(np.sum((y - line @ coef_line) ** 2))
    ssr_quad = float(np.sum((y - quad @ coef_quad) ** 2))
    quadratic = float(coef_quad[2]) / spread**2
    floor = n * (EXACT_FIT_RESOLUTION * float(np.max(np.abs(y)))) ** 2
    if ssr_line <= floor:
        p_value = 1.0  # exact and straight: nothing bends
    elif ssr_quad <= floor:
        p_value = 0.0  # exact and curved: it certainly bends
    else:
        f_statistic = max(ssr_line - ssr_quad, 0.0) / (ssr_quad / (n - 3))
        p_value = t_two_sided_p(math.sqrt(f_statistic), n - 3)
    bending = p_value < BENDING_LEVEL
    return CurvatureTest(
        quadratic=quadratic,
        p_value=p_value,
        bending=bending,
        roll_off=bending and quadratic < 0.0,
    )

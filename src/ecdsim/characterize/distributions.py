"""Student-t, chi-square and F tails and the Student-t quantile, without scipy.

``ecdsim fit drop-test`` needs four numbers from these distributions (a t quantile for
each interval, t tails for the outlier test, chi-square and F tails for the misfit
tests). ``scipy.special`` has them, but importing it costs more than the whole fit of a
bench log (its array-API layer imports ``numpy.testing``, ``numpy.f2py`` and
``numpy.random``), so they are computed here from the regularised incomplete beta and
gamma functions (Abramowitz and Stegun, *Handbook of Mathematical Functions*, 1964):

* Student-t tail, dof ``v``: ``P(T > t) = I_x(v/2, 1/2) / 2`` with ``x = v / (v + t**2)``
  (26.7.1); chi-square: ``P(X > x) = Q(v/2, x/2)`` (26.4.2); Fisher's F:
  ``P(F > f) = I_x(d2/2, d1/2)`` with ``x = d2 / (d2 + d1 f)`` (26.6.2);
* ``I_x(a, b)`` by its continued fraction (26.5.8), evaluated by the modified Lentz
  method on the side of ``x < (a + 1) / (a + b + 2)`` where it converges fast, with
  ``1 - x`` passed exactly rather than recomputed (W. H. Press et al., *Numerical
  Recipes*, 3rd ed., 2007, sections 5.2 and 6.4); ``Q(a, x)`` by its series (6.5.29,
  for ``x < a + 1``) or its continued fraction (6.5.31);
* the t quantile by Newton's method on ``log P(T > t)``, from the normal quantile,
  bracketed so that it cannot leave the root's interval.

Their prefactors ``exp(a log x + b log(1 - x) - log B(a, b))`` lose about
``eps * lgamma(a + b)`` of relative accuracy, so these functions are used for degrees of
freedom up to :data:`MAX_DOF`; :mod:`ecdsim.characterize.stats` hands larger ones, and
arguments outside the plain domain, to scipy. Within it they agree with
``scipy.special`` to 1e-12 relative (tests/test_characterize_distributions.py).
"""

from __future__ import annotations

import math
from statistics import NormalDist

# Up to this many degrees of freedom the log-gamma terms keep 1e-12 relative accuracy
# with margin (lgamma(100) is about 360: 360 * 2.2e-16 = 8e-14); larger ones go to scipy.
MAX_DOF = 200.0
_EPS = 1e-16  # the continued fractions and series stop below this relative change
_TINY = 1e-300  # keeps Lentz's denominators off zero
_MAX_TERMS = 10_000  # far more than the ~sqrt(max(a, b)) terms any argument here needs


def _stirling_remainder(x: float) -> float:
    """``lgamma(x) - ((x - 1/2) log x - x + log(2 pi) / 2)`` for ``x >= 10`` (the
    Stirling series, A&S 6.1.41; the first omitted term is below 1e-17 there)."""
    r = 1.0 / (x * x)
    series = (1.0 / 12, -1.0 / 360, 1.0 / 1260, -1.0 / 1680, 1.0 / 1188, -691.0 / 360360)
    total = 0.0
    for coefficient in reversed(series):
        total = total * r + coefficient
    return total / x


def _log_beta(a: float, b: float) -> float:
    """``log B(a, b)``. For a large argument ``lgamma(a) - lgamma(a + b)`` would cancel
    (each about ``a log a``, each off by an ulp of that), so the difference is taken
    from the Stirling series term by term, where no large terms cancel."""
    small, large = min(a, b), max(a, b)
    if large < 10.0:
        return math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b)
    total = small + large
    difference = (
        -(large - 0.5) * math.log1p(small / large)
        - small * math.log(total)
        + small
        + _stirling_remainder(large)
        - _stirling_remainder(total)
    )
    return math.lgamma(small) + difference


def _beta_fraction(a: float, b: float, x: float) -> float:
    """The continued fraction of ``I_x(a, b)`` (A&S 26.5.8), modified Lentz."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = 1.0
    d = 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > _TINY else _TINY)
    h = d
    for m in range(1, _MAX_TERMS):
        m2 = 2 * m
        for numerator in (
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ):
            d = 1.0 + numerator * d
            d = 1.0 / (d if abs(d) > _TINY else _TINY)
            c = 1.0 + numerator / c
            c = c if abs(c) > _TINY else _TINY
            h *= d * c
        if abs(d * c - 1.0) <= _EPS:
            return h
    raise ArithmeticError(f"incomplete beta I_x({a}, {b}) at x = {x} did not converge")


def incomplete_beta(a: float, b: float, x: float, y: float) -> float:
    """Regularised incomplete beta ``I_x(a, b)`` with ``y = 1 - x`` given exactly.

    >>> round(incomplete_beta(2.0, 3.0, 0.4, 0.6), 12)  # 1 - 0.6**4 - 4 * 0.4 * 0.6**3
    0.5248
    """
    if x <= 0.0:
        return 0.0
    if y <= 0.0:
        return 1.0
    log_front = a * math.log(x) + b * math.log(y) - _log_beta(a, b)
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_fraction(a, b, x) / a
    return 1.0 - math.exp(log_front) * _beta_fraction(b, a, y) / b


def upper_gamma(a: float, x: float) -> float:
    """Regularised upper incomplete gamma ``Q(a, x)`` (A&S 6.5.29 and 6.5.31).

    >>> round(upper_gamma(1.0, 2.0), 15) == round(math.exp(-2.0), 15)
    True
    """
    if x <= 0.0:
        return 1.0
    log_front = a * math.log(x) - x - math.lgamma(a)
    if x < a + 1.0:  # the series of P(a, x); Q = 1 - P is not small here
        term = total = 1.0 / a
        ap = a
        for _ in range(_MAX_TERMS):
            ap += 1.0
            term *= x / ap
            total += term
            if abs(term) <= abs(total) * _EPS:
                return 1.0 - total * math.exp(log_front)
        raise ArithmeticError(f"incomplete gamma P({a}, {x}) did not converge")
    b = x + 1.0 - a
    c = 1.0 / _TINY
    d = 1.0 / b
    h = d
    for i in range(1, _MAX_TERMS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = 1.0 / (d if abs(d) > _TINY else _TINY)
        c = b + an / c
        c = c if abs(c) > _TINY else _TINY
        h *= d * c
        if abs(d * c - 1.0) <= _EPS:
            return math.exp(log_front) * h
    raise ArithmeticError(f"incomplete gamma Q({a}, {x}) did not converge")


def student_t_tail(t: float, dof: float) -> float:
    """``P(T > t)`` for Student's t with ``dof`` degrees of freedom (A&S 26.7.1)."""
    square = t * t
    total = dof + square
    half = 0.5 * incomplete_beta(0.5 * dof, 0.5, dof / total, square / total)
    return half if t >= 0.0 else 1.0 - half


def chi2_tail(value: float, dof: float) -> float:
    """``P(X > value)`` for chi-square with ``dof`` degrees of freedom (A&S 26.4.2)."""
    return upper_gamma(0.5 * dof, 0.5 * value)


def f_tail(value: float, dof_numerator: float, dof_denominator: float) -> float:
    """``P(F > value)`` for Fisher's F (A&S 26.6.2)."""
    scaled = dof_numerator * value
    total = dof_denominator + scaled
    return incomplete_beta(
        0.5 * dof_denominator, 0.5 * dof_numerator, dof_denominator / total, scaled / total
    )


def _t_density_over_tail(t: float, dof: float, tail: float) -> float:
    """``f(t) / P(T > t)``: minus the derivative of ``log P(T > t)``."""
    log_density = (
        -0.5 * (dof + 1.0) * math.log1p(t * t / dof)
        - 0.5 * math.log(dof)
        - _log_beta(0.5 * dof, 0.5)
    )
    return math.exp(log_density) / tail


def student_t_quantile(probability: float, dof: float) -> float:
    """``t`` with ``P(T <= t) = probability``, for ``0 < probability < 1``.

    >>> round(student_t_quantile(0.975, 1.0), 12) == round(math.tan(0.475 * math.pi), 12)
    True
    """
    if probability == 0.5:
        return 0.0
    upper = min(probability, 1.0 - probability)  # P(T > t) for the positive root
    target = math.log(upper)
    # The root of log P(T > t) = log(upper) lies in (low, high): the tail falls with t.
    low, high = 0.0, math.inf
    t = max(-NormalDist().inv_cdf(upper), 1e-3)
    for _ in range(200):
        tail = student_t_tail(t, dof)
        gap = math.log(tail) - target
        if gap > 0.0:
            low = max(low, t)
        else:
            high = min(high, t)
        step = gap / _t_density_over_tail(t, dof, tail)
        proposal = t + step
        if not low < proposal < high:  # Newton overshot the bracket: bisect instead
            proposal = 0.5 * (low + high) if math.isfinite(high) else 2.0 * max(t, low)
        if abs(proposal - t) <= 4.0 * _EPS * abs(proposal):
            t = proposal
            break
        t = proposal
    return t if probability > 0.5 else -t

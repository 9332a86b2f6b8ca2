"""The scipy-free distribution functions of characterize/distributions.py.

Closed forms first (independent of any library): Student's t with 1 and 2 degrees of
freedom (Cauchy; ``1/2 - t / (2 sqrt(2 + t**2))``), chi-square with 2 and 4
(``exp(-x/2)``, ``exp(-x/2) (1 + x/2)``), F(2, 2) (``1 / (1 + f)``) and the incomplete
beta of integer arguments (a binomial sum, A&S 26.5.7). Then scipy.special on random
arguments over the whole domain they are used in (dof up to MAX_DOF).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import special

from ecdsim.characterize import distributions as d

RNG = np.random.default_rng(13)
# 1e-12 relative: the continued fractions and series stop at 1e-16 relative change, and
# the log-gamma prefactors lose at most ~1e-13 up to MAX_DOF (measured worst: 4e-13).
RTOL = 1e-12


def close(a: float, b: float, rtol: float = RTOL) -> bool:
    return abs(a - b) <= rtol * abs(b)


@pytest.mark.parametrize("t", [1e-8, 0.01, 0.3, 1.0, 2.5, 12.7, 300.0, -0.7, -40.0])
def test_t_tail_and_quantile_in_closed_form(t: float) -> None:
    # Written without cancellation for t > 0: 1/2 - atan(t)/pi = atan(1/t)/pi, and
    # 1/2 - t/(2s) = 1/(s (s + t)) with s = sqrt(2 + t**2); a few ulps each.
    root = math.sqrt(2.0 + t * t)
    cauchy = math.atan(1.0 / t) / math.pi if t > 0 else 0.5 - math.atan(t) / math.pi
    two = 1.0 / (root * (root + t)) if t > 0 else 0.5 - t / (2.0 * root)
    assert close(d.student_t_tail(t, 1.0), cauchy)
    assert close(d.student_t_tail(t, 2.0), two)
    # The quantile of the tail itself is -t (1 - tail would round). Near t = 0 the tail
    # 1/2 - O(t) holds t only to ulp(1/2) / t relative: 1e-8 there, 1e-14 from t = 0.01.
    if t >= 0.01:
        assert close(d.student_t_quantile(cauchy, 1.0), -t, 1e-11)
        assert close(d.student_t_quantile(two, 2.0), -t, 1e-11)


def test_t_quantile_of_the_intervals() -> None:
    # 0.975 quantiles: Cauchy tan(0.475 pi); dof 2: (2p - 1) / sqrt(2 p (1 - p)).
    assert close(d.student_t_quantile(0.975, 1.0), math.tan(0.475 * math.pi))
    assert close(d.student_t_quantile(0.975, 2.0), 0.95 / math.sqrt(2.0 * 0.975 * 0.025))
    assert d.student_t_quantile(0.5, 7.0) == 0.0
    # Symmetric (1 - 0.975 is 0.025 only to an ulp, so to 1e-12 rather than exactly).
    assert close(d.student_t_quantile(0.025, 5.0), -d.student_t_quantile(0.975, 5.0))


@pytest.mark.parametrize("x", [0.0, 1e-6, 0.4, 2.0, 9.0, 60.0, 700.0])
def test_chi2_and_f_tails_in_closed_form(x: float) -> None:
    assert close(d.chi2_tail(x, 2.0), math.exp(-x / 2.0))
    assert close(d.chi2_tail(x, 4.0), math.exp(-x / 2.0) * (1.0 + x / 2.0))
    assert close(d.f_tail(x, 2.0, 2.0), 1.0 / (1.0 + x))


@pytest.mark.parametrize(("a", "b"), [(1, 1), (2, 3), (5, 1), (7, 9), (30, 4)])
def test_incomplete_beta_of_integers_is_a_binomial_sum(a: int, b: int) -> None:
    # I_x(a, b) = P(at least a successes in a + b - 1 trials of probability x).
    n = a + b - 1
    for x in (0.05, 0.3, 0.5, 0.77, 0.98):
        exact = sum(math.comb(n, j) * x**j * (1.0 - x) ** (n - j) for j in range(a, n + 1))
        # The binomial sum itself rounds once per term (n terms of a few ulps).
        assert close(d.incomplete_beta(a, b, x, 1.0 - x), exact, 1e-13 * (n + 1))


def test_against_scipy_special_up_to_max_dof() -> None:
    dofs = [*RNG.uniform(0.5, d.MAX_DOF, 120), 1.0, 2.0, 3.0, 4.0, 17.0, d.MAX_DOF]
    for dof in dofs:
        for p in (0.975, 0.995, 0.9, 0.75, 0.6, 0.025, 1e-6, 1e-12):
            assert close(d.student_t_quantile(p, dof), float(special.stdtrit(dof, p))), (p, dof)
        # |t| >= 0.01: nearer 0 scipy's own stdtr is off by up to 3e-9 (dof 1, t 1e-8;
        # the closed-form test above covers that range).
        for t in (*RNG.uniform(0.01, 12.0, 8), -RNG.uniform(0.01, 12.0), 40.0):
            assert close(d.student_t_tail(t, dof), float(special.stdtr(dof, -t))), (t, dof)
        for x in (*RNG.uniform(0.0, 4.0 * dof, 6), dof, 6.0 * dof + 60.0):
            assert close(d.chi2_tail(x, dof), float(special.chdtrc(dof, x))), (x, dof)
        for numerator in (1.0, 2.0, 3.0, 5.0, 17.0, 150.5):
            for f in (*RNG.uniform(0.0, 6.0, 3), 1.0, 50.0):
                expected = float(special.fdtrc(numerator, dof, f))
                assert close(d.f_tail(f, numerator, dof), expected), (f, numerator, dof)

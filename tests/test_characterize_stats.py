"""The distribution tails of characterize/stats.py are scipy.stats' answers.

Up to ``distributions.MAX_DOF`` degrees of freedom they are computed without scipy
(characterize/distributions.py; importing scipy.special costs more than a whole ``ecdsim
fit drop-test``): they must agree with scipy.stats to 1e-12 relative. Above it they call
scipy.special directly, which scipy.stats computes with after its argument checks, and
outside the plain domain (dof 0, inf or NaN, probabilities 0 and 1, infinite statistics)
the functions defer to scipy.stats itself: there they agree bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from ecdsim.characterize.stats import (
    chi2_survival,
    f_survival,
    student_t_ppf,
    student_t_sf,
    t_quantile,
    t_two_sided_p,
)

RNG = np.random.default_rng(20261123)
DOFS = [*RNG.uniform(0.5, 60.0, 40), 1.0, 2.0, 3.0, 17.0, 1e6]
EDGE_DOFS = [0.0, -1.0, np.inf, np.nan]


def same(a: object, b: object) -> bool:
    # 1e-12 relative: the series and continued fractions of distributions.py stop at
    # 1e-16 relative change; its log-gamma prefactors lose at most ~1e-13 up to MAX_DOF
    # (tests/test_characterize_distributions.py measures each function on its own).
    x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.all(np.isclose(x, y, rtol=1e-12, atol=0.0, equal_nan=True)))


@pytest.mark.parametrize("dof", DOFS + EDGE_DOFS)
def test_student_t_matches_scipy_stats(dof: float) -> None:
    for p in (*RNG.uniform(0.0, 1.0, 20), 0.0, 1.0, 0.975, 0.5):
        assert same(student_t_ppf(float(p), dof), stats.t.ppf(p, dof)), (p, dof)
    x = np.concatenate([RNG.standard_normal(50) * 10.0, [0.0, np.inf, -np.inf, np.nan]])
    assert same(student_t_sf(x, dof), stats.t.sf(x, dof))
    assert same(student_t_sf(x[:50], dof), stats.t.sf(x[:50], dof))
    assert same(t_quantile(dof), stats.t.ppf(0.975, dof))


def test_student_t_ppf_with_an_array_of_dofs() -> None:
    dofs = np.array(DOFS)
    assert same(student_t_ppf(0.975, dofs), stats.t.ppf(0.975, dofs))
    with_edges = np.array(DOFS + EDGE_DOFS)
    assert same(student_t_ppf(0.975, with_edges), stats.t.ppf(0.975, with_edges))


@pytest.mark.parametrize("dof", [1, 2, 3, 5, 10, 30, 1000])
def test_two_sided_t_and_chi2_match_scipy_stats(dof: int) -> None:
    for value in (*RNG.uniform(0.0, 40.0, 30), 0.0, -1.0, np.inf, np.nan):
        assert same(t_two_sided_p(float(value), dof), 2.0 * stats.t.sf(abs(value), dof))
        assert same(chi2_survival(float(value), dof), stats.chi2.sf(value, dof)), value


@pytest.mark.parametrize(("a", "b"), [(1, 1), (1, 10), (3, 7), (2, 100), (5, 10**9), (0, 3)])
def test_f_survival_matches_scipy_stats(a: int, b: int) -> None:
    for value in (*RNG.uniform(0.0, 20.0, 30), 0.0, -2.0, np.inf, np.nan):
        assert same(f_survival(float(value), a, b), stats.f.sf(value, a, b)), value


@pytest.mark.parametrize("dof", [1e6, 250.0, *EDGE_DOFS])
def test_outside_the_lean_domain_the_answers_are_scipys_bit_for_bit(dof: float) -> None:
    # Above MAX_DOF (200) and outside the plain domain nothing is computed here.
    for p in (*RNG.uniform(0.0, 1.0, 10), 0.0, 1.0, 0.975):
        assert np.array_equal(student_t_ppf(float(p), dof), stats.t.ppf(p, dof), equal_nan=True)
    x = np.concatenate([RNG.standard_normal(20) * 10.0, [0.0, np.inf, np.nan]])
    assert np.array_equal(student_t_sf(x, dof), stats.t.sf(x, dof), equal_nan=True)
    for value in (*RNG.uniform(0.0, 40.0, 10), np.inf):
        # (the functions take a float dof as well: scipy's answer is the reference)
        chi2 = chi2_survival(float(value), dof)  # type: ignore[arg-type]
        f = f_survival(float(value), 3, dof)  # type: ignore[arg-type]
        assert np.array_equal(chi2, stats.chi2.sf(value, dof), equal_nan=True)
        assert np.array_equal(f, stats.f.sf(value, 3, dof), equal_nan=True)

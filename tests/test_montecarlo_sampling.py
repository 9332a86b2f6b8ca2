"""Designs (seeding, chunking, LHS, Sobol), marginal distributions and the Gaussian copula."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.stats import qmc

from ecdsim.montecarlo import sampling
from ecdsim.montecarlo.tolerances import (
    DISTRIBUTIONS,
    NORMAL_TRUNCATION,
    Tolerance,
    ToleranceSet,
)


def test_chunk_streams_are_the_spawned_children_of_the_seed() -> None:
    # The docstring's claim, checked against numpy's own spawn().
    root = np.random.SeedSequence(12345)
    design, chunks = root.spawn(2)
    children = chunks.spawn(5)
    for k in range(5):
        direct = sampling.chunk_seed(12345, k)
        assert direct.generate_state(4).tolist() == children[k].generate_state(4).tolist()
    assert (
        sampling.design_seed(12345).generate_state(4).tolist() == design.generate_state(4).tolist()
    )


def test_random_chunk_is_independent_of_sample_count_and_of_other_chunks() -> None:
    full = sampling.uniforms("random", 3, 4, 100, 2, 100)
    short = sampling.uniforms("random", 3, 4, 100, 2, 37)  # a last chunk of 37 samples
    np.testing.assert_array_equal(full[:37], short)
    other = sampling.uniforms("random", 3, 4, 100, 1, 100)
    assert not np.any(full == other)  # distinct streams share no value (P ~ 1e-13 otherwise)
    again = sampling.uniforms("random", 3, 4, 100, 2, 100)
    np.testing.assert_array_equal(full, again)


def test_each_lhs_chunk_is_a_latin_hypercube() -> None:
    for count in (50, 37):
        u = sampling.uniforms("lhs", 9, 3, 50, 4, count)
        assert u.shape == (count, 3)
        for j in range(3):
            # One point in each of the `count` equal strata of every column.
            strata = np.floor(u[:, j] * count).astype(int)
            assert sorted(strata.tolist()) == list(range(count))


def test_sobol_chunks_join_into_the_first_n_points_of_one_sequence() -> None:
    seed, d, chunk = 77, 5, 64
    n = 300  # not a multiple of the chunk: the last chunk is short
    # The reference, built from numpy's spawn() and one scipy engine, drawn in one go:
    # scrambled with the root seed's first child (the design stream).
    design = np.random.SeedSequence(seed).spawn(2)[0]
    engine = qmc.Sobol(d, scramble=True, rng=np.random.default_rng(design))
    reference = engine.random(512)[:n]
    pieces = [
        sampling.uniforms("sobol", seed, d, chunk, k, min(chunk, n - k * chunk))
        for k in range(math.ceil(n / chunk))
    ]
    np.testing.assert_array_equal(np.concatenate(pieces), reference)


def test_sobol_rejects_a_chunk_that_is_not_a_power_of_two() -> None:
    with pytest.raises(ValueError, match="power-of-two"):
        sampling.uniforms("sobol", 1, 2, 100, 0, 100)


def test_unknown_sampling_and_bad_counts() -> None:
    with pytest.raises(ValueError, match="unknown sampling"):
        sampling.uniforms("halton", 1, 2, 10, 0, 10)
    with pytest.raises(ValueError, match="1 to 10"):
        sampling.uniforms("random", 1, 2, 10, 0, 11)


def test_new_seed_is_a_valid_seed() -> None:
    seed = sampling.new_seed()
    assert 0 <= seed < 2**63
    np.random.SeedSequence(seed)  # accepted


# Marginals: each standard form against scipy's independent implementation.
GRID = np.linspace(0.0005, 0.9995, 1999)


def test_normal_marginal_matches_scipy_and_is_truncated() -> None:
    normal = DISTRIBUTIONS["normal"]
    np.testing.assert_allclose(normal.ppf(GRID), stats.norm.ppf(GRID), rtol=1e-12, atol=1e-14)
    assert normal.ppf(np.array([0.0, 1.0])).tolist() == [-NORMAL_TRUNCATION, NORMAL_TRUNCATION]
    np.testing.assert_allclose(normal.cdf(normal.ppf(GRID)), GRID, rtol=1e-12)


def test_uniform_and_triangular_marginals_match_scipy() -> None:
    uniform = DISTRIBUTIONS["uniform"]
    np.testing.assert_allclose(
        uniform.ppf(GRID), stats.uniform(loc=-1, scale=2).ppf(GRID), rtol=1e-12, atol=1e-15
    )
    triangular = DISTRIBUTIONS["triangular"]
    reference = stats.triang(c=0.5, loc=-1.0, scale=2.0)
    np.testing.assert_allclose(triangular.ppf(GRID), reference.ppf(GRID), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(triangular.cdf(triangular.ppf(GRID)), GRID, rtol=1e-10)
    # Standard deviations used for reporting: scipy's, independently.
    assert uniform.std == pytest.approx(stats.uniform(loc=-1, scale=2).std(), rel=1e-12)
    assert triangular.std == pytest.approx(reference.std(), rel=1e-12)


def test_tolerance_values_and_scores_invert() -> None:
    tolerance = Tolerance("load.start_torque", "triangular", 3.73, 0.2, "N*m", "plus_minus")
    values = tolerance.values(GRID)
    assert values.min() > 3.53
    assert values.max() < 3.93
    np.testing.assert_allclose(tolerance.scores(values), GRID, rtol=1e-10)


def test_gaussian_copula_gives_the_stated_correlation() -> None:
    rho, n = 0.8, 200_000
    normal = [Tolerance(k, "normal", 1.0, 0.1, "", "") for k in ("a", "b")]
    spread = Tolerance("c", "uniform", 5.0, 1.0, "", "")
    matrix = ((1.0, rho, 0.0), (rho, 1.0, 0.0), (0.0, 0.0, 1.0))
    tolerances = ToleranceSet((*normal, spread), matrix)
    u = sampling.uniforms("random", 5, 3, n, 0, n)
    values = tolerances.values(u)
    sample_rho = np.corrcoef(values[:, 0], values[:, 1])[0, 1]
    # Standard error of a sample correlation: (1 - rho^2) / sqrt(n) = 8e-4; allow 5 of them.
    assert sample_rho == pytest.approx(rho, abs=5 * (1 - rho**2) / math.sqrt(n))
    # Marginals unchanged: each normal keeps mean 1 and sigma 0.1 (SE 0.1/sqrt(n) = 2.2e-4).
    assert values[:, 1].mean() == pytest.approx(1.0, abs=5 * 0.1 / math.sqrt(n))
    assert values[:, 1].std() == pytest.approx(0.1, rel=5 / math.sqrt(2 * n))
    # A quantity in no correlation is untouched, bit for bit.
    np.testing.assert_array_equal(values[:, 2], spread.values(u[:, 2]))

"""Statistics and repeatability: each estimator against a hand derivation or a reference."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from scipy import stats as scipy_stats

from ecdsim.montecarlo import intervals, repeatability, stats


def binomial_cdf(k: int, n: int, p: float) -> float:
    """P(B <= k) for B ~ Binomial(n, p), summed by hand."""
    return sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))


def test_percentiles_are_order_statistics_and_inf_stays_inf() -> None:
    # Sorted: 1 2 3 4 5 6 7 8 inf inf (two stalled samples of ten).
    x = np.array([5, 1, 4, 2, 3, np.inf, np.inf, 6, 7, 8], dtype=float)
    found = stats.percentiles(x, {"P1": 0.01, "P50": 0.5, "P80": 0.8, "P81": 0.81, "P99": 0.99})
    # Rank ceil(p * 10): P1 -> 1st, P50 -> 5th, P80 -> 8th, P81 -> 9th (inf), P99 -> 10th.
    assert {k: v["value"] for k, v in found.items()} == {
        "P1": 1.0,
        "P50": 5.0,
        "P80": 8.0,
        "P81": None,
        "P99": None,
    }


@pytest.mark.parametrize(("n", "p"), [(100, 0.5), (1000, 0.01), (250, 0.95), (20, 0.05)])
def test_percentile_interval_ranks_cover_95_percent(n: int, p: float) -> None:
    low, high = intervals.confidence_ranks(n, p)
    # 1-based ranks r = low + 1, s = high + 1; coverage P(r <= B <= s - 1), by hand.
    r = 1 if low is None else low + 1
    s = n + 1 if high is None else high + 1
    below = binomial_cdf(r - 2, n, p) if r >= 2 else 0.0  # P(B < r)
    above = 1.0 - binomial_cdf(s - 1, n, p)  # P(B >= s)
    if low is not None:
        assert below <= 0.025 + 1e-12
    if high is not None:
        assert above <= 0.025 + 1e-12
    # And the interval is the tightest such: one rank further in breaks a tail.
    if low is not None:
        assert binomial_cdf(r, n, p) > 0.025 - 1e-12  # P(B < r + 1)
    if high is not None and s - 2 >= 0:
        assert 1.0 - binomial_cdf(s - 2, n, p) > 0.025 - 1e-12  # P(B >= s - 1)


def test_small_samples_cannot_bound_extreme_percentiles() -> None:
    found = stats.percentiles(np.arange(1.0, 21.0), {"P1": 0.01})
    # With 20 samples, B ~ Bin(20, 0.01) is 0 with probability 0.82: no lower rank exists.
    assert found["P1"]["low"] is None
    assert found["P1"]["value"] == 1.0


def test_clopper_pearson_against_closed_forms() -> None:
    # k = 0: upper = 1 - 0.025^(1/n); k = n: lower = 0.025^(1/n) (beta quantiles, by hand).
    low, high = intervals.proportion_interval(0, 100)
    assert low == 0.0
    assert high == pytest.approx(1.0 - 0.025 ** (1 / 100), rel=1e-10)
    low, high = intervals.proportion_interval(50, 50)
    assert low == pytest.approx(0.025 ** (1 / 50), rel=1e-10)
    assert high == 1.0
    # Interior: the bounds are where the binomial tails equal 2.5 % (definition).
    low, high = intervals.proportion_interval(7, 40)
    assert binomial_cdf(6, 40, low) == pytest.approx(0.975, abs=1e-9)
    assert binomial_cdf(7, 40, high) == pytest.approx(0.025, abs=1e-9)


def test_describe_reports_infinite_mean_honestly() -> None:
    x = np.array([1.0, 2.0, 3.0, np.inf])
    d = stats.describe(x)
    assert d["mean"] is None
    assert d["std"] is None
    assert d["mean_arriving"] == 2.0
    assert d["std_arriving"] == 1.0  # sample standard deviation of 1, 2, 3
    assert d["arriving"] == 3
    assert d["max"] is None
    assert d["min"] == 1.0
    finite = stats.describe(np.array([1.0, 2.0, 3.0]))
    assert finite["mean"] == finite["mean_arriving"] == 2.0


def test_stall_counts_and_interval() -> None:
    found = stats.stall(np.array([True, False, False, False]))
    assert found["count"] == 1
    assert found["probability"] == 0.25
    assert found["interval95"] == list(intervals.proportion_interval(1, 4))


def test_src_against_a_least_squares_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(2)
    n = 10_000
    x = rng.normal(size=(n, 3)) * np.array([1.0, 0.5, 2.0]) + np.array([3.0, -1.0, 0.0])
    y = 2.0 * x[:, 0] - 3.0 * x[:, 1] + 0.1 * x[:, 2] + rng.normal(scale=0.7, size=n)
    monkeypatch.setattr(stats, "REGRESSION_BLOCK", 1_000)  # ten blocks of accumulation
    src, r2 = stats.standardized_regression(x, y)
    # Reference: ordinary least squares on [1, x] by numpy, scaled by the sample stds.
    design = np.column_stack([np.ones(n), x])
    b, *_ = np.linalg.lstsq(design, y, rcond=None)
    residual = y - design @ b
    expected_r2 = 1.0 - residual @ residual / np.sum((y - y.mean()) ** 2)
    expected_src = b[1:] * x.std(axis=0) / y.std()
    assert src is not None
    assert r2 is not None
    # Same least-squares problem solved two ways: agreement to rounding (1e-10).
    np.testing.assert_allclose(src, expected_src, rtol=1e-10)
    assert r2 == pytest.approx(expected_r2, rel=1e-10)


def test_src_is_undefined_for_too_few_samples_or_a_constant() -> None:
    assert stats.standardized_regression(np.ones((3, 2)), np.arange(3.0)) == (None, None)
    x = np.column_stack([np.arange(10.0), np.ones(10)])
    assert stats.standardized_regression(x, np.arange(10.0)) == (None, None)


def binned_share_linear(bins: int) -> float:
    """Var(E[Z | bin]) for a standard normal Z cut into equal-probability bins, by hand.

    E[Z | a < Z < b] = (phi(a) - phi(b)) / (1 / M); the bins' means have mean 0.
    """
    edges = scipy_stats.norm.ppf(np.linspace(0.0, 1.0, bins + 1))
    phi = scipy_stats.norm.pdf(edges)  # 0 at the infinite ends
    means = (phi[:-1] - phi[1:]) * bins
    return float(np.mean(means**2))


def binned_share_square(bins: int) -> float:
    """Var(E[Z^2 | bin]) / Var(Z^2) for a standard normal Z, by hand.

    E[Z^2 | a < Z < b] = 1 + (a phi(a) - b phi(b)) / (1 / M); Var(Z^2) = 2.
    """
    edges = scipy_stats.norm.ppf(np.linspace(0.0, 1.0, bins + 1))
    with np.errstate(invalid="ignore"):  # inf * 0 at the open ends: the term is 0
        term = np.nan_to_num(edges * scipy_stats.norm.pdf(edges))
    means = 1.0 + (term[:-1] - term[1:]) * bins
    return float(np.mean((means - 1.0) ** 2) / 2.0)


def test_first_order_indices_against_binned_variance_by_hand() -> None:
    rng = np.random.default_rng(11)
    n = 200_000
    z = rng.normal(size=(n, 3))
    scores = scipy_stats.norm.cdf(z)
    bins = stats.bin_count(n)
    assert bins == 58  # round(200000 ** (1/3)) = 58
    labels = stats.bin_labels(scores, bins)
    linear = 2.0 * z[:, 0] + 1.0 * z[:, 1]  # Var = 5; x3 has no effect
    indices = stats.first_order_indices(labels, linear, bins)
    assert indices is not None
    share = binned_share_linear(bins)
    # Delta-method standard error of a squared correlation, 2 sqrt(S) (1 - S) / sqrt(n),
    # is below 2e-3 here; 0.01 is five of them.
    assert indices[0] == pytest.approx(4.0 / 5.0 * share, abs=0.01)
    assert indices[1] == pytest.approx(1.0 / 5.0 * share, abs=0.01)
    assert abs(indices[2]) < 0.01
    # A symmetric nonlinear effect: invisible to a linear fit, seen by the index.
    square = z[:, 0] ** 2
    indices = stats.first_order_indices(labels, square, bins)
    src, r2 = stats.standardized_regression(z, square)
    assert indices is not None
    assert src is not None
    assert r2 is not None
    assert indices[0] == pytest.approx(binned_share_square(bins), abs=0.01)
    assert abs(indices[1]) < 0.01
    assert r2 < 0.01  # E[Z^3] = 0: no linear trend (SE of R^2 with 3 inputs ~ 3/n)


def test_repeatability_against_a_normal_scatter() -> None:
    rng = np.random.default_rng(5)
    n, sigma, nominal, within, runs = 200_000, 0.2, 30.0, 0.5, 500
    times = nominal + sigma * rng.normal(size=n)
    found = repeatability.study(times, nominal, within, runs)
    # P(|t - t0| <= w) = 2 Phi(w / sigma) - 1; binomial SE 3e-4, five of them allowed.
    p = 2.0 * scipy_stats.norm.cdf(within / sigma) - 1.0
    assert found["fraction_within"] == pytest.approx(p, abs=5 * math.sqrt(p * (1 - p) / n))
    low, high = found["fraction_within_interval95"]
    assert low < p < high
    assert found["probability_all_within"] == pytest.approx(found["fraction_within"] ** runs)
    # Median of the largest |t - t0| over 500 runs: sigma * Phi^-1((1 + 0.5^(1/500)) / 2).
    q = 0.5 ** (1.0 / runs)
    typical = sigma * scipy_stats.norm.ppf((1.0 + q) / 2.0)
    # SE of that sample quantile: sqrt(q (1 - q) / n) / (2 phi(z) / sigma) = 3.5e-3 s.
    density = 2.0 * scipy_stats.norm.pdf(typical / sigma) / sigma
    assert found["typical_max_deviation_s"] == pytest.approx(
        typical, abs=5 * math.sqrt(q * (1 - q) / n) / density
    )
    assert found["meets_stated_spread"] is bool(typical <= within)  # 0.64 s > 0.5 s: False
    campaign = found["campaign"]
    first = times[:runs]
    assert campaign["max_deviation_s"] == float(np.max(np.abs(first - nominal)))
    assert campaign["all_within"] is bool(np.all(np.abs(first - nominal) <= within))
    assert campaign["std_s"] == pytest.approx(float(np.std(first, ddof=1)), rel=1e-12)


def test_repeatability_with_stalls_and_a_stalled_nominal() -> None:
    times = np.array([10.0, 10.2, np.inf, 9.9])
    found = repeatability.study(times, 10.0, 0.5, 2)
    assert found["fraction_within"] == 0.75  # the stalled run is never within
    assert found["campaign"]["all_within"] is True  # the first two runs
    found = repeatability.study(times, 10.0, 0.5, 4)
    assert found["campaign"]["stalled"] == 1
    assert found["campaign"]["max_deviation_s"] is None
    assert found["campaign"]["all_within"] is False
    stalled = repeatability.study(times, None, 0.5, 4)
    assert "nominal system stalls" in stalled["note"]


def test_a_sample_mask_equals_dropping_the_samples() -> None:
    # The masked accumulation (no copies) against the plain computation on the kept rows.
    rng = np.random.default_rng(8)
    n = 5_000
    x = rng.normal(size=(n, 2))
    y = x[:, 0] + 0.3 * x[:, 1] ** 2 + rng.normal(scale=0.1, size=n)
    use = rng.random(n) > 0.3
    y_with_stalls = np.where(use, y, np.inf)
    labels = stats.bin_labels(scipy_stats.norm.cdf(x), 17)
    src, r2 = stats.standardized_regression(x, y_with_stalls, use)
    expected_src, expected_r2 = stats.standardized_regression(x[use], y[use])
    assert src is not None
    assert expected_src is not None
    np.testing.assert_allclose(src, expected_src, rtol=1e-12)  # same sums, other order
    assert r2 == pytest.approx(expected_r2, rel=1e-12)
    first = stats.first_order_indices(labels, y_with_stalls, 17, use)
    expected_first = stats.first_order_indices(labels[use], y[use], 17)
    assert first is not None
    assert expected_first is not None
    np.testing.assert_allclose(first, expected_first, rtol=1e-9)


def _samples(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    if kind == "continuous, stalled tail":
        x = rng.lognormal(0.0, 0.2, n)
        x[rng.random(n) < 0.02] = np.inf
    elif kind == "negative, infinite both ways":
        x = rng.normal(-1.0, 3.0, n)
        x[rng.random(n) < 0.01] = -np.inf
        x[rng.random(n) < 0.01] = np.inf
    elif kind == "heavy ties":
        x = rng.integers(0, 5, n).astype(float)
    elif kind == "NaN tail":
        x = rng.random(n)
        x[rng.random(n) < 0.03] = np.nan
    else:  # one value
        x = np.full(n, 2.5)
    return x


@pytest.mark.parametrize(
    "kind",
    [
        "continuous, stalled tail",
        "negative, infinite both ways",
        "heavy ties",
        "NaN tail",
        "one value",
    ],
)
@pytest.mark.parametrize("compiled", [False, True], ids=["numpy", "numba"])
def test_order_statistics_are_those_of_a_full_sort(
    kind: str, compiled: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bracketed selection returns exactly np.sort(x)[ranks] (NaN last), whatever the
    data, by the NumPy passes and by the compiled one; sizes shrunk so that 200,000
    samples take the bracketed path."""
    monkeypatch.setattr(intervals, "compiled_selection", lambda: compiled)
    monkeypatch.setattr(intervals, "BRACKET_MIN_SIZE", 10_000)
    monkeypatch.setattr(intervals, "BRACKET_SUBSAMPLE", 40_000)
    n = 200_000
    x = _samples(kind, n, np.random.default_rng(17))
    ranks = [0, 1, 1999, n // 20, n // 2 - 7, n // 2, 190_000, 196_000, n - 2, n - 1]
    for p in (0.01, 0.05, 0.5, 0.95, 0.99):
        ranks += [intervals.rank_of(n, p), *(r for r in intervals.confidence_ranks(n, p) if r)]
    expected = np.sort(x)[ranks]  # the reference: a full sort
    found = intervals.order_statistics(x, ranks)
    assert np.array_equal(found, expected, equal_nan=True)
    copy = x.copy()
    again = intervals.order_statistics(copy, ranks, overwrite=True)
    assert np.array_equal(again, expected, equal_nan=True)
    assert np.array_equal(np.sort(copy), np.sort(x), equal_nan=True)  # reordered at most


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy", "numba"])
def test_order_statistics_answer_from_the_brackets_on_a_smooth_sample(
    compiled: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """On continuous data the brackets hold their ranks (no fall-back to a partition of
    the whole sample), and the answer is still the full sort's; the compiled pass is
    taken when asked for (the brackets of continuous data are disjoint)."""
    monkeypatch.setattr(intervals, "compiled_selection", lambda: compiled)
    monkeypatch.setattr(intervals, "BRACKET_MIN_SIZE", 10_000)
    monkeypatch.setattr(intervals, "BRACKET_SUBSAMPLE", 40_000)
    calls: list[int] = []
    original = intervals._bracketed_compiled

    def spy(x: Any, edges: Any, members: Any) -> Any:
        calls.append(len(edges))
        return original(x, edges, members)

    monkeypatch.setattr(intervals, "_bracketed_compiled", spy)
    x = _samples("continuous, stalled tail", 200_000, np.random.default_rng(3))
    ranks = [1999, 9999, 99_999, 189_999, 193_000]
    found = intervals._bracketed(x, ranks)
    assert found is not None
    assert [found[r] for r in ranks] == list(np.sort(x)[ranks])
    assert bool(calls) == compiled


def test_order_statistics_refuse_ranks_outside_the_sample() -> None:
    with pytest.raises(IndexError, match="outside a sample of 3"):
        intervals.order_statistics(np.array([1.0, 2.0, 3.0]), [3])


def test_repeatability_in_place_of_reordered_times_is_the_same() -> None:
    """The summary's way (times reordered by its percentiles, deviations computed in
    their place, the first campaign handed over in sample order) gives the same figures
    as the times in order, to the bit."""
    rng = np.random.default_rng(8)
    times = rng.normal(26.0, 0.2, 5000)
    times[[3, 700, 4100]] = np.inf  # one stall inside the first campaign of 500
    expected = repeatability.study(times, 26.0, 0.5, 500)
    reordered = np.sort(times)  # as a partition in place could leave them
    found = repeatability.study(reordered, 26.0, 0.5, 500, overwrite=True, first=times[:500])
    assert found == expected
    assert np.array_equal(np.sort(reordered), np.sort(np.abs(times - 26.0)))  # overwritten

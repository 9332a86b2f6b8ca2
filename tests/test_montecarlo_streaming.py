"""Monte Carlo statistics computed while the chunks are solved (issue 13, item 2).

The sensitivity sums each chunk carries (:mod:`ecdsim.montecarlo.streaming`) are merged
in chunk order; merged, they must give what a one-pass computation over all samples
gives (:func:`ecdsim.montecarlo.stats.sensitivity`, itself checked against least squares
and hand-computed binned variances in test_montecarlo_stats.py). The LHS design is drawn
with NumPy directly and must be scipy's LatinHypercube bit for bit.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from scipy.stats import qmc

from ecdsim._types import FloatArray
from ecdsim.config import load_config
from ecdsim.montecarlo import build_plan, run, sampling, store, streaming
from ecdsim.montecarlo.run import chunk_scores_and_values, evaluate_chunk
from ecdsim.montecarlo.stats import (
    bin_count,
    bin_labels,
    sensitivity,
    sensitivity_from_sums,
    summarize,
)
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "paper_cc16_tolerances.toml"
# Merged pairwise (Chan et al.) against one pass: the same sums in another order, so they
# agree to rounding; the SRCs go through a d x d solve, which can lose a few digits more.
MERGED = 1e-11


@pytest.mark.parametrize(
    ("seed", "dimension", "chunk_size", "index", "count"),
    [(7, 8, 4096, 3, 4096), (1, 3, 100, 0, 37), (2**40, 1, 5, 9, 5)],
)
def test_lhs_is_scipys_latin_hypercube_bit_for_bit(
    seed: int, dimension: int, chunk_size: int, index: int, count: int
) -> None:
    found = sampling.uniforms("lhs", seed, dimension, chunk_size, index, count)
    engine = qmc.LatinHypercube(dimension, rng=sampling.chunk_generator(seed, index))
    assert np.array_equal(found, engine.random(count))


def random_chunk(
    rng: np.random.Generator, n: int, d: int, bins: int
) -> tuple[FloatArray, np.ndarray[Any, Any], FloatArray]:
    values = rng.normal(size=(n, d)) * np.arange(1.0, d + 1.0) + 10.0
    scores = rng.random((n, d))
    labels = bin_labels(scores, bins)
    times = 40.0 + values @ np.linspace(1.0, -1.0, d) + rng.normal(size=n) + 5.0 * scores[:, 0]
    times[rng.random(n) < 0.01] = np.inf  # stalled samples leave the sums
    return values, labels, times


def test_merged_chunk_sums_equal_one_pass_over_all_samples() -> None:
    rng = np.random.default_rng(4)
    d, bins = 5, 12
    chunks = [random_chunk(rng, n, d, bins) for n in (1000, 37, 2500, 1, 800)]
    merged = streaming.Sums.empty(d, bins)
    for values, labels, times in chunks:
        merged = merged.merge(streaming.sums_of(values, labels, times, bins))
    values, labels, times = (np.concatenate(parts) for parts in zip(*chunks, strict=True))
    keys = [f"x{j}" for j in range(d)]
    expected = sensitivity(keys, values, labels, bins, times)
    found = sensitivity_from_sums(keys, merged, bins)
    assert found["samples"] == expected["samples"] == int(np.isfinite(times).sum())
    assert found["r_squared"] == pytest.approx(expected["r_squared"], rel=MERGED)
    by_key = {row["key"]: row for row in expected["inputs"]}
    for row in found["inputs"]:
        assert row["src"] == pytest.approx(by_key[row["key"]]["src"], rel=MERGED)
        # The first-order index of a no-effect input is ~0: compare absolutely there.
        assert row["first_order"] == pytest.approx(
            by_key[row["key"]]["first_order"], rel=MERGED, abs=1e-13
        )


def test_sums_survive_the_metadata_text_exactly() -> None:
    rng = np.random.default_rng(9)
    values, labels, times = random_chunk(rng, 300, 3, 7)
    empty = streaming.Sums.empty(3, 7)
    odd = streaming.Sums(
        np.inf,
        np.full(3, np.nan),
        -np.inf,
        empty.gram,
        empty.cross,
        np.nan,
        empty.bin_counts,
        empty.bin_sums,
    )
    sums = [streaming.sums_of(values, labels, times, 7), odd]
    back = streaming.decode(streaming.encode(sums), 2, 3, 7)
    for a, b in zip(sums, back, strict=True):
        assert np.array_equal(a.to_vector(), b.to_vector(), equal_nan=True)
    with pytest.raises(ValueError, match="wrong length"):
        streaming.decode(streaming.encode(sums), 2, 3, 8)


def test_summary_of_files_without_sums_is_the_same(tmp_path: Path) -> None:
    """A chunk file written before the sums existed is reduced from its own columns."""
    plan = build_plan(load_config(EXAMPLE), 3000, "exact", chunk_size=1024)
    out = tmp_path / "study"
    run(plan, out)
    with_sums = summarize(plan, out)
    path = store.chunk_path(out, 1)
    table = pq.read_table(path)
    tag = json.loads(table.schema.metadata[store.METADATA_KEY])
    del tag[streaming.KEY]
    pq.write_table(
        table.replace_schema_metadata({store.METADATA_KEY: json.dumps(tag).encode()}), path
    )
    assert summarize(plan, out) == with_sums


def test_chunk_sums_bin_like_the_summary_did() -> None:
    """The bins are those of the quantities' own scores, as before (stats.bin_labels)."""
    plan = build_plan(load_config(EXAMPLE), 2000, "exact", chunk_size=2000)
    columns = evaluate_chunk(plan, 0).columns
    bins = bin_count(plan.samples)
    [first, *_] = streaming.chunk_sums(plan, columns)
    tolerance = plan.tolerances.tolerances[0]
    labels = bin_labels(tolerance.scores(columns[tolerance.key]), bins)
    assert np.array_equal(first.bin_counts[0], np.bincount(labels, minlength=bins))


def test_an_in_process_summary_from_memory_equals_one_from_the_files(tmp_path: Path) -> None:
    """run() keeps the summary's columns; the summary is the same read from the files."""
    plan = build_plan(load_config(EXAMPLE), 3000, "exact", chunk_size=1024)
    out = tmp_path / "study"
    run(plan, out)
    assert sorted(store._KEPT[0].filled) == [0, 1, 2]
    from_memory = summarize(plan, out)
    assert not store._KEPT  # taken, and forgotten
    assert summarize(plan, out) == from_memory


def test_bin_labels_floor_the_scaled_score_and_cap_the_top() -> None:
    scores = np.array([[0.0, 0.05], [0.0999, 0.1], [0.95, np.nextafter(1.0, 0.0)], [1.0, 0.5]])
    # floor(10 * score) by hand, capped at bins - 1 = 9 (a score of 1, or one that rounds
    # up to 10 when scaled, belongs to the top bin).
    expected = np.array([[0, 0], [0, 1], [9, 9], [9, 5]], dtype=np.uint8)
    labels = bin_labels(scores, 10)
    assert labels.dtype == np.uint8
    np.testing.assert_array_equal(labels, expected)


def test_a_chunk_file_with_the_wrong_samples_is_refused(tmp_path: Path) -> None:
    """Chunks read back from their files are checked to hold their own sample indices."""
    plan = build_plan(load_config(EXAMPLE), 3000, "exact", chunk_size=1024)
    out = tmp_path / "study"
    run(plan, out)
    store.take_kept(out, plan.identity_sha256)  # forget the in-memory columns: read the files
    path = store.chunk_path(out, 1)
    table = pq.read_table(path)
    shifted = pa.array(table.column("sample").to_numpy() + 1)
    table = table.set_column(table.schema.get_field_index("sample"), "sample", shifted)
    pq.write_table(table, path)  # same tag (identity, index, rows): only the indices differ
    with pytest.raises(ValueError, match="chunk-000001.parquet: does not hold samples 1024..2047"):
        summarize(plan, out)


def test_merged_chunk_moments_equal_one_pass_over_all_samples() -> None:
    """Moments merged chunk by chunk (inf, an all-stalled chunk, one-sample chunks) give
    the mean and standard deviation (n - 1) of all finite values, the extremes of all."""
    rng = np.random.default_rng(11)
    chunks = [rng.normal(30.0, 2.0, n) for n in (1000, 1, 2500, 37, 800)]
    chunks[2][rng.random(2500) < 0.05] = np.inf
    chunks.append(np.full(40, np.inf))  # every sample of this chunk stalls
    chunks.append(np.array([31.5]))
    merged = streaming.Moments.empty()
    for values in chunks:
        merged = merged.merge(streaming.Moments.of(values))
    everything = np.concatenate(chunks)
    finite = everything[np.isfinite(everything)]
    mean, std = merged.mean_and_std()
    assert merged.size == everything.size
    assert merged.count == finite.size
    # Rounding only: each chunk's pairwise sums and the exact pairwise update.
    assert mean == pytest.approx(np.mean(finite), rel=MERGED)
    assert std == pytest.approx(np.std(finite, ddof=1), rel=MERGED)
    assert (merged.lowest, merged.highest) == (np.min(everything), np.inf)
    again = streaming.decode_moments(streaming.encode_moments([(merged, merged)]), 1)
    assert again == [(merged, merged)]
    with pytest.raises(ValueError, match="wrong length"):
        streaming.decode_moments(streaming.encode_moments([(merged, merged)]), 2)


def test_summary_of_files_without_moments_is_the_same(tmp_path: Path) -> None:
    """A chunk file written before the moments existed gets them from its own rows."""
    plan = build_plan(load_config(EXAMPLE), 3000, "exact", chunk_size=1024)
    out = tmp_path / "study"
    run(plan, out)
    with_moments = summarize(plan, out)
    path = store.chunk_path(out, 2)
    table = pq.read_table(path)
    tag = json.loads(table.schema.metadata[store.METADATA_KEY])
    del tag[streaming.MOMENTS_KEY]
    pq.write_table(
        table.replace_schema_metadata({store.METADATA_KEY: json.dumps(tag).encode()}), path
    )
    assert summarize(plan, out) == with_moments


def test_compiled_chunk_sums_are_numpys_to_rounding() -> None:
    """The numba kernel's sums against NumPy's (streaming.sums_of), per temperature: all
    samples arriving, a stalled few (a temperature of its own set), none arriving. The
    counts and bin sums add in the same order (equal); the means and centred sums add in
    another order: relative 1e-12 holds n * eps = 4e-13 for these 4,000 samples."""
    from ecdsim.montecarlo import _streaming_numba

    rng = np.random.default_rng(11)
    d, bins, n = 6, 16, 4000
    values, labels, times = random_chunk(rng, n, d, bins)
    finite = times.copy()
    finite[~np.isfinite(finite)] = 40.0
    rows = np.stack([finite, times, times, np.full(n, np.inf)])
    # Scores whose labels are ``labels`` (the middle of each bin; bin_labels of the
    # sampled scores is tested in test_bin_labels_floor_the_scaled_score_and_cap_the_top).
    scores = (labels.astype(float) + 0.5) / bins
    assert np.array_equal(bin_labels(scores, bins), labels)
    found = _streaming_numba.chunk_sums(
        np.ascontiguousarray(values.T), np.ascontiguousarray(scores.T), list(rows), bins
    )
    for row, part in zip(rows, found, strict=True):
        got = streaming.Sums(*part)
        expected = streaming.sums_of(values, labels, row, bins)
        assert got.count == expected.count
        assert np.array_equal(got.bin_counts, expected.bin_counts)
        assert np.array_equal(got.bin_sums, expected.bin_sums)
        for name in ("mean_x", "mean_y", "gram", "cross", "total"):
            np.testing.assert_allclose(
                getattr(got, name), getattr(expected, name), rtol=1e-12, atol=0.0, err_msg=name
            )


def test_large_chunks_take_the_compiled_sums(monkeypatch: pytest.MonkeyPatch) -> None:
    """The kernel is chosen by the chunk's size (as the exact solution's) and switched off
    by ECDSIM_NUMBA=0; both give the summary's sums of a real chunk to rounding."""
    plan = build_plan(load_config(EXAMPLE), 20_000, "exact", chunk_size=20_000)
    scores, _ = chunk_scores_and_values(plan, 0)
    columns = evaluate_chunk(plan, 0).columns
    assert streaming.compiled_sums(20_000 * len(plan.temperatures))
    compiled = streaming.chunk_sums(plan, columns, scores)
    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    assert not streaming.compiled_sums(20_000 * len(plan.temperatures))
    plain = streaming.chunk_sums(plan, columns, scores)
    for a, b in zip(compiled, plain, strict=True):
        assert a.count == b.count
        assert np.array_equal(a.bin_sums, b.bin_sums)
        # Two orders of the same 20,000-term sums: n * eps = 4e-12 relative, and the
        # off-diagonal Gram terms of independent inputs cancel to ~1/sqrt(n) of their
        # terms' size, which costs up to two digits more: 1e-11 would be tight, so 1e-10.
        np.testing.assert_allclose(a.to_vector(), b.to_vector(), rtol=1e-10, atol=0.0)

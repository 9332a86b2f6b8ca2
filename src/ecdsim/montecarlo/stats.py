"""Statistics of a finished study, per temperature (definitions in docs/montecarlo.md).

Stalled samples. A sample that stalls never reaches the end of travel: its deployment
time is +inf, and it stays in every statistic that can hold it honestly.

* Percentiles are order statistics over *all* N samples, stalled ones included (the
  inverted empirical CDF: P_p is the ceil(p*N)-th smallest time). Where that rank falls
  among the stalled samples the percentile is +inf ("does not arrive"; null in JSON).
  No interpolation is done, so a percentile is never a blend of a time and +inf.
* Each percentile has a distribution-free 95 % confidence interval: the order statistics
  of ranks r and s taken from the binomial distribution of the number of samples below
  the true percentile (null where the sample is too small to bound it).
* The mean and standard deviation over all samples are infinite as soon as one sample
  stalls: they are reported (null otherwise) together with the mean and standard
  deviation over the samples that arrive, and the stall probability with its exact
  (Clopper-Pearson) 95 % interval.
* The end (latch) speed is summarised over the samples that arrive.

Sensitivity of the deployment time to each toleranced quantity, on the samples that
arrive at each temperature:

* standardised regression coefficients (SRC): the least-squares fit
  ``t = b0 + sum(b_i * x_i)`` scaled as ``SRC_i = b_i * std(x_i) / std(t)``, with the
  fit's R^2. For a nearly linear response (R^2 near 1) and independent inputs,
  SRC_i^2 is the share of the variance of t due to x_i and the SRCs rank the inputs.
* first-order (Sobol) indices ``S_i = Var(E[t | x_i]) / Var(t)``, estimated from the
  same samples whatever the design ("given data"): each input's probability range is
  cut into M equal-probability bins by its own distribution function, and S_i is the
  between-bin share of the variance, corrected for the noise of the bin means
  (``(SS_between - (M - 1) * MS_within) / SS_total``). No special (Saltelli) design is
  needed; with correlated inputs S_i includes the effect of the inputs correlated
  with x_i, so the indices no longer add up to at most 1.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float
from ecdsim._version import __version__
from ecdsim.montecarlo import repeatability, streaming

# bin_count, bin_labels, MAX_BINS and SUMMARY_THREADS live in columns (shared with
# streaming and budget) and are re-exported here, where the estimators that use them are.
from ecdsim.montecarlo.columns import MAX_BINS as MAX_BINS
from ecdsim.montecarlo.columns import SUMMARY_THREADS as SUMMARY_THREADS
from ecdsim.montecarlo.columns import bin_count as bin_count
from ecdsim.montecarlo.columns import bin_labels as bin_labels
from ecdsim.montecarlo.columns import output_column
from ecdsim.montecarlo.intervals import (
    confidence_ranks,
    order_statistics,
    proportion_interval,
    rank_of,
)
from ecdsim.montecarlo.streaming import Moments, Sums

if TYPE_CHECKING:
    from pathlib import Path

    from ecdsim.montecarlo.run import Plan
    from ecdsim.montecarlo.store import ChunkReader

PERCENTILES: dict[str, float] = {"P1": 0.01, "P5": 0.05, "P50": 0.50, "P95": 0.95, "P99": 0.99}
REGRESSION_BLOCK = 1_000_000


def _number(value: float) -> float | None:
    """A float for JSON: None for inf or NaN."""
    return float(value) if math.isfinite(value) else None


def percentiles(
    values: ArrayLike,
    probabilities: Mapping[str, float] = PERCENTILES,
    *,
    overwrite: bool = False,
) -> dict[str, dict[str, float | None]]:
    """Each percentile of the values (inf allowed) and its 95 % interval.

    Returns {name: {"value": v, "low": lo, "high": hi}} with None for +inf (a percentile
    in the stalled tail) and for interval ends the sample cannot bound. ``overwrite``:
    the values may be reordered in place (no copy of a whole column).
    """
    x = as_float(values).reshape(-1)
    n = x.size
    if n == 0:
        return {name: {"value": None, "low": None, "high": None} for name in probabilities}
    ranks: dict[str, tuple[int, int | None, int | None]] = {}
    for name, p in probabilities.items():
        ranks[name] = (rank_of(n, p), *confidence_ranks(n, p))
    needed = sorted({r for triple in ranks.values() for r in triple if r is not None})
    ordered = dict(zip(needed, order_statistics(x, needed, overwrite=overwrite), strict=True))

    def at(rank: int | None) -> float | None:
        return None if rank is None else _number(ordered[rank])

    return {
        name: {"value": at(k), "low": at(lo), "high": at(hi)} for name, (k, lo, hi) in ranks.items()
    }


def describe(
    values: ArrayLike, *, overwrite: bool = False, known: Moments | None = None
) -> dict[str, Any]:
    """Percentiles over all values (inf allowed), moments over all and over finite ones.

    ``overwrite``: the values may be reordered in place once the moments are taken.
    ``known``: the values' moments merged chunk by chunk (:class:`.streaming.Moments`),
    used instead of a pass over the values where they are finite.
    """
    x = as_float(values).reshape(-1)
    if known is not None and known.size == x.size:
        mean, std = known.mean_and_std()
        if (mean is None or math.isfinite(mean)) and (std is None or math.isfinite(std)):
            all_finite = known.count == known.size
            return {
                "samples": int(x.size),
                "arriving": int(known.count),
                "percentiles": percentiles(x, overwrite=overwrite),
                "mean": mean if all_finite else None,
                "std": std if all_finite else None,
                "mean_arriving": mean,
                "std_arriving": std,
                "min": _number(known.lowest) if x.size else None,
                "max": _number(known.highest) if x.size else None,
            }
    is_finite = np.isfinite(x)
    finite = x if is_finite.all() else x[is_finite]  # no copy when every sample arrives
    arriving = finite.size
    all_finite = arriving == x.size

    def moments(sample: FloatArray) -> tuple[float | None, float | None]:
        if not sample.size:
            return None, None
        with np.errstate(over="ignore"):
            mean = float(np.mean(sample))
            std = float(np.std(sample, ddof=1)) if sample.size > 1 else None
        if not (np.isfinite(mean) and (std is None or np.isfinite(std))):
            # Finite times near 1e300 s (damping_rate = 1e-304) overflow the sums: scaled
            # by the largest magnitude the moments stay finite (JSON has no infinity).
            scale = float(np.max(np.abs(sample)))
            mean = scale * float(np.mean(sample / scale))
            std = scale * float(np.std(sample / scale, ddof=1)) if sample.size > 1 else None
        return mean, std

    mean, std = moments(finite)
    lowest = _number(float(np.min(x))) if x.size else None
    highest = _number(float(np.max(x))) if x.size else None
    return {
        "samples": int(x.size),
        "arriving": int(arriving),
        "percentiles": percentiles(x, overwrite=overwrite),  # last: it may reorder x
        "mean": mean if all_finite else None,
        "std": std if all_finite else None,
        "mean_arriving": mean,
        "std_arriving": std,
        "min": lowest,
        "max": highest,
    }


def stall(stalled: ArrayLike) -> dict[str, Any]:
    """Stall count, probability and its exact 95 % interval."""
    flags = np.asarray(stalled, dtype=bool).reshape(-1)
    count = int(np.count_nonzero(flags))
    low, high = proportion_interval(count, flags.size)
    return {
        "count": count,
        "probability": count / flags.size if flags.size else None,
        "interval95": [low, high],
    }


def _blocks(n: int) -> range:
    return range(0, n, REGRESSION_BLOCK)


def standardized_regression(
    inputs: FloatArray, response: FloatArray, use: BoolArray | None = None
) -> tuple[FloatArray | None, float | None]:
    """SRCs of each input column and the fit's R^2 (least squares with an intercept).

    ``inputs`` has shape (n, d), ``response`` shape (n,); ``use`` selects the samples
    that enter the fit (all if None). None where the fit is not defined (fewer than
    d + 2 samples, or a constant column or response).

    The normal equations are accumulated over blocks of rows on centred data, so that a
    study of millions of samples needs no (n, d) temporary.
    """
    x = np.asarray(inputs, dtype=float)
    y = np.asarray(response, dtype=float)
    n, d = x.shape
    keep = np.ones(n, dtype=bool) if use is None else np.asarray(use, dtype=bool)
    count = int(np.count_nonzero(keep))
    if count < d + 2:
        return None, None

    def block(start: int) -> tuple[FloatArray, FloatArray]:
        xb, yb = x[start : start + REGRESSION_BLOCK], y[start : start + REGRESSION_BLOCK]
        if use is None:
            return xb, yb
        rows = keep[start : start + REGRESSION_BLOCK]
        return xb[rows], yb[rows]

    x_sum, y_sum = np.zeros(d), 0.0
    for start in _blocks(n):
        xb, yb = block(start)
        x_sum += xb.sum(axis=0)
        y_sum += float(yb.sum())
    x_mean, y_mean = x_sum / count, y_sum / count
    gram = np.zeros((d, d))
    cross = np.zeros(d)
    total = 0.0
    for start in _blocks(n):
        xb, yb = block(start)
        dx = xb - x_mean
        dy = yb - y_mean
        gram += dx.T @ dx
        cross += dx.T @ dy
        total += float(dy @ dy)
    return regression_from_sums(gram, cross, total)


def regression_from_sums(
    gram: FloatArray, cross: FloatArray, total: float
) -> tuple[FloatArray | None, float | None]:
    """SRCs and R^2 from centred sums: ``dx.T @ dx``, ``dx.T @ dy`` and ``dy @ dy``."""
    x_std = np.sqrt(np.diag(gram))
    if total <= 0.0 or np.any(x_std <= 0.0):
        return None, None
    y_std = math.sqrt(total)
    correlation = gram / np.outer(x_std, x_std)
    with_response = cross / (x_std * y_std)
    coefficients = np.linalg.lstsq(correlation, with_response, rcond=None)[0]
    r_squared = float(coefficients @ with_response)
    return as_float(coefficients), r_squared


def first_order_indices(
    labels: np.ndarray[Any, Any],
    response: FloatArray,
    bins: int,
    use: BoolArray | None = None,
) -> FloatArray | None:
    """Given-data first-order indices ``Var(E[t | x_i]) / Var(t)`` of each input column.

    ``labels`` (n, d) are the inputs' equal-probability bins (:func:`bin_labels`);
    ``use`` selects the samples (all if None). The between-bin sum of squares is corrected
    for the noise of the bin means (an ANOVA ``epsilon^2``):
    ``(SS_between - (M - 1) * SS_within / (n - M)) / SS_total``, with M the number of
    non-empty bins. Small negative values mean "no effect within the estimator's noise".
    None where the response is constant or too few samples.
    """
    y = np.asarray(response, dtype=float)
    n, d = labels.shape
    keep = np.ones(n, dtype=bool) if use is None else np.asarray(use, dtype=bool)
    count = int(np.count_nonzero(keep))
    if count <= 2 * bins:
        return None
    mean = float(np.mean(y, where=keep))
    centred = np.where(keep, y - np.where(keep, mean, 0.0), 0.0)  # 0 for unused samples
    total = float(centred @ centred)
    if total <= 0.0:
        return None
    counts = np.empty((d, bins))
    sums = np.empty((d, bins))
    for j in range(d):
        # Unused samples go to an extra bin, which is then dropped.
        label = np.where(keep, labels[:, j], bins)
        counts[j] = np.bincount(label, minlength=bins + 1)[:bins]
        sums[j] = np.bincount(label, weights=centred, minlength=bins + 1)[:bins]
    return first_order_from_bins(counts, sums, total, count)


def first_order_from_bins(
    counts: FloatArray, sums: FloatArray, total: float, count: int
) -> FloatArray:
    """First-order indices from each input's bin counts and bins' sums of centred t.

    ``counts`` and ``sums`` have shape (d, bins); ``total`` is the sum of squares of
    the centred response and ``count`` the number of samples (:func:`first_order_indices`).
    """
    d, bins = counts.shape
    out = np.empty(d)
    for j in range(d):
        filled = counts[j] > 0
        between = float(np.sum(sums[j][filled] ** 2 / counts[j][filled]))
        groups = int(np.count_nonzero(filled))
        within = total - between
        out[j] = (between - (groups - 1) * within / (count - groups)) / total
    return out


def sensitivity(
    keys: Sequence[str],
    values: FloatArray,
    labels: np.ndarray[Any, Any],
    bins: int,
    times: FloatArray,
) -> dict[str, Any]:
    """SRCs, R^2 and first-order indices of the deployment time, on arriving samples.

    ``values`` (n, d) are the inputs [SI], ``labels`` (n, d) their equal-probability bins
    out of ``bins`` (:func:`bin_labels`), ``times`` the deployment times [s], inf where
    stalled.
    """
    arriving = np.isfinite(times)
    use = None if np.all(arriving) else arriving
    coefficients, r_squared = standardized_regression(values, times, use)
    first = first_order_indices(labels, times, bins, use)
    rows: list[dict[str, Any]] = []
    for j, key in enumerate(keys):
        rows.append(
            {
                "key": key,
                "src": None if coefficients is None else float(coefficients[j]),
                "first_order": None if first is None else float(first[j]),
            }
        )
    rows.sort(key=lambda r: -abs(r["src"] or 0.0))
    return {
        "samples": int(np.count_nonzero(arriving)),
        "r_squared": r_squared,
        "bins": bins,
        "inputs": rows,
    }


def sensitivity_from_sums(keys: Sequence[str], sums: Sums, bins: int) -> dict[str, Any]:
    """:func:`sensitivity` from the merged per-chunk sums of :mod:`.streaming`."""
    count = int(sums.count)
    coefficients: FloatArray | None = None
    r_squared: float | None = None
    first: FloatArray | None = None
    if count >= len(keys) + 2:
        coefficients, r_squared = regression_from_sums(sums.gram, sums.cross, sums.total)
    if count > 2 * bins and sums.total > 0.0:
        first = first_order_from_bins(sums.bin_counts, sums.centred_bin_sums(), sums.total, count)
    rows: list[dict[str, Any]] = [
        {
            "key": key,
            "src": None if coefficients is None else float(coefficients[j]),
            "first_order": None if first is None else float(first[j]),
        }
        for j, key in enumerate(keys)
    ]
    rows.sort(key=lambda r: -abs(r["src"] or 0.0))
    return {"samples": count, "r_squared": r_squared, "bins": bins, "inputs": rows}


def nominal(plan: Plan) -> dict[float, dict[str, Any]]:
    """The nominal system's outputs at each temperature (the same code as every sample's)."""
    from ecdsim.deployment import predict
    from ecdsim.montecarlo.run import outputs_of

    prediction = predict(plan.system, list(plan.temperatures), **plan.predict_options())
    found = outputs_of(plan, prediction)
    cases: dict[float, dict[str, Any]] = {}
    for i, t in enumerate(plan.temperatures):
        case: dict[str, Any] = {
            "deployment_time_s": _number(float(found["deployment_time_s"][i])),
            "end_speed_rad_s": float(found["end_speed_rad_s"][i]),
            "stalled": bool(found["stalled"][i]),
        }
        if "min_torque_margin" in found:
            case["min_torque_margin"] = _number(float(found["min_torque_margin"][i]))
        cases[t] = case
    return cases


def margin(plan: Plan, margins: FloatArray) -> dict[str, Any]:
    """The minimum torque margin's distribution, and how often it is below the required."""
    found = describe(margins)
    required = plan.required_margin
    settings = plan.margin
    assert settings is not None  # only called with margin settings
    found["required"] = required
    found["factors_applied"] = settings.factors_applied
    found["damping_speed_rad_s"] = settings.damping_speed
    if required is not None:
        below = int(np.count_nonzero(margins < required))
        low, high = proportion_interval(below, margins.size)
        found["probability_below_required"] = below / margins.size
        found["probability_below_required_interval95"] = [low, high]
    return found


def _misses(
    plan: Plan,
    times: FloatArray,
    stalled: BoolArray,
    speeds: FloatArray,
    margins: FloatArray | None,
) -> dict[str, Any] | None:
    """The probability of missing each requirement (ecdsim.montecarlo.misses), or None
    without [requirements]."""
    if plan.requirements is None:
        return None
    from ecdsim.montecarlo.misses import requirement_misses

    return requirement_misses(plan.requirements, times, stalled, speeds, margins)


def _notes(plan: Plan) -> list[str]:
    return _dynamic_only_note(plan) + _margin_note(plan)


def _dynamic_only_note(plan: Plan) -> list[str]:
    """Tolerances the chosen method cannot see: inertia, heating, roll-off (dynamic only).

    Their sampled values are recorded and their sensitivities come out as 0, which is
    true of the quasi-static methods but easily read as "this does not matter"; say so.
    """
    from ecdsim.methods import SOLVERS

    # The registry's hook, not the method's name (docs/architecture.md, solver registry):
    # a method that takes the dynamic parameters sees these tolerances.
    if SOLVERS[plan.method].needs_dynamics:
        return []
    from ecdsim.config.tolerance_schema import TOLERABLE

    unseen = [
        key
        for key in plan.tolerances.keys
        if key in TOLERABLE and TOLERABLE[key].model_path[0] == "dynamics"
    ]
    if not unseen:
        return []
    one = len(unseen) == 1
    return [
        f"{', '.join(unseen)}: only the dynamic method models {'this' if one else 'these'}; "
        f"with --method {plan.method} the results do not depend on {'it' if one else 'them'} "
        "(sensitivity 0); use --method dynamic"
    ]


def _margin_note(plan: Plan) -> list[str]:
    settings = plan.margin
    if settings is None:
        return [
            "torque margin: not computed; add a [requirements] section with "
            "[requirements.torque_margin] (docs/sizing.md) for its distribution"
        ]
    if not settings.factors_applied and settings.damping_speed is None:
        return [
            "torque margin: no factors applied and damping at the deployment's own speed: "
            "the margin is 0 wherever the mechanism moves, by quasi-static equilibrium "
            "(docs/sizing.md section 5)"
        ]
    return []


def _warnings(tags: list[dict[str, Any]]) -> list[dict[str, Any]]:
    merged: dict[tuple[str, Any, Any], dict[str, Any]] = {}
    for tag in tags:
        for w in tag.get("warnings", []):
            key = (w["code"], w["temperature_C"], w["method"])
            entry = merged.setdefault(
                key,
                {
                    "code": w["code"],
                    "temperature_C": w["temperature_C"],
                    "method": w["method"],
                    "records": 0,
                    "chunks": 0,
                    "example": w["example"],
                },
            )
            entry["records"] += int(w["count"])
            entry["chunks"] += 1
    return sorted(merged.values(), key=lambda e: (e["code"], repr(e["temperature_C"])))


def _merged_sums(
    plan: Plan, reader: ChunkReader, tags: list[dict[str, Any]], bins: int
) -> list[Sums]:
    """Each temperature's sensitivity sums over the whole study, merged in chunk order.

    A chunk file without them (written before they existed) is reduced from its columns.
    """
    d = plan.tolerances.dimension
    merged = [Sums.empty(d, bins) for _ in plan.temperatures]
    for k, tag in enumerate(tags):
        text = tag.get(streaming.KEY)
        try:
            sums = None if text is None else streaming.decode(text, len(merged), d, bins)
        except ValueError:
            sums = None
        if sums is None:
            sums = streaming.chunk_sums(plan, reader.chunk(k, plan.columns))
        merged = [a.merge(b) for a, b in zip(merged, sums, strict=True)]
    return merged


def _merged_moments(
    plan: Plan, tags: list[dict[str, Any]], data: Mapping[str, np.ndarray[Any, Any]]
) -> dict[float, tuple[Moments, Moments]]:
    """Each temperature's moments of the times and speeds, merged in chunk order.

    A chunk file without them (written before they existed) gets them from its rows of
    the whole columns, by the same function that computed the others.
    """
    merged = [(Moments.empty(), Moments.empty()) for _ in plan.temperatures]
    for k, tag in enumerate(tags):
        text = tag.get(streaming.MOMENTS_KEY)
        try:
            found = None if text is None else streaming.decode_moments(text, len(merged))
        except ValueError:
            found = None
        if found is None:
            start, stop = plan.bounds(k)
            found = streaming.chunk_moments(
                plan, {name: column[start:stop] for name, column in data.items()}
            )
        merged = [(a.merge(c), b.merge(d)) for (a, b), (c, d) in zip(merged, found, strict=True)]
    return dict(zip(plan.temperatures, merged, strict=True))


def summarize(plan: Plan, out: Path) -> dict[str, Any]:
    """The study's statistics per temperature, read from its chunk files (JSON-ready)."""
    from ecdsim.montecarlo.store import ChunkReader, take_kept

    reader = ChunkReader(out, plan.chunks)
    tags = reader.tags()
    # Order statistics need whole columns, but only these: the inputs' columns (the bulk
    # of the files) enter through the sums each chunk carries (module streaming).
    # A run in this process kept them in memory (store.keep): only reused chunks are read.
    kept = take_kept(out, plan.identity_sha256)
    rows = [int(t["_rows"]) for t in tags]
    if sum(rows) != plan.samples:
        raise ValueError(f"{out}: the chunk files do not hold samples 0..{plan.samples - 1}")
    # The sample index of each chunk read from its file is checked as it is read; the
    # chunks kept in memory were computed from their own indices in this process.
    data = reader.read(plan.summary_columns, rows, kept, check_samples=True)
    keys = plan.tolerances.keys
    bins = bin_count(plan.samples)
    merged = _merged_sums(plan, reader, tags, bins)
    reference = nominal(plan)

    moments = _merged_moments(plan, tags, data)

    def case_of(temperature: float, sums: Sums) -> dict[str, Any]:
        times = np.asarray(data[output_column("deployment_time_s", temperature)], dtype=float)
        stalled = np.asarray(data[output_column("stalled", temperature)], dtype=bool)
        speeds = np.asarray(data[output_column("end_speed_rad_s", temperature)], dtype=float)
        nominal_case = reference[temperature]
        # The columns are this summary's own: the percentiles reorder the times in place,
        # then the repeatability turns them into deviations in place (its first campaign
        # taken in sample order before), so no column-sized temporary is allocated.
        first = times[: plan.repeat_runs].copy()
        # Before the percentiles reorder the times: how often each requirement is missed.
        margins = (
            np.asarray(data[output_column("min_torque_margin", temperature)], float)
            if plan.margin is not None
            else None
        )
        misses = _misses(plan, times, stalled, speeds, margins)
        times_described = describe(times, overwrite=True, known=moments[temperature][0])
        repeat = repeatability.study(
            times,
            nominal_case["deployment_time_s"],
            plan.repeat_within,
            plan.repeat_runs,
            overwrite=True,
            first=first,
        )
        case = {
            "temperature_C": temperature,
            "nominal": nominal_case,
            "deployment_time_s": times_described,
            "end_speed_rad_s": describe(
                speeds[~stalled] if stalled.any() else speeds,
                overwrite=True,
                known=moments[temperature][1],
            ),
            "stall": stall(stalled),
            "sensitivity": sensitivity_from_sums(keys, sums, bins),
            "repeatability": repeat,
        }
        if margins is not None:
            case["min_torque_margin"] = margin(plan, margins)
        if misses is not None:
            case["requirements"] = misses
        return case

    # The temperatures are independent, and their order statistics (np.partition) and
    # reductions release the GIL, so SUMMARY_THREADS threads share them. Each case is a
    # pure function of its columns, collected in temperature order: the same summary on
    # any number of threads (tested).
    threads = max(1, min(SUMMARY_THREADS, os.cpu_count() or 1, len(plan.temperatures)))
    if threads == 1:
        cases = [case_of(t, sums) for t, sums in zip(plan.temperatures, merged, strict=True)]
    else:
        with ThreadPoolExecutor(threads, thread_name_prefix="ecdsim-summary") as pool:
            cases = list(pool.map(case_of, plan.temperatures, merged))
    return {
        "ecdsim_version": __version__,
        "system": plan.system.name,
        "method": plan.method,
        "samples": plan.samples,
        "seed": plan.seed,
        "sampling": plan.sampling,
        "chunk_size": plan.chunk_size,
        "config_sha256": plan.config_sha256,
        "tolerances": plan.tolerances.to_dict(),
        "correlation": [list(row) for row in plan.tolerances.correlation],
        "cases": cases,
        "warnings": _warnings(tags),
        "notes": _notes(plan),
    }

"""Names and bins shared by the Monte Carlo run, its streaming sums and its statistics.

A module of its own so that :mod:`ecdsim.montecarlo.run` (which writes the columns),
:mod:`ecdsim.montecarlo.streaming` (which reduces them chunk by chunk) and
:mod:`ecdsim.montecarlo.stats` (which reads them back) share these without importing
one another in a loop; :mod:`ecdsim.montecarlo.budget` too.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ecdsim._types import FloatArray

# Most equal-probability bins of the first-order sensitivity estimator (a uint8 label).
MAX_BINS = 64
# Temperatures the summary works on at once (stats.summarize), each with its own
# temporaries: shared with the memory estimate (ecdsim.montecarlo.budget).
SUMMARY_THREADS = 2


def output_column(output: str, temperature: float) -> str:
    """Column name of an output at a temperature [degC], e.g. ``deployment_time_s@-40.0C``."""
    return f"{output}@{float(temperature)!r}C"


def bin_count(n: int) -> int:
    """Equal-probability bins for the first-order estimator: n^(1/3), 2 to MAX_BINS."""
    return int(min(MAX_BINS, max(2, round(n ** (1.0 / 3.0)))))


def bin_labels(scores: FloatArray, bins: int) -> np.ndarray[Any, np.dtype[np.uint8]]:
    """Equal-probability bin of each uniform score: ``floor(score * bins)``, shape kept.

    ``scores`` are the inputs' uniform scores (their own distribution function of the
    value), so every bin holds the same probability of the input.
    """
    if not 1 <= bins <= 255:
        raise ValueError(f"bins must be 1 to 255, got {bins}")
    # Truncated to uint8 first, then capped (a score within 2**-53 of 1 times bins may
    # round up to bins): the same labels as min(score * bins, bins - 1) truncated, for
    # scores in [0, 1], with the cap done on bytes instead of on a float copy (2x faster).
    scaled: FloatArray = np.multiply(np.asarray(scores, dtype=float), bins)
    labels = scaled.astype(np.uint8)
    np.minimum(labels, np.uint8(bins - 1), out=labels)
    return labels

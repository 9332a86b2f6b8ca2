"""One rule for seeds, wherever ecdsim takes one.

``ecdsim sweep --latin N --seed S``, ``ecdsim montecarlo --seed S`` and the config's
``[tolerances] seed`` all accept the same seeds: whole numbers from 0 to 2**63 - 1. NumPy
seeds its generators with non-negative integers only (``SeedSequence`` refuses -1 with a
traceback), and a fresh seed drawn by ecdsim (:func:`ecdsim.montecarlo.sampling.new_seed`)
lies in this range; it is also the range of a signed 64-bit integer, so that a seed
recorded in a Monte Carlo manifest or summary is read back the same by any JSON or
Parquet reader that stores it as int64.
"""

from __future__ import annotations

MAX_SEED = 2**63 - 1
"""The largest seed accepted (the largest signed 64-bit integer)."""

EXPECTED_SEED = f"expected a whole number from 0 to {MAX_SEED} (2**63 - 1)"


def seed_problem(seed: object) -> str | None:
    """Why ``seed`` is not a seed (one phrase, naming what is expected), or None.

    >>> seed_problem(20240611) is None
    True
    >>> seed_problem(-1)
    'expected a whole number from 0 to 9223372036854775807 (2**63 - 1)'
    """
    if isinstance(seed, int) and not isinstance(seed, bool) and 0 <= seed <= MAX_SEED:
        return None
    return EXPECTED_SEED

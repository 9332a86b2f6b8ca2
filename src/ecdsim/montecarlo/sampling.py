"""Designs of uniform scores, chunk by chunk, so that sample i depends only on (seed, i).

A study of N samples is cut into chunks of a fixed size c (the last one may be shorter);
chunk k holds samples k*c to min((k+1)*c, N) - 1. Every chunk is generated on its own,
from the study's seed and its index alone, never from the state of another chunk. So a
chunk computed by any worker, in any order, in this run or in a resumed one, is the same
array of numbers: the results do not depend on the number of workers or on interruptions.

The random streams come from :class:`numpy.random.SeedSequence`: the study's root
``SeedSequence(seed)`` is spawned into two children, ``design`` (index 0, for design-wide
randomness such as Sobol's scrambling) and ``chunks`` (index 1); chunk k's stream is the
k-th child spawned from ``chunks``. Spawned children are identified by their spawn key,
so child k is built directly as ``SeedSequence(seed, spawn_key=(1, k))`` without
spawning the k children before it (the equality is checked in the tests).

The three designs (d = number of toleranced quantities):

* ``random``: independent uniform scores from chunk k's stream. Each chunk draws a full
  (c, d) block and keeps its first rows, so a sample's scores do not even depend on N.
* ``lhs``: each chunk is a Latin hypercube of its own size (the design of
  scipy.stats.qmc.LatinHypercube on chunk k's stream, drawn directly with NumPy):
  every chunk stratifies each quantity into as many equal-probability
  strata as it has samples. The union of the chunks is a *sliced* Latin hypercube: each
  quantity's range is covered c times over, once per chunk, rather than one N-point
  hypercube (which could not be built chunk by chunk without holding an N-long
  permutation per quantity). With the default chunk size (65 536) the stratification
  is already far finer than any percentile's sampling error.
* ``sobol``: one scrambled Sobol sequence for the whole study (scipy.stats.qmc.Sobol,
  scrambled from the ``design`` stream); chunk k is the contiguous block of points k*c to
  (k+1)*c - 1, reached with ``fast_forward``. The union of the chunks is exactly the
  first N points of the sequence. Sobol balance needs power-of-two blocks: the chunk
  size must be a power of two, and N a power of two gives the best-balanced design.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ecdsim._types import FloatArray, as_float

DESIGN_STREAM = 0
CHUNK_STREAM = 1


def design_seed(seed: int) -> np.random.SeedSequence:
    """The study-wide stream (``SeedSequence(seed).spawn(2)[0]``)."""
    return np.random.SeedSequence(seed, spawn_key=(DESIGN_STREAM,))


def chunk_seed(seed: int, index: int) -> np.random.SeedSequence:
    """Chunk ``index``'s stream: ``SeedSequence(seed).spawn(2)[1].spawn(index + 1)[index]``."""
    return np.random.SeedSequence(seed, spawn_key=(CHUNK_STREAM, index))


def chunk_generator(seed: int, index: int) -> np.random.Generator:
    """A Generator on chunk ``index``'s own stream."""
    return np.random.default_rng(chunk_seed(seed, index))


def _random(seed: int, dimension: int, chunk_size: int, index: int, count: int) -> FloatArray:
    block = chunk_generator(seed, index).random((chunk_size, dimension))
    return as_float(block[:count])


def _lhs(seed: int, dimension: int, chunk_size: int, index: int, count: int) -> FloatArray:
    # scipy.stats.qmc.LatinHypercube(d, rng=...).random(count) (scramble, strength 1),
    # drawn the same way from the same stream, so bit for bit the same design (tested):
    # jitter u ~ U(0, 1) of shape (count, d) (Generator.random: the same doubles as the
    # engine's uniform(size=...), 40 % faster), then one random permutation of 1..count per
    # quantity, in order; sample (i, j) is (perm_j[i] - u[i, j]) / count. Without the
    # engine's set-up, and Generator.permutation shuffles a fresh contiguous array, which
    # is 2x faster than shuffling the rows of a tiled one; the random numbers consumed
    # are the same (Fisher-Yates over count elements). The engine draws from the first
    # child spawned from the Generator's seed sequence, built here from its spawn key.
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(CHUNK_STREAM, index, 0)))
    jitter = rng.random((count, dimension))  # = uniform(0, 1): 0 + 1 * x, bit for bit
    strata = np.empty((dimension, count))
    for j in range(dimension):
        strata[j] = rng.permutation(count)
    strata += 1.0  # exact: integers below 2**53
    # Computed in the (d, count) buffer of the strata and handed out as its transpose: the
    # same (count, d) numbers, but each quantity's column contiguous, so that the copula,
    # the marginals and the chunk's columns read and keep them without strided copies.
    np.subtract(strata, jitter.T, out=strata)
    strata /= count
    return strata.T


def _sobol(seed: int, dimension: int, chunk_size: int, index: int, count: int) -> FloatArray:
    from scipy.stats import qmc

    if chunk_size & (chunk_size - 1):
        raise ValueError(f"sobol sampling needs a power-of-two chunk size, got {chunk_size}")
    engine = qmc.Sobol(dimension, scramble=True, rng=np.random.default_rng(design_seed(seed)))
    if index:
        engine.fast_forward(index * chunk_size)
    return as_float(engine.random(chunk_size)[:count])


Design = Callable[[int, int, int, int, int], FloatArray]

DESIGNS: dict[str, Design] = {"random": _random, "lhs": _lhs, "sobol": _sobol}


def uniforms(
    sampling: str, seed: int, dimension: int, chunk_size: int, index: int, count: int
) -> FloatArray:
    """Uniform scores in [0, 1) for chunk ``index``: shape (count, dimension).

    ``count`` is the chunk's sample count (``chunk_size`` except in the last chunk).

    >>> a = uniforms("random", 7, 2, 4, 1, 4)
    >>> b = uniforms("random", 7, 2, 4, 1, 3)  # a shorter last chunk: same first rows
    >>> bool((a[:3] == b).all()), a.shape
    (True, (4, 2))
    """
    if sampling not in DESIGNS:
        raise ValueError(f"unknown sampling {sampling!r}; expected one of {sorted(DESIGNS)}")
    if not 0 < count <= chunk_size:
        raise ValueError(f"a chunk holds 1 to {chunk_size} samples, not {count}")
    return DESIGNS[sampling](seed, dimension, chunk_size, index, count)


def new_seed() -> int:
    """A fresh seed from the operating system's entropy, for a study that gives none."""
    return int(np.random.SeedSequence().entropy) % 2**63  # type: ignore[arg-type]

"""Per-chunk sums of the sensitivity statistics, computed as each chunk is solved.

The sensitivity of the deployment time (:mod:`~ecdsim.montecarlo.stats`: standardised
regression coefficients and given-data first-order indices) needs every sample's d input
values: at 10 million samples, re-reading them from the chunk files was most of the
summary's time. Instead, when chunk k is evaluated, this module reduces it, per
temperature and over the samples that arrive, to mergeable sums:

* the count n, the means of the inputs and of the time, and the centred sums
  ``dx.T @ dx`` (d x d), ``dx.T @ dy`` (d) and ``dy @ dy``;
* for each input, the count and the sum of the times in each of its M equal-probability
  bins (d x M each).

The sums travel in the chunk file's metadata (so a resumed run finds them with the chunk)
and are merged in chunk order with the pairwise update of Chan, Golub and LeVeque
(1979), exact in real arithmetic: the merged centred sums equal those of all samples at
once. The chunk order is fixed, so the merged figures are the same bytes for any number
of workers and after a resume; they differ from a one-pass computation over all samples
by rounding only (relative ~1e-13).
"""

from __future__ import annotations

import base64
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.montecarlo.columns import bin_count, bin_labels, output_column

if TYPE_CHECKING:
    from ecdsim.montecarlo.tolerances import ToleranceSet

KEY = "sensitivity_sums"


@dataclass(frozen=True)
class Sums:
    """Mergeable sums of one temperature's arriving samples (module docstring).

    Attributes
    ----------
    count : number of samples [-]
    mean_x : mean of each input, shape (d,) [SI]
    mean_y : mean deployment time [s]
    gram : ``dx.T @ dx`` of the centred inputs, (d, d)
    cross : ``dx.T @ dy``, (d,)
    total : ``dy @ dy`` [s^2]
    bin_counts : samples in each input's equal-probability bin, (d, M)
    bin_sums : sum of the deployment times in each bin, (d, M) [s]
    """

    count: float
    mean_x: FloatArray
    mean_y: float
    gram: FloatArray
    cross: FloatArray
    total: float
    bin_counts: FloatArray
    bin_sums: FloatArray

    @classmethod
    def empty(cls, d: int, bins: int) -> Sums:
        """The sums of no sample."""
        return cls(
            0.0,
            np.zeros(d),
            0.0,
            np.zeros((d, d)),
            np.zeros(d),
            0.0,
            np.zeros((d, bins)),
            np.zeros((d, bins)),
        )

    def merge(self, other: Sums) -> Sums:
        """The sums of both sample sets (Chan, Golub and LeVeque's pairwise update)."""
        if other.count == 0.0:
            return self
        if self.count == 0.0:
            return other
        n = self.count + other.count
        weight = self.count * other.count / n
        dx = other.mean_x - self.mean_x
        dy = other.mean_y - self.mean_y
        return Sums(
            count=n,
            mean_x=self.mean_x + dx * (other.count / n),
            mean_y=self.mean_y + dy * (other.count / n),
            gram=self.gram + other.gram + weight * np.outer(dx, dx),
            cross=self.cross + other.cross + weight * dx * dy,
            total=self.total + other.total + weight * dy * dy,
            bin_counts=self.bin_counts + other.bin_counts,
            bin_sums=self.bin_sums + other.bin_sums,
        )

    def centred_bin_sums(self) -> FloatArray:
        """Each bin's sum of the times minus the overall mean [s], (d, M)."""
        return self.bin_sums - self.bin_counts * self.mean_y

    def to_vector(self) -> FloatArray:
        """Every number in one float64 vector (the layout :meth:`from_vector` reads)."""
        return np.concatenate(
            [
                [self.count, self.mean_y, self.total],
                self.mean_x,
                self.cross,
                self.gram.ravel(),
                self.bin_counts.ravel(),
                self.bin_sums.ravel(),
            ]
        )

    @classmethod
    def from_vector(cls, vector: FloatArray, d: int, bins: int) -> Sums:
        """The inverse of :meth:`to_vector`."""
        cuts = np.cumsum([3, d, d, d * d, d * bins])
        head, mean_x, cross, gram, counts, sums = np.split(vector, cuts)
        return cls(
            count=float(head[0]),
            mean_x=mean_x,
            mean_y=float(head[1]),
            gram=gram.reshape(d, d),
            cross=cross,
            total=float(head[2]),
            bin_counts=counts.reshape(d, bins),
            bin_sums=sums.reshape(d, bins),
        )


@dataclass(frozen=True)
class _Inputs:
    """What the sums of a set of samples share across temperatures: their inputs' part."""

    mean_x: FloatArray
    dx_rows: FloatArray
    gram: FloatArray
    label_rows: np.ndarray[Any, Any]
    counts: FloatArray

    @classmethod
    def of(cls, values: FloatArray, labels: np.ndarray[Any, Any], bins: int) -> _Inputs:
        n, d = values.shape
        rows = np.array(values.T, order="C")  # (d, n), a copy: each input contiguous
        mean_x = rows.mean(axis=1)
        rows -= mean_x[:, np.newaxis]
        # Each input's labels as one contiguous row of indices (one cast, reused by every
        # temperature's bincount). A bin's sum adds its samples in sample order, as one
        # bincount over all inputs' cells did: the same numbers.
        label_rows = np.array(labels.T, dtype=np.intp, order="C")
        counts = np.empty((d, bins))
        for j in range(d):
            counts[j] = np.bincount(label_rows[j], minlength=bins)
        # NumPy's own (pairwise) sums, not BLAS: a multi-threaded BLAS may split a sum
        # differently from one process to the next; the sums must be the same bytes
        # whoever computes them. Row j's products with rows j..d-1 in one temporary and
        # one reduction along each row: the same pairwise sums as one row pair at a time.
        gram = np.empty((d, d))
        for j in range(d):
            gram[j, j:] = gram[j:, j] = np.add.reduce(rows[j:] * rows[j], axis=1)
        return cls(mean_x, rows, gram, label_rows, counts)


def sums_of(
    values: FloatArray,
    labels: np.ndarray[Any, Any],
    times: FloatArray,
    bins: int,
    shared: _Inputs | None = None,
) -> Sums:
    """The sums of one chunk at one temperature, over the samples whose time is finite.

    ``values`` (n, d) are the inputs [SI], ``labels`` (n, d) their bins out of ``bins``
    (:func:`ecdsim.montecarlo.stats.bin_labels`), ``times`` (n,) the deployment times [s].
    ``shared`` is ``_Inputs.of(values, labels, bins)``, reused when every sample arrives.
    """
    n, d = values.shape
    arriving = np.isfinite(times)
    if not arriving.all():
        values, labels, times = values[arriving], labels[arriving], times[arriving]
        n = times.size
        shared = None
    if n == 0:
        return Sums.empty(d, bins)
    inputs = shared if shared is not None else _Inputs.of(values, labels, bins)
    mean_y = float(times.mean())
    dy = times - mean_y
    weights = np.ascontiguousarray(times, dtype=float)
    sums = np.empty((d, bins))
    for j in range(d):
        sums[j] = np.bincount(inputs.label_rows[j], weights=weights, minlength=bins)
    return Sums(
        count=float(n),
        mean_x=inputs.mean_x,
        mean_y=mean_y,
        gram=inputs.gram,
        cross=np.add.reduce(inputs.dx_rows * dy, axis=1),
        total=float(np.add.reduce(dy * dy)),
        bin_counts=inputs.counts,
        bin_sums=sums,
    )


class Study(Protocol):
    """What the sums need of a study (a :class:`ecdsim.montecarlo.run.Plan`)."""

    @property
    def tolerances(self) -> ToleranceSet:
        """The resolved tolerances, in column order."""
        ...

    @property
    def samples(self) -> int:
        """N, the study's sample count (sets the bins)."""
        ...

    @property
    def temperatures(self) -> tuple[float, ...]:
        """The analysis temperatures [degC]."""
        ...


def chunk_sums(
    plan: Study,
    columns: Mapping[str, np.ndarray[Any, Any]],
    scores: FloatArray | None = None,
    values: FloatArray | None = None,
) -> list[Sums]:
    """One chunk's sums at each of the plan's temperatures, from its columns.

    ``scores`` (n, d) are the inputs' uniform scores as sampled (after the copula); the
    bins are cut on them. Without them (a chunk read back from its file) they are the
    inputs' distribution functions at the values, the same numbers up to rounding (a
    sample within 1e-16 of a bin edge could change bin). ``values`` (n, d) are the
    inputs' columns side by side, if the caller has them so (no copy is then made).
    """
    tolerances = plan.tolerances.tolerances
    bins = bin_count(plan.samples)
    if values is None:
        # (n, d) views of (d, n) stacks: each input's column contiguous, as the chunk's own.
        values = np.stack([np.asarray(columns[t.key], dtype=float) for t in tolerances]).T
    if scores is None:
        scores = np.stack([t.scores(values[:, j]) for j, t in enumerate(tolerances)]).T
    times = [
        np.asarray(columns[output_column("deployment_time_s", t)], dtype=float)
        for t in plan.temperatures
    ]
    if compiled_sums(values.shape[0] * len(plan.temperatures)):
        from ecdsim.montecarlo import _streaming_numba

        rows = np.ascontiguousarray(values.T, dtype=float)
        found = _streaming_numba.chunk_sums(rows, np.ascontiguousarray(scores.T), times, bins)
        return [Sums(*part) for part in found]
    labels = bin_labels(scores, bins)
    shared = _Inputs.of(values, labels, bins)
    return [sums_of(values, labels, row, bins, shared) for row in times]


def compiled_sums(cases: int) -> bool:
    """True if a chunk of ``cases`` samples x temperatures takes its sums from the
    compiled kernel (:mod:`ecdsim.montecarlo._streaming_numba`): numba installed, not
    switched off (``ECDSIM_NUMBA=0``), and a chunk as large as the exact solution's
    compiled kernel asks for (its import is paid once per run, with that kernel's).
    """
    from ecdsim import _numba
    from ecdsim.solvers.exact_kernel import NUMBA_MIN_CASES

    return cases >= NUMBA_MIN_CASES and _numba.enabled()


def encode(sums: Sequence[Sums]) -> str:
    """The sums of each temperature as text for a chunk file's metadata (exact: base64 of
    the float64 bytes, little-endian, so that NaN and inf survive too)."""
    vector = np.concatenate([s.to_vector() for s in sums]).astype("<f8")
    return base64.b64encode(vector.tobytes()).decode("ascii")


def decode(text: str, temperatures: int, d: int, bins: int) -> list[Sums]:
    """The inverse of :func:`encode`; ValueError if the text does not fit the layout."""
    vector = np.frombuffer(base64.b64decode(text.encode("ascii")), dtype="<f8").astype(float)
    if vector.size % temperatures:
        raise ValueError("sensitivity sums of the wrong length")
    parts = np.split(vector, temperatures)
    if parts[0].size != 3 + 2 * d + d * d + 2 * d * bins:
        raise ValueError("sensitivity sums of the wrong length")
    return [Sums.from_vector(p, d, bins) for p in parts]


MOMENTS_KEY = "moments"


@dataclass(frozen=True)
class Moments:
    """Mergeable moments of one output over a set of samples (inf allowed).

    Attributes
    ----------
    size : number of values, infinite ones included [-]
    count : number of finite values [-]
    mean : mean of the finite values
    m2 : sum of the squared deviations of the finite values from their mean
    lowest : smallest value (may be -inf; NaN if any is NaN)
    highest : largest value (may be +inf; NaN if any is NaN)
    """

    size: float
    count: float
    mean: float
    m2: float
    lowest: float
    highest: float

    @classmethod
    def empty(cls) -> Moments:
        """The moments of no value."""
        return cls(0.0, 0.0, 0.0, 0.0, np.inf, -np.inf)

    @classmethod
    def of(cls, values: FloatArray) -> Moments:
        """The moments of the values (NumPy's pairwise sums over them)."""
        x = np.asarray(values, dtype=float).reshape(-1)
        if x.size == 0:
            return cls.empty()
        is_finite = np.isfinite(x)
        finite = x if is_finite.all() else x[is_finite]
        mean = float(np.mean(finite)) if finite.size else 0.0
        with np.errstate(over="ignore", invalid="ignore"):
            deviation = finite - mean
            m2 = float(np.add.reduce(deviation * deviation))
        return cls(float(x.size), float(finite.size), mean, m2, float(x.min()), float(x.max()))

    def merge(self, other: Moments) -> Moments:
        """The moments of both sets (Chan, Golub and LeVeque's pairwise update)."""
        lowest = float(np.minimum(self.lowest, other.lowest))  # NaN propagates
        highest = float(np.maximum(self.highest, other.highest))
        size = self.size + other.size
        if other.count == 0.0 or self.count == 0.0:
            kept = self if other.count == 0.0 else other
            return Moments(size, kept.count, kept.mean, kept.m2, lowest, highest)
        n = self.count + other.count
        with np.errstate(over="ignore", invalid="ignore"):
            delta = other.mean - self.mean
            mean = self.mean + delta * (other.count / n)
            m2 = self.m2 + other.m2 + delta * delta * (self.count * other.count / n)
        return Moments(size, n, mean, m2, lowest, highest)

    def mean_and_std(self) -> tuple[float | None, float | None]:
        """Mean and standard deviation (n - 1) of the finite values; None if undefined."""
        if self.count == 0.0:
            return None, None
        std = math.sqrt(self.m2 / (self.count - 1.0)) if self.count > 1.0 else None
        return self.mean, std

    def to_vector(self) -> FloatArray:
        """The six numbers in the layout :meth:`from_vector` reads."""
        return np.array([self.size, self.count, self.mean, self.m2, self.lowest, self.highest])

    @classmethod
    def from_vector(cls, vector: FloatArray) -> Moments:
        """The inverse of :meth:`to_vector`."""
        size, count, mean, m2, lowest, highest = (float(v) for v in vector)
        return cls(size, count, mean, m2, lowest, highest)


def chunk_moments(
    plan: Study, columns: Mapping[str, np.ndarray[Any, Any]]
) -> list[tuple[Moments, Moments]]:
    """A chunk's moments at each temperature: of the deployment times (all samples) and of
    the end speeds of the samples that do not stall (as the summary describes them)."""
    found = []
    for t in plan.temperatures:
        times = np.asarray(columns[output_column("deployment_time_s", t)], dtype=float)
        stalled = np.asarray(columns[output_column("stalled", t)], dtype=bool)
        speeds = np.asarray(columns[output_column("end_speed_rad_s", t)], dtype=float)
        found.append((Moments.of(times), Moments.of(speeds[~stalled] if stalled.any() else speeds)))
    return found


def encode_moments(moments: Sequence[tuple[Moments, Moments]]) -> str:
    """The moments as text for a chunk file's metadata (base64 of little-endian float64)."""
    parts = [m.to_vector() for pair in moments for m in pair]
    vector = np.concatenate(parts).astype("<f8") if parts else np.zeros(0, "<f8")
    return base64.b64encode(vector.tobytes()).decode("ascii")


def decode_moments(text: str, temperatures: int) -> list[tuple[Moments, Moments]]:
    """The inverse of :func:`encode_moments`; ValueError if the text does not fit."""
    vector = np.frombuffer(base64.b64decode(text.encode("ascii")), dtype="<f8").astype(float)
    if vector.size != 12 * temperatures:
        raise ValueError("moments of the wrong length")
    six = vector.reshape(temperatures, 2, 6)
    return [(Moments.from_vector(a), Moments.from_vector(b)) for a, b in six]

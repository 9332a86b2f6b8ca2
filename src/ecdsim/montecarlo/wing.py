"""Monte Carlo over a wing file's tolerances (docs/wing.md, studies).

A wing file's ``[tolerances]`` is a single hinge's (docs/montecarlo.md: sampling, seed,
chunk_size, quantities, correlations) with the file's key paths as the quantities
(``"wing.panels[2].mass"``, ``"wing.hinges[1].friction.at_0C"``). The study reuses the
single hinge's machinery where it fits: the marginals and the Gaussian copula
(:class:`~ecdsim.montecarlo.tolerances.ToleranceSet`), the seeded designs chunk by chunk
(:func:`~ecdsim.montecarlo.sampling.uniforms`, so a study's first samples do not depend
on how many follow), the statistics with their intervals
(:func:`~ecdsim.montecarlo.stats.describe`, :func:`~ecdsim.montecarlo.stats.stall`), the
driver ranking (:func:`~ecdsim.montecarlo.stats.sensitivity`: standardised regression
coefficients and first-order indices of the deployment time) and the plots. Each sample
is the file with its values set, validated as a file and solved by
:func:`ecdsim.wing.solver.deploy_wing`; its rows are
:meth:`~ecdsim.wing.result.WingResult.summary_rows` (a sweep's columns).

What it leaves to the single hinge's study: chunk files, resuming and parallel workers
(a wing's solve takes milliseconds to a second; the samples run in one process).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim.config.errors import ConfigError
from ecdsim.montecarlo.tolerances import DISTRIBUTIONS, NORMAL_TRUNCATION, Tolerance, ToleranceSet

if TYPE_CHECKING:
    from ecdsim.config.wing_schema import CatalogueReader, WingConfig
    from ecdsim.sweeps import SweepResult

MAX_SAMPLES = 1_000_000
# Per hinge, the outputs summarised over the samples (columns of summary_rows).
HINGE_OUTPUTS = (
    "latch_time_s",
    "latch_speed_rad_s",
    "latch_kinetic_energy_J",
    "peak_latch_torque_Nm",
    "peak_damper_temperature_C",
)


@dataclass
class WingStudy:
    """A wing's Monte Carlo study: its tolerances, the samples' values and rows.

    Attributes
    ----------
    title : the wing file's title
    hinges : the hinges' names, root first
    tolerances : the resolved tolerances (their keys in design order)
    seed, sampling : the design's seed and scheme
    temperatures : [degC]
    scores : the samples' uniform scores with the correlation imposed, (n, d)
    values : the samples' values [SI], (n, d)
    rows : one per (sample, temperature): ``sample``, the keys' values, the wing's outputs
    errors : (sample, message) for samples the solver could not evaluate
    """

    title: str
    hinges: tuple[str, ...]
    tolerances: ToleranceSet
    seed: int
    sampling: str
    temperatures: tuple[float, ...]
    scores: np.ndarray[Any, np.dtype[np.float64]]
    values: np.ndarray[Any, np.dtype[np.float64]]
    rows: list[dict[str, Any]] = field(default_factory=list)
    errors: list[tuple[int, str]] = field(default_factory=list)

    @property
    def samples(self) -> int:
        """The number of samples."""
        return int(self.values.shape[0])

    def column(self, name: str, temperature: float) -> np.ndarray[Any, np.dtype[np.float64]]:
        """One output over the samples at ``temperature`` (NaN where a sample has none;
        ``deployment_time_s`` is inf where the wing did not latch)."""
        rows = [r for r in self.rows if r["temperature_C"] == temperature]
        out = np.array([float(r.get(name, math.nan)) for r in rows])
        if name == "deployment_time_s":
            out[np.isnan(out)] = math.inf
        return out

    def table(self) -> SweepResult:
        """The samples' table (a sweep's: CSV or Parquet, ``write``; the keys' columns
        carry their units)."""
        from ecdsim.sweeps import SweepResult, Vary

        varies = [Vary(t.key, (), (), unit=t.unit) for t in self.tolerances.tolerances]
        return SweepResult(self.rows, varies, self.title, ("wing",), self.errors)

    def summary(self) -> dict[str, Any]:
        """The study's statistics per temperature (JSON-ready; docs/wing.md, studies)."""
        from ecdsim.montecarlo import stats
        from ecdsim.montecarlo.columns import bin_count, bin_labels

        keys = self.tolerances.keys
        cases = []
        for temperature in self.temperatures:
            times = self.column("deployment_time_s", temperature)
            bins = bin_count(self.samples)
            sensitivity = stats.sensitivity(
                keys, self.values, bin_labels(self.scores, bins), bins, times
            )
            hinges = []
            for j, name in enumerate(self.hinges):
                entry: dict[str, Any] = {"hinge": name}
                for output in HINGE_OUTPUTS:
                    x = self.column(f"hinge_{j}_{output}", temperature)
                    present = x[~np.isnan(x)]
                    if present.size:
                        entry[output] = stats.describe(present)
                stuck = self.column(f"hinge_{j}_stuck", temperature)
                entry["stuck"] = stats.stall(stuck == 1.0)
                hinges.append(entry)
            cases.append(
                {
                    "temperature_C": temperature,
                    "deployment_time_s": stats.describe(times),
                    "not_latched": stats.stall(~np.isfinite(times)),
                    "hinges": hinges,
                    "sensitivity": sensitivity,
                }
            )
        return {
            "kind": "wing_montecarlo",
            "system": self.title,
            "method": "wing",
            "samples": self.samples,
            "seed": self.seed,
            "sampling": self.sampling,
            "tolerances": self.tolerances.to_dict(),
            "errors": [{"sample": i, "message": m} for i, m in self.errors],
            "cases": cases,
        }


def resolve(
    config: WingConfig,
    raw: Mapping[str, Any],
    build: Callable[[dict[str, Any]], WingConfig],
) -> ToleranceSet:
    """The wing file's tolerances against its values; :class:`ConfigError` (one line
    each) for a missing section, a key the file does not set, a zero percentage, or a
    spread whose reach (nominal -+ 6 sigma, or -+ plus_minus) the file would refuse
    (``build`` validates a document)."""
    from ecdsim.config.wing_keys import WingKeyError, nominal, set_values

    spec = config.spec.tolerances
    if spec is None:
        raise ConfigError(
            [
                "tolerances: missing; a Monte Carlo study of a wing needs a [tolerances] section "
                'with [tolerances.quantities], e.g. "wing.panels[0].mass" = { distribution = '
                '"normal", sigma = "3 %" } (docs/wing.md)'
            ],
            config.source,
        )
    problems: list[str] = []
    resolved: list[Tolerance] = []
    for q in spec.quantities.values():
        where = f"tolerances.quantities.{q.key}"
        try:
            value = nominal(raw, q.key)
        except WingKeyError as exc:
            problems.extend(f"{where}: {p.removeprefix(q.key + ': ')}" for p in exc.problems)
            continue
        spread, name = q.spread, q.spread_name
        if spread.relative and value == 0.0:
            problems.append(
                f"{where}.{name} = {spread.text!r}: a percentage of a configured value of 0 "
                "is 0; give the spread in the key's unit instead"
            )
            continue
        width = spread.value * abs(value) if spread.relative else spread.value
        scale = width / 3.0 if name == "three_sigma" else width
        reach = DISTRIBUTIONS[q.distribution].reach * scale
        for end, label in ((value - reach, "-"), (value + reach, "+")):
            try:
                build(set_values(raw, {q.key: end}))
            except ConfigError as exc:
                how = f"{NORMAL_TRUNCATION:g} sigma" if q.distribution == "normal" else name
                problems.append(
                    f"{where}.{name} = {spread.text!r}: the {q.distribution} spread reaches "
                    f"{end:.4g} (nominal {label} {how}, nominal {value:.4g}), which the file "
                    f"refuses ({exc.problems[0]}); use a smaller spread"
                )
                break
        tolerance_unit = _unit(q.key)
        resolved.append(
            Tolerance(
                q.key, q.distribution, value, scale, tolerance_unit, f"{name} = {spread.text!r}"
            )
        )
    if problems:
        raise ConfigError(problems, config.source)
    matrix = spec.correlation_matrix()
    return ToleranceSet(tuple(resolved), tuple(tuple(row) for row in matrix))


def _unit(key: str) -> str:
    from ecdsim.config.wing_keys import field_unit

    return field_unit(key) or ""


def design(
    tolerances: ToleranceSet, sampling: str, seed: int, chunk_size: int, samples: int
) -> np.ndarray[Any, np.dtype[np.float64]]:
    """The samples' uniform scores, chunk by chunk as a single hinge's study draws them
    (:func:`ecdsim.montecarlo.sampling.uniforms`), with the correlation imposed."""
    from ecdsim.montecarlo.sampling import uniforms

    parts = []
    for index in range(math.ceil(samples / chunk_size)):
        count = min(chunk_size, samples - index * chunk_size)
        parts.append(uniforms(sampling, seed, tolerances.dimension, chunk_size, index, count))
    u = np.concatenate(parts, axis=0)
    return tolerances.correlate(u)


def run(
    config: WingConfig,
    raw: Mapping[str, Any],
    samples: int,
    *,
    seed: int | None = None,
    sampling: str | None = None,
    temperatures: Sequence[float] | None = None,
    read_catalogue: CatalogueReader | None = None,
    base: Path | None = None,
) -> WingStudy:
    """Draw ``samples`` parameter sets of the wing file's tolerances and solve each.

    ``seed`` and ``sampling`` override ``[tolerances]`` (the seed: else the file's, else
    a fresh one, recorded in the summary). The same seed gives the same samples and
    results.
    """
    from ecdsim.config.wing_keys import set_values
    from ecdsim.config.wing_schema import wing_config_from_document
    from ecdsim.montecarlo.sampling import new_seed
    from ecdsim.tidy import key_column
    from ecdsim.wing.solver import WingUnsupported, deploy_wing

    if not 1 <= samples <= MAX_SAMPLES:
        raise ConfigError([f"--samples {samples}: expected 1 to {MAX_SAMPLES:,}"], config.source)
    folder = base if base is not None else Path(config.source).parent

    def build(document: dict[str, Any]) -> WingConfig:
        return wing_config_from_document(document, config.source, folder, read_catalogue)

    tolerances = resolve(config, raw, build)
    spec = config.spec.tolerances
    assert spec is not None
    chosen_seed = seed if seed is not None else spec.seed if spec.seed is not None else new_seed()
    scheme = sampling or spec.sampling
    if scheme == "sobol" and spec.chunk_size & (spec.chunk_size - 1):
        raise ConfigError(
            [f"tolerances.chunk_size = {spec.chunk_size}: sobol sampling needs a power of two"],
            config.source,
        )
    scores = design(tolerances, scheme, chosen_seed, spec.chunk_size, samples)
    values = tolerances.values_of_scores(scores)
    temps = tuple(temperatures) if temperatures else config.temperatures
    study = WingStudy(
        title=config.spec.title,
        hinges=tuple(h.name for h in config.wing.hinges),
        tolerances=tolerances,
        seed=chosen_seed,
        sampling=scheme,
        temperatures=temps,
        scores=scores,
        values=values,
    )
    keys = tolerances.keys
    for i in range(samples):
        point = {key: float(values[i, k]) for k, key in enumerate(keys)}
        head: dict[str, Any] = {"sample": i}
        head.update({key_column(t.key, t.unit): point[t.key] for t in tolerances.tolerances})
        try:
            sample = build(set_values(raw, point))
            result = deploy_wing(sample.wing, temps, rtol=sample.rtol, stop_time=sample.stop_time)
        except (ConfigError, WingUnsupported) as exc:
            message = exc.problems[0] if isinstance(exc, ConfigError) else str(exc)
            study.errors.append((i, message))
            study.rows.extend(
                {**head, "temperature_C": t, "method": "wing", "error": message} for t in temps
            )
            continue
        for row in result.summary_rows():
            study.rows.append(
                {**head, "temperature_C": row.pop("temperature_C"), "method": "wing", **row}
            )
    return study

"""Tolerances resolved against a configuration: from uniform scores to parameter values.

Each toleranced quantity has a marginal distribution centred on its configured (nominal)
value; the design (:mod:`ecdsim.montecarlo.sampling`) supplies a uniform score u in
[0, 1) per sample and quantity, and the marginal's inverse distribution function maps it
to a value. Correlations act on the normal scores ``z = Phi^-1(u)`` through a Cholesky
factor (a Gaussian copula), so that every marginal stays exactly as specified.

The distributions, in standard form (nominal 0, scale 1; value = nominal + scale * x):

* ``normal``: x = Phi^-1(u), truncated at +-6 (``NORMAL_TRUNCATION``): the tails beyond
  six sigma hold a probability of 2e-9, far below any feasible sample's resolution, and
  the cut keeps every sample finite and inside the physical range checked below;
* ``uniform``: x = 2u - 1, on [-1, 1];
* ``triangular``: symmetric on [-1, 1] with its mode at 0.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.config.errors import ConfigError
from ecdsim.config.tolerance_schema import TOLERABLE, QuantityToleranceSpec, TolerancesSpec
from ecdsim.montecarlo import apply

if TYPE_CHECKING:
    from ecdsim.config import Config

NORMAL_TRUNCATION = 6.0


def _ndtri(u: FloatArray) -> FloatArray:
    from scipy.special import ndtri

    return as_float(ndtri(u))


def _ndtr(z: FloatArray) -> FloatArray:
    from scipy.special import ndtr

    return as_float(ndtr(z))


def normal_ppf(u: ArrayLike) -> FloatArray:
    """Standard normal quantile of u [-], truncated at +-NORMAL_TRUNCATION."""
    z = _ndtri(as_float(u))
    return np.clip(z, -NORMAL_TRUNCATION, NORMAL_TRUNCATION)


def uniform_ppf(u: ArrayLike) -> FloatArray:
    """Quantile of the uniform distribution on [-1, 1] at u [-]."""
    return 2.0 * as_float(u) - 1.0


def triangular_ppf(u: ArrayLike) -> FloatArray:
    """Quantile of the symmetric triangular distribution on [-1, 1] (mode 0) at u [-]."""
    p = as_float(u)
    lower = np.sqrt(2.0 * np.clip(p, 0.0, 0.5)) - 1.0
    upper = 1.0 - np.sqrt(2.0 * np.clip(1.0 - p, 0.0, 0.5))
    return np.where(p < 0.5, lower, upper)


def normal_cdf(x: ArrayLike) -> FloatArray:
    """Standard normal distribution function at x [-]."""
    return _ndtr(as_float(x))


def uniform_cdf(x: ArrayLike) -> FloatArray:
    """Distribution function of the uniform distribution on [-1, 1] at x [-]."""
    return np.clip((as_float(x) + 1.0) / 2.0, 0.0, 1.0)


def triangular_cdf(x: ArrayLike) -> FloatArray:
    """Distribution function of the symmetric triangular distribution on [-1, 1] at x [-]."""
    v = np.clip(as_float(x), -1.0, 1.0)
    return np.where(v < 0.0, 0.5 * (1.0 + v) ** 2, 1.0 - 0.5 * (1.0 - v) ** 2)


@dataclass(frozen=True)
class Distribution:
    """A standard marginal (nominal 0, scale 1) by name: quantile, CDF and reach.

    Attributes
    ----------
    name : registry name
    ppf : quantile function of a uniform score
    cdf : distribution function (the inverse of ppf)
    std : standard deviation of the standard form, in units of the scale [-]
    reach : largest |x| the standard form can take [-]
    """

    name: str
    ppf: Callable[[ArrayLike], FloatArray]
    cdf: Callable[[ArrayLike], FloatArray]
    std: float
    reach: float


DISTRIBUTIONS: dict[str, Distribution] = {
    "normal": Distribution("normal", normal_ppf, normal_cdf, 1.0, NORMAL_TRUNCATION),
    "uniform": Distribution("uniform", uniform_ppf, uniform_cdf, 1.0 / np.sqrt(3.0), 1.0),
    "triangular": Distribution(
        "triangular", triangular_ppf, triangular_cdf, 1.0 / np.sqrt(6.0), 1.0
    ),
}


@dataclass(frozen=True)
class Tolerance:
    """One toleranced quantity, resolved: value = nominal + scale * x, x ~ distribution.

    Attributes
    ----------
    key : dotted config key
    distribution : name in DISTRIBUTIONS
    nominal : the configured value [SI unit of the quantity]
    scale : sigma (normal) or half-width (uniform, triangular) [SI unit of the quantity]
    unit : the SI unit, for output ("" for plain numbers)
    spread_text : the spread as written in the config ("sigma = '3 %'")
    """

    key: str
    distribution: str
    nominal: float
    scale: float
    unit: str
    spread_text: str

    @property
    def marginal(self) -> Distribution:
        """The standard marginal."""
        return DISTRIBUTIONS[self.distribution]

    @property
    def std(self) -> float:
        """Standard deviation of the quantity [SI unit of the quantity]."""
        return self.scale * self.marginal.std

    def values(self, u: ArrayLike) -> FloatArray:
        """The quantity at uniform scores u [-] [SI unit of the quantity]."""
        return self.nominal + self.scale * self.marginal.ppf(u)

    def scores(self, values: ArrayLike) -> FloatArray:
        """The uniform scores [-] of values of the quantity (inverse of ``values``)."""
        return self.marginal.cdf((as_float(values) - self.nominal) / self.scale)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready description."""
        return {
            "key": self.key,
            "distribution": self.distribution,
            "nominal": self.nominal,
            "scale": self.scale,
            "std": self.std,
            "unit": self.unit,
            "spread": self.spread_text,
        }


@dataclass(frozen=True)
class ToleranceSet:
    """All tolerances of a study, and the Gaussian copula that correlates them.

    Attributes
    ----------
    tolerances : one per quantity, in the order of the config
    correlation : correlation matrix of the normal scores (identity if none given)
    """

    tolerances: tuple[Tolerance, ...]
    correlation: tuple[tuple[float, ...], ...]

    @property
    def keys(self) -> tuple[str, ...]:
        """The quantities' dotted keys, in design-column order."""
        return tuple(t.key for t in self.tolerances)

    @property
    def dimension(self) -> int:
        """Number of toleranced quantities (columns of the design)."""
        return len(self.tolerances)

    def correlate(self, u: FloatArray) -> FloatArray:
        """Impose the correlation on uniform scores u of shape (n, d) (Gaussian copula).

        Columns in no correlation are returned untouched (bit for bit).
        """
        matrix = np.asarray(self.correlation, dtype=float)
        involved = np.flatnonzero(np.any(matrix - np.eye(self.dimension) != 0.0, axis=0))
        if involved.size == 0:
            return u
        sub = matrix[np.ix_(involved, involved)]
        lower = np.linalg.cholesky(sub)
        # Clip away exact 0 and 1 so that the normal scores stay finite.
        tiny = np.finfo(float).tiny
        z = _ndtri(np.clip(u[:, involved], tiny, 1.0 - np.finfo(float).epsneg))
        out = u.copy(order="K")  # keeps the design's layout (columns contiguous for LHS)
        out[:, involved] = _ndtr(z @ lower.T)
        return out

    def values(self, u: FloatArray) -> FloatArray:
        """Parameter values of shape (n, d) from uniform scores u of shape (n, d)."""
        return self.values_of_scores(self.correlate(u))

    def values_of_scores(self, scores: FloatArray) -> FloatArray:
        """Parameter values (n, d) from scores that already carry the correlation.

        Each quantity's values are contiguous (the array is column-major): a chunk's
        columns are then views, not copies.
        """
        rows = np.empty((self.dimension, scores.shape[0]))
        for j, t in enumerate(self.tolerances):
            rows[j] = t.values(scores[:, j])
        return rows.T

    def to_dict(self) -> list[dict[str, object]]:
        """JSON-ready description of every tolerance."""
        return [t.to_dict() for t in self.tolerances]


def _resolve_one(
    spec: QuantityToleranceSpec, parameters: apply.Parameters, problems: list[str]
) -> Tolerance | None:
    quantity = TOLERABLE[spec.key]
    where = f"tolerances.quantities.{spec.key}"
    try:
        nominal = apply.nominal(parameters, spec.key)
    except apply.NotTolerable as exc:
        problems.append(f"{where}: {exc}")
        return None
    spread = spec.spread
    name = spec.spread_name
    if spread.relative:
        if nominal == 0.0:
            problems.append(
                f"{where}.{name} = {spread.text!r}: a percentage of a configured value of 0 is "
                f"0; give the spread in {quantity.kind.unit or 'plain numbers'} instead"
            )
            return None
        width = spread.value * abs(nominal)
    else:
        width = spread.value
    scale = width / 3.0 if name == "three_sigma" else width
    marginal = DISTRIBUTIONS[spec.distribution]
    if quantity.lower_bound is not None:
        low = nominal - marginal.reach * scale
        bound = quantity.lower_bound
        if low < bound or (quantity.strict and low == bound):
            unit = f" {quantity.kind.unit}" if quantity.kind.unit else ""
            reach = (
                f"nominal - {NORMAL_TRUNCATION:g} sigma"
                if spec.distribution == "normal"
                else "nominal - plus_minus"
            )
            relation = ">" if quantity.strict else ">="
            problems.append(
                f"{where}.{name} = {spread.text!r}: the {spec.distribution} spread reaches "
                f"{low:.4g}{unit} ({reach}, nominal {nominal:.4g}{unit}), but the quantity must "
                f"stay {relation} {bound:g}{unit}; use a smaller spread"
                + (" or a bounded distribution" if spec.distribution == "normal" else "")
            )
            return None
    if quantity.upper_bound is not None:
        high = nominal + marginal.reach * scale
        if high > quantity.upper_bound:
            problems.append(
                f"{where}.{name} = {spread.text!r}: the {spec.distribution} spread reaches "
                f"{high:.4g} (nominal {nominal:.4g}), but the quantity must stay <= "
                f"{quantity.upper_bound:g}; use a smaller spread"
            )
            return None
    return Tolerance(
        key=spec.key,
        distribution=spec.distribution,
        nominal=nominal,
        scale=scale,
        unit=quantity.kind.unit,
        spread_text=f"{name} = {spread.text!r}",
    )


def resolve(config: Config) -> ToleranceSet:
    """The configuration's tolerances against its nominal values.

    Raises :class:`ConfigError` (one line per problem: key, value, expected unit) if the
    config has no ``[tolerances]`` section, names a quantity the config does not set,
    gives a percentage of zero, or lets a quantity leave its physical range.
    """
    spec = config.spec.tolerances
    if spec is None:
        raise ConfigError(
            [
                "tolerances: missing; a Monte Carlo study needs a [tolerances] section with "
                "[tolerances.quantities] (see docs/montecarlo.md)"
            ],
            config.source,
        )
    parameters = apply.Parameters(config.system, config.spec.dynamics())
    return resolve_spec(spec, parameters, config.source)


def resolve_spec(
    spec: TolerancesSpec, parameters: apply.Parameters, source: str = "<string>"
) -> ToleranceSet:
    """Resolve a validated ``[tolerances]`` spec against the nominal parameters."""
    problems: list[str] = []
    resolved = [_resolve_one(q, parameters, problems) for q in spec.quantities.values()]
    if problems:
        raise ConfigError(problems, source)
    tolerances = tuple(t for t in resolved if t is not None)
    matrix = spec.correlation_matrix()
    return ToleranceSet(tolerances, tuple(tuple(row) for row in matrix))


def standard_deviations(tolerances: Sequence[Tolerance]) -> FloatArray:
    """Standard deviation of each quantity [SI unit of each quantity]."""
    return as_float([t.std for t in tolerances])

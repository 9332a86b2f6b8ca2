"""The ``[tolerances]`` section: which config quantities scatter, and how (docs/montecarlo.md).

A tolerance names a config quantity by its dotted key (``"damper.damping_rate"``), a
distribution (normal, uniform or triangular, centred on the configured value) and one
spread, written in the quantity's own unit or as a percentage of the configured value::

    [tolerances.quantities]
    "damper.damping_rate" = { distribution = "normal", sigma = "3 %" }
    "load.start_torque" = { distribution = "uniform", plus_minus = "0.1 N*m" }

The spread's unit is checked here, against the kind of the quantity named by the key;
the configured (nominal) value, the percentage and the physical range are resolved by
:func:`ecdsim.montecarlo.tolerances.resolve`, which sees the whole configuration.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from ecdsim.config.seeds import EXPECTED_SEED, seed_problem
from ecdsim.config.units import (
    ANGLE,
    DAMPING,
    HEAT_CAPACITY,
    INERTIA,
    LENGTH,
    MASS,
    MAX_QUANTITY_LENGTH,
    NUMBER,
    NUMBER_PATTERN,
    PER_KELVIN,
    SPEED,
    THERMAL_RESISTANCE,
    TORQUE,
    TORQUE_PER_KELVIN,
    TORSIONAL_STIFFNESS,
    Kind,
    QuantityError,
    magnitude_problem,
    quoted,
)

DURATION = Kind("time", "s", "0.5 s")

SAMPLING_METHODS = ("random", "lhs", "sobol")
DISTRIBUTIONS = ("normal", "uniform", "triangular")
SPREAD_FIELDS = {
    "normal": ("sigma", "three_sigma"),
    "uniform": ("plus_minus",),
    "triangular": ("plus_minus",),
}
DEFAULT_CHUNK_SIZE = 65_536

# Linear time: the number pattern splits a digit run one way only (see config.units).
_PERCENT = re.compile(rf"^\s*({NUMBER_PATTERN})\s*(?:%|percent)\s*$")


@dataclass(frozen=True)
class TolerableQuantity:
    """A config quantity that may carry a tolerance, and where it lives in the model.

    Attributes
    ----------
    key : the dotted config key, e.g. "damper.damping_rate"
    kind : its physical kind (unit for spreads and messages)
    model_path : attribute path to the field from ecdsim.montecarlo.apply.Parameters
    owner : the model class that must own the field (e.g. "LinearSpring"); None if any
    lower_bound : the lowest physical value [SI], None if unbounded
    strict : True if the value must exceed lower_bound, False if it may equal it
    upper_bound : the highest physical value [SI] (may equal it), None if unbounded
    """

    key: str
    kind: Kind
    model_path: tuple[str, ...]
    owner: str | None = None
    lower_bound: float | None = None
    strict: bool = False
    upper_bound: float | None = None


def _q(
    key: str, kind: Kind, path: str, owner: str | None = None, **bound: Any
) -> TolerableQuantity:
    # Paths start at ecdsim.montecarlo.apply.Parameters: its DeploymentSystem ("system")
    # or its dynamic parameters ("dynamics", needed only by the dynamic method).
    root = "" if path.startswith("dynamics.") else "system."
    return TolerableQuantity(key, kind, tuple((root + path).split(".")), owner, **bound)


TOLERABLE: dict[str, TolerableQuantity] = {
    q.key: q
    for q in (
        _q("damper.damping_rate", DAMPING, "ecd.damper.damping_rate", lower_bound=0.0, strict=True),
        _q("damper.coulomb_friction", TORQUE, "ecd.damper.coulomb_friction", lower_bound=0.0),
        _q(
            "damper.damping_temperature_coefficient",
            PER_KELVIN,
            "ecd.damper.damping_temperature_coefficient",
        ),
        _q(
            "damper.lubrication_friction.slope",
            TORQUE_PER_KELVIN,
            "ecd.damper.lubrication_friction.slope",
            "LinearTemperatureLaw",
        ),
        _q(
            "damper.lubrication_friction.at_0C",
            TORQUE,
            "ecd.damper.lubrication_friction.at_0c",
            "LinearTemperatureLaw",
        ),
        _q("gearbox.ratio", NUMBER, "ecd.gearbox.ratio", lower_bound=0.0, strict=True),
        _q("gearbox.damping_fraction", NUMBER, "ecd.gearbox.damping_fraction", lower_bound=0.0),
        _q("gearbox.damping_rate", DAMPING, "ecd.gearbox.damping_rate", lower_bound=0.0),
        _q("gearbox.coulomb_friction", TORQUE, "ecd.gearbox.coulomb_friction", lower_bound=0.0),
        # A lossy mesh's efficiencies (issue 16 item 5), in (0, 1].
        _q(
            "gearbox.efficiency.forward",
            NUMBER,
            "ecd.gearbox.efficiency.forward",
            "GearEfficiency",
            lower_bound=0.0,
            strict=True,
            upper_bound=1.0,
        ),
        _q(
            "gearbox.efficiency.backward",
            NUMBER,
            "ecd.gearbox.efficiency.backward",
            "GearEfficiency",
            lower_bound=0.0,
            strict=True,
            upper_bound=1.0,
        ),
        _q(
            "load.start_torque",
            TORQUE,
            "load.spring.start_torque",
            "LinearSpring",
            lower_bound=0.0,
            strict=True,
        ),
        _q("load.end_torque", TORQUE, "load.spring.end_torque", "LinearSpring", lower_bound=0.0),
        _q("load.travel", ANGLE, "load.travel", lower_bound=0.0, strict=True),
        # A factor on every row of [load] resistive_table (a relative spread, e.g. "20 %").
        _q(
            "load.resistive_table",
            NUMBER,
            "load.resistance.scale",
            "ResistiveTable",
            lower_bound=0.0,
        ),
        # Gravity in a ground test (docs/model.md); they need [load.gravity].
        _q("load.gravity.mass", MASS, "load.gravity.mass", "Gravity", lower_bound=0.0),
        _q("load.gravity.cg_radius", LENGTH, "load.gravity.cg_radius", "Gravity", lower_bound=0.0),
        _q("load.gravity.release_angle", ANGLE, "load.gravity.release_angle", "Gravity"),
        _q(
            "load.gravity.offload",
            NUMBER,
            "load.gravity.offload",
            "Gravity",
            lower_bound=0.0,
            upper_bound=1.0,
        ),
        _q(
            "load.spring_temperature_coefficient",
            PER_KELVIN,
            "load.spring.temperature_coefficient",
        ),
        _q(
            "load.system_friction.slope",
            TORQUE_PER_KELVIN,
            "load.system_friction.slope",
            "LinearTemperatureLaw",
        ),
        _q(
            "load.system_friction.at_0C",
            TORQUE,
            "load.system_friction.at_0c",
            "LinearTemperatureLaw",
        ),
        # The dynamic method's parameters (docs/dynamics.md); they need [load] inertia.
        _q("load.inertia", INERTIA, "dynamics.load_inertia", lower_bound=0.0, strict=True),
        _q("damper.rotor_inertia", INERTIA, "dynamics.rotor_inertia", lower_bound=0.0),
        _q("gearbox.inertia", INERTIA, "dynamics.gearbox_inertia", lower_bound=0.0),
        _q(
            "damper.static_friction_factor",
            NUMBER,
            "dynamics.static_friction_factor",
            lower_bound=1.0,
        ),
        _q(
            "damper.stribeck_speed",
            SPEED,
            "dynamics.stribeck_speed",
            lower_bound=0.0,
            strict=True,
        ),
        _q(
            "gearbox.stiffness",
            TORSIONAL_STIFFNESS,
            "dynamics.gear_stiffness",
            lower_bound=0.0,
            strict=True,
        ),
        _q("gearbox.mesh_damping", DAMPING, "dynamics.gear_mesh_damping", lower_bound=0.0),
        # The roll-off law and the damper's heating (docs/dynamics.md); they need
        # [damper.rolloff] or [damper.thermal] (and [load] inertia). A resistance must be
        # finite to take a tolerance: an adiabatic (omitted) one is refused by name.
        _q(
            "damper.rolloff.peak_speed",
            SPEED,
            "dynamics.rolloff.peak_speed",
            "Rolloff",
            lower_bound=0.0,
            strict=True,
        ),
        _q(
            "damper.rolloff.resistivity_coefficient",
            PER_KELVIN,
            "dynamics.rolloff.resistivity_coefficient",
            "Rolloff",
        ),
        _q(
            "damper.thermal.heat_capacity",
            HEAT_CAPACITY,
            "dynamics.thermal.heat_capacity",
            "Thermal",
            lower_bound=0.0,
            strict=True,
        ),
        _q(
            "damper.thermal.thermal_resistance",
            THERMAL_RESISTANCE,
            "dynamics.thermal.thermal_resistance",
            "Thermal",
            lower_bound=0.0,
            strict=True,
        ),
        _q(
            "damper.thermal.housing_heat_capacity",
            HEAT_CAPACITY,
            "dynamics.thermal.housing_heat_capacity",
            "Thermal",
            lower_bound=0.0,
            strict=True,
        ),
        _q(
            "damper.thermal.housing_thermal_resistance",
            THERMAL_RESISTANCE,
            "dynamics.thermal.housing_thermal_resistance",
            "Thermal",
            lower_bound=0.0,
            strict=True,
        ),
    )
}


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Spread(_Section):
    """A tolerance width: an SI value, or a fraction of the nominal value.

    Attributes
    ----------
    value : the width [SI unit of the quantity], or the fraction [-] if relative
    relative : True if ``value`` is a fraction of the nominal value ("5 %" -> 0.05)
    text : the width as written in the file, for messages
    """

    value: float
    relative: bool
    text: str


def parse_spread(raw: object, kind: Kind) -> Spread:
    """A width written in ``kind``'s unit or as a percentage; QuantityError if neither."""
    expected = f"{kind.expected}, or a percentage of the configured value, e.g. '5 %'"
    if isinstance(raw, str):
        if len(raw) > MAX_QUANTITY_LENGTH:
            raise QuantityError(
                f"{quoted(raw)} is too long (at most {MAX_QUANTITY_LENGTH} characters); {expected}"
            )
        match = _PERCENT.match(raw)
        if match is not None:
            fraction = float(match.group(1)) / 100.0
            if not fraction > 0.0 or fraction == float("inf"):
                raise QuantityError(f"{quoted(raw)} must be > 0; {expected}")
            too_far = magnitude_problem(fraction)  # "1e-320 %" made a zero scale
            if too_far is not None:
                raise QuantityError(f"{quoted(raw)} as a fraction {too_far}; {expected}")
            return Spread(value=fraction, relative=True, text=raw)
    try:
        value = kind.parse(raw)
    except QuantityError as exc:
        raise QuantityError(
            f"{exc} (or a percentage of the configured value, e.g. '5 %')"
        ) from None
    if not value > 0.0:
        raise QuantityError(
            f"{quoted(raw)} must be > 0 (remove the entry to hold the quantity at its configured "
            f"value); {expected}"
        )
    return Spread(value=value, relative=False, text=str(raw))


class QuantityToleranceSpec(_Section):
    """One entry of ``[tolerances.quantities]``: a distribution and its spread.

    ``normal`` takes ``sigma`` or ``three_sigma`` (the +-3 sigma band); ``uniform`` and
    ``triangular`` take ``plus_minus`` (the half-width; triangular peaks at the
    configured value). Each spread is in the quantity's unit or a percentage.
    """

    key: str = Field(description="the dotted config key (filled in from the table key)")
    distribution: Literal["normal", "uniform", "triangular"]
    sigma: Spread | None = None
    three_sigma: Spread | None = None
    plus_minus: Spread | None = None

    @field_validator("sigma", "three_sigma", "plus_minus", mode="before")
    @classmethod
    def _parse(cls, value: object, info: ValidationInfo) -> object:
        if value is None or isinstance(value, Spread):
            return value
        quantity = TOLERABLE.get(str(info.data.get("key")))
        if quantity is None:
            return None  # the key's own error is already reported
        try:
            return parse_spread(value, quantity.kind)
        except QuantityError as exc:
            raise PydanticCustomError("quantity", "{detail}", {"detail": str(exc)}) from None

    @model_validator(mode="after")
    def _one_spread(self) -> QuantityToleranceSpec:
        allowed = SPREAD_FIELDS[self.distribution]
        given = [name for name in ("sigma", "three_sigma", "plus_minus") if getattr(self, name)]
        wrong = [name for name in given if name not in allowed]
        if wrong or len(given) != 1:
            choices = " or ".join(allowed)
            raise ValueError(
                f"a {self.distribution} tolerance takes exactly one of {choices}"
                + (f" (got {', '.join(given)})" if given else "")
            )
        return self

    @property
    def spread(self) -> Spread:
        """The one spread given (validated to exist)."""
        for name in ("sigma", "three_sigma", "plus_minus"):
            value: Spread | None = getattr(self, name)
            if value is not None:
                return value
        raise AssertionError("validated to have one spread")  # pragma: no cover

    @property
    def spread_name(self) -> str:
        """Which spread field was given: "sigma", "three_sigma" or "plus_minus"."""
        return next(n for n in ("sigma", "three_sigma", "plus_minus") if getattr(self, n))


class CorrelationSpec(_Section):
    """One ``[[tolerances.correlations]]`` entry: two quantities and their correlation.

    The coefficient is the correlation of the two quantities' normal scores (a Gaussian
    copula); for two normal tolerances it is their ordinary (Pearson) correlation.
    """

    quantities: tuple[str, str]
    coefficient: float = Field(gt=-1.0, lt=1.0)

    @model_validator(mode="after")
    def _two_different(self) -> CorrelationSpec:
        if self.quantities[0] == self.quantities[1]:
            raise ValueError(f"a correlation needs two different quantities, got {self.quantities}")
        return self


class RepeatabilitySpec(_Section):
    """``repeatability``: how many repeated deployments, and the spread they must keep.

    Defaults are the paper's (section 6): over 500 deployments, within 0.5 s.
    """

    runs: int = Field(default=500, ge=2)
    within: float = 0.5

    @field_validator("within", mode="before")
    @classmethod
    def _time(cls, value: object) -> float:
        try:
            seconds = DURATION.parse(value)
        except QuantityError as exc:
            raise PydanticCustomError("quantity", "{detail}", {"detail": str(exc)}) from None
        if not seconds > 0.0:
            raise PydanticCustomError(
                "quantity",
                "{detail}",
                {"detail": f"{quoted(value)} must be > 0; {DURATION.expected}"},
            )
        return seconds


def _flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Dotted keys written unquoted in TOML arrive as nested tables: join them back."""
    flat: dict[str, Any] = {}
    for name, value in table.items():
        key = f"{prefix}{name}"
        if isinstance(value, dict) and "distribution" not in value and value:
            flat.update(_flatten(value, key + "."))
        else:
            flat[key] = value
    return flat


class TolerancesSpec(_Section):
    """``[tolerances]``: the Monte Carlo study's inputs (docs/montecarlo.md).

    Attributes
    ----------
    sampling : "random", "lhs" (Latin hypercube per chunk) or "sobol" (scrambled)
    seed : the study's seed, >= 0; None to draw one (recorded in the run's manifest)
    chunk_size : samples per chunk; fixes the design (a power of two for sobol)
    quantities : the tolerances, by dotted config key
    correlations : correlated pairs (Gaussian copula on the normal scores)
    repeatability : the repeated-deployment study's run count and stated spread
    """

    sampling: Literal["random", "lhs", "sobol"] = "lhs"
    seed: int | None = None
    chunk_size: int = Field(default=DEFAULT_CHUNK_SIZE, ge=1)
    quantities: dict[str, QuantityToleranceSpec] = Field(min_length=1)
    correlations: list[CorrelationSpec] = Field(default_factory=list)
    repeatability: RepeatabilitySpec = Field(default_factory=RepeatabilitySpec)

    @field_validator("seed", mode="before")
    @classmethod
    def _seed_not_boolean(cls, value: object) -> object:
        if isinstance(value, bool):  # pydantic would read true as 1
            raise ValueError(f"{quoted(value)} is not a seed; {EXPECTED_SEED}")
        return value

    @field_validator("seed")
    @classmethod
    def _seed_in_range(cls, value: int | None) -> int | None:
        problem = None if value is None else seed_problem(value)  # the one rule for seeds
        if problem is not None:
            raise ValueError(f"{quoted(value)} is not a seed; {problem}")
        return value

    @field_validator("quantities", mode="before")
    @classmethod
    def _known_keys(cls, value: object) -> object:
        if not isinstance(value, dict):
            return value
        flat = _flatten(value)
        unknown = [key for key in flat if key not in TOLERABLE]
        if unknown:
            names = ", ".join(repr(k) for k in unknown)
            raise PydanticCustomError(
                "quantity",
                "{detail}",
                {
                    "detail": f"{names} cannot take a tolerance; expected one of "
                    + ", ".join(TOLERABLE)
                },
            )
        return {
            key: ({**entry, "key": key} if isinstance(entry, dict) else entry)
            for key, entry in flat.items()
        }

    @model_validator(mode="after")
    def _consistent(self) -> TolerancesSpec:
        problems = []
        if self.sampling == "sobol" and self.chunk_size & (self.chunk_size - 1):
            problems.append(
                f"chunk_size = {self.chunk_size}: sobol sampling needs a power of two "
                "(each chunk is a contiguous, balanced block of the Sobol sequence), "
                "e.g. 65536"
            )
        pairs: set[frozenset[str]] = set()
        for i, correlation in enumerate(self.correlations):
            missing = [q for q in correlation.quantities if q not in self.quantities]
            if missing:
                problems.append(
                    f"correlations[{i}]: {', '.join(repr(q) for q in missing)} has no "
                    "tolerance in [tolerances.quantities]"
                )
            pair = frozenset(correlation.quantities)
            if pair in pairs:
                problems.append(f"correlations[{i}]: the pair {correlation.quantities} repeats")
            pairs.add(pair)
        if not problems and self.correlations and not _positive_definite(self):
            problems.append(
                "correlations: the coefficients are inconsistent (the correlation matrix is "
                "not positive definite); weaken them"
            )
        if problems:
            raise ValueError("; ".join(problems))
        return self

    def correlation_matrix(self) -> list[list[float]]:
        """The correlation matrix of the normal scores, in the order of ``quantities``."""
        keys = list(self.quantities)
        matrix = [[1.0 if i == j else 0.0 for j in range(len(keys))] for i in range(len(keys))]
        for correlation in self.correlations:
            i, j = (keys.index(q) for q in correlation.quantities)
            matrix[i][j] = matrix[j][i] = correlation.coefficient
        return matrix


def _positive_definite(spec: TolerancesSpec) -> bool:
    import numpy as np

    try:
        np.linalg.cholesky(np.asarray(spec.correlation_matrix(), dtype=float))
    except np.linalg.LinAlgError:
        return False
    return True

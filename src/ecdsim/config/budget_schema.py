"""The ``[budget]`` section: a torque budget as a flight program keeps it (docs/qualification.md).

A budget file holds ``[budget]`` alone (``ecdsim margin BUDGET.toml``); a deployment
config may hold one too, where the model fills the torques (``ecdsim margin CONFIG``)::

    [budget]
    available = "44 in*lbf"                  # the drive's minimum available torque
    factors = { known = 1.5, unknown = 3.0 } # one factor per kind, the kinds are the user's
    [[budget.torque]]
    name = "ECD magnetic Coulomb friction"
    value = "6.5 in*lbf"
    kind = "known"

Kinds are names the user chooses (GSFC-STD-7000's known/unknown, ECSS-E-ST-33-01C's
kinds, a program's own); every kind used needs a factor once any factor is given. Factors
per program phase: ``[budget.phases.NAME] factors = {...}``, a kind a phase leaves out
taking the base ``factors``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from pydantic import Field, field_validator, model_validator

from ecdsim.config.fields import NonNegativeTorque, PositiveTorque
from ecdsim.config.sizing_schema import DampingSpeed, Factor, _Section
from ecdsim.config.units import _NUMBER, TORQUE, QuantityError

# The model's resistive torques a config fills the budget with (docs/qualification.md);
# the names are the torque margin's kinds (ecdsim.sizing.margin.RESISTIVE_TYPES).
ModelTerm = Literal[
    "ecd_friction", "system_friction", "damping", "resistive_table", "gravity", "gear_loss"
]
MODEL_TERMS: tuple[str, ...] = ModelTerm.__args__  # type: ignore[attr-defined]


class BudgetTorqueSpec(_Section):
    """``[[budget.torque]]``: one resistive torque of the budget."""

    name: str
    value: NonNegativeTorque
    kind: str
    source: str | None = None

    @field_validator("kind")
    @classmethod
    def _named(cls, value: str) -> str:
        name = value.strip()
        if not name:
            raise ValueError("a kind is a non-empty name, e.g. 'known'")
        return name


class BudgetPhaseSpec(_Section):
    """``[budget.phases.NAME]``: the factors of one program phase."""

    factors: dict[str, Factor] = Field(default_factory=dict)


class BudgetSpec(_Section):
    """``[budget]``: available torque, factors per kind (and phase), resistive torques."""

    name: str | None = None
    available: PositiveTorque | None = None
    factors: dict[str, Factor] = Field(default_factory=dict)
    phases: dict[str, BudgetPhaseSpec] = Field(default_factory=dict)
    torque: list[BudgetTorqueSpec] = Field(default_factory=list)
    # In a config: the kind of each torque the model fills in (default: its own name).
    model_kinds: dict[str, str] = Field(default_factory=dict)
    # In a config: model torques already inside `available` (a drive test's available
    # torque is net of the hinge friction: exclude = ["system_friction"]).
    exclude: list[str] = Field(default_factory=list)
    # In a config: the speed of the damping torque; "deployment" (None) takes the
    # deployment's own speed. Left out: [requirements.torque_margin]'s, else 0 (none).
    damping_speed: DampingSpeed = None

    @property
    def damping_speed_given(self) -> bool:
        """True if the section states a damping speed (None then means "deployment")."""
        return "damping_speed" in self.model_fields_set

    @model_validator(mode="after")
    def _kinds_have_factors(self) -> BudgetSpec:
        unknown = [term for term in self.model_kinds if term not in MODEL_TERMS]
        unknown += [term for term in self.exclude if term not in MODEL_TERMS]
        if unknown:
            where = "model_kinds" if unknown[0] in self.model_kinds else "exclude"
            raise ValueError(
                f"{where}: {unknown[0]!r} is not a torque of the model; expected one of "
                f"{', '.join(MODEL_TERMS)}"
            )
        if not self.factors and not self.phases:
            return self  # no factors at all: every factor 1 ("no factors applied")
        for i, entry in enumerate(self.torque):
            missing = self.phases_missing(entry.kind)
            if missing:
                raise ValueError(
                    f"torque[{i}] ({entry.name!r}): kind {entry.kind!r} has no factor"
                    f"{missing}; known kinds: {', '.join(self.known_kinds()) or 'none'}"
                )
        for term, kind in self.model_kinds.items():
            missing = self.phases_missing(kind)
            if missing:
                raise ValueError(
                    f"model_kinds.{term}: kind {kind!r} has no factor{missing}; known "
                    f"kinds: {', '.join(self.known_kinds()) or 'none'}"
                )
        return self

    def known_kinds(self) -> list[str]:
        """Every kind that has a factor somewhere (base or a phase), sorted."""
        kinds = set(self.factors)
        for phase in self.phases.values():
            kinds |= set(phase.factors)
        return sorted(kinds)

    def phases_missing(self, kind: str) -> str:
        """Where ``kind`` has no factor: "" if it has one everywhere, else " in budget.factors"
        or " in phase(s) X, Y"."""
        if kind in self.factors:
            return ""
        if not self.phases:
            return " in budget.factors"
        lacking = [name for name, phase in self.phases.items() if kind not in phase.factors]
        return f" in phase(s) {', '.join(lacking)} (nor in budget.factors)" if lacking else ""

    def phase_factors(self) -> dict[str, dict[str, float]]:
        """Each phase's factors by kind (a phase's own, else the base's); one phase named
        "" when no phases are given."""
        if not self.phases:
            return {"": dict(self.factors)}
        return {name: {**self.factors, **phase.factors} for name, phase in self.phases.items()}


class StandaloneBudgetSpec(BudgetSpec):
    """``[budget]`` of a budget file: the available torque must be given."""

    available: PositiveTorque


class BudgetFileSpec(_Section):
    """A budget file: an optional title and ``[budget]``."""

    title: str = "torque budget"
    budget: StandaloneBudgetSpec


@dataclass(frozen=True)
class WrittenUnit:
    """The torque unit a user wrote a value in, for showing results in it.

    Attributes
    ----------
    label : the unit as written ("in*lbf")
    si_per_unit : N*m per one of it
    """

    label: str
    si_per_unit: float


def written_unit(value: object) -> WrittenUnit | None:
    """The torque unit of a quantity string as written ("44 in*lbf" -> in*lbf), or None
    where the value is not such a string."""
    if not isinstance(value, str):
        return None
    match = _NUMBER.match(value)
    if match is None or not match.group(2):
        return None
    unit = match.group(2)
    try:
        factor = TORQUE.parse(f"1 {unit}")
    except QuantityError:
        return None
    return WrittenUnit(unit, factor) if factor > 0.0 else None

"""The whole configuration file's schema, with its study sections (docs/config.md).

:class:`ConfigSpec` is :class:`ecdsim.config.schema.CoreConfigSpec` with the sections of
the studies: ``[requirements]`` and ``[fluid_damper]`` (sizing), ``[tolerances]``
(Monte Carlo) and ``[budget]`` (the torque budget, docs/qualification.md). It lives in
its own module so that a file without those sections is validated without importing
their schemas (start-up, docs/architecture.md); the loader picks the spec by the file's
top-level keys.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from ecdsim.config.budget_schema import BudgetSpec
from ecdsim.config.schema import (
    AnalysisSpec,
    DamperSpec,
    GearboxSpec,
    InitialSpec,
    LoadSpec,
    OutputSpec,
    SpecBase,
)
from ecdsim.config.sizing_schema import FluidDamperSpec, RequirementsSpec
from ecdsim.config.tolerance_schema import TolerancesSpec
from ecdsim.config.units import Kind

__all__ = ["ConfigSpec", "describe_field", "model_in"]


class ConfigSpec(SpecBase):
    """A whole configuration file (fields in the order of docs/config.md)."""

    title: str = "deployment"
    damper: DamperSpec
    gearbox: GearboxSpec
    load: LoadSpec
    analysis: AnalysisSpec = Field(default_factory=AnalysisSpec)
    requirements: RequirementsSpec | None = None
    fluid_damper: FluidDamperSpec | None = None
    tolerances: TolerancesSpec | None = None
    budget: BudgetSpec | None = None
    initial: InitialSpec = Field(default_factory=InitialSpec)
    output: OutputSpec = Field(default_factory=OutputSpec)


def describe_field(loc: tuple[Any, ...]) -> tuple[str | None, list[str]]:
    """For a key path: the expected-unit phrase of the field, and the section's known keys."""
    model: type[BaseModel] | None = ConfigSpec
    expected: str | None = None
    known: list[str] = list(ConfigSpec.model_fields)
    for part in loc:
        if model is None or not isinstance(part, str) or part not in model.model_fields:
            return expected, known
        info = model.model_fields[part]
        known = list(model.model_fields)
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        expected = kinds[0].expected if kinds else None
        nested = model_in(info.annotation)
        if nested is not None:
            known = list(nested.model_fields)
        model = nested
    return expected, known


def model_in(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model inside a field's annotation (``X | None`` -> X), or None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = model_in(arg)
        if found is not None:
            return found
    return None

"""The wing file: a TOML description of a planar chain of panels (docs/wing.md).

A wing file has ``title``, ``[wing]`` (named ECDs, panels, hinges, cables, a ground
test), ``[analysis]`` (temperatures, stop time, tolerance) and ``[output]``; it has no
``[damper]``, ``[gearbox]`` or ``[load]``: each hinge carries its own spring and
friction, and names its ECD. The pieces of the single-hinge schema are reused as they
are: an ECD is a ``[damper]`` and a ``[gearbox]`` section (every key of both, the
dynamic ones included) or a catalogue entry; a hinge's spring takes the keys of
``[load]``'s spring (and the same checks, run by ``LoadSpec``'s own validator); its
friction is a friction law (``[load] system_friction``'s form); quantities are the same
fields with the same units and messages. Every problem is reported at once, one line
each, naming the key path, the value and the expected unit (exit code 2 at the
command line).

Catalogue entries are read by a function the caller passes (``read_catalogue``, e.g.
:func:`ecdsim.sizing.catalogue.load_catalogue`): catalogues belong to the sizing
package, a layer above the configuration.
"""

from __future__ import annotations

import hashlib
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Protocol, get_args, get_origin

from pydantic import (
    BaseModel,
    BeforeValidator,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from ecdsim.config.errors import ConfigError
from ecdsim.config.fields import (
    Angle,
    NonNegativeDamping,
    NonNegativeInertia,
    NonNegativeTorque,
    PerKelvin,
    PositiveNumber,
    PositiveTime,
    Temperature,
    Torque,
    quantity,
)
from ecdsim.config.loader import (
    MAX_NESTING,
    error_lines,
    nesting_depth,
    parse_toml,
    read_config_text,
)
from ecdsim.config.schema import (
    DamperSpec,
    FrictionLawSpec,
    GearboxSpec,
    LoadSpec,
    NonNegativeLength,
    Offload,
    OutputSpec,
    PositiveStiffness,
    Restitution,
    StaticFactor,
    Tolerance,
    _Section,
)
from ecdsim.config.tolerance_schema import (
    QuantityToleranceSpec,
    Spread,
    TolerancesSpec,
    parse_spread,
)
from ecdsim.config.units import LENGTH, MASS, Kind, QuantityError
from ecdsim.model import Ecd, Gearbox, HighSpeedDamper
from ecdsim.wing.model import Cable, GroundTest, Hinge, HingeEcd, Latch, Panel, Wing

__all__ = [
    "WingConfig",
    "WingConfigSpec",
    "describe_wing_field",
    "is_wing_document",
    "load_wing_config",
    "parse_wing_config",
]

FORCE = Kind("force", "N", "200 N")


def _positive(x: float) -> str | None:
    return None if x > 0.0 else "must be > 0"


def _non_negative(x: float) -> str | None:
    return None if x >= 0.0 else "must be >= 0"


PositiveMass = Annotated[float, quantity(MASS, _positive), MASS]
PositiveLength = Annotated[float, quantity(LENGTH, _positive), LENGTH]
Length = Annotated[float, quantity(LENGTH), LENGTH]
NonNegativeForce = Annotated[float, quantity(FORCE, _non_negative), FORCE]

NO_ECD = "none"  # a hinge's ``ecd`` for an undamped hinge


class CatalogueEcdSpec(_Section):
    """``catalogue = { file, damper, gearbox, ratio }``: an ECD from a catalogue file.

    ``file`` is read relative to the wing file's folder (docs/sizing.md has the format).
    """

    file: str = Field(min_length=1)
    damper: str = Field(min_length=1)
    gearbox: str = Field(min_length=1)
    ratio: PositiveNumber


class EcdSpec(_Section):
    """``[wing.ecds.NAME]``: an ECD that hinges name; ``damper`` and ``gearbox`` (every key
    of ``[damper]`` and ``[gearbox]``) or a ``catalogue`` entry."""

    damper: DamperSpec | None = None
    gearbox: GearboxSpec | None = None
    catalogue: CatalogueEcdSpec | None = None

    @model_validator(mode="after")
    def _one_form(self) -> EcdSpec:
        inline = self.damper is not None or self.gearbox is not None
        if inline and self.catalogue is not None:
            raise ValueError("give either damper and gearbox, or catalogue, not both")
        if self.catalogue is None and (self.damper is None or self.gearbox is None):
            missing = "damper" if self.damper is None else "gearbox"
            raise ValueError(
                f"missing {missing}: an ECD is a [damper] and a [gearbox] section (every key "
                "they take in a single-hinge file), or catalogue = { file, damper, gearbox, "
                "ratio }"
            )
        return self


class PanelSpec(_Section):
    """``[[wing.panels]]``: one rigid panel, root first (docs/wing.md)."""

    name: str | None = Field(default=None, min_length=1)
    mass: PositiveMass
    length: PositiveLength
    cg_along: Length
    cg_across: Length = 0.0
    inertia: NonNegativeInertia
    thickness: NonNegativeLength = 0.0

    def to_model(self, index: int) -> Panel:
        """The model panel (SI); unnamed panels are "panel 1", "panel 2", ..."""
        return Panel(
            name=self.name or f"panel {index + 1}",
            mass=self.mass,
            length=self.length,
            cg_along=self.cg_along,
            cg_across=self.cg_across,
            inertia=self.inertia,
            thickness=self.thickness,
        )


class LatchSpec(_Section):
    """``[wing.hinges.latch]``: rigid with ``restitution``, or ``stiffness`` and ``damping``."""

    restitution: Restitution | None = None
    stiffness: PositiveStiffness | None = None
    damping: NonNegativeDamping | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> LatchSpec:
        if self.damping is not None and self.stiffness is None:
            raise ValueError("damping needs stiffness (a compliant latch's N*m/rad)")
        if self.stiffness is not None and self.restitution is not None:
            raise ValueError(
                "give restitution (a rigid latch) or stiffness and damping (a compliant "
                "latch), not both"
            )
        return self

    def to_model(self) -> Latch:
        """The model latch (SI)."""
        if self.stiffness is None:
            return Latch(restitution=0.0 if self.restitution is None else self.restitution)
        return Latch(
            stiffness=self.stiffness, damping=0.0 if self.damping is None else self.damping
        )


class HingeSpec(_Section):
    """``[[wing.hinges]]``: one hinge, root first: angles, spring, friction, ECD, latch."""

    name: str | None = Field(default=None, min_length=1)
    stowed_angle: Angle
    deployed_angle: Angle
    start_torque: NonNegativeTorque | None = None
    end_torque: NonNegativeTorque | None = None
    spring_table: list[tuple[Angle, NonNegativeTorque]] | None = None
    spring_temperature_coefficient: PerKelvin = 0.0
    reference_temperature: Temperature = 25.0
    resistive_table: list[tuple[Angle, Torque]] | None = None
    resistive_temperature_coefficient: PerKelvin = 0.0
    friction: FrictionLawSpec | None = None
    static_friction_factor: StaticFactor | None = None
    ecd: str = Field(min_length=1)
    latch: LatchSpec = Field(default_factory=LatchSpec)

    @property
    def travel(self) -> float:
        """|deployed_angle - stowed_angle| [rad]."""
        return abs(self.deployed_angle - self.stowed_angle)

    def _as_load(self) -> LoadSpec:
        """The hinge's spring keys as a ``[load]`` section (unvalidated: built, then checked
        by LoadSpec's own rules), so that the single hinge's code builds the spring."""
        return LoadSpec.model_construct(
            start_torque=self.start_torque,
            end_torque=self.end_torque,
            spring_table=self.spring_table,
            resistive_table=self.resistive_table,
            resistive_temperature_coefficient=self.resistive_temperature_coefficient,
            travel=self.travel,
            system_friction=self.friction,
            spring_temperature_coefficient=self.spring_temperature_coefficient,
            reference_temperature=self.reference_temperature,
        )

    @model_validator(mode="after")
    def _spring(self) -> HingeSpec:
        if self.deployed_angle == self.stowed_angle:
            raise ValueError(
                f"deployed_angle equals stowed_angle ({self.stowed_angle:g} rad): no travel"
            )
        # [load]'s own spring rules (one form; each table from 0, rising, reaching the
        # travel) on the hinge's keys. pydantic wraps a validator in a descriptor that
        # mypy does not see as callable; it is a plain method on the instance.
        self._as_load()._one_spring()  # type: ignore[operator]
        return self


class CableSpec(_Section):
    """``[[wing.cables]]``: a closed cable loop between two adjacent hinges."""

    hinges: tuple[int, int]
    ratio: PositiveNumber
    stiffness: PositiveStiffness | None = None
    pretension: NonNegativeForce | None = None
    pulley_radius: PositiveLength | None = None

    @model_validator(mode="after")
    def _form(self) -> CableSpec:
        first, second = self.hinges
        if first < 1 or second != first + 1:
            raise ValueError(
                f"hinges = {list(self.hinges)}: give two adjacent hinge numbers counted from "
                "the root (1), inboard first, e.g. [1, 2]"
            )
        elastic = [self.pretension is not None, self.pulley_radius is not None]
        if self.stiffness is None and any(elastic):
            raise ValueError(
                "pretension and pulley_radius need stiffness (without it the cable is rigid)"
            )
        if self.stiffness is not None and not all(elastic):
            missing = "pretension" if self.pretension is None else "pulley_radius"
            raise ValueError(
                f"missing {missing}: an elastic cable needs stiffness, pretension (N, each "
                "strand) and pulley_radius (m, at the outboard hinge)"
            )
        return self

    def to_model(self) -> Cable:
        """The model cable (SI); the slack torque is 2 T0 rho (docs/wing.md)."""
        if self.stiffness is None:
            return Cable(inboard=self.hinges[0] - 1, ratio=self.ratio)
        assert self.pretension is not None
        assert self.pulley_radius is not None
        return Cable(
            inboard=self.hinges[0] - 1,
            ratio=self.ratio,
            stiffness=self.stiffness,
            slack_torque=2.0 * self.pretension * self.pulley_radius,
        )


def _one_or_list(value: object) -> object:
    """One value for every panel, or a list of one per panel: read as a list."""
    return value if isinstance(value, list) else [value]


class GroundTestSpec(_Section):
    """``[wing.ground_test]``: gravity in the plane and the offload of each panel."""

    gravity_direction: Angle
    # A single value (every panel) or one per panel, read as a list of one or n.
    offload: Annotated[list[Offload], BeforeValidator(_one_or_list), Field(min_length=1)] = Field(
        default_factory=lambda: [0.0]
    )


class WingSpec(_Section):
    """``[wing]``: named ECDs, panels and hinges root first, cables, a ground test."""

    ecds: dict[str, EcdSpec] = Field(default_factory=dict)
    panels: list[PanelSpec] = Field(min_length=1)
    hinges: list[HingeSpec] = Field(min_length=1)
    cables: list[CableSpec] = Field(default_factory=list)
    ground_test: GroundTestSpec | None = None

    def problems(self) -> list[str]:
        """The rules across panels, hinges, ECDs, cables and the ground test, one line
        each with its key path (checked once every key is valid on its own)."""
        lines = []
        n = len(self.panels)
        if len(self.hinges) != n:
            lines.append(
                f"wing.hinges: {len(self.hinges)} hinges for {n} panels: give one hinge "
                "inboard of each panel, root first"
            )
        if NO_ECD in self.ecds:
            lines.append(f"wing.ecds.{NO_ECD}: the name is reserved for an undamped hinge")
        for i, hinge in enumerate(self.hinges):
            if hinge.ecd != NO_ECD and hinge.ecd not in self.ecds:
                lines.append(
                    f"wing.hinges[{i}].ecd: no ECD {hinge.ecd!r} in [wing.ecds] (known: "
                    f"{sorted(self.ecds)}; or {NO_ECD!r} for an undamped hinge)"
                )
        seen: set[int] = set()
        for k, cable in enumerate(self.cables):
            first, second = cable.hinges
            if second > len(self.hinges):
                lines.append(
                    f"wing.cables[{k}].hinges: hinge {second} does not exist "
                    f"({len(self.hinges)} hinges)"
                )
                continue
            if first in seen:
                lines.append(
                    f"wing.cables[{k}].hinges: a second cable between hinges {first} and {second}"
                )
            seen.add(first)
            if cable.stiffness is None:
                inboard, outboard = self.hinges[first - 1].travel, self.hinges[second - 1].travel
                if abs(outboard - cable.ratio * inboard) > 1e-9 * max(outboard, inboard):
                    lines.append(
                        f"wing.cables[{k}].ratio: a rigid cable holds hinge {second}'s travel "
                        f"({outboard:g} rad) at {cable.ratio:g} x hinge {first}'s "
                        f"({inboard:g} rad), but they differ, so one of them could never "
                        "latch (give the travels in the ratio, or a cable stiffness)"
                    )
        test = self.ground_test
        if test is not None and len(test.offload) not in (1, n):
            lines.append(
                f"wing.ground_test.offload: {len(test.offload)} values for {n} panels (give "
                "one per panel, or one for all)"
            )
        return lines


class WingAnalysisSpec(_Section):
    """``[analysis]`` of a wing file: temperatures and the run's control."""

    temperatures: list[Temperature] = Field(default_factory=lambda: [25.0], min_length=1)
    stop_time: PositiveTime | None = None
    rtol: Tolerance = 1e-8


class WingQuantityToleranceSpec(QuantityToleranceSpec):
    """One entry of a wing file's ``[tolerances.quantities]``: as a single hinge's, the
    key a wing key path (:mod:`ecdsim.config.wing_keys`), its spread in that key's unit."""

    @field_validator("sigma", "three_sigma", "plus_minus", mode="before")
    @classmethod
    def _parse(cls, value: object, info: ValidationInfo) -> object:
        if value is None or isinstance(value, Spread):
            return value
        kind = field_kind(str(info.data.get("key")))
        if kind is None:
            return None  # the key's own error is already reported
        try:
            return parse_spread(value, kind)
        except QuantityError as exc:
            raise PydanticCustomError("quantity", "{detail}", {"detail": str(exc)}) from None


class WingTolerancesSpec(TolerancesSpec):
    """A wing file's ``[tolerances]``: the Monte Carlo study's inputs (docs/wing.md,
    studies), every key of ``[tolerances]`` with wing key paths as the quantities."""

    quantities: dict[str, WingQuantityToleranceSpec] = Field(min_length=1)  # type: ignore[assignment]

    @field_validator("quantities", mode="before")
    @classmethod
    def _known_keys(cls, value: object) -> object:
        if not isinstance(value, dict):
            return value
        problems = [p for key in value if (p := key_problem(key)) is not None]
        if problems:
            raise PydanticCustomError("quantity", "{detail}", {"detail": "; ".join(problems)})
        return {
            key: ({**entry, "key": key} if isinstance(entry, dict) else entry)
            for key, entry in value.items()
        }


class WingConfigSpec(_Section):
    """A whole wing file (docs/wing.md)."""

    title: str = "wing"
    wing: WingSpec
    analysis: WingAnalysisSpec = Field(default_factory=WingAnalysisSpec)
    output: OutputSpec = Field(default_factory=OutputSpec)
    tolerances: WingTolerancesSpec | None = None


class DamperEntryLike(Protocol):
    """What a catalogue's damper entry gives a wing (:class:`ecdsim.sizing.catalogue`)."""

    @property
    def damper(self) -> HighSpeedDamper:
        """The damper model."""
        ...

    @property
    def rotor_inertia(self) -> float | None:
        """The rotor's inertia [kg*m^2], None if not catalogued."""
        ...


class GearboxEntryLike(Protocol):
    """What a catalogue's gearbox entry gives a wing."""

    @property
    def ratios(self) -> tuple[float, ...]:
        """The ratios on offer."""
        ...

    def gearbox(self, ratio: float) -> Gearbox:
        """The gearbox model at ``ratio``."""
        ...


class CatalogueLike(Protocol):
    """A catalogue (:class:`ecdsim.sizing.catalogue.Catalogue`)."""

    def damper(self, name: str) -> DamperEntryLike:
        """The damper called ``name``; KeyError if absent."""
        ...

    def gearbox(self, name: str) -> GearboxEntryLike:
        """The gearbox called ``name``; KeyError if absent."""
        ...


CatalogueReader = Callable[[Path], CatalogueLike]


def _inline_ecd(name: str, spec: EcdSpec) -> HingeEcd:
    damper, gearbox = spec.damper, spec.gearbox
    assert damper is not None
    assert gearbox is not None
    return HingeEcd(
        ecd=Ecd(damper.to_model(), gearbox.to_model()),
        source=f"[wing.ecds.{name}]",
        rotor_inertia=damper.rotor_inertia,
        gearbox_inertia=gearbox.inertia,
        static_friction_factor=damper.static_friction_factor,
        stribeck_speed=damper.stribeck_speed,
        rolloff=damper.rolloff.to_model() if damper.rolloff else None,
        thermal=damper.thermal.to_model() if damper.thermal else None,
        gear_stiffness=gearbox.stiffness,
        gear_mesh_damping=gearbox.mesh_damping,
    )


def _catalogue_ecd(
    name: str, spec: CatalogueEcdSpec, base: Path, read_catalogue: CatalogueReader | None
) -> HingeEcd:
    key = f"wing.ecds.{name}.catalogue"
    if read_catalogue is None:
        raise ConfigError(
            [
                f"{key}: catalogue entries need a catalogue reader (pass read_catalogue="
                "ecdsim.sizing.catalogue.load_catalogue)"
            ]
        )
    catalogue = read_catalogue(base / spec.file)
    try:
        damper_entry = catalogue.damper(spec.damper)
        gearbox_entry = catalogue.gearbox(spec.gearbox)
    except KeyError as exc:
        raise ConfigError([f"{key}: {exc.args[0]}"]) from None
    if not any(math.isclose(spec.ratio, r, rel_tol=1e-12) for r in gearbox_entry.ratios):
        raise ConfigError(
            [
                f"{key}.ratio: {spec.ratio:g} is not a ratio of {spec.gearbox!r} (it offers "
                f"{list(gearbox_entry.ratios)})"
            ]
        )
    rotor = damper_entry.rotor_inertia
    return HingeEcd(
        ecd=Ecd(damper_entry.damper, gearbox_entry.gearbox(spec.ratio)),
        source=f"catalogue {spec.file}: {spec.damper} with {spec.gearbox} at {spec.ratio:g}:1",
        rotor_inertia=0.0 if rotor is None else rotor,
    )


def build_wing(
    spec: WingConfigSpec, base: Path = Path(), read_catalogue: CatalogueReader | None = None
) -> Wing:
    """The model :class:`~ecdsim.wing.model.Wing` (SI) of a validated wing file.

    ``base`` is the folder catalogue files are read from (the wing file's);
    ``read_catalogue`` reads one (needed only when an ECD is a catalogue entry).
    """
    wing = spec.wing
    ecds: dict[str, HingeEcd] = {}
    for name, ecd in wing.ecds.items():
        if ecd.catalogue is not None:
            ecds[name] = _catalogue_ecd(name, ecd.catalogue, base, read_catalogue)
        else:
            ecds[name] = _inline_ecd(name, ecd)
    panels = tuple(p.to_model(i) for i, p in enumerate(wing.panels))
    hinges = tuple(
        Hinge(
            name=h.name or f"hinge {i + 1}",
            stowed_angle=h.stowed_angle,
            deployed_angle=h.deployed_angle,
            load=h._as_load().to_model(),
            ecd=None if h.ecd == NO_ECD else ecds[h.ecd],
            latch=h.latch.to_model(),
            static_friction_factor=h.static_friction_factor,
        )
        for i, h in enumerate(wing.hinges)
    )
    ground = None
    if wing.ground_test is not None:
        offload = wing.ground_test.offload
        values = tuple(offload) if len(offload) > 1 else (offload[0],) * len(panels)
        ground = GroundTest(direction=wing.ground_test.gravity_direction, offload=values)
    cables = tuple(c.to_model() for c in wing.cables)
    return Wing(spec.title, panels, hinges, cables, ground)


@dataclass(frozen=True)
class WingConfig:
    """A validated wing file, in SI units.

    Attributes
    ----------
    wing : the wing model
    temperatures : analysis temperatures [degC]
    stop_time : end of the simulated interval [s] (inf: until every hinge latches or the
        wing rests)
    rtol : the integrator's relative tolerance [-]
    spec : the validated file content
    source : where it came from (a path or "<string>")
    sha256 : hash of the file's bytes
    """

    wing: Wing
    temperatures: tuple[float, ...]
    stop_time: float
    rtol: float
    spec: WingConfigSpec
    source: str
    sha256: str


def is_wing_document(raw: dict[str, Any]) -> bool:
    """True for a parsed TOML document that is a wing file (it has ``[wing]``)."""
    return "wing" in raw


def _container(annotation: Any) -> Any:
    """The list or dict origin of a field's annotation (``X | None`` looked through)."""
    origin = get_origin(annotation)
    if origin in (list, dict):
        return origin
    for arg in get_args(annotation):
        found = _container(arg)
        if found is not None:
            return found
    return None


def _model_in(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def describe_wing_field(loc: tuple[Any, ...]) -> tuple[str | None, list[str]]:
    """For a wing file's key path: the expected-unit phrase, and the section's keys.

    As :func:`ecdsim.config.full_schema.describe_field`, through the lists (``[[...]]``)
    and the named ECDs of a wing file.
    """
    model: type[BaseModel] | None = WingConfigSpec
    expected: str | None = None
    known: list[str] = list(WingConfigSpec.model_fields)
    skip_name = False
    for part in loc:
        if isinstance(part, int):
            continue
        if skip_name:  # the NAME of [wing.ecds.NAME]
            skip_name = False
            continue
        if model is None or part not in model.model_fields:
            return expected, known
        info = model.model_fields[part]
        known = list(model.model_fields)
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        expected = kinds[0].expected if kinds else None
        nested = _model_in(info.annotation)
        if nested is not None:
            known = list(nested.model_fields)
        skip_name = _container(info.annotation) is dict
        model = nested
    return expected, known


# --- key paths into a wing file (ecdsim.config.wing_keys: sweeps, Monte Carlo) ---

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
# wing, then dotted names each with optional [index] parts.
KEY_PATTERN = re.compile(rf"^wing(\.{_NAME}(\[\d+\])*)+$")
_PART = re.compile(rf"({_NAME})((?:\[\d+\])*)")
EXAMPLE_KEY = "wing.hinges[1].friction.at_0C"


class WingKeyError(ConfigError):
    """A key path that is not a quantity of the wing file (one line each)."""


def is_wing_key(key: str) -> bool:
    """True for a key path into ``[wing]`` (``wing.panels[0].mass``)."""
    return KEY_PATTERN.match(key) is not None


def split_key(key: str) -> tuple[str | int, ...]:
    """``wing.hinges[1].friction.at_0C`` -> ``("wing", "hinges", 1, "friction", "at_0C")``."""
    if not is_wing_key(key):
        raise WingKeyError([f"{key!r}: not a wing key; expected a path such as {EXAMPLE_KEY}"])
    parts: list[str | int] = []
    for piece in key.split("."):
        found = _PART.fullmatch(piece)
        assert found is not None  # the pattern above admits only such pieces
        parts.append(found.group(1))
        parts.extend(int(i) for i in re.findall(r"\[(\d+)\]", found.group(2)))
    return tuple(parts)


def field_kind(key: str) -> Kind | None:
    """The quantity kind of a wing key path, or None (not a quantity, or unknown)."""
    from ecdsim.config.overrides import _kind_in

    try:
        parts = split_key(key)
    except WingKeyError:
        return None
    model: Any = WingConfigSpec
    kind: Kind | None = None
    expect: str | None = None  # "index" after a list field, "name" after a dict field
    for part in parts:
        if expect == "index":
            if not isinstance(part, int):
                return None
            expect = None
            continue
        if expect == "name":
            expect = None
            continue
        if isinstance(part, int) or model is None or part not in model.model_fields:
            return None
        info = model.model_fields[part]
        container = _container(info.annotation)
        expect = "index" if container is list else "name" if container is dict else None
        kinds = [m for m in info.metadata if isinstance(m, Kind)]
        kind = kinds[0] if kinds else (None if container else _kind_in(info.annotation))
        model = _model_in(info.annotation)
    if expect is not None or model is not None:
        return None  # a list, a table or an ECD, not one quantity
    return kind


def key_problem(key: str) -> str | None:
    """Why ``key`` cannot be varied (one line), or None."""
    if not is_wing_key(key):
        return (
            f"{key}: not a key of a wing file; give its path in the file, e.g. {EXAMPLE_KEY} "
            "(docs/wing.md)"
        )
    if field_kind(key) is None:
        return (
            f"{key}: not a quantity of a wing file (a path to one number with its unit, "
            f"e.g. {EXAMPLE_KEY}; list entries counted from 0)"
        )
    return None


def validate_wing(raw: dict[str, Any], source: str = "<string>") -> WingConfigSpec:
    """Validate a parsed wing document; :class:`ConfigError` lists every problem."""
    if nesting_depth(raw) > MAX_NESTING:
        raise ConfigError(
            [f"nested too deeply (at most {MAX_NESTING} levels of tables and lists)"], source
        )
    try:
        spec = WingConfigSpec.model_validate(raw)
    except ValidationError as exc:
        raise ConfigError(error_lines(exc, describe_wing_field), source) from None
    problems = spec.wing.problems()
    if problems:
        raise ConfigError(problems, source)
    return spec


def parse_wing_config(
    text: str,
    source: str = "<string>",
    base: Path = Path(),
    read_catalogue: CatalogueReader | None = None,
) -> WingConfig:
    """Validate a wing file's TOML text; :class:`ConfigError` lists every problem.

    ``base``: the folder catalogue files are read from; ``read_catalogue``: reads one.
    """
    raw = parse_toml(text, source)  # invalid TOML, deep nesting, a 4,300-digit integer
    sha256 = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return wing_config_from_document(raw, source, base, read_catalogue, sha256)


def wing_config_from_document(
    raw: dict[str, Any],
    source: str = "<string>",
    base: Path = Path(),
    read_catalogue: CatalogueReader | None = None,
    sha256: str = "",
) -> WingConfig:
    """Validate a parsed wing document (a file's, or one with keys set by a sweep:
    :mod:`ecdsim.config.wing_keys`); :class:`ConfigError` lists every problem."""
    spec = validate_wing(raw, source)
    try:
        wing = build_wing(spec, base, read_catalogue)
    except ConfigError as exc:
        if exc.source is not None:  # a catalogue file's own problems name that file
            raise
        raise ConfigError(exc.problems, source) from None
    analysis = spec.analysis
    return WingConfig(
        wing=wing,
        temperatures=tuple(analysis.temperatures),
        stop_time=math.inf if analysis.stop_time is None else analysis.stop_time,
        rtol=analysis.rtol,
        spec=spec,
        source=source,
        sha256=sha256,
    )


def load_wing_config(path: str | Path, read_catalogue: CatalogueReader | None = None) -> WingConfig:
    """Read and validate a wing file; catalogue files are read relative to its folder."""
    file = Path(path)
    return parse_wing_config(read_config_text(file), str(file), file.parent, read_catalogue)

"""The configuration schema: pydantic models whose quantity fields parse unit strings.

Each quantity field is ``Annotated[float, <parser>, <Kind>]``: the parser turns the string
into an SI float (or a clear error), and the :class:`~ecdsim.config.units.Kind` lets a
missing-key message say which unit was expected.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic_core import PydanticCustomError

from ecdsim.config.fields import (
    Angle,
    NonNegativeAngle,
    NonNegativeDamping,
    NonNegativeInertia,
    NonNegativeNumber,
    NonNegativeTorque,
    PerKelvin,
    PositiveAngle,
    PositiveInertia,
    PositiveNumber,
    PositiveSpeed,
    PositiveTime,
    PositiveTorque,
    Speed,
    Temperature,
    Torque,
    TorquePerKelvin,
    non_negative,
    positive,
    quantity,
)
from ecdsim.config.units import (
    HEAT_CAPACITY,
    LENGTH,
    MASS,
    NUMBER,
    THERMAL_RESISTANCE,
    TORSIONAL_STIFFNESS,
    quoted,
)
from ecdsim.dynamics.kernel import effects as registered_effects
from ecdsim.dynamics.params import INTEGRATORS, DynamicParameters, Rolloff, Thermal
from ecdsim.methods import SOLVERS
from ecdsim.model import (
    Ecd,
    Gearbox,
    GearEfficiency,
    Gravity,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
    ResistiveTable,
    Spring,
    TabulatedSpring,
    TabulatedTemperatureLaw,
    TemperatureLaw,
)

# Dynamics (docs/dynamics.md).
PositiveHeatCapacity = Annotated[float, quantity(HEAT_CAPACITY, positive), HEAT_CAPACITY]
PositiveStiffness = Annotated[float, quantity(TORSIONAL_STIFFNESS, positive), TORSIONAL_STIFFNESS]
PositiveThermalResistance = Annotated[
    float, quantity(THERMAL_RESISTANCE, positive), THERMAL_RESISTANCE
]
StaticFactor = Annotated[
    float, quantity(NUMBER, lambda x: None if x >= 1.0 else "must be >= 1"), NUMBER
]
Restitution = Annotated[
    float, quantity(NUMBER, lambda x: None if 0.0 <= x < 1.0 else "must be in [0, 1)"), NUMBER
]
# The integrators' relative tolerance. Below 1e-13 it cannot be honoured: a step's error
# estimate is the difference of two float64 solutions, each off by a few ulp of the state
# (1e-16 of it per operation), so the step size control chases round-off. scipy and
# MATLAB floor rtol at 100 eps (2.2e-14); measured here (issue 23), the compliant backlash
# no longer reaches the latch at 1e-15 (a "horizon" warning after 31 s instead of 3 s)
# and the heating path at 1e-18, while 1e-13 gives the deployment times of 1e-14 to 1e-12.
MIN_RTOL = 1e-13
MAX_RTOL = 0.1


def _rtol_problem(x: float) -> str | None:
    if MIN_RTOL <= x <= MAX_RTOL:
        return None
    why = " (below it the integrator chases float64 round-off)" if x < MIN_RTOL else ""
    return f"must be in [{MIN_RTOL:g}, {MAX_RTOL:g}]{why}"


Tolerance = Annotated[float, quantity(NUMBER, _rtol_problem), NUMBER]
# A mesh efficiency (issue 16 item 5): dimensionless, 0 excluded (no power passes).
Efficiency = Annotated[
    float, quantity(NUMBER, lambda x: None if 0.0 < x <= 1.0 else "must be in (0, 1]"), NUMBER
]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class FrictionLawSpec(_Section):
    """A friction that depends on temperature (docs/config.md#friction-laws).

    Linear: ``slope`` and the value at one reference temperature, given as ``at_0C``
    (0 degC, the paper's form), ``at_32F`` (32 degF, the same temperature for a degF
    config) or ``at`` with ``value`` (any temperature, e.g. ``at = "77 degF"``). Or a
    measured ``table = [[T, F], ...]``.
    """

    slope: TorquePerKelvin | None = None
    at_0C: Torque | None = None  # noqa: N815 - the paper's name, "value at 0 degC"
    at_32F: Torque | None = None  # noqa: N815 - "value at 32 degF" (= 0 degC)
    at: Temperature | None = None
    value: Torque | None = None
    table: list[tuple[Temperature, Torque]] | None = None

    @model_validator(mode="after")
    def _one_form(self) -> FrictionLawSpec:
        references = [
            name
            for name, given in (
                ("at_0C", self.at_0C is not None),
                ("at_32F", self.at_32F is not None),
                ("at", self.at is not None or self.value is not None),
            )
            if given
        ]
        linear = self.slope is not None or bool(references)
        if linear and self.table is not None:
            raise ValueError(
                "give either slope and at_0C (or at_32F, or at and value), or table, not both"
            )
        if self.table is not None:
            temps = [t for t, _ in self.table]
            if len(temps) < 2:
                raise ValueError("table needs at least two [temperature, torque] points")
            if any(b <= a for a, b in zip(temps, temps[1:], strict=False)):
                raise ValueError(
                    f"table temperatures must be strictly increasing, got {temps} degC"
                )
            return self
        if len(references) > 1:
            raise ValueError(
                f"give one reference value, not {' and '.join(references)} "
                "(at_0C, at_32F, or at with value)"
            )
        if self.slope is None:
            raise ValueError("missing slope (give slope and at_0C, or a table)")
        if not references:
            raise ValueError("missing at_0C (give slope and at_0C, at_32F, or at and value)")
        if references == ["at"] and (self.at is None or self.value is None):
            missing = "at" if self.at is None else "value"
            other = "value" if missing == "at" else "at"
            raise ValueError(
                f"missing {missing}: {other} needs it (e.g. at = '77 degF', value = '4.1 lbf*in')"
            )
        return self

    def reference(self) -> tuple[float, float]:
        """The linear law's reference point: (temperature [degC], value [N*m]) as given."""
        if self.at is not None and self.value is not None:
            return self.at, self.value
        given = self.at_32F if self.at_32F is not None else self.at_0C
        assert given is not None  # _one_form guarantees one reference
        return 0.0, given

    def value_at_0c(self) -> float:
        """The linear law's value at 0 degC [N*m]: ``value - slope * at`` (the model's form)."""
        assert self.slope is not None  # _one_form guarantees it
        temperature, value = self.reference()
        return value - self.slope * temperature if temperature != 0.0 else value

    def to_law(self) -> TemperatureLaw:
        """The model's temperature law (SI)."""
        if self.table is not None:
            return TabulatedTemperatureLaw(
                tuple(t for t, _ in self.table), tuple(v for _, v in self.table)
            )
        # _one_form guarantees the slope and one reference here.
        assert self.slope is not None
        return LinearTemperatureLaw(self.slope, self.value_at_0c())


class RolloffSpec(_Section):
    """``[damper.rolloff]``: Kloss-form roll-off of the eddy torque (docs/dynamics.md)."""

    peak_speed: PositiveSpeed
    resistivity_coefficient: PerKelvin

    def to_model(self) -> Rolloff:
        """The model object (SI)."""
        return Rolloff(self.peak_speed, self.resistivity_coefficient)


class ThermalSpec(_Section):
    """``[damper.thermal]``: lumped heat capacity of the damper, or of its rotor and
    housing (two nodes, with ``housing_heat_capacity``; docs/dynamics.md)."""

    heat_capacity: PositiveHeatCapacity
    thermal_resistance: PositiveThermalResistance | None = None
    housing_heat_capacity: PositiveHeatCapacity | None = None
    housing_thermal_resistance: PositiveThermalResistance | None = None

    @model_validator(mode="after")
    def _housing(self) -> ThermalSpec:
        if self.housing_heat_capacity is None and self.housing_thermal_resistance is not None:
            raise ValueError(
                "housing_thermal_resistance needs housing_heat_capacity (J/K, the housing node)"
            )
        if self.housing_heat_capacity is not None and self.thermal_resistance is None:
            raise ValueError(
                "housing_heat_capacity needs thermal_resistance (K/W, rotor to housing)"
            )
        return self

    def to_model(self) -> Thermal:
        """The model object (SI); no thermal resistance means adiabatic."""
        if self.thermal_resistance is None:
            return Thermal(self.heat_capacity)
        if self.housing_heat_capacity is None:
            return Thermal(self.heat_capacity, self.thermal_resistance)
        return Thermal(
            self.heat_capacity,
            self.thermal_resistance,
            housing_heat_capacity=self.housing_heat_capacity,
            housing_thermal_resistance=math.inf
            if self.housing_thermal_resistance is None
            else self.housing_thermal_resistance,
        )


class DamperSpec(_Section):
    """``[damper]``: the high-speed magnetic damper (paper section 2)."""

    damping_rate: NonNegativeDamping
    reference_temperature: Temperature = 25.0
    damping_temperature_coefficient: PerKelvin = -0.004
    coulomb_friction: NonNegativeTorque
    lubrication_friction: FrictionLawSpec | None = None
    max_linear_speed: PositiveSpeed | None = None
    max_linear_torque: PositiveTorque | None = None
    rotor_inertia: NonNegativeInertia = 0.0  # at the high-speed shaft
    static_friction_factor: StaticFactor = 1.0
    # Stribeck speed of the sliding friction at the input (slow) shaft (dynamic method,
    # docs/model.md); None = kinetic friction independent of speed.
    stribeck_speed: PositiveSpeed | None = None
    rolloff: RolloffSpec | None = None
    thermal: ThermalSpec | None = None

    def to_model(self) -> HighSpeedDamper:
        """The model object (SI)."""
        return HighSpeedDamper(
            damping_rate=self.damping_rate,
            coulomb_friction=self.coulomb_friction,
            lubrication_friction=(
                self.lubrication_friction.to_law()
                if self.lubrication_friction
                else LinearTemperatureLaw()
            ),
            reference_temperature=self.reference_temperature,
            damping_temperature_coefficient=self.damping_temperature_coefficient,
            max_linear_speed=self.max_linear_speed,
            max_linear_torque=self.max_linear_torque,
        )


class GearEfficiencySpec(_Section):
    """``[gearbox] efficiency``: a lossy mesh (docs/model.md, lossy gear).

    ``forward`` while the load drives the damper (every deployment), ``backward`` while
    the damper side drives the load (an overrunning rotor); backward defaults to forward.
    """

    forward: Efficiency
    backward: Efficiency | None = None

    def to_model(self) -> GearEfficiency:
        """The model object."""
        backward = self.forward if self.backward is None else self.backward
        return GearEfficiency(forward=self.forward, backward=backward)


class GearboxSpec(_Section):
    """``[gearbox]``: the step-up gearbox (paper section 3)."""

    ratio: PositiveNumber
    damping_fraction: NonNegativeNumber | None = None
    damping_rate: NonNegativeDamping | None = None
    coulomb_friction: NonNegativeTorque
    lost_motion: NonNegativeAngle = 0.0
    inertia: NonNegativeInertia = 0.0  # referred to the high-speed shaft, like BG and FG
    # Compliant backlash (dynamic method): the mesh's torsional stiffness and damping in
    # series with the lost motion, at the input shaft; omitted = a rigid mesh.
    stiffness: PositiveStiffness | None = None
    mesh_damping: NonNegativeDamping | None = None
    # Mesh efficiency, the load-dependent alternative to FG (issue 16 item 5).
    efficiency: GearEfficiencySpec | None = None

    @model_validator(mode="after")
    def _one_damping(self) -> GearboxSpec:
        if (self.damping_fraction is None) == (self.damping_rate is None):
            raise ValueError(
                "give exactly one of damping_fraction (BG/BD, e.g. 0.26) and damping_rate "
                "(BG in N*m*s/rad)"
            )
        if self.mesh_damping is not None and self.stiffness is None:
            raise ValueError(
                "mesh_damping needs stiffness (the mesh's torsional stiffness in N*m/rad): "
                "it damps a compliant mesh only"
            )
        if self.efficiency is not None and self.coulomb_friction != 0.0:
            raise ValueError(
                f"efficiency replaces the constant gearbox friction: give coulomb_friction = "
                f"'0 N*m' with it (got {self.coulomb_friction:g} N*m; docs/model.md, lossy gear)"
            )
        return self

    def to_model(self) -> Gearbox:
        """The model object (SI)."""
        return Gearbox(
            ratio=self.ratio,
            coulomb_friction=self.coulomb_friction,
            damping_rate=self.damping_rate,
            damping_fraction=self.damping_fraction,
            lost_motion=self.lost_motion,
            efficiency=self.efficiency.to_model() if self.efficiency else None,
        )


# Gravity in a ground test (issue 16 item 2; docs/config.md, docs/model.md).
NonNegativeMass = Annotated[float, quantity(MASS, non_negative), MASS]
NonNegativeLength = Annotated[float, quantity(LENGTH, non_negative), LENGTH]
Offload = Annotated[
    float, quantity(NUMBER, lambda x: None if 0.0 <= x <= 1.0 else "must be in [0, 1]"), NUMBER
]


class GravitySpec(_Section):
    """``[load.gravity]``: gravity on the deployed mass in a ground test (docs/model.md).

    Omitted = flight (0 g), today's model; ``mass = 0`` or ``offload = 1`` give no torque.
    """

    mass: NonNegativeMass
    cg_radius: NonNegativeLength
    release_angle: Angle
    offload: Offload = 0.0

    def to_model(self) -> Gravity:
        """The model object (SI)."""
        return Gravity(self.mass, self.cg_radius, self.release_angle, self.offload)


class LoadSpec(_Section):
    """``[load]``: spring torque over the travel and system friction (paper section 5)."""

    start_torque: NonNegativeTorque | None = None
    end_torque: NonNegativeTorque | None = None
    spring_table: list[tuple[Angle, NonNegativeTorque]] | None = None
    # Harness, cable, blanket torque against angle, opposing deployment positive (a
    # negative row assists); linear between rows (docs/model.md, resistive torques).
    resistive_table: list[tuple[Angle, Torque]] | None = None
    resistive_temperature_coefficient: PerKelvin = 0.0
    travel: PositiveAngle
    system_friction: FrictionLawSpec | None = None
    spring_temperature_coefficient: PerKelvin = 0.0
    reference_temperature: Temperature = 25.0
    # Every load has mass, and the dynamic method divides by it: > 0, unlike the torques.
    inertia: PositiveInertia | None = None
    restitution: Restitution = 0.0
    # Breakaway over kinetic FS_T (dynamic method); None = [damper] static_friction_factor.
    static_friction_factor: StaticFactor | None = None
    gravity: GravitySpec | None = None
    # Viscous drag of the hinge's bearings, T = -c_b omega at the hinge (dynamic method;
    # the registry's worked example, dynamics/kernel/effects.py); None = none.
    bearing_drag: NonNegativeDamping | None = None
    # True in a file `ecdsim fit drop-test -o` wrote without --config: this [load] is a
    # stand-in, and every command flags its results until the line is deleted (issue 26).
    placeholder: bool = False

    @model_validator(mode="after")
    def _one_spring(self) -> LoadSpec:
        linear = self.start_torque is not None or self.end_torque is not None
        if linear and self.spring_table is not None:
            raise ValueError("give either start_torque and end_torque, or spring_table, not both")
        _check_table("resistive_table", self.resistive_table, self.travel)
        if self.spring_table is None:
            if self.start_torque is None or self.end_torque is None:
                missing = "start_torque" if self.start_torque is None else "end_torque"
                raise ValueError(
                    f"missing {missing}; expected a torque in N*m or compatible units, "
                    "e.g. '3.73 N*m' (or give spring_table)"
                )
            return self
        _check_table("spring_table", self.spring_table, self.travel)
        return self

    def spring(self) -> Spring:
        """The spring model (SI)."""
        if self.spring_table is not None:
            return TabulatedSpring(
                tuple(a for a, _ in self.spring_table),
                tuple(t for _, t in self.spring_table),
                self.spring_temperature_coefficient,
                self.reference_temperature,
            )
        assert self.start_torque is not None
        assert self.end_torque is not None
        return LinearSpring(
            self.start_torque,
            self.end_torque,
            self.spring_temperature_coefficient,
            self.reference_temperature,
        )

    def resistance(self) -> ResistiveTable | None:
        """The resistive torque table (SI), None without one."""
        if self.resistive_table is None:
            return None
        return ResistiveTable(
            tuple(a for a, _ in self.resistive_table),
            tuple(t for _, t in self.resistive_table),
            self.resistive_temperature_coefficient,
            self.reference_temperature,
        )

    def to_model(self) -> Load:
        """The model object (SI)."""
        return Load(
            spring=self.spring(),
            resistance=self.resistance(),
            travel=self.travel,
            system_friction=(
                self.system_friction.to_law() if self.system_friction else LinearTemperatureLaw()
            ),
            gravity=None if self.gravity is None else self.gravity.to_model(),
        )


def _check_table(key: str, table: list[tuple[float, float]] | None, travel: float) -> None:
    """A torque table starts at angle 0, rises strictly and reaches the travel."""
    if table is None:
        return
    angles = [a for a, _ in table]
    if len(angles) < 2:
        raise ValueError(f"{key} needs at least two [angle, torque] points")
    if angles[0] != 0.0:
        raise ValueError(f"{key} must start at angle 0 (got {angles[0]:g} rad)")
    if any(b <= a for a, b in zip(angles, angles[1:], strict=False)):
        raise ValueError(f"{key} angles must be strictly increasing")
    if angles[-1] < travel * (1.0 - 1e-12):
        raise ValueError(f"{key} ends at {angles[-1]:g} rad, before the travel {travel:g} rad")


def _known_method(name: object) -> str:
    # Check the type first: a list (methods = [["exact"]]) is not hashable.
    if not isinstance(name, str) or name not in SOLVERS:
        raise PydanticCustomError(
            "method",
            "{detail}",
            {"detail": f"{quoted(name)} is not a method; expected one of {sorted(SOLVERS)}"},
        )
    return name


Method = Annotated[str, BeforeValidator(_known_method)]


def _known_integrator(name: object) -> str:
    if name not in INTEGRATORS:
        raise PydanticCustomError(
            "method",
            "{detail}",
            {"detail": f"{quoted(name)} is not an integrator; expected one of {list(INTEGRATORS)}"},
        )
    return str(name)


class AnalysisSpec(_Section):
    """``[analysis]``: what to compute."""

    temperatures: list[Temperature] = Field(default_factory=lambda: [25.0], min_length=1)
    methods: list[Method] = Field(default_factory=lambda: ["paper", "exact"], min_length=1)
    stop_time: PositiveTime | None = None
    rtol: Tolerance = 1e-8
    integrator: Annotated[str, BeforeValidator(_known_integrator)] = "RODAS4"


class InitialSpec(_Section):
    """``[initial]``: the state at release, for the dynamic method."""

    angle: NonNegativeAngle = 0.0
    speed: Speed = 0.0


def _unit_system(value: object) -> str:
    from ecdsim.units_display import UnitSystemError, check_system

    try:
        return check_system(value, "")
    except UnitSystemError as exc:
        detail = str(exc).removeprefix(": ")
        raise PydanticCustomError("quantity", "{detail}", {"detail": detail}) from None


class OutputSpec(_Section):
    """``[output]``: how results are shown (docs/config.md#output)."""

    # Display unit system of tables, plots, reports and the explorer; JSON stays SI.
    units: Annotated[str, BeforeValidator(_unit_system)] = "si"


class SpecBase(_Section):
    """What every configuration spec has: the check across sections and the models.

    Two specs share it (docs/architecture.md, start-up): :class:`CoreConfigSpec`, a file
    without ``[requirements]``, ``[fluid_damper]`` or ``[tolerances]``, validated without
    importing those sections' schemas (most commands read such a file; about 15 ms of
    start-up), and :class:`ecdsim.config.full_schema.ConfigSpec`, any file. Both declare
    the same fields in the same order, so that messages, reports and round trips see one
    layout.
    """

    if TYPE_CHECKING:
        title: str
        damper: DamperSpec
        gearbox: GearboxSpec
        load: LoadSpec
        analysis: AnalysisSpec
        initial: InitialSpec
        output: OutputSpec

    @model_validator(mode="after")
    def _dynamic_inputs(self) -> SpecBase:
        needing = [m for m in self.analysis.methods if SOLVERS[m].needs_dynamics]
        if needing and self.load.inertia is None:
            raise ValueError(
                f"the {needing[0]} method needs [load] inertia (the load's moment of inertia "
                "about the ECD input shaft, e.g. '5 kg*m^2')"
            )
        if self.initial.angle >= self.load.travel:
            raise ValueError(
                f"initial.angle {self.initial.angle:g} rad must be below the travel "
                f"{self.load.travel:g} rad"
            )
        return self

    def ecd(self) -> Ecd:
        """The ECD model (SI)."""
        return Ecd(self.damper.to_model(), self.gearbox.to_model())

    def dynamics(self) -> DynamicParameters | None:
        """The dynamic parameters (SI), or None without ``[load] inertia``."""
        if self.load.inertia is None:
            return None
        damper = self.damper
        return DynamicParameters(
            load_inertia=self.load.inertia,
            rotor_inertia=damper.rotor_inertia,
            gearbox_inertia=self.gearbox.inertia,
            static_friction_factor=damper.static_friction_factor,
            system_static_friction_factor=self.load.static_friction_factor,
            stribeck_speed=damper.stribeck_speed,
            restitution=self.load.restitution,
            initial_angle=self.initial.angle,
            initial_speed=self.initial.speed,
            rolloff=damper.rolloff.to_model() if damper.rolloff else None,
            thermal=damper.thermal.to_model() if damper.thermal else None,
            stop_time=(
                self.analysis.stop_time if self.analysis.stop_time is not None else math.inf
            ),
            rtol=self.analysis.rtol,
            integrator=self.analysis.integrator,
            gear_stiffness=self.gearbox.stiffness,
            gear_mesh_damping=self.gearbox.mesh_damping,
            effects=registered_effects.config_values(self),
        )


# The top-level sections only ConfigSpec declares (their schemas are imported with it).
STUDY_SECTIONS = ("requirements", "fluid_damper", "tolerances", "budget")


class CoreConfigSpec(SpecBase):
    """A configuration file without ``[requirements]``, ``[fluid_damper]``, ``[tolerances]``.

    Its three study sections read as None, as they do on :class:`ConfigSpec`.
    """

    title: str = "deployment"
    damper: DamperSpec
    gearbox: GearboxSpec
    load: LoadSpec
    analysis: AnalysisSpec = Field(default_factory=AnalysisSpec)
    initial: InitialSpec = Field(default_factory=InitialSpec)
    output: OutputSpec = Field(default_factory=OutputSpec)

    @property
    def requirements(self) -> None:
        """No ``[requirements]`` in this file."""
        return None

    @property
    def fluid_damper(self) -> None:
        """No ``[fluid_damper]`` in this file."""
        return None

    @property
    def tolerances(self) -> None:
        """No ``[tolerances]`` in this file."""
        return None

    @property
    def budget(self) -> None:
        """No ``[budget]`` in this file (docs/qualification.md)."""
        return None

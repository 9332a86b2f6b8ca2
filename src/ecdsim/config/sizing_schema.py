"""Config sections for sizing: ``[requirements]`` and ``[fluid_damper]`` (docs/sizing.md).

Quantity fields come from :mod:`ecdsim.config.fields`, shared with every section.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic_core import PydanticCustomError

from ecdsim.config.fields import (
    NonNegativeAngle,
    NonNegativeTorque,
    Number,
    PositiveInertia,
    PositiveNumber,
    PositiveSpeed,
    PositiveTime,
    PositiveTorque,
    Temperature,
    non_negative,
    positive,
    quantity,
)
from ecdsim.config.units import (
    DYNAMIC_VISCOSITY,
    KINEMATIC_VISCOSITY,
    LENGTH,
    MASS,
    NUMBER,
    SPEED,
    Kind,
    QuantityError,
)

# ASTM D341's two-constant Walther form log10(log10(nu + 0.7)) holds for nu >= 2 mm^2/s;
# below that the standard adds correction terms that ecdsim does not implement.
WALTHER_MIN_VISCOSITY = 2.0e-6  # [m^2/s] = 2 mm^2/s


def _fraction(x: float) -> str | None:
    return None if 0.0 < x <= 1.0 else "must be in (0, 1]"


def _at_least_one(x: float) -> str | None:
    return None if x >= 1.0 else "must be >= 1 (an uncertainty factor never reduces a torque)"


def _deployment_or_speed(value: object) -> float | None:
    """``"deployment"`` (None: the deployment's own speed) or an angular speed >= 0 [rad/s].

    0 (the default) means no damping torque in the margin.
    """
    if value is None or value == "deployment":
        return None
    try:
        number = SPEED.parse(value)
    except QuantityError as exc:
        raise PydanticCustomError(
            "quantity", "{detail}", {"detail": f'{exc} (or "deployment")'}
        ) from None
    if not number >= 0.0:
        raise PydanticCustomError(
            "quantity",
            "{detail}",
            {
                "detail": f'{value!r} must be >= 0 (0 = no damping torque; or "deployment"); '
                f"{SPEED.expected}"
            },
        )
    return number


def _flow_exponent(x: float) -> str | None:
    # A fluid's power-law index: ~0.3-1 for shear-thinning silicones, 1 Newtonian. The
    # segment time raises torques to 1/n, so n near 0 overflows for any torque above 1.
    low, high = FLOW_EXPONENT_RANGE
    return None if low <= x <= high else f"must be in [{low:g}, {high:g}] (1 = Newtonian)"


# The power-law indices accepted for a fluid damper (docs/sizing.md).
FLOW_EXPONENT_RANGE = (0.1, 3.0)
FlowExponent = Annotated[float, quantity(NUMBER, _flow_exponent), NUMBER]


def _known_mass(x: float) -> str | None:
    return None if x > 0.0 else "must be > 0 (leave mass out if it is not known)"


# A catalogue mass: 0 is no placeholder for "unknown" (that would rank a part as weightless).
KnownMass = Annotated[float, quantity(MASS, _known_mass), MASS]
PositiveLength = Annotated[float, quantity(LENGTH, positive), LENGTH]
Efficiency = Annotated[float, quantity(NUMBER, _fraction), NUMBER]
PositiveDynamicViscosity = Annotated[
    float, quantity(DYNAMIC_VISCOSITY, positive), DYNAMIC_VISCOSITY
]
PositiveKinematicViscosity = Annotated[
    float, quantity(KINEMATIC_VISCOSITY, positive), KINEMATIC_VISCOSITY
]
Factor = Annotated[float, quantity(NUMBER, _at_least_one), NUMBER]
DampingSpeed = Annotated[float | None, BeforeValidator(_deployment_or_speed), SPEED]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class FactorsSpec(_Section):
    """Uncertainty factors per resistive-torque kind; 1 means "no factor applied".

    ecdsim ships no standard's values: take them from the standard the project applies
    (docs/sizing.md, "Torque margin"). ``friction`` is the factor of both Coulomb
    frictions (ECSS-E-ST-33-01C has one friction kind); ``ecd_friction`` (FECD_T) and
    ``system_friction`` (FS_T) override it for one of them.
    """

    friction: Factor = 1.0
    ecd_friction: Factor | None = None
    system_friction: Factor | None = None
    damping: Factor = 1.0
    inertia: Factor = 1.0
    spring: Factor = 1.0
    harness: Factor = 1.0
    # [load] resistive_table: harness and blanket torque against angle, its own kind.
    resistive_table: Factor = 1.0
    # [load.gravity]: a ground test's gravity torque where it opposes, its own kind.
    gravity: Factor = 1.0
    # [gearbox] efficiency: the mesh loss at the input, its own kind (issue 16 item 5).
    gear_loss: Factor = 1.0


class AllowancesSpec(_Section):
    """Margin-only resistive torques that the quasi-static deployment does not contain."""

    inertia: NonNegativeTorque = 0.0
    spring: NonNegativeTorque = 0.0
    harness: NonNegativeTorque = 0.0


class TorqueMarginSpec(_Section):
    """``[requirements.torque_margin]``: how the torque margin is computed."""

    damping_speed: DampingSpeed = 0.0
    factors: FactorsSpec = Field(default_factory=FactorsSpec)
    allowances: AllowancesSpec = Field(default_factory=AllowancesSpec)


class RequirementsSpec(_Section):
    """``[requirements]``: what a damper and gear ratio must achieve (docs/sizing.md)."""

    min_deployment_time: PositiveTime | None = None
    max_deployment_time: PositiveTime | None = None
    temperature_range: tuple[Temperature, Temperature] | None = None
    temperatures: list[Temperature] = Field(default_factory=list)
    max_end_speed: PositiveSpeed | None = None
    max_input_torque: PositiveTorque | None = None
    min_torque_margin: Number | None = None
    no_stall: bool = True
    ratio_range: tuple[PositiveNumber, PositiveNumber] = (1.0, 10000.0)
    torque_margin: TorqueMarginSpec = Field(default_factory=TorqueMarginSpec)

    @model_validator(mode="after")
    def _consistent(self) -> RequirementsSpec:
        low, high = self.min_deployment_time, self.max_deployment_time
        if low is not None and high is not None and not low < high:
            raise ValueError(
                f"min_deployment_time ({low:g} s) must be below max_deployment_time ({high:g} s)"
            )
        if self.temperature_range is not None:
            cold, hot = self.temperature_range
            if not cold < hot:
                raise ValueError(
                    f"temperature_range must be [cold, hot] with cold < hot, got "
                    f"[{cold:g}, {hot:g}] degC"
                )
        if self.temperature_range is None and not self.temperatures:
            raise ValueError(
                "give temperature_range = [cold, hot] and/or temperatures = [...]: the "
                "requirements must hold at every one of them"
            )
        lo, hi = self.ratio_range
        if not lo < hi:
            raise ValueError(f"ratio_range must be [low, high] with low < high, got [{lo}, {hi}]")
        return self

    def all_temperatures(self) -> tuple[float, ...]:
        """The range's ends and the listed temperatures, sorted, without repeats [degC]."""
        points = set(self.temperatures)
        if self.temperature_range is not None:
            points.update(self.temperature_range)
        return tuple(sorted(points))


# The power-law fluid damper's own quantities (docs/qualification.md, section 3).
ACTIVATION = Kind("activation temperature (B of exp(B / T_K))", "K", "2040 K")
EXPONENT_SLOPE = Kind("change of the exponent per kelvin", "1/K", "-0.0006 / K")
Activation = Annotated[float, quantity(ACTIVATION, non_negative), ACTIVATION]
ExponentSlope = Annotated[float, quantity(EXPONENT_SLOPE), EXPONENT_SLOPE]


class FluidPowerLawSpec(_Section):
    """``[fluid_damper.power_law]``: a shear-thinning damper's torque-speed law over
    temperature, ``T = torque * (omega / reference_speed)**n(T) * exp(B (1/T_K -
    1/T_ref,K))`` with ``n(T) = exponent + exponent_slope * (T - T_ref)`` (e.g. from
    ``ecdsim fit fluid-damper``)."""

    reference_temperature: Temperature = 25.0
    reference_speed: PositiveSpeed
    torque: PositiveTorque
    exponent: FlowExponent
    exponent_slope: ExponentSlope = 0.0
    activation: Activation = 0.0
    # The bench data's temperatures: a temperature outside them is extrapolation.
    temperatures: list[Temperature] = Field(default_factory=list)


# [fluid_damper] keys of the viscosity model that a power law replaces.
VISCOSITY_KEYS = (
    "law", "dynamic_viscosity", "kinematic_viscosity", "exponent", "match_temperature",
    "match_speed",
)  # fmt: skip


class FluidDamperSpec(_Section):
    """``[fluid_damper]``: a silicone-fluid rotary damper to compare with the ECD, by a
    viscosity law matched to the ECD (``law`` and a viscosity table) or by its measured
    torque-speed law (``[fluid_damper.power_law]``)."""

    name: str = "fluid damper"
    source: str
    law: Literal["andrade", "walther"] | None = None
    power_law: FluidPowerLawSpec | None = None
    dynamic_viscosity: list[tuple[Temperature, PositiveDynamicViscosity]] | None = None
    kinematic_viscosity: list[tuple[Temperature, PositiveKinematicViscosity]] | None = None
    deadband: NonNegativeAngle = math.radians(15.0)
    match_temperature: Temperature = 25.0
    exponent: FlowExponent = 1.0
    match_speed: PositiveSpeed | None = None
    coulomb_friction: NonNegativeTorque | None = None
    load_inertia: PositiveInertia | None = None

    @model_validator(mode="after")
    def _one_table(self) -> FluidDamperSpec:
        if self.power_law is not None:
            clash = [key for key in VISCOSITY_KEYS if key in self.model_fields_set]
            if clash:
                raise ValueError(
                    f"power_law replaces {', '.join(clash)}: give either the measured "
                    "[fluid_damper.power_law] or a viscosity law matched to the ECD"
                )
            return self
        if self.law is None:
            raise ValueError(
                'give law = "andrade" or "walther" with a viscosity table, or the measured '
                "torque-speed law [fluid_damper.power_law] (docs/qualification.md)"
            )
        given = [
            name
            for name in ("dynamic_viscosity", "kinematic_viscosity")
            if getattr(self, name) is not None
        ]
        if len(given) != 1:
            raise ValueError(
                "give exactly one of dynamic_viscosity = [[T, mu], ...] (Pa*s) and "
                "kinematic_viscosity = [[T, nu], ...] (mm^2/s)"
            )
        if self.law == "walther" and self.kinematic_viscosity is None:
            raise ValueError(
                "the Walther law (ASTM D341) is defined on kinematic viscosity: give "
                "kinematic_viscosity = [[T, nu], ...] in mm^2/s"
            )
        points = self.viscosity_points()
        temps = [t for t, _ in points]
        if len(points) < 2:
            raise ValueError(f"{given[0]} needs at least two [temperature, viscosity] points")
        if len(set(temps)) != len(temps):
            raise ValueError(f"{given[0]} has repeated temperatures {sorted(temps)} degC")
        if self.law == "walther":
            low = [v for _, v in points if v < WALTHER_MIN_VISCOSITY]
            if low:
                raise ValueError(
                    f"kinematic_viscosity {low[0] * 1e6:g} mm^2/s is below 2 mm^2/s, where "
                    "ASTM D341's two-constant Walther form does not hold"
                )
        return self

    def viscosity_points(self) -> list[tuple[float, float]]:
        """The (T [degC], viscosity [SI]) points of whichever table was given."""
        table = self.dynamic_viscosity or self.kinematic_viscosity or []
        return [(float(t), float(v)) for t, v in table]

"""Quantity fields shared by every config schema: parse a unit string, check, explain.

Each field type is ``Annotated[float, <parser>, <Kind>]``: the parser turns the string
into an SI float (or a one-line error naming the value and the expected unit), and the
:class:`~ecdsim.config.units.Kind` lets a missing-key message say which unit was
expected. Every section of the configuration builds its fields from :func:`quantity`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated

from pydantic import BeforeValidator
from pydantic_core import PydanticCustomError

from ecdsim.config.units import (
    ANGLE,
    DAMPING,
    INERTIA,
    NUMBER,
    PER_KELVIN,
    SPEED,
    TEMPERATURE,
    TIME,
    TORQUE,
    TORQUE_PER_KELVIN,
    Kind,
    QuantityError,
    quoted,
    temperature_problem,
)

Check = Callable[[float], str | None]


def positive(x: float) -> str | None:
    """Check: > 0."""
    return None if x > 0.0 else "must be > 0"


def non_negative(x: float) -> str | None:
    """Check: >= 0."""
    return None if x >= 0.0 else "must be >= 0"


def quantity(kind: Kind, check: Check | None = None) -> BeforeValidator:
    """A pydantic validator that parses ``kind`` and applies ``check`` to the SI value."""

    def parse(value: object) -> float:
        try:
            number = kind.parse(value)
        except QuantityError as exc:
            raise PydanticCustomError("quantity", "{detail}", {"detail": str(exc)}) from None
        problem = check(number) if check else None
        if problem:
            raise PydanticCustomError(
                "quantity", "{detail}", {"detail": f"{quoted(value)} {problem}; {kind.expected}"}
            )
        return number

    return BeforeValidator(parse)


Torque = Annotated[float, quantity(TORQUE), TORQUE]
PositiveTorque = Annotated[float, quantity(TORQUE, positive), TORQUE]
NonNegativeTorque = Annotated[float, quantity(TORQUE, non_negative), TORQUE]
PositiveDamping = Annotated[float, quantity(DAMPING, positive), DAMPING]
NonNegativeDamping = Annotated[float, quantity(DAMPING, non_negative), DAMPING]
Angle = Annotated[float, quantity(ANGLE), ANGLE]
PositiveAngle = Annotated[float, quantity(ANGLE, positive), ANGLE]
NonNegativeAngle = Annotated[float, quantity(ANGLE, non_negative), ANGLE]
Speed = Annotated[float, quantity(SPEED), SPEED]
PositiveSpeed = Annotated[float, quantity(SPEED, positive), SPEED]
# The same rule as units.parse_temperature, the command line's reader.
Temperature = Annotated[float, quantity(TEMPERATURE, temperature_problem), TEMPERATURE]
PerKelvin = Annotated[float, quantity(PER_KELVIN), PER_KELVIN]
TorquePerKelvin = Annotated[float, quantity(TORQUE_PER_KELVIN), TORQUE_PER_KELVIN]
Number = Annotated[float, quantity(NUMBER), NUMBER]
PositiveNumber = Annotated[float, quantity(NUMBER, positive), NUMBER]
NonNegativeNumber = Annotated[float, quantity(NUMBER, non_negative), NUMBER]
PositiveTime = Annotated[float, quantity(TIME, positive), TIME]
PositiveInertia = Annotated[float, quantity(INERTIA, positive), INERTIA]
NonNegativeInertia = Annotated[float, quantity(INERTIA, non_negative), INERTIA]

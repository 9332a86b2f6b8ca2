"""The damper's eddy-current torque law at its own (high-speed) shaft, by name.

Two laws, each a thin object delegating to :mod:`ecdsim.physics`:

* ``linear``: ``BD_T * omega_d`` with BD_T from the paper's Eq. 1 (first term);
* ``rolloff``: the Kloss form of :mod:`ecdsim.physics.rolloff`.

Both give the torque and its partial derivatives in speed and temperature (for the
integrator's analytic Jacobian). The gearbox damping BG stays linear in every law and is
not part of these objects.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Protocol, Self

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.physics import assembly, rolloff


class EddyLaw(Protocol):
    """Eddy-current torque of the high-speed damper against speed and temperature."""

    @property
    def name(self) -> str:
        """Registry name of the law."""
        ...

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Torque [N*m] at high-speed shaft speed [rad/s] and damper temperature [degC]."""
        ...

    def speed_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Partial derivative of the torque in speed [N*m*s/rad]."""
        ...

    def temperature_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Partial derivative of the torque in temperature [N*m/K]."""
        ...

    def domain_margin(self, temperature: ArrayLike) -> FloatArray:
        """Positive where the law holds at damper temperature T [degC] (its own unit)."""
        ...

    def flattened(self, shape: tuple[int, ...]) -> Self:
        """The law with every parameter broadcast to ``shape`` and raveled (1-D)."""
        ...

    def at(self, index: int) -> Self:
        """The law of one case of a flattened batch, with float parameters."""
        ...

    def take(self, index: NDArray[np.intp]) -> Self:
        """The law of a subset of a flattened batch (1-D parameters)."""
        ...


class _Broadcastable:
    """Shared batch handling for the law dataclasses (every field is numeric)."""

    def flattened(self, shape: tuple[int, ...]) -> Self:
        """The law with every parameter broadcast to ``shape`` and raveled (1-D)."""
        values = {
            f.name: np.broadcast_to(np.asarray(getattr(self, f.name), dtype=float), shape).ravel()
            for f in fields(self)  # type: ignore[arg-type]
        }
        return replace(self, **values)  # type: ignore[type-var]

    def take(self, index: NDArray[np.intp]) -> Self:
        """The law of a subset of a flattened batch (1-D parameters)."""
        values = {
            f.name: np.asarray(getattr(self, f.name), dtype=float)[index]
            for f in fields(self)  # type: ignore[arg-type]
        }
        return replace(self, **values)  # type: ignore[type-var]

    def at(self, index: int) -> Self:
        """The law of one case of a flattened batch, with float parameters."""
        values = {
            f.name: float(np.asarray(getattr(self, f.name)).reshape(-1)[index])
            for f in fields(self)  # type: ignore[arg-type]
        }
        return replace(self, **values)  # type: ignore[type-var]


@dataclass(frozen=True)
class LinearEddy(_Broadcastable):
    """``BD_T * omega_d`` with ``BD_T = BD * (1 + c * (T - T_ref))`` (paper Eq. 1).

    Attributes
    ----------
    damping_rate : BD at the reference temperature [N*m*s/rad]
    reference_temperature : T_ref [degC]
    temperature_coefficient : c, fractional change of BD per kelvin [1/K]
    """

    damping_rate: float | FloatArray
    reference_temperature: float | FloatArray
    temperature_coefficient: float | FloatArray

    @property
    def name(self) -> str:
        """Registry name."""
        return "linear"

    def _rate(self, temperature: ArrayLike) -> FloatArray:
        return assembly.damper_damping_rate(
            self.damping_rate, temperature, self.reference_temperature, self.temperature_coefficient
        )

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """``BD_T * omega_d`` [N*m] (Eq. 1 and the damper's linear torque)."""
        return assembly.damper_torque(self._rate(temperature), speed)

    def speed_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """``BD_T`` [N*m*s/rad], broadcast against the speed."""
        rate = self._rate(temperature)
        return as_float(rate + np.zeros_like(np.asarray(speed, dtype=float)))

    def domain_margin(self, temperature: ArrayLike) -> FloatArray:
        """BD_T [N*m*s/rad]: Eq. 1 has no meaning where it is <= 0."""
        return self._rate(temperature)

    def temperature_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """``BD * c * omega_d`` [N*m/K], the temperature derivative of Eq. 1 times speed."""
        slope = np.asarray(self.damping_rate, float) * np.asarray(self.temperature_coefficient)
        return as_float(slope * np.asarray(speed, dtype=float) + 0.0 * np.asarray(temperature))


@dataclass(frozen=True)
class KlossEddy(_Broadcastable):
    """Kloss-form roll-off ``2 T_peak x / (1 + x**2)``, ``x = omega_d / omega_peak(T)``.

    Attributes
    ----------
    peak_torque : T_peak [N*m]
    reference_peak_speed : omega_peak at T_ref [rad/s]
    resistivity_coefficient : alpha [1/K]
    reference_temperature : T_ref [degC]
    """

    peak_torque: float | FloatArray
    reference_peak_speed: float | FloatArray
    resistivity_coefficient: float | FloatArray
    reference_temperature: float | FloatArray

    @property
    def name(self) -> str:
        """Registry name."""
        return "rolloff"

    def peak_speed(self, temperature: ArrayLike) -> FloatArray:
        """omega_peak at damper temperature T [rad/s]."""
        return rolloff.peak_speed_at(
            temperature,
            self.reference_peak_speed,
            self.resistivity_coefficient,
            self.reference_temperature,
        )

    def domain_margin(self, temperature: ArrayLike) -> FloatArray:
        """omega_peak(T) [rad/s]: the resistivity law has no meaning where it is <= 0."""
        return self.peak_speed(temperature)

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Kloss torque [N*m]."""
        return rolloff.kloss_torque(speed, self.peak_torque, self.peak_speed(temperature))

    def speed_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Local damping rate of the Kloss curve [N*m*s/rad]."""
        return rolloff.kloss_speed_derivative(speed, self.peak_torque, self.peak_speed(temperature))

    def temperature_derivative(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Temperature sensitivity through omega_peak(T) [N*m/K]."""
        d_peak = np.asarray(self.reference_peak_speed, float) * np.asarray(
            self.resistivity_coefficient, float
        )
        return as_float(
            rolloff.kloss_peak_speed_derivative(
                speed, self.peak_torque, self.peak_speed(temperature)
            )
            * d_peak
        )


EDDY_LAWS: dict[str, type[LinearEddy] | type[KlossEddy]] = {
    "linear": LinearEddy,
    "rolloff": KlossEddy,
}

"""The damper's eddy-current torque law at its own (high-speed) shaft, by name.

Two laws, each a thin object delegating to :mod:`ecdsim.physics`:

* ``linear``: ``BD_T * omega_d`` with BD_T from the paper's Eq. 1 (first term);
* ``rolloff``: the Kloss form of :mod:`ecdsim.physics.rolloff`.

Both scale with an affine temperature factor ``f(T) = 1 + c (T - T_ref)`` (Eq. 1's
bracket; the Kloss law's resistivity factor of the peak speed) and are written, for the
integrator, as functions of the speed and that factor: the torque, its partial
derivatives, and the heating power over the factor, ``p = P / f``, which stays finite
where f vanishes (the integrator's temperature state is the factor's logarithm, see
:mod:`ecdsim.physics.thermal`). The gearbox damping BG stays linear in every law and is
not part of these objects.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Protocol, Self

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import ArrayLike, FloatArray, as_float, broadcast
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

    @property
    def reference_temperature(self) -> float | FloatArray:
        """T_ref, where the temperature factor is 1 [degC]."""
        ...

    @property
    def coefficient(self) -> FloatArray:
        """c, the temperature factor's fractional change per kelvin [1/K]."""
        ...

    def factor(self, temperature: ArrayLike) -> FloatArray:
        """The temperature factor ``f = 1 + c (T - T_ref)`` at damper temperature T [degC]."""
        ...

    def torque_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Torque [N*m] at high-speed shaft speed [rad/s] and temperature factor f [-]."""
        ...

    def speed_derivative_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Partial derivative of the torque in speed at factor f [N*m*s/rad]."""
        ...

    def factor_derivative(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Partial derivative of the torque in the factor f [N*m]."""
        ...

    def power_per_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Eddy-current (heating) power over the factor, ``T_eddy omega_d / f`` [W]."""
        ...

    def power_per_factor_derivatives(
        self, speed: ArrayLike, factor: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Partial derivatives of :meth:`power_per_factor` in speed [W*s/rad] and f [W]."""
        ...

    def flattened(self, shape: tuple[int, ...]) -> Self:
        """The law with every parameter broadcast to ``shape`` and raveled (1-D)."""
        ...

    def take(self, index: NDArray[np.intp]) -> Self:
        """The law of a subset of a flattened batch (1-D parameters)."""
        ...


class _Broadcastable:
    """Shared batch handling for the law dataclasses (every field is numeric)."""

    def flattened(self, shape: tuple[int, ...]) -> Self:
        """The law with every parameter broadcast to ``shape`` and raveled (1-D)."""
        values = {
            f.name: broadcast(np.asarray(getattr(self, f.name), dtype=float), shape).ravel()
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

    @property
    def coefficient(self) -> FloatArray:
        """c [1/K]."""
        return np.asarray(self.temperature_coefficient, dtype=float)

    def factor(self, temperature: ArrayLike) -> FloatArray:
        """``1 + c (T - T_ref)``, the bracket of Eq. 1 [-]."""
        return assembly.damper_damping_rate(
            1.0, temperature, self.reference_temperature, self.temperature_coefficient
        )

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """``BD_T * omega_d`` [N*m] (Eq. 1 and the damper's linear torque)."""
        rate = assembly.damper_damping_rate(
            self.damping_rate, temperature, self.reference_temperature, self.temperature_coefficient
        )
        return assembly.damper_torque(rate, speed)

    def torque_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``BD f omega_d`` [N*m]."""
        return assembly.damper_torque(self._rate(factor), speed)

    def speed_derivative_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``BD f`` [N*m*s/rad], broadcast against the speed."""
        return as_float(self._rate(factor) + np.zeros_like(np.asarray(speed, dtype=float)))

    def factor_derivative(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``BD omega_d`` [N*m], broadcast against the factor."""
        bd = np.asarray(self.damping_rate, dtype=float)
        return as_float(bd * np.asarray(speed, dtype=float) + 0.0 * np.asarray(factor, float))

    def power_per_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``BD omega_d**2`` [W]: the power ``BD_T omega_d**2`` over f (any f)."""
        w = np.asarray(speed, dtype=float)
        return as_float(np.asarray(self.damping_rate, dtype=float) * w * w)

    def power_per_factor_derivatives(
        self, speed: ArrayLike, factor: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """``(2 BD omega_d, 0)`` [W*s/rad, W]."""
        by_speed = 2.0 * self.factor_derivative(speed, factor)
        return by_speed, as_float(np.zeros_like(by_speed))

    def _rate(self, factor: ArrayLike) -> FloatArray:
        return as_float(np.asarray(self.damping_rate, dtype=float) * np.asarray(factor, float))


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

    @property
    def coefficient(self) -> FloatArray:
        """alpha [1/K]."""
        return np.asarray(self.resistivity_coefficient, dtype=float)

    def factor(self, temperature: ArrayLike) -> FloatArray:
        """``omega_peak(T) / omega_peak_ref = 1 + alpha (T - T_ref)`` [-]."""
        return rolloff.peak_speed_at(
            temperature, 1.0, self.resistivity_coefficient, self.reference_temperature
        )

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Kloss torque [N*m]."""
        return rolloff.kloss_torque(speed, self.peak_torque, self.peak_speed(temperature))

    def _peak(self, factor: ArrayLike) -> FloatArray:
        return as_float(np.asarray(self.reference_peak_speed, float) * np.asarray(factor, float))

    def torque_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Kloss torque with ``omega_peak = omega_peak_ref f`` [N*m]."""
        return rolloff.kloss_torque(speed, self.peak_torque, self._peak(factor))

    def speed_derivative_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Local damping rate of the Kloss curve [N*m*s/rad]."""
        return rolloff.kloss_speed_derivative(speed, self.peak_torque, self._peak(factor))

    def factor_derivative(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``dT_d/domega_peak * omega_peak_ref`` [N*m]."""
        d_peak = rolloff.kloss_peak_speed_derivative(speed, self.peak_torque, self._peak(factor))
        return as_float(d_peak * np.asarray(self.reference_peak_speed, float))

    def power_per_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """``T_d omega_d / f = omega_peak_ref T_d omega_d / omega_peak`` [W]."""
        per_peak = rolloff.kloss_power_per_peak_speed(speed, self.peak_torque, self._peak(factor))
        return as_float(per_peak * np.asarray(self.reference_peak_speed, float))

    def power_per_factor_derivatives(
        self, speed: ArrayLike, factor: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Through :func:`ecdsim.physics.rolloff.kloss_power_per_peak_speed_derivatives`."""
        ref = np.asarray(self.reference_peak_speed, float)
        by_speed, by_peak = rolloff.kloss_power_per_peak_speed_derivatives(
            speed, self.peak_torque, self._peak(factor)
        )
        return as_float(by_speed * ref), as_float(by_peak * ref * ref)


EDDY_LAWS: dict[str, type[LinearEddy] | type[KlossEddy]] = {
    "linear": LinearEddy,
    "rolloff": KlossEddy,
}

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
from ecdsim.physics import assembly, eddy, rolloff


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

    @property
    def code(self) -> int:
        """The law's code in :mod:`ecdsim.physics.eddy` (``LINEAR`` or ``KLOSS``)."""
        ...

    @property
    def parameters(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(a, b, core)``, the law's parameters in :mod:`ecdsim.physics.eddy`."""
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
        """``BD f omega_d`` [N*m] (:func:`ecdsim.physics.eddy.eddy_torque`)."""
        return _at_factor(self, speed, factor)

    @property
    def code(self) -> int:
        """:data:`ecdsim.physics.eddy.LINEAR`."""
        return eddy.LINEAR

    @property
    def parameters(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(BD, 0, 0)``."""
        return np.asarray(self.damping_rate, dtype=float), np.zeros(()), np.zeros(())


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
        return as_float(
            rolloff.peak_speed_at(
                np.asarray(temperature, dtype=float),
                self.reference_peak_speed,
                self.resistivity_coefficient,
                self.reference_temperature,
            )
        )

    @property
    def coefficient(self) -> FloatArray:
        """alpha [1/K]."""
        return np.asarray(self.resistivity_coefficient, dtype=float)

    def factor(self, temperature: ArrayLike) -> FloatArray:
        """``omega_peak(T) / omega_peak_ref = 1 + alpha (T - T_ref)`` [-]."""
        return as_float(
            rolloff.peak_speed_at(
                np.asarray(temperature, dtype=float),
                1.0,
                self.resistivity_coefficient,
                self.reference_temperature,
            )
        )

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Kloss torque [N*m]."""
        w = np.asarray(speed, dtype=float)
        return as_float(rolloff.kloss_torque(w, self.peak_torque, self.peak_speed(temperature)))

    def torque_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """Kloss torque with ``omega_peak = omega_peak_ref f`` [N*m]."""
        return _at_factor(self, speed, factor)

    @property
    def code(self) -> int:
        """:data:`ecdsim.physics.eddy.KLOSS`."""
        return eddy.KLOSS

    @property
    def parameters(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(T_peak, omega_peak_ref, 0)``."""
        return (
            np.asarray(self.peak_torque, dtype=float),
            np.asarray(self.reference_peak_speed, dtype=float),
            np.zeros(()),
        )


def _at_factor(law: EddyLaw, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
    """The law's torque at a temperature factor, through :mod:`ecdsim.physics.eddy`."""
    a, b, core = law.parameters
    w, f = np.asarray(speed, dtype=float), np.asarray(factor, dtype=float)
    return as_float(eddy.eddy_torque(law.code, a, b, core, w, f))


@dataclass(frozen=True)
class PowerLawDamper(_Broadcastable):
    """A shear-thinning fluid damper, ``T = c max(|w|, w_l)^(n-1) w`` at its shaft
    (:func:`ecdsim.physics.fluid.power_law_parts`; docs/qualification.md section 3).

    ``c`` and ``n`` are the fluid's at each case's temperature (the Arrhenius-Andrade
    consistency and n(T) of ``[fluid_damper.power_law]``, evaluated by the caller): the
    law has no temperature factor, so the dynamic method refuses self-heating with it.

    Attributes
    ----------
    power_coefficient : c [N*m*(s/rad)**n]
    exponent : n [-]
    linear_speed : omega_l, below which the torque is linear (the fluid's Newtonian
        plateau; finite slope at rest) [rad/s], > 0
    """

    power_coefficient: float | FloatArray
    exponent: float | FloatArray
    linear_speed: float | FloatArray

    @property
    def name(self) -> str:
        """Registry name."""
        return "power_law"

    @property
    def reference_temperature(self) -> float | FloatArray:
        """Unused: the law's c and n are already at the case's temperature [degC]."""
        return 0.0

    @property
    def coefficient(self) -> FloatArray:
        """0: no temperature factor [1/K]."""
        return np.zeros(())

    def factor(self, temperature: ArrayLike) -> FloatArray:
        """1 at every temperature [-] (no temperature factor)."""
        return as_float(np.ones_like(np.asarray(temperature, dtype=float)))

    def torque(self, speed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """The power-law torque [N*m] (c and n already at the case's temperature)."""
        return _at_factor(self, speed, 1.0)

    def torque_at_factor(self, speed: ArrayLike, factor: ArrayLike) -> FloatArray:
        """The power-law torque [N*m]; the factor is unused."""
        return _at_factor(self, speed, factor)

    @property
    def code(self) -> int:
        """:data:`ecdsim.physics.eddy.POWER_LAW`."""
        return eddy.POWER_LAW

    @property
    def parameters(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(c, n, omega_l)``."""
        return (
            np.asarray(self.power_coefficient, dtype=float),
            np.asarray(self.exponent, dtype=float),
            np.asarray(self.linear_speed, dtype=float),
        )


EDDY_LAWS: dict[str, type[LinearEddy] | type[KlossEddy]] = {
    "linear": LinearEddy,
    "rolloff": KlossEddy,
}

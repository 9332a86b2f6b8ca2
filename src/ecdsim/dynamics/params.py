"""Parameters of the full deployment dynamics that the quasi-static model does not need.

Frozen dataclasses, SI units, temperatures in degC. Each numeric field may be a float or a
NumPy array that broadcasts against the temperatures and the system's own arrays (one
object can describe a whole Monte Carlo batch). See ``docs/dynamics.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ecdsim.dynamics.kernel import effects as registry
from ecdsim.model import Param

INTEGRATORS = ("RODAS4", "Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class Rolloff:
    """The damper's eddy-current roll-off beyond its linear range (Kloss form).

    See :mod:`ecdsim.physics.rolloff`. The peak torque follows from the damper's rated BD:
    ``T_peak = BD * peak_speed / 2``.

    Attributes
    ----------
    peak_speed : omega_peak, high-speed shaft speed of peak eddy torque at the damper's
        reference temperature [rad/s]
    resistivity_coefficient : alpha, fractional change of the conductor's resistivity per
        kelvin (copper 0.0039) [1/K]
    """

    peak_speed: Param
    resistivity_coefficient: Param

    def __post_init__(self) -> None:
        if np.any(np.asarray(self.peak_speed, dtype=float) <= 0.0):
            raise ValueError("rolloff peak_speed must be > 0")


@dataclass(frozen=True)
class Thermal:
    """The damper as one lumped heat capacity, or rotor and housing as two
    (see :mod:`ecdsim.physics.thermal`).

    Attributes
    ----------
    heat_capacity : C, the damper's (with a housing: the rotor's) heat capacity [J/K], > 0
    thermal_resistance : R, damper to ambient [K/W]; ``inf`` (the default) is adiabatic.
        With a housing it is the rotor's resistance to the housing, R_rh
    housing_heat_capacity : C_h, the housing's heat capacity [J/K], > 0; None (the
        default) for the one-node model
    housing_thermal_resistance : R_he, housing to the environment (the mounting
        interface at the deployment temperature) [K/W]; ``inf`` (the default) adiabatic
    initial_rotor_rise : rotor temperature above the deployment temperature at release
        [K], >= 0 (a deployment that follows another); 0 by default
    initial_housing_rise : the housing's [K], >= 0; 0 by default
    """

    heat_capacity: Param
    thermal_resistance: Param = math.inf
    housing_heat_capacity: Param | None = None
    housing_thermal_resistance: Param = math.inf
    initial_rotor_rise: Param = 0.0
    initial_housing_rise: Param = 0.0

    def __post_init__(self) -> None:
        if np.any(np.asarray(self.heat_capacity, dtype=float) <= 0.0):
            raise ValueError("heat_capacity must be > 0")
        if np.any(np.asarray(self.thermal_resistance, dtype=float) <= 0.0):
            raise ValueError("thermal_resistance must be > 0 (omit it for adiabatic)")
        if self.housing_heat_capacity is not None and np.any(
            np.asarray(self.housing_heat_capacity, dtype=float) <= 0.0
        ):
            raise ValueError("housing_heat_capacity must be > 0")
        if np.any(np.asarray(self.housing_thermal_resistance, dtype=float) <= 0.0):
            raise ValueError("housing_thermal_resistance must be > 0 (omit it for adiabatic)")
        for name in ("initial_rotor_rise", "initial_housing_rise"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(value) & (value >= 0.0)):
                raise ValueError(f"{name} must be finite and >= 0")
        if self.housing_heat_capacity is None and np.any(
            np.asarray(self.initial_housing_rise, dtype=float) != 0.0
        ):
            raise ValueError("initial_housing_rise needs housing_heat_capacity")

    @property
    def two_node(self) -> bool:
        """True when the housing is a node of its own."""
        return self.housing_heat_capacity is not None


@dataclass(frozen=True)
class DynamicParameters:
    """Inertia, stiction, end stop, initial state and run control of a dynamic deployment.

    Attributes
    ----------
    load_inertia : J_L, the load's moment of inertia about the ECD input shaft [kg*m^2], > 0
    rotor_inertia : the damper rotor's inertia at the high-speed shaft [kg*m^2]; reflected
        to the input as ``J * N**2``
    gearbox_inertia : the gear train's inertia referred to the high-speed shaft, like the
        paper's BG and FG [kg*m^2]; reflected as ``J * N**2``
    static_friction_factor : breakaway over kinetic Coulomb friction of the ECD, FECD_T
        [-], >= 1; also of the system friction FS_T unless
        ``system_static_friction_factor`` is given
    restitution : coefficient of restitution at the end of travel [-]; 0 is a latch
        (plastic stop), 0 < e < 1 a rebounding hard stop
    initial_angle : deployed angle at release [rad], 0 <= angle < travel
    initial_speed : load speed at release [rad/s] (the damper side starts with it too
        when there is no lost motion, at rest otherwise)
    rolloff : the damper's roll-off law, or None for linear damping (BD_T * omega, Eq. 1)
    thermal : the damper's heat capacity, or None for a damper held at ambient temperature
    stop_time : end of the simulated interval [s]; ``inf`` runs until the mechanism
        latches or comes to rest for good
    rtol : relative tolerance of the numerical integrator used for nonlinear segments
        (roll-off, heating) [-]; linear segments are solved in closed form
    integrator : ``"RODAS4"`` (vectorised over the batch, the default), or ``"Radau"``,
        ``"BDF"``, ``"LSODA"`` (scipy ``solve_ivp``, one call per segment)
    max_events : safety limit on the number of events per run (impacts, stops, ...)
    system_static_friction_factor : breakaway over kinetic system friction FS_T (hinge,
        harness) [-], >= 1; None (the default) = ``static_friction_factor``, one factor
        for both frictions as before the two were separated
    gear_stiffness : torsional stiffness of the gear mesh in series with the lost motion,
        at the input shaft [N*m/rad], > 0; None (the default) = a rigid mesh (today's
        plastic engagement). Compliant backlash: :mod:`ecdsim.dynamics.backlash`
    gear_mesh_damping : damping of the gear mesh in contact, at the input shaft
        [N*m*s/rad], >= 0 (only with ``gear_stiffness``); None (the default) = 0
    effects : the registered effects' parameters by name, SI
        (:mod:`ecdsim.dynamics.kernel.effects`); an effect not given is absent
    """

    load_inertia: Param
    rotor_inertia: Param = 0.0
    gearbox_inertia: Param = 0.0
    static_friction_factor: Param = 1.0
    restitution: Param = 0.0
    initial_angle: Param = 0.0
    initial_speed: Param = 0.0
    rolloff: Rolloff | None = None
    thermal: Thermal | None = None
    stop_time: float = math.inf
    rtol: float = 1e-8
    integrator: str = "RODAS4"
    max_events: int = 10_000
    system_static_friction_factor: Param | None = None
    stribeck_speed: Param | None = None
    gear_stiffness: Param | None = None
    gear_mesh_damping: Param | None = None
    effects: Mapping[str, Param] = field(default_factory=dict)

    def __post_init__(self) -> None:
        registry.check(self.effects)
        system_factor = (
            1.0 if self.system_static_friction_factor is None
            else self.system_static_friction_factor
        )  # fmt: skip
        mesh_damping = np.asarray(
            0.0 if self.gear_mesh_damping is None else self.gear_mesh_damping, dtype=float
        )
        checks = [
            (
                np.asarray(system_factor, dtype=float) >= 1.0,
                "system_static_friction_factor must be >= 1",
            ),
            (
                np.asarray(math.inf if self.stribeck_speed is None else self.stribeck_speed) > 0.0,
                "stribeck_speed must be > 0",
            ),
            (np.asarray(self.load_inertia, dtype=float) > 0.0, "load_inertia must be > 0"),
            (
                np.asarray(math.inf if self.gear_stiffness is None else self.gear_stiffness) > 0.0,
                "gear_stiffness must be > 0",
            ),
            (
                np.isfinite(mesh_damping) & (mesh_damping >= 0.0),
                "gear_mesh_damping must be >= 0",
            ),
            (np.asarray(self.rotor_inertia, dtype=float) >= 0.0, "rotor_inertia must be >= 0"),
            (
                np.asarray(self.gearbox_inertia, dtype=float) >= 0.0,
                "gearbox_inertia must be >= 0",
            ),
            (
                np.asarray(self.static_friction_factor, dtype=float) >= 1.0,
                "static_friction_factor must be >= 1",
            ),
            (
                (np.asarray(self.restitution, dtype=float) >= 0.0)
                & (np.asarray(self.restitution, dtype=float) < 1.0),
                "restitution must be in [0, 1)",
            ),
            (
                np.isfinite(np.asarray(self.initial_speed, dtype=float)),
                "initial_speed must be finite",
            ),
        ]
        for ok, message in checks:
            if not np.all(ok):
                raise ValueError(message)
        if not self.stop_time > 0.0:
            raise ValueError("stop_time must be > 0")
        if not 0.0 < self.rtol <= 0.1:
            raise ValueError("rtol must be in (0, 0.1]")
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {self.integrator!r}")
        if self.max_events < 1:
            raise ValueError("max_events must be >= 1")

    @property
    def nonlinear(self) -> bool:
        """True when segments need numerical integration (roll-off, heating, Stribeck)."""
        return (
            self.rolloff is not None or self.thermal is not None or self.stribeck_speed is not None
        )

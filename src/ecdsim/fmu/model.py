"""What the FMUs compute, in plain Python: testable without pythonfmu or an FMI host.

:class:`DamperModel` is the ECD (damper + gearbox) referred to the slow shaft, driven by
the shaft speed and the ambient temperature: the damping torque of the dynamic method
(``N (T_eddy(N u, T_d) + BG N u)``, the eddy law of :mod:`ecdsim.dynamics.damping` at
the damper temperature T_d), the ECD's Coulomb friction ``FECD(T_ambient)`` and, when
``[damper.thermal]`` is configured, the lumped self-heating of
:mod:`ecdsim.physics.thermal`, ``C dT_d/dt = T_eddy N u - (T_d - T_ambient) / R``
(Incropera et al., Eq. 5.2), the same balance the dynamic method integrates.

:class:`DeploymentReplay` is the whole spring-driven hinge: the dynamic method is run
once at initialisation and its solution is evaluated at the times asked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.deployment import Prediction
    from ecdsim.dynamics.damping import EddyLaw
    from ecdsim.model import DeploymentSystem

# The config keys an FMU exposes as parameters (FMI name -> config key). Their start
# values are the config's; a host may change them before initialisation.
DAMPER_PARAMETERS = {
    "gear_ratio": "gearbox.ratio",
    "damping_rate": "damper.damping_rate",
    "damping_temperature_coefficient": "damper.damping_temperature_coefficient",
    "damper_coulomb_friction": "damper.coulomb_friction",
    "gearbox_coulomb_friction": "gearbox.coulomb_friction",
}
THERMAL_PARAMETERS = {
    "heat_capacity": "damper.thermal.heat_capacity",
    "thermal_resistance": "damper.thermal.thermal_resistance",
}
DEPLOYMENT_PARAMETERS = {
    **DAMPER_PARAMETERS,
    "load_inertia": "load.inertia",
    "start_torque": "load.start_torque",
    "end_torque": "load.end_torque",
}
# The longest internal integration step of the heat balance [s]: a communication step
# is cut into equal Runge-Kutta steps no longer than this.
MAX_STEP = 1e-3


def config_values(config: Config, names: dict[str, str]) -> dict[str, float]:
    """The SI values of the exposed parameters in ``config`` (missing ones left out)."""
    spec: Any = config.spec
    out = {}
    for name, key in names.items():
        node: Any = spec
        for part in key.split("."):
            node = getattr(node, part, None)
            if node is None:
                break
        if isinstance(node, int | float) and not isinstance(node, bool):
            out[name] = float(node)
    return out


def _dynamic_parameters(config: Config) -> Any:
    from ecdsim.dynamics.params import DynamicParameters

    params = config.spec.dynamics()
    if params is not None:
        return params
    damper = config.spec.damper
    # The damper alone needs no load inertia; any positive value builds its laws.
    return DynamicParameters(
        load_inertia=1.0,
        rolloff=damper.rolloff.to_model() if damper.rolloff else None,
        thermal=damper.thermal.to_model() if damper.thermal else None,
    )


@dataclass
class DamperModel:
    """The ECD referred to the slow shaft, with its temperature as the one state.

    Attributes
    ----------
    system : the deployment system (its ECD gives FECD at any ambient temperature)
    ratio : gear ratio N [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    eddy : the eddy-current law (linear or Kloss roll-off), one case
    heating : whether the damper temperature evolves ([damper.thermal] given)
    heat_capacity : C [J/K] (inf without heating)
    thermal_resistance : R [K/W] (inf: adiabatic)
    forward_efficiency : eta_f of a lossy mesh (1: ideal); the damping torque at the
        slow shaft is divided by it (the shaft always drives this inertia-free damper)
    static_friction_factor : f_D, the damper's breakaway over kinetic friction
    stribeck_speed : w_St [rad/s at the slow shaft] (inf: no Stribeck curve)
    temperature : the damper temperature T_d [degC], the state
    max_step : the longest internal Runge-Kutta step [s]
    """

    system: DeploymentSystem
    ratio: float
    gearbox_damping: float
    eddy: EddyLaw
    heating: bool
    heat_capacity: float
    thermal_resistance: float
    forward_efficiency: float = 1.0
    static_friction_factor: float = 1.0
    stribeck_speed: float = math.inf
    temperature: float = 25.0
    max_step: float = MAX_STEP
    _friction_cache: dict[float, float] = field(default_factory=dict, repr=False)

    @classmethod
    def from_config(cls, config: Config, ambient: float) -> DamperModel:
        """The model of ``config``'s ECD, its damper at ``ambient`` [degC]."""
        from ecdsim.deployment import build_problem
        from ecdsim.dynamics.problem import dynamic_problem

        temps = np.array([float(ambient)])
        ecd = config.system.ecd.at(temps)
        base, fs = build_problem(config.system, ecd, temps)
        problem = dynamic_problem(config.system, ecd, temps, base, fs, _dynamic_parameters(config))
        damper = config.spec.damper
        return cls(
            system=config.system,
            ratio=float(np.ravel(problem.gear_ratio)[0]),
            gearbox_damping=float(np.ravel(problem.gearbox_damping_rate)[0]),
            eddy=problem.eddy,
            heating=bool(problem.thermal),
            heat_capacity=float(np.ravel(problem.heat_capacity)[0]),
            thermal_resistance=float(np.ravel(problem.thermal_resistance)[0]),
            forward_efficiency=float(np.ravel(ecd.forward_efficiency)[0]),
            static_friction_factor=float(damper.static_friction_factor),
            stribeck_speed=math.inf if damper.stribeck_speed is None else damper.stribeck_speed,
            temperature=float(ambient),
        )

    def _factor(self, temperature: float) -> float:
        # Eq. 1's bracket (or the Kloss law's factor), never below 0: the law's zero is
        # approached by heating, never crossed (ecdsim.physics.thermal).
        return max(float(np.ravel(self.eddy.factor(temperature))[0]), 0.0)

    def eddy_torque(self, speed: float, temperature: float) -> float:
        """T_eddy at the high-speed shaft for slow-shaft speed ``speed`` [N*m]."""
        shaft = self.ratio * speed
        return float(np.ravel(self.eddy.torque_at_factor(shaft, self._factor(temperature)))[0])

    def damper_torque(self, speed: float, temperature: float | None = None) -> float:
        """Damping torque at the slow shaft, opposing ``speed`` [N*m]:
        N (T_eddy + BG N u) / eta_f (Eq. 1, 3; a lossy mesh as Modelica's LossyGear in
        its forward mode, which this damper without inertia is always in: the shaft
        drives it)."""
        t = self.temperature if temperature is None else temperature
        shaft = self.ratio * speed
        torque = self.ratio * (self.eddy_torque(speed, t) + self.gearbox_damping * shaft)
        return torque / self.forward_efficiency

    def friction_torque(self, speed: float, ambient: float) -> float:
        """Coulomb friction of the ECD at the slow shaft, opposing ``speed`` [N*m].

        ``FECD(T_ambient)`` (Eq. 2 and 4, at the ambient temperature as in the dynamic
        method, a lossy mesh's 1/eta_f included) times the sign of the speed; with a
        Stribeck speed the dynamic method's curve for the ECD's part,
        ``FECD [1 + (f_D - 1) exp(-(u / w_St)^2)]`` (docs/dynamics.md, "Stribeck
        friction"); 0 at rest, where the holding torque depends on the rest of the
        mechanism.
        """
        if speed == 0.0 or math.isnan(speed):
            return 0.0
        key = float(ambient)
        if key not in self._friction_cache:
            state = self.system.ecd.at(np.array([key]))
            self._friction_cache.clear()
            self._friction_cache[key] = float(np.ravel(state.ecd_friction)[0])
        kinetic = self._friction_cache[key]
        excess = (self.static_friction_factor - 1.0) * kinetic
        if excess != 0.0 and math.isfinite(self.stribeck_speed):
            kinetic += excess * math.exp(-((speed / self.stribeck_speed) ** 2))
        return math.copysign(kinetic, speed)

    def _rate(self, speed: float, temperature: float, ambient: float) -> float:
        power = self.eddy_torque(speed, temperature) * self.ratio * speed
        loss = (
            (temperature - ambient) / self.thermal_resistance
            if math.isfinite(self.thermal_resistance)
            else 0.0
        )
        return (power - loss) / self.heat_capacity

    def advance(self, speed: float, slope: float, ambient: float, step: float) -> None:
        """Integrate the damper temperature over ``step`` [s] (classical Runge-Kutta).

        The speed is ``speed + slope * tau`` at ``tau`` into the step [rad/s]; without
        heating the damper is at the ambient temperature.
        """
        if not self.heating:
            self.temperature = float(ambient)
            return
        if step <= 0.0:
            return
        n = max(1, math.ceil(step / self.max_step - 1e-9))
        h = step / n
        t = self.temperature
        for i in range(n):
            u0 = speed + slope * (i * h)
            um = u0 + slope * (0.5 * h)
            u1 = u0 + slope * h
            k1 = self._rate(u0, t, ambient)
            k2 = self._rate(um, t + 0.5 * h * k1, ambient)
            k3 = self._rate(um, t + 0.5 * h * k2, ambient)
            k4 = self._rate(u1, t + h * k3, ambient)
            t += h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
        self.temperature = t


@dataclass
class DeploymentReplay:
    """The dynamic method's deployment of a config at one ambient temperature.

    Attributes
    ----------
    prediction : the prediction (dynamic method only)
    latch_time : when the hinge reaches the end of travel [s] (inf if it stalls)
    """

    prediction: Prediction
    latch_time: float

    @classmethod
    def from_config(cls, config: Config, ambient: float) -> DeploymentReplay:
        """Run the dynamic method on ``config`` at ``ambient`` [degC]."""
        from ecdsim.deployment import predict

        prediction = predict(
            config.system, [float(ambient)], ["dynamic"], dynamics=config.spec.dynamics()
        )
        time = float(np.ravel(prediction.solutions["dynamic"].deployment_time)[0])
        return cls(prediction, time)

    def at(self, time: float) -> tuple[float, float, bool]:
        """(angle [rad], speed [rad/s], latched) at ``time`` [s].

        From the latch time on the hinge is latched at the end of travel: speed 0.
        """
        trajectory = self.prediction.trajectory("dynamic", np.array([float(time)]))
        angle = float(np.ravel(trajectory.angle)[0])
        latched = bool(time >= self.latch_time)
        speed = 0.0 if latched else float(np.ravel(trajectory.speed)[0])
        return angle, speed, latched

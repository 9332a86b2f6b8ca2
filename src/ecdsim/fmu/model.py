"""What the FMUs compute, in plain Python: testable without pythonfmu or an FMI host.

:class:`DamperModel` is the ECD (damper + gearbox) referred to the slow shaft: the
values of a config that the equations of :mod:`ecdsim.fmu.equations` take, and those
equations called in Python. The damper FMU is the same equations translated to C, its
parameters started at these values (:mod:`ecdsim.fmu.native`); the model holds no law
of its own and no integrator: in model exchange the host integrates the temperature
states, in co-simulation the FMU's RK4 does (docs/fmu.md).

:class:`DeploymentReplay` is the whole spring-driven hinge: the dynamic method is run
once at initialisation and its solution is evaluated at the times asked.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim.fmu import equations

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.deployment import Prediction

# The config keys the deployment FMU exposes as parameters (FMI name -> config key).
# Their start values are the config's; a host may change them before initialisation.
DEPLOYMENT_PARAMETERS = {
    "gear_ratio": "gearbox.ratio",
    "damping_rate": "damper.damping_rate",
    "damping_temperature_coefficient": "damper.damping_temperature_coefficient",
    "damper_coulomb_friction": "damper.coulomb_friction",
    "gearbox_coulomb_friction": "gearbox.coulomb_friction",
    "load_inertia": "load.inertia",
    "start_torque": "load.start_torque",
    "end_torque": "load.end_torque",
}

# The results of equations.damper_outputs, in its order.
DAMPER_OUTPUTS = (
    "damper_torque",
    "friction_torque",
    "coulomb_friction",
    "breakaway_friction",
    "eddy_power",
)
# The arguments of the equations that are inputs and states, not model values.
INPUTS = ("shaft_speed", "ambient_temperature")
STATES = ("damper_temperature", "housing_temperature")

Value = float | bool | int | tuple[float, ...]


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


def _float(value: object, key: str) -> float:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    raise TypeError(f"{key}: the FMU takes one value, not {type(value).__name__}")


def _values(config: Config) -> tuple[dict[str, Value], list[str]]:
    """The equations' model values of ``config`` and the names a host may set."""
    from ecdsim.model import LinearTemperatureLaw, TabulatedTemperatureLaw

    damper = config.system.ecd.damper
    gearbox = config.system.ecd.gearbox
    spec = config.spec.damper
    values: dict[str, Value] = {
        "gear_ratio": _float(gearbox.ratio, "gearbox.ratio"),
        "damping_rate": _float(damper.damping_rate, "damper.damping_rate"),
        "reference_temperature": _float(
            damper.reference_temperature, "damper.reference_temperature"
        ),
        "damping_temperature_coefficient": _float(
            damper.damping_temperature_coefficient, "damper.damping_temperature_coefficient"
        ),
        "rolloff": spec.rolloff is not None,
        "peak_speed": 0.0,
        "resistivity_coefficient": 0.0,
        "gearbox_damping_rate": 0.0,
        "gearbox_damping_fraction": 0.0,
        "forward_efficiency": 1.0,
        "damper_coulomb_friction": _float(damper.coulomb_friction, "damper.coulomb_friction"),
        "gearbox_coulomb_friction": _float(gearbox.coulomb_friction, "gearbox.coulomb_friction"),
        "lubrication_friction_slope": 0.0,
        "lubrication_friction_at_0c": 0.0,
        "lubrication_temperatures": (0.0,),
        "lubrication_frictions": (0.0,),
        "lubrication_points": 0,
        "static_friction_factor": float(spec.static_friction_factor),
        "stribeck_speed": math.inf,
        "heat_capacity": 1.0,
        "thermal_resistance": math.inf,
        "housing": False,
        "housing_heat_capacity": 1.0,
        "housing_thermal_resistance": math.inf,
    }
    exposed = [
        "gear_ratio",
        "damping_rate",
        "reference_temperature",
        "damper_coulomb_friction",
        "gearbox_coulomb_friction",
        "static_friction_factor",
    ]
    if spec.rolloff is None:
        exposed.append("damping_temperature_coefficient")
    else:
        values["peak_speed"] = float(spec.rolloff.peak_speed)
        values["resistivity_coefficient"] = float(spec.rolloff.resistivity_coefficient)
        exposed += ["peak_speed", "resistivity_coefficient"]
    if gearbox.damping_rate is not None:
        values["gearbox_damping_rate"] = _float(gearbox.damping_rate, "gearbox.damping_rate")
        exposed.append("gearbox_damping_rate")
    else:
        values["gearbox_damping_fraction"] = _float(
            gearbox.damping_fraction, "gearbox.damping_fraction"
        )
        exposed.append("gearbox_damping_fraction")
    if gearbox.efficiency is not None:
        values["forward_efficiency"] = _float(gearbox.efficiency.forward, "gearbox.efficiency")
        exposed.append("forward_efficiency")
    law = damper.lubrication_friction
    if isinstance(law, TabulatedTemperatureLaw):
        values["lubrication_temperatures"] = tuple(float(t) for t in law.temperatures)
        values["lubrication_frictions"] = tuple(float(v) for v in law.values)
        values["lubrication_points"] = len(law.temperatures)
        exposed += ["lubrication_temperatures", "lubrication_frictions"]
    elif isinstance(law, LinearTemperatureLaw):
        values["lubrication_friction_slope"] = _float(law.slope, "damper.lubrication_friction")
        values["lubrication_friction_at_0c"] = _float(law.at_0c, "damper.lubrication_friction")
        exposed += ["lubrication_friction_slope", "lubrication_friction_at_0c"]
    else:  # pragma: no cover - the config knows only these two laws
        raise TypeError(f"damper.lubrication_friction: no FMU form for {law!r}")
    if spec.stribeck_speed is not None:
        values["stribeck_speed"] = float(spec.stribeck_speed)
        exposed.append("stribeck_speed")
    thermal = spec.thermal
    if thermal is not None:
        values["heat_capacity"] = float(thermal.heat_capacity)
        exposed.append("heat_capacity")
        if thermal.thermal_resistance is not None:
            values["thermal_resistance"] = float(thermal.thermal_resistance)
            exposed.append("thermal_resistance")
        if thermal.housing_heat_capacity is not None:
            values["housing"] = True
            values["housing_heat_capacity"] = float(thermal.housing_heat_capacity)
            exposed.append("housing_heat_capacity")
            if thermal.housing_thermal_resistance is not None:
                values["housing_thermal_resistance"] = float(thermal.housing_thermal_resistance)
                exposed.append("housing_thermal_resistance")
    return values, exposed


def _call(function: Callable[..., Any], known: Mapping[str, Value]) -> Any:
    """``function`` called with the values of its arguments, by name."""
    names = inspect.signature(function).parameters
    return function(*(known[name] for name in names))


@dataclass(frozen=True)
class DamperModel:
    """The ECD at the slow shaft: the equations' values of one config, and the equations.

    Attributes
    ----------
    values : every argument of :func:`~ecdsim.fmu.equations.damper_outputs` and
        :func:`~ecdsim.fmu.equations.damper_heating` but the inputs and the states, in SI
        (temperatures in degC); a tuple for a table, bools for the structure (``rolloff``,
        ``housing``)
    parameters : the names among ``values`` that the FMU exposes as parameters (the
        config's keys; the others are fixed by its structure)
    heating : whether the damper heats ([damper.thermal]): the damper temperature is
        then a state, else the ambient temperature
    ambient : the config's first analysis temperature [degC], the FMU's start value
    """

    values: dict[str, Value]
    parameters: tuple[str, ...]
    heating: bool
    ambient: float

    @classmethod
    def from_config(cls, config: Config) -> DamperModel:
        """The model of ``config``'s ECD (each value a single number)."""
        values, exposed = _values(config)
        return cls(
            values=values,
            parameters=tuple(exposed),
            heating=config.spec.damper.thermal is not None,
            ambient=float(config.temperatures[0]),
        )

    @property
    def housing(self) -> bool:
        """Two-node heating: the rotor and its housing."""
        return bool(self.values["housing"])

    def with_values(self, **changes: Value) -> DamperModel:
        """The model with some values changed (as an FMU host sets parameters)."""
        unknown = set(changes) - set(self.values)
        if unknown:
            raise KeyError(f"no model value {sorted(unknown)}; choose from {sorted(self.values)}")
        return replace(self, values={**self.values, **changes})

    def outputs(
        self, speed: float, ambient: float, damper_temperature: float | None = None
    ) -> dict[str, float]:
        """The outputs at slow-shaft speed [rad/s], ambient and damper temperature [degC].

        Without heating the damper is at the ambient temperature (``damper_temperature``
        must then be None or equal to it).
        """
        temperature = ambient if damper_temperature is None else damper_temperature
        known = {
            **self.values,
            "shaft_speed": speed,
            "ambient_temperature": ambient,
            "damper_temperature": temperature,
        }
        return dict(zip(DAMPER_OUTPUTS, _call(equations.damper_outputs, known), strict=True))

    def derivatives(
        self,
        speed: float,
        ambient: float,
        damper_temperature: float,
        housing_temperature: float | None = None,
    ) -> tuple[float, float]:
        """(dT_d/dt, dT_h/dt) [K/s] at the given speed and temperatures (heating only)."""
        if not self.heating:
            raise ValueError("this damper has no [damper.thermal]: its temperature is the ambient")
        housing = ambient if housing_temperature is None else housing_temperature
        known = {
            **self.values,
            "shaft_speed": speed,
            "ambient_temperature": ambient,
            "damper_temperature": damper_temperature,
            "housing_temperature": housing,
        }
        rates: tuple[float, float] = _call(equations.damper_heating, known)
        return rates


# Deployment status (the deployment FMU's `status` output): FMI enumeration values.
MOVING, LATCHED, SETTLED, STUCK, STALLED, INCOMPLETE = 1, 2, 3, 4, 5, 6
STATUS_NAMES = {
    MOVING: "moving",
    LATCHED: "latched",
    SETTLED: "settled",
    STUCK: "stuck",
    STALLED: "stalled",
    INCOMPLETE: "incomplete",
}
STATUS_DESCRIPTIONS = {
    MOVING: "deploying (before the run's end)",
    LATCHED: "caught at the end of travel (restitution 0), from the latch time on",
    SETTLED: "rebounds against the end stop died out, from then on",
    STUCK: "held at rest short of the end by static friction (or on the start stop)",
    STALLED: "creeps to a static equilibrium short of the end, reached only "
    "asymptotically: known from the release, so reported from t = 0",
    INCOMPLETE: "the run was cut short (event limit or integration horizon)",
}
_OUTCOMES = {
    "latched": LATCHED,
    "settled": SETTLED,
    "stuck": STUCK,
    "creep": STALLED,
}


@dataclass
class DeploymentReplay:
    """The dynamic method's deployment of a config at one ambient temperature.

    Attributes
    ----------
    prediction : the prediction (dynamic method only)
    latch_time : when the hinge first reaches the end of travel [s] (inf if never)
    outcome : how the run ends (:data:`STATUS_NAMES`: latched, settled, stuck, stalled
        or incomplete)
    end_time : when it ends [s]: the latch, settling or sticking time; 0 for a stall
        (reported from the release on); inf where no end is known
    """

    prediction: Prediction
    latch_time: float
    outcome: int = LATCHED
    end_time: float = math.inf

    @classmethod
    def from_config(cls, config: Config, ambient: float) -> DeploymentReplay:
        """Run the dynamic method on ``config`` at ``ambient`` [degC]."""
        from ecdsim.deployment import predict

        prediction = predict(
            config.system, [float(ambient)], ["dynamic"], dynamics=config.spec.dynamics()
        )
        solution: Any = prediction.solutions["dynamic"]
        latch = float(np.ravel(solution.deployment_time)[0])
        result = solution.result
        name = result.status_names()[0]
        outcome = _OUTCOMES.get(name, INCOMPLETE)
        if outcome == STALLED:
            end = 0.0
        elif outcome == STUCK:
            end = float(np.ravel(result.stuck_time)[0])
        elif outcome == LATCHED:
            end = latch
        else:
            end = float(np.ravel(result.final_time)[0])
        return cls(prediction, latch, outcome, end)

    def status(self, time: float) -> int:
        """The status at ``time`` [s]: moving before the run's end, its outcome from it."""
        return self.outcome if time >= self.end_time else MOVING

    def at(self, time: float) -> tuple[float, float, bool]:
        """(angle [rad], speed [rad/s], latched) at ``time`` [s].

        ``latched`` is true from the first arrival at the end of travel on; with a
        rebounding end stop (restitution > 0) the angle and speed then follow the
        rebounds until they settle.
        """
        trajectory = self.prediction.trajectory("dynamic", np.array([float(time)]))
        angle = float(np.ravel(trajectory.angle)[0])
        speed = float(np.ravel(trajectory.speed)[0])
        latched = bool(time >= self.latch_time)
        if self.outcome == LATCHED and latched:
            speed = 0.0  # caught: the solution's arrival speed is not the hinge's any more
        return angle, speed, latched

"""The FMI 2.0 co-simulation slaves, written with pythonfmu (``pip install 'ecdsim[fmu]'``).

An FMU built by :func:`ecdsim.fmu.build_fmu` holds the config (``resources/``) and a
two-line script subclassing one of these; pythonfmu's loader runs it in the Python the
host provides, which must have ecdsim installed. The physics is in
:mod:`ecdsim.fmu.model`; these classes only map FMI variables onto it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from pythonfmu import (
    Boolean,
    Fmi2Causality,
    Fmi2Slave,
    Fmi2Variability,
    Real,
)

from ecdsim.fmu.model import (
    DAMPER_PARAMETERS,
    DEPLOYMENT_PARAMETERS,
    MAX_STEP,
    THERMAL_PARAMETERS,
    DamperModel,
    DeploymentReplay,
    config_values,
)

CONFIG_FILE = "ecdsim_config.toml"


def _config(resources: str | None, overrides: dict[str, object] | None = None) -> Any:
    from ecdsim.api import load

    if resources is None:
        raise RuntimeError("the FMU has no resources folder (its config is kept there)")
    return load(Path(resources) / CONFIG_FILE, overrides)


def _parameter(slave: Fmi2Slave, name: str, description: str) -> None:
    slave.register_variable(
        Real(
            name,
            causality=Fmi2Causality.parameter,
            variability=Fmi2Variability.fixed,
            description=description,
        )
    )


class DamperSlave(Fmi2Slave):  # type: ignore[misc]
    """The ECD (damper + gearbox) at the slow shaft: speed and ambient in, torques out.

    Inputs: ``shaft_speed`` [rad/s] (slow shaft), ``ambient_temperature`` [degC].
    Outputs: ``damper_torque`` and ``friction_torque`` [N*m] (opposing the speed),
    ``damper_temperature`` [degC] (self-heating with ``[damper.thermal]``, else the
    ambient). Parameters: the config's values of :data:`DAMPER_PARAMETERS` (and
    :data:`THERMAL_PARAMETERS`), ``max_step`` [s], ``input_extrapolation``.
    """

    author = "ecdsim"
    description = "Eddy current damper and gearbox referred to the slow shaft (ecdsim)"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        config = _config(self.resources)
        self._names = dict(DAMPER_PARAMETERS)
        if config.spec.damper.thermal is not None:
            self._names.update(THERMAL_PARAMETERS)
        self.shaft_speed = 0.0
        self.ambient_temperature = float(config.temperatures[0])
        self.max_step = MAX_STEP
        self.input_extrapolation = True
        for name, value in config_values(config, self._names).items():
            setattr(self, name, value)
            _parameter(self, name, f"config key {self._names[name]} (SI)")
        self._names = {n: k for n, k in self._names.items() if hasattr(self, n)}
        _parameter(self, "max_step", "longest internal Runge-Kutta step of the heat balance [s]")
        self.register_variable(
            Boolean(
                "input_extrapolation",
                causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed,
                description="extrapolate the speed over a step from the last two inputs",
            )
        )
        for name, text in (
            ("shaft_speed", "slow-shaft speed [rad/s]"),
            ("ambient_temperature", "ambient temperature [degC]"),
        ):
            self.register_variable(Real(name, causality=Fmi2Causality.input, description=text))
        for name, text in (
            ("damper_torque", "damping torque at the slow shaft, opposing the speed [N*m]"),
            ("friction_torque", "ECD Coulomb friction at the slow shaft, opposing [N*m]"),
            ("damper_temperature", "damper temperature [degC]"),
        ):
            self.register_variable(Real(name, causality=Fmi2Causality.output, description=text))
        self._model: DamperModel | None = None
        self._previous: tuple[float, float] | None = None  # (speed, step) of the last step

    def _build(self) -> DamperModel:
        overrides = {key: getattr(self, name) for name, key in self._names.items()}
        config = _config(self.resources, overrides)
        model = DamperModel.from_config(config, self.ambient_temperature)
        model.max_step = float(self.max_step)
        return model

    @property
    def model(self) -> DamperModel:
        """The damper model, built from the parameters on first use."""
        if self._model is None:
            self._model = self._build()
        return self._model

    def exit_initialization_mode(self) -> None:
        """Build the model from the parameters the host set; T_d starts at ambient."""
        self._model = self._build()
        self._previous = None

    @property
    def damper_torque(self) -> float:
        """The output ``damper_torque`` at the current input and state [N*m]."""
        return self.model.damper_torque(float(self.shaft_speed))

    @property
    def friction_torque(self) -> float:
        """The output ``friction_torque`` [N*m]."""
        return self.model.friction_torque(float(self.shaft_speed), float(self.ambient_temperature))

    @property
    def damper_temperature(self) -> float:
        """The output ``damper_temperature`` [degC]."""
        if not self.model.heating:
            return float(self.ambient_temperature)
        return self.model.temperature

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Advance the damper temperature by one communication step."""
        speed = float(self.shaft_speed)
        slope = 0.0
        if self.input_extrapolation and self._previous is not None:
            before, step = self._previous
            slope = (speed - before) / step if step > 0.0 else 0.0
        if not math.isfinite(speed) or not math.isfinite(slope):
            return False
        self.model.advance(speed, slope, float(self.ambient_temperature), float(step_size))
        self._previous = (speed, float(step_size))
        return True


class DeploymentSlave(Fmi2Slave):  # type: ignore[misc]
    """The spring-driven hinge by the dynamic method: no inputs; angle, speed, latch out.

    Parameters: ``ambient_temperature`` [degC] and the config's values of
    :data:`DEPLOYMENT_PARAMETERS`. Outputs: ``angle`` [rad], ``speed`` [rad/s],
    ``latched`` (true from the end of travel on).
    """

    author = "ecdsim"
    description = "Spring-driven deployment with an eddy current damper (ecdsim dynamic method)"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        config = _config(self.resources)
        self.ambient_temperature = float(config.temperatures[0])
        _parameter(self, "ambient_temperature", "ambient temperature [degC]")
        self._names = dict(DEPLOYMENT_PARAMETERS)
        for name, value in config_values(config, self._names).items():
            setattr(self, name, value)
            _parameter(self, name, f"config key {self._names[name]} (SI)")
        self._names = {n: k for n, k in self._names.items() if hasattr(self, n)}
        self.angle = 0.0
        self.speed = 0.0
        self.latched = False
        for name, text in (
            ("angle", "deployed angle [rad]"),
            ("speed", "hinge speed [rad/s]"),
        ):
            self.register_variable(Real(name, causality=Fmi2Causality.output, description=text))
        self.register_variable(
            Boolean(
                "latched",
                causality=Fmi2Causality.output,
                variability=Fmi2Variability.discrete,
                description="true from the end of travel on",
            )
        )
        self._replay: DeploymentReplay | None = None

    def exit_initialization_mode(self) -> None:
        """Run the dynamic method with the parameters the host set."""
        overrides = {key: getattr(self, name) for name, key in self._names.items()}
        config = _config(self.resources, overrides)
        self._replay = DeploymentReplay.from_config(config, float(self.ambient_temperature))
        self.angle, self.speed, self.latched = self._replay.at(0.0)

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Set the outputs to the deployment's state at the end of the step."""
        if self._replay is None:
            return False
        self.angle, self.speed, self.latched = self._replay.at(current_time + step_size)
        return True

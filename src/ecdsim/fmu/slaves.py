"""The deployment FMU's co-simulation slave, written with pythonfmu (``pip install 'ecdsim[fmu]'``).

An FMU built by :func:`ecdsim.fmu.build_fmu` with ``deployment=True`` holds the config
(``resources/``) and a short script subclassing :class:`DeploymentSlave`; pythonfmu's
loader runs it in the Python the host provides, which must have ecdsim (of the version
that built the FMU) installed. The physics is in :mod:`ecdsim.fmu.model`; this class
only maps FMI variables onto it. (The damper FMU needs no Python: :mod:`ecdsim.fmu.native`.)

The slave runs the dynamic kernels as plain Python (:func:`ecdsim._numba.plain`) and never
loads numba in the host: numba inside the host's calls into the FMU aborted the host
("corrupted double-linked list", rc 134) when it had kernels to compile, and even when
it only found them missing from its cache (docs/fmu.md). A deployment is one run at
initialization and look-ups of its trajectory, milliseconds to seconds in plain Python.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pythonfmu import (
    Boolean,
    Fmi2Causality,
    Fmi2Slave,
    Fmi2Variability,
    Integer,
    Real,
)

from ecdsim import _numba
from ecdsim.fmu.model import DEPLOYMENT_PARAMETERS, MOVING, DeploymentReplay, config_values

CONFIG_FILE = "ecdsim_config.toml"


def _config(resources: str | None, overrides: dict[str, object] | None = None) -> Any:
    # Without the notebook API's placeholder-load warning: the export warned once and the
    # FMU's description says so, while this runs at every instantiation (pythonfmu's
    # builder makes one too), where the warning would repeat with a temporary path.
    from ecdsim.api import _load

    if resources is None:
        raise RuntimeError("the FMU has no resources folder (its config is kept there)")
    return _load(Path(resources) / CONFIG_FILE, overrides)


def _parameter(slave: Fmi2Slave, name: str, description: str) -> None:
    slave.register_variable(
        Real(
            name,
            causality=Fmi2Causality.parameter,
            variability=Fmi2Variability.fixed,
            description=description,
        )
    )


class DeploymentSlave(Fmi2Slave):  # type: ignore[misc]
    """The spring-driven hinge by the dynamic method: no inputs; angle, speed, status out.

    Parameters: ``ambient_temperature`` [degC] and the config's values of
    :data:`~ecdsim.fmu.model.DEPLOYMENT_PARAMETERS`. Outputs: ``angle`` [rad], ``speed``
    [rad/s], ``latched`` (true from the first arrival at the end of travel on) and
    ``status`` (an enumeration: :data:`~ecdsim.fmu.model.STATUS_NAMES`).
    """

    author = "ecdsim"
    description = "Spring-driven deployment with an eddy current damper (ecdsim dynamic method)"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        config = _config(self.resources)
        self.ambient_temperature = float(config.temperatures[0])
        _parameter(self, "ambient_temperature", "ambient temperature")
        self._names = dict(DEPLOYMENT_PARAMETERS)
        for name, value in config_values(config, self._names).items():
            setattr(self, name, value)
            _parameter(self, name, f"config key {self._names[name]}")
        self._names = {n: k for n, k in self._names.items() if hasattr(self, n)}
        self.angle = 0.0
        self.speed = 0.0
        self.latched = False
        self.status = MOVING
        for name, text in (
            ("angle", "deployed angle"),
            ("speed", "hinge speed"),
        ):
            self.register_variable(Real(name, causality=Fmi2Causality.output, description=text))
        self.register_variable(
            Boolean(
                "latched",
                causality=Fmi2Causality.output,
                variability=Fmi2Variability.discrete,
                description="true from the first arrival at the end of travel on",
            )
        )
        self.register_variable(
            Integer(
                "status",
                causality=Fmi2Causality.output,
                variability=Fmi2Variability.discrete,
                description="moving, latched, settled, stuck, stalled or incomplete",
            )
        )
        self._replay: DeploymentReplay | None = None

    def exit_initialization_mode(self) -> None:
        """Run the dynamic method with the parameters the host set."""
        overrides = {key: getattr(self, name) for name, key in self._names.items()}
        config = _config(self.resources, overrides)
        with _numba.plain():
            self._replay = DeploymentReplay.from_config(config, float(self.ambient_temperature))
        self._update(0.0)

    def _update(self, time: float) -> None:
        assert self._replay is not None
        with _numba.plain():
            self.angle, self.speed, self.latched = self._replay.at(time)
        self.status = self._replay.status(time)

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Set the outputs to the deployment's state at the end of the step."""
        if self._replay is None:
            return False
        self._update(current_time + step_size)
        return True

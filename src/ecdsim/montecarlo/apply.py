"""Put sampled values into the model: a DeploymentSystem (and dynamics) of arrays.

Every numeric field of the model may be a NumPy array (:mod:`ecdsim.model`,
:mod:`ecdsim.dynamics.params`), so a chunk of n samples is one system whose toleranced
fields hold n values each; the solvers broadcast them against the temperatures. The
fields are found through :data:`ecdsim.config.tolerance_schema.TOLERABLE` (config key ->
attribute path from :class:`Parameters`) and replaced with :func:`dataclasses.replace`,
so every other field, including ones that later model extensions add, stays as
configured.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.config.tolerance_schema import TOLERABLE
from ecdsim.model import DeploymentSystem

if TYPE_CHECKING:
    from ecdsim.dynamics.params import DynamicParameters


class NotTolerable(ValueError):
    """The configuration does not set the named quantity in a form that takes a tolerance."""


@dataclass(frozen=True)
class Parameters:
    """Everything a deployment prediction takes from the configuration.

    Attributes
    ----------
    system : the deployment system (ECD and load)
    dynamics : the dynamic method's parameters (inertia, ...), None without [load] inertia
    """

    system: DeploymentSystem
    dynamics: DynamicParameters | None = None


_OWNERS = {
    "LinearSpring": "the linear spring's start_torque and end_torque (this config gives a "
    "spring_table)",
    "ResistiveTable": "[load] resistive_table, which this config does not give",
    "Gravity": "[load.gravity], which this config does not give",
    "GearEfficiency": "[gearbox] efficiency, which this config does not give",
    "Rolloff": "[damper.rolloff], which this config does not give",
    "Thermal": "[damper.thermal], which this config does not give",
}

# Fields whose omission in the config means a value the tolerance cannot centre on.
_OMITTED = {
    "damper.thermal.thermal_resistance": "infinite here: [damper.thermal] gives no "
    "thermal_resistance (adiabatic); give a finite one in K/W to take a tolerance",
    "damper.thermal.housing_thermal_resistance": "infinite here: [damper.thermal] gives no "
    "housing_thermal_resistance (adiabatic housing); give a finite one in K/W to take a "
    "tolerance",
    "damper.thermal.housing_heat_capacity": "not set in this config: [damper.thermal] gives no "
    "housing_heat_capacity (one-node heating); give one in J/K for the housing node",
}


def _owner(parameters: Parameters, key: str) -> tuple[Any, str]:
    """The model object that holds ``key``'s field, and the field's name."""
    if key not in TOLERABLE:
        known = ", ".join(TOLERABLE)
        raise NotTolerable(f"{key!r} cannot take a tolerance; expected one of {known}")
    quantity = TOLERABLE[key]
    obj: Any = parameters
    for name in quantity.model_path[:-1]:
        obj = getattr(obj, name)
        if obj is None:
            # An optional part of the model, absent here (the dynamic parameters themselves
            # are absent without [load] inertia, whatever the key's section).
            if name != "dynamics" and quantity.owner in _OWNERS:
                raise NotTolerable(
                    f"not set in this config: it applies to {_OWNERS[quantity.owner]}"
                )
            raise NotTolerable("not set in this config: the dynamic parameters need [load] inertia")
    field = quantity.model_path[-1]
    section = key.rsplit(".", 1)[0]
    if quantity.owner is not None and type(obj).__name__ != quantity.owner:
        what = _OWNERS.get(
            quantity.owner, f"a linear law's slope and at_0C ({section} is {obj.describe()})"
        )
        raise NotTolerable(f"not set in this config: the tolerance applies to {what}")
    if not dataclasses.is_dataclass(obj) or field not in {f.name for f in dataclasses.fields(obj)}:
        raise NotTolerable(f"not set in this config ({type(obj).__name__} has no {field})")
    return obj, field


def nominal(parameters: Parameters, key: str) -> float:
    """The configured value of ``key`` in SI units; NotTolerable if the config lacks it."""
    obj, field = _owner(parameters, key)
    value = getattr(obj, field)
    if key in _OMITTED and (value is None or not np.all(np.isfinite(value))):
        raise NotTolerable(_OMITTED[key])
    if value is None:
        section = key.rsplit(".", 1)[0]
        alternative = {
            "gearbox.damping_rate": "gearbox.damping_fraction",
            "gearbox.damping_fraction": "gearbox.damping_rate",
        }.get(key)
        hint = f"; this config gives {alternative} instead" if alternative else ""
        raise NotTolerable(f"not set in this config's [{section}] section{hint}")
    array = np.asarray(value, dtype=float)
    if array.ndim != 0:
        raise NotTolerable("already an array in this system; give a scalar configuration")
    return float(array)


def _replace_path(obj: Any, path: tuple[str, ...], value: FloatArray) -> Any:
    if len(path) == 1:
        return dataclasses.replace(obj, **{path[0]: value})
    child = getattr(obj, path[0])
    return dataclasses.replace(obj, **{path[0]: _replace_path(child, path[1:], value)})


def apply(parameters: Parameters, values: Mapping[str, FloatArray]) -> Parameters:
    """A copy of ``parameters`` with each keyed field replaced by its array of samples [SI].

    >>> from ecdsim.model import Ecd, Gearbox, HighSpeedDamper, LinearSpring, Load
    >>> base = DeploymentSystem(
    ...     Ecd(HighSpeedDamper(1.3e-4), Gearbox(380.0, damping_fraction=0.26)),
    ...     Load(LinearSpring(3.73, 1.58), 1.57),
    ... )
    >>> varied = apply(Parameters(base), {"gearbox.ratio": np.array([370.0, 390.0])})
    >>> varied.system.ecd.gearbox.ratio.tolist(), varied.system.ecd.gearbox.damping_fraction
    ([370.0, 390.0], 0.26)
    """
    out = parameters
    for key, column in values.items():
        _owner(out, key)  # a clear error for a key these parameters cannot take
        out = _replace_path(out, TOLERABLE[key].model_path, np.asarray(column, dtype=float))
    return out

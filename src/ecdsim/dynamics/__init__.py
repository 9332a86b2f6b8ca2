"""Full deployment dynamics: inertia, stick-slip, lost motion, end stop, roll-off, heating.

The ``dynamic`` method (registered in :data:`ecdsim.methods.SOLVERS`) solves the
deployment as an event-driven sequence of segments: closed form where the dynamics are
linear (:mod:`ecdsim.dynamics.linear`), numerically where the damping rolls off or the
damper heats (:mod:`ecdsim.dynamics.integrate`). See ``docs/dynamics.md``.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ecdsim.dynamics.params import DynamicParameters, Rolloff, Thermal
    from ecdsim.dynamics.problem import DynamicProblem, dynamic_problem
    from ecdsim.dynamics.result import DynamicResult, EnergyBalance, EventLog, TimeSeries
    from ecdsim.dynamics.solver import solve_dynamic

# Imported when first named, so that the config schema's ``ecdsim.dynamics.params`` does
# not pull in the solver and its integrators (docs/architecture.md, "Start-up").
_WHERE = {
    "DynamicParameters": "params",
    "Rolloff": "params",
    "Thermal": "params",
    "DynamicProblem": "problem",
    "dynamic_problem": "problem",
    "DynamicResult": "result",
    "EnergyBalance": "result",
    "EventLog": "result",
    "TimeSeries": "result",
    "solve_dynamic": "solver",
}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{module}"), name)


__all__ = [
    "DynamicParameters",
    "DynamicProblem",
    "DynamicResult",
    "EnergyBalance",
    "EventLog",
    "Rolloff",
    "Thermal",
    "TimeSeries",
    "dynamic_problem",
    "solve_dynamic",
]

"""Full deployment dynamics: inertia, stick-slip, lost motion, end stop, roll-off, heating.

The ``dynamic`` method (registered in :data:`ecdsim.methods.SOLVERS`) solves the
deployment as an event-driven sequence of segments: closed form where the dynamics are
linear (:mod:`ecdsim.dynamics.linear`), numerically where the damping rolls off or the
damper heats (:mod:`ecdsim.dynamics.integrate`). See ``docs/dynamics.md``.
"""

from ecdsim.dynamics.params import DynamicParameters, Rolloff, Thermal
from ecdsim.dynamics.problem import DynamicProblem, dynamic_problem
from ecdsim.dynamics.result import DynamicResult, EnergyBalance, EventLog, TimeSeries
from ecdsim.dynamics.solver import solve_dynamic

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

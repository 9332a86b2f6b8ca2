"""Deployment solvers, by name: each maps a quasi-static problem to a solution.

``SOLVERS`` is the registry that the CLI, the report and later methods share; adding a
method is adding an entry, never an if/elif ladder.
"""

# The dynamic method needs a DynamicProblem (a QuasiStaticProblem with inertia etc.),
# which ecdsim.deployment.predict builds when given dynamics= (docs/dynamics.md).
from ecdsim.dynamics.method import DYNAMIC
from ecdsim.solvers.base import (
    DeploymentSolution,
    QuasiStaticProblem,
    Solver,
    Trajectory,
)
from ecdsim.solvers.exact import EXACT
from ecdsim.solvers.paper import PAPER

SOLVERS: dict[str, Solver] = {PAPER.name: PAPER, EXACT.name: EXACT, DYNAMIC.name: DYNAMIC}

__all__ = [
    "DYNAMIC",
    "EXACT",
    "PAPER",
    "SOLVERS",
    "DeploymentSolution",
    "QuasiStaticProblem",
    "Solver",
    "Trajectory",
]

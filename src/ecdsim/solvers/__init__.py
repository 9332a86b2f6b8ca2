"""Quasi-static deployment solvers: each maps a quasi-static problem to a solution.

The paper's method (:data:`PAPER`) and the exact solution (:data:`EXACT`), with the
problem, the answer and the :class:`Solver` protocol they share. The registry of every
method by name, the dynamic one included, is :data:`ecdsim.methods.SOLVERS`: it sits
above this package and :mod:`ecdsim.dynamics`, so that neither imports the other's
upper layer.
"""

from ecdsim.solvers.base import (
    DeploymentSolution,
    QuasiStaticProblem,
    Solver,
    Trajectory,
)
from ecdsim.solvers.exact import EXACT
from ecdsim.solvers.paper import PAPER

__all__ = [
    "EXACT",
    "PAPER",
    "DeploymentSolution",
    "QuasiStaticProblem",
    "Solver",
    "Trajectory",
]

"""Deployment methods by name: the one registry that every caller looks up.

``SOLVERS`` maps a method's name to its :class:`~ecdsim.solvers.Solver`: the paper's and
the exact quasi-static solvers (:mod:`ecdsim.solvers`) and the full dynamics
(:mod:`ecdsim.dynamics`). ``predict``, the config's ``methods``, the CLI's ``--method``,
the tables, the plots, the report and Monte Carlo all iterate over or look up this one
dictionary; adding a method is adding an entry, never an if/elif ladder. What a method
needs or adds beyond the common answer it declares through the protocol's hooks
(:attr:`~ecdsim.solvers.Solver.needs_dynamics`, and the
:class:`~ecdsim.solvers.DeploymentSolution` methods it overrides).

The registry sits above both the solvers and the dynamics, which never import it, so the
layers stay one-way (docs/architecture.md).
"""

from __future__ import annotations

from ecdsim.dynamics.method import DYNAMIC
from ecdsim.solvers import EXACT, PAPER, Solver

SOLVERS: dict[str, Solver] = {PAPER.name: PAPER, EXACT.name: EXACT, DYNAMIC.name: DYNAMIC}

__all__ = ["SOLVERS"]

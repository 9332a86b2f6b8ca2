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
layers stay one-way (docs/architecture.md). The dynamic method is registered by name and
imported on first look-up (its solver, records and integrators are a tenth of a second
of imports that ``ecdsim deploy`` with the quasi-static methods never uses).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, MutableMapping

from ecdsim.solvers import EXACT, PAPER, Solver


class SolverRegistry(MutableMapping[str, Solver]):
    """Methods by name, in registration order; a lazy entry is imported when first read."""

    def __init__(self, solvers: tuple[Solver, ...] = ()) -> None:
        self._solvers: dict[str, Solver | None] = {s.name: s for s in solvers}
        self._loaders: dict[str, Callable[[], Solver]] = {}

    def add_lazy(self, name: str, loader: Callable[[], Solver]) -> None:
        """Register ``name``, whose solver ``loader()`` imports and returns on first use."""
        self._solvers[name] = None
        self._loaders[name] = loader

    def __getitem__(self, name: str) -> Solver:
        solver = self._solvers[name]
        if solver is None:
            solver = self._loaders.pop(name)()
            if solver.name != name:
                raise RuntimeError(f"method {name!r} loaded a solver named {solver.name!r}")
            self._solvers[name] = solver
        return solver

    def __setitem__(self, name: str, solver: Solver) -> None:
        self._solvers[name] = solver
        self._loaders.pop(name, None)

    def __delitem__(self, name: str) -> None:
        del self._solvers[name]
        self._loaders.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(self._solvers)

    def __len__(self) -> int:
        return len(self._solvers)


def _dynamic() -> Solver:
    from ecdsim.dynamics.method import DYNAMIC

    return DYNAMIC


SOLVERS = SolverRegistry((PAPER, EXACT))
SOLVERS.add_lazy("dynamic", _dynamic)

__all__ = ["SOLVERS", "SolverRegistry"]

"""ecdsim: eddy current damper (ECD) models for spring-driven spacecraft deployments.

The package is layered (see ``docs/architecture.md``):

* :mod:`ecdsim.physics` holds the published models as pure, vectorised functions of SI
  floats or NumPy arrays (temperatures in degC);
* :mod:`ecdsim.model` holds thin frozen dataclasses that group parameters and delegate;
* :mod:`ecdsim.solvers` (quasi-static) and :mod:`ecdsim.dynamics` (full dynamics) solve a
  deployment; :mod:`ecdsim.methods` lists them by name; :mod:`ecdsim.deployment` turns
  a system into result objects;
* :mod:`ecdsim.config`, :mod:`ecdsim.plotting` and :mod:`ecdsim.cli` sit at the edge;
  the studies (:mod:`ecdsim.characterize`, :mod:`ecdsim.sizing`,
  :mod:`ecdsim.montecarlo`), :mod:`ecdsim.report` and :mod:`ecdsim.webapp` build on
  the layers below and are used by the CLI.

Importing :mod:`ecdsim` itself is cheap: it imports nothing heavy.
"""

from ecdsim._version import __version__

__all__ = ["__version__"]

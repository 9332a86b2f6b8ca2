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

Importing :mod:`ecdsim` itself is cheap: it imports nothing heavy. The notebook API
(:mod:`ecdsim.api`, docs/api.md) is exported lazily: ``ecdsim.deploy``, ``ecdsim.deploy_wing``,
``ecdsim.fit``,
``ecdsim.size``, ``ecdsim.sweep`` and ``ecdsim.load`` import it on first use, and
``ecdsim.montecarlo`` (for ``ecdsim.montecarlo.open(folder)``) is imported when first named.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ecdsim._version import __version__

if TYPE_CHECKING:
    from ecdsim.api import deploy, deploy_wing, fit, load, size, sweep

__all__ = ["__version__", "deploy", "deploy_wing", "fit", "load", "size", "sweep"]

_LAZY = {"deploy", "deploy_wing", "fit", "load", "size", "sweep"}


def __getattr__(name: str) -> Any:
    """The notebook API's functions, imported from :mod:`ecdsim.api` on first use."""
    if name in _LAZY:
        from ecdsim import api

        return getattr(api, name)
    if name == "montecarlo":  # ecdsim.montecarlo.open(folder) after a bare import ecdsim
        import ecdsim.montecarlo

        return ecdsim.montecarlo
    raise AttributeError(f"module 'ecdsim' has no attribute {name!r}")

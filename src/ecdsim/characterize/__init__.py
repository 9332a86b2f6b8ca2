"""Characterise a damper from bench tests (paper section 7).

The package turns measurements into the ECD's damping rate BECD(T) and friction FECD(T)
at the input shaft, with honest uncertainty, and writes them back as a configuration
file that ``ecdsim deploy`` reads. One module per idea:

* :mod:`~ecdsim.characterize.csvdata` reads CSV files with unit-bearing headers and
  reports every bad row;
* :mod:`~ecdsim.characterize.stats` holds the least-squares statistics shared by all fits;
* :mod:`~ecdsim.characterize.linefit` fits ``torque = FECD + BECD * speed`` and flags
  roll-off and outliers;
* :mod:`~ecdsim.characterize.droptest` reduces drop tests (with the exact start-up
  transient) and fits each temperature;
* :mod:`~ecdsim.characterize.templaws` fits BECD(T) and FECD(T) laws over temperature;
* :mod:`~ecdsim.characterize.tracefit` fits recorded deployments against the exact solver;
* :mod:`~ecdsim.characterize.export` writes the parameter file (TOML);
* :mod:`~ecdsim.characterize.plots` draws the figures.

Importing this package is cheap; scipy and matplotlib are imported inside functions.
The method is described in ``docs/characterize.md``.
"""

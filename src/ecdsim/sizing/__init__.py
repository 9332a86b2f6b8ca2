"""Sizing: requirements, catalogue search, exact gear-ratio intervals, torque margins, and
the ECD against a viscous fluid damper (docs/sizing.md).

Modules: :mod:`~ecdsim.sizing.requirements` (what must hold, as margins),
:mod:`~ecdsim.sizing.catalogue` (TOML/CSV damper and gearbox catalogues),
:mod:`~ecdsim.sizing.search` (one vectorised pass over the catalogue),
:mod:`~ecdsim.sizing.ratio` (exact intervals of the gear ratio by root finding),
:mod:`~ecdsim.sizing.margin` (torque margin, motorisation-ratio form),
:mod:`~ecdsim.sizing.fluid` (silicone-fluid damper and the comparison),
:mod:`~ecdsim.sizing.plots` and :mod:`~ecdsim.sizing.report` (figures and tables).
"""

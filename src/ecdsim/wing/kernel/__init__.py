"""The wing's model on the dynamic kernel: its words (:mod:`~ecdsim.wing.kernel.layout`),
its equations (:mod:`~ecdsim.wing.kernel.equations`) and its event loop
(:mod:`~ecdsim.wing.kernel.loop`), plain Python in the subset numba compiles, compiled
with the kernel's functions by :func:`ecdsim.dynamics.kernel.build.substituted`
(docs/wing.md, the solver)."""

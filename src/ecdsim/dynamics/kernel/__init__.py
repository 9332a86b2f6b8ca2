"""The dynamic method's kernel: one event loop over N degrees of freedom, written once.

Plain Python in the subset numba compiles, compiled from this very source (or run as it
is) by :mod:`ecdsim.dynamics.kernel.build`: the hinge's equations from the laws of
:mod:`ecdsim.physics` (:mod:`~ecdsim.dynamics.kernel.hinge`), RODAS4
(:mod:`~ecdsim.dynamics.kernel.rodas`), the dense output and its event locator
(:mod:`~ecdsim.dynamics.kernel.dense`, :mod:`~ecdsim.dynamics.kernel.integrate`), the
closed form of linear segments (:mod:`~ecdsim.dynamics.kernel.closed`), the friction
state machine (:mod:`~ecdsim.dynamics.kernel.friction`) and the event loop
(:mod:`~ecdsim.dynamics.kernel.loop`). docs/architecture.md, "The dynamic core".
"""

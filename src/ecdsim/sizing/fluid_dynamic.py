"""The ECD and a fluid damper by the dynamic method (``compare-fluid -m dynamic``).

The quasi-static comparison (:func:`ecdsim.sizing.fluid.compare_fluid`) balances each
damper's torque against the net spring torque and treats the deadband as a separate free
phase. The dynamic method integrates both deployments with inertia on the one dynamic
core (:mod:`ecdsim.dynamics.kernel`): the ECD's from the config (its gearbox, lost motion,
stiction and every other effect of ``[dynamics]``-style keys), and the fluid damper's as
the same hinge with its own damper: the power law of :mod:`ecdsim.physics.fluid` at the
load's shaft (``c(T)``, ``n(T)`` at each temperature), its deadband as the lost motion
(the load moves undamped, against the system friction only, until it closes), its own
Coulomb friction, no gear train and no damper inertia (docs/qualification.md section 3).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.dynamics.damping import PowerLawDamper
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.result import EVENT_KINDS, DynamicResult
from ecdsim.dynamics.solver import solve_dynamic

# The power law's linear core: below omega_l = LINEAR_CORE * omega_r the fluid is taken
# as Newtonian (docs/qualification.md section 3). The bench data never reach that far
# (a flight damper's tested speeds span a decade or two around omega_r); the core keeps
# the stiff integrator's Jacobian finite at rest, and changes a deployment's time by far
# less than the integrator's tolerance (tests/test_fluid_dynamic.py measures it).
LINEAR_CORE = 1e-6


def fluid_problem(
    base: DynamicProblem,
    coefficient: ArrayLike,
    exponent: ArrayLike,
    reference_speed: float,
    friction: ArrayLike,
    deadband: float,
) -> DynamicProblem:
    """The fluid damper's dynamic problem: ``base`` (the ECD's, for its spring, load,
    system friction and settings) with the fluid damper in the ECD's place.

    Parameters
    ----------
    base : the ECD's dynamic problem at the same temperatures
    coefficient : c(T) of ``T = c omega**n`` [N*m*(s/rad)**n]
    exponent : n(T) [-]
    reference_speed : omega_r, the speed the law was measured about [rad/s] (sets the
        linear core LINEAR_CORE * omega_r and the speed scale of the tolerances)
    friction : the fluid damper's Coulomb friction [N*m] (breakaway equal to it)
    deadband : the fluid damper's free angle at the start [rad]
    """
    c = as_float(coefficient)
    n = as_float(exponent)
    law = PowerLawDamper(c, n, LINEAR_CORE * reference_speed)
    fluid_friction = as_float(friction)
    # The secant rate at omega_r: the kernel's speed scale for its tolerances (never a
    # closed-form segment's damping: those refuse the power law).
    secant = as_float(c * np.power(reference_speed, n - 1.0))
    return replace(
        base,
        friction=as_float(fluid_friction + base.system_friction),
        damping_rate=secant,
        eddy=law,
        ecd_friction=fluid_friction,
        static_friction_factor=np.asarray(1.0),
        damper_inertia=np.asarray(0.0),
        lost_motion=np.asarray(float(deadband)),
        gear_ratio=np.asarray(1.0),
        gearbox_damping_rate=np.asarray(0.0),
        forward_efficiency=np.asarray(1.0),
        backward_efficiency=np.asarray(1.0),
        stribeck_speed=np.asarray(math.inf),
        gear_stiffness=np.asarray(math.inf),
        gear_mesh_damping=np.asarray(0.0),
        heat_capacity=np.asarray(math.inf),
        thermal_resistance=np.asarray(math.inf),
        housing_heat_capacity=np.asarray(math.inf),
        housing_thermal_resistance=np.asarray(math.inf),
        initial_rotor_rise=np.asarray(0.0),
        initial_housing_rise=np.asarray(0.0),
        thermal=False,
        two_node=False,
    )


def parameters_for(dynamics: DynamicParameters | None, inertia: float | None) -> DynamicParameters:
    """The dynamic parameters of the comparison: the config's (``[load] inertia`` and the
    keys read with it), with the fluid comparison's load inertia where one is given.
    Raises ValueError without any load inertia."""
    if dynamics is None:
        if inertia is None:
            raise ValueError(
                "fluid_damper.load_inertia: the dynamic method needs the load's inertia "
                "(load_inertia in [fluid_damper], or inertia in [load])"
            )
        return DynamicParameters(load_inertia=inertia)
    if inertia is not None:
        return replace(dynamics, load_inertia=inertia)
    return dynamics


def engagement_speed(result: DynamicResult) -> FloatArray:
    """The load's speed when the lost motion (deadband) closed, per case [rad/s]: 0
    without one (engaged at release), NaN where it never closed."""
    events = result.events
    speed = np.full(result.size, math.nan)
    engaged = np.ravel(result.engagement_time) == 0.0
    speed[engaged] = 0.0
    rows = events.kind == EVENT_KINDS.index("engage")
    speed[events.case[rows]] = events.speed[rows]
    return as_float(speed.reshape(result.batch_shape))


def deployments(
    hinge: object,
    coefficient: FloatArray,
    exponent: FloatArray,
    reference_speed: float,
    friction: FloatArray,
    deadband: float,
) -> tuple[DynamicResult, DynamicResult]:
    """The ECD's and the fluid damper's deployments by the dynamic method: ``hinge`` is
    the ECD's dynamic problem (as :func:`ecdsim.deployment.predict` builds it from the
    config), the fluid damper's is the same hinge with it in the ECD's place
    (:func:`fluid_problem`). Raises TypeError if ``hinge`` is not a DynamicProblem."""
    if not isinstance(hinge, DynamicProblem):
        raise TypeError("the fluid comparison's dynamic method needs a DynamicProblem")
    fluid = fluid_problem(hinge, coefficient, exponent, reference_speed, friction, deadband)
    return solve_dynamic(hinge, record=False), solve_dynamic(fluid, record=False)
